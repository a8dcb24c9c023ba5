"""Rigid-body integration for OpenMM.

openmm-rigid integrates rigid molecules with a symplectic, time-reversible splitting whose free
drift is the exact torque-free motion of each body (van Zon and Schofield, J. Comput. Phys. 225,
145 (2007); J. Chem. Phys. 128, 154119 (2008)).

Importing the package loads the integrator's kernels for the Reference and CPU platforms (import
openmm first or not: openmmrigid imports it).

Contents
--------
RigidBodyIntegrator
    The integrator, an ``openmm.Integrator`` for ``openmm.Context`` and ``openmm.app.Simulation``.
RigidBodyLangevinIntegrator
    The same for constant temperature: a Langevin integrator (LangevinMiddleIntegrator's arrangement, BAOAB with half-step velocities) with the exact free drift.
RigidBodyIntegratorBase
    Their common base (bodies, rotation method, kinetic energies, degrees of freedom).
RigidStateDataReporter
    An ``openmm.app.StateDataReporter`` that takes its degrees of freedom from the integrator, with
    columns for the translational and rotational kinetic energies and temperatures.
rigidBodiesFromTopology
    The bodies (lists of particle indices) of the selected residues of an ``openmm.app.Topology``.
rigidHydrogenGroups
    The bodies of a System's constraint clusters (X-H groups, waters) and, optionally, its planar groups
    (aromatic rings, amides, peptide groups): a model with rigid X-H groups.
removeIntraBodyInteractions
    A copy of a System without the bonded terms, nonbonded pairs and constraints inside each body.
getSupportedPlatforms
    The platforms that have the integrators' kernels here (Reference, CPU, and OpenCL and CUDA where
    their plugins are installed); pluginLoadFailures says why a GPU plugin present did not load.
NoThermostatError
    What ``RigidBodyIntegrator.getTemperature()`` raises without a thermostat (an ``openmm.OpenMMException``
    and an ``AttributeError``, so that openmmtools sees an NVE integrator).
deserializeIntegrator
    A RigidBodyIntegrator or RigidBodyLangevinIntegrator from XML (``openmm.XmlSerializer.deserialize`` does the same).
FreeRotor
    The exact torque-free motion of a single rigid body.
testing
    Small systems and measurements shared by the examples and benchmarks (``testing.alanineDipeptide()``,
    ``testing.waterBox()``, ``testing.energyDrift()``, ...).
special
    The Jacobi elliptic functions and elliptic integrals that FreeRotor is built on.
"""

from importlib.metadata import PackageNotFoundError, version as _distributionVersion

from . import special, testing
from .freerotor import FreeRotor
from .integrator import (AccuracyWarning, NoThermostatError, RigidBodyIntegrator, RigidBodyIntegratorBase, RigidBodyLangevinIntegrator,
                         deserializeIntegrator, getSupportedPlatforms, pluginLoadFailures)
from .intrabody import removeIntraBodyInteractions
from .reporters import RigidStateDataReporter
from .topology import rigidBodiesFromTopology, rigidHydrogenGroups

try:
    __version__ = _distributionVersion("openmm-rigid")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "unknown"

__all__ = ["getSupportedPlatforms", "pluginLoadFailures", "NoThermostatError", "AccuracyWarning", "RigidBodyIntegrator", "RigidBodyLangevinIntegrator", "RigidBodyIntegratorBase", "RigidStateDataReporter", "deserializeIntegrator", "FreeRotor", "special", "testing",
           "rigidBodiesFromTopology", "rigidHydrogenGroups", "removeIntraBodyInteractions", "__version__"]

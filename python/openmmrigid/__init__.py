"""Rigid-body integration for OpenMM.

openmm-rigid integrates rigid molecules with a symplectic, time-reversible splitting whose free
drift is the exact torque-free motion of each body (van Zon and Schofield, J. Comput. Phys. 225,
145 (2007); J. Chem. Phys. 128, 154119 (2008)).

Importing the package loads the integrator's kernels for the Reference and CPU platforms (import
openmm first or not: openmmrigid imports it).

Contents
--------
RigidBodyIntegrator
    Constant energy: kicks by forces and torques, exact free drifts (splittings Verlet, Omelyan2, ...).
RigidBodyBussiIntegrator
    The same with the stochastic velocity rescaling thermostat of Bussi, Donadio and Parrinello.
RigidBodyLangevinIntegrator
    Constant temperature by Langevin dynamics (LangevinMiddleIntegrator's arrangement) with exact drifts.
RigidBodyIntegratorBase
    Their common base: raised moments of inertia, multiple time steps, shadow work and heat, the
    accuracy check.
AccuracyWarning
    What a step says, once, when the run leaves the integrator's accurate range.
rigidBodiesFromTopology, rigidHydrogenGroups, removeIntraBodyInteractions
    Bodies from an ``openmm.app.Topology`` or a System's constraint clusters, and a System without the
    interactions inside each body.
RigidStateDataReporter
    An ``openmm.app.StateDataReporter`` with columns for translation and rotation, shadow work and heat.
deserializeIntegrator, getSupportedPlatforms, pluginLoadFailures
    An integrator from XML; the platforms that have the kernels, and why a GPU plugin did not load.
FreeRotor, special
    The exact torque-free motion of one rigid body, and the elliptic functions it is built on.

``openmm.app`` is imported only when something that needs it is first used (the reporter, the
topology helpers); importing this package changes nothing in ``openmm``.
"""

from importlib.metadata import PackageNotFoundError, version as _distributionVersion

# First of all, before any compiled code of the package loads: the running OpenMM must be the release the
# plugin was built against (exactly: OpenMM's C++ ABI is not stable across releases; _versioncheck.py).
from ._versioncheck import checkOpenMMVersion as _checkOpenMMVersion, runningOpenMMVersion as _runningOpenMMVersion

try:
    from ._build import OPENMM_VERSION as _BUILT_AGAINST_OPENMM
except ImportError:  # a source tree that was never built: nothing to compare with
    _BUILT_AGAINST_OPENMM = None
_checkOpenMMVersion(_BUILT_AGAINST_OPENMM, _runningOpenMMVersion())

from . import special
from .freerotor import FreeRotor
from .integrator import (AccuracyWarning, RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyIntegratorBase,
                         RigidBodyLangevinIntegrator, deserializeIntegrator, getSupportedPlatforms, pluginLoadFailures)
from .intrabody import removeIntraBodyInteractions

#: What needs openmm.app, imported on first use (PEP 562): name -> module.
_LAZY = {"RigidStateDataReporter": "reporters", "rigidBodiesFromTopology": "topology", "rigidHydrogenGroups": "topology"}


def __getattr__(name):
    if name in _LAZY:
        import importlib
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(list(globals()) + list(_LAZY))


try:
    __version__ = _distributionVersion("openmm-rigid")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "unknown"

__all__ = ["RigidBodyIntegrator", "RigidBodyBussiIntegrator", "RigidBodyLangevinIntegrator", "RigidBodyIntegratorBase",
           "AccuracyWarning", "rigidBodiesFromTopology", "rigidHydrogenGroups", "removeIntraBodyInteractions",
           "RigidStateDataReporter", "deserializeIntegrator", "getSupportedPlatforms", "pluginLoadFailures", "FreeRotor",
           "special", "__version__"]

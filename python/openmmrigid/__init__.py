"""Rigid-body integration for OpenMM.

openmm-rigid integrates rigid molecules with a symplectic, time-reversible splitting whose free
drift is the exact torque-free motion of each body (van Zon and Schofield, J. Comput. Phys. 225,
145 (2007); J. Chem. Phys. 128, 154119 (2008)).

Contents
--------
FreeRotor
    The exact torque-free motion of a single rigid body.
special
    The Jacobi elliptic functions and elliptic integrals that FreeRotor is built on.
"""

from importlib.metadata import PackageNotFoundError, version as _distributionVersion

from . import special
from .freerotor import FreeRotor

try:
    __version__ = _distributionVersion("openmm-rigid")
except PackageNotFoundError:  # imported from a source tree that was never installed
    __version__ = "unknown"

__all__ = ["FreeRotor", "special", "__version__"]

"""Jacobi elliptic functions and elliptic integrals, as used by openmmrigid.FreeRotor.

All functions take the parameter m (not the modulus k = sqrt(m)) and, optionally, its complement
m1 = 1 - m. Pass m1 when you know it more precisely than 1 - m can be computed: near m = 1 the
subtraction loses digits, and these functions lose them with it.

The domain is 0 <= m <= 1 with 0 <= m1 <= 1. Every function takes and returns real scalars and
raises openmm.OpenMMException for arguments outside its domain. The C++ implementations
(openmmapi/include/numerics/Elliptic.h) state their accuracy; each function's docstring is the
Doxygen of its C++ implementation, with what the Python function adds (m1 optional).
"""

from . import openmmrigid as _swig
from ._pythonapi import fromCpp
from ._validation import asFloat

__all__ = ["jacobiElliptic", "ellipticK", "ellipticF", "ellipticPi", "carlsonRF", "carlsonRJ"]


_M1_NOTE = "If omitted, it is computed as 1 - m."


def _parameters(owner, m, m1):
    m = asFloat(owner, "m", m)
    m1 = 1.0 - m if m1 is None else asFloat(owner, "m1", m1)
    return m, m1


def jacobiElliptic(u, m, m1=None):
    m, m1 = _parameters("jacobiElliptic", m, m1)
    return _swig.jacobiElliptic(asFloat("jacobiElliptic", "u", u), m, m1)


def ellipticK(m, m1=None):
    m, m1 = _parameters("ellipticK", m, m1)
    return _swig.ellipticK(m, m1)


def ellipticF(x, m, m1=None):
    m, m1 = _parameters("ellipticF", m, m1)
    return _swig.ellipticF(asFloat("ellipticF", "x", x), m, m1)


def ellipticPi(n, x, m, m1=None):
    m, m1 = _parameters("ellipticPi", m, m1)
    return _swig.ellipticPi(asFloat("ellipticPi", "n", n), asFloat("ellipticPi", "x", x), m, m1)


def carlsonRF(x, y, z):
    return _swig.carlsonRF(asFloat("carlsonRF", "x", x), asFloat("carlsonRF", "y", y), asFloat("carlsonRF", "z", z))


def carlsonRJ(x, y, z, p):
    return _swig.carlsonRJ(asFloat("carlsonRJ", "x", x), asFloat("carlsonRJ", "y", y),
                           asFloat("carlsonRJ", "z", z), asFloat("carlsonRJ", "p", p))


# Each function's docstring is its C++ implementation's (numerics/Elliptic.h, through SWIG's -doxygen);
# the Python functions add a default for m1.
for _function in (jacobiElliptic, ellipticK, ellipticF, ellipticPi):
    _function.__doc__ = fromCpp(getattr(_swig, _function.__name__), notes={"m1": _M1_NOTE}, optional=("m1",))
for _function in (carlsonRF, carlsonRJ):
    _function.__doc__ = fromCpp(getattr(_swig, _function.__name__))
del _function

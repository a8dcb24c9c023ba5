"""Jacobi elliptic functions and elliptic integrals, as used by openmmrigid.FreeRotor.

All functions take the parameter m (not the modulus k = sqrt(m)) and, optionally, its complement
m1 = 1 - m. Pass m1 when you know it more precisely than 1 - m can be computed: near m = 1 the
subtraction loses digits, and these functions lose them with it.

The domain is 0 <= m <= 1 with 0 <= m1 <= 1. Every function takes and returns real scalars and
raises openmm.OpenMMException for arguments outside its domain. The C++ implementations
(openmmapi/include/numerics/Elliptic.h) state their accuracy.
"""

from . import openmmrigid as _swig
from ._validation import asFloat

__all__ = ["jacobiElliptic", "ellipticK", "ellipticF", "ellipticPi", "carlsonRF", "carlsonRJ"]


def _parameters(owner, m, m1):
    m = asFloat(owner, "m", m)
    m1 = 1.0 - m if m1 is None else asFloat(owner, "m1", m1)
    return m, m1


def jacobiElliptic(u, m, m1=None):
    """The Jacobi elliptic functions sn, cn and dn (DLMF 22.2).

    Parameters
    ----------
    u : float
        The argument.
    m : float
        The parameter, 0 <= m <= 1.
    m1 : float, optional
        The complementary parameter 1 - m; computed from m if omitted.

    Returns
    -------
    tuple of float
        (sn(u|m), cn(u|m), dn(u|m)).
    """
    m, m1 = _parameters("jacobiElliptic", m, m1)
    return _swig.jacobiElliptic(asFloat("jacobiElliptic", "u", u), m, m1)


def ellipticK(m, m1=None):
    """The complete elliptic integral of the first kind K(m) (DLMF 19.2.8).

    Parameters
    ----------
    m : float
        The parameter, 0 <= m <= 1 (K(1) is infinite).
    m1 : float, optional
        The complementary parameter 1 - m; computed from m if omitted.

    Returns
    -------
    float
    """
    m, m1 = _parameters("ellipticK", m, m1)
    return _swig.ellipticK(m, m1)


def ellipticF(x, m, m1=None):
    """The incomplete elliptic integral of the first kind in Jacobi's form.

    F(x|m) = integral from 0 to x of dt / sqrt((1 - t^2)(1 - m t^2)), so F(sn(u|m)|m) = u for
    |u| <= K(m).

    Parameters
    ----------
    x : float
        The upper limit, |x| <= 1.
    m : float
        The parameter, 0 <= m <= 1.
    m1 : float, optional
        The complementary parameter 1 - m; computed from m if omitted.

    Returns
    -------
    float
    """
    m, m1 = _parameters("ellipticF", m, m1)
    return _swig.ellipticF(asFloat("ellipticF", "x", x), m, m1)


def ellipticPi(n, x, m, m1=None):
    """The incomplete elliptic integral of the third kind in Jacobi's form.

    Pi(n; x|m) = integral from 0 to x of dt / ((1 - n t^2) sqrt((1 - t^2)(1 - m t^2))).

    Parameters
    ----------
    n : float
        The characteristic, with n x^2 < 1.
    x : float
        The upper limit, |x| <= 1.
    m : float
        The parameter, 0 <= m <= 1.
    m1 : float, optional
        The complementary parameter 1 - m; computed from m if omitted.

    Returns
    -------
    float
    """
    m, m1 = _parameters("ellipticPi", m, m1)
    return _swig.ellipticPi(asFloat("ellipticPi", "n", n), asFloat("ellipticPi", "x", x), m, m1)


def carlsonRF(x, y, z):
    """Carlson's symmetric elliptic integral of the first kind R_F(x, y, z) (DLMF 19.16.1).

    Parameters
    ----------
    x, y, z : float
        Non-negative, at most one of them zero.

    Returns
    -------
    float
    """
    return _swig.carlsonRF(asFloat("carlsonRF", "x", x), asFloat("carlsonRF", "y", y), asFloat("carlsonRF", "z", z))


def carlsonRJ(x, y, z, p):
    """Carlson's symmetric elliptic integral of the third kind R_J(x, y, z, p) (DLMF 19.16.2).

    Parameters
    ----------
    x, y, z : float
        Non-negative, at most one of them zero.
    p : float
        Positive.

    Returns
    -------
    float
    """
    return _swig.carlsonRJ(asFloat("carlsonRJ", "x", x), asFloat("carlsonRJ", "y", y),
                           asFloat("carlsonRJ", "z", z), asFloat("carlsonRJ", "p", p))

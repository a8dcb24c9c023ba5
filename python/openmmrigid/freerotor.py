"""The exact torque-free motion of a rigid body: openmmrigid.FreeRotor."""

import numpy as np
from openmm import OpenMMException

from . import openmmrigid as _swig
from ._validation import asFloatArray

__all__ = ["FreeRotor"]

_REPRESENTATION_CODES = {
    "auto": _swig.FreeRotorAutomatic,
    "theta-series": _swig.FreeRotorThetaSeries,
    "elliptic-integral": _swig.FreeRotorEllipticIntegral,
}
_REPRESENTATION_NAMES = {
    _swig.FreeRotorThetaSeries: "theta-series",
    _swig.FreeRotorEllipticIntegral: "elliptic-integral",
}


class FreeRotor:
    """The exact torque-free motion of a rigid body.

    The body's angular velocity and attitude at any time follow in closed form from the initial
    state: Jacobi elliptic functions and either a theta series or an elliptic integral of the third
    kind for an asymmetric top (van Zon and Schofield, J. Comput. Phys. 225, 145 (2007)), elementary
    functions for linear, spherical and symmetric tops. This is the rotational half of the free drift
    in the integrator, exposed for checks and diagnostics.

    All quantities may be in any consistent units (for example amu nm^2, 1/ps and ps). Quantities
    from ``openmm.unit`` are accepted and converted to OpenMM's MD unit system (amu, nm, ps, radian).

    Parameters
    ----------
    moments : array_like, shape (3,)
        The principal moments of inertia (mass x length^2), in any order, non-negative. One may be
        zero if the other two are equal: a linear body, whose zero moment marks its axis.
    omega : array_like, shape (3,)
        The angular velocity at t = 0 in the body frame (1/time).
    attitude : array_like, shape (3, 3), optional
        The rotation matrix (orthonormal, determinant +1) from the lab frame to the body frame at
        t = 0, so that ``attitude @ v_lab`` gives body components. The identity by default.
    representation : {"auto", "theta-series", "elliptic-integral"}, optional
        How an asymmetric top's rotation angle is computed. "auto" picks the cheaper of the two
        exact forms; the others force one of them, for diagnostics. Ignored for other kinds.

    Raises
    ------
    openmm.OpenMMException
        If an argument has the wrong shape or is not numeric, if a moment is negative (or the
        moments are otherwise inconsistent), if any entry is NaN or infinite, if attitude is not a
        rotation, or if the forced representation cannot describe this motion.

    Examples
    --------
    >>> rotor = FreeRotor([1.0, 2.0, 3.0], [0.1, 1.0, 0.2])
    >>> omega, attitude = rotor.evolve(10.0)
    >>> omegas, attitudes = rotor.evolve(np.linspace(0.0, 10.0, 101))  # shapes (101, 3), (101, 3, 3)
    """

    def __init__(self, moments, omega, attitude=None, representation="auto"):
        moments = asFloatArray("FreeRotor", "moments", moments, (3,))
        omega = asFloatArray("FreeRotor", "omega", omega, (3,))
        if attitude is None:
            attitude = np.eye(3)
        attitude = asFloatArray("FreeRotor", "attitude", attitude, (3, 3))
        if not isinstance(representation, str) or representation not in _REPRESENTATION_CODES:
            allowed = ", ".join(f'"{name}"' for name in _REPRESENTATION_CODES)
            raise OpenMMException(f"FreeRotor: representation must be one of {allowed}; received {representation!r}")
        self._requestedRepresentation = representation
        self._rotor = _swig.FreeRotorAdaptor(moments, omega, attitude, _REPRESENTATION_CODES[representation])
        self._kind = self._rotor.getKind()
        self._moments = self._readVector(self._rotor.getMoments)
        self._omega = self._readVector(self._rotor.getOmega)
        self._angularMomentum = self._readVector(self._rotor.getAngularMomentum)
        self._attitude = np.empty((3, 3))
        self._rotor.getAttitude(self._attitude)
        for array in (self._moments, self._omega, self._angularMomentum, self._attitude):
            array.flags.writeable = False

    @staticmethod
    def _readVector(getter):
        vector = np.empty(3)
        getter(vector)
        return vector

    def evolve(self, t):
        """The angular velocity and attitude at time t.

        Parameters
        ----------
        t : float or array_like, shape (n,)
            The time or times, measured from the initial state (same time unit as omega; may be
            negative). A Quantity is converted to ps.

        Returns
        -------
        omega : numpy.ndarray, shape (3,) or (n, 3)
            The body-frame angular velocity at each time (1/time).
        attitude : numpy.ndarray, shape (3, 3) or (n, 3, 3)
            The lab-to-body rotation matrix at each time.

        Raises
        ------
        openmm.OpenMMException
            If t is neither a number nor a 1-D array of numbers.
        """
        times = asFloatArray("FreeRotor.evolve", "t", t)
        flatTimes = times.reshape(-1)
        omega = np.empty((flatTimes.size, 3))
        attitude = np.empty((flatTimes.size, 3, 3))
        self._rotor.evolveInto(flatTimes, omega, attitude)
        if times.ndim == 0:
            return omega[0], attitude[0]
        return omega, attitude

    @property
    def kind(self):
        """str: "linear", "spherical", "symmetric" or "asymmetric", from the principal moments."""
        return self._kind

    @property
    def representation(self):
        """str: "theta-series" or "elliptic-integral" for an asymmetric top, else "closed-form"."""
        return _REPRESENTATION_NAMES.get(self._rotor.getRepresentation(), "closed-form")

    @property
    def energy(self):
        """float: The rotational kinetic energy, 1/2 sum I_k omega_k^2 (mass x length^2 / time^2)."""
        return self._rotor.getEnergy()

    @property
    def parameter(self):
        """float: The elliptic parameter m (0 <= m <= 1) of an asymmetric top's motion; 0 for other kinds."""
        return self._rotor.getParameter()

    @property
    def angularMomentum(self):
        """numpy.ndarray, shape (3,): The angular momentum in the body frame at t = 0 (mass x length^2 / time)."""
        return self._angularMomentum.copy()

    @property
    def moments(self):
        """numpy.ndarray, shape (3,): The principal moments of inertia (mass x length^2)."""
        return self._moments.copy()

    @property
    def omega(self):
        """numpy.ndarray, shape (3,): The body-frame angular velocity at t = 0 (1/time).

        For a linear body, the component along its axis is removed: it carries no motion.
        """
        return self._omega.copy()

    @property
    def attitude(self):
        """numpy.ndarray, shape (3, 3): The lab-to-body rotation matrix at t = 0."""
        return self._attitude.copy()

    def __repr__(self):
        details = f"kind={self.kind!r}, representation={self.representation!r}"
        if self.kind == "asymmetric":
            details += f", parameter={self.parameter:.6g}"
        return (f"openmmrigid.FreeRotor(moments={self._moments.tolist()}, omega={self._omega.tolist()}, "
                f"energy={self.energy:.6g}, {details})")

    def __reduce__(self):
        return (FreeRotor, (self._moments, self._omega, self._attitude, self._requestedRepresentation))

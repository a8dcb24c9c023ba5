"""The exact torque-free motion of a rigid body: openmmrigid.FreeRotor."""

import numpy as np
from openmm import OpenMMException

from . import _pythonapi
from . import openmmrigid as _swig
from ._validation import asFloatArray

__all__ = ["FreeRotor"]

_Cpp = _swig._CppFreeRotor
_REPRESENTATION_CODES = {
    "auto": _Cpp.Automatic,
    "theta-series": _Cpp.ThetaSeries,
    "elliptic-integral": _Cpp.EllipticIntegral,
}
_REPRESENTATION_NAMES = {
    _Cpp.ThetaSeries: "theta-series",
    _Cpp.EllipticIntegral: "elliptic-integral",
}

_EXAMPLES = """Examples
--------
>>> rotor = FreeRotor([1.0, 2.0, 3.0], [0.1, 1.0, 0.2])
>>> omega, attitude = rotor.evolve(10.0)
>>> omegas, attitudes = rotor.evolve(np.linspace(0.0, 10.0, 101))  # shapes (101, 3), (101, 3, 3)"""


class FreeRotor:
    # The docstrings are OpenMMRigid::FreeRotor's (numerics/FreeRotor.h, through SWIG's -doxygen),
    # with what this class does differently: numpy arrays, properties, representations by name.
    __doc__ = _pythonapi.fromCpp(
        _Cpp.__init__, description=_Cpp.__doc__,
        pythonNotes="In Python the arguments may also be openmm.unit Quantities, converted to OpenMM's MD "
                    "unit system (amu, nm, ps, radian).",
        types={"moments": "array_like, shape (3,)", "omega": "array_like, shape (3,)",
               "attitude": "array_like, shape (3, 3)", "representation": '{"auto", "theta-series", "elliptic-integral"}'},
        notes={"attitude": "The identity if omitted.",
               "representation": 'In Python by name: "auto" (Automatic, the default), "theta-series" or '
                                 '"elliptic-integral".'},
        optional=("attitude", "representation"), drop=("checkInput",)) + "\n\n" + _EXAMPLES

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
        self._rotor = _Cpp(moments, omega, attitude, _REPRESENTATION_CODES[representation])
        self._kind = _Cpp.kindName(self._rotor.getKind())
        self._moments = np.array(self._rotor.getMoments())
        self._omega = np.array(self._rotor.getOmega())
        self._angularMomentum = np.array(self._rotor.getAngularMomentum())
        self._attitude = np.array(self._rotor.getAttitude())
        for array in (self._moments, self._omega, self._angularMomentum, self._attitude):
            array.flags.writeable = False

    def evolve(self, t):
        times = asFloatArray("FreeRotor.evolve", "t", t)
        flatTimes = times.reshape(-1)
        omega = np.empty((flatTimes.size, 3))
        attitude = np.empty((flatTimes.size, 3, 3))
        self._rotor.evolveInto(flatTimes, omega, attitude)
        if times.ndim == 0:
            return omega[0], attitude[0]
        return omega, attitude

    evolve.__doc__ = _pythonapi.fromCpp(
        _Cpp.evolve,
        types={"t": "float or array_like, shape (n,)", "omega": "numpy.ndarray, shape (3,) or (n, 3)",
               "attitude": "numpy.ndarray, shape (3, 3) or (n, 3, 3)"},
        notes={"t": "In Python also a 1-D array of times, or a Quantity (converted to ps).",
               "omega": "One row per time for an array t.", "attitude": "One matrix per time for an array t."})

    @property
    def kind(self):
        return self._kind

    @property
    def representation(self):
        return _REPRESENTATION_NAMES.get(self._rotor.getRepresentation(), "closed-form")

    @property
    def energy(self):
        return self._rotor.getEnergy()

    @property
    def parameter(self):
        return self._rotor.getParameter()

    @property
    def angularMomentum(self):
        return self._angularMomentum.copy()

    @property
    def moments(self):
        return self._moments.copy()

    @property
    def omega(self):
        return self._omega.copy()

    @property
    def attitude(self):
        return self._attitude.copy()

    def __repr__(self):
        details = f"kind={self.kind!r}, representation={self.representation!r}"
        if self.kind == "asymmetric":
            details += f", parameter={self.parameter:.6g}"
        return (f"openmmrigid.FreeRotor(moments={self._moments.tolist()}, omega={self._omega.tolist()}, "
                f"energy={self.energy:.6g}, {details})")

    def __reduce__(self):
        return (FreeRotor, (self._moments, self._omega, self._attitude, self._requestedRepresentation))


# Each property documents the C++ getter it reads, with its Python type first (numpy's convention).
for _name, _pythonType, _getter, _note in (
        ("kind", "str", _Cpp.getKind, 'In Python its name: "linear", "spherical", "symmetric" or "asymmetric".'),
        ("representation", "str", _Cpp.getRepresentation,
         'In Python by name: "theta-series" or "elliptic-integral", and "closed-form" for the other kinds.'),
        ("energy", "float", _Cpp.getEnergy, None),
        ("parameter", "float", _Cpp.getParameter, None),
        ("angularMomentum", "numpy.ndarray, shape (3,)", _Cpp.getAngularMomentum, None),
        ("moments", "numpy.ndarray, shape (3,)", _Cpp.getMoments, None),
        ("omega", "numpy.ndarray, shape (3,)", _Cpp.getOmega, None),
        ("attitude", "numpy.ndarray, shape (3, 3)", _Cpp.getAttitude, None)):
    setattr(FreeRotor, _name, property(getattr(FreeRotor, _name).fget, doc=_pythonapi.propertyDoc(_pythonType, _getter, _note)))
del _name, _pythonType, _getter, _note

"""Conversion of user input to float64 arrays, with errors an OpenMM user can act on."""

import numpy as np
from openmm import OpenMMException, unit


def stripUnits(value):
    """Return value in OpenMM's MD unit system (nm, ps, amu, ...) if it is a Quantity, else value."""
    if unit.is_quantity(value):
        return value.value_in_unit_system(unit.md_unit_system)
    return value


def describe(value):
    """What numpy sees in value, for error messages ("list of shape (3,) holding bool"); never raises."""
    try:
        array = np.asarray(value)
    except (TypeError, ValueError):
        return f"a ragged {type(value).__name__}"
    return f"{type(value).__name__} of shape {array.shape} holding {array.dtype.name}"


def asFloatArray(owner, name, value, shape=None):
    """Convert value to a C-contiguous float64 array; shape None allows a scalar or any 1-D length.

    Raises openmm.OpenMMException naming owner, the argument and what was received when value is not
    an array of real numbers of the required shape.
    """
    value = stripUnits(value)
    expected = "a real number or a 1-D array" if shape is None else f"an array of real numbers with shape {shape}"
    try:
        array = np.asarray(value)
        if array.dtype.kind == "O":  # e.g. Fraction, Decimal, mpmath.mpf
            array = array.astype(np.float64)
        if array.dtype.kind not in "iuf":
            raise TypeError
        array = np.asarray(array, dtype=np.float64, order="C")  # keeps 0-d (ascontiguousarray does not)
    except (TypeError, ValueError):
        raise OpenMMException(
            f"{owner}: {name} must be {expected}; received {describe(value)}"
        ) from None
    if (shape is None and array.ndim > 1) or (shape is not None and array.shape != shape):
        raise OpenMMException(f"{owner}: {name} must be {expected}; received shape {array.shape}")
    return array


def asFloat(owner, name, value):
    """Convert a scalar to float, raising openmm.OpenMMException naming owner and argument if it is not one."""
    array = asFloatArray(owner, name, value, shape=())
    return float(array)

// OpenMMRigid::FreeRotor itself, as the private class _CppFreeRotor (its docstrings are the header's
// Doxygen); openmmrigid/freerotor.py builds the user-facing class openmmrigid.FreeRotor on top of it.
// Vectors and matrices cross as float64 buffers (in) and tuples (out); the loop over many times runs
// in C++ (evolveInto).

%{
#include "numerics/FreeRotor.h"
#include <algorithm>
%}

// Vector3 and Matrix3 are std::array aliases in numerics/Matrix3.h, which SWIG does not read: to SWIG
// they are opaque types in OpenMMRigid, converted by the typemaps below.
namespace OpenMMRigid {
class Vector3;
class Matrix3;
} // namespace OpenMMRigid

%rename(_CppFreeRotor) OpenMMRigid::FreeRotor;
// What only C++ callers need: the integrator's in-place drift, the core's shape and rotor.
%ignore OpenMMRigid::FreeRotor::advance;
%ignore OpenMMRigid::FreeRotor::classify;
%ignore OpenMMRigid::FreeRotor::getCore;
%ignore OpenMMRigid::detail::toArray;
%ignore OpenMMRigid::detail::fromArray;

// Vector3 and Matrix3 (std::arrays, row by row) from any C-contiguous float64 buffer of 3 or 9 numbers.
%typemap(in) const OpenMMRigid::Vector3& (OpenMMRigid::Vector3 value, DoubleBuffer buffer) {
    if (!buffer.acquire($input, "$1_name", false))
        SWIG_fail;
    if (buffer.length() != 3) {
        raiseOpenMMException(std::string("$1_name must hold 3 numbers; got ") + std::to_string(buffer.length()));
        SWIG_fail;
    }
    std::copy(buffer.data(), buffer.data() + 3, value.begin());
    $1 = &value;
}
%typemap(in) const OpenMMRigid::Matrix3& (OpenMMRigid::Matrix3 value, DoubleBuffer buffer) {
    if (!buffer.acquire($input, "$1_name", false))
        SWIG_fail;
    if (buffer.length() != 9) {
        raiseOpenMMException(std::string("$1_name must hold 9 numbers; got ") + std::to_string(buffer.length()));
        SWIG_fail;
    }
    for (int i = 0; i < 3; i++)
        std::copy(buffer.data() + 3*i, buffer.data() + 3*i + 3, value[i].begin());
    $1 = &value;
}
%typemap(typecheck, precedence=SWIG_TYPECHECK_POINTER) const OpenMMRigid::Vector3&, const OpenMMRigid::Matrix3& {
    $1 = PyObject_CheckBuffer($input);
}

// Out: a Vector3 as a tuple of 3 floats, a Matrix3 as a tuple of 3 rows.
%{
namespace {
PyObject* vectorToPython(const OpenMMRigid::Vector3& v) {
    return Py_BuildValue("(ddd)", v[0], v[1], v[2]);
}
PyObject* matrixToPython(const OpenMMRigid::Matrix3& a) {
    return Py_BuildValue("((ddd)(ddd)(ddd))", a[0][0], a[0][1], a[0][2], a[1][0], a[1][1], a[1][2],
                         a[2][0], a[2][1], a[2][2]);
}
} // namespace
%}
%typemap(out) const OpenMMRigid::Matrix3& {
    $result = matrixToPython(*$1);
    if ($result == NULL)
        SWIG_fail;
}
%typemap(out) OpenMMRigid::Vector3 {
    $result = vectorToPython($1);
    if ($result == NULL)
        SWIG_fail;
}
%typemap(out) const OpenMMRigid::Vector3& {
    $result = vectorToPython(*$1);
    if ($result == NULL)
        SWIG_fail;
}
// evolve's outputs come back as the tuple (omega, attitude).
%typemap(in, numinputs=0) (OpenMMRigid::Vector3& omega, OpenMMRigid::Matrix3& attitude)
        (OpenMMRigid::Vector3 omegaValue, OpenMMRigid::Matrix3 attitudeValue) {
    $1 = &omegaValue;
    $2 = &attitudeValue;
}
%typemap(argout) (OpenMMRigid::Vector3& omega, OpenMMRigid::Matrix3& attitude) {
    Py_XDECREF($result);  // None, from the void return
    $result = Py_BuildValue("(NN)", vectorToPython(*$1), matrixToPython(*$2));
    if ($result == NULL)
        SWIG_fail;
}
%typemap(doctype) const OpenMMRigid::Vector3&, OpenMMRigid::Vector3, OpenMMRigid::Vector3& "tuple of 3 float"
%typemap(doctype) const OpenMMRigid::Matrix3&, OpenMMRigid::Matrix3& "tuple of 3 rows of 3 float"
%typemap(doctype) const char* "str"

%apply (const double* IN_ARRAY, std::size_t IN_LENGTH) { (const double* times, std::size_t numTimes) };
%apply (double* OUT_ARRAY, std::size_t OUT_LENGTH) {
    (double* omegaOut, std::size_t omegaLength),
    (double* attitudeOut, std::size_t attitudeLength)
};

%include "numerics/FreeRotor.h"

%extend OpenMMRigid::FreeRotor {
    /**
     * Evaluate evolve() at each of numTimes times, for openmmrigid.FreeRotor.evolve: omegaOut receives
     * 3 numbers per time, attitudeOut 9 (row by row).
     */
    void evolveInto(const double* times, std::size_t numTimes, double* omegaOut, std::size_t omegaLength,
                    double* attitudeOut, std::size_t attitudeLength) const {
        if (omegaLength != 3*numTimes || attitudeLength != 9*numTimes)
            throw std::invalid_argument("FreeRotor.evolve: the output arrays must hold 3 and 9 numbers per time");
        OpenMMRigid::Vector3 omega;
        OpenMMRigid::Matrix3 attitude;
        for (std::size_t k = 0; k < numTimes; k++) {
            $self->evolve(times[k], omega, attitude);
            for (int i = 0; i < 3; i++) {
                omegaOut[3*k + i] = omega[i];
                for (int j = 0; j < 3; j++)
                    attitudeOut[9*k + 3*i + j] = attitude[i][j];
            }
        }
    }
}

#ifndef OPENMMRIGID_NUMERICS_RIGIDCORE_H_
#define OPENMMRIGID_NUMERICS_RIGIDCORE_H_

/*
 * The numerics core as C++: the files in numerics/core/ compiled inside namespace OpenMMRigid.
 *
 * The core is the one implementation of each formula the dynamics needs per body (the classification
 * of principal moments, the exact free rotor, NO_SQUISH, Philox and its normal deviates, and the
 * elliptic functions they rest on) and of the Bussi thermostat's factor given its deviates, written
 * so that the same text compiles as C++ (this header), as C99 (core/CorePreludeC.h, tested by
 * tests/core/) and as OpenMM common-compute kernel source for OpenCL and CUDA
 * (core/CorePreludeCommon.h in front of the files). The rules its files follow:
 * - plain structs of doubles and ints with fixed-size arrays, functions that take pointers; no
 *   templates, overloads, references, namespaces, classes or std:: in the shared text;
 * - no allocation, no exceptions: a function that can fail returns a RigidStatus;
 * - every loop has a compile-time bound; no recursion, no function pointers, no variable-length
 *   arrays, no static or global mutable data, no long double; double precision throughout;
 * - only the standard C99 math functions (sqrt, sin, cos, atan, atanh, exp, expm1, log, tanh, sinh,
 *   cosh, fabs, fmod, rint, remainder, frexp, ldexp), which OpenCL C and CUDA provide under the same
 *   names, and HUGE_VAL;
 * - the prelude defines only RIGID_FUNCTION and RIGID_HOT_FUNCTION (the function qualifiers; "hot"
 *   asks the host compiler to inline a function into its callers, so that a hot path compiles as one
 *   function and small fixed loops are unrolled), the integer types RigidUInt32 and RigidUInt64, and
 *   the bit casts rigidDoubleBits() and rigidBitsDouble() between a double and its IEEE 754 bits.
 * The validating classes (FreeRotor, Special::, NormalStream) wrap these functions for the API.
 */

#include <cstdint>
#include <cstring>
#include <math.h>

#define RIGID_FUNCTION inline
#if defined(__GNUC__) || defined(__clang__)
#define RIGID_HOT_FUNCTION inline __attribute__((always_inline))
#else
#define RIGID_HOT_FUNCTION inline
#endif

namespace OpenMMRigid {

typedef std::uint32_t RigidUInt32;
typedef std::uint64_t RigidUInt64;

inline RigidUInt64 rigidDoubleBits(double x) {
    RigidUInt64 bits;
    std::memcpy(&bits, &x, sizeof(bits));
    return bits;
}

inline double rigidBitsDouble(RigidUInt64 bits) {
    double x;
    std::memcpy(&x, &bits, sizeof(x));
    return x;
}

#include "numerics/core/CoreBasics.h"
#include "numerics/core/CoreElliptic.h"
#include "numerics/core/CoreRotor.h"
#include "numerics/core/CoreRotorLanes.h"
#include "numerics/core/CoreNoSquish.h"
#include "numerics/core/CorePhilox.h"
#include "numerics/core/CoreThermostat.h"

} // namespace OpenMMRigid

#undef RIGID_FUNCTION
#undef RIGID_HOT_FUNCTION

#endif // OPENMMRIGID_NUMERICS_RIGIDCORE_H_

/*
 * The prelude that makes the numerics core (numerics/core/Core*.h) a C99 translation unit: include
 * this, then the core files. tests/core/ compiles them this way with -std=c99 -pedantic -Werror.
 */
#ifndef OPENMMRIGID_CORE_PRELUDE_C_H_
#define OPENMMRIGID_CORE_PRELUDE_C_H_

#include <math.h>
#include <stdint.h>
#include <string.h>

#define RIGID_FUNCTION static inline
#define RIGID_HOT_FUNCTION static inline

typedef uint32_t RigidUInt32;
typedef uint64_t RigidUInt64;

static inline RigidUInt64 rigidDoubleBits(double x) {
    RigidUInt64 bits;
    memcpy(&bits, &x, sizeof(bits));
    return bits;
}

static inline double rigidBitsDouble(RigidUInt64 bits) {
    double x;
    memcpy(&x, &bits, sizeof(x));
    return x;
}

#endif /* OPENMMRIGID_CORE_PRELUDE_C_H_ */

/*
 * The prelude that makes the numerics core (numerics/core/Core*.h) OpenMM common-compute kernel
 * source: a platform's kernel source is this file, then the core files, then its kernels, each
 * encoded into the library at build time. OpenMM compiles common kernels as OpenCL C (where
 * __OPENCL_VERSION__ is defined) or as CUDA (NVRTC); DEVICE is OpenMM's qualifier for a function
 * called from a kernel (__device__ on CUDA, nothing on OpenCL). The core needs double precision:
 * only compile it where SUPPORTS_DOUBLE_PRECISION is defined.
 */
#ifndef OPENMMRIGID_CORE_PRELUDE_COMMON_H_
#define OPENMMRIGID_CORE_PRELUDE_COMMON_H_

/* OpenCL C: the runtime compilers define __OPENCL_VERSION__, clang's offline one __OPENCL_C_VERSION__ */
#if defined(__OPENCL_VERSION__) || defined(__OPENCL_C_VERSION__)
#define RIGID_OPENCL 1
#endif

#ifndef DEVICE
#ifdef RIGID_OPENCL
#define DEVICE
#else
#define DEVICE __device__
#endif
#endif

#define RIGID_FUNCTION DEVICE
#define RIGID_HOT_FUNCTION DEVICE

#ifdef RIGID_OPENCL
#pragma OPENCL EXTENSION cl_khr_fp64 : enable
typedef uint RigidUInt32;
typedef ulong RigidUInt64;

DEVICE RigidUInt64 rigidDoubleBits(double x) {
    return as_ulong(x);
}

DEVICE double rigidBitsDouble(RigidUInt64 bits) {
    return as_double(bits);
}
#else
typedef unsigned int RigidUInt32;
typedef unsigned long long RigidUInt64;
#ifndef HUGE_VAL
#define HUGE_VAL __longlong_as_double(0x7ff0000000000000LL)
#endif

DEVICE RigidUInt64 rigidDoubleBits(double x) {
    return (RigidUInt64) __double_as_longlong(x);
}

DEVICE double rigidBitsDouble(RigidUInt64 bits) {
    return __longlong_as_double((long long) bits);
}
#endif

#endif /* OPENMMRIGID_CORE_PRELUDE_COMMON_H_ */

/*
 * The numerics core as OpenCL C kernel source, the way a common-compute platform builds it: the
 * common prelude, the core files, then a kernel. tests/CMakeLists.txt compiles this offline with
 * clang for a SPIR target (no OpenCL runtime needed); the kernels are the shape of a drift's
 * rotation (classify the moments, advance each body exactly) and the Bussi thermostat's factor.
 */
#include "numerics/core/CorePreludeCommon.h"
#include "numerics/core/CoreBasics.h"
#include "numerics/core/CoreElliptic.h"
#include "numerics/core/CoreRotor.h"
#include "numerics/core/CoreNoSquish.h"
#include "numerics/core/CorePhilox.h"
#include "numerics/core/CoreThermostat.h"

__kernel void rotateBodies(int numBodies, __global const double* moments, __global double* omega,
                           __global double* attitude, double dt, int useNoSquish, ulong seed, ulong step,
                           __global double* noise, __global int* status) {
    const int b = get_global_id(0);
    double m[3], w[3], a[3][3], l[3];
    RigidShape shape;
    RigidNormalStream stream;
    int k, j;
    if (b >= numBodies)
        return;
    for (k = 0; k < 3; k++) {
        m[k] = moments[3*b + k];
        w[k] = omega[3*b + k];
        for (j = 0; j < 3; j++)
            a[k][j] = attitude[9*b + 3*k + j];
    }
    status[b] = rigidClassifyMoments(m, &shape);
    if (status[b] == RigidStatusOk && shape.kind != RigidKindPoint) {
        if (useNoSquish) {
            for (k = 0; k < 3; k++)
                l[k] = shape.moments[k]*w[k];
            rigidNoSquishRotate(shape.moments, dt, a, l);
            for (k = 0; k < 3; k++)
                w[k] = (shape.moments[k] > 0.0 ? l[k]/shape.moments[k] : 0.0);
        }
        else
            status[b] = rigidRotorAdvance(&shape, w, a, dt);
    }
    rigidNormalStreamInitialize(&stream, seed, (uint) b, step);
    noise[b] = rigidNormalStreamNext(&stream);
    for (k = 0; k < 3; k++) {
        omega[3*b + k] = w[k];
        for (j = 0; j < 3; j++)
            attitude[9*b + 3*k + j] = a[k][j];
    }
}

/* The Bussi thermostat's factor and new kinetic energy for each case: inputs K, Kbar, c, R_1, S. */
__kernel void stochasticRescaling(int count, __global const double* inputs, __global const int* dofs, __global double* outputs) {
    const int n = get_global_id(0);
    double newKinetic;
    if (n >= count)
        return;
    outputs[2*n] = rigidStochasticRescaling(inputs[5*n], inputs[5*n + 1], dofs[n], inputs[5*n + 2], inputs[5*n + 3], inputs[5*n + 4],
                                            &newKinetic);
    outputs[2*n + 1] = newKinetic;
}

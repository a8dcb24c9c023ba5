/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The numerics core (openmmapi/include/numerics/core/) compiled as a         *
 * standalone C99 translation unit behind its C prelude, with                 *
 * -std=c99 -pedantic -Wall -Wextra -Werror (tests/CMakeLists.txt). The few   *
 * functions below expose it with C linkage to TestCoreC.cpp, which compares  *
 * every result with the C++ API (FreeRotor, Special::, noSquishRotate,       *
 * NormalStream, stochasticRescalingFactor) bit for bit: the same text must   *
 * give the same numbers.                                                     *
 * -------------------------------------------------------------------------- */

#include "numerics/core/CorePreludeC.h"
#include "numerics/core/CoreBasics.h"
#include "numerics/core/CoreElliptic.h"
#include "numerics/core/CoreRotor.h"
#include "numerics/core/CoreRotorLanes.h"
#include "numerics/core/CoreNoSquish.h"
#include "numerics/core/CorePhilox.h"
#include "numerics/core/CoreThermostat.h"

#include "CoreC.h"

static void toMatrix(const double* flat, double matrix[3][3]) {
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            matrix[i][j] = flat[3*i + j];
}

static void fromMatrix(double matrix[3][3], double* flat) {
    int i, j;
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            flat[3*i + j] = matrix[i][j];
}

int coreCClassify(const double* moments, int* kind, int* uniqueAxis, double* classified) {
    RigidShape shape;
    int k;
    const int status = rigidClassifyMoments(moments, &shape);
    if (status != RigidStatusOk)
        return status;
    *kind = shape.kind;
    *uniqueAxis = shape.uniqueAxis;
    for (k = 0; k < 3; k++)
        classified[k] = shape.moments[k];
    return status;
}

int coreCAdvance(const double* moments, double* omega, double* attitude, double t) {
    RigidShape shape;
    double a[3][3];
    int status = rigidClassifyMoments(moments, &shape);
    if (status != RigidStatusOk)
        return status;
    toMatrix(attitude, a);
    status = rigidRotorAdvance(&shape, omega, a, t);
    fromMatrix(a, attitude);
    return status;
}

int coreCAdvanceLanes(int count, const double* moments, double* omega, double* attitude, double t) {
    RigidShape shapes[RigidLanes];
    double w[RigidLanes][3], a[RigidLanes][3][3];
    int b, k, status;
    for (b = 0; b < count; b++) {
        status = rigidClassifyMoments(moments + 3*b, &shapes[b]);
        if (status != RigidStatusOk)
            return status;
        for (k = 0; k < 3; k++)
            w[b][k] = omega[3*b + k];
        toMatrix(attitude + 9*b, a[b]);
    }
    status = rigidRotorAdvanceLanes(count, shapes, w, a, t);
    for (b = 0; b < count; b++) {
        for (k = 0; k < 3; k++)
            omega[3*b + k] = w[b][k];
        fromMatrix(a[b], attitude + 9*b);
    }
    return status;
}

int coreCEvolve(const double* moments, const double* omega, const double* attitude, int representation, int count,
                const double* times, double* omegaOut, double* attitudeOut, double* parameter, int* usedRepresentation) {
    RigidShape shape;
    RigidRotor rotor;
    double a[3][3];
    int status = rigidClassifyMoments(moments, &shape), n;
    if (status != RigidStatusOk)
        return status;
    toMatrix(attitude, a);
    status = rigidRotorInitialize(&rotor, &shape, omega, a, representation, 0, 0.0, 0);
    if (status != RigidStatusOk)
        return status;
    *parameter = rotor.m;
    *usedRepresentation = rotor.representation;
    for (n = 0; n < count; n++) {
        rigidRotorEvolve(&rotor, times[n], omegaOut + 3*n, a);
        fromMatrix(a, attitudeOut + 9*n);
    }
    return status;
}

void coreCJacobi(double u, double m, double m1, double* sn, double* cn, double* dn) {
    RigidJacobi f;
    rigidJacobiElliptic(u, m, m1, &f);
    *sn = f.sn;
    *cn = f.cn;
    *dn = f.dn;
}

double coreCCarlsonRF(double x, double y, double z) {
    return rigidCarlsonRF(x, y, z);
}

double coreCCarlsonRJ(double x, double y, double z, double p) {
    return rigidCarlsonRJ(x, y, z, p);
}

double coreCEllipticK(double m1) {
    return rigidEllipticK(m1);
}

void coreCNoSquish(const double* moments, double dt, double* attitude, double* angularMomentum) {
    double a[3][3];
    toMatrix(attitude, a);
    rigidNoSquishRotate(moments, dt, a, angularMomentum);
    fromMatrix(a, attitude);
}

void coreCRaiseAngularMomentum(const double* attitude, const double* scale, double* l) {
    double a[3][3];
    toMatrix(attitude, a);
    rigidRaiseAngularMomentum(a, scale, l);
}

double coreCRotationalEnergy(const double* moments, const double* angularMomentum) {
    return rigidRotationalEnergy(moments, angularMomentum);
}

void coreCNormals(uint64_t seed, uint32_t stream, uint64_t step, int count, double* normals, double* uniform) {
    RigidNormalStream s;
    int n;
    rigidNormalStreamInitialize(&s, seed, stream, step);
    for (n = 0; n < count; n++)
        normals[n] = rigidNormalStreamNext(&s);
    *uniform = rigidNormalStreamUniform(&s);
}

void coreCPhilox(const uint32_t* counter, const uint32_t* key, uint32_t* block) {
    rigidPhilox4x32(counter, key, block);
}

double coreCStochasticRescaling(double kinetic, double targetKinetic, int dof, double c, double r1, double rest, double* newKinetic) {
    return rigidStochasticRescaling(kinetic, targetKinetic, dof, c, r1, rest, newKinetic);
}

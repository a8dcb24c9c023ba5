/*
 * The numerics core compiled as C (CoreC.c), with C linkage for TestCoreC.cpp. Matrices are flat,
 * row by row; each function returns the core's RigidStatus where the core can fail.
 */
#ifndef OPENMMRIGID_TESTS_CORE_C_H_
#define OPENMMRIGID_TESTS_CORE_C_H_

#include <stdint.h>

#ifdef __cplusplus
extern "C" {
#endif

int coreCClassify(const double* moments, int* kind, int* uniqueAxis, double* classified);
int coreCAdvance(const double* moments, double* omega, double* attitude, double t);
/** rigidRotorAdvanceLanes for count <= RigidLanes bodies: moments, omega and attitude of body b at 3b, 3b and 9b. */
int coreCAdvanceLanes(int count, const double* moments, double* omega, double* attitude, double t);
int coreCEvolve(const double* moments, const double* omega, const double* attitude, int representation, int count,
                const double* times, double* omegaOut, double* attitudeOut, double* parameter, int* usedRepresentation);
void coreCJacobi(double u, double m, double m1, double* sn, double* cn, double* dn);
double coreCCarlsonRF(double x, double y, double z);
double coreCCarlsonRJ(double x, double y, double z, double p);
double coreCEllipticK(double m1);
void coreCRaiseAngularMomentum(const double* attitude, const double* scale, double* l);
double coreCRotationalEnergy(const double* moments, const double* angularMomentum);
void coreCNoSquish(const double* moments, double dt, double* attitude, double* angularMomentum);
void coreCNormals(uint64_t seed, uint32_t stream, uint64_t step, int count, double* normals, double* uniform);
void coreCPhilox(const uint32_t* counter, const uint32_t* key, uint32_t* block);
double coreCStochasticRescaling(double kinetic, double targetKinetic, int dof, double c, double r1, double rest, double* newKinetic);

#ifdef __cplusplus
}
#endif

#endif /* OPENMMRIGID_TESTS_CORE_C_H_ */

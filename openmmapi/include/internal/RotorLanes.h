#ifndef OPENMMRIGID_ROTOR_LANES_H_
#define OPENMMRIGID_ROTOR_LANES_H_

#include "internal/windowsExportRigid.h"
#include "numerics/RigidCore.h"

namespace OpenMMRigid {

/**
 * The exact free rotation of count <= RigidLanes bodies over the time t, as the host platforms'
 * drift calls it: the core's rigidRotorAdvanceLanes(), compiled in its own translation unit
 * (openmmapi/src/RotorLanes.cpp) with the options that let the compiler turn its loops over the
 * lanes into vector instructions. Same contract as rigidRotorAdvance() for each body, and the same
 * results bit for bit; shapes, omega and attitude hold count bodies.
 */
OPENMM_EXPORT_RIGID void advanceFreeRotors(int count, const RigidShape* shapes, double omega[][3], double attitude[][3][3],
                                           double t);

/**
 * rigidReorthonormalize() on count attitudes, compiled as advanceFreeRotors() is (so the products
 * are inlined and vectorized); the results are rigidReorthonormalize()'s bit for bit.
 */
OPENMM_EXPORT_RIGID void reorthonormalizeAttitudes(int count, double attitude[][3][3]);

} // namespace OpenMMRigid

#endif // OPENMMRIGID_ROTOR_LANES_H_

#ifndef OPENMMRIGID_NUMERICS_NOSQUISH_H_
#define OPENMMRIGID_NUMERICS_NOSQUISH_H_

/*
 * The NO_SQUISH free rotation of Miller et al., J. Chem. Phys. 116, 8649 (2002), on Vector3 and
 * Matrix3: the core's rigidNoSquishRotate() (numerics/core/CoreNoSquish.h, which states the splitting
 * and its accuracy) for the host code.
 */

#include "numerics/Matrix3.h"
#include "numerics/RigidCore.h"

namespace OpenMMRigid {

/**
 * Advance a free rigid rotor by dt with the NO_SQUISH splitting.
 *
 * @param moments          the principal moments (a zero moment marks the axis of a linear body, which
 *                         carries no angular momentum and is skipped)
 * @param dt               the time step
 * @param attitude         A (lab to body), advanced in place
 * @param angularMomentum  the angular momentum in the body frame, advanced in place
 */
inline void noSquishRotate(const Vector3& moments, double dt, Matrix3& attitude, Vector3& angularMomentum) {
    double a[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            a[i][j] = attitude[i][j];
    rigidNoSquishRotate(moments.data(), dt, a, angularMomentum.data());
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            attitude[i][j] = a[i][j];
}

} // namespace OpenMMRigid

#endif // OPENMMRIGID_NUMERICS_NOSQUISH_H_

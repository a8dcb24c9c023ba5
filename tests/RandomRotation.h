#ifndef OPENMMRIGID_TESTS_RANDOM_ROTATION_H_
#define OPENMMRIGID_TESTS_RANDOM_ROTATION_H_

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * A uniformly distributed rotation, shared by the tests (TestFreeRotor,      *
 * TestCoreC and the integrator's test systems).                              *
 * -------------------------------------------------------------------------- */

#include "numerics/Matrix3.h"
#include <cmath>

namespace RigidBodyTestSupport {

/**
 * The rotation matrix of a random unit quaternion (a, b, c, d): four standard normal deviates drawn
 * from normal(), normalized, which makes the rotation uniform on SO(3) (Shoemake's construction).
 */
template <class Normal>
OpenMMRigid::Matrix3 randomRotation(Normal&& normal) {
    double a = normal(), b = normal(), c = normal(), d = normal();
    double n = std::sqrt(a*a + b*b + c*c + d*d);
    a /= n; b /= n; c /= n; d /= n;
    return {{{a*a + b*b - c*c - d*d, 2*(b*c - a*d), 2*(b*d + a*c)},
             {2*(b*c + a*d), a*a - b*b + c*c - d*d, 2*(c*d - a*b)},
             {2*(b*d - a*c), 2*(c*d + a*b), a*a - b*b - c*c + d*d}}};
}

} // namespace RigidBodyTestSupport

#endif

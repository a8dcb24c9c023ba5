#ifndef OPENMMRIGID_SPLITTING_H_
#define OPENMMRIGID_SPLITTING_H_

#include "RigidBodyOptions.h"
#include "internal/windowsExportRigid.h"

namespace OpenMMRigid {

/**
 * The stages of one step of a RigidBodyIntegrator splitting. Every splitting is a palindrome that
 * starts and ends with a kick:
 *
 *     kick(a_0 dt) drift(b_0 dt) kick(a_1 dt) drift(b_1 dt) ... drift(b_{s-1} dt) kick(a_s dt)
 *
 * kick(h) adds h times the force (and torque) to each body's linear (and angular) momentum and to
 * each free particle's momentum; drift(h) is the exact free motion of every body and free particle
 * for a time h (with the rotation method of the integrator, and the constraints among free
 * particles). The a_i and b_i are fractions of the step: each set sums to 1, and a_i = a_{s-i},
 * b_i = b_{s-1-i}, which makes the step time-reversible. The forces for a_0 are those at the end of
 * the previous step, so a step costs s force evaluations, one after each drift.
 *
 * The coefficients are the papers' (see splittingScheme() in Splitting.cpp); the tests measure each
 * scheme's order.
 */
struct SplittingScheme {
    static const int MaxDrifts = 4;
    /** The name of the RigidBodyOptions::Splitting value, for messages. */
    const char* name;
    /** s: the number of drifts, which is the number of force evaluations per step. */
    int numDrifts;
    /** a_0 ... a_s. */
    double kicks[MaxDrifts + 1];
    /** b_0 ... b_{s-1}. */
    double drifts[MaxDrifts];
};

/** The number of splittings; RigidBodyOptions::Splitting takes the values 0 to NumSplittings - 1. */
const int NumSplittings = 4;

/**
 * The stages of a splitting.
 *
 * @throws OpenMMException if the value is not a RigidBodyOptions::Splitting, naming it and the valid ones
 */
OPENMM_EXPORT_RIGID const SplittingScheme& splittingScheme(RigidBodyOptions::Splitting splitting);

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_SPLITTING_H_*/

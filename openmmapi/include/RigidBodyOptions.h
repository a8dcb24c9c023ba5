#ifndef OPENMMRIGID_RIGIDBODYOPTIONS_H_
#define OPENMMRIGID_RIGIDBODYOPTIONS_H_

namespace OpenMMRigid {

/**
 * The choices that shape a rigid-body step, apart from the integrators that offer them, so that the
 * step sequence and the platforms can name them without the integrators' headers. The integrators
 * give them their public names: RigidBodyIntegratorBase::Exact, RigidBodyIntegrator::Omelyan2, ...
 */
struct RigidBodyOptions {
    /** How the orientation of each body is advanced during the free drift. */
    enum RotationMethod {
        /** The exact torque-free motion (van Zon and Schofield, 2007). */
        Exact = 0,
        /** The symplectic NO_SQUISH splitting of the free rotation (Miller et al., 2002). */
        NoSquish = 1
    };
    /** The sequence of kicks and drifts of a RigidBodyIntegrator step (internal/Splitting.h has the coefficients). */
    enum Splitting {
        /** Velocity Verlet: kick dt/2, drift dt, kick dt/2. Second order, one force evaluation per step. */
        Verlet = 0,
        /**
         * The optimized two-stage scheme of Omelyan, Mryglod and Folk (2002): kick lambda dt, drift dt/2,
         * kick (1 - 2 lambda) dt, drift dt/2, kick lambda dt with lambda = 0.1931833275037836. Second
         * order with a smaller error than Verlet at the same step; two force evaluations per step.
         */
        Omelyan2 = 1,
        /**
         * Yoshida's triple jump: Verlet steps of w1 dt, w0 dt and w1 dt with w1 = 1/(2 - 2^(1/3)) and
         * w0 = 1 - 2 w1 (the middle one backwards in time). Fourth order, with either rotation method
         * and with constraints; three force evaluations per step.
         */
        Yoshida4 = 2,
        /**
         * The optimized fourth-order Forest-Ruth-like scheme of Omelyan, Mryglod and Folk (2002), in
         * its velocity form: five kicks and four drifts; four force evaluations per step. Fourth order
         * when the drifts are exact: with NoSquish, or for free particles held by constraints (which
         * drift by SHAKE), it is second order. Yoshida4 is fourth order in both cases.
         */
        Omelyan4 = 3
    };
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYOPTIONS_H_*/

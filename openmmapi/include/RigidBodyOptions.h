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
    /**
     * The sequence of kicks and drifts of a RigidBodyIntegrator step. RigidBodyIntegrator::setSplitting()
     * describes each; openmmapi/src/Splitting.cpp has the coefficients.
     */
    enum Splitting {
        /** Velocity Verlet: kick dt/2, drift dt, kick dt/2. Second order, one force evaluation per step. */
        Verlet = 0,
        /** The optimized two-stage scheme of Omelyan, Mryglod and Folk (2002): second order, two force evaluations per step. */
        Omelyan2 = 1,
        /** Yoshida's fourth-order triple jump: three force evaluations per step. */
        Yoshida4 = 2,
        /** The optimized fourth-order Forest-Ruth-like scheme of Omelyan, Mryglod and Folk (2002): four force evaluations per step. */
        Omelyan4 = 3
    };
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYOPTIONS_H_*/

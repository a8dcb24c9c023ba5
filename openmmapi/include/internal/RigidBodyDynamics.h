#ifndef OPENMMRIGID_RIGIDBODYDYNAMICS_H_
#define OPENMMRIGID_RIGIDBODYDYNAMICS_H_

#include "RigidBodyIntegratorBase.h"
#include "internal/RigidBodySystem.h"
#include "internal/windowsExportRigid.h"
#include "numerics/Matrix3.h"
#include "openmm/Vec3.h"
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace OpenMM {
class ReferenceConstraintAlgorithm;
class ThreadPool;
}

namespace OpenMMRigid {

/**
 * The physics of a step of RigidBodyIntegrator or RigidBodyLangevinIntegrator on plain arrays of
 * positions, velocities and forces (every platform's kernel extracts its arrays and calls this
 * class). A step is a sequence of stages (internal/Splitting.h; for the Langevin integrator
 * kickAndDrift, thermalize, drift, closingKick) with a force evaluation, which the caller performs,
 * after each drift:
 *
 *   kickAndDrift(a, b):  for each body, a kick V += F a / M, L += tau a (lab frame) followed by the
 *                        free drift R += V b and the rotation of the attitude for a time b (exact
 *                        free rotor or NO_SQUISH), and the particles placed at R + A^T b_i; free
 *                        particles: kick and drift, with their constraints applied to positions.
 *   closingKick(a):      the last kick of the step, after which the rigid velocities
 *                        v = V + omega x (r - R) are written to the body particles; free particles:
 *                        kick and velocity constraints.
 *   drift(b):            the free drift alone (the second half drift of a Langevin step).
 *   thermalize(c, kT):   the exact Ornstein-Uhlenbeck step of the momenta (see below).
 *   scaleVelocities(a):  every momentum times a (a thermostat's rescaling, after the closing kick).
 *
 * Each is one pass over the bodies (on the thread pool, if there is one). Between them the body
 * momenta live in this class; the particle velocities of the bodies are written once per step.
 * (The free particles' velocities are constrained only after the closing kick: a velocity projection
 * before a drift would change nothing, since the drift's position constraints absorb any velocity
 * component along the constraint gradients.)
 *
 * Forces and torques are summed over the massive particles of each body only: the force on a virtual
 * site has already been distributed to its parents.
 */
class OPENMM_EXPORT_RIGID RigidBodyDynamics {
public:
    explicit RigidBodyDynamics(RigidBodySystem& system);
    ~RigidBodyDynamics();
    /**
     * Run the per-body work on these threads (the CPU platform's); null runs it serially.
     */
    void setThreadPool(OpenMM::ThreadPool* pool);
    /**
     * Set the periodic box the positions live in (the three reduced box vectors, in nm), or null if
     * the System is not periodic. Every fit assembles each body from the periodic images of its
     * particles nearest its first particle, so a molecule split by the boundary is taken whole.
     */
    void setPeriodicBox(const OpenMM::Vec3* vectors);
    /**
     * Set the largest distance, in nm, a body or free particle may move in one drift: further is an
     * unstable simulation, and the drift stops with an OpenMMException saying so.
     *
     * @param limit        the distance (infinity for none)
     * @param description  what the distance is, for the message (a string literal, e.g. "the nonbonded cutoff")
     */
    void setDisplacementLimit(double limit, const char* description);
    /**
     * Give every explicit body that has no shape yet the shape it has in these positions, where
     * they place its particles apart and at finite coordinates (the others wait for later positions).
     * A constraint inside a body that the shape contradicts by more than 1 % is an OpenMMException.
     */
    void captureShapes(const std::vector<OpenMM::Vec3>& positions);
    /** Whether every body has its shape (explicit bodies get theirs from the first positions set). */
    bool allShapesKnown() const;
    /**
     * Fit every body to the positions (mass-weighted least squares, Horn's method), then replace the
     * body particles' positions by the rigid ones and their velocities by the rigid motion with the
     * same linear and angular momentum. Explicit bodies without a shape take it from these positions.
     */
    void project(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    /**
     * project() for the velocities alone, when the bodies are already fitted to the positions (the
     * velocities were set, the positions are those of the last fit or step).
     */
    void projectVelocities(std::vector<OpenMM::Vec3>& velocities);
    /**
     * One stage of a step: kick every body and free particle by the forces, then let it move freely.
     * The body momenta are those the previous stage left, unless something other than this class
     * changed the body particles' velocities since closingKick() or project() wrote them (a
     * CMMotionRemover, which does so without telling the integrator): then they are taken from
     * the particles.
     *
     * @param kick                 the time by which the forces change the momenta, in ps
     * @param drift                the time of the free motion, in ps (may be negative)
     * @param method               how the bodies rotate during the drift
     * @param constraintTolerance  the tolerance of the constraints among free particles
     */
    void kickAndDrift(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                      const std::vector<OpenMM::Vec3>& forces, double kick, double drift,
                      RigidBodyIntegratorBase::RotationMethod method, double constraintTolerance);
    /**
     * A free drift without a kick: kickAndDrift() with no forces.
     *
     * @param drift                the time of the free motion, in ps (may be negative)
     * @param method               how the bodies rotate during the drift
     * @param constraintTolerance  the tolerance of the constraints among free particles
     */
    void drift(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double drift,
               RigidBodyIntegratorBase::RotationMethod method, double constraintTolerance);
    /**
     * The Ornstein-Uhlenbeck stage of a Langevin step: the exact solution, over the time whose
     * damping factor is c, of dp = -gamma p dt + sqrt(2 gamma m kT) dW for every momentum p with
     * mass (or moment) m. For each body, with xi independent standard normal deviates,
     *
     *     V   <- c V   + sqrt((1 - c^2) kT / M) xi          (each lab-frame component of the centre's velocity)
     *     L_k <- c L_k + sqrt((1 - c^2) I_k kT) xi_k        (each principal axis with I_k > 0)
     *
     * where L_k is the angular momentum in the body's principal frame, whose canonical distribution
     * is Gaussian with variance I_k kT; the axis of a linear body (I_0 = 0) carries none, and a
     * single-particle body has no rotation. The xi_k are the body-frame components of a lab-frame
     * standard normal vector, so that the noise does not depend on the choice of principal axes. Free particles: v <- c v + sqrt((1 - c^2) kT / m) xi,
     * then the velocity constraints among them. Body particle velocities are written by the closing
     * kick, as always.
     *
     * Body b draws its six deviates (three for V, three for L) from NormalStream(seed, b, step);
     * free particle i (in the order of RigidBodySystem::getFreeParticles()) its three from
     * NormalStream(seed, numBodies + i, step). The result depends on seed and step only, whatever
     * the threads.
     *
     * @param c                    exp(-friction dt), in [0, 1]
     * @param kT                   the thermal energy, in kJ/mol
     * @param seed                 the key of the random numbers
     * @param step                 the counter of the random numbers: a different value for every call
     * @param constraintTolerance  the tolerance of the constraints among free particles
     */
    void thermalize(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double c, double kT,
                    uint64_t seed, uint64_t step, double constraintTolerance);
    /**
     * Scale every momentum (bodies' linear and angular, free particles') by alpha, after the closing
     * kick: the stochastic velocity rescaling of RigidBodyIntegrator's thermostat. The velocity
     * constraints among free particles stay satisfied.
     */
    void scaleVelocities(std::vector<OpenMM::Vec3>& velocities, double alpha);
    /**
     * The last kick of a step: kick every body and free particle by the forces, write the bodies'
     * rigid velocities to their particles and apply the velocity constraints of the free particles.
     *
     * @param kick                 the time by which the forces change the momenta, in ps
     * @param constraintTolerance  the tolerance of the constraints among free particles
     */
    void closingKick(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                     const std::vector<OpenMM::Vec3>& forces, double kick, double constraintTolerance);
    /**
     * Split the kinetic energy of the velocities: the translation of the bodies' centres plus the free
     * particles, and the rest of the bodies' kinetic energy (their rotation, for rigid velocities).
     */
    void computeKineticEnergies(const std::vector<OpenMM::Vec3>& velocities, double& translational, double& rotational) const;
private:
    struct BodyState {
        Vector3 center, velocity, angularMomentum;  // angular momentum in the lab frame
        Matrix3 attitude;                           // lab to body
    };
    void forEachBody(const std::function<void(int)>& task);
    /** Take body b's momenta from its particles if their velocities are not the ones this class wrote. */
    void refreshMomenta(int b, const std::vector<OpenMM::Vec3>& positions, const std::vector<OpenMM::Vec3>& velocities);
    /** The total force and the torque about the centre on a body. */
    void forceAndTorque(const RigidBody& body, const BodyState& state, const std::vector<OpenMM::Vec3>& positions,
                        const std::vector<OpenMM::Vec3>& forces, OpenMM::Vec3& force, OpenMM::Vec3& torque) const;
    /** kickAndDrift() with forces, drift() without (forces null). */
    void advance(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                 const std::vector<OpenMM::Vec3>* forces, double kick, double drift,
                 RigidBodyIntegratorBase::RotationMethod method, double constraintTolerance);
    /** The free motion of body b for a time h, and its particles placed accordingly. */
    void driftBody(int b, double h, RigidBodyIntegratorBase::RotationMethod method, std::vector<OpenMM::Vec3>& positions);
    /**
     * Give every body without a shape the one it has in these positions; those the positions cannot
     * shape raise the error if strict, else wait.
     */
    void shapeBodies(const std::vector<OpenMM::Vec3>& positions, bool strict);
    /**
     * Give body b the shape it has in the positions. If they cannot give one (non-finite, or every
     * particle at one point), throw if strict, else return false.
     */
    bool shapeBody(int b, const std::vector<OpenMM::Vec3>& positions, bool strict);
    /** The centre of mass of a body's assembled positions, and the positions about it. */
    void centre(const RigidBody& body, const std::vector<OpenMM::Vec3>& whole, Vector3& center, std::vector<Vector3>& centred) const;
    /** The positions of a body's particles, each at the periodic image nearest the first particle. */
    void assemble(const RigidBody& body, const std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& whole) const;
    /** Throw the "unstable" error if a drift would move a body or free particle further than the limit. */
    void checkDisplacement(const char* what, int index, double distance, double drift) const;
    void rotate(const RigidBody& body, BodyState& state, double dt, RigidBodyIntegratorBase::RotationMethod method) const;
    void fitBody(int index, std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    /** Replace body index's particle velocities by the rigid motion with their linear and angular momentum. */
    void projectBodyVelocities(int index, std::vector<OpenMM::Vec3>& velocities);
    RigidBodySystem& system;
    bool periodic;
    OpenMM::Vec3 box[3];
    double displacementLimit;
    const char* displacementLimitName;
    std::vector<BodyState> states;
    std::vector<double> inverseMasses;
    std::vector<OpenMM::Vec3> previousPositions;
    /** The body particles' velocities as this class last wrote or read them, consistent with the states. */
    std::vector<OpenMM::Vec3> writtenVelocities;
    std::unique_ptr<OpenMM::ReferenceConstraintAlgorithm> constraints;
    OpenMM::ThreadPool* threads;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYDYNAMICS_H_*/

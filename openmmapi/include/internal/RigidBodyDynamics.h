#ifndef OPENMMRIGID_RIGIDBODYDYNAMICS_H_
#define OPENMMRIGID_RIGIDBODYDYNAMICS_H_

#include "RigidBodyOptions.h"
#include "internal/RigidBodySystem.h"
#include "internal/windowsExportRigid.h"
#include "numerics/Matrix3.h"
#include "openmm/Vec3.h"
#include <cstdint>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * Threads for the per-body loops of the host stages, supplied by the platform (the CPU platform's
 * thread pool); without one the loops run serially.
 */
class OPENMM_EXPORT_RIGID HostThreads {
public:
    virtual ~HostThreads() {
    }
    virtual int getNumThreads() const = 0;
    /** Run task(thread) once on each thread, thread = 0 ... getNumThreads() - 1, and wait for all. */
    virtual void execute(const std::function<void(int thread)>& task) = 0;
};

/**
 * Whether one loop that a stage repeats (every step, on the same number of items) runs on the host
 * threads or serially: whichever its own recent runs say is faster. Waking a pool's threads and
 * waiting for them costs a round trip that depends on the machine (75 to 85 us for the CPU
 * platform's pool on the 2-core virtual machine of 2026-12-04) and on its load (another program on a
 * core can make the threads slower than one), so no fixed count of items decides it. The loop runs
 * serially first, then once on the threads; after that it takes the faster by the median of the
 * last `Window` runs of each, and every so often runs once the other way (a probe): a probe faster
 * than that median switches, a slower one doubles the interval to the next probe (from
 * `FirstProbeInterval` to `LastProbeInterval` runs), so that a losing probe costs a vanishing share
 * of the time while a change of load is still noticed. Which way a loop runs must change no result:
 * only loops whose items are independent use this.
 */
class OPENMM_EXPORT_RIGID ThreadedLoopChoice {
public:
    static const int Window = 3;
    static const int FirstProbeInterval = 16;
    static const int LastProbeInterval = 4096;
    ThreadedLoopChoice();
    /** Whether the next run should use the threads. */
    bool useThreads() const;
    /** Learn from a run that took `seconds`, on the threads or not (as useThreads() said). */
    void record(bool threaded, double seconds);
private:
    /** The median of the last (at most Window) runs serially (threaded false) or on the threads. */
    double median(bool threaded) const;
    double samples[2][Window];
    int numSamples[2], nextSlot[2];
    long long runs, nextProbe;
    int probeInterval;
    bool preferThreads;
};

/**
 * The constraints among free particles, solved on host arrays: supplied by the platform (the
 * Reference platform's solver), since the step sequence only says when to apply them.
 */
class OPENMM_EXPORT_RIGID HostConstraints {
public:
    virtual ~HostConstraints() {
    }
    /**
     * Move the positions `updated` so that the constraints hold, along the constraint directions of
     * `before` (SHAKE-like), to the relative tolerance.
     */
    virtual void apply(std::vector<OpenMM::Vec3>& before, std::vector<OpenMM::Vec3>& updated,
                       std::vector<double>& inverseMasses, double tolerance) = 0;
    /** Remove the velocity components along the constraints at these positions. */
    virtual void applyToVelocities(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                                   std::vector<double>& inverseMasses, double tolerance) = 0;
};

/**
 * The stages of a rigid-body step (internal/StepSequence.h says in which order they run) carried out
 * on host arrays of positions, velocities and forces: what the Reference and CPU kernels do. The
 * body topology is read, never changed, except that the first fit settles the handedness of shapes
 * built from distances.
 *
 *   kickAndDrift(a, b):  for each body, a kick V += F a / M, L += tau a (lab frame) followed by the
 *                        free drift R += V b and the rotation of the attitude for a time b (exact
 *                        free rotor or NO_SQUISH), and the particles placed at R + A^T b_i; free
 *                        particles: kick and drift, with their constraints applied to positions.
 *                        A kick of 0 reads no forces (the second half drift of a Langevin step).
 *   closingKick(a):      the last kick of the step, after which the rigid velocities
 *                        v = V + omega x (r - R) are written to the body particles; free particles:
 *                        kick and velocity constraints. A kick of 0 reads no forces (the end of a
 *                        Langevin step, whose velocities are half a step behind the positions).
 *   thermalize(c, kT):   the exact Ornstein-Uhlenbeck step of the momenta (see below).
 *   rescaleMomenta(...): the Bussi thermostat's step (after the closing kick): the kinetic energy,
 *                        the factor alpha of eq. (A7) from the deviates given, every momentum times
 *                        alpha (scaleMomenta(alpha)).
 *
 * Each is one pass over the bodies (on the threads, if there are any). Between them the body
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
    /**
     * @param system       the body topology (kept by reference)
     * @param threads      the threads of the per-body loops, or null to run them serially (kept by reference)
     * @param constraints  the solver of the constraints among free particles; required by the stages that
     *                     move free particles if the topology has any (getFreeConstraintSystem()), else
     *                     may be null, as for a platform that uses this class only for its fits (kept by reference)
     */
    RigidBodyDynamics(RigidBodySystem& system, HostThreads* threads, HostConstraints* constraints);
    /** Set the periodic box and the largest plausible drift (see StepGeometry), before a step or a fit. */
    void setGeometry(const StepGeometry& geometry);
    /**
     * Fit every body to the positions (mass-weighted least squares, Horn's method), then replace the
     * body particles' positions by the rigid ones and their velocities by the rigid motion with the
     * same linear and angular momentum. Every body must have its shape.
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
     * @param kick                 the time by which the forces change the momenta, in ps (0: forces not read)
     * @param drift                the time of the free motion, in ps (may be negative; 0: a kick alone,
     *                             which neither moves nor constrains anything)
     * @param method               how the bodies rotate during the drift
     * @param constraintTolerance  the tolerance of the constraints among free particles
     * @param set                  the bodies that take part (the free particles take part unless it is SlowBodies)
     */
    void kickAndDrift(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities,
                      const std::vector<OpenMM::Vec3>& forces, double kick, double drift,
                      RigidBodyOptions::RotationMethod method, double constraintTolerance, BodySet set = AllBodies);
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
     * standard normal vector, so that the noise does not depend on the choice of principal axes.
     * Free particles: v <- c v + sqrt((1 - c^2) kT / m) xi, then the velocity constraints among
     * them. Body particle velocities are written by the closing kick, as always. Returns the heat,
     * the kinetic energy the stage added (as computeKineticEnergies() would sum it before and after:
     * each body's from its momenta, in its own, possibly raised, moments).
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
    double thermalize(std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities, double c, double kT,
                      uint64_t seed, uint64_t step, double constraintTolerance);
    /**
     * Scale every momentum (bodies' linear and angular, free particles') by alpha, after the closing
     * kick: the stochastic velocity rescaling of RigidBodyIntegrator's thermostat. The velocity
     * constraints among free particles stay satisfied.
     */
    void scaleMomenta(std::vector<OpenMM::Vec3>& velocities, double alpha);
    /**
     * One step of RigidBodyIntegrator's Bussi thermostat, after the closing kick: the kinetic energy
     * K (computeKineticEnergies(), translation plus rotation), the factor alpha and the new kinetic
     * energy K' from rigidStochasticRescaling() (numerics/core/CoreThermostat.h: Bussi, Donadio and
     * Parrinello (2007), eqs. (A7) and (A8)) with the deviates given, then scaleMomenta(alpha).
     *
     * @param targetKinetic  Kbar = N_f kT/2, in kJ/mol
     * @param dof            N_f, the number of degrees of freedom
     * @param c              exp(-dt/tau)
     * @param r1             R_1 of eq. (A7), a standard normal deviate
     * @param rest           S of eq. (A7), a chi-squared deviate with N_f - 1 degrees of freedom
     * @param kinetic        set to K, in kJ/mol
     * @param newKinetic     set to K', in kJ/mol
     */
    void rescaleMomenta(std::vector<OpenMM::Vec3>& velocities, double targetKinetic, int dof, double c, double r1, double rest,
                        double& kinetic, double& newKinetic);
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
     * Write every body's rigid velocities v = V + omega x (r - R), from the momenta the stages have
     * made so far, to its particles (and record them as written, so that the next stage keeps those
     * momenta): within a step, before computeKineticEnergies() is asked for the energy of the momenta
     * now (the heat of a Langevin step's Ornstein-Uhlenbeck stage). Free particles' velocities are
     * always current. Changes no momentum.
     */
    void writeBodyVelocities(const std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    /**
     * Split the kinetic energy of the velocities: the translation of the bodies' centres plus the free
     * particles, and the rest of the bodies' kinetic energy (their rotation, for rigid velocities).
     */
    void computeKineticEnergies(const std::vector<OpenMM::Vec3>& velocities, double& translational, double& rotational) const;
    /**
     * Split as computeKineticEnergies() splits it: the kinetic energy the momenta would have after a
     * kick of `kick` by the forces, each body's from its state (V + kick F/M, and L + kick tau in its
     * own moments: the energy of the Hamiltonian integrated), the free particles' from their
     * velocities kicked and projected onto the constraints among them. Changes no state.
     */
    void computeKickedKineticEnergies(const std::vector<OpenMM::Vec3>& positions, const std::vector<OpenMM::Vec3>& velocities,
                                      const std::vector<OpenMM::Vec3>& forces, double kick, double constraintTolerance,
                                      double& translational, double& rotational);
    /** The kinetic energy sum m v^2 / 2 over every particle. */
    double computeKineticEnergy(const std::vector<OpenMM::Vec3>& velocities) const;
    /** The number of doubles of one body's state in getStates(). */
    static const int StateSize = 18;
    /**
     * Every body's state, StateSize doubles each: centre, velocity, angular momentum (lab frame),
     * attitude (lab to body, row-major). A platform that keeps the states itself (on a device) takes
     * them from here after a fit, and gives them back with setStates() before projectVelocities().
     */
    void getStates(std::vector<double>& states) const;
    void setStates(const std::vector<double>& states);
    /**
     * setStates() with the positions and velocities they were saved with (a checkpoint's), if the
     * states place every body particle exactly where the positions have it (else nothing changes and
     * false is returned: the bodies are then to be fitted). The body particles' velocities are
     * recorded as this class's own, so that the next stage keeps the states' momenta.
     */
    bool restoreStates(const std::vector<double>& states, const std::vector<OpenMM::Vec3>& positions,
                       const std::vector<OpenMM::Vec3>& velocities);
    /**
     * The text of the error that stops an unstable step: a body or free particle ("body", "particle")
     * that would move `distance` (not finite: to a non-finite position) in a drift of `drift` ps.
     */
    static std::string unstableMessage(const std::string& className, const char* what, int index, double distance, double drift,
                                       const StepGeometry& geometry);
    /** The text of the error for a body whose velocity, force or torque is not finite. */
    static std::string notFiniteMessage(const std::string& className, int body);
    /**
     * to = from for an array of all the particles, copied in ranges on the threads: the per-step
     * copies a host kernel keeps (the positions it wrote, the velocities a step starts from), so that
     * they do not run on one thread while the rest of the step runs on all.
     */
    void copyParticleArray(const std::vector<OpenMM::Vec3>& from, std::vector<OpenMM::Vec3>& to) const;
    /** Whether two particle arrays are equal element by element (a NaN equals nothing), compared in ranges on the threads. */
    bool particleArraysEqual(const std::vector<OpenMM::Vec3>& a, const std::vector<OpenMM::Vec3>& b) const;
private:
    struct BodyState {
        Vector3 center, velocity, angularMomentum;  // angular momentum in the lab frame
        Matrix3 attitude;                           // lab to body
    };
    /** The internal error of a stage that moves free particles with constraints but was given no solver. */
    void requireConstraints() const;
    /** The first exception thrown by any of several tasks, kept to be rethrown by one thread. */
    class FirstError {
    public:
        /**
         * Run task(); if it throws, keep the first such error. Returns whether task() completed. A
         * template, not a std::function: it runs once per body and stage, and a std::function of a
         * closure with many captures allocates.
         */
        template <class Task>
        bool guard(Task&& task) {
            try {
                task();
                return true;
            }
            catch (const std::exception& e) {
                keep(e.what());
                return false;
            }
        }
        /** Throw the kept error, if any, as an OpenMMException. */
        void rethrow() const;
    private:
        void keep(const char* message);
        std::mutex errorLock;
        std::string error;
    };
    /** The loops that may run on the threads, each with its own ThreadedLoopChoice. */
    enum HostLoop {DriftLoop, ClosingKickLoop, ThermalizeLoop, BodyVelocitiesLoop, CopyLoop, CompareLoop, NumHostLoops};
    /** Run task(b) for every body, on the threads where they pay; the first exception is rethrown here. */
    void forEachBody(HostLoop loop, const std::function<void(int)>& task);
    /**
     * Run task(begin, end, error) for consecutive groups of at most `size` bodies, on the threads where
     * they pay; the task guards each body's work with `error`, whose first exception is rethrown here.
     */
    void forEachBodyGroup(HostLoop loop, int count, int size, const std::function<void(int begin, int end, FirstError& error)>& task);
    /**
     * Run task(thread, begin, end) over 0 ... count - 1: split into one contiguous range per thread
     * where the loop's ThreadedLoopChoice says the threads are faster, else serially as one range
     * (always without threads, and below 64 bodies or 4096 particles).
     */
    void forEachRange(HostLoop loop, int count, const std::function<void(int thread, int begin, int end)>& task) const;
    /** Record body b's particle velocities as those this class wrote or read (writtenVelocities; only body particles' are read). */
    void recordWrittenVelocities(int b, const std::vector<OpenMM::Vec3>& velocities);
    /** Take body b's momenta from its particles if their velocities are not the ones this class wrote. */
    void refreshMomenta(int b, const std::vector<OpenMM::Vec3>& positions, const std::vector<OpenMM::Vec3>& velocities);
    /** The total force and the torque about the centre on body b. */
    void forceAndTorque(int b, const std::vector<OpenMM::Vec3>& positions, const std::vector<OpenMM::Vec3>& forces,
                        OpenMM::Vec3& force, OpenMM::Vec3& torque) const;
    /** Place body b's particles at R + A^T b_i. */
    void placeParticles(int b, std::vector<OpenMM::Vec3>& positions) const;
    /** Throw the "unstable" error if a drift would move a body or free particle further than the limit. */
    void checkDisplacement(const char* what, int index, double distance, double drift) const;
    /** Whether body b's free rotation is the exact one under `method` (every body but a point, except that NO_SQUISH turns non-linear bodies). */
    bool rotatesExactly(int b, RigidBodyOptions::RotationMethod method) const;
    /** NO_SQUISH's free rotation of body b for a time dt. */
    void rotateNoSquish(int b, double dt);
    /** The exact free rotation for a time dt of count <= RigidLanes bodies, side by side (rigidRotorAdvanceLanes). */
    void rotateExactly(int count, const int* bodies, double dt);
    void fitBody(int b, std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    /** Replace body b's particle velocities by the rigid motion with their linear and angular momentum. */
    void projectBodyVelocities(int b, std::vector<OpenMM::Vec3>& velocities);
    /** Write body b's rigid velocities v = V + omega x (r - R) to its particles. */
    void writeRigidVelocities(int b, const std::vector<OpenMM::Vec3>& positions, std::vector<OpenMM::Vec3>& velocities);
    /** The body-frame angular velocity I^-1 L of body b; a zero moment (the axis of a linear body) carries none. */
    Vector3 bodyAngularVelocity(int b, const Vector3& bodyAngularMomentum) const;
    RigidBodySystem& system;
    HostThreads* threads;
    mutable ThreadedLoopChoice loopChoices[NumHostLoops];
    HostConstraints* constraints;
    StepGeometry geometry;
    std::vector<BodyState> states;
    /** Each body's heat in the last thermalize(), summed in body order after the threads. */
    std::vector<double> bodyHeat;
    std::vector<double> inverseMasses;
    std::vector<OpenMM::Vec3> previousPositions;
    /** The body particles' velocities as this class last wrote or read them, consistent with the states (the entries of other particles are not kept). */
    std::vector<OpenMM::Vec3> writtenVelocities;
    /**
     * Scratch for the fits, so that a projection (every barostat move) allocates nothing: one body's
     * assembled positions, their offsets from its centre, its shape (mirrored when its handedness is
     * open), its masses, and the lab-frame arms of its particles.
     */
    std::vector<OpenMM::Vec3> whole;
    std::vector<Vector3> centred, shape, arms;
    std::vector<double> weights;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYDYNAMICS_H_*/

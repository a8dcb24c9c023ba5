#ifndef OPENMMRIGID_RIGIDBODYKERNELS_H_
#define OPENMMRIGID_RIGIDBODYKERNELS_H_

#include "RigidBodyOptions.h"
#include "internal/RigidBodySystem.h"
#include "openmm/KernelImpl.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <cstdint>
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * The platform's part of a rigid-body step: the stages, carried out on the platform's own copy of
 * the positions, velocities and forces, and the projections that keep the bodies coherent with
 * the Context. What runs in which order is not the kernel's business: the step sequence
 * (internal/StepSequence.h) calls the stages, for both integrators, on every platform; the kernel
 * holds the bodies' frames and momenta between the stages and no physics of its own.
 *
 * Every stage starts where the previous one ended: positions, velocities and the bodies' state are
 * the kernel's, and forces are the Context's last evaluation (the step sequence evaluates them).
 */
class IntegrateRigidBodyStepKernel : public OpenMM::KernelImpl {
public:
    static std::string Name() {
        return "IntegrateRigidBodyStep";
    }
    IntegrateRigidBodyStepKernel(std::string name, const OpenMM::Platform& platform) : OpenMM::KernelImpl(name, platform) {
    }
    /**
     * Set up the bodies' state for this body topology (built once per Context by the integrator, and
     * kept alive by it for the kernel's lifetime).
     */
    virtual void initialize(OpenMM::ContextImpl& context, RigidBodySystem& bodies) = 0;
    /** The periodic box and the largest plausible drift, before a projection. */
    virtual void setGeometry(OpenMM::ContextImpl& context, const StepGeometry& geometry) = 0;
    /**
     * Before the first stage of a step: setGeometry(), and remember the positions and velocities
     * the step starts from, for abandonStep().
     */
    virtual void beginStep(OpenMM::ContextImpl& context, const StepGeometry& geometry) = 0;
    /**
     * After a stage failed (an unstable simulation): put back the positions and velocities the step
     * started from, so that the Context holds the last good state.
     */
    virtual void abandonStep(OpenMM::ContextImpl& context) = 0;
    /**
     * Re-fit the bodies to the context's positions, project its velocities onto rigid motion, and
     * place the virtual sites. Every body has its shape. Called when positions changed from outside
     * the integrator.
     */
    virtual void project(OpenMM::ContextImpl& context) = 0;
    /**
     * Project the context's velocities onto rigid motion, the bodies staying as fitted (their
     * positions are current: see positionsAreCurrent()). Called when velocities were set.
     */
    virtual void projectVelocities(OpenMM::ContextImpl& context) = 0;
    /**
     * Whether the context's positions are still those this kernel last wrote (by a step or a
     * projection): if not, something moved the particles without telling the integrator (another
     * integrator of a CompoundIntegrator, the energy minimizer, applyConstraints), and the bodies
     * must be fitted again before the next step.
     */
    virtual bool positionsAreCurrent(OpenMM::ContextImpl& context) const = 0;
    /**
     * Keep a copy of the forces of the Context's last evaluation as force set `slot` (0, 1, ...), for
     * the kicks of multiple time steps: each level's forces outlive the evaluations of the others. The
     * copy is valid until the atoms are reordered, which a platform does only in beforeLastForces(),
     * before the step's last evaluations (of every level).
     */
    virtual void saveForces(OpenMM::ContextImpl& context, int slot) = 0;
    /**
     * Stage: kick the bodies of `set` and (unless set is SlowBodies) the free particles by the forces
     * for a time `kick` (none if 0), then let them move freely for a time `drift` (none if 0: a kick
     * alone; see RigidBodyDynamics::kickAndDrift()). The forces are the Context's last evaluation if
     * `forces` is -1, else the set saveForces() kept in that slot.
     */
    virtual void kickAndDrift(OpenMM::ContextImpl& context, double kick, double drift, RigidBodyOptions::RotationMethod method,
                              double constraintTolerance, int forces, BodySet set) = 0;
    /**
     * Stage: the last kick of a step (forces as for kickAndDrift()), then the rigid velocities of every
     * body written to its particles and the constraints among free particles applied to their velocities.
     */
    virtual void closingKick(OpenMM::ContextImpl& context, double kick, double constraintTolerance, int forces) = 0;
    /**
     * Stage: the exact Ornstein-Uhlenbeck step of every momentum, with damping factor c, at thermal
     * energy kT, its deviates from the counter-based streams NormalStream(seed, stream, counter)
     * (see RigidBodyDynamics::thermalize() for which stream is whose). If `heat`, the kinetic energy
     * it adds (each body's from its momenta, the free particles' after their velocity constraints) is
     * added to the thermostat's work the kernel accumulates (takeThermostatWork()), where the momenta
     * are: on a GPU the host reads nothing.
     */
    virtual void thermalize(OpenMM::ContextImpl& context, double c, double kT, uint64_t seed, uint64_t counter,
                            double constraintTolerance, bool heat) = 0;
    /**
     * Stage: one step of the Bussi thermostat (after a closing kick): the kinetic energy K of the
     * Context's velocities (as computeKineticEnergies() sums it), the factor alpha and the new kinetic
     * energy K' from rigidStochasticRescaling() (numerics/core/CoreThermostat.h, eq. (A7) of Bussi,
     * Donadio and Parrinello (2007)) with the deviates the host drew, every momentum times alpha, and
     * K' - K added to the thermostat's work the kernel accumulates (takeThermostatWork()). On a GPU
     * all of it stays on the device: the host reads nothing.
     *
     * @param targetKinetic  Kbar = N_f kT/2, in kJ/mol
     * @param dof            N_f, the number of degrees of freedom
     * @param c              exp(-dt/tau)
     * @param r1             R_1 of eq. (A7), a standard normal deviate
     * @param rest           S of eq. (A7), a chi-squared deviate with N_f - 1 degrees of freedom
     */
    virtual void rescaleMomenta(OpenMM::ContextImpl& context, double targetKinetic, int dof, double c, double r1, double rest) = 0;
    /**
     * The kinetic energies before and after the last rescaleMomenta(), K and K', in kJ/mol (both 0
     * before the first). On a GPU this waits for the device: call it only for a step that reads
     * energies anyway (one that measures the shadow work).
     */
    virtual void getRescalingEnergies(OpenMM::ContextImpl& context, double& kinetic, double& newKinetic) = 0;
    /**
     * The thermostat's work that rescaleMomenta() (the sum of K' - K) and thermalize() (the heat) have
     * accumulated since the last call, in kJ/mol; the kernel's sum starts again from 0. On a GPU this
     * waits for the device (unless nothing was rescaled or thermalized since the last call): call it
     * only where the host needs the work.
     */
    virtual double takeThermostatWork(OpenMM::ContextImpl& context) = 0;
    /**
     * Add sign times the kinetic energy of the context's velocities (as computeKineticEnergies() sums
     * it) to the kernel's tally, which stays where the momenta are (on a GPU the host reads nothing).
     * The accuracy check tallies the kinetic energy at the start (+1) and the end (-1) of each step it
     * measures, so that what changed the velocities between steps (a CMMotionRemover) is accounted for.
     */
    virtual void tallyKineticEnergy(OpenMM::ContextImpl& context, double sign) = 0;
    /**
     * The tally of tallyKineticEnergy() since the last call, in kJ/mol (the kernel's tally starts again
     * from 0), and in `kinetic` the kinetic energy its last call summed. On a GPU this waits for the device.
     */
    virtual double takeTally(OpenMM::ContextImpl& context, double& kinetic) = 0;
    /**
     * The kinetic energy of the context's velocities, split into translation (centres of mass and
     * free particles) and rotation (about the centres of mass).
     */
    virtual void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational) = 0;
    /**
     * The kinetic energy, split as computeKineticEnergies() splits it, that the momenta would have
     * after a kick of `kick` by the forces (as for kickAndDrift()) (each body's momentum by its force and its
     * angular momentum by its torque; the free particles' velocities by their forces, then projected
     * onto the constraints among them to constraintTolerance), leaving the state as it is. The
     * bodies' momenta are those of the kernel's states: current after a step or a projection.
     */
    virtual void computeKickedKineticEnergies(OpenMM::ContextImpl& context, double kick, double constraintTolerance, int forces,
                                              double& translational, double& rotational) = 0;
    /** The kinetic energy sum m v^2 / 2 over the massive particles. */
    virtual double computeKineticEnergy(OpenMM::ContextImpl& context) = 0;
    /**
     * Before the step's last force evaluation, whose forces the next step's first kick reuses: every
     * stage that can find the simulation unstable has run (a platform that defers its checks reports
     * them here, by an OpenMMException), and a platform that reorders its atoms does it here.
     */
    virtual void beforeLastForces(OpenMM::ContextImpl& context) {
    }
    /**
     * Before a force evaluation in a periodic box other than the last evaluation's (the box set
     * between steps without new positions, a checkpoint, a barostat): a platform that keeps what it
     * built for the old box, and would reuse it as long as the particles stay where they were,
     * drops it here. The common-compute platforms rebuild their neighbour lists at the next
     * evaluation; the Reference and CPU platforms build theirs at every evaluation, and do nothing.
     */
    virtual void boxChanged(OpenMM::ContextImpl& context) {
    }
    /**
     * The bodies' states (RigidBodyDynamics::StateSize doubles each, as RigidBodyDynamics::getStates()
     * writes them), for a checkpoint whose positions and velocities are current (positionsAreCurrent()).
     * Returns false, writing nothing, on a platform that continues a loaded checkpoint from a fit of
     * the bodies instead (the common-compute platforms, whose checkpoints hold their own device arrays).
     */
    virtual bool getBodyStates(OpenMM::ContextImpl& context, std::vector<double>& states) {
        return false;
    }
    /**
     * After a checkpoint of this platform that getBodyStates() wrote is loaded, every body with its
     * shape: take the bodies' states from it, with the Context's positions and velocities as the ones
     * this kernel last wrote, so that the run continues exactly as it would have without the
     * checkpoint. Returns false, changing nothing, if the states do not place the bodies exactly at
     * the Context's positions (bodies whose shapes were taken from other positions): they are fitted.
     */
    virtual bool setBodyStates(OpenMM::ContextImpl& context, const std::vector<double>& states) {
        throw OpenMM::OpenMMException("internal error: this platform saves no bodies' states in its checkpoints");
    }
    /** After the last stage: advance the context's time and step count by dt, and record the positions written. */
    virtual void finishStep(OpenMM::ContextImpl& context, double dt) = 0;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYKERNELS_H_*/

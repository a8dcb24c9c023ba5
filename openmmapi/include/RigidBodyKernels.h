#ifndef OPENMMRIGID_RIGIDBODYKERNELS_H_
#define OPENMMRIGID_RIGIDBODYKERNELS_H_

#include "RigidBodyIntegrator.h"
#include "RigidBodyLangevinIntegrator.h"
#include "openmm/KernelImpl.h"
#include "openmm/System.h"
#include "openmm/internal/ContextImpl.h"
#include <iosfwd>
#include <string>
#include <vector>

namespace OpenMMRigid {

class RigidBodySystem;

/**
 * What the kernels of every rigid-body integrator answer: the bodies, their projection onto rigid
 * motion, and the kinetic energy. (Not a kernel by itself: each integrator has its own, below.)
 */
class RigidBodyStepKernel : public OpenMM::KernelImpl {
public:
    RigidBodyStepKernel(std::string name, const OpenMM::Platform& platform) : OpenMM::KernelImpl(name, platform) {
    }
    /**
     * Re-fit the bodies to the context's positions, project its velocities onto rigid motion, and
     * place the virtual sites. Called when positions changed from outside the integrator.
     */
    virtual void project(OpenMM::ContextImpl& context) = 0;
    /**
     * Project the context's velocities onto rigid motion, the bodies staying as fitted (their
     * positions are current: see positionsAreCurrent()). Called when velocities were set.
     */
    virtual void projectVelocities(OpenMM::ContextImpl& context) = 0;
    /**
     * Give the explicit bodies that have no shape yet the shapes they have in the context's
     * positions (called when positions are set; bodies the positions cannot shape wait).
     */
    virtual void captureShapes(OpenMM::ContextImpl& context) = 0;
    /** Whether every body has its shape. */
    virtual bool allShapesKnown() const = 0;
    /**
     * Whether the context's positions are still those this kernel last wrote (by a step or a
     * projection): if not, something moved the particles without telling the integrator (another
     * integrator of a CompoundIntegrator, the energy minimizer, applyConstraints), and the bodies
     * must be fitted again before the next step.
     */
    virtual bool positionsAreCurrent(OpenMM::ContextImpl& context) const = 0;
    /**
     * Compute the kinetic energy, sum m v^2 / 2 over the massive particles.
     */
    virtual double computeKineticEnergy(OpenMM::ContextImpl& context) = 0;
    /**
     * Split the kinetic energy of the bodies and free particles into translation (centres of mass and
     * free particles) and rotation (about the centres of mass).
     */
    virtual void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational) = 0;
    /** The bodies, as found when the kernel was initialized. */
    virtual const RigidBodySystem& getBodies() const = 0;
    /**
     * Write the kernel's own state (the random numbers and what they produced) to a checkpoint, after
     * the integrator's header (RigidBodyIntegratorBase::createCheckpoint()).
     */
    virtual void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const = 0;
    /**
     * Read the state written by createCheckpoint().
     *
     * @param version  the checkpoint format: 1 (with a header naming the class), or 0 for a checkpoint
     *                 from before headers, whose data end the stream; one that ends here (written before
     *                 the kernel had a state to save) leaves the state as it is
     */
    virtual void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream, int version) = 0;
};

/**
 * This kernel is invoked by RigidBodyIntegrator to take one time step, and to answer questions about
 * the bodies and their kinetic energy.
 */
class IntegrateRigidBodyStepKernel : public RigidBodyStepKernel {
public:
    static std::string Name() {
        return "IntegrateRigidBodyStep";
    }
    IntegrateRigidBodyStepKernel(std::string name, const OpenMM::Platform& platform) : RigidBodyStepKernel(name, platform) {
    }
    /**
     * Initialize the kernel: find the bodies, check the System against them and seed the random
     * numbers of the thermostat (a seed of 0 picks one at random).
     *
     * @param context     the context the integrator is bound to
     * @param integrator  the RigidBodyIntegrator this kernel is used for
     */
    virtual void initialize(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) = 0;
    /**
     * Execute the kernel: one step of the integrator's splitting (internal/Splitting.h), with the
     * virtual sites placed and the forces evaluated after every drift, then, if the integrator has
     * a thermostat, the stochastic rescaling of the velocities. On entry the context holds the forces
     * at the current positions, and the bodies agree with them (see project()); on exit it holds the
     * forces at the new positions.
     *
     * @param context     the context in which to execute this kernel
     * @param integrator  the RigidBodyIntegrator this kernel is being used for
     */
    virtual void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator) = 0;
    /** The kinetic energy the thermostat has added since the kernel was created (negative if it removed energy). */
    virtual double getThermostatWork() const = 0;
};

/**
 * This kernel is invoked by RigidBodyLangevinIntegrator to take one time step, and to answer
 * questions about the bodies and their kinetic energy.
 */
class IntegrateRigidBodyLangevinStepKernel : public RigidBodyStepKernel {
public:
    static std::string Name() {
        return "IntegrateRigidBodyLangevinStep";
    }
    IntegrateRigidBodyLangevinStepKernel(std::string name, const OpenMM::Platform& platform) : RigidBodyStepKernel(name, platform) {
    }
    /**
     * Initialize the kernel: find the bodies, check the System against them and seed the random
     * numbers (a seed of 0 picks one at random).
     *
     * @param context     the context the integrator is bound to
     * @param integrator  the RigidBodyLangevinIntegrator this kernel is used for
     */
    virtual void initialize(OpenMM::ContextImpl& context, const RigidBodyLangevinIntegrator& integrator) = 0;
    /**
     * Execute the kernel: half kick, half drift, Ornstein-Uhlenbeck step, half drift, force
     * evaluation, half kick. On entry the context holds the forces at the current positions, and
     * the bodies agree with them (see project()); on exit it holds the forces at the new positions.
     *
     * @param context     the context in which to execute this kernel
     * @param integrator  the RigidBodyLangevinIntegrator this kernel is being used for
     */
    virtual void execute(OpenMM::ContextImpl& context, const RigidBodyLangevinIntegrator& integrator) = 0;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYKERNELS_H_*/

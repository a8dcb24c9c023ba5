#ifndef OPENMMRIGID_REFERENCERIGIDKERNELS_H_
#define OPENMMRIGID_REFERENCERIGIDKERNELS_H_

#include "RigidBodyKernels.h"
#include "internal/RigidBodyDynamics.h"
#include "internal/RigidBodySystem.h"
#include "openmm/internal/ThreadPool.h"
#include <cstdint>
#include <iosfwd>
#include <memory>
#include <vector>

namespace OpenMMRigid {

/**
 * What the rigid-body kernels of the Reference and CPU platforms share (both keep positions,
 * velocities and forces in the Reference platform's arrays): the bodies and their dynamics, set up
 * from the integrator, and the answers every RigidBodyStepKernel gives. On the CPU platform the
 * per-body work runs on as many threads as the platform's Threads property.
 *
 * @tparam Kernel  the abstract kernel to implement (IntegrateRigidBodyStepKernel or IntegrateRigidBodyLangevinStepKernel)
 */
template <class Kernel>
class ReferenceRigidBodyKernel : public Kernel {
public:
    ReferenceRigidBodyKernel(std::string name, const OpenMM::Platform& platform) : Kernel(name, platform) {
    }
    void project(OpenMM::ContextImpl& context);
    void projectVelocities(OpenMM::ContextImpl& context);
    void captureShapes(OpenMM::ContextImpl& context);
    bool allShapesKnown() const;
    bool positionsAreCurrent(OpenMM::ContextImpl& context) const;
    double computeKineticEnergy(OpenMM::ContextImpl& context);
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational);
    const RigidBodySystem& getBodies() const {
        return *bodies;
    }
    /** Writes the seed and the counter of the random numbers. */
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream, int version);
protected:
    /**
     * Find the bodies of the context's System, set up their dynamics and seed the random numbers
     * (seed 0, as in OpenMM's integrators, asks for one that differs from Context to Context).
     */
    void initializeBodies(OpenMM::ContextImpl& context, const RigidBodyIntegratorBase& integrator, int seed);
    /**
     * Before a step or a fit: tell the dynamics the periodic box and the largest plausible drift (the
     * largest nonbonded cutoff, or half the narrowest box width if that is less).
     */
    void prepare(OpenMM::ContextImpl& context);
    /** Advance the context's time and step count by dt after a step, and record the positions it wrote. */
    void finishStep(OpenMM::ContextImpl& context, double dt);
    std::unique_ptr<RigidBodySystem> bodies;
    std::unique_ptr<RigidBodyDynamics> dynamics;
    std::unique_ptr<OpenMM::ThreadPool> threads;
    std::vector<double> masses;
    /** The positions as this kernel last wrote them (see positionsAreCurrent()). */
    std::vector<OpenMM::Vec3> writtenPositions;
    /** Whether the System is periodic. */
    bool periodic = false;
    /** The key of the random numbers, and the number of stages that have drawn from it (the counter). */
    uint64_t seed = 0, randomCounter = 0;
};

/** The RigidBodyIntegrator step: the stages of its splitting, then the thermostat if there is one. */
class ReferenceIntegrateRigidBodyStepKernel : public ReferenceRigidBodyKernel<IntegrateRigidBodyStepKernel> {
public:
    ReferenceIntegrateRigidBodyStepKernel(std::string name, const OpenMM::Platform& platform) :
            ReferenceRigidBodyKernel<IntegrateRigidBodyStepKernel>(name, platform), thermostatWork(0.0) {
    }
    void initialize(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator);
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator);
    double getThermostatWork() const {
        return thermostatWork;
    }
    /** Also writes the thermostat's work. */
    void createCheckpoint(OpenMM::ContextImpl& context, std::ostream& stream) const;
    void loadCheckpoint(OpenMM::ContextImpl& context, std::istream& stream, int version);
private:
    double thermostatWork;
};

/** The RigidBodyLangevinIntegrator step: kick, half drift, Ornstein-Uhlenbeck, half drift, kick. */
class ReferenceIntegrateRigidBodyLangevinStepKernel : public ReferenceRigidBodyKernel<IntegrateRigidBodyLangevinStepKernel> {
public:
    ReferenceIntegrateRigidBodyLangevinStepKernel(std::string name, const OpenMM::Platform& platform) :
            ReferenceRigidBodyKernel<IntegrateRigidBodyLangevinStepKernel>(name, platform) {
    }
    void initialize(OpenMM::ContextImpl& context, const RigidBodyLangevinIntegrator& integrator);
    void execute(OpenMM::ContextImpl& context, const RigidBodyLangevinIntegrator& integrator);
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_REFERENCERIGIDKERNELS_H_*/

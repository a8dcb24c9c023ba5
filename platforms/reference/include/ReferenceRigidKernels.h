#ifndef OPENMMRIGID_REFERENCERIGIDKERNELS_H_
#define OPENMMRIGID_REFERENCERIGIDKERNELS_H_

#include "RigidBodyKernels.h"
#include "internal/RigidBodyDynamics.h"
#include "internal/RigidBodySystem.h"
#include "openmm/internal/ThreadPool.h"
#include <memory>

namespace OpenMMRigid {

/**
 * The RigidBodyIntegrator step on the Reference and CPU platforms (both keep positions, velocities
 * and forces in the Reference platform's arrays). It extracts the arrays and calls RigidBodyDynamics;
 * on the CPU platform the per-body work runs on as many threads as the platform's Threads property.
 */
class ReferenceIntegrateRigidBodyStepKernel : public IntegrateRigidBodyStepKernel {
public:
    ReferenceIntegrateRigidBodyStepKernel(std::string name, const OpenMM::Platform& platform) :
            IntegrateRigidBodyStepKernel(name, platform) {
    }
    void initialize(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator);
    void execute(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator);
    void project(OpenMM::ContextImpl& context);
    double computeKineticEnergy(OpenMM::ContextImpl& context, const RigidBodyIntegrator& integrator);
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational);
    const RigidBodySystem& getBodies() const {
        return *bodies;
    }
private:
    std::unique_ptr<RigidBodySystem> bodies;
    std::unique_ptr<RigidBodyDynamics> dynamics;
    std::unique_ptr<OpenMM::ThreadPool> threads;
    std::vector<double> masses;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_REFERENCERIGIDKERNELS_H_*/

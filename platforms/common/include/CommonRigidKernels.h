#ifndef OPENMMRIGID_COMMONRIGIDKERNELS_H_
#define OPENMMRIGID_COMMONRIGIDKERNELS_H_

#include "RigidBodyKernels.h"
#include "openmm/common/ComputeArray.h"
#include "openmm/common/ComputeContext.h"
#include "openmm/common/ComputeKernel.h"
#include "openmm/common/IntegrationUtilities.h"
#include <functional>
#include <memory>
#include <string>

namespace OpenMMRigid {

/**
 * The stages of a rigid-body step on a common-compute platform (OpenCL, CUDA): one implementation,
 * its kernels (platforms/common/src/kernels/rigidBodies.cc, behind the numerics core compiled as
 * kernel source) compiled at run time by the platform. The bodies' state (centre, velocity, angular
 * momentum, attitude) lives on the device in double precision in every precision mode; a step never
 * copies to the host except for one status word at its end. Positions the Context holds are in
 * the platform's order and precision (posq, plus posqCorrection in mixed precision); the bodies
 * follow atom reordering through the inverse of the atom index, rebuilt after each reorder.
 *
 * The platform's factory supplies the ComputeContext, a way to make the platform's
 * IntegrationUtilities for a System (the constraint solver for the constraints among free
 * particles: the System's own utilities would also constrain the bodies' atoms), and a way to make
 * the platform rebuild its neighbour lists (boxChanged()), which the common interface lacks.
 */
class CommonIntegrateRigidBodyStepKernel : public IntegrateRigidBodyStepKernel {
public:
    /** Makes the platform's IntegrationUtilities for a System (owned by the caller). */
    typedef std::function<OpenMM::IntegrationUtilities*(const OpenMM::System&)> SolverFactory;
    /** Makes every device of the platform rebuild its neighbour list at the next force evaluation. */
    typedef std::function<void()> NeighbourListRebuild;
    CommonIntegrateRigidBodyStepKernel(std::string name, const OpenMM::Platform& platform, OpenMM::ComputeContext& cc,
                                       SolverFactory makeSolver, NeighbourListRebuild rebuildNeighbourLists);
    ~CommonIntegrateRigidBodyStepKernel();
    void initialize(OpenMM::ContextImpl& context, RigidBodySystem& bodies) override;
    void setGeometry(OpenMM::ContextImpl& context, const StepGeometry& geometry) override;
    void beginStep(OpenMM::ContextImpl& context, const StepGeometry& geometry) override;
    void abandonStep(OpenMM::ContextImpl& context) override;
    void project(OpenMM::ContextImpl& context) override;
    void projectVelocities(OpenMM::ContextImpl& context) override;
    bool positionsAreCurrent(OpenMM::ContextImpl& context) const override;
    void saveForces(OpenMM::ContextImpl& context, int slot) override;
    void kickAndDrift(OpenMM::ContextImpl& context, double kick, double drift, RigidBodyOptions::RotationMethod method,
                      double constraintTolerance, int forces, BodySet set) override;
    void closingKick(OpenMM::ContextImpl& context, double kick, double constraintTolerance, int forces) override;
    void thermalize(OpenMM::ContextImpl& context, double c, double kT, uint64_t seed, uint64_t counter,
                    double constraintTolerance, bool heat) override;
    void rescaleMomenta(OpenMM::ContextImpl& context, double targetKinetic, int dof, double c, double r1, double rest) override;
    void getRescalingEnergies(OpenMM::ContextImpl& context, double& kinetic, double& newKinetic) override;
    double takeThermostatWork(OpenMM::ContextImpl& context) override;
    void tallyKineticEnergy(OpenMM::ContextImpl& context, double sign) override;
    double takeTally(OpenMM::ContextImpl& context, double& kinetic) override;
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational) override;
    void computeKickedKineticEnergies(OpenMM::ContextImpl& context, double kick, double constraintTolerance, int forces,
                                      double& translational, double& rotational) override;
    double computeKineticEnergy(OpenMM::ContextImpl& context) override;
    void beforeLastForces(OpenMM::ContextImpl& context) override;
    void boxChanged(OpenMM::ContextImpl& context) override;
    void finishStep(OpenMM::ContextImpl& context, double dt) override;
private:
    /** The rigid projection of every body's velocities on the device; false if some were not finite (nothing is written for those bodies). */
    bool projectVelocitiesOnDevice(OpenMM::ContextImpl& context);
    class ReorderListener;
    class BodyInfo;
    struct Impl;
    OpenMM::ComputeContext& cc;
    SolverFactory makeSolver;
    NeighbourListRebuild rebuildNeighbourLists;
    std::unique_ptr<Impl> impl;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_COMMONRIGIDKERNELS_H_*/

#ifndef OPENMMRIGID_REFERENCERIGIDKERNELS_H_
#define OPENMMRIGID_REFERENCERIGIDKERNELS_H_

#include "RigidBodyKernels.h"
#include "internal/RigidBodyDynamics.h"
#include "internal/RigidBodySystem.h"
#include <memory>
#include <vector>

namespace OpenMMRigid {

/**
 * The rigid-body kernel of the Reference and CPU platforms (both keep positions, velocities and
 * forces in the Reference platform's host arrays): each stage is the host implementation's
 * (RigidBodyDynamics) on those arrays. This kernel supplies what the host stages take from the
 * platform: the CPU platform's threads (as many as its Threads property) and the Reference
 * platform's solver for the constraints among free particles.
 */
class ReferenceIntegrateRigidBodyStepKernel : public IntegrateRigidBodyStepKernel {
public:
    ReferenceIntegrateRigidBodyStepKernel(std::string name, const OpenMM::Platform& platform);
    ~ReferenceIntegrateRigidBodyStepKernel();
    void initialize(OpenMM::ContextImpl& context, RigidBodySystem& bodies);
    void setGeometry(OpenMM::ContextImpl& context, const StepGeometry& geometry);
    void beginStep(OpenMM::ContextImpl& context, const StepGeometry& geometry);
    void abandonStep(OpenMM::ContextImpl& context);
    void project(OpenMM::ContextImpl& context);
    void projectVelocities(OpenMM::ContextImpl& context);
    bool positionsAreCurrent(OpenMM::ContextImpl& context) const;
    void saveForces(OpenMM::ContextImpl& context, int slot);
    void kickAndDrift(OpenMM::ContextImpl& context, double kick, double drift, RigidBodyOptions::RotationMethod method,
                      double constraintTolerance, int forces, BodySet set);
    void closingKick(OpenMM::ContextImpl& context, double kick, double constraintTolerance, int forces);
    void thermalize(OpenMM::ContextImpl& context, double c, double kT, uint64_t seed, uint64_t counter, double constraintTolerance,
                    bool heat);
    void rescaleMomenta(OpenMM::ContextImpl& context, double targetKinetic, int dof, double c, double r1, double rest);
    void getRescalingEnergies(OpenMM::ContextImpl& context, double& kinetic, double& newKinetic);
    double takeThermostatWork(OpenMM::ContextImpl& context);
    void tallyKineticEnergy(OpenMM::ContextImpl& context, double sign);
    double takeTally(OpenMM::ContextImpl& context, double& kinetic);
    void computeKineticEnergies(OpenMM::ContextImpl& context, double& translational, double& rotational);
    void computeKickedKineticEnergies(OpenMM::ContextImpl& context, double kick, double constraintTolerance, int forces,
                                      double& translational, double& rotational);
    double computeKineticEnergy(OpenMM::ContextImpl& context);
    bool getBodyStates(OpenMM::ContextImpl& context, std::vector<double>& states);
    bool setBodyStates(OpenMM::ContextImpl& context, const std::vector<double>& states);
    void finishStep(OpenMM::ContextImpl& context, double dt);
private:
    /** The Context's forces (-1) or those saveForces() kept in a slot. */
    const std::vector<OpenMM::Vec3>& forceSet(OpenMM::ContextImpl& context, int forces) const;
    std::unique_ptr<HostThreads> threads;
    std::unique_ptr<HostConstraints> constraints;
    std::unique_ptr<RigidBodyDynamics> dynamics;
    /** The positions as this kernel last wrote them (see positionsAreCurrent()): at a step's start, those it starts from. */
    std::vector<OpenMM::Vec3> writtenPositions;
    /** The velocities a step starts from (for abandonStep()). */
    std::vector<OpenMM::Vec3> startVelocities;
    /** The force sets of saveForces(), by slot. */
    std::vector<std::vector<OpenMM::Vec3> > savedForces;
    /**
     * The kinetic energies before and after the last rescaleMomenta(), and the work (K' - K, and the
     * heat of thermalize()) summed since the last takeThermostatWork().
     */
    double rescalingKinetic = 0.0, rescalingNewKinetic = 0.0, thermostatWork = 0.0;
    /** The tally of tallyKineticEnergy() since the last takeTally(), and the kinetic energy its last call summed. */
    double tally = 0.0, tallyKinetic = 0.0;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_REFERENCERIGIDKERNELS_H_*/

#include "ReferenceRigidKernels.h"
#include "internal/Splitting.h"
#include "openmm/Context.h"
#include "openmm/reference/ReferencePlatform.h"
#include <cstdlib>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

ReferencePlatform::PlatformData& platformData(ContextImpl& context) {
    return *reinterpret_cast<ReferencePlatform::PlatformData*>(context.getPlatformData());
}

vector<Vec3>& extractPositions(ContextImpl& context) {
    return *platformData(context).positions;
}

vector<Vec3>& extractVelocities(ContextImpl& context) {
    return *platformData(context).velocities;
}

vector<Vec3>& extractForces(ContextImpl& context) {
    return *platformData(context).forces;
}

} // namespace

void ReferenceIntegrateRigidBodyStepKernel::initialize(ContextImpl& context, const RigidBodyIntegrator& integrator) {
    const System& system = context.getSystem();
    bodies.reset(new RigidBodySystem(system, integrator.getExplicitBodies(), integrator.hasExplicitBodies()));
    dynamics.reset(new RigidBodyDynamics(*bodies));
    masses = bodies->getMasses();
    if (context.getPlatform().getName() == "CPU") {
        int numThreads = atoi(context.getPlatform().getPropertyValue(context.getOwner(), "Threads").c_str());
        if (numThreads > 1) {
            threads.reset(new ThreadPool(numThreads));
            dynamics->setThreadPool(threads.get());
        }
    }
}

void ReferenceIntegrateRigidBodyStepKernel::project(ContextImpl& context) {
    dynamics->project(extractPositions(context), extractVelocities(context));
    context.computeVirtualSites();
}

void ReferenceIntegrateRigidBodyStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator) {
    vector<Vec3>& positions = extractPositions(context);
    vector<Vec3>& velocities = extractVelocities(context);
    vector<Vec3>& forces = extractForces(context);  // refilled in place by each force evaluation
    const SplittingScheme& scheme = splittingScheme(integrator.getSplitting());
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const RigidBodyIntegrator::RotationMethod method = integrator.getRotationMethod();
    // The first kick uses the forces the context holds; every drift is followed by a force evaluation.
    for (int stage = 0; stage < scheme.numDrifts; stage++) {
        dynamics->kickAndDrift(positions, velocities, forces, scheme.kicks[stage]*dt, scheme.drifts[stage]*dt, method, tolerance);
        context.computeVirtualSites();
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    }
    dynamics->closingKick(positions, velocities, forces, scheme.kicks[scheme.numDrifts]*dt, tolerance);
    ReferencePlatform::PlatformData& data = platformData(context);
    data.time += dt;
    data.stepCount++;
}

double ReferenceIntegrateRigidBodyStepKernel::computeKineticEnergy(ContextImpl& context, const RigidBodyIntegrator& integrator) {
    const vector<Vec3>& velocities = extractVelocities(context);
    double energy = 0.0;
    for (size_t i = 0; i < masses.size(); i++)
        energy += 0.5*masses[i]*velocities[i].dot(velocities[i]);
    return energy;
}

void ReferenceIntegrateRigidBodyStepKernel::computeKineticEnergies(ContextImpl& context, double& translational, double& rotational) {
    dynamics->computeKineticEnergies(extractVelocities(context), translational, rotational);
}

} // namespace OpenMMRigid

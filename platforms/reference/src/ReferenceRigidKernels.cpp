#include "ReferenceRigidKernels.h"
#include "internal/Splitting.h"
#include "numerics/StochasticRescaling.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/ReferencePlatform.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <cmath>
#include <cstdlib>
#include <istream>
#include <ostream>
#include <random>
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

// ---- what both kernels share ----

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::initializeBodies(ContextImpl& context, const RigidBodyIntegratorBase& integrator, int chosenSeed) {
    seed = (chosenSeed != 0 ? (uint64_t) (uint32_t) chosenSeed : ((uint64_t) random_device()() << 32) | random_device()());
    randomCounter = 0;
    const System& system = context.getSystem();
    bodies.reset(new RigidBodySystem(system, integrator.getExplicitBodies(), integrator.hasExplicitBodies(),
                                     integrator.getClassName()));
    dynamics.reset(new RigidBodyDynamics(*bodies));
    masses = bodies->getMasses();
    periodic = system.usesPeriodicBoundaryConditions();
    if (context.getPlatform().getName() == "CPU") {
        int numThreads = atoi(context.getPlatform().getPropertyValue(context.getOwner(), "Threads").c_str());
        if (numThreads > 1) {
            threads.reset(new ThreadPool(numThreads));
            dynamics->setThreadPool(threads.get());
        }
    }
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::prepare(ContextImpl& context) {
    double limit = bodies->getLargestCutoff();
    const char* description = "the nonbonded cutoff";
    if (periodic) {
        // The box can change between steps (a barostat).
        Vec3 box[3];
        context.getPeriodicBoxVectors(box[0], box[1], box[2]);
        dynamics->setPeriodicBox(box);
        // The reduced box's widths perpendicular to its faces are a_x, b_y and c_z.
        double halfWidth = 0.5*min(box[0][0], min(box[1][1], box[2][2]));
        if (halfWidth < limit) {
            limit = halfWidth;
            description = "half the periodic box width";
        }
    }
    else
        dynamics->setPeriodicBox(NULL);
    dynamics->setDisplacementLimit(limit, description);
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::project(ContextImpl& context) {
    prepare(context);
    dynamics->project(extractPositions(context), extractVelocities(context));
    context.computeVirtualSites();
    writtenPositions = extractPositions(context);
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::projectVelocities(ContextImpl& context) {
    dynamics->projectVelocities(extractVelocities(context));
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::captureShapes(ContextImpl& context) {
    prepare(context);
    dynamics->captureShapes(extractPositions(context));
}

template <class Kernel>
bool ReferenceRigidBodyKernel<Kernel>::allShapesKnown() const {
    return dynamics->allShapesKnown();
}

template <class Kernel>
bool ReferenceRigidBodyKernel<Kernel>::positionsAreCurrent(ContextImpl& context) const {
    return extractPositions(context) == writtenPositions;
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::finishStep(ContextImpl& context, double dt) {
    ReferencePlatform::PlatformData& data = platformData(context);
    data.time += dt;
    data.stepCount++;
    writtenPositions = *data.positions;
}

template <class Kernel>
double ReferenceRigidBodyKernel<Kernel>::computeKineticEnergy(ContextImpl& context) {
    const vector<Vec3>& velocities = extractVelocities(context);
    double energy = 0.0;
    for (size_t i = 0; i < masses.size(); i++)
        energy += 0.5*masses[i]*velocities[i].dot(velocities[i]);
    return energy;
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::computeKineticEnergies(ContextImpl& context, double& translational, double& rotational) {
    dynamics->computeKineticEnergies(extractVelocities(context), translational, rotational);
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::createCheckpoint(ContextImpl& context, ostream& stream) const {
    stream.write((const char*) &seed, sizeof(seed));
    stream.write((const char*) &randomCounter, sizeof(randomCounter));
}

template <class Kernel>
void ReferenceRigidBodyKernel<Kernel>::loadCheckpoint(ContextImpl& context, istream& stream, int version) {
    // Before headers the integrator's data ended the checkpoint: a RigidBodyIntegrator checkpoint
    // from before the thermostat ends here, and means "no random numbers drawn".
    if (version == 0 && stream.peek() == char_traits<char>::eof()) {
        stream.clear();
        return;
    }
    uint64_t savedSeed, savedCounter;
    stream.read((char*) &savedSeed, sizeof(savedSeed));
    stream.read((char*) &savedCounter, sizeof(savedCounter));
    if (!stream)
        throw OpenMMException(bodies->getClassName() + ": the checkpoint ends within the state of the integrator's random numbers");
    seed = savedSeed;
    randomCounter = savedCounter;
}

template class ReferenceRigidBodyKernel<IntegrateRigidBodyStepKernel>;
template class ReferenceRigidBodyKernel<IntegrateRigidBodyLangevinStepKernel>;

// ---- RigidBodyIntegrator ----

void ReferenceIntegrateRigidBodyStepKernel::initialize(ContextImpl& context, const RigidBodyIntegrator& integrator) {
    initializeBodies(context, integrator, integrator.getRandomNumberSeed());
    thermostatWork = 0.0;
}

void ReferenceIntegrateRigidBodyStepKernel::execute(ContextImpl& context, const RigidBodyIntegrator& integrator) {
    vector<Vec3>& positions = extractPositions(context);
    vector<Vec3>& velocities = extractVelocities(context);
    vector<Vec3>& forces = extractForces(context);  // refilled in place by each force evaluation
    const SplittingScheme& scheme = splittingScheme(integrator.getSplitting());
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const RigidBodyIntegrator::RotationMethod method = integrator.getRotationMethod();
    prepare(context);
    // The first kick uses the forces the context holds; every drift is followed by a force evaluation.
    for (int stage = 0; stage < scheme.numDrifts; stage++) {
        dynamics->kickAndDrift(positions, velocities, forces, scheme.kicks[stage]*dt, scheme.drifts[stage]*dt, method, tolerance);
        context.computeVirtualSites();
        context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    }
    dynamics->closingKick(positions, velocities, forces, scheme.kicks[scheme.numDrifts]*dt, tolerance);
    if (integrator.hasThermostat()) {
        // Bussi, Donadio and Parrinello (2007): one global factor for every momentum, from the exact
        // solution over this step of the stochastic equation for the kinetic energy.
        double translational, rotational, newKinetic;
        dynamics->computeKineticEnergies(velocities, translational, rotational);
        const int dof = bodies->getNumDegreesOfFreedom();
        NormalStream random(seed, 0, randomCounter++);
        double alpha = stochasticRescalingFactor(translational + rotational, 0.5*dof*BOLTZ*integrator.getThermostatTemperature(),
                                                 dof, exp(-dt/integrator.getThermostatCollisionTime()), random, newKinetic);
        dynamics->scaleVelocities(velocities, alpha);
        thermostatWork += newKinetic - (translational + rotational);
    }
    finishStep(context, dt);
}

void ReferenceIntegrateRigidBodyStepKernel::createCheckpoint(ContextImpl& context, ostream& stream) const {
    ReferenceRigidBodyKernel<IntegrateRigidBodyStepKernel>::createCheckpoint(context, stream);
    stream.write((const char*) &thermostatWork, sizeof(thermostatWork));
}

void ReferenceIntegrateRigidBodyStepKernel::loadCheckpoint(ContextImpl& context, istream& stream, int version) {
    if (version == 0 && stream.peek() == char_traits<char>::eof()) {
        stream.clear();
        return;  // written before the thermostat (see the base class)
    }
    ReferenceRigidBodyKernel<IntegrateRigidBodyStepKernel>::loadCheckpoint(context, stream, version);
    double savedWork;
    stream.read((char*) &savedWork, sizeof(savedWork));
    if (!stream)
        throw OpenMMException("RigidBodyIntegrator: the checkpoint ends within the thermostat's state (was it written by a "
                "RigidBodyLangevinIntegrator?)");
    thermostatWork = savedWork;
}

// ---- RigidBodyLangevinIntegrator ----

void ReferenceIntegrateRigidBodyLangevinStepKernel::initialize(ContextImpl& context, const RigidBodyLangevinIntegrator& integrator) {
    initializeBodies(context, integrator, integrator.getRandomNumberSeed());
}

void ReferenceIntegrateRigidBodyLangevinStepKernel::execute(ContextImpl& context, const RigidBodyLangevinIntegrator& integrator) {
    vector<Vec3>& positions = extractPositions(context);
    vector<Vec3>& velocities = extractVelocities(context);
    vector<Vec3>& forces = extractForces(context);
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction();
    const RigidBodyIntegratorBase::RotationMethod method = integrator.getRotationMethod();
    prepare(context);
    // BAOAB (Leimkuhler and Matthews, 2013), as LangevinMiddleIntegrator: B, A, O, A, force, B. With
    // no friction the O stage is the identity and is left out, so that the step is exactly the
    // constant-energy kick, half drift, half drift, kick.
    dynamics->kickAndDrift(positions, velocities, forces, 0.5*dt, 0.5*dt, method, tolerance);
    if (friction > 0.0)
        dynamics->thermalize(positions, velocities, exp(-friction*dt), BOLTZ*integrator.getTemperature(), seed,
                             randomCounter++, tolerance);
    dynamics->drift(positions, velocities, 0.5*dt, method, tolerance);
    context.computeVirtualSites();
    context.calcForcesAndEnergy(true, false, integrator.getIntegrationForceGroups());
    dynamics->closingKick(positions, velocities, forces, 0.5*dt, tolerance);
    finishStep(context, dt);
}

} // namespace OpenMMRigid

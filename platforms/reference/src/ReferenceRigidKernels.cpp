#include "ReferenceRigidKernels.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ThreadPool.h"
#include "openmm/reference/ReferenceConstraints.h"
#include "openmm/reference/ReferencePlatform.h"
#include <cstdlib>

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

/** The CPU platform's threads, for the per-body loops. */
class PoolThreads : public HostThreads {
public:
    explicit PoolThreads(int numThreads) : pool(numThreads) {
    }
    int getNumThreads() const {
        return pool.getNumThreads();
    }
    void execute(const function<void(int thread)>& task) {
        pool.execute([&](ThreadPool&, int thread) { task(thread); });
        pool.waitForThreads();
    }
private:
    ThreadPool pool;
};

/** The Reference platform's solver, for the constraints among free particles. */
class ReferenceHostConstraints : public HostConstraints {
public:
    explicit ReferenceHostConstraints(const System& system) : solver(system) {
    }
    void apply(vector<Vec3>& before, vector<Vec3>& updated, vector<double>& inverseMasses, double tolerance) {
        solver.apply(before, updated, inverseMasses, tolerance);
    }
    void applyToVelocities(vector<Vec3>& positions, vector<Vec3>& velocities, vector<double>& inverseMasses, double tolerance) {
        solver.applyToVelocities(positions, velocities, inverseMasses, tolerance);
    }
private:
    ReferenceConstraints solver;
};

} // namespace

ReferenceIntegrateRigidBodyStepKernel::ReferenceIntegrateRigidBodyStepKernel(string name, const Platform& platform) :
        IntegrateRigidBodyStepKernel(name, platform) {
}

ReferenceIntegrateRigidBodyStepKernel::~ReferenceIntegrateRigidBodyStepKernel() {
}

void ReferenceIntegrateRigidBodyStepKernel::initialize(ContextImpl& context, RigidBodySystem& bodies) {
    if (context.getPlatform().getName() == "CPU") {
        int numThreads = atoi(context.getPlatform().getPropertyValue(context.getOwner(), "Threads").c_str());
        if (numThreads > 1)
            threads.reset(new PoolThreads(numThreads));
    }
    if (bodies.getFreeConstraintSystem() != NULL)
        constraints.reset(new ReferenceHostConstraints(*bodies.getFreeConstraintSystem()));
    dynamics.reset(new RigidBodyDynamics(bodies, threads.get(), constraints.get()));
}

void ReferenceIntegrateRigidBodyStepKernel::setGeometry(ContextImpl& context, const StepGeometry& geometry) {
    dynamics->setGeometry(geometry);
}

void ReferenceIntegrateRigidBodyStepKernel::beginStep(ContextImpl& context, const StepGeometry& geometry) {
    dynamics->setGeometry(geometry);
    // The step sequence proved the positions current (positionsAreCurrent()): writtenPositions holds them.
    dynamics->copyParticleArray(extractVelocities(context), startVelocities);
}

void ReferenceIntegrateRigidBodyStepKernel::abandonStep(ContextImpl& context) {
    extractPositions(context) = writtenPositions;
    extractVelocities(context) = startVelocities;
    context.computeVirtualSites();
}

void ReferenceIntegrateRigidBodyStepKernel::project(ContextImpl& context) {
    dynamics->project(extractPositions(context), extractVelocities(context));
    context.computeVirtualSites();
    dynamics->copyParticleArray(extractPositions(context), writtenPositions);
}

void ReferenceIntegrateRigidBodyStepKernel::projectVelocities(ContextImpl& context) {
    dynamics->projectVelocities(extractVelocities(context));
}

bool ReferenceIntegrateRigidBodyStepKernel::positionsAreCurrent(ContextImpl& context) const {
    return dynamics->particleArraysEqual(extractPositions(context), writtenPositions);
}

const vector<Vec3>& ReferenceIntegrateRigidBodyStepKernel::forceSet(ContextImpl& context, int forces) const {
    if (forces < 0)
        return extractForces(context);
    if (forces >= (int) savedForces.size())
        throw OpenMMException("internal error: no forces were saved in slot " + to_string(forces));
    return savedForces[forces];
}

void ReferenceIntegrateRigidBodyStepKernel::saveForces(ContextImpl& context, int slot) {
    if (slot >= (int) savedForces.size())
        savedForces.resize(slot + 1);
    savedForces[slot] = extractForces(context);
}

void ReferenceIntegrateRigidBodyStepKernel::kickAndDrift(ContextImpl& context, double kick, double drift,
                                                         RigidBodyOptions::RotationMethod method, double constraintTolerance,
                                                         int forces, BodySet set) {
    dynamics->kickAndDrift(extractPositions(context), extractVelocities(context), forceSet(context, forces), kick, drift, method,
                           constraintTolerance, set);
}

void ReferenceIntegrateRigidBodyStepKernel::closingKick(ContextImpl& context, double kick, double constraintTolerance, int forces) {
    dynamics->closingKick(extractPositions(context), extractVelocities(context), forceSet(context, forces), kick, constraintTolerance);
}

void ReferenceIntegrateRigidBodyStepKernel::thermalize(ContextImpl& context, double c, double kT, uint64_t seed, uint64_t counter,
                                                       double constraintTolerance, bool heat) {
    const double added = dynamics->thermalize(extractPositions(context), extractVelocities(context), c, kT, seed, counter,
                                              constraintTolerance);
    if (heat)
        thermostatWork += added;
}

void ReferenceIntegrateRigidBodyStepKernel::rescaleMomenta(ContextImpl& context, double targetKinetic, int dof, double c, double r1,
                                                           double rest) {
    dynamics->rescaleMomenta(extractVelocities(context), targetKinetic, dof, c, r1, rest, rescalingKinetic, rescalingNewKinetic);
    thermostatWork += rescalingNewKinetic - rescalingKinetic;
}

void ReferenceIntegrateRigidBodyStepKernel::getRescalingEnergies(ContextImpl& context, double& kinetic, double& newKinetic) {
    kinetic = rescalingKinetic;
    newKinetic = rescalingNewKinetic;
}

double ReferenceIntegrateRigidBodyStepKernel::takeThermostatWork(ContextImpl& context) {
    const double work = thermostatWork;
    thermostatWork = 0.0;
    return work;
}

void ReferenceIntegrateRigidBodyStepKernel::tallyKineticEnergy(ContextImpl& context, double sign) {
    double translational, rotational;
    dynamics->computeKineticEnergies(extractVelocities(context), translational, rotational);
    tallyKinetic = translational + rotational;
    tally += sign*tallyKinetic;
}

double ReferenceIntegrateRigidBodyStepKernel::takeTally(ContextImpl& context, double& kinetic) {
    const double taken = tally;
    tally = 0.0;
    kinetic = tallyKinetic;
    return taken;
}

void ReferenceIntegrateRigidBodyStepKernel::computeKineticEnergies(ContextImpl& context, double& translational, double& rotational) {
    dynamics->computeKineticEnergies(extractVelocities(context), translational, rotational);
}

void ReferenceIntegrateRigidBodyStepKernel::computeKickedKineticEnergies(ContextImpl& context, double kick, double constraintTolerance,
                                                                         int forces, double& translational, double& rotational) {
    dynamics->computeKickedKineticEnergies(extractPositions(context), extractVelocities(context), forceSet(context, forces), kick,
                                           constraintTolerance, translational, rotational);
}

double ReferenceIntegrateRigidBodyStepKernel::computeKineticEnergy(ContextImpl& context) {
    return dynamics->computeKineticEnergy(extractVelocities(context));
}

bool ReferenceIntegrateRigidBodyStepKernel::getBodyStates(ContextImpl& context, vector<double>& states) {
    dynamics->getStates(states);
    return true;
}

bool ReferenceIntegrateRigidBodyStepKernel::setBodyStates(ContextImpl& context, const vector<double>& states) {
    if (!dynamics->restoreStates(states, extractPositions(context), extractVelocities(context)))
        return false;
    dynamics->copyParticleArray(extractPositions(context), writtenPositions);
    return true;
}

void ReferenceIntegrateRigidBodyStepKernel::finishStep(ContextImpl& context, double dt) {
    ReferencePlatform::PlatformData& data = platformData(context);
    data.time += dt;
    data.stepCount++;
    dynamics->copyParticleArray(*data.positions, writtenPositions);
}

} // namespace OpenMMRigid

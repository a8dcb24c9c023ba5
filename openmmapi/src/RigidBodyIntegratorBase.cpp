#include "RigidBodyIntegratorBase.h"
#include "RigidBodyKernels.h"
#include "internal/RigidBodyDynamics.h"
#include "internal/RigidBodyMolecules.h"
#include "internal/RigidBodySystem.h"
#include "internal/StepSequence.h"
#include "internal/TimeStepLevels.h"
#include "numerics/SymmetricEigen.h"
#include "openmm/AndersenThermostat.h"
#include "openmm/CompoundIntegrator.h"
#include "openmm/MonteCarloAnisotropicBarostat.h"
#include "openmm/MonteCarloBarostat.h"
#include "openmm/MonteCarloFlexibleBarostat.h"
#include "openmm/MonteCarloMembraneBarostat.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <istream>
#include <ostream>
#include <sstream>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** Whether the System has an AndersenThermostat. */
bool hasAndersenThermostat(const System& system) {
    for (int f = 0; f < system.getNumForces(); f++)
        if (dynamic_cast<const AndersenThermostat*>(&system.getForce(f)) != NULL)
            return true;
    return false;
}

/**
 * The frequencies (in calls of ContextImpl::updateContextState()) of the System's Monte Carlo
 * barostats, whose moves change the potential energy between steps.
 */
vector<int> barostatFrequencies(const System& system) {
    vector<int> frequencies;
    for (int f = 0; f < system.getNumForces(); f++) {
        const Force& force = system.getForce(f);
        int frequency = 0;
        if (auto barostat = dynamic_cast<const MonteCarloBarostat*>(&force))
            frequency = barostat->getFrequency();
        else if (auto anisotropic = dynamic_cast<const MonteCarloAnisotropicBarostat*>(&force))
            frequency = anisotropic->getFrequency();
        else if (auto membrane = dynamic_cast<const MonteCarloMembraneBarostat*>(&force))
            frequency = membrane->getFrequency();
        else if (auto flexible = dynamic_cast<const MonteCarloFlexibleBarostat*>(&force))
            frequency = flexible->getFrequency();
        if (frequency > 0)
            frequencies.push_back(frequency);
    }
    return frequencies;
}

/**
 * Refuse an AndersenThermostat with raised moments of inertia, and where it would thermalise part of a body. OpenMM's Andersen thermostat
 * redraws the velocities of whole constraint clusters (AndersenThermostatImpl::calcParticleGroups), of
 * single particles where there are no constraints. A body that is one cluster is redrawn whole, and its
 * rigid projection is then an exact Maxwell-Boltzmann draw of its momenta; a body spread over several
 * clusters (an explicit body without its internal constraints) would be redrawn in parts, and the
 * projection onto rigid motion of partly redrawn velocities throws energy away: it reads cold.
 */
void checkAndersenThermostat(const System& system, const vector<vector<int> >& bodies, bool explicitBodies, bool raisedMoments,
                             const string& className) {
    if (!hasAndersenThermostat(system))
        return;
    // Each redraw is a Maxwell-Boltzmann draw for the particles' masses: the rotation it gives a body
    // is that of its own moments, which the projection keeps, so raised moments would be heated by I'/I.
    if (raisedMoments)
        throw OpenMMException(className + ": an AndersenThermostat cannot be used with raised moments of inertia (it draws "
                "for the particles' own); use RigidBodyLangevinIntegrator or RigidBodyBussiIntegrator instead");
    // Bodies found from constraints are whole clusters: only explicit ones can be split.
    if (!explicitBodies)
        return;
    vector<int> parent(system.getNumParticles());
    for (size_t i = 0; i < parent.size(); i++)
        parent[i] = i;
    function<int(int)> root = [&](int i) {
        while (parent[i] != i)
            i = parent[i] = parent[parent[i]];
        return i;
    };
    for (int c = 0; c < system.getNumConstraints(); c++) {
        int i, j;
        double distance;
        system.getConstraintParameters(c, i, j, distance);
        parent[root(i)] = root(j);
    }
    for (size_t b = 0; b < bodies.size(); b++)
        for (int p : bodies[b])
            if (root(p) != root(bodies[b][0]))
                throw OpenMMException(className + ": the System's AndersenThermostat would redraw body " + to_string(b) +
                        " in parts (no constraints join its particles " + to_string(bodies[b][0]) + " and " + to_string(p) +
                        "), which cools it; use RigidBodyLangevinIntegrator or RigidBodyBussiIntegrator instead, or keep the "
                        "body's constraints");
}

} // namespace

RigidBodyIntegratorBase::RigidBodyIntegratorBase(const string& className, double stepSize) : className(className),
        explicitBodies(false), rotationMethod(Exact), minimumMoment(0.0), measureShadowWork(false), accuracyCheck(true), checkingStep(false), energyWanted(false), andersenThermostat(false), checkedLedger(0.0), stateUpdates(0), bound(false), forcesAreValid(false), needsProjection(true), restoredCheckpoint(false), loadedVelocityKick(0.0) {
    setStepSize(stepSize);
    setConstraintTolerance(1e-5);
}

RigidBodyIntegratorBase::RigidBodyIntegratorBase(const string& className, double stepSize, const vector<vector<int> >& bodies) :
        className(className), bodies(bodies), explicitBodies(true), rotationMethod(Exact), minimumMoment(0.0), measureShadowWork(false), accuracyCheck(true), checkingStep(false), energyWanted(false), andersenThermostat(false), checkedLedger(0.0), stateUpdates(0), bound(false),
        forcesAreValid(false), needsProjection(true), restoredCheckpoint(false), loadedVelocityKick(0.0) {
    setStepSize(stepSize);
    setConstraintTolerance(1e-5);
    for (size_t b = 0; b < bodies.size(); b++)
        for (int p : bodies[b])
            if (p < 0)
                throw OpenMMException(className + ": body " + to_string(b) + " lists the negative particle index " + to_string(p));
}

void RigidBodyIntegratorBase::setStepSize(double size) {
    if (!isfinite(size))
        throw OpenMMException(className + ": the step size is " + to_string(size) + "; it must be a finite number of ps");
    Integrator::setStepSize(size);
}

void RigidBodyIntegratorBase::setRotationMethod(RotationMethod method) {
    if (method != Exact && method != NoSquish)
        throw OpenMMException(className + ": unknown rotation method " + to_string((int) method) + "; use " + className +
                ".Exact (0) or " + className + ".NoSquish (1)");
    rotationMethod = method;
}

void RigidBodyIntegratorBase::setMinimumMomentOfInertia(double moment) {
    if (!(isfinite(moment) && moment >= 0.0 && moment <= MaximumMinimumMoment)) {
        stringstream text;
        text << className << ": the minimum moment of inertia is " << moment << " amu nm^2; it must be between 0 and " <<
                MaximumMinimumMoment << " amu nm^2";
        throw OpenMMException(text.str());
    }
    if (bound && moment != minimumMoment)
        throw OpenMMException(className + ": the minimum moment of inertia cannot change once the integrator is bound to a "
                "Context (the bodies' moments are set then); set it before creating the Context");
    minimumMoment = moment;
}

void RigidBodyIntegratorBase::setForceGroupSubsteps(const vector<pair<int, int> >& substeps) {
    if (bound && substeps != groupSubsteps)
        throw OpenMMException(className + ": the force groups' substeps cannot change once the integrator is bound to a Context "
                "(which bodies move in the substeps is found then); set them before creating the Context");
    const vector<TimeStepLevel> checked = timeStepLevels(substeps, getIntegrationForceGroups(), className);
    groupSubsteps = substeps;
    if (!substeps.empty()) {
        int groups = 0;
        for (const TimeStepLevel& level : checked)
            groups |= level.groups;
        Integrator::setIntegrationForceGroups(groups);
    }
}

void RigidBodyIntegratorBase::setIntegrationForceGroups(int groups) {
    if (!groupSubsteps.empty() && groups != getIntegrationForceGroups())
        throw OpenMMException(className + ": the integration force groups are those setForceGroupSubsteps() lists; change "
                "them there (or call setForceGroupSubsteps([]) first)");
    Integrator::setIntegrationForceGroups(groups);
}

RigidBodyIntegratorBase::~RigidBodyIntegratorBase() {
}

IntegrateRigidBodyStepKernel& RigidBodyIntegratorBase::getKernel() const {
    if (!bound)
        throw OpenMMException(className + ": this information is available once the integrator is bound to a Context");
    return const_cast<Kernel&>(kernel).getAs<IntegrateRigidBodyStepKernel>();
}

const RigidBodySystem& RigidBodyIntegratorBase::getTopology() const {
    if (!bound)
        throw OpenMMException(className + ": this information is available once the integrator is bound to a Context");
    return *topology;
}

vector<string> RigidBodyIntegratorBase::getKernelNames() {
    return {IntegrateRigidBodyStepKernel::Name()};
}

int RigidBodyIntegratorBase::getNumBodies() const {
    if (explicitBodies && !bound)
        return bodies.size();
    return getTopology().getNumBodies();
}

vector<int> RigidBodyIntegratorBase::getBodyParticles(int index) const {
    const RigidBodySystem& all = getTopology();
    if (index < 0 || index >= all.getNumBodies())
        throw OpenMMException(className + ": body index " + to_string(index) + " out of range (there are " +
                to_string(all.getNumBodies()) + " bodies)");
    return vector<int>(all.getBodyParticles(index), all.getBodyParticles(index) + all.getBodySize(index));
}

const RigidBodySystem& RigidBodyIntegratorBase::getShapedBody(int index) const {
    getBodyParticles(index);  // checks the index
    const RigidBodySystem& all = getTopology();
    if (!all.isShapeKnown(index)) {
        // Why the positions gave it none: not finite, or not set (every particle at one point).
        vector<Vec3> positions;
        context->getPositions(positions);
        all.canShape(index, positions, currentGeometry(*context, all), true);
        throw OpenMMException(className + ": body " + to_string(index) + " is an explicit body, which takes its shape from "
                "the positions; set the Context's positions first");
    }
    return all;
}

vector<Vec3> RigidBodyIntegratorBase::getVelocitiesForTemperature(const System& system, double temperature, int randomSeed) const {
    vector<Vec3> velocities = Integrator::getVelocitiesForTemperature(system, temperature, randomSeed);
    if (!bound)
        return velocities;
    // OpenMM's Context takes the drawn velocities back by getVelocityTimeOffset() with the forces of
    // every group (F_i offset / m_i). With multiple time steps the velocities the integrator holds lag
    // half a kick of the slowest level's forces only (the faster levels' kicks close within the
    // step): the other groups' share is given back at the end, and the slowest forces are the ones
    // that turn the raised bodies below.
    const double offset = getVelocityTimeOffset();
    const int slowest = (levels.size() > 1 ? levels[0].groups : -1);
    velocities = raisedVelocities(velocities, offset, slowest);
    if (offset != 0.0 && slowest != -1) {
        vector<Vec3> fast;
        context->calcForcesAndEnergy(true, false, ~slowest);
        context->getForces(fast);
        for (int i = 0; i < system.getNumParticles(); i++)
            if (system.getParticleMass(i) != 0.0)
                velocities[i] += fast[i]*(offset/system.getParticleMass(i));
    }
    return velocities;
}

vector<Vec3> RigidBodyIntegratorBase::raisedVelocities(vector<Vec3> velocities, double offset, int groups) const {
    if (!topology->hasRaisedMoments())
        return velocities;
    // OpenMM draws each particle's velocity from its mass; projected onto rigid motion, a body's angular
    // velocity about principal axis k then has the variance kT / I_k of its particles' moment I_k. The
    // raised body needs kT / I'_k: the angular velocity about each axis is scaled by sqrt(I_k / I'_k).
    // The axes are those of the body's particles as they are now (a fit to the shape would give the
    // same ones, but the projection has not necessarily run yet); where moments are equal any axes in
    // their plane do, since they are raised alike.
    // OpenMM then takes velocities with a time offset (RigidBodyLangevinIntegrator's dt/2) back by
    // offset F_i / m_i, which turns a body's angular velocity by offset I^-1 tau, with the moments of
    // its particles; the body's own is offset I'^-1 tau. The difference is added here.
    vector<Vec3> positions, forces;
    if (offset != 0.0) {
        context->calcForcesAndEnergy(true, false, groups);
        context->getForces(forces);
    }
    context->getPositions(positions);
    const StepGeometry geometry = currentGeometry(*context, *topology);
    vector<Vec3> whole;
    vector<Vector3> centred, arms;
    vector<double> masses;
    for (int b = 0; b < topology->getNumBodies(); b++) {
        const double* scale = topology->getInertiaScale(b);
        if (!topology->isShapeKnown(b) || !rigidMomentsRaised(scale))
            continue;
        const int n = topology->getBodySize(b);
        const int* members = topology->getBodyParticles(b);
        whole.resize(n);
        topology->assemble(b, positions, geometry, whole.data());
        topology->centreOfMass(b, whole.data(), centred);
        const Vector3 velocity = topology->centreOfMass(b, velocities);
        masses.resize(n);
        Vector3 l = {0.0, 0.0, 0.0}, torque = {0.0, 0.0, 0.0};
        for (int i = 0; i < n; i++) {
            masses[i] = topology->getMasses()[members[i]];
            const Vector3 relative = {velocities[members[i]][0] - velocity[0], velocities[members[i]][1] - velocity[1],
                                      velocities[members[i]][2] - velocity[2]};
            const Vector3 moment = cross(centred[i], relative);
            for (int k = 0; k < 3; k++)
                l[k] += masses[i]*moment[k];
            if (offset != 0.0) {
                const Vector3 turn = cross(centred[i], Vector3{forces[members[i]][0], forces[members[i]][1], forces[members[i]][2]});
                for (int k = 0; k < 3; k++)
                    torque[k] += turn[k];
            }
        }
        Vector3 principal;
        Matrix3 axes;  // principal axes as columns: lab = axes body
        principalAxes(centred, masses, principal, axes);
        const Vector3 bodyL = multiplyTransposed(axes, l), bodyTorque = multiplyTransposed(axes, torque);
        const double* mass = topology->getMassMoments(b);
        const double* moments = topology->getMoments(b);
        Vector3 change = {0.0, 0.0, 0.0};
        for (int k = 0; k < 3; k++)
            if (mass[k] > 0.0)
                change[k] = (bodyL[k]/mass[k])*(1.0/sqrt(scale[k]) - 1.0) + offset*bodyTorque[k]*(1.0/mass[k] - 1.0/moments[k]);
        const Vector3 labChange = multiply(axes, change);
        for (int i = 0; i < n; i++) {
            const Vector3 extra = cross(labChange, centred[i]);
            velocities[members[i]] += Vec3(extra[0], extra[1], extra[2]);
        }
    }
    return velocities;
}

int RigidBodyIntegratorBase::getNumDegreesOfFreedom() const {
    // The rotational degrees of freedom of an explicit body depend on its shape (linear or not).
    for (int b = 0; b < getNumBodies(); b++)
        getShapedBody(b);
    return getTopology().getNumDegreesOfFreedom();
}

double RigidBodyIntegratorBase::computeSystemTemperature() {
    int dof = getNumDegreesOfFreedom();
    if (dof <= 0)
        return 0.0;
    return 2.0*computeKineticEnergy()/(dof*BOLTZ);
}

double RigidBodyIntegratorBase::getShadowWork() const {
    getKernel();  // throws unless bound
    if (!measureShadowWork)
        throw OpenMMException(className + ".getShadowWork: the shadow work is not measured; call setMeasureShadowWork(True) "
                "before the steps");
    return stepState.shadowWork;
}

void RigidBodyIntegratorBase::setMeasureShadowWork(bool measure) {
    // The work the kernel holds is heat or not as the steps that did it measured it.
    if (bound && measure != measureShadowWork)
        takeThermostatWork();
    measureShadowWork = measure;
}

double RigidBodyIntegratorBase::getHeat() const {
    getKernel();  // throws unless bound
    if (!measureShadowWork)
        throw OpenMMException(className + ".getHeat: the heat is not measured; call setMeasureShadowWork(True) before the steps");
    takeThermostatWork();
    return stepState.heat;
}

void RigidBodyIntegratorBase::initialize(ContextImpl& contextRef) {
    if (owner != NULL && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    context = &contextRef;
    owner = &contextRef.getOwner();
    try {
        topology.reset(new RigidBodySystem(contextRef.getSystem(), bodies, explicitBodies, className, minimumMoment));
        if (!explicitBodies && topology->getNumBodies() == 0)
            throw OpenMMException(className + ": the System has no rigid bodies: no cluster of its constraints is rigid (was it "
                    "built with rigidWater=False?); build it with rigid water, or give the bodies explicitly");
        checkAndersenThermostat(contextRef.getSystem(), bodies, explicitBodies, minimumMoment > 0.0, className);
        // OpenMM's CompoundIntegrator draws setVelocitiesToTemperature() for the particles' masses
        // without asking the integrators it holds, and its other integrators move the bodies with the
        // moments of their masses: neither is the ensemble of raised moments.
        if (minimumMoment > 0.0 && dynamic_cast<CompoundIntegrator*>(&contextRef.getIntegrator()) != NULL)
            throw OpenMMException(className + ": raised moments of inertia cannot be used in a CompoundIntegrator, whose "
                    "other integrators move the particles' own moments; use this integrator on its own");
        levels = timeStepLevels(groupSubsteps, getIntegrationForceGroups(), className);
        if (levels.size() > 1) {
            int fastGroups = 0;
            for (size_t l = 1; l < levels.size(); l++)
                fastGroups |= levels[l].groups;
            topology->setFastBodies(particlesReachedBy(contextRef.getSystem(), fastGroups));
        }
        try {
            kernel = context->getPlatform().createKernel(IntegrateRigidBodyStepKernel::Name(), contextRef);
        }
        catch (const OpenMMException& e) {
            // A platform whose plugin cannot make the kernel (an OpenCL device without what it needs, say).
            throw OpenMMException(className + ": " + e.what());
        }
        kernel.getAs<IntegrateRigidBodyStepKernel>().initialize(contextRef, *topology);
        if (explicitBodies)
            RigidBodyMoleculesImpl::install(contextRef, bodies, className);
    }
    catch (...) {
        // The Context was not made: the integrator stays free for another one.
        kernel = Kernel();
        topology.reset();
        context = NULL;
        owner = NULL;
        throw;
    }
    stepState = StepState();
    stepState.seed = chooseRandomSeed(getRequestedSeed());
    accuracyMonitor = AccuracyCheck();
    // An AndersenThermostat redraws particle velocities between steps, not as rigid motion: each
    // step's projection then removes energy that is neither its error nor its heat, and the accuracy
    // check would read that as an energy drift. Such a run is not checked.
    andersenThermostat = hasAndersenThermostat(contextRef.getSystem());
    checkedLedger = 0.0;
    barostats.clear();
    for (int frequency : barostatFrequencies(contextRef.getSystem()))
        barostats.push_back({frequency, 0});
    stateUpdates = 0;
    bound = true;
    forcesAreValid = false;
    needsProjection = true;
}

void RigidBodyIntegratorBase::cleanup() {
    bound = false;
    kernel = Kernel();
    topology.reset();
}

void RigidBodyIntegratorBase::applyLoadedVelocityKick() {
    if (loadedVelocityKick == 0.0)
        return;
    // With multiple time steps the velocities lack half a kick of the slowest forces only.
    context->calcForcesAndEnergy(true, false, levels.size() > 1 ? levels[0].groups : getIntegrationForceGroups());
    getKernel().closingKick(*context, loadedVelocityKick, getConstraintTolerance(), -1);
    loadedVelocityKick = 0.0;
}

void RigidBodyIntegratorBase::captureShapes(const StepGeometry& geometry, bool strict) {
    if (topology->allShapesKnown())
        return;
    vector<Vec3> positions;
    context->getPositions(positions);
    topology->captureShapes(positions, geometry, strict, getConstraintTolerance());
}

void RigidBodyIntegratorBase::projectBodies() {
    IntegrateRigidBodyStepKernel& stepKernel = getKernel();
    const StepGeometry geometry = currentGeometry(*context, *topology);
    captureShapes(geometry, true);  // an explicit body still without a shape: the error says why
    stepKernel.setGeometry(*context, geometry);
    stepKernel.project(*context);
}

void RigidBodyIntegratorBase::stateChanged(State::DataType changed) {
    // Every notice makes the forces from the end of the last step stale: new positions, velocities
    // (which the next projection may change), parameters, or a Force's updateParametersInContext()
    // (ContextImpl::systemChanged(), which sends Energy).
    forcesAreValid = false;
    if (restoredCheckpoint) {
        // ContextImpl::loadCheckpoint() ends with the notices Positions, Velocities, Parameters, Energy.
        if (changed == State::Energy)
            restoredCheckpoint = false;
        return;
    }
    if ((changed != State::Positions && changed != State::Velocities) || !bound)
        return;
    accuracyMonitor.stateSet();
    const bool wasFitted = !needsProjection;
    needsProjection = true;
    IntegrateRigidBodyStepKernel& stepKernel = getKernel();
    // Explicit bodies take their shape from the first positions set, whatever (an energy
    // minimization, say) moves the particles before the first step; a constraint the shape
    // contradicts is an error here.
    if (changed == State::Positions)
        captureShapes(currentGeometry(*context, *topology), false);
    // Project now, so that the State a user reads before the first step (its kinetic energy, its
    // velocities) is the rigid one the step starts from. What cannot be projected yet (an explicit
    // body without a shape, a non-finite coordinate) stays for the step, which says what is wrong.
    if (topology->allShapesKnown()) {
        try {
            // New velocities on bodies already fitted to the positions: only the velocities change.
            if (changed == State::Velocities && wasFitted && stepKernel.positionsAreCurrent(*context))
                stepKernel.projectVelocities(*context);
            else
                projectBodies();
            applyLoadedVelocityKick();
            needsProjection = false;
        }
        catch (const OpenMMException&) {
            // Not lost: the bodies stay to be fitted, and the next step (or computeSystemTemperature()) says
            // what is wrong, as the fit throws again there.
            needsProjection = true;
        }
    }
}

double RigidBodyIntegratorBase::computeKineticEnergy() {
    return getKernel().computeKineticEnergy(*context);
}

namespace {

/** The first bytes of the integrator's part of a checkpoint since version 1. */
const char checkpointMagic[8] = {'O', 'M', 'M', 'R', 'I', 'G', 'I', 'D'};
/**
 * 2: RigidBodyLangevinIntegrator's velocities are half a step behind the positions (1: on-step).
 * 3: the shadow work and the heat follow the step state.
 * 4: then the minimum moment of inertia, and the bodies' states (IntegrateRigidBodyStepKernel::getBodyStates())
 *    where the platform saves them: their number (0 for none), then RigidBodyDynamics::StateSize doubles each.
 */
const int32_t checkpointVersion = 4;

} // namespace

void RigidBodyIntegratorBase::createCheckpoint(ostream& stream) const {
    // The bodies' state is a function of the positions and velocities the checkpoint already holds.
    // The header names the format and the class; the step state follows.
    getKernel();  // throws unless bound
    stream.write(checkpointMagic, sizeof(checkpointMagic));
    stream.write((const char*) &checkpointVersion, sizeof(checkpointVersion));
    int32_t length = className.size();
    stream.write((const char*) &length, sizeof(length));
    stream.write(className.data(), length);
    takeThermostatWork();
    stream.write((const char*) &stepState.seed, sizeof(stepState.seed));
    stream.write((const char*) &stepState.randomCounter, sizeof(stepState.randomCounter));
    if (hasThermostatWork())
        stream.write((const char*) &stepState.thermostatWork, sizeof(stepState.thermostatWork));
    stream.write((const char*) &stepState.shadowWork, sizeof(stepState.shadowWork));
    stream.write((const char*) &stepState.heat, sizeof(stepState.heat));
    stream.write((const char*) &minimumMoment, sizeof(minimumMoment));
    // The bodies' states, where they agree with the positions and velocities the checkpoint holds, so
    // that a load continues the run exactly instead of fitting the bodies again (which rounds).
    vector<double> states;
    const bool current = !needsProjection && getKernel().positionsAreCurrent(*context) && getKernel().getBodyStates(*context, states);
    int32_t numStates = (current ? topology->getNumBodies() : 0);
    stream.write((const char*) &numStates, sizeof(numStates));
    if (numStates > 0)
        stream.write((const char*) states.data(), sizeof(double)*states.size());
}

void RigidBodyIntegratorBase::loadCheckpoint(istream& stream) {
    getKernel();  // throws unless bound
    vector<double> savedStates;
    // A checkpoint from before version 1 has no header: its first bytes are a random number seed.
    int32_t version = 0;
    streampos start = stream.tellg();
    char magic[sizeof(checkpointMagic)];
    stream.read(magic, sizeof(magic));
    if (stream.gcount() == sizeof(magic) && equal(magic, magic + sizeof(magic), checkpointMagic)) {
        int32_t length = -1;
        stream.read((char*) &version, sizeof(version));
        stream.read((char*) &length, sizeof(length));
        if (!stream || length < 0 || length > 256)
            throw OpenMMException(className + ": the checkpoint's integrator header is damaged");
        string writer(length, ' ');
        stream.read(&writer[0], length);
        if (!stream)
            throw OpenMMException(className + ": the checkpoint's integrator header is damaged");
        if (version > checkpointVersion)
            throw OpenMMException(className + ": the checkpoint has version " + to_string(version) + " of this plugin's "
                    "format, newer than this build reads (" + to_string(checkpointVersion) + "); update openmm-rigid");
        // RigidBodyIntegrator and RigidBodyBussiIntegrator write the same state (a RigidBodyIntegrator
        // with a thermostat wrote the checkpoints of RigidBodyBussiIntegrator before it was a class).
        const auto format = [](const string& name) {
            return (name == "RigidBodyBussiIntegrator" ? string("RigidBodyIntegrator") : name);
        };
        if (format(writer) != format(className))
            throw OpenMMException(className + ": the checkpoint was written by a " + writer + "; load it with that integrator");
    }
    else {
        stream.clear();
        stream.seekg(start);
    }
    // Before headers the integrator's data ended the checkpoint: one that ends here was written before
    // the integrator had random numbers (a RigidBodyIntegrator without a thermostat), and means "none
    // drawn yet".
    if (version == 0 && stream.peek() == char_traits<char>::eof()) {
        stream.clear();
        takeThermostatWork();  // the step state stays, with all its work
    }
    else {
        StepState saved;
        stream.read((char*) &saved.seed, sizeof(saved.seed));
        stream.read((char*) &saved.randomCounter, sizeof(saved.randomCounter));
        if (!stream)
            throw OpenMMException(className + ": the checkpoint ends within the state of the integrator's random numbers");
        if (hasThermostatWork()) {
            stream.read((char*) &saved.thermostatWork, sizeof(saved.thermostatWork));
            if (!stream)
                throw OpenMMException(className + ": the checkpoint ends within the thermostat's state (was it written by a "
                        "RigidBodyLangevinIntegrator?)");
        }
        if (version >= 3) {
            stream.read((char*) &saved.shadowWork, sizeof(saved.shadowWork));
            stream.read((char*) &saved.heat, sizeof(saved.heat));
            if (!stream)
                throw OpenMMException(className + ": the checkpoint ends within the integrator's shadow work and heat");
        }
        if (version >= 4) {
            double savedMoment = 0.0;
            int32_t numStates = -1;
            stream.read((char*) &savedMoment, sizeof(savedMoment));
            stream.read((char*) &numStates, sizeof(numStates));
            if (!stream || (numStates != 0 && numStates != topology->getNumBodies()))
                throw OpenMMException(className + ": the checkpoint's integrator state is damaged");
            savedStates.resize((size_t) numStates*RigidBodyDynamics::StateSize);
            stream.read((char*) savedStates.data(), sizeof(double)*savedStates.size());
            if (!stream)
                throw OpenMMException(className + ": the checkpoint ends within the bodies' states");
            if (savedMoment != minimumMoment) {
                // The Context holds the checkpoint's positions and velocities already: fitted at the next step.
                needsProjection = true;
                forcesAreValid = false;
                stringstream text;
                text << className << ": the checkpoint was written with a minimum moment of inertia of " << savedMoment <<
                        " amu nm^2, this integrator has " << minimumMoment << "; its velocities are rigid motion with those "
                        "moments, so load it into an integrator with the same one";
                throw OpenMMException(text.str());
            }
        }
        stepState = saved;
        // The work the kernel accumulated since it was last taken belongs to the state replaced: dropped.
        getKernel().takeThermostatWork(*context);
    }
    loadedVelocityKick = getLoadedVelocityKick(version);
    // A checkpoint starts another run (or rewinds this one): the accuracy check starts again.
    accuracyMonitor.rearm();
    forcesAreValid = false;
    needsProjection = true;
    restoredCheckpoint = false;
    if (!savedStates.empty()) {
        // Explicit bodies of a Context whose positions were never set take their shapes from these.
        captureShapes(currentGeometry(*context, *topology), false);
        if (topology->allShapesKnown() && getKernel().setBodyStates(*context, savedStates)) {
            needsProjection = false;
            // The notices of the positions and velocities the load sends next are of this state: no fit.
            restoredCheckpoint = true;
        }
    }
}

bool RigidBodyIntegratorBase::makeBodiesCurrent(Vec3* box, bool* moved) {
    if (!needsProjection && !getKernel().positionsAreCurrent(*context))
        needsProjection = true;  // moved without a notice: a CompoundIntegrator's other integrator, the minimizer
    if (moved != NULL)
        *moved = needsProjection;
    if (needsProjection) {
        projectBodies();
        forcesAreValid = false;
        applyLoadedVelocityKick();
        needsProjection = false;
    }
    // A new box (setPeriodicBoxVectors() between steps, without new positions) sends no notice; the
    // platform is told, since the particles may not have moved (boxChanged()).
    context->getPeriodicBoxVectors(box[0], box[1], box[2]);
    if (box[0] != forcesBox[0] || box[1] != forcesBox[1] || box[2] != forcesBox[2]) {
        if (moved != NULL)
            *moved = true;
        forcesAreValid = false;
        getKernel().boxChanged(*context);
    }
    // A getState() of other force groups overwrites the forces (multiple time steps keep their own copies).
    if (levels.size() == 1 && context->getLastForceGroups() != getIntegrationForceGroups())
        forcesAreValid = false;
    return forcesAreValid;
}

void RigidBodyIntegratorBase::evaluateForces(const Vec3* box, bool energy) {
    if (levels.size() == 1)
        stepState.potentialEnergy = context->calcForcesAndEnergy(true, energy, getIntegrationForceGroups());
    else {
        // Each level's forces kept in its slot (IntegrateRigidBodyStepKernel::saveForces()).
        stepState.potentialEnergy = 0.0;
        for (size_t l = 0; l < levels.size(); l++) {
            stepState.potentialEnergy += context->calcForcesAndEnergy(true, energy, levels[l].groups);
            getKernel().saveForces(*context, l);
        }
    }
    stepState.potentialKnown = energy;
    forcesAreValid = true;
    for (int k = 0; k < 3; k++)
        forcesBox[k] = box[k];
}

double RigidBodyIntegratorBase::computeKickedKineticEnergy(double kick, const string& method) {
    if (!bound)
        throw OpenMMException(className + "." + method + ": the integrator is not bound to a Context");
    Vec3 box[3];
    if (!makeBodiesCurrent(box))
        evaluateForces(box, false);
    double translational, rotational;
    // With multiple time steps the velocities lack half a kick of the slowest forces only (slot 0).
    getKernel().computeKickedKineticEnergies(*context, kick, getConstraintTolerance(), levels.size() > 1 ? 0 : -1, translational,
                                             rotational);
    return translational + rotational;
}

void RigidBodyIntegratorBase::takeThermostatWork() const {
    if (!bound)
        return;
    // The heat is the thermostat's work over the steps that measured it.
    OpenMMRigid::takeThermostatWork(*context, getKernel(), stepState, measureShadowWork);
}

bool RigidBodyIntegratorBase::barostatMayMove(long long call) const {
    for (const auto& barostat : barostats)
        if ((call - barostat.second)%barostat.first == 0)
            return true;
    return false;
}

void RigidBodyIntegratorBase::step(int steps) {
    if (!bound)
        throw OpenMMException("This Integrator is not bound to a context!");
    IntegrateRigidBodyStepKernel& stepKernel = getKernel();
    // The rule: what the step takes from before (the bodies' frames and momenta, the forces of the
    // last evaluation) is proven current first, or rebuilt. The bodies are current if the positions
    // are those the kernel last wrote and no notice came since; the forces are current if, besides,
    // the Context's last evaluation was this integrator's, of its force groups (a getState() of other
    // groups overwrites them).
    restoredCheckpoint = false;
    for (int i = 0; i < steps; ++i) {
        const bool previousEnergyKnown = stepState.potentialKnown;
        const double previousEnergy = stepState.potentialEnergy;
        stateUpdates++;
        if (context->updateContextState()) {
            // A Force (e.g. a barostat) moved the particles: re-fit the bodies to them.
            forcesAreValid = false;
            needsProjection = true;
            if (!barostatMayMove(stateUpdates))
                for (auto& barostat : barostats)
                    barostat.second = stateUpdates%barostat.first;  // a move where none was expected: count from it
        }
        Vec3 box[3];
        bool moved;
        makeBodiesCurrent(box, &moved);
        // A run taken back to before the check fired (a State or checkpoint loaded) is judged again.
        if (accuracyMonitor.firedAfter(context->getTime()))
            accuracyMonitor.rearm();
        // The accuracy check measures in episodes (internal/AccuracyCheck.h), reading the energy at
        // its samples only: between them, the shadow work is the change of the potential energy less
        // the thermostat's work and what changed the energy between steps (the tally of the kinetic
        // energy at the start and end of each step; the potential energy before and after a move).
        AccuracyCheck::Setting setting;
        checkingStep = false;
        bool sample = false, outsideEnergy = false;
        if (accuracyCheck && !andersenThermostat) {
            setting = getAccuracySetting();
            checkingStep = accuracyMonitor.wantsStep(setting, context->getTime());
        }
        if (checkingStep) {
            if (moved && accuracyMonitor.inWindow()) {
                if (previousEnergyKnown)
                    outsideEnergy = true;
                else
                    accuracyMonitor.restart();  // a move whose energy change is unknown: a new window
            }
            sample = accuracyMonitor.wantsSample(setting);
        }
        else
            accuracyMonitor.restart();
        // The energy at the end of the step: for a sample, and before a barostat may move.
        energyWanted = sample || (checkingStep && barostatMayMove(stateUpdates + 1));
        if (!forcesAreValid || (measureShadowWork && !stepState.potentialKnown))
            evaluateForces(box, measureShadowWork || outsideEnergy);
        if (outsideEnergy)
            checkedLedger += stepState.potentialEnergy - previousEnergy;
        try {
            if (checkingStep)
                stepKernel.tallyKineticEnergy(*context, 1.0);
            executeStep(*context);
            if (checkingStep)
                stepKernel.tallyKineticEnergy(*context, -1.0);
        }
        catch (...) {
            // The step stopped part way (an unstable simulation): the Context goes back to the state
            // the step started from, and everything is rebuilt from it.
            stepKernel.abandonStep(*context);
            needsProjection = true;
            forcesAreValid = false;
            accuracyMonitor.restart();
            throw;
        }
        bool fired = false;
        if (sample) {
            takeThermostatWork();
            double kinetic;
            checkedLedger += stepKernel.takeTally(*context, kinetic);
            const double shadowWork = stepState.potentialEnergy - stepState.thermostatWork - checkedLedger;
            const bool quiet = accuracyMonitor.getMessage().empty();
            accuracyMonitor.record(setting, context->getTime(), shadowWork, kinetic);
            fired = quiet && !accuracyMonitor.getMessage().empty();
        }
        forcesAreValid = true;
        for (int k = 0; k < 3; k++)
            forcesBox[k] = box[k];
        // Told here, inside step(), so that every way of stepping says it (a CompoundIntegrator, C++).
        if (fired && !AccuracyCheck::notify(accuracyMonitor.getMessage()))
            throw OpenMMException(accuracyMonitor.getMessage());
    }
}

} // namespace OpenMMRigid

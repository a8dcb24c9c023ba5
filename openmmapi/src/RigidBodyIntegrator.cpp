#include "RigidBodyIntegrator.h"
#include "RigidBodyKernels.h"
#include "internal/RigidBodySystem.h"
#include "internal/Splitting.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize) : explicitBodies(false), rotationMethod(Exact),
        splitting(Verlet), bound(false), forcesAreValid(false), needsProjection(true) {
    setStepSize(stepSize);
    setConstraintTolerance(1e-5);
}

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize, const vector<vector<int> >& bodies) : bodies(bodies),
        explicitBodies(true), rotationMethod(Exact), splitting(Verlet), bound(false), forcesAreValid(false),
        needsProjection(true) {
    setStepSize(stepSize);
    setConstraintTolerance(1e-5);
    for (size_t b = 0; b < bodies.size(); b++)
        for (int p : bodies[b])
            if (p < 0)
                throw OpenMMException("RigidBodyIntegrator: body " + to_string(b) + " lists the negative particle index " + to_string(p));
}

void RigidBodyIntegrator::setRotationMethod(RotationMethod method) {
    if (method != Exact && method != NoSquish)
        throw OpenMMException("RigidBodyIntegrator: unknown rotation method " + to_string((int) method) +
                "; use RigidBodyIntegrator.Exact (0) or RigidBodyIntegrator.NoSquish (1)");
    rotationMethod = method;
}

void RigidBodyIntegrator::setSplitting(Splitting value) {
    splittingScheme(value);  // throws, naming the valid values, unless value is one
    splitting = value;
}

int RigidBodyIntegrator::getNumForceEvaluations() const {
    return splittingScheme(splitting).numDrifts;
}

const IntegrateRigidBodyStepKernel& RigidBodyIntegrator::getKernel() const {
    if (!bound)
        throw OpenMMException("RigidBodyIntegrator: this information is available once the integrator is bound to a Context");
    return kernel.getAs<const IntegrateRigidBodyStepKernel>();
}

IntegrateRigidBodyStepKernel& RigidBodyIntegrator::getKernel() {
    if (!bound)
        throw OpenMMException("RigidBodyIntegrator: this information is available once the integrator is bound to a Context");
    return kernel.getAs<IntegrateRigidBodyStepKernel>();
}

int RigidBodyIntegrator::getNumBodies() const {
    return getKernel().getBodies().getBodies().size();
}

vector<int> RigidBodyIntegrator::getBodyParticles(int index) const {
    const vector<RigidBody>& all = getKernel().getBodies().getBodies();
    if (index < 0 || index >= (int) all.size())
        throw OpenMMException("RigidBodyIntegrator: body index " + to_string(index) + " out of range (there are " +
                to_string(all.size()) + " bodies)");
    return all[index].particles;
}

const RigidBody& RigidBodyIntegrator::getShapedBody(int index) const {
    vector<int> particles = getBodyParticles(index);  // checks the index
    const RigidBody& body = getKernel().getBodies().getBodies()[index];
    if (!body.shapeKnown) {
        // An explicit body takes its shape from the positions; fit now rather than at the next step.
        RigidBodyIntegrator& self = const_cast<RigidBodyIntegrator&>(*this);
        self.getKernel().project(*context);
        self.needsProjection = false;
        self.forcesAreValid = false;
    }
    return body;
}

string RigidBodyIntegrator::getBodyKind(int index) const {
    return RigidBody::kindName(getShapedBody(index).kind);
}

vector<double> RigidBodyIntegrator::getBodyMoments(int index) const {
    const Vector3& moments = getShapedBody(index).moments;
    return vector<double>(moments.begin(), moments.end());
}

int RigidBodyIntegrator::getNumDegreesOfFreedom() const {
    for (int b = 0; b < getNumBodies(); b++)
        getShapedBody(b);
    return getKernel().getBodies().getNumDegreesOfFreedom();
}

double RigidBodyIntegrator::computeSystemTemperature() {
    int dof = getNumDegreesOfFreedom();
    if (dof <= 0)
        return 0.0;
    return 2.0*computeKineticEnergy()/(dof*BOLTZ);
}

double RigidBodyIntegrator::getTranslationalKineticEnergy() {
    double translational, rotational;
    getKernel().computeKineticEnergies(*context, translational, rotational);
    return translational;
}

double RigidBodyIntegrator::getRotationalKineticEnergy() {
    double translational, rotational;
    getKernel().computeKineticEnergies(*context, translational, rotational);
    return rotational;
}

void RigidBodyIntegrator::initialize(ContextImpl& contextRef) {
    if (owner != NULL && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = context->getPlatform().createKernel(IntegrateRigidBodyStepKernel::Name(), contextRef);
    kernel.getAs<IntegrateRigidBodyStepKernel>().initialize(contextRef, *this);
    bound = true;
    forcesAreValid = false;
    needsProjection = true;
}

void RigidBodyIntegrator::cleanup() {
    bound = false;
    kernel = Kernel();
}

vector<string> RigidBodyIntegrator::getKernelNames() {
    vector<string> names;
    names.push_back(IntegrateRigidBodyStepKernel::Name());
    return names;
}

void RigidBodyIntegrator::stateChanged(State::DataType changed) {
    if (changed == State::Positions || changed == State::Velocities) {
        needsProjection = true;
        forcesAreValid = false;
    }
    else if (changed == State::Parameters)
        forcesAreValid = false;
}

double RigidBodyIntegrator::computeKineticEnergy() {
    return getKernel().computeKineticEnergy(*context, *this);
}

void RigidBodyIntegrator::createCheckpoint(ostream& stream) const {
    // The bodies' state is a function of the positions and velocities the checkpoint already holds.
}

void RigidBodyIntegrator::loadCheckpoint(istream& stream) {
    needsProjection = true;
    forcesAreValid = false;
}

void RigidBodyIntegrator::step(int steps) {
    if (!bound)
        throw OpenMMException("This Integrator is not bound to a context!");
    IntegrateRigidBodyStepKernel& stepKernel = getKernel();
    for (int i = 0; i < steps; ++i) {
        if (context->updateContextState()) {
            // A Force (e.g. a barostat) moved the particles: re-fit the bodies to them.
            forcesAreValid = false;
            needsProjection = true;
        }
        if (needsProjection) {
            stepKernel.project(*context);
            needsProjection = false;
            forcesAreValid = false;
        }
        if (!forcesAreValid)
            context->calcForcesAndEnergy(true, false, getIntegrationForceGroups());
        stepKernel.execute(*context, *this);
        forcesAreValid = true;
    }
}

} // namespace OpenMMRigid

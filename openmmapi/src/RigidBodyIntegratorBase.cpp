#include "RigidBodyIntegratorBase.h"
#include "RigidBodyKernels.h"
#include "internal/RigidBodySystem.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

RigidBodyIntegratorBase::RigidBodyIntegratorBase(const string& className, double stepSize) : className(className),
        explicitBodies(false), rotationMethod(Exact), bound(false), forcesAreValid(false), needsProjection(true) {
    setStepSize(stepSize);
    setConstraintTolerance(1e-5);
}

RigidBodyIntegratorBase::RigidBodyIntegratorBase(const string& className, double stepSize, const vector<vector<int> >& bodies) :
        className(className), bodies(bodies), explicitBodies(true), rotationMethod(Exact), bound(false),
        forcesAreValid(false), needsProjection(true) {
    setStepSize(stepSize);
    setConstraintTolerance(1e-5);
    for (size_t b = 0; b < bodies.size(); b++)
        for (int p : bodies[b])
            if (p < 0)
                throw OpenMMException(className + ": body " + to_string(b) + " lists the negative particle index " + to_string(p));
}

void RigidBodyIntegratorBase::setRotationMethod(RotationMethod method) {
    if (method != Exact && method != NoSquish)
        throw OpenMMException(className + ": unknown rotation method " + to_string((int) method) + "; use " + className +
                ".Exact (0) or " + className + ".NoSquish (1)");
    rotationMethod = method;
}

const RigidBodyStepKernel& RigidBodyIntegratorBase::getKernel() const {
    if (!bound)
        throw OpenMMException(className + ": this information is available once the integrator is bound to a Context");
    return kernel.getAs<const RigidBodyStepKernel>();
}

RigidBodyStepKernel& RigidBodyIntegratorBase::getKernel() {
    if (!bound)
        throw OpenMMException(className + ": this information is available once the integrator is bound to a Context");
    return kernel.getAs<RigidBodyStepKernel>();
}

int RigidBodyIntegratorBase::getNumBodies() const {
    return getKernel().getBodies().getBodies().size();
}

vector<int> RigidBodyIntegratorBase::getBodyParticles(int index) const {
    const vector<RigidBody>& all = getKernel().getBodies().getBodies();
    if (index < 0 || index >= (int) all.size())
        throw OpenMMException(className + ": body index " + to_string(index) + " out of range (there are " +
                to_string(all.size()) + " bodies)");
    return all[index].particles;
}

const RigidBody& RigidBodyIntegratorBase::getShapedBody(int index) const {
    vector<int> particles = getBodyParticles(index);  // checks the index
    const RigidBody& body = getKernel().getBodies().getBodies()[index];
    if (!body.shapeKnown) {
        // An explicit body takes its shape from the positions; fit now rather than at the next step.
        RigidBodyIntegratorBase& self = const_cast<RigidBodyIntegratorBase&>(*this);
        self.getKernel().project(*context);
        self.needsProjection = false;
        self.forcesAreValid = false;
    }
    return body;
}

string RigidBodyIntegratorBase::getBodyKind(int index) const {
    return RigidBody::kindName(getShapedBody(index).kind);
}

vector<double> RigidBodyIntegratorBase::getBodyMoments(int index) const {
    const Vector3& moments = getShapedBody(index).moments;
    return vector<double>(moments.begin(), moments.end());
}

int RigidBodyIntegratorBase::getNumDegreesOfFreedom() const {
    for (int b = 0; b < getNumBodies(); b++)
        getShapedBody(b);
    return getKernel().getBodies().getNumDegreesOfFreedom();
}

double RigidBodyIntegratorBase::computeSystemTemperature() {
    int dof = getNumDegreesOfFreedom();
    if (dof <= 0)
        return 0.0;
    return 2.0*computeKineticEnergy()/(dof*BOLTZ);
}

double RigidBodyIntegratorBase::getTranslationalKineticEnergy() {
    double translational, rotational;
    getKernel().computeKineticEnergies(*context, translational, rotational);
    return translational;
}

double RigidBodyIntegratorBase::getRotationalKineticEnergy() {
    double translational, rotational;
    getKernel().computeKineticEnergies(*context, translational, rotational);
    return rotational;
}

void RigidBodyIntegratorBase::initialize(ContextImpl& contextRef) {
    if (owner != NULL && &contextRef.getOwner() != owner)
        throw OpenMMException("This Integrator is already bound to a context");
    context = &contextRef;
    owner = &contextRef.getOwner();
    kernel = context->getPlatform().createKernel(getKernelNames()[0], contextRef);
    initializeKernel(contextRef);
    bound = true;
    forcesAreValid = false;
    needsProjection = true;
}

void RigidBodyIntegratorBase::cleanup() {
    bound = false;
    kernel = Kernel();
}

void RigidBodyIntegratorBase::stateChanged(State::DataType changed) {
    if (changed == State::Positions || changed == State::Velocities) {
        needsProjection = true;
        forcesAreValid = false;
    }
    else if (changed == State::Parameters)
        forcesAreValid = false;
}

double RigidBodyIntegratorBase::computeKineticEnergy() {
    return getKernel().computeKineticEnergy(*context);
}

void RigidBodyIntegratorBase::createCheckpoint(ostream& stream) const {
    // The bodies' state is a function of the positions and velocities the checkpoint already holds;
    // the kernel adds the state of its random numbers.
    getKernel().createCheckpoint(*context, stream);
}

void RigidBodyIntegratorBase::loadCheckpoint(istream& stream) {
    getKernel().loadCheckpoint(*context, stream);
    needsProjection = true;
    forcesAreValid = false;
}

void RigidBodyIntegratorBase::step(int steps) {
    if (!bound)
        throw OpenMMException("This Integrator is not bound to a context!");
    RigidBodyStepKernel& stepKernel = getKernel();
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
        executeKernel(*context);
        forcesAreValid = true;
    }
}

} // namespace OpenMMRigid

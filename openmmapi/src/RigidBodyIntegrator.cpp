#include "RigidBodyIntegrator.h"
#include "RigidBodyKernels.h"
#include "internal/Splitting.h"
#include "openmm/internal/ContextImpl.h"
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize) : RigidBodyIntegratorBase("RigidBodyIntegrator", stepSize),
        splitting(Verlet) {
}

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize, const vector<vector<int> >& bodies) :
        RigidBodyIntegratorBase("RigidBodyIntegrator", stepSize, bodies), splitting(Verlet) {
}

void RigidBodyIntegrator::setSplitting(Splitting value) {
    splittingScheme(value);  // throws, naming the valid values, unless value is one
    splitting = value;
}

int RigidBodyIntegrator::getNumForceEvaluations() const {
    return splittingScheme(splitting).numDrifts;
}

vector<string> RigidBodyIntegrator::getKernelNames() {
    vector<string> names;
    names.push_back(IntegrateRigidBodyStepKernel::Name());
    return names;
}

void RigidBodyIntegrator::initializeKernel(ContextImpl& context) {
    kernel.getAs<IntegrateRigidBodyStepKernel>().initialize(context, *this);
}

void RigidBodyIntegrator::executeKernel(ContextImpl& context) {
    kernel.getAs<IntegrateRigidBodyStepKernel>().execute(context, *this);
}

} // namespace OpenMMRigid

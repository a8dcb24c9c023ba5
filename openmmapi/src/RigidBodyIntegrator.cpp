#include "RigidBodyIntegrator.h"
#include "internal/RigidBodySystem.h"
#include "internal/StepSequence.h"
#include "internal/Splitting.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <cmath>
#include <sstream>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize) : RigidBodyIntegratorBase("RigidBodyIntegrator", stepSize), splitting(Verlet) {
}

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize, const vector<vector<int> >& bodies) :
        RigidBodyIntegratorBase("RigidBodyIntegrator", stepSize, bodies), splitting(Verlet) {
}

RigidBodyIntegrator::RigidBodyIntegrator(const string& className, double stepSize) :
        RigidBodyIntegratorBase(className, stepSize), splitting(Verlet) {
}

RigidBodyIntegrator::RigidBodyIntegrator(const string& className, double stepSize, const vector<vector<int> >& bodies) :
        RigidBodyIntegratorBase(className, stepSize, bodies), splitting(Verlet) {
}

void RigidBodyIntegrator::setSplitting(Splitting value) {
    splittingScheme(value);  // throws, naming the valid values, unless value is one
    splitting = value;
}

AccuracyCheck::Setting RigidBodyIntegrator::getAccuracySetting() const {
    const BussiBath* bath = getBath();
    AccuracyCheck::Setting setting;
    setting.stepSize = getStepSize();
    setting.temperature = (bath != NULL ? bath->temperature : 0.0);
    setting.rescaling = (bath != NULL);
    setting.dof = getTopology().getNumDegreesOfFreedom();
    setting.description = getClassName() + " (" + splittingScheme(splitting).name + ")";
    // With the moments raised already, raising them further does not help past the step the translation
    // allows (benchmarks/step_cap.py).
    if (getMinimumMomentOfInertia() > 0.0)
        setting.remedies = "Use a smaller step or the Omelyan2 splitting (right for rigid water at 6 and 8 fs, where Verlet is "
                "wrong above 4 fs); raising the moments of inertia further does not help";
    else
        setting.remedies = "Use a smaller step, the Omelyan2 splitting (right for rigid water at 6 and 8 fs, where Verlet is "
                "wrong above 4 fs), or raised moments of inertia";
    return setting;
}

void RigidBodyIntegrator::executeStep(ContextImpl& context) {
    stepRigidBodyIntegrator(context, getKernel(), *this, getBath(), getTopology(), stepState);
}

} // namespace OpenMMRigid

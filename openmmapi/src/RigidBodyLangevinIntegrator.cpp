#include "RigidBodyLangevinIntegrator.h"
#include "internal/RigidBodySystem.h"
#include "internal/StepSequence.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include <cmath>
#include <sstream>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** Throw, naming the quantity, its unit and the value, unless value is finite and >= 0. */
void requireNonNegative(double value, const string& quantity, const string& unit) {
    if (!(isfinite(value) && value >= 0.0)) {
        stringstream text;
        text.precision(17);
        text << "RigidBodyLangevinIntegrator: the " << quantity << " must be a finite number >= 0 (in " << unit << "); got " << value;
        throw OpenMMException(text.str());
    }
}

} // namespace

RigidBodyLangevinIntegrator::RigidBodyLangevinIntegrator(double temperature, double frictionCoeff, double stepSize) :
        RigidBodyIntegratorBase("RigidBodyLangevinIntegrator", stepSize), randomNumberSeed(0) {
    setTemperature(temperature);
    setFriction(frictionCoeff);
}

RigidBodyLangevinIntegrator::RigidBodyLangevinIntegrator(double temperature, double frictionCoeff, double stepSize,
                                                         const vector<vector<int> >& bodies) :
        RigidBodyIntegratorBase("RigidBodyLangevinIntegrator", stepSize, bodies), randomNumberSeed(0) {
    setTemperature(temperature);
    setFriction(frictionCoeff);
}

void RigidBodyLangevinIntegrator::setTemperature(double temp) {
    requireNonNegative(temp, "temperature", "K");
    temperature = temp;
}

void RigidBodyLangevinIntegrator::setFriction(double coeff) {
    requireNonNegative(coeff, "friction", "1/ps");
    friction = coeff;
}

AccuracyCheck::Setting RigidBodyLangevinIntegrator::getAccuracySetting() const {
    AccuracyCheck::Setting setting;
    setting.stepSize = getStepSize();
    setting.friction = friction;
    setting.temperature = temperature;
    setting.dof = getTopology().getNumDegreesOfFreedom();
    setting.description = "RigidBodyLangevinIntegrator";
    // With the moments raised already, raising them further does not help past the step the translation
    // allows (benchmarks/step_cap.py: rigid water 14 fs at friction 1/ps, whatever the minimum).
    if (getMinimumMomentOfInertia() > 0.0)
        setting.remedies = "Use a smaller step (rigid water at friction 1/ps, its moments of inertia raised: at most 14 fs, "
                "where the translation limits the step and the moments of inertia are raised already) or more friction";
    else
        setting.remedies = "Use a smaller step (rigid water at friction 1/ps: at most 8 fs), more friction (10/ps keeps rigid "
                "water right at 10 fs), or raised moments of inertia for the bodies";
    return setting;
}

void RigidBodyLangevinIntegrator::executeStep(ContextImpl& context) {
    stepRigidBodyLangevinIntegrator(context, getKernel(), *this, getTopology(), stepState);
}

} // namespace OpenMMRigid

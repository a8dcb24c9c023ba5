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

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize) : RigidBodyIntegratorBase("RigidBodyIntegrator", stepSize),
        splitting(Verlet), thermostat(false), thermostatTemperature(0.0), thermostatCollisionTime(0.0), randomNumberSeed(0) {
}

RigidBodyIntegrator::RigidBodyIntegrator(double stepSize, const vector<vector<int> >& bodies) :
        RigidBodyIntegratorBase("RigidBodyIntegrator", stepSize, bodies), splitting(Verlet), thermostat(false),
        thermostatTemperature(0.0), thermostatCollisionTime(0.0), randomNumberSeed(0) {
}

void RigidBodyIntegrator::setSplitting(Splitting value) {
    splittingScheme(value);  // throws, naming the valid values, unless value is one
    splitting = value;
}

int RigidBodyIntegrator::getNumForceEvaluations() const {
    return splittingScheme(splitting).numDrifts;
}

void RigidBodyIntegrator::setThermostat(double temperature, double collisionTime) {
    if (!(isfinite(temperature) && temperature >= 0.0) || !(isfinite(collisionTime) && collisionTime > 0.0)) {
        stringstream text;
        text.precision(17);
        text << "RigidBodyIntegrator: the thermostat needs a finite temperature >= 0 (in K) and a finite collision time > 0 "
                "(in ps); got temperature " << temperature << ", collision time " << collisionTime;
        throw OpenMMException(text.str());
    }
    thermostat = true;
    thermostatTemperature = temperature;
    thermostatCollisionTime = collisionTime;
}

namespace {

string noThermostatMessage(const string& method) {
    return "RigidBodyIntegrator." + method + ": this integrator has no thermostat, so no temperature: it conserves the "
           "energy (NVE); call setThermostat(temperature, collisionTime) for constant temperature";
}

} // namespace

double RigidBodyIntegrator::getTemperature() const {
    if (!thermostat)
        throw OpenMMException(noThermostatMessage("getTemperature"));
    return thermostatTemperature;
}

void RigidBodyIntegrator::setTemperature(double temperature) {
    if (!thermostat)
        throw OpenMMException(noThermostatMessage("setTemperature"));
    setThermostat(temperature, thermostatCollisionTime);
}

double RigidBodyIntegrator::getBathTemperature(const string& method) const {
    if (!thermostat)
        throw OpenMMException(noThermostatMessage(method));
    return thermostatTemperature;
}

AccuracyCheck::Setting RigidBodyIntegrator::getAccuracySetting() const {
    AccuracyCheck::Setting setting;
    setting.stepSize = getStepSize();
    setting.temperature = (thermostat ? thermostatTemperature : 0.0);
    setting.rescaling = thermostat;
    setting.dof = getTopology().getNumDegreesOfFreedom();
    setting.description = string("RigidBodyIntegrator (") + splittingScheme(splitting).name +
            (thermostat ? " with the Bussi thermostat)" : ", constant energy)");
    // With the moments raised already, raising them further does not help past the step the translation
    // allows (benchmarks/step_cap.py).
    if (getMinimumMomentOfInertia() > 0.0)
        setting.remedies = "Use a smaller step or the Omelyan2 splitting (setSplitting(RigidBodyIntegrator.Omelyan2), right for "
                "rigid water at 6 and 8 fs where Verlet is wrong above 4 fs); the moments of inertia are raised already, and "
                "raising them further does not help past the step the translation allows (rigid water: 14 fs with Langevin "
                "dynamics)";
    else
        setting.remedies = "Use a smaller step, the Omelyan2 splitting (setSplitting(RigidBodyIntegrator.Omelyan2), right for rigid "
                "water at 6 and 8 fs where Verlet is wrong above 4 fs), or raised moments of inertia for the bodies";
    return setting;
}

double RigidBodyIntegrator::getThermostatWork() {
    getKernel();  // throws unless bound
    takeThermostatWork();
    return stepState.thermostatWork;
}

void RigidBodyIntegrator::executeStep(ContextImpl& context) {
    stepRigidBodyIntegrator(context, getKernel(), *this, getTopology(), stepState);
}

} // namespace OpenMMRigid

#include "RigidBodyIntegratorProxy.h"
#include "RigidBodyIntegrator.h"
#include "RigidIntegratorSerialization.h"
#include "openmm/OpenMMException.h"
#include "openmm/serialization/SerializationNode.h"
#include <memory>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/**
 * The format written by serialize(). Version 1: the first. Version 2: adds the splitting. Version 3:
 * adds the thermostat (thermostat, thermostatTemperature, thermostatCollisionTime) and randomSeed.
 * Version 4: adds minimumMomentOfInertia, measureShadowWork, measureHeat, accuracyCheck (read with defaults).
 */
const int CURRENT_VERSION = 4;

} // namespace

RigidBodyIntegratorProxy::RigidBodyIntegratorProxy() : SerializationProxy("RigidBodyIntegrator") {
}

void RigidBodyIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    node.setIntProperty("version", CURRENT_VERSION);
    const RigidBodyIntegrator& integrator = *reinterpret_cast<const RigidBodyIntegrator*>(object);
    serializeRigidIntegratorBase(integrator, node);
    node.setIntProperty("splitting", integrator.getSplitting());
    node.setBoolProperty("thermostat", integrator.hasThermostat());
    node.setDoubleProperty("thermostatTemperature", integrator.getThermostatTemperature());
    node.setDoubleProperty("thermostatCollisionTime", integrator.getThermostatCollisionTime());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
}

void* RigidBodyIntegratorProxy::deserialize(const SerializationNode& node) const {
    int version = node.getIntProperty("version");
    if (version < 1 || version > CURRENT_VERSION)
        throw OpenMMException("RigidBodyIntegrator: unsupported serialization version " + to_string(version) +
                              " (this library reads versions 1 to " + to_string(CURRENT_VERSION) + ")");
    double stepSize = node.getDoubleProperty("stepSize");
    vector<vector<int> > bodies;
    unique_ptr<RigidBodyIntegrator> integrator;
    if (deserializeExplicitBodies(node, bodies))
        integrator.reset(new RigidBodyIntegrator(stepSize, bodies));
    else
        integrator.reset(new RigidBodyIntegrator(stepSize));
    deserializeRigidIntegratorSettings(node, *integrator);
    // Version 1 files have no splitting: they were written when every step was Verlet.
    int splitting = node.getIntProperty("splitting", RigidBodyIntegrator::Verlet);
    integrator->setSplitting(static_cast<RigidBodyIntegrator::Splitting>(splitting));
    // Versions 1 and 2 have no thermostat: they were written when the integrator conserved energy.
    if (node.getBoolProperty("thermostat", false))
        integrator->setThermostat(node.getDoubleProperty("thermostatTemperature"), node.getDoubleProperty("thermostatCollisionTime"));
    integrator->setRandomNumberSeed(node.getIntProperty("randomSeed", integrator->getRandomNumberSeed()));
    return integrator.release();
}

} // namespace OpenMMRigid

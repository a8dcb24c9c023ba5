#include "RigidBodyLangevinIntegratorProxy.h"
#include "RigidBodyLangevinIntegrator.h"
#include "RigidIntegratorSerialization.h"
#include "openmm/serialization/SerializationNode.h"
#include <memory>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** The format written by serialize(). Version 1: the first; 2: minimumMomentOfInertia, measureShadowWork, measureHeat, accuracyCheck (read with defaults). */
const int CURRENT_VERSION = 2;

} // namespace

RigidBodyLangevinIntegratorProxy::RigidBodyLangevinIntegratorProxy() : SerializationProxy("RigidBodyLangevinIntegrator") {
}

void RigidBodyLangevinIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    node.setIntProperty("version", CURRENT_VERSION);
    const RigidBodyLangevinIntegrator& integrator = *reinterpret_cast<const RigidBodyLangevinIntegrator*>(object);
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("friction", integrator.getFriction());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
    serializeRigidIntegratorBase(integrator, node);
}

void* RigidBodyLangevinIntegratorProxy::deserialize(const SerializationNode& node) const {
    checkSerializationVersion(node, "RigidBodyLangevinIntegrator", CURRENT_VERSION);
    double temperature = node.getDoubleProperty("temperature");
    double friction = node.getDoubleProperty("friction");
    double stepSize = node.getDoubleProperty("stepSize");
    vector<vector<int> > bodies;
    unique_ptr<RigidBodyLangevinIntegrator> integrator;
    if (deserializeExplicitBodies(node, bodies))
        integrator.reset(new RigidBodyLangevinIntegrator(temperature, friction, stepSize, bodies));
    else
        integrator.reset(new RigidBodyLangevinIntegrator(temperature, friction, stepSize));
    deserializeRigidIntegratorSettings(node, *integrator);
    integrator->setRandomNumberSeed(node.getIntProperty("randomSeed", integrator->getRandomNumberSeed()));
    return static_cast<Integrator*>(integrator.release());
}

} // namespace OpenMMRigid

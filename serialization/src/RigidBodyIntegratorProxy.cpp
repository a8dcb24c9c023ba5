#include "RigidBodyIntegratorProxy.h"
#include "RigidBodyBussiIntegrator.h"
#include "RigidBodyBussiIntegratorProxy.h"
#include "RigidBodyIntegrator.h"
#include "RigidIntegratorSerialization.h"
#include "openmm/serialization/SerializationNode.h"
#include <memory>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/**
 * 2: the splitting. 3: the thermostat. 4: the settings of RigidBodyIntegratorBase since.
 * 5: the thermostat is RigidBodyBussiIntegrator's (version 1 of its own type).
 */
const int CURRENT_VERSION = 5;
const int CURRENT_BUSSI_VERSION = 1;

/** The settings RigidBodyIntegrator and RigidBodyBussiIntegrator have in common. */
void serializeSplitting(const RigidBodyIntegrator& integrator, SerializationNode& node) {
    serializeRigidIntegratorBase(integrator, node);
    node.setIntProperty("splitting", integrator.getSplitting());
}

/** A RigidBodyBussiIntegrator, with its bodies, heat bath, seed and splitting read from node. */
RigidBodyIntegrator* readBussi(const SerializationNode& node, const string& temperature, const string& collisionTime) {
    const double stepSize = node.getDoubleProperty("stepSize");
    vector<vector<int> > bodies;
    unique_ptr<RigidBodyBussiIntegrator> integrator(deserializeExplicitBodies(node, bodies) ?
            new RigidBodyBussiIntegrator(node.getDoubleProperty(temperature), node.getDoubleProperty(collisionTime), stepSize, bodies) :
            new RigidBodyBussiIntegrator(node.getDoubleProperty(temperature), node.getDoubleProperty(collisionTime), stepSize));
    integrator->setRandomNumberSeed(node.getIntProperty("randomSeed", 0));
    return integrator.release();
}

/** The settings of RigidBodyIntegratorBase and the splitting, read into integrator (whose ownership the caller keeps). */
void readSettings(const SerializationNode& node, RigidBodyIntegrator& integrator) {
    deserializeRigidIntegratorSettings(node, integrator);
    // Version 1 files have no splitting: they were written when every step was Verlet.
    int splitting = node.getIntProperty("splitting", RigidBodyIntegrator::Verlet);
    integrator.setSplitting(static_cast<RigidBodyIntegrator::Splitting>(splitting));
}

} // namespace

RigidBodyIntegratorProxy::RigidBodyIntegratorProxy() : SerializationProxy("RigidBodyIntegrator") {
}

void RigidBodyIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    node.setIntProperty("version", CURRENT_VERSION);
    serializeSplitting(*reinterpret_cast<const RigidBodyIntegrator*>(object), node);
}

void* RigidBodyIntegratorProxy::deserialize(const SerializationNode& node) const {
    checkSerializationVersion(node, "RigidBodyIntegrator", CURRENT_VERSION);
    unique_ptr<RigidBodyIntegrator> integrator;
    if (node.getBoolProperty("thermostat", false))
        integrator.reset(readBussi(node, "thermostatTemperature", "thermostatCollisionTime"));
    else {
        vector<vector<int> > bodies;
        const double stepSize = node.getDoubleProperty("stepSize");
        integrator.reset(deserializeExplicitBodies(node, bodies) ? new RigidBodyIntegrator(stepSize, bodies) :
                         new RigidBodyIntegrator(stepSize));
    }
    readSettings(node, *integrator);
    // XmlSerializer casts the result to the Integrator it asked for.
    return static_cast<Integrator*>(integrator.release());
}

RigidBodyBussiIntegratorProxy::RigidBodyBussiIntegratorProxy() : SerializationProxy("RigidBodyBussiIntegrator") {
}

void RigidBodyBussiIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    node.setIntProperty("version", CURRENT_BUSSI_VERSION);
    const RigidBodyBussiIntegrator& integrator = *reinterpret_cast<const RigidBodyBussiIntegrator*>(object);
    node.setDoubleProperty("temperature", integrator.getTemperature());
    node.setDoubleProperty("collisionTime", integrator.getCollisionTime());
    node.setIntProperty("randomSeed", integrator.getRandomNumberSeed());
    serializeSplitting(integrator, node);
}

void* RigidBodyBussiIntegratorProxy::deserialize(const SerializationNode& node) const {
    checkSerializationVersion(node, "RigidBodyBussiIntegrator", CURRENT_BUSSI_VERSION);
    unique_ptr<RigidBodyIntegrator> integrator(readBussi(node, "temperature", "collisionTime"));
    readSettings(node, *integrator);
    return static_cast<Integrator*>(integrator.release());
}

} // namespace OpenMMRigid

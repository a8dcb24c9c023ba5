#include "RigidBodyIntegratorProxy.h"
#include "RigidBodyIntegrator.h"
#include "openmm/OpenMMException.h"
#include "openmm/serialization/SerializationNode.h"
#include <memory>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** The format written by serialize(). Version 1: the first. Version 2: adds the splitting. */
const int CURRENT_VERSION = 2;

/** The child node with the given name, or NULL if the node has none. */
const SerializationNode* findChild(const SerializationNode& node, const string& name) {
    for (const SerializationNode& child : node.getChildren())
        if (child.getName() == name)
            return &child;
    return NULL;
}

} // namespace

RigidBodyIntegratorProxy::RigidBodyIntegratorProxy() : SerializationProxy("RigidBodyIntegrator") {
}

void RigidBodyIntegratorProxy::serialize(const void* object, SerializationNode& node) const {
    node.setIntProperty("version", CURRENT_VERSION);
    const RigidBodyIntegrator& integrator = *reinterpret_cast<const RigidBodyIntegrator*>(object);
    node.setDoubleProperty("stepSize", integrator.getStepSize());
    node.setDoubleProperty("constraintTolerance", integrator.getConstraintTolerance());
    node.setIntProperty("integrationForceGroups", integrator.getIntegrationForceGroups());
    node.setIntProperty("rotationMethod", integrator.getRotationMethod());
    node.setIntProperty("splitting", integrator.getSplitting());
    // An explicit empty list of bodies (every particle free) differs from "find the bodies in the
    // System", so the flag is written on its own, not inferred from the number of bodies.
    node.setBoolProperty("explicitBodies", integrator.hasExplicitBodies());
    if (integrator.hasExplicitBodies()) {
        SerializationNode& bodies = node.createChildNode("Bodies");
        for (const vector<int>& body : integrator.getExplicitBodies()) {
            SerializationNode& bodyNode = bodies.createChildNode("Body");
            for (int particle : body)
                bodyNode.createChildNode("Particle").setIntProperty("index", particle);
        }
    }
}

void* RigidBodyIntegratorProxy::deserialize(const SerializationNode& node) const {
    int version = node.getIntProperty("version");
    if (version < 1 || version > CURRENT_VERSION)
        throw OpenMMException("RigidBodyIntegrator: unsupported serialization version " + to_string(version) +
                              " (this library reads versions 1 to " + to_string(CURRENT_VERSION) + ")");
    double stepSize = node.getDoubleProperty("stepSize");
    const SerializationNode* bodiesNode = findChild(node, "Bodies");
    unique_ptr<RigidBodyIntegrator> integrator;
    if (node.getBoolProperty("explicitBodies", bodiesNode != NULL)) {
        vector<vector<int> > bodies;
        if (bodiesNode != NULL) {
            for (const SerializationNode& bodyNode : bodiesNode->getChildren()) {
                vector<int> body;
                for (const SerializationNode& particle : bodyNode.getChildren())
                    body.push_back(particle.getIntProperty("index"));
                bodies.push_back(body);
            }
        }
        integrator.reset(new RigidBodyIntegrator(stepSize, bodies));
    }
    else
        integrator.reset(new RigidBodyIntegrator(stepSize));
    integrator->setConstraintTolerance(node.getDoubleProperty("constraintTolerance", integrator->getConstraintTolerance()));
    integrator->setIntegrationForceGroups(node.getIntProperty("integrationForceGroups", integrator->getIntegrationForceGroups()));
    int method = node.getIntProperty("rotationMethod", integrator->getRotationMethod());
    integrator->setRotationMethod(static_cast<RigidBodyIntegrator::RotationMethod>(method));
    // Version 1 files have no splitting: they were written when every step was Verlet.
    int splitting = node.getIntProperty("splitting", RigidBodyIntegrator::Verlet);
    integrator->setSplitting(static_cast<RigidBodyIntegrator::Splitting>(splitting));
    return integrator.release();
}

} // namespace OpenMMRigid

#include "RigidIntegratorSerialization.h"
#include "openmm/OpenMMException.h"

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/** The child node with the given name, or NULL if the node has none. */
const SerializationNode* findChild(const SerializationNode& node, const string& name) {
    for (const SerializationNode& child : node.getChildren())
        if (child.getName() == name)
            return &child;
    return NULL;
}

} // namespace

void checkSerializationVersion(const SerializationNode& node, const string& type, int current) {
    int version = node.getIntProperty("version");
    if (version < 1 || version > current)
        throw OpenMMException(type + ": serialization version " + to_string(version) + " is not one this build reads (1 to " +
                              to_string(current) + ")");
}

void serializeRigidIntegratorBase(const RigidBodyIntegratorBase& integrator, SerializationNode& node) {
    node.setDoubleProperty("stepSize", integrator.getStepSize());
    node.setDoubleProperty("constraintTolerance", integrator.getConstraintTolerance());
    node.setIntProperty("integrationForceGroups", integrator.getIntegrationForceGroups());
    node.setIntProperty("rotationMethod", integrator.getRotationMethod());
    node.setDoubleProperty("minimumMomentOfInertia", integrator.getMinimumMomentOfInertia());
    // An explicit empty list of bodies (every particle free) differs from "find the bodies in the
    // System", so the flag is written on its own, not inferred from the number of bodies.
    node.setBoolProperty("explicitBodies", integrator.hasExplicitBodies());
    node.setBoolProperty("measureShadowWork", integrator.getMeasureShadowWork());
    node.setBoolProperty("accuracyCheck", integrator.getAccuracyCheck());
    if (!integrator.getForceGroupSubsteps().empty()) {
        SerializationNode& substeps = node.createChildNode("ForceGroupSubsteps");
        for (const pair<int, int>& entry : integrator.getForceGroupSubsteps())
            substeps.createChildNode("Group").setIntProperty("group", entry.first).setIntProperty("substeps", entry.second);
    }
    if (integrator.hasExplicitBodies()) {
        SerializationNode& bodies = node.createChildNode("Bodies");
        for (const vector<int>& body : integrator.getExplicitBodies()) {
            SerializationNode& bodyNode = bodies.createChildNode("Body");
            for (int particle : body)
                bodyNode.createChildNode("Particle").setIntProperty("index", particle);
        }
    }
}

bool deserializeExplicitBodies(const SerializationNode& node, vector<vector<int> >& bodies) {
    const SerializationNode* bodiesNode = findChild(node, "Bodies");
    bodies.clear();
    if (!node.getBoolProperty("explicitBodies", bodiesNode != NULL))
        return false;
    if (bodiesNode != NULL) {
        for (const SerializationNode& bodyNode : bodiesNode->getChildren()) {
            vector<int> body;
            for (const SerializationNode& particle : bodyNode.getChildren())
                body.push_back(particle.getIntProperty("index"));
            bodies.push_back(body);
        }
    }
    return true;
}

void deserializeRigidIntegratorSettings(const SerializationNode& node, RigidBodyIntegratorBase& integrator) {
    integrator.setConstraintTolerance(node.getDoubleProperty("constraintTolerance", integrator.getConstraintTolerance()));
    integrator.setIntegrationForceGroups(node.getIntProperty("integrationForceGroups", integrator.getIntegrationForceGroups()));
    int method = node.getIntProperty("rotationMethod", integrator.getRotationMethod());
    integrator.setRotationMethod(static_cast<RigidBodyIntegratorBase::RotationMethod>(method));
    // Files written before the moments could be raised have none raised.
    integrator.setMinimumMomentOfInertia(node.getDoubleProperty("minimumMomentOfInertia", 0.0));
    // Files written when the heat had a switch of its own measure both if they measured either.
    integrator.setMeasureShadowWork(node.getBoolProperty("measureShadowWork", false) || node.getBoolProperty("measureHeat", false));
    integrator.setAccuracyCheck(node.getBoolProperty("accuracyCheck", integrator.getAccuracyCheck()));
    if (const SerializationNode* substepsNode = findChild(node, "ForceGroupSubsteps")) {
        vector<pair<int, int> > substeps;
        for (const SerializationNode& group : substepsNode->getChildren())
            substeps.push_back({group.getIntProperty("group"), group.getIntProperty("substeps")});
        integrator.setForceGroupSubsteps(substeps);
    }
}

} // namespace OpenMMRigid

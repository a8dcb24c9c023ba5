#ifndef OPENMMRIGID_RIGIDINTEGRATORSERIALIZATION_H_
#define OPENMMRIGID_RIGIDINTEGRATORSERIALIZATION_H_

/*
 * What the serialization proxies of the three integrators share: the version check, the
 * settings of RigidBodyIntegratorBase (step size, constraint tolerance, integration force groups,
 * rotation method, minimum moment of inertia) and the explicit bodies,
 *
 *     explicitBodies="1"
 *     <Bodies>
 *         <Body><Particle index="0"/><Particle index="1"/>...</Body>
 *         ...
 *     </Bodies>
 *
 * Private to the serialization library.
 */

#include "RigidBodyIntegratorBase.h"
#include "openmm/serialization/SerializationNode.h"
#include <string>
#include <vector>

namespace OpenMMRigid {

/** An OpenMMException naming `type` unless the node's version is one this build reads, 1 to `current`. */
void checkSerializationVersion(const OpenMM::SerializationNode& node, const std::string& type, int current);

/** Write the step size, constraint tolerance, integration force groups, rotation method, minimum moment of inertia and explicit bodies. */
void serializeRigidIntegratorBase(const RigidBodyIntegratorBase& integrator, OpenMM::SerializationNode& node);

/**
 * Read whether the bodies are explicit and, if so, the bodies. Files without the explicitBodies flag
 * (none written so far) would have explicit bodies exactly when they hold a Bodies node.
 */
bool deserializeExplicitBodies(const OpenMM::SerializationNode& node, std::vector<std::vector<int> >& bodies);

/** Read the constraint tolerance, integration force groups, rotation method (each with the integrator's value as default) and minimum moment of inertia (0 if absent). */
void deserializeRigidIntegratorSettings(const OpenMM::SerializationNode& node, RigidBodyIntegratorBase& integrator);

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDINTEGRATORSERIALIZATION_H_*/

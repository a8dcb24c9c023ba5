#ifndef OPENMMRIGID_RIGIDBODYINTEGRATORPROXY_H_
#define OPENMMRIGID_RIGIDBODYINTEGRATORPROXY_H_

#include "internal/windowsExportRigid.h"
#include "openmm/serialization/SerializationProxy.h"

namespace OpenMMRigid {

/**
 * This is a proxy for serializing RigidBodyIntegrator objects. It writes the step size, constraint
 * tolerance, integration force groups, rotation method, splitting, thermostat, random number seed
 * and, when the bodies were given explicitly, the particle indices of each body:
 *
 *     <Integrator type="RigidBodyIntegrator" version="3" stepSize=".." constraintTolerance=".."
 *                 integrationForceGroups=".." rotationMethod="0" splitting="0" thermostat="1"
 *                 thermostatTemperature=".." thermostatCollisionTime=".." randomSeed=".." explicitBodies="1">
 *         <Bodies>
 *             <Body><Particle index="0"/><Particle index="1"/>...</Body>
 *             ...
 *         </Bodies>
 *     </Integrator>
 *
 * Every field but the step size (and, with thermostat="1", the thermostat's temperature and
 * collision time) is read with a default (the constructor's), so that files written
 * by earlier versions still load: version 1 (before the splitting was a setting) reads as Verlet,
 * versions 1 and 2 (before the thermostat) as no thermostat.
 */
class OPENMM_EXPORT_RIGID RigidBodyIntegratorProxy : public OpenMM::SerializationProxy {
public:
    RigidBodyIntegratorProxy();
    void serialize(const void* object, OpenMM::SerializationNode& node) const;
    void* deserialize(const OpenMM::SerializationNode& node) const;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYINTEGRATORPROXY_H_*/

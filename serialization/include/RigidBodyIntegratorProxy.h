#ifndef OPENMMRIGID_RIGIDBODYINTEGRATORPROXY_H_
#define OPENMMRIGID_RIGIDBODYINTEGRATORPROXY_H_

#include "internal/windowsExportRigid.h"
#include "openmm/serialization/SerializationProxy.h"

namespace OpenMMRigid {

/**
 * This is a proxy for serializing RigidBodyIntegrator objects. It writes the settings of
 * RigidBodyIntegratorBase (step size, constraint tolerance, integration force groups, rotation method,
 * minimum moment of inertia, multiple time steps, measurement and accuracy check switches, and, when the
 * bodies were given explicitly, the particle indices of each body) and the splitting:
 *
 *     <Integrator type="RigidBodyIntegrator" version="5" stepSize=".." rotationMethod="0" splitting="0" ...>
 *         <Bodies>
 *             <Body><Particle index="0"/><Particle index="1"/>...</Body>
 *         </Bodies>
 *     </Integrator>
 *
 * Every field but the step size is read with a default (the constructor's), so that files of earlier
 * versions load: version 1 (before the splitting was a setting) reads as Verlet; versions 3 and 4 with
 * thermostat="1" (a RigidBodyIntegrator with a thermostat, before RigidBodyBussiIntegrator was a class)
 * read as a RigidBodyBussiIntegrator.
 */
class OPENMM_EXPORT_RIGID RigidBodyIntegratorProxy : public OpenMM::SerializationProxy {
public:
    RigidBodyIntegratorProxy();
    void serialize(const void* object, OpenMM::SerializationNode& node) const;
    void* deserialize(const OpenMM::SerializationNode& node) const;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYINTEGRATORPROXY_H_*/

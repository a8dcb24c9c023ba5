#ifndef OPENMMRIGID_RIGIDBODYBUSSIINTEGRATORPROXY_H_
#define OPENMMRIGID_RIGIDBODYBUSSIINTEGRATORPROXY_H_

#include "internal/windowsExportRigid.h"
#include "openmm/serialization/SerializationProxy.h"

namespace OpenMMRigid {

/**
 * This is a proxy for serializing RigidBodyBussiIntegrator objects: what RigidBodyIntegratorProxy writes,
 * with the heat bath's temperature, collision time and random number seed.
 *
 *     <Integrator type="RigidBodyBussiIntegrator" version="1" temperature=".." collisionTime=".." randomSeed=".." ...>
 */
class OPENMM_EXPORT_RIGID RigidBodyBussiIntegratorProxy : public OpenMM::SerializationProxy {
public:
    RigidBodyBussiIntegratorProxy();
    void serialize(const void* object, OpenMM::SerializationNode& node) const;
    void* deserialize(const OpenMM::SerializationNode& node) const;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYBUSSIINTEGRATORPROXY_H_*/

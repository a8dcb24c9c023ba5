#ifndef OPENMMRIGID_RIGIDBODYLANGEVININTEGRATORPROXY_H_
#define OPENMMRIGID_RIGIDBODYLANGEVININTEGRATORPROXY_H_

#include "internal/windowsExportRigid.h"
#include "openmm/serialization/SerializationProxy.h"

namespace OpenMMRigid {

/**
 * This is a proxy for serializing RigidBodyLangevinIntegrator objects. It writes the temperature,
 * friction, random number seed, step size, constraint tolerance, integration force groups, rotation
 * method and, when the bodies were given explicitly, the particle indices of each body:
 *
 *     <Integrator type="RigidBodyLangevinIntegrator" version="1" temperature=".." friction=".."
 *                 randomSeed=".." stepSize=".." constraintTolerance=".." integrationForceGroups=".."
 *                 rotationMethod="0" explicitBodies="1">
 *         <Bodies>
 *             <Body><Particle index="0"/><Particle index="1"/>...</Body>
 *             ...
 *         </Bodies>
 *     </Integrator>
 *
 * The temperature, friction and step size are required; every other field is read with the
 * constructor's default, so that files written by later versions with new optional fields, and
 * hand-written ones, still load.
 */
class OPENMM_EXPORT_RIGID RigidBodyLangevinIntegratorProxy : public OpenMM::SerializationProxy {
public:
    RigidBodyLangevinIntegratorProxy();
    void serialize(const void* object, OpenMM::SerializationNode& node) const;
    void* deserialize(const OpenMM::SerializationNode& node) const;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYLANGEVININTEGRATORPROXY_H_*/

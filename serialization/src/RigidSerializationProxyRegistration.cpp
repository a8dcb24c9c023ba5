/*
 * Registers the serialization proxies of libOpenMMRigid when the library is loaded, as OpenMM's own
 * plugins do: XmlSerializer looks a proxy up by the dynamic type of the object, so
 * XmlSerializer::serialize<OpenMM::Integrator>() finds RigidBodyIntegratorProxy and
 * RigidBodyLangevinIntegratorProxy with nothing for the caller to do. registerRigidSerializationProxies()
 * is exported as well and may be called again.
 */
#include "RigidBodyBussiIntegrator.h"
#include "RigidBodyBussiIntegratorProxy.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyIntegratorProxy.h"
#include "RigidBodyLangevinIntegrator.h"
#include "RigidBodyLangevinIntegratorProxy.h"
#include "openmm/serialization/SerializationProxy.h"

#if defined(_WIN32)
    #include <windows.h>
    extern "C" OPENMM_EXPORT_RIGID void registerRigidSerializationProxies();
    BOOL WINAPI DllMain(HANDLE hModule, DWORD reason, LPVOID reserved) {
        if (reason == DLL_PROCESS_ATTACH)
            registerRigidSerializationProxies();
        return TRUE;
    }
#else
    extern "C" OPENMM_EXPORT_RIGID void __attribute__((constructor)) registerRigidSerializationProxies();
#endif

extern "C" OPENMM_EXPORT_RIGID void registerRigidSerializationProxies() {
    // Registering again would only replace (and leak) the proxy; once is enough.
    static bool registered = false;
    if (registered)
        return;
    registered = true;
    OpenMM::SerializationProxy::registerProxy(typeid(OpenMMRigid::RigidBodyIntegrator),
                                              new OpenMMRigid::RigidBodyIntegratorProxy());
    OpenMM::SerializationProxy::registerProxy(typeid(OpenMMRigid::RigidBodyBussiIntegrator),
                                              new OpenMMRigid::RigidBodyBussiIntegratorProxy());
    OpenMM::SerializationProxy::registerProxy(typeid(OpenMMRigid::RigidBodyLangevinIntegrator),
                                              new OpenMMRigid::RigidBodyLangevinIntegratorProxy());
}

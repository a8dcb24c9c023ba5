#include "ReferenceRigidKernels.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/Platform.h"
#include "openmm/internal/windowsExport.h"

using namespace OpenMM;

namespace OpenMMRigid {

/** Creates the kernel of RigidBodyIntegrator and RigidBodyLangevinIntegrator for the Reference and CPU platforms. */
class ReferenceRigidKernelFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(std::string name, const Platform& platform, ContextImpl& context) const {
        if (name == IntegrateRigidBodyStepKernel::Name())
            return new ReferenceIntegrateRigidBodyStepKernel(name, platform);
        throw OpenMMException((std::string("Tried to create kernel with illegal kernel name '") + name + "'").c_str());
    }
};

} // namespace OpenMMRigid

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

/**
 * OpenMM's plugin entry point (openmm/PluginInitializer.h): register the kernel factory with the
 * Reference and CPU platforms, whichever are loaded. Registering twice is harmless.
 */
extern "C" OPENMM_EXPORT void registerKernelFactories() {
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.getName() == "Reference" || platform.getName() == "CPU") {
            OpenMMRigid::ReferenceRigidKernelFactory* factory = new OpenMMRigid::ReferenceRigidKernelFactory();
            platform.registerKernelFactory(OpenMMRigid::IntegrateRigidBodyStepKernel::Name(), factory);
        }
    }
}

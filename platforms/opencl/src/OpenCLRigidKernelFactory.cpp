// Registers the common-compute rigid-body kernel with OpenMM's OpenCL platform. Built into
// libOpenMMRigidOpenCL.so, which links the wheel's libOpenMMOpenCL.so.
#include "CommonRigidKernels.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/internal/windowsExport.h"
#include "openmm/opencl/OpenCLContext.h"
#include "openmm/opencl/OpenCLIntegrationUtilities.h"
#include "openmm/opencl/OpenCLPlatform.h"

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

class OpenCLRigidKernelFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(string name, const Platform& platform, ContextImpl& context) const override {
        OpenCLContext& cl = *static_cast<OpenCLPlatform::PlatformData*>(context.getPlatformData())->contexts[0];
        if (name == IntegrateRigidBodyStepKernel::Name())
            return new CommonIntegrateRigidBodyStepKernel(name, platform, cl, [&cl](const System& system) {
                return new OpenCLIntegrationUtilities(cl, system);
            });
        throw OpenMMException("openmm-rigid: the OpenCL platform has no kernel '" + name + "'");
    }
};

} // namespace

} // namespace OpenMMRigid

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

extern "C" OPENMM_EXPORT void registerKernelFactories() {
    // Without an OpenCL platform (no OpenCL runtime) there is nothing to register with.
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.getName() == "OpenCL")
            platform.registerKernelFactory(OpenMMRigid::IntegrateRigidBodyStepKernel::Name(),
                                           new OpenMMRigid::OpenCLRigidKernelFactory());
    }
}

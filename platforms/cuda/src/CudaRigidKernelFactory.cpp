// Registers the common-compute rigid-body kernel with OpenMM's CUDA platform. Built into
// libOpenMMRigidCUDA.so, which links the openmm-cuda wheel's libOpenMMCUDA.so (and through it the
// driver, libcuda.so.1: without a driver the library does not load, and nothing is registered).
#include "CommonRigidKernels.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/internal/ContextImpl.h"
#include "openmm/internal/windowsExport.h"
#include "openmm/cuda/CudaContext.h"
#include "openmm/cuda/CudaIntegrationUtilities.h"
#include "openmm/cuda/CudaPlatform.h"

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

class CudaRigidKernelFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(string name, const Platform& platform, ContextImpl& context) const override {
        CudaContext& cu = *static_cast<CudaPlatform::PlatformData*>(context.getPlatformData())->contexts[0];
        if (name == IntegrateRigidBodyStepKernel::Name())
            return new CommonIntegrateRigidBodyStepKernel(name, platform, cu, [&cu](const System& system) {
                return new CudaIntegrationUtilities(cu, system);
            });
        throw OpenMMException("openmm-rigid: the CUDA platform has no kernel '" + name + "'");
    }
};

} // namespace

} // namespace OpenMMRigid

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

extern "C" OPENMM_EXPORT void registerKernelFactories() {
    // No CUDA platform (libOpenMMCUDA.so not loaded into OpenMM): nothing to register with.
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.getName() == "CUDA")
            platform.registerKernelFactory(OpenMMRigid::IntegrateRigidBodyStepKernel::Name(),
                                           new OpenMMRigid::CudaRigidKernelFactory());
    }
}

// Registers the common-compute rigid-body kernel with OpenMM's CUDA platform. Built into
// libOpenMMRigidCUDA.so, which links the openmm-cuda wheel's libOpenMMCUDA.so (and through it the
// driver, libcuda.so.1: without a driver the library does not load, and nothing is registered).
#include "CommonRigidKernelFactory.h"
#include "openmm/internal/windowsExport.h"
#include "openmm/cuda/CudaContext.h"
#include "openmm/cuda/CudaIntegrationUtilities.h"
#include "openmm/cuda/CudaNonbondedUtilities.h"
#include "openmm/cuda/CudaPlatform.h"

using namespace OpenMM;
using namespace OpenMMRigid;

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

extern "C" OPENMM_EXPORT void registerKernelFactories() {
    // No CUDA platform (libOpenMMCUDA.so not loaded into OpenMM): nothing to register with.
    registerCommonRigidKernels<CommonRigidKernelFactory<CudaPlatform::PlatformData, CudaContext, CudaIntegrationUtilities, CudaNonbondedUtilities> >("CUDA");
}

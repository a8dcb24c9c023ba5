// Registers the common-compute rigid-body kernel with OpenMM's OpenCL platform. Built into
// libOpenMMRigidOpenCL.so, which links the wheel's libOpenMMOpenCL.so.
#include "CommonRigidKernelFactory.h"
#include "openmm/internal/windowsExport.h"
#include "openmm/opencl/OpenCLContext.h"
#include "openmm/opencl/OpenCLIntegrationUtilities.h"
#include "openmm/opencl/OpenCLNonbondedUtilities.h"
#include "openmm/opencl/OpenCLPlatform.h"

using namespace OpenMM;
using namespace OpenMMRigid;

extern "C" OPENMM_EXPORT void registerPlatforms() {
}

extern "C" OPENMM_EXPORT void registerKernelFactories() {
    // Without an OpenCL platform (no OpenCL runtime) there is nothing to register with.
    registerCommonRigidKernels<CommonRigidKernelFactory<OpenCLPlatform::PlatformData, OpenCLContext, OpenCLIntegrationUtilities, OpenCLNonbondedUtilities> >("OpenCL");
}

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The physics tests of TestRigidBodyIntegrator.h or TestRigidBodyThermostats.h *
 * on a GPU platform of OpenMM's common compute layer:                        *
 *                                                                            *
 *   TestGpuRigidBody integrator|thermostats OpenCL|CUDA [single|mixed|double] *
 *                                                                            *
 * (precision double unless given). The platform comes from the OpenMM        *
 * installation's plugin folder and the kernels from libOpenMMRigidOpenCL.so  *
 * or libOpenMMRigidCUDA.so (paths passed by CMake). Exits 77 (skipped) where *
 * the platform is absent (no OpenCL runtime, no CUDA driver). The water      *
 * boxes are prepared on the Reference platform: OpenMM's minimiser crashes   *
 * on PoCL's OpenCL.                                                          *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyIntegrator.h"
#include "TestRigidBodyThermostats.h"
#include <string>

int main(int argc, char* argv[]) {
    if (argc < 3) {
        std::cout << "usage: TestGpuRigidBody integrator|thermostats OpenCL|CUDA [single|mixed|double]" << std::endl;
        return 1;
    }
    const std::string suite = argv[1], platformName = argv[2], precision = (argc > 3 ? argv[3] : "double");
    const std::string plugin = (platformName == "CUDA" ? OPENMMRIGID_CUDA_PLUGIN : OPENMMRIGID_OPENCL_PLUGIN);
    OpenMM::Platform::loadPluginsFromDirectory(OPENMM_PLUGIN_DIR);
    bool found = false;
    for (int i = 0; i < OpenMM::Platform::getNumPlatforms(); i++)
        found = found || OpenMM::Platform::getPlatform(i).getName() == platformName;
    if (!found || plugin.empty()) {
        std::cout << "no " << platformName << " platform (or no plugin built for it): skipped" << std::endl;
        return 77;
    }
    return RigidBodyIntegratorTests::runMain([&]() -> OpenMM::Platform& {
        OpenMM::Platform::loadPluginLibrary(plugin);
        RigidBodyIntegratorTests::platformProperties["Precision"] = precision;
        RigidBodyIntegratorTests::constraintSolverAccuracy = 3e-8;  // OpenMM's GPU SHAKE (see TestRigidBodyIntegrator.h)
        RigidBodyIntegratorTests::preparationPlatform = &OpenMM::Platform::getPlatformByName("Reference");
        return OpenMM::Platform::getPlatformByName(platformName);
    }, suite == "thermostats" ? RigidBodyIntegratorTests::runThermostatTests : RigidBodyIntegratorTests::runPlatformTests);
}

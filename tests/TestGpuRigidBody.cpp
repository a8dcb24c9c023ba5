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
        if (precision != "double") {
            // Forces in float (relative rounding 2^-24 = 6e-8): the total force of a step is zero only
            // to that, so the total momentum walks by about sqrt(500) 6e-8 = 1.3e-6 of itself over the
            // 500 steps the momentum test checks (measured 4e-8 after 100 on PoCL, mixed).
            RigidBodyIntegratorTests::momentumTolerance = 2e-6;
            // Positions stored as float plus a float correction in mixed precision (the bodies' state
            // is double), as float in single: the Python suite's free-motion tolerances, 1e-10 and
            // 1e-5 (measured 1.5e-12 of the largest speed in mixed after 5 ps).
            RigidBodyIntegratorTests::freeMotionTolerance = (precision == "mixed" ? 1e-10 : 1e-5);
            // Single precision rounds each position written to float, 2^-24 of ~2 nm = 1.2e-7 nm, 400
            // times (200 steps out, 200 back): a walk of about sqrt(400) 1.2e-7 = 2.4e-6 nm, which the
            // cluster's dynamics then amplifies (measured on PoCL: 3.3e-6 nm in the positions, 1.4e-4
            // nm/ps in the velocities, which the test allows tolerance/0.1 ps): 3e-5 nm. Mixed keeps
            // double's 1e-8 nm (its positions are float plus a float correction).
            if (precision == "single")
                RigidBodyIntegratorTests::reversalTolerance = 3e-5;
        }
        return OpenMM::Platform::getPlatformByName(platformName);
    }, suite == "thermostats" ? RigidBodyIntegratorTests::runThermostatTests : RigidBodyIntegratorTests::runPlatformTests);
}

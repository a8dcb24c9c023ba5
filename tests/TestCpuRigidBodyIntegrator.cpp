/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The physics tests of RigidBodyIntegrator (TestRigidBodyIntegrator.h) on    *
 * the CPU platform, loaded from the OpenMM installation's plugin folder      *
 * (OPENMM_PLUGIN_DIR, passed by CMake), with deterministic forces.          *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyIntegrator.h"

int main() {
    try {
        OpenMM::Platform::loadPluginsFromDirectory(OPENMM_PLUGIN_DIR);
        registerKernelFactories();  // after the CPU platform exists, so that it gets the kernels too
        RigidBodyIntegratorTests::platformProperties["DeterministicForces"] = "true";
        int failures = RigidBodyIntegratorTests::runPlatformTests(OpenMM::Platform::getPlatformByName("CPU"));
        if (failures > 0) {
            std::cout << failures << " test(s) failed" << std::endl;
            return 1;
        }
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The physics tests of RigidBodyIntegrator (TestRigidBodyIntegrator.h) on    *
 * the Reference platform.                                                    *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyIntegrator.h"

int main() {
    try {
        registerKernelFactories();  // libOpenMMRigidReference: the kernels for Reference and CPU
        int failures = RigidBodyIntegratorTests::runPlatformTests(OpenMM::Platform::getPlatformByName("Reference"));
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

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The physics tests of RigidBodyIntegrator (TestRigidBodyIntegrator.h) on    *
 * the Reference platform.                                                    *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyIntegrator.h"

int main() {
    return RigidBodyIntegratorTests::runMain([]() -> OpenMM::Platform& {
        registerKernelFactories();  // libOpenMMRigidReference: the kernels for Reference and CPU
        return OpenMM::Platform::getPlatformByName("Reference");
    }, RigidBodyIntegratorTests::runPlatformTests);
}

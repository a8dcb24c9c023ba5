/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The tests of RigidBodyLangevinIntegrator                                   *
 * (TestRigidBodyLangevinIntegrator.h) on the Reference platform.             *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyLangevinIntegrator.h"

int main() {
    return RigidBodyIntegratorTests::runMain([]() -> OpenMM::Platform& {
        registerKernelFactories();  // libOpenMMRigidReference: the kernels for Reference and CPU
        return OpenMM::Platform::getPlatformByName("Reference");
    }, RigidBodyIntegratorTests::runLangevinTests);
}

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The constant-temperature tests (RigidBodyLangevinIntegrator and           *
 * RigidBodyIntegrator's thermostat, TestRigidBodyThermostats.h) on the       *
 * Reference platform.                                                        *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyThermostats.h"

int main() {
    return RigidBodyIntegratorTests::runMain([]() -> OpenMM::Platform& {
        registerKernelFactories();  // libOpenMMRigidReference: the kernels for Reference and CPU
        return OpenMM::Platform::getPlatformByName("Reference");
    }, RigidBodyIntegratorTests::runThermostatTests);
}

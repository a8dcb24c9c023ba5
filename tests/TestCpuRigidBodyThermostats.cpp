/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The constant-temperature tests (RigidBodyLangevinIntegrator and           *
 * RigidBodyIntegrator's thermostat, TestRigidBodyThermostats.h) on the CPU  *
 * platform, loaded from the OpenMM installation's plugin folder              *
 * (OPENMM_PLUGIN_DIR, passed by CMake), with deterministic forces.           *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyThermostats.h"

int main() {
    return RigidBodyIntegratorTests::runMain([]() -> OpenMM::Platform& {
        OpenMM::Platform::loadPluginsFromDirectory(OPENMM_PLUGIN_DIR);
        registerKernelFactories();  // after the CPU platform exists, so that it gets the kernels too
        RigidBodyIntegratorTests::platformProperties["DeterministicForces"] = "true";
        return OpenMM::Platform::getPlatformByName("CPU");
    }, RigidBodyIntegratorTests::runThermostatTests);
}

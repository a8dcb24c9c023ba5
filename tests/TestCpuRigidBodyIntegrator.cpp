/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The physics tests of RigidBodyIntegrator (TestRigidBodyIntegrator.h) on    *
 * the CPU platform, loaded from the OpenMM installation's plugin folder      *
 * (OPENMM_PLUGIN_DIR, passed by CMake), with deterministic forces.          *
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyIntegrator.h"

int main() {
    return RigidBodyIntegratorTests::runMain([]() -> OpenMM::Platform& {
        OpenMM::Platform::loadPluginsFromDirectory(OPENMM_PLUGIN_DIR);
        registerKernelFactories();  // after the CPU platform exists, so that it gets the kernels too
        RigidBodyIntegratorTests::platformProperties["DeterministicForces"] = "true";
        RigidBodyIntegratorTests::waterSteps = 2000;  // cheap here: resolves drifts of some tens of kJ/mol/ns
        return OpenMM::Platform::getPlatformByName("CPU");
    }, RigidBodyIntegratorTests::runPlatformTests);
}

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * The physics tests of TestRigidBodyIntegrator.h on the OpenCL platform (PoCL on a
 * machine without a GPU), in the precision given as the first argument
 * (single, mixed or double; default double). The OpenCL platform comes from
 * the OpenMM installation's plugin folder and the kernels from
 * libOpenMMRigidOpenCL.so (both paths passed by CMake). Exits 77 (skipped)
 * where there is no OpenCL platform.
 * -------------------------------------------------------------------------- */

#include "TestRigidBodyIntegrator.h"
#include <cstdlib>

int main(int argc, char* argv[]) {
    OpenMM::Platform::loadPluginsFromDirectory(OPENMM_PLUGIN_DIR);
    bool found = false;
    for (int i = 0; i < OpenMM::Platform::getNumPlatforms(); i++)
        found = found || OpenMM::Platform::getPlatform(i).getName() == "OpenCL";
    if (!found) {
        std::cout << "no OpenCL platform: skipped" << std::endl;
        return 77;
    }
    return RigidBodyIntegratorTests::runMain([&]() -> OpenMM::Platform& {
        OpenMM::Platform::loadPluginLibrary(OPENMMRIGID_OPENCL_PLUGIN);
        RigidBodyIntegratorTests::platformProperties["Precision"] = (argc > 1 ? argv[1] : "double");
        RigidBodyIntegratorTests::constraintSolverAccuracy = 3e-8;  // OpenMM's SHAKE on OpenCL (see TestRigidBodyIntegrator.h)
        RigidBodyIntegratorTests::preparationPlatform = &OpenMM::Platform::getPlatformByName("Reference");  // the minimiser crashes on PoCL
        return OpenMM::Platform::getPlatformByName("OpenCL");
    });
}

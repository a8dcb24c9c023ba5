#ifndef OPENMMRIGID_PLATFORMSUPPORT_H_
#define OPENMMRIGID_PLATFORMSUPPORT_H_

#include "internal/windowsExportRigid.h"
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * Get the platforms registered now that have the rigid-body integrators' kernels (the plugins for
 * them are loaded): a Context with a RigidBodyIntegrator or RigidBodyLangevinIntegrator can be
 * created on each. CUDA's plugin comes in its own package, openmm-rigid-cuda-13.
 *
 * Only these platforms claim the kernels, so a Context made without naming a platform takes the
 * fastest of them, as OpenMM chooses for any System (the CPU platform, say, where the GPU platform's
 * plugin is missing). A Context made on a platform that is not listed fails with OpenMM's own
 * OpenMMException ("does not support all required kernels"): OpenMM checks the kernels before the
 * integrator can say more. (The Python package rewords it, naming the platforms listed here.)
 *
 * @return the names of the platforms, e.g. Reference, CPU, OpenCL
 */
OPENMM_EXPORT_RIGID std::vector<std::string> getSupportedPlatforms();

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_PLATFORMSUPPORT_H_*/

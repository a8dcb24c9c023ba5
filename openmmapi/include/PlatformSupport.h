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
 * @return the names of the platforms, e.g. Reference, CPU, OpenCL
 */
OPENMM_EXPORT_RIGID std::vector<std::string> getSupportedPlatforms();

/**
 * Give every platform registered now that has no rigid-body kernels (CUDA without the
 * openmm-rigid-cuda plugin, say) a kernel that cannot be created: a Context made for one of them with
 * a RigidBodyIntegrator then fails with an OpenMMException that names the platforms which do
 * support it and how to get the missing plugin, instead of OpenMM's generic "does not support all
 * required kernels". Call it after the plugins are loaded (the Python package does so on import);
 * a plugin loaded later replaces it with its real kernel.
 *
 * A Context made without a platform then takes the fastest platform as OpenMM would for a
 * System without rigid bodies, and fails with that message if the plugin for it is missing.
 */
OPENMM_EXPORT_RIGID void explainUnsupportedPlatforms();

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_PLATFORMSUPPORT_H_*/

#ifndef OPENMMRIGID_COMMONRIGIDKERNELFACTORY_H_
#define OPENMMRIGID_COMMONRIGIDKERNELFACTORY_H_

#include "CommonRigidKernels.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/Platform.h"
#include "openmm/internal/ContextImpl.h"
#include <string>

namespace OpenMMRigid {

/**
 * The kernel factory of a common-compute platform: its ComputeContext (the first of the platform's
 * contexts) and its IntegrationUtilities class, for the solver of the constraints among free
 * particles. Each GPU plugin instantiates it with its platform's types and registers it with
 * registerCommonRigidKernels().
 */
template <class PlatformData, class ContextType, class UtilitiesType>
class CommonRigidKernelFactory : public OpenMM::KernelFactory {
public:
    OpenMM::KernelImpl* createKernelImpl(std::string name, const OpenMM::Platform& platform, OpenMM::ContextImpl& context) const override {
        ContextType& cc = *static_cast<PlatformData*>(context.getPlatformData())->contexts[0];
        if (name == IntegrateRigidBodyStepKernel::Name())
            return new CommonIntegrateRigidBodyStepKernel(name, platform, cc, [&cc](const OpenMM::System& system) {
                return new UtilitiesType(cc, system);
            });
        throw OpenMM::OpenMMException("openmm-rigid: the " + platform.getName() + " platform has no kernel '" + name + "'");
    }
};

/** Register the factory with the platform of this name, if OpenMM has it (nothing to do otherwise). */
template <class Factory>
void registerCommonRigidKernels(const std::string& platformName) {
    for (int i = 0; i < OpenMM::Platform::getNumPlatforms(); i++) {
        OpenMM::Platform& platform = OpenMM::Platform::getPlatform(i);
        if (platform.getName() == platformName)
            platform.registerKernelFactory(IntegrateRigidBodyStepKernel::Name(), new Factory());
    }
}

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_COMMONRIGIDKERNELFACTORY_H_*/

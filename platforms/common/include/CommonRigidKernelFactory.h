#ifndef OPENMMRIGID_COMMONRIGIDKERNELFACTORY_H_
#define OPENMMRIGID_COMMONRIGIDKERNELFACTORY_H_

#include "CommonRigidKernels.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/Platform.h"
#include "openmm/internal/ContextImpl.h"
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * Makes each device of a common-compute platform rebuild its neighbour list at its next force
 * evaluation. OpenMM 8.6.1 rebuilds one only when a particle has moved by half the padding since it
 * was built (the box is not compared), and the common interface has no call to ask for a rebuild;
 * the platform's setAtomBlockRange() forces one, so each device is given the range of tiles it has
 * now: all of them on one device, and on several the partition their load balancing last chose
 * (read back from each device's first tile, which keeps the devices' ranges adjacent).
 */
template <class NonbondedType>
void rebuildNeighbourLists(OpenMM::ComputeContext& cc) {
    const std::vector<OpenMM::ComputeContext*> contexts = cc.getAllContexts();
    const double blocks = cc.getNumAtomBlocks();
    const double tiles = blocks*(blocks + 1)/2;
    for (size_t i = 0; i < contexts.size(); i++) {
        const double start = contexts[i]->getNonbondedUtilities().getStartTileIndex()/tiles;
        const double end = (i + 1 < contexts.size() ? contexts[i + 1]->getNonbondedUtilities().getStartTileIndex()/tiles : 1.0);
        static_cast<NonbondedType&>(contexts[i]->getNonbondedUtilities()).setAtomBlockRange(start, end);
    }
}

/**
 * The kernel factory of a common-compute platform: its ComputeContext (the first of the platform's
 * contexts), its IntegrationUtilities class, for the solver of the constraints among free
 * particles, and its NonbondedUtilities class, for rebuildNeighbourLists(). Each GPU plugin
 * instantiates it with its platform's types and registers it with registerCommonRigidKernels().
 */
template <class PlatformData, class ContextType, class UtilitiesType, class NonbondedType>
class CommonRigidKernelFactory : public OpenMM::KernelFactory {
public:
    OpenMM::KernelImpl* createKernelImpl(std::string name, const OpenMM::Platform& platform, OpenMM::ContextImpl& context) const override {
        ContextType& cc = *static_cast<PlatformData*>(context.getPlatformData())->contexts[0];
        if (name == IntegrateRigidBodyStepKernel::Name())
            return new CommonIntegrateRigidBodyStepKernel(name, platform, cc, [&cc](const OpenMM::System& system) {
                return new UtilitiesType(cc, system);
            }, [&cc]() {
                rebuildNeighbourLists<NonbondedType>(cc);
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

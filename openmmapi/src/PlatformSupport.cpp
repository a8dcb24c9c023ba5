#include "PlatformSupport.h"
#include "RigidBodyKernels.h"
#include "openmm/KernelFactory.h"
#include "openmm/OpenMMException.h"
#include "openmm/Platform.h"
#include <mutex>
#include <set>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

mutex explainedLock;
/** The platforms given the explaining factory (a plugin loaded after it replaces it, unseen here). */
set<string> explainedPlatforms;

/** Creates no kernel: says which platforms have the rigid-body kernels and how to get the missing plugin. */
class UnsupportedPlatformFactory : public KernelFactory {
public:
    KernelImpl* createKernelImpl(string name, const Platform& platform, ContextImpl& context) const override {
        string supported;
        for (const string& name : getSupportedPlatforms())
            supported += (supported.empty() ? "" : ", ") + name;
        string hint;
        if (platform.getName() == "CUDA")
            hint = " For CUDA, install the plugin for your CUDA version (pip install openmm-rigid[cuda13], which brings "
                   "openmm-rigid-cuda-13).";
        throw OpenMMException("the rigid-body integrators have no kernels for the " + platform.getName() + " platform: they run "
                "on " + supported + "." + hint + " Or create the Context on one of those platforms.");
    }
};

bool hasRealKernels(Platform& platform) {
    if (!platform.supportsKernels({IntegrateRigidBodyStepKernel::Name()}))
        return false;
    lock_guard<mutex> lock(explainedLock);
    return explainedPlatforms.count(platform.getName()) == 0;
}

} // namespace

vector<string> getSupportedPlatforms() {
    vector<string> names;
    for (int i = 0; i < Platform::getNumPlatforms(); i++)
        if (hasRealKernels(Platform::getPlatform(i)))
            names.push_back(Platform::getPlatform(i).getName());
    return names;
}

void explainUnsupportedPlatforms() {
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.supportsKernels({IntegrateRigidBodyStepKernel::Name()}))
            continue;
        UnsupportedPlatformFactory* factory = new UnsupportedPlatformFactory();
        {
            lock_guard<mutex> lock(explainedLock);
            explainedPlatforms.insert(platform.getName());
        }
        platform.registerKernelFactory(IntegrateRigidBodyStepKernel::Name(), factory);
    }
}

} // namespace OpenMMRigid

#include "PlatformSupport.h"
#include "RigidBodyKernels.h"
#include "openmm/Platform.h"

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

vector<string> getSupportedPlatforms() {
    vector<string> names;
    for (int i = 0; i < Platform::getNumPlatforms(); i++) {
        Platform& platform = Platform::getPlatform(i);
        if (platform.supportsKernels({IntegrateRigidBodyStepKernel::Name()}))
            names.push_back(platform.getName());
    }
    return names;
}

} // namespace OpenMMRigid

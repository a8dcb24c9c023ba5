/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * A platform without the rigid-body kernels: once explainUnsupportedPlatforms() *
 * has run, a Context on it fails with a message that names the integrator's  *
 * class and the platforms that have the kernels, not OpenMM's generic "does  *
 * not support all required kernels"; the platforms with kernels keep them.   *
 * The platform without them is the Reference platform under another name.   *
 * -------------------------------------------------------------------------- */

#include "PlatformSupport.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyLangevinIntegrator.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "openmm/reference/ReferencePlatform.h"
#include <iostream>
#include <string>
#include <vector>

using namespace OpenMM;
using namespace OpenMMRigid;
using namespace std;

extern "C" void registerKernelFactories();

namespace {

class UnsupportedPlatform : public ReferencePlatform {
public:
    const string& getName() const override {
        static const string name = "Unsupported";
        return name;
    }
};

void check(bool condition, const string& what) {
    if (!condition)
        throw runtime_error(what);
}

template <class IntegratorClass>
void checkMessage(IntegratorClass& integrator, const string& className) {
    System system;
    for (int i = 0; i < 3; i++)
        system.addParticle(1.0);
    system.addConstraint(0, 1, 0.1);
    system.addConstraint(1, 2, 0.1);
    system.addConstraint(0, 2, 0.15);
    try {
        Context context(system, integrator, Platform::getPlatformByName("Unsupported"));
        check(false, className + ": no error on a platform without kernels");
    }
    catch (const OpenMMException& e) {
        string message = e.what();
        check(message.find(className + ":") == 0, "the message names the class: " + message);
        check(message.find("Unsupported platform") != string::npos, "the message names the platform: " + message);
        check(message.find("Reference") != string::npos, "the message names the platforms with kernels: " + message);
        check(message.find("does not support all required kernels") == string::npos, "not OpenMM's generic message: " + message);
    }
    // The Reference platform keeps its kernels.
    Context context(system, integrator, Platform::getPlatformByName("Reference"));
    context.setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.05, 0.1, 0)});
    integrator.step(2);
}

} // namespace

int main() {
    try {
        Platform::registerPlatform(new UnsupportedPlatform());
        registerKernelFactories();  // the Reference (and CPU) kernels of this plugin
        explainUnsupportedPlatforms();
        vector<string> supported = getSupportedPlatforms();
        check(!supported.empty() && supported[0] == "Reference", "Reference is supported");
        for (const string& name : supported)
            check(name != "Unsupported", "the platform without kernels is not listed as supported");
        RigidBodyIntegrator verlet(0.001);
        checkMessage(verlet, "RigidBodyIntegrator");
        RigidBodyLangevinIntegrator langevin(300.0, 1.0, 0.001);
        checkMessage(langevin, "RigidBodyLangevinIntegrator");
    }
    catch (const exception& e) {
        cout << "FAIL: " << e.what() << endl;
        return 1;
    }
    cout << "Done" << endl;
    return 0;
}

/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * A platform without the rigid-body kernels, faster than every other: it     *
 * does not claim the kernels, so a Context made without naming a platform    *
 * takes one that has them (as it would with a stock integrator on a platform *
 * that has its kernels), and a Context made on it fails with an              *
 * OpenMMException; getSupportedPlatforms() leaves it out. The platform       *
 * without kernels is the Reference platform under another name.             *
 * -------------------------------------------------------------------------- */

#include "PlatformSupport.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyKernels.h"
#include "RigidBodyLangevinIntegrator.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/System.h"
#include "openmm/Vec3.h"
#include "openmm/VerletIntegrator.h"
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
    double getSpeed() const override {
        return 1e6;  // faster than any real platform: OpenMM would choose it if it claimed the kernels
    }
};

void check(bool condition, const string& what) {
    if (!condition)
        throw runtime_error(what);
}

System water() {
    System system;
    for (int i = 0; i < 3; i++)
        system.addParticle(1.0);
    system.addConstraint(0, 1, 0.1);
    system.addConstraint(1, 2, 0.1);
    system.addConstraint(0, 2, 0.15);
    return system;
}

template <class IntegratorClass>
void checkChoice(IntegratorClass& integrator, const string& className) {
    System system = water();
    {
        // No platform named: the fastest one that has the kernels, never the one without.
        Context context(system, integrator);
        const string chosen = context.getPlatform().getName();
        check(chosen != "Unsupported", className + ": a Context without a named platform took the platform without kernels");
        check(Platform::getPlatformByName(chosen).supportsKernels({IntegrateRigidBodyStepKernel::Name()}),
              className + ": the chosen platform has the kernels");
        context.setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.05, 0.1, 0)});
        integrator.step(2);
    }
    // Naming the platform without kernels is an OpenMMException, and the integrator stays usable.
    bool thrown = false;
    try {
        Context context(system, integrator, Platform::getPlatformByName("Unsupported"));
    }
    catch (const OpenMMException&) {
        thrown = true;
    }
    check(thrown, className + ": no error on a platform without kernels");
    Context context(system, integrator, Platform::getPlatformByName("Reference"));
    context.setPositions({Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0.05, 0.1, 0)});
    integrator.step(2);
}

} // namespace

int main() {
    try {
        Platform::registerPlatform(new UnsupportedPlatform());
        registerKernelFactories();  // the Reference (and CPU) kernels of this plugin
        // A stock integrator takes the fastest platform: the fake one is really chosen when it qualifies.
        {
            System system = water();
            VerletIntegrator verlet(0.001);
            Context context(system, verlet);
            check(context.getPlatform().getName() == "Unsupported", "a stock integrator takes the fastest platform");
        }
        vector<string> supported = getSupportedPlatforms();
        check(!supported.empty() && supported[0] == "Reference", "Reference is supported");
        for (const string& name : supported)
            check(name != "Unsupported", "the platform without kernels is not listed as supported");
        check(!Platform::getPlatformByName("Unsupported").supportsKernels({IntegrateRigidBodyStepKernel::Name()}),
              "the platform without kernels does not claim them");
        RigidBodyIntegrator verlet(0.001);
        checkChoice(verlet, "RigidBodyIntegrator");
        RigidBodyLangevinIntegrator langevin(300.0, 1.0, 0.001);
        checkChoice(langevin, "RigidBodyLangevinIntegrator");
    }
    catch (const exception& e) {
        cout << "FAIL: " << e.what() << endl;
        return 1;
    }
    cout << "Done" << endl;
    return 0;
}

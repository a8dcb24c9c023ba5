/* -------------------------------------------------------------------------- *
 *                               OpenMM-Rigid                                 *
 * -------------------------------------------------------------------------- *
 * What a step costs the host on OpenCL: the host waits and the kernel        *
 * launches of one step of each integrator, counted by OpenCLCallCounter.c    *
 * (which every OpenCL call of OpenMM and of the plugins goes through), on a  *
 * PME box of 64 rigid TIP3P waters, against stock OpenMM's VerletIntegrator *
 * and LangevinMiddleIntegrator with SETTLE on the same System:               *
 *                                                                            *
 *   TestOpenCLCallCounts [single|mixed|double]     (mixed unless given)      *
 *                                                                            *
 * Asserted, per step, on steps without an atom reorder: the rigid-body       *
 * integrators make the host stall no more often than stock does (the force  *
 * evaluation's own waits are the same in both), i.e. their own stages add   *
 * no blocking read, Bussi's thermostat included (its kinetic-energy sum and *
 * factor stay on the device); with the shadow work and heat measured (each  *
 * step then reads its energy), RigidBodyBussiIntegrator stalls no more than *
 * RigidBodyIntegrator measuring the same (its heat stays on the device);    *
 * and they launch at most two kernels more than stock. These steps are      *
 * ordinary ones, with the accuracy check off (between its episodes it reads *
 * nothing). Within an episode (the first 4 ps of a Context) every step but  *
 * the check's samples stalls no more than stock's (the heat and the kinetic *
 * energy's tally stay on the device); the samples, which read the energy,   *
 * are counted. A barostat step and a reordering step are measured and       *
 * printed.                                                                   *
 * Exits 77 (skipped) where there is no OpenCL platform.                      *
 * -------------------------------------------------------------------------- */

#include "../RigidBodyTestSystems.h"
#include "RigidBodyBussiIntegrator.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyLangevinIntegrator.h"
#include "internal/AccuracyCheck.h"
#include "openmm/LangevinMiddleIntegrator.h"
#include "openmm/MonteCarloBarostat.h"
#include <cstdio>
#include <initializer_list>
#include <string>
#include <vector>

extern "C" {
typedef struct {
    long stalls, overlappedWaits, blockingReads, blockingWrites, finishes, kernelLaunches, transfers;
} OpenCLCallCounts;
OpenCLCallCounts openclCallCounts(void);
void openclCallCountsReset(void);
}

using namespace RigidBodyIntegratorTests;

namespace {

struct StepCounts {
    string name;
    double stalls = 0, overlappedWaits = 0, launches = 0, transfers = 0;  // per step
    long worstStalls = 0;                                                  // the most in one step
    std::vector<long> stepStalls;                                          // each step's
    long reorders = 0;
};

/** Steps the integrator stepsToMeasure times, one step at a time, and counts each step's calls. */
StepCounts measure(const string& name, Context& context, Integrator& integrator, int steps) {
    StepCounts result;
    result.name = name;
    for (int i = 0; i < steps; i++) {
        openclCallCountsReset();
        integrator.step(1);
        OpenCLCallCounts c = openclCallCounts();
        result.stalls += c.stalls;
        result.overlappedWaits += c.overlappedWaits;
        result.launches += c.kernelLaunches;
        result.transfers += c.transfers;
        result.worstStalls = std::max(result.worstStalls, c.stalls);
        result.stepStalls.push_back(c.stalls);
    }
    result.stalls /= steps;
    result.overlappedWaits /= steps;
    result.launches /= steps;
    result.transfers /= steps;
    return result;
}

void print(const StepCounts& c) {
    std::printf("%-44s stalls %5.2f (worst step %ld)  overlapped waits %5.2f  launches %6.2f  transfers %5.2f\n", c.name.c_str(),
                c.stalls, c.worstStalls, c.overlappedWaits, c.launches, c.transfers);
}

} // namespace

int main(int argc, char* argv[]) {
    const string precision = (argc > 1 ? argv[1] : "mixed");
    try {
        Platform::loadPluginsFromDirectory(OPENMM_PLUGIN_DIR);
        bool found = false;
        for (int i = 0; i < Platform::getNumPlatforms(); i++)
            found = found || Platform::getPlatform(i).getName() == "OpenCL";
        if (!found) {
            std::cout << "no OpenCL platform: skipped" << std::endl;
            return 77;
        }
        Platform::loadPluginLibrary(OPENMMRIGID_OPENCL_PLUGIN);
        Platform& platform = Platform::getPlatformByName("OpenCL");
        preparationPlatform = &Platform::getPlatformByName("Reference");
        Scene scene = makeWaterBox(platform, false);
        System& system = *scene.system;
        const std::map<string, string> properties = {{"Precision", precision}};
        // Steps 21 to 60 of a Context: no reorder (OpenMM reorders every 250 steps); 40 steps, a
        // multiple of the period (2 or 4 steps) with which stock's launches vary.
        const int warmup = 20, steps = 40;
        auto run = [&](const string& name, Integrator& integrator) {
            Context context(system, integrator, platform, properties);
            context.setPositions(scene.positions);
            context.setVelocities(scene.velocities);
            integrator.step(warmup);
            return measure(name, context, integrator, steps);
        };
        VerletIntegrator stockVerlet(0.002);
        LangevinMiddleIntegrator stockLangevin(300.0, 1.0, 0.002);
        RigidBodyIntegrator verlet(0.002);
        RigidBodyBussiIntegrator bussi(300.0, 0.1, 0.002);
        RigidBodyLangevinIntegrator langevin(300.0, 1.0, 0.002);
        for (RigidBodyIntegratorBase* ours : std::initializer_list<RigidBodyIntegratorBase*>{&verlet, &bussi, &langevin})
            ours->setAccuracyCheck(false);
        StepCounts counts[] = {run("stock VerletIntegrator + SETTLE", stockVerlet), run("RigidBodyIntegrator (Verlet)", verlet),
                               run("stock LangevinMiddleIntegrator + SETTLE", stockLangevin),
                               run("RigidBodyLangevinIntegrator", langevin), run("RigidBodyIntegrator + Bussi thermostat", bussi)};
        std::cout << "OpenCL, " << precision << " precision, 64 TIP3P waters, PME; per step, steps " << warmup + 1 << " to "
                  << warmup + steps << ":" << std::endl;
        for (const StepCounts& c : counts)
            print(c);
        // The Bussi thermostat's heat is its work, summed on the device: measuring it (with the shadow
        // work, which reads each step's energy) costs no wait beyond the constant-energy integrator's.
        RigidBodyIntegrator verletShadow(0.002);
        verletShadow.setAccuracyCheck(false);
        verletShadow.setMeasureShadowWork(true);
        RigidBodyBussiIntegrator bussiHeat(300.0, 0.1, 0.002);
        bussiHeat.setAccuracyCheck(false);
        bussiHeat.setMeasureShadowWork(true);
        const StepCounts oursVS = run("RigidBodyIntegrator, shadow work measured", verletShadow);
        const StepCounts oursBH = run("RigidBodyBussiIntegrator, shadow work and heat measured", bussiHeat);
        print(oursVS);
        print(oursBH);

        // Steps within an accuracy check's episode (the first 4 ps of a Context): the check reads the
        // energy at its samples (the first step, then every sampleStride() steps), nothing at the others.
        RigidBodyLangevinIntegrator checkedLangevin(300.0, 1.0, 0.002);
        RigidBodyBussiIntegrator checkedBussi(300.0, 0.1, 0.002);
        RigidBodyIntegrator checkedVerlet(0.002);
        const StepCounts checked[] = {run("RigidBodyLangevinIntegrator, in the check's episode", checkedLangevin),
                                      run("RigidBodyIntegrator + Bussi, in the check's episode", checkedBussi),
                                      run("RigidBodyIntegrator (Verlet), in the check's episode", checkedVerlet)};
        for (const StepCounts& c : checked)
            print(c);
        AccuracyCheck::Setting setting;
        setting.stepSize = 0.002;
        const int stride = AccuracyCheck::sampleStride(setting);

        // Printed only: steps across a reorder, and steps with a barostat move (frequency 1: every step).
        {
            RigidBodyIntegrator reordering(0.002);
            reordering.setAccuracyCheck(false);
            Context context(system, reordering, platform, properties);
            context.setPositions(scene.positions);
            context.setVelocities(scene.velocities);
            // A reorder is due after 250 steps without one; the step that does it waits for the atoms.
            reordering.step(240);
            print(measure("RigidBodyIntegrator, steps 241-260 (one reorders)", context, reordering, 20));
        }
        system.addForce(new MonteCarloBarostat(1.0, 300.0, 1));
        VerletIntegrator stockBarostat(0.002);
        RigidBodyIntegrator oursBarostat(0.002);
        oursBarostat.setAccuracyCheck(false);
        print(run("stock Verlet, barostat every step", stockBarostat));
        print(run("RigidBodyIntegrator, barostat every step", oursBarostat));

        const StepCounts &stockV = counts[0], &oursV = counts[1], &stockL = counts[2], &oursL = counts[3], &oursB = counts[4];
        auto check = [](bool condition, const string& what) {
            if (!condition)
                throw OpenMMException("Assertion failure: " + what);
        };
        for (const StepCounts* ours : {&oursV, &oursB}) {
            check(ours->stalls <= stockV.stalls, ours->name + ": more host stalls per step than stock Verlet's");
            check(ours->worstStalls <= stockV.worstStalls, ours->name + ": a step with more host stalls than stock Verlet's");
        }
        check(oursBH.stalls <= oursVS.stalls && oursBH.worstStalls <= oursVS.worstStalls,
              oursBH.name + ": more host stalls per step than " + oursVS.name);
        check(oursL.stalls <= stockL.stalls && oursL.worstStalls <= stockL.worstStalls,
              "RigidBodyLangevinIntegrator: more host stalls per step than stock LangevinMiddleIntegrator's");
        for (int k = 0; k < 3; k++) {
            const StepCounts& stock = (k == 0 ? stockL : stockV);
            int samples = 0;
            double ordinaryStalls = 0;
            for (int i = 0; i < steps; i++) {
                const int step = warmup + 1 + i;  // 1 for the Context's first step
                if ((step - 1)%stride == 0)
                    samples++;
                else {
                    check(checked[k].stepStalls[i] <= stock.worstStalls, checked[k].name + ": step " + std::to_string(step) +
                          ", not a sample, stalls more than stock's worst step");
                    ordinaryStalls += checked[k].stepStalls[i];
                }
            }
            check(samples >= 1 && ordinaryStalls/(steps - samples) <= stock.stalls,
                  checked[k].name + ": more host stalls per ordinary step than stock's");
        }
        check(oursV.launches <= stockV.launches + 2, "RigidBodyIntegrator: more than stock Verlet's launches + 2");
        check(oursB.launches <= stockV.launches + 2, "RigidBodyIntegrator + Bussi thermostat: more than stock Verlet's launches + 2");
        check(oursL.launches <= stockL.launches + 2, "RigidBodyLangevinIntegrator: more than stock Langevin's launches + 2");
    }
    catch (const std::exception& e) {
        std::cout << "exception: " << e.what() << std::endl;
        return 1;
    }
    std::cout << "Done" << std::endl;
    return 0;
}

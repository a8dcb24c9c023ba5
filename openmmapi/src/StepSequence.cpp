#include "internal/StepSequence.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyKernels.h"
#include "RigidBodyLangevinIntegrator.h"
#include "internal/Splitting.h"
#include "internal/TimeStepLevels.h"
#include "numerics/Philox.h"
#include "numerics/StochasticRescaling.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <string>

using namespace OpenMM;
using namespace std;

namespace OpenMMRigid {

namespace {

/**
 * The force evaluation after a drift: the virtual sites follow their parents, then the integration
 * force groups. Returns their potential energy if asked for (else 0).
 */
double evaluateForces(ContextImpl& context, int groups, bool energy = false) {
    context.computeVirtualSites();
    return context.calcForcesAndEnergy(true, energy, groups);
}

/**
 * The kinetic energy now, from the kernel's stage that splits it (translation plus rotation): the sum
 * the Bussi thermostat rescales. (On OpenCL it is the plugin's own reduction; OpenMM's
 * IntegrationUtilities::computeKineticEnergy, behind computeKineticEnergy(), crashes PoCL for a
 * System of one particle, stock VerletIntegrator's Contexts too.)
 */
double kineticEnergy(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel) {
    double translational, rotational;
    kernel.computeKineticEnergies(context, translational, rotational);
    return translational + rotational;
}

/**
 * The total energy K + U the step starts from, if shadow work is measured: the kinetic energy of the
 * Context's velocities now (a CMMotionRemover or Andersen thermostat may have changed them since the
 * last step) and the potential energy of the forces the step starts with.
 */
double startingEnergy(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel, const StepState& state, bool measure,
                      const string& className) {
    if (!measure)
        return 0.0;
    if (!state.potentialKnown)
        throw OpenMMException(className + ": internal error: the shadow work is measured but the potential energy at the start "
                "of the step is unknown");
    return kineticEnergy(context, kernel) + state.potentialEnergy;
}


/**
 * The inner levels of multiple time steps (internal/TimeStepLevels.h): within a drift of the level
 * above, each level l >= 1 takes r_l = substeps_l / substeps_{l-1} substeps of h, each
 * kick_l(h/2) [drift of the level below, or the free drift] kick_l(h/2), with its forces evaluated at
 * the end of each substep (kept in slot l, so that the evaluations of the other levels do not replace
 * them). The kicks of one level at the same positions are joined (kick_l(h) between substeps). Only
 * the bodies a fast force reaches (and the free particles) take part: the others drift once over the
 * outermost drift, exactly as in pieces (free drifts compose). This is RESPA (M. Tuckerman, B. J. Berne
 * and G. J. Martyna, J. Chem. Phys. 97, 1990 (1992)) with exact rigid-body drifts.
 */
class InnerLevels {
public:
    InnerLevels(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel, const vector<TimeStepLevel>& levels,
                RigidBodyOptions::RotationMethod method, double tolerance, bool measure) :
            context(context), kernel(kernel), levels(levels), method(method), tolerance(tolerance), measure(measure) {
    }
    /** Evaluate level l's forces at the current positions and keep them in slot l; their energy, if asked for (else 0). */
    double evaluate(int l, bool energy) {
        const double potential = evaluateForces(context, levels[l].groups, energy);
        kernel.saveForces(context, l);
        return potential;
    }
    /**
     * A drift of time T of the level above l (level l and those below it kicking inside it). If
     * `middle` is given, it is called at the drift's midpoint (between the kicks there, or halfway
     * through a free drift). If `last`, the drift ends the step: `atEnd` (if given) is called after the
     * last free drift, the platform is told before the first of the final evaluations
     * (beforeLastForces()), and the potential energy of levels l and below at the end is returned
     * if measured (else 0).
     */
    double drift(int l, double T, const function<void()>* middle, bool last, const function<void()>* atEnd) {
        const int r = levels[l].substeps/levels[l - 1].substeps;
        const double h = T/r;
        const bool innermost = (l == (int) levels.size() - 1);
        double potential = 0.0;
        for (int k = 0; k < r; k++) {
            const bool lastSubstep = last && k == r - 1;
            double opening = (k == 0 ? 0.5*h : h);
            if (middle != NULL && r%2 == 0 && k == r/2) {
                // The midpoint falls between two substeps: after every kick that closes the first half.
                kernel.kickAndDrift(context, 0.5*h, 0.0, method, tolerance, l, FastBodies);
                (*middle)();
                opening = 0.5*h;
            }
            const function<void()>* inside = (middle != NULL && r%2 == 1 && k == r/2 ? middle : NULL);
            if (innermost) {
                if (inside != NULL) {
                    kernel.kickAndDrift(context, opening, 0.5*h, method, tolerance, l, FastBodies);
                    (*inside)();
                    kernel.kickAndDrift(context, 0.0, 0.5*h, method, tolerance, l, FastBodies);
                }
                else
                    kernel.kickAndDrift(context, opening, h, method, tolerance, l, FastBodies);
                if (lastSubstep) {
                    if (atEnd != NULL)
                        (*atEnd)();
                    kernel.beforeLastForces(context);
                }
            }
            else {
                kernel.kickAndDrift(context, opening, 0.0, method, tolerance, l, FastBodies);
                potential += drift(l + 1, h, inside, lastSubstep, atEnd);
            }
            const double energy = evaluate(l, lastSubstep && measure);
            if (lastSubstep)
                potential += energy;
        }
        kernel.kickAndDrift(context, 0.5*h, 0.0, method, tolerance, l, FastBodies);
        return potential;
    }
private:
    ContextImpl& context;
    IntegrateRigidBodyStepKernel& kernel;
    const vector<TimeStepLevel>& levels;
    RigidBodyOptions::RotationMethod method;
    double tolerance;
    bool measure;
};

} // namespace

double takeThermostatWork(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel, StepState& state, bool measureHeat) {
    const double work = kernel.takeThermostatWork(context);
    state.thermostatWork += work;
    if (measureHeat)
        state.heat += work;
    return work;
}

uint64_t chooseRandomSeed(int requested) {
    if (requested != 0)
        return (uint64_t) (uint32_t) requested;
    random_device device;
    return ((uint64_t) device() << 32) | device();
}

StepGeometry currentGeometry(ContextImpl& context, const RigidBodySystem& bodies) {
    StepGeometry geometry;
    geometry.displacementLimit = bodies.getLargestCutoff();
    geometry.displacementLimitName = "the nonbonded cutoff";
    geometry.periodic = context.getSystem().usesPeriodicBoundaryConditions();
    if (geometry.periodic) {
        context.getPeriodicBoxVectors(geometry.box[0], geometry.box[1], geometry.box[2]);
        // The reduced box's widths perpendicular to its faces are a_x, b_y and c_z.
        double halfWidth = 0.5*min(geometry.box[0][0], min(geometry.box[1][1], geometry.box[2][2]));
        if (halfWidth < geometry.displacementLimit) {
            geometry.displacementLimit = halfWidth;
            geometry.displacementLimitName = "half the periodic box width";
        }
    }
    return geometry;
}

void stepRigidBodyIntegrator(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel, const RigidBodyIntegrator& integrator,
                             const BussiBath* bath, const RigidBodySystem& bodies, StepState& state) {
    const SplittingScheme& scheme = splittingScheme(integrator.getSplitting());
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const RigidBodyOptions::RotationMethod method = integrator.getRotationMethod();
    const bool measureShadowWork = integrator.getMeasureShadowWork(), energy = integrator.wantsEnergy();
    kernel.beginStep(context, currentGeometry(context, bodies));
    const double startEnergy = startingEnergy(context, kernel, state, measureShadowWork, bodies.getClassName());
    // kick(a_0 dt) drift(b_0 dt) ... drift(b_{s-1} dt) kick(a_s dt): the first kick uses the forces
    // the Context holds, and every drift is followed by a force evaluation. Only the last one needs
    // the energy for the shadow work: the kicks and drifts in between telescope.
    double potential = 0.0;
    const vector<TimeStepLevel>& levels = integrator.getTimeStepLevels();
    if (levels.size() == 1) {
        for (int stage = 0; stage < scheme.numDrifts; stage++) {
            kernel.kickAndDrift(context, scheme.kicks[stage]*dt, scheme.drifts[stage]*dt, method, tolerance, -1, AllBodies);
            const bool last = (stage == scheme.numDrifts - 1);
            if (last)
                kernel.beforeLastForces(context);
            potential = evaluateForces(context, integrator.getIntegrationForceGroups(), last && energy);
        }
        kernel.closingKick(context, scheme.kicks[scheme.numDrifts]*dt, tolerance, -1);
    }
    else {
        // Multiple time steps: the splitting's kicks with the slowest forces (slot 0), each of its
        // drifts the nest of the faster levels (InnerLevels), in which the bodies no fast force
        // reaches drift once, whole, with their kick.
        InnerLevels inner(context, kernel, levels, method, tolerance, energy);
        for (int stage = 0; stage < scheme.numDrifts; stage++) {
            const double kick = scheme.kicks[stage]*dt, drift = scheme.drifts[stage]*dt;
            const bool last = (stage == scheme.numDrifts - 1);
            kernel.kickAndDrift(context, kick, drift, method, tolerance, 0, SlowBodies);
            kernel.kickAndDrift(context, kick, 0.0, method, tolerance, 0, FastBodies);
            potential = inner.drift(1, drift, NULL, last, NULL);
            potential += inner.evaluate(0, last && energy);
        }
        kernel.closingKick(context, scheme.kicks[scheme.numDrifts]*dt, tolerance, 0);
    }
    double kinetic = 0.0;
    if (bath != NULL) {
        // Bussi, Donadio and Parrinello, J. Chem. Phys. 126, 014101 (2007), eq. (A7): one global
        // factor for every momentum, from the exact solution over this step of the stochastic
        // equation for the kinetic energy. Its deviates do not depend on the kinetic energy: drawn
        // here, they go to the kernel, which sums K, takes the factor and scales where the momenta
        // are (on a GPU without the host reading anything) and accumulates the work K' - K, which
        // is also the heat (RigidBodyIntegratorBase::takeThermostatWork()).
        const int dof = bodies.getNumDegreesOfFreedom();
        const double c = exp(-dt/bath->collisionTime);
        NormalStream random(state.seed, 0, state.randomCounter++);
        double r1, rest;
        stochasticRescalingDeviates(dof, c, random, r1, rest);
        kernel.rescaleMomenta(context, 0.5*dof*BOLTZ*bath->temperature, dof, c, r1, rest);
        if (measureShadowWork) {
            // A step that reads energies anyway: the kinetic energy before the rescaling.
            double newKinetic;
            kernel.getRescalingEnergies(context, kinetic, newKinetic);
        }
    }
    else if (measureShadowWork)
        kinetic = kineticEnergy(context, kernel);
    if (measureShadowWork)
        state.shadowWork += kinetic + potential - startEnergy;
    state.potentialEnergy = potential;
    state.potentialKnown = energy;
    kernel.finishStep(context, dt);
}

void stepRigidBodyLangevinIntegrator(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel,
                                     const RigidBodyLangevinIntegrator& integrator, const RigidBodySystem& bodies, StepState& state) {
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction();
    const RigidBodyOptions::RotationMethod method = integrator.getRotationMethod();
    const bool measureShadowWork = integrator.getMeasureShadowWork(), energy = integrator.wantsEnergy();
    kernel.beginStep(context, currentGeometry(context, bodies));
    const double startEnergy = startingEnergy(context, kernel, state, measureShadowWork, bodies.getClassName());
    // LFMiddle (Z. Zhang, X. Liu, K. Yan, M. E. Tuckerman and J. Liu, J. Phys. Chem. A 123, 6056
    // (2019)), as LangevinMiddleIntegrator: B(dt) A(dt/2) O A(dt/2), force. It is BAOAB (Leimkuhler
    // and Matthews, Appl. Math. Res. Express 2013, 34) with the closing half kick of one step joined
    // to the opening half kick of the next: the same positions, while the velocities the Context
    // holds between steps are those after O and A, half a step behind the positions
    // (getVelocityTimeOffset() = dt/2), whose distribution is canonical where BAOAB's on-step
    // velocities read stiff modes (the librations of water) cold. With no friction O is the
    // identity and is left out: the step is then leapfrog Verlet with exact drifts.
    // The O stage: its heat, the kinetic energy it adds, is summed by the kernel where the momenta are,
    // if the step measures it (for getHeat(), getShadowWork(), or the accuracy check).
    const bool heat = integrator.wantsHeat();
    const function<void()> thermostat = [&]() {
        kernel.thermalize(context, exp(-friction*dt), BOLTZ*integrator.getTemperature(), state.seed, state.randomCounter++, tolerance,
                          heat);
    };
    double potential;
    const vector<TimeStepLevel>& levels = integrator.getTimeStepLevels();
    if (levels.size() == 1) {
        kernel.kickAndDrift(context, dt, 0.5*dt, method, tolerance, -1, AllBodies);
        if (friction > 0.0)
            thermostat();
        kernel.kickAndDrift(context, 0.0, 0.5*dt, method, tolerance, -1, AllBodies);
        kernel.beforeLastForces(context);
        potential = evaluateForces(context, integrator.getIntegrationForceGroups(), energy);
    }
    else {
        // Multiple time steps: the kick by the slowest forces (slot 0), then the nest of the faster
        // levels over the whole drift with O at its midpoint (so that, as in BAOAB, what the fast
        // forces do not reach sees one O between two half drifts); the bodies no fast force reaches
        // drift in two halves around it. The velocities between steps lack half a kick of the
        // slowest forces only.
        InnerLevels inner(context, kernel, levels, method, tolerance, energy);
        kernel.kickAndDrift(context, dt, 0.5*dt, method, tolerance, 0, SlowBodies);
        kernel.kickAndDrift(context, dt, 0.0, method, tolerance, 0, FastBodies);
        const function<void()> secondHalf = [&]() {
            kernel.kickAndDrift(context, 0.0, 0.5*dt, method, tolerance, 0, SlowBodies);
        };
        potential = inner.drift(1, dt, friction > 0.0 ? &thermostat : NULL, true, &secondHalf);
        potential += inner.evaluate(0, energy);
    }
    // No kick: the rigid velocities written to the body particles, the constraints among free particles applied to velocities.
    kernel.closingKick(context, 0.0, tolerance, -1);
    if (measureShadowWork) {
        const double heat = takeThermostatWork(context, kernel, state, true);
        state.shadowWork += kineticEnergy(context, kernel) + potential - startEnergy - heat;
    }
    state.potentialEnergy = potential;
    state.potentialKnown = energy;
    kernel.finishStep(context, dt);
}

} // namespace OpenMMRigid

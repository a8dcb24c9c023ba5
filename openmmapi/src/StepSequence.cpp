#include "internal/StepSequence.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyKernels.h"
#include "RigidBodyLangevinIntegrator.h"
#include "internal/Splitting.h"
#include "numerics/Philox.h"
#include "numerics/StochasticRescaling.h"
#include "openmm/Context.h"
#include "openmm/OpenMMException.h"
#include "openmm/reference/SimTKOpenMMRealType.h"
#include <algorithm>
#include <cmath>
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

} // namespace

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
                             const RigidBodySystem& bodies, StepState& state) {
    const SplittingScheme& scheme = splittingScheme(integrator.getSplitting());
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const RigidBodyOptions::RotationMethod method = integrator.getRotationMethod();
    const bool measureShadowWork = integrator.measuresShadowWork();
    kernel.beginStep(context, currentGeometry(context, bodies));
    const double startEnergy = startingEnergy(context, kernel, state, measureShadowWork, integrator.getClassName());
    // kick(a_0 dt) drift(b_0 dt) ... drift(b_{s-1} dt) kick(a_s dt): the first kick uses the forces
    // the Context holds, and every drift is followed by a force evaluation. Only the last one needs
    // the energy for the shadow work: the kicks and drifts in between telescope.
    double potential = 0.0;
    for (int stage = 0; stage < scheme.numDrifts; stage++) {
        kernel.kickAndDrift(context, scheme.kicks[stage]*dt, scheme.drifts[stage]*dt, method, tolerance);
        const bool last = (stage == scheme.numDrifts - 1);
        if (last)
            kernel.beforeLastForces(context);
        potential = evaluateForces(context, integrator.getIntegrationForceGroups(), last && measureShadowWork);
    }
    kernel.closingKick(context, scheme.kicks[scheme.numDrifts]*dt, tolerance);
    double kinetic = 0.0;
    if (integrator.hasThermostat()) {
        // Bussi, Donadio and Parrinello, J. Chem. Phys. 126, 014101 (2007), eq. (A7): one global
        // factor for every momentum, from the exact solution over this step of the stochastic
        // equation for the kinetic energy. Its deviates do not depend on the kinetic energy: drawn
        // here, they go to the kernel, which sums K, takes the factor and scales where the momenta
        // are (on a GPU without the host reading anything) and accumulates the work K' - K, which
        // is also the heat (RigidBodyIntegratorBase::takeThermostatWork()).
        const int dof = bodies.getNumDegreesOfFreedom();
        const double c = exp(-dt/integrator.getThermostatCollisionTime());
        NormalStream random(state.seed, 0, state.randomCounter++);
        double r1, rest;
        stochasticRescalingDeviates(dof, c, random, r1, rest);
        kernel.rescaleMomenta(context, 0.5*dof*BOLTZ*integrator.getThermostatTemperature(), dof, c, r1, rest);
        if (measureShadowWork) {
            // A step that reads energies anyway: the kinetic energy before the rescaling.
            double newKinetic;
            kernel.getRescalingEnergies(context, kinetic, newKinetic);
        }
    }
    else if (measureShadowWork)
        kinetic = kineticEnergy(context, kernel);
    if (measureShadowWork) {
        state.stepShadowWork = kinetic + potential - startEnergy;
        state.stepKinetic = kinetic;
        if (integrator.getMeasureShadowWork())
            state.shadowWork += state.stepShadowWork;
    }
    state.potentialEnergy = potential;
    state.potentialKnown = measureShadowWork;
    kernel.finishStep(context, dt);
}

void stepRigidBodyLangevinIntegrator(ContextImpl& context, IntegrateRigidBodyStepKernel& kernel,
                                     const RigidBodyLangevinIntegrator& integrator, const RigidBodySystem& bodies, StepState& state) {
    const double dt = integrator.getStepSize(), tolerance = integrator.getConstraintTolerance();
    const double friction = integrator.getFriction();
    const RigidBodyOptions::RotationMethod method = integrator.getRotationMethod();
    const bool measureShadowWork = integrator.measuresShadowWork(), measureHeat = integrator.getMeasureHeat();
    kernel.beginStep(context, currentGeometry(context, bodies));
    const double startEnergy = startingEnergy(context, kernel, state, measureShadowWork, integrator.getClassName());
    // LFMiddle (Z. Zhang, X. Liu, K. Yan, M. E. Tuckerman and J. Liu, J. Phys. Chem. A 123, 6056
    // (2019)), as LangevinMiddleIntegrator: B(dt) A(dt/2) O A(dt/2), force. It is BAOAB (Leimkuhler
    // and Matthews, Appl. Math. Res. Express 2013, 34) with the closing half kick of one step joined
    // to the opening half kick of the next: the same positions, while the velocities the Context
    // holds between steps are those after O and A, half a step behind the positions
    // (getVelocityTimeOffset() = dt/2), whose distribution is canonical where BAOAB's on-step
    // velocities read stiff modes (the librations of water) cold. With no friction O is the
    // identity and is left out: the step is then leapfrog Verlet with exact drifts.
    kernel.kickAndDrift(context, dt, 0.5*dt, method, tolerance);
    double heat = 0.0;
    if (friction > 0.0) {
        // The heat is the kinetic energy the O stage adds: read on either side of it, with the
        // bodies' momenta written to their particles first (which changes no momentum).
        const bool measure = (measureShadowWork || measureHeat);
        if (measure) {
            kernel.writeBodyVelocities(context);
            heat = -kineticEnergy(context, kernel);
        }
        kernel.thermalize(context, exp(-friction*dt), BOLTZ*integrator.getTemperature(), state.seed, state.randomCounter++, tolerance);
        if (measure) {
            kernel.writeBodyVelocities(context);
            heat += kineticEnergy(context, kernel);
        }
    }
    kernel.kickAndDrift(context, 0.0, 0.5*dt, method, tolerance);
    kernel.beforeLastForces(context);
    const double potential = evaluateForces(context, integrator.getIntegrationForceGroups(), measureShadowWork);
    // No kick: the rigid velocities written to the body particles, the constraints among free particles applied to velocities.
    kernel.closingKick(context, 0.0, tolerance);
    if (measureHeat)
        state.heat += heat;
    if (measureShadowWork) {
        state.stepKinetic = kineticEnergy(context, kernel);
        state.stepShadowWork = state.stepKinetic + potential - startEnergy - heat;
        if (integrator.getMeasureShadowWork())
            state.shadowWork += state.stepShadowWork;
    }
    state.potentialEnergy = potential;
    state.potentialKnown = measureShadowWork;
    kernel.finishStep(context, dt);
}

} // namespace OpenMMRigid

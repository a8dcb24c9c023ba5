#ifndef OPENMMRIGID_STEPSEQUENCE_H_
#define OPENMMRIGID_STEPSEQUENCE_H_

#include "internal/windowsExportRigid.h"
#include <cstdint>

namespace OpenMM {
class ContextImpl;
}

namespace OpenMMRigid {

class IntegrateRigidBodyStepKernel;
class RigidBodyIntegrator;
class RigidBodyLangevinIntegrator;
class RigidBodySystem;
struct StepGeometry;

/**
 * What the step sequence keeps from step to step, besides the Context: the key of the random numbers
 * and how many stages have drawn from it, the energy the thermostat has put in, and, while they are
 * measured, the shadow work and the heat. Checkpoints save all but the potential energy
 * (RigidBodyIntegratorBase::createCheckpoint()).
 */
struct StepState {
    uint64_t seed = 0, randomCounter = 0;
    /**
     * The thermostat's work, in kJ/mol (the Bussi thermostat's, or the heat of the Ornstein-Uhlenbeck
     * stages), up to the last time it was taken from the kernel, which sums it step by step where the
     * momenta are (IntegrateRigidBodyStepKernel::rescaleMomenta() and thermalize()); what the kernel
     * holds is added (to the heat too, while measured) before either is read, saved or reset
     * (takeThermostatWork()), and dropped when a checkpoint replaces this state.
     */
    double thermostatWork = 0.0;
    /** The energy change of the deterministic stages and of the stochastic ones, in kJ/mol, summed while measured. */
    double shadowWork = 0.0, heat = 0.0;
    /**
     * The potential energy of the integration force groups at the current positions, in kJ/mol,
     * valid if potentialKnown: from the step's last force evaluation, if it asked for the energy
     * (RigidBodyIntegratorBase::wantsEnergy()).
     */
    double potentialEnergy = 0.0;
    bool potentialKnown = false;
};

/** The heat bath of RigidBodyBussiIntegrator's stochastic velocity rescaling: its temperature (K) and collision time (ps). */
struct BussiBath {
    double temperature = 0.0, collisionTime = 0.0;
};

/**
 * Take the thermostat's work the kernel has summed since it was last taken into state.thermostatWork,
 * and into state.heat if measureHeat; returns it. On a GPU this waits for the device.
 */
OPENMM_EXPORT_RIGID double takeThermostatWork(OpenMM::ContextImpl& context, IntegrateRigidBodyStepKernel& kernel, StepState& state,
                                              bool measureHeat);

/**
 * The seed of a new Context's random numbers: the integrator's, or if that is 0 (as in OpenMM's
 * integrators) one that differs from Context to Context.
 */
OPENMM_EXPORT_RIGID uint64_t chooseRandomSeed(int requested);

/**
 * The periodic box now, and the largest plausible drift: the largest nonbonded cutoff, or half the
 * narrowest box width if that is less (the box can change between steps, under a barostat).
 */
OPENMM_EXPORT_RIGID StepGeometry currentGeometry(OpenMM::ContextImpl& context, const RigidBodySystem& bodies);

/**
 * One step of RigidBodyIntegrator, on any platform: the kicks and drifts of its splitting
 * (internal/Splitting.h) with the virtual sites placed and the forces evaluated after each drift,
 * then, with a bath (RigidBodyBussiIntegrator; NULL for constant energy), the thermostat's rescaling of every momentum. On entry the Context holds the
 * forces at the current positions and the kernel's bodies agree with them (and, if shadow work is
 * measured, state.potentialEnergy is their energy); on exit it holds the forces at the new positions.
 *
 * Shadow work: the step's change of K + U before the rescaling, which is the sum over its kicks
 * (the kinetic energy they add) and drifts (the potential energy they add; an exact drift keeps the
 * kinetic energy). Heat: the kinetic energy the rescaling adds, which is the thermostat's work: the
 * kernel sums both (the step reads nothing back unless it measures the shadow work).
 */
OPENMM_EXPORT_RIGID void stepRigidBodyIntegrator(OpenMM::ContextImpl& context, IntegrateRigidBodyStepKernel& kernel,
        const RigidBodyIntegrator& integrator, const BussiBath* bath, const RigidBodySystem& bodies, StepState& state);

/**
 * One step of RigidBodyLangevinIntegrator, on any platform: kick, half drift, Ornstein-Uhlenbeck
 * step, half drift, force evaluation (LFMiddle). On entry the Context holds the forces at the current
 * positions and velocities half a step behind them; on exit, the forces at the new positions and
 * the velocities half a step behind those.
 *
 * Heat: the kinetic energy the Ornstein-Uhlenbeck stage adds, which the kernel sums as the
 * thermostat's work. Shadow work: the rest of the step's change of K + U, which is the kick's kinetic
 * energy and the drifts' potential energy.
 */
OPENMM_EXPORT_RIGID void stepRigidBodyLangevinIntegrator(OpenMM::ContextImpl& context, IntegrateRigidBodyStepKernel& kernel,
        const RigidBodyLangevinIntegrator& integrator, const RigidBodySystem& bodies, StepState& state);

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_STEPSEQUENCE_H_*/

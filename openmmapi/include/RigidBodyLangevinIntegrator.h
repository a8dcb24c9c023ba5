#ifndef OPENMMRIGID_RIGIDBODYLANGEVININTEGRATOR_H_
#define OPENMMRIGID_RIGIDBODYLANGEVININTEGRATOR_H_

#include "RigidBodyIntegratorBase.h"
#include "internal/windowsExportRigid.h"
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * This is a Langevin integrator for systems of rigid molecules: it samples the canonical ensemble at
 * a given temperature, with the exact free drift of RigidBodyIntegrator as its deterministic part.
 * Each step is arranged as in OpenMM's LangevinMiddleIntegrator (the LFMiddle form of the BAOAB
 * splitting of B. Leimkuhler and C. Matthews, Appl. Math. Res. Express 2013, 34 (2013); Z. Zhang
 * et al., J. Phys. Chem. A 123, 6056 (2019)): a kick by the forces and torques, a free drift for
 * half a step, the exact solution of an Ornstein-Uhlenbeck process for a whole step on the momenta,
 * another free drift for half a step, and the force evaluation at the new positions. That is BAOAB
 * (half kick, half drift, Ornstein-Uhlenbeck, half drift, half kick) with the closing half kick of
 * each step joined to the opening half kick of the next: the positions are BAOAB's.
 *
 * The Ornstein-Uhlenbeck step acts on each body's linear momentum P and on its angular momentum in
 * the principal (body) frame, L_k, with c = exp(-friction dt):
 *
 *     P   <- c P   + sqrt((1 - c^2) M kT) xi      (each component)
 *     L_k <- c L_k + sqrt((1 - c^2) I_k kT) xi_k  (each principal axis with I_k > 0)
 *
 * with independent standard normal xi. A linear body has no angular momentum along its axis, and a
 * single-particle body only translates. This is the rigid-body Langevin thermostat of R. L.
 * Davidchack, T. E. Ouldridge and M. V. Tretyakov, J. Chem. Phys. 142, 144114 (2015), in which
 * friction and noise act on the translational momentum and on the body-frame angular momentum and
 * the Ornstein-Uhlenbeck part of the splitting is solved exactly. They write the rotation with
 * quaternions and their conjugate momenta and integrate the Hamiltonian part with NO_SQUISH; here
 * the angular momentum is kept in the principal frame directly, the free rotation is exact (or
 * NO_SQUISH, with setRotationMethod()), and every momentum relaxes at the one rate given by the
 * friction (the rotational friction of each axis is proportional to its moment), so that one
 * parameter sets the coupling as in LangevinMiddleIntegrator. Free particles get the same
 * Ornstein-Uhlenbeck step on their velocities, followed by the velocity constraints among them (the
 * components along the constraints are projected out, as LangevinMiddleIntegrator does); their
 * positions stay constrained.
 *
 * With friction 0 the step is leapfrog Verlet with exact drifts (the positions of RigidBodyIntegrator's
 * Verlet step; no random numbers are drawn); with temperature 0 and friction > 0 the motion is damped.
 *
 * Velocities are those of LangevinMiddleIntegrator: the Context holds the velocities after the
 * Ornstein-Uhlenbeck step and the second half drift, half a step behind the positions, and the
 * kinetic energy, the temperature and the translational
 * and rotational kinetic energies are theirs. For a harmonic mode their distribution is canonical:
 * the sampled m <v^2> is exactly kT at any stable step, where BAOAB's on-step velocities read it low
 * by the factor 1 - (omega dt)^2/4. For rigid water, whose librations are its stiffest modes, the
 * rotational temperature of the on-step velocities reads several percent low at 4 fs, while that of
 * these velocities reads the bath's. For anharmonic modes BAOAB's momenta keep an error of order
 * dt^2 at every point of the step: in rigid water at 8 fs (friction 1/ps) the libration about the
 * axis of least moment reads about 7 % hot, the translation 1 to 2 % cold, and the reported
 * temperature 1 to 2 % hot (LangevinMiddleIntegrator + SETTLE: the same libration, 3 % hot in all),
 * while the configurational averages stay those of the small steps (docs/guide/thermostats.md and
 * docs/validation/thermostats.md give the measurements). Velocities one sets are
 * taken as such half-step velocities (setVelocitiesToTemperature() shifts them by half a kick, as for
 * LangevinMiddleIntegrator).
 *
 * Random numbers: each body and each free particle draws its normal deviates from a counter-based
 * generator (Philox4x32-10) keyed by the seed and counted by step and body, so that a trajectory
 * depends only on the seed, never on the number of threads. The counter is saved in checkpoints.
 */
class OPENMM_EXPORT_RIGID RigidBodyLangevinIntegrator : public RigidBodyIntegratorBase {
public:
    /**
     * Create a RigidBodyLangevinIntegrator whose bodies are the rigid constraint clusters of the System.
     *
     * @param temperature    the temperature of the heat bath, measured in Kelvin
     * @param frictionCoeff  the friction coefficient which couples the system to the heat bath, measured in 1/ps
     * @param stepSize       the step size with which to integrate the system, measured in ps
     * @throws OpenMMException if the temperature or the friction is negative or not finite
     */
    RigidBodyLangevinIntegrator(double temperature, double frictionCoeff, double stepSize);
    /**
     * Create a RigidBodyLangevinIntegrator with explicitly chosen bodies.
     *
     * @param temperature    the temperature of the heat bath, measured in Kelvin
     * @param frictionCoeff  the friction coefficient which couples the system to the heat bath, measured in 1/ps
     * @param stepSize       the step size with which to integrate the system, measured in ps
     * @param bodies         the particle indices of each body. A body may be any set of massive particles
     *                       (a single particle, a linear, planar or three-dimensional molecule).
     *                       Particles in no body move freely.
     * @throws OpenMMException if the temperature or the friction is negative or not finite
     */
    RigidBodyLangevinIntegrator(double temperature, double frictionCoeff, double stepSize,
                                const std::vector<std::vector<int> >& bodies);
    /**
     * Get the temperature of the heat bath.
     *
     * @return the temperature, measured in Kelvin
     */
    double getTemperature() const {
        return temperature;
    }
    /**
     * Set the temperature of the heat bath. It may be changed between steps.
     *
     * @param temp   the temperature of the heat bath, measured in Kelvin
     * @throws OpenMMException if the value is negative or not finite
     */
    void setTemperature(double temp);
    /**
     * Get the friction coefficient which determines how strongly the system is coupled to the heat bath.
     *
     * @return the friction coefficient, measured in 1/ps
     */
    double getFriction() const {
        return friction;
    }
    /**
     * Set the friction coefficient which determines how strongly the system is coupled to the heat
     * bath. It may be changed between steps; with 0 the step is leapfrog Verlet with exact drifts.
     *
     * @param coeff  the friction coefficient, measured in 1/ps
     * @throws OpenMMException if the value is negative or not finite
     */
    void setFriction(double coeff);
    /** Get the random number seed (0: a new one for every Context). See setRandomNumberSeed() for details. */
    int getRandomNumberSeed() const {
        return randomNumberSeed;
    }
    /**
     * Set the random number seed. The precise meaning of this parameter is undefined, and is left up
     * to each Platform to interpret in an appropriate way. It is guaranteed that if two simulations
     * are run with different random number seeds, the sequence of random forces will be different.
     * On the other hand, no guarantees are made about the behavior of simulations that use the same
     * seed. In particular, Platforms are permitted to use non-deterministic algorithms which produce
     * different results on successive runs, even if those runs were initialized identically. (On the
     * Reference and CPU platforms the same seed gives the same trajectory, with any number of threads.)
     *
     * If seed is set to 0 (which is the default value assigned), a unique seed is chosen when a
     * Context is created from this Integrator. This is done to ensure that each Context receives
     * unique random seeds without you needing to set them explicitly. The seed is read when the
     * Context is created; changing it afterwards has no effect on that Context.
     *
     * @param seed  the seed; 0 (the default) picks a new seed for every Context
     */
    void setRandomNumberSeed(int seed) {
        randomNumberSeed = seed;
    }
    /**
     * Get the kinetic energy of the on-step velocities: the momenta the Context holds (half a step
     * behind the positions) kicked by half a step of the forces at the positions now, each body's
     * momentum by its force and its angular momentum by its torque (in its own, possibly raised,
     * moments), the free particles' velocities by their forces and then projected onto the
     * constraints among them. These are the velocities BAOAB holds between its steps (the step is
     * BAOAB's with its closing half kick joined to the next step's opening one), so
     *
     *     W_BAOAB = W + [K_on - K](end) - [K_on - K](start),
     *
     * with W the shadow work (getShadowWork()) and K the Context's kinetic energy, is the shadow work
     * of the same trajectory with on-step velocities at both ends: BAOAB's, whose ends are free of
     * the terms of first order in the step (dt F.v / 2 per degree of freedom) that W's half-step ends
     * carry. That is what the near-equilibrium estimate of the configuration-space error needs
     * (benchmarks/studies/sampling_error.py). The state is left as it is. Only available once the integrator
     * is bound to a Context.
     *
     * @return the kinetic energy, measured in kJ/mol
     */
    double getOnStepKineticEnergy() {
        return computeKickedKineticEnergy(getVelocityTimeOffset(), "getOnStepKineticEnergy");
    }
protected:
    /** The velocities the Context holds lag behind the positions by half a step, as LangevinMiddleIntegrator's. */
    double getVelocityTimeOffset() const {
        return 0.5*getStepSize();
    }
    int getRequestedSeed() const {
        return randomNumberSeed;
    }
    void executeStep(OpenMM::ContextImpl& context);
    AccuracyCheck::Setting getAccuracySetting() const;
    /** A checkpoint from before version 2 holds on-step velocities: they go half a kick back. */
    double getLoadedVelocityKick(int version) const {
        return (version < 2 ? -getVelocityTimeOffset() : 0.0);
    }
private:
    double temperature, friction;
    int randomNumberSeed;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYLANGEVININTEGRATOR_H_*/

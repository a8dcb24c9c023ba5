#ifndef OPENMMRIGID_RIGIDBODYINTEGRATOR_H_
#define OPENMMRIGID_RIGIDBODYINTEGRATOR_H_

#include "RigidBodyIntegratorBase.h"
#include "internal/windowsExportRigid.h"
#include <string>
#include <vector>

namespace OpenMMRigid {

/**
 * This is an Integrator for systems of rigid molecules. Each rigid body moves by a symplectic,
 * time-reversible splitting: a half kick of its linear and angular momentum by the forces and
 * torques, a free drift of its centre and orientation, and another half kick. With the default
 * rotation method (Exact) the drift is the exact torque-free motion of the body (R. van Zon and
 * J. Schofield, J. Comput. Phys. 225, 145 (2007); J. Chem. Phys. 128, 154119 (2008)); NoSquish
 * takes the symplectic rotational splitting of T. F. Miller et al., J. Chem. Phys. 116, 8649 (2002)
 * instead, for comparison. Particles that belong to no body move by velocity Verlet, with the
 * constraints among them applied to positions and velocities.
 *
 * That kick-drift-kick step is the default splitting (Verlet). setSplitting() chooses a longer
 * sequence of kicks and exact drifts instead, with one force evaluation after each drift: the
 * optimized two-stage scheme of I. P. Omelyan, I. M. Mryglod and R. Folk, Phys. Rev. E 65, 056706
 * (2002) (Omelyan2, second order), Yoshida's fourth-order triple jump (H. Yoshida, Phys. Lett. A
 * 150, 262 (1990)) (Yoshida4), or the optimized fourth-order Forest-Ruth-like scheme of Omelyan,
 * Mryglod and Folk, Comput. Phys. Commun. 146, 188 (2002) (Omelyan4). Bodies and free particles
 * follow the same sequence.
 *
 * It conserves the energy. For constant temperature, RigidBodyBussiIntegrator adds the stochastic
 * velocity rescaling of Bussi, Donadio and Parrinello (2007) after every step, and
 * RigidBodyLangevinIntegrator is the Langevin alternative. The settings and diagnostics shared by all
 * three are those of RigidBodyIntegratorBase.
 *
 * The bodies are either found in the System when the Context is created (every cluster of three or
 * more particles that its constraints hold rigid: the rigid waters of TIP3P, SPC/E, TIP4P-Ew and
 * TIP5P, or any other rigid constraint cluster), or given explicitly as lists of particle indices.
 * A body held rigid by constraints takes its shape from the constraint distances, so its motion is
 * that of the constrained system; an explicit body takes the shape it has when the Context's
 * positions are first set (whatever moves the particles before the first step, such as an energy
 * minimization), and is one molecule to OpenMM, so that barostats scale it whole and
 * getState(enforcePeriodicBox=true) keeps it whole. Constraints within a body are implied by its
 * rigidity: an explicit body takes its shape from the positions with them applied where any is off
 * by more than the constraint tolerance (SHAKE, as a constrained integrator applies them), so
 * positions that miss them are fine; a
 * constraint joining a body to anything else is an error. An AndersenThermostat, which redraws the
 * velocities of each constraint cluster, is an error at Context creation for an explicit body that
 * is not one constraint cluster (it would thermalise the body in parts, and cool it). Massless
 * virtual sites are placed from their parents after every move. Each body is assembled from periodic
 * images along its own shortest links, so molecules split by the periodic boundary in the positions
 * given are fine, however far they reach from their first particle.
 *
 * Velocities are on-step. Every step writes the velocity v = V + omega x (r - R) of each body
 * particle back to the Context, so that reporters, State objects and barostats see consistent data.
 * Positions or velocities set from outside (setPositions, setVelocities, setVelocitiesToTemperature,
 * setState, loadCheckpoint) are projected onto rigid-body motion at once, so the State read before
 * the first step is the one the step starts from: each body is re-fitted by a mass-weighted
 * least-squares rigid fit, and its particle velocities are replaced by the rigid motion with the
 * same linear and angular momentum. Whatever moves particles without notice (a Monte Carlo barostat,
 * the energy minimizer, another integrator of a CompoundIntegrator, applyConstraints) is detected at
 * the next step, which fits the bodies again; the forces of the last step are reused only if the
 * Context's last force evaluation was the integrator's own (not a getState() of other force groups)
 * and nothing changed since (updateParametersInContext included). A step that would move a body or
 * free particle further than the nonbonded cutoff or half the box stops with an OpenMMException.
 */
class OPENMM_EXPORT_RIGID RigidBodyIntegrator : public RigidBodyIntegratorBase {
public:
    /**
     * Create a RigidBodyIntegrator whose bodies are the rigid constraint clusters of the System.
     *
     * @param stepSize  the step size with which to integrate the system, measured in ps
     */
    explicit RigidBodyIntegrator(double stepSize);
    /**
     * Create a RigidBodyIntegrator with explicitly chosen bodies.
     *
     * @param stepSize  the step size with which to integrate the system, measured in ps
     * @param bodies    the particle indices of each body. A body may be any set of massive particles
     *                  (a single particle, a linear, planar or three-dimensional molecule).
     *                  Particles in no body move freely.
     */
    RigidBodyIntegrator(double stepSize, const std::vector<std::vector<int> >& bodies);
    /** The sequence of kicks and drifts of a step (setSplitting() describes each). */
    typedef RigidBodyOptions::Splitting Splitting;
    /** Velocity Verlet: kick dt/2, drift dt, kick dt/2. Second order, one force evaluation per step. */
    static constexpr Splitting Verlet = RigidBodyOptions::Verlet;
    /** The optimized two-stage scheme of Omelyan, Mryglod and Folk (2002): second order, two force evaluations per step. */
    static constexpr Splitting Omelyan2 = RigidBodyOptions::Omelyan2;
    /** Yoshida's fourth-order triple jump: three force evaluations per step. */
    static constexpr Splitting Yoshida4 = RigidBodyOptions::Yoshida4;
    /** The optimized fourth-order Forest-Ruth-like scheme of Omelyan, Mryglod and Folk (2002): four force evaluations per step. */
    static constexpr Splitting Omelyan4 = RigidBodyOptions::Omelyan4;
    /**
     * Get the splitting: the sequence of kicks and drifts that makes one step.
     *
     * @return Verlet (the default), Omelyan2, Yoshida4 or Omelyan4
     */
    Splitting getSplitting() const {
        return splitting;
    }
    /**
     * Set the splitting: the sequence of kicks and drifts that makes one step. Each splitting starts
     * with a kick that reuses the forces from the end of the previous step and evaluates the forces
     * once after each of its drifts; bodies and free particles (with their constraints) follow the
     * same sequence. Takes effect at the next step.
     *
     * @param splitting  one of
     *                   - Verlet: velocity Verlet, kick dt/2, drift dt, kick dt/2. Second order, one force
     *                     evaluation per step.
     *                   - Omelyan2: the optimized two-stage scheme of Omelyan, Mryglod and Folk, Phys.
     *                     Rev. E 65, 056706 (2002): kick lambda dt, drift dt/2, kick (1 - 2 lambda) dt,
     *                     drift dt/2, kick lambda dt with lambda = 0.1931833275037836. Second order with a
     *                     smaller error than Verlet at the same step; two force evaluations per step.
     *                   - Yoshida4: Yoshida's triple jump (Phys. Lett. A 150, 262 (1990)), Verlet steps of
     *                     w1 dt, w0 dt and w1 dt with w1 = 1/(2 - 2^(1/3)) and w0 = 1 - 2 w1 (the middle
     *                     one backwards in time). Fourth order, with either rotation method and with
     *                     constraints; three force evaluations per step.
     *                   - Omelyan4: the optimized fourth-order Forest-Ruth-like scheme of Omelyan, Mryglod
     *                     and Folk, Comput. Phys. Commun. 146, 188 (2002), in its velocity form: five kicks
     *                     and four drifts; four force evaluations per step. Fourth order when the drifts
     *                     are exact; with NoSquish, or for free particles held by constraints (which drift
     *                     by SHAKE), it is second order, where Yoshida4 stays fourth order.
     * @throws OpenMMException if the value is not a Splitting
     */
    void setSplitting(Splitting splitting);
protected:
    /** For RigidBodyBussiIntegrator, which adds a thermostat: className names the concrete class in messages. */
    RigidBodyIntegrator(const std::string& className, double stepSize);
    RigidBodyIntegrator(const std::string& className, double stepSize, const std::vector<std::vector<int> >& bodies);
    int getRequestedSeed() const {
        return 0;
    }
    bool hasThermostatWork() const {
        return true;
    }
    AccuracyCheck::Setting getAccuracySetting() const;
    void executeStep(OpenMM::ContextImpl& context);
    /** The thermostat of each step: NULL for constant energy (RigidBodyBussiIntegrator gives its own). */
    virtual const BussiBath* getBath() const {
        return NULL;
    }
private:
    Splitting splitting;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYINTEGRATOR_H_*/

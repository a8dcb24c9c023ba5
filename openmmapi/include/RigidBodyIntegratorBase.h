#ifndef OPENMMRIGID_RIGIDBODYINTEGRATORBASE_H_
#define OPENMMRIGID_RIGIDBODYINTEGRATORBASE_H_

#include "RigidBodyOptions.h"
#include "openmm/Integrator.h"
#include "openmm/Kernel.h"
#include "openmm/Vec3.h"
#include "internal/AccuracyCheck.h"
#include "internal/StepSequence.h"
#include "internal/TimeStepLevels.h"
#include "internal/windowsExportRigid.h"
#include <iosfwd>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace OpenMM {
class SerializationNode;
}

namespace OpenMMRigid {

class IntegrateRigidBodyStepKernel;
class RigidBodySystem;

// The step loop of the integrator contract lives here: update the context state, re-fit the bodies
// if something moved the particles, compute the forces of the integration force groups, run the
// step sequence of internal/StepSequence.h on the platform's kernel. The body topology
// (internal/RigidBodySystem.h) is built once per Context, and every question about the bodies is
// answered from it, without touching the Context's state.
/**
 * The base of RigidBodyIntegrator (constant energy), RigidBodyBussiIntegrator and
 * RigidBodyLangevinIntegrator (constant temperature): what every rigid-body integrator of this plugin
 * has in common. It holds the bodies (found from the System's rigid constraint clusters or given
 * explicitly) and the settings of their motion: the rotation method of the free drift, raised moments
 * of inertia, multiple time steps; and it measures the run: the temperature, the shadow work and heat,
 * and the accuracy check. It cannot be created on its own.
 */
class OPENMM_EXPORT_RIGID RigidBodyIntegratorBase : public OpenMM::Integrator {
public:
    /** How the orientation of each body is advanced during the free drift (see RigidBodyOptions). */
    typedef RigidBodyOptions::RotationMethod RotationMethod;
    /** The exact torque-free motion (van Zon and Schofield, 2007). */
    static constexpr RotationMethod Exact = RigidBodyOptions::Exact;
    /** The symplectic NO_SQUISH splitting of the free rotation (Miller et al., 2002). */
    static constexpr RotationMethod NoSquish = RigidBodyOptions::NoSquish;
    /**
     * Get the method used to advance the orientation of each body.
     *
     * @return Exact (the default) or NoSquish
     */
    RotationMethod getRotationMethod() const {
        return rotationMethod;
    }
    /**
     * Set the method used to advance the orientation of each body.
     *
     * @param method  Exact (the exact free rotation of van Zon and Schofield) or NoSquish (the
     *                NO_SQUISH splitting of Miller et al.)
     * @throws OpenMMException if the value is not a RotationMethod
     */
    void setRotationMethod(RotationMethod method);
#ifndef SWIG
    /**
     * Set the size of each time step, in ps (Integrator::setStepSize(), which Python calls as it is).
     *
     * @throws OpenMMException if the size is not a finite number
     */
    void setStepSize(double size) override;
#endif
    /**
     * Get the number of rigid bodies: explicit bodies at any time, those found from the System's
     * constraints once the integrator is bound to a Context.
     */
    int getNumBodies() const;
    /**
     * Get the particle indices of a rigid body, once the integrator is bound to a Context.
     *
     * @param index  the index of the body, from 0 to getNumBodies() - 1
     * @return the indices of the body's particles, in the order the body was given or found
     */
    std::vector<int> getBodyParticles(int index) const;
    /**
     * Get the smallest principal moment of inertia a body moves with (0, the default: every body moves
     * with the moments of its particles' masses).
     *
     * @return the minimum moment, measured in amu nm^2
     */
    double getMinimumMomentOfInertia() const {
        return minimumMoment;
    }
    /**
     * Raise the moments of inertia of light bodies: every nonzero principal moment of a body that is
     * smaller than this moves with this moment instead (the zero moment of a linear body stays zero).
     * It is the rigid-body counterpart of hydrogen mass repartitioning: the distribution of positions
     * (every configurational average: energies, densities, radial distribution functions) does not
     * depend on the moments of inertia, while the librations of light molecules slow down, which
     * allows a larger step. Each body keeps its mass, centre of mass, shape and forces; its particles
     * keep moving rigidly, v_i = V + omega x r_i, with the angular velocity omega of the raised moments,
     * and the kinetic energy and temperature the integrator reports are those of the raised moments, so
     * that the thermostats work as before. The rotational dynamics (and, through the coupling of
     * rotation and translation in a liquid, the diffusion) is slower: time correlation functions and
     * transport properties are not those of the real molecules. For water (TIP3P moments 0.0061,
     * 0.0116, 0.0177 amu nm^2), 0.04 makes every water a spherical top, whose exact free rotation is
     * also the cheapest one. Set it before the integrator is bound to a Context.
     *
     * Velocities that do not come from this integrator are read as rigid motion with these moments:
     * setVelocitiesToTemperature() draws for them, and a checkpoint records the minimum moment and is
     * refused by an integrator with another one; but velocities set from a State or an array made with
     * other moments keep their angular velocities, so their rotational kinetic energy changes by I'/I.
     * A System with an AndersenThermostat, and a CompoundIntegrator, draw velocities for the particles'
     * own moments: with raised moments, either is refused when the Context is made.
     *
     * @param moment  the minimum moment, measured in amu nm^2 (0 for none, at most MaximumMinimumMoment)
     * @throws OpenMMException if the moment is not between 0 and MaximumMinimumMoment, or the integrator is bound to a Context
     */
    void setMinimumMomentOfInertia(double moment);
    /**
     * Integrate some forces with a smaller step than others (multiple time steps, r-RESPA), in the
     * convention of OpenMM's MTSLangevinIntegrator: a list of (force group, substeps) pairs, each group
     * evaluated that many times per step. The slowest groups (1 substep) kick at the step's kicks; each
     * faster level divides every drift of the level above into substeps / (the level above's substeps)
     * substeps, kicking with its own forces around them. Put the cheap, stiff forces (the solute's
     * bonds, angles, torsions and CMAP) in a fast group and the nonbonded forces in the slow one:
     * the nonbonded forces are then evaluated once per step. Only what the fast forces reach moves in
     * the substeps: a body none of whose particles a fast force acts on (every rigid water) drifts once
     * per drift of the step, exactly as in pieces (free drifts compose), and pays nothing for them.
     *
     * RigidBodyLangevinIntegrator applies its Ornstein-Uhlenbeck stage once per step, at the midpoint
     * of the nest (BAOAB with the inner levels inside the drifts); its velocities between steps then
     * lack half a kick of the slowest forces only. The groups listed replace the integration force
     * groups (setIntegrationForceGroups()): forces in groups not listed are not integrated. An empty
     * list (the default) is one level of the integration force groups; setting it empty after a list
     * keeps the groups that list made the integration force groups (call setIntegrationForceGroups()
     * to change them). Set it before the integrator
     * is bound to a Context.
     *
     * @param groupSubsteps  (force group, substeps) pairs: groups 0 to 31, each once; the slowest
     *                       groups' substeps must be 1, and each level's a multiple of the next
     *                       slower one's
     * @throws OpenMMException if the list breaks these rules, or the integrator is bound to a Context
     */
    void setForceGroupSubsteps(const std::vector<std::pair<int, int> >& groupSubsteps);
    /** Get the (force group, substeps) pairs of setForceGroupSubsteps(), as given (empty: one level). */
    const std::vector<std::pair<int, int> >& getForceGroupSubsteps() const {
        return groupSubsteps;
    }
#ifndef SWIG
    /**
     * Set the force groups to integrate (OpenMM's Integrator::setIntegrationForceGroups()); with
     * setForceGroupSubsteps() they are the groups it lists, and another set is refused.
     */
    void setIntegrationForceGroups(int groups) override;
    /** The levels of the multiple time steps, slowest first (one level without them): valid while bound to a Context. */
    const std::vector<TimeStepLevel>& getTimeStepLevels() const {
        return levels;
    }
#endif
    /**
     * The largest minimum moment of inertia, in amu nm^2: 16,000 times the smallest moment of water.
     * Larger ones only slow the rotation further, while the rounding of each body's angular velocity
     * is magnified by the ratio of its moments (at 1e50, setVelocitiesToTemperature() reads 1e24 K).
     */
    static constexpr double MaximumMinimumMoment = 100.0;
    /**
     * Get the instantaneous temperature, 2 KE / (dof k_B), with the degrees of freedom as this integrator
     * moves the system: 3 per free particle, less one per constraint among free particles, plus 3
     * translational and 0 (one particle), 2 (linear) or 3 rotational ones per body, less 3 with a
     * CMMotionRemover. openmm.app.StateDataReporter uses it. Available once the integrator is bound to
     * a Context and, with explicit bodies, the positions are set.
     *
     * @return the temperature, measured in K
     */
    double computeSystemTemperature();
    /**
     * Set whether to measure the shadow work and the heat of the steps (getShadowWork(), getHeat()). Off
     * by default: it costs an energy evaluation per step. Takes effect at the next step; the sums so far
     * are kept.
     *
     * @param measure  true to measure them
     */
    void setMeasureShadowWork(bool measure);
    /** Get whether the shadow work and the heat are measured (see setMeasureShadowWork()). */
    bool getMeasureShadowWork() const {
        return measureShadowWork;
    }
    /**
     * Get the shadow work: the change of the total energy K + U (U of the integration force groups)
     * made by the deterministic stages (kicks and drifts) of the steps measured since the Context was
     * made, so that shadow work + heat = the change of K + U over those steps. Exact dynamics would give
     * 0; its growth measures the integration error (Sivak, Chodera and Crooks, Phys. Rev. X 3, 011007
     * (2013)). What changes the state between steps (a barostat, a CMMotionRemover, setPositions) is not
     * counted. Saved in checkpoints.
     *
     * @return the shadow work, measured in kJ/mol
     * @throws OpenMMException if the integrator is not bound to a Context, or the shadow work is not measured
     */
    double getShadowWork() const;
    /**
     * Get the heat: the kinetic energy that the stochastic stages (RigidBodyLangevinIntegrator's
     * Ornstein-Uhlenbeck stage, RigidBodyBussiIntegrator's rescaling) added over the steps measured since
     * the Context was made; negative where they took energy away. Saved in checkpoints.
     *
     * @return the heat, measured in kJ/mol
     * @throws OpenMMException if the integrator is not bound to a Context, or the heat is not measured
     */
    double getHeat() const;
    /**
     * Set whether to check, from the run itself, that the step is small enough for the ensemble to be
     * right (on by default). The check reads the energy balance of the steps at samples, in 2 ps windows
     * within episodes of 4 ps every 40 ps, and costs no measurable time. When the run leaves its accurate
     * range (a Langevin run's momenta heated more than 4 % above the bath, a constant-energy run drifting
     * more than 0.01 kT/ps per degree of freedom, a Bussi run's energy error fluctuating more than 0.06
     * times the kinetic energy; in two windows in a row) it says so once, from within the step, naming the
     * step size, the figure and the remedies: in Python as an openmmrigid.AccuracyWarning, in C++ on the
     * standard error stream. The run goes on. A System with an AndersenThermostat is not checked. The
     * manual's guide (docs/guide/accuracy-check.md) gives the limits and the measurements behind them.
     *
     * @param check  true to check (the default)
     */
    void setAccuracyCheck(bool check) {
        accuracyCheck = check;
    }
    /** Get whether the run's accuracy is checked (see setAccuracyCheck()). */
    bool getAccuracyCheck() const {
        return accuracyCheck;
    }
#ifndef SWIG
    /**
     * Whether the step being taken ends with the potential energy evaluated (StepState::potentialEnergy):
     * to measure the shadow work (getShadowWork()), or for the accuracy check.
     */
    bool wantsEnergy() const {
        return measureShadowWork || energyWanted;
    }
    /** Whether the step being taken sums the heat of its stochastic stages: for getHeat(), getShadowWork(), or the accuracy check. */
    bool wantsHeat() const {
        return measureShadowWork || checkingStep;
    }
#endif
    /**
     * Advance a simulation through time by taking a series of time steps.
     *
     * @param steps   the number of time steps to take
     */
    void step(int steps);
protected:
    /** The name of the class the user made, which messages name. */
    const std::string& getClassName() const {
        return className;
    }
    /**
     * @param className  the name of the concrete class, for messages
     * @param stepSize   the step size, measured in ps
     */
    RigidBodyIntegratorBase(const std::string& className, double stepSize);
    /**
     * @param className  the name of the concrete class, for messages
     * @param stepSize   the step size, measured in ps
     * @param bodies     the particle indices of each body
     */
    RigidBodyIntegratorBase(const std::string& className, double stepSize, const std::vector<std::vector<int> >& bodies);
    ~RigidBodyIntegratorBase();
    /** Build the body topology, create the kernel and start the step state (seeded by getRequestedSeed()). */
    void initialize(OpenMM::ContextImpl& context);
    void cleanup();
    void stateChanged(OpenMM::State::DataType changed);
    std::vector<std::string> getKernelNames();
    double computeKineticEnergy();
    bool kineticEnergyRequiresForce() const {
        return false;
    }
    /**
     * Velocities for Context.setVelocitiesToTemperature(): OpenMM's draw for every particle, with the
     * angular velocity of each body whose moments are raised scaled by sqrt(I_k / I'_k) about each of
     * its principal axes, so that its rotation is drawn from the Maxwell-Boltzmann distribution of the
     * raised moments (the projection onto rigid motion keeps the angular velocity of the particles).
     * Where OpenMM then takes the velocities back by getVelocityTimeOffset() (F_i offset / m_i), each
     * raised body's angular velocity is first corrected so that the torque turns it with the raised
     * moments; with multiple time steps, where the held velocities lag half a kick of the slowest
     * level's forces only, the other groups' share of OpenMM's offset is given back.
     */
    std::vector<OpenMM::Vec3> getVelocitiesForTemperature(const OpenMM::System& system, double temperature, int randomSeed) const;
    /**
     * After the positions and velocities OpenMM writes: a header (format version, class name), the
     * seed and counter of the random numbers, and, if hasThermostatWork(), the thermostat's work;
     * the shadow work and heat; the minimum moment of inertia (a load with another is refused); the
     * bodies' states where the platform saves them (IntegrateRigidBodyStepKernel::getBodyStates()),
     * from which a load continues exactly instead of fitting the bodies again.
     */
    void createCheckpoint(std::ostream& stream) const;
    void loadCheckpoint(std::istream& stream);
    /** The integrator's random number seed (0: choose one per Context). */
    virtual int getRequestedSeed() const = 0;
    /**
     * The kick (a time, in ps; 0 for none) that takes the velocities of a checkpoint of this format
     * version to those this build's step expects: applied to the bodies' momenta and the free
     * particles, by the forces at the loaded positions, once the loaded state is projected.
     */
    virtual double getLoadedVelocityKick(int version) const {
        return 0.0;
    }
    /** What the accuracy check needs to know about a step of this integrator (see internal/AccuracyCheck.h). */
    virtual AccuracyCheck::Setting getAccuracySetting() const = 0;
    /** Whether the step state's thermostat work belongs to this integrator's checkpoints. */
    virtual bool hasThermostatWork() const {
        return false;
    }
    /**
     * Take one step: run the step sequence of the concrete integrator. On entry the context holds
     * the forces at the current positions and the bodies agree with them; on exit it holds the
     * forces at the new positions.
     */
    virtual void executeStep(OpenMM::ContextImpl& context) = 0;
    /**
     * The kinetic energy the momenta would have after a kick of `kick` (ps) by the current forces,
     * leaving the state as it is (IntegrateRigidBodyStepKernel::computeKickedKineticEnergies()): the
     * bodies and forces made current first, as a step makes them. Throws unless bound, naming `method`.
     */
    double computeKickedKineticEnergy(double kick, const std::string& method);
    /** The kernel, once the integrator is bound to a Context (throws otherwise). */
    IntegrateRigidBodyStepKernel& getKernel() const;
    /** The body topology, once the integrator is bound to a Context (throws otherwise). */
    const RigidBodySystem& getTopology() const;
    /**
     * Add the thermostat's work the kernel has accumulated since it was last taken (rescaleMomenta()
     * on the device) to stepState.thermostatWork, and to stepState.heat if the heat is measured, if
     * hasThermostatWork(): before the work or the heat is read or saved, and before
     * setMeasureShadowWork() changes what the steps since belong to. On a GPU this waits for the device
     * (unless no step has rescaled since).
     */
    void takeThermostatWork() const;
    /**
     * What the step sequence keeps between steps (random numbers, thermostat work). Mutable so that
     * the const createCheckpoint() can take the kernel's pending thermostat work into it.
     */
    mutable StepState stepState;
private:
    // The XML proxies write the explicit bodies (serialization/src/RigidIntegratorSerialization.cpp).
    friend void serializeRigidIntegratorBase(const RigidBodyIntegratorBase& integrator, OpenMM::SerializationNode& node);
    /** Whether the bodies were given explicitly, rather than found from the System's constraints. */
    bool hasExplicitBodies() const {
        return explicitBodies;
    }
    /** The explicit bodies passed to the constructor (empty when they are found from the System). */
    const std::vector<std::vector<int> >& getExplicitBodies() const {
        return bodies;
    }
    /**
     * getVelocitiesForTemperature()'s raised-moment correction of a draw: each raised body's angular
     * velocity scaled by sqrt(I_k / I'_k), and turned by offset (1/I_k - 1/I'_k) tau with the torque of
     * the force groups whose offset OpenMM's Context is left to take.
     */
    std::vector<OpenMM::Vec3> raisedVelocities(std::vector<OpenMM::Vec3> velocities, double offset, int groups) const;
    /** The degrees of freedom of computeSystemTemperature(). */
    int getNumDegreesOfFreedom() const;
    /** Body b, with its shape (an OpenMMException if it is an explicit body whose positions were never set). */
    const RigidBodySystem& getShapedBody(int b) const;
    /**
     * Give the explicit bodies without a shape the one they have in the Context's positions; those
     * the positions cannot shape wait, or, if strict, are an OpenMMException saying why.
     */
    void captureShapes(const StepGeometry& geometry, bool strict);
    /** Fit the bodies to the Context's positions (giving explicit bodies their shapes first, strictly). */
    void projectBodies();
    /** Apply the kick getLoadedVelocityKick() asked for after a checkpoint, if any (the bodies must be projected). */
    void applyLoadedVelocityKick();
    /**
     * What a step takes from before it, proven current or rebuilt: the bodies fitted again if the
     * positions are not those the kernel last wrote (or a notice came), and whether the forces the
     * Context holds are this integrator's at these positions and this box (returned), box set to the
     * box now, and `moved` (if given) to whether the positions or the box changed since the last step.
     */
    bool makeBodiesCurrent(OpenMM::Vec3* box, bool* moved = NULL);
    /** Whether a barostat of the System may move the particles at this call of updateContextState() (counted by stateUpdates). */
    bool barostatMayMove(long long call) const;
    /**
     * Evaluate the integration force groups' forces (and, if asked, their energy, kept as the step
     * state's potential energy) at the current positions and box, and record them as current.
     */
    void evaluateForces(const OpenMM::Vec3* box, bool energy);
    std::string className;
    std::vector<std::vector<int> > bodies;
    bool explicitBodies;
    RotationMethod rotationMethod;
    double minimumMoment;
    std::vector<std::pair<int, int> > groupSubsteps;
    std::vector<TimeStepLevel> levels;
    bool measureShadowWork, measureHeat, accuracyCheck, checkingStep, energyWanted;
    /** Whether the System has an AndersenThermostat (whose runs the accuracy check leaves alone). */
    bool andersenThermostat;
    /**
     * The accuracy check of this Context's run, and the energy that changed other than by the steps'
     * deterministic stages and the thermostat: the kernel's tally of the kinetic energy at the start
     * and end of the steps measured, and the potential energy a barostat's move added (all steps, not
     * reset; the shadow work at a sample is the potential energy less this and the thermostat's work).
     */
    AccuracyCheck accuracyMonitor;
    double checkedLedger;
    /**
     * The System's Monte Carlo barostats: each one's frequency, and the count of updateContextState()
     * calls (stateUpdates, this integrator's since the Context was made) at which it last moved, or 0.
     * A barostat tries a move every `frequency` calls; the step before one ends with the energy, so
     * that the accuracy check can take the move's energy change out.
     */
    std::vector<std::pair<int, long long> > barostats;
    long long stateUpdates;
    bool bound, forcesAreValid, needsProjection;
    /** Whether the bodies' states came from the checkpoint just loaded (the notices that follow the load change nothing). */
    bool restoredCheckpoint;
    /** The periodic box of the last force evaluation: setPeriodicBoxVectors() sends the integrator no notice. */
    OpenMM::Vec3 forcesBox[3];
    double loadedVelocityKick;
    OpenMM::Kernel kernel;
    std::unique_ptr<RigidBodySystem> topology;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_RIGIDBODYINTEGRATORBASE_H_*/

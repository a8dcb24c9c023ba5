#ifndef OPENMMRIGID_ACCURACYCHECK_H_
#define OPENMMRIGID_ACCURACYCHECK_H_

#include "internal/windowsExportRigid.h"
#include <string>

namespace OpenMMRigid {

/**
 * The signal that a run has left its accurate range, from the run itself: the shadow work of every
 * step (internal/StepSequence.h), the kinetic energy after it, and the heat, read in windows of
 * WindowTime ps (at least MinimumSteps steps). Two figures, each per window:
 *
 * - with a heat bath that thermalizes every step (RigidBodyLangevinIntegrator, friction > 0): the
 *   heating, the fraction by which the momenta the Ornstein-Uhlenbeck stage meets are hotter than the
 *   bath in the steady state. The stage takes out on average (1 - c^2) (K - dof kT / 2) per step,
 *   c = exp(-friction dt), and in a steady state it takes out what the deterministic stages put in,
 *   so heating = 2 (shadow work per step) / ((1 - c^2) dof kT). It is the shadow work's slope over the
 *   window, which telescopes and so is precise within picoseconds, where the kinetic temperature
 *   itself would need tens of them. It grows with the step and falls with the friction, as the error
 *   of the ensemble does.
 * - otherwise (RigidBodyIntegrator, with or without its thermostat, and friction 0): the drift of
 *   the energy, the shadow work's slope per degree of freedom in kT per ps; and with the Bussi
 *   thermostat also the energy error's fluctuation, the standard deviation of the shadow work about
 *   its linear trend over the window divided by that of the kinetic energy (the fluctuation of
 *   Bussi's effective energy against the kinetic energy's: the classic measure of a step size, which
 *   grows as dt^2 and is intensive). The thermostat holds the on-step kinetic energy at the bath's,
 *   so an error that leaves the energy without drift still biases the ensemble (Verlet above 4 fs
 *   in rigid water); without a thermostat the run samples its own (shadow) energy surface, and
 *   only a drift is wrong by the guide's rule for constant energy (docs/guide/accuracy-check.md).
 *
 * It fires when a figure is above its limit in two windows in a row (so that one window's
 * fluctuation does not), once; the limits and their measurements: docs/guide/accuracy-check.md.
 *
 * It measures in episodes: one from the first step of a Context, and from every change of the
 * setting, of at least two windows, continued for as long as the last window is above a limit; then
 * none for PauseTime ps. A run that goes wrong from its start (a step too large for it) is told within
 * two windows; one that goes wrong later, within PauseTime.
 *
 * Within an episode it reads samples, SamplesPerWindow a window (every sampleStride() steps), not
 * every step: the shadow work telescopes, so that between two samples it is the change of the
 * potential energy less what the steps' stochastic stages and the world outside the step added
 * (the thermostat's heat, summed by the kernel where the momenta are; the kinetic energy a
 * CMMotionRemover takes out between steps; a barostat's move), and the potential energy is evaluated
 * only at the samples (RigidBodyIntegratorBase::step()). An ordinary step of an episode then costs two
 * kinetic-energy sums, which stay on a GPU, and no energy evaluation.
 */
class OPENMM_EXPORT_RIGID AccuracyCheck {
public:
    /** The length of a window, in ps. */
    static constexpr double WindowTime = 2.0;
    /** The least number of steps in a window. */
    static constexpr int MinimumSteps = 200;
    /** The number of samples a window of the least length reads (one every sampleStride() steps). */
    static constexpr int SamplesPerWindow = 40;
    /** The time between episodes, in ps. */
    static constexpr double PauseTime = 36.0;
    /** The limit of the heating of a Langevin run (fraction of the bath's temperature). */
    static constexpr double HeatingLimit = 0.04;
    /** The limit of the energy error's fluctuation against the kinetic energy's. */
    static constexpr double FluctuationLimit = 0.06;
    /** The limit of the energy drift, in kT per ps per degree of freedom. */
    static constexpr double DriftLimit = 0.01;
    /**
     * What a step is: its size (ps), the friction of its Ornstein-Uhlenbeck stage (1/ps; 0 if none),
     * the bath's temperature (K; 0 for none: kT is then the kinetic energy's), the degrees of
     * freedom, and, for messages, the integrator's class and the remedies to name. A window is
     * started again when any of these changes.
     */
    struct Setting {
        double stepSize = 0.0, friction = 0.0, temperature = 0.0;
        int dof = 0;
        /** Whether a global thermostat rescales the momenta (Bussi's): the fluctuation is then judged too. */
        bool rescaling = false;
        /** What runs (the class, and its splitting), and what to do about it: one clause, which the message
         *  ends with how to turn the check off. */
        std::string description, remedies;
        bool operator==(const Setting& other) const {
            return stepSize == other.stepSize && friction == other.friction && temperature == other.temperature &&
                   dof == other.dof && rescaling == other.rescaling && description == other.description;
        }
    };
    /**
     * Whether the step about to be taken, of this setting, from this time (ps), is to be measured:
     * within an episode.
     */
    bool wantsStep(const Setting& setting, double time);
    /**
     * Whether the step about to be taken (one wantsStep() accepted) ends at a sample, to be given to
     * record(): the first step of a window (whose end is the window's origin), then every
     * sampleStride() steps.
     */
    bool wantsSample(const Setting& setting);
    /** Whether a window is in progress: the shadow work since its origin must then be accounted for. */
    bool inWindow() const {
        return started;
    }
    /** The number of steps from one sample to the next at this setting: a window reads about SamplesPerWindow. */
    static int sampleStride(const Setting& setting);
    /**
     * A sample, after the step wantsSample() asked for: its setting, the time (ps), the shadow work
     * summed since the window's origin (kJ/mol, any origin; RigidBodyIntegratorBase::step()), and the
     * kinetic energy (kJ/mol).
     */
    void record(const Setting& setting, double time, double shadowWork, double kinetic);
    /** Forget the window in progress (a step that did not finish or was not measured, a new Context). */
    void restart();
    /**
     * The state was set from outside (positions, velocities, a checkpoint): the windows start again,
     * with the origin after the next step, whose shadow work carries the jump from the state set to
     * the integrator's own (velocities drawn for one time read at another: a Langevin step's first
     * kick from canonical velocities adds about (omega dt)^2 kT / 2 per degree of freedom).
     */
    void stateSet();
    /** The message of the signal once it has fired; empty before. */
    const std::string& getMessage() const {
        return message;
    }
    /** Whether the signal fired after this time (ps): a run taken back to before it is judged again (rearm()). */
    bool firedAfter(double time) const {
        return !message.empty() && time < firedTime*(1.0 - 1e-12);
    }
    /** Start afresh, as for a new run: no message, a new episode, windows from after the next step (stateSet()). */
    void rearm() {
        *this = AccuracyCheck();
        stateSet();
    }
    /**
     * What is told when a check fires, once per firing: its message. It returns false to stop the
     * run: the step that fired has finished, and step() then throws an OpenMMException with the
     * message. The Python module sets one that issues an openmmrigid.AccuracyWarning (false where the
     * warning filters make it an error); without one, the message goes to std::cerr as a warning.
     */
    typedef bool (*Notifier)(const std::string& message);
    static void setNotifier(Notifier notifier);
    /** Tell the notifier (or std::cerr) the message; returns what the notifier returned (true for std::cerr). */
    static bool notify(const std::string& message);
private:
    /** Judge the window just completed, whose last sample is at this time (ps). */
    void closeWindow(double lastTime);
    Setting setting;
    bool started = false;
    double startTime = 0.0, startWork = 0.0;
    /** The steps left to the next sample (0: the next step ends at one). */
    int stepsToSample = 0;
    // Sums over the window of t, t^2, w, w^2, t w, K, K^2, with t and w from the window's start.
    double n = 0, st = 0, stt = 0, sw = 0, sww = 0, stw = 0, sk = 0, skk = 0;
    int windowsAbove = 0, windowsInEpisode = 0;
    bool inEpisode = true;
    double nextEpisode = 0.0;
    double firedTime = 0.0;
    std::string message;
};

} // namespace OpenMMRigid

#endif /*OPENMMRIGID_ACCURACYCHECK_H_*/

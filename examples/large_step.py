"""The point of openmm-rigid: rigid water sampled at a step stock OpenMM cannot take.

Rigid TIP4P-Ew water (amber14/tip4pew.xml, PME 0.9 nm, rigidWater, 300 K, friction 1/ps: the systems
of the project's measurements, docs/guide/step-sizes.md) runs at constant temperature, side by side, with

- stock ``LangevinMiddleIntegrator`` + SETTLE at its accurate step, 5 fs by default, and
- ``RigidBodyLangevinIntegrator`` with every moment of inertia raised to at least 0.04 amu nm^2
  (``setMinimumMomentOfInertia``) at its accurate step, 12 fs by default.

Why these steps (docs/guide/raised-moments.md and docs/validation/inertia_sampling.md: 500
TIP4P-Ew waters, NVT, friction 1/ps, U per water against the step, bias tolerance 0.1 kJ/mol): stock
is accurate to 5.3-6 fs (+0.13 kJ/mol at 6 fs in one reading, NaN at 8 fs), and the benchmarks time it
at 5 fs; the rigid integrator with raised moments is accurate to 13.5-14 fs (unstable at 16 fs), and
its accuracy check stays quiet at 12 and 14 fs. 12 fs is the guide's own example for raised moments
and keeps a margin below 13.5 fs. Raised moments keep every configurational average (U, g(r),
density: the orientational Boltzmann weight has no inertia in it), not the dynamics (librations and
diffusion slow), the rigid-body counterpart of hydrogen mass repartitioning. ``--stock-step`` and
``--rigid-step`` change the steps (2 fs for stock is the conventional, conservative choice).

Both start from one state (minimized, then 3 ps of stock dynamics at 2 fs); each draws its own
velocities (the raised moments need theirs), runs ``--discard`` ps that are left out, then ``--time``
ps that are measured. The two Contexts are advanced in turn, one short round each (the same simulated
time), and only the step() calls are timed, so that both see the same load on the machine.

It prints, for each integrator: ns/day (simulated time per wall-clock day of step() calls), the
ratio, the mean potential energy U per molecule with its standard error (from the samples'
autocorrelation) and the difference between the two, and the
temperature with its translational and rotational parts (the rigid integrator's from
``openmmrigid.RigidStateDataReporter``; stock's from each molecule's centre-of-mass and rotational
kinetic energy, from the State's velocities with numpy); whether the rigid integrator's accuracy
check (on by default) fired; and writes a plot of U per molecule and the temperatures against time
(examples/output/large_step.png; needs matplotlib: pip install "openmm-rigid[examples]") and the
samples beside it (large_step.csv).

    python examples/large_step.py [--molecules 500] [--time 30] [--discard 3] [--stock-step 5]
                                  [--rigid-step 12] [--platform CUDA|OpenCL|CPU]

The default settings (500 waters, 3 + 30 ps per integrator) take about a minute and a half on two
CPU cores. The platform is the fastest with
the plugin's kernels (CUDA, then OpenCL on a GPU, then CPU) unless --platform says otherwise.
"""

import argparse
import contextlib
import io
import math
import os
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from _molecules import MOLAR_GAS_CONSTANT, WATERS_PER_CUBIC_NANOMETRE

TEMPERATURE = 300.0   # K
FRICTION = 1.0        # 1/ps: the friction of the step measurements (docs/guide/step-sizes.md)
MINIMUM_MOMENT = 0.04  # amu nm^2: every water a spherical top (its moments are 0.006 to 0.018)
OUTPUT = Path(__file__).resolve().parent / "output" / "large_step.png"


# ---------------------------------------------------------------------------------------------------
# Platform and system


@contextlib.contextmanager
def quiet():
    """Silence what the C++ libraries print on file descriptors 1 and 2 (OpenMM warns about PoCL)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    try:
        with open(os.devnull, "w") as devnull:
            os.dup2(devnull.fileno(), 1)
            os.dup2(devnull.fileno(), 2)
        yield
    finally:
        for descriptor, copy in zip((1, 2), saved):
            os.dup2(copy, descriptor)
            os.close(copy)


def openclRunsOnAGpu():
    """Whether OpenMM's OpenCL platform drives a GPU: PoCL (OpenCL on the CPU) is slower than the CPU platform."""
    system = openmm.System()
    system.addParticle(1.0)
    platform = openmm.Platform.getPlatformByName("OpenCL")
    try:
        with quiet():
            context = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
            name = platform.getPropertyValue(context, "OpenCLPlatformName")
        del context
    except Exception:
        return False
    return "Portable Computing Language" not in name


def choosePlatform(requested):
    """(platform, properties, why) for the runs: the one requested, else the fastest with the plugin's kernels."""
    supported = openmmrigid.getSupportedPlatforms()
    if requested:
        if requested not in supported:
            sys.exit(f"error: platform {requested} has no rigid-body kernels here (these do: {', '.join(supported)})")
        name, why = requested, "as requested"
    elif "CUDA" in supported:
        name, why = "CUDA", "the fastest here"
    elif "OpenCL" in supported and openclRunsOnAGpu():
        name, why = "OpenCL", "the fastest here (no CUDA)"
    else:
        name, why = "CPU", "the fastest here (no GPU platform" + (
            "; OpenCL is PoCL, on the CPU, slower than the CPU platform)" if "OpenCL" in supported else ")")
    platform = openmm.Platform.getPlatformByName(name)
    properties = {"Precision": "mixed"} if name in ("CUDA", "OpenCL") else {}
    return platform, properties, why


def describePlatform(context):
    platform = context.getPlatform()
    name = platform.getName()
    if name == "CPU":
        return f"CPU, {platform.getPropertyValue(context, 'Threads')} threads"
    if name in ("CUDA", "OpenCL"):
        return f"{name} ({platform.getPropertyValue(context, 'DeviceName').strip()}), mixed precision"
    return name


def waterBox(molecules):
    """TIP4P-Ew water in a periodic cube of about `molecules` waters: (topology, positions, system)."""
    edge = (molecules/WATERS_PER_CUBIC_NANOMETRE)**(1/3)
    forceField = app.ForceField("amber14/tip4pew.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forceField, model="tip4pew", boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME,
                                     nonbondedCutoff=min(0.9, 0.45*edge)*unit.nanometer, constraints=None,
                                     rigidWater=True, ewaldErrorTolerance=5e-4)
    return modeller.topology, modeller.positions, system


# ---------------------------------------------------------------------------------------------------
# Runs


class Run:
    """One integrator in its own Simulation: samples of U per molecule and of the temperatures, and the
    wall seconds of the step() calls of each round."""

    def __init__(self, label, short, integrator, topology, system, state, platform, properties, seed):
        self.label, self.short, self.integrator = label, short, integrator
        self.dt = integrator.getStepSize().value_in_unit(unit.picosecond)
        integrator.setRandomNumberSeed(seed)
        self.simulation = app.Simulation(topology, system, integrator, platform, properties)
        self.context = self.simulation.context
        self.context.setState(state)
        # Velocities for this integrator's own moments (a State drawn for the particles' moments would give
        # the raised moments a rotational temperature I'/I times too high).
        self.context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, seed)
        self.molecules = topology.getNumResidues()
        self.times, self.potential, self.temperature, self.translational, self.rotational = [], [], [], [], []
        self.roundSeconds, self.roundSteps = [], []
        self.failure = None

    def advance(self, steps):
        """Take `steps` steps (timed), then sample; a blown-up run is marked failed and stops."""
        if self.failure:
            return
        started = time.perf_counter()
        try:
            self.integrator.step(steps)
        except openmm.OpenMMException as error:
            self.failure = str(error).splitlines()[0]
            return
        self.roundSeconds.append(time.perf_counter() - started)
        self.roundSteps.append(steps)
        state = self.context.getState(getEnergy=True, getPositions=True, getVelocities=True)
        potential = state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/self.molecules
        if not math.isfinite(potential):
            self.failure = "the energy is NaN"
            return
        self.times.append(state.getTime().value_in_unit(unit.picosecond))
        self.potential.append(potential)
        total, translational, rotational = self.temperatures(state)
        self.temperature.append(total)
        self.translational.append(translational)
        self.rotational.append(rotational)


class StockRun(Run):
    """LangevinMiddleIntegrator + SETTLE; temperatures from each molecule's kinetic energy (numpy)."""

    def __init__(self, stepFs, *args):
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, FRICTION/unit.picosecond,
                                                     stepFs*unit.femtoseconds)
        super().__init__(f"stock LangevinMiddleIntegrator + SETTLE, {stepFs:g} fs", "stock", integrator, *args)
        topology, system = args[0], args[1]
        self.bodies = np.array([[atom.index for atom in residue.atoms()] for residue in topology.residues()])
        masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton)
                           for i in range(system.getNumParticles())])
        self.masses = masses[self.bodies][:, :, None]  # molecules x sites x 1 (the M site is massless)
        remover = any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
        self.translationalDof = 3*len(self.bodies) - (3 if remover else 0)
        self.rotationalDof = 3*len(self.bodies)

    def temperatures(self, state):
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)[self.bodies]
        momenta, bodyMasses = (self.masses*velocities).sum(axis=1), self.masses.sum(axis=1)
        translational = 0.5*np.sum(momenta**2/bodyMasses)
        rotational = 0.5*np.sum(self.masses*velocities**2) - translational  # rigid: the motion about the centre
        dof = self.translationalDof + self.rotationalDof
        return (2*(translational + rotational)/(dof*MOLAR_GAS_CONSTANT),
                2*translational/(self.translationalDof*MOLAR_GAS_CONSTANT),
                2*rotational/(self.rotationalDof*MOLAR_GAS_CONSTANT))


class RigidRun(Run):
    """RigidBodyLangevinIntegrator with raised moments; temperatures from RigidStateDataReporter."""

    def __init__(self, stepFs, *args):
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE*unit.kelvin, FRICTION/unit.picosecond,
                                                             stepFs*unit.femtoseconds)
        integrator.setMinimumMomentOfInertia(MINIMUM_MOMENT*unit.amu*unit.nanometer**2)  # before the Context
        super().__init__(f"RigidBodyLangevinIntegrator, moments >= {MINIMUM_MOMENT:g} amu nm^2, {stepFs:g} fs",
                         "rigid", integrator, *args)
        self.buffer = io.StringIO()
        self.reporter = openmmrigid.RigidStateDataReporter(self.buffer, 1, temperature=True,
                                                           translationalTemperature=True, rotationalTemperature=True)

    def temperatures(self, state):
        self.reporter.report(self.simulation, state)
        line = self.buffer.getvalue().strip().splitlines()[-1]
        self.buffer.seek(0)
        self.buffer.truncate()
        total, translational, rotational = (float(value) for value in line.split(","))
        return total, translational, rotational


def meanAndError(values):
    """The mean of a time series and its standard error, sigma sqrt(g/n), with the statistical inefficiency
    g = 1 + 2 sum_k (1 - k/n) C(k) summed until the normalized autocorrelation C first drops to zero (U of
    water stays correlated for a picosecond or more: a few block means underestimate the error)."""
    values = np.asarray(values, dtype=float)
    n = len(values)
    deviations = values - values.mean()
    variance = float(np.mean(deviations**2))
    if n < 4 or variance == 0.0:
        return float(values.mean()), float("nan")
    correlation = np.correlate(deviations, deviations, "full")[n - 1:]/np.arange(n, 0, -1)/variance
    inefficiency = 1.0
    for lag in range(1, n//2):
        if correlation[lag] <= 0.0:
            break
        inefficiency += 2*correlation[lag]*(1 - lag/n)
    return float(values.mean()), float(np.sqrt(variance*inefficiency/n))


def roundLength(stepsFs):
    """The simulated time (fs) each run advances per round: a whole number of steps of each (the least
    common multiple of integer steps) and at least 100 fs; about 100 fs when the steps are not integers."""
    if all(float(step).is_integer() for step in stepsFs):
        common = math.lcm(*(int(step) for step in stepsFs))
        return common*math.ceil(100/common)
    return 100.0


# ---------------------------------------------------------------------------------------------------
# Results


def summarize(runs, rounds, discardRounds):
    """Print the table and its legend; return the production statistics of each run."""
    stats = {}
    for run in runs:
        if run.failure or len(run.times) < rounds:
            stats[run.short] = None
            continue
        production = slice(discardRounds, None)
        seconds = sum(run.roundSeconds[production])
        nanoseconds = sum(run.roundSteps[production])*run.dt/1000
        stats[run.short] = dict(
            nsPerDay=nanoseconds/seconds*86400, msPerStep=1000*seconds/sum(run.roundSteps[production]),
            potential=meanAndError(run.potential[production]), temperature=meanAndError(run.temperature[production]),
            translational=meanAndError(run.translational[production]),
            rotational=meanAndError(run.rotational[production]))
    print(f"\n{'':<68}{'ns/day':>8}{'ms/step':>9}{'U per molecule':>20}{'T':>8}{'T trans':>9}{'T rot':>8}")
    print(f"{'':<68}{'':>8}{'':>9}{'(kJ/mol)':>20}{'(K)':>8}{'(K)':>9}{'(K)':>8}")
    for run in runs:
        s = stats[run.short]
        if s is None:
            print(f"{run.label:<68}FAILED: {run.failure or 'stopped early'}")
            continue
        u, ue = s["potential"]
        print(f"{run.label:<68}{s['nsPerDay']:>8.1f}{s['msPerStep']:>9.2f}{u:>12.3f} +- {ue:<5.3f}"
              f"{s['temperature'][0]:>8.1f}{s['translational'][0]:>9.1f}{s['rotational'][0]:>8.1f}")
    stock, rigid = stats.get("stock"), stats.get("rigid")
    if stock and rigid:
        ratio = rigid["nsPerDay"]/stock["nsPerDay"]
        # The same ratio round by round (simulated time per second of each run in that round), its median:
        # less sensitive to a burst of other work on the machine.
        rates = [np.array(run.roundSteps[discardRounds:])*run.dt/np.array(run.roundSeconds[discardRounds:])
                 for run in runs]
        perRound = float(np.median(rates[1]/rates[0]))
        difference = rigid["potential"][0] - stock["potential"][0]
        error = math.hypot(rigid["potential"][1], stock["potential"][1])
        print(f"\nrigid / stock ns/day: {ratio:.2f} (median over the rounds {perRound:.2f})")
        sigmas = abs(difference)/error
        defaultSteps = round(runs[0].dt*1000, 6) == 5 and round(runs[1].dt*1000, 6) == 12
        print(f"U per molecule, rigid - stock: {difference:+.3f} +- {error:.3f} kJ/mol ({sigmas:.1f} standard errors: "
              + ("the same within the errors)" if sigmas < 2 else "more than these errors; see the legend)")
              + ("; docs/validation/inertia_sampling.md's longer runs put it near -0.2" if defaultSteps else ""))
    print("\nns/day: simulated time per day of the step() calls alone, over the measured part; ms/step: the same per\n"
          "  step; the two runs advance in turn, so both see the same load (other work on the cores adds noise).\n"
          "U per molecule: the mean potential energy per water +- its standard error (from the samples'\n"
          "  autocorrelation; U wanders on a scale of several ps, so a run of 30 ps resolves about 0.1 to 0.2\n"
          "  kJ/mol and its error bar can understate that). A configurational average: raised moments keep it, so\n"
          "  the two differ only by each integrator's small bias at its step; docs/validation/inertia_sampling.md's runs (500 waters, two\n"
          "  starts of 20 ps, against 2 fs) read stock at 4 to 6 fs +0.07 to +0.08 and raised moments at 12 fs\n"
          "  -0.11 +- 0.05 kJ/mol: a difference near -0.2 kJ/mol, 0.4 % of U.\n"
          "T: the kinetic temperature (translational and rotational degrees of freedom together); T trans: that\n"
          "  of the molecules' centres of mass (3 per molecule, less 3 for the CMMotionRemover); T rot: that of\n"
          "  their rotation (3 per molecule; the rigid run's in the raised moments it moves them with). Each reads\n"
          "  the bath's 300 K to within a few K (a large step's usual error in the kinetic temperature); tens of K\n"
          "  too hot means the step is too large.")
    return stats


def writeSamples(runs, path):
    """The samples of both runs as CSV beside the plot: integrator, time (ps), U per molecule (kJ/mol), T,
    T translational, T rotational (K)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w") as out:
        out.write("integrator,time_ps,U_per_molecule_kJ_mol,T_K,T_translational_K,T_rotational_K\n")
        for run in runs:
            for row in zip(run.times, run.potential, run.temperature, run.translational, run.rotational):
                out.write(f"{run.short}," + ",".join(f"{value:.6g}" for value in row) + "\n")
    print(f"samples written to {path}")


def plot(runs, discardRounds, discardPs, stats, title, path):
    try:
        import matplotlib
    except ImportError:
        print("no plot: matplotlib is not installed (pip install matplotlib, or \"openmm-rigid[examples]\")")
        return
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    colours = {"stock": "tab:blue", "rigid": "tab:orange"}
    fig, axes = plt.subplots(3, 1, figsize=(11, 10.5), sharex=True, gridspec_kw=dict(height_ratios=[1.3, 1, 1]))
    panels = [("potential", "U per molecule (kJ/mol)", "kJ/mol", 3),
              ("translational", "T translational (K)", "K", 1), ("rotational", "T rotational (K)", "K", 1)]
    lines = []
    for run in runs:
        if not run.times:
            continue
        colour = colours[run.short]
        s = stats.get(run.short)
        measured = run.times[discardRounds:]
        for axis, (key, _, units, digits) in zip(axes, panels):
            label = f"{run.short}, {run.dt*1000:g} fs"
            if s:
                mean, error = s[key]
                label += f": {mean:.{digits}f} +- {error:.{digits}f} {units}"
                axis.hlines(mean, measured[0], measured[-1], color=colour, ls="--", lw=1.5)
                axis.fill_between([measured[0], measured[-1]], mean - error, mean + error, color=colour, alpha=0.25, lw=0)
            values = np.asarray(getattr(run, key))
            axis.plot(run.times, values, color=colour, lw=0.7, alpha=0.3)
            window = max(1, round(1.0/(run.times[1] - run.times[0]))) if len(run.times) > 1 else 1
            if len(values) >= window:  # the running mean over 1 ps, centred
                smooth = np.convolve(values, np.ones(window)/window, mode="valid")
                offset = (window - 1)//2
                line, = axis.plot(run.times[offset:offset + len(smooth)], smooth, color=colour, lw=1.8, label=label)
            else:
                line, = axis.plot(run.times, values, color=colour, lw=1.2, label=label)
            if key == "potential":
                lines.append((line, run.label + (f", {s['nsPerDay']:.0f} ns/day" if s else ", failed")))
    for axis, (key, ylabel, _, _) in zip(axes, panels):
        axis.axvspan(0, discardPs, color="0.88", zorder=0)
        axis.grid(alpha=0.3)
        axis.set_ylabel(ylabel)
        if key != "potential":
            axis.axhline(TEMPERATURE, color="k", lw=0.8, ls=":")
        low, high = axis.get_ylim()
        axis.set_ylim(low, high + 0.35*(high - low))  # room for the legend above the data
        axis.legend(loc="upper center", ncol=2, fontsize=9, framealpha=0.9)
    axes[0].text(discardPs/2, 0.04, "left out\n(equilibration)", transform=axes[0].get_xaxis_transform(),
                 ha="center", va="bottom", color="0.35", fontsize=9)
    axes[-1].set_xlabel("time (ps)")
    fig.suptitle(title, fontsize=12)
    fig.legend([line for line, _ in lines], [label for _, label in lines], loc="upper center", ncol=1, fontsize=9.5,
               bbox_to_anchor=(0.5, 0.945), frameon=False)
    fig.text(0.5, 0.005, "thin: every sample; thick: running mean over 1 ps; dashed: mean over the measured part; "
             "band: +- standard error; dotted: the bath's 300 K", ha="center", va="bottom", fontsize=9, color="0.3")
    fig.tight_layout(rect=(0, 0.02, 1, 0.905))
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    print(f"plot of U per molecule and the temperatures against time saved to {path}")


# ---------------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--molecules", type=int, default=500, help="approximate number of waters (default 500)")
    parser.add_argument("--time", type=float, default=30.0, help="measured ps per integrator (default 30)")
    parser.add_argument("--discard", type=float, default=3.0,
                        help="ps left out at the start of each run, while it settles at its own step (default 3)")
    parser.add_argument("--equilibrate", type=float, default=3.0,
                        help="ps of stock dynamics at 2 fs after minimizing, the common start (default 3)")
    parser.add_argument("--stock-step", type=float, default=5.0, help="fs (default 5: stock's accurate step)")
    parser.add_argument("--rigid-step", type=float, default=12.0,
                        help="fs (default 12: within the raised moments' accurate 13.5-14 fs)")
    parser.add_argument("--platform", choices=["CUDA", "OpenCL", "CPU", "Reference"],
                        help="default: the fastest with the plugin's kernels")
    parser.add_argument("--output", type=Path, default=OUTPUT, help=f"the plot (default {OUTPUT})")
    args = parser.parse_args()
    started = time.perf_counter()

    platform, properties, why = choosePlatform(args.platform)
    print(f"building a box of about {args.molecules} TIP4P-Ew waters with openmm.app ...", flush=True)
    topology, positions, system = waterBox(args.molecules)
    molecules = topology.getNumResidues()
    context = openmm.Context(system, openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, FRICTION/unit.picosecond,
                                                                     2*unit.femtoseconds), platform, properties)
    print(f"{molecules} TIP4P-Ew waters ({system.getNumParticles()} particles), PME 0.9 nm, 300 K, friction 1/ps; "
          f"platform {describePlatform(context)}: {why}")
    print(f"minimizing, then {args.equilibrate:g} ps of stock LangevinMiddleIntegrator at 2 fs: the common start ...",
          flush=True)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 200)
    context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 1)
    context.getIntegrator().step(round(args.equilibrate/0.002))
    context.setTime(0.0)
    state = context.getState(getPositions=True, getVelocities=True)
    del context

    common = (topology, system, state, platform, properties)
    runs = [StockRun(args.stock_step, *common, 2), RigidRun(args.rigid_step, *common, 3)]
    lengthFs = roundLength([args.stock_step, args.rigid_step])
    stepsPerRound = [max(1, round(lengthFs/(run.dt*1000))) for run in runs]
    discardRounds = math.ceil(args.discard*1000/lengthFs)
    rounds = discardRounds + max(5, math.ceil(args.time*1000/lengthFs))
    totalPs = rounds*lengthFs/1000
    print(f"ready after {time.perf_counter() - started:.0f} s; each integrator runs {totalPs:g} ps "
          f"({discardRounds*lengthFs/1000:g} left out, {(rounds - discardRounds)*lengthFs/1000:g} measured), "
          f"the two in turn, {lengthFs:g} fs each ({' and '.join(str(n) for n in stepsPerRound)} steps) ...", flush=True)

    accuracyWarnings = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", openmmrigid.AccuracyWarning)
        for number in range(rounds):
            for run, steps in zip(runs, stepsPerRound):
                run.advance(steps)
            for warning in caught:
                if issubclass(warning.category, openmmrigid.AccuracyWarning):
                    accuracyWarnings.append((runs[1].times[-1] if runs[1].times else 0.0, str(warning.message)))
                    print(f"  !! the accuracy check fired at {accuracyWarnings[-1][0]:.1f} ps: {warning.message}", flush=True)
                else:
                    warnings.showwarning(warning.message, warning.category, warning.filename, warning.lineno)
            caught.clear()
            if (number + 1) % max(1, rounds//5) == 0 or number + 1 == rounds:
                print(f"  ... {(number + 1)*lengthFs/1000:.1f} of {totalPs:g} ps", flush=True)
            if all(run.failure for run in runs):
                break
    for run in runs:
        if run.failure:
            print(f"  !! {run.label}: stopped at {run.times[-1] if run.times else 0:.1f} ps: {run.failure}")

    stats = summarize(runs, rounds, discardRounds)
    if accuracyWarnings:
        print(f"\nTHE ACCURACY CHECK FIRED for the rigid integrator at {accuracyWarnings[0][0]:.1f} ps: at "
              f"{args.rigid_step:g} fs this run left the integrator's accurate range, so its averages are biased "
              f"(the message above says what to change).")
    elif runs[1].integrator.getAccuracyCheck():
        print(f"\naccuracy check (on, the default): quiet; the rigid integrator stayed within its accurate range "
              f"at {args.rigid_step:g} fs.")
    title = (f"{molecules} rigid TIP4P-Ew waters, 300 K, friction 1/ps ({runs[0].context.getPlatform().getName()}): "
             f"stock {args.stock_step:g} fs vs rigid, raised moments, {args.rigid_step:g} fs")
    if stats.get("stock") and stats.get("rigid"):
        title += f"\nrigid/stock ns/day: {stats['rigid']['nsPerDay']/stats['stock']['nsPerDay']:.2f}"
    if accuracyWarnings:
        title += f"; the rigid integrator's ACCURACY CHECK FIRED at {accuracyWarnings[0][0]:.1f} ps (biased)"
    print()
    writeSamples(runs, args.output.with_suffix(".csv"))
    plot(runs, discardRounds, discardRounds*lengthFs/1000, stats, title, args.output)
    print(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""Energy conservation of RigidBodyIntegrator against stock Verlet + SETTLE, over step sizes (NVE).

Rigid-water boxes of 500 molecules (rigidtesting.waterBox: openmm.app, PME with a 0.9 nm
cutoff and Ewald error tolerance 5e-4, rigidWater=True, the force field's CMMotionRemover) of
TIP3P, SPC/E, TIP4P-Ew and, on request, TIP5P are each minimized and equilibrated once with a stock
LangevinMiddleIntegrator at 300 K (5/ps, 2 fs, SETTLE; on the CPU platform with one thread and
deterministic forces, so that --seed repeats it exactly), and that state made rigid to 1e-10. From
that one state every method runs NVE at each step size, in its own Context, in this one process:

    stock      openmm.VerletIntegrator + SETTLE, constraint tolerance 1e-10
    Exact      openmmrigid.RigidBodyIntegrator, setRotationMethod(RigidBodyIntegrator.Exact)
    NoSquish   openmmrigid.RigidBodyIntegrator, setRotationMethod(RigidBodyIntegrator.NoSquish)
    Omelyan2, Yoshida4, Omelyan4 (--methods schemes): the other splittings, Exact drift

(the table METHODS; each entry builds the integrator for a step size and says how many force
evaluations a step costs). A series (one method, one model) stops at its first unstable step size:
an exception, a non-finite energy, or |E(t) - E(0)| above --threshold kJ/mol per molecule (default 1:
about 13 K of heating at the heat capacity of liquid water).

Each run samples the total energy every --sample-interval fs (the multiple of the step nearest to
it) and reports:
- drift: least-squares slope of E(t), kJ/mol/ns per degree of freedom, with the standard error of
  the slope through 10 block means (too small when the blocks are shorter than the energy's
  correlation time, as in the quick mode's runs of a few ps);
- fluctuation: standard deviation of E about the fitted line. At small steps it has a floor that is
  the potential's, not the integrator's: the Ewald direct-space term is cut off at 0.9 nm before it
  reaches zero (--ewald-tolerance lowers the floor, at a higher cost per step);
- blow-up: whether and when the run became unstable, and why;
- T_trans, T_rot: translational and rotational temperatures by equipartition (3N - 3 and 3N
  degrees of freedom), computed for every method by the same function from positions, velocities
  and masses (stock Verlet's leapfrog velocities moved on by half a step first), checked against
  the State's kinetic energy and, for the rigid integrators, against the split of their own bodies
  (rigidtesting.bodies.kineticEnergies with the integrator's bodies and moments);
- cost: wall time of the step() calls alone, as ms/step, ns/day and seconds per simulated ps.

    python benchmarks/energy_drift.py --quick        # a smoke check: TIP3P + TIP4P-Ew, 2/4/6 fs, 1.5 ps per run
    python benchmarks/energy_drift.py                # TIP3P, SPC/E, TIP4P-Ew, 1 to 8 fs, 20 ps per run
    python benchmarks/energy_drift.py --models all   # the same with TIP5P as well
    python benchmarks/energy_drift.py --methods schemes --models tip4pew --molecules 2000 --time 4 \
        --output benchmarks/results/schemes_tip4pew_2000  # the splittings, per force evaluation

With several force evaluations per step among the methods it also plots the fluctuation against
force evaluations per simulated ps, and for every accuracy level given by stock Verlet's
fluctuation at 1 to 4 fs prints which method and step give the most ns/day at that fluctuation or
better (interpolated in log fluctuation between measured steps, never extrapolated) and the ratio
to stock's ns/day.

Writes docs/results/<name>.md (name: that of --output, default energy_drift; a quick run:
benchmarks/results/) with its figures <name>_drift.png, <name>_fluctuation.png and
<name>_work_precision.png (docs/figures; a quick run: benchmarks/results/), and <output>.csv,
<output>_equal_accuracy.csv and <output>.log. Measured results: docs/results/energy_drift.md.
"""

import argparse
import dataclasses
import datetime
import math
import os
import textwrap
import time
from pathlib import Path
from typing import Callable

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from benchmarking import (RESULTS, Progress, ResultsDocument, cpuProperties, forceEvaluations, header,
                          integratorBodies, openLog, pyplot, rigidDegreesOfFreedom, kineticEnergies as
                          bodyKineticEnergies, say, saveFigure, slopeError, stamp, writeCsv)

plt = pyplot()
import matplotlib.ticker  # noqa: E402 (after pyplot() chose the backend)
import rigidtesting

TEMPERATURE = 300.0  # K
BOLTZMANN = (unit.BOLTZMANN_CONSTANT_kB*unit.AVOGADRO_CONSTANT_NA).value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
CUTOFF = 0.9  # nm
CONSTRAINT_TOLERANCE = 1e-10
EQUILIBRATION_STEP = 2.0  # fs
EQUILIBRATION_FRICTION = 5.0  # 1/ps: strong, so that short (quick) equilibrations reach 300 K after minimization
DRIFT_BLOCKS = 10
KJ = unit.kilojoule_per_mole


# ---------------------------------------------------------------------------------------------------
# Water models and integration methods

@dataclasses.dataclass(frozen=True)
class Model:
    label: str
    forceField: str  # a file in openmm/app/data; the key of MODELS is Modeller.addSolvent's model name


MODELS = {
    "tip3p": Model("TIP3P", "tip3p.xml"),
    "spce": Model("SPC/E", "spce.xml"),
    "tip4pew": Model("TIP4P-Ew", "tip4pew.xml"),
    "tip5p": Model("TIP5P", "tip5p.xml"),
}


@dataclasses.dataclass(frozen=True)
class Method:
    label: str
    colour: str
    marker: str
    forceEvaluations: int  # per step
    build: Callable  # step size (Quantity) -> a new integrator
    prepare: Callable = lambda context: None  # applied to the Context after the starting state is set
    halfStepVelocities: bool = False  # leapfrog: State velocities lag the positions by half a step


def stockVerlet(stepSize):
    integrator = openmm.VerletIntegrator(stepSize)
    integrator.setConstraintTolerance(CONSTRAINT_TOLERANCE)
    return integrator


def constrainStartingState(context):
    context.applyConstraints(CONSTRAINT_TOLERANCE)
    context.applyVelocityConstraints(CONSTRAINT_TOLERANCE)


def rigidBody(rotationMethod, splitting=openmmrigid.RigidBodyIntegrator.Verlet):
    def build(stepSize):
        integrator = openmmrigid.RigidBodyIntegrator(stepSize)
        integrator.setRotationMethod(rotationMethod)
        integrator.setSplitting(splitting)
        return integrator
    return build


def rigidBodyScheme(name, colour, marker):
    """The exact rotation with the splitting `name`; its force evaluations per step (benchmarking.forceEvaluations)."""
    splitting = getattr(openmmrigid.RigidBodyIntegrator, name)
    integrator = openmmrigid.RigidBodyIntegrator(0.001)
    integrator.setSplitting(splitting)
    return Method(f"RigidBodyIntegrator (Exact, {name})", colour, marker, forceEvaluations(integrator),
                  rigidBody(openmmrigid.RigidBodyIntegrator.Exact, splitting))


METHODS = {
    "stock": Method("VerletIntegrator + SETTLE", "C0", "o", 1, stockVerlet, constrainStartingState, halfStepVelocities=True),
    "Exact": Method("RigidBodyIntegrator (Exact)", "C1", "s", 1, rigidBody(openmmrigid.RigidBodyIntegrator.Exact)),
    "NoSquish": Method("RigidBodyIntegrator (NoSquish)", "C2", "^", 1, rigidBody(openmmrigid.RigidBodyIntegrator.NoSquish)),
    # The other splittings of RigidBodyIntegrator.setSplitting around the exact drift.
    "Omelyan2": rigidBodyScheme("Omelyan2", "C3", "D"),
    "Yoshida4": rigidBodyScheme("Yoshida4", "C4", "v"),
    "Omelyan4": rigidBodyScheme("Omelyan4", "C5", "P"),
}
DEFAULT_METHODS = ["stock", "Exact", "NoSquish"]
SCHEMES = ["stock", "Exact", "Omelyan2", "Yoshida4", "Omelyan4"]


# ---------------------------------------------------------------------------------------------------
# Measurements

def rigidKineticEnergies(positions, velocities, masses, bodies):
    """Translational and rotational kinetic energy (kJ/mol) of rigid molecules.

    positions (nm), velocities (nm/ps): arrays (particles, 3); masses (amu): (particles,); bodies:
    (molecules, massive particles per molecule) indices. Translational: 1/2 M V^2 of each centre
    of mass. Rotational: 1/2 L . I^-1 L, with the angular momentum L and inertia tensor I about the
    centre of mass: the kinetic energy of the rigid motion nearest to the velocities in the mass
    metric, which is what velocity constraints (SETTLE, RATTLE) project onto; for velocities that
    are rigid motion already it is all of the kinetic energy left after the translational part.
    """
    m = masses[bodies][..., None]
    total = m.sum(axis=1)
    x, v = positions[bodies], velocities[bodies]
    centre = (m*x).sum(axis=1)/total
    centreVelocity = (m*v).sum(axis=1)/total
    r, u = x - centre[:, None], v - centreVelocity[:, None]
    angularMomentum = (m*np.cross(r, u)).sum(axis=1)
    inertia = (m[..., None]*((r*r).sum(axis=-1)[..., None, None]*np.eye(3) - r[..., :, None]*r[..., None, :])).sum(axis=1)
    omega = np.linalg.solve(inertia, angularMomentum[..., None])[..., 0]
    translational = 0.5*np.sum(total[:, 0]*np.sum(centreVelocity**2, axis=1))
    rotational = 0.5*np.sum(omega*angularMomentum)
    return translational, rotational


def onStepVelocities(state, masses, stepFs):
    """State velocities at the time of the positions: leapfrog velocities moved on by half a step."""
    velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    forces = state.getForces(asNumpy=True).value_in_unit(KJ/unit.nanometer)
    massive = masses > 0
    velocities[massive] += 0.5e-3*stepFs*forces[massive]/masses[massive, None]
    return velocities


# ---------------------------------------------------------------------------------------------------
# Boxes

@dataclasses.dataclass
class Box:
    key: str
    system: openmm.System
    positions: list
    molecules: int
    bodies: np.ndarray  # (molecules, 3) indices of the massive particles of each water
    masses: np.ndarray
    dof: int
    translationalDof: int
    rotationalDof: int
    secondsPerStep: float = float("nan")  # a stock Verlet step under the run's properties
    state: openmm.State = None


def buildBox(key, molecules, ewaldTolerance):
    topology, positions, system = rigidtesting.waterBox(
        key, molecules=molecules, forceField=MODELS[key].forceField, nonbondedCutoff=CUTOFF*unit.nanometer,
        ewaldErrorTolerance=ewaldTolerance)
    masses = rigidtesting.particleMasses(system)
    bodies = np.array([[atom.index for atom in residue.atoms() if masses[atom.index] > 0]
                       for residue in topology.residues()])
    removesMotion = any(isinstance(system.getForce(i), openmm.CMMotionRemover) for i in range(system.getNumForces()))
    count = len(bodies)
    dof = 3*int(np.count_nonzero(masses)) - system.getNumConstraints() - (3 if removesMotion else 0)
    return Box(key, system, positions, count, bodies, masses, dof,
               3*count - (3 if removesMotion else 0), 3*count)


def repeatableProperties(platform, properties):
    """Context properties under which a run repeats bit for bit: on the CPU platform one thread and
    deterministic forces (with more threads both forces and the minimizer's sums vary in the last
    bits from run to run, and the trajectories part)."""
    if platform.getName() != "CPU":
        return properties
    return dict(properties, Threads="1", DeterministicForces="true")


def startEquilibration(box, platform, properties, seed):
    """Minimize and draw velocities (repeatably), and time a stock Verlet step under the run's
    properties for the estimate. Returns the (Context, integrator) to equilibrate with."""
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, EQUILIBRATION_FRICTION/unit.picosecond,
                                                EQUILIBRATION_STEP*unit.femtosecond)
    integrator.setRandomNumberSeed(seed)
    context = openmm.Context(box.system, integrator, platform, repeatableProperties(platform, properties))
    context.setPositions(box.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 200)
    context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, seed)
    probe = stockVerlet(EQUILIBRATION_STEP*unit.femtosecond)
    probeContext = openmm.Context(box.system, probe, platform, properties)
    probeContext.setState(context.getState(getPositions=True, getVelocities=True))
    probe.step(5)
    start = time.perf_counter()
    probe.step(50)
    box.secondsPerStep = (time.perf_counter() - start)/50
    return context, integrator


def finishEquilibration(box, context, integrator, picoseconds):
    steps = int(round(picoseconds*1000/EQUILIBRATION_STEP))
    progress = Progress(f"{MODELS[box.key].label} equilibration", steps)
    done = 0
    while done < steps:
        block = min(100, steps - done)
        integrator.step(block)
        done += block
        progress.update(done)
    # The Langevin State's velocities belong half a step away from its positions and hold its 1e-5
    # constraint tolerance: not quite rigid motion. Every method starts from this state made rigid
    # at 1e-10, so that E(0) is the energy of what each integrates (RigidBodyIntegrator projects a
    # state set from outside only when it next steps, and reports the unprojected kinetic energy
    # until then: about 3 kJ/mol for 500 waters here, an outlier at t = 0 in short runs).
    platform = context.getPlatform()
    rigid = openmm.Context(box.system, stockVerlet(EQUILIBRATION_STEP*unit.femtosecond), platform,
                           repeatableProperties(platform, {}))
    rigid.setState(context.getState(getPositions=True, getVelocities=True, enforcePeriodicBox=True))
    constrainStartingState(rigid)
    box.state = rigid.getState(getPositions=True, getVelocities=True)


# ---------------------------------------------------------------------------------------------------
# One NVE run

def sampling(stepFs, args):
    """Steps between samples and number of samples for one run."""
    every = max(1, int(round(args.sample_interval/stepFs)))
    samples = max(2, int(round(args.time*1000/(every*stepFs))))
    return every, samples


@dataclasses.dataclass
class Trace:
    """What one NVE run recorded: samples, checks, blow-up and timings (seconds)."""
    times: list = dataclasses.field(default_factory=list)  # ps
    energies: list = dataclasses.field(default_factory=list)  # kJ/mol
    translational: list = dataclasses.field(default_factory=list)  # kJ/mol
    rotational: list = dataclasses.field(default_factory=list)  # kJ/mol
    stateMismatch: float = 0.0  # largest relative difference of our kinetic energy from the State's
    integratorMismatch: float = float("nan")  # the same for the trans./rot. split of the rigid integrators' bodies
    bodies: list = None  # the rigid integrator's bodies (benchmarking.integratorBodies), None for stock
    minimumMoment: float = 0.0  # and its minimum moment of inertia (amu nm^2)
    blowup: float = None  # ps
    reason: str = ""
    stepSeconds: float = 0.0
    timedSteps: int = 0
    stateSeconds: float = 0.0


def record(trace, state, time_, box, method, integrator, stepFs):
    """Add one sample to the trace; False (and the reason in the trace) if the run has become unstable."""
    energy = (state.getPotentialEnergy() + state.getKineticEnergy()).value_in_unit(KJ)
    if not math.isfinite(energy):
        trace.blowup, trace.reason = time_, "energy not finite"
        return False
    positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    if method.halfStepVelocities:
        velocities = onStepVelocities(state, box.masses, stepFs)
    else:
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    kinetic = rigidKineticEnergies(positions, velocities, box.masses, box.bodies)
    trace.stateMismatch = max(trace.stateMismatch, abs(sum(kinetic)/state.getKineticEnergy().value_in_unit(KJ) - 1))
    if trace.bodies is not None:
        reported = bodyKineticEnergies(positions, velocities, box.masses, trace.bodies, trace.minimumMoment,
                                       state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer))
        worst = max(abs(ours/theirs - 1) for ours, theirs in zip(kinetic, reported))
        trace.integratorMismatch = worst if math.isnan(trace.integratorMismatch) else max(trace.integratorMismatch, worst)
    trace.times.append(time_)
    trace.energies.append(energy)
    trace.translational.append(kinetic[0])
    trace.rotational.append(kinetic[1])
    return True


def runNVE(box, name, stepFs, args, platform, properties):
    """Run one method at one step size from the box's equilibrated state; return the CSV row."""
    method = METHODS[name]
    integrator = method.build(stepFs*unit.femtosecond)
    context = openmm.Context(box.system, integrator, platform, properties)
    context.setState(box.state)
    method.prepare(context)
    trace = Trace()
    if isinstance(integrator, openmmrigid.RigidBodyIntegratorBase):
        trace.bodies = integratorBodies(integrator)
        trace.minimumMoment = integrator.getMinimumMomentOfInertia().value_in_unit(unit.dalton*unit.nanometer**2)
        counted = rigidDegreesOfFreedom(context, integrator)
        if counted != box.dof:
            say(f"  WARNING: {name}'s bodies have {counted} degrees of freedom, this script counts {box.dof}")
    threads = platform.getPropertyValue(context, "Threads") if platform.getName() == "CPU" else ""
    every, samples = sampling(stepFs, args)
    progress = Progress(f"{MODELS[box.key].label} {name} {stepFs:g} fs", samples)
    for sample in range(samples + 1):
        time_ = sample*every*stepFs/1000
        try:
            if sample > 0:
                start = time.perf_counter()
                integrator.step(every)
                if sample > 1:  # the first block includes the Context's setup
                    trace.stepSeconds += time.perf_counter() - start
                    trace.timedSteps += every
            start = time.perf_counter()
            state = context.getState(getEnergy=True, getPositions=True, getVelocities=True,
                                     getForces=method.halfStepVelocities)
            trace.stateSeconds += time.perf_counter() - start
        except openmm.OpenMMException as error:
            trace.blowup, trace.reason = time_, f"exception: {str(error).splitlines()[0][:60]}"
            break
        if not record(trace, state, time_, box, method, integrator, stepFs):
            break
        if abs(trace.energies[-1] - trace.energies[0]) > args.threshold*box.molecules:
            trace.blowup, trace.reason = time_, f"|E - E0| > {args.threshold:g} kJ/mol per molecule"
            break
        progress.update(sample)
    del context
    return summarize(box, name, stepFs, every, args, trace, threads)


def summarize(box, name, stepFs, every, args, trace, threads):
    nan = float("nan")
    times, energies = np.array(trace.times), np.array(trace.energies)
    drift = fluctuation = driftError = nan
    if len(times) >= 3:
        drift, fluctuation = rigidtesting.energyDrift(times, energies, box.dof)
        driftError = slopeError(times, energies, DRIFT_BLOCKS)*1000/box.dof
    msPerStep = 1000*trace.stepSeconds/trace.timedSteps if trace.timedSteps else nan
    nsPerDay = stepFs*1e-6/(msPerStep/1000)*86400
    samples = len(times)
    return {
        "model": box.key, "model_label": MODELS[box.key].label, "molecules": box.molecules,
        "particles": box.system.getNumParticles(), "dof": box.dof,
        "method": name, "method_label": METHODS[name].label,
        "force_evaluations_per_step": METHODS[name].forceEvaluations, "step_fs": stepFs,
        "simulated_ps": round(times[-1], 6) if len(times) else 0.0, "target_ps": args.time,
        "steps": int(round(times[-1]*1000/stepFs)) if len(times) else 0,
        "sample_interval_fs": every*stepFs, "samples": samples,
        "drift_kJ_mol_ns_dof": drift, "drift_stderr_kJ_mol_ns_dof": driftError,
        "fluctuation_kJ_mol": fluctuation, "fluctuation_kJ_mol_per_molecule": fluctuation/box.molecules,
        "max_abs_dE_kJ_mol_per_molecule": np.max(np.abs(energies - energies[0]))/box.molecules if samples else nan,
        "blew_up": trace.blowup is not None, "blowup_ps": "" if trace.blowup is None else trace.blowup,
        "blowup_reason": trace.reason,
        "T_trans_K": 2*np.mean(trace.translational)/(box.translationalDof*BOLTZMANN) if samples else nan,
        "T_rot_K": 2*np.mean(trace.rotational)/(box.rotationalDof*BOLTZMANN) if samples else nan,
        "kinetic_vs_state_max_rel": trace.stateMismatch, "kinetic_vs_integrator_max_rel": trace.integratorMismatch,
        "ms_per_step": msPerStep, "ns_per_day": nsPerDay,
        "wall_s_per_simulated_ps": msPerStep/stepFs,
        "force_evaluations_per_ps": 1000*METHODS[name].forceEvaluations/stepFs,
        "getstate_ms_per_sample": 1000*trace.stateSeconds/samples if samples else nan,
        "platform": args.platform, "threads": threads, "seed": args.seed,
    }


# ---------------------------------------------------------------------------------------------------
# Report

def cell(value, format, width):
    if value == "" or value is None or (isinstance(value, float) and not math.isfinite(value)):
        return f"{'-':>{width}}"
    return f"{value:{format}}".rjust(width)


COLUMNS = [("drift", "drift_kJ_mol_ns_dof", "+.3f", 9), ("+-", "drift_stderr_kJ_mol_ns_dof", ".3f", 7),
           ("fluct", "fluctuation_kJ_mol", ".2f", 7),
           ("ns/day", "ns_per_day", ".1f", 7), ("T_tr", "T_trans_K", ".1f", 6), ("T_rot", "T_rot_K", ".1f", 6),
           ("blew up", "blowup_ps", ".2f", 8)]


def printTable(rows, args):
    width = sum(column[3] for column in COLUMNS) + 2
    say("\ndrift: kJ/mol/ns per degree of freedom, +- its standard error from 10 block means; fluct: standard "
        "deviation about the fit, kJ/mol;\nns/day: from the step calls alone; T_tr, T_rot: translational and "
        "rotational temperatures (K); blew up: ps into the run;\n'skipped': unstable at a smaller step")
    for model in args.models:
        modelRows = [row for row in rows if row["model"] == model]
        if not modelRows:
            continue
        first = modelRows[0]
        say(f"\n{MODELS[model].label}: {first['molecules']} waters, {first['dof']} degrees of freedom, "
            f"{args.time:g} ps per run")
        say(f"{'':>5}" + "".join(f"  {METHODS[name].label:^{width - 2}}" for name in args.methods))
        say(f"{'step':>5}" + "".join("  " + "".join(f"{title:>{w}}" for title, _, _, w in COLUMNS) for _ in args.methods))
        for stepFs in args.steps:
            line = f"{stepFs:>4g} "
            for name in args.methods:
                row = next((r for r in modelRows if r["method"] == name and r["step_fs"] == stepFs), None)
                if row is None:
                    line += f"  {'skipped':^{width - 2}}"
                else:
                    line += "  " + "".join(cell(row[key], format, w) for _, key, format, w in COLUMNS)
            say(line)


def seriesOf(rows, model, name):
    return sorted((r for r in rows if r["model"] == model and r["method"] == name), key=lambda r: r["step_fs"])


def panels(args, title):
    width = 4.2*len(args.models)
    figure, axes = plt.subplots(1, len(args.models), figsize=(width, 3.8 + 0.15*(len(title)//int(14*width))),
                                squeeze=False, sharey=True)
    figure.suptitle(textwrap.fill(title, int(14*width)), fontsize=9)
    return figure, axes[0]


def finishFigure(figure, axes, path):
    axes[0].legend(fontsize=7, loc="best")
    saveFigure(figure, path)


def plainLogTicks(axis):
    """Ticks at 1, 2, 5 times powers of ten, written plainly (the ranges here span a decade or two)."""
    axis.set_major_locator(matplotlib.ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)))
    axis.set_major_formatter(matplotlib.ticker.FuncFormatter(lambda value, _: f"{value:g}"))
    axis.set_minor_formatter(matplotlib.ticker.NullFormatter())


def squareGuide(ax, rows, key, steps):
    """A dashed line proportional to step^2 through the median value at the middle step size."""
    middle = steps[len(steps)//2]
    values = [r[key] for r in rows if r["step_fs"] == middle and math.isfinite(r[key])]
    if values:
        grid = np.array(steps)
        ax.plot(grid, np.median(values)*(grid/middle)**2, color="grey", linestyle="--", linewidth=0.8,
                label="proportional to step$^2$")


def plotAgainstStep(rows, args, key, errorKey, ylabel, path, title, scale):
    figure, axes = panels(args, title)
    for ax, model in zip(axes, args.models):
        for name in args.methods:
            method, series = METHODS[name], seriesOf(rows, model, name)
            stable = [r for r in series if not r["blew_up"]]
            if stable:
                ax.errorbar([r["step_fs"] for r in stable], [r[key] for r in stable],
                            yerr=[r[errorKey] for r in stable] if errorKey else None, color=method.colour,
                            marker=method.marker, markersize=4, linewidth=1, capsize=2, label=method.label)
            broken = [r for r in series if r["blew_up"] and math.isfinite(r[key])]
            ax.plot([r["step_fs"] for r in broken], [r[key] for r in broken], linestyle="none", marker="x",
                    color=method.colour, markersize=7, label=f"{method.label}: blew up" if broken else None)
        if scale == "symlog":
            ax.set_yscale("symlog", linthresh=0.1)  # below about 0.1 the drift of one run is mostly noise
            ax.axhline(0, color="grey", linewidth=0.5)
        else:
            ax.set_yscale(scale)
            plainLogTicks(ax.yaxis)
            squareGuide(ax, [r for r in rows if r["model"] == model and not r["blew_up"]], key, args.steps)
        ax.set_title(f"{MODELS[model].label}", fontsize=9)
        ax.set_xlabel("time step (fs)")
        ax.set_xticks(args.steps)
        ax.grid(True, which="major", alpha=0.3)
    axes[0].set_ylabel(ylabel)
    finishFigure(figure, axes, path)


def plotWorkPrecision(rows, args, path, title, xKey="wall_s_per_simulated_ps", xLabel="wall time per simulated ps (s)"):
    figure, axes = panels(args, title)
    for ax, model in zip(axes, args.models):
        for name in args.methods:
            method = METHODS[name]
            stable = [r for r in seriesOf(rows, model, name) if not r["blew_up"]]
            if not stable:
                continue
            x = [r[xKey] for r in stable]
            y = [r["fluctuation_kJ_mol"] for r in stable]
            ax.plot(x, y, color=method.colour, marker=method.marker, markersize=4, linewidth=1, label=method.label)
            for r, xi, yi in zip(stable, x, y):
                ax.annotate(f"{r['step_fs']:g}", (xi, yi), textcoords="offset points", xytext=(3, 3), fontsize=6,
                            color=method.colour)
        ax.set_xscale("log")
        ax.set_yscale("log")
        plainLogTicks(ax.xaxis)
        plainLogTicks(ax.yaxis)
        ax.set_title(f"{MODELS[model].label} (labels: step, fs)", fontsize=9)
        ax.set_xlabel(xLabel)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].set_ylabel("energy fluctuation (kJ/mol)")
    finishFigure(figure, axes, path)


# ---------------------------------------------------------------------------------------------------
# Speed at equal accuracy

def atFluctuation(series, level):
    """(ns/day, step fs) of one method's stable series at the energy fluctuation `level`, by linear
    interpolation in log(fluctuation) between the two step sizes around it (log ns/day and log step
    likewise). Above the series' largest fluctuation, its largest stable step (no extrapolation);
    below its smallest, None: no tested step is that accurate."""
    points = sorted(((r["fluctuation_kJ_mol"], r["ns_per_day"], r["step_fs"]) for r in series
                     if not r["blew_up"] and math.isfinite(r["fluctuation_kJ_mol"]) and math.isfinite(r["ns_per_day"])),
                    key=lambda point: point[2])
    if not points or level < points[0][0]:
        return None
    best = None
    for (f0, n0, s0), (f1, n1, s1) in zip(points, points[1:]):
        if f0 <= level <= f1 and f1 > f0:
            w = (math.log(level) - math.log(f0))/(math.log(f1) - math.log(f0))
            candidate = (math.exp((1 - w)*math.log(n0) + w*math.log(n1)), math.exp((1 - w)*math.log(s0) + w*math.log(s1)))
            best = candidate if best is None or candidate[0] > best[0] else best
    for f, n, s in points:  # a measured step at least as accurate as the level
        if f <= level and (best is None or n > best[0]):
            best = (n, s)
    return best


def equalAccuracy(rows, args):
    """For each accuracy level (the fluctuation of stock Verlet at each of its steps up to 4 fs), the
    method and step of this run that give the most ns/day at that fluctuation or better, and the ratio
    to stock's ns/day there. Printed, and returned as rows for a CSV."""
    if "stock" not in args.methods or len(args.methods) < 2:
        return []
    results = []
    for model in args.models:
        stock = [r for r in seriesOf(rows, model, "stock") if not r["blew_up"] and r["step_fs"] <= 4]
        if not stock:
            continue
        say(f"\n{MODELS[model].label}, {args.molecules} waters: the fastest method at each accuracy level "
            f"(ns/day interpolated in log fluctuation between measured steps)")
        say(f"{'level':>26}  {'stock ns/day':>12}  {'best method':<40} {'step fs':>7} {'ns/day':>8} {'ratio':>6}")
        for reference in stock:
            level = reference["fluctuation_kJ_mol"]
            candidates = []
            for name in args.methods:
                if name == "stock":
                    continue
                found = atFluctuation(seriesOf(rows, model, name), level)
                if found:
                    candidates.append((found[0], found[1], name))
            if not candidates:
                say(f"{level:7.3f} kJ/mol (stock {reference['step_fs']:g} fs)  {reference['ns_per_day']:12.2f}  "
                    f"no other method reached it at the steps tested")
                continue
            nsPerDay, step, name = max(candidates)
            ratio = nsPerDay/reference["ns_per_day"]
            say(f"{level:7.3f} kJ/mol (stock {reference['step_fs']:g} fs)  {reference['ns_per_day']:12.2f}  "
                f"{METHODS[name].label:<40} {step:7.2f} {nsPerDay:8.2f} {ratio:6.2f}")
            results.append({"model": model, "molecules": args.molecules, "stock_step_fs": reference["step_fs"],
                            "fluctuation_kJ_mol": level, "fluctuation_kJ_mol_per_molecule": level/args.molecules,
                            "stock_ns_per_day": reference["ns_per_day"], "best_method": name,
                            "best_step_fs": step, "best_ns_per_day": nsPerDay, "ratio_to_stock": ratio,
                            **{f"{other}_ns_per_day": (atFluctuation(seriesOf(rows, model, other), level) or (float("nan"),))[0]
                               for other in args.methods if other != "stock"}})
    return results


# ---------------------------------------------------------------------------------------------------
# Main

def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="a smoke check: TIP3P and TIP4P-Ew, 2/4/6 fs, 1.5 ps per run, 1 ps equilibration")
    parser.add_argument("--models", nargs="+", choices=list(MODELS) + ["all"],
                        help="water models, or all (default: tip3p spce tip4pew; quick: tip3p tip4pew). TIP5P is "
                             "left out by default because a TIP5P step costs 2.5 times a TIP3P step: with it the full "
                             "mode takes about 55 minutes instead of 32")
    parser.add_argument("--methods", nargs="+", choices=list(METHODS) + ["schemes", "all"],
                        help=f"methods (default: {' '.join(DEFAULT_METHODS)}; 'schemes': {' '.join(SCHEMES)}, the "
                             f"splittings of RigidBodyIntegrator.setSplitting with stock; 'all': every one)")
    parser.add_argument("--steps", type=float, nargs="+", help="time steps in fs (default 1 to 8; quick: 2 4 6)")
    parser.add_argument("--molecules", type=int, default=500, help="waters per box (default 500)")
    parser.add_argument("--time", type=float, help="simulated ps per NVE run (default 20; quick: 1.5)")
    parser.add_argument("--equilibrate", type=float,
                        help="ps of Langevin equilibration per model, after minimization (default 5; quick: 1)")
    parser.add_argument("--sample-interval", type=float,
                        help="fs of simulated time between energy samples: the multiple of the step nearest to it "
                             "(default 48, exact but for 5 and 7 fs: 50, 49; quick: 24)")
    parser.add_argument("--ewald-tolerance", type=float, default=5e-4,
                        help="NonbondedForce Ewald error tolerance (default 5e-4, as in examples/rigid_water.py; "
                             "it sets a floor under the fluctuation, see above)")
    parser.add_argument("--threshold", type=float, default=1.0,
                        help="a run is unstable once |E - E0| exceeds this many kJ/mol per molecule (default 1)")
    parser.add_argument("--seed", type=int, default=2024,
                        help="seed of the initial velocities and the Langevin equilibration (default 2024)")
    parser.add_argument("--platform", default="CPU", help="OpenMM platform (default CPU; the plugin has CPU and Reference)")
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's default)")
    parser.add_argument("--output", help="prefix of the output files (default benchmarks/results/energy_drift, "
                                         "quick: benchmarks/results/energy_drift_quick)")
    args = parser.parse_args()
    args.models = args.models or (["tip3p", "tip4pew"] if args.quick else ["tip3p", "spce", "tip4pew"])
    if "all" in args.models:
        args.models = list(MODELS)
    args.methods = args.methods or list(DEFAULT_METHODS)
    if "all" in args.methods:
        args.methods = list(METHODS)
    elif "schemes" in args.methods:
        args.methods = list(dict.fromkeys(SCHEMES + [m for m in args.methods if m != "schemes"]))
    args.steps = sorted(args.steps or ([2.0, 4.0, 6.0] if args.quick else [float(s) for s in range(1, 9)]))
    args.time = args.time or (1.5 if args.quick else 20.0)
    args.equilibrate = args.equilibrate if args.equilibrate is not None else (1.0 if args.quick else 5.0)
    args.sample_interval = args.sample_interval or (24.0 if args.quick else 48.0)
    args.output = Path(args.output or RESULTS/("energy_drift_quick" if args.quick else "energy_drift"))
    if args.molecules < 1 or args.time <= 0 or args.sample_interval <= 0 or min(args.steps) <= 0:
        parser.error("--molecules, --time, --sample-interval and --steps must be positive")
    return args


def estimateSeconds(boxes, args):
    """Equilibration plus NVE runs, from the cost of a stock step in each box (every series stable)."""
    total = 0.0
    for box in boxes:
        cost = box.secondsPerStep
        total += 1.5*cost*args.equilibrate*1000/EQUILIBRATION_STEP  # one thread: slower, not twice as slow
        for stepFs in args.steps:
            every, samples = sampling(stepFs, args)
            for name in args.methods:
                # a sample (energy, forces, copies) costs about 1.3 steps
                total += cost*(METHODS[name].forceEvaluations*every*samples + 1.3*samples)
    return total


def printHeader(args, platform):
    for line in header(platform.getName(), args.threads):
        say(line)
    say(f"settings:  {'quick' if args.quick else 'full'}; models {' '.join(args.models)}; methods {' '.join(args.methods)}; "
        f"steps {' '.join(f'{s:g}' for s in args.steps)} fs; {args.molecules} waters; {args.time:g} ps per run; "
        f"equilibration {args.equilibrate:g} ps; samples every ~{args.sample_interval:g} fs; "
        f"Ewald tolerance {args.ewald_tolerance:g}; "
        f"unstable above {args.threshold:g} kJ/mol per molecule; seed {args.seed}")
    say()


def runAll(args, platform, properties, started):
    """Build and equilibrate every box, then run every method at every step; returns the rows."""
    boxes, equilibrations = [], []
    for key in args.models:
        stamp(f"{MODELS[key].label}: building {args.molecules} waters, minimizing, timing a few steps")
        box = buildBox(key, args.molecules, args.ewald_tolerance)
        equilibrations.append(startEquilibration(box, platform, properties, args.seed))
        boxes.append(box)
        say(f"  {box.molecules} waters, {box.system.getNumParticles()} particles, {box.dof} degrees of freedom; "
            f"stock Verlet {1000*box.secondsPerStep:.2f} ms/step")
    estimate = estimateSeconds(boxes, args)
    stamp(f"estimated total: {(time.perf_counter() - started + estimate)/60:.0f} min if every series stays stable "
          f"(less where one blows up); other work on these cores slows it")
    rows = []
    for index, box in enumerate(boxes):
        stamp(f"{MODELS[box.key].label}: {args.equilibrate:g} ps Langevin equilibration at {TEMPERATURE:g} K")
        context, integrator = equilibrations[index]
        finishEquilibration(box, context, integrator, args.equilibrate)
        equilibrations[index] = context = integrator = None  # free the Langevin Context
        for name in args.methods:
            for stepFs in args.steps:
                row = runNVE(box, name, stepFs, args, platform, properties)
                rows.append(row)
                stamp(f"  {MODELS[box.key].label} {name:<9} {stepFs:g} fs: drift {row['drift_kJ_mol_ns_dof']:+.4f} "
                      f"kJ/mol/ns/dof, fluct {row['fluctuation_kJ_mol']:.3f} kJ/mol, T_tr {row['T_trans_K']:.1f} K, "
                      f"T_rot {row['T_rot_K']:.1f} K, {row['ms_per_step']:.2f} ms/step"
                      + (f"; BLEW UP at {row['blowup_ps']:.3f} ps ({row['blowup_reason']})" if row["blew_up"] else ""))
                if row["blew_up"]:
                    break  # larger steps of this series are skipped
        box.state = None
    return rows


def plotAll(rows, args, platform, document):
    """The figures of the run; returns (path, caption) of each."""
    name = args.output.name
    title = (f"openmm-rigid NVE, {args.molecules} waters, PME, {args.time:g} ps per run, {platform.getName()}, "
             f"OpenMM {openmm.version.full_version}, {datetime.date.today()}{' (quick)' if args.quick else ''}")
    figures = [(document.figurePath(f"{name}_drift.png"), "drift"),
               (document.figurePath(f"{name}_fluctuation.png"), "fluctuation"),
               (document.figurePath(f"{name}_work_precision.png"), "fluctuation against wall time per simulated ps")]
    plotAgainstStep(rows, args, "drift_kJ_mol_ns_dof", "drift_stderr_kJ_mol_ns_dof", "drift (kJ/mol/ns/dof)",
                    figures[0][0], title, "symlog")
    plotAgainstStep(rows, args, "fluctuation_kJ_mol", None, "energy fluctuation (kJ/mol)", figures[1][0], title, "log")
    plotWorkPrecision(rows, args, figures[2][0], title)
    if any(METHODS[method].forceEvaluations > 1 for method in args.methods):
        figures.append((document.figurePath(f"{name}_forces.png"), "fluctuation against force evaluations per ps"))
        plotWorkPrecision(rows, args, figures[-1][0], title, "force_evaluations_per_ps",
                          "force evaluations per simulated ps")
    return figures


def main():
    args = parseArguments()
    openLog(f"{args.output}.log")
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = cpuProperties(platform, args.threads)
    printHeader(args, platform)
    document = ResultsDocument(args.output.name, "Energy conservation against stock Verlet + SETTLE (NVE)",
                               quick=args.quick, platform=platform.getName(), threads=args.threads,
                               about="Method: the docstring of `benchmarks/energy_drift.py`.")
    started = time.perf_counter()
    rows = runAll(args, platform, properties, started)
    with document.capture():
        printTable(rows, args)
    say()
    writeCsv(Path(f"{args.output}.csv"), rows)
    figures = plotAll(rows, args, platform, document)
    with document.capture():
        levels = equalAccuracy(rows, args)
    if levels:
        writeCsv(Path(f"{args.output}_equal_accuracy.csv"), levels)
    for path, caption in figures:
        document.figure(path, caption)
    document.write()
    load = " ".join(f"{value:.2f}" for value in os.getloadavg())
    say(f"total {time.perf_counter() - started:.0f} s; load average now {load}")


if __name__ == "__main__":
    main()

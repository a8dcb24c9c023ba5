#!/usr/bin/env python
"""Configuration-space sampling error against step size: the near-equilibrium estimate of the KL
divergence of each integrator's sampled configurations from the Boltzmann distribution (Sivak,
Chodera and Crooks, Phys. Rev. X 3, 011007 (2013); Fass et al., Entropy 20, 318 (2018); the
estimator: rigidtesting.samplingerror), plotted against ns/day.

Integrators (friction 1/ps, 300 K):

- rigid-exact, rigid-nosquish: RigidBodyLangevinIntegrator (Exact, NoSquish), shadow work from
  setMeasureShadowWork(); rigid-raised: Exact with setMinimumMomentOfInertia(`--floor`);
- stock-middle: LangevinMiddleIntegrator + SETTLE written as a CustomIntegrator (its step, as OpenMM's
  documentation writes it) that sums its shadow work: K + U before and after each step, less the
  kinetic energy its O stage adds;
- openmmtools-vrorv: openmmtools' LangevinIntegrator(splitting="V R O R V", measure_shadow_work=True)
  where openmmtools is installed.

Systems: water, rigid TIP3P with PME 0.9 nm (500 molecules: about openmmtools' WaterBox, Fass et
al.'s system); peptide, alanine dipeptide in 500 TIP3P waters (amber14, constraints=HBonds,
hydrogenMass=3 amu, as benchmarks/nvt_accuracy.py). Equilibrium configurations: `--samples` frames
`--spacing` ps apart from a run of RigidBodyLangevinIntegrator at 1 fs and friction 5/ps (after
`--equilibrate` ps), the same frames for every integrator. For each frame: velocities from
Maxwell-Boltzmann, `--protocol` ps of the integrator (shadow work w_pi), velocities drawn again,
`--protocol` ps more (w_omega); KL = (<w_pi> - <w_omega>)/2 in kT, +- the standard error of the
paired differences (frame i: velocity seeds 100 + 2i and 101 + 2i). The cost: at each step, the integrators a user would run (no shadow work, no
accuracy check; stock-middle as OpenMM's LangevinMiddleIntegrator) timed side by side (interleaved
blocks, medians).
An integrator that fails (NaN, an unstable drift) at a step is not run at larger ones. The rigid
integrators' accuracy check is recorded (whether it fired) and its warning not shown.

    python benchmarks/sampling_error.py --quick      # 216 waters, 3 steps, 3 frames, 0.2 ps: a smoke check of a minute
    python benchmarks/sampling_error.py --systems water --workers 2 --hours 2 --no-timing   # add to the full run
    python benchmarks/sampling_error.py --systems water --report --retime  # time and report (quiet machine)

The full run (50 frames, 6 steps, 5 integrators, 2 systems) is about 18 core-hours on a 2-core CPU
machine, more than a session: its samples are kept between runs in benchmarks/stores/sampling_error/
<molecules>w-<protocol>ps-<platform>/ (benchmarking.SampleStore: the shadow-work pairs of every
integrator, step and frame; the System as XML; the frames, single precision; the equilibrium chain's
last state, which a later run continues for more frames), committed with the code. Each run adds
frames until `--hours` pass or every job has `--samples`, in `--workers` processes at once (two
1-thread workers use a 2-core machine better than one with 2 threads), each job (an integrator at a
step) growing in turn, the fewest frames first, so that an interrupted run leaves an even table; then
it times the steps not yet timed (`--no-timing` leaves that for a quiet machine; `--retime` times them
all again) and writes docs/results/sampling_error.md from everything stored, with the runs that made
it. Frames from different runs and machines are independent samples and pool; the store's folder
names what would make them differ (molecules, protocol, platform) and its set-up must match.

Compare the ranking with the U-per-molecule reading of benchmarks/nvt_accuracy.py
(docs/results/nvt_accuracy.md).

On-step velocities: RigidBodyLangevinIntegrator and LangevinMiddleIntegrator hold velocities half a
step behind the positions (LFMiddle). Their step is BAOAB's with its closing half kick joined to the
next step's opening one, so each protocol starts from canonical on-step velocities moved half a kick
back, and its shadow work is corrected at both ends to BAOAB's (Runner.work): the same quantity that
openmmtools' VRORV (BAOAB) measures. Without that correction (as in the first reduced run of
2026-12-02) the end terms, of first order in the step, gave error bars 5 to 10 times VRORV's.
"""

import argparse
import datetime
import shutil
import time
import warnings

import numpy as np
import openmm
from openmm import app, unit

import benchmarking
from benchmarking import say, stamp
import openmmrigid
from rigidtesting import alanineDipeptide, waterBox
from rigidtesting.samplingerror import configurationKL
import rigidtesting

KJ = unit.kilojoule_per_mole
TEMPERATURE = 300.0
FRICTION = 1.0
KT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(KJ/unit.kelvin)*TEMPERATURE
FLOOR = [0.08]  # rigid-raised's minimum moment of inertia (amu nm^2), set from --floor


def makeSystem(name, molecules):
    if name == "water":
        return waterBox("tip3p", molecules=molecules)
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    return waterBox("tip3p", molecules=molecules, forceField=forceField, solute=alanineDipeptide(),
                    constraints=app.HBonds, hydrogenMass=3*unit.amu)


def stockMiddle(stepPs):
    """LangevinMiddleIntegrator's step as a CustomIntegrator, with its shadow work (kJ/mol) in "work":
    each step adds K + U after the previous step less K + U before it, less the previous step's heat
    (the kinetic energy its O stage and the velocity constraints after it added)."""
    integrator = openmm.CustomIntegrator(stepPs)
    a = np.exp(-FRICTION*stepPs)
    for name, value in (("a", a), ("b", np.sqrt(1 - a*a)), ("kT", KT), ("work", 0.0), ("heat", 0.0), ("start", 0.0),
                        ("started", 0.0), ("ke", 0.0)):
        integrator.addGlobalVariable(name, value)
    integrator.addPerDofVariable("x1", 0.0)
    integrator.addUpdateContextState()
    integrator.addComputeSum("ke", "0.5*m*v*v")
    integrator.addComputeGlobal("work", "work + started*(ke + energy - start - heat)")
    integrator.addComputeGlobal("start", "ke + energy")
    integrator.addComputeGlobal("started", "1")
    integrator.addComputePerDof("v", "v + dt*f/m")
    integrator.addConstrainVelocities()
    integrator.addComputePerDof("x", "x + 0.5*dt*v")
    integrator.addComputeSum("ke", "0.5*m*v*v")
    integrator.addComputeGlobal("heat", "-ke")
    integrator.addComputePerDof("v", "a*v + b*sqrt(kT/m)*gaussian")
    integrator.addComputeSum("ke", "0.5*m*v*v")
    integrator.addComputeGlobal("heat", "heat + ke")
    integrator.addComputePerDof("x", "x + 0.5*dt*v")
    integrator.addComputePerDof("x1", "x")
    integrator.addConstrainPositions()
    integrator.addComputePerDof("v", "v + (x - x1)/dt")
    return integrator


def rigidIntegrator(kind, stepPs):
    integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, stepPs)
    if kind == "rigid-nosquish":
        integrator.setRotationMethod(openmmrigid.RigidBodyLangevinIntegrator.NoSquish)
    if kind == "rigid-raised":
        integrator.setMinimumMomentOfInertia(FLOOR[0])
    return integrator


def timedIntegrator(kind, stepFs):
    """The integrator a user would run, for the cost: no shadow work, no accuracy check; stock-middle
    is OpenMM's LangevinMiddleIntegrator itself."""
    stepPs = stepFs*1e-3
    if kind.startswith("rigid"):
        integrator = rigidIntegrator(kind, stepPs)
        integrator.setAccuracyCheck(False)
        return integrator
    if kind == "stock-middle":
        return openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, stepPs)
    from openmmtools.integrators import LangevinIntegrator
    return LangevinIntegrator(temperature=TEMPERATURE*unit.kelvin, collision_rate=FRICTION/unit.picosecond,
                              timestep=stepPs*unit.picosecond, splitting="V R O R V")


class Runner:
    """One integrator at one step on one System: shadow work (kT) of `steps` steps from a state."""

    def __init__(self, kind, stepFs, system, platform, properties, seed):
        self.kind = kind
        stepPs = stepFs*1e-3
        if kind.startswith("rigid"):
            self.integrator = rigidIntegrator(kind, stepPs)
            self.integrator.setMeasureShadowWork(True)
            self.integrator.setRandomNumberSeed(seed)
        elif kind == "stock-middle":
            self.integrator = stockMiddle(stepPs)
            self.integrator.setRandomNumberSeed(seed)
        else:
            from openmmtools.integrators import LangevinIntegrator
            self.integrator = LangevinIntegrator(temperature=TEMPERATURE*unit.kelvin, collision_rate=FRICTION/unit.picosecond,
                                                 timestep=stepPs*unit.picosecond, splitting="V R O R V",
                                                 measure_shadow_work=True)
            self.integrator.setRandomNumberSeed(seed)
        self.context = openmm.Context(system, self.integrator, platform, properties)
        self.fired = False
        masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
        self.masses = np.where(masses > 0, masses, np.inf)  # a virtual site gets no velocity
        self.halfStepBehind = kind != "openmmtools-vrorv"
        self.failure = None  # why the last work() returned None

    def kinetic(self):
        return self.context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)

    def kick(self, time):
        """The velocities kicked by the current forces for `time` ps, then projected (onto the
        constraints; for the rigid integrators onto rigid motion, where a kick of each particle by its
        force, projected, is the kick of each body's momentum and angular momentum by its force and
        torque); returns the kinetic energy after it."""
        state = self.context.getState(getVelocities=True, getForces=True)
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
        forces = state.getForces(asNumpy=True).value_in_unit(KJ/unit.nanometer)
        self.context.setVelocities(velocities + time*forces/self.masses[:, None])
        self.context.applyVelocityConstraints(1e-10)
        return self.kinetic()

    def work(self, positions, box, steps, velocitySeed):
        """Set the state (positions, box, on-step velocities drawn at 300 K), take `steps` steps, and
        return the shadow work in kT of the protocol with on-step velocities at both ends (BAOAB's);
        None if the run failed.

        The on-step velocities v_0: for the rigid integrators, Context.setVelocitiesToTemperature()
        (the bodies' momenta drawn for their own, possibly raised, moments, then taken half a kick
        back), K(v_0) from getOnStepKineticEnergy(); otherwise Maxwell-Boltzmann draws of every
        particle's velocity, projected (Context.applyVelocityConstraints), and for stock-middle taken
        half a kick back here. For the LFMiddle integrators (the rigid ones and stock-middle), whose
        velocity variable u is half a step behind, u_0 is v_0 less half a kick; their step is BAOAB's
        with its closing half kick joined to the next opening one, so their shadow work over the
        protocol, W (with the kinetic energies of u), is BAOAB's less the ends:
        W_BAOAB = W + [K(u_T + kick) - K(u_T)] - [K(v_0) - K(u_0)]. Those end terms are of
        first order in the step (dt/2 F.v per degree of freedom): left in, their spread would swamp
        the divergence (their mean cancels between the two halves of a protocol, their variance does
        not)."""
        context, integrator = self.context, self.integrator
        if positions is not None:
            context.setPeriodicBoxVectors(*box)
            context.setPositions(positions)
        halfStep = 0.5*integrator.getStepSize().value_in_unit(unit.picosecond)
        ends = 0.0
        if self.kind.startswith("rigid"):
            # Drawn on step for the bodies' own (possibly raised) moments and taken half a kick back by
            # the integrator (Context.setVelocitiesToTemperature()); getOnStepKineticEnergy() kicks forward.
            context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, velocitySeed)
            ends -= integrator.getOnStepKineticEnergy().value_in_unit(KJ) - self.kinetic()
        else:
            rng = np.random.default_rng(velocitySeed)
            context.setVelocities(rng.standard_normal((len(self.masses), 3))*np.sqrt(KT/self.masses)[:, None])
            context.applyVelocityConstraints(1e-10)  # before the work is counted: the constraints' share is no step's
            if self.halfStepBehind:
                onStep = self.kinetic()
                ends -= onStep - self.kick(-halfStep)
        try:
            if self.kind.startswith("rigid"):
                before = integrator.getShadowWork().value_in_unit(KJ)  # the sum so far: this protocol's is the difference
                with warnings.catch_warnings(record=True) as caught:  # recorded, not shown
                    warnings.simplefilter("always", openmmrigid.AccuracyWarning)
                    integrator.step(steps)
                self.fired = self.fired or bool(benchmarking.accuracyWarnings(caught))
                work = integrator.getShadowWork().value_in_unit(KJ) - before
            elif self.kind == "stock-middle":
                for name in ("work", "heat", "started"):
                    integrator.setGlobalVariableByName(name, 0.0)
                integrator.step(steps)
                state = context.getState(getEnergy=True)
                # The last step's part: K + U now less K + U before it, less its heat.
                last = (state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(KJ) - \
                    integrator.getGlobalVariableByName("start") - integrator.getGlobalVariableByName("heat")
                work = integrator.getGlobalVariableByName("work") + last
            else:
                integrator.reset_shadow_work()
                integrator.step(steps)
                work = integrator.get_shadow_work(dimensionless=True)*KT
            if self.kind.startswith("rigid"):
                ends += integrator.getOnStepKineticEnergy().value_in_unit(KJ) - self.kinetic()
            elif self.halfStepBehind:
                halfBehind = self.kinetic()
                ends += self.kick(halfStep) - halfBehind
        except openmm.OpenMMException as error:
            self.failure = str(error).splitlines()[0][:160]
            return None
        work = (work + ends)/KT
        if not np.isfinite(work):
            self.failure = "the shadow work is not finite"
            return None
        return work


STORES = benchmarking.ROOT/"benchmarks"/"stores"/"sampling_error"
# The failure reason of a job that failed without a message (and of every failure recorded before messages were kept).
UNKNOWN_FAILURE = "NaN or an exception"


def frameFiles(folder, name):
    return folder/f"system-{name}.xml", folder/f"frames-{name}.npz", folder/f"chain-{name}.xml"


def ensureFrames(folder, name, molecules, count, spacingPs, equilibratePs, platform, properties):
    """At least `count` equilibrium frames of system `name` in the store's folder: a chain of
    RigidBodyLangevinIntegrator at 1 fs and friction 5/ps (after `equilibratePs`), a frame every
    `spacingPs`. The System is saved as XML (every worker and later run uses that one) and the chain's
    state after its last frame, so that a later run that wants more frames continues it (with a new
    seed); each frame is saved as it is made."""
    systemPath, framesPath, chainPath = frameFiles(folder, name)
    frames = dict(np.load(framesPath)) if framesPath.exists() else {"positions": np.zeros((0, 0, 3)), "boxes": np.zeros((0, 3, 3))}
    have = len(frames["positions"])
    if have >= count:
        return
    integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, 5.0, 0.001)
    integrator.setRandomNumberSeed(2 + have)
    integrator.setAccuracyCheck(False)
    if systemPath.exists():
        system = openmm.XmlSerializer.deserialize(systemPath.read_text())
        context = openmm.Context(system, integrator, platform, properties)
        context.setState(openmm.XmlSerializer.deserialize(chainPath.read_text()))
        stamp(f"{name}: frames {have} to {count - 1}, continuing the chain")
    else:
        _, positions, system = makeSystem(name, molecules)
        systemPath.write_text(openmm.XmlSerializer.serialize(system))
        context = openmm.Context(system, integrator, platform, properties)
        context.setPositions(positions)
        openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
        context.setVelocitiesToTemperature(TEMPERATURE, 2)
        stamp(f"{name}: {system.getNumParticles()} particles; equilibrating {equilibratePs:g} ps, then {count} frames")
        integrator.step(int(round(equilibratePs/0.001)))
    positions, boxes = list(frames["positions"]), list(frames["boxes"])
    while len(positions) < count:
        integrator.step(int(round(spacingPs/0.001)))
        state = context.getState(getPositions=True, getVelocities=True)
        # Single precision (1e-7 of a box edge) keeps the store small; the chain goes on from the
        # full-precision state.
        positions.append(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer).astype(np.float32))
        boxes.append(np.array(state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)))
        np.savez_compressed(framesPath.with_suffix(".tmp.npz"), positions=np.array(positions, np.float32), boxes=np.array(boxes))
        framesPath.with_suffix(".tmp.npz").replace(framesPath)
        chainPath.write_text(openmm.XmlSerializer.serialize(state))


def loadFrames(folder, name):
    systemPath, framesPath, _ = frameFiles(folder, name)
    frames = np.load(framesPath)
    return openmm.XmlSerializer.deserialize(systemPath.read_text()), frames["positions"], frames["boxes"]


def jobKey(systemName, kind, stepFs):
    return f"{systemName}|{kind}|{stepFs:g}"


def blockersAmong(steps):
    """A step does not run once a smaller one of these steps (fs) failed, for the same integrator on the
    same system: the jobs that block a job."""
    def blockers(key):
        systemName, kind, stepFs = key.split("|")
        return [jobKey(systemName, kind, smaller) for smaller in steps if smaller < float(stepFs)]
    return blockers


def worker(folder, keys, steps, target, chunk, deadline, platformName, threads, protocol):
    """Claim jobs and add their samples until every job has `target` or the deadline passes: for each
    frame i, the shadow works (kT) of the protocol from the frame and from the state it reached with
    velocities drawn again (seeds 100 + 2i and 101 + 2i)."""
    store = benchmarking.SampleStore(folder)
    blockers = blockersAmong(steps)
    platform = openmm.Platform.getPlatformByName(platformName)
    properties = benchmarking.cpuProperties(platform, threads)
    loaded = {}
    while time.time() < deadline:
        claimed = store.claim(keys, target, blockers)
        if claimed is None:
            return
        key, missing = claimed
        systemName, kind, stepFs = key.split("|")
        stepFs = float(stepFs)
        if systemName not in loaded:
            loaded[systemName] = loadFrames(folder, systemName)
        system, positions, boxes = loaded[systemName]
        try:
            runner = Runner(kind, stepFs, system, platform, properties, seed=11 + missing[0])
            count = int(round(protocol/(stepFs*1e-3)))
            for index in missing[:chunk]:
                first = runner.work(positions[index].astype(float), boxes[index], count, velocitySeed=100 + 2*index)
                second = runner.work(None, None, count, velocitySeed=101 + 2*index) if first is not None else None
                if first is None or second is None:
                    store.fail(key, index, runner.failure or UNKNOWN_FAILURE)
                    stamp(f"{key}: failed at frame {index} (unstable); larger steps not run")
                    break
                store.add(key, index, (first, second), fired=runner.fired)
                if time.time() >= deadline:
                    break
            del runner
        finally:
            store.release(key)
        done = len(store.samples(key))
        stamp(f"{key}: {done} frame(s)")


def timeSteps(folder, systemName, kinds, steps, platform, properties, repetitions, retime):
    """ns/day at each step: every integrator with samples there, timed side by side (interleaved
    blocks, medians) from the first frame with velocities at 300 K; kept in the store's notes (a step
    is timed again when an integrator is new there, or with retime)."""
    store = benchmarking.SampleStore(folder)
    system, positions, boxes = loadFrames(folder, systemName)
    for stepFs in steps:
        data = store.read()
        kindsHere = [kind for kind in kinds if len(data["jobs"].get(jobKey(systemName, kind, stepFs), {}).get("samples", {})) >= 2
                     and data["jobs"][jobKey(systemName, kind, stepFs)]["failed"] is None]
        noteKey = f"nsPerDay|{systemName}|{stepFs:g}"
        old = data.get("notes", {}).get(noteKey, {})
        if not kindsHere or (not retime and all(kind in old.get("values", {}) for kind in kindsHere)):
            continue
        integrators, contexts = {}, []
        for kind in kindsHere:
            integrators[kind] = timedIntegrator(kind, stepFs)
            context = openmm.Context(system, integrators[kind], platform, properties)
            context.setPeriodicBoxVectors(*boxes[0])
            context.setPositions(positions[0].astype(float))
            context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 3)
            contexts.append(context)
        wall = benchmarking.timeInterleaved(integrators, max(10, int(round(0.2/(stepFs*1e-3)))), repetitions)[0]
        values = {kind: benchmarking.nsPerDay(stepFs, float(np.median(seconds))) for kind, seconds in wall.items()}
        store.note(noteKey, {"values": values, "date": f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}",
                             "commit": benchmarking.commit(), "load": benchmarking.loadAverage()})
        stamp(f"{systemName} {stepFs:g} fs, ns/day side by side: " + ", ".join(f"{kind} {value:.2f}" for kind, value in values.items()))
        del integrators, contexts


def report(folder, systems, kinds, steps, quick, document):
    store = benchmarking.SampleStore(folder)
    data = store.read()
    setup = data["setup"]
    blockers = blockersAmong(steps)
    rows, csvRows = [], []
    for systemName in systems:
        figureData = {}
        for kind in kinds:
            for stepFs in steps:
                key = jobKey(systemName, kind, stepFs)
                job = data["jobs"].get(key)
                if job is None:
                    continue
                if job["failed"] is not None:
                    failed = job["failed"]
                    reason = "" if failed["reason"] == UNKNOWN_FAILURE else f": {failed['reason'][:100]}"
                    rows.append([systemName, kind, f"{stepFs:g}", "", f"unstable (frame {failed['sample']}){reason}", "", ""])
                    continue
                if benchmarking.SampleStore.blocked(data, key, blockers(key)):
                    continue
                pairs = np.array([values for _, values in sorted((int(i), v) for i, v in job["samples"].items())])
                if len(pairs) < 2:
                    continue
                kl, error = configurationKL(pairs[:, 0], pairs[:, 1])
                fired = ("yes" if job["flags"].get("fired") else "no") if kind.startswith("rigid") else ""
                speed = data.get("notes", {}).get(f"nsPerDay|{systemName}|{stepFs:g}", {}).get("values", {}).get(kind)
                rows.append([systemName, kind, f"{stepFs:g}", len(pairs), f"{kl:.3g} +- {error:.2g}",
                             "" if speed is None else f"{speed:.2f}", fired])
                csvRows.append(dict(system=systemName, integrator=kind, stepFs=stepFs, frames=len(pairs), kl=float(kl),
                                    error=float(error), nsPerDay=float("nan") if speed is None else float(speed),
                                    checkFired=fired))
                if speed is not None:
                    figureData.setdefault(kind, []).append((speed, kl, error, stepFs))
        if figureData:
            plt = benchmarking.pyplot()
            figure, axes = plt.subplots(figsize=(6, 4))
            for kind, points in figureData.items():
                points = np.array(points)
                low = np.maximum(points[:, 1], 1e-3)
                axes.errorbar(points[:, 0], low, yerr=[np.minimum(points[:, 2], low - 1e-4), points[:, 2]], marker="o", label=kind)
                for x, y, _, step in points:
                    axes.annotate(f"{step:g}", (x, max(y, 1e-3)), fontsize=7)
            axes.set_xlabel(f"ns/day ({setup['platform']})")
            axes.set_ylabel("configuration-space KL divergence (kT)")
            axes.set_yscale("log")
            axes.set_title(f"{systemName}: sampling error against speed (labels: step in fs)", fontsize=9)
            axes.legend(fontsize=8)
            path = document.figurePath(f"sampling_error_{systemName}.png")
            benchmarking.saveFigure(figure, path)
            document.figure(path, f"{systemName}: KL divergence against ns/day")
    document.section("KL divergence and speed",
                     f"{setup['molecules']} waters; per integrator and step, the frames measured so far (of the equilibrium frames "
                     f"{setup['spacing']:g} ps apart), {setup['protocol']:g} ps per half protocol, friction {FRICTION:g}/ps, "
                     f"{TEMPERATURE:g} K; KL in kT +- one standard error (a value below 0 is 0 within its error). "
                     "Estimates at negative values are plotted at 1e-3 kT. ns/day: side by side at each step, "
                     "comparable within a step.")
    document.table(["system", "integrator", "step (fs)", "frames", "KL (kT)", "ns/day", "accuracy check fired"], rows)
    runs = data["runs"]
    if runs:
        document.section("Runs that made these samples",
                         "Each run adds frames to the store (`" + str(folder.relative_to(benchmarking.ROOT)) + "`); "
                         "frames from different runs are independent samples and pool. Frame pairs added:")
        document.text("\n".join(f"- {benchmarking.SampleStore.describeRun(run)} ({run['machine']})" for run in runs))
    if csvRows:
        benchmarking.writeCsv(benchmarking.RESULTS/"sampling_error"/("quick" if quick else "full")/"sampling_error.csv", csvRows)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="216 waters, steps 2 6 10 fs, 3 frames, 0.2 ps protocols, a fresh store")
    parser.add_argument("--systems", nargs="+", default=None, choices=["water", "peptide"])
    parser.add_argument("--integrators", nargs="+", default=None,
                        choices=["rigid-exact", "rigid-nosquish", "rigid-raised", "stock-middle", "openmmtools-vrorv"])
    parser.add_argument("--floor", type=float, default=0.08, help="rigid-raised's minimum moment (amu nm^2; default 0.08)")
    parser.add_argument("--steps", nargs="+", type=float, default=None, help="steps in fs (default 1 2 4 6 8 10)")
    parser.add_argument("--samples", type=int, default=None, help="equilibrium frames to reach per integrator and step (default 50)")
    parser.add_argument("--spacing", type=float, default=2.0, help="ps between frames (default 2)")
    parser.add_argument("--equilibrate", type=float, default=20.0, help="ps before the first frame (default 20)")
    parser.add_argument("--protocol", type=float, default=None, help="ps of each half of a protocol (default 2)")
    parser.add_argument("--molecules", type=int, default=None, help="waters (default 500; 216 with --quick)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, default=1, help="CPU threads per worker")
    parser.add_argument("--workers", type=int, default=1, help="worker processes adding frames at once")
    parser.add_argument("--chunk", type=int, default=2, help="frames a worker adds to a job before it chooses again")
    parser.add_argument("--hours", type=float, default=None, help="stop adding frames after this long (the report is still written)")
    parser.add_argument("--no-timing", action="store_true", help="leave ns/day for a later run on a quiet machine")
    parser.add_argument("--retime", action="store_true", help="time every step again")
    parser.add_argument("--report", action="store_true", help="add no frames: write the report from the stored ones (with --retime: time first)")
    parser.add_argument("--timing-repetitions", type=int, default=5)
    args = parser.parse_args()
    quick = args.quick
    systems = args.systems or (["water"] if quick else ["water", "peptide"])
    steps = sorted(args.steps or ([2.0, 6.0, 10.0] if quick else [1.0, 2.0, 4.0, 6.0, 8.0, 10.0]))
    samples = args.samples or (3 if quick else 50)
    protocol = args.protocol or (0.2 if quick else 2.0)
    molecules = args.molecules or (216 if quick else 500)
    if quick:
        args.spacing, args.equilibrate = 0.5, 1.0
    FLOOR[0] = args.floor
    kinds = args.integrators or ["rigid-exact", "rigid-nosquish", "rigid-raised", "stock-middle", "openmmtools-vrorv"]
    if "openmmtools-vrorv" in kinds:
        try:
            import openmmtools.integrators  # noqa: F401
        except ImportError:
            say("openmmtools is not installed: openmmtools-vrorv left out")
            kinds = [kind for kind in kinds if kind != "openmmtools-vrorv"]
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = benchmarking.cpuProperties(platform, args.threads)
    # A full run's samples are kept in git (benchmarks/stores/), so that later sessions add to them.
    folder = (benchmarking.RESULTS/"sampling_error"/"quick" if quick else STORES)/f"{molecules}w-{protocol:g}ps-{args.platform}"
    if quick and folder.exists() and not args.report:
        shutil.rmtree(folder)
    setup = dict(molecules=molecules, protocol=protocol, spacing=args.spacing, equilibrate=args.equilibrate, floor=args.floor,
                 platform=args.platform, friction=FRICTION, temperature=TEMPERATURE)
    store = benchmarking.SampleStore(folder, setup)
    before = store.total()
    started = time.time()
    keys = [jobKey(systemName, kind, stepFs) for systemName in systems for kind in kinds for stepFs in steps]
    if not args.report:
        # Frames for the whole target first (one chain per system, all the workers' threads).
        chainProperties = benchmarking.cpuProperties(platform, args.threads*args.workers)
        for systemName in systems:
            ensureFrames(folder, systemName, molecules, samples, args.spacing, args.equilibrate, platform, chainProperties)
        deadline = time.time() + (args.hours*3600 if args.hours is not None else float("inf"))
        benchmarking.runWorkers(worker, (folder, keys, steps, samples, args.chunk, deadline, args.platform, args.threads, protocol),
                                args.workers)
        added = store.total() - before
        store.recordRun(added, time.time() - started, args.platform, args.threads, args.workers)
        stamp(f"{added} frame(s) added")
    # Timed after adding frames (unless --no-timing), or with --report only when --retime asks.
    if not args.no_timing and (not args.report or args.retime):
        for systemName in systems:
            timeSteps(folder, systemName, kinds, steps, platform, properties, args.timing_repetitions, args.retime)
    document = benchmarking.ResultsDocument("sampling_error", "Configuration-space sampling error against step size",
                                            quick=quick, platform=args.platform, threads=args.threads,
                                            about="Method: the docstring of `benchmarks/sampling_error.py`.")
    report(folder, systems, kinds, steps, quick, document)
    document.write()


if __name__ == "__main__":
    main()

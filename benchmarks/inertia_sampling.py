#!/usr/bin/env python
"""Sampling speed with raised moments of inertia: ns/day at equal configurational accuracy, and what
a user gets per wall-hour, for stock LangevinMiddleIntegrator + SETTLE (standard masses, and water
hydrogens at 4 amu: the mass repartitioning any OpenMM user can do by hand) and
RigidBodyLangevinIntegrator (standard moments, and moments raised with setMinimumMomentOfInertia).

Systems: those of benchmarks/nvt_accuracy.py (500 rigid waters, amber14 TIP3P or TIP4P-Ew, PME 0.9 nm,
ewaldErrorTolerance 5e-4, CMMotionRemover, 300 K, friction 1/ps; NPT: MonteCarloBarostat, 1 bar,
every 25 steps; "protein": alanine dipeptide among the 500 TIP3P waters, amber14, HBonds, HMR 3 amu,
NPT, whose bonds cap every configuration's step, so all run at 2 to 5 fs and U is the whole system's
per water), built, minimized and equilibrated as there; and "rigid-solute", the same peptide and waters
with the peptide one rigid body for the rigid integrator (rigidBodiesFromTopology with mergeBonded,
removeIntraBodyInteractions: a rigid small molecule among rigid waters, its shape that of the
equilibrated state) while stock runs it flexible as above, capped at 5 fs. Those are two models: each
family's bias is taken against its own 2 fs runs, and the rigid integrator's starts are its own. Each of `--starts` independent starts
continues that state for 3 ps with stock at 2 fs and its own seed (start 0: the state itself); from
each start, every configuration runs at each of its steps, with velocities drawn for its own masses and
moments (setVelocitiesToTemperature): `--discard` ps discarded, then `--time` ps
sampled every 0.1 ps (U per water, density, reported temperature; every frame the waters' atoms).

Configurational error. The reference is the pooled 2 fs runs of stock and of the rigid integrator with
standard moments (the same model; their difference is printed as a check). For each configuration,
the bias of U per water against the step h (the mean over the starts, its error the starts' errors
combined) is fitted, weighted, by a h^2 + b h^4 (the leading orders of a Langevin splitting's
configurational error): the fit uses every step, so one 2-sigma fluctuation moves it little. The
accurate step is the largest h, up to the largest step that ran stably from every start and before
the first step whose bias is beyond the tolerance by more than 2 standard errors (which, with the
larger ones, stays out of the fit), where the fitted |bias| is at most `--tolerance` (0.1 kJ/mol per water: about the spread of independent 20 ps
runs, 0.25 % of U). The plain rule of nvt_accuracy (largest step within 2 combined standard errors,
every smaller step too) is given beside it, on U, the density in NPT and g_OO about its first peak
(the mean of the oxygens' g(r) over 0.265 to 0.295 nm, sampled with U).

What a user gets, from the runs at each configuration's accurate step (the largest run step not
above it): the oxygen self-diffusion coefficient D (slope of the mean-square displacement between
lags of 1 and 5 ps, / 6), the rotational correlation time tau_1 of the molecular dipole axis
(C_1(t) = <u(0).u(t)>, exponential fit where 0.15 < C_1 < 0.85), and the integrated autocorrelation
time tau_U of U (samples 0.1 ps apart; Sokal's window, c = 5). ns/day is timed at the integer step
below the accurate step, every configuration in turn in one process (`--timing-repetitions` blocks of
`--timing-steps` steps in each of `--timing-contexts` Contexts per configuration, medians of the
pooled blocks); the accuracy check stays on, its default: its episodes cost within noise of a step
without it, docs/results/accuracy_check_cost.md. Effective samples per wall-hour: simulated ps per
hour / (2 tau_U).

    python benchmarks/inertia_sampling.py --quick                  # smoke check, about 5 minutes
    python benchmarks/inertia_sampling.py --systems tip3p-nvt --starts 2 --threads 2
    python benchmarks/inertia_sampling.py --systems tip3p-npt --starts 6 --workers 2 --threads 1 --hours 2 --no-timing
    python benchmarks/inertia_sampling.py --report                 # the report from the stores
    python benchmarks/inertia_sampling.py --retime --systems tip3p-npt --threads 2   # new timing, same sampling

The runs are kept between sessions: each system's in benchmarks/stores/inertia_sampling/<system>/
(benchmarking.SampleStore, committed with the code: a job is a configuration at a step, its samples
the runs from each start, with the start states), so `--starts` is the total a system is to reach and
a run adds what is missing, every job in turn, the fewest starts first, until `--hours` pass. Start 0
is the equilibrated system, start k start k - 1 continued 5 ps by stock at 2 fs. A configuration is
reported with the starts all its steps have. A system is timed when it has no timing yet, or with
`--retime` (the timing is kept in its store); `--no-timing` leaves it for a quiet machine. The runs
of 2026-12-02 and 2026-12-03 made before the stores (their starts 3 ps from one equilibrated state)
were put into the stores once, unchanged (commit 39f4938's `--import-results`, removed since).

Results: the stores; benchmarks/results/inertia_sampling/<mode>/<system>.json (each system's analysis)
and a log; a full run writes docs/results/inertia_sampling.md and docs/figures/inertia_sampling_<system>.png.
"""

import argparse
import json
import shutil
import sys
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from benchmarking import (ROOT, RESULTS as BENCHMARK_RESULTS, Progress, ResultsDocument, SampleStore, blockMean, cpuProperties, runWorkers, header,
                          nsPerDay, openLog, pyplot, rigidDegreesOfFreedom, say, stamp, timeInterleaved, TimingFailure)
from nvt_accuracy import (AMU_PER_NM3_IN_G_PER_ML, BOLTZMANN, FRICTION, SYSTEMS as NVT_SYSTEMS, TEMPERATURE, buildModel,
                          equilibrate, stockDegreesOfFreedom, withoutBarostat)

RESULTS = BENCHMARK_RESULTS/"inertia_sampling"
STORES = ROOT/"benchmarks"/"stores"/"inertia_sampling"   # every system's runs, kept in git (storeOf())
START_SPACING = 5.0         # ps of stock at 2 fs from one start to the next (ensureStarts())
SAMPLE_EVERY = 0.1          # ps
G_SHELL = (0.265, 0.295)    # nm: the shell about the first maximum of g_OO(r) (0.28 nm) whose mean g is observed
HEAVY_HYDROGEN = 4.0        # amu: water hydrogens for stock's mass repartitioning, the oxygen lighter by as much
# The peptide (alanine dipeptide, HBonds, HMR 3 amu, NPT: nvt_accuracy's "protein"): both stock and the
# rigid integrator fail at 6 fs there (docs/results/nvt_accuracy.md), whatever the waters' masses and moments.
PEPTIDE_STEPS = [2, 3, 4, 5]
# "rigid-solute": the same peptide and waters, but for the rigid integrator the peptide is one rigid
# body (rigidBodiesFromTopology with mergeBonded, removeIntraBodyInteractions: examples/rigid_solute.py),
# a rigid small molecule among rigid waters; stock runs the peptide as a user of stock must, flexible
# with HBonds and HMR, at the steps the peptide allows it. The two are different models, so each
# family's bias is taken against its own 2 fs runs (analyse()).
SOLUTE_RESIDUES = ["ACE", "ALA", "NME"]
SYSTEMS = dict(NVT_SYSTEMS, **{"rigid-solute": dict(
    model="tip3p", npt=True, protein=True, rigidSolute=True,
    title="alanine dipeptide in 500 TIP3P waters, NPT: one rigid body for the rigid integrator; flexible, HBonds, HMR 3 amu for stock")})


def configurations(floors, quick, protein=False, rigidSolute=False):
    """label -> (description, rigid, heavy hydrogens, minimum moment, steps in fs). With the peptide
    every configuration takes the steps of PEPTIDE_STEPS: its bonds cap the step, whatever the waters do;
    with the rigid solute only stock's do (the rigid integrator's peptide has no bonds left)."""
    result = {
        "stock": ("LangevinMiddleIntegrator + SETTLE", False, False, 0.0, [2, 4, 6, 8, 10]),
        "stock-heavy": (f"LangevinMiddleIntegrator + SETTLE, water H {HEAVY_HYDROGEN:g} amu", False, True, 0.0, [4, 8, 10, 12, 14]),
        "rigid": ("RigidBodyLangevinIntegrator", True, False, 0.0, [2, 4, 6, 8, 10]),
    }
    for floor in floors:
        result[f"raised-{floor:g}"] = (f"RigidBodyLangevinIntegrator, moments >= {floor:g} amu nm^2", True, False, floor,
                                       [4, 8, 12, 14, 16, 18])
    capped = lambda spec: protein and not (rigidSolute and spec[1])
    result = {label: spec[:4] + (list(PEPTIDE_STEPS),) if capped(spec) else spec for label, spec in result.items()}
    if quick:
        kept = lambda spec: (2, 4) if capped(spec) else (2, 8, 12)
        result = {label: spec[:4] + ([s for s in spec[4] if s in kept(spec)] or spec[4][:1],) for label, spec in result.items()}
    return result


def heavyHydrogens(system, topology):
    """A copy of the System with every water hydrogen at HEAVY_HYDROGEN amu and its oxygen lighter by as much."""
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for residue in topology.residues():
        if residue.name != "HOH":
            continue
        atoms = list(residue.atoms())
        oxygen = next(atom.index for atom in atoms if atom.element == app.element.oxygen)
        for atom in atoms:
            if atom.element == app.element.hydrogen:
                moved = HEAVY_HYDROGEN - copy.getParticleMass(atom.index).value_in_unit(unit.dalton)
                copy.setParticleMass(atom.index, HEAVY_HYDROGEN)
                copy.setParticleMass(oxygen, copy.getParticleMass(oxygen).value_in_unit(unit.dalton) - moved)
    return copy


class Models:
    """The Systems of one system's configurations: stock's (standard and heavy-hydrogen water) and the
    rigid integrator's, the same System or, for the rigid solute, the System without the terms inside
    its bodies (every water and the peptide), with those bodies."""

    def __init__(self, system, topology, rigidSolute):
        self.system, self.heavy, self.rigid, self.bodies = system, heavyHydrogens(system, topology), system, None
        if rigidSolute:
            self.bodies = openmmrigid.rigidBodiesFromTopology(topology, SOLUTE_RESIDUES + ["HOH"], mergeBonded=True,
                                                              system=system)
            self.rigid = openmmrigid.removeIntraBodyInteractions(system, self.bodies)
            last = lambda s: type(s.getForce(s.getNumForces() - 1)).__name__
            assert last(self.rigid) == last(system), "the barostat must stay the last force"

    def of(self, spec):
        """(System, bodies or None) of a configuration."""
        if spec[1]:
            return self.rigid, self.bodies
        return (self.heavy if spec[2] else self.system), None


def makeIntegrator(spec, stepFs, seed, bodies=None):
    _, rigid, _, floor, _ = spec
    dt = stepFs*unit.femtoseconds
    if rigid:
        integrator = (openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, dt) if bodies is None else
                      openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, dt, bodies))
        integrator.setMinimumMomentOfInertia(floor)
    else:
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, dt)
    integrator.setRandomNumberSeed(seed)
    return integrator


class Waters:
    """The atoms of the waters: oxygens and each water's two hydrogens."""

    def __init__(self, topology):
        self.oxygens, self.hydrogens = [], []
        for residue in topology.residues():
            if residue.name == "HOH":
                atoms = list(residue.atoms())
                self.oxygens.append(next(a.index for a in atoms if a.element == app.element.oxygen))
                self.hydrogens.append([a.index for a in atoms if a.element == app.element.hydrogen])
        self.oxygens, self.hydrogens = np.array(self.oxygens), np.array(self.hydrogens)
        self.count = len(self.oxygens)


def simulate(models, state, waters, spec, stepFs, seed, npt, discard, production, platform, properties):
    """One run: the samples, the oxygen positions and dipole axes of every sample, and a failure message."""
    system, bodies = models.of(spec)
    if npt:
        system.getForce(system.getNumForces() - 1).setRandomNumberSeed(seed + 1)
    integrator = makeIntegrator(spec, stepFs, seed, bodies)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    # Fresh velocities for this configuration's masses and moments: those of the start, drawn for the
    # particles' own, would give raised moments a rotational temperature I'/I times too high.
    context.setVelocitiesToTemperature(TEMPERATURE, seed)
    dof = rigidDegreesOfFreedom(context, integrator) if spec[1] else stockDegreesOfFreedom(system)
    totalMass = sum(system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles()))
    dtPs = stepFs/1000
    perSample = max(1, int(round(SAMPLE_EVERY/dtPs)))
    samples = int(round(production/(perSample*dtPs)))
    discardSteps = int(round(discard/dtPs))
    data = {"potential": [], "density": [], "temperature": [], "gShell": []}
    oxygens, axes, boxes = [], [], []
    progress = Progress(f"{spec[0]} {stepFs:g} fs", discardSteps + samples*perSample)
    failure = ""
    try:
        integrator.step(discardSteps)
        progress.update(discardSteps)
        for sample in range(samples):
            integrator.step(perSample)
            current = context.getState(getEnergy=True, getPositions=True)
            potential = current.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/waters.count
            kinetic = current.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
            if not (np.isfinite(potential) and np.isfinite(kinetic)) or potential > 0:
                failure = f"energy {potential:.3g} kJ/mol per water after {discard + (sample + 1)*perSample*dtPs:.2f} ps"
                break
            box = current.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
            positions = current.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            data["potential"].append(potential)
            data["density"].append(totalMass/np.linalg.det(box)*AMU_PER_NM3_IN_G_PER_ML)
            data["temperature"].append(2*kinetic/(dof*BOLTZMANN))
            oxygen = positions[waters.oxygens]
            data["gShell"].append(shellPairDensity(oxygen, np.diag(box)))
            axis = positions[waters.hydrogens].mean(axis=1) - oxygen
            oxygens.append(oxygen)
            axes.append(axis/np.linalg.norm(axis, axis=1)[:, None])
            boxes.append(np.diag(box).copy())
            progress.update(discardSteps + (sample + 1)*perSample)
    except openmm.OpenMMException as error:
        failure = str(error).splitlines()[0][:160]
    return data, np.array(oxygens), np.array(axes), np.array(boxes), failure


def shellPairDensity(oxygens, edges):
    """g_OO(r) averaged over the shell G_SHELL: the oxygen pairs at those distances (minimum image in the
    rectangular box of these edges, nm) over the number an ideal gas of the same density would have
    there. About the height of g_OO's first peak: the water structure that a too-large step (hot
    librations) flattens."""
    delta = oxygens[:, None, :] - oxygens[None, :, :]
    delta -= edges*np.round(delta/edges)
    distances = np.sqrt(np.sum(delta**2, axis=-1))[np.triu_indices(len(oxygens), k=1)]
    pairs = np.count_nonzero((distances >= G_SHELL[0]) & (distances < G_SHELL[1]))
    n = len(oxygens)
    ideal = 0.5*n*(n - 1)/np.prod(edges)*4/3*np.pi*(G_SHELL[1]**3 - G_SHELL[0]**3)
    return pairs/ideal


# ---------------------------------------------------------------------------------------------------
# Dynamics from the samples
# ---------------------------------------------------------------------------------------------------


def diffusion(oxygens, boxes):
    """D in 1e-5 cm^2/s from the oxygens' MSD (unwrapped by minimum-image steps between samples), lags 1 to 5 ps."""
    steps = np.diff(oxygens, axis=0)
    steps -= boxes[1:, None, :]*np.round(steps/boxes[1:, None, :])
    path = np.concatenate([np.zeros((1,) + oxygens.shape[1:]), np.cumsum(steps, axis=0)])
    lags = np.arange(int(1.0/SAMPLE_EVERY), min(int(5.0/SAMPLE_EVERY), len(path)//2) + 1)
    if len(lags) < 2:
        return float("nan")
    msd = [np.mean(np.sum((path[lag:] - path[:-lag])**2, axis=-1)) for lag in lags]
    slope = np.polyfit(lags*SAMPLE_EVERY, msd, 1)[0]    # nm^2/ps
    return float(slope/6*1e3)                            # 1 nm^2/ps = 1e-2 cm^2/s = 1e3 x 1e-5 cm^2/s


def rotationalTime(axes):
    """tau_1 (ps) of the dipole axis: exponential fit of C_1(t) where 0.15 < C_1 < 0.85."""
    maxLag = min(len(axes)//2, int(10.0/SAMPLE_EVERY))
    c = np.array([1.0] + [np.mean(np.sum(axes[lag:]*axes[:-lag], axis=-1)) for lag in range(1, maxLag)])
    use = (c > 0.15) & (c < 0.85)
    if use.sum() < 2:
        return float("nan")
    t = np.arange(len(c))*SAMPLE_EVERY
    return float(-1/np.polyfit(t[use], np.log(c[use]), 1)[0])


def autocorrelationTime(values):
    """Integrated autocorrelation time (ps) of a series sampled every SAMPLE_EVERY: 1/2 + sum rho(k),
    summed up to the first k >= 5 tau (Sokal's window)."""
    x = np.asarray(values) - np.mean(values)
    n = len(x)
    spectrum = np.fft.rfft(x, 2*n)
    rho = np.fft.irfft(spectrum*np.conj(spectrum))[:n]
    rho /= rho[0]
    tau = 0.5
    for k in range(1, n):
        tau += rho[k]
        if k >= 5*tau:
            break
    return float(tau*SAMPLE_EVERY)


# ---------------------------------------------------------------------------------------------------
# One system
# ---------------------------------------------------------------------------------------------------


def build(name):
    """The system's spec, Topology, the System its runs use (NPT or NVT), and the NPT System and the
    positions it is equilibrated from."""
    spec = SYSTEMS[name]
    topology, positions, nptSystem = buildModel(spec["model"], spec["protein"])
    return spec, topology, (nptSystem if spec["npt"] else withoutBarostat(nptSystem)), nptSystem, positions


def storeOf(name, args):
    """The system's runs, kept between sessions (benchmarking.SampleStore): a job is a configuration at
    a step, its samples the runs from each start (the start's index)."""
    folder = (RESULTS/"quick"/"stores" if args.quick else STORES)/name
    return SampleStore(folder, dict(time=args.time, discard=args.discard, equilibrate=args.equilibrate,
                                    sampleEvery=SAMPLE_EVERY, startSpacing=START_SPACING))


def jobKey(label, stepFs):
    return f"{label}|{stepFs:g}"


def jobKeys(configs):
    return [jobKey(label, step) for label, config in configs.items() for step in config[4]]


def blockersIn(configs):
    """A configuration's step is not run once a smaller step of it failed from some start."""
    def blockers(key):
        label, step = key.split("|")
        return [jobKey(label, smaller) for smaller in configs[label][4] if smaller < float(step)]
    return blockers


def startPath(store, index, rigid=False):
    return store.folder/f"{'rigid-' if rigid else ''}start-{index}.xml"


def loadState(path):
    return openmm.XmlSerializer.deserialize(path.read_text())


def ensureStarts(name, store, indices, args, platform, properties):
    """The start states these indices need, made and saved where missing. Start 0: the system minimized
    and equilibrated (nvt_accuracy.equilibrate(): NPT, stock, 2 fs); start k: start k - 1 continued
    START_SPACING ps by stock at 2 fs in the system's ensemble (seed k). With the rigid solute, the
    rigid integrator's start k is start k continued 3 ps by it (start 0: start 0 itself), so that each
    of its runs has the solute's shape of that state (a body takes the shape it has when the Context is
    made), the one model it samples."""
    if not indices:
        return
    needed = [startPath(store, k) for k in range(max(indices) + 1)]
    if SYSTEMS[name].get("rigidSolute"):
        needed += [startPath(store, k, rigid=True) for k in indices]
    if all(path.exists() for path in needed):
        return
    spec, topology, system, nptSystem, positions = build(name)
    for k in range(max(indices) + 1):
        path = startPath(store, k)
        if path.exists():
            continue
        if k == 0:
            stamp(f"{name}: {spec['title']}: minimizing and equilibrating {args.equilibrate:g} ps (stock, 2 fs)")
            state = equilibrate(nptSystem, positions, platform, properties, args.equilibrate)
        else:
            stamp(f"{name}: start {k}: start {k - 1} and {START_SPACING:g} ps (stock, 2 fs)")
            integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, 2*unit.femtoseconds)
            integrator.setRandomNumberSeed(k)
            if spec["npt"]:
                system.getForce(system.getNumForces() - 1).setRandomNumberSeed(k)
            context = openmm.Context(system, integrator, platform, properties)
            context.setState(loadState(startPath(store, k - 1)))
            context.setVelocitiesToTemperature(TEMPERATURE, k)
            integrator.step(int(round(START_SPACING/0.002)))
            state = context.getState(getPositions=True, getVelocities=True)
            del context
        path.write_text(openmm.XmlSerializer.serialize(state))
    if spec.get("rigidSolute"):
        models = Models(system, topology, True)
        rigidConfig = configurations([], False, True, True)["rigid"]
        for k in indices:
            path = startPath(store, k, rigid=True)
            if path.exists():
                continue
            if k == 0:
                path.write_text(startPath(store, 0).read_text())
                continue
            integrator = makeIntegrator(rigidConfig, 2, k, models.bodies)
            context = openmm.Context(models.rigid, integrator, platform, properties)
            context.setState(loadState(startPath(store, k)))
            context.setVelocitiesToTemperature(TEMPERATURE, k)
            integrator.step(1500)
            path.write_text(openmm.XmlSerializer.serialize(context.getState(getPositions=True, getVelocities=True)))
            del context


def worker(name, folder, configs, target, deadline, args):
    """Claim jobs (a configuration at a step) and run them from their next start, until every job has
    `target` starts or the deadline passes."""
    store = SampleStore(folder)
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = cpuProperties(platform, args.threads)
    spec, topology, system, _, _ = build(name)
    rigidSolute = spec.get("rigidSolute", False)
    models = Models(system, topology, rigidSolute)
    waters = Waters(topology)
    labels, keys, blockers = list(configs), jobKeys(configs), blockersIn(configs)
    while time.time() < deadline:
        claimed = store.claim(keys, target, blockers)
        if claimed is None:
            return
        key, missing = claimed
        label, stepFs = key.split("|")
        stepFs, config, start = float(stepFs), configs[label], missing[0]
        stepFs = int(stepFs) if stepFs.is_integer() else stepFs
        try:
            state = loadState(startPath(store, start, rigid=rigidSolute and config[1]))
            seed = 1000*start + 10*labels.index(label) + config[4].index(stepFs) + 1
            data, oxygens, axes, boxes, failure = simulate(models, state, waters, config, stepFs, seed, spec["npt"],
                                                           args.discard, args.time, platform, properties)
            if failure or len(data["potential"]) < 20:
                store.fail(key, start, failure or "too few samples")
                say(f"  {label} {stepFs:g} fs start {start}: unstable ({failure or 'too few samples'})")
            else:
                run = {quantity: [float(v) for v in blockMean(values)] for quantity, values in data.items()}
                run.update(D=diffusion(oxygens, boxes), tauRot=rotationalTime(axes), tauU=autocorrelationTime(data["potential"]))
                store.add(key, start, run)
                say(f"  {label} {stepFs:g} fs start {start}: U/water {run['potential'][0]:.3f} +- {run['potential'][1]:.3f}, "
                    f"T {run['temperature'][0]:.1f} K, D {run['D']:.2f}, tau_1 {run['tauRot']:.2f} ps, tau_U {run['tauU']:.2f} ps")
        finally:
            store.release(key)


def resultOf(name, store, tolerance):
    """The system's result for analyse() and report(), from its store: the runs from the starts that
    every running job has (a failed job keeps its runs and its failure; the steps it blocks are
    "not run"), the configurations, the timing and the runs that made the samples."""
    spec = SYSTEMS[name]
    data = store.read()
    notes = data.get("notes", {})
    configs = notes.get("configs", {})
    keys, blockers = jobKeys(configs), blockersIn(configs)
    jobs = data["jobs"]
    running = [key for key in keys if jobs.get(key, {}).get("failed") is None and not SampleStore.blocked(data, key, blockers(key))]
    # Each configuration with the starts all its running steps have (a configuration added later
    # catches up on its own).
    startsOf = {label: min((len(jobs.get(key, {}).get("samples", {})) for key in running if key.startswith(label + "|")),
                           default=0) for label in configs}
    runs = []
    for key in keys:
        label, step = key.split("|")
        starts = startsOf[label]
        step = int(float(step)) if float(step).is_integer() else float(step)
        job = jobs.get(key, {"samples": {}, "failed": None})
        if SampleStore.blocked(data, key, blockers(key)):
            runs += [dict(config=label, step=step, start=start, failure="not run (unstable at a smaller step)")
                     for start in range(starts)]
            continue
        for index, run in job["samples"].items():
            if int(index) < starts or job["failed"] is not None:
                runs.append(dict(run, config=label, step=step, start=int(index), failure=""))
        if job["failed"] is not None:
            runs.append(dict(config=label, step=step, start=job["failed"]["sample"], failure=job["failed"]["reason"]))
    waters = notes.get("waters")
    if waters is None:
        waters = Waters(buildModel(spec["model"], spec["protein"])[0]).count
        store.note("waters", waters)
    result = dict(name=name, title=spec["title"], npt=spec["npt"], waters=waters, runs=runs, starts=startsOf,
                  separateModels=spec.get("rigidSolute", False), configs=configs, tolerance=tolerance, history=data["runs"],
                  store=str(store.folder.relative_to(ROOT) if store.folder.is_relative_to(ROOT) else store.folder))
    for field in ("timed", "timingFailures", "retimed"):
        if field in notes:
            result[field] = notes[field]
    analyse(result)
    return result


def runSystem(name, args, platform, properties):
    """Add starts to the system's store until every job has --starts (or --hours pass), then analyse
    and, where it is not timed yet (or with --retime), time it."""
    started = time.perf_counter()
    store = storeOf(name, args)
    spec = SYSTEMS[name]
    configs = configurations(args.floors, args.quick, spec["protein"], spec.get("rigidSolute", False))
    known = store.read().get("notes", {}).get("configs", {})
    store.note("configs", dict(known, **{label: list(config) for label, config in configs.items()}))
    data = store.read()
    before = store.total()
    blockers = blockersIn(configs)
    needed = sorted({start for key in jobKeys(configs)
                     if data["jobs"].get(key, {}).get("failed") is None and not SampleStore.blocked(data, key, blockers(key))
                     for start in range(args.starts) if str(start) not in data["jobs"].get(key, {}).get("samples", {})})
    chainProperties = cpuProperties(platform, args.threads*args.workers)
    ensureStarts(name, store, needed, args, platform, chainProperties)
    deadline = time.time() + (args.hours*3600 if args.hours is not None else float("inf"))
    runWorkers(worker, (name, store.folder, configs, args.starts, deadline, args), args.workers)
    added = store.total() - before
    store.recordRun(added, time.perf_counter() - started, platform.getName(), args.threads or None, args.workers)
    result = resultOf(name, store, args.tolerance)
    stamp(f"{name}: {added} runs added; starts " + ", ".join(f"{label} {count}" for label, count in result["starts"].items())
          + "; accurate steps "
          + ", ".join(f"{label} {entry['accurateStep']}" for label, entry in result["summary"].items()))
    if not args.no_timing and ("timed" not in result or args.retime):
        timeSystem(name, store, result, args, platform, properties)
    return result


def timeSystem(name, store, result, args, platform, properties):
    """Time the system at its accurate steps (timing()) from start 0, and keep the timing in the store."""
    ensureStarts(name, store, [0], args, platform, properties)
    spec, topology, system, _, _ = build(name)
    stamp(f"{name}: timing")
    result.pop("timingFailures", None)
    timing(result, Models(system, topology, spec.get("rigidSolute", False)), loadState(startPath(store, 0)), result["configs"],
           platform, properties, args)
    store.note("timed", result["timed"])
    store.note("timingFailures", result.get("timingFailures", {}))
    store.note("retimed", header(platform.getName(), args.threads or None))


def pooled(runs, key):
    """Mean over the starts of a run's (mean, error) and the combined error."""
    values = [run[key] for run in runs]
    return float(np.mean([v[0] for v in values])), float(np.sqrt(sum(v[1]**2 for v in values))/len(values))


def analyse(result):
    runs = result["runs"]
    keys = ("potential", "density") if result["npt"] else ("potential",)
    if all("gShell" in r for r in runs if not r["failure"]):  # (runs made before 2026-12-03 lack it)
        keys += ("gShell",)
    good = lambda label, step: [r for r in runs if r["config"] == label and r["step"] == step and not r["failure"]]

    def referenceOf(labels):
        """The pooled 2 fs runs of these configurations: {key: (mean, error)}."""
        values = {key: [pooled(good(label, 2), key) for label in labels if good(label, 2)] for key in keys}
        return {key: (float(np.mean([v[0] for v in pairs])), float(np.sqrt(sum(v[1]**2 for v in pairs))/len(pairs)))
                for key, pairs in values.items() if pairs}

    # One model: stock's and the rigid integrator's 2 fs runs pooled (their difference printed as a check).
    # Two models (the rigid solute): each family, stock's and the rigid integrator's, against its own.
    if result.get("separateModels"):
        references = {False: referenceOf(["stock"]), True: referenceOf(["rigid"])}
        result["reference"], result["rigidReference"] = references[False], references[True]
        result.pop("referenceCheck", None)
    else:
        reference = referenceOf(["stock", "rigid"])
        references = {False: reference, True: reference}
        result["reference"] = reference
        if len(good("stock", 2)) and len(good("rigid", 2)):
            a, b = pooled(good("stock", 2), "potential"), pooled(good("rigid", 2), "potential")
            result["referenceCheck"] = [a[0] - b[0], float(np.hypot(a[1], b[1]))]
    summary = {}
    for label, config in result["configs"].items():
        reference = references[bool(config[1])]
        starts = len({r["start"] for r in runs if r["config"] == label})
        points = []
        for step in config[4]:
            done = good(label, step)
            if len(done) < starts:
                break
            entry = dict(step=step)
            for key in keys:
                mean, error = pooled(done, key)
                entry[key] = [mean, error, mean - reference[key][0], float(np.hypot(error, reference[key][1]))]
            for key in ("temperature",):
                entry[key] = list(pooled(done, key))
            for key in ("D", "tauRot", "tauU"):
                entry[key] = float(np.mean([r[key] for r in done]))
            points.append(entry)
        # A step that failed while it was timed (timing()) is not stable from every start either.
        failedTiming = min(result.get("timingFailures", {}).get(label, []), default=None)
        if failedTiming is not None:
            points = [p for p in points if p["step"] < failedTiming]
        largestStable = points[-1]["step"] if points else None
        # A step whose bias is beyond the tolerance by more than 2 standard errors is clearly inaccurate:
        # it and the larger ones bound the accurate range and stay out of the fit (an error of several
        # kJ/mol near instability would otherwise bend the fit at the small steps).
        retained = []
        for p in points:
            if abs(p["potential"][2]) > result["tolerance"] + 2*p["potential"][3]:
                break
            retained.append(p)
        fit = fitBias(retained) if retained else None
        accurate = accurateStep(fit, retained, result["tolerance"]) if retained else None
        plain = None
        for entry in points:
            if entry["step"] != 2 and any(abs(entry[key][2]) >= 2*entry[key][3] for key in keys):
                break
            plain = entry["step"]
        summary[label] = dict(points=points, largestStable=largestStable, fit=fit, accurateStep=accurate, plainStep=plain)
    result["summary"] = summary


def fitBias(points):
    """Weighted least squares of bias(h) = a h^2 + b h^4 (h in fs) through the points: [a, b]."""
    h = np.array([p["step"] for p in points], dtype=float)
    bias = np.array([p["potential"][2] for p in points])
    error = np.array([p["potential"][3] for p in points])
    design = np.stack([h**2, h**4], axis=1)/error[:, None]
    if len(h) < 2:
        design = design[:, :1]
    coefficients = np.linalg.lstsq(design, bias/error, rcond=None)[0]
    return [float(c) for c in coefficients] + [0.0]*(2 - len(coefficients))


def accurateStep(fit, points, tolerance):
    """The largest h (0.1 fs grid), up to the largest stable step, with |a h^2 + b h^4| <= tolerance."""
    best = None
    for h in np.arange(1.0, points[-1]["step"] + 1e-9, 0.1):
        if abs(fit[0]*h**2 + fit[1]*h**4) > tolerance:
            break
        best = round(float(h), 1)
    return best


def timing(result, models, state, configs, platform, properties, args):
    """ns/day of each configuration at the integer step at or below its accurate step, interleaved; a
    rigid configuration with its accuracy check on, its default."""
    while True:
        try:
            return timeOnce(result, models, state, configs, platform, properties, args)
        except TimingFailure as failure:
            # A step that fails within the timing's few hundred steps from a fresh start is not one a
            # user can run: it counts as a start that did not run stably (analyse()), and the timing
            # starts again with that configuration's accurate step below it.
            label, step, _ = failure.label
            say(f"  {label} at {step} fs: unstable while timed ({str(failure.error)[:90]}); its accurate step is now below")
            result.setdefault("timingFailures", {}).setdefault(label, []).append(step)
            analyse(result)


def timeOnce(result, models, state, configs, platform, properties, args):
    # Each configuration in --timing-contexts Contexts of their own (velocities drawn with their own
    # seeds), their blocks pooled: two Contexts of one configuration, timed side by side, differ by up
    # to 4 % on this machine (the layout each one's memory and neighbour list happen to get), which one
    # Context per configuration would put into the ratios.
    integrators, contexts = {}, []

    def bind(key, integrator, config, seed):
        context = openmm.Context(models.of(config)[0], integrator, platform, properties)
        context.setState(state)
        # Velocities for this configuration's masses and moments, as in its runs: the start's, drawn
        # for the particles' own, would give raised moments a rotation I'/I times too hot, which a
        # step near the largest stable one does not survive.
        context.setVelocitiesToTemperature(TEMPERATURE, seed)
        integrators[key] = integrator
        contexts.append(context)

    for label, config in configs.items():
        step = result["summary"][label]["accurateStep"]
        if not step:
            continue
        step = int(np.floor(step))
        for copy in range(args.timing_contexts):
            seed = 5 + copy
            bind((label, step, copy), makeIntegrator(config, step, seed, models.of(config)[1]), config, seed)
    wall, _ = timeInterleaved(integrators, args.timing_steps, args.timing_repetitions)
    result["timed"] = {}
    for label, config in configs.items():
        keys = [key for key in wall if key[0] == label]
        if not keys:
            continue
        step = keys[0][1]
        entry = result["summary"][label]
        seconds = float(np.median([t for key in keys for t in wall[key]]))
        timed = dict(step=step, msPerStep=1000*seconds, contexts=len(keys), blocks=len(keys)*args.timing_repetitions)
        entry.update(timedStep=step, msPerStep=timed["msPerStep"], nsPerDay=nsPerDay(step, timed["msPerStep"]/1000))
        result["timed"][label] = timed
        say(f"  {label} at {step} fs: {entry['msPerStep']:.2f} ms/step, {entry['nsPerDay']:.1f} ns/day")


def perWallHour(entry):
    """D, tau_1 and tau_U of a configuration (means over its runs at steps up to the accurate step:
    they are properties of the dynamics, which the step changes little there, and one run's estimate
    of tau_U scatters by a factor 2), and what an hour of wall time gives: simulated ps, effective
    samples of U (ps / 2 tau_U), rotational correlation times (ps / tau_1) and D t (1e-5 cm^2/s ps)."""
    near = [p for p in entry["points"] if p["step"] <= entry["accurateStep"]] or entry["points"][:1]
    D, tauRot, tauU = (float(np.mean([p[key] for p in near])) for key in ("D", "tauRot", "tauU"))
    ps = entry["nsPerDay"]*1000/24
    return dict(D=D, tauRot=tauRot, tauU=tauU, ps=ps, samples=ps/(2*tauU), rotations=ps/tauRot, diffusion=D*ps)


# ---------------------------------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------------------------------


def report(results, quick):
    document = ResultsDocument("inertia_sampling", "Sampling speed with raised moments of inertia", quick=quick,
                               about=__doc__.split("\n\n")[0].replace("\n", " "))
    for result in results:  # each analysed by resultOf()
        document.section(result["title"])
        history = result.get("history", [])
        if history:
            document.text(f"Runs that made these samples ({result['store']}; runs added): "
                          + "; ".join(SampleStore.describeRun(run) for run in history) + ".")
        if "potential" not in result["reference"]:
            document.text("No run at 2 fs has finished yet: no reference, nothing to compare.")
            continue
        reference = result["reference"]["potential"]
        check = result.get("referenceCheck")
        rigidReference = result.get("rigidReference", {}).get("potential")
        document.text(f"Reference U/water {reference[0]:.3f} +- {reference[1]:.3f} kJ/mol (pooled 2 fs runs"
                      + (f"; stock - rigid at 2 fs: {check[0]:+.3f} +- {check[1]:.3f}" if check else "")
                      + (f" of stock; the rigid integrator's model, whose solute is one body without its internal terms: "
                         f"{rigidReference[0]:.3f} +- {rigidReference[1]:.3f}, its own 2 fs runs" if rigidReference else "")
                      + "). "
                      f"Tolerance {result['tolerance']:g} kJ/mol per water; {result['waters']} waters; starts per configuration: "
                      + ", ".join(f"{label} {count}" for label, count in result["starts"].items()) + ".")
        rows = []
        shell = any("gShell" in p for entry in result["summary"].values() for p in entry["points"])
        biasOf = lambda p, key: f"{p[key][2]:+.3f} ({p[key][2]/p[key][3]:+.1f} sigma)"
        for label, entry in result["summary"].items():
            for p in entry["points"]:
                rows.append([label, f"{p['step']:g}", f"{p['potential'][0]:.3f} +- {p['potential'][1]:.3f}", biasOf(p, "potential")]
                            + ([f"{p['gShell'][0]:.3f}", biasOf(p, "gShell")] if shell else [])
                            + [f"{p['temperature'][0]:.1f}", f"{p['D']:.2f}", f"{p['tauRot']:.2f}", f"{p['tauU']:.2f}"])
            failures = sorted({(r["step"], r["failure"]) for r in result["runs"] if r["config"] == label and r["failure"]})
            for step, failure in failures[:1]:
                rows.append([label, f"{step:g}", "unstable: " + failure[:70]] + [""]*(7 if shell else 5))
        document.table(["configuration", "step (fs)", "U/water (kJ/mol)", "bias"]
                       + ([f"g_OO, {G_SHELL[0]:g}-{G_SHELL[1]:g} nm", "its bias"] if shell else [])
                       + ["T (K)", "D (1e-5 cm^2/s)", "tau_1 (ps)", "tau_U (ps)"], rows)
        if shell:
            document.text(f"g_OO: the mean of the oxygens' g(r) over {G_SHELL[0]:g} to {G_SHELL[1]:g} nm, about its first peak "
                          "(shellPairDensity()); the 2-sigma rule reads it with U (and the density in NPT).")
        for label, entry in result["summary"].items():
            timed = result.get("timed", {}).get(label)
            if timed and entry["accurateStep"]:
                # A report made again with another rule: the cost per step measured at the timed step,
                # at the integer step below this accurate step (marked with * where they differ).
                step = int(np.floor(entry["accurateStep"]))
                entry.update(timedStep=step, msPerStep=timed["msPerStep"], nsPerDay=nsPerDay(step, timed["msPerStep"]/1000),
                             rescaled=step != timed["step"])
        hours = {label: perWallHour(entry) for label, entry in result["summary"].items() if "nsPerDay" in entry}
        stock, heavy = hours.get("stock"), hours.get("stock-heavy")
        rows = []
        for label, entry in result["summary"].items():
            if label not in hours:
                rows.append([label] + ["-"]*9)
                continue
            hour = hours[label]
            rows.append([label, f"{entry['accurateStep']:g}", f"{entry['plainStep']}",
                         f"{entry['timedStep']}" + (f" (*timed at {result['timed'][label]['step']})" if entry.get("rescaled") else ""),
                         f"{entry['msPerStep']:.2f}", f"{entry['nsPerDay']:.1f}",
                         f"{entry['nsPerDay']/result['summary']['stock']['nsPerDay']:.2f}" if stock else "-",
                         f"{entry['nsPerDay']/result['summary']['stock-heavy']['nsPerDay']:.2f}" if heavy else "-",
                         f"{hour['D']:.2f} / {hour['tauRot']:.2f} / {hour['tauU']:.2f}",
                         " / ".join(f"{hour[key]/stock[key]:.2f}" for key in ("samples", "diffusion", "rotations")) if stock else "-"])
        document.table(["configuration", "accurate step (fit, fs)", "2-sigma rule (fs)", "timed at (fs)", "ms/step", "ns/day",
                        "vs stock", "vs stock heavy-H", "D / tau_1 / tau_U (mean of runs to that step)",
                        "per wall-hour vs stock: U samples / D t / rotations"], rows)
        if result.get("timingFailures"):
            document.text("Unstable while timed (a fresh start, a few hundred steps), so not counted as stable from every "
                          "start: " + "; ".join(f"{label} at {', '.join(f'{s:g}' for s in steps)} fs"
                                                for label, steps in result["timingFailures"].items()) + ".")
        # A timing kept in a store from before the accuracy check read samples has a rigid configuration's
        # ms/step weighted from two: a step with the check off, and one of a twin that measured the shadow
        # work at every step, standing in for a step in the check's episodes (which then evaluated the
        # energy); a new timing (--retime) times the check as users run it.
        split = {label: t for label, t in result.get("timed", {}).items() if "msPaused" in t}
        notes = []
        if split:
            notes.append("ms/step of a rigid configuration was timed before the accuracy check read samples, as a long "
                         "run with the check on: the cost of a step with the check off and of one in its episodes (then "
                         "an energy evaluation every step, timed by a twin measuring the shadow work at every step), "
                         "weighted by the share of steps the check measured; "
                         + "; ".join(f"{label} {t['msPaused']:.2f} and {t['msEpisode']:.2f} ms, {100*t['checkDuty']:.0f} %"
                                     for label, t in split.items()))
        elif result.get("timed"):
            notes.append("ms/step of a rigid configuration with the accuracy check on, its default: its episodes cost "
                         "within noise of a step without it (docs/results/accuracy_check_cost.md)")
        if result.get("retimed"):
            notes.append("Timed again: " + "; ".join(result["retimed"]))
        if notes:
            document.text(". ".join(notes) + ".")
        figure = plot(result, document.figurePath(f"inertia_sampling_{result['name']}.png"))
        if figure:
            document.figure(figure, f"{result['title']}: bias of U against step, and ns/day at the accurate step")
    document.write()


def plot(result, path):
    plt = pyplot()
    if plt is None:
        return None
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for label, entry in result["summary"].items():
        if not entry["points"]:
            continue
        h = np.array([p["step"] for p in entry["points"]])
        bias = np.array([p["potential"][2] for p in entry["points"]])
        error = np.array([p["potential"][3] for p in entry["points"]])
        line = left.errorbar(h, bias, yerr=error, marker="o", linestyle="none", label=label, capsize=3)
        grid = np.linspace(0, h.max(), 100)
        a, b = entry["fit"]
        left.plot(grid, a*grid**2 + b*grid**4, color=line[0].get_color(), alpha=0.6)
    tolerance = result["tolerance"]
    left.axhspan(-tolerance, tolerance, color="0.9")
    left.set_xlabel("step (fs)")
    left.set_ylabel("U/water - reference (kJ/mol)")
    left.legend(fontsize=8)
    labels = [label for label, entry in result["summary"].items() if "nsPerDay" in entry]
    right.bar(labels, [result["summary"][label]["nsPerDay"] for label in labels], color="tab:blue")
    right.set_ylabel("ns/day at the accurate step")
    right.tick_params(axis="x", labelrotation=20, labelsize=8)
    figure.suptitle(result["title"])
    figure.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.savefig(path, dpi=110)
    plt.close(figure)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--systems", nargs="+", default=["tip3p-nvt"], choices=list(SYSTEMS))
    parser.add_argument("--floors", nargs="+", type=float, default=[0.04], help="minimum moments to try (amu nm^2)")
    parser.add_argument("--starts", type=int, default=2, help="starts every configuration and step is to have (in total, over runs)")
    parser.add_argument("--time", type=float, default=20.0, help="ps sampled per run")
    parser.add_argument("--discard", type=float, default=2.0, help="ps discarded per run")
    parser.add_argument("--equilibrate", type=float, default=20.0, help="ps of stock NPT equilibration")
    parser.add_argument("--tolerance", type=float, default=0.1, help="accepted |bias| of U per water (kJ/mol)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, default=0, help="CPU threads per worker")
    parser.add_argument("--workers", type=int, default=1, help="worker processes running at once")
    parser.add_argument("--hours", type=float, default=None, help="start no run after this long (the report is still written)")
    parser.add_argument("--no-timing", action="store_true", help="leave the timing for a run on a quiet machine")
    parser.add_argument("--timing-steps", type=int, default=100)
    parser.add_argument("--timing-repetitions", type=int, default=7)
    parser.add_argument("--timing-contexts", type=int, default=2, help="Contexts timed per configuration, pooled")
    parser.add_argument("--quick", action="store_true", help="a smoke check: short runs, few steps, one start, a fresh store")
    parser.add_argument("--report", action="store_true", help="only write the report from the stores")
    parser.add_argument("--retime", action="store_true",
                        help="time the systems of --systems again (their sampling kept), then write the report")
    args = parser.parse_args()
    if args.quick:
        args.starts, args.time, args.discard, args.equilibrate = 1, 2.0, 0.5, 2.0
        args.timing_steps, args.timing_repetitions = 10, 3
    folder = RESULTS/("quick" if args.quick else "full")
    folder.mkdir(parents=True, exist_ok=True)
    stores = RESULTS/"quick"/"stores" if args.quick else STORES
    if not args.report:
        openLog(folder/("retime.txt" if args.retime else "log.txt"))
        platform = openmm.Platform.getPlatformByName(args.platform)
        properties = cpuProperties(platform, args.threads)
        for name in args.systems:
            if args.quick and (stores/name).exists():
                shutil.rmtree(stores/name)
            store = storeOf(name, args)
            if args.retime:
                timeSystem(name, store, resultOf(name, store, args.tolerance), args, platform, properties)
            else:
                runSystem(name, args, platform, properties)
    results = [resultOf(path.parent.name, SampleStore(path.parent), args.tolerance)
               for path in sorted(stores.glob("*/store.json")) if path.parent.name in SYSTEMS]
    for result in results:
        (folder/f"{result['name']}.json").write_text(json.dumps(result, indent=1))
    report([result for result in results if result["runs"]], args.quick)


if __name__ == "__main__":
    sys.exit(main())

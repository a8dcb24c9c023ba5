#!/usr/bin/env python
"""Configurational accuracy against step size at constant temperature (and pressure):
RigidBodyLangevinIntegrator (Exact rotation, and NoSquish) next to LangevinMiddleIntegrator + SETTLE.

Systems (openmm.app ForceField and Modeller, amber14 force fields, PME with a 0.9 nm cutoff and
ewaldErrorTolerance 5e-4, CMMotionRemover, 300 K, friction 1/ps; NPT: MonteCarloBarostat at 1 bar
every 25 steps):

- tip3p-nvt, tip3p-npt: 500 rigid TIP3P waters;
- tip4pew-nvt, tip4pew-npt: 500 rigid TIP4P-Ew waters;
- protein: alanine dipeptide (amber14-all, rigidtesting.alanineDipeptide()) in 500 rigid TIP3P
  waters, NPT, constraints=HBonds, hydrogenMass=3 amu. RigidBodyLangevinIntegrator moves the waters
  as rigid bodies and the peptide as free atoms with its bonds to hydrogen constrained.

Each model is minimized and equilibrated once, NPT, with LangevinMiddleIntegrator + SETTLE at 2 fs;
the NVT box is that state without the barostat. From that one state, every integrator runs at every
step of `--steps` (1, 2, 4, 6, 8, 10 fs for water, 1 to 6 fs for the protein): `--discard` ps
thrown away, then `--time` ps sampled every 0.1 ps:

- the potential energy per water (for the protein: the total potential energy divided by the
  number of waters, so that it reads on the same scale);
- the density (NPT), from the box volume;
- the temperature each integrator reports, 2 KE / (dof R) with the State's kinetic energy and the
  integrator's degrees of freedom: for LangevinMiddleIntegrator counted as app.StateDataReporter
  counts them (3 per massive particle, less the constraints, less 3 for the CMMotionRemover), for
  RigidBodyLangevinIntegrator those of its bodies and free particles (benchmarking.rigidDegreesOfFreedom:
  the count its computeSystemTemperature() uses);
- every 0.2 ps the water oxygens, for g_OO(r) (minimum image in the cubic box, 0.005 nm bins).

Errors are standard errors of the mean from block means: the larger of the 5-block and 10-block
estimates, since the density under a Monte Carlo barostat correlates over picoseconds.

Reference: the 1 fs runs of LangevinMiddleIntegrator and of RigidBodyLangevinIntegrator (Exact),
pooled (the mean of the two means). Both sample the same model (the same rigid water, the same
constraints), their step-size errors at 1 fs are a sixteenth of those at 4 fs, and pooling two
independent runs halves the reference's variance; the table gives their difference as a check.
NoSquish is run from 4 fs up only: below that its rotation error is far below the noise.

A run agrees with the reference if its U/molecule (and, NPT, its density) differ from the
reference's by less than 2 combined standard errors. For each integrator, the largest step that
agrees, with every smaller step it was run at agreeing too; an integrator that is unstable at a step
(an exception, or a non-finite energy) is not run at larger ones. Then, side by side in the same
process, the cost: each integrator timed at its largest agreeing step (and all at 4 fs; with --retime
also at the pooled water boxes' steps, and for the protein at each one's largest stable step), several
repetitions of a fixed number of steps taken in turn, medians; ns/day, and the ratio of ns/day at
equal accuracy (rigid at its largest agreeing step over stock at its own).

    python benchmarks/nvt_accuracy.py --quick                       # smoke check, 2 systems, about 2 minutes
    python benchmarks/nvt_accuracy.py --systems tip3p-nvt tip3p-npt protein --threads 1 &
    python benchmarks/nvt_accuracy.py --systems tip4pew-nvt tip4pew-npt --threads 1 &
    python benchmarks/nvt_accuracy.py --report                      # assemble the results of both

Each system's results go to benchmarks/results/nvt_accuracy/<mode>/<system>.json (mode: full or
quick) with a log next to them; after a run (or with --report) the report is assembled from every
system saved in that mode: a full run writes docs/results/nvt_accuracy.md and
docs/figures/nvt_accuracy_<system>.png, a quick one writes them under benchmarks/results/nvt_accuracy/quick/.
"""

import argparse
import datetime
import json
import os
import sys
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from benchmarking import (RESULTS as BENCHMARK_RESULTS, ROOT, Progress, ResultsDocument, blockMean, commit, command,
                          machine, nsPerDay, openLog, pyplot, radialDistribution, rigidDegreesOfFreedom, say, stamp)
import rigidtesting  # tests/python, on the path benchmarking sets

RESULTS = BENCHMARK_RESULTS/"nvt_accuracy"

TEMPERATURE = 300*unit.kelvin
FRICTION = 1/unit.picosecond
PRESSURE = 1*unit.bar
BAROSTAT_INTERVAL = 25
MOLECULES = 500
SAMPLE_EVERY = 0.1     # ps
FRAME_EVERY = 2        # samples
RDF_MAX, RDF_BIN = 0.9, 0.005   # nm
RDF_FROM = 0.24        # nm: below it g_OO is zero
AGREEMENT = 2.0        # combined standard errors
NOSQUISH_FROM = 4.0    # fs
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
AMU_PER_NM3_IN_G_PER_ML = 1.66053906660e-3   # 1 amu/nm^3 in g/mL

SYSTEMS = {
    "tip3p-nvt": dict(model="tip3p", npt=False, protein=False, title="TIP3P, 500 waters, NVT"),
    "tip3p-npt": dict(model="tip3p", npt=True, protein=False, title="TIP3P, 500 waters, NPT"),
    "tip4pew-nvt": dict(model="tip4pew", npt=False, protein=False, title="TIP4P-Ew, 500 waters, NVT"),
    "tip4pew-npt": dict(model="tip4pew", npt=True, protein=False, title="TIP4P-Ew, 500 waters, NPT"),
    "protein": dict(model="tip3p", npt=True, protein=True,
                    title="alanine dipeptide in 500 TIP3P waters, HBonds, HMR 3 amu, NPT"),
}
WATER_STEPS = [1, 2, 4, 6, 8, 10]
PROTEIN_STEPS = [1, 2, 3, 4, 5, 6]
INTEGRATORS = {"stock": "LangevinMiddleIntegrator + SETTLE", "exact": "RigidBodyLangevinIntegrator (Exact)",
               "nosquish": "RigidBodyLangevinIntegrator (NoSquish)"}

# ---------------------------------------------------------------------------------------------------
# Systems
# ---------------------------------------------------------------------------------------------------


def buildModel(model, protein):
    """Topology, positions and the NPT System of one model (the barostat is the last force)."""
    options = dict(constraints=app.HBonds, hydrogenMass=3*unit.amu) if protein else dict(constraints=None)
    topology, positions, system = rigidtesting.waterBox(
        model, molecules=MOLECULES, forceField=["amber14-all.xml", f"amber14/{model}.xml"],
        solute=rigidtesting.alanineDipeptide() if protein else None, **options)
    system.addForce(openmm.MonteCarloBarostat(PRESSURE, TEMPERATURE, BAROSTAT_INTERVAL))
    return topology, positions, system


def withoutBarostat(system):
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    copy.removeForce(copy.getNumForces() - 1)
    return copy


class Analysis:
    """What the samples are reduced with: the waters' oxygens, their count, the total mass."""

    def __init__(self, topology, system):
        waters = [residue for residue in topology.residues() if residue.name == "HOH"]
        self.oxygens = np.array([atom.index for residue in waters for atom in residue.atoms()
                                 if atom.element == app.element.oxygen])
        self.waters = len(waters)
        self.totalMass = sum(system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles()))


def stockDegreesOfFreedom(system):
    """The degrees of freedom app.StateDataReporter counts."""
    dof = 3*sum(1 for i in range(system.getNumParticles()) if system.getParticleMass(i) > 0*unit.dalton)
    dof -= sum(1 for i in range(system.getNumConstraints())
               if system.getParticleMass(system.getConstraintParameters(i)[0]) > 0*unit.dalton
               or system.getParticleMass(system.getConstraintParameters(i)[1]) > 0*unit.dalton)
    if any(isinstance(system.getForce(i), openmm.CMMotionRemover) for i in range(system.getNumForces())):
        dof -= 3
    return dof


def equilibrate(system, positions, platform, properties, picoseconds):
    """Minimize, then NPT with LangevinMiddleIntegrator + SETTLE at 2 fs; the final State."""
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, 2*unit.femtoseconds)
    integrator.setRandomNumberSeed(1)
    system.getForce(system.getNumForces() - 1).setRandomNumberSeed(1)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 500)
    context.setVelocitiesToTemperature(TEMPERATURE, 1)
    integrator.step(int(round(picoseconds/0.002)))
    return context.getState(getPositions=True, getVelocities=True)


# ---------------------------------------------------------------------------------------------------
# Runs
# ---------------------------------------------------------------------------------------------------


def makeIntegrator(kind, stepFs, seed):
    dt = stepFs*unit.femtoseconds
    if kind == "stock":
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, dt)
    else:
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, dt)
        integrator.setRotationMethod(openmmrigid.RigidBodyLangevinIntegrator.Exact if kind == "exact"
                                     else openmmrigid.RigidBodyLangevinIntegrator.NoSquish)
    integrator.setRandomNumberSeed(seed)
    return integrator


def makeContext(system, state, kind, stepFs, seed, platform, properties, npt):
    if npt:
        system.getForce(system.getNumForces() - 1).setRandomNumberSeed(seed + 1)
    integrator = makeIntegrator(kind, stepFs, seed)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    return context, integrator


def simulate(system, state, analysis, kind, stepFs, seed, npt, discard, production, platform, properties):
    """One run. Returns the samples (dict of lists), the oxygen frames and box edges, ms per step, and
    a failure message (empty if it finished)."""
    context, integrator = makeContext(system, state, kind, stepFs, seed, platform, properties, npt)
    dof = rigidDegreesOfFreedom(context, integrator) if kind != "stock" else stockDegreesOfFreedom(system)
    dtPs = stepFs/1000
    perSample = max(1, int(round(SAMPLE_EVERY/dtPs)))
    samples = max(10, int(round(production/(perSample*dtPs))))
    discardSteps = int(round(discard/dtPs))
    data = {"potential": [], "density": [], "temperature": []}
    frames, edges = [], []
    progress = Progress(f"{INTEGRATORS[kind]} {stepFs:g} fs", discardSteps + samples*perSample)
    stepping, failure = 0.0, ""
    try:
        for done in range(0, discardSteps, perSample):
            integrator.step(min(perSample, discardSteps - done))
            progress.update(done + perSample)
        for sample in range(samples):
            start = time.perf_counter()
            integrator.step(perSample)
            stepping += time.perf_counter() - start
            wantFrame = (sample + 1) % FRAME_EVERY == 0
            current = context.getState(getEnergy=True, getPositions=wantFrame)
            box = current.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
            potential = current.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/analysis.waters
            kinetic = current.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
            if not (np.isfinite(potential) and np.isfinite(kinetic)) or potential > 0:
                failure = f"energy {potential:.3g} kJ/mol per water after {discard + (sample + 1)*perSample*dtPs:.2f} ps"
                break
            data["potential"].append(potential)
            data["density"].append(analysis.totalMass/np.linalg.det(box)*AMU_PER_NM3_IN_G_PER_ML)
            data["temperature"].append(2*kinetic/(dof*BOLTZMANN))
            if sample == 0 and hasattr(integrator, "computeSystemTemperature"):
                # The State's kinetic energy and this dof give what StateDataReporter prints.
                reported = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
                if abs(reported - data["temperature"][0]) > 1e-6*reported:
                    say(f"  note: computeSystemTemperature() {reported:.4f} K, 2 KE/(dof R) {data['temperature'][0]:.4f} K")
            if wantFrame:
                frames.append(current.getPositions(asNumpy=True).value_in_unit(unit.nanometer)[analysis.oxygens])
                edges.append(np.diag(box).copy())
            progress.update(discardSteps + (sample + 1)*perSample)
    except openmm.OpenMMException as error:
        failure = str(error).splitlines()[0][:160]
    msPerStep = 1000*stepping/max(1, len(data["potential"])*perSample)
    return data, np.array(frames), np.array(edges), msPerStep, failure


def timeIntegrators(system, state, configurations, npt, platform, properties, steps, repetitions):
    """Seconds per step of each (kind, step) configuration: `repetitions` rounds in which each
    configuration takes `steps` steps in turn, medians."""
    contexts = {}
    for kind, stepFs in configurations:
        context, integrator = makeContext(system, state, kind, stepFs, 5, platform, properties, npt)
        integrator.step(20)
        contexts[(kind, stepFs)] = (context, integrator)
    times = {key: [] for key in contexts}
    for _ in range(repetitions):
        for key, (context, integrator) in contexts.items():
            start = time.perf_counter()
            integrator.step(steps)
            context.getState(getEnergy=True)
            times[key].append((time.perf_counter() - start)/steps)
    return {key: float(np.median(values)) for key, values in times.items()}


# ---------------------------------------------------------------------------------------------------
# Analysis
# ---------------------------------------------------------------------------------------------------


def summarize(data, frames, edges):
    """Means and errors of one run; g(r) as its mean and error per bin."""
    summary = {key: blockMean(values) for key, values in data.items()}
    radii, g = radialDistribution(frames, edges, RDF_MAX, RDF_BIN)
    gMean, gError = blockMean(g)
    return {key: [float(v[0]), float(v[1])] for key, v in summary.items()}, radii, gMean, gError


def compareToReference(run, reference, window):
    """Differences from the reference (value, combined error), g_OO first-peak height and chi^2 per bin."""
    comparison = {}
    for key in ("potential", "density", "temperature"):
        mean, error = run["summary"][key]
        comparison[key] = [mean - reference[key][0], float(np.hypot(error, reference[key][1]))]
    g, gError = np.array(run["g"]), np.array(run["gError"])
    peak = float(g[window].mean())
    # The error of a mean over neighbouring bins, taken as that of one bin (they correlate).
    comparison["peak"] = [peak - reference["peak"][0], float(np.hypot(gError[window].mean(), reference["peak"][1]))]
    run["peak"] = [peak, float(gError[window].mean())]
    radii = np.array(run["radii"])
    useful = (radii > RDF_FROM) & (reference["gError"] > 0)
    chi = (g - reference["g"])[useful]/np.hypot(gError, reference["gError"])[useful]
    comparison["gChi2"] = float(np.mean(chi**2))
    return comparison


def reference(runs):
    """The pooled 1 fs reference: the mean of the 1 fs runs of stock and Exact."""
    ones = [run for run in runs if run["step"] == 1 and run["kind"] in ("stock", "exact") and not run["failure"]]
    pooled = {}
    for key in ("potential", "density", "temperature"):
        pooled[key] = [float(np.mean([r["summary"][key][0] for r in ones])),
                       float(np.sqrt(sum(r["summary"][key][1]**2 for r in ones))/len(ones))]
    pooled["g"] = np.mean([r["g"] for r in ones], axis=0)
    pooled["gError"] = np.sqrt(np.sum([np.array(r["gError"])**2 for r in ones], axis=0))/len(ones)
    radii = np.array(ones[0]["radii"])
    inPeak = (radii > 0.25) & (radii < 0.32)
    top = np.argmax(np.where(inPeak, pooled["g"], -1))
    window = np.zeros(len(radii), dtype=bool)
    window[top - 1:top + 2] = True
    pooled["peak"] = [float(pooled["g"][window].mean()), float(pooled["gError"][window].mean())]
    pooled["peakRadius"] = float(radii[top])
    return pooled, window, ones


def agrees(comparison, npt):
    keys = ("potential", "density") if npt else ("potential",)
    return all(abs(comparison[key][0]) < AGREEMENT*comparison[key][1] for key in keys)


def largestAgreeing(runs, kind, npt):
    """The largest step of `kind` that agrees with the reference, every smaller step it ran at agreeing too."""
    best = None
    for run in sorted((r for r in runs if r["kind"] == kind), key=lambda r: r["step"]):
        if run["failure"] or not (run["step"] == 1 or agrees(run["comparison"], npt)):
            break
        best = run["step"]
    return best


# ---------------------------------------------------------------------------------------------------
# One system
# ---------------------------------------------------------------------------------------------------


def runSystem(name, state, topology, npt_system, args, platform, properties, steps):
    spec = SYSTEMS[name]
    system = npt_system if spec["npt"] else withoutBarostat(npt_system)
    analysis = Analysis(topology, system)
    started = time.perf_counter()
    say()
    stamp(f"{name}: {spec['title']}; {system.getNumParticles()} particles, {analysis.waters} waters")
    runs = []
    for kind in ("stock", "exact", "nosquish"):
        for index, stepFs in enumerate(steps):
            if kind == "nosquish" and stepFs < NOSQUISH_FROM:
                continue
            if any(r["kind"] == kind and r["failure"] for r in runs):
                say(f"  {INTEGRATORS[kind]} {stepFs:g} fs: not run (unstable at a smaller step)")
                continue
            seed = 1000 + 100*list(INTEGRATORS).index(kind) + index
            data, frames, edges, ms, failure = simulate(system, state, analysis, kind, stepFs, seed, spec["npt"],
                                                        args.discard, args.time, platform, properties)
            run = dict(kind=kind, step=stepFs, ms=ms, failure=failure)
            if failure or len(frames) < 4:
                run["failure"] = failure or "too few samples"
                say(f"  {INTEGRATORS[kind]} {stepFs:g} fs: unstable ({run['failure']})")
            else:
                summary, radii, gMean, gError = summarize(data, frames, edges)
                run.update(summary=summary, radii=radii.tolist(), g=gMean.tolist(), gError=gError.tolist(),
                           series={key: [round(v, 6) for v in values] for key, values in data.items()})
                say(f"  {INTEGRATORS[kind]} {stepFs:g} fs: U/water {summary['potential'][0]:.3f} +- "
                    f"{summary['potential'][1]:.3f} kJ/mol, density {summary['density'][0]:.4f} +- "
                    f"{summary['density'][1]:.4f} g/mL, T {summary['temperature'][0]:.1f} +- "
                    f"{summary['temperature'][1]:.1f} K, {ms:.2f} ms/step")
            runs.append(run)

    pooled, window, ones = reference(runs)
    for run in runs:
        if not run["failure"]:
            run["comparison"] = compareToReference(run, pooled, window)
    best = {kind: largestAgreeing(runs, kind, spec["npt"]) for kind in INTEGRATORS}
    stamp(f"{name}: largest agreeing steps " + ", ".join(f"{k} {v} fs" for k, v in best.items()) + "; timing")
    configurations = timingConfigurations(runs, best)
    seconds = timeIntegrators(system, state, configurations, spec["npt"], platform, properties,
                              args.timing_steps, args.timing_repetitions)
    timing = [dict(kind=kind, step=step, msPerStep=1000*seconds[(kind, step)],
                   nsPerDay=nsPerDay(step, seconds[(kind, step)])) for kind, step in configurations]
    for entry in timing:
        say(f"  {INTEGRATORS[entry['kind']]} {entry['step']:g} fs: {entry['msPerStep']:.2f} ms/step, "
            f"{entry['nsPerDay']:.2f} ns/day")
    reference_ = {key: value for key, value in pooled.items() if key in ("potential", "density", "temperature", "peak",
                                                                          "peakRadius")}
    reference_["runsAgree"] = {key: [ones[0]["summary"][key][0] - ones[-1]["summary"][key][0],
                                     float(np.hypot(ones[0]["summary"][key][1], ones[-1]["summary"][key][1]))]
                               for key in ("potential", "density", "temperature")}
    return dict(name=name, title=spec["title"], npt=spec["npt"], particles=system.getNumParticles(),
                waters=analysis.waters, runs=runs, reference=reference_, best=best, timing=timing,
                seconds=time.perf_counter() - started)


# ---------------------------------------------------------------------------------------------------
# Report
# ---------------------------------------------------------------------------------------------------


def ratios(result):
    """ns/day at the largest agreeing step of each integrator, and each rigid one's over stock's."""
    speed = {entry["kind"]: entry["nsPerDay"] for entry in result["timing"] if entry["step"] == result["best"][entry["kind"]]}
    stock = speed.get("stock")
    return speed, {kind: speed[kind]/stock for kind in ("exact", "nosquish") if kind in speed and stock}


def pooledWater(results):
    """Deviations from the reference averaged over the water boxes, per integrator and step: each
    system's difference, the mean over the systems that have it, its error sqrt(sum sigma^2)/n. A
    step unstable in any box is unstable here. Returns {(kind, step): dict} and the largest agreeing
    step per integrator (the same rule as for one system)."""
    boxes = [r for r in results if r["name"] != "protein"]
    pooled = {}
    for kind in INTEGRATORS:
        for step in sorted({run["step"] for r in boxes for run in r["runs"] if run["kind"] == kind}):
            runs = [next((run for run in r["runs"] if run["kind"] == kind and run["step"] == step), None) for r in boxes]
            if any(run is None or run["failure"] for run in runs):
                pooled[(kind, step)] = dict(failure=True)
                continue
            entry = dict(failure=False, boxes=len(runs))
            for key, systems in (("potential", boxes), ("density", [r for r in boxes if r["npt"]]),
                                 ("temperature", boxes)):
                values = [run["comparison"][key] for run, r in zip(runs, boxes) if r in systems]
                if values:
                    entry[key] = [float(np.mean([v[0] for v in values])),
                                  float(np.sqrt(sum(v[1]**2 for v in values))/len(values))]
            pooled[(kind, step)] = entry
    best, anyAgreeing = {}, {}
    for kind in INTEGRATORS:
        best[kind] = None
        for step in sorted(step for k, step in pooled if k == kind):
            entry = pooled[(kind, step)]
            if entry["failure"] or not (step == 1 or agrees(entry, "density" in entry)):
                break
            best[kind] = step
        # The looser reading: the largest stable step that agrees, whatever a smaller step gave (a
        # 2-sigma test fails one time in twenty by chance, and there are a dozen steps).
        agreeing = [step for k, step in pooled if k == kind and not pooled[(k, step)]["failure"]
                    and (step == 1 or agrees(pooled[(k, step)], "density" in pooled[(k, step)]))]
        anyAgreeing[kind] = max(agreeing) if agreeing else None
    return pooled, best, anyAgreeing


def goal(result):
    return 1.25 if result["name"] == "protein" else 1.5


def fmt(value, error, digits):
    return f"{value:.{digits}f} +- {error:.{digits}f}"


def reportMarkdown(results, meta, figures):
    """The body of the report (after ResultsDocument's header): Markdown lines."""
    lines = [f"Each run: {meta['discard']:g} ps discarded, {meta['time']:g} ps sampled every {SAMPLE_EVERY} ps, "
             "from one equilibrated state per model; 300 K, friction 1/ps; errors are standard errors of the "
             "mean (larger of 5- and 10-block estimates). Reference: the 1 fs runs of LangevinMiddle and of "
             "RigidBodyLangevin (Exact), pooled. \"Agrees\": |U/molecule - ref| (and, NPT, |density - ref|) "
             f"below {AGREEMENT:g} combined standard errors, at this step and every smaller one run.", "",
             "## Headline: ns/day at equal accuracy", "",
             f"ns/day: each integrator timed at its step, the configurations of a system taken in turn "
             f"({meta['timing']}, medians), same platform and threads.", "",
             "| system | stock: largest agreeing step, ns/day | Exact: step, ns/day, ratio | NoSquish: step, ns/day, "
             "ratio | goal | met? |", "| --- | --- | --- | --- | ---: | --- |"]
    for result in results:
        speed, ratio = ratios(result)

        def cell(kind):
            step = result["best"][kind]
            if step is None:
                return "none"
            text = f"{step:g} fs, {speed[kind]:.2f}"
            return text + (f", **{ratio[kind]:.2f}x**" if kind in ratio else "")
        met = ratio.get("exact", 0) >= goal(result)
        lines.append(f"| {result['title']} | {cell('stock')} | {cell('exact')} | {cell('nosquish')} | "
                     f">= {goal(result):g}x | {'yes' if met else '**no**'} |")
    pooled, pooledStrict, pooledAny = pooledWater(results)
    boxes = [r for r in results if r["name"] != "protein"]

    def speedAt(result, kind, step):
        return next((e["nsPerDay"] for e in result["timing"] if e["kind"] == kind and e["step"] == step), None)
    for pooledBest, reading in ((pooledStrict, "every smaller step agreeing"),
                                (pooledAny, "largest agreeing step, smaller ones not required")):
        if len(boxes) < 2:
            break
        cells, pooledRatio = [], {}
        for kind in INTEGRATORS:
            step = pooledBest[kind]
            if step is None:
                cells.append("none")
                continue
            text = f"{step:g} fs"
            if kind != "stock" and pooledBest["stock"] is not None:
                each = [speedAt(r, kind, step)/speedAt(r, "stock", pooledBest["stock"]) for r in boxes
                        if speedAt(r, kind, step) and speedAt(r, "stock", pooledBest["stock"])]
                if len(each) == len(boxes):
                    pooledRatio[kind] = float(np.mean(each))
                    text += f", **{np.mean(each):.2f}x** (mean of the boxes' ratios, {min(each):.2f} to {max(each):.2f})"
                else:
                    text += ", ratio: not timed at this step (run --retime)"
            cells.append(text)
        met = ("yes" if pooledRatio["exact"] >= 1.5 else "**no**") if "exact" in pooledRatio else ""
        lines.append(f"| the {len(boxes)} water boxes pooled (below), {reading} | {cells[0]} | {cells[1]} | {cells[2]} "
                     f"| >= 1.5x | {met} |")
    if len(boxes) > 1:
        lines += ["", f"### Pooled over the {len(boxes)} water boxes", "",
                  "Each box's deviation from its own reference, averaged over the boxes (density: the NPT "
                  "boxes), error sqrt(sum sigma^2)/n; the same agreement rule. Halving the error this way "
                  "resolves what one box cannot, assuming the step-size error has the same sign in "
                  "TIP3P and TIP4P-Ew.", "",
                  "| integrator | step | dU/molecule (kJ/mol) | dU (sigma) | d density (g/mL) | drho (sigma) | "
                  "dT reported (K) | agrees |", "| --- | ---: | ---: | ---: | ---: | ---: | ---: | --- |"]
        for (kind, step), entry in pooled.items():
            if entry["failure"]:
                lines.append(f"| {INTEGRATORS[kind]} | {step:g} fs | unstable in a box | | | | | |")
                continue
            u, t = entry["potential"], entry["temperature"]
            rho = entry.get("density")
            agree = "ref" if step == 1 else ("yes" if agrees(entry, rho is not None) else "no")
            lines.append(f"| {INTEGRATORS[kind]} | {step:g} fs | {u[0]:+.3f} +- {u[1]:.3f} | {u[0]/u[1]:+.1f} | "
                         + (f"{rho[0]:+.4f} +- {rho[1]:.4f} | {rho[0]/rho[1]:+.1f} | " if rho else "| | ")
                         + f"{t[0]:+.1f} +- {t[1]:.1f} | {agree} |")
    lines += ["", "Cost per step at 4 fs (same timing): " + "; ".join(
        f"{r['name']}: " + ", ".join(f"{e['kind']} {e['msPerStep']:.2f} ms" for e in r["timing"] if e["step"] == 4)
        for r in results) + ".", ""]
    for result in results:
        ref = result["reference"]
        lines += [f"## {result['title']}", "",
                  f"{result['particles']} particles, {result['waters']} waters. Reference (pooled 1 fs): "
                  f"U/molecule {fmt(*ref['potential'], 3)} kJ/mol"
                  + (f", density {fmt(*ref['density'], 4)} g/mL" if result["npt"] else "")
                  + f", g_OO first peak {fmt(*ref['peak'], 3)} at {ref['peakRadius']:.4f} nm. "
                  f"The two 1 fs runs (stock - Exact) differ by {fmt(*ref['runsAgree']['potential'], 3)} kJ/mol"
                  + (f" and {fmt(*ref['runsAgree']['density'], 4)} g/mL" if result["npt"] else "") + ".", "",
                  "| integrator | step | U/molecule (kJ/mol) | dU (sigma) | "
                  + ("density (g/mL) | drho (sigma) | " if result["npt"] else "")
                  + "T reported (K) | g_OO peak | g chi2/bin | agrees | ms/step (run) |",
                  "| --- | ---: | ---: | ---: | " + ("---: | ---: | " if result["npt"] else "") + "---: | ---: | ---: | --- | ---: |"]
        for run in result["runs"]:
            name = INTEGRATORS[run["kind"]]
            if run["failure"]:
                cells = [name, f"{run['step']:g} fs", f"unstable: {run['failure'][:90]}"] + [""]*(9 if result["npt"] else 7)
                lines.append("| " + " | ".join(cells) + " |")
                continue
            s, c = run["summary"], run["comparison"]
            sigma = lambda key: f"{c[key][0]:+.{3 if key == 'potential' else 4}f} ({c[key][0]/c[key][1]:+.1f})"
            agree = "ref" if run["step"] == 1 else ("yes" if agrees(c, result["npt"]) else "no")
            lines.append(f"| {name} | {run['step']:g} fs | {fmt(*s['potential'], 3)} | {sigma('potential')} | "
                         + (f"{fmt(*s['density'], 4)} | {sigma('density')} | " if result["npt"] else "")
                         + f"{fmt(*s['temperature'], 1)} | {fmt(*run['peak'], 3)} | {c['gChi2']:.2f} | {agree} | "
                         f"{run['ms']:.2f} |")
        lines += ["", "Timed side by side (medians of the repetitions): " + "; ".join(
            f"{INTEGRATORS[e['kind']]} at {e['step']:g} fs {e['msPerStep']:.2f} ms/step, {e['nsPerDay']:.2f} ns/day"
            for e in result["timing"]) + f". System wall time {result['seconds']/60:.1f} min.", "",
            f"![{result['name']}]({figures[result['name']]})", ""]
    lines += ["## All runs (CSV)", "", "```csv",
              "system,integrator,step_fs,U_per_molecule,U_error,density,density_error,T_reported,T_error,"
              "gOO_peak,gOO_peak_error,g_chi2_per_bin,dU_sigma,drho_sigma,agrees,ms_per_step,failure"]
    for result in results:
        for run in result["runs"]:
            if run["failure"]:
                lines.append(f"{result['name']},{run['kind']},{run['step']:g},,,,,,,,,,,,,,\"{run['failure']}\"")
                continue
            s, c = run["summary"], run["comparison"]
            lines.append(",".join([result["name"], run["kind"], f"{run['step']:g}"]
                                  + [f"{s[k][i]:.6g}" for k in ("potential", "density", "temperature") for i in (0, 1)]
                                  + [f"{run['peak'][0]:.4f}", f"{run['peak'][1]:.4f}", f"{c['gChi2']:.3f}",
                                     f"{c['potential'][0]/c['potential'][1]:.2f}",
                                     f"{c['density'][0]/c['density'][1]:.2f}" if result["npt"] else "",
                                     "ref" if run["step"] == 1 else str(agrees(c, result["npt"])).lower(),
                                     f"{run['ms']:.3f}", ""]))
    lines += ["```", ""]
    return lines


def plot(result, path):
    plt = pyplot()
    panels = [("potential", "U/molecule - ref (kJ/mol)"), ("density", "density - ref (g/mL)"),
              ("temperature", "T reported (K)"), ("peak", "g_OO first peak - ref")]
    if not result["npt"]:
        panels.remove(("density", "density - ref (g/mL)"))
    figure, axes = plt.subplots(1, len(panels), figsize=(4.2*len(panels), 3.8))
    colours = {"stock": "tab:gray", "exact": "tab:blue", "nosquish": "tab:orange"}
    offsets = {"stock": -0.12, "exact": 0.0, "nosquish": 0.12}
    for axis, (key, label) in zip(axes, panels):
        inRange, offScale = [], []
        for kind in INTEGRATORS:
            runs = [r for r in result["runs"] if r["kind"] == kind and not r["failure"]]
            if not runs:
                continue
            x = np.array([r["step"] for r in runs]) + offsets[kind]
            if key == "temperature":
                y = [r["summary"]["temperature"][0] for r in runs]
                e = [2*r["summary"]["temperature"][1] for r in runs]
            else:
                y = [r["comparison"][key][0] for r in runs]
                e = [2*r["comparison"][key][1] for r in runs]
            axis.errorbar(x, y, yerr=e, marker="o", capsize=3, color=colours[kind], label=INTEGRATORS[kind])
            # Scale to the steps up to 8 fs; larger ones that fall outside are marked at the edge.
            inRange += [(v - d, v + d) for r, v, d in zip(runs, y, e) if r["step"] <= 8]
            offScale += [(xi, v, kind) for r, xi, v in zip(runs, x, y) if r["step"] > 8]
            failed = [r["step"] for r in result["runs"] if r["kind"] == kind and r["failure"]]
            for step in failed:
                axis.axvline(step + offsets[kind], color=colours[kind], linestyle=":", linewidth=1)
        axis.axhline(300 if key == "temperature" else 0, color="black", linewidth=0.5)
        if inRange:
            low, high = min(v[0] for v in inRange), max(v[1] for v in inRange)
            low, high = low - 0.15*(high - low), high + 0.15*(high - low)
            axis.set_ylim(low, high)
            for xi, v, kind in offScale:
                if not low <= v <= high:
                    edge = high if v > high else low
                    axis.annotate(f"{v:+.3g}", (xi, edge), xytext=(14*list(INTEGRATORS).index(kind) - 24, -10 if v > high else 4),
                                  textcoords="offset points", ha="center", fontsize=7, color=colours[kind])
        axis.set_xlabel("step (fs)")
        axis.set_ylabel(label)
    axes[0].legend(fontsize=7)
    figure.suptitle(f"{result['title']} (error bars 2 sigma; dotted: unstable; numbers: off scale)", fontsize=10)
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def timingConfigurations(runs, best):
    """What to time: each integrator at its largest agreeing step, and every one stable at 4 fs at 4 fs."""
    stableAt4 = {r["kind"] for r in runs if r["step"] == 4 and not r["failure"]}
    # And, where every step is at most 6 fs (the protein), each at its largest stable step.
    largestStable = {(kind, max(r["step"] for r in runs if r["kind"] == kind and not r["failure"]))
                     for kind in best if max(r["step"] for r in runs) <= 6}
    return sorted({(kind, step) for kind, step in best.items() if step is not None} | {(kind, 4) for kind in stableAt4}
                  | largestStable,
                  key=lambda c: (list(INTEGRATORS).index(c[0]), c[1]))


def retime(mode, args, meta):
    """Time the saved systems again, one process, the configurations of each taken in turn."""
    folder = RESULTS/mode
    names = [name for name in (args.systems or SYSTEMS) if (folder/f"{name}.json").exists()]
    openLog(folder/"nvt_accuracy_retime.log")
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = {"Threads": str(args.threads)} if args.platform == "CPU" else {}
    states = {}
    saved = [json.loads((folder/f"{name}.json").read_text()) for name in SYSTEMS if (folder/f"{name}.json").exists()]
    _, pooledBest, pooledAny = pooledWater(saved)
    for name in names:
        spec = SYSTEMS[name]
        result = json.loads((folder/f"{name}.json").read_text())
        key = (spec["model"], spec["protein"])
        if key not in states:
            topology, positions, system = buildModel(spec["model"], spec["protein"])
            stamp(f"{name}: equilibrating 5 ps for the timing")
            states[key] = (system, equilibrate(system, positions, platform, properties, 5.0))
        npt_system, state = states[key]
        system = npt_system if spec["npt"] else withoutBarostat(npt_system)
        configurations = timingConfigurations(result["runs"], result["best"])
        if not spec["protein"]:
            configurations = sorted(set(configurations) | {(kind, step) for chosen in (pooledBest, pooledAny)
                                                          for kind, step in chosen.items() if step is not None},
                                    key=lambda c: (list(INTEGRATORS).index(c[0]), c[1]))
        seconds = timeIntegrators(system, state, configurations, spec["npt"], platform, properties,
                                  args.timing_steps, args.timing_repetitions)
        result["timing"] = [dict(kind=kind, step=step, msPerStep=1000*seconds[(kind, step)],
                                 nsPerDay=nsPerDay(step, seconds[(kind, step)])) for kind, step in configurations]
        result["meta"]["retime"] = meta["command"]
        result["meta"]["timing"] = f"{args.timing_repetitions} x {args.timing_steps} steps"
        for entry in result["timing"]:
            say(f"  {INTEGRATORS[entry['kind']]} {entry['step']:g} fs: {entry['msPerStep']:.2f} ms/step, "
                f"{entry['nsPerDay']:.2f} ns/day")
        (folder/f"{name}.json").write_text(json.dumps(result))
        say(f"  load average {os.getloadavg()[0]:.1f}")


def writeReport(mode, meta):
    folder = RESULTS/mode
    results = [json.loads((folder/f"{name}.json").read_text()) for name in SYSTEMS if (folder/f"{name}.json").exists()]
    if not results:
        say("no results to report")
        return
    metas = [result["meta"] for result in results]
    meta = dict(metas[0])
    meta["commands"] = sorted({m["command"] for m in metas}, key=lambda c: [m["command"] for m in metas].index(c))
    meta["commands"] += sorted({m["retime"] for m in metas if "retime" in m})
    meta["commands"] += ["python benchmarks/nvt_accuracy.py --report" + (" --quick" if mode == "quick" else "")]
    meta["timing"] = ", ".join(sorted({m.get("timing", "") for m in metas} - {""})) or "5 x 200 steps at the end of each system's runs"
    meta["date"] = ", ".join(sorted({m["date"] for m in metas}))
    figureFolder = ROOT/"docs"/"figures" if mode == "full" else folder
    document = ResultsDocument("nvt_accuracy", "NVT/NPT accuracy against step size: RigidBodyLangevinIntegrator and "
                               "LangevinMiddleIntegrator + SETTLE", quick=mode == "quick", provenance=[
                                   f"date: {meta['date']}", f"commit: {meta['commit']}", f"machine: {meta['machine']}",
                                   f"software: OpenMM {openmm.__version__}",
                                   f"platform: {meta['platform']} ({meta['threads']} thread(s) per process)",
                                   "commands:"], about="```\n" + "\n".join(meta["commands"]) + "\n```")
    if mode == "quick":
        document.path = folder/"nvt_accuracy.md"
    figures = {}
    for result in results:
        path = figureFolder/f"nvt_accuracy_{result['name']}.png"
        plot(result, path)
        figures[result["name"]] = os.path.relpath(path, document.path.parent)
    document.lines += reportMarkdown(results, meta, figures)
    document.write()


# ---------------------------------------------------------------------------------------------------


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="smoke check: tip3p-npt and protein, 1 ps per run")
    parser.add_argument("--systems", nargs="+", choices=list(SYSTEMS), help="default: all (quick: tip3p-npt protein)")
    parser.add_argument("--steps", type=float, nargs="+", help="step sizes in fs, 1 first (default: 1 2 4 6 8 10 for "
                        "water, 1 2 3 4 5 6 for the protein)")
    parser.add_argument("--time", type=float, help="sampled ps per run (default 25; quick 1)")
    parser.add_argument("--discard", type=float, help="ps discarded at the start of each run (default 2; quick 0.5)")
    parser.add_argument("--equilibrate", type=float, help="ps of the shared NPT equilibration (default 20; quick 2)")
    parser.add_argument("--threads", type=int, default=1, help="CPU platform threads (default 1)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--timing-steps", type=int, help="steps per timed repetition (default 200; quick 20)")
    parser.add_argument("--timing-repetitions", type=int, default=5)
    parser.add_argument("--report", action="store_true", help="only assemble the report from saved results")
    parser.add_argument("--retime", action="store_true", help="time the saved systems again (after all runs are done, "
                        "when nothing else of this benchmark runs) and assemble the report")
    args = parser.parse_args()
    mode = "quick" if args.quick else "full"
    defaults = dict(time=(1.0, 25.0), discard=(0.5, 2.0), equilibrate=(2.0, 20.0), timing_steps=(20, 200))
    for key, (quick, full) in defaults.items():
        if getattr(args, key) is None:
            setattr(args, key, quick if args.quick else full)
    systems = args.systems or (["tip3p-npt", "protein"] if args.quick else list(SYSTEMS))
    folder = RESULTS/mode
    folder.mkdir(parents=True, exist_ok=True)
    meta = dict(date=f"{datetime.datetime.now():%Y-%m-%d}", commit=commit(), command=command(), machine=machine(),
                platform=args.platform, threads=args.threads if args.platform == "CPU" else "-",
                time=args.time, discard=args.discard)
    if args.report:
        writeReport(mode, meta)
        return
    if args.retime:
        retime(mode, args, meta)
        writeReport(mode, meta)
        return
    openLog(folder/f"nvt_accuracy_{'_'.join(systems)}.log")
    say(f"{meta['command']}: {datetime.datetime.now():%Y-%m-%d %H:%M}, commit {meta['commit']}, {meta['machine']}, OpenMM "
        f"{openmm.__version__}, platform {args.platform} ({meta['threads']} threads); {args.discard:g} ps discarded and "
        f"{args.time:g} ps sampled per run")
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = {"Threads": str(args.threads)} if args.platform == "CPU" else {}
    states = {}
    for name in systems:
        spec = SYSTEMS[name]
        key = (spec["model"], spec["protein"])
        if key not in states:
            topology, positions, system = buildModel(spec["model"], spec["protein"])
            stamp(f"{spec['model']}{' + alanine dipeptide' if spec['protein'] else ''}: minimizing and equilibrating "
                  f"{args.equilibrate:g} ps NPT (LangevinMiddleIntegrator + SETTLE, 2 fs)")
            states[key] = (topology, system, equilibrate(system, positions, platform, properties, args.equilibrate))
        topology, system, state = states[key]
        steps = args.steps or (PROTEIN_STEPS if spec["protein"] else WATER_STEPS)
        result = runSystem(name, state, topology, system, args, platform, properties, steps)
        result["meta"] = meta
        (folder/f"{name}.json").write_text(json.dumps(result))
        stamp(f"{name} done in {result['seconds']/60:.1f} min; saved {folder/(name + '.json')}")
    writeReport(mode, meta)


if __name__ == "__main__":
    sys.exit(main())

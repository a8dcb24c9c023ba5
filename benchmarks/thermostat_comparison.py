#!/usr/bin/env python
"""Constant temperature and pressure: RigidBodyLangevinIntegrator next to stock LangevinMiddleIntegrator + SETTLE.

One box of about 500 TIP4P-Ew waters (openmm.app, PME with a 0.9 nm cutoff and ewaldErrorTolerance
5e-4, a CMMotionRemover, a MonteCarloBarostat at 1 bar and 300 K every 25 steps), minimized and
equilibrated once with LangevinMiddleIntegrator + SETTLE at 2 fs. From that state four runs at 300 K
with friction 1/ps: RigidBodyLangevinIntegrator (Exact rotation) and stock LangevinMiddleIntegrator
+ SETTLE, each at 2 fs and 4 fs. Each run equilibrates for a while of its own (discarded), then
samples every 0.1 ps:

- the density (g/mL) from the box volume the barostat sets;
- the potential energy per molecule (kJ/mol);
- the translational and rotational temperatures, both computed here in the same way for every
  integrator from the velocities the State holds (centre-of-mass motion of each water, 3N - 3
  degrees of freedom with the CMMotionRemover, and the rest, 3N): RigidBodyLangevinIntegrator's are
  on-step, LangevinMiddleIntegrator's half a step off, as each integrator defines them;
- every 0.2 ps the oxygen positions, for the O-O radial distribution function (numpy, minimum image
  in the cubic box, bins of 0.005 nm up to 1 nm); the table gives the height of its first peak, the
  maximum of each block's mean g(r) averaged over the blocks.

Errors are standard errors of the mean from block averages (10 blocks in the full mode, 5 in the
quick one). The density under a Monte Carlo barostat and the temperatures with friction 1/ps
correlate over picoseconds: the 0.8 ps blocks of the quick mode understate the errors, and even the
6 ps blocks of the full mode may. The table lists each run and, per step size, the difference between the two
integrators in units of its combined error. The plot shows g_OO(r) of the four runs and the
differences with their 2-sigma bands.

    python benchmarks/thermostat_comparison.py            # full: 60 ps per run, about 15 to 20 minutes on 2 cores
    python benchmarks/thermostat_comparison.py --quick    # a smoke check: 4 ps per run, a few minutes

Writes docs/results/thermostat_comparison.md and docs/figures/thermostat_comparison.png (a quick run:
both in benchmarks/results/), and benchmarks/results/thermostat_comparison.csv (the table) and .log
(a copy of what is printed).
"""

import os
import argparse
import sys
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from benchmarking import (RESULTS, ResultsDocument, blockMean, cpuProperties, header, molecularKineticEnergies, openLog,
                          pyplot, radialDistribution, say, saveFigure, stamp, writeCsv)
import rigidtesting  # tests/python, on the path benchmarking sets

TEMPERATURE = 300*unit.kelvin
FRICTION = 1/unit.picosecond
PRESSURE = 1*unit.bar
BAROSTAT_INTERVAL = 25
SAMPLE_EVERY = 0.1     # ps
FRAME_EVERY = 0.2      # ps
RDF_MAX, RDF_BIN = 1.0, 0.005   # nm
AMU_PER_NM3_IN_G_PER_ML = 1.66053906660e-24/1e-21
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)

# ---------------------------------------------------------------------------------------------------
# The box
# ---------------------------------------------------------------------------------------------------

def buildBox(molecules):
    """A cubic box of about `molecules` TIP4P-Ew waters with PME and a MonteCarloBarostat."""
    edge = (molecules/rigidtesting.WATERS_PER_CUBIC_NANOMETRE)**(1/3)
    topology, positions, system = rigidtesting.waterBox("tip4pew", edge=edge)
    barostat = openmm.MonteCarloBarostat(PRESSURE, TEMPERATURE, BAROSTAT_INTERVAL)
    barostat.setRandomNumberSeed(11)
    system.addForce(barostat)
    return topology, positions, system


class Molecules:
    """Index arrays for the per-molecule analysis: the massive atoms of each water, their masses, the oxygens."""

    def __init__(self, topology, system):
        self.atoms, self.oxygens = [], []
        for residue in topology.residues():
            massive = [atom.index for atom in residue.atoms()
                       if system.getParticleMass(atom.index).value_in_unit(unit.dalton) > 0]
            self.atoms.append(massive)
            self.oxygens.extend(atom.index for atom in residue.atoms() if atom.element == app.element.oxygen)
        self.atoms = np.array(self.atoms)                         # (N, 3): O, H, H
        self.particleMasses = rigidtesting.particleMasses(system)
        self.masses = self.particleMasses[self.atoms]
        self.oxygens = np.array(self.oxygens)
        self.count = len(self.atoms)
        self.totalMass = self.masses.sum()


def equilibratedState(system, positions, platform, properties, time_ps, stepFs):
    """Minimize, then equilibrate with LangevinMiddleIntegrator + SETTLE (and the barostat)."""
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, stepFs*unit.femtosecond)
    integrator.setRandomNumberSeed(1)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 500)
    context.setVelocitiesToTemperature(TEMPERATURE, 1)
    integrator.step(int(round(time_ps/(stepFs/1000))))
    return context.getState(getPositions=True, getVelocities=True)


# ---------------------------------------------------------------------------------------------------
# A run
# ---------------------------------------------------------------------------------------------------

def makeIntegrator(kind, stepFs, seed):
    dt = stepFs*unit.femtosecond
    if kind == "rigid":
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, dt)
        integrator.setRotationMethod(openmmrigid.RigidBodyLangevinIntegrator.Exact)
    else:
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, dt)
    integrator.setRandomNumberSeed(seed)
    return integrator


def simulate(system, state, molecules, platform, properties, kind, stepFs, equilibrate_ps, production_ps, seed):
    """One run: returns the samples (dict of arrays), the oxygen frames and boxes, and ms per step."""
    integrator = makeIntegrator(kind, stepFs, seed)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    dt_ps = stepFs/1000
    integrator.step(int(round(equilibrate_ps/dt_ps)))
    perSample = int(round(SAMPLE_EVERY/dt_ps))
    perFrame = int(round(FRAME_EVERY/SAMPLE_EVERY))
    samples = int(round(production_ps/SAMPLE_EVERY))
    data = {name: [] for name in ("density", "potential", "translational", "rotational")}
    frames, boxes = [], []
    stepping = 0.0
    for sample in range(samples):
        start = time.perf_counter()
        integrator.step(perSample)
        stepping += time.perf_counter() - start
        wantFrame = (sample + 1) % perFrame == 0
        current = context.getState(getEnergy=True, getVelocities=True, getPositions=wantFrame)
        box = current.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
        volume = np.linalg.det(box)
        velocities = current.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
        translational, rotational = molecularKineticEnergies(velocities, molecules.particleMasses, molecules.atoms)
        data["density"].append(molecules.totalMass/volume*AMU_PER_NM3_IN_G_PER_ML)
        data["potential"].append(current.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/molecules.count)
        data["translational"].append(2*translational/((3*molecules.count - 3)*BOLTZMANN))
        data["rotational"].append(2*rotational/(3*molecules.count*BOLTZMANN))
        if wantFrame:
            frames.append(current.getPositions(asNumpy=True).value_in_unit(unit.nanometer)[molecules.oxygens])
            boxes.append(np.diag(box).copy())
    return {k: np.array(v) for k, v in data.items()}, np.array(frames), np.array(boxes), 1000*stepping/(samples*perSample)


# ---------------------------------------------------------------------------------------------------
# Analysis
# ---------------------------------------------------------------------------------------------------

def firstPeak(radii, g):
    """Height and position of the first maximum of g_OO (between 0.25 and 0.32 nm)."""
    window = (radii > 0.25) & (radii < 0.32)
    index = np.argmax(g[..., window], axis=-1)
    return g[..., window].max(axis=-1), radii[window][index]


# ---------------------------------------------------------------------------------------------------

NAMES = {"rigid": "RigidBodyLangevinIntegrator (Exact)", "stock": "LangevinMiddleIntegrator + SETTLE"}
QUANTITIES = [("density", "density (g/mL)", 4), ("potential", "U/molecule (kJ/mol)", 3),
              ("translational", "T trans (K)", 1), ("rotational", "T rot (K)", 1), ("peak", "g_OO peak", 3)]


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="a smoke check: 4 ps per run instead of 60, after 5 ps of shared equilibration")
    parser.add_argument("--molecules", type=int, default=500, help="approximate number of waters (default 500)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's)")
    args = parser.parse_args()
    # The shared start: minimized, then equilibrated (the minimized box relaxes over several ps with
    # friction 1/ps; the quick mode takes 4 fs steps). Each run then discards a
    # while of its own before sampling.
    args.equilibrate, args.production, args.blocks, args.initial, args.initialStep = \
        (1.0, 4.0, 5, 5.0, 4) if args.quick else (5.0, 60.0, 10, 20.0, 2)
    return args


def runAll(args, platform, properties):
    """The shared equilibration, then the four runs (each integrator at 2 and 4 fs)."""
    topology, positions, system = buildBox(args.molecules)
    molecules = Molecules(topology, system)
    say(f"{molecules.count} TIP4P-Ew waters, PME, MonteCarloBarostat (1 bar, every {BAROSTAT_INTERVAL} steps), "
        f"300 K, friction 1/ps; each run: {args.equilibrate:g} ps discarded, {args.production:g} ps sampled; "
        f"errors from {args.blocks} block means")
    stamp(f"minimizing and equilibrating {args.initial:g} ps with LangevinMiddleIntegrator + SETTLE at "
          f"{args.initialStep} fs")
    state = equilibratedState(system, positions, platform, properties, args.initial, args.initialStep)
    runs = []
    for stepFs in (2, 4):
        for kind in ("rigid", "stock"):
            stamp(f"{NAMES[kind]} at {stepFs} fs")
            data, frames, boxes, msPerStep = simulate(system, state, molecules, platform, properties, kind, stepFs,
                                                      args.equilibrate, args.production, seed=100 + stepFs)
            radii, g = radialDistribution(frames, boxes, RDF_MAX, RDF_BIN)
            runs.append(dict(kind=kind, step=stepFs, data=data, radii=radii, g=g, ms=msPerStep))
    return molecules, runs


def summarize(run, blocks):
    """The table's row of one run: each quantity's mean and standard error."""
    row = {"integrator": NAMES[run["kind"]], "step (fs)": run["step"], "ms/step": run["ms"]}
    for key, _, _ in QUANTITIES:
        if key == "peak":
            # The peak of each block's mean g(r) (a single frame's g is too noisy for its maximum).
            n = len(run["g"])//blocks*blocks
            blockCurves = run["g"][:n].reshape(blocks, -1, run["g"].shape[1]).mean(axis=1)
            heights = firstPeak(run["radii"], blockCurves)[0]
            row[key] = (heights.mean(), heights.std(ddof=1)/np.sqrt(blocks))
        else:
            row[key] = blockMean(run["data"][key], blocks)
    row["peak position"] = firstPeak(run["radii"], run["g"].mean(axis=0))[1]
    return row


def tabulate(runs, blocks):
    """Print the table and the differences between the integrators; returns the rows."""
    rows = []
    for run in runs:
        run["row"] = summarize(run, blocks)
        rows.append(run["row"])
    say(f"{'integrator':<38}{'step':>5}" + "".join(f"{title:>22}" for _, title, _ in QUANTITIES) + f"{'ms/step':>9}")
    for row in rows:
        cells = "".join(f"{row[key][0]:>{13}.{digits}f} +- {row[key][1]:<5.{digits}f}" for key, _, digits in QUANTITIES)
        say(f"{row['integrator']:<38}{row['step (fs)']:>3} fs{cells}{row['ms/step']:>9.2f}")
    say()
    say("difference rigid - stock at the same step, in units of the combined standard error:")
    for stepFs in (2, 4):
        rigid, stock = [r["row"] for r in runs if r["step"] == stepFs]
        parts = []
        for key, title, digits in QUANTITIES:
            difference = rigid[key][0] - stock[key][0]
            error = np.hypot(rigid[key][1], stock[key][1])
            parts.append(f"{title.split(' (')[0]} {difference:+.{digits}f} ({difference/error:+.1f} sigma)")
        say(f"  {stepFs} fs: " + "; ".join(parts))
    for run in runs:
        say(f"  first g_OO peak of {NAMES[run['kind']]} at {run['step']} fs: r = {run['row']['peak position']:.3f} nm")
    return rows


def plot(runs, blocks, title, path):
    """g_OO of the four runs, and rigid - stock with 2-sigma bands."""
    plt = pyplot()
    figure, (top, bottom) = plt.subplots(2, 1, figsize=(7, 7), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    colours = {2: "tab:blue", 4: "tab:red"}
    for run in runs:
        mean, _ = blockMean(run["g"], blocks)
        top.plot(run["radii"], mean, color=colours[run["step"]], linestyle="-" if run["kind"] == "rigid" else "--",
                 label=f"{NAMES[run['kind']]}, {run['step']} fs")
    for stepFs in (2, 4):
        rigid, stock = [blockMean(r["g"], blocks) for r in runs if r["step"] == stepFs]
        difference, error = rigid[0] - stock[0], np.hypot(rigid[1], stock[1])
        radii = runs[0]["radii"]
        bottom.plot(radii, difference, color=colours[stepFs], label=f"{stepFs} fs")
        bottom.fill_between(radii, -2*error, 2*error, color=colours[stepFs], alpha=0.15)
    top.set_ylabel("g_OO(r)")
    top.set_title(title)
    top.legend(fontsize=8)
    bottom.axhline(0, color="black", linewidth=0.5)
    bottom.set_xlabel("r (nm)")
    bottom.set_ylabel("rigid - stock (band: 2 sigma)")
    bottom.legend(fontsize=8)
    bottom.set_xlim(0.2, RDF_MAX)
    saveFigure(figure, path)


def main():
    args = parseArguments()
    openLog(RESULTS/"thermostat_comparison.log")
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = cpuProperties(platform, args.threads)
    threads = args.threads or (platform.getPropertyDefaultValue("Threads") if args.platform == "CPU" else None)
    document = ResultsDocument("thermostat_comparison", "Constant temperature and pressure: RigidBodyLangevinIntegrator "
                               "and LangevinMiddleIntegrator + SETTLE", quick=args.quick, platform=args.platform,
                               threads=threads, about="Method: the docstring of `benchmarks/thermostat_comparison.py`.")
    for line in header(args.platform, threads):
        say(line)
    started = time.perf_counter()
    molecules, runs = runAll(args, platform, properties)
    say()
    with document.capture():
        rows = tabulate(runs, args.blocks)
    writeCsv(RESULTS/"thermostat_comparison.csv",
             [{"integrator": row["integrator"], "step_fs": row["step (fs)"], "ms_per_step": row["ms/step"],
               **{f"{key}{suffix}": float(value) for key, _, _ in QUANTITIES
                  for suffix, value in zip(("", "_error"), row[key])}} for row in rows])
    figure = document.figurePath("thermostat_comparison.png")
    plot(runs, args.blocks, f"TIP4P-Ew, {molecules.count} waters, NPT 300 K / 1 bar, friction 1/ps, "
         f"{args.production:g} ps per run", figure)
    document.figure(figure, "g_OO of the four runs")
    document.write()
    say(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    sys.exit(main())

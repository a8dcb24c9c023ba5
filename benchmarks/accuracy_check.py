#!/usr/bin/env python
"""The accuracy check (setAccuracyCheck(), on by default) on the runs of issue 23's table: which fire,
after how many ps, and which stay quiet, with the figure of every 2 ps window.

System: rigid water (rigidtesting.waterBox: TIP3P unless --model, PME 0.9 nm), minimized and
equilibrated 5 ps with LangevinMiddleIntegrator + SETTLE at 2 fs and 300 K; every run starts from that
state. Each run measures its shadow work (setMeasureShadowWork) and reads it every 0.05 ps, with the
kinetic energy: the figure of each 2 ps window is computed here from those samples (the heating
2 W_step / ((1 - c^2) dof kT) for Langevin, the fluctuation of the shadow work about its trend over
the kinetic energy's otherwise), next to the time the integrator's own check fired (None: quiet).

Runs (name: integrator, step): L<dt>f<friction>: RigidBodyLangevinIntegrator; BV<dt>, BO<dt>:
RigidBodyBussiIntegrator (tau 1 ps), Verlet or Omelyan2; NVE<dt>, NVEO<dt>: RigidBodyIntegrator,
without a thermostat. A suffix m<k> raises every moment of inertia to at least k/100 amu nm^2
(setMinimumMomentOfInertia): L14f1m4 is Langevin at 14 fs, friction 1/ps, moments of at least 0.04.

    python benchmarks/accuracy_check.py --quick          # 216 waters, L8f1 and L10f1, 10 ps each: minutes
    python benchmarks/accuracy_check.py                   # every run, 216 waters, 40 ps: docs/results/accuracy_check.md
    python benchmarks/accuracy_check.py --molecules 500 --runs L10f1 BV6 L8f1 BO6 --time 30
    python benchmarks/accuracy_check.py --molecules 500 --runs L12f1m4 L14f1m4 L16f1m4 --time 30

--cost measures what the check's episodes cost instead (docs/results/accuracy_check_cost.md): 2000
TIP4P-Ew waters (PME 0.9 nm, Ewald tolerance 5e-4), minimized and equilibrated 1 ps with
LangevinMiddleIntegrator; RigidBodyLangevinIntegrator (300 K, 1/ps) and RigidBodyBussiIntegrator
(Verlet, tau 1 ps), both at 2 fs, each as three Contexts from that state: the check off,
the check on (the default; every timed step lies in the first episode, the first 4 ps of a Context),
and the check off with setMeasureShadowWork(True), which evaluates the energy at every step as the
episodes did before they read samples. Stock LangevinMiddleIntegrator for scale. Blocks of --block
steps, one block of each in turn (benchmarking.timeInterleaved), --repetitions blocks each; reported:
median ms/step, and the ratio to the check off, the median of the blocks' ratios (block r of one
against block r of the other, timed side by side) with their quartiles, of the wall time and of the
process's CPU time.

    python benchmarks/accuracy_check.py --cost            # about 5 minutes (one thread)
"""

import argparse
import re
import time
import warnings

import numpy as np
import openmm
from openmm import unit

import benchmarking
from benchmarking import say, stamp
import openmmrigid
from rigidtesting import waterBox

KJ = unit.kilojoule_per_mole
R = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(KJ/unit.kelvin)
RUNS = ["L10f1", "L11f1", "BV6", "BV8", "NVE10", "L1f1", "L2f1", "L4f1", "L6f1", "L8f1", "L10f10", "BO6", "BO8", "BV4",
        "NVE2", "NVE4", "NVE6", "NVE7", "NVEO6"]


def makeIntegrator(name):
    match = re.fullmatch(r"(L|BV|BO|NVEO|NVE)(\d+)(?:f(\d+))?(?:m(\d+))?", name)
    if match is None:
        raise SystemExit(f"unknown run {name}")
    kind, step, friction, minimum = match.group(1), float(match.group(2))*1e-3, match.group(3), match.group(4)
    if kind == "L":
        integrator = openmmrigid.RigidBodyLangevinIntegrator(300, float(friction or 1), step)
    else:
        integrator = (openmmrigid.RigidBodyBussiIntegrator(300, 1.0, step) if kind in ("BV", "BO") else
                      openmmrigid.RigidBodyIntegrator(step))
        integrator.setSplitting(openmmrigid.RigidBodyIntegrator.Omelyan2 if kind in ("BO", "NVEO") else openmmrigid.RigidBodyIntegrator.Verlet)
    if minimum:
        integrator.setMinimumMomentOfInertia(float(minimum)*0.01)
    return integrator


def run(name, system, state, platform, properties, picoseconds, every=0.05):
    integrator = makeIntegrator(name)
    dt = integrator.getStepSize().value_in_unit(unit.picosecond)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    if integrator.getMinimumMomentOfInertia().value_in_unit(unit.amu*unit.nanometer**2) > 0:
        # the equilibrated velocities keep their angular velocity: I'/I times too hot in rotation
        context.setVelocitiesToTemperature(300, 1)
    integrator.setMeasureShadowWork(True)
    dof = benchmarking.rigidDegreesOfFreedom(context, integrator)
    n = max(1, int(round(every/dt)))
    rows, fired, failure = [], None, ""
    with warnings.catch_warnings(record=True) as caught:  # recorded, not shown
        warnings.simplefilter("always", openmmrigid.AccuracyWarning)
        try:
            for i in range(int(round(picoseconds/dt/n))):
                integrator.step(n)
                kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
                rows.append(((i + 1)*n*dt, integrator.getShadowWork().value_in_unit(KJ), kinetic))
                if fired is None and benchmarking.accuracyWarnings(caught):
                    fired = (i + 1)*n*dt
        except openmm.OpenMMException as error:
            failure = f"unstable at {len(rows)*n*dt:.1f} ps"
    times, work, kinetic = np.array(rows).T
    friction = integrator.getFriction().value_in_unit(unit.picosecond**-1) if hasattr(integrator, "getFriction") else 0.0
    figures, m = [], int(round(2.0/(n*dt)))
    for k in range(len(times)//m):
        t, w, K = times[k*m:(k + 1)*m], work[k*m:(k + 1)*m], kinetic[k*m:(k + 1)*m]
        fit = np.polyfit(t, w, 1)
        if friction > 0:
            c = np.exp(-friction*dt)
            figures.append(2*fit[0]*dt/((1 - c*c)*dof*R*300))
        else:
            figures.append((w - np.polyval(fit, t)).std()/K.std())
    temperature = 2*kinetic[len(kinetic)//5:].mean()/(dof*R)
    messages = benchmarking.accuracyWarnings(caught)
    return dict(run=name, temperature=float(temperature), fired=fired, failure=failure,
                low=float(min(figures)) if figures else np.nan, high=float(max(figures)) if figures else np.nan,
                kind="heating" if friction > 0 else "fluctuation", message=messages[-1] if messages else "")


def measureCost(args):
    """--cost: the episodes' cost against the check off, side by side (the module's docstring)."""
    platform = openmm.Platform.getPlatformByName("CPU")
    properties = {"Threads": str(args.threads)}
    _, positions, system = waterBox("tip4pew", molecules=2000, nonbondedCutoff=0.9*unit.nanometer, ewaldErrorTolerance=5e-4)
    equilibration = openmm.LangevinMiddleIntegrator(300, 1, 0.002)
    context = openmm.Context(system, equilibration, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 200)
    context.setVelocitiesToTemperature(300, 1)
    equilibration.step(500)
    state = context.getState(getPositions=True, getVelocities=True, enforcePeriodicBox=True)
    del context
    # Every timed step of a "check on" Context within its first episode (the first 4 ps).
    if (args.repetitions + 1)*args.block*0.002 >= 2*benchmarking.CHECK_WINDOW_PS:
        raise SystemExit("--repetitions x --block would leave the first episode")

    def make(kind, mode):
        if kind == "stock":
            return openmm.LangevinMiddleIntegrator(300, 1, 0.002)
        if kind == "Langevin":
            integrator = openmmrigid.RigidBodyLangevinIntegrator(300, 1, 0.002)
        else:
            integrator = openmmrigid.RigidBodyBussiIntegrator(300, 1.0, 0.002)
        integrator.setAccuracyCheck(mode == "check on")
        integrator.setMeasureShadowWork(mode == "energy every step")
        return integrator

    modes = ["check off", "check on", "energy every step"]
    integrators = {"stock LangevinMiddle": make("stock", None)}
    for kind in ("Langevin", "Bussi"):
        for mode in modes:
            integrators[f"{kind}, {mode}"] = make(kind, mode)
    contexts = []
    for integrator in integrators.values():
        contexts.append(openmm.Context(system, integrator, platform, properties))
        contexts[-1].setState(state)
    wall, cpu = benchmarking.timeInterleaved(integrators, args.block, args.repetitions)
    document = benchmarking.ResultsDocument("accuracy_check_cost", "What the accuracy check's episodes cost",
                                            platform="CPU", threads=args.threads,
                                            about="Method: the docstring of `benchmarks/accuracy_check.py` (--cost).")
    rows = []
    for label in wall:
        kind = label.split(",")[0]
        row = [label, f"{1e3*np.median(wall[label]):.3f}"]
        for times in (wall, cpu):
            off = times.get(f"{kind}, check off")
            ratios = np.array(times[label])/np.array(off) if off else None
            row.append("" if ratios is None else
                       f"{np.median(ratios):.4f} ({np.percentile(ratios, 25):.4f} to {np.percentile(ratios, 75):.4f})")
        rows.append(row)
        say("  ".join(f"{cell:<36}" if i == 0 else f"{cell:>26}" for i, cell in enumerate(row)))
    document.section("Cost per step", f"2000 TIP4P-Ew waters, PME, 2 fs, CPU platform, {args.threads} thread(s); "
                     f"{args.repetitions} blocks of {args.block} steps each, interleaved. Ratios: the median over the "
                     "blocks of block r against block r of the check off, with the quartiles; of the wall time, and of "
                     "the process's CPU time (which other processes on a shared machine stretch less).")
    document.table(["integrator", "median ms/step", "ratio to the check off, wall (quartiles)",
                    "ratio to the check off, CPU time (quartiles)"], rows)
    document.write()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--runs", nargs="+", default=None)
    parser.add_argument("--model", default="tip3p")
    parser.add_argument("--molecules", type=int, default=216)
    parser.add_argument("--time", type=float, default=None, help="ps per run (default 40; 10 with --quick)")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--cost", action="store_true", help="measure the episodes' cost instead (see the docstring)")
    parser.add_argument("--block", type=int, default=30, help="--cost: steps per timed block")
    parser.add_argument("--repetitions", type=int, default=31, help="--cost: timed blocks of each integrator")
    args = parser.parse_args()
    if args.cost:
        measureCost(args)
        return
    runs = args.runs or (["L8f1", "L10f1"] if args.quick else RUNS)
    picoseconds = args.time or (10.0 if args.quick else 40.0)
    platform = openmm.Platform.getPlatformByName("CPU")
    properties = {"Threads": str(args.threads)}
    _, positions, system = waterBox(args.model, molecules=args.molecules)
    equilibration = openmm.LangevinMiddleIntegrator(300, 1, 0.002)
    context = openmm.Context(system, equilibration, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context)
    context.setVelocitiesToTemperature(300, 1)
    equilibration.step(2500)
    state = context.getState(getPositions=True, getVelocities=True)
    del context
    document = benchmarking.ResultsDocument("accuracy_check", "The accuracy check on runs inside and outside their range",
                                            quick=args.quick, platform="CPU", threads=args.threads,
                                            about="Method: the docstring of `benchmarks/accuracy_check.py`.")
    table = []
    for name in runs:
        started = time.perf_counter()
        result = run(name, system, state, platform, properties, picoseconds)
        stamp(f"{name}: T {result['temperature']:.1f} K, fired {result['fired']}, {result['kind']} {result['low']:.3f} to "
              f"{result['high']:.3f} {result['failure']} ({time.perf_counter() - started:.0f} s)")
        table.append([name, f"{result['temperature']:.1f}", "quiet" if result["fired"] is None else f"at {result['fired']:.1f} ps",
                      f"{result['kind']} {result['low']:.3f} to {result['high']:.3f}", result["failure"]])
        if result["message"]:
            say(f"  {result['message']}")
    document.section("Runs", f"{args.molecules} {args.model} waters, {picoseconds:g} ps per run.")
    document.table(["run", "T (K)", "check", "figure per 2 ps window", "note"], table)
    document.write()


if __name__ == "__main__":
    main()

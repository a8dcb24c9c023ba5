#!/usr/bin/env python
"""Where the kinetic energy of rigid water sits at large Langevin steps: translation and each principal axis.

The temperature a Langevin integrator reports at a large step is the mean kinetic energy of the
velocities it holds; this benchmark splits it by motion. One box of rigid water per model (500
molecules by default, PME 0.9 nm), minimized and equilibrated with LangevinMiddleIntegrator + SETTLE
(2 fs, 6 ps). From that state, for each friction, step size and integrator:

- RigidBodyLangevinIntegrator (Exact rotation), whose velocities are half a step behind the positions;
- LangevinMiddleIntegrator + SETTLE, whose velocities are the same half-step ones;

each run equilibrates for 2 ps of its own and samples every 10 steps for `--time` ps. From the held
velocities and positions of each molecule: the centre-of-mass (translational) temperature (3 N - 3
degrees of freedom, the CMMotionRemover's 3 taken off), and the rotational temperature about each
principal axis, in the order of increasing moment (N degrees of freedom each): the axis of least
moment is the fastest libration. "T reported" is 2 KE / (k dof) with the integrator's kinetic energy
and OpenMM's count of degrees of freedom, as StateDataReporter computes it. Errors: standard errors
of block means (the larger of 5- and 10-block estimates).

For a harmonic mode both integrators' half-step velocities are canonical at any stable step; for the
anharmonic librations of a liquid their distribution keeps the splitting's error of order dt^2,
which is what this measures. Stronger friction pulls it back towards the bath's.

    python benchmarks/langevin_axes.py                       # 2 models x 2, 4, 8 fs x friction 1 and 10/ps: about 30 min
    python benchmarks/langevin_axes.py --quick               # smoke run: TIP3P, 216 waters, 4 fs, 1 ps

Writes docs/results/langevin_axes.md (a quick run: benchmarks/results/) and a figure.
"""

import argparse
import time

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from benchmarking import (RESULTS, blockMean, openRun, principalKineticEnergies, pyplot, saveFigure, say, stamp,
                          writeCsv)
import rigidtesting

TEMPERATURE = 300.0
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
KINDS = {"exact": "RigidBodyLangevinIntegrator (Exact)", "stock": "LangevinMiddleIntegrator + SETTLE"}


def equilibratedBox(model, waters, platform, properties):
    topology, positions, system = rigidtesting.waterBox(model, molecules=waters)
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, 1.0, 0.002)
    integrator.setRandomNumberSeed(3)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
    context.setVelocitiesToTemperature(TEMPERATURE, 3)
    integrator.step(3000)
    return system, context.getState(getPositions=True, getVelocities=True)


def makeIntegrator(kind, friction, stepFs):
    if kind == "exact":
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, friction, stepFs/1000)
    else:
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, friction, stepFs/1000)
        integrator.setConstraintTolerance(1e-8)
    integrator.setRandomNumberSeed(11)
    return integrator


def run(system, state, molecules, masses, kind, friction, stepFs, production, platform, properties):
    """Block means (value, error) of the reported, translational and per-axis rotational temperatures."""
    integrator = makeIntegrator(kind, friction, stepFs)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    steps = lambda ps: int(round(ps*1000/stepFs))
    count = len(molecules)
    dof = rigidtesting.degreesOfFreedom(system)
    samples = []
    integrator.step(steps(2.0))
    for _ in range(max(20, steps(production)//10)):
        integrator.step(10)
        current = context.getState(getPositions=True, getVelocities=True, getEnergy=True, enforcePeriodicBox=False)
        translational, axes = principalKineticEnergies(
            current.getPositions(asNumpy=True).value_in_unit(unit.nanometer),
            current.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond), masses, molecules)
        reported = 2*current.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)/(dof*BOLTZMANN)
        samples.append([reported, 2*translational/((3*count - 3)*BOLTZMANN)] + list(2*axes/(count*BOLTZMANN)))
    if not np.all(np.isfinite(samples)):
        raise openmm.OpenMMException("NaN in the kinetic energies")
    return blockMean(np.array(samples))


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--models", nargs="+", help="water models (default tip3p tip4pew; quick tip3p)")
    parser.add_argument("--steps", type=float, nargs="+", help="step sizes in fs (default 2 4 8; quick 4)")
    parser.add_argument("--frictions", type=float, nargs="+", help="friction coefficients in 1/ps (default 1 10; quick 1)")
    parser.add_argument("--waters", type=int, help="molecules per box (default 500; quick 100)")
    parser.add_argument("--time", type=float, help="sampled ps per run (default 20; quick 1)")
    parser.add_argument("--quick", action="store_true", help="a smoke run: TIP3P, 216 waters, 4 fs, friction 1/ps, 1 ps")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's)")
    args = parser.parse_args()
    args.models = args.models or (["tip3p"] if args.quick else ["tip3p", "tip4pew"])
    args.steps = args.steps or ([4.0] if args.quick else [2.0, 4.0, 8.0])
    args.frictions = args.frictions or ([1.0] if args.quick else [1.0, 10.0])
    args.waters = args.waters or (216 if args.quick else 500)
    args.time = args.time or (1.0 if args.quick else 20.0)
    return args


def cell(mean, error):
    return f"{mean:.1f} +- {error:.1f}"


def tabulate(rows, args, document):
    columns = ["model", "friction (1/ps)", "integrator", "step (fs)", "T reported (K)", "T translation (K)",
               "T rotation, least moment (K)", "middle moment (K)", "largest moment (K)"]
    table = [[model.upper(), f"{friction:g}", KINDS[kind], f"{stepFs:g}"]
             + ([cell(m, e) for m, e in zip(*result)] if result is not None else [failure] + [""]*4)
             for model, friction, kind, stepFs, result, failure in rows]
    document.section("Temperatures by motion",
                     f"{args.waters} waters per box, 300 K, {args.time:g} ps sampled per run; +- one standard error.")
    document.table(columns, table)
    say("\n".join(" | ".join(row) for row in table))
    names = ["reported", "translation", "axis1", "axis2", "axis3"]
    writeCsv(RESULTS/"langevin_axes.csv",
             [dict(model=model, friction=friction, integrator=kind, step_fs=stepFs, quantity=name,
                   mean=float(m), error=float(e))
              for model, friction, kind, stepFs, result, _ in rows if result is not None
              for name, m, e in zip(names, *result)])


def plot(rows, args, document):
    plt = pyplot()
    figure, panels = plt.subplots(1, len(args.models), figsize=(5.5*len(args.models), 4), squeeze=False)
    for panel, model in zip(panels[0], args.models):
        for (kind, friction), style in zip([(k, f) for f in args.frictions for k in KINDS], ["-o", "--s", "-^", "--v"]):
            points = [(stepFs, result) for m, f, k, stepFs, result, _ in rows
                      if m == model and f == friction and k == kind and result is not None]
            if not points:
                continue
            steps = [s for s, _ in points]
            for index, label in ((2, "least-moment libration"), (1, "translation")):
                panel.errorbar(steps, [r[0][index] for _, r in points], [r[1][index] for _, r in points], fmt=style,
                               capsize=3, label=f"{kind}, friction {friction:g}/ps: {label}")
        panel.axhline(TEMPERATURE, color="gray", lw=0.8)
        panel.set_xlabel("step (fs)")
        panel.set_ylabel("temperature (K)")
        panel.set_title(model.upper())
        panel.legend(fontsize=7)
    path = document.figurePath("langevin_axes.png")
    saveFigure(figure, path)
    document.figure(path, "translational and least-moment rotational temperature against step")


def main():
    args = parseArguments()
    platform, properties, document = openRun("langevin_axes", "Rigid water at large Langevin steps: temperature by motion", args)
    started, rows = time.time(), []
    for model in args.models:
        stamp(f"{model}: building and equilibrating {args.waters} waters")
        system, state = equilibratedBox(model, args.waters, platform, properties)
        masses = rigidtesting.particleMasses(system)
        molecules = np.flatnonzero(masses > 0).reshape(-1, 3)
        for friction in args.frictions:
            for stepFs in args.steps:
                for kind in KINDS:
                    stamp(f"{model}, friction {friction:g}/ps, {kind} at {stepFs:g} fs")
                    try:
                        result, failure = run(system, state, molecules, masses, kind, friction, stepFs, args.time,
                                              platform, properties), ""
                    except openmm.OpenMMException as error:
                        result, failure = None, "failed: " + str(error).splitlines()[0][:80]
                    rows.append((model, friction, kind, stepFs, result, failure))
    tabulate(rows, args, document)
    plot(rows, args, document)
    document.write()
    say(f"total {time.time() - started:.0f} s")


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""Which temperature each thermostat of this plugin reads, against the step size.

One box of about 100 TIP3P waters (amber14/tip3p.xml, reaction field with a 0.6 nm cutoff, no
CMMotionRemover), minimized and equilibrated with LangevinMiddleIntegrator + SETTLE. From that
state, for each step size (1, 2, 4, 6, 8 fs by default):

- RigidBodyBussiIntegrator: the stochastic velocity rescaling of Bussi, Donadio and Parrinello
  (collision time 0.1 ps). Its velocities are on-step: the rescaling after each step
  samples their total kinetic energy from the canonical distribution, so the temperature it
  reports (computeSystemTemperature(), StateDataReporter's column) is right by construction. How
  that energy divides between translation and rotation is the dynamics' business: at large steps
  the on-step velocities of the stiff librations read cold and the translation, as a result, warm.
- RigidBodyLangevinIntegrator (friction 10/ps), whose velocities are half a step behind the
  positions (as LangevinMiddleIntegrator's), where they are canonical: every part reads the bath.
- LangevinMiddleIntegrator + SETTLE (friction 10/ps), where it is stable.

Each run equilibrates for 2 ps of its own, then samples every 4 steps for `--time` ps: the reported
temperature, the translational and rotational temperatures (3 N degrees of freedom each, from the
split of the rigid integrators' bodies, rigidtesting.bodies.rigidKineticEnergies, or for the stock integrator
from the molecules' centre-of-mass velocities), and the potential energy per molecule. Errors:
standard errors of 20 block means.

    python benchmarks/thermostat_temperature.py              # 20 ps per run: about 10 minutes on 2 cores
    python benchmarks/thermostat_temperature.py --quick      # 1 and 4 fs, 1 ps per run: a smoke check

Writes docs/results/thermostat_temperature.md (a quick run: benchmarks/results/), and
benchmarks/results/thermostat_temperature.csv and .log.
"""

import argparse
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from benchmarking import (RESULTS, blockMean, integratorBodies, rigidKineticEnergies, molecularKineticEnergies, openRun,
                          say, stamp, writeCsv)
import rigidtesting

TEMPERATURE = 300.0
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
KINDS = ["bussi", "rigid-langevin", "langevin-middle"]
BLOCKS = 20


def equilibratedBox(edge, platform, properties):
    """The water box, its System and an equilibrated State (LangevinMiddleIntegrator + SETTLE, 2 fs, 10 ps)."""
    topology, positions, system = rigidtesting.waterBox(
        "tip3p", edge=edge, forceField="amber14/tip3p.xml", nonbondedMethod=app.CutoffPeriodic,
        nonbondedCutoff=0.6*unit.nanometer, removeCMMotion=False)
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, 10/unit.picosecond, 2*unit.femtoseconds)
    integrator.setRandomNumberSeed(7)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
    context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 7)
    integrator.step(5000)
    return system, context.getState(getPositions=True, getVelocities=True)


def makeIntegrator(kind, stepFs, seed):
    dt = stepFs*unit.femtoseconds
    if kind == "bussi":
        integrator = openmmrigid.RigidBodyBussiIntegrator(TEMPERATURE*unit.kelvin, 0.1*unit.picosecond, dt)
    elif kind == "rigid-langevin":
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE*unit.kelvin, 10/unit.picosecond, dt)
    else:
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, 10/unit.picosecond, dt)
    integrator.setRandomNumberSeed(seed)
    return integrator


def kineticParts(context, integrator, masses, molecules, bodies):
    """Translational and rotational kinetic energy (kJ/mol): for a rigid integrator the split of its
    bodies (`bodies`, rigidtesting.bodies.rigidKineticEnergies), else the molecules' centre-of-mass
    motion and the rest."""
    if bodies is not None:
        return rigidKineticEnergies(context, integrator, bodies, masses)
    velocities = context.getState(getVelocities=True).getVelocities(asNumpy=True)
    return molecularKineticEnergies(velocities.value_in_unit(unit.nanometer/unit.picosecond), masses, molecules)


def run(system, state, kind, stepFs, production, masses, molecules, platform, properties):
    integrator = makeIntegrator(kind, stepFs, seed=11)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    steps = lambda ps: int(round(ps*1000/stepFs))
    numWaters = len(molecules)
    dof = 6*numWaters
    samples = {"reported": [], "translational": [], "rotational": [], "potential": []}
    bodies = integratorBodies(integrator) if isinstance(integrator, openmmrigid.RigidBodyIntegratorBase) else None
    try:
        integrator.step(steps(min(2.0, production)))
        for _ in range(max(20, steps(production)//4)):
            integrator.step(4)
            energy = context.getState(getEnergy=True)
            translational, rotational = kineticParts(context, integrator, masses, molecules, bodies)
            kinetic = energy.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
            samples["reported"].append(2*kinetic/(dof*BOLTZMANN))
            samples["translational"].append(2*translational/(3*numWaters*BOLTZMANN))
            samples["rotational"].append(2*rotational/(3*numWaters*BOLTZMANN))
            samples["potential"].append(energy.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/numWaters)
    except openmm.OpenMMException as error:
        return None, str(error).splitlines()[0][:80]
    if not all(np.all(np.isfinite(values)) for values in samples.values()):
        return None, "NaN"
    return {name: blockMean(values, BLOCKS) for name, values in samples.items()}, ""


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=float, nargs="+", help="step sizes in fs (default 1 2 4 6 8; quick 1 4)")
    parser.add_argument("--time", type=float, help="sampled ps per run (default 20; quick 1)")
    parser.add_argument("--edge", type=float, default=1.5, help="box edge in nm (default 1.5: about 100 waters)")
    parser.add_argument("--quick", action="store_true", help="a smoke check: 1 and 4 fs, 1 ps per run")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's)")
    args = parser.parse_args()
    args.steps = args.steps or ([1, 4] if args.quick else [1, 2, 4, 6, 8])
    args.time = args.time or (1.0 if args.quick else 20.0)
    return args


def tabulate(rows, waters, args, document):
    """The table, printed and put in the results document; the CSV."""
    with document.capture():
        say(f"Temperatures (K) and potential energy per molecule (kJ/mol), {waters} TIP3P waters, 300 K, "
            f"{args.time:g} ps per run; +- one standard error of {BLOCKS} block means")
        say(f"{'integrator':16s} {'step':>5s} {'T reported':>15s} {'T trans':>15s} {'T rot':>15s} {'U/molecule':>17s}")
        for kind, stepFs, result, failure in rows:
            if result is None:
                say(f"{kind:16s} {stepFs:4g}  failed: {failure}")
                continue
            cells = [f"{result[q][0]:7.1f} +- {result[q][1]:4.1f}" for q in ("reported", "translational", "rotational")]
            say(f"{kind:16s} {stepFs:4g}  {cells[0]:>15s} {cells[1]:>15s} {cells[2]:>15s} "
                f"{result['potential'][0]:8.3f} +- {result['potential'][1]:5.3f}")
    writeCsv(RESULTS/"thermostat_temperature.csv",
             [dict(integrator=kind, step_fs=stepFs, quantity=quantity, mean=float(mean), error=float(error))
              for kind, stepFs, result, _ in rows if result is not None for quantity, (mean, error) in result.items()])


def main():
    args = parseArguments()
    platform, properties, document = openRun("thermostat_temperature", "Which temperature each thermostat reads, against the step", args)
    started = time.time()
    stamp("building and equilibrating the water box (LangevinMiddleIntegrator + SETTLE, 10 ps)")
    system, state = equilibratedBox(args.edge, platform, properties)
    masses = rigidtesting.particleMasses(system)
    molecules = np.arange(system.getNumParticles()).reshape(-1, 3)
    stamp(f"{len(molecules)} waters; {args.time:g} ps per run after {min(2.0, args.time):g} ps of its own equilibration")
    rows = []
    for stepFs in args.steps:
        for kind in KINDS:
            stamp(f"{kind} at {stepFs:g} fs")
            result, failure = run(system, state, kind, stepFs, args.time, masses, molecules, platform, properties)
            rows.append((kind, stepFs, result, failure))
    say()
    tabulate(rows, len(molecules), args, document)
    document.write()
    say(f"total {time.time() - started:.0f} s")


if __name__ == "__main__":
    main()

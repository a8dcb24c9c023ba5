#!/usr/bin/env python
"""Which temperature each thermostat of this plugin reads, against the step size.

One box of about 100 TIP3P waters (amber14/tip3p.xml, reaction field with a 0.6 nm cutoff, no
CMMotionRemover), minimized and equilibrated with LangevinMiddleIntegrator + SETTLE. From that
state, for each step size (1, 2, 4, 6, 8 fs by default):

- RigidBodyIntegrator with the stochastic velocity rescaling of Bussi, Donadio and Parrinello
  (setThermostat, collision time 0.1 ps). Its velocities are on-step: the rescaling after each step
  samples their total kinetic energy from the canonical distribution, so the temperature it
  reports (computeSystemTemperature(), StateDataReporter's column) is right by construction. How
  that energy divides between translation and rotation is the dynamics' business: at large steps
  the on-step velocities of the stiff librations read cold and the translation, as a result, warm.
- RigidBodyLangevinIntegrator (friction 10/ps), whose velocities are half a step behind the
  positions (as LangevinMiddleIntegrator's), where they are canonical: every part reads the bath.
- LangevinMiddleIntegrator + SETTLE (friction 10/ps), where it is stable.

Each run equilibrates for 2 ps of its own, then samples every 4 steps for `--time` ps: the reported
temperature, the translational and rotational temperatures (3 N degrees of freedom each, from the
integrator's own kinetic-energy split, or for the stock integrator from the molecules' centre-of-mass
velocities), and the potential energy per molecule. Errors: standard errors of 20 block means.

    python benchmarks/thermostat_temperature.py              # 20 ps per run: about 10 minutes on 2 cores
    python benchmarks/thermostat_temperature.py --time 4     # a quick look

Writes benchmarks/results/thermostat_temperature.csv and .log.
"""

import argparse
import csv
import math
import time
from pathlib import Path

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from reporting import openLog, say, stamp

RESULTS = Path(__file__).resolve().parent / "results"
TEMPERATURE = 300.0
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
KINDS = ["bussi", "rigid-langevin", "langevin-middle"]


def equilibratedBox(edge):
    """The water box, its System and an equilibrated State (LangevinMiddleIntegrator + SETTLE, 2 fs, 10 ps)."""
    forceField = app.ForceField("amber14/tip3p.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forceField, model="tip3p", boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.CutoffPeriodic, nonbondedCutoff=0.6*unit.nanometer,
                                     rigidWater=True, removeCMMotion=False)
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, 10/unit.picosecond, 2*unit.femtoseconds)
    integrator.setRandomNumberSeed(7)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("CPU"))
    context.setPositions(modeller.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
    context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 7)
    integrator.step(5000)
    return system, context.getState(getPositions=True, getVelocities=True)


def makeIntegrator(kind, stepFs, seed):
    dt = stepFs*unit.femtoseconds
    if kind == "bussi":
        integrator = openmmrigid.RigidBodyIntegrator(dt)
        integrator.setThermostat(TEMPERATURE*unit.kelvin, 0.1*unit.picosecond)
    elif kind == "rigid-langevin":
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE*unit.kelvin, 10/unit.picosecond, dt)
    else:
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE*unit.kelvin, 10/unit.picosecond, dt)
    integrator.setRandomNumberSeed(seed)
    return integrator


def kineticParts(context, integrator, masses, molecules):
    """Translational and rotational kinetic energy (kJ/mol): the integrator's split if it has one,
    else the molecules' centre-of-mass motion and the rest."""
    if hasattr(integrator, "getTranslationalKineticEnergy"):
        return (integrator.getTranslationalKineticEnergy().value_in_unit(unit.kilojoule_per_mole),
                integrator.getRotationalKineticEnergy().value_in_unit(unit.kilojoule_per_mole))
    v = context.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    m = masses[molecules]                       # (N, 3)
    vm = v[molecules]                           # (N, 3, 3)
    centre = np.einsum("na,nak->nk", m, vm)/m.sum(axis=1)[:, None]
    translational = 0.5*np.sum(m.sum(axis=1)*np.sum(centre**2, axis=1))
    total = 0.5*np.sum(m[:, :, None]*vm**2)
    return translational, total - translational


def blockMean(values, blocks=20):
    values = np.asarray(values)
    means = values[:len(values)//blocks*blocks].reshape(blocks, -1).mean(axis=1)
    return values.mean(), means.std(ddof=1)/math.sqrt(blocks)


def run(system, state, kind, stepFs, production, masses, molecules):
    integrator = makeIntegrator(kind, stepFs, seed=11)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("CPU"))
    context.setState(state)
    steps = lambda ps: int(round(ps*1000/stepFs))
    numWaters = len(molecules)
    dof = 6*numWaters
    samples = {"reported": [], "translational": [], "rotational": [], "potential": []}
    try:
        integrator.step(steps(2.0))
        for _ in range(max(20, steps(production)//4)):
            integrator.step(4)
            energy = context.getState(getEnergy=True)
            translational, rotational = kineticParts(context, integrator, masses, molecules)
            kinetic = energy.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
            samples["reported"].append(2*kinetic/(dof*BOLTZMANN))
            samples["translational"].append(2*translational/(3*numWaters*BOLTZMANN))
            samples["rotational"].append(2*rotational/(3*numWaters*BOLTZMANN))
            samples["potential"].append(energy.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/numWaters)
    except openmm.OpenMMException as error:
        return None, str(error).splitlines()[0][:80]
    if not all(np.all(np.isfinite(values)) for values in samples.values()):
        return None, "NaN"
    return {name: blockMean(values) for name, values in samples.items()}, ""


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=float, nargs="+", default=[1, 2, 4, 6, 8], help="step sizes in fs")
    parser.add_argument("--time", type=float, default=20.0, help="sampled ps per run (default 20)")
    parser.add_argument("--edge", type=float, default=1.5, help="box edge in nm (default 1.5: about 100 waters)")
    args = parser.parse_args()
    RESULTS.mkdir(exist_ok=True)
    openLog(RESULTS/"thermostat_temperature.log")
    started = time.time()
    stamp("building and equilibrating the water box (LangevinMiddleIntegrator + SETTLE, 10 ps)")
    system, state = equilibratedBox(args.edge)
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    molecules = np.arange(system.getNumParticles()).reshape(-1, 3)
    stamp(f"{len(molecules)} waters; {args.time:g} ps per run after 2 ps of its own equilibration")
    rows = []
    for stepFs in args.steps:
        for kind in KINDS:
            stamp(f"{kind} at {stepFs:g} fs")
            result, failure = run(system, state, kind, stepFs, args.time, masses, molecules)
            rows.append((kind, stepFs, result, failure))
    say()
    say(f"Temperatures (K) and potential energy per molecule (kJ/mol), {len(molecules)} TIP3P waters, 300 K, "
        f"{args.time:g} ps per run; +- one standard error of 20 block means")
    say(f"{'integrator':16s} {'step':>5s} {'T reported':>15s} {'T trans':>15s} {'T rot':>15s} {'U/molecule':>17s}")
    with open(RESULTS/"thermostat_temperature.csv", "w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(["integrator", "step_fs", "quantity", "mean", "error"])
        for kind, stepFs, result, failure in rows:
            if result is None:
                say(f"{kind:16s} {stepFs:4g}  failed: {failure}")
                continue
            cells = [f"{result[q][0]:7.1f} +- {result[q][1]:4.1f}" for q in ("reported", "translational", "rotational")]
            say(f"{kind:16s} {stepFs:4g}  {cells[0]:>15s} {cells[1]:>15s} {cells[2]:>15s} "
                f"{result['potential'][0]:8.3f} +- {result['potential'][1]:5.3f}")
            for quantity, (mean, error) in result.items():
                writer.writerow([kind, stepFs, quantity, f"{mean:.6g}", f"{error:.3g}"])
    say()
    say(f"wrote {RESULTS/'thermostat_temperature.csv'}; total {time.time() - started:.0f} s")


if __name__ == "__main__":
    main()

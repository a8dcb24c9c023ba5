"""Rigid TIP4P-Ew water: openmmrigid.RigidBodyIntegrator next to stock Verlet + SETTLE.

Builds a box of TIP4P-Ew water with openmm.app (PME), equilibrates it with a stock Langevin
integrator, then runs NVE from the same state with stock VerletIntegrator + SETTLE and with
RigidBodyIntegrator (Exact and NoSquish rotation), and prints how well each conserves the total
energy: the drift (slope of a linear fit, per degree of freedom) and the fluctuation (standard
deviation about the fit), and what a step costs.

Step: 2 fs by default, the step most production water simulations use, where both integrators are
well inside their accurate range (docs/validation/energy_drift.md, TIP4P-Ew: up to 6 fs both drift
within +-0.1 kJ/mol/ns/dof and fluctuate alike, the fluctuation at 1 to 2 fs mostly the PME cutoff's
floor and growing as the step squared beyond it; at 7 fs both drift, at 8 fs both blow up). So this
compares the two at an equal, ordinary step, where the rigid integrator is no more accurate than
stock and costs a little more; its gain is a larger step at constant temperature with raised
moments of inertia, which examples/large_step.py (scripts/demo.sh) shows. --step 4 or 6 shows the
fluctuation grow.

The three runs are interleaved: each Context in turn advances one sampling interval, and only the
step() calls are timed, so that all three see the same load on the machine (timing them one after
another on shared cores can make any of them look faster or slower). The cost is given as ms/step
and as the median, over the rounds, of each integrator's time divided by stock's in the same round.

    python examples/rigid_water.py [--molecules 500] [--step 2] [--time 5] [--platform CPU]

The default settings take about a minute on two cores.
"""

import argparse
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from _molecules import WATERS_PER_CUBIC_NANOMETRE, degreesOfFreedom, energyDrift


class Run:
    """One integrator in its own Context, from `state`: times (ps), total energies (kJ/mol), seconds in step()."""

    def __init__(self, name, system, state, integrator, platform):
        self.name, self.integrator = name, integrator
        self.context = openmm.Context(system, integrator, platform)
        self.context.setState(state)
        if isinstance(integrator, openmm.VerletIntegrator):
            self.context.applyConstraints(1e-10)
            self.context.applyVelocityConstraints(1e-10)
        self.times, self.energies, self.roundSeconds = [], [], []
        self.record()

    def record(self):
        current = self.context.getState(getEnergy=True)
        self.times.append(current.getTime().value_in_unit(unit.picosecond))
        self.energies.append((current.getKineticEnergy() + current.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole))

    def advance(self, steps):
        start = time.perf_counter()
        self.integrator.step(steps)
        self.roundSeconds.append(time.perf_counter() - start)
        self.record()


def runInterleaved(runs, steps, sampleEvery):
    """Advance every run by `sampleEvery` steps in turn until each has taken `steps`, with a progress line."""
    rounds = steps//sampleEvery
    for number in range(rounds):
        for run in runs:
            run.advance(sampleEvery)
        if (number + 1) % max(1, rounds//5) == 0 or number + 1 == rounds:
            print(f"  ... {(number + 1)*sampleEvery} of {steps} steps", flush=True)


def waterBox(model, edge):
    """A periodic cubic box of rigid water with the given edge (nm), built with openmm.app: PME, a 0.9 nm
    cutoff (at most 0.45 of the edge), rigid water; (topology, positions, system)."""
    forceField = app.ForceField(f"{model}.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forceField, model=model, boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME,
                                     nonbondedCutoff=min(0.9, 0.45*edge)*unit.nanometer, constraints=app.HBonds,
                                     rigidWater=True, ewaldErrorTolerance=5e-4)
    return modeller.topology, modeller.positions, system


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--molecules", type=int, default=500, help="approximate number of waters (default 500)")
    parser.add_argument("--model", default="tip4pew", choices=["tip4pew", "tip3p", "spce"])
    parser.add_argument("--step", type=float, default=2.0, help="time step in fs (default 2)")
    parser.add_argument("--time", type=float, default=5.0, help="NVE time per integrator in ps (default 5)")
    parser.add_argument("--equilibrate", type=float, default=2.0, help="Langevin equilibration in ps (default 2)")
    parser.add_argument("--platform", default="CPU")
    args = parser.parse_args()

    platform = openmm.Platform.getPlatformByName(args.platform)
    started = time.perf_counter()
    print(f"building a box of about {args.molecules} {args.model.upper()} waters with openmm.app ...", flush=True)
    topology, positions, system = waterBox(args.model, edge=(args.molecules/WATERS_PER_CUBIC_NANOMETRE)**(1/3))
    waters = topology.getNumResidues()
    print(f"{waters} {args.model.upper()} waters, {system.getNumParticles()} particles, PME, platform {args.platform}")

    print(f"minimizing, then equilibrating {args.equilibrate:g} ps with stock LangevinMiddleIntegrator at 300 K ...",
          flush=True)
    equilibration = openmm.LangevinMiddleIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtosecond)
    context = openmm.Context(system, equilibration, platform)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 200)
    context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    equilibration.step(int(args.equilibrate*500))
    state = context.getState(getPositions=True, getVelocities=True)
    del context
    print(f"ready after {time.perf_counter() - started:.0f} s", flush=True)

    dt = args.step*unit.femtosecond
    steps = int(round(args.time/(args.step/1000)))
    sampleEvery = max(1, steps//200)
    steps -= steps % sampleEvery
    dof = degreesOfFreedom(system)
    stock = openmm.VerletIntegrator(dt)
    stock.setConstraintTolerance(1e-10)
    runs = [Run("stock VerletIntegrator + SETTLE", system, state, stock, platform)]
    for name, method in (("RigidBodyIntegrator (Exact)", openmmrigid.RigidBodyIntegrator.Exact),
                         ("RigidBodyIntegrator (NoSquish)", openmmrigid.RigidBodyIntegrator.NoSquish)):
        rigid = openmmrigid.RigidBodyIntegrator(dt)
        rigid.setRotationMethod(method)
        runs.append(Run(name, system, state, rigid, platform))
    print(f"NVE for {steps*args.step/1000:g} ps at {args.step:g} fs ({steps} steps) from the same equilibrated state, "
          f"the three integrators interleaved ({sampleEvery} steps each in turn); {dof} degrees of freedom ...",
          flush=True)
    runInterleaved(runs, steps, sampleEvery)

    print(f"\n{'integrator':<34}{'drift':>17}{'fluctuation':>13}{'ms/step':>9}{'cost / stock':>14}")
    print(f"{'':<34}{'(kJ/mol/ns/dof)':>17}{'(kJ/mol)':>13}{'':>9}{'(median)':>14}")
    stockSeconds = np.array(runs[0].roundSeconds)
    for run in runs:
        energies = np.array(run.energies)
        if not np.all(np.isfinite(energies)):
            print(f"{run.name:<34}{'unstable (NaN)':>30}")
            continue
        drift, fluctuation = energyDrift(run.times, energies, dof)
        msPerStep = 1000*sum(run.roundSeconds)/steps
        ratio = np.median(np.array(run.roundSeconds)/stockSeconds)
        print(f"{run.name:<34}{drift:>+17.4f}{fluctuation:>13.3f}{msPerStep:>9.2f}{ratio:>14.3f}")
    print("\ndrift: slope of a linear fit of the total energy over the run, per degree of freedom (0 for an ideal\n"
          "  integrator; short runs scatter about it, in either sign);\n"
          "fluctuation: standard deviation of the total energy about that fit (smaller is more accurate; at 1 to\n"
          "  2 fs most of it comes from the PME cutoff, not from the integrator: see docs/validation/energy_drift.md);\n"
          "ms/step: wall time of the step() calls alone; cost / stock: median over the rounds of the integrator's\n"
          "  time over stock's in the same round. Other work on the same cores still adds noise: the step-cost results\n"
          "  figures come from python benchmarks/run.py step_cost (longer blocks, medians of repetitions).")
    print(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

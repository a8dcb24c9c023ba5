"""Rigid TIP4P-Ew water: openmmrigid.RigidBodyIntegrator next to stock Verlet + SETTLE.

Builds a box of TIP4P-Ew water with openmm.app (PME), equilibrates it with a stock Langevin
integrator, then runs NVE from the same state with both integrators and prints how well each
conserves the total energy: the drift (slope of a linear fit, per degree of freedom) and the
fluctuation (standard deviation about the fit).

    python examples/rigid_water.py [--molecules 500] [--step 2] [--time 10] [--platform CPU]

The default settings take about a minute on two cores.
"""

import argparse
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid


def buildWater(molecules, model):
    """A cubic box of about `molecules` waters of the given model ("tip4pew", "tip3p", "spce")."""
    forceField = app.ForceField(f"{model}.xml")
    modeller = app.Modeller(app.Topology(), [])
    edge = (molecules/33.4)**(1/3)  # liquid water holds about 33.4 molecules per nm^3
    modeller.addSolvent(forceField, model=model, boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=min(0.9, 0.45*edge)*unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True, ewaldErrorTolerance=5e-4)
    return modeller, system


def degreesOfFreedom(system):
    """3 per massive particle, less one per constraint and 3 more with a CMMotionRemover (as OpenMM counts them)."""
    massive = sum(1 for i in range(system.getNumParticles()) if system.getParticleMass(i) > 0*unit.dalton)
    remover = any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
    return 3*massive - system.getNumConstraints() - (3 if remover else 0)


def runNVE(system, state, integrator, platform, steps, sampleEvery):
    """Run from `state`; return times (ps), total energies (kJ/mol) and seconds per step."""
    context = openmm.Context(system, integrator, platform)
    context.setState(state)
    if isinstance(integrator, openmm.VerletIntegrator):
        context.applyConstraints(1e-10)
        context.applyVelocityConstraints(1e-10)
    times, energies = [], []
    start = time.perf_counter()
    for sample in range(steps//sampleEvery + 1):
        if sample > 0:
            integrator.step(sampleEvery)
        current = context.getState(getEnergy=True)
        times.append(current.getTime().value_in_unit(unit.picosecond))
        energies.append((current.getKineticEnergy() + current.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole))
    elapsed = time.perf_counter() - start
    return np.array(times), np.array(energies), elapsed/steps


def summarize(times, energies, dof):
    slope, intercept = np.polyfit(times, energies, 1)
    fluctuation = np.std(energies - (slope*times + intercept))
    return slope*1000/dof, fluctuation


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
    modeller, system = buildWater(args.molecules, args.model)
    waters = modeller.topology.getNumResidues()
    print(f"{waters} {args.model.upper()} waters, {system.getNumParticles()} particles, PME, platform {args.platform}")

    equilibration = openmm.LangevinMiddleIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtosecond)
    context = openmm.Context(system, equilibration, platform)
    context.setPositions(modeller.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 200)
    context.setVelocitiesToTemperature(300*unit.kelvin, 1)
    equilibration.step(int(args.equilibrate*500))
    state = context.getState(getPositions=True, getVelocities=True)
    del context

    dt = args.step*unit.femtosecond
    steps = int(round(args.time/(args.step/1000)))
    sampleEvery = max(1, steps//200)
    dof = degreesOfFreedom(system)
    print(f"NVE for {args.time:g} ps at {args.step:g} fs ({steps} steps) from the same equilibrated state; {dof} degrees of freedom\n")
    print(f"{'integrator':<34}{'drift (kJ/mol/ns/dof)':>24}{'fluctuation (kJ/mol)':>24}{'ms/step':>10}")
    stock = openmm.VerletIntegrator(dt)
    stock.setConstraintTolerance(1e-10)
    candidates = [("stock VerletIntegrator + SETTLE", stock)]
    for name, method in (("RigidBodyIntegrator (Exact)", openmmrigid.RigidBodyIntegrator.Exact),
                         ("RigidBodyIntegrator (NoSquish)", openmmrigid.RigidBodyIntegrator.NoSquish)):
        rigid = openmmrigid.RigidBodyIntegrator(dt)
        rigid.setRotationMethod(method)
        candidates.append((name, rigid))
    for name, integrator in candidates:
        times, energies, seconds = runNVE(system, state, integrator, platform, steps, sampleEvery)
        if not np.all(np.isfinite(energies)):
            print(f"{name:<34}{'unstable (NaN)':>24}")
            continue
        drift, fluctuation = summarize(times, energies, dof)
        print(f"{name:<34}{drift:>24.4g}{fluctuation:>24.4g}{seconds*1000:>10.2f}")
    print("\ndrift: slope of a linear fit of the total energy, per degree of freedom; fluctuation: "
          "standard deviation about that fit.")


if __name__ == "__main__":
    main()

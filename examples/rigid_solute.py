"""A rigid solute in rigid water from a PDB: rigidBodiesFromTopology and removeIntraBodyInteractions.

Alanine dipeptide (ACE-ALA-NME: a small solute spanning three residues, amber14 parameters) is read
from a PDB file with app.PDBFile (examples/data/alanine-dipeptide.pdb: use your own file the same
way) and solvated with openmm.app.Modeller (TIP3P, 1 nm padding); ForceField.createSystem builds the
System as for any simulation (PME, constraints=HBonds, rigidWater=True). Then, in two lines,

    bodies = openmmrigid.rigidBodiesFromTopology(topology, ["ACE", "ALA", "NME", "HOH"], mergeBonded=True, system=system)
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)

the solute becomes one rigid body (its three residues merged through their bonds) and every water
another, and the System loses what the bodies do not feel: the solute's bonds, angles, torsions,
constraints and internal nonbonded pairs, the waters' constraints. The solute's shape is that of the
minimized structure (minimized with the full, flexible System first). A RigidBodyLangevinIntegrator
at 300 K (after 1 ps of warming up at a stronger friction) runs it with RigidStateDataReporter printing the translational and rotational temperatures;
at the end the script checks that the solute kept its shape and that the energy of the full System
differs from the lean one's by the same constant as at the start.

Step: 2 fs by default, a conservative step for a first run of a new rigid model: the point here is
the lean System and the bodies' shapes, not speed. For this solute in rigid water the measurements (docs/guide/step-sizes.md) read,
by the kinetic temperature, 8 fs with standard moments and 14 fs with moments raised to 0.04 amu nm^2
(setMinimumMomentOfInertia) as accurate, but its potential energy at large steps is not resolved
there; --step 8 runs at the larger step with the accuracy check watching.

    python examples/rigid_solute.py [--time 4] [--keep-internal] [--platform CPU]

--keep-internal runs the full System instead (the same motion, at the cost of computing the
internal terms). The default settings take about a minute on two cores. Writes
examples/output/rigid_solute.pdb (the last frame, molecules whole).
"""

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from _molecules import bodyKinds, degreesOfFreedom

SOLUTE = Path(__file__).resolve().parent / "data" / "alanine-dipeptide.pdb"


def potentialEnergy(system, positions, platform):
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
    context.setPositions(positions)
    return context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)


def pairDistances(positions):
    return np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=-1)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--time", type=float, default=4.0, help="ps of Langevin dynamics (default 4)")
    parser.add_argument("--step", type=float, default=2.0, help="fs (default 2)")
    parser.add_argument("--keep-internal", action="store_true", help="run the full System, internal terms and all")
    parser.add_argument("--platform", default="CPU")
    args = parser.parse_args()
    started = time.perf_counter()
    platform = openmm.Platform.getPlatformByName(args.platform)

    print("reading the solute, solvating it with Modeller and building the System ...", flush=True)
    pdb = app.PDBFile(str(SOLUTE))
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.addSolvent(forceField, model="tip3p", padding=1.0*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True)

    print("minimizing with the full, flexible System ...", flush=True)
    minimizer = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
    minimizer.setPositions(modeller.positions)
    openmm.LocalEnergyMinimizer.minimize(minimizer, 10, 500)
    positions = minimizer.getState(getPositions=True).getPositions()
    del minimizer

    # The two lines this example is about.
    bodies = openmmrigid.rigidBodiesFromTopology(modeller.topology, ["ACE", "ALA", "NME", "HOH"], mergeBonded=True,
                                                 system=system)
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)

    solute = next(body for body in bodies if len(body) > 3)
    before = {type(f).__name__: f for f in system.getForces()}
    after = {type(f).__name__: f for f in lean.getForces()}
    waters = sum(1 for residue in modeller.topology.residues() if residue.name == "HOH")
    print(f"{system.getNumParticles()} atoms: the solute ({len(solute)} atoms, 3 residues) and {waters} waters, "
          f"{len(bodies)} rigid bodies in all")
    print("removed by removeIntraBodyInteractions: "
          f"bonds {before['HarmonicBondForce'].getNumBonds()} -> {after['HarmonicBondForce'].getNumBonds()}, "
          f"angles {before['HarmonicAngleForce'].getNumAngles()} -> {after['HarmonicAngleForce'].getNumAngles()}, "
          f"torsions {before['PeriodicTorsionForce'].getNumTorsions()} -> {after['PeriodicTorsionForce'].getNumTorsions()}, "
          f"constraints {system.getNumConstraints()} -> {lean.getNumConstraints()}; nonbonded exceptions "
          f"{before['NonbondedForce'].getNumExceptions()} -> {after['NonbondedForce'].getNumExceptions()} "
          "(every pair inside the solute now one, with no charge and no Lennard-Jones)")

    model = system if args.keep_internal else lean
    integrator = openmmrigid.RigidBodyLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, args.step*unit.femtosecond,
                                                         bodies)
    integrator.setRandomNumberSeed(22)
    simulation = app.Simulation(modeller.topology, model, integrator, platform)
    simulation.context.setPositions(positions)
    simulation.context.setVelocitiesToTemperature(300*unit.kelvin, 22)
    # The bodies' kinds by their principal moments (from masses and positions) and the degrees of freedom they
    # leave: 3 per body and 3 more (2 for a linear one), less 3 for the CMMotionRemover.
    kinds = bodyKinds(model, positions.value_in_unit(unit.nanometer), bodies)
    dof = degreesOfFreedom(model, bodies, kinds)
    print(f"running {'the full' if args.keep_internal else 'the lean'} System: {integrator.getNumBodies()} bodies "
          f"({', '.join(f'{n} {k}' for k, n in sorted(Counter(kinds).items()))}), {dof} degrees "
          f"of freedom; RigidBodyLangevinIntegrator at 300 K, 1/ps, {args.step:g} fs, {args.time:g} ps\n", flush=True)
    # The velocities drawn for every atom keep their temperature when they are projected onto the bodies (the
    # projection removes the non-rigid share of the energy together with its degrees of freedom); a short warm-up
    # at a stronger friction lets the freshly built box settle before the run is reported.
    print("warming up: 1 ps at friction 10/ps ...", flush=True)
    integrator.setFriction(10/unit.picosecond)
    simulation.step(int(round(1000/args.step)))
    integrator.setFriction(1/unit.picosecond)
    steps = int(round(args.time*1000/args.step))
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(
        sys.stdout, max(1, steps//8), step=True, potentialEnergy=True, temperature=True, translationalTemperature=True,
        rotationalTemperature=True, speed=True))
    start = np.array(positions.value_in_unit(unit.nanometer))  # the shape the bodies took
    stepStart = time.perf_counter()
    simulation.step(steps)
    elapsed = time.perf_counter() - stepStart

    state = simulation.context.getState(getPositions=True, enforcePeriodicBox=True)
    end = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    shape = np.abs(pairDistances(end[solute]) - pairDistances(start[solute])).max()
    offsetStart = potentialEnergy(system, start, platform) - potentialEnergy(lean, start, platform)
    offsetEnd = potentialEnergy(system, end, platform) - potentialEnergy(lean, end, platform)
    print(f"\n{steps} steps in {elapsed:.1f} s ({elapsed/steps*1000:.2f} ms/step)")
    print(f"solute shape: largest change of an interatomic distance {shape:.1e} nm (rigid)")
    print(f"E(full System) - E(lean System): {offsetStart:.4f} kJ/mol at the start, {offsetEnd:.4f} at the end: the "
          "energy of the removed terms, a constant (to the CPU platform's single-precision rounding)")
    print("Temperature columns: 'Temperature' counts every degree of freedom the integrator moves "
          f"({dof}); the translational and rotational ones count 3 per body (and free "
          "particle), less 3 for the CMMotionRemover, and 3 per rigid body that is not linear: each should read 300 K "
          "within its noise (RigidBodyLangevinIntegrator reports LangevinMiddleIntegrator's half-step velocities, "
          "whose temperature is the bath's at any stable step; see docs/guide/thermostats.md).")
    output = Path(__file__).resolve().parent / "output"
    output.mkdir(exist_ok=True)
    with open(output / "rigid_solute.pdb", "w") as stream:
        app.PDBFile.writeFile(modeller.topology, state.getPositions(), stream)
    print(f"wrote {output / 'rigid_solute.pdb'}; total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""The ensembles openmmtools gives the rigid-body integrators, side by side with stock.

The cases of issue 26, each set up as an openmmtools user would (ThermodynamicState.create_context,
apply_to_context, ContextCache, MCMC moves), on a box of about 100 TIP3P waters (amber14/tip3p.xml,
reaction field with a 0.6 nm cutoff, no CMMotionRemover) minimized and equilibrated with
LangevinMiddleIntegrator + SETTLE:

1. AndersenThermostat (5/ps, put in the System beforehand so that openmmtools keeps it; its own is 1/ps),
   which openmmtools keeps in (or adds to) the System of an integrator it sees as unthermostated (RigidBodyIntegrator; stock VerletIntegrator): bodies found
   from the constraints, explicit bodies that keep their constraints, explicit bodies without them
   (removeIntraBodyInteractions), stock Verlet + SETTLE.
2. RigidBodyBussiIntegrator, created at 300 K and moved to 330 K by
   apply_to_context (whether openmmtools added an AndersenThermostat, what the integrator's
   temperature is, what the run reads); stock LangevinMiddleIntegrator the same way.
3. CompoundIntegrator[RigidBodyLangevinIntegrator, Verlet] the same way; stock
   CompoundIntegrator[LangevinMiddleIntegrator, Verlet].
4. openmmtools' HostGuestExplicit with the guest (B2) as an explicit body that keeps its
   constraints, from the test system's positions: the constraint error of those positions, and of
   the guest in the Context after setPositions and after 10 steps; stock applies its constraints.
5. The moves through one ContextCache at 330 K: RigidLangevinDynamicsMove and RigidBussiDynamicsMove
   against openmmtools' LangevinDynamicsMove.

Each temperature run equilibrates 2 ps, then samples the temperature every 10 steps for --time ps
(kinetic energy over the integrator's degrees of freedom; for stock, 6 per water); errors are
standard errors of block means (the larger of the estimates from 5 and from 10 blocks).

    python benchmarks/openmmtools_ensembles.py              # 40 ps per run: about 10 minutes on 2 cores
    python benchmarks/openmmtools_ensembles.py --quick      # 2 ps per run: a smoke check

Writes docs/results/openmmtools_ensembles.md (a quick run: benchmarks/results/) and
benchmarks/results/openmmtools_ensembles.log.
"""

import argparse
import logging

import numpy as np
import openmm
from openmm import app, unit
from openmmtools import cache, mcmc, states, testsystems

import openmmrigid
from benchmarking import blockMean, openRun, say, stamp
from openmmrigid.openmmtools import RigidBussiDynamicsMove, RigidLangevinDynamicsMove

KB = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)
STEP = 2.0 * unit.femtosecond


def waterBox(edge, platform, properties):
    """About 100 equilibrated TIP3P waters: (system, state, bodies)."""
    forcefield = app.ForceField("amber14/tip3p.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forcefield, model="tip3p", boxSize=openmm.Vec3(edge, edge, edge) * unit.nanometer)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.CutoffPeriodic,
                                     nonbondedCutoff=0.6 * unit.nanometer, rigidWater=True, removeCMMotion=False)
    integrator = openmm.LangevinMiddleIntegrator(300 * unit.kelvin, 10 / unit.picosecond, STEP)
    integrator.setRandomNumberSeed(3)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(modeller.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 200)
    context.setVelocitiesToTemperature(300 * unit.kelvin, 3)
    integrator.step(2500)
    bodies = [[atom.index for atom in residue.atoms()] for residue in modeller.topology.residues()]
    return system, context.getState(getPositions=True, getVelocities=True), bodies


def sampleTemperature(context, integrator, dof, picoseconds):
    """Mean and block error of the kinetic temperature, after 2 ps of equilibration."""
    steps = int(round(picoseconds / STEP.value_in_unit(unit.picosecond)))
    integrator.step(int(round(2.0 / STEP.value_in_unit(unit.picosecond))))
    samples = []
    for _ in range(steps // 10):
        integrator.step(10)
        kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        samples.append(2.0 * kinetic / (dof * KB))
    return blockMean(np.array(samples))


def formatTemperature(measured):
    mean, error = measured[0], measured[1]
    return f"{mean:.1f} +- {error:.1f}"


def andersens(system):
    return sum(isinstance(force, openmm.AndersenThermostat) for force in system.getForces())


def thermostatedRun(name, make, getTemperature, system, state, dof, picoseconds, platform, properties):
    """create_context at 300 K, apply_to_context at 330 K, run: a row of the table. The integrator's
    temperature is read from our own reference to it (and to the one in a CompoundIntegrator):
    Context.getIntegrator() and CompoundIntegrator.getIntegrator() give a plain openmm.Integrator proxy
    for the plugin's integrators."""
    cold = states.ThermodynamicState(system, 300 * unit.kelvin)
    hot = states.ThermodynamicState(system, 330 * unit.kelvin)
    integrator, inner = make()
    context = cold.create_context(integrator, platform, properties)
    hot.apply_to_context(context)
    context.setState(state)
    seen = getTemperature(integrator, inner)
    measured = sampleTemperature(context, integrator, dof, picoseconds)
    return [name, str(andersens(context.getSystem())), f"{seen.value_in_unit(unit.kelvin):.0f}", formatTemperature(measured)]


def andersenRun(name, integrator, system, state, dof, picoseconds, platform, properties):
    thermodynamic = states.ThermodynamicState(system, 300 * unit.kelvin)
    try:
        context = thermodynamic.create_context(integrator, platform, properties)
    except openmm.OpenMMException as error:
        say(f"  {name}: {error}")
        return [name, "refused when the Context is made (OpenMMException: each body would be redrawn in parts)"]
    context.setState(state)
    return [name, formatTemperature(sampleTemperature(context, integrator, dof, picoseconds))]


def hostGuest(platform, properties):
    """Rows: the guest's worst constraint error in the given positions, in the Context, after 10 steps."""
    test = testsystems.HostGuestExplicit()
    guest = [atom.index for residue in test.topology.residues() if residue.name == "B2" for atom in residue.atoms()]
    inGuest = set(guest)
    constraints = [test.system.getConstraintParameters(c) for c in range(test.system.getNumConstraints())]
    constraints = [(i, j, d.value_in_unit(unit.nanometer)) for i, j, d in constraints if i in inGuest and j in inGuest]

    def worst(positions):
        x = positions.value_in_unit(unit.nanometer) if unit.is_quantity(positions) else positions
        return max(abs(np.linalg.norm(np.asarray(x[i]) - np.asarray(x[j])) - d) / d for i, j, d in constraints)

    rows = [["the test system's positions, as given", f"{worst(test.positions):.1e}", "-"]]
    for name, integrator in (("RigidBodyIntegrator, the guest an explicit body", openmmrigid.RigidBodyIntegrator(STEP, [guest])),
                             ("stock VerletIntegrator", openmm.VerletIntegrator(STEP))):
        context = openmm.Context(test.system, integrator, platform, properties)
        context.setPositions(test.positions)
        context.setVelocitiesToTemperature(300 * unit.kelvin, 1)
        if isinstance(integrator, openmm.VerletIntegrator):
            context.applyConstraints(1e-8)
        atStart = worst(context.getState(getPositions=True).getPositions(asNumpy=True))
        integrator.step(10)
        rows.append([name, f"{atStart:.1e}", f"{worst(context.getState(getPositions=True).getPositions(asNumpy=True)):.1e}"])
    return len(guest), len(constraints), rows


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--time", type=float, default=40.0, help="ps sampled per temperature run (default 40)")
    parser.add_argument("--edge", type=float, default=1.5, help="nm, the water box (default 1.5: about 100 waters)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--quick", action="store_true", help="2 ps per run, results in benchmarks/results")
    args = parser.parse_args()
    if args.quick:
        args.time = 2.0
    logging.getLogger("openmmtools").setLevel(logging.ERROR)
    platform, properties, document = openRun("openmmtools_ensembles", "The ensembles openmmtools gives the rigid-body integrators", args)
    stamp("building and equilibrating the water box")
    system, state, bodies = waterBox(args.edge, platform, properties)
    dof = 6 * len(bodies)
    stamp(f"{len(bodies)} waters, {dof} degrees of freedom; {args.time:g} ps per run")

    stamp("1. AndersenThermostat (5/ps) kept by openmmtools for unthermostated integrators, 300 K")
    andersen = openmm.XmlSerializer.clone(system)
    andersen.addForce(openmm.AndersenThermostat(300 * unit.kelvin, 5 / unit.picosecond))
    lean = openmmrigid.removeIntraBodyInteractions(andersen, bodies)
    rows = [andersenRun("RigidBodyIntegrator, bodies found from the constraints", openmmrigid.RigidBodyIntegrator(STEP),
                        andersen, state, dof, args.time, platform, properties),
            andersenRun("RigidBodyIntegrator, explicit bodies keeping their constraints",
                        openmmrigid.RigidBodyIntegrator(STEP, bodies), andersen, state, dof, args.time, platform, properties),
            andersenRun("RigidBodyIntegrator, explicit bodies without constraints (removeIntraBodyInteractions)",
                        openmmrigid.RigidBodyIntegrator(STEP, bodies), lean, state, dof, args.time, platform, properties),
            andersenRun("stock VerletIntegrator + SETTLE", openmm.VerletIntegrator(STEP), andersen, state, dof, args.time,
                        platform, properties)]
    document.section("1. AndersenThermostat with rigid bodies (openmmtools keeps or adds one for unthermostated integrators)",
                     "Temperature read (K) for a 300 K bath, 5/ps.")
    document.table(["integrator", "temperature (K)"], rows)

    stamp("2-3. thermostated integrators: created at 300 K, applied at 330 K")

    # Each make() returns (the integrator, the first of a CompoundIntegrator or None).
    def bussi():
        return openmmrigid.RigidBodyBussiIntegrator(300 * unit.kelvin, 0.1 * unit.picosecond, STEP), None

    def compound(first):
        def make():
            integrator = openmm.CompoundIntegrator()
            inner, _ = first()
            integrator.addIntegrator(inner)
            integrator.addIntegrator(openmm.VerletIntegrator(STEP))
            return integrator, inner
        return make

    def rigidLangevin():
        return openmmrigid.RigidBodyLangevinIntegrator(300 * unit.kelvin, 1 / unit.picosecond, STEP), None

    def stockLangevin():
        return openmm.LangevinMiddleIntegrator(300 * unit.kelvin, 1 / unit.picosecond, STEP), None

    def first(integrator, inner):
        return inner.getTemperature()

    def own(integrator, inner):
        return integrator.getTemperature()

    rows = [thermostatedRun("RigidBodyBussiIntegrator (0.1 ps)", bussi, own, system, state, dof, args.time,
                            platform, properties),
            thermostatedRun("stock LangevinMiddleIntegrator (1/ps)", stockLangevin, own, system, state, dof, args.time,
                            platform, properties),
            thermostatedRun("CompoundIntegrator[RigidBodyLangevinIntegrator (1/ps), Verlet]", compound(rigidLangevin), first,
                            system, state, dof, args.time, platform, properties),
            thermostatedRun("stock CompoundIntegrator[LangevinMiddleIntegrator (1/ps), Verlet]", compound(stockLangevin), first,
                            system, state, dof, args.time, platform, properties)]
    document.section("2-3. Thermostated integrators through ThermodynamicState",
                     "Created with `create_context` at 300 K, then `apply_to_context` at 330 K: AndersenThermostats "
                     "openmmtools added, the integrator's temperature after that, and the temperature the run reads (K).")
    document.table(["integrator", "Andersen added", "integrator's T (K)", "temperature read (K)"], rows)

    stamp("4. HostGuestExplicit, the guest an explicit body that keeps its constraints")
    size, count, rows = hostGuest(platform, properties)
    document.section("4. Explicit body with internal constraints from ordinary positions",
                     f"openmmtools' HostGuestExplicit, the guest B2 ({size} atoms, {count} constraints) one explicit "
                     "body: the largest relative error of its constraints.")
    document.table(["positions", "after setPositions (stock: and applyConstraints)", "after 10 steps"], rows)

    stamp("5. the moves through one ContextCache at 330 K")
    contexts = cache.ContextCache(platform=platform, platform_properties=properties)
    hot = states.ThermodynamicState(system, 330 * unit.kelvin)
    rows = []
    steps = int(round(args.time / STEP.value_in_unit(unit.picosecond)))
    for name, move in (("RigidLangevinDynamicsMove (1/ps)", RigidLangevinDynamicsMove(n_steps=10)),
                       ("RigidBussiDynamicsMove (0.1 ps)", RigidBussiDynamicsMove(n_steps=10)),
                       ("openmmtools LangevinDynamicsMove (1/ps)", mcmc.LangevinDynamicsMove(timestep=STEP, n_steps=10,
                                                                                                collision_rate=1 / unit.picosecond))):
        sampler = states.SamplerState(state.getPositions(asNumpy=True), velocities=state.getVelocities(asNumpy=True),
                                      box_vectors=state.getPeriodicBoxVectors())
        for _ in range(200):  # 2 ps of equilibration
            move.apply(hot, sampler, context_cache=contexts)
        samples = []
        for _ in range(steps // 10):
            move.apply(hot, sampler, context_cache=contexts)
            samples.append(2.0 * sampler.kinetic_energy.value_in_unit(unit.kilojoule_per_mole) / (dof * KB))
        rows.append([name, formatTemperature(blockMean(np.array(samples)))])
    document.section("5. The moves at 330 K (one ContextCache)", "Temperature read (K) for a 330 K state.")
    document.table(["move", "temperature (K)"], rows)
    document.write()


if __name__ == "__main__":
    main()

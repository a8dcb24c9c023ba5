"""The studies' shared set-ups: systems, starting states, integrators by name and observables; each exists once, here.

Systems are built with openmm.app as users build them (PME 0.9 nm, ewaldErrorTolerance 5e-4, rigid
water); a study asks for an equilibrated starting state with ``start()``, which builds, minimizes and
equilibrates once (stock LangevinMiddleIntegrator + SETTLE at 2 fs, 300 K, 1/ps) and keeps the result in
``benchmarks/results/starts/`` for every later run.

Integrators are named (``makeIntegrator``): every study that compares "stock-middle" with
"rigid-langevin" compares the same two things.
"""

import fcntl

import openmm
import openmm.app as app
import openmm.unit as unit
import numpy as np

import openmmrigid
import rigidtesting
from harness import RESULTS, say

TEMPERATURE = 300.0                 # K
FRICTION = 1.0                      # 1/ps
BOLTZMANN = 0.00831446261815324     # kJ/mol/K
KJ = unit.kilojoule_per_mole
BONDED = (openmm.HarmonicBondForce, openmm.HarmonicAngleForce, openmm.PeriodicTorsionForce, openmm.CMAPTorsionForce)
WATER = {"HOH", "WAT"}              # water's residue names: openmm.app's, Amber's

# ---------------------------------------------------------------------------------------------------
# Systems


class Built:
    """A system as a study uses it: topology, positions, System, and the indices of each water's
    massive atoms (molecules x atoms; empty for none; a water is a residue named as in WATER)."""

    def __init__(self, topology, positions, system):
        self.topology, self.positions, self.system = topology, positions, system
        waters = [residue for residue in topology.residues() if residue.name in WATER]
        massive = [[atom.index for atom in residue.atoms() if system.getParticleMass(atom.index) > 0*unit.dalton]
                   for residue in waters]
        self.waters = np.array(massive, dtype=int) if massive else np.zeros((0, 3), dtype=int)
        self.oxygens = np.array([atom.index for residue in waters for atom in residue.atoms()
                                 if atom.element == app.element.oxygen], dtype=int)
        self.masses = rigidtesting.particleMasses(system)


def water(model="tip3p", molecules=500, barostat=False, **options):
    """A cubic box of rigid water of `model` (amber14's model files: tip3p, spce, tip4pew, tip5p...),
    with a MonteCarloBarostat (1 bar, every 25 steps) as the last force if asked."""
    topology, positions, system = rigidtesting.waterBox(
        model, molecules=molecules, forceField=["amber14-all.xml", f"amber14/{model}.xml"], **options)
    if barostat:
        system.addForce(openmm.MonteCarloBarostat(1.0, TEMPERATURE, 25))
    return Built(topology, positions, system)


def dipeptideInWater(molecules=500, barostat=True, hydrogenMass=3.0, constraints=app.HBonds):
    """Alanine dipeptide among TIP3P waters (amber14, HBonds, HMR to `hydrogenMass` amu or none), NPT by default."""
    topology, positions, system = rigidtesting.waterBox(
        "tip3p", molecules=molecules, forceField=["amber14-all.xml", "amber14/tip3p.xml"],
        solute=rigidtesting.alanineDipeptide(), constraints=constraints,
        hydrogenMass=hydrogenMass and hydrogenMass*unit.amu)
    if barostat:
        system.addForce(openmm.MonteCarloBarostat(1.0, TEMPERATURE, 25))
    return Built(topology, positions, system)


def villin(hydrogenMass=None, constraints=app.HBonds, padding=0.9):
    """Villin headpiece (openmm's app/data/test.pdb) re-solvated in TIP3P with Modeller: amber14, PME
    0.9 nm, rigid water."""
    import os
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.deleteWater()
    modeller.addSolvent(forceField, model="tip3p", padding=padding*unit.nanometer)
    options = dict(nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer, constraints=constraints,
                   rigidWater=True, ewaldErrorTolerance=5e-4)
    if hydrogenMass:
        options["hydrogenMass"] = hydrogenMass*unit.amu
    return Built(modeller.topology, modeller.positions, forceField.createSystem(modeller.topology, **options))


def dhfr(hydrogenMass=None, constraints=app.HBonds):
    """Dihydrofolate reductase in TIP3P, the Joint Amber-CHARMM benchmark (JAC, 23,558 atoms; openmmtools' data/dhfr):
    its Amber prmtop and restart read by openmm.app (the restart's box, 6.16 nm), PME 0.9 nm as villin."""
    import importlib.util, os   # found, not imported: openmmtools' import is slow and loud
    folder = os.path.join(importlib.util.find_spec("openmmtools").submodule_search_locations[0], "data", "dhfr")
    prmtop = app.AmberPrmtopFile(os.path.join(folder, "JAC.prmtop"))
    inpcrd = app.AmberInpcrdFile(os.path.join(folder, "JAC.inpcrd"))
    system = prmtop.createSystem(nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer, constraints=constraints,
                                 rigidWater=True, ewaldErrorTolerance=5e-4, hydrogenMass=hydrogenMass and hydrogenMass*unit.amu)
    system.setDefaultPeriodicBoxVectors(*inpcrd.boxVectors)
    prmtop.topology.setPeriodicBoxVectors(inpcrd.boxVectors)
    return Built(prmtop.topology, inpcrd.positions, system)


def bondedApart(built, heavyWaterHydrogens=False):
    """`built` with the solute's bonded forces (BONDED) in force group 1 and the rest in group 0, for multiple
    time steps; heavyWaterHydrogens: water O 10, H 4 amu (the repartitioning OpenMM no longer does for water)."""
    for force in built.system.getForces():
        force.setForceGroup(1 if isinstance(force, BONDED) else 0)
    if heavyWaterHydrogens:
        oxygens = set(built.oxygens.tolist())
        for index in built.waters.ravel():
            built.system.setParticleMass(int(index), (10.0 if index in oxygens else 4.0)*unit.amu)
        built.masses = rigidtesting.particleMasses(built.system)
    return built


def start(name, built, platform, properties, picoseconds=5.0, seed=1):
    """The equilibrated State of `built` (a Built): minimized, then `picoseconds` of stock
    LangevinMiddleIntegrator + SETTLE at 2 fs; made once and kept as benchmarks/results/starts/<name>.xml
    (a name says what was built: change the name when the system changes)."""
    path = RESULTS/"starts"/f"{name}.xml"
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path.with_suffix(".lock"), "a") as lock:      # workers wait for the one that makes it
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not path.exists():
            _equilibrate(path, name, built, platform, properties, picoseconds, seed)
    return openmm.XmlSerializer.deserialize(path.read_text())


def _equilibrate(path, name, built, platform, properties, picoseconds, seed):
    say(f"equilibrating {name} ({picoseconds:g} ps)")
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, 2*unit.femtoseconds)
    integrator.setRandomNumberSeed(seed)
    for force in built.system.getForces():
        if isinstance(force, openmm.MonteCarloBarostat):
            force.setRandomNumberSeed(seed)
    context = openmm.Context(built.system, integrator, platform, properties)
    context.setPositions(built.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 500)
    context.setVelocitiesToTemperature(TEMPERATURE, seed)
    integrator.step(int(round(picoseconds/0.002)))
    state = context.getState(getPositions=True, getVelocities=True, enforcePeriodicBox=False)
    temporary = path.with_suffix(".tmp")
    temporary.write_text(openmm.XmlSerializer.serialize(state))
    temporary.replace(path)


def withoutBarostat(system):
    """A copy of the System without its MonteCarloBarostat."""
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for index in reversed(range(copy.getNumForces())):
        if isinstance(copy.getForce(index), openmm.MonteCarloBarostat):
            copy.removeForce(index)
    return copy


# ---------------------------------------------------------------------------------------------------
# Integrators by name

INTEGRATORS = {
    "stock-middle": "LangevinMiddleIntegrator + SETTLE",
    "stock-verlet": "VerletIntegrator + SETTLE",
    "stock-vv": "openmmtools VelocityVerletIntegrator + SETTLE (on-step velocities)",
    "stock-vrorv": "openmmtools LangevinIntegrator, splitting V R O R V, + SETTLE (on-step velocities)",
    "rigid-langevin": "RigidBodyLangevinIntegrator",
    "rigid-verlet": "RigidBodyIntegrator",
    "rigid-bussi": "RigidBodyBussiIntegrator",
}


def makeIntegrator(name, stepFs, seed=0, temperature=TEMPERATURE, friction=FRICTION, floor=None, rotation=None,
                   splitting=None, collisionTime=0.1, bodies=None):
    """The integrator called `name` (INTEGRATORS) at `stepFs` fs; floor: raised moments (amu nm^2);
    rotation: "exact" or "nosquish"; splitting: RigidBodyIntegrator's (e.g. "Omelyan2")."""
    dt = stepFs*unit.femtoseconds
    if name == "stock-middle":
        integrator = openmm.LangevinMiddleIntegrator(temperature, friction, dt)
    elif name == "stock-verlet":
        integrator = openmm.VerletIntegrator(dt)
    elif name == "stock-vv":
        from openmmtools.integrators import VelocityVerletIntegrator
        integrator = VelocityVerletIntegrator(dt)
    elif name == "stock-vrorv":
        from openmmtools.integrators import LangevinIntegrator
        integrator = LangevinIntegrator(temperature*unit.kelvin, friction/unit.picosecond, dt, splitting="V R O R V")
    elif name in ("rigid-langevin", "rigid-verlet", "rigid-bussi"):
        extra = [] if bodies is None else [bodies]
        if name == "rigid-langevin":
            integrator = openmmrigid.RigidBodyLangevinIntegrator(temperature, friction, dt, *extra)
        elif name == "rigid-verlet":
            integrator = openmmrigid.RigidBodyIntegrator(dt, *extra)
        else:
            integrator = openmmrigid.RigidBodyBussiIntegrator(temperature, collisionTime, dt, *extra)
        if floor:
            integrator.setMinimumMomentOfInertia(floor)
        if rotation:
            integrator.setRotationMethod({"exact": integrator.Exact, "nosquish": integrator.NoSquish}[rotation])
        if splitting:
            integrator.setSplitting(getattr(openmmrigid.RigidBodyIntegrator, splitting))
    else:
        raise ValueError(f"unknown integrator {name!r}; known: {', '.join(INTEGRATORS)}")
    if hasattr(integrator, "setRandomNumberSeed"):
        integrator.setRandomNumberSeed(seed + 1)   # 0 would pick a seed of its own
    integrator.setConstraintTolerance(1e-8)
    return integrator


def context(built, integrator, state, platform, properties, seed=0, system=None):
    """A Context of the system (or `system`) with the integrator, set to `state`, barostat seeded."""
    system = system or built.system
    for force in system.getForces():
        if isinstance(force, openmm.MonteCarloBarostat):
            force.setRandomNumberSeed(seed + 1)
    ctx = openmm.Context(system, integrator, platform, properties)
    ctx.setState(state)
    return ctx


# ---------------------------------------------------------------------------------------------------
# Observables

def waterTemperatures(positions, velocities, built, minimumMoment=0.0, box=None):
    """Translational and rotational temperature (K) of the rigid waters from positions and velocities
    (arrays, nm and nm/ps), the same computation for every integrator: T = 2 K / (f k) with f = 3N (less 3
    for translation with a CMMotionRemover) and K_rot = 1/2 sum_k I'_k w_k^2 about each molecule's
    principal axes, I'_k its moments raised to minimumMoment (rigidtesting.bodies.kineticEnergies)."""
    from rigidtesting.bodies import kineticEnergies
    translational, rotational = kineticEnergies(positions, velocities, built.masses, built.waters, minimumMoment, box)
    n = len(built.waters)
    removed = 3 if any(isinstance(force, openmm.CMMotionRemover) for force in built.system.getForces()) else 0
    return 2*translational/((3*n - removed)*BOLTZMANN), 2*rotational/(3*n*BOLTZMANN)

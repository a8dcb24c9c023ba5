"""The state of a Context with a rigid-body integrator stays coherent with what OpenMM and the user do
around the steps. Each test compares with an independent answer (mostly a fresh Context with the same
System set to the same State, whose next steps are the right ones) or expects an OpenMMException:

- force-group queries between steps, updateParametersInContext and CompoundIntegrator switching
  to another integrator and back leave the trajectory as a fresh Context would run it;
- explicit bodies are molecules: Context.getMolecules, getState(enforcePeriodicBox=True) and
  MonteCarloBarostat keep them whole;
- an explicit body takes its shape when positions are first set (a minimizer afterwards does not
  reshape it);
- molecules split across the periodic boundary (positions wrapped atom by atom) move as whole ones;
- a blow-up raises at the step where it happens;
- the State right after setVelocities reports the rigid projection of what was set;
- numpy scalars are accepted wherever stock OpenMM accepts them;
- checkpoints: one of the other integrator class is refused by name, and checkpoints written by an
  older build (tests/python/data, made by make_legacy_checkpoints.py) still load and continue, those
  of a RigidBodyIntegrator with setThermostat() in the RigidBodyBussiIntegrator that replaced it;
- error messages name the class the user made and say what is wrong.

Reference runs in double precision and is compared to rounding; CPU (deterministic forces) to a few
times the float noise of its forces, measured as 1.4e-8 nm after 10 steps and 3.6e-8 nm after 20 for
two Contexts that should agree.
"""

import importlib.util
import pathlib

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest

import systems
from openmmrigid import RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyLangevinIntegrator
from rigidtesting import particleMasses
from systems import make_context, positions_of, velocities_of

PLATFORMS = systems.PLATFORMS
EDGE = 1.5  # nm, the water box
STEP = 0.002  # ps
DATA = pathlib.Path(__file__).resolve().parent / "data"


def _load_legacy_module():
    spec = importlib.util.spec_from_file_location("make_legacy_checkpoints", DATA / "make_legacy_checkpoints.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


legacy = _load_legacy_module()


# The legacy checkpoints' System and integrators in today's API ("thermostat", written by a RigidBodyIntegrator
# with setThermostat(300 K, 0.1 ps), loads into the RigidBodyBussiIntegrator that replaced it).
legacy_integrator = legacy.legacy_integrator
legacy_context = legacy.legacy_context


# ------------------------------------------------------------------------------------------------
# Systems, Contexts and measurements
# ------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def water():
    """About 100 TIP3P waters (rigidWater constraints), PME 0.7 nm, equilibrated at 300 K."""
    return systems.water_box(size=EDGE, cutoff=0.7)


def water_molecules(water):
    return [[atom.index for atom in residue.atoms()] for residue in water.topology.residues()]


def explicit_bodies(water):
    """The water box as explicit bodies: its System without constraints, and one body per water."""
    system = openmm.XmlSerializer.clone(water.system)
    while system.getNumConstraints() > 0:
        system.removeConstraint(system.getNumConstraints() - 1)
    return system, water_molecules(water)


def water_system(water, bodySource):
    """(System, explicit bodies or None) for bodies found from constraints or given explicitly."""
    return explicit_bodies(water) if bodySource == "explicit" else (openmm.XmlSerializer.clone(water.system), None)


def rigid_integrator(bodies=None, integratorClass=RigidBodyIntegrator):
    """A RigidBodyIntegrator, a RigidBodyBussiIntegrator at 300 K and 0.1 ps, or a
    RigidBodyLangevinIntegrator at 300 K and 1/ps, with explicit bodies or (bodies None) bodies found
    from the constraints."""
    arguments = {RigidBodyIntegrator: (STEP,), RigidBodyBussiIntegrator: (300.0, 0.1, STEP),
                 RigidBodyLangevinIntegrator: (300.0, 1.0, STEP)}[integratorClass]
    return integratorClass(*arguments, *([bodies] if bodies is not None else []))


def started(system, integrator, platformName, positions, velocities=None):
    context = make_context(system, integrator, platformName)
    context.setPositions(positions)
    if velocities is not None:
        context.setVelocities(velocities)
    return context


def fresh(system, integrator, platformName, state):
    """The independent answer: a new Context with the same System, set to the State."""
    context = make_context(system, integrator, platformName)
    context.setState(state)
    return context


def full_state(context):
    return context.getState(getPositions=True, getVelocities=True)


def tolerance(platformName, reference, cpu):
    return reference if platformName == "Reference" else cpu


def assert_below(**figures):
    """figures: name=(value, limit). Fails if any value is not below its limit, listing every value."""
    report = ", ".join(f"{name} {value:.3g} (limit {limit:.0e})" for name, (value, limit) in figures.items())
    assert all(value < limit for value, limit in figures.values()), report


def max_difference(a, b):
    return np.abs(np.asarray(a) - np.asarray(b)).max()


def minimum_image(difference, edge=EDGE):
    return difference - edge * np.round(difference / edge)


def body_distances(positions, bodies):
    """Every distance between two particles of one body, as they lie (no periodic images)."""
    return np.array([np.linalg.norm(positions[body[i]] - positions[body[j]])
                     for body in bodies for i in range(len(body)) for j in range(i + 1, len(body))])


def kinetic_energy(context):
    return context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)


def two_close_waters(water, separation):
    """Two TIP3P waters of the box (CutoffPeriodic), the second moved so that its oxygen lies
    `separation` nm from the first's."""
    modeller = app.Modeller(water.topology, [openmm.Vec3(*x) for x in water.positions] * unit.nanometer)
    modeller.delete(list(modeller.topology.residues())[2:])
    system = app.ForceField("amber14/tip3p.xml").createSystem(
        modeller.topology, nonbondedMethod=app.CutoffPeriodic, nonbondedCutoff=0.6 * unit.nanometer, rigidWater=True)
    positions = np.array(modeller.positions.value_in_unit(unit.nanometer))
    positions[3:] += positions[0] - positions[3] + np.array([separation, 0.0, 0.0])
    return system, positions


# ------------------------------------------------------------------------------------------------
# What happens between steps
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
def test_force_group_query_between_steps(water, platformName):
    system, _ = water_system(water, "constraints")
    restraint = openmm.CustomExternalForce("0.5*k*((x-x0)^2 + (y-y0)^2 + (z-z0)^2)")
    restraint.addGlobalParameter("k", 1000.0)
    for name in ("x0", "y0", "z0"):
        restraint.addPerParticleParameter(name)
    for i, x in enumerate(water.positions):
        restraint.addParticle(i, list(x))
    restraint.setForceGroup(1)
    system.addForce(restraint)
    integrator = rigid_integrator()
    context = started(system, integrator, platformName, water.positions, water.velocities)
    start = full_state(context)
    integrator.step(5)
    context.getState(getForces=True, groups={1})
    integrator.step(5)
    unqueried = rigid_integrator()
    answer = fresh(system, unqueried, platformName, start)
    unqueried.step(5)
    unqueried.step(5)
    assert max_difference(positions_of(context), positions_of(answer)) < tolerance(platformName, 1e-9, 1e-6)


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_update_parameters_in_context(water, platformName):
    system, _ = water_system(water, "constraints")
    integrator = rigid_integrator()
    context = started(system, integrator, platformName, water.positions, water.velocities)
    integrator.step(5)
    nonbonded = next(f for f in system.getForces() if isinstance(f, openmm.NonbondedForce))
    for i in range(nonbonded.getNumParticles()):
        charge, sigma, epsilon = nonbonded.getParticleParameters(i)
        nonbonded.setParticleParameters(i, 0.5 * charge, sigma, epsilon)
    nonbonded.updateParametersInContext(context)
    updated = full_state(context)
    integrator.step(10)
    answerIntegrator = rigid_integrator()
    answer = fresh(system, answerIntegrator, platformName, updated)
    answerIntegrator.step(10)
    assert_below(
        positions=(max_difference(positions_of(context), positions_of(answer)), tolerance(platformName, 1e-8, 1e-6)),
        velocities=(max_difference(velocities_of(context), velocities_of(answer)), tolerance(platformName, 1e-6, 1e-4)))


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_compound_integrator_switching_back(water, platformName):
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(rigid_integrator())
    compound.addIntegrator(openmm.VerletIntegrator(STEP))
    context = started(water.system, compound, platformName, water.positions, water.velocities)
    compound.step(5)
    compound.setCurrentIntegrator(1)
    compound.step(10)
    afterVerlet = full_state(context)
    compound.setCurrentIntegrator(0)
    compound.step(5)
    answerIntegrator = rigid_integrator()
    answer = fresh(water.system, answerIntegrator, platformName, afterVerlet)
    answerIntegrator.step(5)
    assert max_difference(positions_of(context), positions_of(answer)) < tolerance(platformName, 1e-8, 1e-6)


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator])
def test_box_change_between_steps(water, integratorClass, platformName):
    """setPeriodicBoxVectors() between steps, without new positions, sends the integrator no notice:
    the next step must still use the forces in the new box. The answer: a fresh Context loaded from a
    checkpoint of the state right after the change (the same random numbers for Bussi and Langevin)."""
    system, _ = water_system(water, "constraints")
    integrator = rigid_integrator(integratorClass=integratorClass)
    if integratorClass is not RigidBodyIntegrator:
        integrator.setRandomNumberSeed(11)
    context = started(system, integrator, platformName, water.positions, water.velocities)
    integrator.step(3)
    box = context.getState().getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
    context.setPeriodicBoxVectors(*(0.97 * box))
    checkpoint = context.createCheckpoint()
    integrator.step(1)
    answerIntegrator = rigid_integrator(integratorClass=integratorClass)
    if integratorClass is not RigidBodyIntegrator:
        answerIntegrator.setRandomNumberSeed(11)
    answer = make_context(system, answerIntegrator, platformName)
    answer.loadCheckpoint(checkpoint)
    answerIntegrator.step(1)
    assert max_difference(positions_of(context), positions_of(answer)) < tolerance(platformName, 1e-12, 1e-7)


def two_slabs_across_the_boundary():
    """(System, positions, velocities): two slabs of 32 particles each (one atom block of the GPU
    platforms each: different parameters, so reordering never mixes them) that face each other across
    the x boundary 0.85 nm apart, beyond the 0.7 nm cutoff and its padding, and a rigid water between
    them. Reaction-field electrostatics, so that a pair of the two slabs taken or missed shows."""
    edge = (3.0, 1.6, 1.6)
    system = openmm.System()
    system.setDefaultPeriodicBoxVectors(openmm.Vec3(edge[0], 0, 0), openmm.Vec3(0, edge[1], 0), openmm.Vec3(0, 0, edge[2]))
    nonbonded = openmm.NonbondedForce()
    nonbonded.setNonbondedMethod(openmm.NonbondedForce.CutoffPeriodic)
    nonbonded.setCutoffDistance(0.7)
    positions = []
    grid = [0.2, 0.6, 1.0, 1.4]
    for charge, layers in ((0.5, (0.1, 0.4)), (-0.5, (1.95, 2.25))):
        for x in layers:
            for y in grid:
                for z in grid:
                    system.addParticle(40.0)
                    nonbonded.addParticle(charge, 0.2, 0.5)
                    positions.append((x, y, z))
    oxygen = system.addParticle(15.999)
    nonbonded.addParticle(-0.834, 0.315, 0.636)
    positions.append((1.17, 0.8, 0.8))
    for offset in ((0.0757, 0.0586, 0.0), (-0.0757, 0.0586, 0.0)):
        system.addParticle(1.008)
        nonbonded.addParticle(0.417, 1.0, 0.0)
        positions.append(tuple(np.add(positions[oxygen], offset)))
    for hydrogen in (oxygen + 1, oxygen + 2):
        system.addConstraint(oxygen, hydrogen, 0.09572)
        nonbonded.addException(oxygen, hydrogen, 0.0, 1.0, 0.0)
    system.addConstraint(oxygen + 1, oxygen + 2, 0.15139)
    nonbonded.addException(oxygen + 1, oxygen + 2, 0.0, 1.0, 0.0)
    system.addForce(nonbonded)
    velocities = np.random.default_rng(3).normal(0.0, 0.3, (system.getNumParticles(), 3))
    return system, np.array(positions), velocities


def shrink_between_steps_and_compare(platformName, properties=None, evaluations=0):
    """Two steps of the two slabs, `evaluations` force evaluations by getState(), the box 0.25 nm
    shorter along x, one step; then the same step from a fresh Context loaded from a checkpoint of the
    state right after the change. The largest differences of positions and velocities."""
    system, positions, velocities = two_slabs_across_the_boundary()
    integrator = rigid_integrator()
    if properties is None:
        context = make_context(system, integrator, platformName)
    else:
        context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(platformName), properties)
    context.setPositions(positions)
    context.setVelocities(velocities)
    integrator.step(2)
    for _ in range(evaluations):
        context.getState(getEnergy=True)
    box = context.getState().getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
    box[0] *= 2.75 / 3.0
    context.setPeriodicBoxVectors(*box)
    checkpoint = context.createCheckpoint()
    integrator.step(1)
    answerIntegrator = rigid_integrator()
    answer = make_context(system, answerIntegrator, platformName)
    answer.loadCheckpoint(checkpoint)
    answerIntegrator.step(1)
    return (max_difference(positions_of(context), positions_of(answer)),
            max_difference(velocities_of(context), velocities_of(answer)))


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_box_change_between_steps_brings_new_neighbours(platformName):
    """A box shrunk between steps (no new positions) brings pairs within the cutoff that were beyond
    it and its padding in the old box. The GPU platforms rebuild their neighbour list only when a
    particle moved; the step after the change must still take those pairs (as a fresh Context does),
    here 16 pairs 0.6 nm apart across the x boundary, about 36 kJ/mol/nm each (missed, they change
    the velocities by 2e-3 nm/ps)."""
    positions, velocities = shrink_between_steps_and_compare(platformName)
    assert_below(positions=(positions, tolerance(platformName, 1e-12, 1e-9)),
                 velocities=(velocities, tolerance(platformName, 1e-12, 1e-7)))


@pytest.mark.skipif("OpenCL" not in PLATFORMS, reason="the OpenCL platform is not available")
def test_box_change_between_steps_brings_new_neighbours_on_every_device():
    """The same on a Context that shares its force evaluations between two devices (the one OpenCL
    device twice), each building the neighbour list of its own range of tiles. The platform's load
    balancing resets both lists in the first 200 evaluations and every 30th after; 205 evaluations
    come first, so that the step after the change is not one of those."""
    positions, velocities = shrink_between_steps_and_compare(
        "OpenCL", {"Precision": "double", "DeviceIndex": "0,0"}, evaluations=205)
    assert_below(positions=(positions, 1e-9), velocities=(velocities, 1e-7))


# ------------------------------------------------------------------------------------------------
# Explicit bodies are molecules, and keep the shape they were given
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
def test_explicit_bodies_are_context_molecules(water, platformName):
    system, bodies = explicit_bodies(water)
    context = started(system, rigid_integrator(bodies), platformName, water.positions)
    moleculeOf = {}
    for index, molecule in enumerate(context.getMolecules()):
        for particle in molecule:
            moleculeOf[particle] = index
    split = [body for body in bodies if len({moleculeOf[i] for i in body}) > 1]
    assert not split, f"{len(split)} of {len(bodies)} bodies span more than one of Context.getMolecules()"


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_enforce_periodic_box_keeps_explicit_bodies_whole(water, platformName):
    system, bodies = explicit_bodies(water)
    context = started(system, rigid_integrator(bodies), platformName, water.positions + 0.5 * EDGE)
    unwrapped = positions_of(context)
    wrapped = context.getState(getPositions=True, enforcePeriodicBox=True).getPositions(asNumpy=True)
    wrapped = wrapped.value_in_unit(unit.nanometer)
    assert max_difference(body_distances(wrapped, bodies), body_distances(unwrapped, bodies)) < 1e-9


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_barostat_moves_explicit_bodies_as_molecules(water, platformName):
    """Each explicit body is one of the molecules that OpenMM's barostat scales, and keeps its shape
    through the barostat's moves. On Reference the run is also compared with its answer, the same box
    held by its rigidWater constraints, which the barostat already moves as molecules: the same
    barostat seed draws the same trial moves for both, and the deterministic energies make the same
    decisions. The CPU and GPU platforms promise no such thing (their sums vary from run to run, and a
    decision near its threshold can go either way, so the volumes part after a few moves)."""
    volumes = {}
    for bodySource in ("explicit", "constraints"):
        system, bodies = water_system(water, bodySource)
        barostat = openmm.MonteCarloBarostat(1 * unit.bar, 300 * unit.kelvin, 1)
        barostat.setRandomNumberSeed(4)
        system.addForce(barostat)
        integrator = rigid_integrator(bodies)
        context = started(system, integrator, platformName, water.positions, water.velocities)
        volumes[bodySource] = [context.getState().getPeriodicBoxVolume().value_in_unit(unit.nanometer**3)]
        for _ in range(5):
            integrator.step(10)
            volumes[bodySource].append(context.getState().getPeriodicBoxVolume().value_in_unit(unit.nanometer**3))
        if bodySource == "explicit":
            molecules = {frozenset(molecule) for molecule in context.getMolecules()}
            assert all(frozenset(body) in molecules for body in bodies), "an explicit body is not one molecule"
            distances = body_distances(positions_of(context), bodies)
            shapeError = max_difference(distances, body_distances(water.positions, bodies))
    explicit, constrained = np.array(volumes["explicit"]), np.array(volumes["constraints"])
    assert_below(body_shape=(shapeError, 1e-9), volume_change=(abs(explicit[-1] / explicit[0] - 1), 0.1))
    assert explicit[-1] != explicit[0], "the barostat accepted no move in 50"
    if platformName == "Reference":
        assert_below(volumes_against_constrained_box=(np.abs(explicit / constrained - 1).max(), 1e-6))


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_explicit_body_shape_from_first_positions(water, platformName):
    """Explicit bodies take their shape from the first positions set. Positions set later that pull
    them out of shape are fitted to it, not adopted: those of a minimizer, which does not know the
    bodies, and a small distortion of every atom that a step then starts from."""
    system, bodies = explicit_bodies(water)
    # TIP3P hydrogens have no Lennard-Jones core: with the atoms free the minimizer can drop one onto
    # a neighbouring oxygen (NaN). A small core keeps the minimization finite; it still pulls the
    # bodies out of shape, since it does not know them.
    nonbonded = next(f for f in system.getForces() if isinstance(f, openmm.NonbondedForce))
    for i in range(system.getNumParticles()):
        if system.getParticleMass(i).value_in_unit(unit.dalton) < 2:
            charge = nonbonded.getParticleParameters(i)[0]
            nonbonded.setParticleParameters(i, charge, 0.1, 0.2)
    shape = body_distances(water.positions, bodies)
    atoms = started(system, openmm.VerletIntegrator(STEP), platformName, water.positions)
    systems.minimize(atoms, 10, 50)
    assert max_difference(body_distances(positions_of(atoms), bodies), shape) > 1e-3
    integrator = rigid_integrator(bodies)
    context = started(system, integrator, platformName, water.positions)
    systems.minimize(context, 10, 50)
    assert max_difference(body_distances(positions_of(context), bodies), shape) < 1e-9
    # No step from the minimized positions: the minimizer (on the CPU platform, not deterministic)
    # moves the free hydrogens into places that the fitted bodies' hydrogens may then overlap, which
    # the integrator rightly refuses as unstable. A step from a distortion of 0.004 nm per coordinate.
    distorted = water.positions + np.random.default_rng(3).normal(scale=0.004, size=water.positions.shape)
    assert max_difference(body_distances(distorted, bodies), shape) > 1e-3
    context.setPositions(distorted)
    integrator.step(1)
    assert max_difference(body_distances(positions_of(context), bodies), shape) < 1e-9


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("bodySource", ["constraints", "explicit"])
def test_molecules_split_across_the_boundary(water, bodySource, platformName):
    system, bodies = water_system(water, bodySource)
    wrapped = water.positions - EDGE * np.floor(water.positions / EDGE)
    waters = water_molecules(water)
    assert max_difference(body_distances(wrapped, waters), body_distances(water.positions, waters)) > 0.5
    runs = []
    for positions in (water.positions, wrapped):
        integrator = rigid_integrator(bodies)
        context = started(system, integrator, platformName, positions, water.velocities)
        integrator.step(20)
        runs.append((positions_of(context), kinetic_energy(context)))
    (whole, wholeEnergy), (split, splitEnergy) = runs
    positionTolerance = tolerance(platformName, 1e-8, 1e-6)
    shapeError = max_difference(body_distances(split, waters), body_distances(whole, waters))
    assert_below(body_shape=(shapeError, positionTolerance),
                 positions_minimum_image=(np.abs(minimum_image(split - whole)).max(), positionTolerance),
                 kinetic_energy_relative=(abs(splitEnergy / wholeEnergy - 1), tolerance(platformName, 1e-8, 1e-6)))


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator])
def test_blow_up_raises_at_that_step(water, integratorClass, platformName):
    system, positions = two_close_waters(water, 0.02)
    integrator = rigid_integrator(integratorClass=integratorClass)
    context = started(system, integrator, platformName, positions)
    step_raises_unstable(context, integrator, integratorClass)


def step_raises_unstable(context, integrator, integratorClass):
    """step(1) raises the "unstable" error naming the class, and the Context is back at the state the
    step started from; the message, for more checks."""
    before = positions_of(context), velocities_of(context)
    with pytest.raises(openmm.OpenMMException) as error:
        integrator.step(1)
        pytest.fail(f"step(1) did not raise; positions reached {np.abs(positions_of(context)).max():.3g} nm")
    message = str(error.value)
    assert "unstable" in message and integratorClass.__name__ in message, message
    assert np.array_equal(positions_of(context), before[0]) and np.array_equal(velocities_of(context), before[1])
    return message


def constrained_pair_turned_square(integratorClass, platformName):
    """Two free particles 0.1 nm apart along x, held by a constraint, in a periodic 3 nm box with a
    1 nm cutoff, and a body (one water) elsewhere. The second particle's velocity takes it, in the
    first drift of a 2 fs step (the whole step for Verlet, half of it for Langevin), to 0.2 nm from
    the first along y: the constrained direction is perpendicular to the old one, where the
    iteration of the constraint solver (SHAKE, CCMA) divides by zero. The displacement before the
    constraints is 0.22 nm, well inside the cutoff."""
    system = openmm.System()
    edge = 3.0
    system.setDefaultPeriodicBoxVectors(openmm.Vec3(edge, 0, 0), openmm.Vec3(0, edge, 0), openmm.Vec3(0, 0, edge))
    for mass in (12.0, 12.0, 16.0, 1.0, 1.0):
        system.addParticle(mass)
    system.addConstraint(0, 1, 0.1)
    for i, j, distance in ((2, 3, 0.09572), (2, 4, 0.09572), (3, 4, 0.15139)):
        system.addConstraint(i, j, distance)
    nonbonded = openmm.NonbondedForce()
    nonbonded.setNonbondedMethod(openmm.NonbondedForce.CutoffPeriodic)
    nonbonded.setCutoffDistance(1.0)
    for _ in range(system.getNumParticles()):
        nonbonded.addParticle(0.0, 0.3, 0.0)
    system.addForce(nonbonded)
    half = np.sqrt(0.09572**2 - (0.15139 / 2)**2)
    positions = np.array([[1.0, 1.0, 1.0], [1.1, 1.0, 1.0], [2.0, 2.0, 2.0],
                          [2.0 + 0.15139 / 2, 2.0 + half, 2.0], [2.0 - 0.15139 / 2, 2.0 + half, 2.0]])
    velocities = np.zeros_like(positions)
    firstDrift = 0.001 if integratorClass is RigidBodyLangevinIntegrator else 0.002
    velocities[1] = [-0.1 / firstDrift, 0.2 / firstDrift, 0.0]
    integrator = rigid_integrator(integratorClass=integratorClass)
    context = make_context(system, integrator, platformName)
    context.setPositions(positions)
    context.setVelocities(velocities)
    return context, integrator


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator])
def test_constraint_solver_blow_up_raises_at_that_step(integratorClass, platformName):
    """Where the constraints among free particles cannot be satisfied from a drift (the solver
    divides by zero and returns non-finite or far-flung positions, without an error of its own), the
    step stops with the "unstable" error, and the Context keeps finite positions and stays usable:
    before the check, the positions became NaN and the next force evaluation on the CPU platform
    could crash the process (seen with HMR at 8 fs)."""
    context, integrator = constrained_pair_turned_square(integratorClass, platformName)
    message = step_raises_unstable(context, integrator, integratorClass)
    # The Reference and CPU solvers leave NaN there, OpenCL's SHAKE far-flung finite positions.
    assert "non-finite" in message or "would move" in message, message
    assert "particle 0" in message or "particle 1" in message, message


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_state_after_set_velocities_is_projected(water, platformName):
    # One step first, so that the positions are rigid to rounding and only the velocities are projected.
    integrator = rigid_integrator()
    context = started(water.system, integrator, platformName, water.positions, water.velocities)
    integrator.step(1)
    masses = particleMasses(water.system)
    rng = np.random.default_rng(17)
    thermal = rng.normal(size=water.positions.shape) * np.sqrt(systems.BOLTZMANN * 300.0 / masses)[:, None]
    context.setVelocities(thermal)
    bodies = [list(integrator.getBodyParticles(b)) for b in range(integrator.getNumBodies())]
    free = sorted(set(range(len(masses))) - {i for body in bodies for i in body})
    projected = systems.rigid_motion(masses, positions_of(context), thermal, bodies, free)(0.0)[1]
    expectedEnergy = 0.5 * np.sum(masses[:, None] * projected**2)
    for stage in ("after_setVelocities", "after_step0"):
        if stage == "after_step0":
            integrator.step(0)
        state = context.getState(getVelocities=True, getEnergy=True)
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
        energy = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        assert_below(**{f"velocities_{stage}": (max_difference(velocities, projected), 1e-10),
                        f"kinetic_energy_relative_{stage}": (abs(energy / expectedEnergy - 1), 1e-10)})


# ------------------------------------------------------------------------------------------------
# numpy scalars, as stock OpenMM takes them
# ------------------------------------------------------------------------------------------------

def _three_particles():
    system = openmm.System()
    for mass in (16.0, 1.0, 1.0):
        system.addParticle(mass)
    return system


def _bound(integrator):
    """The integrator in a Reference Context of three particles; returns (integrator, context)."""
    context = openmm.Context(_three_particles(), integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(np.array([[0.0, 0.0, 0.0], [0.09572, 0.0, 0.0], [-0.024, 0.0927, 0.0]]))
    return integrator, context


def _steps_taken(integrator, count):
    integrator, context = _bound(integrator)
    integrator.step(count)
    return context.getStepCount()


def _body_query(method, index):
    integrator, context = _bound(RigidBodyIntegrator(STEP, [[0, 1, 2]]))
    return getattr(integrator, method)(index)


def _bussi_settings(integrator):
    return integrator.getTemperature(), integrator.getCollisionTime(), integrator.getStepSize()


def _set_get(target, setter, getter, *values):
    getattr(target, setter)(*values)
    return getattr(target, getter)()


def _langevin_settings(integrator):
    return integrator.getTemperature(), integrator.getFriction(), integrator.getStepSize()


def _stock_index(n):
    return _three_particles().getParticleMass(n(0))


def _stock_enum(n):
    return _set_get(openmm.NonbondedForce(), "setNonbondedMethod", "getNonbondedMethod",
                    n(openmm.NonbondedForce.CutoffPeriodic))


def _stock_step_size(n):
    return openmm.VerletIntegrator(n(STEP)).getStepSize()


def _stock_temperature(n):
    return _set_get(openmm.LangevinMiddleIntegrator(300.0, 1.0, STEP), "setTemperature", "getTemperature", n(310.0))


def _stock_seed(n):
    return _set_get(openmm.LangevinMiddleIntegrator(300.0, 1.0, STEP), "setRandomNumberSeed", "getRandomNumberSeed",
                    n(5))


def _rigid_setting(setter, getter, *values):
    return _set_get(RigidBodyIntegrator(STEP), setter, getter, *values)


def _bussi_setting(setter, getter, *values):
    return _set_get(RigidBodyBussiIntegrator(300.0, 0.1, STEP), setter, getter, *values)


# (name, numpy type, stock use, rigid use): a use takes n, which makes each number it passes, and
# returns what the calls give back. The stock use shows that stock OpenMM takes that numpy type there.
NUMPY_CASES = [
    ("step", np.int64, lambda n: _steps_taken(openmm.VerletIntegrator(STEP), n(3)),
     lambda n: _steps_taken(RigidBodyIntegrator(STEP, [[0, 1, 2]]), n(3))),
    ("getBodyParticles", np.int32, _stock_index, lambda n: list(_body_query("getBodyParticles", n(0)))),
    ("getBodyParticles", np.int64, _stock_index, lambda n: list(_body_query("getBodyParticles", n(0)))),
    ("RigidBodyIntegrator", np.float32, _stock_step_size, lambda n: RigidBodyIntegrator(n(STEP)).getStepSize()),
    ("RigidBodyIntegrator", np.float64, _stock_step_size, lambda n: RigidBodyIntegrator(n(STEP)).getStepSize()),
    ("RigidBodyLangevinIntegrator", np.float32,
     lambda n: _langevin_settings(openmm.LangevinMiddleIntegrator(n(300.0), n(1.0), n(STEP))),
     lambda n: _langevin_settings(RigidBodyLangevinIntegrator(n(300.0), n(1.0), n(STEP)))),
    ("RigidBodyBussiIntegrator", np.float32,
     lambda n: _langevin_settings(openmm.LangevinMiddleIntegrator(n(300.0), n(1.0), n(STEP))),
     lambda n: _bussi_settings(RigidBodyBussiIntegrator(n(300.0), n(0.1), n(STEP)))),
    ("RigidBodyBussiIntegrator", np.float64,
     lambda n: _langevin_settings(openmm.LangevinMiddleIntegrator(n(300.0), n(1.0), n(STEP))),
     lambda n: _bussi_settings(RigidBodyBussiIntegrator(n(300.0), n(0.1), n(STEP)))),
    ("setRotationMethod", np.int64, _stock_enum,
     lambda n: _rigid_setting("setRotationMethod", "getRotationMethod", n(RigidBodyIntegrator.NoSquish))),
    ("setSplitting", np.int64, _stock_enum,
     lambda n: _rigid_setting("setSplitting", "getSplitting", n(RigidBodyIntegrator.Omelyan2))),
    ("setMinimumMomentOfInertia", np.float32, _stock_temperature,
     lambda n: _rigid_setting("setMinimumMomentOfInertia", "getMinimumMomentOfInertia", n(0.04))),
    ("setRandomNumberSeed", np.int64, _stock_seed,
     lambda n: _bussi_setting("setRandomNumberSeed", "getRandomNumberSeed", n(5))),
    ("setRandomNumberSeed", np.int64, _stock_seed,
     lambda n: _set_get(RigidBodyLangevinIntegrator(300.0, 1.0, STEP), "setRandomNumberSeed", "getRandomNumberSeed", n(5))),
    ("setTemperature", np.float32, _stock_temperature,
     lambda n: _bussi_setting("setTemperature", "getTemperature", n(310.0))),
    ("setCollisionTime", np.float32, _stock_temperature,
     lambda n: _bussi_setting("setCollisionTime", "getCollisionTime", n(0.25))),
    ("setTemperature", np.float32, _stock_temperature,
     lambda n: _set_get(RigidBodyLangevinIntegrator(300.0, 1.0, STEP), "setTemperature", "getTemperature", n(310.0))),
]


@pytest.mark.parametrize("scalar, stockUse, rigidUse", [case[1:] for case in NUMPY_CASES],
                         ids=[f"{case[0]}-{case[1].__name__}" for case in NUMPY_CASES])
def test_numpy_scalars(scalar, stockUse, rigidUse):
    try:
        stockUse(scalar)
    except TypeError:
        pytest.skip(f"stock OpenMM does not take a numpy {scalar.__name__} there either")
    assert rigidUse(scalar) == rigidUse(lambda x: scalar(x).item())


# ------------------------------------------------------------------------------------------------
# Checkpoints
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("written, loaded", [("langevin", "plain"), ("plain", "langevin"),
                                             ("langevin", "thermostat"), ("thermostat", "langevin")])
def test_checkpoint_of_the_other_class_is_refused(written, loaded, platformName):
    positions, velocities = legacy.water_positions()
    writer, writerIntegrator = legacy_context(written, "constraints", platformName)
    writer.setPositions(positions)
    writer.setVelocities(velocities)
    writerIntegrator.step(2)
    reader, readerIntegrator = legacy_context(loaded, "constraints", platformName)
    with pytest.raises(openmm.OpenMMException) as error:
        reader.loadCheckpoint(writer.createCheckpoint())
        readerIntegrator.step(1)
    message = str(error.value)
    # Both classes by name: the reader's first, and the writer's ("RigidBodyIntegrator" alone must not
    # pass for "RigidBodyBussiIntegrator").
    readerName, writerName = type(readerIntegrator).__name__, type(writerIntegrator).__name__
    assert message.startswith(readerName + ":"), message
    assert f" {writerName}" in message, message


@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator])
@pytest.mark.parametrize("bodySource", ["constraints", "explicit"])
def test_checkpoint_continues_bit_for_bit_on_reference(water, bodySource, integratorClass):
    """On Reference a checkpoint continues exactly the run that wrote it, as stock integrators do:
    loaded into the Context that wrote it or into a new one, 200 steps later positions and velocities
    equal those of the run that went on (explicit bodies take their shapes from the first positions
    set: the new Context is given the same ones). Fitting the bodies again on load (as before) rounds
    them: 9e-12 nm after 400 Verlet steps, 1e-9 after 400 Langevin steps. A new Context whose explicit
    bodies take their shapes from the checkpoint's positions (none set before) is fitted: to rounding."""
    system, bodies = water_system(water, bodySource)
    integrator = rigid_integrator(bodies, integratorClass)
    context = started(system, integrator, "Reference", water.positions, water.velocities)
    integrator.step(10)
    checkpoint = context.createCheckpoint()
    integrator.step(200)
    expected = (positions_of(context), velocities_of(context))
    runs = []
    for setFirst in (True, False):
        again = rigid_integrator(bodies, integratorClass)
        loaded = make_context(system, again, "Reference")
        if setFirst:
            loaded.setPositions(water.positions)
        loaded.loadCheckpoint(checkpoint)
        again.step(200)
        runs.append((loaded, setFirst or bodies is None))
    context.loadCheckpoint(checkpoint)
    integrator.step(200)
    runs.append((context, True))
    for run, exact in runs:
        positions, velocities = positions_of(run), velocities_of(run)
        if exact:
            assert np.array_equal(positions, expected[0]) and np.array_equal(velocities, expected[1])
        else:
            assert max_difference(positions, expected[0]) < 1e-8


@pytest.mark.parametrize("prefix, kind", [("legacy", kind) for kind in legacy.KINDS] + [("v1", kind) for kind in legacy.V1_KINDS])
@pytest.mark.parametrize("bodySource", legacy.BODY_SOURCES)
def test_legacy_checkpoints_still_load(kind, bodySource, prefix):
    """Checkpoints of formats 0 and 1 continue the trajectory their writer took. Their Langevin
    velocities are on-step: loaded, they go half a kick back to the half-step velocities of today's
    step, which is the same in positions, so the positions agree to rounding (in the harmonic trap
    the half kick moves them by about 1e-3 nm in the five steps)."""
    context, integrator = legacy_context(kind, bodySource)
    context.loadCheckpoint((DATA / f"{legacy.stem(kind, bodySource, prefix)}.chk").read_bytes())
    integrator.step(legacy.STEPS_AFTER)
    expected = np.load(DATA / f"{legacy.stem(kind, bodySource, prefix)}.npy")
    assert max_difference(positions_of(context), expected) < 1e-12


# ------------------------------------------------------------------------------------------------
# Messages
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator])
def test_a_system_without_rigid_bodies_is_refused(water, integratorClass):
    """Water built with rigidWater=False has no rigid constraint cluster: the integrator found no body
    and ran as a plain integrator without a word. Refused, naming the likely cause; an explicit empty
    list of bodies still runs the System without bodies, as asked."""
    system, _ = explicit_bodies(water)
    with pytest.raises(openmm.OpenMMException, match=f"{integratorClass.__name__}: the System has no rigid bodies.*rigidWater=False"):
        make_context(system, rigid_integrator(None, integratorClass), "Reference")
    integrator = rigid_integrator([], integratorClass)
    context = started(system, integrator, "Reference", water.positions)
    integrator.step(2)
    assert integrator.getNumBodies() == 0


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("problem", ["coincident", "not-finite"])
def test_an_explicit_body_without_a_shape_says_why(water, problem, platformName):
    """An explicit body whose positions cannot shape it (its particles at one point, or a coordinate
    NaN) was reported by the queries that need the bodies' shapes (computeSystemTemperature(); the
    degrees of freedom count the body's kind) as positions never set; each says what is wrong with the
    positions given, as the step does. The other bodies are unaffected."""
    system, bodies = explicit_bodies(water)
    integrator = rigid_integrator(bodies)
    context = make_context(system, integrator, platformName)
    positions = np.array(water.positions)
    if problem == "coincident":
        positions[bodies[3]] = positions[bodies[3][0]]
        expected = "body 3 all sit at one point"
    else:
        positions[bodies[3][1], 2] = np.nan
        # (OpenCL reads the whole molecule back as NaN: its first particle is named there.)
        expected = "particle (" + "|".join(str(i) for i in bodies[3][:2]) + ") of body 3 has a non-finite position"
    context.setPositions(positions)
    for call in (integrator.computeSystemTemperature, lambda: integrator.step(1)):
        with pytest.raises(openmm.OpenMMException, match=f"RigidBodyIntegrator: .*{expected}"):
            call()
    assert integrator.getBodyParticles(0) == bodies[0] and integrator.getBodyParticles(3) == bodies[3]


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator])
def test_particle_twice_in_a_body(water, integratorClass, platformName):
    system, _ = explicit_bodies(water)
    with pytest.raises(openmm.OpenMMException) as error:
        make_context(system, rigid_integrator([[0, 1, 0]], integratorClass), platformName)
    message = str(error.value)
    assert message.startswith(integratorClass.__name__), message
    assert "twice" in message


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_langevin_body_constrained_to_a_free_particle(water, platformName):
    system, bodies = explicit_bodies(water)
    system.addConstraint(bodies[0][2], bodies[1][0], 0.3)
    with pytest.raises(openmm.OpenMMException) as error:
        make_context(system, rigid_integrator(bodies[:1], RigidBodyLangevinIntegrator), platformName)
    message = str(error.value)
    assert message.startswith("RigidBodyLangevinIntegrator"), message


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("ratio, applied", [(1.05, True), (1 + 1e-7, False)], ids=["5%-off", "1e-7-off"])
def test_constraint_within_an_explicit_body(water, ratio, applied, platformName):
    """A constraint inside an explicit body gives the body its length, as a constrained integrator
    would apply it to the positions: one that the positions miss by more than the constraint tolerance
    (5 %) is applied before the body takes its shape; one they meet within it (1e-7) leaves the
    positions' shape exact."""
    system, bodies = explicit_bodies(water)
    oxygen, hydrogen = bodies[0][:2]
    given = np.linalg.norm(water.positions[oxygen] - water.positions[hydrogen])
    system.addConstraint(oxygen, hydrogen, ratio * given)
    integrator = rigid_integrator(bodies)
    context = make_context(system, integrator, platformName)
    context.setPositions(water.positions)
    integrator.step(1)
    positions = positions_of(context)
    distance = np.linalg.norm(positions[oxygen] - positions[hydrogen])
    assert abs(distance - (ratio * given if applied else given)) < 1e-9


@pytest.mark.parametrize("platformName", ["Reference", "CPU"])
def test_one_particle_moved_without_notice_in_a_large_system(platformName):
    """Over 4096 particles, where the comparison of the positions with the ones the integrator wrote
    (RigidBodyDynamics::particleArraysEqual) may run on the CPU platform's threads, one range each
    (whichever is faster; TestHostThreads checks every range): a CustomIntegrator in a
    CompoundIntegrator moves only the last particle, which sends no notice. The rigid integrator's
    next step must fit the bodies to the moved positions, as a fresh Context set to that State does
    (a comparison that missed the last range would undo the move). No forces: the step is the
    integrator's alone."""
    waters = 1500  # 4500 particles
    system = openmm.System()
    lattice = np.array([(i, j, k) for i in range(30) for j in range(30) for k in range(25)])[:waters] * 0.31
    geometry = np.array([[0.0, 0.0, 0.0], [0.09572, 0.0, 0.0], [-0.0239988, 0.0926627, 0.0]])
    rng = np.random.default_rng(5)
    positions = []
    for site in lattice:
        a, _ = np.linalg.qr(rng.standard_normal((3, 3)))
        first = system.getNumParticles()
        for mass, offset in zip((15.999, 1.008, 1.008), geometry):
            system.addParticle(mass)
            positions.append(site + a @ offset)
        system.addConstraint(first, first + 1, 0.09572)
        system.addConstraint(first, first + 2, 0.09572)
        system.addConstraint(first + 1, first + 2, 0.15139)
    positions = np.array(positions)
    mover = openmm.CustomIntegrator(STEP)
    mover.addPerDofVariable("moved", 0.0)
    mover.addComputePerDof("x", "x + 0.01*moved")
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(rigid_integrator())
    compound.addIntegrator(mover)
    platform, properties = systems.platform_and_properties(platformName)
    if platformName == "CPU":
        properties["Threads"] = "2"
    context = openmm.Context(system, compound, platform, properties)
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300, 3)
    compound.step(2)
    moved = np.zeros((system.getNumParticles(), 3))
    moved[-1] = 1.0
    mover.setPerDofVariableByName("moved", [openmm.Vec3(*row) for row in moved])
    beforeMove = positions_of(context)
    compound.setCurrentIntegrator(1)
    compound.step(1)
    afterMove = full_state(context)
    shift = positions_of(context) - beforeMove
    assert np.abs(shift[:-1]).max() == 0 and np.allclose(shift[-1], 0.01), "the mover should move the last particle alone"
    compound.setCurrentIntegrator(0)
    compound.step(1)
    answerIntegrator = rigid_integrator()
    answer = openmm.Context(system, answerIntegrator, platform, properties)
    answer.setState(afterMove)
    answerIntegrator.step(1)
    difference = max_difference(positions_of(context), positions_of(answer))
    assert difference < tolerance(platformName, 1e-12, 1e-9), f"positions differ by {difference:.3g} nm from a fresh Context's"

"""RigidStateDataReporter's columns: translational and rotational kinetic energy and temperature, shadow work
and heat.

The reporter computes the kinetic energies itself, from the State's positions and velocities (numpy over the
bodies of each size), and counts the degrees of freedom from the bodies' geometry and the System. Each value is
checked against an independent one:
- the two energies add up to the State's kinetic energy, which the integrator computes itself (in the raised
  moments too), to 1e-9 relative;
- each agrees with rigidtesting.bodies.rigidKineticEnergies (per body, written apart) and, on the isolated
  cluster, with a from-scratch computation here (centre-of-mass velocities, velocities relative to them);
- on synthetic bodies built from known moments, rotations and angular velocities (split across a triclinic
  box), with the energies those give in closed form;
- the degrees of freedom are counted by hand, and agree with rigidDegreesOfFreedom() and with what
  computeSystemTemperature() divides by.
Systems: systems.cluster() (explicit bodies of every kind, free atoms joined by a constraint, a
CMMotionRemover), systems.mixed_system() (explicit waters, benzene, a linear CO2, Na+ as one particle; a free
flexible peptide with HBonds constraints and a free Cl-; periodic, moved so that bodies straddle the box) and
systems.water_box() with raised moments of inertia.
"""

import csv
import io
import xml.etree.ElementTree as ElementTree

import numpy as np
import openmm
import pytest
from openmm import app, unit

import openmmrigid
import systems
from openmmrigid import reporters
from rigidtesting.bodies import bodyKind, rigidDegreesOfFreedom, rigidKineticEnergies

GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
KINETIC_COLUMNS = ["Translational Kinetic Energy (kJ/mole)", "Rotational Kinetic Energy (kJ/mole)",
                   "Translational Temperature (K)", "Rotational Temperature (K)"]
KILOJOULES = unit.kilojoule_per_mole


def plainTopology(numParticles):
    topology = app.Topology()
    residue = topology.addResidue("X", topology.addChain())
    for _ in range(numParticles):
        topology.addAtom("X", None, residue)
    return topology


def clusterSimulation(integrator=None):
    cluster = systems.cluster(seed=8)
    system = cluster.system
    first, second = cluster.free
    system.addConstraint(first, second, float(np.linalg.norm(cluster.positions[first] - cluster.positions[second])))
    system.addForce(openmm.CMMotionRemover(3))
    if integrator is None:
        integrator = openmmrigid.RigidBodyIntegrator(0.001, cluster.bodies)
    simulation = app.Simulation(plainTopology(system.getNumParticles()), system, integrator,
                                openmm.Platform.getPlatformByName("Reference"))
    simulation.context.setPositions(cluster.positions)
    simulation.context.setVelocities(cluster.velocities)
    return simulation, cluster


def kineticReporter(output, interval, **kwargs):
    return openmmrigid.RigidStateDataReporter(
        output, interval, kineticEnergy=True, temperature=True, translationalKineticEnergy=True,
        rotationalKineticEnergy=True, translationalTemperature=True, rotationalTemperature=True, **kwargs)


def independentValues(state, cluster):
    """Translational and rotational kinetic energies (kJ/mol) and their degrees of freedom, from scratch."""
    x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    m = cluster.masses
    translational = rotational = 0.0
    rotationalDof = 0
    for body in cluster.bodies:
        mass = m[body].sum()
        velocity = m[body] @ v[body]/mass
        translational += 0.5*mass*velocity @ velocity
        rotational += 0.5*np.sum(m[body]*np.sum((v[body] - velocity)**2, axis=1))
        relative = x[body] - m[body] @ x[body]/mass
        rank = np.linalg.matrix_rank(relative, tol=1e-6) if len(body) > 1 else 0
        rotationalDof += {0: 0, 1: 2}.get(rank, 3)  # a point, a line, or a body in 2 or 3 dimensions
    translational += 0.5*np.sum(m[cluster.free]*np.sum(v[cluster.free]**2, axis=1))
    constraintsAmongFree = 1
    translationalDof = 3*len(cluster.bodies) + 3*len(cluster.free) - constraintsAmongFree - 3
    return translational, rotational, translationalDof, rotationalDof


def readCsv(text):
    lines = text.splitlines()
    assert lines[0].startswith('#"')
    header = next(csv.reader([lines[0][1:]]))
    rows = [[float(value) for value in row] for row in csv.reader(lines[1:])]
    return header, rows


def checkKineticRow(row, state, context, integrator, translationalDof, rotationalDof):
    """A row of kineticReporter(): kinetic energy, temperature and the four columns, against the State's
    kinetic energy, rigidKineticEnergies, the degrees of freedom counted by the caller and
    computeSystemTemperature()."""
    kinetic, temperature, translational, rotational, translationalT, rotationalT = row
    assert kinetic == pytest.approx(state.getKineticEnergy().value_in_unit(KILOJOULES), rel=1e-12)
    # The two parts make up the integrator's own kinetic energy.
    assert translational + rotational == pytest.approx(kinetic, rel=1e-9)
    expectedTranslational, expectedRotational = rigidKineticEnergies(context, integrator)
    assert translational == pytest.approx(expectedTranslational, rel=1e-9)
    assert rotational == pytest.approx(expectedRotational, rel=1e-9)
    assert translationalT == pytest.approx(2*translational/(translationalDof*GAS_CONSTANT), rel=1e-12)
    assert rotationalT == pytest.approx(2*rotational/(rotationalDof*GAS_CONSTANT), rel=1e-12)
    # The temperature column is the integrator's, and the two temperatures weighted by their degrees of
    # freedom make it up.
    dof = translationalDof + rotationalDof
    assert dof == rigidDegreesOfFreedom(context, integrator)
    assert temperature == pytest.approx(integrator.computeSystemTemperature().value_in_unit(unit.kelvin), rel=1e-12)
    assert temperature == pytest.approx(2*kinetic/(dof*GAS_CONSTANT), rel=1e-9)
    assert (translationalDof*translationalT + rotationalDof*rotationalT)/dof == pytest.approx(temperature, rel=1e-9)


def test_columns_match_an_independent_computation():
    simulation, cluster = clusterSimulation()
    output = io.StringIO()
    reporter = kineticReporter(output, 5, step=True)
    simulation.reporters.append(reporter)
    expected = []
    for _ in range(4):
        simulation.step(5)
        state = simulation.context.getState(getPositions=True, getVelocities=True, getEnergy=True)
        expected.append((state, independentValues(state, cluster)))
    header, rows = readCsv(output.getvalue())
    assert header == ["Step", "Kinetic Energy (kJ/mole)", "Temperature (K)"] + KINETIC_COLUMNS
    kinds = {bodyKind(cluster.masses[body], state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)[body])
             for body in cluster.bodies}
    assert {"point", "linear", "asymmetric", "symmetric", "spherical"} <= kinds
    for row, (state, (translational, rotational, translationalDof, rotationalDof)) in zip(rows, expected):
        step, kinetic, temperature, reportedTranslational, reportedRotational, tTrans, tRot = row
        assert reportedTranslational == pytest.approx(translational, rel=1e-9)
        assert reportedRotational == pytest.approx(rotational, rel=1e-9)
        assert reportedTranslational + reportedRotational == pytest.approx(
            state.getKineticEnergy().value_in_unit(KILOJOULES), rel=1e-9)
        assert tTrans == pytest.approx(2*translational/(translationalDof*GAS_CONSTANT), rel=1e-9)
        assert tRot == pytest.approx(2*rotational/(rotationalDof*GAS_CONSTANT), rel=1e-9)
    # The last row, at the Context's present state, against the helpers and computeSystemTemperature() too.
    checkKineticRow(rows[-1][1:], expected[-1][0], simulation.context, simulation.integrator,
                    *independentValues(expected[-1][0], cluster)[2:])
    assert [row[0] for row in rows] == [5, 10, 15, 20]
    # The count by hand: 27 sites, the last two free atoms joined by a constraint, 25 bodies, of which two
    # are single particles and four linear (two CO2, two CO); a CMMotionRemover.
    assert len(cluster.bodies) == 25 and len(cluster.free) == 2
    counts = {kind: sum(1 for body in cluster.bodies if bodyKind(cluster.masses[body], cluster.positions[body]) == kind)
              for kind in ("point", "linear")}
    assert counts == {"point": 2, "linear": 4}
    assert reporter._bodies.translationalDof == 3*25 + 3*2 - 1 - 3 == 77
    assert reporter._bodies.rotationalDof == 3*(25 - 2 - 4) + 2*4 == 65
    # The temperature column divides by the integrator's count, not the stock one (3 per particle less the
    # constraints), in every row.
    for row, (state, _) in zip(rows, expected):
        assert row[2] == pytest.approx(2*state.getKineticEnergy().value_in_unit(KILOJOULES)/((77 + 65)*GAS_CONSTANT),
                                       rel=1e-9)


@pytest.fixture(scope="module")
def mixed():
    return systems.mixed_system()


def cutApart(state, bodies, box, rng):
    """A copy of the State (through its XML) in which each particle of the bodies is moved by random whole box
    vectors, as a State wrapped atom by atom would have them."""
    root = ElementTree.fromstring(openmm.XmlSerializer.serialize(state))
    entries = list(root.find("Positions"))
    for body in bodies:
        for particle in body:
            shift = rng.integers(-1, 2, size=3) @ box
            for axis, name in enumerate("xyz"):
                entries[particle].set(name, repr(float(entries[particle].get(name)) + float(shift[axis])))
    return openmm.XmlSerializer.deserialize(ElementTree.tostring(root, encoding="unicode"))


@pytest.mark.parametrize("minimumMoment", [0.0, 1.0])
def test_explicit_bodies_in_a_periodic_box(mixed, minimumMoment):
    """Waters, benzene, a linear CO2 and Na+ (one particle) as explicit bodies, a flexible peptide with HBonds
    constraints and Cl- free. With raised moments of 1 amu nm^2, every water is a spherical top of that
    moment, the benzene's two least moments are raised, and the CO2's (a line's) are. A State whose bodies
    are cut apart by the box (the integrator keeps them whole in the wrapped States it gives, but a State may
    come from elsewhere) gives the same columns."""
    system = mixed.system
    bodies = mixed.waters + [mixed.benzene, mixed.co2, mixed.sodium]
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    box = np.array([v.value_in_unit(unit.nanometer) for v in system.getDefaultPeriodicBoxVectors()])
    integrator = openmmrigid.RigidBodyIntegrator(0.001, bodies)
    integrator.setMinimumMomentOfInertia(minimumMoment)
    simulation = app.Simulation(mixed.topology, system, integrator, openmm.Platform.getPlatformByName("CPU"))
    simulation.context.setPositions(mixed.positions)
    simulation.context.setVelocities(mixed.velocities)
    output = io.StringIO()
    reporter = kineticReporter(output, 3)
    simulation.reporters.append(reporter)
    simulation.step(6)
    state = simulation.context.getState(getPositions=True, getVelocities=True, getEnergy=True)
    # The count by hand: the peptide's 22 atoms and Cl- free, with the peptide's HBonds constraints (12,
    # none involving a body); 278 waters and the benzene 3 + 3, the CO2 3 + 2, Na+ 3; a CMMotionRemover.
    free = mixed.peptide + mixed.chloride
    freeConstraints = sum(1 for c in range(system.getNumConstraints())
                          if set(system.getConstraintParameters(c)[:2]) <= set(free))
    assert len(free) == 23 and freeConstraints == 12 and len(mixed.waters) == 278
    assert any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
    translationalDof = 3*23 - 12 + 3*(278 + 3) - 3
    rotationalDof = 3*278 + 3 + 2 + 0
    assert (reporter._bodies.translationalDof, reporter._bodies.rotationalDof) == (translationalDof, rotationalDof)
    header, rows = readCsv(output.getvalue())
    assert len(rows) == 2
    checkKineticRow(rows[-1], state, simulation.context, integrator, translationalDof, rotationalDof)
    cut = cutApart(state, [mixed.benzene, mixed.co2] + mixed.waters, box, np.random.default_rng(5))
    assert np.ptp(cut.getPositions(asNumpy=True).value_in_unit(unit.nanometer)[mixed.benzene], axis=0).max() > 1.0
    reporter.report(simulation, cut)
    assert readCsv(output.getvalue())[1][-1] == pytest.approx(rows[-1], rel=1e-12)
    groups = {group.size: group for group in reporter._bodies.groups}
    if minimumMoment > 0:
        # Which bodies take which path: the waters all raised (spherical), the benzene (12) and the CO2 (3,
        # linear) partly, Na+ not at all.
        assert [(len(rows), allRaised) for rows, _, _, _, allRaised in groups[3].raised] == [(278, True), (1, False)]
        assert [(len(rows), allRaised) for rows, _, _, _, allRaised in groups[12].raised] == [(1, False)]
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
        relative = [velocities[b] - masses[b] @ velocities[b]/masses[b].sum() for b in bodies]
        particlesRotational = sum(0.5*np.sum(masses[b]*np.sum(r**2, axis=1)) for b, r in zip(bodies, relative))
        assert rows[-1][3] > 1.5*particlesRotational  # the raised moments carry more at these angular velocities
    else:
        assert all(not group.raised for group in groups.values())


@pytest.fixture(scope="module")
def waterBox():
    return systems.water_box()


@pytest.mark.parametrize("minimumMoment", [0.05, 0.01])
def test_water_box_with_raised_moments(waterBox, minimumMoment):
    """Bodies found from SETTLE; 0.05 amu nm^2 raises all three TIP3P moments (0.0061, 0.0116, 0.0177), 0.01
    only the least."""
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    integrator.setMinimumMomentOfInertia(minimumMoment)
    simulation = app.Simulation(waterBox.topology, waterBox.system, integrator,
                                openmm.Platform.getPlatformByName("CPU"))
    simulation.context.setPositions(waterBox.positions)
    simulation.context.setVelocities(waterBox.velocities)
    output = io.StringIO()
    reporter = kineticReporter(output, 5)
    simulation.reporters.append(reporter)
    simulation.step(10)
    state = simulation.context.getState(getPositions=True, getVelocities=True, getEnergy=True)
    waters = waterBox.system.getNumParticles()//3
    assert integrator.getNumBodies() == waters
    # 3 translational per water less 3 for the CMMotionRemover, 3 rotational per water.
    assert any(isinstance(force, openmm.CMMotionRemover) for force in waterBox.system.getForces())
    header, rows = readCsv(output.getvalue())
    checkKineticRow(rows[-1], state, simulation.context, integrator, 3*waters - 3, 3*waters)
    (rows, _, _, _, allRaised), = reporter._bodies.groups[0].raised
    assert len(rows) == waters and allRaised == (minimumMoment == 0.05)


def randomRotations(rng, count):
    """count rotation matrices uniformly distributed on SO(3), from random unit quaternions (as
    rigidtesting.randomRotation, for many at once)."""
    quaternions = rng.normal(size=(4, count))
    w, x, y, z = quaternions/np.linalg.norm(quaternions, axis=0)
    return np.stack([np.stack([1 - 2*(y*y + z*z), 2*(x*y - w*z), 2*(x*z + w*y)], axis=-1),
                     np.stack([2*(x*y + w*z), 1 - 2*(x*x + z*z), 2*(y*z - w*x)], axis=-1),
                     np.stack([2*(x*z - w*y), 2*(y*z + w*x), 1 - 2*(x*x + y*y)], axis=-1)], axis=1)


def rigidBodies(rng, shapes, count, box, minimumMoment):
    """Synthetic rigid bodies: `count` copies of each body-frame shape (masses, principal coordinates), each
    turned by a random rotation, placed at random in the box with its particles moved by random box vectors,
    and given a random centre-of-mass velocity and angular velocity. Returns masses, positions, velocities,
    the index array of each shape's bodies, and the translational and rotational energies in closed form:
    M |V|^2 / 2 and sum_k I'_k omega_k^2 / 2 in the principal frame (I'_k = max(I_k, minimumMoment) for
    nonzero I_k; a line's axis carries nothing)."""
    masses, positions, velocities, indices = [], [], [], []
    translational = rotational = 0.0
    start = 0
    for shapeMasses, coordinates in shapes:
        shapeMasses = np.asarray(shapeMasses, dtype=float)
        coordinates = np.asarray(coordinates, dtype=float)
        coordinates = coordinates - shapeMasses @ coordinates/shapeMasses.sum()
        # The coordinates must be principal: no products of inertia.
        second = np.einsum("i,ij,ik->jk", shapeMasses, coordinates, coordinates)
        assert np.abs(second - np.diag(np.diag(second))).max() < 1e-15
        moments = np.trace(second) - np.diag(second)
        n = len(shapeMasses)
        rotations = randomRotations(rng, count)
        omega = rng.normal(scale=20.0, size=(count, 3))  # in the body frame
        velocity = rng.normal(size=(count, 3))
        relative = np.einsum("bjk,ik->bij", rotations, coordinates)
        centre = rng.uniform(0, 1, size=(count, 3)) @ box
        shift = rng.integers(-1, 2, size=(count, n, 3)) @ box
        masses.append(np.tile(shapeMasses, count))
        positions.append((centre[:, None, :] + relative + shift).reshape(-1, 3))
        velocities.append((velocity[:, None, :] + np.cross(np.einsum("bjk,bk->bj", rotations, omega)[:, None, :],
                                                           relative)).reshape(-1, 3))
        translational += 0.5*shapeMasses.sum()*np.sum(velocity**2)
        raised = np.where(moments > 1e-12*moments.max(), np.maximum(moments, minimumMoment), 0.0)
        rotational += 0.5*np.sum(raised*omega**2)
        indices.append(np.arange(start, start + n*count).reshape(count, n))
        start += n*count
    return (np.concatenate(masses), np.concatenate(positions), np.concatenate(velocities), indices, translational,
            rotational)


WATER_SHAPE = ([15.999, 1.008, 1.008], [[0.0, 0.0, 0.0065], [0.0757, 0.0, -0.0521], [-0.0757, 0.0, -0.0521]])
AMMONIA_SHAPE = ([14.007, 1.008, 1.008, 1.008],
                 [[0.0, 0.0, 0.0], [0.094, 0.0, -0.038], [-0.047, 0.0814, -0.038], [-0.047, -0.0814, -0.038]])
LINEAR_SHAPE = ([12.011, 15.999, 15.999], [[0.0, 0.0, 0.0], [0.116, 0.0, 0.0], [-0.116, 0.0, 0.0]])


@pytest.mark.parametrize("minimumMoment", [0.0, 0.01, 0.05, 0.5])
def test_vectorized_energies_of_known_rigid_motion(minimumMoment):
    """The numerics on their own, against the closed form, with bodies split across a triclinic box: waters
    (asymmetric), ammonia (symmetric) and linear triatomics; 0.01 raises some moments of the waters, 0.05 all
    of them, 0.5 every moment of every body."""
    rng = np.random.default_rng(3)
    box = np.array([[2.0, 0.0, 0.0], [0.6, 1.9, 0.0], [-0.5, 0.7, 2.1]])
    masses, positions, velocities, indices, translational, rotational = rigidBodies(
        rng, [WATER_SHAPE, AMMONIA_SHAPE, LINEAR_SHAPE], 200, box, minimumMoment)
    groups = [reporters._BodyGroup(index, masses, positions, box, minimumMoment) for index in indices]
    assert [int(np.count_nonzero(group.linear)) for group in groups] == [0, 0, 200]
    assert [group.rotationalDof for group in groups] == [600, 600, 400]
    energies = [group.kineticEnergies(positions, velocities, box, minimumMoment) for group in groups]
    assert sum(e[0] for e in energies) == pytest.approx(translational, rel=1e-12)
    assert sum(e[1] for e in energies) == pytest.approx(rotational, rel=1e-10)
    if minimumMoment == 0.0:  # the particles' own kinetic energy
        assert sum(sum(e) for e in energies) == pytest.approx(0.5*np.sum(masses*np.sum(velocities**2, axis=1)),
                                                              rel=1e-10)


def test_columns_go_before_volume_and_speed_and_work_with_langevin():
    integrator = openmmrigid.RigidBodyLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 0.001,
                                                         systems.cluster(seed=8).bodies)
    simulation, cluster = clusterSimulation(integrator)
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(
        output, 4, time=True, rotationalTemperature=True, translationalKineticEnergy=True, elapsedTime=True,
        separator="\t"))
    simulation.step(8)
    lines = output.getvalue().splitlines()
    assert lines[0] == '#"Time (ps)"\t"Translational Kinetic Energy (kJ/mole)"\t"Rotational Temperature (K)"\t' \
                       '"Elapsed Time (s)"'
    values = [float(v) for v in lines[-1].split("\t")]
    translational, rotational = rigidKineticEnergies(simulation.context, integrator)
    assert values[1] == pytest.approx(translational, rel=1e-9)
    rotationalDof = independentValues(simulation.context.getState(getPositions=True, getVelocities=True), cluster)[3]
    assert values[2] == pytest.approx(2*rotational/(rotationalDof*GAS_CONSTANT), rel=1e-9)


def test_without_the_new_columns_it_is_a_state_data_reporter():
    simulation, _ = clusterSimulation()
    rigid, stock = io.StringIO(), io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(rigid, 5, step=True, potentialEnergy=True,
                                                                   temperature=True))
    simulation.reporters.append(app.StateDataReporter(stock, 5, step=True, potentialEnergy=True, temperature=True))
    simulation.step(10)
    assert rigid.getvalue() == stock.getvalue()
    # Both print the integrator's temperature (computeSystemTemperature), not the stock count's.
    temperature = float(rigid.getvalue().splitlines()[-1].split(",")[-1])
    assert temperature == simulation.integrator.computeSystemTemperature().value_in_unit(unit.kelvin)


def test_rotational_temperature_is_nan_without_rotation():
    system = openmm.System()
    for _ in range(3):
        system.addParticle(1.0)
    integrator = openmmrigid.RigidBodyIntegrator(0.001, [[0]])
    simulation = app.Simulation(plainTopology(3), system, integrator, openmm.Platform.getPlatformByName("Reference"))
    simulation.context.setPositions(np.eye(3))
    simulation.context.setVelocities(np.ones((3, 3)))
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(output, 1, rotationalTemperature=True,
                                                                   translationalTemperature=True))
    simulation.step(1)
    translational, rotational = (float(v) for v in output.getvalue().splitlines()[1].split(","))
    assert np.isnan(rotational)
    assert translational == pytest.approx(2*(3*0.5*3.0)/(9*GAS_CONSTANT), rel=1e-12)


def test_the_columns_need_a_rigid_body_integrator():
    simulation, _ = clusterSimulation(openmm.VerletIntegrator(0.001))
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(io.StringIO(), 1, rotationalKineticEnergy=True))
    with pytest.raises(ValueError, match="rotationalKineticEnergy need a RigidBodyIntegrator"):
        simulation.step(1)


@pytest.mark.parametrize("thermostat", ["langevin", "bussi"])
def test_shadow_work_and_heat_columns(thermostat):
    """The columns are the integrator's sums (which test_shadow_work.py checks) at the report; one switch,
    setMeasureShadowWork(True), measures both."""
    bodies = systems.cluster(seed=8).bodies
    if thermostat == "langevin":
        integrator = openmmrigid.RigidBodyLangevinIntegrator(300, 5, 0.002, bodies)
    else:
        integrator = openmmrigid.RigidBodyBussiIntegrator(300, 0.1, 0.002, bodies)
    integrator.setMeasureShadowWork(True)
    simulation, _ = clusterSimulation(integrator)
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(output, 5, step=True, totalEnergy=True,
                                                                   shadowWork=True, heat=True))
    simulation.step(20)
    header, rows = readCsv(output.getvalue())
    assert header[-2:] == ["Shadow Work (kJ/mole)", "Heat (kJ/mole)"]
    assert rows[-1][2] == integrator.getShadowWork().value_in_unit(KILOJOULES)
    assert rows[-1][3] == integrator.getHeat().value_in_unit(KILOJOULES)
    assert len(rows) == 4 and rows[0][3] != 0.0


@pytest.mark.parametrize("column", ["shadowWork", "heat"])
def test_shadow_work_and_heat_columns_need_the_measurement(column):
    simulation, _ = clusterSimulation(openmmrigid.RigidBodyLangevinIntegrator(300, 5, 0.002,
                                                                              systems.cluster(seed=8).bodies))
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(io.StringIO(), 1, **{column: True}))
    with pytest.raises(ValueError, match=rf"{column} needs .*setMeasureShadowWork\(True\)"):
        simulation.step(1)

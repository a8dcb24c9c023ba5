"""RigidBodyIntegrator with what OpenMM scripts use around an integrator: barostats, CMMotionRemover,
integration force groups, DCDReporter, and positions or velocities set from outside."""

import struct

import numpy as np
import openmm
import pytest
from openmm import app, unit

import openmmrigid
import rigidtesting
import systems
from rigidtesting.bodies import bodyKind, rigidDegreesOfFreedom

PLATFORMS = systems.PLATFORMS


def water_box(edge=1.4, barostat=False, cmMotionRemover=False):
    forceField = app.ForceField("tip3p.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forceField, model="tip3p", boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.6*unit.nanometer,
                                     rigidWater=True, removeCMMotion=cmMotionRemover)
    if barostat:
        system.addForce(openmm.MonteCarloBarostat(1*unit.bar, 300*unit.kelvin, 2))
    positions = np.array(modeller.positions.value_in_unit(unit.nanometer))
    return system, positions


def make_context(system, integrator, platformName):
    """A Context; on CPU with deterministic force summation, so that two runs can be compared bit for
    bit; on a GPU platform in double precision."""
    return systems.make_context(system, integrator, platformName)


def minimized_context(system, positions, integrator, platformName):
    context = make_context(system, integrator, platformName)
    context.setPositions(positions)
    systems.minimize(context, 10, 100)
    context.setVelocitiesToTemperature(300*unit.kelvin, 5)
    return context


def constraint_errors(system, positions):
    errors = []
    for c in range(system.getNumConstraints()):
        i, j, distance = system.getConstraintParameters(c)
        errors.append(abs(np.linalg.norm(positions[i] - positions[j]) - distance.value_in_unit(unit.nanometer)))
    return np.array(errors)


def state_arrays(context):
    state = context.getState(getPositions=True, getVelocities=True)
    return (np.array(state.getPositions().value_in_unit(unit.nanometer)),
            np.array(state.getVelocities().value_in_unit(unit.nanometer/unit.picosecond)))


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_barostat_moves_keep_bodies_rigid(platformName):
    system, positions = water_box(barostat=True)
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    context = minimized_context(system, positions, integrator, platformName)
    volumes = []
    for _ in range(10):
        integrator.step(10)
        box = context.getState().getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
        volumes.append(np.linalg.det(box))
        current, velocities = state_arrays(context)
        # Rigid to rounding after every accepted or rejected move (the barostat scales molecule centres).
        assert constraint_errors(system, current).max() < 1e-10
        assert np.all(np.isfinite(velocities))
    assert len(set(np.round(volumes, 12))) > 1, "no barostat move was accepted; the test checks nothing"


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_cm_motion_remover(platformName):
    system, positions = water_box(cmMotionRemover=True)
    masses = rigidtesting.particleMasses(system)
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    context = minimized_context(system, positions, integrator, platformName)
    # Give the whole box a drift the remover must take out.
    _, velocities = state_arrays(context)
    context.setVelocities(velocities + np.array([0.5, -0.3, 0.2]))
    integrator.step(3)
    _, velocities = state_arrays(context)
    momentum = (masses[:, None]*velocities).sum(axis=0)
    scale = np.sqrt((masses[:, None]*velocities**2).sum()*masses.sum())
    # The remover acts at the start of each step; what the last step adds is the impulse of the net
    # force, zero but for rounding: about 1e-10 on Reference, but on CPU its single-precision forces
    # sum to about 0.5 kJ/mol/nm, an impulse of 1e-3 against a drift of 1e4 amu nm/ps taken out.
    netForce = context.getState(getForces=True).getForces(asNumpy=True).value_in_unit(
        unit.kilojoule_per_mole/unit.nanometer).sum(axis=0)
    assert np.linalg.norm(momentum) < 1e-6*scale + 2*0.002*np.linalg.norm(netForce)
    # The degrees of freedom include the 3 the remover takes away (the same count as OpenMM's: 3 per
    # massive particle, less one per constraint and 3 for the remover), and the temperature is the
    # kinetic energy's in them.
    dof = 6*integrator.getNumBodies() - 3
    assert dof == 3*int((masses > 0).sum()) - system.getNumConstraints() - 3
    assert rigidDegreesOfFreedom(context, integrator) == dof
    kinetic = context.getState(getEnergy=True).getKineticEnergy()
    expected = (2*kinetic/(dof*unit.MOLAR_GAS_CONSTANT_R)).value_in_unit(unit.kelvin)
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(expected, rel=1e-9)


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_integration_force_groups(platformName):
    """Integrating only group 0 of a two-group system is the same as a system with group 0 alone."""
    system, positions = water_box()
    extra = openmm.CustomExternalForce("0.5*k*(x^2 + y^2 + z^2)")
    extra.addGlobalParameter("k", 50.0)
    for i in range(system.getNumParticles()):
        if system.getParticleMass(i) > 0*unit.dalton:
            extra.addParticle(i, [])
    extra.setForceGroup(1)
    system.addForce(extra)
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    integrator.setIntegrationForceGroups(1 << 0)
    context = minimized_context(system, positions, integrator, platformName)
    start = context.getState(getPositions=True, getVelocities=True)
    # Two CPU Contexts give the same positions forces that differ by float rounding (their neighbour
    # lists were built at different positions, so the sums run in another order: up to 6e-4 kJ/mol/nm
    # seen), and the motion of liquid water amplifies that: after 20 steps two runs of one System
    # differ by 3e-8 nm typically and occasionally by more than 1e-6. A few steps keep the comparison
    # at the rounding level (6 steps); Reference, in double precision, is compared over 20.
    steps = 20 if platformName == "Reference" else 6
    integrator.step(steps)
    withGroups, _ = state_arrays(context)

    alone = openmm.System()
    for i in range(system.getNumParticles()):
        alone.addParticle(system.getParticleMass(i))
    for c in range(system.getNumConstraints()):
        alone.addConstraint(*system.getConstraintParameters(c))
    alone.setDefaultPeriodicBoxVectors(*system.getDefaultPeriodicBoxVectors())
    for force in system.getForces():
        if force.getForceGroup() == 0:
            alone.addForce(openmm.XmlSerializer.clone(force))
    reference = openmmrigid.RigidBodyIntegrator(0.002)
    referenceContext = make_context(alone, reference, platformName)
    referenceContext.setState(start)
    reference.step(steps)
    withoutGroup, _ = state_arrays(referenceContext)
    tolerance = 1e-9 if platformName == "Reference" else 1e-6
    assert np.abs(withGroups - withoutGroup).max() < tolerance
    # And the excluded group does matter: integrating both groups gives another trajectory.
    context.setState(start)
    integrator.setIntegrationForceGroups(0b11)
    integrator.step(steps)
    bothGroups, _ = state_arrays(context)
    assert np.abs(bothGroups - withoutGroup).max() > 1e-4


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_dcd_reporter(platformName, tmp_path):
    system, positions = water_box()
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    forceField = app.ForceField("tip3p.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forceField, model="tip3p", boxSize=openmm.Vec3(1.4, 1.4, 1.4)*unit.nanometer)
    simulation = app.Simulation(modeller.topology, system, integrator, openmm.Platform.getPlatformByName(platformName))
    simulation.context.setPositions(positions)
    systems.minimize(simulation.context, 10, 100)
    path = tmp_path/"trajectory.dcd"
    simulation.reporters.append(app.DCDReporter(str(path), 5))
    simulation.step(20)
    del simulation  # closes the file
    header = path.read_bytes()[:100]
    frames = struct.unpack("<i", header[8:12])[0]
    assert frames == 4


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_set_positions_and_velocities_are_projected(platformName):
    """Non-rigid positions and velocities set from outside become rigid motion with the same momentum."""
    system, positions = water_box()
    for force in list(system.getForces()):
        system.removeForce(0)
    masses = rigidtesting.particleMasses(system)
    integrator = openmmrigid.RigidBodyIntegrator(0.001)
    context = make_context(system, integrator, platformName)
    rng = np.random.default_rng(3)
    noisy = positions + rng.normal(scale=2e-3, size=positions.shape)
    velocities = rng.normal(scale=0.5, size=positions.shape)
    context.setPositions(noisy)
    context.setVelocities(velocities)
    integrator.step(1)
    after, newVelocities = state_arrays(context)
    assert constraint_errors(system, after).max() < 1e-10
    for b in range(integrator.getNumBodies()):
        members = integrator.getBodyParticles(b)
        m = masses[members]
        # The centre moves with the centre-of-mass velocity of what was set (no forces act).
        before = (m[:, None]*noisy[members]).sum(axis=0)/m.sum()
        now = (m[:, None]*after[members]).sum(axis=0)/m.sum()
        velocity = (m[:, None]*velocities[members]).sum(axis=0)/m.sum()
        assert np.abs(now - before - 0.001*velocity).max() < 1e-12
        # Rigid velocities: no component stretches any pair.
        for i in range(len(members)):
            for j in range(i + 1, len(members)):
                separation = after[members[i]] - after[members[j]]
                relative = newVelocities[members[i]] - newVelocities[members[j]]
                assert abs(separation @ relative) < 1e-12
    # Projection removes the internal (non-rigid) kinetic energy, never adds any.
    assert (masses[:, None]*newVelocities**2).sum() < (masses[:, None]*velocities**2).sum()


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_set_velocities_to_temperature(platformName):
    system, positions = water_box()
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    context = minimized_context(system, positions, integrator, platformName)
    integrator.step(1)
    current, velocities = state_arrays(context)
    for c in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(c)
        assert abs((current[i] - current[j]) @ (velocities[i] - velocities[j])) < 1e-10
    temperature = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    assert 150 < temperature < 450


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_kinds_of_symmetric_bodies_far_from_the_origin(platformName):
    """Rounding of coordinates a few nm from the origin must not turn a symmetric shape asymmetric: the
    shapes the Context reports, as set and after free rotation, keep their kind (moments within 1e-10
    relative are equal, as the integrator counts them; rigidtesting.bodies), and each body has its 6
    degrees of freedom."""
    rng = np.random.default_rng(11)
    tetrahedron = 0.1/np.sqrt(3.0)*np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)
    angles = 2*np.pi*np.arange(3)/3
    pyramid = np.vstack([[0.0, 0.0, 0.04], np.column_stack([0.094*np.cos(angles), 0.094*np.sin(angles), np.zeros(3)])])
    shapes = [("spherical", tetrahedron, [1.0, 1.0, 1.0, 1.0]), ("symmetric", pyramid, [14.0, 1.0, 1.0, 1.0])]
    system = openmm.System()
    positions, bodies, expected = [], [], []
    for k in range(40):
        kind, shape, masses = shapes[k % 2]
        rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        centre = rng.uniform(2.0, 6.0, size=3)
        members = []
        for point, mass in zip(shape @ rotation.T + centre, masses):
            members.append(system.addParticle(mass))
            positions.append(point)
        bodies.append(members)
        expected.append(kind)
    integrator = openmmrigid.RigidBodyIntegrator(0.001, bodies)
    context = make_context(system, integrator, platformName)
    context.setPositions(np.array(positions))
    masses = rigidtesting.particleMasses(system)

    def kinds():
        current = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        return [bodyKind(masses[body], current[body]) for body in bodies]
    assert kinds() == expected
    # Spin every body (rigid velocities: a random angular velocity about its centre) and let it rotate.
    centred = np.array(positions)
    velocities = np.zeros_like(centred)
    for body in bodies:
        centre = masses[body] @ centred[body]/masses[body].sum()
        velocities[body] = np.cross(rng.normal(scale=5.0, size=3), centred[body] - centre)
    context.setVelocities(velocities)
    integrator.step(20)
    assert kinds() == expected
    assert rigidDegreesOfFreedom(context, integrator) == 6*len(bodies)

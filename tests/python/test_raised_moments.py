"""Raised moments of inertia (RigidBodyIntegratorBase.setMinimumMomentOfInertia), the rigid-body
counterpart of hydrogen mass repartitioning:

- the moments the dynamics uses are the particles' own with every nonzero one raised to the floor,
  in the same axes (the kinetic energy of a turn about each principal axis); a water raised past its
  largest moment turns as a spherical top; the zero moment of a linear body stays zero and a point
  stays a point (the degrees of freedom the temperature counts);
- a free body moves as the exact free rotor of the raised moments with the angular velocity of its
  particles' velocities (openmmrigid.FreeRotor as an independent reference), on every platform;
- every way of writing velocities keeps the angular velocity (setVelocities, a checkpoint loaded
  into a new Context, the momenta rebuilt after a CMMotionRemover): velocities read back equal those
  written, and the kinetic energy reported is that of the raised moments, sum L_k^2 / (2 I'_k) (a
  projection that took the particles' angular momentum as the body's would drain the rotation);
- setVelocitiesToTemperature() draws each body's rotation from the Maxwell-Boltzmann distribution of
  the raised moments, and takes RigidBodyLangevinIntegrator's half-step offset with them;
- RigidStateDataReporter's columns read the kinetic energy of the raised moments;
- the configurational distribution does not change: dipoles in a uniform field sample <cos theta>
  = coth(x) - 1/x with and without raised moments, and a water box reads the bath temperature in
  translation and rotation with them;
- every mass and the minimum moment times 4, at twice the step and half the friction, is the same
  run bit for bit on Reference with velocities halved (the scaling benchmarks/studies/step_cap.py reads its
  doubled-mass runs by);
- energy is conserved without a thermostat, and bad values are refused with the class named.
"""

import io

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import openmmrigid
import rigidtesting
import systems
from openmmrigid import RigidBodyIntegrator, RigidBodyLangevinIntegrator
from rigidtesting.bodies import bodyKind, principalMoments, rigidDegreesOfFreedom, rigidKineticEnergies
from test_langevin import BOLTZMANN, assert_water_temperatures, block_mean, small_water_box  # noqa: F401

AMU_NM2 = unit.amu * unit.nanometer**2


def raised(moments, floor):
    moments = np.asarray(moments, dtype=float)
    return np.where(moments > 0.0, np.maximum(moments, floor), 0.0)


def body_omegas(masses, positions, velocities, bodies):
    """Each body's angular velocity (lab frame) fitted to its particles' velocities, its principal
    moments (ascending) and axes (columns), and its centre-of-mass velocity."""
    result = []
    for body in bodies:
        m, x, v = masses[body], positions[body], velocities[body]
        centre, velocity = m @ x / m.sum(), m @ v / m.sum()
        r = x - centre
        inertia = sum(mi * (ri @ ri * np.eye(3) - np.outer(ri, ri)) for mi, ri in zip(m, r))
        moments, axes = np.linalg.eigh(inertia)
        l = sum(mi * np.cross(ri, vi - velocity) for mi, ri, vi in zip(m, r, v))
        bodyL = axes.T @ l
        bodyOmega = np.where(moments > 1e-9 * moments[-1], bodyL / np.where(moments > 0, moments, 1.0), 0.0)
        result.append((axes @ bodyOmega, moments, axes, velocity))
    return result


def kinetic_energy_of_raised(masses, positions, velocities, bodies, free, floor):
    """sum M V^2 / 2 + sum_k I'_k omega_k^2 / 2 over the bodies, plus the free particles' m v^2 / 2."""
    energy = 0.5 * np.sum(masses[free, None] * velocities[free] ** 2)
    for body, (omega, moments, axes, velocity) in zip(bodies, body_omegas(masses, positions, velocities, bodies)):
        bodyOmega = axes.T @ omega
        energy += 0.5 * masses[body].sum() * velocity @ velocity
        energy += 0.5 * np.sum(raised(np.where(moments > 1e-9 * moments[-1], moments, 0.0), floor) * bodyOmega**2)
    return energy


# ------------------------------------------------------------------------------------------------
# The moments
# ------------------------------------------------------------------------------------------------

def test_moments_are_raised_to_the_floor_in_the_same_axes():
    """Each body of the cluster (every kind) turned at 1 rad/ps about each principal axis of its
    particles, nothing else moving, has the kinetic energy I'_k / 2 of that axis's raised moment
    (1e-13 relative): the moments are the particles' own, every nonzero one raised to the floor, in
    the same axes. The temperature counts the degrees of freedom of the particles' kinds (a linear
    body's zero moment stays zero: two rotational ones; a point none)."""
    cluster = systems.cluster(seed=3, grid=(3, 3, 2), forces=False)
    floor = 0.012
    integrator = RigidBodyIntegrator(0.001, cluster.bodies)
    integrator.setMinimumMomentOfInertia(floor * AMU_NM2)
    assert integrator.getMinimumMomentOfInertia().value_in_unit(AMU_NM2) == floor
    context = systems.make_context(cluster.system, integrator, "Reference")
    context.setPositions(cluster.positions)
    kinds = {bodyKind(cluster.masses[body], cluster.positions[body]) for body in cluster.bodies}
    assert kinds >= {"point", "linear", "symmetric", "asymmetric", "spherical"}
    raisedSome = keptSome = False
    for body in cluster.bodies:
        if len(body) == 1:
            continue
        _, moments, axes, _ = body_omegas(cluster.masses, cluster.positions, np.zeros_like(cluster.positions), [body])[0]
        moments = np.where(moments > 1e-9 * moments[-1], moments, 0.0)
        relative = cluster.positions[body] - cluster.masses[body] @ cluster.positions[body] / cluster.masses[body].sum()
        for k in range(3):
            velocities = np.zeros_like(cluster.positions)
            velocities[body] = np.cross(axes[:, k], relative)
            context.setVelocities(velocities)
            kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
            if moments[k] == 0.0:
                assert kinetic < 1e-25  # about a linear body's axis: no particle moves
            else:
                assert kinetic == pytest.approx(0.5 * raised(moments, floor)[k], rel=1e-13)
            raisedSome |= 0 < moments[k] < floor
            keptSome |= moments[k] > floor
    assert raisedSome and keptSome
    context.setVelocities(cluster.velocities)
    kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(
        2 * kinetic / (rigidDegreesOfFreedom(context, integrator) * BOLTZMANN), rel=1e-12)


def test_a_water_raised_past_its_largest_moment_is_a_spherical_top():
    """A water (the cluster's first body) with every moment raised to 0.05 amu nm^2 turns freely about
    any axis at a constant angular velocity (1e-10 relative after 0.05 ps, a radian), its kinetic
    energy 0.05 omega^2 / 2; without the floor the same water tumbles."""
    cluster = systems.cluster(seed=3, grid=(3, 3, 2), forces=False)
    water = cluster.bodies[0]
    assert np.all(principalMoments(cluster.masses[water], cluster.positions[water]) < 0.05)
    omega = np.array([5.0, 10.0, 15.0])
    relative = cluster.positions[water] - cluster.masses[water] @ cluster.positions[water] / cluster.masses[water].sum()
    velocities = np.zeros_like(cluster.positions)
    velocities[water] = np.cross(omega, relative)
    for floor in (0.05, 0.0):
        integrator = RigidBodyIntegrator(0.001, cluster.bodies)
        integrator.setMinimumMomentOfInertia(floor)
        context = systems.make_context(cluster.system, integrator, "Reference")
        context.setPositions(cluster.positions)
        context.setVelocities(velocities)
        integrator.step(50)
        turned = body_omegas(cluster.masses, systems.positions_of(context), systems.velocities_of(context), [water])[0][0]
        change = np.linalg.norm(turned - omega) / np.linalg.norm(omega)
        if floor > 0:
            assert change < 1e-10, turned
            kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
            assert kinetic == pytest.approx(0.5 * floor * omega @ omega, rel=1e-12)
        else:
            assert change > 0.01, turned


def test_bad_minimum_moments_are_refused():
    for integrator in (RigidBodyIntegrator(0.001), RigidBodyLangevinIntegrator(300, 1, 0.001)):
        name = type(integrator).__name__
        for bad in (-0.01, float("nan"), float("inf"), 100.001, 1e50):
            with pytest.raises(openmm.OpenMMException, match=f"{name}: the minimum moment of inertia .* must be between 0 and 100"):
                integrator.setMinimumMomentOfInertia(bad)
        assert integrator.getMinimumMomentOfInertia().value_in_unit(AMU_NM2) == 0.0
    cluster = systems.cluster(seed=3, grid=(2, 2, 2), forces=False)
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.001, cluster.bodies)
    integrator.setMinimumMomentOfInertia(0.02)
    context = systems.make_context(cluster.system, integrator, "Reference")
    context.setPositions(cluster.positions)
    integrator.setMinimumMomentOfInertia(0.02)  # the same value: nothing changes
    with pytest.raises(openmm.OpenMMException, match="RigidBodyLangevinIntegrator: the minimum moment of inertia cannot change"):
        integrator.setMinimumMomentOfInertia(0.03)
    integrator.step(2)
    assert integrator.getMinimumMomentOfInertia().value_in_unit(AMU_NM2) == 0.02


# ------------------------------------------------------------------------------------------------
# Free motion, projections and kinetic energy
# ------------------------------------------------------------------------------------------------

FLOOR = 0.03


@pytest.mark.parametrize("platform", systems.PLATFORMS)
def test_free_bodies_move_as_the_exact_rotor_of_the_raised_moments(platform):
    """No forces: after 40 steps of 5 fs every body is where the exact free rotor with the raised
    moments and the particles' angular velocity puts it, and the velocities read back are those of
    that rotor (not of the particles' moments: they differ by up to a factor 8 here)."""
    cluster = systems.cluster(seed=4, grid=(2, 2, 2), forces=False)
    exact = systems.rigid_motion(cluster.masses, cluster.positions, cluster.velocities, cluster.bodies, cluster.free,
                                 minimumMoment=FLOOR)
    unraised = systems.rigid_motion(cluster.masses, cluster.positions, cluster.velocities, cluster.bodies, cluster.free)
    integrator = RigidBodyIntegrator(0.005, cluster.bodies)
    integrator.setMinimumMomentOfInertia(FLOOR)
    context = systems.make_context(cluster.system, integrator, platform)
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    double = platform in ("Reference", "CPU")
    tolerance = 1e-9 if double else 1e-5
    np.testing.assert_allclose(systems.velocities_of(context), cluster.velocities, atol=tolerance * 10, rtol=0)
    integrator.step(40)
    positions, velocities = exact(0.2)
    assert np.max(np.abs(systems.positions_of(context) - positions)) < tolerance
    assert np.max(np.abs(systems.velocities_of(context) - velocities)) < 10 * tolerance
    assert np.max(np.abs(unraised(0.2)[0] - positions)) > 0.01


@pytest.mark.parametrize("platform", systems.PLATFORMS)
def test_velocities_and_kinetic_energy_with_raised_moments(platform):
    """Rigid velocities set in the Context read back unchanged (the projection keeps the angular
    velocity), and the kinetic energy (State, the temperature) is that of the raised moments, computed
    here from the velocities with numpy, and rigidtesting.bodies.rigidKineticEnergies's translational
    and rotational parts add up to it."""
    cluster = systems.cluster(seed=6, grid=(3, 3, 2))
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.001, cluster.bodies)
    integrator.setMinimumMomentOfInertia(FLOOR)
    context = systems.make_context(cluster.system, integrator, platform)
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    double = platform in ("Reference", "CPU")
    np.testing.assert_allclose(systems.velocities_of(context), cluster.velocities, atol=1e-10 if double else 1e-5, rtol=0)
    expected = kinetic_energy_of_raised(cluster.masses, cluster.positions, cluster.velocities, cluster.bodies, cluster.free, FLOOR)
    particles = 0.5 * np.sum(cluster.masses[:, None] * cluster.velocities**2)
    assert expected > 1.5 * particles  # raised moments: the test can tell the two apart
    rtol = 1e-10 if double else 1e-5
    state = context.getState(getEnergy=True)
    assert state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole) == pytest.approx(expected, rel=rtol)
    assert sum(rigidKineticEnergies(context, integrator)) == pytest.approx(expected, rel=rtol)
    temperature = 2 * expected / (rigidDegreesOfFreedom(context, integrator) * BOLTZMANN)
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(temperature, rel=rtol)


@pytest.mark.parametrize("platform", systems.PLATFORMS)
def test_checkpoint_and_cmmotionremover_keep_the_raised_momenta(platform):
    """A checkpoint loaded into a new Context continues with the same kinetic energy (and, on
    Reference, the same trajectory: 1e-9 nm after 50 steps); with a CMMotionRemover, whose changes
    the step takes back into the bodies' momenta from the particles, the energy of the raised moments
    is conserved (a step that rebuilt the momenta with the particles' moments would lose most of the
    rotational energy at once)."""
    cluster = systems.cluster(seed=8, grid=(3, 3, 2), drift=(0.2, -0.1, 0.3))
    cluster.system.addForce(openmm.CMMotionRemover(1))
    integrator = RigidBodyIntegrator(0.001, cluster.bodies)
    integrator.setMinimumMomentOfInertia(FLOOR)
    context = systems.make_context(cluster.system, integrator, platform)
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    integrator.step(20)
    first = context.getState(getEnergy=True)
    checkpoint = context.createCheckpoint()
    integrator.step(50)
    last = context.getState(getEnergy=True, getPositions=True)
    copy = RigidBodyIntegrator(0.001, cluster.bodies)
    copy.setMinimumMomentOfInertia(FLOOR)
    copyContext = systems.make_context(cluster.system, copy, platform)
    copyContext.loadCheckpoint(checkpoint)
    rtol = 1e-10 if platform == "Reference" else 1e-5
    assert copyContext.getState(getEnergy=True).getKineticEnergy() / unit.kilojoule_per_mole == pytest.approx(
        first.getKineticEnergy() / unit.kilojoule_per_mole, rel=rtol)
    if platform == "Reference":
        copy.step(50)
        assert np.max(np.abs(systems.positions_of(copyContext) - last.getPositions(asNumpy=True).value_in_unit(unit.nanometer))) < 1e-9
    energy = lambda s: (s.getKineticEnergy() + s.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole)
    kinetic = first.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert abs(energy(last) - energy(first)) < 1e-3 * kinetic


def test_velocities_to_temperature_follow_the_raised_moments():
    """setVelocitiesToTemperature(): about each principal axis, omega_k^2 I'_k / kT averages to 1
    over 400 free waters (each axis within 4.5 standard errors of the chi-square mean; the particles'
    own moments would give I'_k / I_k, 2.3 to 6.5 here)."""
    waters = systems.cluster(seed=2, grid=(10, 8, 5), spacing=0.4, forces=False)
    bodies = [b for b in waters.bodies if len(b) == 3 and np.allclose(sorted(waters.masses[b]), sorted(waters.masses[waters.bodies[0]]))]
    temperature = 300.0
    integrator = RigidBodyIntegrator(0.001, waters.bodies)
    integrator.setMinimumMomentOfInertia(0.04)
    context = systems.make_context(waters.system, integrator, "Reference")
    context.setPositions(waters.positions)
    context.setVelocitiesToTemperature(temperature, 5)
    velocities = systems.velocities_of(context)
    kT = BOLTZMANN * temperature
    ratios = []
    for omega, moments, axes, _ in body_omegas(waters.masses, systems.positions_of(context), velocities, bodies):
        ratios.append((axes.T @ omega) ** 2 * raised(moments, 0.04) / kT)
    ratios = np.array(ratios)
    assert len(ratios) >= 300
    mean = ratios.mean(axis=0)
    error = np.sqrt(2.0 / len(ratios))
    assert np.all(np.abs(mean - 1.0) < 4.5 * error), mean


# ------------------------------------------------------------------------------------------------
# What is sampled
# ------------------------------------------------------------------------------------------------

def dipoles_in_a_field(count=300, field=100.0, seed=9):
    """count TIP3P-shaped waters (rigid by constraints) far apart, no interactions, in a uniform
    field along z (kJ/mol/nm per unit charge) acting on their charges: each samples
    p(cos theta) ~ exp(x cos theta), x = mu E / kT."""
    rng = np.random.default_rng(seed)
    oh, angle = 0.09572, np.radians(104.52)
    template = np.array([[0.0, 0.0, 0.0], [oh, 0.0, 0.0], [oh * np.cos(angle), oh * np.sin(angle), 0.0]])
    masses, charges = [15.99943, 1.007947, 1.007947], [-0.834, 0.417, 0.417]
    system = openmm.System()
    external = openmm.CustomExternalForce("-q*field*z")
    external.addGlobalParameter("field", field)
    external.addPerParticleParameter("q")
    positions = []
    side = int(np.ceil(count ** (1 / 3)))
    for n in range(count):
        site = np.array([n % side, (n // side) % side, n // side**2]) * 1.0
        rotation = systems.randomRotation(rng)
        first = system.getNumParticles()
        for k in range(3):
            system.addParticle(masses[k])
            external.addParticle(first + k, [charges[k]])
            positions.append(site + rotation @ template[k])
        system.addConstraint(first, first + 1, oh)
        system.addConstraint(first, first + 2, oh)
        system.addConstraint(first + 1, first + 2, np.linalg.norm(template[1] - template[2]))
    system.addForce(external)
    dipole = np.array(charges) @ template
    return system, np.array(positions), np.linalg.norm(dipole), dipole


@pytest.mark.parametrize("floor", [0.0, 0.04])
def test_dipoles_in_a_field_sample_the_same_orientations(floor):
    """<cos theta> of 300 independent rigid dipoles in a field is the Langevin function
    coth(x) - 1/x (x = mu E / kT = 1.96 here: 0.530) within 4.5 standard errors of the mean over the
    bodies (each body's time average is one independent sample), with and without raised moments;
    so is <cos^2 theta> = 1 - 2 <cos theta> / x."""
    temperature = 300.0
    system, positions, mu, dipole = dipoles_in_a_field()
    x = mu * 100.0 / (BOLTZMANN * temperature)
    integrator = RigidBodyLangevinIntegrator(temperature, 5.0, 0.004)
    integrator.setMinimumMomentOfInertia(floor)
    integrator.setRandomNumberSeed(17)
    context = systems.make_context(system, integrator, "Reference")
    context.setPositions(positions)
    context.setVelocitiesToTemperature(temperature, 3)
    integrator.step(500)
    n = system.getNumParticles() // 3
    charges = np.tile([-0.834, 0.417, 0.417], n)
    cosines = []
    for _ in range(300):
        integrator.step(5)
        p = systems.positions_of(context)
        moments = (charges[:, None] * p).reshape(n, 3, 3).sum(axis=1)
        cosines.append(moments[:, 2] / np.linalg.norm(moments, axis=1))
    cosines = np.array(cosines)
    expected = 1 / np.tanh(x) - 1 / x
    perBody = cosines.mean(axis=0)
    error = perBody.std(ddof=1) / np.sqrt(n)
    print(f"floor {floor}: <cos> {perBody.mean():.4f} +- {error:.4f}, exact {expected:.4f}")
    assert error < 0.02
    assert abs(perBody.mean() - expected) < 4.5 * error
    squares = (cosines**2).mean(axis=0)
    squareError = squares.std(ddof=1) / np.sqrt(n)
    assert abs(squares.mean() - (1 - 2 * expected / x)) < 4.5 * squareError


def test_water_reads_the_bath_temperature_with_raised_moments(small_water_box):
    """About 100 TIP3P waters, every moment raised to 0.04 amu nm^2 (spherical tops), 4 fs, friction
    20/ps: the translational, rotational and reported temperatures are 300 K within 4.5 block
    standard errors and 1.5 %."""
    system, state = small_water_box
    integrator = RigidBodyLangevinIntegrator(300 * unit.kelvin, 20 / unit.picosecond, 4 * unit.femtoseconds)
    integrator.setMinimumMomentOfInertia(0.04 * AMU_NM2)
    integrator.setRandomNumberSeed(23)
    context = openmm.Context(system, integrator, *systems.platform_and_properties("CPU"))
    context.setState(state)
    integrator.step(500)
    water = list(integrator.getBodyParticles(0))
    masses = rigidtesting.particleMasses(system)[water]
    assert np.all(principalMoments(masses, systems.positions_of(context)[water]) < 0.04)  # all raised: spherical tops
    assert_water_temperatures(integrator, 300.0, samples=2500, every=2, blocks=20, label="raised moments: ", tolerance=0.015,
                              context=context)


def test_xml_keeps_the_minimum_moment():
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.004)
    integrator.setMinimumMomentOfInertia(0.025)
    copy = openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(integrator))
    assert isinstance(copy, RigidBodyLangevinIntegrator)
    assert copy.getMinimumMomentOfInertia().value_in_unit(AMU_NM2) == 0.025


def test_velocities_to_temperature_take_the_offset_with_the_raised_moments():
    """RigidBodyLangevinIntegrator's velocities are half a step behind the positions, so OpenMM takes
    a drawn set back by dt/2 of force over mass: with raised moments each body's angular velocity
    must go back by dt/2 I'^-1 tau, not by its particles' I^-1 tau. The same draw without an offset
    (RigidBodyIntegrator, same seed), taken back by hand with the raised moments, gives the same
    velocities (Reference, 1e-9 relative)."""
    cluster = systems.cluster(seed=12, grid=(3, 3, 2))
    dt = 0.008
    langevin = RigidBodyLangevinIntegrator(300, 1, dt, cluster.bodies)
    plain = RigidBodyIntegrator(dt, cluster.bodies)
    contexts = []
    for integrator in (langevin, plain):
        integrator.setMinimumMomentOfInertia(FLOOR)
        context = systems.make_context(cluster.system, integrator, "Reference")
        context.setPositions(cluster.positions)
        context.setVelocitiesToTemperature(300, 11)
        contexts.append(context)
    offset = dt / 2
    positions = systems.positions_of(contexts[1])
    drawn = systems.velocities_of(contexts[1])
    forces = contexts[1].getState(getForces=True).getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole / unit.nanometer)
    expected = drawn.copy()
    for p in cluster.free:
        expected[p] -= offset * forces[p] / cluster.masses[p]
    turned = 0.0
    for body, (omega, moments, axes, velocity) in zip(cluster.bodies, body_omegas(cluster.masses, positions, drawn, cluster.bodies)):
        m = cluster.masses[body]
        r = positions[body] - m @ positions[body] / m.sum()
        torque = np.sum(np.cross(r, forces[body]), axis=0)
        velocity = velocity - offset * forces[body].sum(axis=0) / m.sum()
        if len(body) > 1:
            real = np.where(moments > 1e-9 * moments[-1], moments, 0.0)
            inverse = np.where(real > 0, 1 / np.where(real > 0, raised(real, FLOOR), 1.0), 0.0)
            omega = omega - offset * axes @ (inverse * (axes.T @ torque))
            turned = max(turned, np.linalg.norm(offset * axes @ ((1 / np.where(real > 0, real, np.inf) - inverse) * (axes.T @ torque))))
        expected[body] = velocity + np.cross(omega, r)
    assert turned > 1e-3  # the particles' moments would turn some body visibly differently
    np.testing.assert_allclose(systems.velocities_of(contexts[0]), expected, rtol=0, atol=1e-9 * np.max(np.abs(expected)))


def test_reporter_columns_read_the_raised_moments():
    """RigidStateDataReporter's kinetic energy and rotational columns are those of the raised
    moments, computed here from the State (the cluster of test_reporter_columns, a CMMotionRemover)."""
    from test_reporter_columns import clusterSimulation, readCsv
    integrator = RigidBodyIntegrator(0.001, systems.cluster(seed=8).bodies)
    integrator.setMinimumMomentOfInertia(FLOOR)
    simulation, cluster = clusterSimulation(integrator)
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(output, 5, step=True, kineticEnergy=True,
                                                                   rotationalKineticEnergy=True, translationalKineticEnergy=True))
    expected = []
    for _ in range(3):
        simulation.step(5)
        state = simulation.context.getState(getPositions=True, getVelocities=True)
        x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
        total = kinetic_energy_of_raised(cluster.masses, x, v, cluster.bodies, cluster.free, FLOOR)
        unraised = kinetic_energy_of_raised(cluster.masses, x, v, cluster.bodies, cluster.free, 0.0)
        expected.append((total, unraised))
    header, rows = readCsv(output.getvalue())
    for (step, kinetic, translational, rotational), (total, unraised) in zip(rows, expected):
        assert kinetic == pytest.approx(total, rel=1e-6)   # the reporter prints 6 or more digits
        assert translational + rotational == pytest.approx(total, rel=1e-6)
        assert total > 1.2 * unraised


def test_tip4pew_with_a_barostat_reads_the_bath_with_raised_moments():
    """TIP4P-Ew (a massless virtual site per water) in a 1.7 nm box, PME, MonteCarloBarostat every 10
    steps, moments raised to 0.04 amu nm^2, 4 fs, friction 20/ps: the barostat moves the box, the
    waters stay rigid with their virtual sites in place, and the translational, rotational and
    reported temperatures are 300 K within 4.5 block standard errors and 2 %."""
    box = systems.water_box("tip4pew", size=1.7)
    system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(box.system))
    barostat = openmm.MonteCarloBarostat(1 * unit.bar, 300 * unit.kelvin, 10)
    barostat.setRandomNumberSeed(3)
    system.addForce(barostat)
    integrator = RigidBodyLangevinIntegrator(300 * unit.kelvin, 20 / unit.picosecond, 4 * unit.femtoseconds)
    integrator.setMinimumMomentOfInertia(0.04)
    integrator.setRandomNumberSeed(29)
    context = openmm.Context(system, integrator, *systems.platform_and_properties("CPU"))
    context.setPositions(box.positions)
    context.setVelocitiesToTemperature(300, 29)
    volume = context.getState().getPeriodicBoxVolume()
    integrator.step(300)
    water = list(integrator.getBodyParticles(0))
    assert len(water) == 3
    masses = rigidtesting.particleMasses(system)[water]
    assert np.all(principalMoments(masses, systems.positions_of(context)[water]) < 0.04)  # all raised: spherical tops
    assert_water_temperatures(integrator, 300.0, samples=1500, every=2, blocks=15, label="TIP4P-Ew NPT: ", tolerance=0.02,
                              context=context)
    state = context.getState(getPositions=True)
    assert state.getPeriodicBoxVolume() != volume
    x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    check = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName("Reference"))
    check.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
    check.setPositions(x)
    check.computeVirtualSites()
    np.testing.assert_allclose(systems.positions_of(check), x, atol=1e-9, rtol=0)
    for i in range(system.getNumConstraints()):
        a, b, distance = system.getConstraintParameters(i)
        assert abs(np.linalg.norm(x[a] - x[b]) - distance.value_in_unit(unit.nanometer)) < 1e-9


@pytest.mark.parametrize("langevin", [False, True], ids=["RigidBodyIntegrator", "RigidBodyLangevinIntegrator"])
def test_four_times_the_masses_is_half_the_step(small_water_box, langevin):
    """Neither mass nor inertia enters the configurational distribution, and uniformly heavier bodies
    only move more slowly: with every mass and the minimum moment times 4, the step times 2 and the
    friction halved, each kick, drift and Ornstein-Uhlenbeck factor is the same number, with velocities
    halved, as in the run at the standard masses (factors of 2, so the scaling itself rounds nothing).
    On Reference, from the same state and seed, the positions after 40 steps are the same bit for bit,
    the velocities half, the kinetic energies equal. A moment, friction or noise taken with the wrong
    inertia (the particles' rather than the raised one, or not scaled with the masses) breaks it.
    Minimum 0.01 amu nm^2: TIP3P's smallest moment (0.0061) is raised, the water stays asymmetric."""
    system, state = small_water_box
    heavy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for i in range(heavy.getNumParticles()):
        heavy.setParticleMass(i, 4 * system.getParticleMass(i))
    positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    runs = []
    for model, scale in ((system, 1), (heavy, 4)):
        root = np.sqrt(scale)
        if langevin:
            integrator = RigidBodyLangevinIntegrator(300, 4.0 / root, 0.002 * root)
            integrator.setRandomNumberSeed(5)
        else:
            integrator = RigidBodyIntegrator(0.002 * root)
        integrator.setMinimumMomentOfInertia(0.01 * scale)
        context = systems.make_context(model, integrator, "Reference")
        context.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
        context.setPositions(positions)
        context.setVelocities(velocities / root)
        water = list(integrator.getBodyParticles(0))
        moments = raised(principalMoments(rigidtesting.particleMasses(model)[water], positions[water]), 0.01 * scale)
        assert moments[0] == 0.01 * scale and len(set(np.round(moments / moments[-1], 12))) == 3  # raised, asymmetric
        integrator.step(40)
        final = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
        runs.append((final.getPositions(asNumpy=True).value_in_unit(unit.nanometer),
                     final.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond) * root,
                     final.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)))
    (x1, v1, k1), (x4, v4, k4) = runs
    moved = np.abs(x1 - positions).max()
    print(f"moved up to {moved:.3g} nm; positions differ by {np.abs(x4 - x1).max():.3g} nm, "
          f"velocities by {np.abs(v4 - v1).max():.3g} nm/ps, kinetic energies {k1:.6f} and {k4:.6f} kJ/mol")
    assert moved > 0.01
    np.testing.assert_array_equal(x4, x1)
    np.testing.assert_array_equal(v4, v1)
    assert k4 == k1


# ------------------------------------------------------------------------------------------------
# Every path that draws or loads velocities
# ------------------------------------------------------------------------------------------------

def test_the_largest_minimum_moment_still_draws_the_bath_temperature():
    """At the largest minimum moment (100 amu nm^2, 16,000 times water's smallest moment),
    setVelocitiesToTemperature() gives the bath's temperature, translation and rotation alike, and
    the kinetic energy of the raised moments is conserved by free motion (at 1e50 the rounding of each
    angular velocity, magnified by I'/I, read 1e24 K). 80 free waters: 480 degrees of freedom, a
    standard error of 6.5 % of the temperature; 30 % is over 4.5 of them."""
    waters = systems.cluster(seed=2, grid=(5, 4, 4), spacing=0.4, forces=False)
    integrator = RigidBodyIntegrator(0.002, waters.bodies)
    integrator.setMinimumMomentOfInertia(RigidBodyIntegrator.MaximumMinimumMoment)
    context = systems.make_context(waters.system, integrator, "Reference")
    context.setPositions(waters.positions)
    context.setVelocitiesToTemperature(300, 3)
    kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(300, rel=0.3)
    translational, rotational = rigidKineticEnergies(context, integrator)
    assert translational + rotational == pytest.approx(kinetic, rel=1e-6)
    assert rotational / kinetic == pytest.approx(0.5, abs=0.15)
    integrator.step(100)
    after = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert after == pytest.approx(kinetic, rel=1e-9)


def test_compound_integrator_with_raised_moments_is_refused():
    """OpenMM's CompoundIntegrator draws setVelocitiesToTemperature() for the particles' masses
    without asking the integrator it holds (mean T_rot 1252 K for a 300 K draw with floor 0.04), and
    its other integrators move the bodies with their own moments: refused when the Context is made.
    Without raised moments the same CompoundIntegrator runs."""
    waters = systems.cluster(seed=2, grid=(2, 2, 2), spacing=0.4, forces=False)
    for floor in (0.04, 0.0):
        compound = openmm.CompoundIntegrator()
        rigid = RigidBodyLangevinIntegrator(300, 1, 0.002, waters.bodies)
        rigid.setMinimumMomentOfInertia(floor)
        compound.addIntegrator(rigid)
        compound.addIntegrator(openmm.VerletIntegrator(0.001))
        if floor > 0:
            with pytest.raises(openmm.OpenMMException, match="RigidBodyLangevinIntegrator: raised moments of inertia cannot be "
                                                             "used in a CompoundIntegrator"):
                systems.make_context(waters.system, compound, "Reference")
        else:
            context = systems.make_context(waters.system, compound, "Reference")
            context.setPositions(waters.positions)
            compound.step(2)


@pytest.mark.parametrize("platform", ["Reference"] + systems.GPU_PLATFORMS[:1])
def test_checkpoint_from_another_minimum_moment_is_refused(platform):
    """A checkpoint's velocities are rigid motion with the moments of the run that wrote it: loaded
    with another minimum moment, the rotational kinetic energy changed by I'/I without a word (451 ->
    1078 kJ/mol). The checkpoint records the minimum moment; another one is refused, and the Context
    goes on from the checkpoint's positions and velocities, fitted to its own bodies."""
    cluster = systems.cluster(seed=8, grid=(2, 2, 2))
    writer = RigidBodyIntegrator(0.001, cluster.bodies)
    writer.setMinimumMomentOfInertia(0.04)
    context = systems.make_context(cluster.system, writer, platform)
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    writer.step(5)
    checkpoint = context.createCheckpoint()
    for floor in (0.0, 0.05):
        reader = RigidBodyIntegrator(0.001, cluster.bodies)
        reader.setMinimumMomentOfInertia(floor)
        readerContext = systems.make_context(cluster.system, reader, platform)
        readerContext.setPositions(cluster.positions)
        with pytest.raises(openmm.OpenMMException, match=r"RigidBodyIntegrator: the checkpoint was written with a minimum "
                                                         r"moment of inertia of 0\.04 amu nm\^2, this integrator has " + f"{floor:g};"):
            readerContext.loadCheckpoint(checkpoint)
        reader.step(2)
        assert np.all(np.isfinite(systems.positions_of(readerContext)))
    same = RigidBodyIntegrator(0.001, cluster.bodies)
    same.setMinimumMomentOfInertia(0.04)
    sameContext = systems.make_context(cluster.system, same, platform)
    sameContext.loadCheckpoint(checkpoint)
    assert rigidKineticEnergies(sameContext, same)[1] == pytest.approx(rigidKineticEnergies(context, writer)[1], rel=1e-6)
    assert sameContext.getState(getEnergy=True).getKineticEnergy() / unit.kilojoule_per_mole == pytest.approx(
        context.getState(getEnergy=True).getKineticEnergy() / unit.kilojoule_per_mole, rel=1e-6)

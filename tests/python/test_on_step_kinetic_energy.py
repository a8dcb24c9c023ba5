"""RigidBodyLangevinIntegrator.getOnStepKineticEnergy(): the kinetic energy of the velocities half a
kick ahead of those the Context holds (BAOAB's on-step velocities).

- Against an independent numpy computation from the State (positions, rigid velocities, forces):
  each body's momentum and angular momentum kicked by half a step of its force and torque, its
  energy in the lab-frame inertia tensor of its particles (a pseudo-inverse for a linear body), the
  free particles' velocities kicked and projected onto their constraints (Lagrange multipliers
  solved densely); on the mixed system (asymmetric, symmetric, linear and single-particle bodies, a
  peptide with HBonds among free particles) and, with raised moments, on a water box (each body's
  angular momentum in the raised principal moments, from the particles' angular velocity).
- It leaves the state as it is: a run that asks for it at every step continues bit for bit as one
  that does not (Reference).
- Friction 0: the integrator's trajectory from (x, v - kick) is velocity Verlet's from (x, v), so its
  on-step kinetic energy and its shadow work corrected to on-step ends (the formula of the method's
  documentation) agree with RigidBodyIntegrator's (Verlet, on-step velocities) after 20 steps, on
  Reference and the first GPU platform.
- Unbound: an OpenMMException naming the class and the method.
"""

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import systems
from openmmrigid import RigidBodyIntegrator, RigidBodyLangevinIntegrator
from rigidtesting import particleMasses
from rigidtesting.bodies import bodyKind

KJ = unit.kilojoule_per_mole
NM_PS = unit.nanometer / unit.picosecond
DT = 0.002


@pytest.fixture(scope="module")
def mixed():
    return systems.mixed_system()


@pytest.fixture(scope="module")
def water_state():
    return systems.small_water_box(200)


def state_arrays(context):
    state = context.getState(getPositions=True, getVelocities=True, getForces=True)
    return (state.getPositions(asNumpy=True).value_in_unit(unit.nanometer), state.getVelocities(asNumpy=True).value_in_unit(NM_PS),
            state.getForces(asNumpy=True).value_in_unit(KJ / unit.nanometer))


def masses_of(system):
    return np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])


def body_momenta(m, x, v, f):
    """Mass, centre velocity, force; the particles' angular momentum, torque and inertia tensor about the centre."""
    mass = m.sum()
    centre = m @ x / mass
    velocity = m @ v / mass
    d = x - centre
    angular = np.sum(m[:, None] * np.cross(d, v - velocity), axis=0)
    torque = np.sum(np.cross(d, f), axis=0)
    inertia = np.sum(m[:, None, None] * (np.sum(d * d, axis=1)[:, None, None] * np.eye(3) - d[:, :, None] * d[:, None, :]), axis=0)
    return mass, velocity, f.sum(axis=0), angular, torque, inertia


def kicked_free_energy(system, m, x, v, f, free, kick, project=True):
    """The free particles' kinetic energy after the kick, projected onto the constraints among them."""
    free = set(free)
    kicked = v.copy()
    for p in free:
        kicked[p] += kick * f[p] / m[p]
    pairs = []
    for c in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(c)
        if i in free and j in free:
            pairs.append((i, j))
    if pairs and project:
        # Velocity corrections dv_i = sum_c lambda_c g_ci / m_i with g_c = d(|r_i - r_j|)/dr: solve G lambda = -g.v.
        n = len(pairs)
        gradients = np.zeros((n, len(m), 3))
        for c, (i, j) in enumerate(pairs):
            d = x[i] - x[j]
            gradients[c, i], gradients[c, j] = d, -d
        inverse = np.where(m > 0, 1 / np.where(m > 0, m, 1), 0)
        G = np.einsum("apk,bpk,p->ab", gradients, gradients, inverse)
        rate = np.einsum("apk,pk->a", gradients, kicked)
        multipliers = np.linalg.solve(G, -rate)
        kicked += np.einsum("a,apk,p->pk", multipliers, gradients, inverse)
    return sum(0.5 * m[p] * kicked[p] @ kicked[p] for p in free)


def numpy_on_step_energy(system, integrator, context, floor=0.0, project=True, kick=0.5 * DT):
    x, v, f = state_arrays(context)
    m = masses_of(system)
    energy, inBodies = 0.0, set()
    for b in range(integrator.getNumBodies()):
        members = list(integrator.getBodyParticles(b))
        inBodies.update(members)
        members = [p for p in members if m[p] > 0]  # a virtual site carries no mass
        mass, velocity, force, angular, torque, inertia = body_momenta(m[members], x[members], v[members], f[members])
        kickedVelocity = velocity + kick * force / mass
        energy += 0.5 * mass * kickedVelocity @ kickedVelocity
        if len(members) == 1:
            continue
        moments, axes = np.linalg.eigh(inertia)
        nonzero = moments > 1e-9 * moments.max()
        if floor > 0:
            # The Hamiltonian's angular momentum: the raised moments times the particles' angular velocity.
            omega = np.linalg.pinv(inertia, rcond=1e-9) @ angular
            raised = np.where(nonzero, np.maximum(moments, floor), 0.0)
            angular = axes @ (raised * (axes.T @ omega))
            moments = raised
        bodyMomentum = axes.T @ (angular + kick * torque)
        energy += 0.5 * np.sum(bodyMomentum[nonzero] ** 2 / moments[nonzero])
    free = [p for p in range(len(m)) if p not in inBodies and m[p] > 0]
    return energy + kicked_free_energy(system, m, x, v, f, free, kick, project)


def test_on_step_energy_against_numpy_on_the_mixed_system(mixed):
    bodies = mixed.waters + [mixed.benzene, mixed.co2, mixed.sodium]
    integrator = RigidBodyLangevinIntegrator(300, 1.0, DT, bodies)
    integrator.setConstraintTolerance(1e-10)
    integrator.setRandomNumberSeed(3)
    context = systems.make_context(mixed.system, integrator, "Reference")
    context.setPositions(mixed.positions)
    context.setVelocities(mixed.velocities)
    integrator.step(3)
    masses = particleMasses(mixed.system)
    kinds = {bodyKind(masses[body], mixed.positions[body]) for body in bodies}
    assert {"asymmetric", "symmetric", "linear", "point"} <= kinds
    expected = numpy_on_step_energy(mixed.system, integrator, context)
    unprojected = numpy_on_step_energy(mixed.system, integrator, context, project=False)
    halfStep = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    onStep = integrator.getOnStepKineticEnergy().value_in_unit(KJ)
    # The kick and the projection of the free particles' kick matter far above the agreement asked for.
    # The kick's first-order change, a sum of h F.v of either sign, can cancel (0.1 kJ/mol of 2100 in one
    # clean clone's state); its second-order term cannot: the energy is quadratic in the kick h (the
    # projection is linear), so K(2h) - 2 K(h) + K(0) = h^2 (sum F^2/m + torques' tau.I^-1.tau) > 0. The
    # projection removes a sum of squares.
    h = 0.5 * DT
    curvature = (numpy_on_step_energy(mixed.system, integrator, context, kick=2 * h) - 2 * expected
                 + numpy_on_step_energy(mixed.system, integrator, context, kick=0.0))
    assert curvature > 1e-6 * expected
    assert onStep != pytest.approx(halfStep, rel=1e-9)
    assert unprojected - expected > 1e-6 * expected
    assert onStep == pytest.approx(expected, rel=1e-9)


def test_on_step_energy_with_raised_moments_against_numpy(water_state):
    system, state = water_state
    floor = 0.08
    integrator = RigidBodyLangevinIntegrator(300, 1.0, DT)
    integrator.setMinimumMomentOfInertia(floor)
    integrator.setRandomNumberSeed(4)
    context = systems.make_context(system, integrator, "Reference")
    context.setState(state)
    context.setVelocitiesToTemperature(300, 4)
    integrator.step(3)
    expected = numpy_on_step_energy(system, integrator, context, floor)
    unraised = numpy_on_step_energy(system, integrator, context)
    onStep = integrator.getOnStepKineticEnergy().value_in_unit(KJ)
    assert abs(expected - unraised) > 1e-2 * expected  # the raised moments matter here
    assert onStep == pytest.approx(expected, rel=1e-9)


def test_asking_changes_no_trajectory(water_state):
    system, state = water_state
    runs = []
    for ask in (False, True):
        integrator = RigidBodyLangevinIntegrator(300, 1.0, DT)
        integrator.setRandomNumberSeed(5)
        context = systems.make_context(system, integrator, "Reference")
        context.setState(state)
        for _ in range(5):
            integrator.step(1)
            if ask:
                integrator.getOnStepKineticEnergy()
        runs.append(state_arrays(context)[:2])
    for a, b in zip(*runs):
        assert np.array_equal(a, b)


@pytest.mark.parametrize("platformName", ["Reference"] + systems.GPU_PLATFORMS[:1])
def test_without_friction_it_is_velocity_verlets_on_step_energy(water_state, platformName):
    system, state = water_state
    steps = 20
    verlet = RigidBodyIntegrator(DT)
    verlet.setMeasureShadowWork(True)
    verletContext = systems.make_context(system, verlet, platformName)
    verletContext.setState(state)
    verletContext.setVelocitiesToTemperature(300, 6)
    x, v, f = state_arrays(verletContext)
    m = masses_of(system)
    langevin = RigidBodyLangevinIntegrator(300, 0.0, DT)
    langevin.setMeasureShadowWork(True)
    context = systems.make_context(system, langevin, platformName)
    context.setState(state)
    # Half a kick back: a kick of each particle by its force, projected onto rigid motion, is the kick
    # of each body's momentum and angular momentum by its force and torque.
    context.setVelocities(v - 0.5 * DT * f / m[:, None])
    startOnStep = langevin.getOnStepKineticEnergy().value_in_unit(KJ)
    startHalfStep = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    verletStart = verletContext.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    assert startOnStep == pytest.approx(verletStart, rel=1e-9)
    verlet.step(steps)
    langevin.step(steps)
    assert np.max(np.abs(state_arrays(context)[0] - state_arrays(verletContext)[0])) < 1e-9
    onStep = langevin.getOnStepKineticEnergy().value_in_unit(KJ)
    halfStep = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    verletKinetic = verletContext.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    assert onStep == pytest.approx(verletKinetic, rel=1e-8)
    corrected = langevin.getShadowWork().value_in_unit(KJ) + (onStep - halfStep) - (startOnStep - startHalfStep)
    uncorrected = langevin.getShadowWork().value_in_unit(KJ)
    verletWork = verlet.getShadowWork().value_in_unit(KJ)
    assert abs(uncorrected - verletWork) > 1e-2  # the ends matter
    assert corrected == pytest.approx(verletWork, abs=1e-6)


def test_unbound_is_an_error():
    integrator = RigidBodyLangevinIntegrator(300, 1.0, DT)
    with pytest.raises(openmm.OpenMMException, match="RigidBodyLangevinIntegrator.getOnStepKineticEnergy"):
        integrator.getOnStepKineticEnergy()

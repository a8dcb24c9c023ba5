"""Shadow work, heat and the accuracy check of both integrators:

- a rigid body (its particles in a harmonic trap whose stiffness is proportional to their mass, so
  that its centre oscillates and it feels no torque: the rotation stays free) and a free particle in
  the same trap: the shadow work of each step of RigidBodyIntegrator equals the analytic energy change
  of its substeps (the kicks' kinetic energy and the drifts' potential energy, followed in Python
  through the splitting's table), for Verlet and Omelyan2; for RigidBodyLangevinIntegrator the shadow
  work and the heat of each step equal those reconstructed from the states before and after it (the
  kick's kinetic energy and the potential energy change; the Ornstein-Uhlenbeck stage's kinetic energy);
- for RigidBodyBussiIntegrator, in the same trap with Verlet, the heat of each step is the kinetic
  energy change of its rescaling (the step's Verlet stages, then every velocity times one factor) and
  the shadow work that of the Verlet stages;
- a free asymmetric top: zero shadow work with the exact drift (to rounding), not with NoSquish;
  with friction, the heat is then the whole energy change;
- energy accounting: shadow work + heat = the change of K + U (over a stretch of steps: differences
  of the sums), with RigidBodyBussiIntegrator (whose heat is its thermostat's work) and with
  Langevin, on Reference and CPU; measuring changes no trajectory (Reference, bit for bit);
  checkpoints keep the sums; the sums need setMeasureShadowWork(True) (one switch measures both),
  RigidBodyIntegrator's heat is zero;
- the accuracy check fires on rigid water driven past its range (Langevin at 11 fs and friction
  1/ps; RigidBodyBussiIntegrator with Verlet at 8 fs) within a few ps, naming the class, the step
  and the remedies, once, as an AccuracyWarning, and stays quiet in long runs inside it (Langevin at
  4 fs, RigidBodyBussiIntegrator with Omelyan2 at 6 fs); switched off it measures nothing.
"""

import warnings

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import systems
from openmmrigid import AccuracyWarning, RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyLangevinIntegrator

KJ = unit.kilojoule_per_mole
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(KJ / unit.kelvin)
OMELYAN_LAMBDA = 0.1931833275037836
# Kicks and drifts of each splitting, in units of the step (RigidBodyIntegrator.setSplitting()).
SPLITTINGS = {
    "Verlet": (RigidBodyIntegrator.Verlet, [0.5, 0.5], [1.0]),
    "Omelyan2": (RigidBodyIntegrator.Omelyan2, [OMELYAN_LAMBDA, 1 - 2 * OMELYAN_LAMBDA, OMELYAN_LAMBDA], [0.5, 0.5]),
}

# An asymmetric body (particles 0-3) and a free particle (4), all in the trap U = kappa m |r|^2 / 2.
MASSES = np.array([12.0, 1.0, 16.0, 14.0, 20.0])
POSITIONS = np.array([[0.10, 0.02, -0.03], [0.21, 0.05, -0.01], [0.08, 0.15, 0.02], [0.04, -0.03, 0.12], [-0.2, 0.1, 0.05]])
BODY = [0, 1, 2, 3]
KAPPA = 2000.0  # 1/ps^2: omega = 44.7/ps, a period of 0.14 ps


def trap_system(kappa=KAPPA):
    system = openmm.System()
    trap = openmm.CustomExternalForce("0.5*k*(x^2 + y^2 + z^2)")
    trap.addPerParticleParameter("k")
    for i, mass in enumerate(MASSES):
        system.addParticle(mass)
        trap.addParticle(i, [kappa * mass])
    system.addForce(trap)
    return system


def trap_energy(positions, kappa=KAPPA):
    return 0.5 * kappa * np.sum(MASSES * np.sum(positions**2, axis=1))


def state_of(context):
    state = context.getState(getPositions=True, getVelocities=True)
    return (np.asarray(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)),
            np.asarray(state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)))


def kinetic_parts(velocities):
    """The translational kinetic energy of the body's centre plus the free particle, and the body's rotational one."""
    masses = MASSES[BODY]
    centre = masses @ velocities[BODY] / masses.sum()
    translational = 0.5 * masses.sum() * centre @ centre + 0.5 * MASSES[4] * velocities[4] @ velocities[4]
    rotational = 0.5 * np.sum(masses * np.sum((velocities[BODY] - centre)**2, axis=1))
    return translational, rotational


def trap_context(integrator, platformName="Reference", kappa=KAPPA):
    context = openmm.Context(trap_system(kappa), integrator, openmm.Platform.getPlatformByName(platformName))
    context.setPositions(POSITIONS)
    rng = np.random.default_rng(5)
    context.setVelocities(rng.normal(0.0, 1.0, (5, 3)) / np.sqrt(MASSES)[:, None] * 3.0)
    return context


def centre_and_free(positions, velocities):
    """(mass, position, velocity) of the body's centre and of the free particle."""
    masses = MASSES[BODY]
    return [(masses.sum(), masses @ positions[BODY] / masses.sum(), masses @ velocities[BODY] / masses.sum()),
            (MASSES[4], positions[4].copy(), velocities[4].copy())]


@pytest.mark.parametrize("name", list(SPLITTINGS))
def test_rigid_body_integrator_shadow_work_is_the_substeps_energy_change(name):
    """Each step's shadow work is the sum of the kicks' kinetic energy and the drifts' potential energy,
    followed in Python through the splitting (the rotation is free: no torque, exact drift)."""
    splitting, kicks, drifts = SPLITTINGS[name]
    dt = 0.004
    integrator = RigidBodyIntegrator(dt, [BODY])
    integrator.setSplitting(splitting)
    integrator.setMeasureShadowWork(True)
    context = trap_context(integrator)
    previous = 0.0
    for step in range(40):
        positions, velocities = state_of(context)
        expected = 0.0
        moved = []
        for mass, x, v in centre_and_free(positions, velocities):
            # A particle of mass m in the trap kappa m |x|^2 / 2: kick v -= kappa x h, drift x += v h.
            for stage in range(len(drifts)):
                before = 0.5 * mass * v @ v
                v = v - KAPPA * x * kicks[stage] * dt
                expected += 0.5 * mass * v @ v - before
                before = 0.5 * KAPPA * mass * x @ x
                x = x + v * drifts[stage] * dt
                expected += 0.5 * KAPPA * mass * x @ x - before
            before = 0.5 * mass * v @ v
            v = v - KAPPA * x * kicks[-1] * dt
            expected += 0.5 * mass * v @ v - before
            moved.append((x, v))
        integrator.step(1)
        work = integrator.getShadowWork().value_in_unit(KJ)
        after, afterVelocities = state_of(context)
        (centre, centreVelocity), (free, freeVelocity) = moved
        assert np.allclose(MASSES[BODY] @ after[BODY] / MASSES[BODY].sum(), centre, rtol=0, atol=1e-12)
        assert np.allclose(after[4], free, rtol=0, atol=1e-12)
        scale = trap_energy(positions) + sum(kinetic_parts(velocities))
        assert abs((work - previous) - expected) < 1e-9 * scale, (step, work - previous, expected)
        previous = work
    assert abs(previous) > 1e-6 * scale  # the trap at omega dt = 0.18 does make shadow work


def test_langevin_shadow_work_and_heat_of_each_step():
    """Kick, half drift, O, half drift: from the states before and after a step, the kick's velocity
    v_B = v_0 + F(x_0) dt / m; the O stage's output is the velocity after the step (the drifts keep it),
    so shadow work = K(v_B) - K(v_0) + U(x_1) - U(x_0) and heat = K(v_1) - K(v_B) (the body's rotational
    energy changes only in O: no torque, exact drift)."""
    dt = 0.004
    integrator = RigidBodyLangevinIntegrator(300, 20, dt, [BODY])
    integrator.setRandomNumberSeed(3)
    integrator.setMeasureShadowWork(True)  # shadow work and heat
    context = trap_context(integrator)
    previousWork = previousHeat = 0.0
    for step in range(40):
        positions, velocities = state_of(context)
        integrator.step(1)
        after, afterVelocities = state_of(context)
        work = integrator.getShadowWork().value_in_unit(KJ)
        heat = integrator.getHeat().value_in_unit(KJ)
        expectedWork = trap_energy(after) - trap_energy(positions)
        expectedHeat = kinetic_parts(afterVelocities)[1] - kinetic_parts(velocities)[1]
        for (mass, x, v), (_, _, v1) in zip(centre_and_free(positions, velocities), centre_and_free(after, afterVelocities)):
            kicked = v - KAPPA * x * dt
            expectedWork += 0.5 * mass * (kicked @ kicked - v @ v)
            expectedHeat += 0.5 * mass * (v1 @ v1 - kicked @ kicked)
        scale = trap_energy(positions) + sum(kinetic_parts(velocities))
        assert abs((work - previousWork) - expectedWork) < 1e-9 * scale, step
        assert abs((heat - previousHeat) - expectedHeat) < 1e-9 * scale, step
        previousWork, previousHeat = work, heat


def test_bussi_heat_of_each_step_is_its_rescaling():
    """RigidBodyBussiIntegrator with Verlet: a step is the Verlet step (kick, drift, kick) followed by
    the rescaling of every velocity by one factor. From the state before a step, the Verlet step of
    the body's centre and the free particle (the rotation is free and keeps its energy) gives the
    positions after it and the kinetic energy K' before the rescaling: the heat of the step is
    K(v_1) - K', the shadow work that of the Verlet step, and translation and rotation are rescaled
    by the same factor. tau = 0.05 ps: the rescalings are far from 1."""
    dt = 0.004
    integrator = RigidBodyBussiIntegrator(300, 0.05, dt, [BODY])
    integrator.setRandomNumberSeed(3)
    integrator.setMeasureShadowWork(True)  # the heat is the thermostat's work
    context = trap_context(integrator)
    previousWork = previousHeat = 0.0
    largest = 0.0
    for step in range(40):
        positions, velocities = state_of(context)
        integrator.step(1)
        after, afterVelocities = state_of(context)
        work = integrator.getShadowWork().value_in_unit(KJ)
        heat = integrator.getHeat().value_in_unit(KJ)
        translational, rotational = kinetic_parts(velocities)
        expectedWork = verletTranslational = 0.0
        moved = []
        for mass, x, v in centre_and_free(positions, velocities):
            before = 0.5 * KAPPA * mass * x @ x + 0.5 * mass * v @ v
            half = v - KAPPA * x * dt / 2
            x = x + half * dt
            v = half - KAPPA * x * dt / 2
            verletTranslational += 0.5 * mass * v @ v
            expectedWork += 0.5 * KAPPA * mass * x @ x + 0.5 * mass * v @ v - before
            moved.append(x)
        afterTranslational, afterRotational = kinetic_parts(afterVelocities)
        expectedHeat = afterTranslational + afterRotational - (verletTranslational + rotational)
        scale = trap_energy(positions) + translational + rotational
        assert np.allclose(MASSES[BODY] @ after[BODY] / MASSES[BODY].sum(), moved[0], rtol=0, atol=1e-12)
        assert np.allclose(after[4], moved[1], rtol=0, atol=1e-12)
        assert afterTranslational / verletTranslational == pytest.approx(afterRotational / rotational, rel=1e-9)
        assert abs((work - previousWork) - expectedWork) < 1e-9 * scale, step
        assert abs((heat - previousHeat) - expectedHeat) < 1e-9 * scale, step
        largest = max(largest, abs(expectedHeat) / scale)
        previousWork, previousHeat = work, heat
    assert largest > 0.01  # the thermostat does exchange energy


def free_top_context(integrator):
    system = openmm.System()
    for mass in MASSES[BODY]:
        system.addParticle(mass)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(POSITIONS[BODY])
    # A fast tumble about an axis far from the principal ones, and a drift.
    omega = np.array([30.0, -55.0, 80.0])
    velocities = np.cross(omega, POSITIONS[BODY] - MASSES[BODY] @ POSITIONS[BODY] / MASSES[BODY].sum()) + [0.3, -0.2, 0.1]
    context.setVelocities(velocities)
    return context


def test_free_rotation_makes_no_shadow_work_with_the_exact_drift():
    results = {}
    for method in (RigidBodyIntegrator.Exact, RigidBodyIntegrator.NoSquish):
        integrator = RigidBodyIntegrator(0.005, [BODY])
        integrator.setRotationMethod(method)
        integrator.setMeasureShadowWork(True)
        context = free_top_context(integrator)
        energy = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
        largest = 0.0
        for _ in range(50):
            integrator.step(1)
            largest = max(largest, abs(integrator.getShadowWork().value_in_unit(KJ)))
        results[method] = largest / energy
    assert results[RigidBodyIntegrator.Exact] < 1e-12
    assert results[RigidBodyIntegrator.NoSquish] > 1e-6  # NO_SQUISH's rotation changes the kinetic energy


def test_free_rotation_with_friction_is_all_heat():
    integrator = RigidBodyLangevinIntegrator(300, 5, 0.005, [BODY])
    integrator.setMeasureShadowWork(True)
    context = free_top_context(integrator)
    start = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    integrator.step(50)
    end = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)
    assert abs(integrator.getShadowWork().value_in_unit(KJ)) < 1e-12 * start
    assert integrator.getHeat().value_in_unit(KJ) == pytest.approx(end - start, rel=1e-12, abs=1e-12 * start)


def total_energy(context, integrator):
    state = context.getState(getEnergy=True, groups=integrator.getIntegrationForceGroups())
    return (state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(KJ)


@pytest.fixture(scope="module")
def water_state():
    """systems.small_water_box() after 1000 steps of equilibration."""
    return systems.small_water_box(1000)


def water_context(water_state, integrator, platformName="CPU"):
    system, state = water_state
    context = openmm.Context(system, integrator, *systems.platform_and_properties(platformName))
    context.setState(state)
    return context


@pytest.mark.parametrize("platformName", ["Reference", "CPU"] + systems.GPU_PLATFORMS[:1])
@pytest.mark.parametrize("kind", ["langevin", "bussi-omelyan2"])
def test_shadow_work_and_heat_make_up_the_energy_change(water_state, platformName, kind):
    """Over 30 steps after the first (differences of the sums), shadow work + heat = the change of
    K + U; for RigidBodyBussiIntegrator the effective energy K + U - heat changes by the shadow work
    only, as the thermostat's work did."""
    if kind == "langevin":
        integrator = RigidBodyLangevinIntegrator(300, 5, 0.004)
    else:
        integrator = RigidBodyBussiIntegrator(300, 0.05, 0.004)
        integrator.setSplitting(RigidBodyIntegrator.Omelyan2)
    integrator.setMeasureShadowWork(True)  # shadow work and heat
    context = water_context(water_state, integrator, platformName)
    integrator.step(1)
    workStart, heatStart = integrator.getShadowWork().value_in_unit(KJ), integrator.getHeat().value_in_unit(KJ)
    start = total_energy(context, integrator)
    integrator.step(30)
    change = total_energy(context, integrator) - start
    work = integrator.getShadowWork().value_in_unit(KJ) - workStart
    heat = integrator.getHeat().value_in_unit(KJ) - heatStart
    scale = abs(start)
    tolerance = 1e-9 if platformName != "OpenCL" else 1e-5  # single precision on the device
    assert abs(work + heat - change) < tolerance * scale, (work, heat, change)
    assert work != 0 and heat != 0  # both measured


@pytest.mark.parametrize("kind", ["langevin", "verlet", "bussi"])
def test_measuring_changes_no_trajectory(kind):
    """On Reference, bit for bit: measuring (and the accuracy check) reads, never writes, the state."""
    results = []
    for measure in (False, True):
        if kind == "verlet":
            integrator = RigidBodyIntegrator(0.004, [BODY])
        else:
            integrator = (RigidBodyLangevinIntegrator(300, 20, 0.004, [BODY]) if kind == "langevin" else
                          RigidBodyBussiIntegrator(300, 0.05, 0.004, [BODY]))
            integrator.setRandomNumberSeed(9)
        integrator.setMeasureShadowWork(measure)
        integrator.setAccuracyCheck(measure)
        context = trap_context(integrator)
        integrator.step(25)
        results.append(state_of(context))
    for a, b in zip(results[0], results[1]):
        assert np.array_equal(a, b)


def test_checkpoint_keeps_the_sums_and_errors_name_the_class():
    unmeasured = RigidBodyLangevinIntegrator(300, 20, 0.004, [BODY])
    unmeasuredContext = trap_context(unmeasured)
    for name in ("getShadowWork", "getHeat"):
        with pytest.raises(openmm.OpenMMException, match=f"RigidBodyLangevinIntegrator.{name}: .*setMeasureShadowWork"):
            getattr(unmeasured, name)()
    del unmeasuredContext
    integrator = RigidBodyLangevinIntegrator(300, 20, 0.004, [BODY])
    integrator.setRandomNumberSeed(4)
    integrator.setMeasureShadowWork(True)
    context = trap_context(integrator)
    integrator.step(10)
    checkpoint = context.createCheckpoint()
    saved = (integrator.getShadowWork(), integrator.getHeat())
    integrator.step(10)
    continued = (integrator.getShadowWork(), integrator.getHeat(), state_of(context))
    context.loadCheckpoint(checkpoint)
    assert (integrator.getShadowWork(), integrator.getHeat()) == saved
    integrator.step(10)
    # The first step after the load takes its starting energy from a new evaluation (and the loaded
    # velocities' projection): equal to the continued run's to rounding.
    for value, expected in zip((integrator.getShadowWork(), integrator.getHeat()), continued[:2]):
        assert value.value_in_unit(KJ) == pytest.approx(expected.value_in_unit(KJ), rel=1e-12)
    for a, b in zip(state_of(context), continued[2]):
        assert np.allclose(a, b, rtol=0, atol=1e-10)  # the loaded state is fitted again: equal to rounding
    # The errors name the class; a RigidBodyIntegrator measures no heat (constant energy), and its
    # shadow work is the whole change of K + U.
    for cls in (RigidBodyIntegrator, RigidBodyBussiIntegrator):
        plain = (RigidBodyIntegrator(0.004, [BODY]) if cls is RigidBodyIntegrator else
                 RigidBodyBussiIntegrator(300, 0.05, 0.004, [BODY]))
        plainContext = trap_context(plain)
        for name in ("getShadowWork", "getHeat"):
            with pytest.raises(openmm.OpenMMException, match=f"{cls.__name__}.{name}: .*setMeasureShadowWork"):
                getattr(plain, name)()
        del plainContext
    plain = RigidBodyIntegrator(0.004, [BODY])
    plain.setMeasureShadowWork(True)
    plainContext = trap_context(plain)
    start = total_energy(plainContext, plain)
    plain.step(10)
    assert plain.getHeat().value_in_unit(KJ) == 0
    work = plain.getShadowWork().value_in_unit(KJ)
    assert work != 0 and work == pytest.approx(total_energy(plainContext, plain) - start, rel=1e-9)


# ------------------------------------------------------------------------------------------------
# The accuracy check
# ------------------------------------------------------------------------------------------------

def accuracy_warnings(caught):
    return [w for w in caught if issubclass(w.category, AccuracyWarning)]


def run_checked(water_state, integrator, picoseconds, chunk=0.5):
    """Step in chunks of `chunk` ps until the check fires (an AccuracyWarning is issued) or
    `picoseconds` have passed: the time it fired (None if not), and the AccuracyWarnings step() issued."""
    context = water_context(water_state, integrator)
    dt = integrator.getStepSize().value_in_unit(unit.picosecond)
    steps = int(round(chunk / dt))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AccuracyWarning)
        for i in range(int(round(picoseconds / chunk))):
            integrator.step(steps)
            if accuracy_warnings(caught):
                integrator.step(steps)  # a later step() does not issue it again
                del context
                return (i + 1) * steps * dt, accuracy_warnings(caught)
    del context
    return None, accuracy_warnings(caught)


def test_accuracy_check_fires_for_langevin_past_its_range(water_state):
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.011)
    fired, caught = run_checked(water_state, integrator, 12)
    assert fired is not None and fired <= 6.0, fired
    assert len(caught) == 1
    message = str(caught[0].message)
    for words in ("RigidBodyLangevinIntegrator at a step of 11 fs", "friction 1/ps", "above the bath", "smaller step",
                  "more friction", "raised moments of inertia"):
        assert words in message, (words, message)


def test_accuracy_check_fires_for_verlet_with_the_bussi_thermostat_at_8_fs(water_state):
    integrator = RigidBodyBussiIntegrator(300, 1.0, 0.008)
    fired, caught = run_checked(water_state, integrator, 12)
    assert fired is not None and fired <= 6.0, fired
    assert len(caught) == 1
    message = str(caught[0].message)
    for words in ("RigidBodyBussiIntegrator (Verlet) at a step of 8 fs", "fluctuates", "smaller step",
                  "Omelyan2", "raised moments of inertia"):
        assert words in message, (words, message)


@pytest.mark.parametrize("langevin", [True, False], ids=["langevin-11fs", "bussi-verlet-8fs"])
def test_accuracy_check_with_raised_moments_does_not_suggest_raising_them(water_state, langevin):
    """A run whose moments are raised already is not told to raise them: Langevin is told where raised
    moments stop helping (rigid water: 14 fs at friction 1/ps, where the translation caps the step),
    RigidBodyBussiIntegrator that raising them further does not help. The minimum of 0.007 amu nm^2
    raises only TIP3P's smallest moment (0.0061), so the runs fire as without it."""
    if langevin:
        integrator = RigidBodyLangevinIntegrator(300, 1, 0.011)
        suggestion, expected = "or raised moments of inertia for the bodies", (
            "RigidBodyLangevinIntegrator at a step of 11 fs", "smaller step", "moments of inertia are raised already", "14 fs",
            "translation")
    else:
        integrator = RigidBodyBussiIntegrator(300, 1.0, 0.008)
        suggestion, expected = "or raised moments of inertia", (
            "RigidBodyBussiIntegrator (Verlet) at a step of 8 fs", "smaller step", "Omelyan2",
            "raising the moments of inertia further does not help")
    integrator.setMinimumMomentOfInertia(0.007)
    fired, caught = run_checked(water_state, integrator, 12)
    assert fired is not None and fired <= 6.0, fired
    message = str(caught[0].message)
    assert suggestion not in message, message
    for words in expected:
        assert words in message, (words, message)


@pytest.mark.parametrize("kind", ["langevin-4fs", "bussi-omelyan2-6fs"])
def test_accuracy_check_is_quiet_inside_the_range(water_state, kind):
    if kind == "langevin-4fs":
        integrator = RigidBodyLangevinIntegrator(300, 1, 0.004)
    else:
        integrator = RigidBodyBussiIntegrator(300, 1.0, 0.006)
        integrator.setSplitting(RigidBodyIntegrator.Omelyan2)
    fired, caught = run_checked(water_state, integrator, 20, chunk=5)
    assert fired is None and not caught, [str(w.message) for w in caught]


def test_accuracy_check_takes_out_the_barostat_and_the_motion_remover(water_state):
    """The check reads the energy at its samples only, so what changes the energy between steps is
    taken out of the shadow work: a barostat's accepted moves (the potential energy before and after
    each) and a CMMotionRemover's (the kinetic energy at the ends of each step, tallied on the device).
    Omelyan2 with the Bussi thermostat at 6 fs, inside its range, stays quiet under NPT; without the
    barostat's moves taken out it fired (fluctuation 0.094, the moves' energy read as the error's). At
    8 fs Verlet, outside its range, it still fires under NPT."""
    system, state = water_state
    system = openmm.XmlSerializer.clone(system)
    system.addForce(openmm.CMMotionRemover(1))
    barostat = openmm.MonteCarloBarostat(1 * unit.bar, 300 * unit.kelvin, 5)
    barostat.setRandomNumberSeed(2)
    system.addForce(barostat)
    fired = {}
    for splitting, dt in ((RigidBodyIntegrator.Omelyan2, 0.006), (RigidBodyIntegrator.Verlet, 0.008)):
        integrator = RigidBodyBussiIntegrator(300, 1.0, dt)
        integrator.setSplitting(splitting)
        context = openmm.Context(system, integrator, *systems.platform_and_properties("CPU"))
        context.setState(state)
        volume = context.getState().getPeriodicBoxVolume()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", AccuracyWarning)
            integrator.step(int(round(8.0 / dt)))
        assert context.getState().getPeriodicBoxVolume() != volume, "the barostat accepted no move"
        fired[dt] = [str(w.message) for w in accuracy_warnings(caught)]
        del context
    assert fired[0.006] == [], fired[0.006]
    assert len(fired[0.008]) == 1 and "RigidBodyBussiIntegrator (Verlet) at a step of 8 fs" in fired[0.008][0], fired[0.008]


def test_accuracy_check_off(water_state):
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.011)
    integrator.setAccuracyCheck(False)
    fired, caught = run_checked(water_state, integrator, 6, chunk=3)
    assert fired is None and not caught


def test_accuracy_check_reads_again_after_a_change_of_step(water_state):
    """Quiet at 4 fs past its first episode; the step raised to 11 fs starts a new one, which fires."""
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.004)
    context = water_context(water_state, integrator)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AccuracyWarning)
        integrator.step(2000)  # 8 ps: the first episode (4 ps) is over
    assert accuracy_warnings(caught) == []
    integrator.setStepSize(0.011)
    with pytest.warns(AccuracyWarning, match="at a step of 11 fs"):
        integrator.step(int(6.0 / 0.011))
    del context


def test_accuracy_check_is_quiet_when_the_state_is_set_again_and_again(water_state):
    """Canonical velocities set every 0.5 ps (as a sampling protocol does) make each first kick's
    shadow work jump (by about (omega dt)^2 kT / 2 per degree of freedom): the check starts its
    windows again after each and stays quiet at 8 fs."""
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.008)
    context = water_context(water_state, integrator)
    system = water_state[0]
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    rng = np.random.default_rng(1)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AccuracyWarning)
        for _ in range(20):
            context.setVelocities(rng.standard_normal((len(masses), 3)) * np.sqrt(BOLTZMANN * 300 / masses)[:, None])
            integrator.step(62)
    assert accuracy_warnings(caught) == []


FIRING_STEPS = int(round(8.0 / 0.011))  # Langevin at 11 fs fires within 6 ps


def test_accuracy_warning_through_a_compound_integrator_and_simulation(water_state):
    """The warning is issued from within the step, however it was taken: a CompoundIntegrator's step()
    (which never calls our Python wrapper of step()) and app.Simulation.step() both warn once,
    attributed to the line of this file that stepped (not openmm/app/simulation.py)."""
    system, state = water_state
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(openmm.VerletIntegrator(0.001))
    compound.addIntegrator(RigidBodyLangevinIntegrator(300, 1, 0.011))
    compound.setCurrentIntegrator(1)
    context = openmm.Context(system, compound, *systems.platform_and_properties("CPU"))
    context.setState(state)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AccuracyWarning)
        compound.step(FIRING_STEPS)
        compound.step(10)
    caught = accuracy_warnings(caught)
    assert len(caught) == 1 and "RigidBodyLangevinIntegrator at a step of 11 fs" in str(caught[0].message)
    assert caught[0].filename == __file__
    del context
    simulation = openmm.app.Simulation(openmm.app.Topology(), system, RigidBodyLangevinIntegrator(300, 1, 0.011),
                                       *systems.platform_and_properties("CPU"))
    simulation.context.setState(state)
    with pytest.warns(AccuracyWarning, match="at a step of 11 fs") as caught:
        simulation.step(FIRING_STEPS)
    assert [w.filename for w in accuracy_warnings(caught)] == [__file__]


def test_accuracy_warning_as_an_error_stops_the_step(water_state):
    """With the warning filtered as an error, the step that fired raises it: as an AccuracyWarning
    from the integrator's own step(), as an OpenMMException with the same message from a
    CompoundIntegrator's (whose wrapper is openmm's). The Context holds the state after that step."""
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.011)
    context = water_context(water_state, integrator)
    start, startTime = context.getStepCount(), context.getState().getTime().value_in_unit(unit.picosecond)
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        with pytest.raises(AccuracyWarning, match="at a step of 11 fs"):
            integrator.step(FIRING_STEPS)
    steps = context.getStepCount() - start
    assert 0 < steps < FIRING_STEPS
    assert context.getState().getTime().value_in_unit(unit.picosecond) - startTime == pytest.approx(steps * 0.011)
    integrator.step(2)  # fired once: the run goes on quietly
    del context
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(RigidBodyLangevinIntegrator(300, 1, 0.011))
    context = water_context(water_state, compound)
    with warnings.catch_warnings():
        warnings.simplefilter("error", AccuracyWarning)
        with pytest.raises(openmm.OpenMMException, match="at a step of 11 fs"):
            compound.step(FIRING_STEPS)


def test_accuracy_check_is_rearmed_by_a_rewind(water_state):
    """After the check fired (once: it stays quiet for the rest of the run), a checkpoint or State from
    before it makes the check judge the run again (otherwise the rerun would never be judged): the
    rerun fires again, after each kind of rewind."""
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.011)
    context = water_context(water_state, integrator)
    checkpoint = context.createCheckpoint()
    before = context.getState(getPositions=True, getVelocities=True)
    with pytest.warns(AccuracyWarning, match="at a step of 11 fs"):
        integrator.step(FIRING_STEPS)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AccuracyWarning)
        integrator.step(FIRING_STEPS)
    assert accuracy_warnings(caught) == []  # fired once: quiet without a rewind
    for rewind in (lambda: context.loadCheckpoint(checkpoint), lambda: context.setState(before)):
        rewind()
        with pytest.warns(AccuracyWarning, match="at a step of 11 fs"):
            integrator.step(FIRING_STEPS)


def test_accuracy_check_leaves_andersen_runs_alone(water_state):
    """An AndersenThermostat's redraws are not rigid motion: the next step's projection removes energy
    (counted as shadow work), which the check would read as a drift; such runs are not checked."""
    system, state = water_state
    system = openmm.XmlSerializer.clone(system)
    system.addForce(openmm.AndersenThermostat(300, 5))
    integrator = RigidBodyIntegrator(0.002)
    integrator.setMeasureShadowWork(True)
    context = openmm.Context(system, integrator, *systems.platform_and_properties("CPU"))
    context.setState(state)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", AccuracyWarning)
        integrator.step(2500)
    assert accuracy_warnings(caught) == []
    assert integrator.getShadowWork().value_in_unit(KJ) < 0  # the projections' losses are in it

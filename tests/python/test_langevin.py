"""Tests of openmmrigid.RigidBodyLangevinIntegrator from Python (the C++ tests,
TestRigidBodyThermostats.h, check the exact properties of the step on the Reference, CPU and OpenCL
platforms: seeds, friction 0 as leapfrog Verlet, exact damping at temperature 0, ...):

- a small box of rigid TIP3P water reaches the bath temperature in translation and in rotation,
  each within 4.5 block standard errors;
- the kinetic energy of free rigid bodies (no forces) follows the canonical Gamma distribution:
  Kolmogorov-Smirnov tests of the total and of the rotational energy of single asymmetric and
  linear bodies;
- Simulation checkpoints continue a trajectory (its random numbers too);
- bad temperatures and frictions raise openmm.OpenMMException and leave the Context usable;
- construction from floats and Quantities, the getters' units; pickle, copy, deepcopy and
  deserializeIntegrator keep every setting and give back the right class (openmm.XmlSerializer
  gives back an openmm.Integrator that runs ours and keeps every setting); the integrator in
  app.Simulation with StateDataReporter and a MonteCarloBarostat.

The kinetic energies, degrees of freedom and body kinds are computed from the State
(rigidtesting.bodies), independently of the integrator's own sums.
"""

import io

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest
from scipy import stats

import openmmrigid
import systems
from systems import COPY_METHODS, copy_integrator
from openmmrigid import RigidBodyIntegrator, RigidBodyIntegratorBase, RigidBodyLangevinIntegrator
from rigidtesting.bodies import bodyKind, rigidDegreesOfFreedom, rigidKineticEnergies
from test_integrator_api import EXPLICIT_BODIES, MASSES, POSITIONS, platform, topology_for, trapped_system

PLATFORMS = ["Reference", "CPU"]
BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)


def settings(integrator):
    """Every setting a copy must keep (the bodies, explicit or not, through the XML, which writes them)."""
    return (integrator.getTemperature(), integrator.getFriction(), integrator.getRandomNumberSeed(),
            integrator.getStepSize(), integrator.getConstraintTolerance(), integrator.getIntegrationForceGroups(),
            integrator.getRotationMethod(), integrator.getMinimumMomentOfInertia(), integrator.getMeasureShadowWork(),
            integrator.getAccuracyCheck(), openmm.XmlSerializer.serialize(integrator))


def configured(bodies):
    """An integrator with every setting away from its default."""
    arguments = (310.0, 2.5, 0.0015)
    integrator = RigidBodyLangevinIntegrator(*arguments, bodies) if bodies is not None else RigidBodyLangevinIntegrator(*arguments)
    integrator.setRandomNumberSeed(1234)
    integrator.setConstraintTolerance(3e-7)
    integrator.setIntegrationForceGroups({0, 2, 5})
    integrator.setRotationMethod(RigidBodyLangevinIntegrator.NoSquish)
    integrator.setMinimumMomentOfInertia(0.0125)
    integrator.setMeasureShadowWork(True)
    integrator.setAccuracyCheck(False)
    return integrator


def trapped_context(platformName, integrator):
    context = openmm.Context(trapped_system(), integrator, platform(platformName))
    context.setPositions(POSITIONS)
    context.setVelocitiesToTemperature(300, 1)
    return context


# ------------------------------------------------------------------------------------------------
# Temperature of rigid water
# ------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def small_water_box():
    """systems.small_water_box() after 500 steps of equilibration."""
    return systems.small_water_box(500)


def assert_water_temperatures(integrator, target, samples, every, blocks, label="", tolerance=None, *, context):
    """Sample the translational and rotational kinetic energies of the rigid waters (from the State of
    `context`, the integrator's Context: rigidtesting.bodies.rigidKineticEnergies) every `every` steps,
    `samples` times, and check each temperature (3 N degrees of freedom each) and the temperature
    StateDataReporter reads (computeSystemTemperature()): its block standard error below 1 % of the
    target (so that the test can see a bias of a few percent), and the mean within 4.5 of those
    errors of the target and, if given, within `tolerance` (relative) of it."""
    numWaters = integrator.getNumBodies()
    translational, rotational, reported = [], [], []
    for _ in range(samples):
        integrator.step(every)
        parts = rigidKineticEnergies(context, integrator)
        translational.append(parts[0])
        rotational.append(parts[1])
        reported.append(integrator.computeSystemTemperature().value_in_unit(unit.kelvin))
    for name, temperatures in (("translational", 2 * np.asarray(translational) / (3 * numWaters * BOLTZMANN)),
                               ("rotational", 2 * np.asarray(rotational) / (3 * numWaters * BOLTZMANN)),
                               ("reported", np.asarray(reported))):
        mean, error = block_mean(temperatures, blocks=blocks)
        print(f"{label}{name} temperature: {mean:.2f} +- {error:.2f} K ({numWaters} waters)")
        assert error < 0.01 * target
        assert abs(mean - target) < 4.5 * error, f"{name} temperature {mean:.2f} +- {error:.2f} K, not {target} K"
        if tolerance is not None:
            assert abs(mean - target) < tolerance * target, f"{name} temperature {mean:.2f} K, not {target} K within {tolerance:.1%}"


def block_mean(samples, blocks=20):
    """The mean of the samples and its standard error from the means of consecutive blocks."""
    samples = np.asarray(samples)
    means = samples[:len(samples) // blocks * blocks].reshape(blocks, -1).mean(axis=1)
    return samples.mean(), means.std(ddof=1) / np.sqrt(blocks)


def equilibrated_langevin(box, temperature, friction, stepFs, seed, steps):
    """A RigidBodyLangevinIntegrator (friction in 1/ps, step in fs) and its Context on the CPU
    platform, from the box's state, after `steps` steps of its own equilibration."""
    system, state = box
    integrator = RigidBodyLangevinIntegrator(temperature * unit.kelvin, friction / unit.picosecond, stepFs * unit.femtoseconds)
    integrator.setRandomNumberSeed(seed)
    context = openmm.Context(system, integrator, *systems.platform_and_properties("CPU"))
    context.setState(state)
    integrator.step(steps)
    return context, integrator


def test_water_reaches_the_bath_temperature(small_water_box):
    """The mean translational and rotational temperatures, each from its own kinetic energy and its
    3 N degrees of freedom, are 300 K within 4.5 standard errors of 20 block means (10 ps at 1 fs;
    friction 50/ps decorrelates the kinetic energy within a few tens of fs, so the blocks of 0.5 ps
    are independent). The error itself must be small enough for the test to mean something: below
    1 % of the target. (BAOAB's on-step velocities, which this integrator reported before, read the
    rotation 0.3 % low at 1 fs, about one standard error; the 4 fs test below tells them apart.)"""
    system, state = small_water_box
    target = 300.0
    context, integrator = equilibrated_langevin(small_water_box, target, friction=50, stepFs=1, seed=11, steps=1000)
    numWaters = integrator.getNumBodies()
    assert numWaters == system.getNumParticles() // 3 and rigidDegreesOfFreedom(context, integrator) == 6 * numWaters
    # The temperature the integrator reports divides by the same degrees of freedom.
    kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(
        2 * kinetic / (6 * numWaters * BOLTZMANN), rel=1e-6)
    assert_water_temperatures(integrator, target, samples=5000, every=2, blocks=20, context=context)


def test_water_temperature_reads_right_at_4_fs(small_water_box):
    """At 4 fs the temperature the integrator reports (StateDataReporter's column), and each of the
    translational and rotational parts, is 300 K within 4.5 standard errors and 1.5 %: the velocities
    it reports are LangevinMiddleIntegrator's, half a step behind the positions, whose distribution
    is canonical. (BAOAB's on-step velocities read the rotational temperature about 4 % low here.)
    Friction 20/ps; samples 8 fs apart, 20 blocks of 2 ps."""
    target = 300.0
    context, integrator = equilibrated_langevin(small_water_box, target, friction=20, stepFs=4, seed=13, steps=500)
    assert_water_temperatures(integrator, target, samples=5000, every=2, blocks=20, label="4 fs: ", tolerance=0.015,
                              context=context)


# ------------------------------------------------------------------------------------------------
# The canonical distribution of the kinetic energy
# ------------------------------------------------------------------------------------------------

def test_kinetic_energy_distribution_is_canonical():
    """Free bodies of every kind and free atoms without forces: the free motion keeps each body's
    kinetic energy and the Ornstein-Uhlenbeck step keeps the canonical momenta, so the total kinetic
    energy is Gamma(dof/2, kT) distributed (dof counted from the bodies' kinds), the rotational energy of
    an asymmetric body Gamma(3/2, kT) and of a linear body Gamma(1, kT), exactly. Samples are 4 steps
    apart at friction dt = 0.5 (correlation of the energy c^8 = 0.02: independent), the rotational
    ones pooled over bodies of a kind. Kolmogorov-Smirnov at the 0.1 % level (fixed seed); a noise
    amplitude off by a few percent fails it."""
    cluster = systems.cluster(seed=4, grid=(3, 3, 3), forces=False)
    temperature, dt = 300.0, 0.002
    kT = BOLTZMANN * temperature
    integrator = RigidBodyLangevinIntegrator(temperature, 0.5 / dt, dt, cluster.bodies)
    integrator.setRandomNumberSeed(21)
    context = systems.make_context(cluster.system, integrator, "Reference")
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    integrator.step(10)
    dof = rigidDegreesOfFreedom(context, integrator)
    positions = systems.positions_of(context)
    kinds = [bodyKind(cluster.masses[body], positions[body]) for body in cluster.bodies]
    assert {"asymmetric", "linear"} <= set(kinds)
    total, rotational = [], {"asymmetric": [], "linear": []}
    for _ in range(1500):
        integrator.step(4)
        velocities = systems.velocities_of(context)
        total.append(0.5 * np.sum(cluster.masses[:, None] * velocities**2))
        for body, kind in zip(cluster.bodies, kinds):
            if kind in rotational:
                masses, v = cluster.masses[body], velocities[body]
                relative = v - masses @ v / masses.sum()
                rotational[kind].append(0.5 * np.sum(masses[:, None] * relative**2))
    checks = [("total", total, dof / 2), ("asymmetric rotation", rotational["asymmetric"], 1.5),
              ("linear rotation", rotational["linear"], 1.0)]
    for name, energies, shape in checks:
        result = stats.kstest(energies, stats.gamma(shape, scale=kT).cdf)
        print(f"{name}: {len(energies)} samples, mean {np.mean(energies):.4f} (expected {shape * kT:.4f}) kJ/mol, "
              f"KS p = {result.pvalue:.3g}")
        assert result.pvalue > 1e-3, f"{name}: KS p-value {result.pvalue:.3g}"


# ------------------------------------------------------------------------------------------------
# Seeds, checkpoints, limits of friction and temperature
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
def test_simulation_checkpoint_continues(platformName):
    integrator = RigidBodyLangevinIntegrator(300.0, 5.0, 0.001, EXPLICIT_BODIES)
    integrator.setRandomNumberSeed(3)
    simulation = app.Simulation(topology_for(len(MASSES)), trapped_system(), integrator, platform(platformName))
    simulation.context.setPositions(POSITIONS)
    simulation.context.setVelocitiesToTemperature(300, 3)
    simulation.step(10)
    checkpoint = io.BytesIO()
    simulation.saveCheckpoint(checkpoint)
    simulation.step(20)
    expected = systems.positions_of(simulation.context)
    checkpoint.seek(0)
    simulation.loadCheckpoint(checkpoint)
    simulation.step(20)
    # Loading re-fits the bodies to the positions (rounding); other random numbers would differ by far more.
    assert np.abs(systems.positions_of(simulation.context) - expected).max() < 1e-10


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_bad_values_leave_a_usable_context(platformName):
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(openmm.OpenMMException, match="temperature"):
            RigidBodyLangevinIntegrator(bad, 1.0, 0.001)
        with pytest.raises(openmm.OpenMMException, match="friction"):
            RigidBodyLangevinIntegrator(300.0, bad, 0.001, EXPLICIT_BODIES)
    with pytest.raises(openmm.OpenMMException, match=r"temperature.*-5"):
        RigidBodyLangevinIntegrator(-5 * unit.kelvin, 1.0, 0.001)
    integrator = RigidBodyLangevinIntegrator(300.0, 2.0, 0.001, EXPLICIT_BODIES)
    context = trapped_context(platformName, integrator)
    integrator.step(5)
    with pytest.raises(openmm.OpenMMException, match=r"temperature.*-3"):
        integrator.setTemperature(-3.0)
    with pytest.raises(openmm.OpenMMException, match=r"friction.*nan"):
        integrator.setFriction(float("nan"))
    with pytest.raises(openmm.OpenMMException, match="friction"):
        integrator.setFriction(-1 / unit.picosecond)
    assert integrator.getTemperature() == 300.0 * unit.kelvin
    assert integrator.getFriction() == 2.0 / unit.picosecond
    integrator.step(5)
    assert np.all(np.isfinite(systems.positions_of(context)))
    assert 0 < integrator.computeSystemTemperature().value_in_unit(unit.kelvin) < 1e4


# ------------------------------------------------------------------------------------------------
# Construction, settings and copies
# ------------------------------------------------------------------------------------------------

def test_classes():
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.002)
    assert isinstance(integrator, openmm.Integrator) and isinstance(integrator, RigidBodyIntegratorBase)
    assert not isinstance(integrator, RigidBodyIntegrator)
    assert isinstance(RigidBodyIntegrator(0.002), RigidBodyIntegratorBase)
    for name in ("RigidBodyLangevinIntegrator", "RigidBodyIntegratorBase"):
        assert name in openmmrigid.__all__ and hasattr(openmmrigid, name)
    assert RigidBodyLangevinIntegrator.Exact == RigidBodyIntegrator.Exact == 0
    assert RigidBodyLangevinIntegrator.NoSquish == RigidBodyIntegrator.NoSquish == 1
    assert not hasattr(integrator, "setSplitting")


@pytest.mark.parametrize("arguments", [
    (300, 1, 0.002),
    (300 * unit.kelvin, 1 / unit.picosecond, 2 * unit.femtoseconds),
    (300 * unit.kelvin, 0.001 / unit.femtosecond, 0.002 * unit.picosecond),
])
def test_units(arguments):
    for integrator in (RigidBodyLangevinIntegrator(*arguments), RigidBodyLangevinIntegrator(*arguments, [[0, 1]])):
        assert integrator.getTemperature() == 300 * unit.kelvin
        assert integrator.getFriction().value_in_unit(unit.picosecond**-1) == pytest.approx(1.0)
        assert integrator.getStepSize().value_in_unit(unit.picosecond) == pytest.approx(0.002)
        assert integrator.getRandomNumberSeed() == 0 and integrator.getRotationMethod() == RigidBodyLangevinIntegrator.Exact
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.002)
    integrator.setTemperature(77 * unit.kelvin)
    integrator.setFriction(0.5 / unit.femtosecond)
    assert integrator.getTemperature() == 77 * unit.kelvin
    assert integrator.getFriction().value_in_unit(unit.picosecond**-1) == pytest.approx(500.0)
    with pytest.raises(TypeError):
        integrator.setFriction(1 * unit.picosecond)  # not a rate
    with pytest.raises(TypeError):
        RigidBodyLangevinIntegrator(300 * unit.nanometer, 1, 0.002)


BODY_CHOICES = {"found": None, "explicit": EXPLICIT_BODIES, "none": []}


@pytest.mark.parametrize("choice", BODY_CHOICES)
@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_every_setting(choice, method):
    original = configured(BODY_CHOICES[choice])
    duplicate = copy_integrator(original, method)
    assert type(duplicate) is RigidBodyLangevinIntegrator
    assert duplicate.thisown
    expected = settings(original)
    del original  # the copy owns its own C++ object
    assert settings(duplicate) == expected
    assert duplicate.getTemperature() == 310 * unit.kelvin and duplicate.getRandomNumberSeed() == 1234


@pytest.mark.parametrize("choice", BODY_CHOICES)
def test_openmm_copies_run_ours_and_keep_every_setting(choice):
    """openmm.XmlSerializer.deserialize() and clone() know only openmm.Integrator: they give back the
    same C++ class (its XML is the original's) without our methods; deserializeIntegrator() of that
    XML is ours with every setting."""
    original = configured(BODY_CHOICES[choice])
    xml = openmm.XmlSerializer.serialize(original)
    for duplicate in (openmm.XmlSerializer.deserialize(xml), openmm.XmlSerializer.clone(original)):
        assert type(duplicate) is openmm.Integrator and not hasattr(duplicate, "getTemperature")
        assert openmm.XmlSerializer.serialize(duplicate) == xml
        assert settings(openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(duplicate))) == settings(original)


def test_xml_format_and_versions():
    xml = openmm.XmlSerializer.serialize(configured([[0, 1, 2], [3]]))
    assert 'type="RigidBodyLangevinIntegrator"' in xml and 'version="2"' in xml
    for attribute in ("temperature", "friction", "randomSeed", "stepSize", "constraintTolerance",
                      "integrationForceGroups", "rotationMethod", "minimumMomentOfInertia", "explicitBodies", "measureShadowWork",
                      "accuracyCheck"):
        assert attribute + "=" in xml
    assert "measureHeat=" not in xml  # one switch measures shadow work and heat
    minimal = ('<?xml version="1.0" ?>\n<Integrator temperature="250" friction="3" stepSize=".004" '
               'type="RigidBodyLangevinIntegrator" version="1"/>\n')
    assert type(openmm.XmlSerializer.deserialize(minimal)) is openmm.Integrator
    integrator = openmmrigid.deserializeIntegrator(minimal)
    assert type(integrator) is RigidBodyLangevinIntegrator
    assert settings(integrator) == settings(RigidBodyLangevinIntegrator(250, 3, 0.004))
    # Version 2 files written when the heat had a switch of its own measure both if they measured either.
    for measured in ('measureHeat="1"', 'measureShadowWork="1"', 'measureShadowWork="1" measureHeat="1"'):
        old = minimal.replace('version="1"', f'version="2" {measured}')
        assert openmmrigid.deserializeIntegrator(old).getMeasureShadowWork()
    unmeasured = minimal.replace('version="1"', 'version="2" measureHeat="0"')
    assert not openmmrigid.deserializeIntegrator(unmeasured).getMeasureShadowWork()
    for bad, words in (('version="3"', "version"), ('version="1" rotationMethod="4"', "rotation method")):
        text = ('<?xml version="1.0" ?>\n<Integrator temperature="250" friction="3" stepSize=".004" '
                f'type="RigidBodyLangevinIntegrator" {bad}/>\n')
        for deserialize in (openmm.XmlSerializer.deserialize, openmmrigid.deserializeIntegrator):
            with pytest.raises(openmm.OpenMMException, match=words):
                deserialize(text)
    negative = minimal.replace('friction="3"', 'friction="-3"')
    with pytest.raises(openmm.OpenMMException, match="friction"):
        openmmrigid.deserializeIntegrator(negative)
    with pytest.raises(openmm.OpenMMException):
        openmmrigid.deserializeIntegrator(minimal.replace(' temperature="250"', ""))
    # A RigidBodyLangevinIntegrator is not a RigidBodyIntegrator: pickled states do not cross over.
    plain = RigidBodyIntegrator.__new__(RigidBodyIntegrator)
    with pytest.raises(openmm.OpenMMException, match="RigidBodyLangevinIntegrator"):
        plain.__setstate__(openmm.XmlSerializer.serialize(configured(None)))


# ------------------------------------------------------------------------------------------------
# With app.Simulation
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
def test_simulation_and_reporter(platformName):
    integrator = RigidBodyLangevinIntegrator(300, 10, 0.001, EXPLICIT_BODIES)
    simulation = app.Simulation(topology_for(len(MASSES)), trapped_system(), integrator, platform(platformName))
    simulation.context.setPositions(POSITIONS)
    output = io.StringIO()
    simulation.reporters.append(app.StateDataReporter(output, 5, step=True, temperature=True))
    simulation.step(10)
    reported = float(output.getvalue().splitlines()[-1].split(",")[1])
    assert reported == pytest.approx(integrator.computeSystemTemperature().value_in_unit(unit.kelvin), rel=1e-6)
    assert integrator.getNumBodies() == len(EXPLICIT_BODIES)
    assert [list(integrator.getBodyParticles(b)) for b in range(len(EXPLICIT_BODIES))] == EXPLICIT_BODIES
    positions, masses = systems.positions_of(simulation.context), np.array(MASSES)
    kinds = [bodyKind(masses[body], positions[body]) for body in EXPLICIT_BODIES]
    assert kinds == ["asymmetric", "linear", "point", "asymmetric"]


def test_barostat_keeps_bodies_rigid():
    """MonteCarloBarostat moves (which scale the molecules' centres) with the Langevin integrator."""
    box = systems.water_box("tip3p", size=1.5, seed=3)
    system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(box.system))
    system.addForce(openmm.MonteCarloBarostat(1 * unit.bar, 300 * unit.kelvin, 5))
    integrator = RigidBodyLangevinIntegrator(300, 5, 0.002)
    integrator.setRandomNumberSeed(2)
    context = systems.make_context(system, integrator, "CPU")
    context.setPositions(box.positions)
    context.setVelocities(box.velocities)
    volume = context.getState().getPeriodicBoxVolume()
    integrator.step(300)
    assert context.getState().getPeriodicBoxVolume() != volume
    positions = systems.positions_of(context)
    # Rigid to rounding: each water keeps the shape its constraints give it.
    for c in range(system.getNumConstraints()):
        i, j, length = system.getConstraintParameters(c)
        assert np.linalg.norm(positions[i] - positions[j]) == pytest.approx(length.value_in_unit(unit.nanometer), abs=1e-12)

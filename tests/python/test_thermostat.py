"""Tests of RigidBodyBussiIntegrator, RigidBodyIntegrator with the thermostat of stochastic velocity
rescaling (Bussi, Donadio and Parrinello, J. Chem. Phys. 126, 014101 (2007)), from Python; the C++ tests
(TestRigidBodyThermostats.h) check eq. (A7) itself, exact damping, the effective energy to second
order, seeds, threads and checkpoints on both platforms.

- a small box of rigid TIP3P water reaches the bath temperature in translation and in rotation,
  each within 4.5 block standard errors;
- the total kinetic energy of free rigid bodies follows the canonical Gamma distribution
  (Kolmogorov-Smirnov);
- the settings: units, errors naming the class, the class itself (RigidBodyIntegrator has no
  temperature), copies (pickle, copy, deepcopy, deserializeIntegrator; openmm.XmlSerializer gives back
  an openmm.Integrator that runs ours), the XML of a RigidBodyIntegrator with a thermostat (the format
  before RigidBodyBussiIntegrator) read as a RigidBodyBussiIntegrator (the XML format and its versions
  are tested in C++, TestSerialization.cpp), and the thermostat's work (the heat) kept by Simulation
  checkpoints.
"""

import io

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest
from scipy import stats

import systems
import openmmrigid
from systems import COPY_METHODS, copy_integrator
from openmmrigid import RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyIntegratorBase
from rigidtesting.bodies import rigidDegreesOfFreedom
from test_integrator_api import EXPLICIT_BODIES, MASSES, POSITIONS, platform, topology_for, trapped_system
from test_langevin import BOLTZMANN, assert_water_temperatures, small_water_box  # noqa: F401 (small_water_box is a fixture)


def thermostatted(stepSize, temperature=300.0, collisionTime=0.1, bodies=None, seed=1):
    arguments = (temperature, collisionTime, stepSize)
    integrator = RigidBodyBussiIntegrator(*arguments, bodies) if bodies is not None else RigidBodyBussiIntegrator(*arguments)
    integrator.setRandomNumberSeed(seed)
    return integrator


def test_water_reaches_the_bath_temperature(small_water_box):  # noqa: F811 (the fixture)
    """The thermostat controls the total kinetic energy; the dynamics shares it between translation
    and rotation. Each of their mean temperatures (3 N degrees of freedom each) is 300 K within 4.5
    standard errors of 12 block means of 4 ps (48 ps at 2 fs, tau = 0.1 ps), and the error is below 1 %.
    (The block error itself scatters from run to run, since CPU forces are not bitwise repeatable: 2.0
    to 3.2 K over 24 ps; 48 ps keeps it below the 3 K that makes a 5 % bias fail the test.)"""
    system, state = small_water_box
    target = 300.0
    integrator = thermostatted(2 * unit.femtoseconds, target * unit.kelvin, 0.1 * unit.picosecond, seed=13)
    context = openmm.Context(system, integrator, *systems.platform_and_properties("CPU"))
    context.setState(state)
    integrator.step(500)
    assert_water_temperatures(integrator, target, samples=6000, every=4, blocks=12, label="thermostat, ", context=context)


def test_kinetic_energy_distribution_is_canonical():
    """Free bodies of every kind and free atoms without forces: the free motion keeps the kinetic
    energy and the rescaling samples it exactly from Gamma(dof/2, kT). dt/tau = 0.5, samples 6 steps
    apart (correlation exp(-3) = 0.05); Kolmogorov-Smirnov at the 0.1 % level (fixed seed)."""
    cluster = systems.cluster(seed=4, grid=(3, 3, 3), forces=False)
    temperature, dt = 300.0, 0.002
    integrator = thermostatted(dt, temperature, 2 * dt, cluster.bodies, seed=23)
    context = systems.make_context(cluster.system, integrator, "Reference")
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    integrator.step(10)
    dof = rigidDegreesOfFreedom(context, integrator)
    energies = []
    for _ in range(1500):
        integrator.step(6)
        energies.append(context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole))
    result = stats.kstest(energies, stats.gamma(dof / 2, scale=BOLTZMANN * temperature).cdf)
    print(f"thermostat: {len(energies)} samples, mean {np.mean(energies):.3f} (expected "
          f"{dof / 2 * BOLTZMANN * temperature:.3f}) kJ/mol, KS p = {result.pvalue:.3g}")
    assert result.pvalue > 1e-3


# ------------------------------------------------------------------------------------------------
# Settings
# ------------------------------------------------------------------------------------------------

def test_settings_and_units():
    integrator = RigidBodyBussiIntegrator(310 * unit.kelvin, 50 * unit.femtoseconds, 2 * unit.femtoseconds)
    assert integrator.getRandomNumberSeed() == 0
    assert integrator.getTemperature() == 310 * unit.kelvin
    assert integrator.getCollisionTime().value_in_unit(unit.picosecond) == pytest.approx(0.05)
    assert integrator.getStepSize().value_in_unit(unit.picosecond) == pytest.approx(0.002)
    assert integrator.getSplitting() == RigidBodyIntegrator.Verlet
    integrator.setTemperature(0)
    integrator.setCollisionTime(1.0)
    assert integrator.getTemperature() == 0 * unit.kelvin
    assert integrator.getCollisionTime() == 1.0 * unit.picosecond
    integrator.setTemperature(280 * unit.kelvin)
    integrator.setCollisionTime(250 * unit.femtoseconds)
    assert integrator.getTemperature() == 280 * unit.kelvin
    assert integrator.getCollisionTime().value_in_unit(unit.picosecond) == pytest.approx(0.25)
    for temperature, collisionTime in ((-1, 0.1), (float("nan"), 0.1), (300, 0), (300, -1), (300, float("inf"))):
        what = "temperature" if collisionTime == 0.1 else "collision time"
        with pytest.raises(openmm.OpenMMException, match=f"RigidBodyBussiIntegrator: the {what}"):
            RigidBodyBussiIntegrator(temperature, collisionTime, 0.002)
        with pytest.raises(openmm.OpenMMException, match=f"RigidBodyBussiIntegrator: the {what}"):
            if what == "temperature":
                integrator.setTemperature(temperature)
            else:
                integrator.setCollisionTime(collisionTime)
    assert integrator.getTemperature() == 280 * unit.kelvin  # bad values change nothing
    assert integrator.getCollisionTime().value_in_unit(unit.picosecond) == pytest.approx(0.25)
    with pytest.raises(TypeError):
        RigidBodyBussiIntegrator(300 * unit.kelvin, 1 / unit.picosecond, 0.002)  # a rate, not a time
    with pytest.raises(TypeError):
        integrator.setCollisionTime(1 / unit.picosecond)
    with pytest.raises(TypeError):
        integrator.setTemperature(300 * unit.nanometer)
    with pytest.raises(openmm.OpenMMException, match="RigidBodyBussiIntegrator: .*bound to a Context"):
        integrator.getHeat()
    for name in ("getTemperature", "setTemperature", "getCollisionTime", "setCollisionTime", "getRandomNumberSeed",
                 "setRandomNumberSeed"):
        assert getattr(RigidBodyBussiIntegrator, name).__doc__
    assert "Bussi" in RigidBodyBussiIntegrator.__doc__


def test_the_class_says_whether_there_is_a_thermostat():
    """RigidBodyBussiIntegrator is a RigidBodyIntegrator (the splittings) with a heat bath; a
    RigidBodyIntegrator has no temperature at all, so that openmmtools (and anything that asks for
    getTemperature) sees the constant-energy integrator it is."""
    bussi, plain = RigidBodyBussiIntegrator(300, 0.1, 0.002), RigidBodyIntegrator(0.002)
    assert isinstance(bussi, RigidBodyIntegrator) and isinstance(bussi, RigidBodyIntegratorBase)
    assert isinstance(bussi, openmm.Integrator) and not isinstance(plain, RigidBodyBussiIntegrator)
    assert "RigidBodyBussiIntegrator" in openmmrigid.__all__
    for name in ("getTemperature", "setTemperature", "getCollisionTime", "setCollisionTime", "getRandomNumberSeed",
                 "setRandomNumberSeed"):
        assert hasattr(bussi, name) and not hasattr(plain, name), name
    for name in ("setThermostat", "removeThermostat", "hasThermostat", "getThermostatWork", "getThermostatTemperature"):
        assert not hasattr(bussi, name) and not hasattr(plain, name), name
    bussi.setSplitting(RigidBodyIntegrator.Omelyan2)
    assert bussi.getSplitting() == RigidBodyIntegrator.Omelyan2


@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_the_thermostat(method):
    original = thermostatted(0.002, 280.0, 0.25, EXPLICIT_BODIES, seed=99)
    original.setSplitting(RigidBodyIntegrator.Omelyan2)
    duplicate = copy_integrator(original, method)
    assert type(duplicate) is RigidBodyBussiIntegrator
    assert duplicate.getRandomNumberSeed() == 99
    assert duplicate.getTemperature() == 280 * unit.kelvin
    assert duplicate.getCollisionTime() == 0.25 * unit.picosecond
    assert duplicate.getSplitting() == RigidBodyIntegrator.Omelyan2
    assert openmm.XmlSerializer.serialize(duplicate) == openmm.XmlSerializer.serialize(original)  # the bodies too
    assert "<Bodies>" in openmm.XmlSerializer.serialize(duplicate)


def test_openmm_copies_run_ours():
    """openmm.XmlSerializer.deserialize() and clone() give back an openmm.Integrator without our methods
    whose C++ object is a RigidBodyBussiIntegrator with every setting (its XML is the original's)."""
    original = thermostatted(0.002, 280.0, 0.25, EXPLICIT_BODIES, seed=99)
    xml = openmm.XmlSerializer.serialize(original)
    for duplicate in (openmm.XmlSerializer.deserialize(xml), openmm.XmlSerializer.clone(original)):
        assert type(duplicate) is openmm.Integrator and not hasattr(duplicate, "getTemperature")
        assert openmm.XmlSerializer.serialize(duplicate) == xml
        assert type(openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(duplicate))) is RigidBodyBussiIntegrator


def test_xml_of_a_thermostatted_rigid_body_integrator_reads_as_bussi():
    """The XML a RigidBodyIntegrator with setThermostat() wrote (version 3 and 4 of its format) is read
    as a RigidBodyBussiIntegrator with the same heat bath, seed, splitting and bodies; without the
    thermostat it stays a RigidBodyIntegrator."""
    old = ('<?xml version="1.0" ?>\n<Integrator accuracyCheck="1" constraintTolerance="1e-05" explicitBodies="1" '
           'integrationForceGroups="-1" measureHeat="1" measureShadowWork="0" minimumMomentOfInertia="0" randomSeed="99" '
           'rotationMethod="0" splitting="1" stepSize=".002" thermostat="1" thermostatCollisionTime=".25" '
           'thermostatTemperature="280" type="RigidBodyIntegrator" version="4">\n'
           '<Bodies><Body><Particle index="0"/><Particle index="1"/><Particle index="2"/></Body>'
           '<Body><Particle index="4"/><Particle index="5"/></Body></Bodies>\n</Integrator>\n')
    for version in ("3", "4"):
        integrator = openmmrigid.deserializeIntegrator(old.replace('version="4"', f'version="{version}"'))
        assert type(integrator) is RigidBodyBussiIntegrator
        assert integrator.getTemperature() == 280 * unit.kelvin
        assert integrator.getCollisionTime() == 0.25 * unit.picosecond
        assert integrator.getRandomNumberSeed() == 99 and integrator.getSplitting() == RigidBodyIntegrator.Omelyan2
        assert integrator.getMeasureShadowWork()  # the heat was measured: one switch measures both now
        expected = thermostatted(0.002, 280.0, 0.25, [[0, 1, 2], [4, 5]], seed=99)
        expected.setSplitting(RigidBodyIntegrator.Omelyan2)
        expected.setMeasureShadowWork(True)
        assert openmm.XmlSerializer.serialize(integrator) == openmm.XmlSerializer.serialize(expected)
    # openmm's own deserializer makes the same integrator, as an openmm.Integrator.
    assert 'type="RigidBodyBussiIntegrator"' in openmm.XmlSerializer.serialize(openmm.XmlSerializer.deserialize(old))
    plain = openmmrigid.deserializeIntegrator(old.replace('thermostat="1"', 'thermostat="0"'))
    assert type(plain) is RigidBodyIntegrator and not hasattr(plain, "getTemperature")


@pytest.mark.parametrize("platformName", ["Reference", "CPU"])
def test_simulation_checkpoint_keeps_the_work(platformName):
    integrator = thermostatted(0.001, 200.0, 0.05, EXPLICIT_BODIES, seed=8)
    integrator.setMeasureShadowWork(True)  # the heat of a Bussi integrator is its thermostat's work
    simulation = app.Simulation(topology_for(len(MASSES)), trapped_system(), integrator, platform(platformName))
    simulation.context.setPositions(POSITIONS)
    simulation.context.setVelocitiesToTemperature(300, 3)
    simulation.step(20)
    checkpoint = io.BytesIO()
    simulation.saveCheckpoint(checkpoint)
    work = integrator.getHeat()
    simulation.step(20)
    expected, expectedWork = systems.positions_of(simulation.context), integrator.getHeat()
    assert expectedWork != work
    checkpoint.seek(0)
    simulation.loadCheckpoint(checkpoint)
    assert integrator.getHeat() == work
    simulation.step(20)
    assert np.abs(systems.positions_of(simulation.context) - expected).max() < 1e-10
    assert integrator.getHeat().value_in_unit(unit.kilojoule_per_mole) == pytest.approx(
        expectedWork.value_in_unit(unit.kilojoule_per_mole), abs=1e-9)

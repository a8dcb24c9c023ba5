"""Tests of RigidBodyIntegrator's thermostat (stochastic velocity rescaling of Bussi, Donadio and
Parrinello, J. Chem. Phys. 126, 014101 (2007)) from Python; the C++ tests
(TestRigidBodyThermostats.h) check eq. (A7) itself, exact damping, the effective energy to second
order, seeds, threads and checkpoints on both platforms.

- a small box of rigid TIP3P water reaches the bath temperature in translation and in rotation,
  each within 4.5 block standard errors;
- the total kinetic energy of free rigid bodies follows the canonical Gamma distribution
  (Kolmogorov-Smirnov);
- the settings: units, errors, removal, copies (pickle, copy, XmlSerializer; the XML format and its
  versions are tested in C++, TestSerialization.cpp), and the work kept by Simulation checkpoints.
"""

import io

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest
from scipy import stats

import systems
from systems import COPY_METHODS, copy_integrator
from openmmrigid import RigidBodyIntegrator
from test_integrator_api import EXPLICIT_BODIES, MASSES, POSITIONS, platform, topology_for, trapped_system
from test_langevin import BOLTZMANN, assert_water_temperatures, small_water_box  # noqa: F401 (small_water_box is a fixture)


def thermostatted(stepSize, temperature=300.0, collisionTime=0.1, bodies=None, seed=1):
    integrator = RigidBodyIntegrator(stepSize, bodies) if bodies is not None else RigidBodyIntegrator(stepSize)
    integrator.setThermostat(temperature, collisionTime)
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
    assert_water_temperatures(integrator, target, samples=6000, every=4, blocks=12, label="thermostat, ")


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
    dof = integrator.getNumDegreesOfFreedom()
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
    integrator = RigidBodyIntegrator(0.002)
    assert not integrator.hasThermostat() and integrator.getRandomNumberSeed() == 0
    assert integrator.getThermostatTemperature() == 0 * unit.kelvin
    integrator.setThermostat(310 * unit.kelvin, 50 * unit.femtoseconds)
    assert integrator.hasThermostat()
    assert integrator.getThermostatTemperature() == 310 * unit.kelvin
    assert integrator.getThermostatCollisionTime().value_in_unit(unit.picosecond) == pytest.approx(0.05)
    integrator.setThermostat(0, 1.0)
    assert integrator.getThermostatTemperature() == 0 * unit.kelvin
    assert integrator.getThermostatCollisionTime() == 1.0 * unit.picosecond
    for temperature, collisionTime in ((-1, 0.1), (float("nan"), 0.1), (300, 0), (300, -1), (300, float("inf"))):
        with pytest.raises(openmm.OpenMMException, match="collision time"):
            integrator.setThermostat(temperature, collisionTime)
    assert integrator.getThermostatTemperature() == 0 * unit.kelvin
    with pytest.raises(TypeError):
        integrator.setThermostat(300 * unit.kelvin, 1 / unit.picosecond)  # a rate, not a time
    integrator.removeThermostat()
    assert not integrator.hasThermostat()
    with pytest.raises(openmm.OpenMMException, match="bound to a Context"):
        integrator.getThermostatWork()
    for name in ("setThermostat", "removeThermostat", "hasThermostat", "getThermostatWork"):
        assert getattr(RigidBodyIntegrator, name).__doc__
    assert "Bussi" in RigidBodyIntegrator.setThermostat.__doc__


@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_the_thermostat(method):
    original = thermostatted(0.002, 280.0, 0.25, EXPLICIT_BODIES, seed=99)
    duplicate = copy_integrator(original, method)
    assert type(duplicate) is RigidBodyIntegrator
    assert duplicate.hasThermostat() and duplicate.getRandomNumberSeed() == 99
    assert duplicate.getThermostatTemperature() == 280 * unit.kelvin
    assert duplicate.getThermostatCollisionTime() == 0.25 * unit.picosecond
    assert duplicate.getExplicitBodies() == EXPLICIT_BODIES


@pytest.mark.parametrize("platformName", ["Reference", "CPU"])
def test_simulation_checkpoint_keeps_the_work(platformName):
    integrator = thermostatted(0.001, 200.0, 0.05, EXPLICIT_BODIES, seed=8)
    simulation = app.Simulation(topology_for(len(MASSES)), trapped_system(), integrator, platform(platformName))
    simulation.context.setPositions(POSITIONS)
    simulation.context.setVelocitiesToTemperature(300, 3)
    simulation.step(20)
    checkpoint = io.BytesIO()
    simulation.saveCheckpoint(checkpoint)
    work = integrator.getThermostatWork()
    simulation.step(20)
    expected, expectedWork = systems.positions_of(simulation.context), integrator.getThermostatWork()
    assert expectedWork != work
    checkpoint.seek(0)
    simulation.loadCheckpoint(checkpoint)
    assert integrator.getThermostatWork() == work
    simulation.step(20)
    assert np.abs(systems.positions_of(simulation.context) - expected).max() < 1e-10
    assert integrator.getThermostatWork().value_in_unit(unit.kilojoule_per_mole) == pytest.approx(
        expectedWork.value_in_unit(unit.kilojoule_per_mole), abs=1e-9)

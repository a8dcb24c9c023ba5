"""The integrators in openmmtools, as its users run them (skipped where openmmtools is absent; CI
installs it with the test extras).

- ThermodynamicState with each integrator: RigidBodyLangevinIntegrator, RigidBodyBussiIntegrator
  and a CompoundIntegrator holding either are seen as thermostated (no AndersenThermostat added, the
  state's temperature set on our integrator, a wrong one refused); RigidBodyIntegrator is NVE to
  openmmtools (it has no getTemperature attribute at all), so it gets an AndersenThermostat whose
  temperature follows the state;
- our classes come back from CompoundIntegrator.getIntegrator (the one method of openmm that
  openmmrigid wraps, for openmmtools' sake) and Context.getIntegrator;
- the moves of openmmrigid.openmmtools: a ContextCache reuses one Context across temperatures and
  copies the temperature into its integrator; the moves survive pickle and openmmtools'
  serialization; a few ParallelTemperingSampler iterations run and their NetCDF storage reads back
  (moves, states, rigid waters).

The AndersenThermostat openmmtools adds, and explicit bodies with internal constraints from ordinary
positions, are tested in test_andersen_and_internal_constraints.py (they need no openmmtools).
"""

import copy
import pickle

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest

import openmmrigid

openmmtools = pytest.importorskip("openmmtools")
from openmmtools import cache, multistate, states, utils  # noqa: E402

from openmmrigid.openmmtools import RigidBussiDynamicsMove, RigidLangevinDynamicsMove  # noqa: E402

REFERENCE = openmm.Platform.getPlatformByName("Reference")
T300, T350 = 300.0 * unit.kelvin, 350.0 * unit.kelvin
OH_DISTANCE = 0.09572  # TIP3P, nm


@pytest.fixture(scope="module")
def water():
    """27 rigid TIP3P waters in a 1 nm box, reaction field with a 0.45 nm cutoff, minimised:
    (system, positions as an array in nm, box vectors)."""
    forcefield = app.ForceField("amber14/tip3p.xml")
    modeller = app.Modeller(app.Topology(), [])
    modeller.addSolvent(forcefield, model="tip3p", boxSize=openmm.Vec3(1.0, 1.0, 1.0) * unit.nanometer)
    system = forcefield.createSystem(modeller.topology, nonbondedMethod=app.CutoffPeriodic,
                                     nonbondedCutoff=0.45 * unit.nanometer, rigidWater=True)
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), REFERENCE)
    context.setPositions(modeller.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 200)
    state = context.getState(getPositions=True)
    return system, state.getPositions(asNumpy=True).value_in_unit(unit.nanometer), state.getPeriodicBoxVectors()


def andersen_thermostats(system):
    return [force for force in system.getForces() if isinstance(force, openmm.AndersenThermostat)]


def rigid_langevin(temperature):
    return openmmrigid.RigidBodyLangevinIntegrator(temperature, 1.0 / unit.picosecond, 2.0 * unit.femtosecond)


def rigid_bussi(temperature):
    return openmmrigid.RigidBodyBussiIntegrator(temperature, 0.1 * unit.picosecond, 2.0 * unit.femtosecond)


def compound_of(make):
    def factory(temperature):
        compound = openmm.CompoundIntegrator()
        compound.addIntegrator(make(temperature))
        compound.addIntegrator(openmm.VerletIntegrator(1.0 * unit.femtosecond))
        return compound
    return factory


THERMOSTATED = {"RigidBodyLangevinIntegrator": rigid_langevin, "RigidBodyBussiIntegrator": rigid_bussi,
                "Compound[RigidBodyLangevinIntegrator, Verlet]": compound_of(rigid_langevin),
                "Compound[RigidBodyBussiIntegrator, Verlet]": compound_of(rigid_bussi)}


def rigid_member(integrator):
    """The rigid-body integrator itself, or the first of a CompoundIntegrator."""
    return integrator.getIntegrator(0) if isinstance(integrator, openmm.CompoundIntegrator) else integrator


@pytest.mark.parametrize("name", list(THERMOSTATED))
def test_thermostated_integrators_follow_the_state(water, name):
    """openmmtools sees our heat bath: no AndersenThermostat in the Context's System, each state's
    temperature set on our integrator, and an integrator at another temperature refused."""
    system, positions, box = water
    make = THERMOSTATED[name]
    cold, hot = states.ThermodynamicState(system, T300), states.ThermodynamicState(system, T350)
    context = cold.create_context(make(T300), REFERENCE)
    assert andersen_thermostats(context.getSystem()) == []
    integrator = context.getIntegrator()
    assert type(rigid_member(integrator)).__name__ in name
    assert rigid_member(integrator).getTemperature() == T300
    hot.apply_to_context(context)
    assert rigid_member(integrator).getTemperature() == T350
    assert hot.is_context_compatible(context)
    context.setPositions(positions)
    context.setVelocitiesToTemperature(T350, 1)
    integrator.step(3)
    assert np.isfinite(context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole))
    with pytest.raises(states.ThermodynamicsError):
        cold.create_context(make(T350), REFERENCE)


def test_nve_integrator_is_not_thermostated(water):
    """RigidBodyIntegrator has no temperature (no getTemperature or setTemperature attribute at all),
    so openmmtools gives its System an AndersenThermostat and sets that to each state's temperature;
    bodies found from constraints are whole clusters, which the Andersen thermostat redraws whole."""
    system, positions, box = water
    integrator = openmmrigid.RigidBodyIntegrator(2.0 * unit.femtosecond)
    assert not hasattr(integrator, "getTemperature") and not hasattr(integrator, "setTemperature")
    with pytest.raises(AttributeError):
        integrator.getTemperature()
    context = states.ThermodynamicState(system, T300).create_context(integrator, REFERENCE)
    thermostats = andersen_thermostats(context.getSystem())
    assert len(thermostats) == 1
    states.ThermodynamicState(system, T350).apply_to_context(context)
    assert context.getParameter(openmm.AndersenThermostat.Temperature()) == pytest.approx(350.0)
    # The thermostat is a class of its own: RigidBodyBussiIntegrator has the temperature (Quantities).
    other = rigid_bussi(T300)
    assert isinstance(other, openmmrigid.RigidBodyIntegrator)
    other.setTemperature(320.0 * unit.kelvin)
    assert other.getTemperature() == 320.0 * unit.kelvin
    assert other.getCollisionTime() == 0.1 * unit.picosecond


def test_compound_and_context_return_our_classes(water):
    """CompoundIntegrator.getIntegrator gives back a RigidBodyLangevinIntegrator or RigidBodyBussiIntegrator
    (the same C++ object: a setting made through it is the compound's), stock members unchanged;
    Context.getIntegrator gives back the integrator the Context was made with."""
    system, positions, box = water
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(rigid_langevin(T300))
    compound.addIntegrator(rigid_bussi(T300))
    compound.addIntegrator(openmm.LangevinMiddleIntegrator(T300, 1.0, 0.001))
    first, second, third = (compound.getIntegrator(i) for i in range(3))
    assert type(first) is openmmrigid.RigidBodyLangevinIntegrator
    assert type(second) is openmmrigid.RigidBodyBussiIntegrator
    assert type(third) is openmm.LangevinMiddleIntegrator
    first.setTemperature(310.0)
    second.setTemperature(320.0)
    assert compound.getIntegrator(0).getTemperature() == 310.0 * unit.kelvin
    assert compound.getIntegrator(1).getTemperature() == 320.0 * unit.kelvin
    assert compound.getIntegrator(1).getCollisionTime() == 0.1 * unit.picosecond
    context = openmm.Context(system, compound, REFERENCE)
    assert context.getIntegrator() is compound
    assert type(context.getIntegrator().getIntegrator(1)) is openmmrigid.RigidBodyBussiIntegrator
    rigid = rigid_langevin(T300)
    assert openmm.Context(system, rigid, REFERENCE).getIntegrator() is rigid
    bussi = rigid_bussi(T300)
    assert openmm.Context(system, bussi, REFERENCE).getIntegrator() is bussi


def test_context_cache_reuses_one_context_across_temperatures(water):
    """Each move applied at two temperatures through one ContextCache: one Context per integrator
    class, whose integrator (a copy the cache made) has the last state's temperature; the thermostat's
    collision time and the move's bodies survive the copy."""
    system, positions, box = water
    contexts = cache.ContextCache(platform=REFERENCE)
    sampler_state = states.SamplerState(positions * unit.nanometer, box_vectors=box)
    cold, hot = states.ThermodynamicState(system, T300), states.ThermodynamicState(system, T350)
    moves = [RigidLangevinDynamicsMove(n_steps=5), RigidBussiDynamicsMove(n_steps=5, collision_time=0.2 * unit.picosecond)]
    for count, move in enumerate(moves, start=1):
        move.apply(cold, sampler_state, context_cache=contexts)
        move.apply(hot, sampler_state, context_cache=contexts)
        assert len(contexts) == count
        context, integrator = contexts.get_context(hot, move._get_integrator(hot))
        assert type(integrator) is type(move._get_integrator(hot))
        assert integrator.getTemperature() == T350
        assert andersen_thermostats(context.getSystem()) == []
    assert type(integrator) is openmmrigid.RigidBodyBussiIntegrator
    assert integrator.getCollisionTime() == 0.2 * unit.picosecond
    assert np.all(np.isfinite(sampler_state.positions.value_in_unit(unit.nanometer)))


@pytest.mark.parametrize("move", [RigidLangevinDynamicsMove(timestep=1.5 * unit.femtosecond, n_steps=7, bodies=[[0, 1, 2]],
                                                            rotation_method="NoSquish", reassign_velocities=True),
                                  RigidBussiDynamicsMove(n_steps=3, splitting="Omelyan2")],
                         ids=["Langevin", "Bussi"])
def test_moves_copy_and_serialize(move):
    """pickle, deepcopy and openmmtools' serialization (what its storage writes) give the same settings,
    and the integrator the copy makes is configured alike."""
    thermodynamic = states.ThermodynamicState(openmm.System(), T300)
    for duplicate in (pickle.loads(pickle.dumps(move)), copy.deepcopy(move), utils.deserialize(utils.serialize(move))):
        assert type(duplicate) is type(move) and duplicate.__getstate__() == move.__getstate__()
        original, copied = move._get_integrator(thermodynamic), duplicate._get_integrator(thermodynamic)
        assert openmm.XmlSerializer.serialize(copied) == openmm.XmlSerializer.serialize(original)


def test_moves_refuse_bad_settings():
    with pytest.raises(ValueError, match="RigidLangevinDynamicsMove: the timestep must be positive"):
        RigidLangevinDynamicsMove(timestep=0.0)
    with pytest.raises(ValueError, match="RigidBussiDynamicsMove: unknown splitting 'Leapfrog'"):
        RigidBussiDynamicsMove(splitting="Leapfrog")
    with pytest.raises(ValueError, match="body 0 must list particle indices"):
        RigidLangevinDynamicsMove(bodies=[[0, 1.5]])


def test_parallel_tempering_runs_and_its_storage_reads_back(water, tmp_path):
    """Three replicas from 300 to 360 K (geometric) with the Langevin move, three iterations on Reference, in a
    NetCDF file; read back: the move (our class and settings), the temperatures, finite energies, and
    positions whose waters are still rigid."""
    system, positions, box = water
    move = RigidLangevinDynamicsMove(n_steps=10)
    sampler = multistate.ParallelTemperingSampler(mcmc_moves=move, number_of_iterations=3)
    sampler.energy_context_cache = cache.ContextCache(platform=REFERENCE)
    sampler.sampler_context_cache = cache.ContextCache(platform=REFERENCE)
    path = str(tmp_path / "tempering.nc")
    reporter = multistate.MultiStateReporter(path, checkpoint_interval=1)
    sampler.create(states.ThermodynamicState(system, T300), states.SamplerState(positions * unit.nanometer, box_vectors=box),
                   reporter, min_temperature=T300, max_temperature=360.0 * unit.kelvin, n_temperatures=3)
    sampler.run()
    reporter.close()

    reporter = multistate.MultiStateReporter(path, open_mode="r")
    try:
        stored_states, _ = reporter.read_thermodynamic_states()
        expected = 300.0 * (360.0 / 300.0) ** (np.arange(3) / 2)
        assert np.allclose([state.temperature.value_in_unit(unit.kelvin) for state in stored_states], expected, rtol=1e-12)
        stored_moves = reporter.read_mcmc_moves()
        assert len(stored_moves) == 3
        for stored in stored_moves:
            assert type(stored) is RigidLangevinDynamicsMove and stored.__getstate__() == move.__getstate__()
        assert reporter.read_last_iteration() == 3
        energies, _, _ = reporter.read_energies(iteration=3)
        assert energies.shape == (3, 3) and np.all(np.isfinite(energies))
        for sampler_state in reporter.read_sampler_states(iteration=3):
            x = sampler_state.positions.value_in_unit(unit.nanometer)
            # Wrapped into the box molecule by molecule (enforcePeriodicBox keeps each water whole).
            oxygen, hydrogens = x[0::3], (x[1::3], x[2::3])
            for h in hydrogens:
                assert np.max(np.abs(np.linalg.norm(h - oxygen, axis=1) - OH_DISTANCE)) < 1e-6
    finally:
        reporter.close()

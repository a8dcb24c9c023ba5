"""Tests of the Python surface of openmmrigid's integrators (the physics is tested elsewhere):

- the public methods of each class, exactly (the lean API of issue 41);
- construction from floats and openmm.unit Quantities, bodies from lists, tuples, ranges and numpy
  arrays, and bad input raising openmm.OpenMMException with a message naming the body or entry;
- the rotation method, RigidBodyBussiIntegrator's heat bath, and the settings inherited from
  openmm.Integrator;
- pickle, copy.copy, copy.deepcopy and openmmrigid.deserializeIntegrator keep every setting and the
  class (RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator, explicit bodies
  included); openmm.XmlSerializer.deserialize and clone (not patched) give an openmm.Integrator that
  serializes the same and runs bit for bit as the original on Reference; CompoundIntegrator.getIntegrator
  (the one method of openmm the package wraps) gives back our class; the
  XML reads with defaults (older files, a version-3 RigidBodyIntegrator with a thermostat becoming a
  RigidBodyBussiIntegrator) and refuses newer versions;
- the integrator in openmm.Context and openmm.app.Simulation on the Reference and CPU platforms:
  bodies, degrees of freedom and temperature against what the State gives (rigidtesting.bodies),
  saveState/loadState, checkpoints, CheckpointReporter;
- the temperature that RigidStateDataReporter (and openmm.app.StateDataReporter, through
  computeSystemTemperature) report for explicit bodies, against 2 KE / (dof k_B) computed here.
"""

import copy
import io
import os
import xml.etree.ElementTree as ElementTree

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest

import openmmrigid
from openmmrigid import (RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyIntegratorBase,
                         RigidBodyLangevinIntegrator, RigidStateDataReporter)
from rigidtesting.bodies import bodyKind, principalMoments, rigidDegreesOfFreedom, rigidKineticEnergies
from systems import COPY_METHODS, copy_integrator

PLATFORMS = ["Reference", "CPU"]
GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)
CLASSES = [RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator]


def make(cls, stepSize, *bodies):
    """An integrator of cls (the thermostatted ones at 300 K, 0.1 ps and 1/ps) with the step size and, if
    given, explicit bodies."""
    leading = {RigidBodyIntegrator: (), RigidBodyBussiIntegrator: (300.0, 0.1),
               RigidBodyLangevinIntegrator: (300.0, 1.0)}[cls]
    return cls(*leading, stepSize, *bodies)


def serialized_bodies(integrator):
    """The explicit bodies the integrator's XML holds (None: found from the System's constraints)."""
    root = ElementTree.fromstring(openmm.XmlSerializer.serialize(integrator))
    if root.get("explicitBodies") != "1":
        assert root.find("Bodies") is None
        return None
    return [[int(particle.get("index")) for particle in body.iter("Particle")] for body in root.iter("Body")]


def settings(integrator):
    """Every setting a copy must keep: the common ones, and those of the integrator's own class."""
    common = [integrator.getStepSize(), integrator.getConstraintTolerance(), integrator.getIntegrationForceGroups(),
              integrator.getRotationMethod(), integrator.getMinimumMomentOfInertia(), integrator.getForceGroupSubsteps(),
              integrator.getMeasureShadowWork(), integrator.getAccuracyCheck(), serialized_bodies(integrator)]
    own = [getattr(integrator, name)() for name in ("getSplitting", "getTemperature", "getCollisionTime", "getFriction",
                                                    "getRandomNumberSeed") if hasattr(integrator, name)]
    return tuple(common + own)


def configured(bodies, cls=RigidBodyIntegrator):
    """An integrator with every setting away from its default."""
    integrator = make(cls, 0.0015, *([bodies] if bodies is not None else []))
    integrator.setConstraintTolerance(3e-7)
    integrator.setIntegrationForceGroups({0, 2, 5})
    integrator.setRotationMethod(RigidBodyIntegrator.NoSquish)
    integrator.setMinimumMomentOfInertia(0.0125)
    integrator.setMeasureShadowWork(True)
    integrator.setAccuracyCheck(False)
    if isinstance(integrator, RigidBodyIntegrator):
        integrator.setSplitting(RigidBodyIntegrator.Yoshida4)
    if isinstance(integrator, RigidBodyBussiIntegrator):
        integrator.setTemperature(310.0)
        integrator.setCollisionTime(0.25)
    if isinstance(integrator, RigidBodyLangevinIntegrator):
        integrator.setTemperature(290.0)
        integrator.setFriction(2.5)
    if hasattr(integrator, "setRandomNumberSeed"):
        integrator.setRandomNumberSeed(4242)
    return integrator


# A body of each kind, two free particles, in a harmonic trap (so that the bodies feel torques).
#   particles 0-3: asymmetric top; 4-5: linear; 6: single-particle body; 7-9: asymmetric top;
#   10, 11: free particles.
EXPLICIT_BODIES = [[0, 1, 2, 3], [4, 5], [6], [7, 8, 9]]
MASSES = [12.0, 1.0, 16.0, 14.0, 12.0, 16.0, 40.0, 16.0, 1.0, 1.0, 23.0, 35.5]
POSITIONS = np.array([
    [0.00, 0.00, 0.00], [0.11, 0.00, 0.00], [-0.03, 0.12, 0.01], [0.02, 0.03, 0.13],
    [0.60, 0.00, 0.00], [0.72, 0.00, 0.00],
    [0.00, 0.70, 0.00],
    [0.00, 0.00, 0.70], [0.09, 0.03, 0.72], [-0.03, 0.09, 0.69],
    [0.50, 0.50, 0.00], [-0.50, 0.00, 0.50]])
# 3 + 3 rotational (asymmetric), 3 + 2 (linear), 3 (point), 3 + 3 (asymmetric), 3 per free particle.
EXPLICIT_DOF = 6 + 5 + 3 + 6 + 3 + 3


def trapped_system(cmMotionRemover=False):
    system = openmm.System()
    for mass in MASSES:
        system.addParticle(mass)
    trap = openmm.CustomExternalForce("0.5*k*((x-0.2)^2 + 2*(y-0.1)^2 + 3*z^2)")
    trap.addGlobalParameter("k", 500.0)
    for i in range(len(MASSES)):
        trap.addParticle(i, [])
    system.addForce(trap)
    if cmMotionRemover:
        system.addForce(openmm.CMMotionRemover())
    return system


def topology_for(numParticles):
    topology = app.Topology()
    residue = topology.addResidue("MOL", topology.addChain())
    for i in range(numParticles):
        topology.addAtom(f"C{i}", app.element.carbon, residue)
    return topology


def platform(name):
    try:
        return openmm.Platform.getPlatformByName(name)
    except openmm.OpenMMException:
        pytest.skip(f"the {name} platform is not available")


def explicit_context(platformName, integrator=None):
    integrator = RigidBodyIntegrator(0.001, EXPLICIT_BODIES) if integrator is None else integrator
    context = openmm.Context(trapped_system(), integrator, platform(platformName))
    context.setPositions(POSITIONS)
    context.setVelocitiesToTemperature(300, 1)
    return context, integrator


def kinetic_energy_by_hand(state, masses):
    velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    return 0.5 * float(np.sum(np.asarray(masses)[:, None] * velocities**2))


# ------------------------------------------------------------------------------------------------
# The public surface
# ------------------------------------------------------------------------------------------------

BASE_METHODS = {"getRotationMethod", "setRotationMethod", "getMinimumMomentOfInertia", "setMinimumMomentOfInertia",
                "getForceGroupSubsteps", "setForceGroupSubsteps", "getNumBodies", "getBodyParticles",
                "computeSystemTemperature", "getMeasureShadowWork", "setMeasureShadowWork", "getShadowWork", "getHeat",
                "getAccuracyCheck", "setAccuracyCheck"}
BASE_CONSTANTS = {"Exact", "NoSquish", "MaximumMinimumMoment"}
SPLITTINGS = {"Verlet", "Omelyan2", "Yoshida4", "Omelyan4"}
PUBLIC_SURFACE = {
    RigidBodyIntegratorBase: BASE_METHODS | BASE_CONSTANTS,
    RigidBodyIntegrator: BASE_METHODS | BASE_CONSTANTS | {"getSplitting", "setSplitting"} | SPLITTINGS,
    RigidBodyBussiIntegrator: BASE_METHODS | BASE_CONSTANTS | {"getSplitting", "setSplitting"} | SPLITTINGS
    | {"getTemperature", "setTemperature", "getCollisionTime", "setCollisionTime", "getRandomNumberSeed",
       "setRandomNumberSeed"},
    RigidBodyLangevinIntegrator: BASE_METHODS | BASE_CONSTANTS
    | {"getTemperature", "setTemperature", "getFriction", "setFriction", "getRandomNumberSeed", "setRandomNumberSeed",
       "getOnStepKineticEnergy"},
}
REMOVED = ["setThermostat", "removeThermostat", "hasThermostat", "getThermostatTemperature", "getThermostatCollisionTime",
           "getThermostatWork", "setMeasureHeat", "getMeasureHeat", "getShadowWorkInKT", "getHeatInKT", "resetShadowWork",
           "resetHeat", "getAccuracyWarning", "getBodyKind", "getBodyMoments", "getBodyMassMoments",
           "getTranslationalKineticEnergy", "getRotationalKineticEnergy", "getNumDegreesOfFreedom",
           "getNumForceEvaluations", "hasExplicitBodies", "getExplicitBodies", "getClassName", "getVelocityTimeOffset"]


@pytest.mark.parametrize("cls", PUBLIC_SURFACE, ids=lambda cls: cls.__name__)
def test_public_surface_is_exactly_the_lean_api(cls):
    """What each class adds to openmm.Integrator, exactly: nothing removed by issue 41 is left, and
    nothing new appears without this list being updated."""
    public = {name for name in dir(cls) if not name.startswith("_") and name != "thisown"}
    added = public - {name for name in dir(openmm.Integrator) if not name.startswith("_")}
    assert added == PUBLIC_SURFACE[cls], (sorted(added - PUBLIC_SURFACE[cls]), sorted(PUBLIC_SURFACE[cls] - added))
    for name in REMOVED:
        assert not hasattr(cls, name), name


def test_class_hierarchy():
    assert issubclass(RigidBodyBussiIntegrator, RigidBodyIntegrator)
    for cls in CLASSES:
        assert issubclass(cls, RigidBodyIntegratorBase) and issubclass(cls, openmm.Integrator)
    assert not issubclass(RigidBodyLangevinIntegrator, RigidBodyIntegrator)
    # openmmtools asks an integrator for getTemperature(): the constant-energy one has none.
    assert not hasattr(RigidBodyIntegrator(0.001), "getTemperature")
    assert not hasattr(openmmrigid, "NoThermostatError")
    assert not hasattr(openmmrigid, "testing")


# ------------------------------------------------------------------------------------------------
# Construction and settings
# ------------------------------------------------------------------------------------------------

def test_is_an_openmm_integrator():
    for cls in CLASSES:
        integrator = make(cls, 0.002)
        assert isinstance(integrator, openmm.Integrator)
        assert getattr(openmmrigid, cls.__name__) is cls
    for name in ("RigidBodyIntegrator", "RigidBodyBussiIntegrator", "RigidBodyLangevinIntegrator", "AccuracyWarning",
                 "deserializeIntegrator", "RigidStateDataReporter", "FreeRotor", "special"):
        assert name in openmmrigid.__all__ and hasattr(openmmrigid, name)


@pytest.mark.parametrize("stepSize, expected", [
    (0.002, 0.002),
    (2 * unit.femtoseconds, 0.002),
    (0.5 * unit.picosecond, 0.5),
    (np.float64(0.001), 0.001),
    (1, 1.0),
])
def test_step_size_float_or_quantity(stepSize, expected):
    for cls in CLASSES:
        for integrator in (make(cls, stepSize), make(cls, stepSize, [[0, 1, 2]])):
            value = integrator.getStepSize()
            assert unit.is_quantity(value)
            assert value.value_in_unit(unit.picosecond) == pytest.approx(expected, rel=1e-15)
        integrator.setStepSize(3 * unit.femtoseconds)
        assert integrator.getStepSize().value_in_unit(unit.picosecond) == pytest.approx(0.003, rel=1e-15)


def test_step_size_of_wrong_kind():
    with pytest.raises(TypeError):
        RigidBodyIntegrator(2 * unit.nanometer)
    with pytest.raises(TypeError):
        RigidBodyIntegrator("0.002")
    with pytest.raises(TypeError):
        RigidBodyBussiIntegrator(300.0, 0.1, 2 * unit.nanometer)


def test_bussi_heat_bath():
    """RigidBodyBussiIntegrator(temperature, collisionTime, stepSize[, bodies]): floats or Quantities,
    the getters return Quantities, and a bad bath is refused naming the class, keeping the old value."""
    integrator = RigidBodyBussiIntegrator(300 * unit.kelvin, 100 * unit.femtoseconds, 2 * unit.femtoseconds, [[0, 1, 2]])
    assert integrator.getTemperature() == 300 * unit.kelvin
    assert integrator.getCollisionTime().value_in_unit(unit.picosecond) == pytest.approx(0.1, rel=1e-15)
    assert integrator.getStepSize().value_in_unit(unit.picosecond) == pytest.approx(0.002, rel=1e-15)
    assert integrator.getNumBodies() == 1
    assert integrator.getRandomNumberSeed() == 0 and integrator.getSplitting() == RigidBodyIntegrator.Verlet
    integrator.setTemperature(310.0)
    integrator.setCollisionTime(0.5 * unit.picoseconds)
    integrator.setRandomNumberSeed(17)
    integrator.setSplitting(RigidBodyIntegrator.Omelyan2)
    assert (integrator.getTemperature(), integrator.getCollisionTime()) == (310 * unit.kelvin, 0.5 * unit.picoseconds)
    assert (integrator.getRandomNumberSeed(), integrator.getSplitting()) == (17, RigidBodyIntegrator.Omelyan2)
    integrator.setTemperature(0.0)  # allowed: damps the motion
    assert integrator.getTemperature() == 0 * unit.kelvin
    for bad in (-1.0, float("nan"), float("inf")):
        with pytest.raises(openmm.OpenMMException, match="RigidBodyBussiIntegrator: the temperature"):
            integrator.setTemperature(bad)
        with pytest.raises(openmm.OpenMMException, match="RigidBodyBussiIntegrator: the temperature"):
            RigidBodyBussiIntegrator(bad, 0.1, 0.002)
    for bad in (0.0, -0.1, float("nan"), float("inf")):
        with pytest.raises(openmm.OpenMMException, match="RigidBodyBussiIntegrator"):
            integrator.setCollisionTime(bad)
        with pytest.raises(openmm.OpenMMException, match="RigidBodyBussiIntegrator"):
            RigidBodyBussiIntegrator(300.0, bad, 0.002)
    assert (integrator.getTemperature(), integrator.getCollisionTime()) == (0 * unit.kelvin, 0.5 * unit.picoseconds)


@pytest.mark.parametrize("bodies", [
    [[0, 1, 2], [3, 4, 5]],
    ((0, 1, 2), (3, 4, 5)),
    [range(3), range(3, 6)],
    np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int32),
    np.array([[0, 1, 2], [3, 4, 5]], dtype=np.int64),
    np.array([[0, 1, 2], [3, 4, 5]], dtype=np.uint16),
    [np.arange(3), [np.int64(3), np.int32(4), 5]],
])
def test_bodies_from_any_integer_sequences(bodies):
    for cls in CLASSES:
        integrator = make(cls, 0.001, bodies)
        assert integrator.getNumBodies() == 2  # explicit bodies are counted before a Context exists
        assert serialized_bodies(integrator) == [[0, 1, 2], [3, 4, 5]]
        context = openmm.Context(trapped_system(), integrator, platform("Reference"))
        context.setPositions(POSITIONS)
        particles = [integrator.getBodyParticles(b) for b in range(integrator.getNumBodies())]
        assert particles == [[0, 1, 2], [3, 4, 5]]
        assert all(type(i) is int for body in particles for i in body)


def test_bodies_ragged_and_empty():
    ragged = RigidBodyIntegrator(0.001, [[0], [1, 2], [3, 4, 5, 6]])
    assert ragged.getNumBodies() == 3 and serialized_bodies(ragged) == [[0], [1, 2], [3, 4, 5, 6]]
    none = RigidBodyIntegrator(0.001, [])  # explicit: every particle free
    assert none.getNumBodies() == 0 and serialized_bodies(none) == []
    found = RigidBodyIntegrator(0.001)  # the System's constraint clusters
    assert serialized_bodies(found) is None
    with pytest.raises(openmm.OpenMMException, match="once the integrator is bound"):
        found.getNumBodies()


@pytest.mark.parametrize("bodies, words", [
    ([[0, -1, 2]], ["body 0", "-1"]),
    ([[0, 1], [2, -5]], ["body 1", "-5"]),
    ([[0, 1.0, 2]], ["body 0", "entry 1", "1.0"]),
    ([[0, 1], [2, np.float64(3)]], ["body 1", "entry 1"]),
    ([[0, "1"]], ["body 0", "entry 1"]),
    ([[0, None]], ["body 0", "entry 1"]),
    ([[[0, 1]]], ["body 0", "entry 0"]),
    ([[0, 2**40]], ["body 0", "entry 1"]),
    ([0, 1, 2], ["body 0"]),
    (["012"], ["body 0"]),
    ("012", ["bodies"]),
    (np.array([[0.0, 1.0, 2.0]]), ["body 0", "entry 0"]),
    (5, ["bodies"]),
    (None, ["bodies"]),
])
def test_bad_bodies(bodies, words):
    for cls in CLASSES:
        with pytest.raises(openmm.OpenMMException) as error:
            make(cls, 0.001, bodies)
        for word in words:
            assert word in str(error.value)


def test_bad_bodies_found_with_the_system():
    system = trapped_system()
    for bodies, word in (([[0, 1, 99]], "99"), ([[0, 1, 2], [2, 3, 4]], "2")):
        for cls in CLASSES:
            with pytest.raises(openmm.OpenMMException, match=word):
                openmm.Context(system, make(cls, 0.001, bodies), platform("Reference"))


@pytest.mark.parametrize("integratorClass", CLASSES)
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")], ids=str)
def test_non_finite_step_size_is_a_bad_argument(integratorClass, bad):
    """A step size that is not a number is refused where it is given, naming the class, not reported
    later as an unstable simulation; the integrator keeps its step."""
    with pytest.raises(openmm.OpenMMException, match=f"{integratorClass.__name__}: the step size is .*finite"):
        make(integratorClass, bad)
    integrator = make(integratorClass, 0.002)
    with pytest.raises(openmm.OpenMMException, match=f"{integratorClass.__name__}: the step size is .*finite"):
        integrator.setStepSize(bad)
    with pytest.raises(openmm.OpenMMException, match=f"{integratorClass.__name__}: the step size"):
        integrator.setStepSize(bad * unit.femtoseconds)
    assert integrator.getStepSize() == 0.002 * unit.picoseconds


def test_rotation_method():
    integrator = RigidBodyIntegrator(0.001)
    assert (RigidBodyIntegrator.Exact, RigidBodyIntegrator.NoSquish) == (0, 1)
    assert integrator.getRotationMethod() == RigidBodyIntegrator.Exact
    integrator.setRotationMethod(RigidBodyIntegrator.NoSquish)
    assert integrator.getRotationMethod() == RigidBodyIntegrator.NoSquish
    for bad in (2, -1, 7):
        with pytest.raises(openmm.OpenMMException, match="rotation method"):
            integrator.setRotationMethod(bad)
    with pytest.raises(TypeError):
        integrator.setRotationMethod("Exact")
    assert integrator.getRotationMethod() == RigidBodyIntegrator.NoSquish


def test_inherited_settings():
    integrator = RigidBodyIntegrator(0.001)
    integrator.setConstraintTolerance(1e-8)
    assert integrator.getConstraintTolerance() == 1e-8
    integrator.setIntegrationForceGroups({1, 3})
    assert integrator.getIntegrationForceGroups() == (1 << 1) | (1 << 3)
    assert integrator.getIntegrationForceGroups() == 10


def test_queries_need_a_context():
    for cls in CLASSES:
        integrator = make(cls, 0.001, EXPLICIT_BODIES)
        assert integrator.getNumBodies() == len(EXPLICIT_BODIES)  # explicit bodies are counted without one
        with pytest.raises(openmm.OpenMMException, match="once the integrator is bound"):
            make(cls, 0.001).getNumBodies()  # bodies found from the System's constraints are not
        integrator.setMeasureShadowWork(True)
        for query in (integrator.computeSystemTemperature, integrator.getShadowWork, integrator.getHeat,
                      lambda: integrator.getBodyParticles(0), lambda: integrator.step(1)):
            with pytest.raises(openmm.OpenMMException):
                query()


def test_reporter_docstring():
    """The integrators' docstrings are the headers' Doxygen: test_docstrings.py. The reporter is Python's
    own: it must point to what the lean API has (computeSystemTemperature()), none of what it removed."""
    doc = RigidStateDataReporter.__doc__
    assert "computeSystemTemperature" in doc
    named = [name for name in REMOVED if name in doc]
    assert not named, f"RigidStateDataReporter's docstring names methods removed from the integrators: {named}"


# ------------------------------------------------------------------------------------------------
# Copies and serialization
# ------------------------------------------------------------------------------------------------

BODY_CHOICES = {"found": None, "explicit": EXPLICIT_BODIES, "none": []}


@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
@pytest.mark.parametrize("choice", BODY_CHOICES)
@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_every_setting_and_the_class(cls, choice, method):
    original = configured(BODY_CHOICES[choice], cls)
    duplicate = copy_integrator(original, method)
    assert type(duplicate) is cls
    assert duplicate.thisown
    assert settings(duplicate) == settings(original)
    assert duplicate.getIntegrationForceGroups() == (1 << 0) | (1 << 2) | (1 << 5)
    assert serialized_bodies(duplicate) == BODY_CHOICES[choice]
    del original  # the copy owns its own C++ object
    assert settings(duplicate)[0].value_in_unit(unit.picosecond) == 0.0015


@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
def test_configured_changes_every_setting(cls):
    """What the copies are checked on: configured() moves every setting but the substeps (their own
    test below) away from the default, so a copy that dropped one would show."""
    changed, default = settings(configured(EXPLICIT_BODIES, cls)), settings(make(cls, 0.002))
    assert len(changed) == len(default) == 9 + {RigidBodyIntegrator: 1, RigidBodyBussiIntegrator: 4,
                                                RigidBodyLangevinIntegrator: 3}[cls]
    for index, (value, initial) in enumerate(zip(changed, default)):
        if index != 5:  # getForceGroupSubsteps()
            assert value != initial, index


@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_force_group_substeps(method):
    original = RigidBodyBussiIntegrator(300.0, 0.1, 0.004)
    original.setForceGroupSubsteps([(0, 1), (1, 2), (3, 4)])
    duplicate = copy_integrator(original, method)
    assert type(duplicate) is RigidBodyBussiIntegrator
    assert duplicate.getForceGroupSubsteps() == [(0, 1), (1, 2), (3, 4)]
    assert duplicate.getIntegrationForceGroups() == (1 << 0) | (1 << 1) | (1 << 3)


def test_deepcopy_keeps_python_attributes():
    for cls in CLASSES:
        original = make(cls, 0.001)
        original.note = {"label": [1, 2]}
        duplicate = copy.deepcopy(original)
        assert type(duplicate) is cls
        assert duplicate.note == original.note and duplicate.note is not original.note


@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
def test_deserialize_integrator_gives_the_class(cls):
    """openmmrigid.deserializeIntegrator(xml) returns the class that was serialized, with its explicit
    bodies, owning its C++ object, and serializing to the same XML."""
    original = configured(EXPLICIT_BODIES, cls)
    xml = openmm.XmlSerializer.serialize(original)
    integrator = openmmrigid.deserializeIntegrator(xml)
    assert type(integrator) is cls and integrator.thisown
    assert integrator.getNumBodies() == len(EXPLICIT_BODIES)
    assert serialized_bodies(integrator) == EXPLICIT_BODIES
    assert settings(integrator) == settings(original)
    assert openmm.XmlSerializer.serialize(integrator) == xml
    context, _ = explicit_context("Reference", integrator)
    integrator.step(2)
    assert [integrator.getBodyParticles(b) for b in range(len(EXPLICIT_BODIES))] == EXPLICIT_BODIES


def final_state(integrator, steps=30):
    """Positions and velocities after `steps` steps of the trapped system on Reference, from fixed ones."""
    context, _ = explicit_context("Reference", integrator)
    integrator.step(steps)
    state = context.getState(getPositions=True, getVelocities=True)
    return (state.getPositions(asNumpy=True).value_in_unit(unit.nanometer),
            state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond))


@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
@pytest.mark.parametrize("how", ["deserialize", "clone"])
def test_xml_serializer_gives_a_working_openmm_integrator(cls, how):
    """openmm is not patched: XmlSerializer.deserialize() and clone() give an openmm.Integrator, which
    serializes to the same XML and runs in a Context bit for bit as the original does on Reference (the
    same seed); deserializeIntegrator() of its XML gives the class back."""
    def original():
        integrator = make(cls, 0.002, EXPLICIT_BODIES)
        integrator.setMinimumMomentOfInertia(0.01)
        if hasattr(integrator, "setRandomNumberSeed"):
            integrator.setRandomNumberSeed(29)
        return integrator
    source = original()
    xml = openmm.XmlSerializer.serialize(source)
    plain = openmm.XmlSerializer.deserialize(xml) if how == "deserialize" else openmm.XmlSerializer.clone(source)
    assert isinstance(plain, openmm.Integrator) and plain.thisown
    assert openmm.XmlSerializer.serialize(plain) == xml
    assert plain.getStepSize() == 0.002 * unit.picoseconds
    assert type(openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(plain))) is cls
    expectedPositions, expectedVelocities = final_state(original())
    positions, velocities = final_state(plain)
    assert np.array_equal(positions, expectedPositions) and np.array_equal(velocities, expectedVelocities)
    assert not np.array_equal(positions, POSITIONS)  # it moved


def test_compound_integrator_gives_back_our_class():
    """CompoundIntegrator.getIntegrator() returns our class for ours (the one method of openmm the package
    wraps, for tools such as openmmtools that walk a compound), the same integrator as the one added."""
    bussi = RigidBodyBussiIntegrator(300.0, 0.1, 0.001, EXPLICIT_BODIES)
    bussi.setRandomNumberSeed(3)
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(openmm.VerletIntegrator(0.001))
    compound.addIntegrator(bussi)
    compound.setCurrentIntegrator(1)
    context = openmm.Context(trapped_system(), compound, platform("Reference"))
    context.setPositions(POSITIONS)
    context.setVelocitiesToTemperature(300, 1)
    compound.step(5)
    assert type(compound.getIntegrator(0)) is openmm.VerletIntegrator
    walked = compound.getIntegrator(1)
    assert type(walked) is RigidBodyBussiIntegrator and not walked.thisown
    assert openmm.XmlSerializer.serialize(walked) == openmm.XmlSerializer.serialize(bussi)
    assert walked.getTemperature() == 300 * unit.kelvin
    walked.setTemperature(280.0)  # the same C++ object as the one added
    assert bussi.getTemperature() == 280 * unit.kelvin
    assert walked.getBodyParticles(1) == EXPLICIT_BODIES[1]
    assert bussi.getNumBodies() == len(EXPLICIT_BODIES)
    assert bussi.getBodyParticles(1) == EXPLICIT_BODIES[1]
    assert bussi.computeSystemTemperature().value_in_unit(unit.kelvin) > 0


def test_xml_format():
    xml = openmm.XmlSerializer.serialize(configured([[0, 1, 2], [3]]))
    assert 'type="RigidBodyIntegrator"' in xml and 'version="5"' in xml
    for attribute in ("stepSize", "constraintTolerance", "integrationForceGroups", "rotationMethod", "minimumMomentOfInertia",
                      "splitting", "explicitBodies", "measureShadowWork", "accuracyCheck"):
        assert attribute + "=" in xml
    # No thermostat any more: that is RigidBodyBussiIntegrator's; the heat is measured with the shadow work.
    for attribute in ("thermostat", "thermostatTemperature", "thermostatCollisionTime", "temperature", "randomSeed",
                      "measureHeat"):
        assert f" {attribute}=" not in xml
    assert xml.count("<Body>") == 2 and xml.count("<Particle") == 4
    bussi = openmm.XmlSerializer.serialize(configured([[0, 1, 2], [3]], RigidBodyBussiIntegrator))
    assert 'type="RigidBodyBussiIntegrator"' in bussi and 'version="1"' in bussi
    for attribute in ("stepSize", "splitting", "temperature", "collisionTime", "randomSeed", "explicitBodies",
                      "measureShadowWork", "accuracyCheck"):
        assert f" {attribute}=" in bussi
    assert bussi.count("<Body>") == 2 and bussi.count("<Particle") == 4
    langevin = openmm.XmlSerializer.serialize(configured(None, RigidBodyLangevinIntegrator))
    assert 'type="RigidBodyLangevinIntegrator"' in langevin and 'version="2"' in langevin
    for attribute in ("temperature", "friction", "randomSeed", "measureShadowWork"):
        assert f" {attribute}=" in langevin
    assert " measureHeat=" not in langevin


def test_xml_defaults_for_older_files():
    minimal = '<?xml version="1.0" ?>\n<Integrator stepSize=".004" type="RigidBodyIntegrator" version="1"/>\n'
    integrator = openmmrigid.deserializeIntegrator(minimal)
    default = RigidBodyIntegrator(0.004)
    assert type(integrator) is RigidBodyIntegrator
    assert settings(integrator) == settings(default)
    plain = openmm.XmlSerializer.deserialize(minimal)
    assert isinstance(plain, openmm.Integrator) and plain.getStepSize() == 0.004 * unit.picoseconds
    withBodies = ('<?xml version="1.0" ?>\n<Integrator stepSize=".004" type="RigidBodyIntegrator" version="1">'
                  '<Bodies><Body><Particle index="3"/><Particle index="4"/></Body></Bodies></Integrator>\n')
    withBodies = openmmrigid.deserializeIntegrator(withBodies)
    assert withBodies.getNumBodies() == 1 and serialized_bodies(withBodies) == [[3, 4]]


@pytest.mark.parametrize("version", [3, 4])
def test_xml_of_an_older_thermostatted_integrator_is_a_bussi_integrator(version):
    """A RigidBodyIntegrator written with setThermostat() (versions 3 and 4) reads back as the
    RigidBodyBussiIntegrator that replaced it, with its bath, seed, splitting and bodies."""
    xml = ('<?xml version="1.0" ?>\n<Integrator stepSize=".003" thermostat="1" thermostatTemperature="310" '
           f'thermostatCollisionTime=".2" randomSeed="7" splitting="1" type="RigidBodyIntegrator" version="{version}">'
           '<Bodies><Body><Particle index="0"/><Particle index="1"/><Particle index="2"/></Body></Bodies></Integrator>\n')
    integrator = openmmrigid.deserializeIntegrator(xml)
    assert type(integrator) is RigidBodyBussiIntegrator
    assert integrator.getTemperature() == 310 * unit.kelvin
    assert integrator.getCollisionTime() == 0.2 * unit.picoseconds
    assert integrator.getStepSize() == 0.003 * unit.picoseconds
    assert (integrator.getRandomNumberSeed(), integrator.getSplitting()) == (7, RigidBodyIntegrator.Omelyan2)
    assert serialized_bodies(integrator) == [[0, 1, 2]]
    unthermostatted = openmmrigid.deserializeIntegrator(xml.replace('thermostat="1"', 'thermostat="0"'))
    assert type(unthermostatted) is RigidBodyIntegrator


def test_xml_errors():
    for xml in ('<Integrator stepSize=".004" type="RigidBodyIntegrator" version="6"/>',
                '<Integrator stepSize=".004" temperature="300" collisionTime=".1" type="RigidBodyBussiIntegrator" version="2"/>',
                '<Integrator stepSize=".004" temperature="300" friction="1" type="RigidBodyLangevinIntegrator" version="3"/>'):
        xml = '<?xml version="1.0" ?>\n' + xml + "\n"
        for read in (openmm.XmlSerializer.deserialize, openmmrigid.deserializeIntegrator):
            with pytest.raises(openmm.OpenMMException, match="version"):
                read(xml)
    badMethod = '<?xml version="1.0" ?>\n<Integrator stepSize=".004" rotationMethod="5" type="RigidBodyIntegrator" version="1"/>\n'
    with pytest.raises(openmm.OpenMMException, match="rotation method"):
        openmm.XmlSerializer.deserialize(badMethod)
    with pytest.raises(openmm.OpenMMException, match="rotation method"):
        openmmrigid.deserializeIntegrator(badMethod)
    badBath = ('<?xml version="1.0" ?>\n<Integrator stepSize=".004" temperature="-300" collisionTime=".1" '
               'type="RigidBodyBussiIntegrator" version="1"/>\n')
    with pytest.raises(openmm.OpenMMException, match="RigidBodyBussiIntegrator: the temperature"):
        openmmrigid.deserializeIntegrator(badBath)
    with pytest.raises(openmm.OpenMMException, match="openmm-rigid"):
        openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(openmm.VerletIntegrator(0.001)))


def test_other_integrators_unchanged():
    for integrator in (openmm.VerletIntegrator(0.001), openmm.LangevinMiddleIntegrator(300, 1, 0.002)):
        xml = openmm.XmlSerializer.serialize(integrator)
        assert type(openmm.XmlSerializer.deserialize(xml)) is type(integrator)
        assert type(openmm.XmlSerializer.clone(integrator)) is type(integrator)
        assert type(copy.deepcopy(integrator)) is type(integrator)


def test_kernels_load_once():
    from openmmrigid import integrator as module
    counts = [len(openmm.Platform.getPluginLoadFailures())]
    module._loadKernels()  # already registered: loads nothing
    assert len(openmm.Platform.getPluginLoadFailures()) == counts[0]
    for name in PLATFORMS:
        try:
            assert openmm.Platform.getPlatformByName(name).supportsKernels(["IntegrateRigidBodyStep"])
        except openmm.OpenMMException:
            pass  # platform not available
    for cls in CLASSES:
        context, integrator = explicit_context("Reference", make(cls, 0.001, EXPLICIT_BODIES))
        integrator.step(2)


def test_only_platforms_with_kernels_claim_them():
    # OpenMM chooses the default platform among those that claim every kernel: a platform that
    # claimed ours without having it (an explaining stand-in) would take a Context made without a
    # named platform away from the ones that can run it (TestPlatformSupport makes such a platform).
    supported = openmmrigid.getSupportedPlatforms()
    assert "Reference" in supported and "CPU" in supported
    for i in range(openmm.Platform.getNumPlatforms()):
        platform = openmm.Platform.getPlatform(i)
        assert platform.supportsKernels(["IntegrateRigidBodyStep"]) == (platform.getName() in supported)


def test_context_constructor_is_openmms_own():
    """openmm.Context is not wrapped: making one with a rigid integrator goes straight to OpenMM."""
    assert openmm.Context.__init__.__module__ == "openmm.openmm"
    assert not hasattr(openmm.Context.__init__, "_openmmrigidOriginal")
    assert not hasattr(openmm.Context.__init__, "__wrapped__")


def test_named_platform_without_kernels_gives_openmms_message():
    """A Context made with a rigid-body integrator (alone or in a CompoundIntegrator) on a platform
    without its kernels fails with OpenMM's own message (openmm is not patched to reword it). Runs
    where such a platform exists (CUDA without the CUDA plugin, for one); the C++ TestPlatformSupport
    makes one everywhere."""
    lacking = [openmm.Platform.getPlatform(i) for i in range(openmm.Platform.getNumPlatforms())
               if not openmm.Platform.getPlatform(i).supportsKernels(["IntegrateRigidBodyStep"])]
    if not lacking:
        pytest.skip("every platform here has the rigid-body kernels")
    system = trapped_system()
    for lacks in lacking:
        for integrator in (RigidBodyIntegrator(0.001), RigidBodyBussiIntegrator(300, 0.1, 0.001),
                           RigidBodyLangevinIntegrator(300, 1, 0.001)):
            compound = openmm.CompoundIntegrator()
            compound.addIntegrator(openmm.VerletIntegrator(0.001))
            compound.addIntegrator(copy.deepcopy(integrator))
            for attempt in (integrator, compound):
                with pytest.raises(openmm.OpenMMException, match="does not support all required kernels"):
                    openmm.Context(system, attempt, lacks)


# ------------------------------------------------------------------------------------------------
# In a Context and a Simulation
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
def test_context_queries(platformName, cls):
    context, integrator = explicit_context(platformName, make(cls, 0.001, EXPLICIT_BODIES))
    assert context.getIntegrator() is integrator
    integrator.step(5)
    assert integrator.getNumBodies() == len(EXPLICIT_BODIES)
    for index, body in enumerate(EXPLICIT_BODIES):
        particles = integrator.getBodyParticles(index)
        assert particles == body and all(type(i) is int for i in particles)
    with pytest.raises(openmm.OpenMMException):
        integrator.getBodyParticles(len(EXPLICIT_BODIES))
    state = context.getState(getEnergy=True, getVelocities=True, getPositions=True)
    positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    masses = np.array(MASSES)
    assert [bodyKind(masses[b], positions[b]) for b in EXPLICIT_BODIES] == ["asymmetric", "linear", "point", "asymmetric"]
    moments = principalMoments(masses[EXPLICIT_BODIES[0]], positions[EXPLICIT_BODIES[0]])
    assert list(moments) == sorted(moments) and moments[0] > 0
    assert rigidDegreesOfFreedom(context, integrator) == EXPLICIT_DOF
    total = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert total == pytest.approx(kinetic_energy_by_hand(state, MASSES), rel=1e-9)
    # The velocities are rigid motions: translation of the centres plus rotation about them is all of it.
    translational, rotational = rigidKineticEnergies(context, integrator)
    assert rotational > 0 and translational > 0
    assert translational + rotational == pytest.approx(total, rel=1e-9)
    temperature = integrator.computeSystemTemperature()
    assert unit.is_quantity(temperature)
    assert temperature.value_in_unit(unit.kelvin) == pytest.approx(2 * total / (EXPLICIT_DOF * GAS_CONSTANT), rel=1e-9)


def test_bound_to_one_context():
    for cls in CLASSES:
        context, integrator = explicit_context("Reference", make(cls, 0.001, EXPLICIT_BODIES))
        with pytest.raises(openmm.OpenMMException):
            openmm.Context(trapped_system(), integrator, platform("Reference"))


@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
def test_copy_of_a_bound_integrator_is_unbound(cls):
    context, integrator = explicit_context("Reference", make(cls, 0.001, EXPLICIT_BODIES))
    integrator.step(3)
    duplicate = copy.deepcopy(integrator)
    assert type(duplicate) is cls
    assert duplicate.getNumBodies() == integrator.getNumBodies()  # explicit bodies are counted unbound too
    for query in (lambda: duplicate.getBodyParticles(0), duplicate.computeSystemTemperature):
        with pytest.raises(openmm.OpenMMException, match="once the integrator is bound"):
            query()
    other = openmm.Context(trapped_system(), duplicate, platform("Reference"))
    other.setPositions(POSITIONS)
    duplicate.step(3)
    assert duplicate.getNumBodies() == integrator.getNumBodies()
    assert duplicate.getBodyParticles(0) == EXPLICIT_BODIES[0]


def test_bodies_found_from_constraints():
    """Two rigid constraint triangles are two bodies; 18 - 6 constraints = 12 degrees of freedom."""
    system = openmm.System()
    positions = []
    for offset in (0.0, 0.5):
        first = system.getNumParticles()
        for mass, position in ((16.0, [0, 0, 0]), (1.0, [0.09572, 0, 0]), (1.0, [-0.024, 0.0927, 0])):
            system.addParticle(mass)
            positions.append(np.array(position) + offset)
        for i, j in ((0, 1), (0, 2), (1, 2)):
            system.addConstraint(first + i, first + j, float(np.linalg.norm(positions[first + i] - positions[first + j])))
    for cls in CLASSES:
        integrator = make(cls, 0.001)
        context = openmm.Context(system, integrator, platform("Reference"))
        context.setPositions(positions)
        context.setVelocitiesToTemperature(300, 2)
        integrator.step(3)
        assert integrator.getNumBodies() == 2
        assert integrator.getBodyParticles(1) == [3, 4, 5]
        assert rigidDegreesOfFreedom(context, integrator) == 12
        kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(
            2 * kinetic / (12 * GAS_CONSTANT), rel=1e-9)


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("cls", CLASSES, ids=lambda cls: cls.__name__)
def test_simulation_state_and_checkpoint(platformName, cls, tmp_path):
    system = trapped_system()
    integrator = make(cls, 0.001, EXPLICIT_BODIES)
    if hasattr(integrator, "setRandomNumberSeed"):
        integrator.setRandomNumberSeed(8)
    simulation = app.Simulation(topology_for(len(MASSES)), system, integrator, platform(platformName))
    assert simulation.integrator is integrator and simulation.context.getIntegrator() is integrator
    simulation.context.setPositions(POSITIONS)
    simulation.context.setVelocitiesToTemperature(300, 3)
    simulation.step(10)

    stateFile = io.StringIO()
    simulation.saveState(stateFile)
    checkpointFile = io.BytesIO()
    simulation.saveCheckpoint(checkpointFile)
    simulation.step(10)
    reference = simulation.context.getState(getPositions=True, getVelocities=True)
    referencePositions = reference.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    referenceVelocities = reference.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)

    def compare():
        simulation.step(10)
        state = simulation.context.getState(getPositions=True, getVelocities=True)
        assert np.allclose(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer), referencePositions,
                           rtol=0, atol=1e-9)
        assert np.allclose(state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond),
                           referenceVelocities, rtol=0, atol=1e-7)

    # A saved State has no random number state: only the constant-energy integrator repeats from it.
    if cls is RigidBodyIntegrator:
        stateFile.seek(0)
        simulation.loadState(stateFile)
        compare()
    checkpointFile.seek(0)
    simulation.loadCheckpoint(checkpointFile)
    compare()

    path = str(tmp_path / "rigid.chk")
    simulation.reporters.append(app.CheckpointReporter(path, 5))
    simulation.step(5)
    assert os.path.getsize(path) > 0
    simulation.loadCheckpoint(path)
    simulation.step(1)


# ------------------------------------------------------------------------------------------------
# Temperature
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("cmMotionRemover", [False, True])
def test_reported_temperature(platformName, cmMotionRemover):
    system = trapped_system(cmMotionRemover)
    expectedDof = EXPLICIT_DOF - (3 if cmMotionRemover else 0)
    integrator = RigidBodyIntegrator(0.001, EXPLICIT_BODIES)
    simulation = app.Simulation(topology_for(len(MASSES)), system, integrator, platform(platformName))
    simulation.context.setPositions(POSITIONS)
    simulation.context.setVelocitiesToTemperature(300, 4)
    rigidOutput, plainOutput = io.StringIO(), io.StringIO()
    rigid = RigidStateDataReporter(rigidOutput, 5, step=True, kineticEnergy=True, temperature=True)
    plain = app.StateDataReporter(plainOutput, 5, step=True, kineticEnergy=True, temperature=True)
    simulation.reporters += [rigid, plain]
    simulation.step(5)

    state = simulation.context.getState(getVelocities=True, getEnergy=True)
    kineticEnergy = kinetic_energy_by_hand(state, MASSES)
    expected = 2 * kineticEnergy / (expectedDof * GAS_CONSTANT)
    assert rigidDegreesOfFreedom(simulation.context, integrator) == expectedDof
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(expected, rel=1e-9)
    for output in (rigidOutput, plainOutput):
        lines = output.getvalue().splitlines()
        assert len(lines) == 2 and "Temperature (K)" in lines[0]
        step, reportedEnergy, temperature = (float(value) for value in lines[1].split(","))
        assert step == 5
        assert reportedEnergy == pytest.approx(kineticEnergy, rel=1e-9)
        assert temperature == pytest.approx(expected, rel=1e-9)
    # What the constraint count alone would give: 3 per particle, no constraints here.
    naiveDof = 3 * len(MASSES) - (3 if cmMotionRemover else 0)
    assert naiveDof != expectedDof


def test_reporter_with_another_integrator():
    """With an integrator that is not a RigidBodyIntegrator it is a plain StateDataReporter."""
    system = trapped_system()
    simulation = app.Simulation(topology_for(len(MASSES)), system, openmm.VerletIntegrator(0.001), platform("Reference"))
    simulation.context.setPositions(POSITIONS)
    simulation.context.setVelocitiesToTemperature(300, 5)
    output = io.StringIO()
    reporter = RigidStateDataReporter(output, 2, temperature=True)
    simulation.reporters.append(reporter)
    simulation.step(2)
    assert reporter._dof == 3 * len(MASSES)
    state = simulation.context.getState(getEnergy=True)
    expected = 2 * state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole) / (3 * len(MASSES) * GAS_CONSTANT)
    assert float(output.getvalue().splitlines()[1]) == pytest.approx(expected, rel=1e-9)

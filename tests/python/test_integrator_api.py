"""Tests of the Python surface of openmmrigid.RigidBodyIntegrator (the physics is tested elsewhere):

- construction from floats and openmm.unit Quantities, bodies from lists, tuples, ranges and numpy
  arrays, and bad input raising openmm.OpenMMException with a message naming the body or entry;
- the rotation method and the settings inherited from openmm.Integrator;
- pickle, copy.copy, copy.deepcopy, openmm.XmlSerializer (serialize, deserialize, clone) and
  openmmrigid.deserializeIntegrator keep every setting and give back a RigidBodyIntegrator; the XML
  reads with defaults (older files) and refuses newer versions;
- the integrator in openmm.Context and openmm.app.Simulation on the Reference and CPU platforms:
  queries with units, saveState/loadState, checkpoints, CheckpointReporter;
- the temperature that RigidStateDataReporter (and openmm.app.StateDataReporter, through
  computeSystemTemperature) report for explicit bodies, against 2 KE / (dof k_B) computed here.
"""

import copy
import io
import os

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest

import openmmrigid
from openmmrigid import RigidBodyIntegrator, RigidStateDataReporter
from systems import COPY_METHODS, copy_integrator

PLATFORMS = ["Reference", "CPU"]
GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)


def settings(integrator):
    """Every setting a copy must keep."""
    return (integrator.getStepSize(), integrator.getConstraintTolerance(), integrator.getIntegrationForceGroups(),
            integrator.getRotationMethod(), integrator.getMinimumMomentOfInertia(), integrator.getSplitting(), integrator.hasExplicitBodies(),
            integrator.getExplicitBodies(), integrator.getMeasureShadowWork(), integrator.getMeasureHeat(),
            integrator.getAccuracyCheck())


def configured(bodies):
    """An integrator with every setting away from its default."""
    integrator = RigidBodyIntegrator(0.0015, bodies) if bodies is not None else RigidBodyIntegrator(0.0015)
    integrator.setConstraintTolerance(3e-7)
    integrator.setIntegrationForceGroups({0, 2, 5})
    integrator.setRotationMethod(RigidBodyIntegrator.NoSquish)
    integrator.setMinimumMomentOfInertia(0.0125)
    integrator.setSplitting(RigidBodyIntegrator.Yoshida4)
    integrator.setMeasureShadowWork(True)
    integrator.setMeasureHeat(True)
    integrator.setAccuracyCheck(False)
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
    integrator = integrator or RigidBodyIntegrator(0.001, EXPLICIT_BODIES)
    context = openmm.Context(trapped_system(), integrator, platform(platformName))
    context.setPositions(POSITIONS)
    context.setVelocitiesToTemperature(300, 1)
    return context, integrator


def kinetic_energy_by_hand(state, masses):
    velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    return 0.5 * float(np.sum(np.asarray(masses)[:, None] * velocities**2))


# ------------------------------------------------------------------------------------------------
# Construction and settings
# ------------------------------------------------------------------------------------------------

def test_is_an_openmm_integrator():
    integrator = RigidBodyIntegrator(0.002)
    assert isinstance(integrator, openmm.Integrator)
    assert openmmrigid.RigidBodyIntegrator is RigidBodyIntegrator
    for name in ("RigidBodyIntegrator", "RigidStateDataReporter", "FreeRotor", "special"):
        assert name in openmmrigid.__all__ and hasattr(openmmrigid, name)


@pytest.mark.parametrize("stepSize, expected", [
    (0.002, 0.002),
    (2 * unit.femtoseconds, 0.002),
    (0.5 * unit.picosecond, 0.5),
    (np.float64(0.001), 0.001),
    (1, 1.0),
])
def test_step_size_float_or_quantity(stepSize, expected):
    for integrator in (RigidBodyIntegrator(stepSize), RigidBodyIntegrator(stepSize, [[0, 1, 2]])):
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
    integrator = RigidBodyIntegrator(0.001, bodies)
    assert integrator.hasExplicitBodies()
    assert integrator.getExplicitBodies() == [[0, 1, 2], [3, 4, 5]]
    assert all(type(i) is int for body in integrator.getExplicitBodies() for i in body)


def test_bodies_ragged_and_empty():
    assert RigidBodyIntegrator(0.001, [[0], [1, 2], [3, 4, 5, 6]]).getExplicitBodies() == [[0], [1, 2], [3, 4, 5, 6]]
    none = RigidBodyIntegrator(0.001, [])  # explicit: every particle free
    assert none.hasExplicitBodies() and none.getExplicitBodies() == []
    found = RigidBodyIntegrator(0.001)  # the System's constraint clusters
    assert not found.hasExplicitBodies() and found.getExplicitBodies() == []


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
    with pytest.raises(openmm.OpenMMException) as error:
        RigidBodyIntegrator(0.001, bodies)
    for word in words:
        assert word in str(error.value)


def test_bad_bodies_found_with_the_system():
    system = trapped_system()
    for bodies, word in (([[0, 1, 99]], "99"), ([[0, 1, 2], [2, 3, 4]], "2")):
        with pytest.raises(openmm.OpenMMException, match=word):
            openmm.Context(system, RigidBodyIntegrator(0.001, bodies), platform("Reference"))


@pytest.mark.parametrize("integratorClass", [RigidBodyIntegrator, openmmrigid.RigidBodyLangevinIntegrator])
@pytest.mark.parametrize("bad", [float("nan"), float("inf"), -float("inf")], ids=str)
def test_non_finite_step_size_is_a_bad_argument(integratorClass, bad):
    """A step size that is not a number is refused where it is given, naming the class, not reported
    later as an unstable simulation; the integrator keeps its step."""
    leading = () if integratorClass is RigidBodyIntegrator else (300.0, 1.0)
    with pytest.raises(openmm.OpenMMException, match=f"{integratorClass.__name__}: the step size is .*finite"):
        integratorClass(*leading, bad)
    integrator = integratorClass(*leading, 0.002)
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
    integrator = RigidBodyIntegrator(0.001, EXPLICIT_BODIES)
    assert integrator.getNumBodies() == len(EXPLICIT_BODIES)  # explicit bodies are counted without one
    with pytest.raises(openmm.OpenMMException, match="once the integrator is bound"):
        RigidBodyIntegrator(0.001).getNumBodies()  # bodies found from the System's constraints are not
    for query in (integrator.getNumDegreesOfFreedom,
                  integrator.getTranslationalKineticEnergy, integrator.getRotationalKineticEnergy,
                  lambda: integrator.getBodyParticles(0), lambda: integrator.step(1)):
        with pytest.raises(openmm.OpenMMException):
            query()


def test_reporter_docstring():
    # The integrators' docstrings are the headers' Doxygen: test_docstrings.py. The reporter is Python's own.
    assert "getNumDegreesOfFreedom" in RigidStateDataReporter.__doc__


# ------------------------------------------------------------------------------------------------
# Copies and serialization
# ------------------------------------------------------------------------------------------------

BODY_CHOICES = {"found": None, "explicit": EXPLICIT_BODIES, "none": []}


@pytest.mark.parametrize("choice", BODY_CHOICES)
@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_every_setting(choice, method):
    original = configured(BODY_CHOICES[choice])
    duplicate = copy_integrator(original, method)
    assert type(duplicate) is RigidBodyIntegrator
    assert duplicate.thisown
    assert settings(duplicate) == settings(original)
    assert duplicate.getIntegrationForceGroups() == (1 << 0) | (1 << 2) | (1 << 5)
    del original  # the copy owns its own C++ object
    assert settings(duplicate)[0].value_in_unit(unit.picosecond) == 0.0015


def test_deepcopy_keeps_python_attributes():
    original = RigidBodyIntegrator(0.001)
    original.note = {"label": [1, 2]}
    duplicate = copy.deepcopy(original)
    assert duplicate.note == original.note and duplicate.note is not original.note


def test_xml_format():
    xml = openmm.XmlSerializer.serialize(configured([[0, 1, 2], [3]]))
    assert 'type="RigidBodyIntegrator"' in xml and 'version="4"' in xml
    for attribute in ("stepSize", "constraintTolerance", "integrationForceGroups", "rotationMethod", "minimumMomentOfInertia", "splitting",
                      "thermostat", "thermostatTemperature", "thermostatCollisionTime", "randomSeed", "explicitBodies",
                      "measureShadowWork", "measureHeat", "accuracyCheck"):
        assert attribute + "=" in xml
    assert xml.count("<Body>") == 2 and xml.count("<Particle") == 4


def test_xml_defaults_for_older_files():
    minimal = '<?xml version="1.0" ?>\n<Integrator stepSize=".004" type="RigidBodyIntegrator" version="1"/>\n'
    integrator = openmm.XmlSerializer.deserialize(minimal)
    default = RigidBodyIntegrator(0.004)
    assert type(integrator) is RigidBodyIntegrator
    assert settings(integrator) == settings(default)
    withBodies = ('<?xml version="1.0" ?>\n<Integrator stepSize=".004" type="RigidBodyIntegrator" version="1">'
                  '<Bodies><Body><Particle index="3"/><Particle index="4"/></Body></Bodies></Integrator>\n')
    assert openmmrigid.deserializeIntegrator(withBodies).getExplicitBodies() == [[3, 4]]


def test_xml_errors():
    newer = '<?xml version="1.0" ?>\n<Integrator stepSize=".004" type="RigidBodyIntegrator" version="5"/>\n'
    with pytest.raises(openmm.OpenMMException, match="version"):
        openmm.XmlSerializer.deserialize(newer)
    badMethod = '<?xml version="1.0" ?>\n<Integrator stepSize=".004" rotationMethod="5" type="RigidBodyIntegrator" version="1"/>\n'
    with pytest.raises(openmm.OpenMMException, match="rotation method"):
        openmm.XmlSerializer.deserialize(badMethod)
    with pytest.raises(openmm.OpenMMException, match="RigidBodyIntegrator"):
        openmmrigid.deserializeIntegrator(openmm.XmlSerializer.serialize(openmm.VerletIntegrator(0.001)))


def test_other_integrators_unchanged():
    for integrator in (openmm.VerletIntegrator(0.001), openmm.LangevinMiddleIntegrator(300, 1, 0.002)):
        xml = openmm.XmlSerializer.serialize(integrator)
        assert type(openmm.XmlSerializer.deserialize(xml)) is type(integrator)
        assert type(openmm.XmlSerializer.clone(integrator)) is type(integrator)
        assert type(copy.deepcopy(integrator)) is type(integrator)


def test_kernels_load_once():
    from openmmrigid import integrator as module
    module._loadKernels()  # already registered: loads nothing
    module._patchXmlSerializer()  # already wrapped: wraps nothing
    assert not hasattr(openmm.XmlSerializer._deserializeIntegrator._openmmrigidOriginal, "_openmmrigidOriginal")
    for name in PLATFORMS:
        try:
            assert openmm.Platform.getPlatformByName(name).supportsKernels(["IntegrateRigidBodyStep"])
        except openmm.OpenMMException:
            pass  # platform not available
    context, integrator = explicit_context("Reference")
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


def test_named_platform_without_kernels_is_explained(monkeypatch):
    """A Context made with a rigid-body integrator (alone or in a CompoundIntegrator) on a platform
    without its kernels fails with a message that names the class, the platform and the platforms
    that have the kernels; OpenMM's own error is kept for any other integrator or cause. No platform
    here lacks the kernels, so OpenMM's refusal and the platform's answer are stood in for (the C++
    TestPlatformSupport makes a real one)."""
    generic = "Specified a Platform for a Context which does not support all required kernels"

    def refuse(self, *args, **kwargs):
        raise openmm.OpenMMException(generic)
    monkeypatch.setattr(openmm.Context.__init__, "_openmmrigidOriginal", refuse)
    monkeypatch.setattr(openmm.Platform, "supportsKernels", lambda self, names: self.getName() != "CUDA-like")
    monkeypatch.setattr(openmm.Platform, "getName", lambda self: "CUDA-like")
    cpu = platform("CPU")
    system = trapped_system()
    compound = openmm.CompoundIntegrator()
    compound.addIntegrator(openmm.VerletIntegrator(0.001))
    compound.addIntegrator(openmmrigid.RigidBodyLangevinIntegrator(300, 1, 0.001))
    for integrator, className in ((RigidBodyIntegrator(0.001), "RigidBodyIntegrator"),
                                  (compound, "RigidBodyLangevinIntegrator")):
        with pytest.raises(openmm.OpenMMException) as error:
            openmm.Context(system, integrator, cpu)
        message = str(error.value)
        assert message.startswith(f"{className}: the CUDA-like platform has no kernels"), message
        assert "Reference" in message and "getSupportedPlatforms" in message
        assert generic in str(error.value.__cause__)
    with pytest.raises(openmm.OpenMMException, match=generic):
        openmm.Context(system, openmm.VerletIntegrator(0.001), cpu)
    monkeypatch.setattr(openmm.Platform, "supportsKernels", lambda self, names: True)
    with pytest.raises(openmm.OpenMMException, match=generic):  # not for want of our kernel
        openmm.Context(system, RigidBodyIntegrator(0.001), cpu)


# ------------------------------------------------------------------------------------------------
# In a Context and a Simulation
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platformName", PLATFORMS)
def test_context_queries(platformName):
    context, integrator = explicit_context(platformName)
    assert context.getIntegrator() is integrator
    integrator.step(5)
    assert integrator.getNumBodies() == len(EXPLICIT_BODIES)
    for index, body in enumerate(EXPLICIT_BODIES):
        particles = integrator.getBodyParticles(index)
        assert particles == body and all(type(i) is int for i in particles)
    with pytest.raises(openmm.OpenMMException):
        integrator.getBodyParticles(len(EXPLICIT_BODIES))
    assert [integrator.getBodyKind(i) for i in range(4)] == ["asymmetric", "linear", "point", "asymmetric"]
    moments = integrator.getBodyMoments(0)
    assert unit.is_quantity(moments) and len(moments) == 3
    values = moments.value_in_unit(unit.amu * unit.nanometer**2)
    assert values == sorted(values) and values[0] > 0
    assert integrator.getNumDegreesOfFreedom() == EXPLICIT_DOF
    translational = integrator.getTranslationalKineticEnergy()
    rotational = integrator.getRotationalKineticEnergy()
    for energy in (translational, rotational):
        assert unit.is_quantity(energy) and energy.unit == unit.kilojoule_per_mole
    state = context.getState(getEnergy=True, getVelocities=True)
    total = state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert (translational + rotational).value_in_unit(unit.kilojoule_per_mole) == pytest.approx(total, rel=1e-9)
    assert total == pytest.approx(kinetic_energy_by_hand(state, MASSES), rel=1e-9)
    temperature = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    assert temperature == pytest.approx(2 * total / (EXPLICIT_DOF * GAS_CONSTANT), rel=1e-9)


def test_bound_to_one_context():
    context, integrator = explicit_context("Reference")
    with pytest.raises(openmm.OpenMMException):
        openmm.Context(trapped_system(), integrator, platform("Reference"))


def test_copy_of_a_bound_integrator_is_unbound():
    context, integrator = explicit_context("Reference")
    integrator.step(3)
    duplicate = copy.deepcopy(integrator)
    assert duplicate.getNumBodies() == integrator.getNumBodies()  # explicit bodies are counted unbound too
    with pytest.raises(openmm.OpenMMException, match="once the integrator is bound"):
        duplicate.getBodyKind(0)
    other = openmm.Context(trapped_system(), duplicate, platform("Reference"))
    other.setPositions(POSITIONS)
    duplicate.step(3)
    assert duplicate.getNumBodies() == integrator.getNumBodies()


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
    integrator = RigidBodyIntegrator(0.001)
    context = openmm.Context(system, integrator, platform("Reference"))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300, 2)
    integrator.step(3)
    assert integrator.getNumBodies() == 2
    assert integrator.getBodyParticles(1) == [3, 4, 5]
    assert integrator.getNumDegreesOfFreedom() == 12


@pytest.mark.parametrize("platformName", PLATFORMS)
def test_simulation_state_and_checkpoint(platformName, tmp_path):
    system = trapped_system()
    simulation = app.Simulation(topology_for(len(MASSES)), system, RigidBodyIntegrator(0.001, EXPLICIT_BODIES),
                                platform(platformName))
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
    simulation = app.Simulation(topology_for(len(MASSES)), system, RigidBodyIntegrator(0.001, EXPLICIT_BODIES),
                                platform(platformName))
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
    assert rigid._dof == expectedDof
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

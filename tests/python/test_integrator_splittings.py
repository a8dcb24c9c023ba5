"""Tests of RigidBodyIntegrator's splittings (setSplitting), on the Reference and the CPU platform.

- the stage sequence, pinned exactly: a rigid body and two free particles in an anisotropic
  harmonic trap computed by an openmm.PythonForce, which records every configuration at which the
  integrator evaluates forces; a reimplementation here (kicks, drifts with openmmrigid.FreeRotor,
  each scheme written the way its paper writes it) must evaluate the forces at the same
  configurations, the same number of times (1, 2, 3 and 4 per step for Verlet, Omelyan2, Yoshida4 and
  Omelyan4), and end in the same state, to 1e-12; RigidBodyBussiIntegrator runs the same stages, then
  rescales all velocities by one factor;
- a CMMotionRemover (which changes velocities without telling the integrator) leaves the trajectory
  of a cluster with no net momentum unchanged for every splitting;
- on a box of rigid TIP3P water (PME, 2 fs) the total energy of Omelyan2 fluctuates less than half
  as much as Verlet's (Omelyan, Mryglod and Folk's optimized scheme);
- the API: constants, defaults, errors naming the bad value; copies and serialization keep the
  splitting, in RigidBodyIntegrator and RigidBodyBussiIntegrator (versions of the XML format:
  TestSerialization.cpp).

Each splitting's order, exact free motion, time reversal, conservation of momentum and constraints
among free particles (Yoshida4 fourth order with them) are tested in C++, tests/TestRigidBodyIntegrator.h,
on the Reference, CPU and OpenCL platforms.
"""


import numpy as np
import openmm
import openmm.unit as unit
import pytest

import openmmrigid
import systems
from openmmrigid import FreeRotor, RigidBodyBussiIntegrator, RigidBodyIntegrator

PLATFORMS = ["Reference", "CPU"]
SPLITTINGS = {"Verlet": RigidBodyIntegrator.Verlet, "Omelyan2": RigidBodyIntegrator.Omelyan2,
              "Yoshida4": RigidBodyIntegrator.Yoshida4, "Omelyan4": RigidBodyIntegrator.Omelyan4}
#: Force evaluations per step (the scheme's kicks, adjacent ones of consecutive steps merged).
FORCE_EVALUATIONS = {"Verlet": 1, "Omelyan2": 2, "Yoshida4": 3, "Omelyan4": 4}

# ------------------------------------------------------------------------------------------------
# Each scheme as its paper writes it: a list of ("kick", fraction of the step) and ("drift", ...).
# ------------------------------------------------------------------------------------------------

# Omelyan, Mryglod and Folk, Phys. Rev. E 65, 056706 (2002): lambda in closed form.
_ROOT = np.cbrt(2 * np.sqrt(326.0) + 36)
OMELYAN2_LAMBDA = 0.1931833275037836
# Yoshida, Phys. Lett. A 150, 262 (1990): the triple jump.
YOSHIDA_W1 = 1 / (2 - 2 ** (1 / 3))
YOSHIDA_W0 = 1 - 2 * YOSHIDA_W1
# Omelyan, Mryglod and Folk, Comput. Phys. Commun. 146, 188 (2002): velocity version (VEFRL).
VEFRL_XI, VEFRL_LAMBDA, VEFRL_CHI = 0.1644986515575760, -0.02094333910398989, 1.235692651138917


def verlet_operations(fraction):
    return [("kick", fraction / 2), ("drift", fraction), ("kick", fraction / 2)]


def paper_operations(name):
    if name == "Verlet":
        return verlet_operations(1.0)
    if name == "Omelyan2":
        lam = OMELYAN2_LAMBDA
        return [("kick", lam), ("drift", 0.5), ("kick", 1 - 2 * lam), ("drift", 0.5), ("kick", lam)]
    if name == "Yoshida4":  # three whole Verlet steps: the integrator merges their adjacent kicks
        return verlet_operations(YOSHIDA_W1) + verlet_operations(YOSHIDA_W0) + verlet_operations(YOSHIDA_W1)
    xi, lam, chi = VEFRL_XI, VEFRL_LAMBDA, VEFRL_CHI
    return [("kick", xi), ("drift", (1 - 2 * lam) / 2), ("kick", chi), ("drift", lam), ("kick", 1 - 2 * (chi + xi)),
            ("drift", lam), ("kick", chi), ("drift", (1 - 2 * lam) / 2), ("kick", xi)]


def test_coefficients_satisfy_their_conditions():
    """The coefficients written above are the papers' (not the integrator's table, which the other
    tests check against these): lambda equals its closed form, the triple jump cancels the third-order
    error (2 w1^3 + w0^3 = 0), and every scheme's kicks and drifts each add up to one step."""
    assert OMELYAN2_LAMBDA == pytest.approx(0.5 - _ROOT / 12 + 1 / (6 * _ROOT), abs=1e-16)
    assert 2 * YOSHIDA_W1 ** 3 + YOSHIDA_W0 ** 3 == pytest.approx(0.0, abs=1e-14)
    for name in SPLITTINGS:
        operations = paper_operations(name)
        for kind in ("kick", "drift"):
            assert sum(f for k, f in operations if k == kind) == pytest.approx(1.0, abs=1e-14), (name, kind)


# ------------------------------------------------------------------------------------------------
# The stage sequence, pinned with a PythonForce
# ------------------------------------------------------------------------------------------------

# A water-like asymmetric body (particles 0-2) with a TIP4P-like massless virtual site (5) and two
# free particles (3, 4), all in the trap U = sum_i (r_i - c) K (r_i - c) / 2 with K anisotropic, so
# that the body feels a torque (the site's share too, once OpenMM hands its force to the parents).
PIN_MASSES = np.array([15.999, 1.008, 1.008, 12.0, 40.0, 0.0])
SITE_WEIGHTS = np.array([0.8, 0.1, 0.1])            # site 5 = 0.8 r_0 + 0.1 r_1 + 0.1 r_2
PIN_POSITIONS = np.array([[0.00, 0.00, 0.00], [0.0757, 0.0586, 0.0], [-0.0757, 0.0586, 0.0],
                          [0.30, -0.10, 0.20], [-0.25, 0.15, -0.10], [0.0, 0.0, 0.0]]) + np.array([0.05, 0.02, -0.03])
PIN_POSITIONS[5] = SITE_WEIGHTS @ PIN_POSITIONS[:3]
PIN_BODY = [0, 1, 2]
TRAP_STIFFNESS = np.array([300.0, 500.0, 800.0])   # kJ/mol/nm^2
TRAP_CENTRE = np.array([0.1, -0.2, 0.05])           # nm


def trap_forces(positions):
    return -TRAP_STIFFNESS * (positions - TRAP_CENTRE)


def trap_forces_on_massive(positions):
    """The trap forces with the site's force handed to its parents, as OpenMM does."""
    forces = trap_forces(positions)
    forces[PIN_BODY] += np.outer(SITE_WEIGHTS, forces[5])
    return forces


def pin_velocities():
    """Rigid velocities for the body (V + omega x (r - R)) and arbitrary ones for the free particles."""
    masses = PIN_MASSES[PIN_BODY]
    centre = masses @ PIN_POSITIONS[PIN_BODY] / masses.sum()
    velocities = np.zeros_like(PIN_POSITIONS)
    velocities[PIN_BODY] = np.array([0.3, -0.2, 0.5]) + np.cross([4.0, -7.0, 11.0], PIN_POSITIONS[PIN_BODY] - centre)
    velocities[3] = [-0.4, 0.6, 0.1]
    velocities[4] = [0.2, 0.1, -0.3]
    velocities[5] = SITE_WEIGHTS @ velocities[PIN_BODY]
    return velocities


class Recorder:
    """The computation of a PythonForce that records every configuration it is asked about."""

    def __init__(self, forces):
        self.forces = forces
        self.configurations = []

    def __call__(self, state):
        positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        self.configurations.append(np.array(positions))
        forces = self.forces(positions)
        return 0.0, forces


class ReimplementedStep:
    """The body and free particles moved by a sequence of kicks and drifts, written here with
    openmmrigid.FreeRotor for the drift of the body; records where it evaluates forces."""

    def __init__(self, positions, velocities):
        masses = PIN_MASSES[PIN_BODY]
        self.mass = masses.sum()
        self.centre = masses @ positions[PIN_BODY] / self.mass
        self.velocity = masses @ velocities[PIN_BODY] / self.mass
        relative = positions[PIN_BODY] - self.centre
        self.angularMomentum = np.sum(masses[:, None] * np.cross(relative, velocities[PIN_BODY] - self.velocity), axis=0)
        inertia = sum(m * (r @ r * np.eye(3) - np.outer(r, r)) for m, r in zip(masses, relative))
        self.moments, axes = np.linalg.eigh(inertia)
        if np.linalg.det(axes) < 0:
            axes[:, 0] = -axes[:, 0]
        self.attitude = axes.T                                  # lab -> body
        self.bodyCoordinates = relative @ self.attitude.T
        self.free = [3, 4]
        self.positions = np.array(positions, dtype=float)
        self.velocities = np.array(velocities, dtype=float)
        self.forces = None
        self.configurations = []

    def currentForces(self):
        if self.forces is None:   # forces are evaluated once per configuration, as the integrator does
            self.configurations.append(self.positions.copy())
            self.forces = trap_forces_on_massive(self.positions)
        return self.forces

    def kick(self, h):
        forces = self.currentForces()
        self.velocity = self.velocity + forces[PIN_BODY].sum(axis=0) * h / self.mass
        self.angularMomentum = self.angularMomentum + np.sum(
            np.cross(self.positions[PIN_BODY] - self.centre, forces[PIN_BODY]), axis=0) * h
        self.velocities[self.free] += forces[self.free] * h / PIN_MASSES[self.free, None]

    def drift(self, h):
        self.centre = self.centre + self.velocity * h
        omega = (self.attitude @ self.angularMomentum) / self.moments
        _, self.attitude = FreeRotor(self.moments, omega, self.attitude).evolve(h)
        self.positions[PIN_BODY] = self.centre + self.bodyCoordinates @ self.attitude
        self.positions[self.free] += self.velocities[self.free] * h
        self.positions[5] = SITE_WEIGHTS @ self.positions[PIN_BODY]
        self.forces = None

    def rigidVelocities(self):
        omega = self.attitude.T @ ((self.attitude @ self.angularMomentum) / self.moments)
        self.velocities[PIN_BODY] = self.velocity + np.cross(omega, self.positions[PIN_BODY] - self.centre)
        return self.velocities


def pinned_system():
    """The trap system of the pinning tests, with its two recording PythonForces: (system, recorder of
    the trap, recorder of a second force outside the integration force groups)."""
    system = openmm.System()
    for mass in PIN_MASSES:
        system.addParticle(mass)
    system.setVirtualSite(5, openmm.ThreeParticleAverageSite(0, 1, 2, *SITE_WEIGHTS))
    recorder = Recorder(trap_forces)
    outside = Recorder(lambda positions: np.zeros_like(positions))
    trap, other = openmm.PythonForce(recorder), openmm.PythonForce(outside)
    other.setForceGroup(1)
    system.addForce(trap)
    system.addForce(other)
    return system, recorder, outside


def assert_configurations(evaluated, expected):
    for k, (actual, reference) in enumerate(zip(evaluated, expected)):
        error = np.max(np.abs(actual - reference))
        assert error < 1e-12, f"force evaluation {k}: configuration off by {error:.3g} nm"


@pytest.mark.parametrize("name", list(SPLITTINGS))
@pytest.mark.parametrize("platform", PLATFORMS)
def test_stage_sequence(platform, name):
    """The integrator evaluates the forces at exactly the configurations (to 1e-12 nm), and exactly as
    often (1 + steps x FORCE_EVALUATIONS), as the scheme written out from its paper, and ends in
    the same positions and velocities. The configurations include the virtual site, so a force
    evaluation before the site is placed would show; a second PythonForce outside the integration
    force groups is never evaluated by step()."""
    dt, steps = 0.01, 4
    system, recorder, outside = pinned_system()
    integrator = RigidBodyIntegrator(dt, [PIN_BODY])
    integrator.setSplitting(SPLITTINGS[name])
    integrator.setIntegrationForceGroups({0})
    context = systems.make_context(system, integrator, platform)
    velocities = pin_velocities()
    context.setPositions(PIN_POSITIONS)
    context.setVelocities(velocities)
    recorder.configurations.clear()
    outside.configurations.clear()
    integrator.step(steps)
    evaluated = recorder.configurations

    reference = ReimplementedStep(PIN_POSITIONS, velocities)
    for _ in range(steps):
        for kind, fraction in paper_operations(name):
            getattr(reference, kind)(fraction * dt)
    assert len(evaluated) == 1 + steps * FORCE_EVALUATIONS[name] == len(reference.configurations)
    assert outside.configurations == []
    assert_configurations(evaluated, reference.configurations)
    assert np.max(np.abs(evaluated[-1] - PIN_POSITIONS)) > 0.01  # the test means something only if they moved
    assert np.max(np.abs(systems.positions_of(context) - reference.positions)) < 1e-12
    assert np.max(np.abs(systems.velocities_of(context) - reference.rigidVelocities())) < 1e-11


@pytest.mark.parametrize("name", list(SPLITTINGS))
@pytest.mark.parametrize("platform", PLATFORMS)
def test_bussi_stage_sequence(platform, name):
    """RigidBodyBussiIntegrator runs the same splitting, then rescales every velocity by one factor
    (tau = 2 dt, so the factors differ from 1 by far more than the tolerance): each of 4 steps,
    written out from the state before it, evaluates the forces at the same configurations, as often
    (none again after the rescaling, which moves nothing), and ends at the same positions, with the
    reference's velocities times one common factor (to 1e-11 nm/ps)."""
    dt, steps = 0.01, 4
    system, recorder, outside = pinned_system()
    integrator = RigidBodyBussiIntegrator(300, 2 * dt, dt, [PIN_BODY])
    integrator.setRandomNumberSeed(5)
    integrator.setSplitting(SPLITTINGS[name])
    integrator.setIntegrationForceGroups({0})
    context = systems.make_context(system, integrator, platform)
    context.setPositions(PIN_POSITIONS)
    context.setVelocities(pin_velocities())
    recorder.configurations.clear()
    massive = np.flatnonzero(PIN_MASSES > 0)
    factors = []
    for step in range(steps):
        positions, velocities = systems.positions_of(context), systems.velocities_of(context)
        velocities[5] = SITE_WEIGHTS @ velocities[PIN_BODY]
        start = len(recorder.configurations)
        integrator.step(1)
        reference = ReimplementedStep(positions, velocities)
        if step > 0:  # the forces at the start of this step are those at the end of the last
            reference.forces = trap_forces_on_massive(positions)
        for kind, fraction in paper_operations(name):
            getattr(reference, kind)(fraction * dt)
        evaluated = recorder.configurations[start:]
        assert len(evaluated) == len(reference.configurations) == FORCE_EVALUATIONS[name] + (step == 0)
        assert_configurations(evaluated, reference.configurations)
        assert np.max(np.abs(systems.positions_of(context) - reference.positions)) < 1e-12
        expected, actual = reference.rigidVelocities()[massive], systems.velocities_of(context)[massive]
        factor = np.sum(actual * expected) / np.sum(expected * expected)
        assert np.max(np.abs(actual - factor * expected)) < 1e-11, step
        factors.append(factor)
    assert outside.configurations == []
    assert np.max(np.abs(np.array(factors) - 1)) > 1e-3, factors  # the thermostat did rescale
    assert np.max(np.abs(recorder.configurations[-1] - PIN_POSITIONS)) > 0.01


# ------------------------------------------------------------------------------------------------
# Velocities changed behind the integrator's back
# ------------------------------------------------------------------------------------------------

def rigid_integrator(dt, bodies, name, method=RigidBodyIntegrator.Exact):
    integrator = RigidBodyIntegrator(dt, bodies)
    integrator.setSplitting(SPLITTINGS[name])
    integrator.setRotationMethod(method)
    return integrator


def start(cluster, platform, dt, name, system=None):
    integrator = rigid_integrator(dt, cluster.bodies, name)
    context = systems.make_context(system or cluster.system, integrator, platform)
    context.setPositions(cluster.positions)
    context.setVelocities(cluster.velocities)
    return integrator, context


@pytest.mark.parametrize("name", list(SPLITTINGS))
@pytest.mark.parametrize("platform", PLATFORMS)
def test_cm_motion_remover_changes_nothing_without_net_momentum(platform, name):
    """A CMMotionRemover changes the velocities at the start of every step without telling the
    integrator, which then rebuilds the body momenta from them, once per step. For a cluster with no
    net momentum it changes nothing but rounding: 100 steps of 2 fs with and without it agree to
    1e-9 nm. (Rebuilding at every stage of a step would throw away the earlier stages' kicks.)"""
    cluster = systems.cluster(seed=7, grid=(3, 3, 2))
    cluster.velocities -= cluster.masses @ cluster.velocities / cluster.masses.sum()
    withRemover = openmm.XmlSerializer.clone(cluster.system)
    withRemover.addForce(openmm.CMMotionRemover(1))
    final = []
    for system in (cluster.system, withRemover):
        integrator, context = start(cluster, platform, 0.002, name, system)
        integrator.step(100)
        final.append(systems.positions_of(context))
    difference = np.max(np.abs(final[0] - final[1]))
    assert difference < 1e-9, f"with and without a CMMotionRemover: {difference:.3g} nm apart"
    assert np.max(np.abs(final[0] - cluster.positions)) > 0.05


# ------------------------------------------------------------------------------------------------
# Energy in rigid water
# ------------------------------------------------------------------------------------------------

def test_omelyan2_fluctuates_less_than_verlet_in_water():
    """Rigid TIP3P water (158 molecules, PME, switched cutoff 0.7 nm, with the CMMotionRemover that
    openmm.app adds), 500 steps of 2 fs from the same state on the CPU platform: the rms deviation of
    the total energy about its linear fit is less than half of Verlet's for Omelyan2 (measured 3.4 to
    3.7 times less), as Omelyan, Mryglod and Folk found for their optimized scheme at equal step."""
    box = systems.water_box("tip3p", size=1.7)
    fluctuations = {}
    for name in ("Verlet", "Omelyan2"):
        integrator = RigidBodyIntegrator(0.002)
        integrator.setSplitting(SPLITTINGS[name])
        context = systems.make_context(box.system, integrator, "CPU")
        context.setPositions(box.positions)
        context.setVelocities(box.velocities)
        times, energies = systems.run_energies(context, integrator, 500, 5)
        fluctuations[name] = systems.energy_drift(times, energies)[2]
    assert fluctuations["Omelyan2"] < fluctuations["Verlet"] / 2, fluctuations


# ------------------------------------------------------------------------------------------------
# API and serialization
# ------------------------------------------------------------------------------------------------

def test_constants_and_defaults():
    assert (RigidBodyIntegrator.Verlet, RigidBodyIntegrator.Omelyan2, RigidBodyIntegrator.Yoshida4,
            RigidBodyIntegrator.Omelyan4) == (0, 1, 2, 3)
    for integrator in (RigidBodyIntegrator(0.002), RigidBodyBussiIntegrator(300, 0.1, 0.002)):
        assert integrator.getSplitting() == RigidBodyIntegrator.Verlet
        for name, value in SPLITTINGS.items():
            integrator.setSplitting(value)
            assert integrator.getSplitting() == value
    assert not hasattr(RigidBodyIntegrator(0.002), "getNumForceEvaluations")  # FORCE_EVALUATIONS says it


def test_unknown_splitting():
    integrator = RigidBodyIntegrator(0.002)
    integrator.setSplitting(RigidBodyIntegrator.Omelyan2)
    for bad in (4, -1, 17):
        with pytest.raises(openmm.OpenMMException, match=rf"unknown splitting {bad}\b") as error:
            integrator.setSplitting(bad)
        for name in SPLITTINGS:
            assert f"RigidBodyIntegrator.{name}" in str(error.value)
    with pytest.raises(TypeError):
        integrator.setSplitting("Omelyan2")
    assert integrator.getSplitting() == RigidBodyIntegrator.Omelyan2


@pytest.mark.parametrize("cls", [RigidBodyIntegrator, RigidBodyBussiIntegrator])
@pytest.mark.parametrize("how", systems.COPY_METHODS)
@pytest.mark.parametrize("name", list(SPLITTINGS))
def test_copies_keep_the_splitting(name, how, cls):
    bodies = [[0, 1, 2]]
    original = RigidBodyIntegrator(0.002, bodies) if cls is RigidBodyIntegrator else RigidBodyBussiIntegrator(300, 0.1, 0.002, bodies)
    original.setSplitting(SPLITTINGS[name])
    original.setRotationMethod(RigidBodyIntegrator.NoSquish)
    duplicate = systems.copy_integrator(original, how)
    assert type(duplicate) is cls
    assert duplicate.getSplitting() == SPLITTINGS[name]
    assert duplicate.getRotationMethod() == RigidBodyIntegrator.NoSquish
    assert openmm.XmlSerializer.serialize(duplicate) == openmm.XmlSerializer.serialize(original)


def test_xml_writes_the_splitting():
    integrator = RigidBodyIntegrator(0.002)
    integrator.setSplitting(RigidBodyIntegrator.Yoshida4)
    xml = openmm.XmlSerializer.serialize(integrator)
    assert 'version="5"' in xml and 'splitting="2"' in xml
    bussi = RigidBodyBussiIntegrator(300, 0.1, 0.002)
    bussi.setSplitting(RigidBodyIntegrator.Omelyan4)
    xml = openmm.XmlSerializer.serialize(bussi)
    assert 'type="RigidBodyBussiIntegrator"' in xml and 'version="1"' in xml and 'splitting="3"' in xml
    assert openmmrigid.deserializeIntegrator(xml).getSplitting() == RigidBodyIntegrator.Omelyan4


def test_bad_splitting_in_xml():
    xml = '<?xml version="1.0" ?>\n<Integrator splitting="9" stepSize=".002" type="RigidBodyIntegrator" version="2"/>\n'
    with pytest.raises(openmm.OpenMMException, match="unknown splitting 9"):
        openmmrigid.deserializeIntegrator(xml)
    xml = ('<?xml version="1.0" ?>\n<Integrator collisionTime=".1" splitting="9" stepSize=".002" temperature="300" '
           'type="RigidBodyBussiIntegrator" version="1"/>\n')
    with pytest.raises(openmm.OpenMMException, match="unknown splitting 9"):
        openmmrigid.deserializeIntegrator(xml)

"""The analysis of the accuracy_check and sampling_error studies (benchmarks/studies/) against independent computations:
the accuracy check's window figures on series of known slope and spread, the limits and window against the C++ header,
the run names' integrators, stock-middle's shadow work against velocity Verlet's energy change computed here and, with
constraints, its steps against LangevinMiddleIntegrator's; rigid-mts's frames and draw against its model and the same
integrator without substeps."""

import re
import sys
from pathlib import Path

import numpy as np
import openmm
import pytest

import openmmrigid

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
from studies import accuracy_check, sampling_error  # noqa: E402


def headerConstant(name):
    text = (ROOT/"openmmapi"/"include"/"internal"/"AccuracyCheck.h").read_text()
    match = re.search(r"static constexpr (?:double|int) " + name + r" = ([0-9.eE+-]+);", text)
    assert match, f"{name} not found in AccuracyCheck.h"
    return float(match.group(1))


def test_limits_and_window_are_the_checks_own():
    assert accuracy_check.LIMITS == {"heating": headerConstant("HeatingLimit"), "fluctuation": headerConstant("FluctuationLimit"),
                                     "drift": headerConstant("DriftLimit")}
    assert accuracy_check.CHECK_WINDOW_PS == headerConstant("WindowTime")


def samples(slope, wiggle=0.0):
    """Samples every 0.05 ps over 6 ps (three 2 ps windows of 40): W = slope t + wiggle (+1, -1, -1, +1, ...), a pattern that
    a line fitted to a window leaves whole (its sums with 1 and with t vanish), and K = 1000 +- 10 (mean 1000, std 10)."""
    index = np.arange(120)
    times = 0.05*(index + 1)
    return times, slope*times + wiggle*np.array([1, -1, -1, 1])[index % 4], 1000.0 + 10.0*(-1.0)**index


def test_heating_is_the_shadow_works_slope_over_what_the_thermostat_takes_out():
    dt, friction, dof = 0.004, 1.0, 1500
    figures = accuracy_check.windowFigures(*samples(slope=37.0, wiggle=2.0), dt, friction, dof)
    expected = 2*37.0*dt/((1 - np.exp(-friction*dt)**2)*dof*accuracy_check.KT)
    assert list(figures) == ["heating"]
    np.testing.assert_allclose(figures["heating"], [expected]*3, rtol=1e-9)


def test_fluctuation_and_drift_without_friction():
    figures = accuracy_check.windowFigures(*samples(slope=5.0, wiggle=3.0), 0.004, 0.0, 1500)
    assert sorted(figures) == ["drift", "fluctuation"] and len(figures["drift"]) == 3
    np.testing.assert_allclose(figures["drift"], 5.0/(2*1000.0), rtol=1e-9)     # slope/(dof kT), kT = 2<K>/dof
    np.testing.assert_allclose(figures["fluctuation"], 3.0/10.0, rtol=1e-9)     # std(W - fit)/std(K)


@pytest.mark.parametrize("run, kind, step, splitting, floor", [
    ("L14f1m4", openmmrigid.RigidBodyLangevinIntegrator, 14, None, 0.04),
    ("BO6", openmmrigid.RigidBodyBussiIntegrator, 6, openmmrigid.RigidBodyIntegrator.Omelyan2, 0.0),
    ("BV4", openmmrigid.RigidBodyBussiIntegrator, 4, openmmrigid.RigidBodyIntegrator.Verlet, 0.0),
    ("NVE10", openmmrigid.RigidBodyIntegrator, 10, openmmrigid.RigidBodyIntegrator.Verlet, 0.0)])
def test_run_names_give_their_integrators(run, kind, step, splitting, floor):
    integrator = accuracy_check.makeIntegrator(run)
    assert type(integrator) is kind
    assert integrator.getStepSize().value_in_unit(openmm.unit.femtosecond) == pytest.approx(step)
    assert integrator.getMinimumMomentOfInertia().value_in_unit(openmm.unit.amu*openmm.unit.nanometer**2) == pytest.approx(floor)
    if splitting is not None:
        assert integrator.getSplitting() == splitting
    if kind is openmmrigid.RigidBodyLangevinIntegrator:
        assert integrator.getFriction().value_in_unit(openmm.unit.picosecond**-1) == pytest.approx(1.0)
    if kind is openmmrigid.RigidBodyBussiIntegrator:
        assert integrator.getCollisionTime().value_in_unit(openmm.unit.picosecond) == pytest.approx(1.0)


def test_stock_middle_shadow_work_is_velocity_verlets_energy_change_without_friction(monkeypatch):
    """At zero friction LangevinMiddle's step is leapfrog, whose on-step form is velocity Verlet: the shadow work of a
    protocol, with its ends moved on step, is then the energy change of velocity Verlet from the same start."""
    monkeypatch.setattr(sampling_error.setups, "FRICTION", 0.0)
    n, spring, stepFs, steps, seed = 8, 2000.0, 8.0, 40, 7
    masses = np.linspace(4.0, 20.0, n)
    system, force = openmm.System(), openmm.CustomExternalForce("0.5*k*(x*x + y*y + z*z)")
    force.addGlobalParameter("k", spring)
    for mass in masses:
        force.addParticle(system.addParticle(mass), [])
    system.addForce(force)
    positions = np.random.default_rng(1).normal(0.0, 0.05, (n, 3))
    integrator = sampling_error.makeIntegrator("stock-middle", stepFs, 3, shadow=True)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(positions)
    work = sampling_error.halfProtocol(context, integrator, "stock-middle", steps, seed, masses)

    dt, kT = stepFs*1e-3, sampling_error.KT
    x = positions.copy()
    v = np.random.default_rng(seed).standard_normal((n, 3))*np.sqrt(kT/masses)[:, None]   # halfProtocol's draw
    energy = lambda x, v: 0.5*np.sum(masses[:, None]*v*v) + 0.5*spring*np.sum(x*x)      # noqa: E731
    start = energy(x, v)
    for _ in range(steps):
        v = v - 0.5*dt*spring*x/masses[:, None]
        x = x + dt*v
        v = v - 0.5*dt*spring*x/masses[:, None]
    expected = (energy(x, v) - start)/kT
    assert abs(expected) > 1e-3                 # the step is large enough for a shadow work to measure
    assert work == pytest.approx(expected, rel=1e-6, abs=1e-9)


class QuickEnvironment:
    """What sampling_error's functions take of harness.Environment: a quick run into `folder` (hashable, as frames() needs), on
    Reference, whose results are the same at every run (the CPU platform's sums in single precision and thread order are not:
    the comparisons below would hold only most of the time there)."""

    def __init__(self, folder, system, frames):
        self.quick, self.folder, self.properties = True, folder, {}
        self.platform = openmm.Platform.getPlatformByName("Reference")
        self.study = type("Grid", (), {"jobs": staticmethod(lambda quick: [({"system": system}, list(range(frames)))])})


def test_rigid_mts_on_the_villin_twin_samples_its_own_model(tmp_path, monkeypatch):
    """The quick run's twin of villin-planar (the dipeptide): its frames are the integrator's model (the same bodies, each of
    one shape in every frame); a draw is Maxwell-Boltzmann on step with substeps (the on-step kinetic energy of the same draw
    for the integrator without them), and the KL at 2 fs (8 frames, 0.2 ps halves) is within three errors of 0."""
    from rigidtesting.bodies import _whole, integratorBodies
    monkeypatch.setattr(sampling_error.setups, "RESULTS", tmp_path)   # its starting state too
    frames, name = 8, "dipeptide-planar"
    env = QuickEnvironment(tmp_path, name, frames)
    built, bodies, frame = sampling_error.frames(name, frames, env)
    assert sum(map(len, bodies)) > sum(map(len, sampling_error.model("dipeptide-xh")[1]))   # the peptide groups' C and O too
    masses = np.where(built.masses > 0, built.masses, np.inf)
    integrator = sampling_error.makeIntegrator("rigid-mts", 12, 3, shadow=True, bodies=bodies)
    context = openmm.Context(built.system, integrator, env.platform, env.properties)
    context.setState(frame(0))
    assert [list(body) for body in integratorBodies(integrator)] == [list(body) for body in bodies]
    assert [tuple(pair) for pair in integrator.getForceGroupSubsteps()] == [(0, 1), (1, 12)]
    box = np.asarray(frame(0).getPeriodicBoxVectors(asNumpy=True)._value)
    shape = lambda x: np.concatenate([np.linalg.norm(whole[:, None] - whole[None], axis=-1).ravel()   # noqa: E731
                                      for whole in (_whole(x[body], box) for body in bodies)])   # the distances in each body
    first, last = (shape(np.asarray(frame(i).getPositions(asNumpy=True)._value)) for i in (0, frames - 1))
    assert np.abs(first - last).max() < 1e-5   # nm: rigid (the flexible model's move by ~0.01)

    plain = sampling_error.setups.makeIntegrator("rigid-langevin", 12, 3, floor=sampling_error.XH_FLOOR, bodies=bodies)
    reference = openmm.Context(built.system, plain, env.platform, env.properties)
    reference.setState(frame(0))
    reference.setVelocitiesToTemperature(sampling_error.setups.TEMPERATURE, 5)
    assert sampling_error.halfProtocol(context, integrator, "rigid-mts", 0, 5, masses) == 0.0   # the draw alone
    assert integrator.getOnStepKineticEnergy()._value == pytest.approx(plain.getOnStepKineticEnergy()._value, rel=1e-7)

    works = [sampling_error.measure(dict(system=name, integrator="rigid-mts", step=2, seed=i), env) for i in range(frames)]
    kl, error = sampling_error.configurationKL(*np.array(works).T)
    assert 0 < error < 0.5 and abs(kl) < 3*error   # kT


def test_stock_middle_is_langevin_middle_with_constraints_and_a_motion_remover(tmp_path, monkeypatch):
    """On the quick run's twin of villin-hmr (HMR, HBonds, SETTLE, a CMMotionRemover) at zero friction stock-middle's steps are
    LangevinMiddleIntegrator's (whose velocities lag half a kick): its sums change no trajectory, and its shadow work is the
    change of K + U with on-step velocities less the starting centre-of-mass motion the remover takes out (no work; before,
    it was summed)."""
    monkeypatch.setattr(sampling_error.setups, "RESULTS", tmp_path)
    monkeypatch.setattr(sampling_error.setups, "FRICTION", 0.0)
    built, _ = sampling_error.model("dipeptide-hmr")
    platform, properties, steps, seed = openmm.Platform.getPlatformByName("Reference"), {}, 20, 4   # the same at every run
    start = sampling_error.setups.start("dipeptide", built, platform, properties, 0.2)
    middle = sampling_error.makeIntegrator("stock-middle", 2, 3, shadow=True)
    stock = openmm.LangevinMiddleIntegrator(300, 0, 0.002)
    contexts = [sampling_error.setups.context(built, each, start, platform, properties) for each in (middle, stock)]
    for each in (middle, stock):
        each.setConstraintTolerance(1e-10)
    energy = lambda context: context.getState(getEnergy=True).getPotentialEnergy()._value + 0.5*np.sum(   # noqa: E731
        built.masses[:, None]*context.getState(getVelocities=True).getVelocities(asNumpy=True)._value**2)
    masses = np.where(built.masses > 0, built.masses, np.inf)
    drawn = np.random.default_rng(seed).standard_normal((len(masses), 3))*np.sqrt(sampling_error.KT/masses)[:, None]
    contexts[0].setVelocities(drawn)   # halfProtocol's draw, on step
    contexts[0].applyVelocityConstraints(1e-10)
    state = contexts[0].getState(getVelocities=True, getForces=True)
    v, f = state.getVelocities(asNumpy=True)._value, state.getForces(asNumpy=True)._value
    contexts[1].setVelocities(v - 0.001*f/masses[:, None])
    contexts[1].applyVelocityConstraints(1e-10)
    before, motion = energy(contexts[0]), 0.5*np.sum((built.masses @ v)**2)/built.masses.sum()
    work = sampling_error.halfProtocol(contexts[0], middle, "stock-middle", steps, seed, masses)
    stock.step(steps)
    x = [context.getState(getPositions=True).getPositions(asNumpy=True)._value for context in contexts]
    assert np.abs(x[0] - x[1]).max() < 1e-6   # nm
    assert work*sampling_error.KT == pytest.approx(energy(contexts[0]) - before + motion, abs=1e-3)   # kJ/mol

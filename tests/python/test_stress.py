"""Stability stress tests of RigidBodyIntegrator: the fast subset of benchmarks/studies/stress.py, on small
versions of its scenarios (built in rigidtesting.stress). Every run is checked for

- finiteness: no NaN or infinity in positions, velocities or energy, and no exception;
- rigidity: no distance within a body changes by more than 1e-12 nm (absolute: the bodies are 0.1
  to 0.5 nm across and lie within a few nm of the origin, where double rounding is about 1e-15 nm);
- conservation: where the forces sum to zero (the Lennard-Jones pair forces, double precision on
  both platforms), total linear momentum to 1e-10 relative (every scenario drifts), and in an
  isolated system total angular momentum to 1e-10 relative; with PME, the change of momentum over
  each step equals the impulse of the net force;
- energy: the largest |E(t) - E(0)| over a fixed time falls by 4 +- 1 when the step halves (second
  order; a first-order error, such as kick and drift of inconsistent lengths, gives 2), and at the
  smaller step it is below 1e-3 of the kinetic energy;

and each test checks that its scenario is what it claims (the extreme moments, the separatrix
crossings, the spin) so that it cannot pass by testing nothing.
"""

import numpy as np
import openmm.unit as unit
import pytest

import systems
from rigidtesting import stress
from rigidtesting.bodies import bodyKind, principalMoments

PLATFORMS = ["Reference", "CPU"]
METHODS = ["Exact", "NoSquish"]

RIGIDITY_TOLERANCE = 1e-12    # nm
MOMENTUM_TOLERANCE = 1e-10    # relative
IMPULSE_TOLERANCE = 1e-10     # of the summed |F| dt
ORDER_RATIO, ORDER_SPREAD = 4.0, 1.0
CONVERGED_ENERGY = 1e-3       # of the kinetic energy, at the smaller step
FREE_TOLERANCE = 1e-12        # relative: the exact free rotor's invariants, and rad per rad turned


def check_run(scenario, run):
    """Finite, rigid, and the momenta that the forces conserve are conserved; a rigid-body
    integrator's temperature counts the degrees of freedom of its bodies (2 KE / (dof kB), dof from
    rigidtesting.bodies: a linear body rotates about two axes, a point about none)."""
    where = f"{scenario.name}, dt = {run.stepSize} ps"
    assert run.error is None and run.finite, f"{where}: not finite after {run.steps} steps ({run.error})"
    assert run.rigidity <= RIGIDITY_TOLERANCE, f"{where}: a distance within a body changed by {run.rigidity:.3g} nm"
    if scenario.forcesSumToZero:
        change = run.relative_momentum_change()
        assert change <= MOMENTUM_TOLERANCE, f"{where}: total momentum changed by {change:.3g} (relative)"
    angular = run.relative_angular_change()
    if angular is not None:
        assert angular <= MOMENTUM_TOLERANCE, f"{where}: total angular momentum changed by {angular:.3g} (relative)"
    kinetic = run.context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    temperature = run.integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    assert temperature == pytest.approx(2 * kinetic / (run.dof * stress.BOLTZMANN), rel=1e-9), where


def second_order_runs(scenario, platform, method, dt, duration, samples=40):
    """Runs at dt and dt/2 over the same time, sampled at the same times; checks each run and that
    the energy error is second order and converged. Returns both runs."""
    steps = round(duration / dt)
    interval = max(1, steps // samples)
    coarse = stress.run(scenario, scenario.integrator(dt, method), platform, steps, interval)
    fine = stress.run(scenario, scenario.integrator(dt / 2, method), platform, 2 * steps, 2 * interval)
    for run in (coarse, fine):
        check_run(scenario, run)
    errors = coarse.max_energy_change(), fine.max_energy_change()
    report = (f"{scenario.name}, {method} on {platform}: max |E - E(0)| {errors[0]:.3g} kJ/mol at {dt} ps, "
              f"{errors[1]:.3g} at {dt / 2} ps, kinetic energy {fine.kinetic0:.4g} kJ/mol")
    print(report)
    assert errors[1] > 0.0, report
    assert abs(errors[0] / errors[1] - ORDER_RATIO) <= ORDER_SPREAD, report
    assert errors[1] <= CONVERGED_ENERGY * fine.kinetic0, report
    return coarse, fine


# ------------------------------------------------------------------------------------------------
# Extreme shapes in a hot Lennard-Jones bath
# ------------------------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def baths():
    return {periodic: stress.bodies_in_bath(copies=2, bathAtoms=40, temperature=2000.0, periodic=periodic, seed=3,
                                            spin=0.0 if periodic else 1.0)
            for periodic in (True, False)}


def check_shapes(scenario, run, copies):
    """The bodies are what the scenario says (EXTREME_SHAPES, `copies` of each, in order): their
    principal moments and kinds from the particles (rigidtesting.bodies), the bodies the integrator
    moves being the scenario's."""
    integrator = run.integrator
    assert [list(integrator.getBodyParticles(b)) for b in range(integrator.getNumBodies())] == scenario.bodies
    moments = [principalMoments(scenario.masses[body], scenario.positions[body]) for body in scenario.bodies]
    kinds = [bodyKind(scenario.masses[body], scenario.positions[body]) for body in scenario.bodies]
    rod, nearSpherical, nearSymmetric, linear = moments[0], moments[copies], moments[2 * copies], moments[3 * copies]
    assert abs(rod[0] / rod[2] / 1e-6 - 1) < 0.01, rod
    assert 0.5e-9 < (nearSpherical[1] - nearSpherical[0]) / nearSpherical[2] < 3e-9, nearSpherical
    assert 0.5e-9 < (nearSpherical[2] - nearSpherical[1]) / nearSpherical[2] < 3e-9, nearSpherical
    assert 0.5e-9 < (nearSymmetric[2] - nearSymmetric[1]) / nearSymmetric[2] < 3e-9, nearSymmetric
    assert kinds[::copies] == ["asymmetric", "asymmetric", "asymmetric", "linear", "asymmetric"], kinds
    assert run.kinds == ["asymmetric", "linear"]
    assert linear[0] < 1e-12 * linear[2], linear


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("platform", PLATFORMS)
@pytest.mark.parametrize("periodic", [True, False], ids=["periodic", "isolated"])
def test_extreme_bodies_in_hot_bath(baths, periodic, platform, method):
    """A rod with principal moments 1e6 apart, near-spherical and near-symmetric tops (moments 1e-9
    apart), linear and bent triatomics among argon at 2000 K, kicked across the separatrix."""
    scenario = baths[periodic]
    coarse, fine = second_order_runs(scenario, platform, method, 0.002, 0.3)
    check_shapes(scenario, fine, copies=2)
    if periodic:
        # The isolated cluster flies apart; in the box the collisions go on.
        assert np.sum(fine.crossings) >= 2, f"separatrix crossings per body: {fine.crossings}"


# ------------------------------------------------------------------------------------------------
# 5000 K
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("platform", PLATFORMS)
def test_hot_cluster(platform, method):
    """systems.cluster() at 5000 K: every body kind (asymmetric, symmetric, spherical, linear, point),
    free ions, Lennard-Jones + Coulomb; isolated, drifting and spinning."""
    scenario = stress.hot_cluster(5000.0, seed=2)
    coarse, fine = second_order_runs(scenario, platform, method, 0.001, 0.2)
    assert fine.kinds == ["asymmetric", "linear", "point", "spherical", "symmetric"]
    assert np.sum(fine.crossings) >= 10, f"separatrix crossings per body: {fine.crossings}"


@pytest.fixture(scope="module")
def hot_water():
    return stress.water("tip4pew", size=1.5, temperature=5000.0)


@pytest.mark.parametrize("method", METHODS)
def test_hot_water(hot_water, method):
    """TIP4P-Ew (with its virtual site) at 5000 K, PME, on the CPU platform (PME on Reference is too
    slow for this file): rigid to 1e-12 nm after the first step, second-order energy error."""
    second_order_runs(hot_water, "CPU", method, 0.001, 0.1, samples=20)


def test_hot_water_momentum_is_impulse_of_net_force(hot_water):
    """PME forces do not sum to zero; the momentum must still change by exactly the impulse of the
    net force, dt (F_n + F_n+1) / 2 per step, the virtual sites' forces passed on to the waters.
    On Reference only: the CPU platform's float forces, recomputed for a State, may differ from
    those its step used by a rounding (stock VerletIntegrator shows the same)."""
    integrator = hot_water.integrator(0.001)
    context = systems.make_context(hot_water.system, integrator, "Reference")
    context.setPositions(hot_water.positions)
    context.setVelocities(hot_water.velocities)
    integrator.step(1)  # the first step projects the starting positions onto the bodies' shapes
    mismatch = stress.impulse_mismatch(context, hot_water.masses, 10)
    assert mismatch <= IMPULSE_TOLERANCE, f"momentum differs from the impulse by {mismatch:.3g} of the summed |F| dt"


def test_water_at_large_step():
    """TIP3P at 300 K with 7 fs steps, the largest with which benchmarks/studies/stress.py finds 500 waters
    within 5 % of their kinetic energy over 20 ps (8 fs passes its 1 ps scan and then heats by 10 %):
    finite, rigid, within that 5 % over 0.5 ps."""
    scenario = stress.water("tip3p", size=1.5)
    for method in METHODS:
        run = stress.run(scenario, scenario.integrator(0.007, method), "CPU", 72, 8)
        check_run(scenario, run)
        change = run.max_energy_change()
        assert change <= 0.05 * run.kinetic0, f"{method}: max |E - E(0)| {change:.3g} kJ/mol, KE {run.kinetic0:.4g}"


# ------------------------------------------------------------------------------------------------
# |omega| = 1e4 / ps
# ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("platform", PLATFORMS)
def test_fast_spin_alone_is_exact(platform):
    """No forces, 500 steps of 2 fs (omega dt = 20 rad, 1e4 rad in all): Exact keeps the body's energy
    to 1e-12 relative and follows its exact free motion (FreeRotor from its starting state) to 1e-12
    rad per radian turned (the frequency is known to the rounding of the energy, so the angle's error
    grows with the angle)."""
    scenario = stress.spinning_body(omega=1e4)
    run = stress.run(scenario, scenario.integrator(0.002), platform, 500, 50)
    check_run(scenario, run)
    assert run.max_energy_change() <= FREE_TOLERANCE * run.kinetic0
    exact = systems.rigid_motion(scenario.masses, scenario.positions, scenario.velocities, scenario.bodies,
                                 scenario.free)
    expectedPositions, expectedVelocities = exact(1.0)
    centre = scenario.masses @ scenario.positions / scenario.masses.sum()
    radius = np.max(np.linalg.norm(scenario.positions - centre, axis=1))
    speed = np.max(np.linalg.norm(expectedVelocities, axis=1))
    assert speed > 0.5e4 * radius  # it does spin that fast
    angle = max(np.max(np.abs(systems.positions_of(run.context) - expectedPositions)) / radius,
                np.max(np.abs(systems.velocities_of(run.context) - expectedVelocities)) / speed)
    assert angle <= FREE_TOLERANCE * 1e4, f"off the exact motion by {angle:.3g} rad after 1e4 rad"


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("platform", PLATFORMS)
def test_fast_spin_in_bath(platform, method):
    """The spinning body among 60 argon atoms (omega dt = 0.2 and 0.1 rad): second order for both
    methods. Exact's free rotation conserves the spin's energy exactly, so its error is that of the
    bath's motion: below 1e-3 of the bath's kinetic energy, though the spin holds a thousand times more."""
    scenario = stress.spinning_body(omega=1e4, bathAtoms=60)
    coarse, fine = second_order_runs(scenario, platform, method, 2e-5, 0.01)
    if method == "Exact":
        bath = scenario.free
        bathKinetic = 0.5 * np.sum(scenario.masses[bath, None] * scenario.velocities[bath] ** 2)
        assert fine.kinetic0 > 1000 * bathKinetic
        assert coarse.max_energy_change() <= CONVERGED_ENERGY * bathKinetic, \
            f"max |E - E(0)| {coarse.max_energy_change():.3g} kJ/mol, bath kinetic energy {bathKinetic:.4g}"

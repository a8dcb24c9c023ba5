"""Physics of openmmrigid.RigidBodyIntegrator through the Python API: one smoke run per claim.

The claims are tested in C++ (tests/TestRigidBodyIntegrator.h, on the Reference, CPU and OpenCL
platforms, for every splitting and rotation method); here each is run once, on one platform, from
systems built in Python (systems.py, with openmm.app where a user would use it), with the units and
exceptions a Python user sees:

- no forces: one step of 25 ps equals the exact free motion (openmmrigid.FreeRotor, straight lines);
- second order: the error at 0.1 ps falls by 4 +- 0.5 when the step halves;
- time reversal: n steps, velocities negated, n steps back to the start within 1e-8 nm;
- total linear and angular momentum of an isolated cluster conserved to 1e-10 relative;
- a box of rigid TIP4P-Ew water built by openmm.app drifts no more than VerletIntegrator + SETTLE
  from the same state, and fluctuates no more;
- a mixed system (alanine dipeptide with HBonds constraints, rigid water, benzene, CO2 and a
  single-particle body) conserves energy, keeps its bodies rigid and its constraints;
- bad input raises openmm.OpenMMException naming the particle or body, and leaves a usable Context.

The small-cluster tests use pair forces evaluated in double precision (see systems.py); the water
and mixed systems use OpenMM's NonbondedForce with PME as a user would.
"""

import re

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import systems
from openmmrigid import RigidBodyIntegrator
from rigidtesting import particleMasses
from rigidtesting.bodies import bodyKind, rigidDegreesOfFreedom

# One platform per claim: the C++ suites run each on Reference, CPU and OpenCL.
PLATFORM = "Reference"
METHODS = {"Exact": RigidBodyIntegrator.Exact, "NoSquish": RigidBodyIntegrator.NoSquish}

FREE_MOTION_TOLERANCE = 1e-12      # nm, and nm/ps for velocities
REVERSAL_TOLERANCE = 1e-8          # nm
MOMENTUM_TOLERANCE = 1e-10         # relative
RIGIDITY_TOLERANCE = 1e-12         # nm, change of any distance within a body
ORDER_RATIO, ORDER_RATIO_SPREAD = 4.0, 0.5


def rigid_integrator(dt, bodies=None, method="Exact"):
    integrator = RigidBodyIntegrator(dt) if bodies is None else RigidBodyIntegrator(dt, bodies)
    integrator.setRotationMethod(METHODS[method])
    return integrator


start = systems.start_context


def run_cluster(cluster, platform, dt, steps, method="Exact"):
    integrator = rigid_integrator(dt, cluster.bodies, method)
    context = start(cluster.system, integrator, platform, cluster.positions, cluster.velocities)
    integrator.step(steps)
    return systems.positions_of(context), systems.velocities_of(context)


def rms(a, b):
    return np.sqrt(np.mean(np.sum((np.asarray(a) - np.asarray(b)) ** 2, axis=1)))


# ------------------------------------------------------------------------------------------------
# Free motion
# ------------------------------------------------------------------------------------------------

def test_free_motion_single_large_step(platform=PLATFORM):
    """One step of 25 ps equals the exact motion (no error builds up with the step size)."""
    cluster = systems.cluster(seed=4, grid=(2, 2, 2), forces=False)
    exact = systems.rigid_motion(cluster.masses, cluster.positions, cluster.velocities, cluster.bodies, cluster.free)
    integrator = rigid_integrator(25.0, cluster.bodies)
    context = start(cluster.system, integrator, platform, cluster.positions, cluster.velocities)
    integrator.step(1)
    expectedPositions, expectedVelocities = exact(25.0)
    assert np.max(np.abs(systems.positions_of(context) - expectedPositions)) < FREE_MOTION_TOLERANCE
    speed = np.max(np.linalg.norm(cluster.velocities, axis=1))
    assert np.max(np.abs(systems.velocities_of(context) - expectedVelocities)) < FREE_MOTION_TOLERANCE * speed


# ------------------------------------------------------------------------------------------------
# Order, reversibility, momentum
# ------------------------------------------------------------------------------------------------

ORDER_TIME = 0.1           # ps
ORDER_STEPS = (0.001, 0.0005)
ORDER_REFERENCE_STEP = 0.0005 / 16


@pytest.fixture(scope="module")
def interacting_cluster():
    return systems.cluster(seed=7, grid=(3, 3, 2))


_referenceRuns = {}


def reference_run(cluster, platform, method):
    key = (platform, method)
    if key not in _referenceRuns:
        _referenceRuns[key] = run_cluster(cluster, platform, ORDER_REFERENCE_STEP,
                                          round(ORDER_TIME / ORDER_REFERENCE_STEP), method)
    return _referenceRuns[key]


def test_second_order(interacting_cluster, platform=PLATFORM, method="Exact"):
    """The error at t = 0.1 ps falls by 4 +- 0.5 when the step halves (1 fs -> 0.5 fs)."""
    referencePositions, referenceVelocities = reference_run(interacting_cluster, platform, method)
    errors = []
    for dt in ORDER_STEPS:
        positions, velocities = run_cluster(interacting_cluster, platform, dt, round(ORDER_TIME / dt), method)
        errors.append(rms(positions, referencePositions))
    ratio = errors[0] / errors[1]
    assert abs(ratio - ORDER_RATIO) < ORDER_RATIO_SPREAD, \
        f"position errors {errors[0]:.3g} nm (1 fs), {errors[1]:.3g} nm (0.5 fs): ratio {ratio:.3f}"


def test_time_reversible(interacting_cluster, platform=PLATFORM, method="Exact"):
    """200 steps of 2 fs, velocities negated, 200 steps: back at the start within 1e-8 nm."""
    integrator = rigid_integrator(0.002, interacting_cluster.bodies, method)
    context = start(interacting_cluster.system, integrator, platform, interacting_cluster.positions,
                    interacting_cluster.velocities)
    integrator.step(200)
    moved = np.max(np.abs(systems.positions_of(context) - interacting_cluster.positions))
    assert moved > 0.05  # the test means something only if the molecules went somewhere
    context.setVelocities(-systems.velocities_of(context))
    integrator.step(200)
    error = np.max(np.abs(systems.positions_of(context) - interacting_cluster.positions))
    assert error < REVERSAL_TOLERANCE, f"returned within {error:.3g} nm of the start"
    velocityError = np.max(np.abs(systems.velocities_of(context) + interacting_cluster.velocities))
    assert velocityError < REVERSAL_TOLERANCE / 0.002 * 0.1


def test_momentum_conserved(platform=PLATFORM, method="Exact"):
    """An isolated cluster that drifts and spins keeps its total linear and angular momentum to 1e-10."""
    cluster = systems.cluster(seed=9, grid=(3, 3, 2), drift=(0.3, -0.2, 0.1), spin=1.5)
    integrator = rigid_integrator(0.002, cluster.bodies, method)
    context = start(cluster.system, integrator, platform, cluster.positions, cluster.velocities)
    masses = cluster.masses[:, None]

    def momenta():
        r, v = systems.positions_of(context), systems.velocities_of(context)
        return np.sum(masses * v, axis=0), np.sum(masses * np.cross(r, v), axis=0)

    linear0, angular0 = momenta()
    for block in range(5):
        integrator.step(100)
        linear, angular = momenta()
        linearError = np.linalg.norm(linear - linear0) / np.linalg.norm(linear0)
        angularError = np.linalg.norm(angular - angular0) / np.linalg.norm(angular0)
        assert linearError < MOMENTUM_TOLERANCE, f"after {100 * (block + 1)} steps: P off by {linearError:.3g}"
        assert angularError < MOMENTUM_TOLERANCE, f"after {100 * (block + 1)} steps: L off by {angularError:.3g}"


# ------------------------------------------------------------------------------------------------
# Energy conservation: rigid water side by side with VerletIntegrator + SETTLE
# ------------------------------------------------------------------------------------------------

# Steps per platform (blocks of 50 and 100 steps for the drift's standard error). The C++ suite runs
# the drift comparison for 2000 steps on CPU, with both rotation methods; this is the run of a box
# built with openmm.app.
WATER_STEPS = {"Reference": 400, "CPU": 2000}
WATER_BLOCKS = {"Reference": 8, "CPU": 20}
WATER_INTERVAL, WATER_DT = 5, 0.002
DRIFT_SIGMAS = 3.0
FLUCTUATION_GUARD = 1.5


@pytest.fixture(scope="module")
def water_boxes():
    return {}


def water_box(boxes, model):
    if model not in boxes:
        boxes[model] = systems.water_box(model)
    return boxes[model]


_verletRuns = {}


def verlet_energies(box, model, platform):
    key = (model, platform)
    if key not in _verletRuns:
        integrator = openmm.VerletIntegrator(WATER_DT)
        context = start(box.system, integrator, platform, box.positions, box.velocities)
        _verletRuns[key] = (systems.run_energies(context, integrator, WATER_STEPS[platform], WATER_INTERVAL),
                            context.getState(getEnergy=True).getPotentialEnergy())
    return _verletRuns[key]


def test_water_energy_no_worse_than_verlet_settle(water_boxes, platform="CPU", model="tip4pew", method="Exact"):
    """NVE at 2 fs from the same state over the same steps: the rigid integrator's energy drift
    (slope of the line through block means of E(t)) is no larger than VerletIntegrator + SETTLE's,
    within three combined standard errors of the two slopes. (Over 32 ps on the CPU platform the two
    drift by less than 10 kJ/mol/ns; a few hundred steps resolve only drifts of some hundreds.) The fluctuation about the fitted line is at most 1.5
    times Verlet's: not a claim that it is smaller, a guard against gross errors (a missing torque
    or virtual-site force shows up there first)."""
    box = water_box(water_boxes, model)
    (verletTimes, verletEnergies), _ = verlet_energies(box, model, platform)
    integrator = rigid_integrator(WATER_DT, None, method)
    context = start(box.system, integrator, platform, box.positions, box.velocities)
    assert integrator.getNumBodies() == len(list(box.topology.residues()))
    # The same start: the rigid Context projects the positions onto the bodies at once, which moves
    # them by no more than the box's constraint error (CPU SETTLE: a few 1e-9 nm), and those positions
    # give Verlet the same potential energy. (Total energies differ at t = 0: VerletIntegrator reads
    # the velocities as half a step behind, this integrator as on-step.)
    projected = systems.positions_of(context)
    assert np.max(np.abs(projected - box.positions)) < 1e-7
    potential0 = context.getState(getEnergy=True).getPotentialEnergy()
    verletPotential0 = start(box.system, openmm.VerletIntegrator(WATER_DT), platform, projected,
                             box.velocities).getState(getEnergy=True).getPotentialEnergy()
    assert abs((potential0 - verletPotential0).value_in_unit(unit.kilojoule_per_mole)) < 1e-6
    times, energies = systems.run_energies(context, integrator, WATER_STEPS[platform], WATER_INTERVAL)
    rigidSlope, rigidError = systems.block_drift(times, energies, WATER_BLOCKS[platform])
    verletSlope, verletError = systems.block_drift(verletTimes, verletEnergies, WATER_BLOCKS[platform])
    rigidFluctuation = systems.energy_drift(times, energies)[2]
    verletFluctuation = systems.energy_drift(verletTimes, verletEnergies)[2]
    report = (f"{model} {method} on {platform}: rigid {1000 * rigidSlope:.0f} +- {1000 * rigidError:.0f} kJ/mol/ns "
              f"(rms {rigidFluctuation:.3f} kJ/mol), Verlet+SETTLE {1000 * verletSlope:.0f} +- {1000 * verletError:.0f} "
              f"kJ/mol/ns (rms {verletFluctuation:.3f} kJ/mol), {WATER_STEPS[platform]} steps")
    print(report)
    allowance = DRIFT_SIGMAS * np.hypot(rigidError, verletError)
    assert abs(rigidSlope) <= abs(verletSlope) + allowance, report
    assert rigidFluctuation <= FLUCTUATION_GUARD * verletFluctuation, report


# ------------------------------------------------------------------------------------------------
# A mixed system
# ------------------------------------------------------------------------------------------------

MIXED_STEPS, MIXED_INTERVAL, MIXED_TOLERANCE = 300, 5, 1e-6


@pytest.fixture(scope="module")
def mixed():
    return systems.mixed_system()


def pair_distances(positions, indices):
    x = positions[indices]
    return np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1)


def test_mixed_system(mixed, platform="CPU"):
    """Alanine dipeptide (free, HBonds constraints) in rigid water with a rigid benzene, a rigid CO2,
    a Na+ body and a free Cl-: bodies rigid to 1e-12 nm, constraints within the tolerance (positions
    and velocities), energy within 0.002 kT per degree of freedom of its start and without a drift
    larger than twice its own statistical error plus that budget over the run."""
    bodies = mixed.waters + [mixed.benzene, mixed.co2, mixed.sodium]
    integrator = rigid_integrator(0.002, bodies)
    integrator.setConstraintTolerance(MIXED_TOLERANCE)
    context = start(mixed.system, integrator, platform, mixed.positions, mixed.velocities)
    masses = particleMasses(mixed.system)
    kinds = [bodyKind(masses[body], mixed.positions[body]) for body in bodies]
    assert kinds[-3:] == ["symmetric", "linear", "point"]
    # The integrator moves them so: its temperature counts 2 rotational degrees of freedom for the
    # CO2, none for the Na+.
    dof = rigidDegreesOfFreedom(context, integrator)
    kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert integrator.computeSystemTemperature().value_in_unit(unit.kelvin) == pytest.approx(
        2 * kinetic / (dof * systems.BOLTZMANN), rel=1e-9)
    times, energies = systems.run_energies(context, integrator, MIXED_STEPS, MIXED_INTERVAL)
    positions, velocities = systems.positions_of(context), systems.velocities_of(context)
    assert np.all(np.isfinite(positions))

    for body in bodies:
        change = np.max(np.abs(pair_distances(positions, body) - pair_distances(mixed.positions, body)))
        assert change < RIGIDITY_TOLERANCE, f"body {body}: a distance changed by {change:.3g} nm"

    inBody = set(i for body in bodies for i in body)
    checked = 0
    for k in range(mixed.system.getNumConstraints()):
        i, j, distance = mixed.system.getConstraintParameters(k)
        distance = distance.value_in_unit(unit.nanometer)
        if i in inBody or j in inBody:
            continue
        checked += 1
        delta = positions[i] - positions[j]
        length = np.linalg.norm(delta)
        assert abs(length / distance - 1) <= MIXED_TOLERANCE, f"constraint {k} ({i}-{j}): {length} nm, not {distance}"
        rate = np.dot(delta, velocities[i] - velocities[j]) / length
        assert abs(rate) <= MIXED_TOLERANCE * 10.0, f"constraint {k} ({i}-{j}): length changes at {rate} nm/ps"
    assert checked == 12  # the peptide's bonds to hydrogen

    budget = 0.002 * systems.BOLTZMANN * 300.0 * dof
    slope, error, fluctuation = systems.energy_drift(times, energies)
    report = (f"mixed on {platform}: {dof} dof, drift {1000 * slope:.0f} +- {1000 * error:.0f} kJ/mol/ns, rms "
              f"{fluctuation:.3f} kJ/mol, max |E - E(0)| {np.max(np.abs(energies - energies[0])):.3f}, budget {budget:.3f} kJ/mol")
    print(report)
    assert np.max(np.abs(energies - energies[0])) < budget, report
    assert abs(slope) * times[-1] < budget + 2.0 * error * times[-1], report


# ------------------------------------------------------------------------------------------------
# Bad input
# ------------------------------------------------------------------------------------------------

def small_system(numParticles=6):
    system = openmm.System()
    for _ in range(numParticles):
        system.addParticle(1.0)
    return system


SMALL_POSITIONS = np.array([[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.0, 0.12, 0.0],
                            [0.5, 0.5, 0.5], [0.6, 0.5, 0.5], [0.5, 0.65, 0.55]])


def names(message, *indices):
    """Whether message names one of the given particle or body indices."""
    return any(re.search(rf"\b{index}\b", message) for index in indices) and \
        re.search(r"particle|body", message, re.IGNORECASE)


def expect_context_error(system, bodies, platform, *indices):
    with pytest.raises(openmm.OpenMMException) as error:
        integrator = RigidBodyIntegrator(0.001, bodies)
        context = systems.make_context(system, integrator, platform)
        context.setPositions(SMALL_POSITIONS[:system.getNumParticles()])
        integrator.step(1)
    assert names(str(error.value), *indices), str(error.value)
    return str(error.value)


def test_particle_in_two_bodies(platform=PLATFORM):
    expect_context_error(small_system(), [[0, 1, 2], [2, 3, 4]], platform, 2)


def test_nan_positions(platform=PLATFORM):
    """NaN coordinates: step() raises naming the particle or its body; valid positions make the
    Context usable again, and it then moves exactly as a fresh one would."""
    system = small_system()
    bodies = [[0, 1, 2], [3, 4]]
    velocities = np.zeros((6, 3))
    velocities[:, 0] = 0.5
    integrator = RigidBodyIntegrator(0.01, bodies)
    context = systems.make_context(system, integrator, platform)
    context.setPositions(SMALL_POSITIONS)
    context.setVelocities(velocities)
    integrator.step(2)
    bad = SMALL_POSITIONS.copy()
    bad[4, 1] = np.nan
    context.setPositions(bad)
    with pytest.raises(openmm.OpenMMException) as error:
        integrator.step(1)
    assert names(str(error.value), 4, 1), str(error.value)
    context.setPositions(SMALL_POSITIONS)
    context.setVelocities(velocities)
    context.setTime(0.0)
    integrator.step(10)
    positions = systems.positions_of(context)
    assert np.all(np.isfinite(positions))
    assert np.max(np.abs(positions - (SMALL_POSITIONS + 0.1 * velocities))) < 1e-12

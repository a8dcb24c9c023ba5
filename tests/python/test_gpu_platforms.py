"""The rigid-body integrators on the GPU platforms present (OpenCL through PoCL on a machine without a
GPU, CUDA where there is one), in single, mixed and double precision, against the Reference platform.

The Reference platform's trajectories are checked against the exact free rotor, ODE integrations and
stock OpenMM elsewhere; here every GPU platform must reproduce them, to what its precision allows:
free motion to 1e-10 nm in double and mixed precision (the bodies' state is double on the device in
every mode; mixed precision keeps positions as float plus a float correction), the same Langevin and
Bussi trajectories from the same seed (the random numbers are the same counter-based streams on every
platform), time reversibility, runs past the atom reordering of a periodic box, and checkpoints that
continue bit for bit where the platform promises deterministic forces (CUDA with DeterministicForces,
set by platform_and_properties; OpenCL in double precision) and to float's resolution elsewhere. Each test makes few Contexts: PoCL compiles kernels on first use (its cache is
kept in the build folder by scripts/test.sh).
"""

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import openmmrigid
import rigidtesting
import systems
from rigidtesting.bodies import bodyKind
from systems import positions_of, velocities_of

PRECISIONS = ["single", "mixed", "double"]
CASES = [(platform, precision) for platform in systems.GPU_PLATFORMS for precision in PRECISIONS]
pytestmark = pytest.mark.skipif(not systems.GPU_PLATFORMS, reason="no GPU platform (OpenCL or CUDA) with the plugin's kernels")

# Free motion: exact to rounding in double and mixed precision (double body state, positions double or
# float + correction); single precision rounds each position to float (about 1e-7 relative of ~1 nm).
# float; free atoms add their float rounding at every step (measured 2e-6 nm after 50 steps).
FREE_MOTION_TOLERANCE = {"double": 1e-10, "mixed": 1e-10, "single": 1e-5}


def gpu_context(system, integrator, platformName, precision):
    platform, properties = systems.platform_and_properties(platformName, precision)
    return openmm.Context(system, integrator, platform, properties)


def start(context, positions, velocities):
    context.setPositions(positions)
    context.setVelocities(velocities)
    return context


def run_pair(system, makeIntegrator, positions, velocities, steps, platformName, precision):
    """The same run on Reference and on the GPU platform: both final (positions, velocities)."""
    results = []
    for name in ("Reference", platformName):
        integrator = makeIntegrator()
        if name == "Reference":
            context = systems.make_context(system, integrator, "Reference")
        else:
            context = gpu_context(system, integrator, name, precision)
        start(context, positions, velocities)
        integrator.step(steps)
        results.append((positions_of(context), velocities_of(context)))
    return results


@pytest.mark.parametrize("platformName,precision", CASES)
@pytest.mark.parametrize("method", ["Exact", "NoSquish"])
def test_free_motion_matches_reference(platformName, precision, method):
    """Every kind of body (asymmetric, symmetric, spherical, linear, point) and free atoms, no forces."""
    cluster = systems.cluster(seed=3, forces=False)

    def make():
        integrator = openmmrigid.RigidBodyIntegrator(0.004, cluster.bodies)
        integrator.setRotationMethod(getattr(openmmrigid.RigidBodyIntegrator, method))
        return integrator

    (refX, refV), (x, v) = run_pair(cluster.system, make, cluster.positions, cluster.velocities, 50, platformName, precision)
    compared = np.ones(len(x), dtype=bool)
    if method == "NoSquish":
        # NO_SQUISH's rotations about the principal axes depend on which axes a body was given where
        # its moments are equal (spherical and symmetric tops: any frame of the degenerate space is
        # principal), and a shape read from positions rounded to mixed precision picks other ones:
        # its trajectory is then another, equally valid, approximation. The exact rotation is the
        # same whatever the frame (checked above for every body).
        kinds = kinds_of(cluster)
        for body, kind in zip(cluster.bodies, kinds):
            if kind in ("spherical", "symmetric"):
                compared[body] = False
    tolerance = FREE_MOTION_TOLERANCE[precision]
    assert np.abs(x - refX)[compared].max() < tolerance, np.abs(x - refX)[compared].max()
    # Velocities are kept in double in mixed precision, in float in single.
    assert np.abs(v - refV)[compared].max() < (tolerance if precision != "single" else 1e-5), np.abs(v - refV)[compared].max()


def kinds_of(cluster):
    """The kind of each body of the cluster, as the integrator classifies it (rigidtesting.bodies)."""
    masses = rigidtesting.particleMasses(cluster.system)
    positions = np.asarray(cluster.positions)
    return [bodyKind(masses[body], positions[body]) for body in cluster.bodies]


@pytest.fixture(scope="module")
def water():
    return systems.water_box("tip4pew", size=1.5, seed=7, cutoff=0.6)


@pytest.mark.parametrize("platformName,precision", CASES)
@pytest.mark.parametrize("kind", ["Verlet", "Omelyan2 Bussi", "Langevin"])
def test_water_trajectory_matches_reference(water, platformName, precision, kind):
    """A PME box of TIP4P-Ew (a massless virtual site per water): 20 steps of 2 fs; the thermostats
    draw the same random numbers on both platforms."""

    def make():
        if kind == "Langevin":
            integrator = openmmrigid.RigidBodyLangevinIntegrator(300.0, 5.0, 0.002)
        elif kind == "Omelyan2 Bussi":
            integrator = openmmrigid.RigidBodyBussiIntegrator(300.0, 0.05, 0.002)
            integrator.setSplitting(openmmrigid.RigidBodyIntegrator.Omelyan2)
        else:
            return openmmrigid.RigidBodyIntegrator(0.002)
        integrator.setRandomNumberSeed(11)
        return integrator

    (refX, refV), (x, v) = run_pair(water.system, make, water.positions, water.velocities, 20, platformName, precision)
    # The platforms' forces differ (PME, and single-precision arithmetic): stock VerletIntegrator +
    # SETTLE moves as far apart between the same two platforms (measured 1.1e-5 nm in double
    # precision, as for RigidBodyIntegrator). The rigid trajectories, thermostatted ones included
    # (their random numbers are the same on both), must stay as close as the stock ones.
    stockX = stock_difference(water, platformName, precision)
    assert np.abs(x - refX).max() < 3*stockX + 1e-9, (np.abs(x - refX).max(), stockX)


_stockDifferences = {}


def stock_difference(scene, platformName, precision, steps=20):
    """The largest position difference between Reference and the platform after the same steps of
    stock VerletIntegrator + SETTLE (and its other constraints) from the scene's state."""
    key = (id(scene), platformName, precision, steps)
    if key not in _stockDifferences:
        def make():
            integrator = openmm.VerletIntegrator(0.002)
            integrator.setConstraintTolerance(1e-6 if precision == "single" else 1e-10)
            return integrator
        (refX, _), (x, _) = run_pair(scene.system, make, scene.positions, scene.velocities, steps, platformName, precision)
        _stockDifferences[key] = np.abs(x - refX).max()
    return _stockDifferences[key]


@pytest.mark.parametrize("platformName,precision", [case for case in CASES if case[1] != "single"])
def test_time_reversible(platformName, precision):
    """Forward, velocities reversed, as many steps back: the start again (a cluster with forces)."""
    cluster = systems.cluster(seed=5)
    integrator = openmmrigid.RigidBodyIntegrator(0.002, cluster.bodies)
    context = start(gpu_context(cluster.system, integrator, platformName, precision), cluster.positions, cluster.velocities)
    begin = positions_of(context)
    integrator.step(100)
    context.setVelocities(-velocities_of(context))
    integrator.step(100)
    assert np.abs(positions_of(context) - begin).max() < 1e-9


@pytest.mark.parametrize("platformName,precision", CASES)
def test_runs_past_a_reorder(platformName, precision):
    """300 steps of a periodic TIP3P box: the platform reorders the atoms (and wraps molecules into
    the box) when the Context is set up and every 250 steps. The bodies stay rigid, the positions the
    Context reports stay continuous (no jump by a box vector), and the energy is conserved as well as
    stock VerletIntegrator + SETTLE conserves it on the same platform and precision."""
    water = systems.water_box("tip3p", size=1.6, seed=9, cutoff=0.7)
    bodies = [list(range(i, i + 3)) for i in range(0, water.system.getNumParticles(), 3)]
    lengths = [np.linalg.norm(water.positions[b[0]] - water.positions[b[k]]) for b in bodies for k in (1, 2)]
    spreads = {}
    for name in ("rigid", "stock"):
        if name == "rigid":
            integrator = openmmrigid.RigidBodyIntegrator(0.002)
        else:
            integrator = openmm.VerletIntegrator(0.002)
            integrator.setConstraintTolerance(1e-6 if precision == "single" else 1e-9)
        context = start(gpu_context(water.system, integrator, platformName, precision), water.positions, water.velocities)
        energies, previous = [], positions_of(context)
        for block in range(30):
            integrator.step(10)
            state = context.getState(getEnergy=True, getPositions=True)
            energies.append((state.getPotentialEnergy() + state.getKineticEnergy()).value_in_unit(unit.kilojoule_per_mole))
            now = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            # A fast hydrogen moves about 0.1 nm in 10 steps; a jump by a box vector is 1.6 nm.
            assert np.abs(now - previous).max() < 0.5, f"{name}: a particle jumped {np.abs(now - previous).max():.3g} nm in 10 steps"
            previous = now
        spreads[name] = np.std(energies)
        if name == "rigid":
            now = positions_of(context)
            current = [np.linalg.norm(now[b[0]] - now[b[k]]) for b in bodies for k in (1, 2)]
            assert np.abs(np.array(current) - lengths).max() < (1e-5 if precision == "single" else 1e-9)
    assert spreads["rigid"] < 2*spreads["stock"] + 0.05, spreads


@pytest.mark.parametrize("platformName,precision", CASES)
@pytest.mark.parametrize("integratorClass", [openmmrigid.RigidBodyIntegrator, openmmrigid.RigidBodyBussiIntegrator,
                                             openmmrigid.RigidBodyLangevinIntegrator])
def test_checkpoint_continues_bit_for_bit(water, platformName, precision, integratorClass):
    leading = {openmmrigid.RigidBodyIntegrator: (), openmmrigid.RigidBodyBussiIntegrator: (300.0, 0.1),
               openmmrigid.RigidBodyLangevinIntegrator: (300.0, 1.0)}[integratorClass]
    integrator = integratorClass(*leading, 0.002)
    context = start(gpu_context(water.system, integrator, platformName, precision), water.positions, water.velocities)
    integrator.step(10)
    checkpoint = context.createCheckpoint()
    integrator.step(10)
    continued = positions_of(context)
    # A loaded checkpoint is fitted again (as new positions are): the same run to rounding, and two
    # loads of one checkpoint the same run bit for bit where the platform promises deterministic
    # forces (CUDA with DeterministicForces, which platform_and_properties sets; OpenCL in double
    # precision), and to float's resolution elsewhere.
    runs = []
    for attempt in range(2):
        context.loadCheckpoint(checkpoint)
        integrator.step(10)
        runs.append((positions_of(context), velocities_of(context)))
    # (Mixed precision evaluates forces in float: a refit's last-bit changes reach the trajectory at
    # float's resolution, as in single precision.)
    tolerance = 1e-9 if precision == "double" else 1e-5
    if platformName == "CUDA" or precision == "double":
        assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])
    else:
        assert np.abs(runs[0][0] - runs[1][0]).max() < tolerance, np.abs(runs[0][0] - runs[1][0]).max()
    assert np.abs(runs[0][0] - continued).max() < tolerance, np.abs(runs[0][0] - continued).max()


@pytest.fixture(scope="module")
def mixed():
    return systems.mixed_system()


@pytest.mark.parametrize("platformName,precision", CASES)
@pytest.mark.parametrize("splitting", ["Verlet", "Omelyan2", "Yoshida4", "Omelyan4"])
def test_mixed_system_matches_reference(mixed, platformName, precision, splitting):
    """Alanine dipeptide (free particles with HBonds constraints, solved by the platform's own solver)
    in rigid water with explicit rigid benzene, CO2 and Na+, a free Cl-, PME: 10 steps of every
    splitting as close to Reference as stock Verlet + SETTLE stays between the same platforms, with
    the constraints among free particles met."""
    bodies = mixed.waters + [mixed.benzene, mixed.co2, mixed.sodium]
    tolerance = 1e-5 if precision == "single" else 1e-7

    def make():
        integrator = openmmrigid.RigidBodyIntegrator(0.002, bodies)
        integrator.setSplitting(getattr(openmmrigid.RigidBodyIntegrator, splitting))
        integrator.setConstraintTolerance(tolerance)
        return integrator

    (refX, _), (x, _) = run_pair(mixed.system, make, mixed.positions, mixed.velocities, 10, platformName, precision)
    stockX = stock_difference(mixed, platformName, precision, steps=10)
    assert np.abs(x - refX).max() < 3*stockX + 1e-9, (np.abs(x - refX).max(), stockX)
    inBody = set(i for body in bodies for i in body)
    for k in range(mixed.system.getNumConstraints()):
        i, j, distance = mixed.system.getConstraintParameters(k)
        if i not in inBody:
            # OpenMM's GPU SHAKE meets the length to about 1.5e-8 in double precision whatever it is asked.
            length = np.linalg.norm(x[i] - x[j])
            assert abs(length/distance.value_in_unit(unit.nanometer) - 1) < max(tolerance, 3e-8)


@pytest.mark.parametrize("platformName,precision", [case for case in CASES if case[1] != "single"])
def test_bussi_work_and_checkpoint_match_reference(platformName, precision):
    """The Bussi thermostat's work (RigidBodyBussiIntegrator's heat, measured with setMeasureShadowWork),
    summed on the device and read only when asked for, is Reference's (the same seed draws the same
    deviates): at a checkpoint, after a load of it that must drop the work done since (not read, still
    on the device) and keep exactly the saved value, and after the run continues from the load. The kinetic energies differ as the platforms' trajectories do
    (their forces differ: after 30 steps the positions are about 1e-8 nm apart in double and mixed
    precision alike, and the work 1e-9 to 3e-8 of itself), so the work must agree to 1e-6 of itself,
    where one step's work lost, leaked or counted twice is some 1e-2 of it."""
    cluster = systems.cluster(seed=5)
    KJ = unit.kilojoule_per_mole
    works = {}
    for name in ("Reference", platformName):
        integrator = openmmrigid.RigidBodyBussiIntegrator(200.0, 0.02, 0.002, cluster.bodies)
        integrator.setRandomNumberSeed(13)
        integrator.setMeasureShadowWork(True)
        if name == "Reference":
            context = systems.make_context(cluster.system, integrator, "Reference")
        else:
            context = gpu_context(cluster.system, integrator, name, precision)
        start(context, cluster.positions, cluster.velocities)
        integrator.step(15)
        checkpoint = context.createCheckpoint()
        saved = integrator.getHeat().value_in_unit(KJ)
        integrator.step(15)
        context.loadCheckpoint(checkpoint)
        loaded = integrator.getHeat().value_in_unit(KJ)
        assert loaded == saved, (name, loaded, saved)
        integrator.step(15)
        works[name] = (saved, integrator.getHeat().value_in_unit(KJ), positions_of(context))
    (refSaved, refContinued, refX), (saved, continued, x) = works["Reference"], works[platformName]
    print(f"{platformName} {precision}: work {saved} then {continued} kJ/mol, Reference {refSaved} then {refContinued}; "
          f"positions {np.abs(x - refX).max():.3g} nm apart")
    assert abs(saved) > 1.0 and abs(continued - saved) > 1.0  # the thermostat does work in both halves
    tolerance = 1e-6
    assert abs(saved - refSaved) < tolerance*abs(refSaved), (saved, refSaved)
    assert abs(continued - refContinued) < tolerance*abs(refContinued), (continued, refContinued)

"""Multiple time steps by force group (RigidBodyIntegratorBase.setForceGroupSubsteps):
- one level (every group with one substep) is today's step, bit for bit (Reference), in both integrators;
- a stiff fast force (the peptide's bonds, angles and torsions) conserves the energy better with
  substeps, by about the square of their number, as RESPA's inner Verlet does;
- a body no fast force reaches drifts once per drift of the step: its trajectory is the one it has
  when its drift is cut into the substeps (a zero fast force on it makes it take part), to 1e-12 nm;
- the energy balance dE = W + Q holds over the nest (Langevin with its O stage at the midpoint, and
  Omelyan2 in RigidBodyBussiIntegrator), on Reference and CPU;
- CPU and the GPU platforms follow Reference; a checkpoint continues the run bit for bit on Reference;
  copies keep the substeps; bad lists, changes once bound and conflicting integration force groups
  are refused with the class named.
"""

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit
import pytest

import rigidtesting
import systems
from openmmrigid import RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyLangevinIntegrator
from systems import COPY_METHODS, copy_integrator, positions_of, velocities_of

KJ = unit.kilojoule_per_mole
BONDED = (openmm.HarmonicBondForce, openmm.HarmonicAngleForce, openmm.PeriodicTorsionForce, openmm.CMAPTorsionForce)
FAST_GROUP = 1


def split_groups(system):
    """A copy of the System with the bonded forces in FAST_GROUP and everything else in group 0, and
    without its CMMotionRemover (which changes the velocities between steps: the energy it removes
    is neither the integrator's shadow work nor its heat)."""
    split = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for index in reversed(range(split.getNumForces())):
        if isinstance(split.getForce(index), openmm.CMMotionRemover):
            split.removeForce(index)
    for force in split.getForces():
        force.setForceGroup(FAST_GROUP if isinstance(force, BONDED) else 0)
    return split


def constraint_clusters(system, particles):
    """The clusters of the System's constraints among the particles (each a heavy atom with its
    hydrogens, for HBonds constraints), as sorted lists."""
    parent = {p: p for p in particles}

    def root(p):
        while parent[p] != p:
            p = parent[p]
        return p
    for k in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(k)
        if i in parent and j in parent:
            parent[root(i)] = root(j)
    clusters = {}
    for p in particles:
        clusters.setdefault(root(p), []).append(p)
    return sorted(sorted(cluster) for cluster in clusters.values() if len(cluster) > 1)


@pytest.fixture(scope="module")
def mixed():
    """systems.mixed_system() with its bonded forces in group 1, and as bodies the waters, benzene,
    CO2, Na+ and the peptide's X-H groups: the bonded forces reach the X-H groups (fast bodies) and
    the peptide's other atoms (free), not the waters, benzene, CO2 or Na+ (slow bodies)."""
    mixed = systems.mixed_system()
    mixed.split = split_groups(mixed.system)
    mixed.groups = constraint_clusters(mixed.system, mixed.peptide)
    assert len(mixed.groups) == 6  # two methyls, a CH, a CH3 of alanine, two NH
    mixed.bodies = mixed.waters + [mixed.benzene, mixed.co2, mixed.sodium] + mixed.groups
    return mixed


start = systems.start_context


def make(kind, dt, bodies, substeps=None):
    if kind == "langevin":
        integrator = RigidBodyLangevinIntegrator(300, 2, dt, bodies)
        integrator.setRandomNumberSeed(17)
    else:
        integrator = RigidBodyIntegrator(dt, bodies)
    if substeps is not None:
        integrator.setForceGroupSubsteps(substeps)
    return integrator


@pytest.mark.parametrize("kind", ["verlet", "langevin"])
def test_one_level_is_todays_step_bit_for_bit(mixed, kind):
    runs = []
    for substeps in (None, [(0, 1), (FAST_GROUP, 1)]):
        integrator = make(kind, 0.002, mixed.bodies, substeps)
        context = start(mixed.split, integrator, "Reference", mixed.positions, mixed.velocities)
        integrator.step(15)
        runs.append((positions_of(context), velocities_of(context)))
    assert np.array_equal(runs[0][0], runs[1][0]) and np.array_equal(runs[0][1], runs[1][1])


def peptide_in_vacuum():
    """Alanine dipeptide without cutoff, HBonds constraints, its bonded forces in FAST_GROUP."""
    pdb = rigidtesting.alanineDipeptide()
    forcefield = app.ForceField("amber14-all.xml")
    system = split_groups(forcefield.createSystem(pdb.topology, nonbondedMethod=app.NoCutoff, constraints=app.HBonds))
    integrator = openmm.VerletIntegrator(0.001)
    integrator.setConstraintTolerance(1e-10)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(pdb.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 1.0, 200)
    context.setVelocitiesToTemperature(300 * unit.kelvin, 3)
    integrator.step(200)
    state = context.getState(getPositions=True, getVelocities=True)
    return system, state.getPositions(asNumpy=True), state.getVelocities(asNumpy=True)


def test_substeps_conserve_the_energy_of_stiff_fast_forces():
    """The peptide's heavy-atom bonds (periods near 20 fs) under Verlet at 3 fs: the energy error is
    mostly theirs, and falls as (1/r)^2 with r substeps; at least 4 times less with 4 substeps."""
    system, positions, velocities = peptide_in_vacuum()
    fluctuations = {}
    for inner in (1, 4):
        integrator = RigidBodyIntegrator(0.003, [])
        integrator.setConstraintTolerance(1e-10)
        integrator.setForceGroupSubsteps([(0, 1), (FAST_GROUP, inner)])
        context = start(system, integrator, "Reference", positions, velocities)
        times, energies = systems.run_energies(context, integrator, 400, 2)
        fluctuations[inner] = np.std(energies)
    print("rms energy fluctuation, 1 and 4 substeps:", fluctuations)
    assert fluctuations[4] < fluctuations[1] / 4, fluctuations


@pytest.mark.parametrize("kind", ["verlet", "langevin"])
def test_a_body_no_fast_force_reaches_drifts_whole_as_in_pieces(mixed, kind):
    """The waters drift once per step; with a fast force of zero on them they take part in the three
    substeps instead. Free drifts compose, so both runs are the same to rounding, everywhere."""
    reached = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(mixed.split))
    zero = openmm.CustomExternalForce("0*x")
    for water in mixed.waters:
        for particle in water:
            zero.addParticle(particle, [])
    zero.setForceGroup(FAST_GROUP)
    reached.addForce(zero)
    runs = []
    for system in (mixed.split, reached):
        integrator = make(kind, 0.003, mixed.bodies, [(0, 1), (FAST_GROUP, 3)])
        context = start(system, integrator, "Reference", mixed.positions, mixed.velocities)
        integrator.step(10)
        runs.append(positions_of(context))
    difference = np.abs(runs[0] - runs[1]).max()
    print(kind, "largest difference", difference)
    assert difference < 1e-12, difference


def total_energy(context, integrator):
    state = context.getState(getEnergy=True, groups=integrator.getIntegrationForceGroups())
    return (state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(KJ)


@pytest.mark.parametrize("platformName", ["Reference", "CPU"])
@pytest.mark.parametrize("kind", ["langevin", "bussi-omelyan2"])
def test_shadow_work_and_heat_make_up_the_energy_change(mixed, platformName, kind):
    if kind == "langevin":
        integrator = make("langevin", 0.004, mixed.bodies, [(0, 1), (FAST_GROUP, 4)])
    else:
        integrator = RigidBodyBussiIntegrator(300, 0.05, 0.004, mixed.bodies)
        integrator.setForceGroupSubsteps([(0, 1), (FAST_GROUP, 2)])
        integrator.setSplitting(RigidBodyIntegrator.Omelyan2)
    integrator.setMeasureShadowWork(True)  # the shadow work and the heat
    context = start(mixed.split, integrator, platformName, mixed.positions, mixed.velocities)
    integrator.step(1)
    workBefore, heatBefore = integrator.getShadowWork().value_in_unit(KJ), integrator.getHeat().value_in_unit(KJ)
    before = total_energy(context, integrator)
    integrator.step(20)
    change = total_energy(context, integrator) - before
    work = integrator.getShadowWork().value_in_unit(KJ) - workBefore
    heat = integrator.getHeat().value_in_unit(KJ) - heatBefore
    assert work != 0 and heat != 0
    assert abs(work + heat - change) < 1e-9 * abs(before), (work, heat, change)


def platform_context(system, integrator, platformName, positions, velocities):
    """A Context on the platform (double precision on a GPU platform) from the state."""
    platform, properties = systems.platform_and_properties(platformName)
    if platformName in systems.GPU_PLATFORMS:
        properties = dict(properties, Precision="double")
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    context.setVelocities(velocities)
    return context


@pytest.mark.parametrize("platformName", ["CPU"] + systems.GPU_PLATFORMS)
@pytest.mark.parametrize("kind", ["verlet", "langevin"])
def test_platforms_follow_reference(mixed, platformName, kind):
    """Ten steps of 3 fs with 3 substeps: as close to Reference as stock Verlet (and its constraint
    solvers) stays between the same platforms in as many steps."""
    final = {}
    for name in ("Reference", platformName):
        integrator = make(kind, 0.003, mixed.bodies, [(0, 1), (FAST_GROUP, 3)])
        integrator.setConstraintTolerance(1e-8)
        stock = openmm.VerletIntegrator(0.001)
        stock.setConstraintTolerance(1e-10)
        contexts = [platform_context(mixed.split, integrator, name, mixed.positions, mixed.velocities),
                    platform_context(mixed.split, stock, name, mixed.positions, mixed.velocities)]
        integrator.step(10)
        stock.step(30)
        final[name] = [positions_of(context) for context in contexts]
    difference = np.abs(final[platformName][0] - final["Reference"][0]).max()
    stockDifference = np.abs(final[platformName][1] - final["Reference"][1]).max()
    print(platformName, kind, difference, stockDifference)
    assert difference < 3*stockDifference + 1e-9, (difference, stockDifference)


@pytest.mark.parametrize("kind", ["verlet", "langevin"])
def test_checkpoint_continues_bit_for_bit(mixed, kind):
    integrator = make(kind, 0.003, mixed.bodies, [(0, 1), (FAST_GROUP, 3)])
    context = start(mixed.split, integrator, "Reference", mixed.positions, mixed.velocities)
    integrator.step(5)
    checkpoint = context.createCheckpoint()
    integrator.step(8)
    straight = positions_of(context), velocities_of(context)
    context.loadCheckpoint(checkpoint)
    integrator.step(8)
    assert np.array_equal(straight[0], positions_of(context)) and np.array_equal(straight[1], velocities_of(context))


@pytest.mark.parametrize("method", COPY_METHODS)
def test_copies_keep_the_substeps(method):
    integrator = RigidBodyLangevinIntegrator(300, 1, 0.004)
    integrator.setForceGroupSubsteps([(3, 4), (0, 1), (2, 2), (5, 4)])
    copy = copy_integrator(integrator, method)
    assert copy.getForceGroupSubsteps() == [(3, 4), (0, 1), (2, 2), (5, 4)]
    assert copy.getIntegrationForceGroups() == (1 << 0) | (1 << 2) | (1 << 3) | (1 << 5)


@pytest.mark.parametrize("substeps,message", [
    ([(0, 2), (1, 4)], "slowest force groups have 2 substeps"),
    ([(0, 1), (1, 2), (2, 3)], "3 substeps is not a multiple of 2"),
    ([(0, 1), (0, 2)], "force group 0 is listed twice"),
    ([(32, 1)], "force group 32 is not a force group"),
    ([(0, 1), (1, 0)], "force group 1 has 0 substeps"),
    ([(0, 1, 2)], "give a list of (force group, substeps) pairs"),
    ("0,1", "give a list of (force group, substeps) pairs"),
])
def test_bad_substeps_are_refused(substeps, message):
    integrator = RigidBodyIntegrator(0.002)
    with pytest.raises(openmm.OpenMMException, match=r"RigidBodyIntegrator|setForceGroupSubsteps") as error:
        integrator.setForceGroupSubsteps(substeps)
    assert message in str(error.value)
    assert integrator.getForceGroupSubsteps() == []


def test_changes_once_bound_and_other_integration_groups_are_refused(mixed):
    integrator = make("langevin", 0.002, mixed.bodies, [(0, 1), (FAST_GROUP, 2)])
    with pytest.raises(openmm.OpenMMException, match="RigidBodyLangevinIntegrator: the integration force groups are those"):
        integrator.setIntegrationForceGroups({0})
    integrator.setIntegrationForceGroups({0, FAST_GROUP})  # the same groups: accepted
    context = start(mixed.split, integrator, "Reference", mixed.positions, mixed.velocities)
    with pytest.raises(openmm.OpenMMException, match="RigidBodyLangevinIntegrator: the force groups' substeps cannot change"):
        integrator.setForceGroupSubsteps([(0, 1), (FAST_GROUP, 4)])
    integrator.setForceGroupSubsteps([(0, 1), (FAST_GROUP, 2)])  # unchanged: accepted
    integrator.step(2)
    assert np.all(np.isfinite(positions_of(context)))


def test_an_empty_list_keeps_the_groups_the_last_list_made(mixed):
    """setForceGroupSubsteps([]) after a list goes back to one level, of the integration force groups that
    list set (its groups' union), which setIntegrationForceGroups() may then change."""
    integrator = make("langevin", 0.002, mixed.bodies, [(0, 1), (FAST_GROUP, 2)])
    assert integrator.getIntegrationForceGroups() == (1 << 0) | (1 << FAST_GROUP)
    integrator.setForceGroupSubsteps([])
    assert integrator.getForceGroupSubsteps() == []
    assert integrator.getIntegrationForceGroups() == (1 << 0) | (1 << FAST_GROUP)
    integrator.setIntegrationForceGroups({0})  # one level again: any groups
    assert integrator.getIntegrationForceGroups() == 1


def test_compound_integrator_steps_as_the_integrator_alone(mixed):
    """Inside a CompoundIntegrator (with a stock VerletIntegrator beside it, never stepped here) the
    nest is the same, bit for bit on Reference; after the other integrator moved the particles, the
    levels' forces are evaluated again, and the run goes on from the new positions."""
    runs = []
    for compound in (False, True):
        integrator = make("langevin", 0.003, mixed.bodies, [(0, 1), (FAST_GROUP, 3)])
        if compound:
            holder = openmm.CompoundIntegrator()
            holder.addIntegrator(integrator)
            holder.addIntegrator(openmm.VerletIntegrator(0.0005))
            holder.setCurrentIntegrator(0)
            context = start(mixed.split, holder, "Reference", mixed.positions, mixed.velocities)
        else:
            context = start(mixed.split, integrator, "Reference", mixed.positions, mixed.velocities)
        integrator.step(6)
        runs.append(positions_of(context))
        if compound:
            holder.setCurrentIntegrator(1)
            holder.step(2)
            holder.setCurrentIntegrator(0)
            holder.step(4)
            assert np.all(np.isfinite(positions_of(context)))
            assert np.abs(positions_of(context) - runs[-1]).max() > 0
    assert np.array_equal(runs[0], runs[1])


@pytest.mark.parametrize("floor", [None, 0.05])
def test_velocities_drawn_for_a_temperature_are_on_step_with_substeps(mixed, floor):
    """setVelocitiesToTemperature draws on-step velocities and takes them back by the offset the
    integrator holds: with substeps half a kick of the slowest forces only (OpenMM's Context takes
    every group's). The same draw with and without substeps must then be the same on-step
    velocities: the same on-step kinetic energy, with raised moments too."""
    energies = []
    for substeps in (None, [(0, 1), (FAST_GROUP, 4)]):
        integrator = make("langevin", 0.004, mixed.bodies, substeps)
        if floor is not None:
            integrator.setMinimumMomentOfInertia(floor)
        context = start(mixed.split, integrator, "Reference", mixed.positions, mixed.velocities)
        context.setVelocitiesToTemperature(300, 5)
        energies.append(integrator.getOnStepKineticEnergy().value_in_unit(KJ))
    assert energies[1] == pytest.approx(energies[0], rel=1e-10)

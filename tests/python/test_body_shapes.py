"""The shape a body takes from positions: assembled whole from its periodic images however far it
reaches from its first particle, and linear when its particles lie on a line to the precision of the
coordinates a user has (a PDB or .gro file).

Each answer is computed here independently: the rigid motion of the body's contiguous coordinates
(numpy: the velocities a body of that inertia tensor keeps of given particle velocities, and their
kinetic energy), the same body listed from another particle, the same molecule given exactly linear,
the degrees of freedom the temperature counts. Every case runs on Reference, CPU and the GPU
platforms present.
"""

import numpy as np
import openmm
import pytest
from openmm import unit

import openmmrigid
import systems
from rigidtesting import randomRotation
from rigidtesting.stress import inertia_tensor
from systems import make_context, positions_of, velocities_of

PLATFORMS = systems.PLATFORMS
EDGE = 3.0  # nm


def rigidProjection(masses, coordinates, velocities):
    """The rigid motion of particle velocities for a body at these contiguous coordinates: the
    velocities V + omega x r with the body's momentum and angular momentum (omega = I^-1 L, I the
    full inertia tensor of the coordinates), and their kinetic energy M V^2 / 2 + omega.I.omega / 2."""
    masses, coordinates = np.asarray(masses, dtype=float), np.asarray(coordinates, dtype=float)
    total = masses.sum()
    relative = coordinates - masses @ coordinates / total
    velocity = masses @ velocities / total
    inertia = inertia_tensor(masses, coordinates)
    omega = np.linalg.solve(inertia, np.sum(masses[:, None] * np.cross(relative, velocities - velocity), axis=0))
    return velocity + np.cross(omega, relative), 0.5 * total * velocity @ velocity + 0.5 * omega @ inertia @ omega


def kineticEnergy(context):
    return context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)


def temperatureDegreesOfFreedom(context, integrator):
    """The degrees of freedom the integrator's temperature counts: 2 KE / (kB T)."""
    temperature = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    return 2 * kineticEnergy(context) / (systems.BOLTZMANN * temperature)


#: Box vectors (nm): a cube of edge EDGE, and a triclinic cell in OpenMM's reduced form with the same widths.
BOXES = {"cubic": np.diag([EDGE] * 3), "triclinic": np.array([[EDGE, 0, 0], [0.9, EDGE, 0], [-1.1, 0.7, EDGE]])}


def periodicSystem(masses, edge=EDGE, box=None):
    """Particles with these masses in a periodic box (a cube of this edge, or these box vectors), with
    a NonbondedForce that acts on nothing (it only makes the System periodic)."""
    system = openmm.System()
    box = np.diag([edge] * 3) if box is None else box
    system.setDefaultPeriodicBoxVectors(*(openmm.Vec3(*vector) for vector in box))
    nonbonded = openmm.NonbondedForce()
    nonbonded.setNonbondedMethod(openmm.NonbondedForce.CutoffPeriodic)
    nonbonded.setCutoffDistance(0.4)
    for mass in masses:
        system.addParticle(mass)
        nonbonded.addParticle(0.0, 0.3, 0.0)
    system.addForce(nonbonded)
    return system


def intraBodyDistances(positions):
    return np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=-1)


# ------------------------------------------------------------------------------------------------
# Bodies reaching farther than half the box from their first particle
# ------------------------------------------------------------------------------------------------

def kinkedRod():
    """A rod of nine carbons 0.2 nm apart (1.6 nm long) with a tenth bent off its end: farther than
    half a 3 nm box from its first particle, each link far shorter than that."""
    coordinates = [[0.2 * k, 0.0, 0.0] for k in range(9)] + [[1.6, 0.15, 0.0]]
    return [12.0] * len(coordinates), np.array(coordinates) + 0.5


def wrapIntoCell(positions, box):
    """Each position moved by whole box vectors into the cell (c, then b, then a), atom by atom."""
    wrapped = np.array(positions, dtype=float)
    for k in (2, 1, 0):
        wrapped -= np.outer(np.floor(wrapped[:, k] / box[k][k]), box[k])
    return wrapped


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("boxName", BOXES)
@pytest.mark.parametrize("wrapped", [False, True], ids=["contiguous", "wrapped"])
def test_large_body_assembled_whole(platformName, boxName, wrapped):
    """The velocities read back are the rigid motion of the body as it is contiguous, their kinetic
    energy that of its inertia tensor (the body folded at half the box, as a nearest-image assembly
    from its first particle makes it, has another)."""
    masses, coordinates = kinkedRod()
    box = BOXES[boxName]
    rng = np.random.default_rng(5)
    velocities = rng.normal(scale=0.3, size=coordinates.shape)
    rigid, energy = rigidProjection(masses, coordinates, velocities)
    folded = coordinates.copy()
    folded[np.abs(coordinates[:, 0] - coordinates[0, 0]) > 0.5 * EDGE] -= box[0]
    assert abs(rigidProjection(masses, folded, velocities)[1] / energy - 1) > 0.01  # the test can tell
    given = wrapIntoCell(coordinates, box) if wrapped else coordinates
    runs = {}
    # Listed from an end (its first particle 1.6 nm from the far end), and from the middle.
    for order in ([list(range(10))], [[4, 5, 6, 7, 8, 9, 0, 1, 2, 3]]):
        integrator = openmmrigid.RigidBodyIntegrator(0.002, order)
        context = make_context(periodicSystem(masses, box=box), integrator, platformName)
        context.setPositions(given)
        context.setVelocities(velocities)
        assert kineticEnergy(context) == pytest.approx(energy, rel=1e-10)
        np.testing.assert_allclose(velocities_of(context), rigid, rtol=0, atol=1e-10)
        integrator.step(100)
        runs[order[0][0]] = positions_of(context)
    for positions in runs.values():
        # The integrator writes each body whole, at one of its images.
        assert np.abs(intraBodyDistances(positions) - intraBodyDistances(coordinates)).max() < 1e-9
    # Both lists give the same motion, up to a lattice vector (each body is placed at the image of its first particle).
    lattice = np.linalg.solve(box.T, (runs[0] - runs[4]).T).T
    assert np.abs(lattice - np.round(lattice)).max() < 1e-9


@pytest.mark.parametrize("platformName", ["Reference"])
def test_body_with_a_link_as_long_as_half_the_box_is_an_error(platformName):
    """Two particles 1.0 nm apart can be placed only in a box wider than 2 nm: in a smaller one the
    nearer image is as plausible as the farther, and the fit says so, naming the body."""
    masses = [12.0, 12.0]
    coordinates = np.array([[0.5, 0.5, 0.5], [1.5, 0.5, 0.5]])
    integrator = openmmrigid.RigidBodyIntegrator(0.002, [[0, 1]])
    context = make_context(periodicSystem(masses), integrator, platformName)
    context.setPositions(coordinates)
    integrator.step(1)
    context.setPeriodicBoxVectors(openmm.Vec3(1.9, 0, 0), openmm.Vec3(0, 1.9, 0), openmm.Vec3(0, 0, 1.9))
    with pytest.raises(openmm.OpenMMException, match=r"RigidBodyIntegrator: body 0 cannot be assembled .* half the periodic box's smallest width is 0\.95 nm"):
        context.setPositions(coordinates)
        integrator.step(1)


def test_solvated_dipeptide_body_from_topology():
    """The issue's path: alanine dipeptide as one body from rigidBodiesFromTopology (its first atom
    an end of the molecule) in a 1.45 nm water box: the peptide moves with the inertia tensor of the
    peptide as built (its velocities read back are the rigid motion of it, their kinetic energy that
    of its inertia)."""
    from test_topology_bodies import solvatedDipeptide
    size = 1.45
    topology, positions, system = solvatedDipeptide("tip3p", size=size)
    bodies = openmmrigid.rigidBodiesFromTopology(topology, ["HOH"], merge=[[0, 1, 2]], system=system)
    peptide = bodies[0]
    masses = [system.getParticleMass(i).value_in_unit(unit.amu) for i in peptide]
    reach = np.linalg.norm(positions[peptide] - positions[peptide[0]], axis=1).max()
    assert reach > 0.5 * size  # the case at risk: farther from its first atom than half the box
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    integrator = openmmrigid.RigidBodyIntegrator(0.001, bodies)
    context = make_context(lean, integrator, "Reference")
    context.setPositions(positions)
    velocities = np.zeros((system.getNumParticles(), 3))
    velocities[peptide] = np.random.default_rng(3).normal(scale=0.3, size=(len(peptide), 3))
    context.setVelocities(velocities)
    rigid, energy = rigidProjection(masses, positions[peptide], velocities[peptide])
    assert kineticEnergy(context) == pytest.approx(energy, rel=1e-9)
    np.testing.assert_allclose(velocities_of(context)[peptide], rigid, rtol=0, atol=1e-9)


# ------------------------------------------------------------------------------------------------
# Nearly linear molecules
# ------------------------------------------------------------------------------------------------

CARBON_OXYGEN = 0.116  # nm, TraPPE CO2
CO2_MASSES = [12.011, 15.999, 15.999]
CO2 = np.array([[0, 0, 0], [0, 0, CARBON_OXYGEN], [0, 0, -CARBON_OXYGEN]])


def co2Positions(count, rng):
    """count CO2 molecules near the points of a grid in the 3 nm box, each randomly turned and moved
    off its point (a carbon on a point of the rounding grid would keep the rounded molecule straight)."""
    grid = np.array([[i, j, k] for i in range(4) for j in range(4) for k in range(4)])[:count] * 0.75 + 0.4
    return np.concatenate([CO2 @ randomRotation(rng).T + centre + rng.uniform(0.0, 0.1, 3) for centre in grid])


@pytest.mark.parametrize("platformName", PLATFORMS)
@pytest.mark.parametrize("precision", [1e-4, 1e-3], ids=["pdb", "gro"])
def test_co2_from_rounded_coordinates_is_linear(platformName, precision):
    count = 16
    rng = np.random.default_rng(8)
    exact = co2Positions(count, rng)
    rounded = np.round(exact / precision) * precision
    bodies = [[3 * m, 3 * m + 1, 3 * m + 2] for m in range(count)]
    system = periodicSystem(CO2_MASSES * count)
    integrator = openmmrigid.RigidBodyIntegrator(0.002, bodies)
    context = make_context(system, integrator, platformName)
    context.setPositions(rounded)
    # Put on a line: the fitted positions are within the rounding of the given ones, each body
    # exactly straight, its bond lengths those of the rounded input to the rounding.
    fitted = positions_of(context)
    assert np.abs(fitted - rounded).max() < precision
    for body in bodies:
        x = fitted[body]
        assert np.linalg.norm(np.cross(x[1] - x[0], x[2] - x[0])) < 1e-12
    # The same motion as the exactly linear molecules (a fresh Context), to the size of the rounding.
    velocities = rng.normal(scale=0.3, size=exact.shape)
    context.setVelocities(velocities)
    # Linear: two rotational degrees of freedom per body, none about its axis.
    assert temperatureDegreesOfFreedom(context, integrator) == pytest.approx(5 * count, rel=1e-9)
    answerIntegrator = openmmrigid.RigidBodyIntegrator(0.002, bodies)
    answer = make_context(system, answerIntegrator, platformName)
    answer.setPositions(exact)
    answer.setVelocities(velocities)
    assert temperatureDegreesOfFreedom(answer, answerIntegrator) == pytest.approx(5 * count, rel=1e-9)
    integrator.step(200)
    answerIntegrator.step(200)
    energy = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    answerEnergy = answer.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    assert abs(energy / answerEnergy - 1) < 100 * precision


def test_bent_molecule_stays_asymmetric():
    """A genuinely bent triatomic (170 degrees: its centre 0.01 nm off the line of its ends) is not
    straightened: it keeps its place, rotates about three axes (six degrees of freedom), with the
    inertia tensor of its coordinates, and moves freely as the exact rotor of its moments."""
    half = np.radians(85.0)
    coordinates = np.array([[0, 0, 0], [CARBON_OXYGEN * np.sin(half), 0, CARBON_OXYGEN * np.cos(half)],
                            [-CARBON_OXYGEN * np.sin(half), 0, CARBON_OXYGEN * np.cos(half)]]) + 1.0
    integrator = openmmrigid.RigidBodyIntegrator(0.002, [[0, 1, 2]])
    context = make_context(periodicSystem(CO2_MASSES), integrator, "Reference")
    context.setPositions(coordinates)
    velocities = np.random.default_rng(4).normal(scale=0.3, size=(3, 3))
    context.setVelocities(velocities)
    assert np.abs(positions_of(context) - coordinates).max() < 1e-12
    assert temperatureDegreesOfFreedom(context, integrator) == pytest.approx(6, rel=1e-9)
    rigid, energy = rigidProjection(CO2_MASSES, coordinates, velocities)
    assert kineticEnergy(context) == pytest.approx(energy, rel=1e-10)
    np.testing.assert_allclose(velocities_of(context), rigid, rtol=0, atol=1e-10)
    exact = systems.rigid_motion(np.array(CO2_MASSES), coordinates, rigid, [[0, 1, 2]], [])
    integrator.step(100)
    expectedPositions, expectedVelocities = exact(0.2)
    assert np.abs(positions_of(context) - expectedPositions).max() < 1e-9
    assert np.abs(velocities_of(context) - expectedVelocities).max() < 1e-8

"""Scenarios and measurements for the stability stress tests of RigidBodyIntegrator: the fast subset
in tests/python/test_stress.py and the long runs of benchmarks/studies/stress.py.

Scenarios (each a Scenario: a System with the state to start it from):

- bodies_in_bath(): rigid bodies of extreme shapes, given as explicit bodies, among free
  Lennard-Jones atoms, hot enough that collisions keep kicking the bodies across the separatrix
  (2 E I2 = L^2) of their free motion. The shapes: a thin rod whose principal moments span a ratio
  of 1e6 (collinear atoms and one tiny off-axis mass), near-spherical and near-symmetric tops whose
  moments differ by 1e-9 relative (octahedra of six atoms around a centre), a linear CO2-like
  triatomic and a generic bent (asymmetric) triatomic. Periodic (a cube, Lennard-Jones switched off
  smoothly before half the edge) or an isolated cluster.
- spinning_body(): one bent triatomic spinning at |omega| = 1e4 ps^-1 about a direction that is no
  principal axis (particle velocities v = omega x r about its centre), alone with no forces or in a
  Lennard-Jones bath kept outside the sphere its atoms sweep.
- hot_cluster(): cluster() (water-, ammonia-, methane-, CO2-, CO-like bodies, point bodies
  and free ions, Lennard-Jones + Coulomb) at any temperature, isolated.
- water(): a rigid TIP3P or TIP4P-Ew box from water_box() (PME), without the
  CMMotionRemover that ForceField adds (it would hide what the integrator does to the momentum),
  its velocities scaled to any temperature.

The pair forces of the first three are a CustomBondForce over all intermolecular pairs: evaluated
in double precision on the Reference and the CPU platform, equal and opposite for each pair, so that
the total force vanishes to rounding and total momentum (and, isolated, angular momentum) is
conserved to rounding by a correct integrator.

Measurements: run() integrates a scenario and samples, every so many steps, the total energy, the
largest change of any intra-body distance, total linear and angular momentum, finiteness, and on
which side of its separatrix each rotating body is; Run summarises them.
"""

import functools
import math

import numpy as np
import openmm
import openmm.unit as unit

import openmmrigid
from . import randomRotation as _random_rotation, waterBox
from .bodies import bodyKind, rigidDegreesOfFreedom

# ------------------------------------------------------------------------------------------------
# What the scenarios are built from: small molecules of every body kind, a cluster of them, a water
# box with a minimised and thermalised starting state, the exact free motion of bodies.
# ------------------------------------------------------------------------------------------------

KJ_PER_MOL_PER_NM = 138.935456  # Coulomb's constant, kJ mol^-1 nm e^-2 (OpenMM's ONE_4PI_EPS0)
BOLTZMANN = 0.00831446261815324  # kJ/mol/K


def platform_and_properties(name, precision="double"):
    """The platform and the properties the tests use with it: a GPU platform in the given precision
    (double unless asked), and DeterministicForces wherever the platform has that property (CPU, and
    CUDA, whose PME otherwise spreads charges with float atomics in single and mixed precision, so
    that two runs from one state differ), so that comparisons of two runs hold bit for bit where the
    platform promises it."""
    platform = openmm.Platform.getPlatformByName(name)
    properties = {}
    if name in ("OpenCL", "CUDA"):
        properties["Precision"] = precision
    if "DeterministicForces" in platform.getPropertyNames():
        properties["DeterministicForces"] = "true"
    return platform, properties


def _tetrahedron(length):
    return length / np.sqrt(3.0) * np.array([[1, 1, 1], [1, -1, -1], [-1, 1, -1], [-1, -1, 1]], dtype=float)


def _water_like():
    # Asymmetric top (all three principal moments differ).
    angle = np.radians(104.52)
    oh = 0.09572
    coordinates = np.array([[0.0, 0.0, 0.0],
                            [oh * np.sin(angle / 2), oh * np.cos(angle / 2), 0.0],
                            [-oh * np.sin(angle / 2), oh * np.cos(angle / 2), 0.0]])
    return ("water", [15.999, 1.008, 1.008], coordinates, [-0.834, 0.417, 0.417],
            [0.315, 0.1, 0.1], [0.636, 0.0, 0.0])


def _ammonia_like():
    # Symmetric top: N above an equilateral triangle of H.
    h = 0.0381
    r = 0.0939
    coordinates = [[0.0, 0.0, h]]
    for k in range(3):
        phi = 2 * np.pi * k / 3
        coordinates.append([r * np.cos(phi), r * np.sin(phi), 0.0])
    return ("ammonia", [14.007, 1.008, 1.008, 1.008], np.array(coordinates), [-0.9, 0.3, 0.3, 0.3],
            [0.325, 0.1, 0.1, 0.1], [0.711, 0.0, 0.0, 0.0])


def _methane_like():
    # Spherical top: C at the centre of a regular tetrahedron of H.
    coordinates = np.vstack([[0.0, 0.0, 0.0], _tetrahedron(0.109)])
    return ("methane", [12.011] + [1.008] * 4, coordinates, [-0.24, 0.06, 0.06, 0.06, 0.06],
            [0.35, 0.25, 0.25, 0.25, 0.25], [0.276, 0.125, 0.125, 0.125, 0.125])


def _carbon_dioxide():
    # Linear triatomic.
    co = 0.116
    return ("co2", [12.011, 15.999, 15.999], np.array([[0.0, 0.0, 0.0], [0.0, 0.0, co], [0.0, 0.0, -co]]),
            [0.7, -0.35, -0.35], [0.28, 0.305, 0.305], [0.224, 0.657, 0.657])


def _carbon_monoxide():
    # Linear diatomic with unequal masses.
    return ("co", [12.011, 15.999], np.array([[0.0, 0.0, 0.0], [0.0, 0.0, 0.1128]]), [0.02, -0.02],
            [0.33, 0.31], [0.4, 0.5])


def _sodium():
    # A single-particle body: translation only.
    return ("sodium", [22.99], np.zeros((1, 3)), [1.0], [0.25], [0.36])


def _chloride():
    # A free particle (in no body).
    return ("chloride", [35.45], np.zeros((1, 3)), [-1.0], [0.44], [0.42])


def _argon():
    return ("argon", [39.948], np.zeros((1, 3)), [0.0], [0.34], [0.996])


class Cluster:
    """A non-periodic System of small molecules and the state to start it from.

    Attributes: system, positions and velocities ((n, 3) arrays, nm and nm/ps), bodies (lists of
    particle indices), free (indices of particles in no body), masses, molecules (one list of
    particle indices per molecule, bodies and free atoms alike).
    """


def cluster(seed=1, spacing=0.5, grid=(3, 3, 3), temperature=300.0, drift=(0.0, 0.0, 0.0), spin=0.0,
            forces=True):
    """An isolated cluster: molecules of every kind on a grid, random orientations, thermal rigid
    velocities (each body moves rigidly: v_i = V + omega x (r_i - R)).

    drift (nm/ps) is added to every velocity and spin (rad/ps) rotates the whole cluster about the
    z axis through its centre of mass, so that total linear and angular momentum are non-zero.
    With forces=False the System holds no forces at all.
    """
    rng = np.random.default_rng(seed)
    kinds = [_water_like, _ammonia_like, _methane_like, _carbon_dioxide, _carbon_monoxide, _sodium]
    freeKinds = [_chloride, _argon]
    sites = [np.array([i, j, k], dtype=float) * spacing
             for i in range(grid[0]) for j in range(grid[1]) for k in range(grid[2])]
    # Every body kind at least twice, then waters; the last two sites hold free atoms.
    plan = kinds + kinds + [_water_like] * max(0, len(sites) - 2 * len(kinds) - 2) + freeKinds
    plan = plan[:len(sites)]
    system = openmm.System()
    positions, velocities, masses, charges, sigmas, epsilons = [], [], [], [], [], []
    bodies, free, molecules = [], [], []
    for site, make in zip(sites, plan):
        name, molMasses, coordinates, molCharges, molSigmas, molEpsilons = make()
        molMasses = np.array(molMasses)
        # Place the molecule's centre of mass on the grid site, randomly oriented.
        centre = molMasses @ coordinates / molMasses.sum()
        rotation = _random_rotation(rng)
        molPositions = (coordinates - centre) @ rotation.T + site + rng.normal(scale=0.02, size=3)
        comVelocity = rng.normal(scale=np.sqrt(BOLTZMANN * temperature / molMasses.sum()), size=3)
        relative = molPositions - molMasses @ molPositions / molMasses.sum()
        inertia = sum(m * (np.dot(r, r) * np.eye(3) - np.outer(r, r)) for m, r in zip(molMasses, relative))
        omega = np.zeros(3)
        if len(molMasses) > 1:
            moments, axes = np.linalg.eigh(inertia)
            bodyOmega = np.array([rng.normal(scale=np.sqrt(BOLTZMANN * temperature / I)) if I > 1e-9 * moments[-1]
                                  else 0.0 for I in moments])
            omega = axes @ bodyOmega
        indices = list(range(system.getNumParticles(), system.getNumParticles() + len(molMasses)))
        for k in range(len(molMasses)):
            system.addParticle(molMasses[k])
            positions.append(molPositions[k])
            velocities.append(comVelocity + np.cross(omega, relative[k]))
        masses.extend(molMasses)
        charges.extend(molCharges)
        sigmas.extend(molSigmas)
        epsilons.extend(molEpsilons)
        molecules.append(indices)
        if make in freeKinds:
            free.extend(indices)
        else:
            bodies.append(indices)
    positions = np.array(positions)
    velocities = np.array(velocities)
    masses = np.array(masses)
    centre = masses @ positions / masses.sum()
    velocities += np.asarray(drift, dtype=float) + np.cross([0.0, 0.0, spin], positions - centre)
    if forces:
        pairs = openmm.CustomBondForce(
            "4*epsilon*((sigma/r)^12 - (sigma/r)^6) + coulomb*qq/r")
        pairs.addGlobalParameter("coulomb", KJ_PER_MOL_PER_NM)
        for parameter in ("qq", "sigma", "epsilon"):
            pairs.addPerBondParameter(parameter)
        molecule = np.empty(len(masses), dtype=int)
        for index, members in enumerate(molecules):
            molecule[members] = index
        for i in range(len(masses)):
            for j in range(i + 1, len(masses)):
                if molecule[i] != molecule[j]:
                    pairs.addBond(i, j, [charges[i] * charges[j], 0.5 * (sigmas[i] + sigmas[j]),
                                         np.sqrt(epsilons[i] * epsilons[j])])
        system.addForce(pairs)
    result = Cluster()
    result.system = system
    result.positions = positions
    result.velocities = velocities
    result.bodies = bodies
    result.free = free
    result.masses = masses
    result.molecules = molecules
    return result


class RigidMotion:
    """The exact torque-free motion of one body, from its initial positions and velocities.

    With minimumMoment, the body moves as RigidBodyIntegratorBase.setMinimumMomentOfInertia() makes
    it: every nonzero principal moment raised to at least minimumMoment, with the angular velocity
    of the given velocities (its angular momentum is that of the raised moments).
    """

    def __init__(self, masses, positions, velocities, minimumMoment=0.0):
        masses = np.asarray(masses, dtype=float)
        self.centre = masses @ positions / masses.sum()
        self.velocity = masses @ velocities / masses.sum()
        relative = positions - self.centre
        self.rotor = None
        self.bodyCoordinates = relative
        if len(masses) == 1:
            return
        inertia = sum(m * (np.dot(r, r) * np.eye(3) - np.outer(r, r)) for m, r in zip(masses, relative))
        moments, axes = np.linalg.eigh(inertia)       # columns of axes: principal axes (lab frame)
        if np.linalg.det(axes) < 0:
            axes[:, 0] = -axes[:, 0]
        attitude = axes.T                               # lab -> body
        angularMomentum = sum(m * np.cross(r, v - self.velocity)
                              for m, r, v in zip(masses, relative, velocities))
        bodyMomentum = attitude @ angularMomentum
        linear = moments[0] <= 1e-12 * moments[2]
        if linear:
            # The axis of a linear body carries no angular momentum; FreeRotor wants the zero moment exact.
            moments[0] = 0.0
            bodyOmega = np.array([0.0, bodyMomentum[1] / moments[1], bodyMomentum[2] / moments[2]])
        else:
            bodyOmega = bodyMomentum / moments
        moments = np.where(moments > 0.0, np.maximum(moments, minimumMoment), 0.0)
        self.bodyCoordinates = relative @ attitude.T
        if linear:
            self.bodyCoordinates[:, 1:] = 0.0
        self.rotor = openmmrigid.FreeRotor(moments, bodyOmega, attitude)

    def at(self, t):
        """Positions and velocities at time t (ps)."""
        if self.rotor is None:
            return self.centre + self.velocity * t + self.bodyCoordinates * 0.0, \
                np.tile(self.velocity, (len(self.bodyCoordinates), 1))
        omega, attitude = self.rotor.evolve(t)
        relative = self.bodyCoordinates @ attitude          # rows: A^T b_i
        labOmega = attitude.T @ omega
        return self.centre + self.velocity * t + relative, self.velocity + np.cross(labOmega, relative)


def rigid_motion(masses, positions, velocities, bodies, free, minimumMoment=0.0):
    """A function t -> (positions, velocities) giving the exact free motion of every body (its
    moments raised to minimumMoment, see RigidMotion) and the straight-line motion of every free
    particle."""
    motions = [(body, RigidMotion(masses[body], positions[body], velocities[body], minimumMoment)) for body in bodies]

    def at(t):
        r = np.array(positions, dtype=float)
        v = np.array(velocities, dtype=float)
        for body, motion in motions:
            r[body], v[body] = motion.at(t)
        r[free] = positions[free] + velocities[free] * t
        return r, v
    return at


WATER_MODELS = {"tip3p": "amber14/tip3p.xml", "tip4pew": "amber14/tip4pew.xml"}


class Solvated:
    """A System from openmm.app with a minimised starting state (positions and velocities as numpy
    arrays in nm and nm/ps) that satisfies every constraint."""


def _prepare(topology, positions, system, seed, frozen=(), temperature=300.0, equilibrate=500):
    """Minimise (particles in frozen held fixed) and draw velocities; constraints hold to what the CPU
    platform's SETTLE gives (a few 1e-9 nm)."""
    minimise = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for index in frozen:
        minimise.setParticleMass(index, 0.0)
    integrator = openmm.VerletIntegrator(0.001)
    integrator.setConstraintTolerance(1e-10)
    context = openmm.Context(minimise, integrator, openmm.Platform.getPlatformByName("CPU"), {"DeterministicForces": "true"})
    context.setPositions(positions)
    context.applyConstraints(1e-10)
    openmm.LocalEnergyMinimizer.minimize(context, 5.0, 100)
    context.setVelocitiesToTemperature(temperature * unit.kelvin, seed)
    if equilibrate > 0:
        # Thermalise so that the NVE runs of the tests start near equilibrium (no relaxation
        # transient on top of the drift they measure).
        thermostat = openmm.LangevinMiddleIntegrator(temperature * unit.kelvin, 5.0 / unit.picosecond,
                                                     0.002 * unit.picosecond)
        thermostat.setRandomNumberSeed(seed)
        thermostat.setConstraintTolerance(1e-10)
        equilibration = openmm.Context(minimise, thermostat, openmm.Platform.getPlatformByName("CPU"),
                                       {"DeterministicForces": "true"})
        equilibration.setState(context.getState(getPositions=True, getVelocities=True))
        thermostat.step(equilibrate)
        context.setState(equilibration.getState(getPositions=True, getVelocities=True))
        context.applyConstraints(1e-10)
    context.applyVelocityConstraints(1e-10)
    state = context.getState(getPositions=True, getVelocities=True)
    result = Solvated()
    result.system = system
    result.topology = topology
    result.positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    result.velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    for index in frozen:
        result.velocities[index] = 0.0
    return result


def water_box(model="tip3p", size=1.7, seed=5, cutoff=0.7):
    """A cubic box (edge `size` nm) of rigid water, PME with a switched Lennard-Jones cutoff."""
    topology, positions, system = waterBox(model, edge=size, forceField=["amber14-all.xml", WATER_MODELS[model]],
                                           nonbondedCutoff=cutoff * unit.nanometer,
                                           switchDistance=(cutoff - 0.1) * unit.nanometer, constraints=None,
                                           ewaldErrorTolerance=1e-4)
    return _prepare(topology, positions, system, seed)


def energy_drift(times, energies):
    """The least-squares slope of energies against times (kJ/mol/ps when times are in ps), its
    standard error, and the root-mean-square residual about the fitted line."""
    times = np.asarray(times, dtype=float)
    energies = np.asarray(energies, dtype=float)
    design = np.vstack([times, np.ones_like(times)]).T
    (slope, intercept), *_ = np.linalg.lstsq(design, energies, rcond=None)
    residual = energies - (slope * times + intercept)
    n = len(times)
    standardError = np.sqrt(residual @ residual / (n - 2) / np.sum((times - times.mean()) ** 2))
    return slope, standardError, np.sqrt(np.mean(residual ** 2))


def block_drift(times, energies, blocks):
    """The drift of energies against times from the means of `blocks` consecutive blocks: slope and
    standard error of the line through the block means. Block means are nearly independent when a
    block is longer than the correlation time of the energy fluctuations, so this standard error
    understates the uncertainty of the slope less than that of a fit to every sample does; a
    wandering as slow as the whole series escapes it all the same (in NVE water boxes of 64 molecules
    over 4 ps, the slopes of independent runs scattered up to twice their block errors)."""
    n = len(times) // blocks * blocks
    blockTimes = np.asarray(times[:n], dtype=float).reshape(blocks, -1).mean(axis=1)
    blockEnergies = np.asarray(energies[:n], dtype=float).reshape(blocks, -1).mean(axis=1)
    slope, standardError, _ = energy_drift(blockTimes, blockEnergies)
    return slope, standardError


def positions_of(context):
    return context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)


def velocities_of(context):
    return context.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(
        unit.nanometer / unit.picosecond)



# A pair closer than this fraction of its sigma is refused when molecules are placed.
PLACEMENT_CLEARANCE = 0.85


# ------------------------------------------------------------------------------------------------
# Shapes: (name, masses in amu, body-frame coordinates in nm, Lennard-Jones sigma in nm, epsilon in
# kJ/mol). A particle with epsilon 0 interacts with nothing.
# ------------------------------------------------------------------------------------------------

class Shape:
    """A rigid molecule in its own frame: masses, coordinates and Lennard-Jones parameters per atom."""

    def __init__(self, name, masses, coordinates, sigmas, epsilons):
        self.name = name
        self.masses = np.asarray(masses, dtype=float)
        self.coordinates = np.asarray(coordinates, dtype=float)
        self.sigmas = np.asarray(sigmas, dtype=float)
        self.epsilons = np.asarray(epsilons, dtype=float)

    def principal_moments(self):
        return np.linalg.eigvalsh(inertia_tensor(self.masses, self.coordinates))


def rod(ratio=1e-6, atoms=5, spacing=0.1, offset=0.05):
    """Collinear carbon-like atoms and one tiny inert mass `offset` nm off the axis at the rod's
    centre, so heavy that smallest / largest principal moment is `ratio`."""
    axis = (np.arange(atoms) - (atoms - 1) / 2) * spacing
    rodMoment = 12.0 * np.sum(axis ** 2)
    # Moments: m' d^2 about the axis, rodMoment and rodMoment + m' d^2 across it (up to the shift of
    # the centre of mass, of order m'/M, which the computed moments include).
    tiny = ratio * rodMoment / (offset ** 2 * (1.0 - ratio))
    coordinates = [[x, 0.0, 0.0] for x in axis] + [[0.0, offset, 0.0]]
    return Shape("rod", [12.0] * atoms + [tiny], coordinates, [0.3] * atoms + [0.1], [0.5] * atoms + [0.0])


def octahedron(name, a, b, c):
    """A centre atom and six light atoms at +-a x, +-b y, +-c z: moments 2m(b^2 + c^2), 2m(a^2 + c^2),
    2m(a^2 + b^2). The outer atoms are small for their distance, so the surface is bumpy and
    collisions exert torques (a smooth sphere of atoms would hardly turn its angular momentum)."""
    coordinates = [[0, 0, 0], [a, 0, 0], [-a, 0, 0], [0, b, 0], [0, -b, 0], [0, 0, c], [0, 0, -c]]
    return Shape(name, [12.0] + [4.0] * 6, coordinates, [0.3] + [0.25] * 6, [0.3] + [0.4] * 6)


def near_spherical(gap=1e-9, size=0.2):
    """(a, b, c)^2 = s (1, 1 + 2 gap, 1 + 6 gap): principal moments 4 m s (1 + gap/2, 1 + 3 gap/2,
    1 + 2 gap), apart by gap and gap / 2 relative."""
    s = size ** 2
    return octahedron("near-spherical", math.sqrt(s), math.sqrt(s * (1 + 2 * gap)), math.sqrt(s * (1 + 6 * gap)))


def near_symmetric(gap=1e-9, size=0.2):
    """A prolate top: (a, b, c)^2 = s (1 + 3 gap, 1, 2), principal moments 4 m s (1 + 3 gap / 2) and
    6 m s (1, 1 + gap)."""
    s = size ** 2
    return octahedron("near-symmetric", math.sqrt(s * (1 + 3 * gap)), math.sqrt(s), math.sqrt(2 * s))


def linear_triatomic():
    """CO2-like: a linear rotor."""
    co = 0.116
    return Shape("linear", [12.011, 15.999, 15.999], [[0, 0, 0], [0, 0, co], [0, 0, -co]],
                 [0.28, 0.305, 0.305], [0.22, 0.66, 0.66])


def bent_triatomic():
    """A generic asymmetric top of water's geometry, every atom interacting."""
    angle, length = np.radians(104.52), 0.09572
    coordinates = [[0, 0, 0], [length * np.sin(angle / 2), length * np.cos(angle / 2), 0],
                   [-length * np.sin(angle / 2), length * np.cos(angle / 2), 0]]
    return Shape("bent", [15.999, 1.008, 1.008], coordinates, [0.315, 0.2, 0.2], [0.636, 0.1, 0.1])


def bath_atom():
    """Argon."""
    return Shape("argon", [39.948], [[0.0, 0.0, 0.0]], [0.34], [0.996])


EXTREME_SHAPES = (rod, near_spherical, near_symmetric, linear_triatomic, bent_triatomic)


# ------------------------------------------------------------------------------------------------
# Building blocks
# ------------------------------------------------------------------------------------------------

def inertia_tensor(masses, positions):
    relative = positions - masses @ positions / masses.sum()
    return np.einsum("i,ij->", masses, relative ** 2) * np.eye(3) - np.einsum("i,ij,ik->jk", masses, relative, relative)


def rigid_thermal_velocities(masses, positions, temperature, rng):
    """Velocities of a rigid molecule at temperature: centre-of-mass velocity and angular velocity
    about each principal axis drawn from Maxwell-Boltzmann (none about the axis of a linear one)."""
    total = masses.sum()
    velocity = rng.normal(scale=np.sqrt(BOLTZMANN * temperature / total), size=3)
    if len(masses) == 1:
        return velocity[None, :]
    moments, axes = np.linalg.eigh(inertia_tensor(masses, positions))
    bodyOmega = np.array([rng.normal(scale=np.sqrt(BOLTZMANN * temperature / moment)) if moment > 1e-10 * moments[-1]
                          else 0.0 for moment in moments])
    return velocity + np.cross(axes @ bodyOmega, positions - masses @ positions / total)


def lennard_jones_pairs(sigmas, epsilons, molecules, cutoff=None):
    """A CustomBondForce with the Lennard-Jones energy of every pair of interacting particles in
    different molecules (Lorentz-Berthelot). With a cutoff it uses periodic boundary conditions
    and goes smoothly to zero (a quintic switch, continuous to the second derivative) from 0.8
    cutoff to cutoff."""
    if cutoff is None:
        force = openmm.CustomBondForce("4*epsilon*((sigma/r)^12 - (sigma/r)^6)")
    else:
        force = openmm.CustomBondForce("4*epsilon*((sigma/r)^12 - (sigma/r)^6)*switch;"
                                       "switch = 1 - x^3*(10 - 15*x + 6*x^2);"
                                       "x = min(1, max(0, (r - switchDistance)/(cutoff - switchDistance)))")
        force.addGlobalParameter("cutoff", cutoff)
        force.addGlobalParameter("switchDistance", 0.8 * cutoff)
        force.setUsesPeriodicBoundaryConditions(True)
    force.addPerBondParameter("sigma")
    force.addPerBondParameter("epsilon")
    molecule = np.empty(len(sigmas), dtype=int)
    for index, members in enumerate(molecules):
        molecule[members] = index
    for i in range(len(sigmas)):
        if epsilons[i] == 0.0:
            continue
        for j in range(i + 1, len(sigmas)):
            if epsilons[j] != 0.0 and molecule[i] != molecule[j]:
                force.addBond(i, j, [0.5 * (sigmas[i] + sigmas[j]), math.sqrt(epsilons[i] * epsilons[j])])
    return force


def place(shapes, edge, rng, periodic, keepOut=None):
    """Random positions and orientations for the shapes in a cube of the given edge (nm), refusing
    overlaps closer than PLACEMENT_CLEARANCE sigma (minimum image if periodic) and, with keepOut =
    (centre, radius), anything inside that sphere. Returns one (n, 3) array per shape."""
    placed, placedSigmas, result = np.zeros((0, 3)), np.zeros(0), []
    for shape in shapes:
        for attempt in range(5000):
            centre = rng.uniform(0.0, edge, size=3)
            candidate = shape.coordinates @ _random_rotation(rng).T + centre
            if keepOut is not None and np.min(np.linalg.norm(candidate - keepOut[0], axis=1)) < keepOut[1]:
                continue
            if len(placed) == 0:
                break
            delta = candidate[:, None, :] - placed[None, :, :]
            if periodic:
                delta -= edge * np.round(delta / edge)
            distance = np.linalg.norm(delta, axis=-1)
            if np.all(distance >= PLACEMENT_CLEARANCE * 0.5 * (shape.sigmas[:, None] + placedSigmas[None, :])):
                break
        else:
            raise RuntimeError(f"could not place a {shape.name} in a {edge:.2f} nm box; lower the density")
        placed = np.vstack([placed, candidate])
        placedSigmas = np.concatenate([placedSigmas, shape.sigmas])
        result.append(candidate)
    return result


class Scenario:
    """A System and the state to start it from.

    Attributes: name, system, positions and velocities ((n, 3) arrays, nm and nm/ps), masses,
    bodies (explicit bodies: lists of particle indices; None when the integrator is to find them
    from the constraints), free (particles in no body), periodic, temperature (K, nominal),
    forcesSumToZero (whether total momentum is conserved), and rigidPairs: (i, j, distance) of
    every pair whose distance must not change (all pairs within each explicit body, or the
    constraints of bodies found from the System).
    """

    def __init__(self, name, system, positions, velocities, bodies, periodic, temperature, forcesSumToZero):
        self.name = name
        self.system = system
        self.positions = np.array(positions, dtype=float)
        self.velocities = np.array(velocities, dtype=float)
        self.masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton)
                                for i in range(system.getNumParticles())])
        self.bodies = bodies
        self.periodic = periodic
        self.temperature = temperature
        self.forcesSumToZero = forcesSumToZero
        if bodies is not None:
            inBody = {i for body in bodies for i in body}
            self.free = [i for i in range(len(self.masses)) if i not in inBody]
            pairs = [(i, j, np.linalg.norm(self.positions[i] - self.positions[j]))
                     for body in bodies for a, i in enumerate(body) for j in body[a + 1:]]
        else:
            self.free = None
            pairs = []
            for k in range(system.getNumConstraints()):
                i, j, distance = system.getConstraintParameters(k)
                pairs.append((i, j, distance.value_in_unit(unit.nanometer)))
        self.rigidPairs = (np.array([p[0] for p in pairs], dtype=int), np.array([p[1] for p in pairs], dtype=int),
                           np.array([p[2] for p in pairs], dtype=float))

    def integrator(self, stepSize, method="Exact"):
        """A RigidBodyIntegrator for this scenario's bodies with the given rotation method."""
        integrator = (openmmrigid.RigidBodyIntegrator(stepSize) if self.bodies is None
                      else openmmrigid.RigidBodyIntegrator(stepSize, self.bodies))
        integrator.setRotationMethod({"Exact": openmmrigid.RigidBodyIntegrator.Exact,
                                      "NoSquish": openmmrigid.RigidBodyIntegrator.NoSquish}[method])
        return integrator


def _system(masses, edge=None):
    system = openmm.System()
    for mass in masses:
        system.addParticle(mass)
    if edge is not None:
        system.setDefaultPeriodicBoxVectors(openmm.Vec3(edge, 0, 0), openmm.Vec3(0, edge, 0), openmm.Vec3(0, 0, edge))
    return system


def _assemble(name, shapes, positions, velocities, asBody, edge, periodic, temperature, forces=True):
    """A Scenario from per-molecule shapes, positions and velocities; asBody[k] says whether
    molecule k is a body (else its particles are free)."""
    molecules, bodies, start = [], [], 0
    for shape, isBody in zip(shapes, asBody):
        members = list(range(start, start + len(shape.masses)))
        molecules.append(members)
        if isBody:
            bodies.append(members)
        start += len(members)
    masses = np.concatenate([shape.masses for shape in shapes])
    system = _system(masses, edge if periodic else None)
    if forces:
        cutoff = min(1.0, 0.49 * edge) if periodic else None
        system.addForce(lennard_jones_pairs(np.concatenate([s.sigmas for s in shapes]),
                                            np.concatenate([s.epsilons for s in shapes]), molecules, cutoff))
    return Scenario(name, system, np.vstack(positions), np.vstack(velocities), bodies, periodic, temperature, True)


# ------------------------------------------------------------------------------------------------
# Scenarios
# ------------------------------------------------------------------------------------------------

def bodies_in_bath(copies=2, bathAtoms=30, temperature=2000.0, density=20.0, periodic=True, seed=1,
                   drift=(0.4, -0.3, 0.2), spin=0.0, shapes=EXTREME_SHAPES):
    """`copies` of each extreme shape as explicit bodies among `bathAtoms` free argon atoms, at
    `density` particles per nm^3, thermal rigid velocities at `temperature` (K) plus a uniform
    drift (nm/ps) and, isolated, a spin (rad/ps) about z through the centre of mass, so that total
    linear and angular momentum are not zero."""
    rng = np.random.default_rng(seed)
    molecules = [make() for make in shapes for _ in range(copies)] + [bath_atom() for _ in range(bathAtoms)]
    count = sum(len(shape.masses) for shape in molecules)
    edge = (count / density) ** (1.0 / 3.0)
    positions = place(molecules, edge, rng, periodic)
    velocities = [rigid_thermal_velocities(s.masses, r, temperature, rng) for s, r in zip(molecules, positions)]
    masses = np.concatenate([s.masses for s in molecules])
    allPositions = np.vstack(positions)
    centre = masses @ allPositions / masses.sum()
    extra = [np.asarray(drift, dtype=float) + np.cross([0.0, 0.0, spin], r - centre) for r in positions]
    velocities = [v + e for v, e in zip(velocities, extra)]
    name = f"bodies in {'periodic' if periodic else 'isolated'} LJ bath, {temperature:g} K"
    isBody = [len(s.masses) > 1 for s in molecules]
    return _assemble(name, molecules, positions, velocities, isBody, edge, periodic, temperature)


def spinning_body(omega=1e4, bathAtoms=0, temperature=300.0, edge=3.0, seed=2, drift=(0.3, 0.1, -0.2)):
    """A bent triatomic spinning at |omega| (rad/ps) about a random direction through its centre of
    mass (v = drift + omega x (r - R)); with bathAtoms > 0, argon around it at `temperature` in a
    periodic cube of the given edge (nm), none closer to its centre than the sphere its atoms sweep
    plus 0.85 sigma. Without a bath the System has no forces at all."""
    rng = np.random.default_rng(seed)
    body = bent_triatomic()
    centred = body.coordinates - body.masses @ body.coordinates / body.masses.sum()
    radius = np.max(np.linalg.norm(centred, axis=1))
    bath = [bath_atom() for _ in range(bathAtoms)]
    edge = edge if bathAtoms else None
    middle = np.full(3, 0.5 * edge) if bathAtoms else np.zeros(3)
    bodyPositions = centred @ _random_rotation(rng).T + middle
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    bodyVelocities = np.asarray(drift, dtype=float) + np.cross(omega * direction, bodyPositions - middle)
    positions, velocities = [bodyPositions], [bodyVelocities]
    if bathAtoms:
        keepOut = (middle, radius + PLACEMENT_CLEARANCE * 0.5 * (0.34 + np.max(body.sigmas)))
        bathPositions = place(bath, edge, rng, True, keepOut)
        positions += bathPositions
        velocities += [rigid_thermal_velocities(s.masses, r, temperature, rng) for s, r in zip(bath, bathPositions)]
    name = f"body spinning at {omega:g}/ps" + (f" in LJ bath of {bathAtoms}" if bathAtoms else ", alone")
    return _assemble(name, [body] + bath, positions, velocities, [True] + [False] * bathAtoms, edge,
                     bathAtoms > 0, temperature, forces=bathAtoms > 0)


def hot_cluster(temperature=5000.0, seed=1, grid=(3, 3, 2), spacing=0.5):
    """cluster() at `temperature`, drifting and spinning (isolated; every body kind)."""
    molecules = cluster(seed=seed, grid=grid, spacing=spacing, temperature=temperature, drift=(0.3, -0.2, 0.1),
                        spin=1.5)
    return Scenario(f"hot cluster, {temperature:g} K", molecules.system, molecules.positions, molecules.velocities,
                    molecules.bodies, False, temperature, True)


@functools.lru_cache(maxsize=None)
def _water_box(model, size, seed, cutoff):
    return water_box(model, size=size, seed=seed, cutoff=cutoff)


def water(model="tip3p", size=1.7, temperature=300.0, cutoff=0.7, seed=5):
    """A rigid-water box (PME) from water_box (built once per set of arguments) without its
    CMMotionRemover, its 300 K velocities scaled to `temperature` (scaling keeps them rigid)."""
    box = _water_box(model, size, seed, cutoff)
    system = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(box.system))
    for k in reversed(range(system.getNumForces())):
        if isinstance(system.getForce(k), openmm.CMMotionRemover):
            system.removeForce(k)
    velocities = box.velocities * math.sqrt(temperature / 300.0)
    label = {"tip3p": "TIP3P", "tip4pew": "TIP4P-Ew"}[model]
    name = f"{label} water x{len(list(box.topology.residues()))}, {temperature:g} K"
    # PME's reciprocal-space forces do not sum to zero, and the CPU platform computes them in single precision.
    return Scenario(name, system, box.positions, velocities, None, True, temperature, False)


# ------------------------------------------------------------------------------------------------
# Measurements
# ------------------------------------------------------------------------------------------------

def rigidity_error(positions, rigidPairs):
    """The largest change (nm) of any distance that must stay fixed."""
    i, j, distance = rigidPairs
    if len(i) == 0:
        return 0.0
    return float(np.max(np.abs(np.linalg.norm(positions[i] - positions[j], axis=1) - distance)))


def momenta(masses, positions, velocities):
    """Total linear momentum and angular momentum about the origin (amu nm/ps, amu nm^2/ps)."""
    weighted = masses[:, None] * velocities
    return weighted.sum(axis=0), np.cross(positions, weighted).sum(axis=0)


def separatrix_sides(masses, positions, velocities, bodies):
    """For each body, the sign of 2 E I2 - L^2 of its rotation about its centre (+1: rotation about
    the axis of the smallest moment, -1: about that of the largest; the separatrix is 0), or 0 for
    a linear or single-particle body. 2 E I2 - L^2 = sum_k L_k^2 (I2 / I_k - 1) in principal axes,
    which keeps the moments' small differences exact. Bodies of equal size are done together."""
    sides = np.zeros(len(bodies), dtype=int)
    bySize = {}
    for b, body in enumerate(bodies):
        if len(body) > 1:
            bySize.setdefault(len(body), []).append(b)
    for group in bySize.values():
        members = np.array([bodies[b] for b in group])                       # (bodies, particles)
        m, r, v = masses[members], positions[members], velocities[members]
        total = m.sum(axis=1)
        relative = r - np.einsum("bi,bij->bj", m, r)[:, None, :] / total[:, None, None]
        spin = v - np.einsum("bi,bij->bj", m, v)[:, None, :] / total[:, None, None]
        inertia = (np.einsum("bi,bij->b", m, relative ** 2)[:, None, None] * np.eye(3)
                   - np.einsum("bi,bij,bik->bjk", m, relative, relative))
        moments, axes = np.linalg.eigh(inertia)
        angular = np.einsum("bji,bj->bi", axes, np.einsum("bi,bij->bj", m, np.cross(relative, spin)))
        rotating = moments[:, 0] > 1e-10 * moments[:, 2]
        moments[~rotating] = 1.0  # linear: no separatrix (and no division by its zero moment)
        value = np.sum(angular ** 2 * (moments[:, 1:2] / moments - 1.0), axis=1)
        sides[group] = np.where(rotating, np.sign(value), 0).astype(int)
    return sides


class Run:
    """What run() measured. Attributes: steps (completed), stepSize (ps), error (the exception's
    message if the integrator raised), finite (no NaN or infinity seen), times, energies (kJ/mol,
    total), kinetic0 (initial kinetic energy), dof, rigidity (largest change of any fixed distance,
    nm), momentumChange (|P - P0|, amu nm/ps) and momentum0 (|P0|), angularChange and angular0
    (isolated systems only, else None), crossings (separatrix crossings seen, per body), kinds (of the
    bodies, as rigidtesting.bodies.bodyKind names them from the starting positions), and context and
    integrator (at the end of the run)."""

    def max_energy_change(self):
        return float(np.max(np.abs(self.energies - self.energies[0]))) if len(self.energies) > 1 else 0.0

    def drift(self):
        """The least-squares slope of the total energy, kJ/mol/ps."""
        return energy_drift(self.times, self.energies)[0] if len(self.energies) > 2 else 0.0

    def relative_momentum_change(self):
        return self.momentumChange / self.momentum0

    def relative_angular_change(self):
        return None if self.angularChange is None else self.angularChange / self.angular0


def _state_arrays(context):
    state = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
    return (state.getPositions(asNumpy=True).value_in_unit(unit.nanometer),
            state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond),
            (state.getPotentialEnergy() + state.getKineticEnergy()).value_in_unit(unit.kilojoule_per_mole),
            state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole))


def run(scenario, integrator, platform, steps, interval, catch=False, properties=None):
    """Integrate `steps` steps of the scenario with `integrator` on `platform` (name), sampling every
    `interval` steps. With catch=True an OpenMMException from the integrator ends the run and is
    recorded (a run that blows up) instead of propagating. Stops early once anything is not finite."""
    platformObject, defaults = platform_and_properties(platform)
    context = openmm.Context(scenario.system, integrator, platformObject, dict(defaults, **(properties or {})))
    context.setPositions(scenario.positions)
    context.setVelocities(scenario.velocities)
    rigid = isinstance(integrator, openmmrigid.RigidBodyIntegratorBase)
    bodies = ([list(integrator.getBodyParticles(b)) for b in range(integrator.getNumBodies())] if rigid
              else (scenario.bodies or []))
    result = Run()
    result.integrator = integrator
    result.stepSize = integrator.getStepSize().value_in_unit(unit.picosecond)
    result.kinds = (sorted({bodyKind(scenario.masses[body], scenario.positions[body]) for body in bodies}) if rigid
                    else [])
    result.dof = (rigidDegreesOfFreedom(context, integrator) if rigid else
                  3 * scenario.system.getNumParticles()
                  - sum(scenario.system.isVirtualSite(i) * 3 for i in range(scenario.system.getNumParticles()))
                  - scenario.system.getNumConstraints())
    result.error, result.finite, result.steps = None, True, 0
    result.rigidity = 0.0
    times, energies, sides = [], [], []
    isolated = not scenario.periodic
    momentum0 = angular0 = None
    momentumChange = angularChange = 0.0
    while True:
        positions, velocities, energy, kinetic = _state_arrays(context)
        if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(velocities)) and np.isfinite(energy)):
            result.finite = False
            break
        linear, angular = momenta(scenario.masses, positions, velocities)
        if momentum0 is None:
            momentum0, angular0, result.kinetic0 = linear, angular, kinetic
        momentumChange = max(momentumChange, float(np.linalg.norm(linear - momentum0)))
        angularChange = max(angularChange, float(np.linalg.norm(angular - angular0)))
        if result.steps > 0 or scenario.bodies is not None:
            # Bodies found from constraints take their shape from the constraint distances, which
            # the starting positions may miss by a rounding (water_box's come from the CPU
            # platform's SETTLE, whose H-H distance is single precision): the first step projects them.
            result.rigidity = max(result.rigidity, rigidity_error(positions, scenario.rigidPairs))
        times.append(result.steps * result.stepSize)
        energies.append(energy)
        sides.append(separatrix_sides(scenario.masses, positions, velocities, bodies))
        if result.steps >= steps:
            break
        block = min(interval, steps - result.steps)
        try:
            integrator.step(block)
        except openmm.OpenMMException as error:
            if not catch:
                raise
            result.error = str(error).split("\n")[0]
            result.finite = "nan" not in result.error.lower() and result.finite
            break
        result.steps += block
    result.times, result.energies = np.array(times), np.array(energies)
    result.momentum0 = float(np.linalg.norm(momentum0))
    result.momentumChange = momentumChange
    result.angular0 = float(np.linalg.norm(angular0)) if isolated else None
    result.angularChange = angularChange if isolated else None
    sides = np.array(sides)
    result.crossings = (np.sum((sides[1:] * sides[:-1]) < 0, axis=0) if len(sides) > 1
                        else np.zeros(len(bodies), dtype=int))
    result.context = context
    return result


def impulse_mismatch(context, masses, steps):
    """Step an on-step integrator (velocities at the same time as positions) `steps` times, one at
    a time, and compare the change of total momentum with the impulse of the net force,
    sum over steps of dt (F_n + F_{n+1}) / 2 (massless virtual sites excluded: their forces have
    already been passed on to their parents). Returns the largest difference relative to the total
    magnitude of the impulses, sum dt (|F_n| + |F_{n+1}|) / 2 over all particles."""
    integrator = context.getIntegrator()
    dt = integrator.getStepSize().value_in_unit(unit.picosecond)
    massive = (masses > 0)[:, None]

    def sample():
        state = context.getState(getVelocities=True, getForces=True)
        forces = state.getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole / unit.nanometer) * massive
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
        return masses @ velocities, forces.sum(axis=0), np.abs(forces).sum()

    momentum0, force, magnitude = sample()
    impulse, scale, worst = np.zeros(3), 0.0, 0.0
    for _ in range(steps):
        integrator.step(1)
        momentum, nextForce, nextMagnitude = sample()
        impulse += 0.5 * dt * (force + nextForce)
        scale += 0.5 * dt * (magnitude + nextMagnitude)
        worst = max(worst, float(np.max(np.abs(momentum - momentum0 - impulse))))
        force, magnitude = nextForce, nextMagnitude
    return worst / scale

"""Helpers shared by the examples (not part of openmmrigid): boxes of small rigid molecules, and what
the examples measure in their runs, from the State with numpy.

Boxes of rigid molecules
    RigidMolecule, boxEdge(), rigidMoleculeBox(), compressBox(), equilibrateByRedraws()
Measurements
    sampleNVE(), energyDrift(), rigidTemperatures(), shapeDeviations(),
    principalMoments(), bodyKinds(), degreesOfFreedom()

The examples import it as ``from _molecules import ...``: ``python examples/X.py`` puts the examples'
folder on sys.path.
"""

import dataclasses
import time

import numpy as np
import openmm
from openmm import unit

MOLAR_GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
WATERS_PER_CUBIC_NANOMETRE = 33.4  # liquid water near 300 K and 1 bar
AVOGADRO = 6.02214076e23
ROTATIONAL_DEGREES_OF_FREEDOM = {"point": 0, "linear": 2, "spherical": 3, "symmetric": 3, "asymmetric": 3}


# ---------------------------------------------------------------------------------------------------
# Boxes of small rigid molecules


@dataclasses.dataclass
class RigidMolecule:
    """Geometry (nm, any orientation) and nonbonded parameters (charges in e, sigmas in nm, epsilons
    in kJ/mol) of one rigid molecule, per atom.

    combining: "lorentz-berthelot" (arithmetic sigma, geometric epsilon: NonbondedForce does it) or
    "geometric" (geometric sigma and epsilon, as OPLS: a CustomNonbondedForce does the Lennard-Jones).
    """
    name: str
    masses: list
    coordinates: list
    charges: list
    sigmas: list
    epsilons: list
    combining: str = "lorentz-berthelot"

    @property
    def mass(self):
        """The molecule's mass in amu."""
        return float(np.sum(self.masses))


def boxEdge(molecule, count, density):
    """The edge (nm) of a cubic box holding `count` molecules at `density` (g/cm^3)."""
    return (count*molecule.mass/AVOGADRO/density*1e21)**(1/3)


def randomRotation(rng):
    """A rotation matrix uniformly distributed on SO(3), from a random unit quaternion."""
    quaternion = rng.normal(size=4)
    w, x, y, z = quaternion/np.linalg.norm(quaternion)
    return np.array([[1 - 2*(y*y + z*z), 2*(x*y - w*z), 2*(x*z + w*y)],
                     [2*(x*y + w*z), 1 - 2*(x*x + z*z), 2*(y*z - w*x)],
                     [2*(x*z - w*y), 2*(y*z + w*x), 1 - 2*(x*x + y*y)]])


def packMolecules(molecule, count, edge, rng, closest=0.8, attempts=200000):
    """Positions (count, atoms, 3) of randomly placed and oriented copies of the molecule in a periodic
    cube, each kept only if every atom pair between molecules is at least `closest` times its
    Lennard-Jones sigma apart (the mild overlaps left relax in the first steps)."""
    local = np.array(molecule.coordinates, dtype=float)
    local -= np.average(local, axis=0, weights=molecule.masses)
    sigmas = np.array(molecule.sigmas)
    contact = closest*0.5*(sigmas[:, None] + sigmas[None, :])
    placed = np.empty((0, len(local), 3))
    for _ in range(attempts):
        candidate = local @ randomRotation(rng).T + rng.uniform(0, edge, size=3)
        separation = candidate[None, :, None, :] - placed[:, None, :, :]
        separation -= edge*np.round(separation/edge)
        if np.any(np.linalg.norm(separation, axis=-1) < contact):
            continue
        placed = np.concatenate([placed, candidate[None]])
        if len(placed) == count:
            return placed
    raise RuntimeError(f"placed only {len(placed)} of {count} {molecule.name} molecules; lower the density")


def rigidMoleculeBox(molecule, count, density, seed, cutoff=1.0, switchWidth=0.1):
    """A periodic cubic box of `count` copies of a RigidMolecule at `density` (g/cm^3), packed at random.

    Returns (system, positions, bodies): the System (PME for the charges; Lennard-Jones switched off
    between cutoff - switchWidth and cutoff nm, with the long-range dispersion correction; nothing
    acts within a molecule), the positions (particles x 3, nm) and one list of particle indices per
    molecule, for ``RigidBodyIntegrator(stepSize, bodies)``.
    """
    rng = np.random.default_rng(seed)
    edge = boxEdge(molecule, count, density)
    positions = packMolecules(molecule, count, edge, rng).reshape(-1, 3)
    system = openmm.System()
    system.setDefaultPeriodicBoxVectors(*(openmm.Vec3(*row) for row in edge*np.eye(3)))
    coulomb = openmm.NonbondedForce()
    coulomb.setNonbondedMethod(openmm.NonbondedForce.PME)
    geometric = molecule.combining == "geometric"
    if geometric:  # the Lennard-Jones in a CustomNonbondedForce, NonbondedForce only for the charges
        lennardJones = openmm.CustomNonbondedForce("4*epsilon*((sigma/r)^12 - (sigma/r)^6); "
                                                   "sigma = sqrt(sigma1*sigma2); epsilon = sqrt(epsilon1*epsilon2)")
        lennardJones.addPerParticleParameter("sigma")
        lennardJones.addPerParticleParameter("epsilon")
        lennardJones.setNonbondedMethod(openmm.CustomNonbondedForce.CutoffPeriodic)
        lennardJones.setUseLongRangeCorrection(True)
    else:
        lennardJones = coulomb
    forces = [coulomb, lennardJones] if geometric else [coulomb]
    for force in forces:
        force.setCutoffDistance(cutoff)
    lennardJones.setUseSwitchingFunction(True)
    lennardJones.setSwitchingDistance(cutoff - switchWidth)
    bodies = []
    for _ in range(count):
        body = [system.addParticle(mass) for mass in molecule.masses]
        for charge, sigma, epsilon in zip(molecule.charges, molecule.sigmas, molecule.epsilons):
            if geometric:
                coulomb.addParticle(charge, 1.0, 0.0)
                lennardJones.addParticle([sigma, epsilon])
            else:
                coulomb.addParticle(charge, sigma, epsilon)
        for a in range(len(body)):
            for b in range(a + 1, len(body)):
                coulomb.addException(body[a], body[b], 0.0, 1.0, 0.0)
                if geometric:
                    lennardJones.addExclusion(body[a], body[b])
        bodies.append(body)
    for force in forces:
        system.addForce(force)
    return system, positions, bodies


def particleMasses(system):
    """The particle masses in amu (0 for virtual sites)."""
    return np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])


def equilibrateByRedraws(context, integrator, temperature, picoseconds, every=0.1, seed=1):
    """Andersen-style equilibration with the integrator itself: run `picoseconds`, the velocities redrawn
    at `temperature` (K) every `every` ps with zero total momentum, then scaled to that temperature
    exactly, so that an NVE run that follows starts at the temperature asked for.

    A rigid-body integrator projects the particle velocities onto rigid motion; the momentum and
    angular momentum of independent Maxwell-Boltzmann particle velocities are Gaussian with
    covariances kT M and kT I, so each redraw is an exact draw from the bodies' Boltzmann distribution.
    """
    masses = particleMasses(context.getSystem())
    interval = max(1, int(round(every/integrator.getStepSize().value_in_unit(unit.picosecond))))
    for block in range(int(round(picoseconds/every))):
        context.setVelocitiesToTemperature(temperature*unit.kelvin, seed + block)
        state = context.getState(getVelocities=True)
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
        context.setVelocities(velocities - masses @ velocities/masses.sum())
        integrator.step(interval)
    current = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    velocities = context.getState(getVelocities=True).getVelocities(asNumpy=True)
    context.setVelocities(velocities*np.sqrt(temperature/current))


def compressBox(context, integrator, bodies, edge, temperature, factor=0.98, picosecondsPerStage=0.2, seed=1):
    """Shrink a cubic box to `edge` (nm), `factor` at a time, moving the bodies' centres of mass with it
    (their shapes unchanged), with equilibrateByRedraws() for picosecondsPerStage after each stage.
    Returns the number of stages."""
    bodies = np.array(bodies)
    bodyMasses = particleMasses(context.getSystem())[bodies][:, :, None]
    current = context.getState().getPeriodicBoxVectors()[0][0].value_in_unit(unit.nanometer)
    stage = 0
    while current > edge*(1 + 1e-12):
        smaller = max(edge, current*factor)
        positions = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        centres = (bodyMasses*positions[bodies]).sum(axis=1, keepdims=True)/bodyMasses.sum(axis=1, keepdims=True)
        positions[bodies] += (smaller/current - 1)*centres
        context.setPeriodicBoxVectors(*(openmm.Vec3(*row) for row in smaller*np.eye(3)))
        context.setPositions(positions)
        equilibrateByRedraws(context, integrator, temperature, picosecondsPerStage, seed=seed + 1000*stage)
        current, stage = smaller, stage + 1
    return stage


# ---------------------------------------------------------------------------------------------------
# Measurements


def kineticEnergies(masses, velocities, bodies):
    """Translational and rotational kinetic energy (kJ/mol) of rigid bodies that all have the same
    number of particles (bodies: an array bodies x particles) and are alone in the System: that of
    their centres of mass, and the rest."""
    m, v = masses[bodies][:, :, None], velocities[bodies]
    total = 0.5*np.sum(m*v*v)
    momenta, bodyMasses = (m*v).sum(axis=1), m.sum(axis=1)
    translational = 0.5*np.sum(momenta**2/bodyMasses)
    return translational, total - translational


@dataclasses.dataclass
class NVESamples:
    """Samples of a run: times (ps, from 0), total energies (kJ/mol), the bodies' translational and
    rotational kinetic energies (kJ/mol; empty unless sampleNVE() was given the bodies), and the wall
    seconds per step."""
    times: np.ndarray
    energies: np.ndarray
    translational: np.ndarray
    rotational: np.ndarray
    secondsPerStep: float


def sampleNVE(context, integrator, steps, sampleEvery, bodies=None):
    """Run `steps` steps from the Context's state, sampling at the start and every `sampleEvery` steps;
    with `bodies` (a box of one rigid molecule, see kineticEnergies()) also the kinetic energies of
    translation and rotation, from the State's velocities."""
    masses = particleMasses(context.getSystem())
    times, energies, translational, rotational = [], [], [], []
    elapsed = 0.0
    for sample in range(steps//sampleEvery + 1):
        if sample > 0:
            started = time.perf_counter()
            integrator.step(sampleEvery)
            elapsed += time.perf_counter() - started
        state = context.getState(getEnergy=True, getVelocities=bodies is not None)
        times.append(state.getTime().value_in_unit(unit.picosecond))
        energies.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole))
        if bodies is not None:
            velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
            kinetic = kineticEnergies(masses, velocities, np.array(bodies))
            translational.append(kinetic[0])
            rotational.append(kinetic[1])
    return NVESamples(np.array(times) - times[0], np.array(energies), np.array(translational), np.array(rotational),
                      elapsed/max(steps, 1))


def energyDrift(times, energies, dof):
    """Energy drift and fluctuation of a run: the slope of the least-squares line through the total
    energies (kJ/mol) against time (ps), in kJ/mol/ns per degree of freedom, and the standard deviation
    of the energies about that line (kJ/mol)."""
    times, energies = np.asarray(times, dtype=float), np.asarray(energies, dtype=float)
    slope, intercept = np.polyfit(times, energies, 1)
    return float(slope*1000/dof), float(np.std(energies - (slope*times + intercept)))


def blockAverage(values, blocks=5):
    """The mean of a time series and its standard error from `blocks` consecutive block means."""
    means = np.array([block.mean() for block in np.array_split(np.asarray(values, dtype=float), blocks)])
    return means.mean(), means.std(ddof=1)/np.sqrt(blocks)


def rigidTemperatures(samples, bodies, rotationalDofPerBody, blocks=5):
    """Translational and rotational temperatures (K) of a box of `bodies` rigid bodies from sampleNVE()'s
    kinetic energies, and their difference (rotational minus translational: zero at equipartition),
    each as (mean, standard error) from `blocks` block means.

    Translation: 3 per body less 3 for the total momentum, zero and conserved; rotation:
    rotationalDofPerBody (2 for linear bodies, 3 otherwise) per body.
    """
    translational = 2*samples.translational/((3*bodies - 3)*MOLAR_GAS_CONSTANT)
    rotational = 2*samples.rotational/(rotationalDofPerBody*bodies*MOLAR_GAS_CONSTANT)
    return (blockAverage(translational, blocks), blockAverage(rotational, blocks),
            blockAverage(rotational - translational, blocks))


def shapeDeviations(context, bodies, reference):
    """How far the bodies are from their shapes in `reference` positions (particles x 3, nm): the largest
    change of any distance between two particles of a body (nm), and the singular values of each body's
    centred coordinates over the square root of its size (bodies x 3, descending: a linear body has the
    last two zero, a planar one the last). The bodies must all have the same number of particles."""
    positions = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    now, before = positions[np.array(bodies)], np.asarray(reference)[np.array(bodies)]
    pairs = np.triu_indices(now.shape[1], 1)

    def distances(x):
        return np.linalg.norm(x[:, :, None, :] - x[:, None, :, :], axis=-1)[:, pairs[0], pairs[1]]

    change = float(np.abs(distances(now) - distances(before)).max())
    extents = np.linalg.svd(now - now.mean(axis=1, keepdims=True), compute_uv=False)/np.sqrt(now.shape[1])
    return change, extents


def principalMoments(masses, positions):
    """The principal moments of inertia (amu nm^2, ascending) of particles with these masses (amu) and
    positions (nm): the eigenvalues of their inertia tensor about their centre of mass."""
    masses, positions = np.asarray(masses, dtype=float), np.asarray(positions, dtype=float)
    r = positions - np.average(positions, axis=0, weights=masses)
    inertia = np.einsum("i,ij,ik->jk", masses, r, r)
    return np.clip(np.linalg.eigvalsh(np.trace(inertia)*np.eye(3) - inertia), 0, None)  # clip -1e-17 to 0


def bodyKind(moments, tolerance=1e-6):
    """The kind of a rigid body by its principal moments (ascending), the integrator's classification:
    "point" (all zero), "linear" (one zero), "spherical" (all equal), "symmetric" (two equal) or
    "asymmetric", equal and zero meaning within `tolerance` times the largest (the integrator's own
    tolerance is far tighter; this one also suits positions read back from a single-precision State)."""
    small, middle, large = moments
    equal = tolerance*large
    if large == 0:
        return "point"
    if small <= equal:
        return "linear"
    if large - small <= equal:
        return "spherical"
    return "symmetric" if min(middle - small, large - middle) <= equal else "asymmetric"


def bodyKinds(system, positions, bodies):
    """The kind of every body (a list of particle indices) at these positions (particles x 3, nm)."""
    masses, positions = particleMasses(system), np.asarray(positions, dtype=float)
    return [bodyKind(principalMoments(masses[list(body)], positions[list(body)])) for body in bodies]


def degreesOfFreedom(system, bodies=(), kinds=()):
    """The degrees of freedom a rigid-body integrator moves: 3 per massive particle in no body, less one
    per constraint between two such particles; 3 per body plus 0, 2 or 3 rotational ones by its kind;
    less 3 with a CMMotionRemover. Without bodies it is OpenMM's own count (bodies held by constraints,
    such as rigid waters, are counted right by their constraints)."""
    masses = particleMasses(system)
    inBody = np.zeros(len(masses), dtype=bool)
    for body in bodies:
        inBody[list(body)] = True
    free = np.sum((masses > 0) & ~inBody)
    constraints = 0
    for k in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(k)
        constraints += not (inBody[i] or inBody[j])
    remover = any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
    rotational = sum(ROTATIONAL_DEGREES_OF_FREEDOM[kind] for kind in kinds)
    return int(3*free - constraints + 3*len(bodies) + rotational - (3 if remover else 0))

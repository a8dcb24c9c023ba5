"""Small systems and measurements shared by the examples and benchmarks (and usable by tests).

Systems
    alanineDipeptide()
        Alanine dipeptide (ACE-ALA-NME, all hydrogens, in vacuum) as an ``openmm.app.PDBFile``: a
        solute for ``Modeller.addSolvent``, with names the amber14 force field matches.
    waterBox(model, molecules=None, edge=None, ...)
        A periodic box of water built with ``openmm.app`` (Modeller and ForceField), PME, rigid water:
        ``(topology, positions, system)``.
    RigidMolecule, rigidMoleculeBox(molecule, count, density, seed)
        A box of copies of one small rigid molecule at random positions and orientations, with the
        bodies to give ``RigidBodyIntegrator`` explicitly.
    randomRotation(rng)
        A rotation matrix uniformly distributed on SO(3).

Running and measuring
    equilibrateByRedraws(), compressBox(), sampleNVE(), energyDrift(), blockAverage(),
    rigidTemperatures(), shapeDeviations(), bodyKinds(), degreesOfFreedom().

openmmrigid.testing.samplingerror
    The near-equilibrium estimate of the configuration-space KL divergence from shadow work
    (``configurationKL``), and a 1-D harmonic oscillator whose exact value is known, shared by
    benchmarks/sampling_error.py and the test suite.

openmmrigid.testing.stress
    The stability stress scenarios (extreme body shapes in a hot bath, a fast spinning body, hot
    clusters and water) and their measurements, shared by benchmarks/stress.py and the test suite.
"""

import dataclasses
import io
import time

import numpy as np
import openmm
from openmm import app, unit

__all__ = ["alanineDipeptide", "waterBox", "degreesOfFreedom", "randomRotation", "RigidMolecule", "boxEdge",
           "rigidMoleculeBox", "equilibrateByRedraws", "compressBox", "NVESamples", "sampleNVE", "energyDrift",
           "blockAverage", "rigidTemperatures", "shapeDeviations", "bodyKinds"]

MOLAR_GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
WATERS_PER_CUBIC_NANOMETRE = 33.4  # liquid water near 300 K and 1 bar
_AVOGADRO = 6.02214076e23

_ALANINE_DIPEPTIDE_PDB = """\
ATOM      1  H1  ACE     1       2.000   1.000  -0.000
ATOM      2  CH3 ACE     1       2.000   2.090   0.000
ATOM      3  H2  ACE     1       1.486   2.454   0.890
ATOM      4  H3  ACE     1       1.486   2.454  -0.890
ATOM      5  C   ACE     1       3.427   2.641  -0.000
ATOM      6  O   ACE     1       4.391   1.877  -0.000
ATOM      7  N   ALA     2       3.555   3.970  -0.000
ATOM      8  H   ALA     2       2.733   4.556  -0.000
ATOM      9  CA  ALA     2       4.853   4.614  -0.000
ATOM     10  HA  ALA     2       5.408   4.316   0.890
ATOM     11  CB  ALA     2       5.661   4.221  -1.232
ATOM     12  HB1 ALA     2       5.123   4.521  -2.131
ATOM     13  HB2 ALA     2       6.630   4.719  -1.206
ATOM     14  HB3 ALA     2       5.809   3.141  -1.241
ATOM     15  C   ALA     2       4.713   6.129   0.000
ATOM     16  O   ALA     2       3.601   6.653   0.000
ATOM     17  N   NME     3       5.846   6.835   0.000
ATOM     18  H   NME     3       6.737   6.359  -0.000
ATOM     19  C   NME     3       5.846   8.284   0.000
ATOM     20  H1  NME     3       4.819   8.648   0.000
ATOM     21  H2  NME     3       6.360   8.648   0.890
ATOM     22  H3  NME     3       6.360   8.648  -0.890
TER
END
"""


def alanineDipeptide():
    """Alanine dipeptide (ACE-ALA-NME, 22 atoms) in vacuum: an openmm.app.PDBFile."""
    return app.PDBFile(io.StringIO(_ALANINE_DIPEPTIDE_PDB))


# ---------------------------------------------------------------------------------------------------
# Water


def waterBox(model="tip4pew", molecules=None, edge=None, forceField=None, solute=None, **options):
    """A periodic cubic box of rigid water built with openmm.app: (topology, positions, system).

    model: Modeller.addSolvent's water model ("tip3p", "spce", "tip4pew", "tip5p", ...).
    molecules: how many waters to add, or edge: the edge of the cubic box in nm (give one of the two);
    with neither, 500 waters. forceField: an ``app.ForceField``, or file names for one (default
    ``"<model>.xml"`` from openmm's data). solute: an ``app.PDBFile`` (or anything with ``topology`` and
    ``positions``) to solvate; it comes first in the topology. options go to
    ``ForceField.createSystem``; unless given there: PME, a 0.9 nm cutoff (at most 0.45 of the edge
    when the edge is given), ``rigidWater=True``, ``ewaldErrorTolerance=5e-4``.
    """
    if molecules is not None and edge is not None:
        raise ValueError("waterBox: give the number of molecules or the edge of the box, not both")
    if forceField is None:
        forceField = app.ForceField(f"{model}.xml")
    elif not isinstance(forceField, app.ForceField):
        forceField = app.ForceField(*([forceField] if isinstance(forceField, str) else forceField))
    if solute is not None:
        modeller = app.Modeller(solute.topology, solute.positions)
    else:
        modeller = app.Modeller(app.Topology(), [])
    if edge is not None:
        modeller.addSolvent(forceField, model=model, boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
        cutoff = min(0.9, 0.45*edge)
    else:
        modeller.addSolvent(forceField, model=model, numAdded=500 if molecules is None else molecules)
        cutoff = 0.9
    settings = dict(nonbondedMethod=app.PME, nonbondedCutoff=cutoff*unit.nanometer, rigidWater=True,
                    ewaldErrorTolerance=5e-4)
    settings.update(options)
    system = forceField.createSystem(modeller.topology, **settings)
    return modeller.topology, modeller.positions, system


def degreesOfFreedom(system):
    """OpenMM's count for a System: 3 per massive particle, less one per constraint and 3 more with a
    CMMotionRemover (what a stock integrator's temperature uses)."""
    massive = sum(1 for i in range(system.getNumParticles()) if system.getParticleMass(i) > 0*unit.dalton)
    remover = any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
    return 3*massive - system.getNumConstraints() - (3 if remover else 0)


# ---------------------------------------------------------------------------------------------------
# Boxes of small rigid molecules


def randomRotation(rng):
    """A rotation matrix uniformly distributed on SO(3), from a random unit quaternion (rng: a numpy
    ``Generator``)."""
    quaternion = rng.normal(size=4)
    w, x, y, z = quaternion/np.linalg.norm(quaternion)
    return np.array([[1 - 2*(y*y + z*z), 2*(x*y - w*z), 2*(x*z + w*y)],
                     [2*(x*y + w*z), 1 - 2*(x*x + z*z), 2*(y*z - w*x)],
                     [2*(x*z - w*y), 2*(y*z + w*x), 1 - 2*(x*x + y*y)]])


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
    return (count*molecule.mass/_AVOGADRO/density*1e21)**(1/3)


def _packMolecules(molecule, count, edge, rng, closest=0.8, attempts=200000):
    """Positions (count, atoms, 3) of randomly placed and oriented copies of the molecule in a periodic
    cube, each accepted only if every atom pair between molecules is at least `closest` times its
    Lennard-Jones sigma apart (the mild overlaps left relax in the first steps)."""
    local = np.array(molecule.coordinates, dtype=float)
    local -= np.average(local, axis=0, weights=molecule.masses)
    sigmas = np.array(molecule.sigmas)
    contact = closest*0.5*(sigmas[:, None] + sigmas[None, :])
    placed = np.empty((0, len(local), 3))
    for _ in range(attempts):
        candidate = local @ randomRotation(rng).T + rng.uniform(0, edge, size=3)
        if len(placed):
            separation = candidate[None, :, None, :] - placed[:, None, :, :]
            separation -= edge*np.round(separation/edge)
            if np.any(np.linalg.norm(separation, axis=-1) < contact[None, :, :]):
                continue
        placed = np.concatenate([placed, candidate[None]])
        if len(placed) == count:
            return placed
    raise RuntimeError(f"rigidMoleculeBox: placed only {len(placed)} of {count} {molecule.name} molecules; "
                       "lower the density")


def rigidMoleculeBox(molecule, count, density, seed, cutoff=1.0, switchWidth=0.1):
    """A periodic cubic box of `count` copies of a RigidMolecule at `density` (g/cm^3), packed at random.

    Returns (system, positions, bodies): the System (PME for the charges; Lennard-Jones switched off
    between cutoff - switchWidth and cutoff nm, with the long-range dispersion correction; nothing
    acts within a molecule), positions (particles x 3, nm) and one list of particle indices per
    molecule, for ``RigidBodyIntegrator(stepSize, bodies)``. Random packing jams well below liquid
    density for larger molecules: pack dilute and bring the box to density with compressBox().
    """
    rng = np.random.default_rng(seed)
    edge = boxEdge(molecule, count, density)
    positions = _packMolecules(molecule, count, edge, rng)
    system = openmm.System()
    system.setDefaultPeriodicBoxVectors(*(openmm.Vec3(*row) for row in edge*np.eye(3)))
    coulomb = openmm.NonbondedForce()
    coulomb.setNonbondedMethod(openmm.NonbondedForce.PME)
    coulomb.setCutoffDistance(cutoff)
    geometric = molecule.combining == "geometric"
    if geometric:
        dispersion = openmm.CustomNonbondedForce("4*epsilon*((sigma/r)^12 - (sigma/r)^6); "
                                                 "sigma = sqrt(sigma1*sigma2); epsilon = sqrt(epsilon1*epsilon2)")
        dispersion.addPerParticleParameter("sigma")
        dispersion.addPerParticleParameter("epsilon")
        dispersion.setNonbondedMethod(openmm.CustomNonbondedForce.CutoffPeriodic)
        dispersion.setUseLongRangeCorrection(True)
    lennardJones = dispersion if geometric else coulomb
    lennardJones.setCutoffDistance(cutoff)
    lennardJones.setUseSwitchingFunction(True)
    lennardJones.setSwitchingDistance(cutoff - switchWidth)
    bodies = []
    for _ in range(count):
        body = [system.addParticle(mass) for mass in molecule.masses]
        for charge, sigma, epsilon in zip(molecule.charges, molecule.sigmas, molecule.epsilons):
            if geometric:
                coulomb.addParticle(charge, 1.0, 0.0)
                dispersion.addParticle([sigma, epsilon])
            else:
                coulomb.addParticle(charge, sigma, epsilon)
        for a in range(len(body)):
            for b in range(a + 1, len(body)):
                coulomb.addException(body[a], body[b], 0.0, 1.0, 0.0)
                if geometric:
                    dispersion.addExclusion(body[a], body[b])
        bodies.append(body)
    system.addForce(coulomb)
    if geometric:
        system.addForce(dispersion)
    return system, positions.reshape(-1, 3), bodies


def particleMasses(system):
    """The System's particle masses in amu, as a numpy array (0 for virtual sites)."""
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
    dt = integrator.getStepSize().value_in_unit(unit.picosecond)
    interval = max(1, int(round(every/dt)))
    velocityUnit = unit.nanometer/unit.picosecond
    for block in range(int(round(picoseconds/every))):
        context.setVelocitiesToTemperature(temperature*unit.kelvin, seed + block)
        velocities = context.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(velocityUnit)
        context.setVelocities(velocities - masses @ velocities/masses.sum())
        integrator.step(interval)
    current = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    velocities = context.getState(getVelocities=True).getVelocities(asNumpy=True)
    context.setVelocities(velocities*np.sqrt(temperature/current))


def compressBox(context, integrator, bodies, edge, temperature, factor=0.98, picosecondsPerStage=0.2, seed=1):
    """Shrink a cubic box to `edge` (nm), `factor` at a time, moving the bodies' centres of mass with it
    (their shapes unchanged), with equilibrateByRedraws() for picosecondsPerStage after each stage.
    Returns the number of stages."""
    masses = particleMasses(context.getSystem())
    bodies = np.array(bodies)
    bodyMasses = masses[bodies][:, :, None]
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


@dataclasses.dataclass
class NVESamples:
    """Samples of a run: times (ps, from 0), total energies (kJ/mol), for a rigid-body integrator its
    translational and rotational kinetic energies (kJ/mol, empty otherwise), and wall seconds per step."""
    times: np.ndarray
    energies: np.ndarray
    translational: np.ndarray
    rotational: np.ndarray
    secondsPerStep: float


def sampleNVE(context, integrator, steps, sampleEvery):
    """Run `steps` steps from the Context's state, sampling at the start and every `sampleEvery` steps."""
    rigid = hasattr(integrator, "getRotationalKineticEnergy")
    times, energies, translational, rotational = [], [], [], []
    elapsed = 0.0
    kj = unit.kilojoule_per_mole
    for sample in range(steps//sampleEvery + 1):
        if sample > 0:
            started = time.perf_counter()
            integrator.step(sampleEvery)
            elapsed += time.perf_counter() - started
        state = context.getState(getEnergy=True)
        times.append(state.getTime().value_in_unit(unit.picosecond))
        energies.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(kj))
        if rigid:
            translational.append(integrator.getTranslationalKineticEnergy().value_in_unit(kj))
            rotational.append(integrator.getRotationalKineticEnergy().value_in_unit(kj))
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
    """The mean of a time series and its standard error from `blocks` consecutive block means (along the
    first axis: an array of series gives arrays)."""
    means = np.array([block.mean(axis=0) for block in np.array_split(np.asarray(values, dtype=float), blocks)])
    return means.mean(axis=0), means.std(axis=0, ddof=1)/np.sqrt(blocks)


def rigidTemperatures(samples, bodies, rotationalDofPerBody, blocks=5):
    """Translational and rotational temperatures (K) of a box of `bodies` rigid bodies (and no free
    particles) from sampleNVE()'s kinetic energies, and their difference (rotational minus
    translational: zero at equipartition), each as (mean, standard error) from `blocks` block means.

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


def bodyKinds(integrator):
    """{kind: count} of a rigid-body integrator's bodies (``getBodyKind``)."""
    kinds = {}
    for index in range(integrator.getNumBodies()):
        kind = integrator.getBodyKind(index)
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds

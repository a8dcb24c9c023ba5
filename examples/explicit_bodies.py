"""Boxes of small rigid molecules given to RigidBodyIntegrator as explicit bodies, and the checks the
examples print: shared by co2_box.py and benzene.py (solvated_peptide.py uses runNVE and
energyConservation).

- RigidMolecule: a molecule's geometry and nonbonded parameters; buildBox() packs copies of it at
  random positions and orientations into a periodic box and makes the System (PME, a switched
  Lennard-Jones cutoff, no interactions within a molecule: a rigid molecule's internal forces
  cannot move it). Random packing jams well below liquid density for larger molecules, so the box
  may be packed dilute and compress() brings it to the density wanted, a few per cent at a time.
- equilibrate(): Andersen-style equilibration with the rigid integrator itself: the velocities are
  redrawn from the Boltzmann distribution at regular intervals (and scaled to the temperature at
  the end). RigidBodyIntegrator projects the particle velocities onto rigid motion (keeping each
  body's momentum and angular momentum), and the momentum and angular momentum of independent
  Maxwell-Boltzmann particle velocities are Gaussian with covariances kT M and kT I, so each redraw
  is an exact draw from the rigid bodies' Boltzmann distribution.
- runNVE(), energyConservation(), temperatures(), shapeDeviations(): the measurements.
"""

import time
from dataclasses import dataclass

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from rigid_water import summarize

BOLTZMANN = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
AVOGADRO = 6.02214076e23


@dataclass
class RigidMolecule:
    """Geometry (nm, any orientation) and nonbonded parameters (e, nm, kJ/mol) of one rigid molecule.

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
        return float(np.sum(self.masses))


def randomRotation(rng):
    """A rotation matrix uniformly distributed on SO(3) (from a random unit quaternion)."""
    w, x, y, z = (lambda q: q/np.linalg.norm(q))(rng.normal(size=4))
    return np.array([[1 - 2*(y*y + z*z), 2*(x*y - w*z), 2*(x*z + w*y)],
                     [2*(x*y + w*z), 1 - 2*(x*x + z*z), 2*(y*z - w*x)],
                     [2*(x*z - w*y), 2*(y*z + w*x), 1 - 2*(x*x + y*y)]])


def boxEdge(molecule, count, density):
    """The edge (nm) of a cubic box holding `count` molecules at `density` (g/cm^3)."""
    return (count*molecule.mass/AVOGADRO/density*1e21)**(1/3)


def packMolecules(molecule, count, edge, rng, closest=0.8, attempts=200000):
    """Positions (count, atoms, 3) of `count` randomly placed and oriented copies of the molecule in a
    periodic cube: each accepted only if every atom pair between molecules is at least `closest` times
    its Lennard-Jones sigma apart (the overlaps left are mild and relax in the first steps)."""
    local = np.array(molecule.coordinates, dtype=float)
    local -= np.average(local, axis=0, weights=molecule.masses)
    sigmas = np.array(molecule.sigmas)
    contact = closest*0.5*(sigmas[:, None] + sigmas[None, :])  # atom of the new molecule x atom placed
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
    raise RuntimeError(f"packMolecules: placed only {len(placed)} of {count} {molecule.name} molecules; "
                       "lower the density or `closest`")


def buildBox(molecule, count, density, seed, cutoff=1.0, switchWidth=0.1):
    """A periodic cubic box of `count` rigid copies of the molecule at `density` (g/cm^3), packed at random.

    Returns the System, the positions (particles x 3, nm) and the bodies (one list of particle indices
    per molecule). PME for the charges; Lennard-Jones switched off between cutoff - switchWidth and
    cutoff, with the long-range dispersion correction.
    """
    rng = np.random.default_rng(seed)
    edge = boxEdge(molecule, count, density)
    positions = packMolecules(molecule, count, edge, rng)
    system = openmm.System()
    system.setDefaultPeriodicBoxVectors(*(openmm.Vec3(*row) for row in edge*np.eye(3)))
    coulomb = openmm.NonbondedForce()
    coulomb.setNonbondedMethod(openmm.NonbondedForce.PME)
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
    coulomb.setCutoffDistance(cutoff)
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
    return np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])


def compress(context, integrator, bodies, edge, temperature, factor=0.98, picosecondsPerStage=0.2, seed=1):
    """Shrink the cubic box to `edge` (nm) by `factor` at a time, moving the bodies' centres of mass
    with it (shapes unchanged), with picosecondsPerStage of equilibration (equilibrate()) after each."""
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
        equilibrate(context, integrator, temperature, picosecondsPerStage, seed=seed + 1000*stage)
        current, stage = smaller, stage + 1
    return stage


def removeMomentum(context, masses):
    """Subtract the centre-of-mass velocity from every particle (rigid motion stays rigid)."""
    velocities = context.getState(getVelocities=True).getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    velocities -= masses @ velocities/masses.sum()
    context.setVelocities(velocities)


def equilibrate(context, integrator, temperature, picoseconds, every=0.1, seed=1):
    """Run `picoseconds` with the velocities redrawn at `temperature` (K) every `every` ps (total
    momentum zero), then scale them to that temperature exactly (the integrator's own temperature),
    so that an NVE run that follows starts at the temperature asked for, not one draw away from it."""
    masses = particleMasses(context.getSystem())
    dt = integrator.getStepSize().value_in_unit(unit.picosecond)
    interval = max(1, int(round(every/dt)))
    for block in range(int(round(picoseconds/every))):
        context.setVelocitiesToTemperature(temperature*unit.kelvin, seed + block)
        removeMomentum(context, masses)
        integrator.step(interval)
    current = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    velocities = context.getState(getVelocities=True).getVelocities(asNumpy=True)
    context.setVelocities(velocities*np.sqrt(temperature/current))


@dataclass
class NVERun:
    """Samples of an NVE run: times (ps), total energies (kJ/mol), and for a RigidBodyIntegrator the
    translational and rotational kinetic energies (kJ/mol); wall seconds per step."""
    times: np.ndarray
    energies: np.ndarray
    translational: np.ndarray
    rotational: np.ndarray
    secondsPerStep: float


def runNVE(context, integrator, steps, sampleEvery):
    """Run `steps` steps from the Context's state, sampling every `sampleEvery` steps (and at the start)."""
    rigid = isinstance(integrator, openmmrigid.RigidBodyIntegrator)
    times, energies, translational, rotational = [], [], [], []
    elapsed = 0.0
    for sample in range(steps//sampleEvery + 1):
        if sample > 0:
            started = time.perf_counter()
            integrator.step(sampleEvery)
            elapsed += time.perf_counter() - started
        state = context.getState(getEnergy=True)
        times.append(state.getTime().value_in_unit(unit.picosecond))
        energies.append((state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(unit.kilojoule_per_mole))
        if rigid:
            translational.append(integrator.getTranslationalKineticEnergy().value_in_unit(unit.kilojoule_per_mole))
            rotational.append(integrator.getRotationalKineticEnergy().value_in_unit(unit.kilojoule_per_mole))
    return NVERun(np.array(times) - times[0], np.array(energies), np.array(translational), np.array(rotational),
                  elapsed/max(steps, 1))


def energyConservation(run, dof):
    """Drift (kJ/mol/ns per degree of freedom, from a linear fit) and fluctuation about it (kJ/mol)."""
    return summarize(run.times, run.energies, dof)


def blockMean(values, blocks=5):
    """The mean of `values` and its standard error from `blocks` consecutive block means."""
    means = np.array([block.mean() for block in np.array_split(np.asarray(values), blocks)])
    return means.mean(), means.std(ddof=1)/np.sqrt(blocks)


def temperatures(run, bodies, rotationalDofPerBody, blocks=5):
    """Mean translational and rotational temperatures (K) and their difference (rotational minus
    translational: zero at equipartition), each with its standard error from `blocks` block means.

    Translation: 3 per body less 3 for the total momentum, which is zero and conserved; rotation:
    rotationalDofPerBody (2 for linear bodies, 3 otherwise) per body.
    """
    translational = 2*run.translational/((3*bodies - 3)*BOLTZMANN)
    rotational = 2*run.rotational/(rotationalDofPerBody*bodies*BOLTZMANN)
    return blockMean(translational, blocks), blockMean(rotational, blocks), blockMean(rotational - translational, blocks)


def shapeDeviations(context, bodies, reference):
    """How far the bodies are from their initial shapes: the largest change of any distance between two
    particles of a body (nm), and the singular values of each body's centred coordinates (bodies x 3,
    descending; a linear body has the last two zero, a planar one the last)."""
    positions = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    now, before = positions[np.array(bodies)], reference[np.array(bodies)]
    pairs = np.triu_indices(now.shape[1], 1)
    distances = lambda x: np.linalg.norm(x[:, :, None, :] - x[:, None, :, :], axis=-1)[:, pairs[0], pairs[1]]
    change = np.abs(distances(now) - distances(before)).max()
    extents = np.linalg.svd(now - now.mean(axis=1, keepdims=True), compute_uv=False)/np.sqrt(now.shape[1])
    return change, extents


def bodyKinds(integrator):
    """{kind: count} of the integrator's bodies."""
    kinds = {}
    for index in range(integrator.getNumBodies()):
        kind = integrator.getBodyKind(index)
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


def equilibrateRunAndReport(context, integrator, args, dof, bodies, reference, rotationalDofPerBody, history=""):
    """Equilibrate, run NVE for args.time ps at args.step fs and print what the example shows: energy
    drift and fluctuation, translational and rotational temperatures (rotationalDofPerBody each) and how
    rigid the molecules stayed (intramolecular distances against `reference` positions, and the extent
    of each molecule off its best-fit line (linear) or plane (planar)). `history` says what came before
    the equilibration, for the heading."""
    equilibrate(context, integrator, args.temperature, args.equilibrate, seed=args.seed)
    steps = int(round(args.time/(args.step*1e-3)))
    run = runNVE(context, integrator, steps, max(1, steps//500))
    drift, fluctuation = energyConservation(run, dof)
    (translational, translationalError), (rotational, rotationalError), (excess, excessError) = \
        temperatures(run, args.molecules, rotationalDofPerBody)
    change, extents = shapeDeviations(context, bodies, reference)
    shape, axis = ("line", 1) if rotationalDofPerBody == 2 else ("plane", 2)
    print(f"\nNVE, {args.method} rotation, {args.time:g} ps at {args.step:g} fs ({steps} steps, "
          f"{run.secondsPerStep*1e3:.2f} ms/step) after {history}{args.equilibrate:g} ps of equilibration:")
    print(f"  energy drift {drift:+.4f} kJ/mol/ns/dof, fluctuation {fluctuation:.3f} kJ/mol "
          f"(total energy {run.energies.mean():.1f} kJ/mol)")
    print(f"  temperature: translational {translational:.1f} +- {translationalError:.1f} K, "
          f"rotational {rotational:.1f} +- {rotationalError:.1f} K ({rotationalDofPerBody} per molecule); "
          f"rotational - translational {excess:+.1f} +- {excessError:.1f} K")
    print(f"  rigidity: largest change of an intramolecular distance {change:.1e} nm; largest distance from the "
          f"best-fit {shape} through a molecule (RMS over its atoms) {extents[:, axis].max():.1e} nm")

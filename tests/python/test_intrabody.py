"""openmmrigid.removeIntraBodyInteractions: what it removes, what it keeps, and that rigid bodies
cannot tell the difference.

Systems: alanine dipeptide (amber14: bonds, angles, torsions, 1-4 exceptions, nonbonded pairs) in
vacuum, with one force of every other handled type added over its atoms (CMAP, RB torsions,
custom bond / angle / torsion / compound-bond forces with global parameters and a tabulated
function, a CustomNonbondedForce, and a positional restraint that reads coordinates), and the same
dipeptide in TIP3P water with PME. Bodies: ACE with half of ALA (two residues merged), and NME;
ALA's carbonyl moves freely; in water, every water too. All on the Reference platform (double
precision), comparing the original System with the copy:

- the total force and the torque about the centre of mass on every body, and the force on every
  free particle, agree to rounding;
- the terms, exceptions, exclusions and constraints removed or added are exactly those inside the
  bodies, counted here from the original System;
- a RigidBodyIntegrator trajectory of the original System has a potential energy that differs from
  the copy's by a constant, and a trajectory of the copy follows it.
"""

import itertools

import numpy as np
import openmm
import pytest
from openmm import app, unit

import openmmrigid
import rigidtesting

REFERENCE = openmm.Platform.getPlatformByName("Reference")
# ACE and ALA merged, but ALA's carbonyl C and O free; NME a body of its own.
SELECTION = dict(residues=["NME"], atoms={"ALA": "N|H|CA|HA|CB|HB[1-3]"}, merge=[[0, 1]])


def addEveryBondedType(system, positions):
    """One force of each other handled type over the peptide (22 atoms), in its own force group."""
    rng = np.random.default_rng(4)
    n = 22
    cmap = openmm.CMAPTorsionForce()
    cmap.addMap(4, list(rng.normal(size=16)))
    cmap.addTorsion(0, 1, 4, 6, 8, 4, 6, 8, 14)  # reaches ALA's free carbonyl C
    cmap.addTorsion(0, 1, 4, 6, 8, 4, 6, 8, 10)  # within ACE + ALA's N, CA, CB
    cmap.addTorsion(0, 16, 17, 18, 19, 17, 18, 19, 20)  # within NME
    rb = openmm.RBTorsionForce()
    for quartet in ((0, 1, 4, 6), (6, 8, 14, 16), (16, 18, 19, 20), (1, 4, 6, 8)):
        rb.addTorsion(*quartet, *rng.normal(size=6))
    bond = openmm.CustomBondForce("kb*(r - r0)^2 + shift")
    bond.addGlobalParameter("shift", 0.25)
    bond.addPerBondParameter("kb")
    bond.addPerBondParameter("r0")
    angle = openmm.CustomAngleForce("ka*(theta - t0)^2")
    angle.addPerAngleParameter("ka")
    angle.addPerAngleParameter("t0")
    torsion = openmm.CustomTorsionForce("kt*cos(2*theta)")
    torsion.addPerTorsionParameter("kt")
    for i, j in itertools.combinations(range(n), 2):
        if rng.random() < 0.3:
            bond.addBond(i, j, [rng.uniform(10, 100), 0.2])
    for i, j, k in itertools.combinations(range(n), 3):
        if rng.random() < 0.05:
            angle.addAngle(i, j, k, [rng.uniform(1, 10), 1.9])
    for i, j, k, l in itertools.combinations(range(n), 4):
        if rng.random() < 0.01:
            torsion.addTorsion(i, j, k, l, [rng.uniform(1, 5)])
    compound = openmm.CustomCompoundBondForce(3, "kc*table(distance(p1, p3)) + g*angle(p1, p2, p3)")
    compound.addTabulatedFunction("table", openmm.Continuous1DFunction(list(np.cos(np.linspace(0, 3, 20))), 0.0, 1.0))
    compound.addGlobalParameter("g", 2.0)
    compound.addPerBondParameter("kc")
    compound.addEnergyParameterDerivative("g")
    for i, j, k in itertools.combinations(range(n), 3):
        if rng.random() < 0.05:
            compound.addBond([i, j, k], [rng.uniform(1, 10)])
    restraint = openmm.CustomCompoundBondForce(2, "kr*((x1 - x0)^2 + (y1 - y0)^2 + (z1 - z0)^2) + distance(p1, p2)")
    restraint.addGlobalParameter("x0", float(positions[0][0]))
    restraint.addGlobalParameter("y0", float(positions[0][1]))
    restraint.addGlobalParameter("z0", float(positions[0][2]))
    restraint.addPerBondParameter("kr")
    restraint.addBond([0, 1], [100.0])
    custom = openmm.CustomNonbondedForce("eps*exp(-r/0.2)")
    custom.addGlobalParameter("eps", 3.0)
    for _ in range(system.getNumParticles()):
        custom.addParticle([])
    custom.addExclusion(0, 1)
    custom.addExclusion(4, 14)
    for group, force in enumerate((cmap, rb, bond, angle, torsion, compound, restraint, custom), start=5):
        force.setForceGroup(group)
        force.setName(f"test {type(force).__name__} {group}")
        system.addForce(force)


def vacuumDipeptide():
    pdb = rigidtesting.alanineDipeptide()
    forceField = app.ForceField("amber14-all.xml")
    system = forceField.createSystem(pdb.topology, nonbondedMethod=app.NoCutoff, constraints=app.HBonds)
    positions = np.array(pdb.positions.value_in_unit(unit.nanometer))
    addEveryBondedType(system, positions)
    bodies = openmmrigid.rigidBodiesFromTopology(pdb.topology, system=system, **SELECTION)
    return pdb.topology, positions, system, bodies


def solvatedDipeptide():
    pdb = rigidtesting.alanineDipeptide()
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    modeller = app.Modeller(pdb.topology, pdb.positions)
    size = 1.8
    positions = np.array(modeller.positions.value_in_unit(unit.nanometer))
    modeller.positions = (positions - positions.mean(axis=0) + 0.5*size)*unit.nanometer
    modeller.addSolvent(forceField, model="tip3p", boxSize=openmm.Vec3(size, size, size)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.7*unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True, ewaldErrorTolerance=1e-5)
    selection = dict(SELECTION, residues=["NME", "HOH"])
    bodies = openmmrigid.rigidBodiesFromTopology(modeller.topology, system=system, **selection)
    positions = np.array(modeller.positions.value_in_unit(unit.nanometer))
    return modeller.topology, positions, system, bodies


@pytest.fixture(scope="module")
def vacuum():
    return vacuumDipeptide()


@pytest.fixture(scope="module")
def solvated():
    return solvatedDipeptide()


def forcesAndEnergy(system, positions):
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), REFERENCE)
    context.setPositions(positions)
    context.computeVirtualSites()
    state = context.getState(getForces=True, getEnergy=True)
    return (state.getForces(asNumpy=True).value_in_unit(unit.kilojoule_per_mole/unit.nanometer),
            state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole))


def forceAndTorque(system, positions, forces, body):
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in body])
    centre = masses @ positions[body]/masses.sum()
    return forces[body].sum(axis=0), np.cross(positions[body] - centre, forces[body]).sum(axis=0)


def checkBodiesFeelTheSame(system, lean, positions, bodies):
    original, _ = forcesAndEnergy(system, positions)
    reduced, _ = forcesAndEnergy(lean, positions)
    scale = np.abs(original).max()
    inBody = {i for body in bodies for i in body}
    free = [i for i in range(system.getNumParticles()) if i not in inBody and not system.isVirtualSite(i)]
    changed = 0.0
    for body in bodies:
        force, torque = forceAndTorque(system, positions, original, body)
        leanForce, leanTorque = forceAndTorque(system, positions, reduced, body)
        np.testing.assert_allclose(leanForce, force, rtol=0, atol=1e-9*scale)
        np.testing.assert_allclose(leanTorque, torque, rtol=0, atol=1e-9*scale)
        changed = max(changed, np.abs(reduced[body] - original[body]).max())
    np.testing.assert_allclose(reduced[free], original[free], rtol=0, atol=1e-9*scale)
    assert changed > 1e-3*scale  # the per-atom forces inside the bodies did change: something was removed
    return scale


def test_forces_and_torques_on_bodies_are_unchanged_in_vacuum(vacuum):
    _, positions, system, bodies = vacuum
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    checkBodiesFeelTheSame(system, lean, positions, bodies)


def test_forces_and_torques_on_bodies_are_unchanged_with_pme(solvated):
    _, positions, system, bodies = solvated
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    checkBodiesFeelTheSame(system, lean, positions, bodies)


def particlesOfTerms(force):
    """The particles of each term of a handled bonded force, through the API."""
    if isinstance(force, openmm.HarmonicBondForce):
        return [tuple(force.getBondParameters(i)[:2]) for i in range(force.getNumBonds())]
    if isinstance(force, openmm.HarmonicAngleForce):
        return [tuple(force.getAngleParameters(i)[:3]) for i in range(force.getNumAngles())]
    if isinstance(force, (openmm.PeriodicTorsionForce, openmm.RBTorsionForce)):
        return [tuple(force.getTorsionParameters(i)[:4]) for i in range(force.getNumTorsions())]
    if isinstance(force, openmm.CMAPTorsionForce):
        return [tuple(force.getTorsionParameters(i)[1:]) for i in range(force.getNumTorsions())]
    if isinstance(force, openmm.CustomBondForce):
        return [tuple(force.getBondParameters(i)[:2]) for i in range(force.getNumBonds())]
    if isinstance(force, openmm.CustomAngleForce):
        return [tuple(force.getAngleParameters(i)[:3]) for i in range(force.getNumAngles())]
    if isinstance(force, openmm.CustomTorsionForce):
        return [tuple(force.getTorsionParameters(i)[:4]) for i in range(force.getNumTorsions())]
    if isinstance(force, openmm.CustomCompoundBondForce):
        return [tuple(force.getBondParameters(i)[0]) for i in range(force.getNumBonds())]
    return None


def test_exactly_the_terms_inside_bodies_go(vacuum):
    _, _, system, bodies = vacuum
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    bodyOf = {i: b for b, body in enumerate(bodies) for i in body}

    def inside(particles):
        return len({bodyOf.get(p, -1 - p) for p in particles}) == 1 and particles[0] in bodyOf

    assert lean.getNumForces() == system.getNumForces()
    kinds = set()
    for before, after in zip(system.getForces(), lean.getForces()):
        assert type(before) is type(after)
        assert (before.getForceGroup(), before.getName()) == (after.getForceGroup(), after.getName())
        assert before.usesPeriodicBoundaryConditions() == after.usesPeriodicBoundaryConditions()
        terms = particlesOfTerms(before)
        if terms is None:
            continue
        restraint = isinstance(before, openmm.CustomCompoundBondForce) and "x1" in before.getEnergyFunction()
        expected = terms if restraint else [t for t in terms if not inside(t)]
        assert particlesOfTerms(after) == expected
        if not restraint and len(expected) < len(terms):
            kinds.add(type(before).__name__)
        if hasattr(before, "getNumGlobalParameters"):
            assert [(before.getGlobalParameterName(i), before.getGlobalParameterDefaultValue(i))
                    for i in range(before.getNumGlobalParameters())] == \
                   [(after.getGlobalParameterName(i), after.getGlobalParameterDefaultValue(i))
                    for i in range(after.getNumGlobalParameters())]
    assert kinds == {"HarmonicBondForce", "HarmonicAngleForce", "PeriodicTorsionForce", "RBTorsionForce",
                     "CMAPTorsionForce", "CustomBondForce", "CustomAngleForce", "CustomTorsionForce",
                     "CustomCompoundBondForce"}
    # Constraints: those inside a body go, the others stay (in order).
    constraints = [tuple(system.getConstraintParameters(i)[:2]) for i in range(system.getNumConstraints())]
    kept = [tuple(lean.getConstraintParameters(i)[:2]) for i in range(lean.getNumConstraints())]
    assert kept == [c for c in constraints if not inside(c)] and len(kept) < len(constraints)
    # Every pair inside a body is a zero exception / an exclusion; the others are as they were.
    pairs = {tuple(sorted(pair)) for body in bodies for pair in itertools.combinations(body, 2)}
    nonbonded = next(f for f in system.getForces() if isinstance(f, openmm.NonbondedForce))
    leanNonbonded = next(f for f in lean.getForces() if isinstance(f, openmm.NonbondedForce))
    exceptions = {}
    for i in range(leanNonbonded.getNumExceptions()):
        p, q, charge, sigma, epsilon = leanNonbonded.getExceptionParameters(i)
        exceptions[tuple(sorted((p, q)))] = (charge.value_in_unit(unit.elementary_charge**2),
                                             epsilon.value_in_unit(unit.kilojoule_per_mole))
    assert pairs <= set(exceptions) and all(exceptions[pair] == (0.0, 0.0) for pair in pairs)
    for i in range(nonbonded.getNumExceptions()):
        p, q, charge, sigma, epsilon = nonbonded.getExceptionParameters(i)
        if tuple(sorted((p, q))) not in pairs:
            assert exceptions[tuple(sorted((p, q)))] == (charge.value_in_unit(unit.elementary_charge**2),
                                                         epsilon.value_in_unit(unit.kilojoule_per_mole))
    assert leanNonbonded.getNumExceptions() == len(set(exceptions) | pairs)
    custom = next(f for f in lean.getForces() if isinstance(f, openmm.CustomNonbondedForce))
    exclusions = [tuple(sorted(custom.getExclusionParticles(i))) for i in range(custom.getNumExclusions())]
    assert len(exclusions) == len(set(exclusions)) and set(exclusions) == pairs | {(0, 1), (4, 14)}


def test_a_copy_with_nothing_to_remove_is_the_same_system(vacuum):
    """Single-particle bodies hold no term: the copy serializes exactly as the original (nothing is lost)."""
    _, _, system, _ = vacuum
    lean = openmmrigid.removeIntraBodyInteractions(system, [[i] for i in range(0, 22, 3)])
    assert openmm.XmlSerializer.serialize(lean) == openmm.XmlSerializer.serialize(system)


def test_original_is_unchanged(vacuum):
    _, _, system, bodies = vacuum
    before = openmm.XmlSerializer.serialize(system)
    openmmrigid.removeIntraBodyInteractions(system, bodies)
    assert openmm.XmlSerializer.serialize(system) == before


def test_energy_differs_by_a_constant_along_a_rigid_trajectory(vacuum):
    _, positions, system, bodies = vacuum
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    # The full System keeps the constraints inside the bodies, and a body takes its shape from positions
    # with those applied; the lean one has none. Starting from positions that satisfy them gives both
    # the same bodies.
    helper = openmm.Context(system, openmm.VerletIntegrator(0.001), REFERENCE)
    helper.setPositions(positions)
    helper.applyConstraints(1e-12)
    positions = helper.getState(getPositions=True).getPositions(asNumpy=True)
    contexts = []
    for model in (system, lean):
        integrator = openmmrigid.RigidBodyIntegrator(0.0005, bodies)
        integrator.setConstraintTolerance(1e-10)
        context = openmm.Context(model, integrator, REFERENCE)
        context.setPositions(positions)
        context.setVelocitiesToTemperature(300*unit.kelvin, 17)
        contexts.append((context, integrator))
    contexts[1][0].setVelocities(contexts[0][0].getState(getVelocities=True).getVelocities())
    probe = openmm.Context(lean, openmm.VerletIntegrator(0.001), REFERENCE)
    differences, energies = [], []
    for _ in range(10):
        for context, integrator in contexts:
            integrator.step(20)
        state = contexts[0][0].getState(getPositions=True, getEnergy=True)
        probe.setPositions(state.getPositions())
        energy = state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)
        energies.append(energy)
        differences.append(energy - probe.getState(getEnergy=True).getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole))
    assert np.ptp(energies) > 1.0  # the energy itself moves along the trajectory
    assert np.ptp(differences) < 1e-9*max(abs(e) for e in energies) + 1e-9
    assert abs(differences[0]) > 1.0  # ... by a non-trivial constant
    # The lean System's own trajectory is the same motion.
    original = contexts[0][0].getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    reduced = contexts[1][0].getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    np.testing.assert_allclose(reduced, original, rtol=0, atol=1e-8)


def test_virtual_sites_with_parents_in_one_body_count_as_part_of_it():
    system = openmm.System()
    for mass in (12.0, 1.0, 1.0, 16.0, 14.0):
        system.addParticle(mass)
    system.addParticle(0.0)
    system.setVirtualSite(5, openmm.ThreeParticleAverageSite(0, 1, 2, 0.5, 0.25, 0.25))
    nonbonded = openmm.NonbondedForce()
    for charge in (0.3, 0.1, 0.1, -0.2, 0.5, -0.8):
        nonbonded.addParticle(charge, 0.3, 0.5)
    system.addForce(nonbonded)
    lean = openmmrigid.removeIntraBodyInteractions(system, [[0, 1, 2, 3]])
    force = lean.getForce(0)
    pairs = {tuple(sorted(force.getExceptionParameters(i)[:2])) for i in range(force.getNumExceptions())}
    assert pairs == {tuple(sorted(pair)) for pair in itertools.combinations([0, 1, 2, 3, 5], 2)}
    positions = np.array([[0, 0, 0], [0.1, 0, 0], [0, 0.11, 0], [0.05, 0.05, 0.12], [0.5, 0.1, 0.2], [0, 0, 0]])
    checkBodiesFeelTheSame(system, lean, positions, [[0, 1, 2, 3]])


@pytest.mark.parametrize("bodies, message", [
    ([[0, 1], [1, 2]], "particle 1 is in bodies 0 and 1"),
    ([[0, 1], []], "body 1 is empty"),
    ([[0, 99]], "body 0 holds particle 99, but the system has 22 particles"),
    ([[0, "a"]], "must be a list of lists of particle indices"),
    (7, "must be a list of lists of particle indices"),
])
def test_bad_bodies_name_what_is_wrong(vacuum, bodies, message):
    _, _, system, _ = vacuum
    with pytest.raises(ValueError, match=message):
        openmmrigid.removeIntraBodyInteractions(system, bodies)


def test_virtual_site_in_a_body_and_not_a_system_are_errors():
    system = openmm.System()
    for mass in (1.0, 1.0, 0.0):
        system.addParticle(mass)
    system.setVirtualSite(2, openmm.TwoParticleAverageSite(0, 1, 0.5, 0.5))
    with pytest.raises(ValueError, match="particle 2, a virtual site"):
        openmmrigid.removeIntraBodyInteractions(system, [[0, 1, 2]])
    with pytest.raises(ValueError, match="system must be an openmm.System"):
        openmmrigid.removeIntraBodyInteractions("system", [[0, 1]])

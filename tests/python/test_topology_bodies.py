"""openmmrigid.rigidBodiesFromTopology: bodies from an openmm.app Topology, and those bodies under a
barostat and periodic wrapping.

The selections are checked against the Topology read independently (residue by residue, atom by
atom); the errors for each kind of bad selection name what is wrong. The last test runs a peptide
made one rigid body (three residues merged) with rigid TIP3P water, its positions wrapped atom by
atom across the box edge, under a MonteCarloBarostat, with the intra-body interactions removed so
that nothing but the integrator keeps the bodies molecules: every body stays rigid and, in
positions wrapped by OpenMM, whole.
"""


import numpy as np
import openmm
import pytest
from openmm import app, unit

import openmmrigid
import rigidtesting
from rigidtesting.bodies import bodyKind, rigidDegreesOfFreedom
from rigidtesting.stress import BOLTZMANN


def solvatedDipeptide(model="tip4pew", size=1.8, constraints=app.HBonds):
    """Alanine dipeptide (ACE ALA NME) in a small water box: topology, positions (nm), system."""
    forceField = app.ForceField("amber14-all.xml", f"amber14/{model}.xml")
    pdb = rigidtesting.alanineDipeptide()
    modeller = app.Modeller(pdb.topology, pdb.positions)
    positions = np.array(modeller.positions.value_in_unit(unit.nanometer))
    modeller.positions = (positions - positions.mean(axis=0) + 0.5*size)*unit.nanometer
    modeller.addSolvent(forceField, model=model, boxSize=openmm.Vec3(size, size, size)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.7*unit.nanometer,
                                     constraints=constraints, rigidWater=True)
    return modeller.topology, np.array(modeller.positions.value_in_unit(unit.nanometer)), system


@pytest.fixture(scope="module")
def tip4pew():
    return solvatedDipeptide("tip4pew")


def residueAtoms(topology, name):
    return [[atom.index for atom in residue.atoms()] for residue in topology.residues() if residue.name == name]


def test_one_body_per_selected_residue(tip4pew):
    topology, _, system = tip4pew
    bodies = openmmrigid.rigidBodiesFromTopology(topology, ["NME", "ACE"], system=system)
    assert bodies == residueAtoms(topology, "ACE") + residueAtoms(topology, "NME")
    assert openmmrigid.rigidBodiesFromTopology(topology, "ACE", system=system) == residueAtoms(topology, "ACE")


def test_water_bodies_leave_out_virtual_sites(tip4pew):
    topology, _, system = tip4pew
    waters = residueAtoms(topology, "HOH")
    assert all(len(water) == 4 for water in waters)  # O, H1, H2 and the M site
    expected = [[i for i in water if not system.isVirtualSite(i)] for water in waters]
    assert all(len(water) == 3 for water in expected)
    assert openmmrigid.rigidBodiesFromTopology(topology, ["HOH"], system=system) == expected
    # Without the System, atoms with no element (the M sites here) are taken as the virtual sites.
    assert openmmrigid.rigidBodiesFromTopology(topology, ["HOH"]) == expected


def test_atom_name_patterns(tip4pew):
    topology, _, system = tip4pew
    alanine = next(residue for residue in topology.residues() if residue.name == "ALA")
    methyl = sorted(atom.index for atom in alanine.atoms() if atom.name in ("CB", "HB1", "HB2", "HB3"))
    assert openmmrigid.rigidBodiesFromTopology(topology, ["ALA"], atoms={"ALA": "CB|HB[1-3]"}, system=system) == [methyl]
    # A plain pattern applies to every selected residue; it must match the whole name.
    bodies = openmmrigid.rigidBodiesFromTopology(topology, ["ACE", "NME"], atoms="C|CH3|H[1-3]", system=system)
    names = [[next(a.name for a in topology.atoms() if a.index == i) for i in body] for body in bodies]
    assert names == [["H1", "CH3", "H2", "H3", "C"], ["C", "H1", "H2", "H3"]]


def test_merging_residues(tip4pew):
    topology, _, system = tip4pew
    residues = {residue.name: residue for residue in topology.residues() if residue.name != "HOH"}
    peptide = sorted(atom.index for name in ("ACE", "ALA", "NME") for atom in residues[name].atoms())
    aceAla = sorted(atom.index for name in ("ACE", "ALA") for atom in residues[name].atoms())
    nme = [atom.index for atom in residues["NME"].atoms()]
    # By Residue objects or indices; the group's residues need not be in `residues`.
    assert openmmrigid.rigidBodiesFromTopology(topology, ["NME"], merge=[[residues["ACE"], residues["ALA"]]],
                                               system=system) == [aceAla, nme]
    assert openmmrigid.rigidBodiesFromTopology(topology, merge=[[residues["ACE"].index, residues["ALA"].index]],
                                               system=system) == [aceAla]
    # mergeBonded joins the residues the topology's bonds connect.
    assert openmmrigid.rigidBodiesFromTopology(topology, ["ACE", "ALA", "NME"], mergeBonded=True,
                                               system=system) == [peptide]
    # ... but not atoms left out of the selection: the side chain alone is bonded to nothing selected.
    sideChain = openmmrigid.rigidBodiesFromTopology(topology, ["ACE", "ALA"], atoms={"ALA": "CB|HB[1-3]"},
                                                    mergeBonded=True, system=system)
    assert sideChain == [[atom.index for atom in residues["ACE"].atoms()],
                         sorted(a.index for a in residues["ALA"].atoms() if a.name.startswith(("CB", "HB")))]


def test_bodies_drive_the_integrator(tip4pew):
    topology, positions, system = tip4pew
    bodies = openmmrigid.rigidBodiesFromTopology(topology, ["HOH"], merge=[[0, 1, 2]], system=system)
    integrator = openmmrigid.RigidBodyIntegrator(0.001, bodies)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(positions)
    assert integrator.getNumBodies() == len(bodies)
    assert sorted(list(integrator.getBodyParticles(b)) for b in range(len(bodies))) == sorted(bodies)
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    kinds = {bodyKind(masses[body], positions[body]) for body in bodies}
    assert kinds == {"asymmetric"}
    # The integrator moves each as a rotor about three axes: 6 degrees of freedom a body, less the
    # 3 of the CMMotionRemover, in the temperature it reports.
    context.setVelocitiesToTemperature(300 * unit.kelvin, 5)
    dof = rigidDegreesOfFreedom(context, integrator)
    assert dof == 6 * len(bodies) - 3
    kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
    temperature = integrator.computeSystemTemperature().value_in_unit(unit.kelvin)
    assert temperature == pytest.approx(2 * kinetic / (dof * BOLTZMANN), rel=1e-9)


@pytest.mark.parametrize("arguments, message", [
    (dict(residues=["LIG"]), "no residue of the topology is named 'LIG'"),
    (dict(residues=["ALA"], atoms={"ALA": "CB|HB["}), "not a valid regular expression"),
    (dict(residues=["ALA"], atoms={"ALA": "XX"}), "matches no atom of residue ALA 2"),
    (dict(residues=["ALA"], atoms={"NME": "C"}), "no selected residue has that name"),
    (dict(residues=[], merge=[[0, 1], [1, 2]]), "is in merge groups 0 and 1"),
    (dict(residues=[], merge=[[0, 10**6]]), "residue index 1000000 is out of range"),
    (dict(residues=[]), "nothing is selected"),
    (dict(residues=[3]), "must hold residue names"),
    (dict(residues=["HOH"], atoms={"HOH": "M"}), "has no selected atom that is not a virtual site"),
    (dict(residues=["ALA"], atoms={"ALA": "CB|HB1"}), "constraint .* joins atom .* a rigid body cannot be constrained"),
])
def test_bad_selections_name_what_is_wrong(tip4pew, arguments, message):
    topology, _, system = tip4pew
    with pytest.raises(ValueError, match=message):
        openmmrigid.rigidBodiesFromTopology(topology, system=system, **arguments)


def test_bad_systems_and_topologies(tip4pew):
    topology, _, system = tip4pew
    with pytest.raises(ValueError, match="must be an openmm.app.Topology"):
        openmmrigid.rigidBodiesFromTopology(system, ["ALA"])
    with pytest.raises(ValueError, match="the system has 3 particles but the topology"):
        small = openmm.System()
        for _ in range(3):
            small.addParticle(1.0)
        openmmrigid.rigidBodiesFromTopology(topology, ["ALA"], system=small)
    massless = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    cb = next(atom.index for atom in topology.atoms() if atom.name == "CB")
    massless.setParticleMass(cb, 0.0)
    with pytest.raises(ValueError, match=f"atom CB \\(particle {cb}\\) of residue ALA 2 .* has zero mass"):
        openmmrigid.rigidBodiesFromTopology(topology, ["ALA"], system=massless)


def wrapAtoms(positions, edge):
    return positions - edge*np.floor(positions/edge)


def minimumImageDistances(positions, edge):
    separation = positions[:, None, :] - positions[None, :, :]
    separation -= edge*np.round(separation/edge)
    return np.linalg.norm(separation, axis=-1)


def test_barostat_and_periodic_wrapping_keep_bodies_whole():
    size = 1.8
    topology, positions, system = solvatedDipeptide("tip3p", size=size, constraints=app.HBonds)
    bodies = openmmrigid.rigidBodiesFromTopology(topology, ["HOH"], merge=[[0, 1, 2]], system=system)
    peptide = bodies[0]
    assert len(peptide) == 22
    # Minimize with the stock machinery, then put the peptide across a corner of the box and wrap
    # every atom into the box on its own, which splits the peptide into pieces.
    minimizer = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName("CPU"))
    minimizer.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(minimizer, 10, 100)
    positions = minimizer.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    del minimizer
    positions = wrapAtoms(positions - positions[peptide].mean(axis=0), size)
    assert np.ptp(positions[peptide], axis=0).max() > 0.5*size  # split by the wrapping
    shapes = [minimumImageDistances(positions[body], size) for body in bodies]

    # Nothing but the integrator's bodies holds the peptide or a water together as a molecule now.
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    assert lean.getNumConstraints() == 0
    barostat = openmm.MonteCarloBarostat(2000*unit.bar, 300*unit.kelvin, 5)
    barostat.setRandomNumberSeed(5)
    lean.addForce(barostat)
    integrator = openmmrigid.RigidBodyIntegrator(0.002, bodies)
    context = openmm.Context(lean, integrator, openmm.Platform.getPlatformByName("CPU"))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300*unit.kelvin, 3)
    volume = context.getState().getPeriodicBoxVolume().value_in_unit(unit.nanometer**3)
    integrator.step(150)
    state = context.getState(getPositions=True, enforcePeriodicBox=True)
    assert abs(state.getPeriodicBoxVolume().value_in_unit(unit.nanometer**3)/volume - 1) > 1e-3  # the barostat moved
    wrapped = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    edges = np.diag(state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer))
    for body, shape in zip(bodies, shapes):
        x = wrapped[body]
        # Whole: the plain distances (no minimum image) are the body's own distances, which are unchanged.
        plain = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1)
        np.testing.assert_allclose(plain, shape, atol=1e-8)
        centre = x.mean(axis=0)
        assert np.all(centre > -0.5) and np.all(centre < edges + 0.5)

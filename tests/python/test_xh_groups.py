"""openmmrigid.rigidHydrogenGroups: the System's constraint clusters (X-H groups, waters) and planar
groups as rigid bodies.

The bodies are checked against the System's constraints read independently (the clusters counted
with a union-find here) and against the Topology by atom name: every constrained pair in one body,
no particle in two bodies, one heavy atom per X-H body, three-atom waters without the TIP4P M site,
and with planarGroups the phenylalanine rings and peptide groups whole. The bodies run: a short
Langevin run of villin (HP35, from openmm's app/data/test.pdb, in vacuum) and of solvated alanine
dipeptide keeps every body's distances, X-H bonds included, to 1e-6 nm. Each kind of bad input
raises a ValueError naming what is wrong.
"""

import os

import numpy as np
import openmm
import pytest
from openmm import app, unit

import openmmrigid
from test_topology_bodies import solvatedDipeptide

FORCE_FIELD = ("amber14-all.xml", "amber14/tip3p.xml")


def villinInVacuum(constraints=app.HBonds):
    """Villin headpiece (HP35: PHE, TRP, ASN, GLN, HIS, PRO) without its water and ion, in vacuum."""
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.delete([residue for residue in modeller.topology.residues() if residue.name in ("HOH", "Cl")])
    system = app.ForceField(*FORCE_FIELD).createSystem(modeller.topology, nonbondedMethod=app.NoCutoff,
                                                       constraints=constraints)
    return modeller.topology, np.array(modeller.positions.value_in_unit(unit.nanometer)), system


@pytest.fixture(scope="module")
def villin():
    return villinInVacuum()


@pytest.fixture(scope="module")
def tip3p():
    return solvatedDipeptide("tip3p")


def constraintClusters(system):
    """The connected components of the constraint graph (sets of particle indices), by union-find."""
    parent = {}

    def root(i):
        parent.setdefault(i, i)
        while parent[i] != i:
            i = parent[i]
        return i

    for k in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(k)
        parent[root(i)] = root(j)
    clusters = {}
    for i in list(parent):
        clusters.setdefault(root(i), set()).add(i)
    return list(clusters.values())


def checkPartition(bodies, system):
    """Bodies sorted, disjoint, in order, and every constrained pair inside one of them."""
    assert all(body == sorted(body) for body in bodies)
    assert [body[0] for body in bodies] == sorted(body[0] for body in bodies)
    bodyOf = {}
    for number, body in enumerate(bodies):
        for index in body:
            assert index not in bodyOf, f"particle {index} is in two bodies"
            bodyOf[index] = number
    for k in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(k)
        assert i in bodyOf and bodyOf[i] == bodyOf.get(j), f"constraint {k} ({i}, {j}) is not inside one body"
    return bodyOf


def isHydrogen(atom):
    return atom.element is not None and atom.element.symbol == "H"


def test_xh_groups_are_the_constraint_clusters(villin, tip3p):
    for topology, _, system in (villin, tip3p):
        bodies = openmmrigid.rigidHydrogenGroups(topology, system)
        checkPartition(bodies, system)
        clusters = constraintClusters(system)
        assert len(bodies) == len(clusters)
        assert sorted(map(sorted, clusters)) == sorted(bodies)
        atoms = list(topology.atoms())
        for body in bodies:
            if atoms[body[0]].residue.name == "HOH":
                continue
            heavy = [i for i in body if not isHydrogen(atoms[i])]
            assert len(heavy) == 1, [atoms[i].name for i in body]
            assert len(body) >= 2
    # Villin's X-H groups: e.g. every CH3 is one 4-atom body, the lysine NH3+ too.
    topology, _, system = villin
    atoms = list(topology.atoms())
    names = {tuple(atoms[i].name for i in body) for body in openmmrigid.rigidHydrogenGroups(topology, system)}
    assert ("NZ", "HZ1", "HZ2", "HZ3") in names and ("CB", "HB1", "HB2", "HB3") in names


def test_waters_are_three_atom_bodies(tip3p):
    topology, _, system = tip3p
    bodies = openmmrigid.rigidHydrogenGroups(topology, system)
    waters = [[atom.index for atom in residue.atoms()] for residue in topology.residues() if residue.name == "HOH"]
    assert waters and all(len(water) == 3 for water in waters)
    assert all(water in bodies for water in waters)
    # Selecting by name or by Residue objects gives the waters alone.
    assert openmmrigid.rigidHydrogenGroups(topology, system, residues="HOH") == waters
    residues = [residue for residue in topology.residues() if residue.name == "HOH"]
    assert openmmrigid.rigidHydrogenGroups(topology, system, residues=residues) == waters
    assert openmmrigid.rigidHydrogenGroups(topology, system, residues=["ALA", "HOH"]) == \
        [body for body in bodies if next(a for a in topology.atoms() if a.index == body[0]).residue.name in ("ALA", "HOH")]


def test_tip4p_virtual_sites_are_left_out():
    topology, _, system = solvatedDipeptide("tip4pew", size=1.6)
    bodies = openmmrigid.rigidHydrogenGroups(topology, system, residues="HOH")
    sites = [i for i in range(system.getNumParticles()) if system.isVirtualSite(i)]
    assert sites
    assert not set(sites) & {i for body in bodies for i in body}
    assert bodies == openmmrigid.rigidBodiesFromTopology(topology, "HOH", system=system)


def test_planar_groups(villin):
    topology, _, system = villin
    bodies = openmmrigid.rigidHydrogenGroups(topology, system, planarGroups=True)
    bodyOf = checkPartition(bodies, system)
    atoms = list(topology.atoms())
    residues = list(topology.residues())
    ringNames = {"PHE": {"CG", "CD1", "CD2", "CE1", "CE2", "CZ", "HD1", "HD2", "HE1", "HE2", "HZ"},
                 "TRP": {"CG", "CD1", "CD2", "NE1", "CE2", "CE3", "CZ2", "CZ3", "CH2",
                         "HD1", "HE1", "HE3", "HZ2", "HZ3", "HH2"},
                 "HIS": {"CG", "ND1", "CD2", "CE1", "NE2", "HD2", "HE1", "HE2"},
                 "ASN": {"CG", "OD1", "ND2", "HD21", "HD22"},
                 "GLN": {"CD", "OE1", "NE2", "HE21", "HE22"}}
    seen = set()
    for residue in residues:
        if residue.name in ringNames:
            ring = [atom.index for atom in residue.atoms() if atom.name in ringNames[residue.name]]
            assert len(ring) == len(ringNames[residue.name])
            # the ring (or amide) is exactly one body: nothing else of the residue joined it (no CB, no HA)
            assert bodies[bodyOf[ring[0]]] == sorted(ring), residue
            seen.add(residue.name)
    assert seen == set(ringNames)
    # Every peptide group C(i) O(i) N(i+1) H(i+1) is one body (PRO's N has no H: C, O, N).
    peptides = 0
    for before, after in zip(residues[:-1], residues[1:]):
        named = {atom.name: atom.index for atom in before.atoms()}
        following = {atom.name: atom.index for atom in after.atoms()}
        group = sorted([named["C"], named["O"], following["N"]] + ([following["H"]] if "H" in following else []))
        assert bodies[bodyOf[group[0]]] == group, (before, after)
        peptides += 1
    assert peptides == len(residues) - 1 == 34
    # The terminal N (H1 H2 H3) stays an X-H group; bodies not touched by a planar group are unchanged.
    plain = openmmrigid.rigidHydrogenGroups(topology, system)
    planar = {i for body in bodies if len(body) > 4 or atoms[body[0]].name == "C" for i in body}
    assert [body for body in plain if not set(body) & planar] == [body for body in bodies if not set(body) & planar]
    # Each PHE ring merges its 5 C-H groups (-4 bodies, 4 PHE), TRP's 6 (-5), HIS's 3 (-2); ASN's and GLN's
    # NH2 and each N-H become their groups (no change); the PRO peptide group C O N is a new body (+1).
    assert len(bodies) == len(plain) - 4*4 - 5 - 2 + 1


def test_peptide_groups_need_both_residues_selected(tip3p):
    topology, _, system = tip3p
    bodies = openmmrigid.rigidHydrogenGroups(topology, system, residues=["ALA"], planarGroups=True)
    atoms = list(topology.atoms())
    # ACE-ALA and ALA-NME cross into unselected residues: ALA keeps its X-H groups only.
    assert bodies == openmmrigid.rigidHydrogenGroups(topology, system, residues="ALA")
    assert all(atoms[i].residue.name == "ALA" for body in bodies for i in body)
    bodies = openmmrigid.rigidHydrogenGroups(topology, system, residues=["ACE", "ALA", "NME"], planarGroups=True)
    assert [[atoms[i].name for i in body] for body in bodies if atoms[body[0]].name == "C"][:2] == \
        [["C", "O", "N", "H"], ["C", "O", "N", "H"]]


def distances(positions, bodies):
    return np.concatenate([np.linalg.norm(positions[body][:, None] - positions[body][None], axis=-1).ravel()
                           for body in bodies])


@pytest.mark.parametrize("planar", [False, True])
def test_bodies_run_and_keep_their_shape(villin, tip3p, planar):
    for (topology, positions, system), platform in ((villin, "Reference"), (tip3p, "CPU")):
        bodies = openmmrigid.rigidHydrogenGroups(topology, system, planarGroups=planar)
        lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
        integrator = openmmrigid.RigidBodyLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtoseconds,
                                                             bodies)
        integrator.setRandomNumberSeed(3)
        properties = {"Threads": "1"} if platform == "CPU" else {}
        context = openmm.Context(lean, integrator, openmm.Platform.getPlatformByName(platform), properties)
        context.setPositions(positions)
        context.setVelocitiesToTemperature(300*unit.kelvin, 5)
        integrator.step(20)
        state = context.getState(getPositions=True, getEnergy=True)
        assert np.isfinite(state.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole))
        assert np.isfinite(state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole))
        after = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        assert np.max(np.abs(after - positions)) > 1e-3  # it moved
        assert np.max(np.abs(distances(after, bodies) - distances(positions, bodies))) < 1e-6
        xh = [(i, j) for i, j, _ in (system.getConstraintParameters(k) for k in range(system.getNumConstraints()))]
        before = np.linalg.norm(positions[[i for i, _ in xh]] - positions[[j for _, j in xh]], axis=1)
        now = np.linalg.norm(after[[i for i, _ in xh]] - after[[j for _, j in xh]], axis=1)
        assert np.max(np.abs(now - before)) < 1e-6


def test_errors_name_what_is_wrong(villin, tip3p):
    topology, _, system = villin
    with pytest.raises(ValueError, match="topology must be an openmm.app.Topology"):
        openmmrigid.rigidHydrogenGroups("villin", system)
    with pytest.raises(ValueError, match="system must be an openmm.System"):
        openmmrigid.rigidHydrogenGroups(topology, None)
    with pytest.raises(ValueError, match="'XYZ'"):
        openmmrigid.rigidHydrogenGroups(topology, system, residues=["PHE", "XYZ"])
    with pytest.raises(ValueError, match="residue names"):
        openmmrigid.rigidHydrogenGroups(topology, system, residues=["PHE", 3])
    with pytest.raises(ValueError, match="residues must be"):
        openmmrigid.rigidHydrogenGroups(topology, system, residues=7)
    with pytest.raises(ValueError, match="empty"):
        openmmrigid.rigidHydrogenGroups(topology, system, residues=[])
    otherResidue = next(tip3p[0].residues())
    with pytest.raises(ValueError, match="not a residue of this topology"):
        openmmrigid.rigidHydrogenGroups(topology, system, residues=[otherResidue])
    with pytest.raises(ValueError, match="the system has 3 particles but the topology"):
        small = openmm.System()
        for _ in range(3):
            small.addParticle(1.0)
        openmmrigid.rigidHydrogenGroups(topology, small)
    # No constraints at all, and none in the selection.
    _, _, flexible = villinInVacuum(constraints=None)
    with pytest.raises(ValueError, match="constraints=app.HBonds"):
        openmmrigid.rigidHydrogenGroups(topology, flexible)
    with pytest.raises(ValueError, match="no constraint in the selected residues"):
        openmmrigid.rigidHydrogenGroups(topology, _withoutConstraintsOf(system, topology, "PHE"), residues="PHE")
    # A cluster that crosses residues: with AllBonds the whole chain is one cluster.
    _, _, allBonds = villinInVacuum(constraints=app.AllBonds)
    with pytest.raises(ValueError, match=r"joins the selected .*atom .* of residue PHE .* to the unselected"):
        openmmrigid.rigidHydrogenGroups(topology, allBonds, residues="PHE")
    # Massless particles and virtual sites in a cluster.
    massless = openmm.System()
    massless.__setstate__(system.__getstate__())
    hydrogen = next(atom for atom in topology.atoms() if atom.name == "HA")
    massless.setParticleMass(hydrogen.index, 0.0)
    with pytest.raises(ValueError, match=f"atom HA \\(particle {hydrogen.index}\\).*zero mass"):
        openmmrigid.rigidHydrogenGroups(topology, massless)
    tip4p, _, tip4pSystem = solvatedDipeptide("tip4pew", size=1.6)
    site = next(i for i in range(tip4pSystem.getNumParticles()) if tip4pSystem.isVirtualSite(i))
    tip4pSystem.addConstraint(site - 3, site, 0.015)
    name = list(tip4p.atoms())[site].name
    with pytest.raises(ValueError, match=f"atom {name} \\(particle {site}\\).*virtual site"):
        openmmrigid.rigidHydrogenGroups(tip4p, tip4pSystem)


def _withoutConstraintsOf(system, topology, name):
    """A copy of the System without the constraints that touch residues named `name`."""
    copy = openmm.System()
    copy.__setstate__(system.__getstate__())
    inResidue = {atom.index for atom in topology.atoms() if atom.residue.name == name}
    for k in reversed(range(copy.getNumConstraints())):
        i, j, _ = copy.getConstraintParameters(k)
        if i in inResidue or j in inResidue:
            copy.removeConstraint(k)
    return copy

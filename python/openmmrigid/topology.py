"""openmmrigid.rigidBodiesFromTopology: the rigid bodies of an openmm.app Topology, by residue name;
openmmrigid.rigidHydrogenGroups: its X-H groups and waters (and planar groups) as rigid bodies.

The integrators take explicit bodies as lists of particle indices; this module finds them from what
an openmm.app script already has (the Topology, and the System built from it), so that a rigid
ligand or solute is one line beside ``ForceField.createSystem``. Pure Python: it reads the Topology
and, if given, the System, and changes neither.
"""

import re
from collections.abc import Iterable, Mapping

import openmm
from openmm import app, unit

__all__ = ["rigidBodiesFromTopology", "rigidHydrogenGroups"]


def _describeResidue(residue):
    """'LIG 12 (index 11, chain A)': the name, PDB id and index by which a user finds a residue."""
    if residue.chain is None:
        return f"{residue.name} {residue.id} (residue index {residue.index})"
    chain = f"chain {residue.chain.id}" if residue.chain.id.strip() else f"chain index {residue.chain.index}"
    return f"{residue.name} {residue.id} (residue index {residue.index}, {chain})"


def _describeAtom(atom):
    return f"atom {atom.name} (particle {atom.index}) of residue {_describeResidue(atom.residue)}"


def _residueNames(residues):
    if isinstance(residues, str):
        return [residues]
    if not isinstance(residues, Iterable):
        raise ValueError(f"rigidBodiesFromTopology: residues must be a residue name or a list of residue names; "
                         f"received {residues!r}")
    names = list(residues)
    for name in names:
        if not isinstance(name, str):
            raise ValueError(f"rigidBodiesFromTopology: residues must hold residue names (str); received {name!r}")
    return names


def _compile(pattern, where):
    if not isinstance(pattern, str):
        raise ValueError(f"rigidBodiesFromTopology: the atom-name pattern {where} must be a regular expression "
                         f"(str); received {pattern!r}")
    try:
        return re.compile(pattern)
    except re.error as error:
        raise ValueError(f"rigidBodiesFromTopology: the atom-name pattern {pattern!r} {where} is not a valid "
                         f"regular expression: {error}") from None


def _atomPatterns(atoms, knownNames):
    """atoms (None, a pattern, or {residue name: pattern}) as (a default pattern or None, {name: pattern})."""
    if atoms is None:
        return None, {}
    if isinstance(atoms, str):
        return _compile(atoms, "given for every residue"), {}
    if isinstance(atoms, Mapping):
        patterns = {}
        for name, pattern in atoms.items():
            if name not in knownNames:
                raise ValueError(f"rigidBodiesFromTopology: atoms gives a pattern for residue name {name!r}, but no "
                                 f"selected residue has that name (selected: {', '.join(sorted(knownNames)) or 'none'})")
            patterns[name] = _compile(pattern, f"for residue {name!r}")
        return None, patterns
    raise ValueError("rigidBodiesFromTopology: atoms must be None, a regular expression over atom names, or a dict "
                     f"from residue name to one; received {atoms!r}")


def _residueByReference(reference, residues, where):
    if isinstance(reference, app.Residue):
        if reference.index >= len(residues) or residues[reference.index] is not reference:
            raise ValueError(f"rigidBodiesFromTopology: {where}: residue {reference.name} {reference.id} is not a "
                             "residue of this topology")
        return reference
    if isinstance(reference, bool) or not hasattr(reference, "__index__"):
        raise ValueError(f"rigidBodiesFromTopology: {where} must hold openmm.app.Residue objects or residue "
                         f"indices; received {reference!r}")
    index = reference.__index__()
    if not 0 <= index < len(residues):
        raise ValueError(f"rigidBodiesFromTopology: {where}: residue index {index} is out of range (the topology "
                         f"has {len(residues)} residues)")
    return residues[index]


def _mergeGroups(merge, residues):
    """merge as lists of Residue objects; a residue in two groups is an error."""
    if merge is None:
        return []
    if not isinstance(merge, Iterable) or isinstance(merge, (str, app.Residue)):
        raise ValueError("rigidBodiesFromTopology: merge must be a list of groups of residues (each a list of "
                         f"openmm.app.Residue objects or residue indices); received {merge!r}")
    groups, groupOf = [], {}
    for number, group in enumerate(merge):
        if not isinstance(group, Iterable) or isinstance(group, (str, app.Residue)):
            raise ValueError(f"rigidBodiesFromTopology: merge group {number} must be a list of residues; "
                             f"received {group!r}")
        members = []
        for reference in group:
            residue = _residueByReference(reference, residues, f"merge group {number}")
            if residue.index in groupOf and groupOf[residue.index] != number:
                raise ValueError(f"rigidBodiesFromTopology: residue {_describeResidue(residue)} is in merge groups "
                                 f"{groupOf[residue.index]} and {number}; its atoms would be in two bodies")
            if residue.index not in groupOf:
                groupOf[residue.index] = number
                members.append(residue)
        if not members:
            raise ValueError(f"rigidBodiesFromTopology: merge group {number} is empty")
        groups.append(members)
    return groups


def _skippedParticles(topology, system):
    """The particles that are in no body: virtual sites (and, without a System, atoms with no element)."""
    if system is None:
        return {atom.index for atom in topology.atoms() if atom.element is None}
    if system.getNumParticles() != topology.getNumAtoms():
        raise ValueError(f"rigidBodiesFromTopology: the system has {system.getNumParticles()} particles but the "
                         f"topology {topology.getNumAtoms()} atoms; pass the System built from this topology")
    return {i for i in range(system.getNumParticles()) if system.isVirtualSite(i)}


def _mergeBondedBodies(bodies, topology):
    """Merge the bodies that a bond of the topology joins (union-find over body numbers)."""
    bodyOf = {index: number for number, body in enumerate(bodies) for index in body}
    parent = list(range(len(bodies)))

    def root(number):
        while parent[number] != number:
            parent[number] = parent[parent[number]]
            number = parent[number]
        return number

    for atom1, atom2 in topology.bonds():
        first, second = bodyOf.get(atom1.index), bodyOf.get(atom2.index)
        if first is not None and second is not None:
            parent[root(first)] = root(second)
    merged = {}
    for number, body in enumerate(bodies):
        merged.setdefault(root(number), []).extend(body)
    return list(merged.values())


def _checkSystem(bodies, topology, system):
    """Errors the integrator would raise later, named here by atom: massless members, constraints out of a body."""
    atoms = list(topology.atoms())
    bodyOf = {index: number for number, body in enumerate(bodies) for index in body}
    for index in bodyOf:
        if system.getParticleMass(index).value_in_unit(unit.dalton) == 0:
            raise ValueError(f"rigidBodiesFromTopology: {_describeAtom(atoms[index])} has zero mass (OpenMM holds "
                             "it fixed), so it cannot be part of a rigid body; leave it out of the selection")
    for constraint in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(constraint)
        first, second = bodyOf.get(i), bodyOf.get(j)
        if (first is not None or second is not None) and first != second:
            def where(body):
                return "in no body" if body is None else f"in body {body}"
            raise ValueError(
                f"rigidBodiesFromTopology: constraint {constraint} joins {_describeAtom(atoms[i])} ({where(first)}) "
                f"to {_describeAtom(atoms[j])} ({where(second)}); a rigid body cannot be constrained to anything "
                "outside it: select both atoms or neither (or build the System with fewer constraints)")


def rigidBodiesFromTopology(topology, residues=(), atoms=None, merge=None, mergeBonded=False, system=None):
    """The rigid bodies of the selected residues of a Topology, as lists of particle indices.

    Each selected residue becomes one body holding its selected atoms, unless ``merge`` or
    ``mergeBonded`` joins residues into one body. The result is what ``RigidBodyIntegrator(stepSize,
    bodies)`` and ``RigidBodyLangevinIntegrator(temperature, friction, stepSize, bodies)`` take.

    Parameters
    ----------
    topology : openmm.app.Topology
        The topology the System was built from (atom indices are particle indices).
    residues : str or list of str
        The names of the residues to make rigid, as in the topology (``"LIG"``, ``["LIG", "HOH"]``),
        matched exactly (``openmm.app.PDBFile`` reads HIE, HID and HIP as HIS, for example). Every name must occur. With explicit bodies the integrator makes nothing
        else rigid: list the water's residue name (``"HOH"``) too if the water should stay rigid.
    atoms : str or dict, optional
        Which atoms of a selected residue belong to its body: a regular expression that must match
        the whole atom name (``re.fullmatch``), for every selected residue (a str) or per residue
        name (a dict; residues whose name is not a key give all their atoms). For example
        ``{"TRP": "CB|CG|CD[12]|NE1|CE[23]|CZ[23]|CH2|H[BDEZH].*"}`` makes the side chain of every
        tryptophan rigid. The pattern must match at least one atom of every residue it applies to.
    merge : list of lists, optional
        Groups of residues (``openmm.app.Residue`` objects or residue indices) whose selected atoms
        make one body each, for a molecule spanning residues. The residues of a group are selected
        whether or not their names are in ``residues``; ``atoms`` applies to them by name.
    mergeBonded : bool, optional
        If True, bodies joined by a bond of the topology between their selected atoms become one
        body (a ligand made of several residues, without listing them). Default False.
    system : openmm.System, optional
        The System built from this topology. With it, virtual sites (``System.isVirtualSite``, such
        as the M site of TIP4P water) are left out of the bodies (the integrator moves them with
        their parents), and the selection is checked for what the integrator would refuse: a body
        member of zero mass, a constraint between a body and an atom outside it. Without it, atoms
        with no element are taken to be the virtual sites.

    Returns
    -------
    list of list of int
        The bodies, each sorted, in the order of their first particle.

    Raises
    ------
    ValueError
        If a residue name matches no residue, a pattern is not a valid regular expression or matches
        no atom of a residue it applies to, a residue is in two merge groups, a body would hold no
        massive particle, the System does not match the topology, a body member has zero mass, or
        a constraint joins a body to a particle outside it; the message names the residue or atom.

    Examples
    --------
    >>> system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, constraints=app.HBonds)
    >>> bodies = openmmrigid.rigidBodiesFromTopology(pdb.topology, ["LIG", "HOH"], system=system)
    >>> integrator = openmmrigid.RigidBodyIntegrator(2*unit.femtoseconds, bodies)
    """
    if not isinstance(topology, app.Topology):
        raise ValueError(f"rigidBodiesFromTopology: topology must be an openmm.app.Topology; received {topology!r}")
    names = _residueNames(residues)
    allResidues = list(topology.residues())
    groups = _mergeGroups(merge, allResidues)
    if not names and not groups:
        raise ValueError("rigidBodiesFromTopology: nothing is selected; give residue names (residues=[...]) or "
                         "merge groups")
    present = {residue.name for residue in allResidues}
    for name in names:
        if name not in present:
            raise ValueError(f"rigidBodiesFromTopology: no residue of the topology is named {name!r} (its residue "
                             f"names: {', '.join(sorted(present))})")
    wanted = set(names)
    selected = [residue for residue in allResidues if residue.name in wanted]
    merged = {residue.index for group in groups for residue in group}
    defaultPattern, patterns = _atomPatterns(atoms, wanted | {allResidues[i].name for i in merged})
    skipped = _skippedParticles(topology, system)

    def selectedAtoms(residue):
        pattern = patterns.get(residue.name, defaultPattern)
        chosen = [atom for atom in residue.atoms() if pattern is None or pattern.fullmatch(atom.name)]
        if pattern is not None and not chosen:
            raise ValueError(f"rigidBodiesFromTopology: the atom-name pattern {pattern.pattern!r} matches no atom of "
                             f"residue {_describeResidue(residue)} (its atoms: "
                             f"{', '.join(atom.name for atom in residue.atoms())})")
        massive = [atom.index for atom in chosen if atom.index not in skipped]
        if not massive:
            raise ValueError(f"rigidBodiesFromTopology: residue {_describeResidue(residue)} has no selected atom that "
                             "is not a virtual site, so it cannot make a body")
        return massive

    bodies = [selectedAtoms(residue) for residue in selected if residue.index not in merged]
    bodies += [[index for residue in group for index in selectedAtoms(residue)] for group in groups]
    if mergeBonded:
        bodies = _mergeBondedBodies(bodies, topology)
    bodies = sorted((sorted(body) for body in bodies), key=lambda body: body[0])
    if system is not None:
        _checkSystem(bodies, topology, system)
    return bodies


# ---------------------------------------------------------------------------------------------------
# Rigid X-H groups (and planar groups) from the System's constraints

# The planar groups of planarGroups=True: per residue name, the heavy atoms of each group, by name. The
# hydrogens bonded to them (by the Topology's bonds) join the group too.
_AROMATIC_RINGS = {
    "PHE": ("CG", "CD1", "CD2", "CE1", "CE2", "CZ"),
    "TYR": ("CG", "CD1", "CD2", "CE1", "CE2", "CZ"),
    "TRP": ("CG", "CD1", "CD2", "NE1", "CE2", "CE3", "CZ2", "CZ3", "CH2"),
    "HIS": ("CG", "ND1", "CD2", "CE1", "NE2"),
    "HID": ("CG", "ND1", "CD2", "CE1", "NE2"),
    "HIE": ("CG", "ND1", "CD2", "CE1", "NE2"),
    "HIP": ("CG", "ND1", "CD2", "CE1", "NE2"),
}
_SIDE_CHAIN_AMIDES = {
    "ASN": ("CG", "OD1", "ND2"),
    "GLN": ("CD", "OE1", "NE2"),
}


def _hydrogenGroupResidues(topology, residues):
    """The selected residues (None: all) as a list of Residue objects, from names or Residue objects."""
    allResidues = list(topology.residues())
    if residues is None:
        return allResidues
    if isinstance(residues, (str, app.Residue)):
        residues = [residues]
    if not isinstance(residues, Iterable):
        raise ValueError("rigidHydrogenGroups: residues must be None, a residue name, a list of residue names or "
                         f"a collection of openmm.app.Residue objects; received {residues!r}")
    residues = list(residues)
    if not residues:
        raise ValueError("rigidHydrogenGroups: residues is empty; pass None to select every residue")
    if all(isinstance(residue, str) for residue in residues):
        present = {residue.name for residue in allResidues}
        for name in residues:
            if name not in present:
                raise ValueError(f"rigidHydrogenGroups: no residue of the topology is named {name!r} (its residue "
                                 f"names: {', '.join(sorted(present))})")
        wanted = set(residues)
        return [residue for residue in allResidues if residue.name in wanted]
    if all(isinstance(residue, app.Residue) for residue in residues):
        for residue in residues:
            if residue.index >= len(allResidues) or allResidues[residue.index] is not residue:
                raise ValueError(f"rigidHydrogenGroups: residue {residue.name} {residue.id} is not a residue of "
                                 "this topology")
        chosen = {residue.index for residue in residues}
        return [residue for residue in allResidues if residue.index in chosen]
    wrong = next(residue for residue in residues if not isinstance(residue, (str, app.Residue)))
    raise ValueError("rigidHydrogenGroups: residues must hold residue names (str) or openmm.app.Residue objects, "
                     f"not a mixture or anything else; received {wrong!r}")


def _planarGroups(topology, selected):
    """The planar groups of the selected residues, each a list of atom indices (see rigidHydrogenGroups)."""
    bonded = {}
    for atom1, atom2 in topology.bonds():
        bonded.setdefault(atom1.index, []).append(atom2)
        bonded.setdefault(atom2.index, []).append(atom1)

    def withHydrogens(atoms):
        group = [atom.index for atom in atoms]
        for atom in atoms:
            group += [other.index for other in bonded.get(atom.index, ())
                      if other.element is not None and other.element.symbol == "H"]
        return group

    def named(residue, names):
        """The residue's atoms of these names, or None if it lacks one (a terminal or unusual residue)."""
        byName = {atom.name: atom for atom in residue.atoms()}
        if not all(name in byName for name in names):
            return None
        return [byName[name] for name in names]

    groups = []
    isSelected = {residue.index for residue in selected}
    for residue in selected:
        names = _AROMATIC_RINGS.get(residue.name) or _SIDE_CHAIN_AMIDES.get(residue.name)
        atoms = named(residue, names) if names else None
        if atoms is not None:
            groups.append(withHydrogens(atoms))
        # The peptide group that follows this residue: its C and O, the next residue's N and N's hydrogens.
        carbonyl = named(residue, ("C", "O"))
        if carbonyl is None:
            continue
        for other in bonded.get(carbonyl[0].index, ()):
            following = other.residue
            if (other.name == "N" and following is not residue and following.index in isSelected):
                groups.append([atom.index for atom in carbonyl] + withHydrogens([other]))
    return groups


def rigidHydrogenGroups(topology, system, residues=None, planarGroups=False):
    """The constraint clusters (X-H groups, waters) and optional planar groups of a System, as rigid bodies.

    Every cluster of the System's constraints (a connected component of the graph whose edges are
    ``System.getConstraintParameters``) whose atoms all lie in the selected residues becomes one rigid
    body. For a System built with ``constraints=app.HBonds, rigidWater=True`` that is each heavy atom
    with the hydrogens bonded to it (the X-H groups: CH, CH2, CH3, NH, NH3+, OH, SH, ...) and each
    water molecule (its massive atoms: a virtual site, such as the M site of TIP4P water, is in no
    body; the integrator moves it with its parents). The result is what
    ``RigidBodyIntegrator(stepSize, bodies)`` and ``RigidBodyLangevinIntegrator(temperature,
    friction, stepSize, bodies)`` take. With explicit bodies the integrator makes nothing else rigid,
    so the bodies hold everything that should be rigid, waters included; the constraints of clusters
    outside the selection stay constraints among free particles.

    This is a change of the model, not only of the integrator: a rigid X-H group also freezes its
    H-X-H angles (the constraints hold only the X-H bond lengths), and with ``planarGroups`` the
    internal geometry of each aromatic ring, amide and peptide group is frozen too, much as
    GROMACS's virtual-site hydrogens are. Each body keeps the shape it has when the Context's
    positions are set: start from an energy-minimized or freshly built structure, not from a thermal
    snapshot of a flexible run, whose distortions would be frozen in. The
    bonded terms and nonbonded pairs inside each body then do no work: remove them with
    ``openmmrigid.removeIntraBodyInteractions(system, bodies)``, which gives the same motion at less
    cost. The light X-H bodies are typically run with raised moments of inertia
    (``integrator.setMinimumMomentOfInertia(...)``, which leaves the distribution of positions
    unchanged) in place of hydrogen mass repartitioning, to allow a larger step.

    Parameters
    ----------
    topology : openmm.app.Topology
        The topology the System was built from (atom indices are particle indices).
    system : openmm.System
        The System built from this topology, with constraints (``ForceField.createSystem(...,
        constraints=app.HBonds)``); it is read, not changed.
    residues : None, str, list of str, or collection of openmm.app.Residue, optional
        The residues whose constraint clusters (and planar groups) become bodies: None (the default)
        for every residue; else residue names as in the topology (``"HOH"``, ``["ALA", "HOH"]``;
        every name must occur), or Residue objects of this topology.
    planarGroups : bool, optional
        If True, also make each planar group of the selected residues one body, merged with every
        constraint cluster that shares an atom with it (and groups that share an atom are merged
        too): the aromatic rings of PHE and TYR (CG, CD1, CD2, CE1, CE2, CZ), TRP (CG, CD1, CD2,
        NE1, CE2, CE3, CZ2, CZ3, CH2) and HIS, HID, HIE, HIP (CG, ND1, CD2, CE1, NE2); the
        side-chain amides of ASN (CG, OD1, ND2) and GLN (CD, OE1, NE2); and the backbone peptide
        groups: the C and O of a residue with the N of the next residue, where a bond of the
        topology joins that C to that N and both residues are selected. Each group also holds the
        hydrogens bonded to its atoms in the topology (ring hydrogens, HD21 and HD22, the amide H;
        the N of proline has none, so its peptide group is C, O and N; TYR's OH is not in the ring).
        Atoms are found by name; a residue that lacks one of the names (a terminal residue without
        C or O, an unusual variant) gives no group of that kind. Such a body is not one constraint
        cluster, so a System with an ``AndersenThermostat`` is refused with it. Default False.

    Returns
    -------
    list of list of int
        The bodies, each sorted, in the order of their first particle.

    Raises
    ------
    ValueError
        If topology or system is of the wrong type or they differ in particle count, a residue name
        matches no residue, the System has no constraint in the selected residues, a constraint
        cluster reaches from a selected residue into one that is not selected, or a body would hold
        a virtual site or a massless particle; the message names the residue or atoms.

    Examples
    --------
    >>> forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    >>> modeller = app.Modeller(pdb.topology, pdb.positions)
    >>> modeller.addSolvent(forceField, padding=1.0*unit.nanometer)
    >>> system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, constraints=app.HBonds)
    >>> bodies = openmmrigid.rigidHydrogenGroups(modeller.topology, system)
    >>> lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    >>> integrator = openmmrigid.RigidBodyLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond,
    ...                                                      2*unit.femtoseconds, bodies)
    >>> simulation = app.Simulation(modeller.topology, lean, integrator)
    """
    if not isinstance(topology, app.Topology):
        raise ValueError(f"rigidHydrogenGroups: topology must be an openmm.app.Topology; received {topology!r}")
    if not isinstance(system, openmm.System):
        raise ValueError(f"rigidHydrogenGroups: system must be an openmm.System; received {system!r}")
    if system.getNumParticles() != topology.getNumAtoms():
        raise ValueError(f"rigidHydrogenGroups: the system has {system.getNumParticles()} particles but the "
                         f"topology {topology.getNumAtoms()} atoms; pass the System built from this topology")
    selected = _hydrogenGroupResidues(topology, residues)
    atoms = list(topology.atoms())
    inSelection = {atom.index for residue in selected for atom in residue.atoms()}

    parent = list(range(system.getNumParticles()))

    def root(index):
        while parent[index] != index:
            parent[index] = parent[parent[index]]
            index = parent[index]
        return index

    def join(first, second):
        parent[root(first)] = root(second)

    constrained = set()
    for constraint in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(constraint)
        join(i, j)
        constrained.update((i, j))
    clusters = {}
    for index in sorted(constrained):
        clusters.setdefault(root(index), []).append(index)
    members = set()
    for cluster in clusters.values():
        inside = [index for index in cluster if index in inSelection]
        if not inside:
            continue
        if len(inside) < len(cluster):
            outside = [index for index in cluster if index not in inSelection]
            raise ValueError(
                "rigidHydrogenGroups: a constraint cluster joins the selected "
                f"{', '.join(_describeAtom(atoms[i]) for i in inside)} to the unselected "
                f"{', '.join(_describeAtom(atoms[i]) for i in outside)}; select both residues or neither")
        members.update(cluster)
    if not members:
        where = "the selected residues" if residues is not None else "the System"
        raise ValueError(f"rigidHydrogenGroups: there is no constraint in {where} (the System has "
                         f"{system.getNumConstraints()} constraints in all), so there are no X-H groups to make "
                         "rigid; build it with constraints=app.HBonds (and rigidWater=True)")
    if planarGroups:
        for group in _planarGroups(topology, selected):
            for index in group[1:]:
                join(group[0], index)
            members.update(group)
    for index in sorted(members):
        if system.isVirtualSite(index):
            raise ValueError(f"rigidHydrogenGroups: {_describeAtom(atoms[index])} is a virtual site held in a "
                             "constraint cluster or planar group; a virtual site cannot be part of a rigid body")
        if system.getParticleMass(index).value_in_unit(unit.dalton) == 0:
            raise ValueError(f"rigidHydrogenGroups: {_describeAtom(atoms[index])} has zero mass (OpenMM holds it "
                             "fixed), so it cannot be part of a rigid body; leave its residue out of the selection")
    bodies = {}
    for index in sorted(members):
        bodies.setdefault(root(index), []).append(index)
    return sorted(bodies.values(), key=lambda body: body[0])

"""openmmrigid.rigidBodiesFromTopology: the rigid bodies of an openmm.app Topology, by residue name.

The integrators take explicit bodies as lists of particle indices; this module finds them from what
an openmm.app script already has (the Topology, and the System built from it), so that a rigid
ligand or solute is one line beside ``ForceField.createSystem``. Pure Python: it reads the Topology
and, if given, the System, and changes neither.
"""

import re
from collections.abc import Iterable, Mapping

from openmm import app, unit

__all__ = ["rigidBodiesFromTopology"]


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

"""openmmrigid.removeIntraBodyInteractions: a System without the interactions a rigid body does not feel.

The forces between the atoms of one rigid body (its bonds, angles, torsions, and the nonbonded pairs
among its own atoms) sum to zero force and zero torque on it: they do no work, and their energy is
a constant while the body stays rigid. Computing them costs time for nothing. This module makes a
copy of a System without them, for use with the rigid-body integrators and the same bodies. Pure
Python; the System passed in is not changed.
"""

import re
import xml.etree.ElementTree as ElementTree

import openmm

__all__ = ["removeIntraBodyInteractions"]

# The bonded forces whose terms are removed: XML container of the terms, and the attributes that
# name a term's particles (as openmm.XmlSerializer writes them; checked against the API in the tests).
_BONDED_TERMS = {
    "HarmonicBondForce": ("Bonds", re.compile(r"p[0-9]+")),
    "HarmonicAngleForce": ("Angles", re.compile(r"p[0-9]+")),
    "PeriodicTorsionForce": ("Torsions", re.compile(r"p[0-9]+")),
    "RBTorsionForce": ("Torsions", re.compile(r"p[0-9]+")),
    "CMAPTorsionForce": ("Torsions", re.compile(r"[ab][0-9]+")),
    "CustomBondForce": ("Bonds", re.compile(r"p[0-9]+")),
    "CustomAngleForce": ("Angles", re.compile(r"p[0-9]+")),
    "CustomTorsionForce": ("Torsions", re.compile(r"p[0-9]+")),
    "CustomCompoundBondForce": ("Bonds", re.compile(r"p[0-9]+")),
}
# A CustomCompoundBondForce whose energy reads its particles' coordinates (x1, y2, z3, ...) is not a
# function of the body's shape alone (a positional restraint, a wall): its terms are kept.
_COORDINATE = re.compile(r"(?<![A-Za-z0-9_.])[xyz][0-9]+(?![A-Za-z0-9_(])")


def _validatedBodies(system, bodies):
    """bodies as lists of int, each particle in at most one body, none a virtual site."""
    try:
        lists = [[int(index) for index in body] for body in bodies]
    except (TypeError, ValueError):
        raise ValueError("removeIntraBodyInteractions: bodies must be a list of lists of particle indices; "
                         f"received {bodies!r}") from None
    bodyOf = {}
    count = system.getNumParticles()
    for number, body in enumerate(lists):
        if not body:
            raise ValueError(f"removeIntraBodyInteractions: body {number} is empty")
        for index in body:
            if not 0 <= index < count:
                raise ValueError(f"removeIntraBodyInteractions: body {number} holds particle {index}, but the system "
                                 f"has {count} particles")
            if system.isVirtualSite(index):
                raise ValueError(f"removeIntraBodyInteractions: body {number} holds particle {index}, a virtual site; "
                                 "virtual sites follow their parents and are in no body")
            if index in bodyOf and bodyOf[index] != number:
                raise ValueError(f"removeIntraBodyInteractions: particle {index} is in bodies {bodyOf[index]} and "
                                 f"{number}")
            bodyOf[index] = number
    return lists, bodyOf


def _withVirtualSites(system, bodies, bodyOf):
    """Each body with the virtual sites whose parents all lie in it (they move rigidly with it); bodyOf
    is extended to them."""
    rigid = [list(dict.fromkeys(body)) for body in bodies]
    sites = [i for i in range(system.getNumParticles()) if system.isVirtualSite(i)]
    changed = True
    while changed:  # again, for sites built on other sites
        changed = False
        for index in sites:
            if index in bodyOf:
                continue
            site = system.getVirtualSite(index)
            owners = {bodyOf.get(site.getParticle(k)) for k in range(site.getNumParticles())}
            if len(owners) == 1 and None not in owners:
                number = owners.pop()
                bodyOf[index] = number
                rigid[number].append(index)
                changed = True
    return rigid


def _inOneBody(particles, bodyOf):
    first = bodyOf.get(particles[0])
    return first is not None and all(bodyOf.get(p) == first for p in particles[1:])


def _pruneBondedTerms(force, bodyOf):
    """Remove from a <Force> element the terms whose particles all lie in one body; True if it is a handled type."""
    kind = force.get("type")
    if kind not in _BONDED_TERMS:
        return False
    if kind == "CustomCompoundBondForce" and _COORDINATE.search(force.get("energy", "")):
        return False
    containerName, particleAttribute = _BONDED_TERMS[kind]
    container = force.find(containerName)
    if container is None:
        return True
    for term in list(container):
        particles = [int(value) for name, value in term.attrib.items() if particleAttribute.fullmatch(name)]
        if particles and _inOneBody(particles, bodyOf):
            container.remove(term)
    return True


def _removeConstraints(root, bodyOf):
    constraints = root.find("Constraints")
    if constraints is None:
        return
    for constraint in list(constraints):
        if _inOneBody([int(constraint.get("p1")), int(constraint.get("p2"))], bodyOf):
            constraints.remove(constraint)


def _pairs(body):
    for a in range(len(body)):
        for b in range(a + 1, len(body)):
            yield body[a], body[b]


def _zeroNonbondedPairs(force, rigid):
    """Make every pair within a body a NonbondedForce exception with no charge product and no epsilon."""
    exceptions = {}
    for index in range(force.getNumExceptions()):
        i, j, _, _, _ = force.getExceptionParameters(index)
        exceptions[(min(i, j), max(i, j))] = index
    zeroed = set()
    for body in rigid:
        for i, j in _pairs(body):
            index = exceptions.get((min(i, j), max(i, j)))
            if index is None:
                force.addException(i, j, 0.0, 1.0, 0.0)
            else:
                _, _, _, sigma, _ = force.getExceptionParameters(index)
                force.setExceptionParameters(index, i, j, 0.0, sigma, 0.0)
                zeroed.add(index)
    # An offset would bring a zeroed exception's charge product or epsilon back when its global parameter is nonzero.
    for offset in range(force.getNumExceptionParameterOffsets()):
        parameter, index, _, _, _ = force.getExceptionParameterOffset(offset)
        if index in zeroed:
            force.setExceptionParameterOffset(offset, parameter, index, 0.0, 0.0, 0.0)


def _excludeCustomNonbondedPairs(force, rigid):
    excluded = set()
    for index in range(force.getNumExclusions()):
        i, j = force.getExclusionParticles(index)
        excluded.add((min(i, j), max(i, j)))
    for body in rigid:
        for i, j in _pairs(body):
            if (min(i, j), max(i, j)) not in excluded:
                force.addExclusion(i, j)


def removeIntraBodyInteractions(system, bodies):
    """A copy of a System without the interactions among the atoms of each rigid body.

    Off unless called: the integrators never change the System. The copy differs from the original
    only in what does no work on rigid bodies, so that with the same bodies it gives the same
    forces and torques on every body, and the same motion, while its potential energy differs by a
    constant (the energy of the removed terms, fixed by the bodies' shapes; constant while global
    parameters are unchanged). Use it with the same bodies, passed explicitly to the integrator
    (``RigidBodyIntegrator(stepSize, bodies)``): the copy no longer holds the constraints from which
    bodies would be found, and with another integrator it is a different model.

    In the copy:

    - Terms whose particles all lie in one body are removed from ``HarmonicBondForce``,
      ``HarmonicAngleForce``, ``PeriodicTorsionForce``, ``RBTorsionForce``, ``CMAPTorsionForce``,
      ``CustomBondForce``, ``CustomAngleForce``, ``CustomTorsionForce`` and
      ``CustomCompoundBondForce`` (unless its energy reads particle coordinates x1, y1, z1, ...,
      which a rigid motion changes; such a force is kept whole). Each of these forces stays at its
      index, with its force group, name, periodic-boundary flag, global parameters, energy
      parameter derivatives, tabulated functions and CMAP maps: the copy is made through
      ``openmm.XmlSerializer`` with only the terms taken out.
    - Every pair of particles within a body is, in each ``NonbondedForce``, an exception with
      chargeProd 0 and epsilon 0 (an existing exception is set to that, keeping its index; its
      exception parameter offsets, if any, are set to zero), and in each ``CustomNonbondedForce``
      an exclusion. With PME, OpenMM then also subtracts the pair's reciprocal-space energy, so the
      whole Coulomb interaction within the body goes (a constant, as the rest).
    - The constraints between two particles of one body are removed.
    - A virtual site whose parents all lie in one body counts as part of it for the above.
    - Every other force (GBSAOBCForce, CustomGBForce, CustomHbondForce, CustomCentroidBondForce,
      CustomManyParticleForce, AMOEBA forces, forces from other plugins, ...) is left as it is:
      they still compute their intra-body parts, which is correct, only not cheaper.

    Parameters
    ----------
    system : openmm.System
        The System to copy; it is not changed.
    bodies : list of lists of int
        The particle indices of each rigid body, as given to the integrator (for example from
        ``openmmrigid.rigidBodiesFromTopology``). Particles in no body are untouched.

    Returns
    -------
    openmm.System
        The new System.

    Raises
    ------
    ValueError
        If bodies is not a list of lists of particle indices, a body is empty, an index is out of
        range or a virtual site, or a particle is in two bodies.

    Examples
    --------
    >>> bodies = openmmrigid.rigidBodiesFromTopology(topology, ["LIG", "HOH"], system=system)
    >>> lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    >>> simulation = app.Simulation(topology, lean, openmmrigid.RigidBodyIntegrator(2*unit.femtoseconds, bodies))
    """
    if not isinstance(system, openmm.System):
        raise ValueError(f"removeIntraBodyInteractions: system must be an openmm.System; received {system!r}")
    bodies, bodyOf = _validatedBodies(system, bodies)
    rigid = _withVirtualSites(system, bodies, bodyOf)
    root = ElementTree.fromstring(openmm.XmlSerializer.serialize(system))
    _removeConstraints(root, bodyOf)
    forces = root.find("Forces")
    for force in (forces if forces is not None else []):
        _pruneBondedTerms(force, bodyOf)
    copy = openmm.XmlSerializer.deserialize(ElementTree.tostring(root, encoding="unicode"))
    for force in copy.getForces():
        if isinstance(force, openmm.NonbondedForce):
            _zeroNonbondedPairs(force, rigid)
        elif isinstance(force, openmm.CustomNonbondedForce):
            _excludeCustomNonbondedPairs(force, rigid)
    return copy

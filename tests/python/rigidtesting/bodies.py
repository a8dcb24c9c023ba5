"""What the tests measure of the bodies, computed from the State alone (masses, positions, velocities):
independent of the integrator's own sums, which are not public.

principalMoments(masses, positions)
    The principal moments of inertia about the centre of mass, ascending (amu nm^2).
bodyKind(masses, positions)
    "point", "linear", "spherical", "symmetric" or "asymmetric", as the integrator classifies a body (a
    body within 0.002 nm of its axis and 1 % of its length is linear; moments within 1e-10, relative,
    are equal).
rigidKineticEnergies(context, integrator)
    The translational (bodies' centres of mass and free particles) and rotational kinetic energy (kJ/mol)
    of the State's velocities, the rotation in the bodies' raised moments.
rigidDegreesOfFreedom(context, integrator)
    The degrees of freedom as the integrator moves the system (what computeSystemTemperature() divides by).
"""

import numpy as np
import openmm
from openmm import unit

LINEAR_TOLERANCE = 0.002  # nm: RigidBodySystem::LinearTolerance
EQUAL_MOMENTS = 1e-10     # relative


def _inertia(masses, positions):
    masses = np.asarray(masses, dtype=float)
    positions = np.asarray(positions, dtype=float)
    relative = positions - masses @ positions / masses.sum()
    tensor = np.einsum("i,ij,ik->jk", masses, relative, relative)
    return np.trace(tensor) * np.eye(3) - tensor, relative


def principalMoments(masses, positions):
    """The principal moments of inertia about the centre of mass, ascending."""
    if len(masses) == 1:
        return np.zeros(3)
    return np.linalg.eigvalsh(_inertia(masses, positions)[0])


def _isLinear(masses, positions):
    inertia, relative = _inertia(masses, positions)
    axes = np.linalg.eigh(inertia)[1]
    along = relative @ axes[:, 0]
    offAxis = np.linalg.norm(relative - np.outer(along, axes[:, 0]), axis=1).max()
    return offAxis <= LINEAR_TOLERANCE and offAxis <= 0.01 * np.abs(along).max()


def bodyKind(masses, positions):
    """The kind of a body with these particles, as the integrator names it."""
    if len(masses) == 1 or np.ptp(np.asarray(positions, dtype=float), axis=0).max() == 0.0:
        return "point"
    if _isLinear(masses, positions):
        return "linear"
    moments = principalMoments(masses, positions)
    close = [abs(moments[k + 1] - moments[k]) <= EQUAL_MOMENTS * moments[2] for k in range(2)]
    if all(close):
        return "spherical"
    return "symmetric" if any(close) else "asymmetric"


def _state(context):
    state = context.getState(getPositions=True, getVelocities=True)
    positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond)
    box = state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
    return positions, velocities, box


def _whole(positions, box, periodic):
    """A body's positions with every particle at the image nearest the first (bodies are small)."""
    if not periodic:
        return positions
    delta = positions - positions[0]
    for k in (2, 1, 0):
        delta -= np.outer(np.round(delta[:, k] / box[k][k]), box[k])
    return positions[0] + delta


def _bodies(context, integrator):
    system = context.getSystem()
    masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
    bodies = [np.array(integrator.getBodyParticles(b)) for b in range(integrator.getNumBodies())]
    inBody = np.zeros(len(masses), dtype=bool)
    for body in bodies:
        inBody[body] = True
    free = np.flatnonzero(~inBody & (masses > 0.0))
    return system, masses, bodies, free


def rigidKineticEnergies(context, integrator):
    """(translational, rotational) kinetic energy in kJ/mol of the State's velocities, each body's rotation
    in its moments raised to integrator.getMinimumMomentOfInertia()."""
    system, masses, bodies, free = _bodies(context, integrator)
    positions, velocities, box = _state(context)
    floor = integrator.getMinimumMomentOfInertia().value_in_unit(unit.amu * unit.nanometer**2)
    periodic = system.usesPeriodicBoundaryConditions()
    translational = 0.5 * float(np.sum(masses[free] * np.sum(velocities[free]**2, axis=1)))
    rotational = 0.0
    for body in bodies:
        m = masses[body]
        v = velocities[body]
        centreVelocity = m @ v / m.sum()
        translational += 0.5 * m.sum() * float(centreVelocity @ centreVelocity)
        if len(body) == 1:
            continue
        inertia, relative = _inertia(m, _whole(positions[body], box, periodic))
        angularMomentum = np.sum(m[:, None] * np.cross(relative, v - centreVelocity), axis=0)
        moments, axes = np.linalg.eigh(inertia)
        bodyMomentum = axes.T @ angularMomentum
        # The angular velocity of the particles' motion (none along a linear body's axis), and the energy
        # of that angular velocity in the raised moments.
        omega = np.array([bodyMomentum[k] / moments[k] if moments[k] > 1e-10 * moments[2] else 0.0 for k in range(3)])
        raised = np.where(moments > 1e-10 * moments[2], np.maximum(moments, floor), 0.0)
        rotational += 0.5 * float(np.sum(raised * omega**2))
    return translational, rotational


def rigidDegreesOfFreedom(context, integrator):
    """3 per free particle less one per constraint between free particles, 3 + (0, 2 or 3) per body (one
    particle, linear, other), less 3 with a CMMotionRemover."""
    system, masses, bodies, free = _bodies(context, integrator)
    positions, _, box = _state(context)
    freeSet = set(free.tolist())
    dof = 3 * len(free) - sum(1 for c in range(system.getNumConstraints())
                              if set(system.getConstraintParameters(c)[:2]) <= freeSet)
    for body in bodies:
        kind = bodyKind(masses[body], _whole(positions[body], box, system.usesPeriodicBoundaryConditions()))
        dof += 3 + {"point": 0, "linear": 2}.get(kind, 3)
    if any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces()):
        dof -= 3
    return dof

"""What the tests and benchmarks measure of the bodies, computed from the State alone (masses, positions,
velocities), independently of the integrator's own sums, which are not public.

principalMoments(masses, positions)
    The principal moments of inertia about the centre of mass, ascending (amu nm^2).
bodyKind(masses, positions), bodyKinds(context, integrator)
    "point", "linear", "spherical", "symmetric" or "asymmetric", as the integrator classifies a body (one
    within 0.002 nm of its axis and 1 % of its length is linear; moments within 1e-10, relative, are equal).
kineticEnergies(positions, velocities, masses, bodies, minimumMoment, box), rigidKineticEnergies(context, integrator)
    The translational (bodies' centres of mass and free particles) and rotational kinetic energy (kJ/mol)
    of velocities that are rigid motion, the rotation in the bodies' raised moments: numpy over all the
    bodies of one size at once.
rigidDegreesOfFreedom(context, integrator)
    The degrees of freedom as the integrator moves the system (what computeSystemTemperature() divides by).
"""

import numpy as np
import openmm
from openmm import unit

from rigidtesting import particleMasses

LINEAR_TOLERANCE = 0.002  # nm: RigidBodySystem::LinearTolerance
EQUAL_MOMENTS = 1e-10     # relative to the largest moment; below it a moment is zero


def integratorBodies(integrator):
    """The bodies of a rigid-body integrator bound to a Context: a list of arrays of particle indices."""
    return [np.asarray(integrator.getBodyParticles(b), dtype=int) for b in range(integrator.getNumBodies())]


def _whole(positions, box):
    """Positions (..., k, 3) of bodies with each particle at the image nearest the body's first (box: rows
    of the periodic box vectors, or None)."""
    positions = np.array(positions, dtype=float)
    if box is None:
        return positions
    delta = positions - positions[..., :1, :]
    for k in (2, 1, 0):
        delta -= np.round(delta[..., k] / box[k][k])[..., None] * box[k]
    return positions[..., :1, :] + delta


def _inertia(masses, positions):
    """Positions relative to the centre of mass (..., k, 3) and inertia tensors (..., 3, 3) of bodies:
    masses (..., k), positions (..., k, 3)."""
    m = np.asarray(masses, dtype=float)[..., None]
    centre = (m * positions).sum(axis=-2) / m.sum(axis=-2)
    r = positions - centre[..., None, :]
    outer = (m[..., None] * r[..., :, None] * r[..., None, :]).sum(axis=-3)
    return r, np.trace(outer, axis1=-2, axis2=-1)[..., None, None] * np.eye(3) - outer


def principalMoments(masses, positions):
    """The principal moments of inertia about the centre of mass (the body whole), ascending."""
    if len(masses) == 1:
        return np.zeros(3)
    return np.linalg.eigvalsh(_inertia(masses, np.asarray(positions, dtype=float))[1])


def bodyKind(masses, positions):
    """The kind of a body with these particles (the body whole), as the integrator names it."""
    positions = np.asarray(positions, dtype=float)
    if len(masses) == 1 or np.ptp(positions, axis=0).max() == 0.0:
        return "point"
    relative, inertia = _inertia(masses, positions)
    moments, axes = np.linalg.eigh(inertia)
    along = relative @ axes[:, 0]
    offAxis = np.linalg.norm(relative - np.outer(along, axes[:, 0]), axis=1).max()
    if offAxis <= LINEAR_TOLERANCE and offAxis <= 0.01 * np.abs(along).max():
        return "linear"
    close = [abs(moments[k + 1] - moments[k]) <= EQUAL_MOMENTS * moments[2] for k in range(2)]
    if all(close):
        return "spherical"
    return "symmetric" if any(close) else "asymmetric"


def _stateArrays(context, velocities=False):
    """Positions, velocities (if asked) and box (None if not periodic) of the Context's State, as arrays."""
    state = context.getState(getPositions=True, getVelocities=velocities)
    x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer / unit.picosecond) if velocities else None
    box = (state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
           if context.getSystem().usesPeriodicBoundaryConditions() else None)
    return x, v, box


def bodyKinds(context, integrator, positions=None):
    """The kind of each body of a rigid-body integrator bound to the Context, from the Context's positions or
    from `positions` (particles x 3, nm, a Quantity or not: those the Context was given, exact where a
    single-precision platform would round them)."""
    masses = particleMasses(context.getSystem())
    x, _, box = _stateArrays(context)
    if positions is not None:
        x = np.asarray(positions.value_in_unit(unit.nanometer) if unit.is_quantity(positions) else positions, dtype=float)
    return [bodyKind(masses[body], _whole(x[body], box)) for body in integratorBodies(integrator)]


def kineticEnergies(positions, velocities, masses, bodies, minimumMoment=0.0, box=None):
    """(translational, rotational) kinetic energy in kJ/mol of rigid motion: translational, 1/2 M V^2 of each
    body's centre of mass plus 1/2 m v^2 of each free massive particle; rotational, 1/2 sum_k I'_k w_k^2 of
    each body, with the angular velocity w of its particles' velocities (w_k = L_k / I_k about the principal
    axes of the particles' masses; none about a linear body's axis) and the moments I'_k it moves with,
    raised to minimumMoment (amu nm^2, a Quantity or not) where nonzero and smaller. With raised moments
    the sum is the integrator's (and the State's) kinetic energy, not 1/2 sum m v^2.

    positions (nm), velocities (nm/ps): arrays (particles, 3); masses (amu); bodies: index arrays; box: the
    periodic box vectors (rows, nm) where the positions may be wrapped, else None."""
    positions, velocities = np.asarray(positions, dtype=float), np.asarray(velocities, dtype=float)
    masses = np.asarray(masses, dtype=float)
    if unit.is_quantity(minimumMoment):
        minimumMoment = minimumMoment.value_in_unit(unit.dalton * unit.nanometer**2)
    free = masses > 0
    bySize = {}
    for body in bodies:
        free[body] = False
        bySize.setdefault(len(body), []).append(body)
    translational = 0.5 * float(np.sum(masses[free] * np.sum(velocities[free]**2, axis=1)))
    rotational = 0.0
    for group in bySize.values():
        group = np.array(group)
        m, v = masses[group], velocities[group]                              # (N, k), (N, k, 3)
        total = m.sum(axis=1)
        speed = np.einsum("nk,nki->ni", m, v) / total[:, None]
        translational += 0.5 * float(np.sum(total * np.sum(speed**2, axis=1)))
        if group.shape[1] == 1:
            continue
        r, inertia = _inertia(m, _whole(positions[group], box))
        angular = np.einsum("nk,nki->ni", m, np.cross(r, v - speed[:, None, :]))
        moments, axes = np.linalg.eigh(inertia)                              # ascending, axes as columns
        principal = np.einsum("nij,ni->nj", axes, angular)
        turning = moments > EQUAL_MOMENTS * moments[:, 2:]
        omega = np.divide(principal, moments, out=np.zeros_like(principal), where=turning)
        rotational += 0.5 * float(np.sum(np.where(turning, np.maximum(moments, minimumMoment), 0.0) * omega**2))
    return translational, rotational


def rigidKineticEnergies(context, integrator, bodies=None, masses=None):
    """kineticEnergies() of the Context's State with the integrator's bodies and minimum moment (bodies and
    masses: integratorBodies() and particleMasses(), to spare finding them at every sample)."""
    x, v, box = _stateArrays(context, velocities=True)
    return kineticEnergies(x, v, particleMasses(context.getSystem()) if masses is None else masses,
                           integratorBodies(integrator) if bodies is None else bodies,
                           integrator.getMinimumMomentOfInertia(), box)


def rigidDegreesOfFreedom(context, integrator, inside=None):
    """3 per free particle less one per constraint between free particles, 3 + (0, 2 or 3) per body (one
    particle, linear, other), less 3 with a CMMotionRemover. With `inside` (a mask of particles): a part's,
    its free particles and the bodies wholly inside, without the CMMotionRemover's 3 (it fixes the whole
    system's momentum, not the part's). An integrator without bodies (a stock one) has every particle free."""
    system = context.getSystem()
    masses = particleMasses(system)
    free = masses > 0 if inside is None else (masses > 0) & inside
    bodies = integratorBodies(integrator) if hasattr(integrator, "getNumBodies") else []
    for body in bodies:
        free[body] = False
    dof = 3 * int(np.count_nonzero(free))
    dof += sum(3 + {"point": 0, "linear": 2}.get(kind, 3) for body, kind in zip(bodies, bodyKinds(context, integrator) if bodies else [])
               if inside is None or inside[body].all())
    for c in range(system.getNumConstraints()):
        i, j, _ = system.getConstraintParameters(c)
        dof -= int(free[i] and free[j])
    if inside is None and any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces()):
        dof -= 3
    return dof

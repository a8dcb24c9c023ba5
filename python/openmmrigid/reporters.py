"""openmmrigid.RigidStateDataReporter: a StateDataReporter with columns for the translational and rotational
kinetic energies and temperatures of rigid bodies, computed from the State, and for the shadow work and heat."""

import numpy as np
import openmm
from openmm import app, unit

from .integrator import RigidBodyIntegratorBase

__all__ = ["RigidStateDataReporter"]

# The extra columns: keyword argument and header.
_COLUMNS = (
    ("translationalKineticEnergy", "Translational Kinetic Energy (kJ/mole)"),
    ("rotationalKineticEnergy", "Rotational Kinetic Energy (kJ/mole)"),
    ("translationalTemperature", "Translational Temperature (K)"),
    ("rotationalTemperature", "Rotational Temperature (K)"),
    ("shadowWork", "Shadow Work (kJ/mole)"),
    ("heat", "Heat (kJ/mole)"),
)
# The columns computed from the State's positions and velocities.
_KINETIC = ("translationalKineticEnergy", "rotationalKineticEnergy", "translationalTemperature",
            "rotationalTemperature")
# The columns that need the integrator to measure them (setMeasureShadowWork(True) switches on both).
_MEASURED = ("shadowWork", "heat")
# The stock columns that come before the extra ones (those after them: volume, density, speed, ...).
_STOCK_COLUMNS_BEFORE = ("_progress", "_step", "_time", "_potentialEnergy", "_kineticEnergy", "_totalEnergy",
                         "_temperature")

_LINEAR_TOLERANCE = 0.002  # nm: the integrator's rule (RigidBodySystem::LinearTolerance), with 1 % of the length
_ZERO_MOMENT = 1e-10       # a principal moment at most this fraction of the largest is zero (a line's axis)


def _whole(positions, box):
    """Each body's particles at the periodic images nearest its first particle.

    positions: (bodies, n, 3) in nm; box: the 3x3 periodic box vectors (rows, OpenMM's reduced form), or None
    for a non-periodic System. Returns the positions with every particle moved by whole box vectors to within
    half a box of the body's first particle (bodies are smaller than half a box), in the same shape.
    """
    if box is None:
        return positions
    delta = positions - positions[:, :1, :]
    for k in (2, 1, 0):  # reduced form: c, then b, then a (each only adds to the components before its own)
        delta -= np.round(delta[..., k]/box[k][k])[..., None]*box[k]
    return positions[:, :1, :] + delta


def _centreOfMassVelocities(masses, velocities):
    """The centre-of-mass velocity of each body (bodies, 3): masses (bodies, n), velocities (bodies, n, 3)."""
    return np.einsum("bi,bij->bj", masses, velocities)/masses.sum(axis=1)[:, None]


def _inertiaTensors(masses, positions):
    """The inertia of each body about its centre of mass.

    masses: (bodies, n) in amu; positions: (bodies, n, 3), whole, in nm. Returns (relative, tensors): the
    positions relative to the centre of mass (bodies, n, 3) and the inertia tensors
    I = sum_i m_i (|r_i|^2 1 - r_i r_i^T) (bodies, 3, 3) in amu nm^2.
    """
    centre = np.einsum("bi,bij->bj", masses, positions)/masses.sum(axis=1)[:, None]
    relative = positions - centre[:, None, :]
    second = np.matmul((masses[..., None]*relative).transpose(0, 2, 1), relative)
    return relative, np.einsum("bii->b", second)[:, None, None]*np.eye(3) - second


def _angularMomenta(masses, relative, velocities, centreVelocity):
    """The angular momentum of each body's particles about its centre of mass (bodies, 3), amu nm^2/ps:
    sum_i m_i r_i x (v_i - V), with relative positions r_i (bodies, n, 3) and velocities (bodies, n, 3)."""
    return np.einsum("bi,bij->bj", masses, np.cross(relative, velocities - centreVelocity[:, None, :]))


def _zeroMoments(moments, linear):
    """Which principal moments (bodies, 3, ascending) are zero: those at most 1e-10 of the body's largest,
    and the least one of a linear body (linear: (bodies,) bool), whose axis carries no rotation."""
    zero = moments <= _ZERO_MOMENT*moments[:, 2:3]
    zero[:, 0] |= linear
    return zero


def _isLinear(relative, moments, axes):
    """Which bodies are linear, by the integrator's rule.

    relative: positions relative to the centre of mass (bodies, n, 3); moments, axes: np.linalg.eigh of the
    inertia tensors. A body is linear when every particle lies within 0.002 nm of the axis of least moment
    (through the centre of mass) and within 1 % of the body's reach along that axis (the largest distance of
    a particle from the centre of mass, measured along it). Returns a bool array (bodies,); bodies whose
    particles all sit at one point (largest moment 0) count as not linear.
    """
    axis = axes[:, :, 0]
    along = np.einsum("bij,bj->bi", relative, axis)
    offAxis = np.linalg.norm(relative - along[..., None]*axis[:, None, :], axis=2).max(axis=1)
    return (offAxis <= _LINEAR_TOLERANCE) & (offAxis <= 0.01*np.abs(along).max(axis=1)) & (moments[:, 2] > 0.0)


def _relativeKineticEnergy(masses, velocities, centreVelocity):
    """sum_b sum_i m_i |v_i - V_b|^2 / 2 (kJ/mol): the particles' kinetic energy relative to their bodies'
    centres of mass, which is the rotational energy of rigid motion in the particles' own moments (what the
    integrator sums for a body whose moments are not raised)."""
    return 0.5*float(np.sum(masses*np.sum((velocities - centreVelocity[:, None, :])**2, axis=2)))


def _raisedRotationalEnergy(tensors, angularMomenta, linear, minimumMoment):
    """The rotational energy (kJ/mol) of bodies moving with raised moments, in their principal frames.

    tensors: inertia tensors (bodies, 3, 3); angularMomenta: the particles' angular momenta about the centres
    of mass (bodies, 3); linear: (bodies,) bool. With the principal moments I_k and axes of np.linalg.eigh,
    L_k the angular momentum along axis k, omega_k = L_k / I_k the angular velocity of the particles' motion
    about a nonzero moment (none about a zero one: _zeroMoments) and I'_k = max(I_k, minimumMoment), it is
    sum_b sum_k L'_k^2 / (2 I'_k) = sum_b sum_k I'_k omega_k^2 / 2, with L'_k = I'_k omega_k the angular
    momentum of the body the integrator moves (whose particles move with omega).
    """
    moments, axes = np.linalg.eigh(tensors)
    bodyMomenta = np.einsum("bjk,bj->bk", axes, angularMomenta)
    zero = _zeroMoments(moments, linear)
    omega = np.where(zero, 0.0, bodyMomenta/np.where(zero, 1.0, moments))
    raised = np.where(zero, 0.0, np.maximum(moments, minimumMoment))
    return 0.5*float(np.sum(raised*omega**2))


def _isotropicRotationalEnergy(tensors, angularMomenta, minimumMoment):
    """The rotational energy (kJ/mol) of bodies that are not linear and whose three moments are all raised to
    minimumMoment (spherical tops of moment I' = minimumMoment): I' |omega|^2 / 2 summed, with omega the
    solution of I omega = L (tensors (bodies, 3, 3), angularMomenta (bodies, 3)). The same as
    _raisedRotationalEnergy for these bodies, without their principal axes."""
    omega = np.linalg.solve(tensors, angularMomenta[..., None])[..., 0]
    return 0.5*minimumMoment*float(np.sum(omega**2))


def _rotationalDegreesOfFreedom(size, linear):
    """The rotational degrees of freedom of bodies of `size` particles: 0 for one particle, else 2 per linear
    body (linear: bool array) and 3 per other."""
    if size == 1:
        return 0
    return int(2*np.count_nonzero(linear) + 3*np.count_nonzero(~linear))


class _BodyGroup:
    """The bodies of one size: index (bodies, n) into the System's particles, their masses, which are
    linear, and how their rotational energy is computed (the moments of a rigid body do not change, so the
    choice made at the first report holds): `plain` (the rows of the bodies with no moment raised:
    _relativeKineticEnergy, as the integrator sums it) and `raised` (those that are not linear with all
    three moments raised: _isotropicRotationalEnergy; the others: _raisedRotationalEnergy)."""

    def __init__(self, index, masses, positions, box, minimumMoment):
        self.index = index
        self.masses = masses[index]
        self.size = index.shape[1]
        bodies = len(index)
        self.linear = np.zeros(bodies, dtype=bool)
        raised = np.zeros(bodies, dtype=bool)
        isotropic = np.zeros(bodies, dtype=bool)
        if self.size > 1:
            relative, tensors = _inertiaTensors(self.masses, _whole(positions[index], box))
            moments, axes = np.linalg.eigh(tensors)
            self.linear = _isLinear(relative, moments, axes)
            nonzero = ~_zeroMoments(moments, self.linear)
            below = nonzero & (moments < minimumMoment)
            raised = below.any(axis=1)
            isotropic = below.all(axis=1) & ~self.linear
        self.plain = np.flatnonzero(~raised)
        # The bodies whose rotation needs their inertia: (rows, particle index, masses, linear, all three
        # moments raised).
        self.raised = [(rows, index[rows], self.masses[rows], self.linear[rows], allRaised)
                       for rows, allRaised in ((np.flatnonzero(isotropic), True),
                                               (np.flatnonzero(raised & ~isotropic), False)) if len(rows)]
        self.rotationalDof = _rotationalDegreesOfFreedom(self.size, self.linear)

    def kineticEnergies(self, positions, velocities, box, minimumMoment):
        """(translational, rotational) kinetic energy in kJ/mol of these bodies: positions (particles, 3) nm,
        velocities (particles, 3) nm/ps, box vectors (nm) or None."""
        v = velocities[self.index]
        centreVelocity = _centreOfMassVelocities(self.masses, v)
        translational = 0.5*float(np.sum(self.masses.sum(axis=1)*np.sum(centreVelocity**2, axis=1)))
        if self.size == 1:
            return translational, 0.0
        rows = self.plain
        rotational = _relativeKineticEnergy(self.masses[rows], v[rows], centreVelocity[rows]) if len(rows) else 0.0
        for rows, index, masses, linear, allRaised in self.raised:
            relative, tensors = _inertiaTensors(masses, _whole(positions[index], box))
            angularMomenta = _angularMomenta(masses, relative, v[rows], centreVelocity[rows])
            if allRaised:
                rotational += _isotropicRotationalEnergy(tensors, angularMomenta, minimumMoment)
            else:
                rotational += _raisedRotationalEnergy(tensors, angularMomenta, linear, minimumMoment)
        return translational, rotational


def _freeKineticEnergy(masses, velocities):
    """sum_i m_i |v_i|^2 / 2 (kJ/mol) of the free particles: masses (n,) amu, velocities (n, 3) nm/ps."""
    return 0.5*float(np.sum(masses*np.sum(velocities**2, axis=1)))


class _Bodies:
    """What the reporter needs of the bodies, read once at the first report: the bodies grouped by size
    (_BodyGroup), the free massive particles and their masses, and the degrees of freedom (translational: 3
    per free massive particle less one per constraint between two free particles, 3 per body, less 3 with a
    CMMotionRemover; rotational: 0, 2 or 3 per body)."""

    def __init__(self, system, integrator, positions, box):
        masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton)
                           for i in range(system.getNumParticles())])
        self.periodic = system.usesPeriodicBoundaryConditions()
        minimum = integrator.getMinimumMomentOfInertia()
        self.minimumMoment = minimum.value_in_unit(unit.dalton*unit.nanometer**2) if unit.is_quantity(minimum) \
            else float(minimum)
        bySize = {}
        numBodies = integrator.getNumBodies()
        for b in range(numBodies):
            body = tuple(integrator.getBodyParticles(b))
            bySize.setdefault(len(body), []).append(body)
        inBody = np.zeros(len(masses), dtype=bool)
        self.groups = []
        for size, members in sorted(bySize.items()):
            index = np.array(members, dtype=np.int64).reshape(len(members), size)
            inBody[index] = True
            self.groups.append(_BodyGroup(index, masses, positions, box if self.periodic else None,
                                          self.minimumMoment))
        self.free = np.flatnonzero(~inBody & (masses > 0.0))
        self.freeMasses = masses[self.free]
        free = np.zeros(len(masses), dtype=bool)
        free[self.free] = True
        freeConstraints = sum(1 for c in range(system.getNumConstraints())
                              if all(free[p] for p in system.getConstraintParameters(c)[:2]))
        cmMotion = any(isinstance(force, openmm.CMMotionRemover) for force in system.getForces())
        self.rotationalDof = sum(group.rotationalDof for group in self.groups)
        self.translationalDof = 3*len(self.free) - freeConstraints + 3*numBodies - (3 if cmMotion else 0)

    def kineticEnergies(self, positions, velocities, box):
        """(translational, rotational) kinetic energy in kJ/mol of positions and velocities (numpy, nm, nm/ps)
        and box vectors (nm)."""
        translational = _freeKineticEnergy(self.freeMasses, velocities[self.free])
        rotational = 0.0
        for group in self.groups:
            groupTranslational, groupRotational = group.kineticEnergies(
                positions, velocities, box if self.periodic else None, self.minimumMoment)
            translational += groupTranslational
            rotational += groupRotational
        return translational, rotational


def _stateArrays(state):
    """The positions (nm), velocities (nm/ps) and box vectors (nm) of a State as numpy arrays."""
    positions = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    box = state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
    return np.asarray(positions), np.asarray(velocities), np.asarray(box)


class RigidStateDataReporter(app.StateDataReporter):
    """A StateDataReporter that can report the kinetic energy and temperature of the rigid bodies'
    translation and rotation apart, and the shadow work and heat of a rigid-body integrator.

    The temperature column (``temperature=True``) is ``openmm.app.StateDataReporter``'s, which takes
    ``integrator.computeSystemTemperature()`` when the integrator has it, as every rigid-body integrator
    does: 2 KE / (dof k_B) with the degrees of freedom as the integrator moves the system (6 per body, 5
    if linear, 3 for a single particle; 3 per free particle less its constraints; less 3 with a
    CMMotionRemover), where the stock count (3 per particle less one per constraint) is wrong for bodies
    given explicitly as lists of particles.

    It takes the arguments of ``openmm.app.StateDataReporter`` (see that class) and six more, all
    False by default, each adding a column after the stock energy and temperature columns (before
    volume, density, speed and times), in this order:

    translationalKineticEnergy : bool
        That of the bodies' centres of mass plus that of the free particles (kJ/mole).
    rotationalKineticEnergy : bool
        That of the bodies' rotation about their centres of mass, in the moments the integrator moves
        them with (kJ/mole): sum_k L_k^2 / (2 I'_k) over each body's principal axes, with
        I'_k = max(I_k, ``getMinimumMomentOfInertia()``) for each nonzero moment I_k and L_k = I'_k omega_k
        the angular momentum of the particles' angular velocity omega about that axis (for a body with no
        moment raised, the particles' kinetic energy relative to its centre of mass).
    translationalTemperature : bool
        2 KE_trans / (dof_trans R) (K), with dof_trans 3 per body and per free particle, less one per
        constraint between free particles, less 3 with a CMMotionRemover (it removes translation).
    rotationalTemperature : bool
        2 KE_rot / (dof_rot R) (K), with dof_rot 0 per single-particle body, 2 per linear body and 3
        per other body. "nan" when there are no rotational degrees of freedom.
    shadowWork : bool
        ``integrator.getShadowWork()``: the energy change of the steps' deterministic stages, summed
        (kJ/mole); the integrator must measure it (``setMeasureShadowWork(True)`` before the steps).
    heat : bool
        ``integrator.getHeat()``: the kinetic energy the steps' stochastic stages (the Langevin
        friction and noise, the Bussi thermostat) added, summed (kJ/mole); measured with the shadow
        work (``setMeasureShadowWork(True)`` before the steps).

    The four kinetic columns are computed here, with numpy over all bodies of a size at once, from the
    positions and velocities of the State the reporter is given (it asks for them when one of these
    columns is on): each body is made whole (the periodic images nearest its first particle), its
    centre-of-mass velocity, its angular momentum about the centre of mass and its principal moments and
    axes give its translational and rotational energy. The bodies (``getNumBodies()``,
    ``getBodyParticles()``), the masses and the degrees of freedom are read at the first report (the
    bodies are fixed once the Context exists); a body is linear when its particles lie within 0.002 nm of
    its axis of least moment and within 1 % of its length, the integrator's rule. The two energies add up
    to the State's kinetic energy, and the two temperatures, weighted by their degrees of freedom, to the
    temperature column. The velocities are those the integrator reports (on-step for
    ``RigidBodyIntegrator`` and ``RigidBodyBussiIntegrator``; see ``RigidBodyLangevinIntegrator`` for
    where its velocities are).

    These six columns need a ``RigidBodyIntegrator``, ``RigidBodyBussiIntegrator`` or
    ``RigidBodyLangevinIntegrator``. With any other integrator, and without them, the reporter behaves
    exactly like ``openmm.app.StateDataReporter``.

    Raises
    ------
    ValueError
        At the first report, if one of the six columns is requested and the Simulation's
        integrator is not a rigid-body integrator, or the shadow work or heat is requested and the
        integrator does not measure them.

    Examples
    --------
    >>> import sys
    >>> simulation.reporters.append(RigidStateDataReporter(sys.stdout, 100, step=True, temperature=True,
    ...                                                    translationalTemperature=True, rotationalTemperature=True))
    """

    def __init__(self, file, reportInterval, translationalKineticEnergy=False, rotationalKineticEnergy=False,
                 translationalTemperature=False, rotationalTemperature=False, shadowWork=False, heat=False, **kwargs):
        super().__init__(file, reportInterval, **kwargs)
        self._rigidColumns = [(keyword, header) for (keyword, header), wanted in zip(
            _COLUMNS, (translationalKineticEnergy, rotationalKineticEnergy, translationalTemperature,
                       rotationalTemperature, shadowWork, heat)) if wanted]
        self._kineticColumns = any(keyword in _KINETIC for keyword, _ in self._rigidColumns)
        if self._kineticColumns:
            self._needsPositions = self._needsVelocities = True
            self._includes = list(self._includes) + ["positions", "velocities"]
        self._bodies = None

    def _initializeConstants(self, simulation):
        super()._initializeConstants(simulation)
        integrator = simulation.context.getIntegrator()
        rigid = isinstance(integrator, RigidBodyIntegratorBase)
        if self._rigidColumns and not rigid:
            raise ValueError(f"RigidStateDataReporter: the columns {', '.join(k for k, _ in self._rigidColumns)} "
                             f"need a RigidBodyIntegrator, RigidBodyBussiIntegrator or RigidBodyLangevinIntegrator; "
                             f"the simulation's integrator is a {type(integrator).__name__}")
        measured = [keyword for keyword, _ in self._rigidColumns if keyword in _MEASURED]
        if measured and not integrator.getMeasureShadowWork():
            raise ValueError(f"RigidStateDataReporter: the column{'s' if len(measured) > 1 else ''} "
                             f"{' and '.join(measured)} need{'' if len(measured) > 1 else 's'} the integrator to "
                             f"measure {'them' if len(measured) > 1 else 'it'}; call "
                             f"integrator.setMeasureShadowWork(True) before the steps")
        # The temperature column needs nothing here: the stock reporter asks computeSystemTemperature().
        if self._kineticColumns:
            state = simulation.context.getState(getPositions=True)
            positions = np.asarray(state.getPositions(asNumpy=True).value_in_unit(unit.nanometer))
            box = np.asarray(state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer))
            self._bodies = _Bodies(simulation.system, integrator, positions, box)

    def _insertionIndex(self):
        return sum(1 for name in _STOCK_COLUMNS_BEFORE if getattr(self, name))

    def _constructHeaders(self):
        headers = super()._constructHeaders()
        at = self._insertionIndex()
        return headers[:at] + [header for _, header in self._rigidColumns] + headers[at:]

    def _constructReportValues(self, simulation, state):
        values = super()._constructReportValues(simulation, state)
        if not self._rigidColumns:
            return values
        integrator = simulation.context.getIntegrator()
        kilojoules = unit.kilojoules_per_mole
        computed = {}
        if self._kineticColumns:
            bodies = self._bodies
            translational, rotational = bodies.kineticEnergies(*_stateArrays(state))
            gasConstant = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(kilojoules/unit.kelvin)

            def temperature(energy, dof):
                return 2*energy/(dof*gasConstant) if dof > 0 else float("nan")

            computed = {"translationalKineticEnergy": translational, "rotationalKineticEnergy": rotational,
                        "translationalTemperature": temperature(translational, bodies.translationalDof),
                        "rotationalTemperature": temperature(rotational, bodies.rotationalDof)}
        if "shadowWork" in dict(self._rigidColumns):
            computed["shadowWork"] = integrator.getShadowWork().value_in_unit(kilojoules)
        if "heat" in dict(self._rigidColumns):
            computed["heat"] = integrator.getHeat().value_in_unit(kilojoules)
        at = self._insertionIndex()
        return values[:at] + [computed[keyword] for keyword, _ in self._rigidColumns] + values[at:]

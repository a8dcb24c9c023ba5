"""openmmrigid.RigidStateDataReporter: a StateDataReporter whose temperature counts rigid bodies right,
with columns for the translational and rotational kinetic energies and temperatures."""

from openmm import app, unit

__all__ = ["RigidStateDataReporter"]

_ROTATIONAL_DOF = {"point": 0, "linear": 2}  # every other kind of body: 3

# The extra columns: keyword argument and header.
_COLUMNS = (
    ("translationalKineticEnergy", "Translational Kinetic Energy (kJ/mole)"),
    ("rotationalKineticEnergy", "Rotational Kinetic Energy (kJ/mole)"),
    ("translationalTemperature", "Translational Temperature (K)"),
    ("rotationalTemperature", "Rotational Temperature (K)"),
    ("shadowWork", "Shadow Work (kJ/mole)"),
    ("heat", "Heat (kJ/mole)"),
)
# The columns that need the integrator to measure them: keyword -> the switch.
_MEASURED = {"shadowWork": "setMeasureShadowWork", "heat": "setMeasureHeat"}
# The stock columns that come before the extra ones (those after them: volume, density, speed, ...).
_STOCK_COLUMNS_BEFORE = ("_progress", "_step", "_time", "_potentialEnergy", "_kineticEnergy", "_totalEnergy",
                         "_temperature")


def _rotationalDegreesOfFreedom(integrator):
    """The rotational degrees of freedom of a bound rigid-body integrator: 0 per point body, 2 per
    linear one and 3 per other body."""
    return sum(_ROTATIONAL_DOF.get(integrator.getBodyKind(b), 3) for b in range(integrator.getNumBodies()))


class RigidStateDataReporter(app.StateDataReporter):
    """A StateDataReporter that takes the number of degrees of freedom from a RigidBodyIntegrator,
    and can report the kinetic energy and temperature of translation and of rotation apart.

    ``openmm.app.StateDataReporter`` counts 3 degrees of freedom per massive particle, less one per
    constraint and 3 for a CMMotionRemover. That is right for bodies held rigid by constraints (a
    rigid water has 9 - 3 = 6) but not for bodies given explicitly as lists of particles, which have
    6 (5 if linear, 3 for a single particle) however many particles they hold. This reporter takes
    the count from ``integrator.getNumDegreesOfFreedom()`` instead, so that the temperature column is
    2 KE / (dof k_B) with KE the kinetic energy in kJ/mol and dof as the integrator moves the system.

    It takes the arguments of ``openmm.app.StateDataReporter`` (see that class) and six more, all
    False by default, each adding a column after the stock energy and temperature columns (before
    volume, density, speed and times), in this order:

    translationalKineticEnergy : bool
        ``integrator.getTranslationalKineticEnergy()``: that of the bodies' centres of mass plus
        that of the free particles (kJ/mole).
    rotationalKineticEnergy : bool
        ``integrator.getRotationalKineticEnergy()``: that of the bodies' rotation about their
        centres of mass (kJ/mole).
    translationalTemperature : bool
        2 KE_trans / (dof_trans R) (K), with dof_trans = ``getNumDegreesOfFreedom()`` - dof_rot:
        3 per body and per free particle, less one per constraint among free particles, less 3
        with a CMMotionRemover (it removes translation).
    rotationalTemperature : bool
        2 KE_rot / (dof_rot R) (K), with dof_rot 0 per single-particle body, 2 per linear body and 3
        per other body (``getBodyKind``). "nan" when there are no rotational degrees of freedom.
    shadowWork : bool
        ``integrator.getShadowWork()``: the energy change of the steps' deterministic stages, summed
        (kJ/mole); the integrator must measure it (``setMeasureShadowWork(True)`` before the steps).
    heat : bool
        ``integrator.getHeat()``: the kinetic energy the steps' stochastic stages added, summed
        (kJ/mole); the integrator must measure it (``setMeasureHeat(True)`` before the steps).

    The two temperatures add up, weighted by their degrees of freedom, to the temperature column.
    These six columns need a ``RigidBodyIntegrator`` or ``RigidBodyLangevinIntegrator``; the
    degrees of freedom are counted at the first report (the bodies are fixed once the Context
    exists). With any other integrator, and without them, the reporter behaves exactly like
    ``openmm.app.StateDataReporter``.

    Raises
    ------
    ValueError
        At the first report, if one of the six columns is requested and the Simulation's
        integrator is not a rigid-body integrator, or the shadow work or heat is requested and the
        integrator does not measure it.

    Notes
    -----
    A RigidBodyIntegrator also has ``computeSystemTemperature()``, which
    ``openmm.app.StateDataReporter`` prefers to its own count when an integrator has it; both
    reporters therefore print the same, correct temperature for it. The velocities behind the
    kinetic energies are those the integrator reports (on-step for ``RigidBodyIntegrator``; see
    ``RigidBodyLangevinIntegrator`` for where its velocities are).

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

    def _initializeConstants(self, simulation):
        super()._initializeConstants(simulation)
        integrator = simulation.context.getIntegrator()
        isRigid = hasattr(integrator, "getRotationalKineticEnergy") and hasattr(integrator, "getBodyKind")
        if self._temperature and hasattr(integrator, "getNumDegreesOfFreedom"):
            self._dof = integrator.getNumDegreesOfFreedom()
        if self._rigidColumns:
            if not isRigid:
                raise ValueError(f"RigidStateDataReporter: the columns {', '.join(k for k, _ in self._rigidColumns)} "
                                 f"need a RigidBodyIntegrator or RigidBodyLangevinIntegrator; the simulation's "
                                 f"integrator is a {type(integrator).__name__}")
            for keyword, _ in self._rigidColumns:
                if keyword in _MEASURED and not getattr(integrator, "getM" + _MEASURED[keyword][4:])():
                    raise ValueError(f"RigidStateDataReporter: the column {keyword} needs the integrator to measure it; "
                                     f"call integrator.{_MEASURED[keyword]}(True) before the steps")
            self._rotationalDof = _rotationalDegreesOfFreedom(integrator)
            self._translationalDof = integrator.getNumDegreesOfFreedom() - self._rotationalDof

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
        translational = integrator.getTranslationalKineticEnergy().value_in_unit(kilojoules)
        rotational = integrator.getRotationalKineticEnergy().value_in_unit(kilojoules)
        gasConstant = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(kilojoules/unit.kelvin)

        def temperature(energy, dof):
            return 2*energy/(dof*gasConstant) if dof > 0 else float("nan")

        computed = {"translationalKineticEnergy": translational, "rotationalKineticEnergy": rotational,
                    "translationalTemperature": temperature(translational, self._translationalDof),
                    "rotationalTemperature": temperature(rotational, self._rotationalDof)}
        if "shadowWork" in dict(self._rigidColumns):
            computed["shadowWork"] = integrator.getShadowWork().value_in_unit(kilojoules)
        if "heat" in dict(self._rigidColumns):
            computed["heat"] = integrator.getHeat().value_in_unit(kilojoules)
        at = self._insertionIndex()
        return values[:at] + [computed[keyword] for keyword, _ in self._rigidColumns] + values[at:]

"""openmmrigid.RigidStateDataReporter: a StateDataReporter whose temperature counts rigid bodies right."""

from openmm import app

__all__ = ["RigidStateDataReporter"]


class RigidStateDataReporter(app.StateDataReporter):
    """A StateDataReporter that takes the number of degrees of freedom from a RigidBodyIntegrator.

    ``openmm.app.StateDataReporter`` counts 3 degrees of freedom per massive particle, less one per
    constraint and 3 for a CMMotionRemover. That is right for bodies held rigid by constraints (a
    rigid water has 9 - 3 = 6) but not for bodies given explicitly as lists of particles, which have
    6 (5 if linear, 3 for a single particle) however many particles they hold. This reporter takes
    the count from ``integrator.getNumDegreesOfFreedom()`` instead, so that the temperature column is
    2 KE / (dof k_B) with KE the kinetic energy in kJ/mol and dof as the integrator moves the system.

    With any other integrator it behaves exactly like ``openmm.app.StateDataReporter``. It takes the
    same arguments (see that class).

    Notes
    -----
    A RigidBodyIntegrator also has ``computeSystemTemperature()``, which
    ``openmm.app.StateDataReporter`` prefers to its own count when an integrator has it; both
    reporters therefore print the same, correct temperature for it. Use this one where the count
    itself matters to code that reads it (``reporter._dof``), or to make the intent explicit.

    Examples
    --------
    >>> import sys
    >>> simulation.reporters.append(RigidStateDataReporter(sys.stdout, 100, step=True, temperature=True))
    """

    def _initializeConstants(self, simulation):
        super()._initializeConstants(simulation)
        if self._temperature:
            integrator = simulation.context.getIntegrator()
            if hasattr(integrator, "getNumDegreesOfFreedom"):
                self._dof = integrator.getNumDegreesOfFreedom()

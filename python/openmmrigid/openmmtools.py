"""MCMC moves of openmmtools that run the rigid-body integrators.

openmmtools (``pip install openmmtools``) drives free-energy and enhanced-sampling calculations
through thermodynamic states, Context caches, MCMC moves and multistate samplers (replica exchange,
parallel tempering, SAMS), across processes with MPI through mpiplus. The integrators of openmmrigid
work there as they are: ``RigidBodyLangevinIntegrator`` and ``RigidBodyBussiIntegrator`` expose
``getTemperature()`` and ``setTemperature()``, so ``ThermodynamicState`` sees their heat bath, adds no
``AndersenThermostat`` and sets their temperature for each state; ``RigidBodyIntegrator`` has no
temperature, so it is treated as the NVE integrator it is. This module adds the
moves, so that no user has to write them:

RigidLangevinDynamicsMove
    Langevin dynamics with ``RigidBodyLangevinIntegrator`` (as openmmtools' ``LangevinDynamicsMove``
    runs ``LangevinMiddleIntegrator``).
RigidBussiDynamicsMove
    Dynamics with ``RigidBodyBussiIntegrator``, the stochastic velocity rescaling thermostat (Bussi,
    Donadio and Parrinello, J. Chem. Phys. 126, 014101 (2007)), any splitting.

Both are ``openmmtools.mcmc.BaseIntegratorMove`` subclasses: they run in a ``ContextCache`` (a Context
is reused across thermodynamic states that differ only in temperature), restart from the state
before the move when a step fails (an unstable step raises ``openmm.OpenMMException``), and
serialize through ``__getstate__``/``__setstate__``, which is how openmmtools stores a sampler's moves
in its NetCDF files and reads them back. The bodies (``None``: the System's rigid constraint clusters,
such as rigid water; or explicit lists of particle indices) are part of the move.

Importing this module needs openmmtools; without it the ImportError says so.
"""

try:
    from openmmtools import mcmc as _mcmc
except ImportError as error:  # pragma: no cover - exercised only where openmmtools is absent
    raise ImportError("openmmrigid.openmmtools needs openmmtools: pip install openmmtools "
                      f"(or pip install 'openmm-rigid[test]'); importing it failed with: {error}") from error

import openmm.unit as unit

from .integrator import RigidBodyBussiIntegrator, RigidBodyIntegrator, RigidBodyLangevinIntegrator

__all__ = ["RigidLangevinDynamicsMove", "RigidBussiDynamicsMove"]

_ROTATION_METHODS = {"Exact": RigidBodyIntegrator.Exact, "NoSquish": RigidBodyIntegrator.NoSquish}
_SPLITTINGS = {"Verlet": RigidBodyIntegrator.Verlet, "Omelyan2": RigidBodyIntegrator.Omelyan2,
               "Yoshida4": RigidBodyIntegrator.Yoshida4, "Omelyan4": RigidBodyIntegrator.Omelyan4}


def _bodies(bodies):
    """bodies as a list of lists of plain ints (storable as YAML), or None; ValueError if it is not one."""
    if bodies is None:
        return None
    try:
        result = [[int(p) for p in body] for body in bodies]
    except TypeError:
        raise ValueError(f"bodies must be None (the System's rigid constraint clusters) or a sequence of sequences of "
                         f"particle indices; got {bodies!r}") from None
    for index, body in enumerate(bodies):
        if any(int(p) != p for p in body):
            raise ValueError(f"body {index} must list particle indices (ints); got {body!r}")
    return result


def _name(value, names, what, cls):
    """The name of an option given by name or by the integrator's constant; ValueError naming the choices otherwise."""
    for name, constant in names.items():
        if value == name or (not isinstance(value, str) and value == constant):
            return name
    raise ValueError(f"{cls}: unknown {what} {value!r}; use one of {', '.join(names)}")


def _positive(value, unitOf, what, cls):
    """value as a Quantity in unitOf's dimension (a plain number is taken in unitOf), checked > 0."""
    if not unit.is_quantity(value):
        value = value * unitOf
    number = value.value_in_unit(unitOf)
    if not number > 0:
        raise ValueError(f"{cls}: the {what} must be positive; got {value}")
    return value


class _RigidDynamicsMove(_mcmc.BaseIntegratorMove):
    """What the two moves share: step size, bodies, rotation method, and their serialization."""

    def __init__(self, timestep, n_steps, bodies, rotation_method, reassign_velocities, n_restart_attempts, **kwargs):
        super().__init__(n_steps=n_steps, reassign_velocities=reassign_velocities,
                         n_restart_attempts=n_restart_attempts, **kwargs)
        name = type(self).__name__
        self.timestep = _positive(timestep, unit.picosecond, "timestep", name)
        self.bodies = _bodies(bodies)
        self.rotation_method = _name(rotation_method, _ROTATION_METHODS, "rotation method", name)

    def _configure(self, integrator):
        integrator.setRotationMethod(_ROTATION_METHODS[self.rotation_method])
        return integrator

    def _bodyArguments(self):
        return () if self.bodies is None else (self.bodies,)

    def __getstate__(self, **kwargs):
        serialization = super().__getstate__()
        serialization.update(timestep=self.timestep, bodies=self.bodies, rotation_method=self.rotation_method)
        return serialization

    def __setstate__(self, serialization):
        super().__setstate__(serialization)
        self.timestep = serialization["timestep"]
        self.bodies = serialization["bodies"]
        self.rotation_method = serialization["rotation_method"]


class RigidLangevinDynamicsMove(_RigidDynamicsMove):
    """Langevin dynamics of rigid bodies (``openmmrigid.RigidBodyLangevinIntegrator``) as an MCMC move.

    The rigid-body counterpart of openmmtools' ``LangevinDynamicsMove``: each application runs
    ``n_steps`` steps of ``RigidBodyLangevinIntegrator`` at the thermodynamic state's temperature (the
    exact free drift of every rigid body, LangevinMiddleIntegrator's arrangement of the Langevin
    steps). Like that move it samples the canonical ensemble up to the integrator's discretisation
    error; the temperature is the state's, set on the Context's integrator by openmmtools.

    Parameters
    ----------
    timestep : openmm.unit.Quantity or float
        The step size (a float is in ps). Default 2 fs.
    collision_rate : openmm.unit.Quantity or float
        The friction coefficient (a float is in 1/ps). Default 1/ps.
    n_steps : int
        The steps per application. Default 1000.
    bodies : list of list of int, optional
        Explicit rigid bodies (particle indices); None (the default) takes the System's rigid
        constraint clusters (rigid water and other rigid molecules).
    rotation_method : str
        "Exact" (the default, the exact free rotor) or "NoSquish".
    reassign_velocities : bool
        Whether to draw new velocities at the state's temperature before each application.
    n_restart_attempts : int
        How many times a failed application (an unstable step) is restarted from the state it began from.

    Raises
    ------
    ValueError
        If the step size or friction is not positive, or the bodies or rotation method are not valid.
    """

    def __init__(self, timestep=2.0 * unit.femtosecond, collision_rate=1.0 / unit.picosecond, n_steps=1000, bodies=None,
                 rotation_method="Exact", reassign_velocities=False, n_restart_attempts=4, **kwargs):
        super().__init__(timestep, n_steps, bodies, rotation_method, reassign_velocities, n_restart_attempts, **kwargs)
        self.collision_rate = _positive(collision_rate, unit.picosecond**-1, "collision rate", type(self).__name__)

    def __getstate__(self, **kwargs):
        serialization = super().__getstate__(**kwargs)
        serialization["collision_rate"] = self.collision_rate
        return serialization

    def __setstate__(self, serialization):
        super().__setstate__(serialization)
        self.collision_rate = serialization["collision_rate"]

    def _get_integrator(self, thermodynamic_state):
        """Implement BaseIntegratorMove._get_integrator(): a RigidBodyLangevinIntegrator at the state's temperature."""
        integrator = RigidBodyLangevinIntegrator(thermodynamic_state.temperature, self.collision_rate, self.timestep,
                                                 *self._bodyArguments())
        return self._configure(integrator)


class RigidBussiDynamicsMove(_RigidDynamicsMove):
    """Dynamics of rigid bodies with ``openmmrigid.RigidBodyBussiIntegrator``, the stochastic velocity
    rescaling thermostat (Bussi, Donadio and Parrinello, J. Chem. Phys. 126, 014101 (2007)) as an MCMC move.

    Each application runs ``n_steps`` steps of the symplectic splitting chosen (exact free drifts),
    each followed by the global rescaling of all momenta that samples the canonical kinetic energy at
    the state's temperature, set on the Context's integrator by openmmtools. Between rescalings the
    dynamics is Hamiltonian, and a rescaling changes every momentum by the same factor.

    Parameters
    ----------
    timestep : openmm.unit.Quantity or float
        The step size (a float is in ps). Default 2 fs.
    collision_time : openmm.unit.Quantity or float
        The thermostat's relaxation time tau (a float is in ps). Default 0.1 ps.
    n_steps : int
        The steps per application. Default 1000.
    bodies : list of list of int, optional
        Explicit rigid bodies (particle indices); None (the default) takes the System's rigid
        constraint clusters.
    splitting : str
        "Verlet" (the default), "Omelyan2", "Yoshida4" or "Omelyan4" (see RigidBodyIntegrator.setSplitting).
    rotation_method : str
        "Exact" (the default) or "NoSquish".
    reassign_velocities : bool
        Whether to draw new velocities at the state's temperature before each application.
    n_restart_attempts : int
        How many times a failed application (an unstable step) is restarted from the state it began from.

    Raises
    ------
    ValueError
        If the step size or collision time is not positive, or the bodies, splitting or rotation method are not valid.
    """

    def __init__(self, timestep=2.0 * unit.femtosecond, collision_time=0.1 * unit.picosecond, n_steps=1000, bodies=None,
                 splitting="Verlet", rotation_method="Exact", reassign_velocities=False, n_restart_attempts=4, **kwargs):
        super().__init__(timestep, n_steps, bodies, rotation_method, reassign_velocities, n_restart_attempts, **kwargs)
        self.collision_time = _positive(collision_time, unit.picosecond, "collision time", type(self).__name__)
        self.splitting = _name(splitting, _SPLITTINGS, "splitting", type(self).__name__)

    def __getstate__(self, **kwargs):
        serialization = super().__getstate__(**kwargs)
        serialization.update(collision_time=self.collision_time, splitting=self.splitting)
        return serialization

    def __setstate__(self, serialization):
        super().__setstate__(serialization)
        self.collision_time = serialization["collision_time"]
        self.splitting = serialization["splitting"]

    def _get_integrator(self, thermodynamic_state):
        """Implement BaseIntegratorMove._get_integrator(): a RigidBodyBussiIntegrator at the state's temperature."""
        integrator = RigidBodyBussiIntegrator(thermodynamic_state.temperature, self.collision_time, self.timestep,
                                              *self._bodyArguments())
        integrator.setSplitting(_SPLITTINGS[self.splitting])
        return self._configure(integrator)

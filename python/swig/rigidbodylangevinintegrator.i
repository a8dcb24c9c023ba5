// OpenMMRigid::RigidBodyLangevinIntegrator as a subclass of openmm.Integrator (through
// RigidBodyIntegratorBase, wrapped in rigidbodyintegrator.i with the typemaps both classes use).
// Units follow OpenMM's LangevinMiddleIntegrator: the temperature, friction and step size may be
// openmm.unit Quantities (converted to K, 1/ps and ps; a Quantity of another dimension is an error);
// getTemperature and getFriction return Quantities.

// ---- units ----

%pythonprepend OpenMMRigid::RigidBodyLangevinIntegrator::RigidBodyLangevinIntegrator %{
    args = list(args)
    for _index, _unitOfArgument in enumerate((_unit.kelvin, _unit.picosecond**-1, _unit.picosecond)):
        if len(args) > _index and _unit.is_quantity(args[_index]):
            args[_index] = args[_index].value_in_unit(_unitOfArgument)
%}
%pythonprepend OpenMMRigid::RigidBodyLangevinIntegrator::setTemperature %{
    if _unit.is_quantity(temp):
        temp = temp.value_in_unit(_unit.kelvin)
%}
%pythonprepend OpenMMRigid::RigidBodyLangevinIntegrator::setFriction %{
    if _unit.is_quantity(coeff):
        coeff = coeff.value_in_unit(_unit.picosecond**-1)
%}
%pythonappend OpenMMRigid::RigidBodyLangevinIntegrator::getTemperature %{
    val = _unit.Quantity(val, _unit.kelvin)
%}
%pythonappend OpenMMRigid::RigidBodyLangevinIntegrator::getFriction %{
    val = _unit.Quantity(val, _unit.picosecond**-1)
%}

// ---- docstrings (numpy style; the C++ header has the Doxygen originals) ----

%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator "
A Langevin integrator for systems of rigid molecules (constant temperature).

Each step is arranged as in ``openmm.LangevinMiddleIntegrator`` (LFMiddle, the leapfrog form of
BAOAB: Leimkuhler and Matthews, Appl. Math. Res. Express 2013, 34 (2013); Zhang et al., J. Phys.
Chem. A 123, 6056 (2019)): a kick by the forces and torques, a free drift for half a step (the
exact free rotor of van Zon and Schofield, or NO_SQUISH), the exact Ornstein-Uhlenbeck step of the
momenta for a whole step, another half drift, and the force evaluation at the new positions; one
force evaluation per step. The positions are BAOAB's. With c = exp(-friction dt) the Ornstein-Uhlenbeck step sets each body's
centre-of-mass momentum P <- c P + sqrt((1 - c^2) M kT) xi and its angular momentum in the
principal frame L_k <- c L_k + sqrt((1 - c^2) I_k kT) xi_k (axes with I_k > 0): the rigid-body
Langevin thermostat of Davidchack, Ouldridge and Tretyakov, J. Chem. Phys. 142, 144114 (2015), with
every momentum relaxing at the one rate ``friction``. Free particles get the same step on their
velocities, then their velocity constraints.

Bodies, rotation methods and every query (``getNumBodies``, ``getBodyKind``,
``getNumDegreesOfFreedom``, ``computeSystemTemperature``, ``getTranslationalKineticEnergy``, ...)
are those of ``RigidBodyIntegrator``. Velocities are those of ``LangevinMiddleIntegrator``: half a
step behind the positions (``getVelocityTimeOffset()`` is dt/2), after the Ornstein-Uhlenbeck step,
where their distribution is canonical, so that the kinetic energy and the temperature
(``StateDataReporter``'s column) read the bath's: 300.5 +- 0.6 K for rigid water at 4 fs, where
BAOAB's on-step velocities read the rotational temperature 4 % low. Velocities one sets are taken as
such half-step velocities; ``setVelocitiesToTemperature`` shifts them by half a kick.

Parameters
----------
temperature : float or openmm.unit.Quantity
    The temperature of the heat bath, in K if a plain number.
frictionCoeff : float or openmm.unit.Quantity
    The friction coefficient, in 1/ps if a plain number.
stepSize : float or openmm.unit.Quantity
    The step size, in ps if a plain number.
bodies : sequence of sequences of int, optional
    The particle indices of each body. Without this argument the bodies are the System's rigid
    constraint clusters (rigid water etc.).

Raises
------
openmm.OpenMMException
    If the temperature or friction is negative or not finite, or bodies is not a sequence of
    sequences of particle indices.

Examples
--------
>>> from openmm import unit
>>> integrator = RigidBodyLangevinIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtoseconds)
>>> integrator.setRandomNumberSeed(42)
";
%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator::getTemperature "
Get the temperature of the heat bath.

Returns
-------
openmm.unit.Quantity
    The temperature, in K.
";
%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator::setTemperature "
Set the temperature of the heat bath. It may be changed between steps.

Parameters
----------
temp : float or openmm.unit.Quantity
    The temperature, in K if a plain number.

Raises
------
openmm.OpenMMException
    If the value is negative or not finite (the setting is then unchanged).
";
%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator::getFriction "
Get the friction coefficient which couples the system to the heat bath.

Returns
-------
openmm.unit.Quantity
    The friction, in 1/ps.
";
%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator::setFriction "
Set the friction coefficient which couples the system to the heat bath. It may be changed between
steps; 0 makes the step the constant-energy kick, half drift, half drift, kick.

Parameters
----------
coeff : float or openmm.unit.Quantity
    The friction, in 1/ps if a plain number.

Raises
------
openmm.OpenMMException
    If the value is negative or not finite (the setting is then unchanged).
";
%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator::getRandomNumberSeed "
Get the random number seed (0: a new one is chosen for every Context).

Returns
-------
int
";
%feature("docstring") OpenMMRigid::RigidBodyLangevinIntegrator::setRandomNumberSeed "
Set the random number seed, read when a Context is created.

With the same seed, the Reference and CPU platforms give the same trajectory, with any number of
threads; different seeds give different ones. 0 (the default) picks a new seed for every Context.

Parameters
----------
seed : int
";

// ---- the class ----

%include "RigidBodyLangevinIntegrator.h"

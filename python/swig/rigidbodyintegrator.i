// OpenMMRigid::RigidBodyIntegrator (and, in rigidbodylangevinintegrator.i, RigidBodyLangevinIntegrator)
// as subclasses of openmm.Integrator, through their common base RigidBodyIntegratorBase, which holds
// the bodies, the rotation method and the questions one asks about them.
//
// OpenMM's own classes come from the openmm wheel's swig/OpenMMSwigHeaders.i, imported (not
// included): the proxy class derives from openmm.Integrator, and SWIG's shared type table (runtime
// version 5 in both modules) lets openmm.Context, XmlSerializer and the inherited methods
// (getStepSize, setConstraintTolerance, setIntegrationForceGroups, ...) accept the object.
// Units follow OpenMM's wrappers: a step size may be an openmm.unit Quantity; energies come back in
// kJ/mol, moments in amu nm^2.

// The wheel's header, written for openmm's own module, draws warnings that do not concern the classes
// used here: nested classes (325), a member named None (314), OUTPUT typemaps it %applys from a
// typemap file the wheel does not ship (453).
#pragma SWIG nowarn=314,325,453
%import(module="openmm") "swig/OpenMMSwigHeaders.i"
%include "std_string.i"

%{
// SWIG writes the up-casts of every class in the imported hierarchy (all of openmm's Integrators and
// Forces), so the wrapper needs their declarations, as openmm's own wrapper does.
#include "OpenMM.h"
#include "OpenMMAmoeba.h"
#include "OpenMMDrude.h"
#include "openmm/PythonForce.h"
#include "openmm/RPMDIntegrator.h"
#include "openmm/RPMDMonteCarloBarostat.h"
#include "RigidBodyIntegrator.h"
#include "RigidBodyLangevinIntegrator.h"
#include "openmm/serialization/XmlSerializer.h"
#include <climits>
#include <sstream>
#include <vector>

namespace {

/** repr(object) as a std::string, for error messages; never fails. */
std::string pythonRepr(PyObject* object) {
    std::string text = "?";
    PyObject* repr = PyObject_Repr(object);
    if (repr != NULL) {
        const char* utf8 = PyUnicode_AsUTF8(repr);
        if (utf8 != NULL)
            text = utf8;
        Py_DECREF(repr);
    }
    PyErr_Clear();
    return text;
}

/**
 * Convert any iterable of iterables of integers (lists, tuples, numpy arrays of any integer dtype)
 * to the bodies of RigidBodyIntegrator. On failure raise openmm.OpenMMException naming the body and
 * entry and return false. Ranges are the C++ constructor's to check.
 */
bool bodiesFromPython(PyObject* input, std::vector<std::vector<int> >& bodies) {
    if (PyUnicode_Check(input) || PyBytes_Check(input)) {
        raiseOpenMMException("RigidBodyIntegrator: bodies must be a sequence of sequences of particle indices; got " +
                             pythonRepr(input));
        return false;
    }
    PyObject* outer = PySequence_Fast(input, "");
    if (outer == NULL) {
        PyErr_Clear();
        raiseOpenMMException("RigidBodyIntegrator: bodies must be a sequence of sequences of particle indices; got " +
                             pythonRepr(input));
        return false;
    }
    bool ok = true;
    Py_ssize_t numBodies = PySequence_Fast_GET_SIZE(outer);
    bodies.assign(numBodies, std::vector<int>());
    for (Py_ssize_t i = 0; ok && i < numBodies; i++) {
        PyObject* body = PySequence_Fast_GET_ITEM(outer, i);
        PyObject* inner = (PyUnicode_Check(body) || PyBytes_Check(body)) ? NULL : PySequence_Fast(body, "");
        if (inner == NULL) {
            PyErr_Clear();
            raiseOpenMMException("RigidBodyIntegrator: body " + std::to_string(i) +
                                 " must be a sequence of particle indices; got " + pythonRepr(body));
            ok = false;
            break;
        }
        Py_ssize_t size = PySequence_Fast_GET_SIZE(inner);
        for (Py_ssize_t j = 0; j < size; j++) {
            PyObject* entry = PySequence_Fast_GET_ITEM(inner, j);
            // __index__ accepts Python and numpy integers and rejects floats (1.0 is not an index).
            PyObject* index = PyNumber_Index(entry);
            long value = index == NULL ? -1 : PyLong_AsLong(index);
            Py_XDECREF(index);
            if (index == NULL || PyErr_Occurred() || value < INT_MIN || value > INT_MAX) {
                PyErr_Clear();
                raiseOpenMMException("RigidBodyIntegrator: entry " + std::to_string(j) + " of body " + std::to_string(i) +
                                     " is not a particle index (an int); got " + pythonRepr(entry));
                ok = false;
                break;
            }
            bodies[i].push_back(static_cast<int>(value));
        }
        Py_DECREF(inner);
    }
    Py_DECREF(outer);
    return ok;
}

PyObject* intListToPython(const std::vector<int>& values) {
    PyObject* list = PyList_New(values.size());
    for (std::size_t i = 0; list != NULL && i < values.size(); i++)
        PyList_SET_ITEM(list, i, PyLong_FromLong(values[i]));
    return list;
}

} // namespace

namespace OpenMMRigid {
namespace Python {

/**
 * Deserialize XML written by XmlSerializer for a RigidBodyIntegrator or RigidBodyLangevinIntegrator;
 * the caller owns the result (openmmrigid/integrator.py gives it its most derived class).
 */
RigidBodyIntegratorBase* deserializeRigidIntegrator(const std::string& xml) {
    std::istringstream stream(xml);
    OpenMM::Integrator* integrator = OpenMM::XmlSerializer::deserialize<OpenMM::Integrator>(stream);
    RigidBodyIntegratorBase* rigid = dynamic_cast<RigidBodyIntegratorBase*>(integrator);
    if (rigid == NULL) {
        delete integrator;
        throw OpenMM::OpenMMException("deserializeIntegrator: the XML does not describe a RigidBodyIntegrator or "
                                      "a RigidBodyLangevinIntegrator");
    }
    return rigid;
}

/** A copy of integrator with every setting, not bound to any Context; the caller owns it. */
RigidBodyIntegratorBase* cloneRigidIntegrator(const RigidBodyIntegratorBase& integrator) {
    return dynamic_cast<RigidBodyIntegratorBase*>(OpenMM::XmlSerializer::clone<OpenMM::Integrator>(integrator));
}

/** integrator as a RigidBodyIntegrator (not a copy), or NULL if it is another kind of Integrator. */
RigidBodyIntegrator* asRigidBodyIntegrator(OpenMM::Integrator* integrator) {
    return dynamic_cast<RigidBodyIntegrator*>(integrator);
}

/** integrator as a RigidBodyLangevinIntegrator (not a copy), or NULL if it is another kind of Integrator. */
RigidBodyLangevinIntegrator* asRigidBodyLangevinIntegrator(OpenMM::Integrator* integrator) {
    return dynamic_cast<RigidBodyLangevinIntegrator*>(integrator);
}

} // namespace Python
} // namespace OpenMMRigid
%}

// ---- typemaps ----

%typemap(typecheck, precedence=SWIG_TYPECHECK_POINTER) const std::vector<std::vector<int> >& bodies {
    // Only one constructor of each class takes bodies (the last argument): let anything through, so
    // that the in typemap reports what is wrong with it (as openmm.OpenMMException) rather than the
    // overload dispatcher.
    $1 = 1;
}
%typemap(in) const std::vector<std::vector<int> >& bodies (std::vector<std::vector<int> > converted) {
    if (!bodiesFromPython($input, converted))
        SWIG_fail;
    $1 = &converted;
}
%typemap(out) std::vector<int> {
    $result = intListToPython($1);
    if ($result == NULL)
        SWIG_fail;
}
%typemap(out) const std::vector<std::vector<int> >& {
    $result = PyList_New($1->size());
    for (std::size_t i = 0; $result != NULL && i < $1->size(); i++) {
        PyObject* body = intListToPython((*$1)[i]);
        if (body == NULL) {
            Py_CLEAR($result);
            break;
        }
        PyList_SET_ITEM($result, i, body);
    }
    if ($result == NULL)
        SWIG_fail;
}
%typemap(out) std::vector<double> {
    $result = PyList_New($1.size());
    for (std::size_t i = 0; $result != NULL && i < $1.size(); i++)
        PyList_SET_ITEM($result, i, PyFloat_FromDouble(($1)[i]));
    if ($result == NULL)
        SWIG_fail;
}
// getRotationMethod and getSplitting return their enums as plain ints, equal to the class constants
// (RigidBodyIntegrator.Exact, .NoSquish; .Verlet, .Omelyan2, .Yoshida4, .Omelyan4).

// ---- units, as OpenMM's own wrappers handle them ----

%pythonbegin %{
from openmm import unit as _unit
import openmm as _openmm_package
%}

%pythonprepend OpenMMRigid::RigidBodyIntegrator::RigidBodyIntegrator %{
    args = list(args)
    if len(args) > 0 and _unit.is_quantity(args[0]):
        args[0] = args[0].value_in_unit(_unit.picosecond)
%}
%pythonprepend OpenMMRigid::RigidBodyIntegrator::setThermostat %{
    if _unit.is_quantity(temperature):
        temperature = temperature.value_in_unit(_unit.kelvin)
    if _unit.is_quantity(collisionTime):
        collisionTime = collisionTime.value_in_unit(_unit.picosecond)
%}
%pythonappend OpenMMRigid::RigidBodyIntegrator::getThermostatTemperature %{
    val = _unit.Quantity(val, _unit.kelvin)
%}
%pythonappend OpenMMRigid::RigidBodyIntegrator::getThermostatCollisionTime %{
    val = _unit.Quantity(val, _unit.picosecond)
%}
%pythonappend OpenMMRigid::RigidBodyIntegrator::getThermostatWork %{
    val = _unit.Quantity(val, _unit.kilojoule_per_mole)
%}
%pythonappend OpenMMRigid::RigidBodyIntegratorBase::getTranslationalKineticEnergy %{
    val = _unit.Quantity(val, _unit.kilojoule_per_mole)
%}
%pythonappend OpenMMRigid::RigidBodyIntegratorBase::getRotationalKineticEnergy %{
    val = _unit.Quantity(val, _unit.kilojoule_per_mole)
%}
%pythonappend OpenMMRigid::RigidBodyIntegratorBase::computeSystemTemperature %{
    val = _unit.Quantity(val, _unit.kelvin)
%}
%pythonappend OpenMMRigid::RigidBodyIntegratorBase::getBodyMoments %{
    val = _unit.Quantity(val, _unit.amu*_unit.nanometer**2)
%}

// ---- docstrings (numpy style; the C++ header has the Doxygen originals) ----

%feature("docstring") OpenMMRigid::RigidBodyIntegrator "
An Integrator for systems of rigid molecules.

Each rigid body moves by a symplectic, time-reversible splitting: a half kick of its linear and
angular momentum by the forces and torques, a free drift of its centre and orientation, and another
half kick. With the default rotation method (``RigidBodyIntegrator.Exact``) the drift is the exact
torque-free motion of the body (R. van Zon and J. Schofield, J. Comput. Phys. 225, 145 (2007);
J. Chem. Phys. 128, 154119 (2008)); ``RigidBodyIntegrator.NoSquish`` takes the symplectic splitting
of T. F. Miller et al., J. Chem. Phys. 116, 8649 (2002) instead. Particles in no body move by
velocity Verlet, with the constraints among them applied to positions and velocities.

That kick-drift-kick step is the default splitting, ``RigidBodyIntegrator.Verlet``;
``setSplitting()`` chooses a longer sequence of kicks and exact drifts, with one force evaluation
after each drift: ``Omelyan2`` (the optimized second-order scheme of I. P. Omelyan, I. M. Mryglod
and R. Folk, Phys. Rev. E 65, 056706 (2002); two force evaluations per step), ``Yoshida4``
(Yoshida's fourth-order triple jump, Phys. Lett. A 150, 262 (1990); three) or ``Omelyan4`` (the
optimized fourth-order Forest-Ruth-like scheme of Omelyan, Mryglod and Folk, Comput. Phys. Commun.
146, 188 (2002); four).

Without more the integrator conserves the energy; ``setThermostat(temperature, collisionTime)``
adds the stochastic velocity rescaling of Bussi, Donadio and Parrinello (2007) after every step for
constant temperature (``RigidBodyLangevinIntegrator`` is the Langevin alternative).

The bodies are either found in the System when the Context is created (every cluster of three or
more particles that its constraints hold rigid, such as rigid water), or given explicitly as lists
of particle indices. An explicit body takes the shape it has when the Context's positions are
first set, and is one molecule to OpenMM (barostats and periodic wrapping keep it whole). Velocities
are on-step; each step writes v = V + omega x (r - R) back to every body particle. Positions or
velocities set from outside are projected onto rigid-body motion at once; whatever moves the
particles without notice (a barostat, the minimizer, another integrator of a CompoundIntegrator) is
detected and the bodies are fitted again at the next step, and cached forces are reused only while
they are current. Bodies split by the periodic boundary are assembled whole. A step that would move
a body further than the nonbonded cutoff or half the box raises OpenMMException.

Parameters
----------
stepSize : float or openmm.unit.Quantity
    The step size, in ps if a plain number.
bodies : sequence of sequences of int, optional
    The particle indices of each body (lists, tuples or integer numpy arrays). A body may be any
    set of massive particles. Particles in no body move freely. Without this argument the bodies
    are the System's rigid constraint clusters.

Raises
------
openmm.OpenMMException
    If bodies is not a sequence of sequences of integer particle indices, or holds a bad index.

Notes
-----
Temperature: ``getNumDegreesOfFreedom()`` counts 3 translational and 0, 2 or 3 rotational degrees
of freedom per body. ``openmm.app.StateDataReporter`` uses ``computeSystemTemperature()`` when an
integrator has it, as this one does, so its temperature column is right for explicit bodies too;
``openmmrigid.RigidStateDataReporter`` takes its degrees of freedom from the integrator as well.

Examples
--------
>>> from openmm import unit
>>> integrator = RigidBodyIntegrator(2*unit.femtoseconds)                   # rigid waters etc.
>>> integrator = RigidBodyIntegrator(0.002, [[0, 1, 2], [3, 4, 5, 6]])      # explicit bodies
>>> integrator.setRotationMethod(RigidBodyIntegrator.NoSquish)
>>> integrator.setSplitting(RigidBodyIntegrator.Omelyan2)                    # two forces per step
>>> integrator.setThermostat(300*unit.kelvin, 0.1*unit.picosecond)          # constant temperature
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getRotationMethod "
Get the method used to advance the orientation of each body.

Returns
-------
int
    ``RigidBodyIntegrator.Exact`` (the default) or ``RigidBodyIntegrator.NoSquish``.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::setRotationMethod "
Set the method used to advance the orientation of each body.

Parameters
----------
method : int
    ``RigidBodyIntegrator.Exact`` (the exact free rotation of van Zon and Schofield) or
    ``RigidBodyIntegrator.NoSquish`` (the NO_SQUISH splitting of Miller et al.).

Raises
------
openmm.OpenMMException
    If method is not one of these values.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::getSplitting "
Get the splitting: the sequence of kicks and free drifts that makes one step.

Returns
-------
int
    ``RigidBodyIntegrator.Verlet`` (the default), ``.Omelyan2``, ``.Yoshida4`` or ``.Omelyan4``.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::setSplitting "
Set the splitting: the sequence of kicks and free drifts that makes one step.

Each splitting starts with a kick that reuses the forces from the end of the previous step and
evaluates the forces once after each of its drifts; bodies and free particles (with their
constraints) follow the same sequence.

Parameters
----------
splitting : int
    ``RigidBodyIntegrator.Verlet``: kick dt/2, drift dt, kick dt/2 (second order, one force
    evaluation per step). ``RigidBodyIntegrator.Omelyan2``: kick lambda dt, drift dt/2, kick
    (1 - 2 lambda) dt, drift dt/2, kick lambda dt with lambda = 0.1931833275037836 (Omelyan, Mryglod
    and Folk, Phys. Rev. E 65, 056706 (2002); second order, two). ``RigidBodyIntegrator.Yoshida4``:
    Verlet steps of w1 dt, w0 dt, w1 dt with w1 = 1/(2 - 2^(1/3)), w0 = 1 - 2 w1 (Yoshida, Phys.
    Lett. A 150, 262 (1990); fourth order, three). ``RigidBodyIntegrator.Omelyan4``: the velocity
    form of the optimized Forest-Ruth-like scheme of Omelyan, Mryglod and Folk, Comput. Phys.
    Commun. 146, 188 (2002) (four; fourth order with exact drifts, second order with ``NoSquish``
    or for free particles held by constraints, where Yoshida4 stays fourth order).

Raises
------
openmm.OpenMMException
    If splitting is not one of these values.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::setThermostat "
Add a thermostat: global stochastic velocity rescaling after every step.

After every step all momenta (the bodies' linear and angular ones and the free particles') are
scaled by one common factor, which samples the kinetic energy from the exact solution over one step
of the stochastic velocity rescaling of G. Bussi, D. Donadio and M. Parrinello, J. Chem. Phys. 126,
014101 (2007), eq. (A7), with the degrees of freedom of ``getNumDegreesOfFreedom()``. The system
then samples the canonical ensemble; the total energy minus ``getThermostatWork()`` (Bussi's
effective energy) is conserved as the total energy is without a thermostat. Replaces any thermostat
set before; takes effect at the next step.

The velocities it rescales, and reports, are on-step: the temperature of their total kinetic energy
(``computeSystemTemperature()``, ``StateDataReporter``'s column) reads the bath's at any step size, by
construction. How that energy divides between translation and rotation is the dynamics': for rigid
water at 6 to 8 fs the on-step rotation reads about 13 K cold and the translation as much warm.

Parameters
----------
temperature : float or openmm.unit.Quantity
    The temperature of the heat bath, in K if a plain number (0 damps the motion).
collisionTime : float or openmm.unit.Quantity
    tau, the relaxation time of the kinetic energy, in ps if a plain number.

Raises
------
openmm.OpenMMException
    If the temperature is negative or not finite, or the collision time is not positive and finite.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::removeThermostat "
Remove the thermostat: the integrator conserves the energy again (the default).
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::hasThermostat "
Get whether a thermostat is set.

Returns
-------
bool
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::getThermostatTemperature "
Get the temperature of the thermostat (0 K if none was ever set).

Returns
-------
openmm.unit.Quantity
    The temperature, in K.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::getThermostatCollisionTime "
Get the collision time tau of the thermostat (0 ps if none was ever set).

Returns
-------
openmm.unit.Quantity
    The collision time, in ps.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::getThermostatWork "
Get the kinetic energy the thermostat has added since the Context was created (negative where it
removed energy). The total energy minus this is Bussi's effective energy, conserved up to the
integration error. Saved in checkpoints. Only available once the integrator is bound to a Context.

Returns
-------
openmm.unit.Quantity
    The energy, in kJ/mol.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::setRandomNumberSeed "
Set the random number seed of the thermostat, read when a Context is created.

With the same seed, the Reference and CPU platforms give the same trajectory, with any number of
threads; different seeds give different ones. 0 (the default) picks a new seed for every Context.

Parameters
----------
seed : int
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::getRandomNumberSeed "
Get the random number seed of the thermostat (0: a new one is chosen for every Context).

Returns
-------
int
";
%feature("docstring") OpenMMRigid::RigidBodyIntegrator::getNumForceEvaluations "
Get the number of force evaluations per step that the splitting takes: 1 (Verlet), 2 (Omelyan2),
3 (Yoshida4) or 4 (Omelyan4).

Returns
-------
int
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::hasExplicitBodies "
Get whether the bodies were given explicitly rather than found from the System's constraints.

Returns
-------
bool
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getExplicitBodies "
Get the explicit bodies passed to the constructor.

Returns
-------
list of list of int
    The particle indices of each body; empty when the bodies are found from the System.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getNumBodies "
Get the number of rigid bodies. Only available once the integrator is bound to a Context.

Returns
-------
int
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getBodyParticles "
Get the particle indices of a rigid body. Only available once the integrator is bound to a Context.

Parameters
----------
index : int
    The index of the body, from 0 to ``getNumBodies() - 1``.

Returns
-------
list of int
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getBodyKind "
Get the kind of a rigid body. Only available once the integrator is bound to a Context (for an
explicit body, once positions have been set).

Parameters
----------
index : int
    The index of the body, from 0 to ``getNumBodies() - 1``.

Returns
-------
str
    \"point\" (one particle: translation only), \"linear\" (two rotational degrees of freedom),
    \"spherical\", \"symmetric\" or \"asymmetric\" (by its principal moments).
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getBodyMoments "
Get the principal moments of inertia of a rigid body, in ascending order.

Parameters
----------
index : int
    The index of the body, from 0 to ``getNumBodies() - 1``.

Returns
-------
openmm.unit.Quantity
    A list of three moments, in amu nm^2.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getTranslationalKineticEnergy "
Get the kinetic energy of the translation of the bodies' centres of mass plus that of the free
particles. Only available once the integrator is bound to a Context.

Returns
-------
openmm.unit.Quantity
    The energy, in kJ/mol.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getRotationalKineticEnergy "
Get the kinetic energy of the rotation of the bodies about their centres of mass. Only available
once the integrator is bound to a Context.

Returns
-------
openmm.unit.Quantity
    The energy, in kJ/mol.
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::getNumDegreesOfFreedom "
Get the number of degrees of freedom of the system as this integrator moves it. Only available
once the integrator is bound to a Context.

3 per free particle, less one per constraint among free particles, plus 3 translational and 0
(point), 2 (linear) or 3 rotational ones per body, less 3 if the System has a CMMotionRemover. The
temperature is 2 KE / (dof k_B).

Returns
-------
int
";
%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase::step "
Advance a simulation through time by taking a series of time steps.

Parameters
----------
steps : int
    The number of time steps to take.
";

// ---- the classes ----

%feature("docstring") OpenMMRigid::RigidBodyIntegratorBase "
The base of RigidBodyIntegrator and RigidBodyLangevinIntegrator: the bodies, the rotation method of
their free drift, and the questions one may ask about them (kinds, moments, kinetic energies,
degrees of freedom, temperature). It cannot be created on its own.
";

#define OPENMM_EXPORT_RIGID
// The helpers behind pickle, copy and XmlSerializer (openmmrigid/integrator.py); private names.
%rename(_deserializeRigidIntegrator) OpenMMRigid::Python::deserializeRigidIntegrator;
%rename(_cloneRigidIntegrator) OpenMMRigid::Python::cloneRigidIntegrator;
%rename(_asRigidBodyIntegrator) OpenMMRigid::Python::asRigidBodyIntegrator;
%rename(_asRigidBodyLangevinIntegrator) OpenMMRigid::Python::asRigidBodyLangevinIntegrator;
%newobject OpenMMRigid::Python::deserializeRigidIntegrator;
%newobject OpenMMRigid::Python::cloneRigidIntegrator;
// The options are the integrators' class constants (RigidBodyIntegrator.Exact, ...), not a class of their own.
%ignore OpenMMRigid::RigidBodyOptions;
%include "RigidBodyOptions.h"
%include "RigidBodyIntegratorBase.h"
%include "RigidBodyIntegrator.h"

%extend OpenMMRigid::RigidBodyIntegratorBase {
%pythoncode %{
    def __getstate__(self):
        return _openmm_package.XmlSerializer.serialize(self)

    def __setstate__(self, serializationString):
        from openmmrigid.integrator import _mostDerived
        integrator = _mostDerived(_deserializeRigidIntegrator(serializationString))
        if not isinstance(integrator, type(self)):
            raise _openmm_package.OpenMMException(
                f"{type(self).__name__}: the serialized integrator is a {type(integrator).__name__}")
        self.this = integrator.this

    def __copy__(self):
        from openmmrigid.integrator import _mostDerived
        duplicate = _mostDerived(_cloneRigidIntegrator(self))
        duplicate.__class__ = self.__class__
        attributes = {key: value for key, value in self.__dict__.items() if key != 'this'}
        from copy import deepcopy
        duplicate.__dict__.update(deepcopy(attributes))
        return duplicate

    def __deepcopy__(self, memo):
        return self.__copy__()
%}
}

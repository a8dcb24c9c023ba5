// OpenMMRigid::RigidBodyIntegrator (and, in rigidbodylangevinintegrator.i, RigidBodyLangevinIntegrator)
// as subclasses of openmm.Integrator, through their common base RigidBodyIntegratorBase, which holds
// the bodies, the rotation method and the questions one asks about them.
//
// OpenMM's own classes come from the openmm wheel's swig/OpenMMSwigHeaders.i, imported (not
// included): the proxy class derives from openmm.Integrator, and SWIG's shared type table (runtime
// version 5 in both modules) lets openmm.Context, XmlSerializer and the inherited methods
// (getStepSize, setConstraintTolerance, setIntegrationForceGroups, ...) accept the object.
// Units follow OpenMM's wrappers (a step size may be an openmm.unit Quantity; energies come back in
// kJ/mol, moments in amu nm^2): openmmrigid/_pythonapi.py adds the conversions and their notes.

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
#include "RigidBodyBussiIntegrator.h"
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

/**
 * Convert an iterable of (force group, substeps) pairs of integers to setForceGroupSubsteps()'s list.
 * On failure raise openmm.OpenMMException naming the entry and return false. Ranges are the C++ setter's to check.
 */
bool groupSubstepsFromPython(PyObject* input, std::vector<std::pair<int, int> >& substeps) {
    const std::string usage = "setForceGroupSubsteps: give a list of (force group, substeps) pairs of ints, such as [(0, 1), (1, 4)]";
    PyObject* outer = (PyUnicode_Check(input) || PyBytes_Check(input)) ? NULL : PySequence_Fast(input, "");
    if (outer == NULL) {
        PyErr_Clear();
        raiseOpenMMException(usage + "; got " + pythonRepr(input));
        return false;
    }
    bool ok = true;
    substeps.clear();
    for (Py_ssize_t i = 0; ok && i < PySequence_Fast_GET_SIZE(outer); i++) {
        PyObject* entry = PySequence_Fast_GET_ITEM(outer, i);
        PyObject* pair = (PyUnicode_Check(entry) || PyBytes_Check(entry)) ? NULL : PySequence_Fast(entry, "");
        long values[2] = {0, 0};
        ok = (pair != NULL && PySequence_Fast_GET_SIZE(pair) == 2);
        for (int k = 0; ok && k < 2; k++) {
            PyObject* index = PyNumber_Index(PySequence_Fast_GET_ITEM(pair, k));
            values[k] = index == NULL ? -1 : PyLong_AsLong(index);
            ok = (index != NULL && !PyErr_Occurred() && values[k] >= INT_MIN && values[k] <= INT_MAX);
            Py_XDECREF(index);
        }
        Py_XDECREF(pair);
        if (!ok) {
            PyErr_Clear();
            raiseOpenMMException(usage + "; entry " + std::to_string(i) + " is " + pythonRepr(entry));
            break;
        }
        substeps.push_back({(int) values[0], (int) values[1]});
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
        throw OpenMM::OpenMMException("deserializeIntegrator: the XML describes no integrator of openmm-rigid");
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

/** integrator as a RigidBodyBussiIntegrator (not a copy), or NULL if it is another kind of Integrator. */
RigidBodyBussiIntegrator* asRigidBodyBussiIntegrator(OpenMM::Integrator* integrator) {
    return dynamic_cast<RigidBodyBussiIntegrator*>(integrator);
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
%typemap(typecheck, precedence=SWIG_TYPECHECK_POINTER) const std::vector<std::pair<int, int> >& groupSubsteps {
    $1 = 1;
}
%typemap(in) const std::vector<std::pair<int, int> >& groupSubsteps (std::vector<std::pair<int, int> > converted) {
    if (!groupSubstepsFromPython($input, converted))
        SWIG_fail;
    $1 = &converted;
}
%typemap(out) const std::vector<std::pair<int, int> >& {
    $result = PyList_New($1->size());
    for (std::size_t i = 0; $result != NULL && i < $1->size(); i++)
        PyList_SET_ITEM($result, i, Py_BuildValue("(ii)", (*$1)[i].first, (*$1)[i].second));
    if ($result == NULL)
        SWIG_fail;
}
%typemap(doctype) const std::vector<std::pair<int, int> >& "list of (int, int)"
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

// ---- docstrings ----
// SWIG's -doxygen turns the headers' Doxygen into the docstrings; the doctype typemaps name the Python
// types of what the typemaps above convert. The Python-only notes (openmm.unit Quantities, and the
// conversions themselves) are added by openmmrigid/_pythonapi.py, in one table.
%typemap(doctype) const std::vector<std::vector<int> >& "list of list of int"
%typemap(doctype) std::vector<int> "list of int"
%typemap(doctype) std::vector<double> "list of float"

%pythonbegin %{
import openmm as _openmm_package
%}

#define OPENMM_EXPORT_RIGID
// The helpers behind pickle, copy and XmlSerializer (openmmrigid/integrator.py); private names.
%rename(_deserializeRigidIntegrator) OpenMMRigid::Python::deserializeRigidIntegrator;
%rename(_cloneRigidIntegrator) OpenMMRigid::Python::cloneRigidIntegrator;
%rename(_asRigidBodyIntegrator) OpenMMRigid::Python::asRigidBodyIntegrator;
%rename(_asRigidBodyLangevinIntegrator) OpenMMRigid::Python::asRigidBodyLangevinIntegrator;
%rename(_asRigidBodyBussiIntegrator) OpenMMRigid::Python::asRigidBodyBussiIntegrator;
%newobject OpenMMRigid::Python::deserializeRigidIntegrator;
%newobject OpenMMRigid::Python::cloneRigidIntegrator;
// The options are the integrators' class constants (RigidBodyIntegrator.Exact, ...), not a class of their own.
%ignore OpenMMRigid::RigidBodyOptions;
%include "RigidBodyOptions.h"
%include "RigidBodyIntegratorBase.h"
%include "RigidBodyIntegrator.h"
%include "RigidBodyBussiIntegrator.h"

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

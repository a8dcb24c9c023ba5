// The SWIG module openmmrigid._openmmrigid (proxy: openmmrigid/openmmrigid.py). Users import the
// package openmmrigid, whose Python classes (FreeRotor, special) call into this module; RigidBodyIntegrator and
// RigidBodyLangevinIntegrator are the proxy classes defined here (swig/rigidbodyintegrator.i,
// swig/rigidbodylangevinintegrator.i), re-exported by the package.
%module(package="openmmrigid") openmmrigid

// Numbers as OpenMM's own wrappers take them: anything Python can turn into an int or a float (numpy
// scalars such as np.int64 or np.float32) where the C++ takes an int or a double.
%begin %{
#define SWIG_PYTHON_CAST_MODE
%}

%{
#include <exception>
#include <string>

/**
 * Raise openmm.OpenMMException with the given message, the exception an OpenMM user catches.
 * Falls back to RuntimeError only if the openmm package itself cannot be imported.
 */
static void raiseOpenMMException(const std::string& message) {
    PyObject* openmm = PyImport_ImportModule("openmm");
    PyObject* exceptionClass = openmm == NULL ? NULL : PyObject_GetAttrString(openmm, "OpenMMException");
    Py_XDECREF(openmm);
    if (exceptionClass == NULL) {
        PyErr_Clear();
        PyErr_SetString(PyExc_RuntimeError, message.c_str());
        return;
    }
    PyErr_SetString(exceptionClass, message.c_str());
    Py_DECREF(exceptionClass);
}

#include "internal/AccuracyCheck.h"

/**
 * The Python error of the last accuracy warning that the warning filters made an error, and its
 * message: kept out of the interpreter while the C++ exception that stops the step unwinds (openmm's
 * own wrappers, a CompoundIntegrator's step(), fail with a Python error pending), and raised instead
 * of an OpenMMException by this module's wrappers when that exception reaches them.
 */
static PyObject *accuracyErrorType = NULL, *accuracyErrorValue = NULL, *accuracyErrorTraceback = NULL;
static std::string accuracyErrorMessage;

static void dropAccuracyError() {
    Py_CLEAR(accuracyErrorType);
    Py_CLEAR(accuracyErrorValue);
    Py_CLEAR(accuracyErrorTraceback);
    accuracyErrorMessage.clear();
}

/** Set the kept accuracy error as the Python error if the C++ exception is the one it stopped; true if it did. */
static bool restoreAccuracyError(const char* message) {
    const bool ours = (accuracyErrorType != NULL && accuracyErrorMessage == message);
    if (ours) {
        PyErr_Restore(accuracyErrorType, accuracyErrorValue, accuracyErrorTraceback);
        accuracyErrorType = accuracyErrorValue = accuracyErrorTraceback = NULL;
        accuracyErrorMessage.clear();
    }
    else
        dropAccuracyError();
    return ours;
}

/**
 * The accuracy check's notifier in Python (AccuracyCheck::setNotifier()): the message issued as an
 * openmmrigid.AccuracyWarning by openmmrigid.integrator._issueAccuracyWarning, from within the step
 * that fired, whichever wrapper called it (with the GIL released or not). False if issuing it raised
 * (the warning filters made it an error): the step then stops, and the error is kept for
 * restoreAccuracyError().
 */
static bool pythonAccuracyNotifier(const std::string& message) {
    PyGILState_STATE gil = PyGILState_Ensure();
    PyObject* module = PyImport_ImportModule("openmmrigid.integrator");
    PyObject* result = (module == NULL ? NULL : PyObject_CallMethod(module, "_issueAccuracyWarning", "s", message.c_str()));
    const bool issued = (result != NULL);
    Py_XDECREF(result);
    Py_XDECREF(module);
    if (!issued) {
        dropAccuracyError();
        PyErr_Fetch(&accuracyErrorType, &accuracyErrorValue, &accuracyErrorTraceback);
        accuracyErrorMessage = message;
    }
    PyGILState_Release(gil);
    return issued;
}
%}

%init %{
    OpenMMRigid::AccuracyCheck::setNotifier(&pythonAccuracyNotifier);
%}

// The calls that may take long run with the GIL released, as OpenMM's own wrappers run step(), so that
// other Python threads (a progress bar, a Jupyter kernel, a sampler's workers) run meanwhile. Nothing
// they do touches Python objects; the accuracy check's notifier takes the GIL itself.
%define RELEASE_GIL(method)
%exception method {
    PyThreadState* savedThread = PyEval_SaveThread();
    try {
        $action
    }
    catch (const std::exception& e) {
        PyEval_RestoreThread(savedThread);
        if (!restoreAccuracyError(e.what()))
            raiseOpenMMException(e.what());
        SWIG_fail;
    }
    catch (...) {
        PyEval_RestoreThread(savedThread);
        raiseOpenMMException("openmmrigid: unknown C++ exception");
        SWIG_fail;
    }
    PyEval_RestoreThread(savedThread);
}
%enddef
RELEASE_GIL(OpenMMRigid::RigidBodyIntegratorBase::step)
RELEASE_GIL(OpenMMRigid::RigidBodyIntegratorBase::computeSystemTemperature)
RELEASE_GIL(OpenMMRigid::RigidBodyLangevinIntegrator::getOnStepKineticEnergy)

// Every C++ exception (OpenMM::OpenMMException and std::invalid_argument both derive from
// std::exception) reaches Python as openmm.OpenMMException with its message.
%exception {
    try {
        $action
    }
    catch (const std::exception& e) {
        // The step stopped by an AccuracyWarning that the filters made an error raises that warning.
        if (!restoreAccuracyError(e.what()))
            raiseOpenMMException(e.what());
        SWIG_fail;
    }
    catch (...) {
        raiseOpenMMException("openmmrigid: unknown C++ exception");
        SWIG_fail;
    }
}

// The Python names of C++ types in the docstrings SWIG's -doxygen writes (its defaults: "boolean", "string").
%typemap(doctype) bool "bool"
%typemap(doctype) std::string, const std::string& "str"

%include "swig/buffers.i"
%include "swig/special.i"
%include "swig/freerotor.i"
%include "swig/rigidbodyintegrator.i"
%include "swig/rigidbodylangevinintegrator.i"

// The helpers behind pickle, copy and XmlSerializer (defined in swig/rigidbodyintegrator.i, renamed
// to private names there), declared once both integrator classes are known.
namespace OpenMMRigid {
namespace Python {
RigidBodyIntegratorBase* deserializeRigidIntegrator(const std::string& xml);
RigidBodyIntegratorBase* cloneRigidIntegrator(const RigidBodyIntegratorBase& integrator);
RigidBodyIntegrator* asRigidBodyIntegrator(OpenMM::Integrator* integrator);
RigidBodyLangevinIntegrator* asRigidBodyLangevinIntegrator(OpenMM::Integrator* integrator);
RigidBodyBussiIntegrator* asRigidBodyBussiIntegrator(OpenMM::Integrator* integrator);
} // namespace Python
} // namespace OpenMMRigid

// Which platforms have the kernels (openmmrigid.getSupportedPlatforms()).
%{
#include "PlatformSupport.h"
%}
%typemap(out) std::vector<std::string> {
    const std::vector<std::string>& names = $1;
    $result = PyList_New(names.size());
    for (size_t i = 0; i < names.size(); i++)
        PyList_SetItem($result, i, PyUnicode_FromString(names[i].c_str()));
}
%typemap(doctype) std::vector<std::string> "list of str"
%include "PlatformSupport.h"

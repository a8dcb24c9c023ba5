"""openmmrigid.RigidBodyIntegrator, openmmrigid.RigidBodyLangevinIntegrator and what makes them work
with the rest of OpenMM.

The classes themselves are SWIG proxies (python/swig/rigidbodyintegrator.i and
rigidbodylangevinintegrator.i), subclasses of ``openmm.Integrator`` through their common base
``RigidBodyIntegratorBase``. Importing this module also

- loads the platform kernels, ``libOpenMMRigidReference.so`` from this package's folder, with
  ``openmm.Platform.loadPluginLibrary`` (which calls the library's ``registerKernelFactories``);
  importing again, or a library already loaded from ``OPENMM_PLUGIN_DIR``, loads nothing twice;
- makes ``openmm.XmlSerializer.deserialize``, ``openmm.XmlSerializer.clone`` and
  ``openmm.CompoundIntegrator.getIntegrator`` return a ``RigidBodyIntegrator`` or
  ``RigidBodyLangevinIntegrator`` for one. The openmm wheel turns the Integrator it returns into the
  most derived class it knows of (SWIG's ``%factory``), which stops at ``openmm.Integrator`` for
  classes from plugins; the functions are wrapped so that they hand back the right class when the
  C++ object is one of ours, and change nothing for any other integrator. (``Context.getIntegrator()``
  returns the Python object the Context was made with, so it is already of the right class.)
- makes ``openmm.Context(system, integrator, platform)`` with a rigid-body integrator on a platform
  that has no kernels for it (CUDA without the openmm-rigid-cuda wheel) fail with a message that
  names the platforms that have them, instead of OpenMM's generic "does not support all required
  kernels". Only the platforms that have the kernels claim them, so a Context made without naming a
  platform takes the fastest of those.

``RigidBodyIntegrator.getTemperature`` and ``setTemperature`` raise ``NoThermostatError`` (an
``openmm.OpenMMException`` that is also an ``AttributeError``) when no thermostat is set: tools that
detect a heat bath by calling ``getTemperature()`` and catching ``AttributeError`` (openmmtools'
``ThermodynamicState``) then treat the integrator as the NVE integrator it is.

The serialization proxies themselves are registered by libOpenMMRigid when it loads, so that C++ code and
``openmm.XmlSerializer.serialize`` find it with nothing to do.
"""

import functools
import os
import sys
import warnings

import openmm

from . import _pythonapi
from . import openmmrigid as _swig

__all__ = ["RigidBodyIntegrator", "RigidBodyLangevinIntegrator", "RigidBodyIntegratorBase", "deserializeIntegrator",
           "getSupportedPlatforms", "pluginLoadFailures", "NoThermostatError", "AccuracyWarning"]

RigidBodyIntegratorBase = _swig.RigidBodyIntegratorBase
RigidBodyIntegrator = _swig.RigidBodyIntegrator
RigidBodyLangevinIntegrator = _swig.RigidBodyLangevinIntegrator
getSupportedPlatforms = _swig.getSupportedPlatforms

# The docstrings are the headers' Doxygen (SWIG's -doxygen); _pythonapi adds the unit conversions and
# the notes about them, and writes the sections in numpy style.
_pythonapi.applyToClasses(RigidBodyIntegratorBase, RigidBodyIntegrator, RigidBodyLangevinIntegrator)
getSupportedPlatforms.__doc__ = _pythonapi.numpyStyle(getSupportedPlatforms.__doc__)


class NoThermostatError(openmm.OpenMMException, AttributeError):
    """Raised by ``RigidBodyIntegrator.getTemperature()`` and ``setTemperature()`` when the integrator has
    no thermostat (it conserves the energy: NVE). It is an ``openmm.OpenMMException``, as every error of
    the integrators, and an ``AttributeError``, as a missing ``getTemperature`` is to tools that detect
    thermostated integrators that way (openmmtools)."""


def _raisingNoThermostatError(method):
    """method, raising NoThermostatError (with the C++ message) where it fails for want of a thermostat."""
    def wrapper(self, *args, **kwargs):
        try:
            return method(self, *args, **kwargs)
        except openmm.OpenMMException as error:
            if isinstance(error, NoThermostatError) or self.hasThermostat():
                raise
            raise NoThermostatError(str(error)) from None
    functools.update_wrapper(wrapper, method)
    # As for every method _pythonapi wrapped: __wrapped__ is SWIG's own (whose docstring and signature are the C++ ones).
    wrapper.__wrapped__ = getattr(method, "__wrapped__", method)
    return wrapper


for _name in ("getTemperature", "setTemperature"):
    setattr(RigidBodyIntegrator, _name, _raisingNoThermostatError(getattr(RigidBodyIntegrator, _name)))


class AccuracyWarning(RuntimeWarning):
    """Issued by ``step()``, once, when the integrator's accuracy check (``setAccuracyCheck()``) finds
    that the run has left its accurate range: the message names the step size, the figure against its
    limit, and the remedies. It is issued from within the step however the step was taken (the
    integrator's ``step()``, a ``CompoundIntegrator``'s, ``app.Simulation.step()``), pointing at the
    line of the script that stepped. A warning, not an error: the run goes on, biased
    (``warnings.simplefilter("error", AccuracyWarning)`` makes the step stop with it; through a
    ``CompoundIntegrator`` it then stops with an ``openmm.OpenMMException`` of the same message)."""


#: The folders whose frames a warning skips to reach the line that stepped: openmm's (app.Simulation)
#: and this package's (the SWIG proxies).
_INTERNAL_FOLDERS = tuple(os.path.dirname(os.path.abspath(module.__file__)) + os.sep for module in (openmm, _swig))


def _issueAccuracyWarning(message):
    """Issue the accuracy check's message as an AccuracyWarning, attributed to the first frame outside
    openmm and openmmrigid. Called by the SWIG module from within the step that fired."""
    level, frame = 2, sys._getframe(1)
    while frame is not None and os.path.abspath(frame.f_code.co_filename).startswith(_INTERNAL_FOLDERS):
        frame = frame.f_back
        level += 1
    warnings.warn(message, AccuracyWarning, stacklevel=level)


_KERNEL_NAME = "IntegrateRigidBodyStep"


def _libraryName(target):
    """CMake's file name for the shared library `target` on this system."""
    return {"win32": f"{target}.dll", "darwin": f"lib{target}.dylib"}.get(sys.platform, f"lib{target}.so")


# The plugin for each platform: the Reference one (Reference and CPU) is required; a GPU platform's is
# loaded where both the plugin and the platform are present.
_KERNEL_LIBRARY = _libraryName("OpenMMRigidReference")
_GPU_LIBRARIES = {"OpenCL": _libraryName("OpenMMRigidOpenCL"), "CUDA": _libraryName("OpenMMRigidCUDA")}

#: Why a GPU platform's plugin present in this package's folder did not load (platform name -> message).
pluginLoadFailures = {}


def _kernelsAreRegistered(platformName="Reference"):
    """Whether the platform already has the kernels (from this module or a plugin folder)."""
    try:
        return openmm.Platform.getPlatformByName(platformName).supportsKernels([_KERNEL_NAME])
    except Exception:  # no such platform: nothing can be registered anyway
        return False


def _platformExists(name):
    return any(openmm.Platform.getPlatform(i).getName() == name for i in range(openmm.Platform.getNumPlatforms()))


def _loadKernels():
    """Load the rigid-body integrators' kernels for every platform this installation has them for, once."""
    folder = os.path.dirname(os.path.abspath(__file__))
    if not _kernelsAreRegistered():
        path = os.path.join(folder, _KERNEL_LIBRARY)
        try:
            openmm.Platform.loadPluginLibrary(path)
        except Exception as error:
            raise ImportError(f"openmmrigid: cannot load the rigid-body integrator kernels from {path}: {error}") from error
    # A GPU plugin that cannot load (no driver, no OpenCL runtime) must not stop the package: the
    # reason is kept in pluginLoadFailures, as openmm.Platform.getPluginLoadFailures() does.
    for platformName, library in _GPU_LIBRARIES.items():
        path = os.path.join(folder, library)
        if not os.path.exists(path) or not _platformExists(platformName) or _kernelsAreRegistered(platformName):
            continue
        try:
            openmm.Platform.loadPluginLibrary(path)
        except Exception as error:
            pluginLoadFailures[platformName] = f"{path}: {error}"


def _mostDerived(integrator):
    """integrator as a RigidBodyIntegrator or RigidBodyLangevinIntegrator if its C++ object is one (the
    new proxy takes over its ownership); any other integrator unchanged."""
    if type(integrator) not in (openmm.Integrator, RigidBodyIntegratorBase):  # already the right class, or another
        return integrator
    for cast in (_swig._asRigidBodyLangevinIntegrator, _swig._asRigidBodyIntegrator):
        rigid = cast(integrator)
        if rigid is not None:
            rigid.thisown = integrator.thisown
            integrator.thisown = False
            return rigid
    return integrator


def _returningRigidBodyIntegrators(function):
    def wrapper(*args):
        return _mostDerived(function(*args))
    wrapper.__name__ = function.__name__
    wrapper.__doc__ = function.__doc__
    wrapper._openmmrigidOriginal = function
    return staticmethod(wrapper)


def _patchXmlSerializer():
    """Wrap XmlSerializer._deserializeIntegrator and _cloneIntegrator, once."""
    for name in ("_deserializeIntegrator", "_cloneIntegrator"):
        function = getattr(openmm.XmlSerializer, name, None)
        if function is None or hasattr(function, "_openmmrigidOriginal"):
            continue
        setattr(openmm.XmlSerializer, name, _returningRigidBodyIntegrators(function))


def _patchCompoundIntegrator():
    """Wrap CompoundIntegrator.getIntegrator, once, so that it returns our classes for ours (the
    compound keeps owning the integrator, as with stock ones)."""
    function = openmm.CompoundIntegrator.getIntegrator
    if hasattr(function, "_openmmrigidOriginal"):
        return

    def getIntegrator(self, *args):
        return _mostDerived(function(self, *args))
    functools.update_wrapper(getIntegrator, function)
    getIntegrator._openmmrigidOriginal = function
    openmm.CompoundIntegrator.getIntegrator = getIntegrator


#: What OpenMM says when a Context is made on a platform without one of the kernels it needs.
_MISSING_KERNELS = "does not support all required kernels"


def _rigidIntegratorIn(integrator):
    """The rigid-body integrator that integrator is or holds (a CompoundIntegrator's), or None."""
    if isinstance(integrator, RigidBodyIntegratorBase):
        return integrator
    if isinstance(integrator, openmm.CompoundIntegrator):
        for i in range(integrator.getNumIntegrators()):
            rigid = _rigidIntegratorIn(integrator.getIntegrator(i))
            if rigid is not None:
                return rigid
    return None


def _unsupportedPlatformMessage(integrator, platform):
    """The message for a Context made with a rigid-body integrator on a platform without its kernels."""
    supported = getSupportedPlatforms()
    message = (f"{type(integrator).__name__}: the {platform.getName()} platform has no kernels for the rigid-body "
               f"integrators; they run on {', '.join(supported)} (openmmrigid.getSupportedPlatforms()).")
    if platform.getName() == "CUDA":
        message += (" For CUDA, install the plugin for your CUDA version: pip install \"openmm-rigid[cuda13]\" (the "
                    "openmm-rigid-cuda-13 wheel).")
    return message + " Or make the Context without naming a platform, and OpenMM takes the fastest of those."


def _patchContext():
    """Wrap Context.__init__, once, so that a Context made with a rigid-body integrator on a platform that
    has no kernels for it says so and names the platforms that have them, instead of OpenMM's generic
    message. OpenMM checks the kernels before the integrator can speak; only that error is reworded,
    and only where the platform named lacks the rigid-body kernel."""
    if hasattr(openmm.Context.__init__, "_openmmrigidOriginal"):
        return
    original = openmm.Context.__init__

    def __init__(self, *args, **kwargs):
        try:
            __init__._openmmrigidOriginal(self, *args, **kwargs)
        except openmm.OpenMMException as error:
            integrator = _rigidIntegratorIn(args[1] if len(args) > 1 else kwargs.get("integrator"))
            platform = args[2] if len(args) > 2 else kwargs.get("platform")
            if (_MISSING_KERNELS in str(error) and integrator is not None and isinstance(platform, openmm.Platform)
                    and not platform.supportsKernels([_KERNEL_NAME])):
                raise openmm.OpenMMException(_unsupportedPlatformMessage(integrator, platform)) from error
            raise
    functools.update_wrapper(__init__, original)
    __init__._openmmrigidOriginal = original
    openmm.Context.__init__ = __init__


def deserializeIntegrator(xml):
    """Reconstruct a RigidBodyIntegrator or RigidBodyLangevinIntegrator from the XML that
    ``openmm.XmlSerializer.serialize`` wrote.

    ``openmm.XmlSerializer.deserialize(xml)`` does the same once openmmrigid is imported; this
    function also checks that the XML describes one of these integrators.

    Parameters
    ----------
    xml : str
        The serialized integrator.

    Returns
    -------
    RigidBodyIntegrator or RigidBodyLangevinIntegrator
        A new integrator, not bound to any Context, with every setting of the serialized one.

    Raises
    ------
    openmm.OpenMMException
        If the XML cannot be read or describes another kind of integrator.
    """
    return _mostDerived(_swig._deserializeRigidIntegrator(xml))


_loadKernels()
_patchXmlSerializer()
_patchCompoundIntegrator()
_patchContext()

"""openmmrigid.RigidBodyIntegrator, RigidBodyBussiIntegrator and RigidBodyLangevinIntegrator.

The classes are SWIG proxies (python/swig/rigidbodyintegrator.i and rigidbodylangevinintegrator.i),
subclasses of ``openmm.Integrator`` through their common base ``RigidBodyIntegratorBase``. Importing this
module loads the platform kernels (``libOpenMMRigidReference.so`` from this package's folder, and the GPU
plugins beside it where their platforms exist) with ``openmm.Platform.loadPluginLibrary``. The serialization
proxies are registered by libOpenMMRigid when it loads.

OpenMM's wrappers turn an Integrator they return into the most derived class they know of, which stops at
``openmm.Integrator`` for a plugin's classes: ``openmm.XmlSerializer.deserialize()`` hands back an
``openmm.Integrator`` that runs ours but has none of its methods. ``deserializeIntegrator()`` returns the
right class; ``copy``, ``pickle`` and ``Context.getIntegrator()`` keep it.

One method of openmm is wrapped, ``CompoundIntegrator.getIntegrator`` (``_patchCompoundIntegrator``): tools
that walk a compound integrator (openmmtools' ``ThermodynamicState`` finds each heat bath by calling
``getTemperature()`` on ``compound.getIntegrator(i)``) would otherwise see no heat bath in our integrators,
set no temperature on them and add an ``AndersenThermostat`` at the state's temperature: a silent wrong
ensemble. No other way reaches those tools. The wrapper returns our class for ours and the same object as
before for every other integrator.
"""

import functools
import os
import sys
import warnings

import openmm

from . import _pythonapi
from . import openmmrigid as _swig

__all__ = ["RigidBodyIntegrator", "RigidBodyBussiIntegrator", "RigidBodyLangevinIntegrator", "RigidBodyIntegratorBase",
           "deserializeIntegrator", "getSupportedPlatforms", "pluginLoadFailures", "AccuracyWarning"]

RigidBodyIntegratorBase = _swig.RigidBodyIntegratorBase
RigidBodyIntegrator = _swig.RigidBodyIntegrator
RigidBodyBussiIntegrator = _swig.RigidBodyBussiIntegrator
RigidBodyLangevinIntegrator = _swig.RigidBodyLangevinIntegrator
getSupportedPlatforms = _swig.getSupportedPlatforms

# The docstrings are the headers' Doxygen (SWIG's -doxygen); _pythonapi adds the unit conversions and
# the notes about them, and writes the sections in numpy style.
_pythonapi.applyToClasses(RigidBodyIntegratorBase, RigidBodyIntegrator, RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator)
getSupportedPlatforms.__doc__ = _pythonapi.numpyStyle(getSupportedPlatforms.__doc__)


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
    """integrator as a RigidBodyIntegrator, RigidBodyBussiIntegrator or RigidBodyLangevinIntegrator if its C++ object is one (the
    new proxy takes over its ownership); any other integrator unchanged."""
    if type(integrator) not in (openmm.Integrator, RigidBodyIntegratorBase):  # already the right class, or another
        return integrator
    for cast in (_swig._asRigidBodyLangevinIntegrator, _swig._asRigidBodyBussiIntegrator, _swig._asRigidBodyIntegrator):
        rigid = cast(integrator)
        if rigid is not None:
            rigid.thisown = integrator.thisown
            integrator.thisown = False
            return rigid
    return integrator


def _patchCompoundIntegrator():
    """Wrap CompoundIntegrator.getIntegrator, once, so that it returns our classes for ours (the compound keeps
    owning the integrator, as with stock ones). See the module's docstring for why."""
    original = openmm.CompoundIntegrator.getIntegrator
    if hasattr(original, "_openmmrigidOriginal"):
        return

    def getIntegrator(self, *args):
        return _mostDerived(original(self, *args))
    functools.update_wrapper(getIntegrator, original)
    getIntegrator._openmmrigidOriginal = original
    openmm.CompoundIntegrator.getIntegrator = getIntegrator


def deserializeIntegrator(xml):
    """Reconstruct an integrator of openmm-rigid from the XML that ``openmm.XmlSerializer.serialize`` wrote.

    ``openmm.XmlSerializer.deserialize(xml)`` makes the same integrator, returned as an ``openmm.Integrator``
    without this package's methods; this function returns its own class.

    Parameters
    ----------
    xml : str
        The serialized integrator.

    Returns
    -------
    RigidBodyIntegrator, RigidBodyBussiIntegrator or RigidBodyLangevinIntegrator
        A new integrator, not bound to any Context, with every setting of the serialized one.

    Raises
    ------
    openmm.OpenMMException
        If the XML cannot be read or describes another kind of integrator.
    """
    return _mostDerived(_swig._deserializeRigidIntegrator(xml))


_loadKernels()
_patchCompoundIntegrator()

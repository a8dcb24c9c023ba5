"""openmmrigid.RigidBodyIntegrator and what makes it work with the rest of OpenMM.

The class itself is the SWIG proxy (python/swig/rigidbodyintegrator.i), a subclass of
``openmm.Integrator``. Importing this module also

- loads the platform kernels, ``libOpenMMRigidReference.so`` from this package's folder, with
  ``openmm.Platform.loadPluginLibrary`` (which calls the library's ``registerKernelFactories``);
  importing again, or a library already loaded from ``OPENMM_PLUGIN_DIR``, loads nothing twice;
- makes ``openmm.XmlSerializer.deserialize`` and ``openmm.XmlSerializer.clone`` return a
  ``RigidBodyIntegrator`` for one. The openmm wheel turns the Integrator it deserializes into the
  most derived class it knows of, which stops at ``openmm.Integrator`` for classes from plugins;
  the two functions it calls for integrators are wrapped so that they hand back a
  RigidBodyIntegrator when the C++ object is one, and change nothing for any other integrator.

The serialization proxy itself is registered by libOpenMMRigid when it loads, so that C++ code and
``openmm.XmlSerializer.serialize`` find it with nothing to do.
"""

import os
import sys

import openmm

from . import openmmrigid as _swig

__all__ = ["RigidBodyIntegrator", "deserializeIntegrator"]

RigidBodyIntegrator = _swig.RigidBodyIntegrator

_KERNEL_NAME = "IntegrateRigidBodyStep"
# CMake's name for the shared library OpenMMRigidReference on each system.
_KERNEL_LIBRARY = {"win32": "OpenMMRigidReference.dll", "darwin": "libOpenMMRigidReference.dylib"}.get(
    sys.platform, "libOpenMMRigidReference.so")


def _kernelsAreRegistered():
    """Whether the Reference platform already has the kernels (from this module or a plugin folder)."""
    try:
        return openmm.Platform.getPlatformByName("Reference").supportsKernels([_KERNEL_NAME])
    except Exception:  # no Reference platform: nothing can be registered anyway
        return False


def _loadKernels():
    """Load the Reference and CPU kernels of RigidBodyIntegrator, once."""
    if _kernelsAreRegistered():
        return
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), _KERNEL_LIBRARY)
    try:
        openmm.Platform.loadPluginLibrary(path)
    except Exception as error:
        raise ImportError(f"openmmrigid: cannot load the RigidBodyIntegrator kernels from {path}: {error}") from error


def _asRigidBodyIntegrator(integrator):
    """integrator as a RigidBodyIntegrator if its C++ object is one (taking over its ownership), else unchanged."""
    if type(integrator) is not openmm.Integrator:  # already the right class, or another known one
        return integrator
    rigid = _swig._asRigidBodyIntegrator(integrator)
    if rigid is None:
        return integrator
    rigid.thisown = integrator.thisown
    integrator.thisown = False
    return rigid


def _returningRigidBodyIntegrators(function):
    def wrapper(*args):
        return _asRigidBodyIntegrator(function(*args))
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


def deserializeIntegrator(xml):
    """Reconstruct a RigidBodyIntegrator from the XML that ``openmm.XmlSerializer.serialize`` wrote.

    ``openmm.XmlSerializer.deserialize(xml)`` does the same once openmmrigid is imported; this
    function also checks that the XML describes a RigidBodyIntegrator.

    Parameters
    ----------
    xml : str
        The serialized integrator.

    Returns
    -------
    RigidBodyIntegrator
        A new integrator, not bound to any Context, with every setting of the serialized one.

    Raises
    ------
    openmm.OpenMMException
        If the XML cannot be read or describes another kind of integrator.
    """
    return _swig._deserializeRigidBodyIntegrator(xml)


_loadKernels()
_patchXmlSerializer()

"""openmmrigid.RigidBodyIntegrator, openmmrigid.RigidBodyLangevinIntegrator and what makes them work
with the rest of OpenMM.

The classes themselves are SWIG proxies (python/swig/rigidbodyintegrator.i and
rigidbodylangevinintegrator.i), subclasses of ``openmm.Integrator`` through their common base
``RigidBodyIntegratorBase``. Importing this module also

- loads the platform kernels, ``libOpenMMRigidReference.so`` from this package's folder, with
  ``openmm.Platform.loadPluginLibrary`` (which calls the library's ``registerKernelFactories``);
  importing again, or a library already loaded from ``OPENMM_PLUGIN_DIR``, loads nothing twice;
- makes ``openmm.XmlSerializer.deserialize`` and ``openmm.XmlSerializer.clone`` return a
  ``RigidBodyIntegrator`` or ``RigidBodyLangevinIntegrator`` for one. The openmm wheel turns the
  Integrator it deserializes into the most derived class it knows of, which stops at
  ``openmm.Integrator`` for classes from plugins; the two functions it calls for integrators are
  wrapped so that they hand back the right class when the C++ object is one of ours, and change
  nothing for any other integrator.

The serialization proxies themselves are registered by libOpenMMRigid when it loads, so that C++ code and
``openmm.XmlSerializer.serialize`` find it with nothing to do.
"""

import os
import sys

import openmm

from . import openmmrigid as _swig

__all__ = ["RigidBodyIntegrator", "RigidBodyLangevinIntegrator", "RigidBodyIntegratorBase", "deserializeIntegrator"]

RigidBodyIntegratorBase = _swig.RigidBodyIntegratorBase
RigidBodyIntegrator = _swig.RigidBodyIntegrator
RigidBodyLangevinIntegrator = _swig.RigidBodyLangevinIntegrator

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
    """Load the Reference and CPU kernels of the rigid-body integrators, once."""
    if _kernelsAreRegistered():
        return
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), _KERNEL_LIBRARY)
    try:
        openmm.Platform.loadPluginLibrary(path)
    except Exception as error:
        raise ImportError(f"openmmrigid: cannot load the rigid-body integrator kernels from {path}: {error}") from error


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

"""Loading the CUDA kernels of the rigid-body integrators, when they are installed and can run.

``libOpenMMRigidCUDA.so`` comes in its own wheel, ``openmm-rigid-cuda-13`` (``pip install
openmm-rigid[cuda13]``), which puts it in this package's folder beside the Reference kernels. It links
OpenMM's libOpenMMCUDA.so and through it the NVIDIA driver (``libcuda.so.1``): on a machine without
one, OpenMM has no CUDA platform and the library cannot load. That is the usual case, not an error,
so nothing here raises or prints; why the kernels were not loaded is kept in ``loadFailure``.
"""

import os

import openmm

_KERNEL_NAME = "IntegrateRigidBodyStep"
_LIBRARY = "libOpenMMRigidCUDA.so"  # Linux only, as OpenMM's CUDA wheels are

#: Why the CUDA kernels are not registered (a sentence), or None once they are.
loadFailure = "loadCudaKernels() was not called"


def _cudaPlatform():
    for i in range(openmm.Platform.getNumPlatforms()):
        platform = openmm.Platform.getPlatform(i)
        if platform.getName() == "CUDA":
            return platform
    return None


def loadCudaKernels(folder=None):
    """Register the rigid-body kernels with OpenMM's CUDA platform, once; quietly do nothing where
    that cannot be done.

    folder is where to look for libOpenMMRigidCUDA.so: this package's folder unless given. Returns
    True when the CUDA platform has the kernels (loaded now, or already, e.g. from
    ``OPENMM_PLUGIN_DIR``); otherwise False, with the reason in ``loadFailure``: no CUDA platform (no
    NVIDIA driver, or openmm-cuda-13 not installed), the CUDA wheel of openmm-rigid not installed, or
    the library failing to load.
    """
    global loadFailure
    platform = _cudaPlatform()
    if platform is None:
        loadFailure = "OpenMM has no CUDA platform (no NVIDIA driver, or openmm-cuda-13 is not installed)"
        return False
    if platform.supportsKernels([_KERNEL_NAME]):
        loadFailure = None
        return True
    path = os.path.join(folder or os.path.dirname(os.path.abspath(__file__)), _LIBRARY)
    if not os.path.exists(path):
        loadFailure = f"{path} is not there (pip install openmm-rigid[cuda13])"
        return False
    try:
        openmm.Platform.loadPluginLibrary(path)
    except Exception as error:  # OpenMMException: the dynamic loader's message
        loadFailure = f"cannot load {path}: {error}"
        return False
    if not platform.supportsKernels([_KERNEL_NAME]):
        loadFailure = f"{path} loaded but registered no kernels with the CUDA platform"
        return False
    loadFailure = None
    return True

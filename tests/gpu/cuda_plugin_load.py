"""Check how libOpenMMRigidCUDA.so loads through openmmrigid's loader (python/openmmrigid/_cudaplugin.py).

Where OpenMM has a CUDA platform (a driver, or the CUDA toolkit's stub driver on LD_LIBRARY_PATH as
libcuda.so.1: OpenMM then registers the platform, and only creating a Context fails), loading must
register the kernel IntegrateRigidBodyStep with it. Where it has none (no driver), the loader must
return False and print nothing: a machine without an NVIDIA GPU is the usual case.

    python cuda_plugin_load.py <_cudaplugin.py> <folder of libOpenMMRigidCUDA.so> [--stub <folder>]

--stub: the folder of the stub libcuda.so.1, which the caller put on LD_LIBRARY_PATH (the dynamic
loader reads it when the process starts); the CUDA platform must then be there. An empty folder
means that no stub was found: the check is skipped (exit code 77).
"""

import argparse
import importlib.util
import os
import sys
import tempfile

SKIPPED = 77


def loadModule(path):
    spec = importlib.util.spec_from_file_location("openmmrigid_cudaplugin", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def callCapturingOutput(function, *arguments):
    """function(*arguments), and what it wrote to the process's stdout and stderr (C++ included)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    with tempfile.TemporaryFile() as capture:
        os.dup2(capture.fileno(), 1)
        os.dup2(capture.fileno(), 2)
        try:
            result = function(*arguments)
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for descriptor in saved:
                os.close(descriptor)
        capture.seek(0)
        return result, capture.read().decode(errors="replace")


def main(loaderPath, pluginFolder, stubFolder):
    if stubFolder == "":
        print("skipped: no stub libcuda.so was found (a CUDA toolkit's lib64/stubs; no pip package ships one)")
        return SKIPPED
    expectCuda = stubFolder is not None
    if expectCuda and stubFolder not in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep):
        print(f"FAILED: {stubFolder} is not on LD_LIBRARY_PATH")
        return 1
    import openmm
    loader = loadModule(loaderPath)
    names = [openmm.Platform.getPlatform(i).getName() for i in range(openmm.Platform.getNumPlatforms())]
    print(f"OpenMM {openmm.version.full_version}: platforms {names}")
    hasCuda = "CUDA" in names
    if expectCuda and not hasCuda:
        print("FAILED: no CUDA platform although the stub driver is on LD_LIBRARY_PATH:",
              *openmm.Platform.getPluginLoadFailures(), sep="\n    ")
        return 1
    loaded, output = callCapturingOutput(loader.loadCudaKernels, pluginFolder)
    print(f"loadCudaKernels: {loaded}; loadFailure: {loader.loadFailure}")
    if hasCuda:
        registered = openmm.Platform.getPlatformByName("CUDA").supportsKernels(["IntegrateRigidBodyStep"])
        if not (loaded and registered):
            print(f"FAILED: the CUDA platform is there but the kernel is not registered ({registered=})")
            return 1
        print("the CUDA platform has IntegrateRigidBodyStep")
    else:
        if loaded:
            print("FAILED: the loader reports success without a CUDA platform")
            return 1
        if output:
            print(f"FAILED: the loader was not quiet without a driver; it wrote:\n{output}")
            return 1
        print("no CUDA platform: the loader declined quietly")
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("loader", help="python/openmmrigid/_cudaplugin.py")
    parser.add_argument("pluginFolder", help="the folder of libOpenMMRigidCUDA.so")
    parser.add_argument("--stub", help="the folder of the stub libcuda.so.1 on LD_LIBRARY_PATH ('' if none)")
    arguments = parser.parse_args()
    sys.exit(main(arguments.loader, arguments.pluginFolder, arguments.stub))

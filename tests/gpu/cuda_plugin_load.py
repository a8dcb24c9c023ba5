"""Check how libOpenMMRigidCUDA.so loads into OpenMM, with the stub driver and without a driver.

Where OpenMM has a CUDA platform (a driver, or the CUDA toolkit's stub driver on LD_LIBRARY_PATH as
libcuda.so.1: OpenMM then registers the platform, and only creating a Context fails), loading the
library must register the kernel IntegrateRigidBodyStep with it. Where it has none (no driver), the
library cannot load: that must be an ordinary exception, with nothing printed, which openmmrigid's
loader (integrator.py) never even meets, since it loads a GPU plugin only where its platform exists.

    python cuda_plugin_load.py <libOpenMMRigidCUDA.so> [--stub <folder>]

--stub: the folder of the stub libcuda.so.1, which the caller put on LD_LIBRARY_PATH (the dynamic
loader reads it when the process starts); the CUDA platform must then be there. An empty folder
means that no stub was found: the check is skipped (exit code 77).
"""

import argparse
import os
import sys
import tempfile

SKIPPED = 77
KERNEL = "IntegrateRigidBodyStep"


def callCapturingOutput(function, *arguments):
    """(function(*arguments) or None, the exception it raised or None, what it wrote to the process's
    stdout and stderr, C++ included)."""
    sys.stdout.flush()
    sys.stderr.flush()
    saved = [os.dup(1), os.dup(2)]
    result = error = None
    with tempfile.TemporaryFile() as capture:
        os.dup2(capture.fileno(), 1)
        os.dup2(capture.fileno(), 2)
        try:
            result = function(*arguments)
        except Exception as exception:
            error = exception
        finally:
            sys.stdout.flush()
            sys.stderr.flush()
            os.dup2(saved[0], 1)
            os.dup2(saved[1], 2)
            for descriptor in saved:
                os.close(descriptor)
        capture.seek(0)
        return result, error, capture.read().decode(errors="replace")


def main(library, stubFolder):
    if stubFolder == "":
        print("skipped: no stub libcuda.so was found (a CUDA toolkit's lib64/stubs; no pip package ships one)")
        return SKIPPED
    expectCuda = stubFolder is not None
    if expectCuda and stubFolder not in os.environ.get("LD_LIBRARY_PATH", "").split(os.pathsep):
        print(f"FAILED: {stubFolder} is not on LD_LIBRARY_PATH")
        return 1
    import openmm
    names = [openmm.Platform.getPlatform(i).getName() for i in range(openmm.Platform.getNumPlatforms())]
    print(f"OpenMM {openmm.version.full_version}: platforms {names}")
    hasCuda = "CUDA" in names
    if expectCuda and not hasCuda:
        print("FAILED: no CUDA platform although the stub driver is on LD_LIBRARY_PATH:",
              *openmm.Platform.getPluginLoadFailures(), sep="\n    ")
        return 1
    _, error, output = callCapturingOutput(openmm.Platform.loadPluginLibrary, library)
    if hasCuda:
        if error is not None:
            print(f"FAILED: the CUDA platform is there but {library} does not load: {error}")
            return 1
        if not openmm.Platform.getPlatformByName("CUDA").supportsKernels([KERNEL]):
            print(f"FAILED: {library} loaded but the CUDA platform has no {KERNEL}")
            return 1
        print(f"loaded; the CUDA platform has {KERNEL}")
    else:
        if error is None:
            print(f"FAILED: {library} loaded although OpenMM has no CUDA platform (no driver)")
            return 1
        if output:
            print(f"FAILED: loading without a driver printed:\n{output}")
            return 1
        print(f"no driver: loading fails quietly with {type(error).__name__}: {error}")
    return 0


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("library", help="libOpenMMRigidCUDA.so")
    parser.add_argument("--stub", help="the folder of the stub libcuda.so.1 on LD_LIBRARY_PATH ('' if none)")
    arguments = parser.parse_args()
    sys.exit(main(arguments.library, arguments.stub))

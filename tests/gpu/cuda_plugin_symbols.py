"""Check that every symbol libOpenMMRigidCUDA.so needs is defined once the driver is there.

The link with --no-undefined already proves that the plugin's own references resolve in the
libraries it links; `ldd -r` also relocates those libraries, and libOpenMMCUDA.so needs the driver,
libcuda.so.1. With the CUDA toolkit's stub driver on LD_LIBRARY_PATH (as libcuda.so.1, the
name the driver has), nothing may be left undefined or not found.

    python cuda_plugin_symbols.py <libOpenMMRigidCUDA.so> <folder holding libcuda.so.1, or "">

Exits 77 (skipped) when no stub folder is given.
"""

import os
import subprocess
import sys

SKIPPED = 77


def main(library, stubFolder):
    if not stubFolder:
        print("skipped: no stub libcuda.so was found (a CUDA toolkit's lib64/stubs; no pip package ships one)")
        return SKIPPED
    environment = dict(os.environ, LD_LIBRARY_PATH=os.pathsep.join(
        filter(None, [stubFolder, os.environ.get("LD_LIBRARY_PATH")])))
    result = subprocess.run(["ldd", "-r", library], env=environment, capture_output=True, text=True)
    output = result.stdout + result.stderr
    problems = [line.strip() for line in output.splitlines() if "undefined symbol" in line or "not found" in line]
    print(output.strip())
    if result.returncode != 0 or problems:
        print(f"FAILED: {len(problems)} unresolved ({result.returncode=})")
        return 1
    print(f"{os.path.basename(library)}: every symbol resolves (driver: the stub in {stubFolder})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2] if len(sys.argv) > 2 else ""))

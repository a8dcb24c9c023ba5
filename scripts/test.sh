#!/usr/bin/env bash
# Build openmm-rigid and run every test, from a clean checkout on a Debian machine with python3,
# cmake and g++. Everything else (openmm, SWIG, scikit-build-core, numpy, pytest, ...) comes from
# PyPI into .venv. Exits non-zero if the build or any test fails.
#
#   bash scripts/test.sh
#
# Steps: .venv (created if missing) -> pip install ".[test]" (the wheel: SWIG module + package)
# -> C++ tests in build/ctest against the venv's OpenMM -> ctest -> pytest tests/python.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1

# Install a Debian package, only as root and only when something is missing.
aptInstall() {
    if [[ $(id -u) -ne 0 ]] || ! command -v apt-get >/dev/null; then
        echo "error: $* is needed; install it (e.g. sudo apt-get install $*) and rerun" >&2
        exit 1
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@"
}

# .venv, recreated if a previous attempt left it without a working pip.
if ! .venv/bin/python -m pip --version >/dev/null 2>&1; then
    if ! python3 -c 'import ensurepip, venv' >/dev/null 2>&1; then
        aptInstall python3-venv
    fi
    rm -rf .venv
    python3 -m venv .venv
fi
python=.venv/bin/python

# The SWIG module compiles against Python.h (python3-dev on Debian's own python3).
if ! "$python" -c 'import os, sysconfig, sys; sys.exit(not os.path.exists(os.path.join(sysconfig.get_paths()["include"], "Python.h")))'; then
    aptInstall python3-dev
fi

# The numerics core is also GPU kernel source: tests/core compiles it as OpenCL C with clang and runs
# it on PoCL (OpenCL on the CPU), where these are installed. Installed here as root on Debian; elsewhere
# those tests are left out (TestCoreC, the C99 build of the same text, always runs).
if [[ $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
    missing=()
    for package in clang pocl-opencl-icd ocl-icd-opencl-dev; do
        dpkg -s "$package" >/dev/null 2>&1 || missing+=("$package")
    done
    if (( ${#missing[@]} )); then
        aptInstall "${missing[@]}" || echo "warning: could not install ${missing[*]}; the OpenCL tests of the core are left out" >&2
    fi
fi
# PoCL compiles kernels on first use: keep its cache in the build folder.
export POCL_CACHE_DIR="$repo/build/pocl-cache"
mkdir -p "$POCL_CACHE_DIR"

"$python" -m pip install --upgrade pip
# The build requirements too, so that the quick rebuild `pip install --no-build-isolation .` works.
"$python" -m pip install scikit-build-core "swig>=4.2"
"$python" -m pip install ".[test]"
# The CUDA plugin is built and checked without a GPU (tests/gpu: symbols, loading with the stub driver,
# offline NVRTC compile) where the openmm-cuda-13 wheel brings libOpenMMCUDA.so, cuda.h and NVRTC.
# Optional: without it those checks are left out. Never uninstall it: its RECORD lists
# OpenMM.libs/include, which pip would delete with it.
"$python" -m pip install "openmm-cuda-13==8.6.1" ||
    echo "warning: could not install openmm-cuda-13; the CUDA plugin and its checks are left out" >&2

openmmDir="$("$python" -c 'import importlib.util, os; print(os.path.join(os.path.dirname(importlib.util.find_spec("openmm").submodule_search_locations[0]), "OpenMM.libs"))')"
cmake -S . -B build/ctest -DOPENMM_DIR="$openmmDir" -DBUILD_TESTING=ON -DCMAKE_BUILD_TYPE=Release
cmake --build build/ctest --parallel "$(nproc)"

# Run both suites even if the first fails, so one run reports everything.
status=0
(cd build/ctest && ctest --output-on-failure) || status=1
# From the repository root the source tree holds no importable openmmrigid (the sources are in
# python/), so this tests the installed wheel.
"$python" -m pytest tests/python -q || status=1
# Every validation study's smoke run (tiny systems, a few seconds each): the measuring code runs end to
# end; its output goes to benchmarks/results/quick/, never over the committed summaries and pages.
"$python" benchmarks/run.py all --quick --threads 2 > build/validation-quick.log 2>&1 ||
    { tail -n 60 build/validation-quick.log; status=1; }
bash scripts/docs.sh || status=1  # the manual (docs/), every warning an error
exit "$status"

#!/usr/bin/env bash
# shellcheck disable=SC2317 # setup() and build() run through phase()
# The GPU checks of openmm-rigid in one go, on a machine with an NVIDIA GPU and its driver: from a
# clean checkout on a Debian-like box with python3, cmake and g++ (everything else from PyPI), build
# with CUDA and OpenCL, run the C++ and Python platform tests on CUDA and OpenCL, then the step-cost
# benchmark on CUDA. Sized for 10 minutes; each phase has its own time limit within that.
#
#   bash benchmarks/gpu_check.sh            # logs in $OUT/gpu_check if OUT is set, else build/gpu-check/logs
#
# Environment: OUT (where logs go), BUDGET_S (total seconds, default 570), STEP_COST_ARGS (extra
# arguments for step_cost.py). Exits non-zero if the build failed or any phase failed; summary.txt
# lists each phase with its status and seconds.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"
work="$repo/build/gpu-check"
logs="${OUT:+$OUT/gpu_check}"
logs="${logs:-$work/logs}"
mkdir -p "$work" "$logs"
budget=${BUDGET_S:-570}
deadline=$((SECONDS + budget))
summary="$logs/summary.txt"
: > "$summary"
CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 CMAKE_BUILD_PARALLEL_LEVEL
status=0

# phase NAME LIMIT_S COMMAND...: runs COMMAND with its output in NAME.log, for at most LIMIT_S seconds
# (and never past the deadline, less `reserve` seconds kept for the phases after it).
reserve=0
phase() {
    local name=$1 limit=$2 start=$SECONDS rc=0
    shift 2
    local left=$((deadline - SECONDS - reserve))
    (( limit > left )) && limit=$left
    if (( limit < 10 )); then
        echo "$name: skipped (no time left)" | tee -a "$summary"
        status=1
        return 1
    fi
    echo "== $name (at most ${limit} s)"
    if declare -F "$1" >/dev/null; then  # a function of this script: run it in a bash of its own
        timeout --kill-after=10 "$limit" bash -c "set -euo pipefail; $(declare -f "$1"); $1" > "$logs/$name.log" 2>&1 || rc=$?
    else
        timeout --kill-after=10 "$limit" "$@" > "$logs/$name.log" 2>&1 || rc=$?
    fi
    local result="ok"
    (( rc == 124 || rc == 137 )) && result="TIMED OUT"
    (( rc != 0 && rc != 124 && rc != 137 )) && result="FAILED ($rc)"
    echo "$name: $result, $((SECONDS - start)) s" | tee -a "$summary"
    (( rc == 0 )) || { status=1; tail -n 30 "$logs/$name.log"; return 1; }
}

{ nvidia-smi || echo "no nvidia-smi"; echo; g++ --version | head -1; cmake --version | head -1; python3 --version; nproc; } \
    > "$logs/machine.log" 2>&1 || true

# 1. A virtual environment with the wheels; OpenCL's C headers where apt can bring them (the driver
# brings the NVIDIA OpenCL runtime). Never uninstall openmm-cuda-13: its RECORD lists OpenMM.libs/include.
export python="$work/venv/bin/python" work
setup() {
    [[ -x "$python" ]] || python3 -m venv "$work/venv"
    "$python" -m pip install -q openmm==8.6.1 openmm-cuda-13==8.6.1 numpy scipy mpmath matplotlib pytest \
        "swig>=4.2" scikit-build-core
    if [[ ! -e /usr/include/CL/cl.h && $(id -u) -eq 0 ]] && command -v apt-get >/dev/null; then
        { apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq ocl-icd-opencl-dev; } ||
            echo "warning: no OpenCL headers; the OpenCL plugin is not built"
    fi
    "$python" -c "import openmm; print([openmm.Platform.getPlatform(i).getName() for i in range(openmm.Platform.getNumPlatforms())]); print(openmm.Platform.getPluginLoadFailures())"
}
reserve=420
phase setup 240 setup || exit 1
openmmDir="$("$python" -c 'import importlib.util, os; print(os.path.join(os.path.dirname(importlib.util.find_spec("openmm").submodule_search_locations[0]), "OpenMM.libs"))')"
export openmmDir

# 2. The C++ tests' build (CUDA required, OpenCL where found), then the package and its CUDA wheel
# installed into the venv for the Python tests and the benchmark.
build() {
    cmake -S . -B "$work/build" -DOPENMM_DIR="$openmmDir" -DPython_EXECUTABLE="$python" -DBUILD_TESTING=ON \
          -DOPENMMRIGID_BUILD_CUDA=ON -DOPENMMRIGID_BUILD_OPENCL=AUTO -DCMAKE_BUILD_TYPE=Release
    cmake --build "$work/build"
    "$python" -m pip install --no-build-isolation --no-deps .
    "$python" -m pip install --no-build-isolation --no-deps ./packaging/cuda
    "$python" -c "import openmmrigid, openmm
for name in ('CUDA', 'OpenCL'):
    try:
        print(name, openmm.Platform.getPlatformByName(name).supportsKernels(['IntegrateRigidBodyStep']))
    except Exception as error:
        print(name, 'absent:', error)"
}
reserve=300
phase build 300 build || exit 1

# 3. The platform tests on CUDA and OpenCL: C++ (ctest, by name) and Python (pytest ids name the platform).
reserve=150
phase ctest 240 bash -c "cd '$work/build' && ctest --output-on-failure --no-tests=error -j 4 -R '${CTEST_REGEX:-CUDA|Cuda|OpenCL}'" || true
phase pytest 240 "$python" -m pytest tests/python -q -k "cuda or opencl" -p no:cacheprovider || true

# 4. The step-cost benchmark on CUDA; its results beside the logs.
reserve=0
# shellcheck disable=SC2086 # STEP_COST_ARGS is a list of arguments
phase step_cost 300 "$python" benchmarks/step_cost.py --platform CUDA --precision mixed ${STEP_COST_ARGS:---sizes 2000 20000 --models tip4pew --seconds 1} || true
cp -r benchmarks/results "$logs/results" 2>/dev/null || true
cp docs/results/step_cost_CUDA_mixed.md "$logs/" 2>/dev/null || true   # its results document

cat "$summary"
exit "$status"

#!/usr/bin/env bash
# shellcheck disable=SC2317 # the phase functions run through phase()
# The GPU check of openmm-rigid in one offline call, for a machine with an NVIDIA GPU and no network
# (an offline GPU host, such as one with its own Python 3.12 with numpy, scipy, pytest, cmake, ninja,
# scikit-build-core, g++ and nvcc, and no openmm). Two halves:
#
#   bash scripts/gpu_check.sh fetch   # here, with a network: every wheel the check needs, into .whl/
#   bash scripts/gpu_check.sh         # there, offline: install, build, test, benchmark, report
#
# fetch downloads (pip download --no-deps --only-binary=:all:, for PYTHON_VERSION, default 3.12, and
# manylinux x86_64) openmm==8.6.1, openmm-cuda-13==8.6.1, swig, matplotlib and the packages it needs,
# and mpmath, about 40 MB, into .whl/ (ignored by git; a run on the GPU machine carries it along), and
# copies this machine's OpenCL C headers (/usr/include/CL) there, which the wheel does not ship.
#
# The check (no argument) installs the wheels with pip --no-index --no-deps --target into
# build/gpu-check/site (on PYTHONPATH), keeps every kernel cache in build/gpu-check/cache
# (CUDA_CACHE_PATH, OPENMM_CACHE_DIR, POCL_CACHE_DIR), builds the plugins and the C++ tests (CUDA
# and, where the OpenCL headers and loader are found, OpenCL) and the two wheels, then runs the
# CUDA and OpenCL tests (ctest; pytest -k "cuda or opencl"), ptxas's report of the kernels'
# registers and spills (NVRTC offline, as ctest's CudaKernelsNvrtc compiles them, with
# --ptxas-options=-v: OpenMM passes no compiler options of a plugin's), and the step_cost study on
# CUDA in mixed precision (benchmarks/run.py step_cost: stock Verlet against ours, Exact and
# NoSquish). Where there is no CUDA device, every CUDA step is skipped with a line saying so and the rest must pass (that is how it is rehearsed without a GPU: docs/gpu.md).
#
# Environment: GPU_CHECK_PYTHON (default python3), OUT (results in $OUT/gpu_check, else
# build/gpu-check/results), BUDGET_S (seconds in all, default 480), GPU_CHECK_PYTEST_K (replaces pytest's -k
# selection: a rehearsal on PoCL takes a part of the OpenCL tests). Exits non-zero if a phase failed.
# The results folder holds at most 6 files: gpu_check.md (the results document), summary.txt,
# logs.tar.gz (every phase's log), and the step_cost study's summary and page.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"
wheels="$repo/.whl"

if [[ "${1:-}" == "fetch" ]]; then
    version="${PYTHON_VERSION:-3.12}"
    rm -rf "$wheels"  # one Python version's wheels at a time: they must fit in what is carried along
    mkdir -p "$wheels"
    platforms=()
    for tag in manylinux_2_34_x86_64 manylinux_2_28_x86_64 manylinux_2_17_x86_64 manylinux2014_x86_64; do
        platforms+=(--platform "$tag")
    done
    python3 -m pip download --no-deps --only-binary=:all: --python-version "$version" --implementation cp "${platforms[@]}" \
        -d "$wheels" openmm==8.6.1 openmm-cuda-13==8.6.1 "swig>=4.2" mpmath matplotlib contourpy cycler fonttools \
        kiwisolver pillow pyparsing python-dateutil six
    if [[ -e /usr/include/CL/cl.h ]]; then
        rm -rf "$wheels/opencl-headers"
        mkdir -p "$wheels/opencl-headers"
        cp -r /usr/include/CL "$wheels/opencl-headers/"
    fi
    du -sh "$wheels"
    exit 0
fi
[[ $# -eq 0 ]] || { echo "usage: bash scripts/gpu_check.sh [fetch]" >&2; exit 2; }

python="${GPU_CHECK_PYTHON:-python3}"
work="$repo/build/gpu-check"
logs="$work/logs"
results="${OUT:+$OUT/gpu_check}"
results="${results:-$work/results}"
site="$work/site"
rm -rf "$logs" "$results"
mkdir -p "$work" "$logs" "$results" "$work/cache/cuda" "$work/cache/openmm" "$work/cache/pocl" "$work/tmp"
budget=${BUDGET_S:-480}
deadline=$((SECONDS + budget))
summary="$logs/summary.txt"
: > "$summary"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1 PIP_NO_INDEX=1
export CMAKE_BUILD_PARALLEL_LEVEL="$(nproc)"
export PYTHONPATH="$site${PYTHONPATH:+:$PYTHONPATH}" PATH="$site/bin:$PATH"
export CUDA_CACHE_PATH="$work/cache/cuda" OPENMM_CACHE_DIR="$work/cache/openmm" POCL_CACHE_DIR="$work/cache/pocl"
export TMPDIR="$work/tmp" MPLCONFIGDIR="$work/tmp"
export python site work repo wheels
status=0

# phase NAME LIMIT_S FUNCTION: runs FUNCTION (of this script) in a bash of its own, its output in
# NAME.log, for at most LIMIT_S seconds and never past the deadline less `reserve` seconds kept for
# the phases after it (both sized for the default budget of 480 s, and scaled with BUDGET_S).
reserve=0
phase() {
    local name=$1 limit=$(($2*budget/480)) function=$3 start=$SECONDS rc=0
    local left=$((deadline - SECONDS - reserve*budget/480))
    (( limit > left )) && limit=$left
    if (( limit < 10 )); then
        echo "$name: skipped (no time left)" | tee -a "$summary"
        status=1
        return 1
    fi
    echo "== $name (at most ${limit} s)"
    timeout --kill-after=10 "$limit" bash -c "set -euo pipefail; $(declare -f "$function"); $function" > "$logs/$name.log" 2>&1 || rc=$?
    local result="ok"
    (( rc == 124 || rc == 137 )) && result="TIMED OUT"
    (( rc != 0 && rc != 124 && rc != 137 )) && result="FAILED ($rc)"
    echo "$name: $result, $((SECONDS - start)) s" | tee -a "$summary"
    (( rc == 0 )) || { status=1; tail -n 30 "$logs/$name.log"; return 1; }
}
skip() {
    echo "$1: skipped ($2)" | tee -a "$summary"
}

# Results: whatever happened, the document and the logs are written.
finish() {
    set +e +o pipefail
    {
        echo "# GPU check of openmm-rigid"
        echo
        echo "$(date -u '+%Y-%m-%d %H:%M UTC'); commit $(git -C "$repo" rev-parse --short HEAD 2>/dev/null || echo unknown)" \
             "$(git -C "$repo" diff --quiet 2>/dev/null || echo '(with local changes)'); command: bash scripts/gpu_check.sh"
        echo
        echo '## Machine'
        echo '```'
        cat "$logs/machine.log" 2>/dev/null
        echo '```'
        echo '## Phases'
        echo '```'
        cat "$summary"
        echo '```'
        for name in ctest pytest; do
            [[ -e "$logs/$name.log" ]] || continue
            echo "## $name"
            echo '```'
            grep -E "Test +#|tests passed|tests failed|passed|failed|skipped|SKIPPED|FAILED|Error" "$logs/$name.log" | tail -n 60
            echo '```'
        done
        if [[ -e "$logs/registers.log" ]]; then
            echo '## Registers and spills (ptxas -v, sm_90)'
            echo
            "$python" - "$logs/registers.log" <<'TABLE'
import re, sys
print("| kernel | precision | registers | stack frame (bytes) | spill stores | spill loads |")
print("| --- | --- | --- | --- | --- | --- |")
precision = kernel = None
frame = {}
for line in open(sys.argv[1]):
    if re.match(r"\S+\.cc\s+(single|mixed|double)\s", line):
        precision = line.split()[1]
    elif match := re.search(r"Function properties for (\w+)", line):
        kernel = match.group(1)
    elif (match := re.search(r"(\d+) bytes stack frame, (\d+) bytes spill stores, (\d+) bytes spill loads", line)) and kernel:
        frame[kernel] = match.groups()
    elif (match := re.search(r"Used (\d+) registers", line)) and kernel in frame:
        print(f"| {kernel} | {precision} | {match.group(1)} | " + " | ".join(frame.pop(kernel)) + " |")
        kernel = None
TABLE
        fi
        if [[ -e "$logs/step_cost.log" ]]; then
            echo '## Step cost (CUDA, mixed precision)'
            echo '```'
            grep -v '^\[' "$logs/step_cost.log" | tail -n 40
            echo '```'
        fi
    } > "$results/gpu_check.md"
    cp "$summary" "$results/"
    tar -czf "$results/logs.tar.gz" -C "$work" logs
    for file in benchmarks/data/step_cost.json docs/validation/step_cost.md; do
        [[ -e "$file" ]] && cp "$file" "$results/"
    done
    echo "results in $results:"
    ls "$results"
    cat "$summary"
}
trap finish EXIT

{ nvidia-smi || echo "no nvidia-smi"; echo; g++ --version | head -1; cmake --version | head -1; "$python" --version
  command -v nvcc >/dev/null && nvcc --version | tail -2; echo "$(nproc) cores"; } > "$logs/machine.log" 2>&1 || true

# 1. The wheels, from .whl/ alone (PIP_NO_INDEX), into one folder on PYTHONPATH. libOpenMMCUDA.so
# finds NVIDIA's runtime libraries (cudart, NVRTC, cuFFT) in pip's nvidia packages, which are too
# large to carry: here it takes the CUDA toolkit's, the one nvcc belongs to.
setup() {
    [[ -d "$wheels" ]] || { echo "no $wheels: run 'bash scripts/gpu_check.sh fetch' where there is a network"; exit 1; }
    rm -rf "$site"
    "$python" -m pip install --no-index --no-deps --find-links "$wheels" --target "$site" openmm==8.6.1 openmm-cuda-13==8.6.1 \
        swig mpmath matplotlib contourpy cycler fonttools kiwisolver pillow pyparsing python-dateutil six
    "$python" -c "import openmm; print('OpenMM', openmm.__version__, 'from', openmm.__file__)"
    ldd "$site/OpenMM.libs/lib/plugins/libOpenMMCUDA.so" | grep -E "not found|cudart|nvrtc|cufft|libcuda" || true
}
cudaLibraries=""
if command -v nvcc >/dev/null; then
    toolkit="$(cd "$(dirname "$(command -v nvcc)")/.." && pwd)"
    for folder in "$toolkit/lib64" "$toolkit/targets/x86_64-linux/lib"; do
        [[ -d "$folder" ]] && cudaLibraries="${cudaLibraries:+$cudaLibraries:}$folder"
    done
fi
export LD_LIBRARY_PATH="${cudaLibraries}${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
reserve=400
phase setup 90 setup || exit 1

# Is there a CUDA device? (A Context on the CUDA platform.)
cuda=0
"$python" - > "$logs/cuda_device.log" 2>&1 <<'EOF' && cuda=1
import openmm
print("plugin load failures:", openmm.Platform.getPluginLoadFailures())
platform = openmm.Platform.getPlatformByName("CUDA")
system = openmm.System()
system.addParticle(1.0)
context = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
print("CUDA device:", platform.getPropertyValue(context, "DeviceName"))
EOF
if (( cuda )); then
    grep "CUDA device" "$logs/cuda_device.log" | tee -a "$summary"
else
    echo "no CUDA device here ($(tail -n 1 "$logs/cuda_device.log")): every CUDA step below is skipped" | tee -a "$summary"
fi
export cuda

# 2. The plugins and the C++ tests (CUDA where its headers are found; OpenCL where the OpenCL headers,
# from .whl/opencl-headers if the system has none, and the loader are), then the two wheels, built
# here and unpacked into the same folder as OpenMM (the plugins find it at $ORIGIN/../OpenMM.libs).
build() {
    local options=(-DOPENMM_DIR="$site/OpenMM.libs" -DPython_EXECUTABLE="$python" -DBUILD_TESTING=ON
                   -DOPENMMRIGID_BUILD_CUDA=AUTO -DOPENMMRIGID_BUILD_OPENCL=AUTO -DCMAKE_BUILD_TYPE=Release)
    if [[ ! -e /usr/include/CL/cl.h && -e "$wheels/opencl-headers/CL/cl.h" ]]; then
        local loader
        loader="$(ldconfig -p | awk '/libOpenCL\.so(\.1)? /{print $NF; exit}')"
        [[ -n "$loader" ]] && options+=(-DOpenCL_INCLUDE_DIR="$wheels/opencl-headers" -DOpenCL_LIBRARY="$loader")
    fi
    local generator=()
    command -v ninja >/dev/null && generator=(-G Ninja)
    cmake -S . -B "$work/build" "${generator[@]}" "${options[@]}"
    cmake --build "$work/build"
    rm -rf "$work/dist" "$work/unpacked"
    "$python" -m pip wheel --no-build-isolation --no-deps --no-index . -w "$work/dist"
    if [[ -n "$(find "$work/build" -name libOpenMMRigidCUDA.so -print -quit)" ]]; then
        "$python" -m pip wheel --no-build-isolation --no-deps --no-index ./packaging/cuda -w "$work/dist"
    fi
    "$python" -m pip install --no-index --no-deps --target "$work/unpacked" "$work/dist"/*.whl
    cp -a "$work/unpacked/." "$site/"
    "$python" -c "import openmmrigid, openmm
print('openmmrigid from', openmmrigid.__file__)
for name in ('CUDA', 'OpenCL'):
    try:
        print(name, openmm.Platform.getPlatformByName(name).supportsKernels(['IntegrateRigidBodyStep']))
    except Exception as error:
        print(name, 'absent:', error)"
}
reserve=300
phase build 240 build || exit 1

# 3. The platform tests: ctest by name (the CUDA runs report themselves skipped, 77, without a
# device), pytest by the ids, which name the platform.
ctestRun() {
    local pattern="OpenCL|Cuda"
    (( cuda )) && pattern="CUDA|Cuda|OpenCL"
    cd "$work/build"
    # CudaKernelsNvrtc is the registers phase, with ptxas's report.
    ctest --output-on-failure --no-tests=error -j 4 -R "$pattern" -E CudaKernelsNvrtc
}
pytestRun() {
    local selection="opencl"
    (( cuda )) && selection="cuda or opencl"
    "$python" -m pytest tests/python -q -k "${GPU_CHECK_PYTEST_K:-$selection}" -p no:cacheprovider -rs
}
reserve=200
phase ctest 120 ctestRun || true
(( cuda )) || skip "ctest on CUDA" "no CUDA device; the CUDA plugin's build, load and NVRTC checks ran"
reserve=150
phase pytest 120 pytestRun || true
(( cuda )) || skip "pytest on CUDA" "no CUDA device"

# 4. Registers and spills of every kernel: ctest's own NVRTC compile of the kernel files (the
# CudaKernelsNvrtc test, left out of the ctest phase), with ptxas verbose. Needs no device.
registers() {
    cd "$work/build"
    local command
    command="$(ctest --show-only=json-v1 | "$python" -c "
import json, shlex, sys
tests = [t for t in json.load(sys.stdin)['tests'] if t['name'] == 'CudaKernelsNvrtc']
print(shlex.join(tests[0]['command']) if tests else '')")"
    [[ -n "$command" ]] || { echo "no CudaKernelsNvrtc test (no NVRTC found when configuring)"; exit 1; }
    eval "$command --ptxas-verbose --arch sm_90"
}
reserve=120
phase registers 60 registers || true

# 5. The step cost on CUDA, mixed precision (states prepared on the CPU platform).
stepCost() {
    # The study's own grid (water boxes of 500 to 8000, states equilibrated on the CPU platform); its
    # summary and page come back with the results.
    "$python" benchmarks/run.py step_cost --platform CUDA
}
reserve=0
if (( cuda )); then
    phase step_cost 240 stepCost || true
else
    skip "step_cost on CUDA" "no CUDA device"
fi
exit "$status"

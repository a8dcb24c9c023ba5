#!/usr/bin/env bash
# Build the openmm-rigid-cuda-13 wheel (libOpenMMRigidCUDA.so alone, py3-none-linux_x86_64) into dist/,
# in one command, from a clone of openmm-rigid (see packaging/cuda/README.md):
#
#   bash packaging/cuda/build.sh            # build dist/openmm_rigid_cuda_13-<version>-py3-none-linux_x86_64.whl
#   bash packaging/cuda/build.sh --install  # and install it
#   bash packaging/cuda/build.sh --outdir DIR   # the wheel into DIR instead of dist/
#
# It builds with the Python of $PYTHON, else .venv/bin/python of the clone, else python3, and installs
# into that environment what the build reads, where missing: openmm and openmm-cuda-13 at the pinned
# release (8.6.1: OpenMM's C++ ABI is not stable across releases, so the plugin must be built against
# the OpenMM it will run with) and scikit-build-core. No GPU, driver or nvcc is needed: OpenMM compiles
# the kernels at run time with NVRTC; cuda.h comes with openmm-cuda-13's nvidia-cuda-runtime (or from a
# CUDA toolkit). The CMake build folder is build/cuda-wheel-<tag> (incremental on a rerun).
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
cd "$repo"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1

install=0
outdir=dist
while (( $# )); do
    case "$1" in
        --install) install=1 ;;
        --outdir) outdir="${2:?--outdir needs a folder}"; shift ;;
        -h|--help) sed -n '2,14p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'; exit 0 ;;
        *) echo "error: unknown option $1 (known: --install, --outdir DIR)" >&2; exit 2 ;;
    esac
    shift
done

if [[ -n "${PYTHON:-}" ]]; then
    python="$PYTHON"
elif [[ -x .venv/bin/python ]]; then
    python=.venv/bin/python
else
    python=python3
fi

# The pins, read from packaging/cuda/pyproject.toml's build requirements (one place to change them).
mapfile -t requirements < <("$python" - <<'EOF'
import re
text = open("packaging/cuda/pyproject.toml", encoding="utf-8").read()
requires = re.search(r"^requires\s*=\s*\[(.*?)\]", text, re.M | re.S).group(1)
for requirement in re.findall(r'"([^"]+)"', requires):
    print(requirement)
EOF
)
echo "== $python: making sure the build has ${requirements[*]}"
missing=()
for requirement in "${requirements[@]}"; do
    "$python" - "$requirement" <<'EOF' || missing+=("$requirement")
import re, sys
from importlib.metadata import PackageNotFoundError, version
name, operator, wanted = re.match(r"([A-Za-z0-9_.-]+)\s*(==|>=)?\s*(.*)", sys.argv[1]).groups()
try:
    have = version(name)
except PackageNotFoundError:
    sys.exit(1)
if operator == "==" and have != wanted:
    sys.exit(1)
if operator == ">=":
    parse = lambda text: tuple(int(part) for part in re.findall(r"\d+", text)[:3])
    sys.exit(parse(have) < parse(wanted))
EOF
done
if (( ${#missing[@]} )); then
    echo "== installing ${missing[*]}"
    "$python" -m pip install -q "${missing[@]}"
fi

echo "== building the wheel (CMake folder build/cuda-wheel-*)"
mkdir -p "$outdir"
"$python" -m pip wheel --no-deps --no-build-isolation ./packaging/cuda -w "$outdir"
wheel="$(ls -t "$outdir"/openmm_rigid_cuda_13-*.whl | head -n 1)"
if ! "$python" -m zipfile -l "$wheel" | grep -q "openmmrigid/libOpenMMRigidCUDA.so"; then
    echo "error: $wheel holds no openmmrigid/libOpenMMRigidCUDA.so" >&2
    exit 1
fi
echo "== built $wheel"

if (( install )); then
    echo "== installing $wheel"
    "$python" -m pip install -q --force-reinstall --no-deps "$wheel"
    "$python" -c "
import openmm, openmmrigid
try:
    cuda = openmm.Platform.getPlatformByName('CUDA')
except Exception:
    print('installed; OpenMM has no CUDA platform here (no NVIDIA driver), so the plugin is not loaded')
else:
    print('installed; CUDA platform has the rigid-body kernels:', cuda.supportsKernels(['IntegrateRigidBodyStep']))
"
fi

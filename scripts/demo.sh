#!/usr/bin/env bash
# The main job: rigid TIP4P-Ew water sampled side by side by stock LangevinMiddleIntegrator + SETTLE at
# its accurate step (5 fs) and by RigidBodyLangevinIntegrator with raised moments of inertia at its own
# (12 fs), interleaved so that their costs compare under the same load: ns/day, their ratio, U per
# molecule and the translational and rotational temperatures, and a plot (examples/large_step.py;
# options pass through, e.g. bash scripts/demo.sh --molecules 1000 --time 8).
#
#   bash scripts/demo.sh
#
# openmm-rigid is installed into .venv (created if missing) with the "examples" extra (matplotlib) only
# when the installed build is not that of these sources: a stamp in .venv records a hash of the sources
# the build reads (CMakeLists.txt, pyproject.toml, cmake/, openmmapi/, platforms/, python/,
# serialization/; tracked and untracked files, edits included) and of the installed distribution's
# RECORD, written after a successful install. A second run with nothing changed starts in seconds.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
python=.venv/bin/python
stamp=.venv/.openmm-rigid-demo-stamp

if ! "$python" -m pip --version >/dev/null 2>&1; then
    rm -rf .venv
    python3 -m venv .venv || {
        echo "error: python3 cannot create a virtual environment; install python3-venv and rerun" >&2
        exit 1
    }
    "$python" -m pip install -q --upgrade pip
fi

# The hash of the sources the build reads: names and contents.
sourceHash() {
    local paths=(CMakeLists.txt pyproject.toml cmake openmmapi platforms python serialization)
    {
        if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
            git ls-files -z --cached --others --exclude-standard -- "${paths[@]}"
        else
            find "${paths[@]}" -type f -print0
        fi
    } | sort -z | { xargs -0 -r sha256sum 2>/dev/null || true; } | sha256sum | cut -d' ' -f1
}

# The hash of the installed distribution's RECORD (empty if openmm-rigid is not installed): an install
# by anyone else since the stamp was written changes it.
installedHash() {
    "$python" - <<'EOF' 2>/dev/null || true
import hashlib, importlib.metadata
record = importlib.metadata.distribution("openmm-rigid").read_text("RECORD") or ""
print(hashlib.sha256(record.encode()).hexdigest())
EOF
}

current="source $(sourceHash)"
if [[ -f "$stamp" && "$(cat "$stamp")" == "$current installed $(installedHash)" ]] \
        && "$python" -c "import openmmrigid, matplotlib" >/dev/null 2>&1; then
    echo "== openmm-rigid in .venv is up to date with these sources: no rebuild"
else
    echo "== installing openmm-rigid into .venv (the first time this builds the plugin: a few minutes)"
    rm -f "$stamp"
    "$python" -m pip install -q ".[examples]"
    echo "$current installed $(installedHash)" > "$stamp"
fi
echo "== running examples/large_step.py $*"
"$python" examples/large_step.py "$@"

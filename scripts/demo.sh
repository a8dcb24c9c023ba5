#!/usr/bin/env bash
# Install openmm-rigid into .venv (created if missing) and run the main job: rigid TIP4P-Ew water with
# RigidBodyIntegrator next to stock Verlet + SETTLE (examples/rigid_water.py; options pass through).
# The three integrators run interleaved, so their costs are compared under the same load.
#
#   bash scripts/demo.sh
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1

if ! .venv/bin/python -m pip --version >/dev/null 2>&1; then
    rm -rf .venv
    python3 -m venv .venv || {
        echo "error: python3 cannot create a virtual environment; install python3-venv and rerun" >&2
        exit 1
    }
fi
echo "== installing openmm-rigid into .venv (the first time this builds the plugin: a few minutes)"
.venv/bin/python -m pip install -q --upgrade pip
.venv/bin/python -m pip install -q .
echo "== running examples/rigid_water.py $*"
.venv/bin/python examples/rigid_water.py "$@"

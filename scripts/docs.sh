#!/usr/bin/env bash
# Build the manual (docs/, Sphinx) into build/docs/html, every warning an error. Needs the .venv that
# scripts/test.sh makes, with the package installed (the API pages import it); scripts/test.sh runs
# this after the tests.
#
#   bash scripts/docs.sh
#
# Steps: pip install -r docs/requirements.txt into .venv -> the validation figures from their
# summaries (benchmarks/run.py all --report) -> Doxygen (apt-installed as root where it
# is missing) writes the public headers' XML into build/docs/doxygen -> sphinx-build -W --keep-going,
# from a fresh environment, so that every page is read and every warning reported.
set -euo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$repo"
export PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INPUT=1
python=.venv/bin/python

if ! "$python" -c 'import openmmrigid' >/dev/null 2>&1; then
    echo "error: .venv with openmm-rigid installed is needed; run bash scripts/test.sh first" >&2
    exit 1
fi
"$python" -m pip install --quiet -r docs/requirements.txt

# Doxygen reads the C++ headers for the C++ API page (breathe renders its XML).
if ! command -v doxygen >/dev/null; then
    if [[ $(id -u) -ne 0 ]] || ! command -v apt-get >/dev/null; then
        echo "error: doxygen is needed; install it (e.g. sudo apt-get install doxygen) and rerun" >&2
        exit 1
    fi
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq doxygen
fi
rm -rf build/docs/doxygen
mkdir -p build/docs/doxygen
doxygen docs/Doxyfile

# The validation pages' figures, drawn from the committed summaries (benchmarks/data; git ignores them).
"$python" benchmarks/run.py all --report > /dev/null

# -E: read every page (an incremental build reports the warnings of changed pages only); -q: print
# only the warnings.
"$python" -m sphinx -W --keep-going -E -q -b html docs build/docs/html
echo "The manual: $repo/build/docs/html/index.html"

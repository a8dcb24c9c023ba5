#!/usr/bin/env python
"""Build and run the free-rotor cost benchmark (benchmarks/FreeRotorCost.cpp).

Configures the project in build/bench with -DOPENMMRIGID_BUILD_BENCHMARKS=ON and
-DCMAKE_BUILD_TYPE=Release against the OpenMM headers of this interpreter's openmm wheel, builds
FreeRotorCost, runs it pinned to one core (taskset -c 0 where available), prints the table with the
performance goals beside it, and writes docs/results/free_rotor_cost.md and
benchmarks/results/free_rotor_cost.csv. A run takes seconds once built (the build a few minutes).

Goals (per body, one core): an asymmetric top costs at most 500 ns to construct and evolve once, at
most 150 ns to evolve an existing rotor, and at most 300 ns in FreeRotor::advance (construct and
evolve once, fused, with the input checks) and in rigidRotorAdvance ("core-advance": the same without
checks, with the body's kind classified beforehand) and in advanceFreeRotors ("lanes": the same for
four bodies at once, per body, which is what the host platforms' drift calls per group of bodies
and step).

Usage: python benchmarks/free_rotor_cost.py [--no-build] [--core N]
"""

import argparse
import importlib.util
import os
import shutil
import subprocess
import sys

from benchmarking import RESULTS, ROOT, ResultsDocument, machine, say, writeCsv

BUILD = ROOT / "build" / "bench"

# Goals in ns per call for the asymmetric top as FreeRotor's Automatic choice runs it (theta series at
# generic m, elliptic integral near the separatrix). The row with the elliptic integral forced at
# generic m is there for comparison only.
GOALS = {"construct+evolve": 500.0, "evolve": 150.0, "advance": 300.0, "core-advance": 300.0, "lanes": 300.0}
GOAL_KINDS = ("asymmetric", "asymmetric-near-separatrix")


def openmmDir():
    spec = importlib.util.find_spec("openmm")
    if spec is None or not spec.submodule_search_locations:
        sys.exit(f"free_rotor_cost.py: the openmm package is not importable from {sys.executable}")
    return os.path.normpath(os.path.join(spec.submodule_search_locations[0], "..", "OpenMM.libs"))


def build():
    configure = ["cmake", "-S", str(ROOT), "-B", str(BUILD), "-DOPENMMRIGID_BUILD_BENCHMARKS=ON",
                 "-DCMAKE_BUILD_TYPE=Release", f"-DOPENMM_DIR={openmmDir()}", "-DBUILD_TESTING=OFF"]
    subprocess.run(configure, check=True, stdout=subprocess.DEVNULL)
    subprocess.run(["cmake", "--build", str(BUILD), "--target", "FreeRotorCost", "-j", "2"], check=True)


def executable():
    for path in BUILD.rglob("FreeRotorCost*"):
        if path.is_file() and os.access(path, os.X_OK) and path.suffix in ("", ".exe"):
            return path
    sys.exit(f"free_rotor_cost.py: no FreeRotorCost executable under {BUILD}")


def goalFor(kind, mode):
    return GOALS.get(mode) if kind in GOAL_KINDS else None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--no-build", action="store_true", help="run the existing build/bench executable")
    parser.add_argument("--core", type=int, default=0, help="the core to pin to (default 0)")
    args = parser.parse_args()
    if not args.no_build:
        build()
    command = [str(executable())]
    pinned = shutil.which("taskset") is not None
    if pinned:
        command = ["taskset", "-c", str(args.core)] + command
    else:
        print("taskset not found: running unpinned", file=sys.stderr)
    output = subprocess.run(command, check=True, capture_output=True, text=True).stdout

    lines = [line.split(",")[1:] for line in output.splitlines() if line.startswith("CSV,")]
    records = [dict(zip(lines[0], values)) for values in lines[1:]]
    checksum = next((line for line in output.splitlines() if line.startswith("checksum")), "")

    document = ResultsDocument("free_rotor_cost", "Cost of one free-rotor call (C++, one core)",
                               about="Method: the docstrings of `benchmarks/free_rotor_cost.py` and "
                                     "`benchmarks/FreeRotorCost.cpp`.")
    with document.capture():
        say(f"Free rotor cost on {machine()}, {'pinned to core ' + str(args.core) if pinned else 'unpinned'}; "
            f"ns per call, median of {records[0]['repetitions']} repetitions x {records[0]['calls']} calls")
        say()
        say(f"{'kind':<28} {'mode':<17} {'representation':<18} {'median':>8} {'min':>8} {'max':>8}  goal")
        for record in records:
            goal = goalFor(record["kind"], record["mode"])
            median = float(record["median_ns"])
            verdict = "" if goal is None else f"<= {goal:.0f}  {'met' if median <= goal else 'MISSED'}"
            record["goal_ns"] = "" if goal is None else f"{goal:.0f}"
            record["meets_goal"] = "" if goal is None else str(median <= goal).lower()
            say(f"{record['kind']:<28} {record['mode']:<17} {record['representation']:<18} "
                f"{median:8.1f} {float(record['min_ns']):8.1f} {float(record['max_ns']):8.1f}  {verdict}")
        say()
        say(checksum)
    writeCsv(RESULTS/"free_rotor_cost.csv", records)
    document.write()


if __name__ == "__main__":
    main()

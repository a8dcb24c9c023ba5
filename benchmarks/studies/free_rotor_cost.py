"""The cost of one exact free-rotor call (van Zon and Schofield, J. Comput. Phys. 225, 145 (2007)) in C++:
benchmarks/FreeRotorCost.cpp, built in Release with -DOPENMMRIGID_BUILD_BENCHMARKS=ON and run pinned to one core."""

import importlib.util, os, shutil, subprocess
from harness import ROOT, Study, pyplot, say

BUILD, MODES = ROOT/"build"/"bench", ("construct+evolve", "advance", "core-advance", "lanes", "evolve")
GOALS = {(kind, mode): ns for kind in ("asymmetric", "asymmetric-near-separatrix")      # ns per body
         for mode, ns in {"construct+evolve": 500, "evolve": 150, "advance": 300, "core-advance": 300, "lanes": 300}.items()}

def run(env):
    """Build FreeRotorCost (incremental after the first time) and run it, pinned with taskset where there is one; a quick
    run with 256 inputs, 16384 calls and 3 repetitions."""
    libs = os.path.normpath(os.path.join(importlib.util.find_spec("openmm").submodule_search_locations[0], "..", "OpenMM.libs"))
    for arguments in (["-S", ROOT, "-B", BUILD, "-DOPENMMRIGID_BUILD_BENCHMARKS=ON", "-DBUILD_TESTING=OFF", f"-DOPENMM_DIR={libs}",
                       "-DCMAKE_BUILD_TYPE=Release", "-DOPENMMRIGID_BUILD_CUDA=OFF", "-DOPENMMRIGID_BUILD_OPENCL=OFF"],
                      ["--build", BUILD, "--target", "FreeRotorCost", "-j", "2"]):
        subprocess.run(["cmake", *arguments], check=True, stdout=subprocess.DEVNULL)
    pinned, quick = shutil.which("taskset") is not None, ["256", "16384", "3"] if env.quick else []
    output = subprocess.run((["taskset", "-c", "0"] if pinned else []) + [BUILD/"benchmarks"/"FreeRotorCost"] + quick, check=True,
                            capture_output=True, text=True).stdout
    say(output)
    rows = [line.split(",")[1:] for line in output.splitlines() if line.startswith("CSV,")][1:]   # kind, mode, representation, ns...
    return dict(pinned=pinned, repetitions=int(rows[0][6]), calls=int(rows[0][7]),
                rows=[dict(kind=k, mode=m, representation=r, ns=[float(v) for v in ns]) for k, m, r, *ns, _, _ in rows])

def report(summary, page):
    ns = {(r["kind"], r["mode"]): r["ns"][0] for r in summary["rows"]}
    goal = lambda r: GOALS.get((r["kind"], r["mode"]))   # noqa: E731
    missed = [f"{r['kind']} {r['mode']}" for r in summary["rows"] if goal(r) and r["ns"][0] > goal(r)]
    page.text(f"A generic asymmetric top costs **{ns['asymmetric', 'lanes']:.0f} ns** per body in `advanceFreeRotors` (bodies in "
              f"vector lanes, the CPU and Reference platforms' call) against {ns['asymmetric', 'core-advance']:.0f} ns in the "
              f"scalar `rigidRotorAdvance` (the GPU kernels' call). Goals missed: {', '.join(missed) or 'none'}. Medians of "
              f"{summary['repetitions']} repetitions of {summary['calls']} calls{'' if summary['pinned'] else ', not pinned'}.")
    page.table(["kind", "mode", "representation", "median ns", "min", "max", "goal", ""],
               [[r["kind"], r["mode"], r["representation"]] + [f"{v:.1f}" for v in r["ns"]]
                + ([f"<= {goal(r)}", "met" if r["ns"][0] <= goal(r) else "**missed**"] if goal(r) else ["", ""])
                for r in summary["rows"]])
    kinds = list(dict.fromkeys(r["kind"] for r in summary["rows"]))
    figure, axes = pyplot().subplots(figsize=(9, 5))
    for offset, mode in enumerate(MODES):
        found = [(kinds.index(r["kind"]) + 0.16*(offset - 2), r["ns"]) for r in summary["rows"] if r["mode"] == mode]
        axes.barh([y for y, _ in found], [n[0] for _, n in found], 0.16, label=mode, error_kw=dict(ecolor="grey"),
                  xerr=[[n[0] - n[1] for _, n in found], [n[2] - n[0] for _, n in found]])
    axes.axvline(300, color="k", ls="--", lw=0.8, label="300 ns goal")
    axes.set(xscale="log", xlabel="ns per call (bars: range of the repetitions)")
    axes.set_yticks(range(len(kinds)), kinds, fontsize=8)
    axes.invert_yaxis()
    axes.legend(fontsize=7)
    page.figure(figure, "calls", "The cost of one free-rotor call by kind of body and entry point.")

STUDY = Study("free_rotor_cost", "Cost of one free-rotor call",
              "Advancing bodies in vector lanes, as the CPU and Reference platforms do, a generic asymmetric top costs about "
              "two thirds of the scalar call of the GPU kernels and meets the 300 ns per body goal that the scalar call misses.",
              report, run=run, method="""
`benchmarks/FreeRotorCost.cpp` (its header says what each mode calls; `construct+evolve` is an integrator's cost per body
and step), 8192 random states per kind, asymmetric tops by their parameter m; the median of 9 repetitions of 131072 calls.""",
              caveats="""
A call in isolation: the machine moves these figures by up to a factor of two, so read rows side by side, not across runs;
the rotor's share of a whole step is the step_cost page's.""")

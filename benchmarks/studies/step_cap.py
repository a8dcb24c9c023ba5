"""What caps the step of rigid water with raised moments: rotation or translation."""

import numpy as np

from harness import Study, pyplot
from studies import _sampling as sampling

STEPS = {"stock": [2], "rigid": [2], "raised-0.04": [14, 16, 18], "raised-0.16": [14, 16, 18], "raised-0.16-mass2": [16, 18, 20, 22, 24],
         "stock-heavy": [12, 14, 16], "stock-heavy-mass2": [14, 16, 18, 20]}
FAMILIES = {"raised moments": ["raised-0.04", "raised-0.16", "raised-0.16-mass2"], "stock, H 4 amu": ["stock-heavy", "stock-heavy-mass2"]}

def measure(job, env):
    return sampling.sample(job["system"], job["config"], job["step"], job["seed"], env, kinetic=True)

def summarize(results, env):
    """Per step the runs pooled, U against the pooled 2 fs runs of stock and rigid; the step at standard masses."""
    rows, keep = sampling.reduce(results), ("system", "config", "step", "runs", "failed", "T", "Ttrans", "Trot", "dU")
    references = {system: {"U": ref["U"]} for system, ref in sampling.compare(rows, ("stock", "rigid"), 2).items()}
    return dict(references=references, rows=[dict({k: r[k] for k in keep if k in r}, failures=int(bool(r["failed"])),
                                                  standardStep=r["step"]/np.sqrt(sampling.CONFIGS[r["config"]].get("masses", 1)))
                                             for r in rows if r["step"] != 2])

def accurate(rows):
    """The largest step at standard masses with every run to it stable and |bias| <= TOLERANCE + one standard error."""
    good = sampling.upTo(rows, lambda r: r["failures"] or abs(r["dU"][0]) > sampling.TOLERANCE + r["dU"][1], "standardStep")
    return good[-1]["standardStep"] if good else None

def report(summary, page):
    rows, references = summary["rows"], summary["references"]
    steps = {s: [accurate([r for r in rows if r["system"] == s and r["config"] in f]) for f in FAMILIES.values()] for s in references}
    page.section("Accurate steps at standard masses", "Masses and moments times k at the step h sqrt(k) are the standard masses at h "
                 "with sqrt(k) times the friction, update by update: mass x2 is a finer grid of steps (floor 0.08 amu nm^2). Accurate: "
                 "every run stable and |bias| <= 0.1 kJ/mol by one standard error, up to that step.")
    page.table(["system"] + [f"{f} (fs)" for f in FAMILIES] + ["ratio"],
               [[s, f"{a:.1f}", f"{b:.1f}", f"{a/b:.2f}"] for s, (a, b) in steps.items() if a and b])
    sampling.runsTable(page, rows, [("standard-mass step (fs)", lambda r: f"{r['standardStep']:.1f}"), ("T reported (K)", "T", 1),
                                    ("T translation (K)", "Ttrans", 1), ("T rotation (K)", "Trot", 1), ("U/water bias", "dU", 3, True),
                                    ("runs failed", lambda r: f"{r['failures']} of {r['runs'] + r['failures']}")])
    figure, axes = pyplot().subplots(2, len(references), figsize=(6*len(references), 8), squeeze=False)
    for column, system in enumerate(references):
        mine = [r for r in rows if r["system"] == system and "Ttrans" in r]
        colors = sampling.biasPanel(axes[0, column], mine, "dU", 0.6, x="standardStep")
        for config in dict.fromkeys(r["config"] for r in mine):
            for key, style in (("Ttrans", "o-"), ("Trot", "s--")):
                axes[1, column].plot(*zip(*[(r["standardStep"], r[key][0]) for r in mine if r["config"] == config]), style,
                                     color=colors[config], label=f"{config}: {key[1:]}")
        axes[0, column].set(title=system, ylabel="U/water - reference (kJ/mol)")
        axes[1, column].set(xlabel="step at standard masses (fs)", ylabel="kinetic temperature (K)")
    axes[0, 0].legend(fontsize=7)
    axes[1, 0].legend(fontsize=6, ncol=2)
    page.figure(figure, "temperatures", "Bias of U (2 sigma) and the translational and rotational temperatures against the step")

STUDY = Study(
    "step_cap", "What caps the step with raised moments: rotation or translation",
    "With raised moments the step of rigid water is capped by translation, not rotation: a four times higher floor cools "
    "the rotation at 16 fs but not the translation, 18 fs fails at any floor, and on a finer grid raised moments stay "
    "accurate to 14 fs (TIP4P-Ew) and 15.6 fs (TIP3P) against stock with heavy hydrogens' 12 and 12.7 fs.",
    report, grid=[dict(system=["tip4pew-nvt", "tip3p-nvt"], config=[c], step=steps, seed=[0, 1, 2]) for c, steps in STEPS.items()],
    quick=[dict(system=["tip3p-nvt"], config=["stock", "rigid"], step=[2]),
           dict(system=["tip3p-nvt"], config=["raised-0.16", "raised-0.16-mass2", "stock-heavy-mass2"], step=[16])],
    measure=measure, summarize=summarize, method="""
500 waters, NVT, 300 K, 1/ps, one motion changed at a time: the floor of the moments from 0.04 to 0.16 amu nm^2
(librations twice as slow again); every mass doubled with that floor (translation sqrt(2) times slower, rotation as is);
the same doubling for stock with water H at 4 amu. Neither mass nor inertia enters the configurational distribution.
Three starts per step, 2 ps discarded, 20 ps sampled every 0.1 ps (`studies/_sampling.py`).""", caveats="""
Doubled masses buy nothing per wall-hour (the dynamics slows as much) and lift stock's heavy hydrogens as much, so 1.3
times stock with heavy hydrogens stays out of reach. What the accuracy check says at these steps: `accuracy_check`.""")

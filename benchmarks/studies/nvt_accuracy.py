"""Configurational accuracy against the step: RigidBodyLangevinIntegrator (Exact, NoSquish) beside LangevinMiddle + SETTLE."""

import numpy as np

from harness import Study, nsPerDay, pyplot
from studies import _sampling as sampling

NAMES, WATER = ["stock", "exact", "nosquish"], [s for s in sampling.SYSTEMS if s != "protein"]
# Water at 1-10 fs, the peptide at 1-6 fs; NoSquish from 4 fs (below, its rotation error is far below the noise).
GRID = [dict(system=WATER, config=NAMES[:2], step=[1, 2, 4, 6, 8, 10]), dict(system=WATER, config=NAMES[2:], step=[4, 6, 8, 10]),
        dict(system=["protein"], config=NAMES[:2], step=[1, 2, 3, 4, 5, 6]), dict(system=["protein"], config=NAMES[2:], step=[4, 5, 6])]

def measure(job, env):
    return sampling.sample(job["system"], job["config"], job["step"], job["seed"], env, time=25.0)

def summarize(results, env):
    """Runs against their system's pooled 1 fs runs of stock and Exact; every stable run timed side by side (9 x 100 steps)."""
    rows = sampling.reduce(results)
    references, timing = sampling.compare(rows, ("stock", "exact"), 1), []
    for system in references:
        stable = {(r["config"], r["step"]): (r["config"], r["step"]) for r in rows if r["system"] == system and not r["failed"]}
        times = sampling.timeSteps(system, stable, env, *((10, 3) if env.quick else (100, 9)))
        timing += [dict(system=system, config=c, step=s, msPerStep=ms) for (c, s), ms in times.items() if ms]
    return dict(references=references, rows=rows, timing=timing)

def agrees(row):
    """Within 2 combined standard errors of the reference in U (and, NPT, density); 1 fs is the reference."""
    return not row["failed"] and (row["step"] == 1 or all(abs(row[k][0]) < 2*row[k][1] for k in ("dU", "ddensity") if k in row))

def largest(rows, strict=True):
    """The largest step that agrees, with every smaller step agreeing too (strict), or whatever they gave."""
    steps = [r["step"] for r in (sampling.upTo(rows, lambda r: not agrees(r)) if strict else rows) if agrees(r)]
    return max(steps, default=None)

def pooledBoxes(rows):
    """Deviations averaged over the water boxes (density: NPT ones), error sqrt(sum sigma^2)/n; unstable in a box: unstable."""
    boxes, entries = [s for s in dict.fromkeys(r["system"] for r in rows) if s != "protein"], []
    for config, step in dict.fromkeys((r["config"], r["step"]) for r in rows if r["system"] in boxes):
        runs = [next((r for r in rows if (r["system"], r["config"], r["step"]) == (box, config, step)), None) for box in boxes]
        failed = "unstable in a box" if any(r is None or r["failed"] for r in runs) else None
        entries.append(dict(system="pooled", config=config, step=step, failed=failed, runs=0 if failed else len(boxes), **{} if failed else {
            k: sampling.pooled([r for r in runs if k in r], k) for k in ("dU", "dT", "ddensity", "dgShell") if any(k in r for r in runs)}))
    return boxes, entries

def report(summary, page):
    rows, timing, references = summary["rows"], summary["timing"], summary["references"]
    (boxes, pooled), table = pooledBoxes(rows), []
    speed = lambda system, config, step: next((nsPerDay(step, t["msPerStep"]/1000) for t in timing
                                               if (t["system"], t["config"], t["step"]) == (system, config, step)), None)
    for system, strict in [(s, True) for s in references] + [("pooled", True), ("pooled", False)]:
        where = boxes if system == "pooled" else [system]
        best = {c: largest([r for r in pooled + rows if (r["system"], r["config"]) == (system, c)], strict) for c in NAMES}
        ratio = {c: [speed(b, c, best[c])/speed(b, "stock", best["stock"]) for b in where
                     if speed(b, c, best[c]) and speed(b, "stock", best["stock"])] for c in NAMES}
        def cell(c):
            text = (f"{best[c]:g} fs" if best[c] else "none") + (f", {speed(system, c, best[c]):.1f} ns/day" if speed(system, c, best[c]) else "")
            if c != "stock" and ratio[c] and len(ratio[c]) == len(where):
                text += f", **{np.mean(ratio[c]):.2f}x**" + (f" ({min(ratio[c]):.2f} to {max(ratio[c]):.2f})" if len(where) > 1 else "")
            return text
        table.append([system + ("" if strict else ", smaller steps not required")] + [cell(c) for c in NAMES])
    page.section("ns/day at equal accuracy", "Each integrator's largest step agreeing with the 1 fs reference (every smaller step "
                 "agreeing too, unless said), its ns/day and, bold, that over stock's at stock's own such step; pooled over the "
                 f"{len(boxes)} water boxes: the mean of their ratios (their range). Goals: 1.5x in water, 1.25x with the peptide.")
    page.table(["system"] + NAMES, table)
    page.section("Every run", "Deviations from each system's reference (its 1 fs runs pooled: \"reference\"), and averaged over the "
                 "water boxes (\"pooled\").")
    sampling.runsTable(page, [dict(ref, system=s, config="reference", step=1, failed=None) for s, ref in references.items()] + pooled + rows,
                       [("U/water (kJ/mol)", "U", 3), ("dU/water", "dU", 3, True), ("density (g/mL)", "density", 4),
                        ("d density", "ddensity", 4, True), ("T reported (K)", "T", 1), ("dT", "dT", 1, True), ("g_OO shell", "gShell", 3),
                        ("d g_OO shell", "dgShell", 3, True), ("agrees", lambda r: "ref" if r["step"] == 1 else "yes" if agrees(r) else "no")])
    figure, axes = pyplot().subplots(2, len(references) + 1, figsize=(3.4*len(references) + 3.4, 6.5), squeeze=False)
    for column, system in enumerate(list(references) + ["pooled"]):
        for row, (key, cap, label) in enumerate((("dU", 1.0, "U/water (kJ/mol)"), ("dT", 15.0, "T reported (K)"))):
            sampling.biasPanel(axes[row, column], [r for r in pooled + rows if r["system"] == system], key, cap, spread=0.12)
            axes[row, column].set(title=system, xlabel="step (fs)", ylabel=f"{label} - reference")
    axes[0, 0].legend(fontsize=7)
    page.figure(figure, "deviations", "Deviations from the 1 fs reference against the step (2 sigma; triangles at an edge: off scale, see the table)")

STUDY = Study(
    "nvt_accuracy", "Configurational accuracy against the step (NVT and NPT)",
    "Pooled over four water boxes, RigidBodyLangevinIntegrator keeps the 1 fs potential energy up to 8 fs, where stock "
    "LangevinMiddleIntegrator + SETTLE reads 0.2 kJ/mol per water high, for about 1.1 times stock's ns/day at equal "
    "accuracy: the goal of 1.5 is not met, nor 1.25 with the solvated peptide, whose bonds cap both integrators at 5 fs.",
    report, grid=GRID, quick=[dict(system=WATER[:2], config=NAMES[:2], step=[1, 4]), dict(system=WATER[:2], config=NAMES[2:], step=[4])],
    measure=measure, summarize=summarize, method="""
Integrators: stock, LangevinMiddleIntegrator + SETTLE; exact and nosquish, RigidBodyLangevinIntegrator. Systems
(`studies/_sampling.py`): 500 rigid TIP3P or TIP4P-Ew waters (amber14, PME 0.9 nm; NPT: 1 bar, barostat every 25 steps)
and protein (alanine dipeptide in 500 TIP3P waters, HBonds, HMR 3 amu, NPT); 300 K, 1/ps. From one NPT-equilibrated state
per model each run discards 2 ps and samples 25 ps every 0.1 ps; standard errors of block means. A run agrees with the
pooled 1 fs runs of stock and exact when its U (NPT: and density) is within 2 combined standard errors.""", caveats="""
- The resolution is about 0.1 kJ/mol per water (2 sigma) only pooled over the boxes; per box it is 0.10 to 0.31 kJ/mol
  and 0.004 to 0.01 g/mL, and the rule falls to single 2-3 sigma fluctuations: the per-box ratios measure noise.
- Exact and NoSquish are not told apart up to 8 fs: in these liquids the forces limit the step, not the rotation.
- With the peptide all runs at 2 to 5 fs read 0.1 to 0.2 kJ/mol lower and up to 0.008 g/mL denser than at 1 fs, also
  with new seeds: the step (the barostat's 25-step interval) or a slow density drift, left open.
- Timed at one thread on a shared 2-core machine: costs per step scatter by about 20 %.""")

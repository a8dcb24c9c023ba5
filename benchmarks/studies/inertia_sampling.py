"""ns/day at equal configurational accuracy with the moments of inertia of rigid water raised."""

import numpy as np

from harness import Study, nsPerDay, pm, pyplot
from studies import _sampling as sampling

STEPS = {"stock": [2, 4, 6, 8, 10], "stock-heavy": [4, 8, 10, 12, 14], "rigid": [2, 4, 6, 8, 10],
         "raised-0.04": [4, 8, 12, 14, 16, 18], "raised-0.08": [4, 8, 12, 14, 16, 18]}

GRID = [dict(system=[s for s in sampling.SYSTEMS if s != "protein"], config=[c], step=steps, seed=range(6)) for c, steps in STEPS.items()]
GRID += [dict(system=["protein"], config=list(STEPS), step=[2, 3, 4, 5], seed=range(6))]     # the peptide's bonds cap every step

def measure(job, env):
    return sampling.sample(job["system"], job["config"], job["step"], job["seed"], env, dynamics=True)

def analyse(rows):
    """Fits of one system's rows: bias(h) = a h^2 + b h^4 (a Langevin splitting's leading configurational errors), weighted,
    through the steps stable from every start up to the first beyond the tolerance by 2 sigma; the accurate step: the
    largest h (0.1 fs apart, to the last of those) with |fit| <= TOLERANCE; D, tauRot, tauU: the means of the rows to it
    (properties of the dynamics, which the step changes little; one run's tauU scatters by a factor 2)."""
    fits = {}
    for config in dict.fromkeys(r["config"] for r in rows):
        mine = [r for r in rows if r["config"] == config]
        points = sampling.upTo(mine, lambda r: r["failed"] or r["runs"] < mine[0]["runs"])
        kept = sampling.upTo(points, lambda r: abs(r["dU"][0]) > sampling.TOLERANCE + 2*r["dU"][1])
        fit, accurate = [0.0, 0.0], None
        if kept:
            h, (bias, error) = np.array([r["step"] for r in kept], float), np.array([r["dU"] for r in kept]).T
            design = np.stack([h**2, h**4], 1)[:, :len(h)]/error[:, None]      # one point: a h^2 alone
            fit = list(np.linalg.lstsq(design, bias/error, rcond=None)[0]) + [0.0]*(len(h) < 2)
            grid = np.arange(1.0, h.max() + 1e-9, 0.1)
            beyond = np.abs(fit[0]*grid**2 + fit[1]*grid**4) > sampling.TOLERANCE
            first = int(np.argmax(beyond)) if beyond.any() else len(grid)
            accurate = round(float(grid[first - 1]), 1) if first else None
        near = [r for r in points if accurate and r["step"] <= accurate] or points[:1]
        fits[config] = dict(fit=fit, accurate=accurate, starts=mine[0]["runs"], **{k: float(np.mean([r.get(k) for r in near],
                            dtype=float)) if near else None for k in ("D", "tauRot", "tauU")})
    return fits

def summarize(results, env):
    """Rows against each system's pooled 2 fs runs of stock and rigid, the fits, and the accurate steps rounded down timed
    side by side in two Contexts each (7 x 100 steps)."""
    rows = sampling.reduce(results)
    summary = dict(rows=rows, references=sampling.compare(rows, ("stock", "rigid"), 2), fits={}, timing=[])
    for system in summary["references"]:
        fits = summary["fits"][system] = analyse([r for r in rows if r["system"] == system])
        steps = {c: (c, int(f["accurate"])) for c, f in fits.items() if f["accurate"]}
        times = sampling.timeSteps(system, steps, env, *((10, 3) if env.quick else (100, 7)), contexts=2)
        summary["timing"] += [dict(system=system, config=c, step=steps[c][1], msPerStep=ms) for c, ms in times.items() if ms]
    [row.pop(key, None) for row in rows for key in ("D", "tauRot", "tauU")]      # their means to the accurate step: the fits'
    return summary

def report(summary, page):
    rows, timing, table, hourly = summary["rows"], summary["timing"], [], []
    figure, axes = pyplot().subplots((len(summary["fits"]) + 2)//3, 3, figsize=(14, 4*((len(summary["fits"]) + 2)//3)), squeeze=False)
    for axis, (system, fits) in zip(axes.flat, summary["fits"].items()):
        mine, timed = [r for r in rows if r["system"] == system], {t["config"]: t for t in timing if t["system"] == system}
        speed = {c: nsPerDay(int(f["accurate"]), timed[c]["msPerStep"]/1000) for c, f in fits.items() if c in timed and f["accurate"]}
        versus = lambda c, base: f"{speed[c]/speed[base]:.2f}" if c in speed and base in speed else "-"
        for c, f in fits.items():
            step = int(f["accurate"] or 0)
            table.append([system, c, f["starts"], f"{f['accurate'] or 0:g}"] + ([f"{step}" + (f" (*{timed[c]['step']})" if timed[c]["step"] != step
                          else ""), f"{timed[c]['msPerStep']:.2f}", f"{speed[c]:.1f}"] if c in speed else ["-"]*3)
                         + [versus(c, "stock"), versus(c, "stock-heavy")])
        dynamics = {c: np.array([fits[c].get(k) for k in ("D", "tauRot", "tauU")], dtype=float) for c in speed}   # None: nan
        rate = {c: np.array([1/(2*tauU), D, 1/tauRot])*speed[c]*1000/24 for c, (D, tauRot, tauU) in dynamics.items()}
        hourly += [[system, c] + [pm([v, None], digits) for v, digits in zip([*dynamics[c], r[0], *r/rate["stock"]],
                   (2, 2, 2, 0, 2, 2, 2))] for c, r in rate.items() if "stock" in rate]
        colors = sampling.biasPanel(axis, [r for r in mine if not r["failed"]], "dU", 0.6)
        for c, f in fits.items():
            grid = np.linspace(0, max([r["step"] for r in mine if r["config"] == c and not r["failed"]] or [0]), 100)
            axis.plot(grid, f["fit"][0]*grid**2 + f["fit"][1]*grid**4, color=colors.get(c), alpha=0.6)
        axis.axhspan(-sampling.TOLERANCE, sampling.TOLERANCE, color="0.9")
        axis.set(title=system, xlabel="step (fs)", ylabel="U/water - reference (kJ/mol)")
    axes[0, 0].legend(fontsize=7)
    [axis.set_visible(False) for axis in axes.flat[len(summary["fits"]):]]
    page.section("ns/day at equal accuracy", "Each configuration's accurate step (the fit's), its cost per step timed side by side "
                 "at that step rounded down (*: at the step given, where the accurate step moved after the timing) and ns/day.")
    page.table(["system", "configuration", "starts", "accurate step (fs)", "timed at (fs)", "ms/step", "ns/day", "vs stock",
                "vs stock heavy-H"], table)
    page.figure(figure, "bias", "Bias of U per water against the step (2 sigma) with the fits (grey: the tolerance; triangles "
                "at an edge: off scale)")
    page.section("Independent samples per wall-hour", "Raised moments slow rotation and diffusion: D, tau_1 and tau_U (means of "
                 "the runs to the accurate step), U samples per wall-hour (simulated ps/h over 2 tau_U) and, relative to stock, the "
                 "independent samples of U, the diffusion distance D t and the rotations t/tau_1 per wall-hour.")
    page.table(["system", "configuration", "D (1e-5 cm^2/s)", "tau_1 (ps)", "tau_U (ps)", "U samples/h", "vs stock: U samples",
                "D t", "rotations"], hourly)
    page.section("Every run", "Means over the starts against each system's reference, its 2 fs runs of stock and rigid pooled ("
                 + "; ".join(f"{s} {pm(ref['U'], 3)} kJ/mol" for s, ref in summary["references"].items()) + ").")
    sampling.runsTable(page, rows, [("U/water (kJ/mol)", "U", 3), ("bias", "dU", 3, True), ("g_OO shell", "gShell", 3),
                                    ("its bias", "dgShell", 3, True), ("T (K)", "T", 1)])

STUDY = Study(
    "inertia_sampling", "Sampling speed with raised moments of inertia",
    "Raising the moments of inertia of rigid water to 0.04 or 0.08 amu nm^2 takes RigidBodyLangevinIntegrator from 7 to "
    "8 fs to 14 fs at equal accuracy in NVT: 2.24 times stock's ns/day in TIP4P-Ew (1.15 times stock with 4 amu hydrogens), "
    "1.57 to 1.66 times in TIP3P (1.04 to 1.11); with the solvated peptide, whose bonds cap every configuration, no gain.",
    report, grid=GRID,
    quick=dict(system=["tip3p-nvt"], config=["stock", "rigid", "raised-0.04"], step=[2, 8], seed=[0, 1]),
    measure=measure, summarize=summarize, method="""
The systems of `nvt_accuracy`; stock LangevinMiddle + SETTLE (stock-heavy: water H at 4 amu, the O lighter by as much),
RigidBodyLangevinIntegrator with standard moments (rigid) and setMinimumMomentOfInertia(0.04, 0.08 amu nm^2). Each seed
is an independent start; each run draws velocities for its masses and moments, discards 2 ps and samples 20 ps every 0.1
ps. Tolerance: 0.1 kJ/mol per water, the spread of independent 20 ps runs. Per run, from the samples: D, the slope of the
oxygens' mean-square displacement over lags of 1 to 5 ps over 6; tau_1, exp(-t/tau_1) fitted to the dipole axes' C_1(t) where
0.15 < C_1 < 0.85; tau_U, U's integrated autocorrelation time (Sokal's window, c = 5).""", caveats="""
- NPT is not resolved by two to six starts: run means scatter with the volume (up to 1.75 times the block errors, which
  hold in NVT), and TIP4P-Ew NPT reads stock-heavy and raised moments low from dips of 0.12-0.16 kJ/mol at middle steps
  that come back at larger ones. Every point shares the reference's error; a point known to 0.03 kJ/mol takes 20 runs.
- Raised moments slow the dynamics, so ns/day overstates the gain in independent samples; the rates per wall-hour have no
  error bars (one run's tau_U scatters by a factor 2; each is a mean over 2 to 6 starts and a few steps). A step at 13-14
  fs costs 5 to 12 % more than stock's at 5-8 fs (OpenMM's neighbour list); two timings hours apart differ by up to 8 %.""")

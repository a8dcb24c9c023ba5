"""Energy conservation of rigid water (NVE) over steps and splittings (docs/theory/splittings.md), against stock."""
import math, time
import numpy as np, openmm
import openmmrigid, rigidtesting, setups
from harness import FORCE_EVALUATIONS, Study, Unstable, nsPerDay, pyplot, slopeError

BOXES = {"tip3p-500": ("tip3p", 500, 20.0), "spce-500": ("spce", 500, 20.0), "tip4pew-500": ("tip4pew", 500, 20.0),
         "tip4pew-2000": ("tip4pew", 2000, 4.0), "tip3p-216": ("tip3p", 216, 0.5)}  # model, waters, ps per run
METHODS = {"stock": (None, "Verlet"), "Exact": ("exact", "Verlet"), "NoSquish": ("nosquish", "Verlet"),
           **{name: ("exact", name) for name in ("Omelyan2", "Yoshida4", "Omelyan4")}}  # rotation, splitting

def rigidStart(built, name, env, picoseconds, seed):
    """The start (setups.start) made rigid to 1e-10, so that E(0) is the energy of what every method integrates."""
    context = openmm.Context(built.system, openmm.VerletIntegrator(0.001), env.platform, env.properties)
    context.setState(setups.start(name, built, env.platform, env.properties, picoseconds=picoseconds, seed=seed + 1))
    context.applyConstraints(1e-10)
    context.applyVelocityConstraints(1e-10)
    return context.getState(getPositions=True, getVelocities=True)

class Trajectory:
    """One NVE run: the total energy at each sample, the wall time of the step calls but the first (it sets the Context
    up), and why it stopped: an exception, a non-finite energy or |E - E0| above `limit` kJ/mol."""
    def __init__(self, built, integrator, state, env, stepFs, limit):
        self.integrator, self.stepFs, self.limit, self.seconds, self.timed = integrator, stepFs, limit, 0.0, 0
        self.context = setups.context(built, integrator, state, env.platform, env.properties)
        self.times, self.energies, self.failure, self.steps = [], [], None, 0
        self.advance(0)
    def advance(self, steps):
        """`steps` steps, then a sample; False once the run has failed (self.failure says when and why)."""
        start, energy = time.perf_counter(), math.nan
        try:
            self.integrator.step(steps)
            seconds, state = time.perf_counter() - start, self.context.getState(getEnergy=True)
            energy = (state.getPotentialEnergy() + state.getKineticEnergy()).value_in_unit(setups.KJ)
        except openmm.OpenMMException as error:
            self.failure = str(error).splitlines()[0][:70]
        self.steps += steps
        if self.failure is None and abs(energy - (self.energies or [energy])[0]) <= self.limit:   # not NaN
            if len(self.times) > 1:
                self.seconds, self.timed = self.seconds + seconds, self.timed + steps
            self.times.append(self.steps*self.stepFs/1000)
            self.energies.append(energy)
            return True
        self.failure = f"blew up at {self.steps*self.stepFs/1000:.2f} ps: {self.failure or '|E - E0| above the limit'}"
        return False
    def result(self, dof):
        """Drift per degree of freedom and fluctuation (rigidtesting.energyDrift), the drift's error from 10 block means."""
        if self.failure or len(self.times) < 3:
            return dict(failed=self.failure or "too short")
        drift, fluctuation = rigidtesting.energyDrift(self.times, self.energies, dof)
        return dict(drift=drift, driftError=slopeError(self.times, self.energies)*1000/dof, fluctuation=fluctuation,
                    nsPerDay=nsPerDay(self.stepFs, self.seconds/self.timed), failed=None)

def measure(job, env):
    (model, molecules, picoseconds), step, (rotation, splitting) = BOXES[job["box"]], job["step"], METHODS[job["method"]]
    built = setups.water(model, molecules)
    state = rigidStart(built, f"energy_drift-{job['box']}-{job['seed']}", env, 0.2 if env.quick else 5.0, job["seed"])
    integrator = setups.makeIntegrator("rigid-verlet" if rotation else "stock-verlet", step, rotation=rotation,
                                        splitting=splitting if rotation else None)   # SETTLE: exact at any tolerance
    run = Trajectory(built, integrator, state, env, step, 1.0*molecules)   # blown up: ~13 K of heating
    while run.steps*step < 1000*picoseconds and run.advance(max(1, round(min(48, 40*picoseconds)/step))):
        pass   # a sample every ~48 fs, at least 25 a run
    if run.failure:
        raise Unstable(run.failure)
    return dict(run.result(rigidtesting.degreesOfFreedom(built.system)), seed=job["seed"])

def atFluctuation(points, level):
    """(ns/day, step): the most ns/day of a method's runs, points [(fluctuation, ns/day, step)], at fluctuation <= level:
    log ns/day and log step linear in log fluctuation between steps that bracket it, or a measured step; no extrapolation."""
    points = sorted(points, key=lambda point: point[2])
    found = [(speed, step) for fluctuation, speed, step in points if fluctuation <= level]
    for (f0, n0, s0), (f1, n1, s1) in zip(points, points[1:]):
        if f0 <= level <= f1 and f1 > f0:
            w = math.log(level/f0)/math.log(f1/f0)
            found.append((n0**(1 - w)*n1**w, s0**(1 - w)*s1**w))
    return max(found, default=None)

def equalAccuracy(results):
    """Per box, start and stock step up to 4 fs: the method (and step) with most ns/day at stock's fluctuation."""
    runs, rows = {}, []
    for result, sample in [(result, sample) for result in results for sample in result["samples"]]:
        runs.setdefault((result["job"]["box"], sample["seed"]), {}).setdefault(result["job"]["method"], []).append(
            (sample["fluctuation"], sample["nsPerDay"], result["job"]["step"]))
    for (box, seed), methods in runs.items():
        for level, speed, step in sorted(point for point in methods.get("stock", []) if point[2] <= 4):
            best = max([(*atFluctuation(points, level), name) for name, points in methods.items()
                        if name != "stock" and atFluctuation(points, level)], default=(None, None, None))
            rows.append(dict(box=box, seed=seed, stockStep=step, fluctuation=level, stockNsPerDay=speed, best=best[2],
                             bestStep=best[1], bestNsPerDay=best[0], ratio=best[0] and best[0]/speed))
    return rows

def summarize(results, env):
    """Per job, the means over starts; the drift's error the larger of their spread's and their own errors combined."""
    rows = []
    for result in results:
        samples, n = result["samples"], len(result["samples"])
        rows.append(dict(result["job"], starts=n, failed=result["failed"], blocked=result["blocked"]))
        if samples:
            mean = lambda key: float(np.mean([sample[key] for sample in samples]))   # noqa: E731
            spread = np.std([s["drift"] for s in samples], ddof=1)/math.sqrt(n) if n > 1 else 0.0
            rows[-1].update(drift=mean("drift"), fluctuation=mean("fluctuation"), nsPerDay=mean("nsPerDay"),
                            driftError=max(math.sqrt(sum(s["driftError"]**2 for s in samples))/n, spread))
    return {"rows": rows, "equalAccuracy": equalAccuracy(results)}

def cell(row):   # "drift ± error; fluctuation", or why there is none
    if row.get("drift") is None:
        return row["failed"].split(":")[0] if row.get("failed") else "unstable before" if row.get("blocked") else ""
    return (f"{row['drift']:+.3f}" + (f" ± {row['driftError']:.3f}" if row.get("driftError") is not None else "")
            + (f"; {row['fluctuation']:.2f}" if row.get("fluctuation") is not None else ""))

def report(summary, page):
    rows, boxes = summary["rows"], list(dict.fromkeys(row["box"] for row in summary["rows"]))
    plotted = [b for b in boxes if sum(r["box"] == b and r.get("fluctuation") is not None for r in rows) > 1]
    page.section("Drift and fluctuation", "Cells: drift ± its standard error (kJ/mol/ns/dof); fluctuation (kJ/mol), whose "
                 "floor is the potential's (the Ewald term cut off at 0.9 nm). Above it the Verlet splittings' grows as the "
                 "step squared (the error of splitting the forces, not of the rotation); Omelyan2's stays at it to 6-8 fs.")
    figure, axes = pyplot().subplots(2, len(plotted), figsize=(3.6*len(plotted), 6.4), squeeze=False)
    for box in boxes:
        mine = {(r["method"], r["step"]): r for r in rows if r["box"] == box}
        methods, steps = [m for m in METHODS if any(m == k[0] for k in mine)], sorted({s for _, s in mine})
        page.text(f"{BOXES[box][1]} waters of {BOXES[box][0]} ({box}), {BOXES[box][2]:g} ps per run:")
        page.table(["step (fs)"] + methods, [[f"{s:g}"] + [cell(mine.get((m, s), {})) for m in methods] for s in steps])
        if box not in plotted:
            continue
        column = plotted.index(box)
        for method in methods:
            done = [mine[m, s] for m, s in sorted(mine) if m == method and mine[m, s].get("drift") is not None]
            style = dict(marker="o", ms=3, color=f"C{list(METHODS).index(method)}", label=method)
            axes[0][column].errorbar([r["step"] for r in done], [r["drift"] for r in done],
                                     [r.get("driftError") or 0 for r in done], capsize=2, **style)
            done, forces = [r for r in done if r.get("fluctuation")], FORCE_EVALUATIONS[getattr(
                openmmrigid.RigidBodyIntegrator, METHODS[method][1])]
            axes[1][column].plot([1000*forces/r["step"] for r in done], [r["fluctuation"] for r in done], **style)
        axes[0][column].set_yscale("symlog", linthresh=0.1)
        axes[0][column].set(title=box, xlabel="step (fs)", ylabel="drift (kJ/mol/ns/dof)")
        axes[1][column].set(xlabel="force evaluations per ps", ylabel="fluctuation (kJ/mol)", **(dict(
            xscale="log", yscale="log") if any(r.get("fluctuation") for r in mine.values()) else {}))
        axes[1][column].minorticks_off()
    axes[0][0].legend(fontsize=7)
    page.figure(figure, "drift", "Drift (linear within ±0.1); fluctuation against force evaluations per ps")
    page.section("Which splitting for a given accuracy", "The fastest method at stock's fluctuation (J/mol per molecule).")
    page.table(["box", "start", "stock step", "fluctuation", "stock ns/day", "best (step)", "its ns/day", "ratio"],
               [[r["box"], r["seed"] + 1, f"{r['stockStep']:g} fs", f"{1000*r['fluctuation']/BOXES[r['box']][1]:.2f}",
                 f"{r['stockNsPerDay']:.1f}"] + ([f"{r['best']} ({r['bestStep']:.1f} fs)", f"{r['bestNsPerDay']:.1f}",
                                                 f"{r['ratio']:.2f}"] if r["best"] else ["none", "", ""])
                for r in summary["equalAccuracy"]])

STUDY = Study(
    "energy_drift", "Energy conservation against stock Verlet + SETTLE",
    "Up to 6 fs, rigid water moved by `RigidBodyIntegrator` (Exact or NoSquish rotation) conserves the energy as well "
    "as stock `VerletIntegrator` + SETTLE (drift within ±0.1 kJ/mol/ns per degree of freedom), stays stable longer at "
    "7 and 8 fs, and with the `Omelyan2` splitting at 6 fs reaches about stock's accuracy at 1 to 2 fs.", report,
    method="""Rigid water (`setups.water`: amber14 TIP3P, SPC/E, TIP4P-Ew; PME 0.9 nm, Ewald tolerance 5e-4), equilibrated
once per start, made rigid to 1e-10; from it every method runs NVE at each step in its own Context: stock
`VerletIntegrator` + SETTLE, `RigidBodyIntegrator` with Exact or NoSquish rotation, and its splittings Omelyan2, Yoshida4,
Omelyan4 (2, 3, 4 force evaluations a step) with Exact rotation. A series stops at its first unstable step (an exception,
a non-finite energy or |E - E0| above 1 kJ/mol per molecule). Drift: slope of a line fitted to the total energy (every
~48 fs) per degree of freedom (2997 for 500 waters), its error that of the line through 10 block means; fluctuation: the
standard deviation about it; ns/day of the step calls.""",
    caveats="""ns/day of runs one after another on a shared machine: rough ratios (side by side: step_cost). Block
errors of runs a few ps long are too small. Below the potential's floor (a tighter `ewaldErrorTolerance`) the
higher-order splittings would separate further: not shown. Water alone, NVE, CPU; a protein: hmr_schemes.""",
    grid={"box": ["tip3p-500", "spce-500", "tip4pew-500", "tip4pew-2000"], "method": list(METHODS),
          "step": [1, 2, 3, 4, 5, 6, 7, 8, 10, 12], "seed": [0, 1]},
    quick={"box": ["tip3p-216"], "method": ["stock", "Exact", "Omelyan2"], "step": [2, 4], "seed": [0]},
    measure=measure, summarize=summarize)

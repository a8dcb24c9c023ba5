#!/usr/bin/env python
"""Wall time per step of RigidBodyIntegrator next to stock VerletIntegrator + SETTLE on one platform
(CPU by default; --platform OpenCL or CUDA, in --precision single, mixed or double).

Part 1, water boxes: TIP3P and TIP4P-Ew boxes (openmm.app, PME, cutoff 0.9 nm, rigid water) of 500,
2000 and 8000 molecules, each minimized and briefly equilibrated with a stock Langevin integrator.
From that one state, three Contexts are created once each: stock VerletIntegrator + SETTLE,
RigidBodyIntegrator (Exact) and RigidBodyIntegrator (NoSquish), all at 2 fs. After a warm-up block
each, blocks of `integrator.step(n)` are timed with time.perf_counter(), interleaved (A B C A B C ...);
nothing else is inside the timed region. Reported: the median ms/step of each and its ratio to stock.
The accuracy check stays on, its default: its episodes cost within noise of a step without it,
docs/results/accuracy_check_cost.md.

Part 2, the integrator alone: Systems of N (8000) rigid bodies with no forces at all (a System with
particles and, for water, its constraints: the cheapest force evaluation there is; a zero-energy
CustomExternalForce would still loop over the particles),
random orientations, velocities from setVelocitiesToTemperature(300 K). Body kinds: water (TIP3P
geometry, asymmetric, bodies found from the constraints) and, as explicit bodies, linear CO2 (3
collinear particles), a spherical CH4-like top (centre + 4 tetrahedral H), a symmetric NH3-like top
(4 particles) and single particles. Reported: median ns/body/step for Exact and NoSquish, the accuracy
check off: with no forces its episodes' kinetic-energy sums are no longer within noise (x1.12 to 1.37
of such a step on one CPU thread), and a timing from a fresh Context is all episode (interleaved
with stock VerletIntegrator on the same System, shown for scale only) and Exact/NoSquish. This
includes the fixed cost of a step (the Python call, an empty force evaluation), spread over N bodies;
the kinds of the integrator's bodies (benchmarking.bodyKind, from the moments of the positions given)
are checked and written to the CSV.

On the CPU platform both parts run with one thread and with its default thread count (property
Threads); on a GPU platform in the one precision asked for (mixed by default, as OpenMM users run).
The states are prepared on the CPU platform either way.

    python benchmarks/step_cost.py            # full: about 15 to 18 minutes on 2 cores
    python benchmarks/step_cost.py --quick    # small sizes, short blocks: under 2 minutes
    python benchmarks/step_cost.py --platform OpenCL --sizes 2000 --models tip4pew --only boxes

Writes docs/results/step_cost.md (the tables, with the command; a --quick run writes
benchmarks/results/step_cost.md instead), and benchmarks/results/step_cost.csv, integrator_only.csv, step_cost.png and step_cost.log
(a copy of what is printed); on a GPU platform with its name and precision in each file name
(step_cost_OpenCL_mixed.md, ...).
"""

import argparse
import datetime
import math
import statistics
import sys
import time

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from benchmarking import (RESULTS, ResultsDocument, blockSteps, bodyKinds, header, loadAverage, machine, medianRange, openLog,
                          pyplot, say, saveFigure, stamp, timeInterleaved, writeCsv)

plt = pyplot()
import matplotlib.ticker  # noqa: E402 (after pyplot() chose the backend)
import rigidtesting

STEP = 2*unit.femtosecond
PLATFORM_NAME = ["CPU"]  # the platform timed, for the tables (set by main)
CUTOFF = 0.9*unit.nanometer
TEMPERATURE = 300*unit.kelvin
MODEL_NAMES = {"tip3p": "TIP3P", "tip4pew": "TIP4P-Ew"}
STOCK, EXACT, NOSQUISH = "VerletIntegrator+SETTLE", "RigidBodyIntegrator/Exact", "RigidBodyIntegrator/NoSquish"
# With --langevin: the Langevin pair, ours timed against stock LangevinMiddleIntegrator (1/ps, 300 K).
STOCK_LANGEVIN, LANGEVIN = "LangevinMiddleIntegrator+SETTLE", "RigidBodyLangevinIntegrator/Exact"


# ---------------------------------------------------------------------------------------------------
# Machine, options

def printHeader(args):
    for line in header(PLATFORM_NAME[0]):
        say(line)
    say(f"settings: {'quick' if args.quick else 'full'}; step 2 fs; repetitions {args.repetitions}; "
        f"block target {args.seconds:g} s unless --steps; threads {', '.join(args.threads)}")
    say()


def threadProperties(threads):
    """Context properties for a thread count (a 'default' entry has become the platform's default), or
    for a GPU platform (whose 'threads' entry is its precision)."""
    if threads in ("single", "mixed", "double"):
        return {"Precision": threads}
    return {"Threads": threads}


def threadsOf(platform, context):
    """The CPU platform's thread count of a Context, or a GPU platform's precision."""
    if platform.getName() == "CPU":
        return int(platform.getPropertyValue(context, "Threads"))
    return platform.getPropertyValue(context, "Precision")


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="small boxes (250, 500 molecules) and short blocks: under 2 minutes")
    parser.add_argument("--sizes", type=int, nargs="+", help="water molecules per box (default 500 2000 8000)")
    parser.add_argument("--models", nargs="+", choices=sorted(MODEL_NAMES), help="water models (default tip3p tip4pew)")
    parser.add_argument("--repetitions", type=int, default=5, help="timed blocks per integrator (default 5)")
    parser.add_argument("--steps", type=int,
                        help="steps per timed block in the water boxes (default: chosen so a block takes --seconds)")
    parser.add_argument("--body-steps", type=int, help="steps per timed block in part 2 (default: chosen likewise)")
    parser.add_argument("--seconds", type=float,
                        help="target seconds per timed block in the boxes, half that in part 2 (default 2, quick 0.25)")
    parser.add_argument("--threads", nargs="+",
                        help="CPU thread counts; 'default' is the platform's default, Threads as OpenMM "
                             "chooses it (default: 1 default; a count given twice runs once)")
    parser.add_argument("--bodies", type=int, default=8000, help="bodies per kind in part 2 (default 8000)")
    parser.add_argument("--only", choices=["boxes", "bodies"], help="run only part 1 (boxes) or part 2 (bodies)")
    parser.add_argument("--langevin", action="store_true",
                        help="part 1 also times stock LangevinMiddleIntegrator + SETTLE and RigidBodyLangevinIntegrator "
                             "(Exact), the latter's ratio taken to the former")
    parser.add_argument("--platform", default="CPU", choices=["CPU", "OpenCL", "CUDA"],
                        help="the platform of every timed Context (default CPU)")
    parser.add_argument("--precision", default="mixed", choices=["single", "mixed", "double"],
                        help="a GPU platform's precision (default mixed)")
    args = parser.parse_args()
    args.sizes = args.sizes or ([250, 500] if args.quick else [500, 2000, 8000])
    args.models = args.models or ["tip3p", "tip4pew"]
    args.seconds = args.seconds or (0.25 if args.quick else 2.0)
    args.threads = args.threads or ["1", "default"]
    args.equilibrationSteps = 100 if args.quick else 500
    args.minimizeIterations = 100 if args.quick else 200
    for threads in args.threads:
        if threads != "default" and not (threads.isdigit() and int(threads) > 0):
            parser.error(f"--threads: {threads!r} is neither a positive integer nor 'default'")
    if args.repetitions < 5:
        print(f"note: {args.repetitions} repetitions; the benchmark's rule is medians of at least five", file=sys.stderr)
    return args


# ---------------------------------------------------------------------------------------------------
# Part 1: water boxes with PME

def buildBox(model, molecules):
    return rigidtesting.waterBox(model, molecules=molecules, nonbondedCutoff=CUTOFF, ewaldErrorTolerance=5e-4)


def equilibratedState(positions, system, cpu, steps, iterations):
    """Minimize (at most `iterations`), then run `steps` steps of LangevinMiddleIntegrator at 300 K (default threads)."""
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, 1/unit.picosecond, STEP)
    integrator.setRandomNumberSeed(2024)
    context = openmm.Context(system, integrator, cpu)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, iterations)
    context.setVelocitiesToTemperature(TEMPERATURE, 2024)
    integrator.step(steps)
    return context.getState(getPositions=True, getVelocities=True, enforcePeriodicBox=True)


def boxIntegrators(langevin):
    stock = openmm.VerletIntegrator(STEP)
    exact = openmmrigid.RigidBodyIntegrator(STEP)
    exact.setRotationMethod(openmmrigid.RigidBodyIntegrator.Exact)
    noSquish = openmmrigid.RigidBodyIntegrator(STEP)
    noSquish.setRotationMethod(openmmrigid.RigidBodyIntegrator.NoSquish)
    integrators = {STOCK: stock, EXACT: exact, NOSQUISH: noSquish}
    if langevin:
        integrators[STOCK_LANGEVIN] = openmm.LangevinMiddleIntegrator(TEMPERATURE, 1/unit.picosecond, STEP)
        integrators[LANGEVIN] = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, 1/unit.picosecond, STEP)
    return integrators


def measureBox(model, molecules, system, state, cpu, threads, args):
    """One row per integrator for this box and thread setting (cpu: the platform timed)."""
    integrators = boxIntegrators(args.langevin)
    contexts = []
    for integrator in integrators.values():
        context = openmm.Context(system, integrator, cpu, threadProperties(threads))
        context.setState(state)
        contexts.append(context)
    actualThreads = threadsOf(cpu, contexts[0])
    bodies = integrators[EXACT].getNumBodies()
    if bodies != molecules:
        say(f"  WARNING: RigidBodyIntegrator found {bodies} bodies in {molecules} waters")
    steps = blockSteps(integrators[STOCK], args.steps, args.seconds, 20)
    times, _ = timeInterleaved(integrators, steps, args.repetitions)
    rows = []
    for label, samples in times.items():
        median, low, high = medianRange(samples, 1e3)
        stockMedian = 1e3*statistics.median(times[STOCK_LANGEVIN if label in (STOCK_LANGEVIN, LANGEVIN) else STOCK])
        rows.append({"model": model, "molecules": molecules, "integrator": label, "threads": actualThreads,
                     "median_ms_per_step": f"{median:.4f}", "ratio_to_stock": f"{median/stockMedian:.4f}",
                     "repetitions": args.repetitions, "steps": steps,
                     "min_ms_per_step": f"{low:.4f}", "max_ms_per_step": f"{high:.4f}"})
    stamp(f"  {MODEL_NAMES[model]} {molecules} threads={actualThreads}: {steps} steps/block; "
             + "; ".join(f"{row['integrator'].split('/')[-1]} {float(row['median_ms_per_step']):.3f} ms "
                         f"[{float(row['min_ms_per_step']):.3f}-{float(row['max_ms_per_step']):.3f}]" for row in rows))
    del contexts
    return rows


def runBoxes(args, cpu):
    rows = []
    for model in args.models:
        for molecules in args.sizes:
            stamp(f"{MODEL_NAMES[model]} {molecules}: building, minimizing ({args.minimizeIterations} iterations), "
                     f"{args.equilibrationSteps} Langevin steps")
            started = time.perf_counter()
            topology, positions, system = buildBox(model, molecules)
            waters = topology.getNumResidues()
            state = equilibratedState(positions, system, openmm.Platform.getPlatformByName("CPU"), args.equilibrationSteps,
                                      args.minimizeIterations)
            stamp(f"  {waters} waters, {system.getNumParticles()} particles; ready in {time.perf_counter() - started:.0f} s")
            for threads in args.threads:
                rows.extend(measureBox(model, waters, system, state, cpu, threads, args))
    return rows


def printBoxTable(rows):
    say(f"\nPart 1: water boxes, PME (cutoff 0.9 nm), 2 fs, {PLATFORM_NAME[0]} platform; median ms/step (ratio to stock)")
    say("(ours: with the accuracy check on, its default)")
    say(f"{'model':<10}{'molecules':>10}{'threads':>8}{'stock':>10}{'Exact':>10}{'NoSquish':>10}"
        f"{'Exact/stock':>13}{'NoSq/stock':>12}")
    for key in sorted({(r["model"], r["molecules"], r["threads"]) for r in rows},
                      key=lambda k: (k[0], k[1], k[2])):
        cells = {r["integrator"]: r for r in rows if (r["model"], r["molecules"], r["threads"]) == key}
        say(f"{MODEL_NAMES[key[0]]:<10}{key[1]:>10}{key[2]:>8}"
            + "".join(f"{float(cells[label]['median_ms_per_step']):>10.3f}" for label in (STOCK, EXACT, NOSQUISH))
            + f"{float(cells[EXACT]['ratio_to_stock']):>13.3f}{float(cells[NOSQUISH]['ratio_to_stock']):>12.3f}")
    if any(r["integrator"] == LANGEVIN for r in rows):
        say("\nLangevin (1/ps): median ms/step; ours/stock is RigidBodyLangevinIntegrator/LangevinMiddleIntegrator")
        say(f"{'model':<10}{'molecules':>10}{'threads':>8}{'stock':>10}{'ours':>10}{'ours/stock':>12}")
        for r in sorted((r for r in rows if r["integrator"] == LANGEVIN), key=lambda r: (r["model"], r["molecules"], r["threads"])):
            stock = next(s for s in rows if s["integrator"] == STOCK_LANGEVIN
                         and (s["model"], s["molecules"], s["threads"]) == (r["model"], r["molecules"], r["threads"]))
            say(f"{MODEL_NAMES[r['model']]:<10}{r['molecules']:>10}{r['threads']:>8}{float(stock['median_ms_per_step']):>10.3f}"
                f"{float(r['median_ms_per_step']):>10.3f}{float(r['ratio_to_stock']):>12.3f}")


# ---------------------------------------------------------------------------------------------------
# Part 2: the integrator alone, by body kind

def tetrahedron(bond):
    return [[0, 0, 0]] + [list(bond*np.array(v)/math.sqrt(3)) for v in ((1, 1, 1), (1, -1, -1), (-1, 1, -1), (-1, -1, 1))]


def pyramid(bond, angle):
    """NH3: N at the origin, three H at `bond` nm with H-N-H `angle` degrees (a symmetric top)."""
    sin2 = (1 - math.cos(math.radians(angle)))/1.5  # cos(HNH) = cos^2(t) - sin^2(t)/2 for polar angle t
    s, c = math.sqrt(sin2), math.sqrt(1 - sin2)
    return [[0, 0, 0]] + [[bond*s*math.cos(p), bond*s*math.sin(p), -bond*c] for p in np.radians([0, 120, 240])]


def waterGeometry():
    half = math.radians(104.52/2)
    return [[0, 0, 0], [0.09572*math.sin(half), 0.09572*math.cos(half), 0], [-0.09572*math.sin(half), 0.09572*math.cos(half), 0]]


# kind: (label, masses in amu, body-frame positions in nm, expected benchmarking.bodyKind)
BODY_KINDS = {
    "water": ("water (TIP3P, asymmetric)", [15.999, 1.008, 1.008], waterGeometry(), "asymmetric"),
    "linear": ("linear (CO2, 3 particles)", [12.011, 15.999, 15.999], [[0, 0, 0], [0, 0, 0.1162], [0, 0, -0.1162]], "linear"),
    "spherical": ("spherical (CH4-like, 5 particles)", [12.011] + 4*[1.008], tetrahedron(0.1087), "spherical"),
    "symmetric": ("symmetric (NH3-like, 4 particles)", [14.007] + 3*[1.008], pyramid(0.1012, 106.67), "symmetric"),
    "point": ("single particle (Ar)", [39.948], [[0, 0, 0]], "point"),
}


def bodySystem(kind, count, seed=1):
    """A System of `count` randomly oriented bodies of one kind, all centred at the origin, no forces.

    Water gets its three constraints (the integrator finds the bodies); the other kinds are explicit.
    The centres are all at the origin (nothing interacts, so overlap costs nothing) because the integrator
    takes an explicit body's kind from the moments of its initial coordinates with a tolerance of 8 ulps
    of the largest moment: at lattice sites a few nm out, the rounding of centre + offset makes about 60 %
    of tetrahedra and NH3 pyramids "asymmetric" or "symmetric" instead.
    """
    _, masses, local, _ = BODY_KINDS[kind]
    local = np.array(local, dtype=float)
    local -= np.average(local, axis=0, weights=masses)
    system, positions, bodies = openmm.System(), [], []
    rng = np.random.default_rng(seed)
    for index in range(count):
        rotation = rigidtesting.randomRotation(rng)
        body = [system.addParticle(mass) for mass in masses]
        positions.extend(openmm.Vec3(*(rotation@r)) for r in local)
        bodies.append(body)
        if kind == "water":
            for i, j in ((0, 1), (0, 2), (1, 2)):
                system.addConstraint(body[i], body[j], float(np.linalg.norm(local[i] - local[j])))
    return system, positions*unit.nanometer, (None if kind == "water" else bodies)


def stockIntegrator():
    """The floor: stock Verlet on the same System (SETTLE for water; free particles for the other kinds)."""
    return openmm.VerletIntegrator(STEP)


def rigidIntegrator(bodies, method):
    """The integrator alone, its accuracy check off (the module's docstring, part 2)."""
    integrator = openmmrigid.RigidBodyIntegrator(STEP) if bodies is None else openmmrigid.RigidBodyIntegrator(STEP, bodies)
    integrator.setRotationMethod(method)
    integrator.setAccuracyCheck(False)
    return integrator


def foundKinds(context, integrator, positions, expected, kind):
    """'kind:count;...' of the integrator's bodies (benchmarking.bodyKinds, from the positions the Context
    was given), with a warning when under 99 % are `expected`."""
    found = {}
    for name in bodyKinds(context, integrator, positions):
        found[name] = found.get(name, 0) + 1
    if found.get(expected, 0) < 0.99*integrator.getNumBodies():
        say(f"  WARNING: {kind} bodies classified as {found}, expected {expected!r}")
    return ";".join(f"{name}:{number}" for name, number in sorted(found.items()))


def measureKind(kind, cpu, threads, args):
    system, positions, bodies = bodySystem(kind, args.bodies)
    integrators = {"stock": stockIntegrator(),
                   "Exact": rigidIntegrator(bodies, openmmrigid.RigidBodyIntegrator.Exact),
                   "NoSquish": rigidIntegrator(bodies, openmmrigid.RigidBodyIntegrator.NoSquish)}
    contexts = []
    for integrator in integrators.values():
        context = openmm.Context(system, integrator, cpu, threadProperties(threads))
        context.setPositions(positions)
        context.setVelocitiesToTemperature(TEMPERATURE, 7)
        contexts.append(context)
    actualThreads = threadsOf(cpu, contexts[0])
    steps = blockSteps(integrators["Exact"], args.body_steps, args.seconds/2, 10)  # steadier than the boxes
    times, _ = timeInterleaved(integrators, steps, args.repetitions)
    kinds = foundKinds(contexts[list(integrators).index("Exact")], integrators["Exact"], positions, BODY_KINDS[kind][3],
                       kind)
    count = integrators["Exact"].getNumBodies()
    ratio = statistics.median(times["Exact"])/statistics.median(times["NoSquish"])
    rows = []
    for method, samples in times.items():
        median, low, high = medianRange(samples, 1e9/count)
        rows.append({"kind": kind, "particles_per_body": len(BODY_KINDS[kind][1]), "bodies": count, "method": method,
                     "threads": actualThreads, "median_ns_per_body_step": f"{median:.2f}",
                     "exact_to_nosquish": "" if method == "stock" else f"{ratio:.4f}", "repetitions": args.repetitions, "steps": steps,
                     "min_ns_per_body_step": f"{low:.2f}", "max_ns_per_body_step": f"{high:.2f}", "forces": "none",
                     "kinds_found": kinds})
    stamp(f"  {kind} x{count} threads={actualThreads}: {steps} steps/block; "
             + "; ".join(f"{row['method']} {float(row['median_ns_per_body_step']):.1f} ns "
                         f"[{float(row['min_ns_per_body_step']):.1f}-{float(row['max_ns_per_body_step']):.1f}]" for row in rows))
    del contexts
    return rows


def runBodies(args, cpu):
    stamp(f"Part 2: {args.bodies} bodies per kind, no forces")
    rows = []
    for kind in BODY_KINDS:
        for threads in args.threads:
            rows.extend(measureKind(kind, cpu, threads, args))
    return rows


def printBodyTable(rows):
    say(f"\nPart 2: integrator alone (System with no forces), 2 fs, {PLATFORM_NAME[0]} platform; median ns/body/step")
    say(f"{'kind':<36}{'bodies':>8}{'threads':>8}{'Exact':>10}{'NoSquish':>10}{'Exact/NoSq':>12}{'(stock)':>10}")
    for kind in BODY_KINDS:
        for threads in sorted({r["threads"] for r in rows if r["kind"] == kind}):
            cells = {r["method"]: r for r in rows if r["kind"] == kind and r["threads"] == threads}
            say(f"{BODY_KINDS[kind][0]:<36}{cells['Exact']['bodies']:>8}{threads:>8}"
                f"{float(cells['Exact']['median_ns_per_body_step']):>10.1f}"
                f"{float(cells['NoSquish']['median_ns_per_body_step']):>10.1f}"
                f"{float(cells['Exact']['exact_to_nosquish']):>12.3f}"
                f"{float(cells['stock']['median_ns_per_body_step']):>10.1f}")
    say("Each includes the fixed cost of a step (the Python call, an empty force evaluation) spread over the\n"
        "bodies. (stock): VerletIntegrator on the same System, for scale only: SETTLE for water, free\n"
        "particles for the other kinds; nothing is subtracted.")


def plotBoxes(axes, rows):
    keys = sorted({(r["model"], r["molecules"], r["threads"]) for r in rows})
    width = 0.27
    for offset, label in enumerate((STOCK, EXACT, NOSQUISH)):
        values = [float(next(r["median_ms_per_step"] for r in rows if (r["model"], r["molecules"], r["threads"]) == key
                             and r["integrator"] == label)) for key in keys]
        bars = axes.bar(np.arange(len(keys)) + (offset - 1)*width, values, width, label=label)
        if label != STOCK:
            ratios = [next(r["ratio_to_stock"] for r in rows if (r["model"], r["molecules"], r["threads"]) == key
                           and r["integrator"] == label) for key in keys]
            axes.bar_label(bars, [f"{float(x):.2f}" for x in ratios], fontsize=6, rotation=90, padding=2)
    axes.set_xticks(np.arange(len(keys)), [f"{MODEL_NAMES[m]}\n{n}, {t} thr" for m, n, t in keys], fontsize=7)
    axes.set_yscale("log")
    axes.yaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    axes.yaxis.set_minor_formatter(matplotlib.ticker.ScalarFormatter())
    axes.tick_params(axis="y", which="both", labelsize=7)
    axes.set_ylabel("ms/step (median)")
    axes.set_title("Water boxes, PME, 2 fs (labels: ratio to stock)", fontsize=9)
    axes.legend(fontsize=7)


def plotBodies(axes, rows):
    kinds = [kind for kind in BODY_KINDS if any(r["kind"] == kind for r in rows)]
    threadCounts = sorted({r["threads"] for r in rows})
    series = [(method, threads) for threads in threadCounts for method in ("stock", "Exact", "NoSquish")]
    colours = {"stock": "C0", "Exact": "C1", "NoSquish": "C2"}
    width = 0.8/len(series)
    for offset, (method, threads) in enumerate(series):
        values = [float(next(r["median_ns_per_body_step"] for r in rows
                             if r["kind"] == kind and r["method"] == method and r["threads"] == threads)) for kind in kinds]
        label = "stock Verlet (for scale)" if method == "stock" else method
        axes.bar(np.arange(len(kinds)) + (offset - (len(series) - 1)/2)*width, values, width, color=colours[method],
                 hatch="" if threads == threadCounts[0] else "//", edgecolor="white", linewidth=0,
                 label=f"{label}, {threads} thr")
    axes.set_xticks(np.arange(len(kinds)), [BODY_KINDS[kind][0].replace(" (", "\n(") for kind in kinds], fontsize=7)
    axes.set_ylabel("ns/body/step (median)")
    axes.set_title(f"Integrator alone, no forces, {rows[0]['bodies']} bodies per kind", fontsize=9)
    axes.legend(fontsize=7)


def plot(path, boxRows, bodyRows, title):
    panels = [(plotBoxes, boxRows), (plotBodies, bodyRows)]
    panels = [(function, rows) for function, rows in panels if rows]
    figure, axes = plt.subplots(len(panels), 1, figsize=(10, 4.2*len(panels)), squeeze=False)
    for (function, rows), ax in zip(panels, axes[:, 0]):
        function(ax, rows)
    figure.suptitle(title, fontsize=9)
    saveFigure(figure, path)


def main():
    args = parseArguments()
    suffix = "" if args.platform == "CPU" else f"_{args.platform}_{args.precision}"
    openLog(RESULTS / f"step_cost{suffix}.log")
    cpu = openmm.Platform.getPlatformByName(args.platform)  # the platform timed
    if args.platform == "CPU":
        default = cpu.getPropertyDefaultValue("Threads")
        args.threads = list(dict.fromkeys(default if t == "default" else str(int(t)) for t in args.threads))
    else:
        args.threads = [args.precision]
    PLATFORM_NAME[0] = args.platform if args.platform == "CPU" else f"{args.platform} ({args.precision} precision)"
    document = ResultsDocument(f"step_cost{suffix}", f"Cost per step against stock OpenMM, {PLATFORM_NAME[0]} platform",
                               quick=args.quick, platform=PLATFORM_NAME[0],
                               about="Method: the docstring of `benchmarks/step_cost.py`. Threads: "
                                     f"{', '.join(args.threads)}.")
    printHeader(args)
    start = time.perf_counter()
    boxRows = runBoxes(args, cpu) if args.only != "bodies" else []
    bodyRows = runBodies(args, cpu) if args.only != "boxes" else []
    with document.capture():
        if boxRows:
            printBoxTable(boxRows)
        if bodyRows:
            printBodyTable(bodyRows)
    say()
    if boxRows:
        writeCsv(RESULTS / f"step_cost{suffix}.csv", boxRows)
    if bodyRows:
        writeCsv(RESULTS / f"integrator_only{suffix}.csv", bodyRows)
    figure = document.figurePath(f"step_cost{suffix}.png")
    plot(figure, boxRows, bodyRows,
         f"openmm-rigid step cost, {PLATFORM_NAME[0]}, {machine()}, OpenMM {openmm.version.full_version}, "
         f"{datetime.date.today()}{' (quick)' if args.quick else ''}")
    document.figure(figure, "step cost")
    document.write()
    say(f"total {time.perf_counter() - start:.0f} s; load average now {loadAverage()}")


if __name__ == "__main__":
    main()

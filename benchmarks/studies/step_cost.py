"""Cost per step against stock OpenMM: whole steps of PME water boxes, and the integrator alone on force-free bodies
of each kind, each timed interleaved (harness.timeInterleaved) with what it is compared with."""

import numpy as np, openmm
import harness, setups
from harness import Study, pyplot
from rigidtesting import randomRotation
from rigidtesting.stress import _ammonia_like, _argon, _carbon_dioxide, _methane_like, _water_like

MODELS, METHODS = {"tip3p": "TIP3P", "tip4pew": "TIP4P-Ew"}, ("stock", "Exact", "NoSquish")
KINDS = {"water": _water_like, "CO2": _carbon_dioxide, "CH4-like": _methane_like, "NH3-like": _ammonia_like, "Ar": _argon}
FULL = dict(models=list(MODELS), sizes=[500, 2000, 8000], bodies=8000, seconds=2.0, ps=1.0)
QUICK = dict(models=["tip3p"], sizes=[216], bodies=500, seconds=0.05, ps=0.1)

def timed(system, integrators, setState, env, threads, seconds, scale):
    """Contexts for {label: integrator} (a GPU in mixed precision), set by setState(context), timed in 5 interleaved blocks
    of about `seconds`: {platform, threads, steps, wall: {label: [median, min, max] s/step x scale}, cpu: likewise}."""
    gpu = env.platformName not in ("CPU", "Reference")
    properties = {"Precision": "mixed"} if gpu else harness.cpuProperties(env.platformName, threads)
    contexts = [openmm.Context(system, integrator, env.platform, properties) for integrator in integrators.values()]
    for context in contexts:
        setState(context)
    steps = harness.blockSteps(next(iter(integrators.values())), None, seconds, 10)
    times = dict(zip(("wall", "cpu"), harness.timeInterleaved(integrators, steps, 5)))
    threads = int(env.platform.getPropertyValue(contexts[0], "Threads")) if env.platformName == "CPU" else None
    return dict(platform=env.platformName + (", mixed" if gpu else ""), threads=threads, steps=steps,
                **{c: {k: harness.medianRange(v, scale) for k, v in t.items()} for c, t in times.items()})

def timeBodies(env, kind, count, threads, seconds, seed=1):
    """The integrator alone: `count` randomly oriented bodies of `kind`, no forces, accuracy check off (its episodes' energy
    sums are not negligible then), beside stock Verlet on the System (SETTLE for water, whose bodies the integrator finds);
    ns per body and step. All at the origin: elsewhere the rounding of centre + offset makes tetrahedra 'asymmetric'."""
    masses, local = KINDS[kind]()[1:3]
    local = np.asarray(local, float) - np.average(local, axis=0, weights=masses)
    rng, system, x, bodies = np.random.default_rng(seed), openmm.System(), [], []
    for _ in range(count):
        bodies.append([system.addParticle(mass) for mass in masses])
        x.append(local @ randomRotation(rng).T)
        for i, j in ((0, 1), (0, 2), (1, 2)) if kind == "water" else ():
            system.addConstraint(bodies[-1][i], bodies[-1][j], float(np.linalg.norm(local[i] - local[j])))
    x, bodies = np.concatenate(x), None if kind == "water" else bodies
    integrators = dict(zip(METHODS, [openmm.VerletIntegrator(0.002)] + [setups.makeIntegrator(
        "rigid-verlet", 2, rotation=rotation, bodies=bodies) for rotation in ("exact", "nosquish")]))
    for method in METHODS[1:]:
        integrators[method].setAccuracyCheck(False)
    setState = lambda c: (c.setPositions(x), c.setVelocitiesToTemperature(300, 7))   # noqa: E731
    return dict(kind=kind, bodies=count, **timed(system, integrators, setState, env, threads, seconds, 1e9/count))

def run(env):
    s, boxes, cpu = QUICK if env.quick else FULL, [], openmm.Platform.getPlatformByName("CPU")
    threads = [env.threads] if env.threads or env.platformName != "CPU" else sorted(
        {1, 1 if env.quick else int(env.platform.getPropertyDefaultValue("Threads"))})
    for model, size, count in ((m, n, t) for m in s["models"] for n in s["sizes"] for t in threads):
        built = setups.water(model, size)
        state = setups.start(f"step_cost-{'quick-' if env.quick else ''}{model}-{size}", built, cpu, {}, s["ps"])
        integrators = dict(zip(METHODS, [setups.makeIntegrator("stock-verlet", 2)] + [
            setups.makeIntegrator("rigid-verlet", 2, rotation=rotation) for rotation in ("exact", "nosquish")]))
        row = timed(built.system, integrators, lambda c: c.setState(state), env, count, s["seconds"], 1e3)
        boxes.append(dict(model=model, molecules=len(built.waters), **row))
        harness.stamp(str(boxes[-1]))
    return dict(boxes=boxes, bodies=[timeBodies(env, k, s["bodies"], t, s["seconds"]/2) for k in KINDS for t in threads])

def ratio(row, label, to="stock"):
    return row["wall"][label][0]/row["wall"][to][0]

def report(summary, page):
    boxes, bodies = summary["boxes"], summary["bodies"]
    for platform in dict.fromkeys(r["platform"] for r in boxes):
        exact, noSquish = ([ratio(r, m) for r in boxes if r["platform"] == platform] for m in METHODS[1:])
        page.text(f"{platform}, {len(exact)} box(es): Exact / stock **median {np.median(exact):.3f}** ({min(exact):.3f} to "
                  f"{max(exact):.3f}); NoSquish / stock median {np.median(noSquish):.3f}.")
    page.table(["platform", "model", "waters", "threads"] + [f"{m} ms/step" for m in METHODS] + ["Exact / stock", "NoSq. / stock"],
               [[r["platform"], MODELS[r["model"]], r["molecules"], r["threads"]] + [f"{r['wall'][m][0]:.3f}" for m in METHODS]
                + [f"{ratio(r, m):.3f}" for m in METHODS[1:]] for r in boxes])
    page.section("The integrator alone", "Force-free bodies, accuracy check off: median wall ns per body and step, with a step's "
                 "fixed cost (the Python call, an empty force evaluation) spread over them; stock Verlet on the System for scale.")
    page.table(["platform", "kind", "bodies", "threads", "Exact", "NoSquish", "Exact / NoSquish", "stock"],
               [[r["platform"], r["kind"], r["bodies"], r["threads"]] + [f"{r['wall'][m][0]:.1f}"
                for m in METHODS[1:]] + [f"{ratio(r, 'Exact', 'NoSquish'):.3f}", f"{r['wall']['stock'][0]:.1f}"] for r in bodies])
    figure, axes = pyplot().subplots(figsize=(9, 4))
    for offset, label in ((-0.1, "Exact"), (0.1, "NoSquish")):
        values = np.array([r["wall"][label] for r in boxes], dtype=float)/[[r["wall"]["stock"][0]] for r in boxes]
        spread = None if np.isnan(values).any() else np.abs(values[:, 1:] - values[:, :1]).T
        axes.errorbar(np.arange(len(boxes)) + offset, values[:, 0], yerr=spread, fmt="o", capsize=3, label=f"{label} / stock")
    axes.axhline(1, color="grey", lw=0.8)
    axes.set_xticks(range(len(boxes)), [f"{r['model']}\n{r['molecules']}\n{r['threads'] or r['platform'][:6]}" for r in boxes])
    axes.set(ylabel="wall time per step / stock's", xlabel="model, waters, CPU threads or platform")
    axes.legend()
    page.figure(figure, "ratios", "A step's cost relative to stock's in each water box (bars, where kept: range of the blocks).")

STUDY = Study("step_cost", "Cost per step against stock OpenMM",
              "On the CPU platform a step of RigidBodyIntegrator costs within a few per cent of a step of stock VerletIntegrator + "
              "SETTLE in PME water boxes of 500 to 8000 TIP3P or TIP4P-Ew waters, at 1 and 2 threads.", report, run=run, method="""
Water boxes (amber14, PME 0.9 nm) of 500, 2000 and 8000 waters from one equilibrated state each: stock `VerletIntegrator`
+ SETTLE, `RigidBodyIntegrator` Exact and NoSquish, 2 fs, accuracy check on (the default); after a warm-up block each, 5
interleaved blocks of about 2 s; CPU platform at 1 thread and its default. The integrator alone: 8000 bodies a kind.""", caveats="""
One machine, one run: a difference of 3 % between integrators is at the edge of what five blocks resolve on a shared
2-core machine; read ratios within a run. OpenCL here is PoCL, OpenCL on a CPU: it says nothing of a GPU.""")

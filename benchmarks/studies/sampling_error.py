"""KL divergence of each integrator's configurations from Boltzmann's, from shadow work (Sivak, Chodera and Crooks 2013;
Fass et al. 2018): per frame, velocities drawn, 2 ps (shadow work w_π), drawn again, 2 ps (w_ω); KL ≈ (⟨w_π⟩ − ⟨w_ω⟩)/2 ±
the standard error of the paired halves, on-step velocities at both ends; within errors of 0 (it is never negative): KL
at most twice its error. water: 500 rigid TIP3P (PME 0.9 nm); peptide: alanine dipeptide in 500 TIP3P (amber14, HBonds,
3 amu H); 300 K, 1/ps. Frames (the seeds, shared): RigidBodyLangevinIntegrator (1 fs, 5/ps), 20 ps, then one every 2 ps.
rigid-exact, rigid-nosquish: its rotations; rigid-raised: moments raised to 0.08 amu nm²; stock-middle:
LangevinMiddleIntegrator + SETTLE (a CustomIntegrator summing its shadow work); openmmtools-vrorv: openmmtools' BAOAB. A
failure stops the larger steps. ns/day: the integrators as users run them, side by side."""
import fcntl
import functools
import numpy as np
import openmm
from openmm import unit
import setups
from harness import Study, TimingFailure, Unstable, nsPerDay, pyplot, timeInterleaved
from rigidtesting.samplingerror import configurationKL

KJ, KT = unit.kilojoule_per_mole, setups.BOLTZMANN*setups.TEMPERATURE
FLOOR = 0.08   # rigid-raised's moments of inertia, amu nm^2
SETUP = {False: dict(protocol=2.0, spacing=2.0, equilibrate=20.0),   # ps: a half protocol, between frames, before them
         True: dict(protocol=0.2, spacing=0.25, equilibrate=0.5)}      # (a quick run)
KINDS = ["rigid-exact", "rigid-nosquish", "rigid-raised", "stock-middle", "openmmtools-vrorv"]
# LangevinMiddleIntegrator's step (OpenMM's documentation) with on-step velocities (its kick split into halves at either
# end) summing its shadow work: the change of K + U over the step less the heat its O stage brings in.
MIDDLE = """ComputeSum ke 0.5*m*v*v; ComputeGlobal shadow_work shadow_work - ke - energy; UpdateContextState
ComputePerDof v v + 0.5*dt*f/m; ConstrainVelocities; ComputePerDof x x + 0.5*dt*v; ComputeSum ke 0.5*m*v*v
ComputeGlobal shadow_work shadow_work + ke; ComputePerDof v a*v + b*sqrt(kT/m)*gaussian; ComputeSum ke 0.5*m*v*v
ComputeGlobal shadow_work shadow_work - ke; ComputePerDof x x + 0.5*dt*v; ComputePerDof x1 x; ConstrainPositions
ComputePerDof v v + (x - x1)/dt; ComputePerDof v v + 0.5*dt*f/m; ConstrainVelocities; ComputeSum ke 0.5*m*v*v
ComputeGlobal shadow_work shadow_work + ke + energy"""

@functools.lru_cache(None)
def frames(name, count, env):
    """The system (peptide, or water<n>: n waters, 500 without n) and a reader of its `count` equilibrium frames."""
    built = setups.dipeptideInWater(barostat=False) if name == "peptide" else setups.water(molecules=int(name[5:] or 500))
    setup, folder = SETUP[env.quick], env.folder/f"frames-{name}"
    folder.mkdir(exist_ok=True)
    with open(folder/"lock", "a") as lock:   # workers wait for the one that makes them
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder/f"{count - 1}.xml").exists():
            start = setups.start(f"sampling-{name}", built, env.platform, env.properties, 0.5 if env.quick else 5.0)
            integrator = setups.makeIntegrator("rigid-langevin", 1, seed=1, friction=5.0)
            context = setups.context(built, integrator, start, env.platform, env.properties)
            integrator.step(round(setup["equilibrate"]/0.001))
            for i in range(count):
                integrator.step(round(setup["spacing"]/0.001))
                (folder/f"{i}.xml").write_text(openmm.XmlSerializer.serialize(context.getState(getPositions=True)))
    return built, lambda i: openmm.XmlSerializer.deserialize((folder/f"{i}.xml").read_text())

def makeIntegrator(kind, stepFs, seed, shadow):
    """`kind` at 1/ps: with shadow, as measured (its shadow work summed); else as users run it (no accuracy check)."""
    if kind.startswith("rigid"):
        integrator = setups.makeIntegrator("rigid-langevin", stepFs, seed, floor=FLOOR if kind == "rigid-raised" else None,
                                           rotation="nosquish" if kind == "rigid-nosquish" else "exact")
        integrator.setMeasureShadowWork(shadow)
        integrator.setAccuracyCheck(False)   # its two 2 ps windows outlast a half protocol
    elif kind == "stock-middle" and shadow:
        integrator, a = openmm.CustomIntegrator(stepFs*1e-3), np.exp(-setups.FRICTION*stepFs*1e-3)
        for name, value in dict(a=a, b=np.sqrt(1 - a*a), kT=KT, shadow_work=0, ke=0).items():
            integrator.addGlobalVariable(name, value)
        integrator.addPerDofVariable("x1", 0.0)
        for operation in MIDDLE.replace("\n", ";").split(";"):
            name, *arguments = operation.split(maxsplit=2)
            getattr(integrator, "add" + name)(*arguments)
    elif kind == "stock-middle":
        integrator = setups.makeIntegrator(kind, stepFs, seed)
    else:
        from openmmtools.integrators import LangevinIntegrator
        integrator = LangevinIntegrator(setups.TEMPERATURE*unit.kelvin, setups.FRICTION/unit.picosecond,
                                        stepFs*unit.femtosecond, splitting="V R O R V", measure_shadow_work=shadow)
    integrator.setRandomNumberSeed(seed + 1)
    return integrator

def halfProtocol(context, integrator, kind, steps, seed, masses):
    """Velocities drawn at 300 K, `steps` steps: the shadow work (kT) with on-step velocities at both ends (BAOAB's). The
    rigid integrator holds velocities half a kick behind (its step is BAOAB's with the closing half kick joined to the
    next opening one): its on-step kinetic energy puts the ends on step (terms of first order that would swamp the KL)."""
    if kind.startswith("rigid"):   # drawn for the bodies' own moments, taken half a kick back by the Context
        context.setVelocitiesToTemperature(setups.TEMPERATURE*unit.kelvin, seed)
        kinetic = lambda: context.getState(getEnergy=True).getKineticEnergy()   # noqa: E731
        before = integrator.getShadowWork() + integrator.getOnStepKineticEnergy() - kinetic()
        integrator.step(steps)
        after = integrator.getShadowWork() + integrator.getOnStepKineticEnergy() - kinetic()
        return (after - before).value_in_unit(KJ)/KT
    context.setVelocities(np.random.default_rng(seed).standard_normal((len(masses), 3))*np.sqrt(KT/masses)[:, None])
    context.applyVelocityConstraints(1e-10)   # the constraints' share is no step's work
    integrator.setGlobalVariableByName("shadow_work", 0.0)   # openmmtools' VRORV sums it too
    integrator.step(steps)
    return integrator.getGlobalVariableByName("shadow_work")/KT

def measure(job, env):
    """Frame i (the seed): the shadow works (kT) from it and on from where it led (velocities drawn at 100 + 2i + k)."""
    i, kind, stepPs = job["seed"], job["integrator"], job["step"]*1e-3
    built, frame = frames(job["system"], max(len(seeds) for _, seeds in env.study.jobs(env.quick)), env)
    integrator = makeIntegrator(kind, job["step"], 10 + i, shadow=True)
    context = setups.context(built, integrator, frame(i), env.platform, env.properties)
    masses, steps = np.where(built.masses > 0, built.masses, np.inf), round(SETUP[env.quick]["protocol"]/stepPs)
    try:
        works = [halfProtocol(context, integrator, kind, steps, 100 + 2*i + k, masses) for k in (0, 1)]
    except openmm.OpenMMException as error:
        raise Unstable(f"frame {i}: {str(error).split('.')[0]}")
    if not np.all(np.isfinite(works)):
        raise Unstable(f"frame {i}: the shadow work is not finite")
    return works

def timeStep(name, stepFs, kinds, env):
    """ns/day at one step of the integrators as users run them, side by side from frame 0 (interleaved 0.2 ps blocks)."""
    built, frame = frames(name, 1, env)
    integrators = {kind: makeIntegrator(kind, stepFs, 3, shadow=False) for kind in kinds}
    contexts = [setups.context(built, each, frame(0), env.platform, env.properties) for each in integrators.values()]
    for context in contexts:
        context.setVelocitiesToTemperature(setups.TEMPERATURE, 3)
    try:
        wall = timeInterleaved(integrators, max(10, round(0.2/(stepFs*1e-3))), 2 if env.quick else 5)[0]
    except TimingFailure:
        return {}
    return {kind: nsPerDay(stepFs, float(np.median(seconds))) for kind, seconds in wall.items()}

def summarize(results, env):
    """Per system, integrator and step (unless blocked): frames, KL and its standard error (kT), why it failed, ns/day."""
    rows = []
    for result in (result for result in results if not result["blocked"]):
        rows.append(dict(result["job"], frames=len(result["samples"]), failed=result["failed"]))
        if len(result["samples"]) > 1 and not result["failed"]:
            rows[-1]["kl"], rows[-1]["error"] = configurationKL(*np.array(result["samples"]).T)
    for name, step in sorted({(row["system"], row["step"]) for row in rows}):
        here = [row for row in rows if (row["system"], row["step"]) == (name, step) and "kl" in row]
        speeds = timeStep(name, step, [row["integrator"] for row in here], env) if here else {}
        for row in here:
            row["nsPerDay"] = speeds.get(row["integrator"])
    return {"setup": dict(SETUP[env.quick], floor=FLOOR, friction=setups.FRICTION), "rows": rows}

def report(summary, page):
    names = list(dict.fromkeys(row["system"] for row in summary["rows"]))
    figure, axes = pyplot().subplots(1, len(names), figsize=(5.5*len(names), 4.2), squeeze=False)
    for name, ax in zip(names, axes[0]):
        mine, table = [row for row in summary["rows"] if row["system"] == name], []
        for r in mine:
            cells = [f"unstable: {r['failed']}", "", ""]
            if "kl" in r:
                speed = f"{r['nsPerDay']:.1f}" if r.get("nsPerDay") else ""
                cells = [f"{r['kl']:.3g} ± {r['error']:.2g}", f"{r['kl']/r['error']:.1f}", speed]
            table.append([r["integrator"], r["step"], r["frames"] or ""] + cells)
        page.section(name)
        page.table(["integrator", "step (fs)", "frames", "KL (kT) ± standard error", "KL/error", "ns/day"], table)
        timed = [r for r in mine if r.get("nsPerDay")]
        for kind in dict.fromkeys(r["integrator"] for r in timed):
            points = [(r["nsPerDay"], r["kl"], r["error"], r["step"]) for r in timed if r["integrator"] == kind]
            ax.errorbar(*np.array(points).T[:3], marker="o", capsize=3, label=kind)
            for x, y, _, step in points:
                ax.annotate(f"{step:g}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(yscale="symlog", xlabel="ns/day", ylabel="configuration-space KL (kT)", title=f"{name} (labels: step in fs)")
        ax.legend(fontsize=7)
    page.figure(figure, "kl", "KL divergence against ns/day ± one standard error (symmetric-log axis: linear within ±2 kT)")

STUDY = Study(
    "sampling_error", "Configuration-space sampling error against the step",
    "In 500 TIP3P waters the configurations of RigidBodyLangevinIntegrator are within errors of the Boltzmann distribution "
    "from 1 to 8 fs and off at 10 fs unless its moments are raised, where stock LangevinMiddleIntegrator is unstable; "
    "on the dipeptide with HMR every integrator fails at 6 fs.", report, method=__doc__,
    caveats="""Few frames (10 to 18 of 50): errors grow from 0.1 kT at 1 fs to 2 to 6 kT at 10 fs, so 2 to 8 fs does not
rank the integrators; stock-middle's work spreads most (noise along the constraints). The estimate's bias is not measured
(rigid-raised's 0.26 ± 0.07 kT at 2 fs is unexplained). ns/day: one timing per step. On the peptide the solute caps the step
before any integrator leaves its range.""",
    grid={"system": ["water", "peptide"], "integrator": KINDS, "step": [1, 2, 4, 6, 8, 10], "seed": list(range(50))},
    quick={"system": ["water216"], "integrator": KINDS, "step": [2, 10], "seed": [0, 1]},
    measure=measure, summarize=summarize)

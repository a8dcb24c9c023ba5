"""KL divergence of each integrator's configurations from Boltzmann's, from shadow work (Sivak, Chodera and Crooks 2013;
Fass et al. 2018): per frame, velocities drawn, 2 ps (shadow work w_π), drawn again, 2 ps (w_ω); KL ≈ (⟨w_π⟩ − ⟨w_ω⟩)/2 ±
the standard error of the paired halves, on-step velocities at both ends; within errors of 0 (it is never negative): KL
at most twice its error. water: 500 rigid TIP3P (PME 0.9 nm); peptide: alanine dipeptide in 500 TIP3P (amber14, HBonds,
3 amu H); 300 K, 1/ps. Frames (the seeds, shared): RigidBodyLangevinIntegrator (1 fs, 5/ps), 20 ps, then one every 2 ps.
rigid-exact, rigid-nosquish: its rotations; rigid-raised: moments raised to 0.08 amu nm²; stock-middle:
LangevinMiddleIntegrator + SETTLE (a CustomIntegrator summing its shadow work, its O stage's heat taken on the constrained
velocities); openmmtools-vrorv: openmmtools' BAOAB. A failure stops the larger steps. ns/day: the integrators as users run
them, side by side. The solvated protein's rows are protein_sampling_error's, with the same functions."""
import fcntl
import functools
import numpy as np
import openmm
from openmm import unit
import openmmrigid
import setups
from harness import Study, TimingFailure, Unstable, nsPerDay, pyplot, timeInterleaved
from rigidtesting.samplingerror import configurationKL
from studies import protein_mts

KJ, KT = unit.kilojoule_per_mole, setups.BOLTZMANN*setups.TEMPERATURE
FLOOR = 0.08   # rigid-raised's moments of inertia, amu nm^2
XH_FLOOR = 0.16                         # rigid-mts*: the protein's bodies' raised moments (amu nm^2)
SUBSTEPS = {"rigid-mts": 1.0, "rigid-mts-2fs": 2.0}   # their bonded forces' substep (fs)
# ps: a half protocol, between frames, before them (Model: a protein model's, from an equilibrated start); True: quick
SETUP = {False: dict(protocol=2.0, spacing=2.0, equilibrate=20.0, equilibrateModel=5.0),
         True: dict(protocol=0.2, spacing=0.25, equilibrate=0.5, equilibrateModel=0.5)}
KINDS = ["rigid-exact", "rigid-nosquish", "rigid-raised", "stock-middle", "openmmtools-vrorv"]
# LangevinMiddleIntegrator's step (OpenMM's documentation) with on-step velocities (its kick split into halves at either
# end) summing its shadow work: the change of K + U over the step less the heat its O stage brings in, taken on its
# velocities constrained (v1 keeps them as they are for the step): the constrained drift takes the O stage's noise along
# the n_c constraints out again, n_c kT (1 - a²)/2 a step, which as work would add -n_c kT γt to each ⟨w⟩ and its noise to
# the KL. The CMMotionRemover's change (UpdateContextState) comes before the step's sums: no work of the step.
MIDDLE = """UpdateContextState; ComputeSum ke 0.5*m*v*v; ComputeGlobal shadow_work shadow_work - ke - energy
ComputePerDof v v + 0.5*dt*f/m; ConstrainVelocities; ComputePerDof x x + 0.5*dt*v; ComputeSum ke 0.5*m*v*v
ComputeGlobal shadow_work shadow_work + ke; ComputePerDof v a*v + b*sqrt(kT/m)*gaussian; ComputePerDof v1 v
ConstrainVelocities; ComputeSum ke 0.5*m*v*v; ComputePerDof v v1; ComputeGlobal shadow_work shadow_work - ke
ComputePerDof x x + 0.5*dt*v; ComputePerDof x1 x; ConstrainPositions; ComputePerDof v v + (x - x1)/dt
ComputePerDof v v + 0.5*dt*f/m; ConstrainVelocities; ComputeSum ke 0.5*m*v*v
ComputeGlobal shadow_work shadow_work + ke + energy"""

@functools.lru_cache(None)
def model(name):
    """(Built, bodies) of a system: water<n> (n rigid TIP3P, 500 without n) or peptide (bodies None: the integrator's own,
    its constraints' clusters); <protein>-hmr, <protein>-xh, <protein>-planar (protein_mts.build's villin or dipeptide,
    bonded forces in group 1): flexible with HMR 3 amu, or with its X-H groups (and planar groups) and waters rigid bodies
    (openmmrigid.rigidHydrogenGroups)."""
    protein, _, variant = name.partition("-")
    if not variant:
        return (setups.dipeptideInWater(barostat=False) if name == "peptide" else
                setups.water(molecules=int(name[5:] or 500))), None
    built = protein_mts.build(protein, "hmr" if variant == "hmr" else "plain")
    return built, None if variant == "hmr" else openmmrigid.rigidHydrogenGroups(built.topology, built.system,
                                                                                 planarGroups=variant == "planar")

@functools.lru_cache(None)
def frames(name, count, env):
    """model(name) and a reader of its `count` equilibrium frames, its own model's at 1 fs and 5/ps: water, peptide by
    RigidBodyLangevinIntegrator from a start of their own; a protein's, from protein_mts's equilibrated start with fresh
    velocities, by LangevinMiddleIntegrator (-hmr) or RigidBodyLangevinIntegrator with its bodies and XH_FLOOR."""
    (built, bodies), setup, folder = model(name), SETUP[env.quick], env.folder/f"frames-{name}"
    folder.mkdir(exist_ok=True)
    with open(folder/"lock", "a") as lock:   # workers wait for the one that makes them
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder/f"{count - 1}.xml").exists():
            protein, _, variant = name.partition("-")
            if variant:
                startName, picoseconds = protein_mts.STARTS[protein]
                start = setups.start(startName, protein_mts.build(protein, "plain"), env.platform, env.properties, picoseconds)
                integrator = setups.makeIntegrator("rigid-langevin" if bodies else "stock-middle", 1, seed=1, friction=5.0,
                                                   floor=XH_FLOOR if bodies else None, bodies=bodies)
            else:
                start = setups.start(f"sampling-{name}", built, env.platform, env.properties, 0.5 if env.quick else 5.0)
                integrator = setups.makeIntegrator("rigid-langevin", 1, seed=1, friction=5.0)
            context = setups.context(built, integrator, start, env.platform, env.properties)
            if variant:   # the start's velocities are the flexible model's
                context.setVelocitiesToTemperature(setups.TEMPERATURE, 1)
            integrator.step(round(setup["equilibrateModel" if variant else "equilibrate"]/0.001))
            for i in range(count):
                integrator.step(round(setup["spacing"]/0.001))
                (folder/f"{i}.xml").write_text(openmm.XmlSerializer.serialize(context.getState(getPositions=True)))
    return built, bodies, lambda i: openmm.XmlSerializer.deserialize((folder/f"{i}.xml").read_text())

def makeIntegrator(kind, stepFs, seed, shadow, bodies=None):
    """`kind` at 1/ps: with shadow, as measured (its shadow work summed); else as users run it (OpenMM's default constraint
    tolerance, no accuracy check). rigid-mts*: bodies (model()'s), XH_FLOOR, the bonded forces (group 1) in SUBSTEPS."""
    if kind.startswith("rigid"):
        integrator = setups.makeIntegrator("rigid-langevin", stepFs, seed, bodies=bodies,
                                           floor=FLOOR if kind == "rigid-raised" else XH_FLOOR if kind in SUBSTEPS else None,
                                           rotation="nosquish" if kind == "rigid-nosquish" else "exact")
        if kind in SUBSTEPS:
            integrator.setForceGroupSubsteps([(0, 1), (1, max(1, round(stepFs/SUBSTEPS[kind])))])
        integrator.setMeasureShadowWork(shadow)
        integrator.setAccuracyCheck(False)   # its two 2 ps windows outlast a half protocol
    elif kind == "stock-middle" and shadow:
        integrator, a = openmm.CustomIntegrator(stepFs*1e-3), np.exp(-setups.FRICTION*stepFs*1e-3)
        for name, value in dict(a=a, b=np.sqrt(1 - a*a), kT=KT, shadow_work=0, ke=0).items():
            integrator.addGlobalVariable(name, value)
        integrator.addPerDofVariable("x1", 0.0)
        integrator.addPerDofVariable("v1", 0.0)
        for operation in MIDDLE.replace("\n", ";").split(";"):
            name, *arguments = operation.split(maxsplit=2)
            getattr(integrator, "add" + name)(*arguments)
    elif kind == "stock-middle":
        integrator = setups.makeIntegrator(kind, stepFs, seed)
    else:
        from openmmtools.integrators import LangevinIntegrator
        integrator = LangevinIntegrator(setups.TEMPERATURE*unit.kelvin, setups.FRICTION/unit.picosecond,
                                        stepFs*unit.femtosecond, splitting="V R O R V", measure_shadow_work=shadow)
    if not shadow:
        integrator.setConstraintTolerance(1e-5)
    integrator.setRandomNumberSeed(seed + 1)
    return integrator

def halfProtocol(context, integrator, kind, steps, seed, masses):
    """Velocities drawn at 300 K, `steps` steps: the shadow work (kT) with on-step velocities at both ends (BAOAB's). The
    rigid integrator holds velocities half a kick behind (its step is BAOAB's with the closing half kick joined to the
    next opening one; with substeps, half a kick of the slowest forces): its on-step kinetic energy puts the ends on step
    (terms of first order that would swamp the KL)."""
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
    count = max(len(seeds) for other, seeds in env.study.jobs(env.quick) if other["system"] == job["system"])
    built, bodies, frame = frames(job["system"], count, env)
    integrator = makeIntegrator(kind, job["step"], 10 + i, shadow=True, bodies=bodies)
    context = setups.context(built, integrator, frame(i), env.platform, env.properties)
    masses, steps = np.where(built.masses > 0, built.masses, np.inf), round(SETUP[env.quick]["protocol"]/stepPs)
    try:
        works = [halfProtocol(context, integrator, kind, steps, 100 + 2*i + k, masses) for k in (0, 1)]
    except openmm.OpenMMException as error:
        raise Unstable(f"frame {i}: {str(error).split('.')[0]}")
    if not np.all(np.isfinite(works)):
        raise Unstable(f"frame {i}: the shadow work is not finite")
    return works

def timeRows(rows, env):
    """ns/day of the rows' integrators as users run them, side by side, each from frame 0 of its system (interleaved blocks
    of 0.2 ps at the smallest step): {(system, integrator, step): ns/day}."""
    integrators, contexts = {}, []
    for row in rows:
        built, bodies, frame = frames(row["system"], 1, env)
        key = (row["system"], row["integrator"], row["step"])
        integrators[key] = makeIntegrator(row["integrator"], row["step"], 3, shadow=False, bodies=bodies)
        contexts.append(setups.context(built, integrators[key], frame(0), env.platform, env.properties))
        contexts[-1].setVelocitiesToTemperature(setups.TEMPERATURE, 3)
    try:
        steps = max(10, round(0.2/(min(row["step"] for row in rows)*1e-3)))
        wall = timeInterleaved(integrators, steps, 2 if env.quick else 5)[0]
    except TimingFailure:
        return {}
    return {key: nsPerDay(key[2], float(np.median(seconds))) for key, seconds in wall.items()}

def panel(name):
    """The family of a system: a protein for its models (timed and plotted together), else the system."""
    return name.partition("-")[0]

def summarize(results, env):
    """Per system, integrator and step (unless blocked): frames, KL and its standard error (kT), why it failed, ns/day."""
    rows = []
    for result in (result for result in results if not result["blocked"]):
        rows.append(dict(result["job"], frames=len(result["samples"]), failed=result["failed"]))
        if len(result["samples"]) > 1 and not result["failed"]:
            rows[-1]["kl"], rows[-1]["error"] = configurationKL(*np.array(result["samples"]).T)
    together = lambda row: panel(row["system"]) if "-" in row["system"] else (row["system"], row["step"])  # noqa: E731
    for group in dict.fromkeys(together(row) for row in rows if "kl" in row):   # a protein's models at all steps at once
        here = [row for row in rows if together(row) == group and "kl" in row]
        speeds = timeRows(here, env)
        for row in here:
            row["nsPerDay"] = speeds.get((row["system"], row["integrator"], row["step"]))
    return {"setup": dict(SETUP[env.quick], floor=FLOOR, friction=setups.FRICTION, xhFloor=XH_FLOOR, substeps=SUBSTEPS),
            "rows": rows}

def report(summary, page):
    """A section per system; a panel per family (panel()): a protein's models side by side."""
    names = list(dict.fromkeys(row["system"] for row in summary["rows"]))
    panels = list(dict.fromkeys(map(panel, names)))
    figure, axes = pyplot().subplots(1, len(panels), figsize=(5.5*len(panels), 4.2), squeeze=False)
    for name in names:
        mine, table, ax = [row for row in summary["rows"] if row["system"] == name], [], axes[0][panels.index(panel(name))]
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
            ax.errorbar(*np.array(points).T[:3], marker="o", capsize=3,
                        label=kind if name == panel(name) else f"{kind}, {name}")
            for x, y, _, step in points:
                ax.annotate(f"{step:g}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
    for name, ax in zip(panels, axes[0]):
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
rank the integrators; stock-middle's work spreads most (its water and peptide rows were run when the O stage's noise along
the constraints counted as work: a constant -n_c kT γt in ⟨w⟩, noise in the KL). The estimate's bias is not measured
(rigid-raised's 0.26 ± 0.07 kT at 2 fs is unexplained). ns/day: one timing per step. On the peptide the solute caps the step
before any integrator leaves its range.""",
    grid={"system": ["water", "peptide"], "integrator": KINDS, "step": [1, 2, 4, 6, 8, 10], "seed": list(range(50))},
    quick={"system": ["water216"], "integrator": KINDS, "step": [2, 10], "seed": [0, 1]},
    measure=measure, summarize=summarize)

"""Configuration-space KL divergence from Boltzmann's against the step and ns/day, from shadow work (Sivak, Chodera and Crooks,
Phys. Rev. X 3, 011007 (2013); Fass et al., Entropy 20, 318 (2018); estimator: rigidtesting.samplingerror.configurationKL)."""
import fcntl, functools, importlib.util
import numpy as np, openmm
from openmm import unit
import setups
from harness import Study, TimingFailure, Unstable, nsPerDay, pyplot, timeInterleaved
from rigidtesting.samplingerror import configurationKL

KJ, KT, FLOOR = unit.kilojoule_per_mole, setups.BOLTZMANN*setups.TEMPERATURE, 0.08   # FLOOR: rigid-raised's, amu nm^2
SETUP = {False: dict(protocol=2.0, spacing=2.0, equilibrate=20.0), True: dict(protocol=0.2, spacing=0.25, equilibrate=0.5)}  # ps
KINDS = ["rigid-exact", "rigid-nosquish", "rigid-raised", "stock-middle"] + (["openmmtools-vrorv"] if importlib.util.find_spec("openmmtools") else [])
# LangevinMiddleIntegrator's step (OpenMM's documentation) summing its shadow work: K + U after each step less K + U before it,
# less the heat its O stage added (halfProtocol sets work, heat and start before a run and adds the last step's part).
MIDDLE = """sum ke 0.5*m*v*v; global work work + ke + energy - start - heat; global start ke + energy; perDof v v + dt*f/m
constrainVelocities; perDof x x + 0.5*dt*v; sum ke 0.5*m*v*v; global heat -ke; perDof v a*v + b*sqrt(kT/m)*gaussian
sum ke 0.5*m*v*v; global heat heat + ke; perDof x x + 0.5*dt*v; perDof x1 x; constrainPositions; perDof v v + (x - x1)/dt"""

@functools.lru_cache(None)
def build(name):
    return setups.dipeptideInWater(500, barostat=False) if name == "peptide" else setups.water("tip3p", 216 if name == "water216" else 500)

def frames(name, count, env):
    """The system and a reader of its `count` equilibrium frames, made once (RigidBodyLangevinIntegrator, 1 fs, 5/ps)."""
    built = build(name)
    folder, setup = env.folder/f"frames-{name}", SETUP[env.quick]
    folder.mkdir(exist_ok=True)
    with open(folder/"lock", "a") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (folder/f"{count - 1}.xml").exists():
            integrator = setups.makeIntegrator("rigid-langevin", 1, seed=1, friction=5.0)
            start = setups.start(f"sampling-{name}", built, env.platform, env.properties, picoseconds=0.5 if env.quick else 5.0)
            context = setups.context(built, integrator, start, env.platform, env.properties)
            integrator.step(round(setup["equilibrate"]/0.001))
            for i in range(count):
                integrator.step(round(setup["spacing"]/0.001))
                (folder/f"{i}.xml").write_text(openmm.XmlSerializer.serialize(context.getState(getPositions=True)))
    return built, lambda i: openmm.XmlSerializer.deserialize((folder/f"{i}.xml").read_text())

def makeIntegrator(kind, stepFs, seed, shadow):
    """`kind` at 1/ps: with shadow, as measured (its shadow work summed); else as a user runs it (no accuracy check)."""
    if kind.startswith("rigid"):
        integrator = setups.makeIntegrator("rigid-langevin", stepFs, seed, floor=FLOOR if kind == "rigid-raised" else None,
                                            rotation="nosquish" if kind == "rigid-nosquish" else "exact")
        integrator.setMeasureShadowWork(shadow)
        integrator.setAccuracyCheck(False)   # its two 2 ps windows outlast a half protocol
    elif kind == "stock-middle" and shadow:
        integrator, a = openmm.CustomIntegrator(stepFs*1e-3), np.exp(-setups.FRICTION*stepFs*1e-3)
        for name, value in dict(a=a, b=np.sqrt(1 - a*a), kT=KT, work=0, heat=0, start=0, ke=0).items():
            integrator.addGlobalVariable(name, value)
        integrator.addPerDofVariable("x1", 0.0)
        integrator.addUpdateContextState()
        for operation, *arguments in (line.strip().split(" ", 2) for line in MIDDLE.replace("\n", ";").split(";")):
            getattr(integrator, {"sum": "addComputeSum", "global": "addComputeGlobal", "perDof": "addComputePerDof"}
                    .get(operation, "add" + operation[0].upper() + operation[1:]))(*arguments)
    elif kind == "stock-middle":
        integrator = setups.makeIntegrator(kind, stepFs, seed)
    else:
        from openmmtools.integrators import LangevinIntegrator
        integrator = LangevinIntegrator(temperature=setups.TEMPERATURE*unit.kelvin, collision_rate=setups.FRICTION/unit.picosecond,
                                        timestep=stepFs*unit.femtosecond, splitting="V R O R V", measure_shadow_work=shadow)
    integrator.setRandomNumberSeed(seed + 1)
    return integrator

def kinetic(context, masses=None, kick=0.0):
    """The kinetic energy (kJ/mol), after kicking the velocities by the forces for `kick` ps and projecting them."""
    if kick:
        state = context.getState(getVelocities=True, getForces=True)
        context.setVelocities(state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
                              + kick*state.getForces(asNumpy=True).value_in_unit(KJ/unit.nanometer)/masses[:, None])
        context.applyVelocityConstraints(1e-10)
    return context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)

def halfProtocol(context, integrator, kind, steps, seed, masses):
    """On-step velocities drawn at 300 K, `steps` steps: the shadow work (kT) with on-step velocities at both ends (BAOAB's,
    which openmmtools' VRORV measures). The LFMiddle integrators (rigid, stock-middle) hold velocities u half a kick behind,
    their step being BAOAB's with its closing half kick joined to the next opening one: W_BAOAB = W + [K(u_T + kick) -
    K(u_T)] - [K(v_0) - K(u_0)], end terms of first order in the step whose spread would otherwise swamp the KL."""
    if kind.startswith("rigid"):   # drawn for the bodies' own moments, taken half a kick back by the Context
        context.setVelocitiesToTemperature(setups.TEMPERATURE*unit.kelvin, seed)
        work = lambda: (integrator.getShadowWork() + integrator.getOnStepKineticEnergy()).value_in_unit(KJ) - kinetic(context)  # noqa: E731
        before = work()
        integrator.step(steps)
        return (work() - before)/KT
    context.setVelocities(np.random.default_rng(seed).standard_normal((len(masses), 3))*np.sqrt(KT/masses)[:, None])
    context.applyVelocityConstraints(1e-10)   # the constraints' share is no step's work
    if kind == "openmmtools-vrorv":
        integrator.reset_shadow_work()
        integrator.step(steps)
        return integrator.get_shadow_work(dimensionless=True)
    half, onStep = 0.5*integrator.getStepSize().value_in_unit(unit.picosecond), kinetic(context)
    ends = kinetic(context, masses, -half) - onStep   # K(u_0) - K(v_0)
    energy = lambda: context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(KJ) + kinetic(context)  # noqa: E731
    for name, value in dict(work=0.0, heat=0.0, start=energy()).items():
        integrator.setGlobalVariableByName(name, value)
    integrator.step(steps)
    work = energy() + sum(integrator.getGlobalVariableByName(name)*sign for name, sign in dict(work=1, start=-1, heat=-1).items())
    return (work + ends - kinetic(context) + kinetic(context, masses, half))/KT

def measure(job, env):
    """Frame i (the seed): the shadow works (kT) from it and from where they led, velocities drawn again (seeds 100 + 2i, 101 + 2i)."""
    i, kind = job["seed"], job["integrator"]
    built, frame = frames(job["system"], len(env.study.jobs(env.quick)[1]), env)
    integrator = makeIntegrator(kind, job["step"], 10 + i, shadow=True)
    context = setups.context(built, integrator, frame(i), env.platform, env.properties)
    masses, steps = np.where(built.masses > 0, built.masses, np.inf), round(SETUP[env.quick]["protocol"]/(job["step"]*1e-3))
    try:
        works = [halfProtocol(context, integrator, kind, steps, 100 + 2*i + k, masses) for k in (0, 1)]
    except openmm.OpenMMException as error:
        raise Unstable(f"frame {i}: {str(error).splitlines()[0][:120]}")
    if not np.all(np.isfinite(works)):
        raise Unstable(f"frame {i}: the shadow work is not finite")
    return works

def timeStep(name, stepFs, kinds, env):
    """ns/day at one step of the integrators as users run them, side by side from frame 0 (interleaved blocks of 0.2 ps)."""
    built, frame = frames(name, 1, env)
    integrators = {kind: makeIntegrator(kind, stepFs, 3, shadow=False) for kind in kinds}
    contexts = [setups.context(built, integrator, frame(0), env.platform, env.properties) for integrator in integrators.values()]
    for context in contexts:
        context.setVelocitiesToTemperature(setups.TEMPERATURE, 3)
    try:
        wall = timeInterleaved(integrators, max(10, round(0.2/(stepFs*1e-3))), 2 if env.quick else 5)[0]
    except TimingFailure:
        return {}
    return {kind: nsPerDay(stepFs, float(np.median(seconds))) for kind, seconds in wall.items()}

def summarize(results, env):
    """Per system, integrator and step (not blocked): frames, KL and its standard error (kT), why it failed, ns/day."""
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
    setup, rows, plt = summary["setup"], summary["rows"], pyplot()
    page.text(f"Half protocols of {setup['protocol']:g} ps, frames {setup['spacing']:g} ps apart, raised moments {setup['floor']:g} "
              "amu nm². KL in kT ± one standard error (a divergence is never negative).")
    names = list(dict.fromkeys(row["system"] for row in rows))
    figure, axes = plt.subplots(1, len(names), figsize=(5.5*len(names), 4.2), squeeze=False)
    for name, ax in zip(names, axes[0]):
        mine = [row for row in rows if row["system"] == name]
        page.section(name)
        page.table(["integrator", "step (fs)", "frames", "KL (kT)", "KL/error", "ns/day"], [
            [r["integrator"], r["step"], r["frames"] or ""] + ([f"{r['kl']:.3g} ± {r['error']:.2g}", f"{r['kl']/r['error']:.1f}",
             f"{r['nsPerDay']:.1f}" if r.get("nsPerDay") else ""] if "kl" in r else [f"unstable: {r['failed']}", "", ""]) for r in mine])
        for kind in dict.fromkeys(row["integrator"] for row in mine):
            points = [(p["nsPerDay"], p["kl"], p["error"], p["step"]) for p in mine if p["integrator"] == kind and p.get("nsPerDay")]
            if points:
                ax.errorbar(*list(zip(*points))[:3], marker="o", capsize=3, label=kind)
            for x, y, _, step in points:
                ax.annotate(f"{step:g}", (x, y), fontsize=7, xytext=(3, 3), textcoords="offset points")
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(yscale="symlog", xlabel="ns/day", ylabel="configuration-space KL (kT)", title=f"{name} (labels: step in fs)")
        ax.legend(fontsize=7)
    page.figure(figure, "kl", "KL divergence against ns/day, ± one standard error (symmetric-log axis: linear within ±2 kT)")

STUDY = Study(
    "sampling_error", "Configuration-space sampling error against the step",
    "In 500 TIP3P waters the configurations of RigidBodyLangevinIntegrator are within errors of the Boltzmann distribution from 1 to "
    "8 fs and off at 10 fs unless its moments are raised, where stock LangevinMiddleIntegrator is unstable; on the dipeptide with HMR "
    "every integrator fails at 6 fs.", report,
    method="""Systems: water, 500 rigid TIP3P (PME 0.9 nm); peptide, alanine dipeptide in 500 TIP3P (amber14, HBonds, 3 amu H); NVT,
300 K, friction 1/ps. Frames (the seeds), shared by the integrators: RigidBodyLangevinIntegrator at 1 fs and 5/ps, 20 ps, then one
every 2 ps. rigid-exact, rigid-nosquish: RigidBodyLangevinIntegrator's rotations; rigid-raised: moments raised to 0.08 amu nm²;
stock-middle: LangevinMiddleIntegrator + SETTLE as a CustomIntegrator summing its shadow work; openmmtools-vrorv: openmmtools' BAOAB.
Per frame: velocities drawn, 2 ps (shadow work w_π), drawn again, 2 ps (w_ω); KL ≈ (⟨w_π⟩ − ⟨w_ω⟩)/2 ± the standard error of the
paired halves, half-step-behind velocities corrected to on-step work at both ends. A failure stops the larger steps. ns/day: the
integrators as users run them (no shadow work, no check) side by side. Within errors of 0: |KL/error| ≤ 2.""",
    caveats="""Few frames (10 to 18 of 50): errors grow from 0.1 kT at 1 fs to 2 to 6 kT at 10 fs, so 2 to 8 fs does not rank the
integrators; stock-middle's work spreads the most (its O stage's noise along the constraints), its outliers are heavy tails. The
near-equilibrium estimate's bias is not measured (raised moments' 0.26 ± 0.07 kT at 2 fs is unexplained). ns/day: one timing of five
blocks per step, comparable within a step. On the peptide the solute caps the step before any integrator leaves its range.""",
    grid={"system": ["water", "peptide"], "integrator": KINDS, "step": [1, 2, 4, 6, 8, 10], "seed": list(range(50))},
    quick={"system": ["water216"], "integrator": KINDS, "step": [2, 10], "seed": [0, 1]}, measure=measure, summarize=summarize)

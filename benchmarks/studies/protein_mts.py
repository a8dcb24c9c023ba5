"""Rigid X-H groups and multiple time steps against stock OpenMM on a solvated protein. Another system: SYSTEMS, STARTS, the grid."""
import functools, itertools
import numpy as np, openmm, openmm.app as app
import openmmrigid, rigidtesting, setups
from harness import Study, Unstable, blockMean, overSeeds, blockSteps, nsPerDay, pyplot, rigidDegreesOfFreedom, timeInterleaved
from rigidtesting.bodies import integratorBodies, kineticEnergies
from setups import BOLTZMANN, FRICTION, KJ, TEMPERATURE

FLOOR, SUBSTEP = 0.16, 2.0   # the rigid rows' raised moments (amu nm^2); the bonded forces' substep (fs)
VARIANTS = {"plain": {}, "hmr": dict(hydrogenMass=3.0), "hangles": dict(hydrogenMass=3.0, constraints=app.HAngles, heavyWaterHydrogens=True)}
CONFIGURATIONS = {   # name: (label, model, steps (fs), system variant, integrator)
    "stock": ("stock LangevinMiddle", "flexible", [2], "plain", "stock"),
    "stock-hmr": ("stock LangevinMiddle, HMR 3 amu", "flexible", [4], "hmr", "stock"),
    "hangles": ("stock, H angles, HMR, heavy water H", "H angles", [2], "hangles", "stock"),
    "recipe": ("stock recipe (H angles, heavy water H, bonded 2 fs)", "H angles", [6, 8, 10], "hangles", "recipe"),
    "xh": ("rigid X-H groups", "rigid X-H", [2, 4, 5, 6], "plain", "rigid"),
    "xh-mts": ("rigid X-H groups + bonded 2 fs", "rigid X-H", [6, 8, 10, 12], "plain", "rigid-mts"),
    "mts": ("bonded 2 fs, X-H bonds constrained", "flexible", [4, 6, 8], "plain", "mts"),
    "stock-mts": ("stock MTSLangevinIntegrator, HMR 3 amu, bonded 2 fs", "flexible", [6, 8], "hmr", "stock-mts"),
    "xh-mts-1fs": ("rigid X-H groups + bonded 1 fs", "rigid X-H", [12], "plain", "rigid-mts"),
    "xh-mts-0.32": ("the same, moments raised to 0.32", "rigid X-H", [12], "plain", "rigid-mts"),
    "xh-mts-f5": ("the same, friction 5/ps", "rigid X-H", [12], "plain", "rigid-mts"),
    "planar": ("rigid X-H and planar groups", "rigid planar", [2], "plain", "rigid-planar"),
    "planar-mts": ("rigid X-H and planar groups + bonded 1 fs", "rigid planar", [8, 10, 12, 14], "plain", "rigid-planar-mts"),
    "planar-mts-2fs": ("rigid X-H and planar groups + bonded 2 fs", "rigid planar", [10, 12], "plain", "rigid-planar-mts")}
REFERENCE = {"flexible": ("stock", 2), "H angles": ("hangles", 2), "rigid X-H": ("xh", 2), "rigid planar": ("planar", 2)}
OVERRIDES = {"xh-mts-1fs": dict(substep=1.0), "xh-mts-0.32": dict(floor=0.32), "xh-mts-f5": dict(friction=5.0), "planar-mts": dict(substep=1.0)}   # of FLOOR, SUBSTEP, FRICTION
OWN = ["stock", "stock-hmr", "hangles", "recipe", "xh", "xh-mts", "mts"]   # this study's grid; the others are protein_step_cap's
FULL = dict(equilibrate_ps=1.0, sampled_ps=4.0, every_ps=0.1, timed_s=2.0, repetitions=5)
QUICK = dict(equilibrate_ps=0.02, sampled_ps=0.1, every_ps=0.01, timed_s=0.0, repetitions=2)
STARTS = {"villin": ("villin-tip3p-0.9nm", 5.0), "dipeptide": ("quick-dipeptide-tip3p-216", 0.2), "dhfr": ("dhfr-jac-tip3p", 5.0)}   # setups.start: name, ps
EXTRA = {"T_solute": ("T solute bias (K)", 1), "helix": ("helix bias", 3), "dihedral_rms": ("dihedral rms bias (deg)", 1)}   # runs since: column, digits

def dipeptide(hydrogenMass=None, constraints=app.HBonds):
    """Alanine dipeptide in 216 TIP3P waters (setups.dipeptideInWater, constant volume): the quick run's system."""
    return setups.dipeptideInWater(216, barostat=False, hydrogenMass=hydrogenMass, constraints=constraints)

SYSTEMS = {"villin": setups.villin, "dipeptide": dipeptide, "dhfr": setups.dhfr}   # builder(hydrogenMass, constraints)

@functools.lru_cache(maxsize=None)
def build(system, variant):
    """The system with a variant of VARIANTS, its bonded forces apart (setups.bondedApart)."""
    options = dict(VARIANTS[variant])
    heavy = options.pop("heavyWaterHydrogens", False)
    return setups.bondedApart(SYSTEMS[system](**options), heavy)

def stockRecipe(stepFs, substeps, temperature=TEMPERATURE, friction=FRICTION):
    """r-RESPA (Tuckerman, Berne & Martyna 1992) with the bonded forces (group 1) in `substeps` velocity Verlet steps and one exact O stage
    at the outer midpoint (BAOAB's place, Leimkuhler & Matthews 2013), a CustomIntegrator: V0 [V1 R V1]^(n/2) O [V1 R V1]^(n-n/2) V0."""
    dt, half = stepFs*1e-3, substeps//2
    integrator, h, a = openmm.CustomIntegrator(dt), dt/substeps, np.exp(-friction*dt)
    integrator.addPerDofVariable("x1", 0.0)
    integrator.addUpdateContextState()
    for stage in ["V0"] + ["V1", "R", "V1"]*half + ["O"] + ["V1", "R", "V1"]*(substeps - half) + ["V0"]:
        if stage == "R":   # a drift, constrained, with the velocities of the constrained drift
            integrator.addComputePerDof("x", f"x + {h}*v")
            integrator.addComputePerDof("x1", "x")
            integrator.addConstrainPositions()
            integrator.addComputePerDof("v", f"v + (x - x1)/{h}")
        elif stage == "O":
            integrator.addComputePerDof("v", f"{a}*v + {np.sqrt((1 - a*a)*BOLTZMANN*temperature)}*gaussian/sqrt(m)")
        else:
            integrator.addComputePerDof("v", f"v + {0.5*(dt if stage == 'V0' else h)}*f{stage[1]}/m")
        integrator.addConstrainVelocities()
    return integrator

def prepared(job, env):
    """(context, integrator, degrees of freedom) of a job: its system's equilibrated start, fresh velocities."""
    _, _, _, variant, kind = CONFIGURATIONS[job["configuration"]]
    built, step, seed, (name, picoseconds) = build(job["system"], variant), job["step"], job["seed"], STARTS[job["system"]]
    state = setups.start(name, build(job["system"], "plain"), env.platform, env.properties, picoseconds)
    bodies = openmmrigid.rigidHydrogenGroups(built.topology, built.system, planarGroups="planar" in kind) if kind.startswith("rigid") else None
    floor, substep, friction = (OVERRIDES.get(job["configuration"], {}).get(key, default)
                                for key, default in (("floor", FLOOR), ("substep", SUBSTEP), ("friction", FRICTION)))
    substeps = max(1, round(step/substep))
    integrator = (stockRecipe(step, max(2, substeps)) if kind == "recipe" else
                  openmm.MTSLangevinIntegrator(TEMPERATURE, friction, step*1e-3, [(0, 1), (1, substeps)]) if kind == "stock-mts" else
                  setups.makeIntegrator("stock-middle" if kind == "stock" else "rigid-langevin", step, seed, floor=floor, bodies=bodies,
                                        friction=friction))
    if kind.startswith("rigid") and kind.endswith("mts"): integrator.setForceGroupSubsteps([(0, 1), (1, substeps)])
    integrator.setConstraintTolerance(1e-5)   # OpenMM's default, what users run
    integrator.setRandomNumberSeed(seed + 1)
    context = setups.context(built, integrator, state, env.platform, env.properties, seed)
    if variant == "hangles": context.applyConstraints(1e-6)   # the start satisfies HBonds only
    context.setVelocitiesToTemperature(TEMPERATURE, seed + 1)
    return context, integrator, rigidtesting.degreesOfFreedom(built.system) if kind in ("stock", "recipe", "stock-mts") else rigidDegreesOfFreedom(context, integrator)

def solute(built):
    """The protein's particles, a mask: those of residues that are neither water nor one ion."""
    return np.array([atom.residue.name not in setups.WATER and len(atom.residue) > 1 for atom in built.topology.atoms()])

def soluteKinetic(context, integrator, inside):
    """(the kinetic energy (kJ/mol) of a State's particles in `inside` (a mask), their degrees of freedom), as the T column counts the
    whole system's: rigid motion in the raised moments (the State's; rigidtesting.bodies.kineticEnergies) of the bodies inside and the
    free particles, and harness.rigidDegreesOfFreedom of the part."""
    rigid = hasattr(integrator, "getNumBodies")
    bodies = [body for body in integratorBodies(integrator) if inside[body].all()] if rigid else []
    masses, floor = np.where(inside, rigidtesting.particleMasses(context.getSystem()), 0.0), integrator.getMinimumMomentOfInertia() if rigid else 0.0
    kinetic = lambda state: sum(kineticEnergies(state.getPositions(asNumpy=True)._value, state.getVelocities(asNumpy=True)._value, masses, bodies,
                                                floor, state.getPeriodicBoxVectors(asNumpy=True)._value))
    return kinetic, rigidDegreesOfFreedom(context, integrator, inside)

def helical(phi, psi):
    """Whether (phi, psi) (deg) is in the alpha-helical basin (xh_groups_model.analyse counts its share too)."""
    return (phi > -160) & (phi < -20) & (psi > -120) & (psi < 50)

def dihedralFluctuation(angles):
    """The rms fluctuation (deg) of each dihedral (columns of frames x dihedrals, deg) about its own circular mean, averaged over the dihedrals."""
    turns = np.exp(1j*np.radians(angles))
    return float(np.degrees(np.sqrt(np.mean(np.angle(turns/turns.mean(axis=0))**2, axis=0))).mean())

def measure(job, env):
    """One run: every `every_ps` U, T, the solute's bonded U, its temperature (soluteKinetic) and its share of alpha-helical (phi, psi), as block
    means and their errors (harness.blockMean); the rms fluctuation of phi and psi within the run (dihedralFluctuation; no error)."""
    from studies.xh_groups_model import backboneDihedrals, geometry   # here, not above: that module imports this one
    settings, step, samples, frames = QUICK if env.quick else FULL, job["step"], [], []
    context, integrator, dof = prepared(job, env)
    built = build(job["system"], CONFIGURATIONS[job["configuration"]][3])
    (kinetic, soluteDof), dihedrals = soluteKinetic(context, integrator, solute(built)), np.concatenate(backboneDihedrals(built.topology))
    try:
        integrator.step(round(settings["equilibrate_ps"]*1000/step))
        for _ in range(round(settings["sampled_ps"]/settings["every_ps"])):
            integrator.step(max(1, round(settings["every_ps"]*1000/step)))
            state, bonded = context.getState(getEnergy=True, getPositions=True, getVelocities=True), context.getState(getEnergy=True, groups={1})
            frames.append(geometry(state.getPositions(asNumpy=True)._value, dihedrals))
            samples.append([state.getPotentialEnergy().value_in_unit(KJ), 2*state.getKineticEnergy().value_in_unit(KJ)/(dof*BOLTZMANN),
                            bonded.getPotentialEnergy().value_in_unit(KJ), 2*kinetic(state)/(soluteDof*BOLTZMANN),
                            helical(*np.split(frames[-1], 2)).mean()])
    except openmm.OpenMMException as error:
        raise Unstable(str(error).split(";")[0])
    if not np.all(np.isfinite(samples)): raise Unstable(f"non-finite energy within {len(samples)*settings['every_ps']:g} ps")
    return dict({name: [float(v) for v in blockMean(column)] for name, column in zip(("U", "T", "bonded", "T_solute", "helix"), np.array(samples).T)},
                dihedral_rms=[dihedralFluctuation(frames), None])

def biasRows(results):
    """Rows: U, T, the solute's bonded U and the EXTRA observables its runs have ([mean, error]) over the seeds, and the biases of all but T
    against the model's reference (no error where a mean has none)."""
    rows = []
    for result in results:
        job, ok, samples = result["job"], result["samples"] and not result["failed"], result["samples"]
        rows.append(dict(job, against="{} model, {} fs".format(model := CONFIGURATIONS[job["configuration"]][1], REFERENCE[model][1]),
                         seeds=len(samples), failed=result["failed"] or ("blocked" if result["blocked"] else None),
                         **{k: overSeeds([s[k] for s in samples]) if ok else None for k in ("U", "T", "bonded")},
                         **{k: overSeeds([s[k] for s in samples]) for k in EXTRA if ok and all(k in s for s in samples)}))
    ran = {(row["system"], row["configuration"], row["step"]): row for row in rows if row["U"]}
    for row in ran.values():
        ref = ran.get((row["system"], *REFERENCE[CONFIGURATIONS[row["configuration"]][1]]))
        for k in [k for k in ("U", "bonded", *EXTRA) if k in row and k in (ref or {})]:
            row[f"{k}_bias"] = row[k][0] - ref[k][0]
            row[f"{k}_bias_error"] = None if None in (row[k][1], ref[k][1]) else float(np.hypot(row[k][1], ref[k][1]))
    return rows, ran

def summarize(results, env):
    """biasRows(), and every configuration that ran timed side by side (ns/day)."""
    settings, (rows, ran) = QUICK if env.quick else FULL, biasRows(results)
    for system in dict.fromkeys(row["system"] for row in rows):   # speed: one process, blocks interleaved
        kept = {key: prepared(dict(row, seed=0), env) for key, row in ran.items() if key[0] == system}   # contexts kept alive
        steps = 5 if env.quick else min(blockSteps(made[1], None, settings["timed_s"], 10) for made in kept.values())
        for key, times in timeInterleaved({key: made[1] for key, made in kept.items()}, steps, settings["repetitions"])[0].items():
            ran[key]["ns_per_day"] = nsPerDay(key[2], float(np.median(times)))
    return {"settings": dict(settings, floor=FLOOR, substep_fs=SUBSTEP), "rows": rows}

def accurateSteps(rows):
    """{configuration: its largest step up to which every step ran with U and the solute's bonded U within two combined errors}."""
    found, stopped = {}, set()
    for row in sorted(rows, key=lambda row: row["step"]):
        name = row["configuration"]
        if name not in stopped and row.get("U_bias") is not None and all(abs(row[k + "_bias"]) <= 2*row[k + "_bias_error"] for k in ("U", "bonded")):
            found[name] = row["step"]
        else:
            found.setdefault(name, None), stopped.add(name)
    return found

def section(page, title, text, rows):
    """A section: the text, then the rows' biases (bold beyond two errors; the EXTRA ones' only where rows have them), T, ns/day, x stock HMR
    4 fs, and the accurate steps."""
    page.section(title, text)
    bias = lambda row, k, f: "" if row.get(k + "_bias") is None else f"{row[k + '_bias']:+.{f}f}" if row[k + "_bias_error"] is None else (
        "**{}**" if abs(row[k + "_bias"]) > 2*row[k + "_bias_error"] else "{}").format(f"{row[k + '_bias']:+.{f}f} ± {row[k + '_bias_error']:.{f}f}")
    base, accurate = ([r.get("ns_per_day") for r in rows if (r["configuration"], r["step"]) == ("stock-hmr", 4)] + [None])[0], accurateSteps(rows)
    extra = [k for k in EXTRA if any(row.get(k) for row in rows)]
    page.table(["configuration", "step (fs)", "against", "U bias (kJ/mol)", "bonded U bias (kJ/mol)", *[EXTRA[k][0] for k in extra], "T (K)",
                "ns/day", "x stock HMR 4 fs", "accurate step"],
               [[CONFIGURATIONS[row["configuration"]][0], row["step"], row["against"], bias(row, "U", 0), bias(row, "bonded", 1),
                 *[bias(row, k, EXTRA[k][1]) for k in extra],
                 "" if row["T"] is None else f"{row['T'][0]:.1f}" + ("" if row["T"][1] is None else f" ± {row['T'][1]:.1f}"),
                 *([f"{row['ns_per_day']:.1f}", f"{row['ns_per_day']/(base or np.nan):.2f}"] if row.get("ns_per_day") else ["", ""]),
                 row["failed"] or ("reference" if (row["configuration"], row["step"]) in REFERENCE.values() else
                                   "**yes**" if accurate[row["configuration"]] == row["step"] else "")] for row in rows])

def biasFigure(page, name, rows):
    """The figure `name`: the biases of U and of the solute's bonded energy (± two errors) of each configuration against the outer step."""
    figure, axes = pyplot().subplots(1, 2, figsize=(11, 4))
    for (axis, k), (shift, configuration) in itertools.product(zip(axes, ("U", "bonded")), enumerate(dict.fromkeys(row["configuration"] for row in rows))):
        mine = [row for row in rows if row["configuration"] == configuration and row.get("U_bias") is not None]   # shifted apart by 0.06 fs each
        axis.errorbar([row["step"] + 0.06*shift for row in mine], [row[k + "_bias"] for row in mine], [2*row[k + "_bias_error"] for row in mine],
                      marker="o", capsize=3, label=CONFIGURATIONS[configuration][0])
        axis.set(xlabel="outer step (fs)", ylabel=f"{'U' if k == 'U' else 'solute bonded U'} - model at 2 fs (kJ/mol)")
    axes[1].legend(fontsize=7, loc="upper left")
    page.figure(figure, name, "Bias of U and of the solute's bonded energy (± two standard errors) against the outer step; 0: no bias")

def report(summary, page):
    for system in dict.fromkeys(row["system"] for row in summary["rows"]):
        rows = [row for row in summary["rows"] if row["system"] == system]
        accurate, speed = accurateSteps(rows), {(row["configuration"], row["step"]): row.get("ns_per_day") for row in rows}
        (ours, recipe), base = [speed.get((name, accurate.get(name))) for name in ("xh-mts", "recipe")], speed.get(("stock-hmr", 4))
        section(page, f"{system}: accuracy and speed", f"Accurate steps: rigid X-H groups with substeps {accurate['xh-mts']} fs, {ours/base:.2f} x stock "
                f"HMR at 4 fs; the recipe {accurate['recipe']} fs, {recipe/base:.2f} x: {ours/recipe:.2f} x the recipe." if ours and recipe and base else "", rows)
        biasFigure(page, system, rows)
    for earlier in summary.get("earlier", []):   # runs transcribed from the pages this one replaced
        section(page, earlier["title"], earlier["text"], earlier["rows"])

STUDY = Study(
    "protein_mts", "A solvated protein: rigid X-H groups and multiple time steps against stock OpenMM", report=report,
    claim="On villin in TIP3P, rigid X-H groups with raised moments and the bonded forces in 2 fs substeps keep U and the solute's bonded energy within "
          "two standard errors of their model up to 10 fs, at 2.16 times the ns/day of stock `LangevinMiddleIntegrator` with HMR at 4 fs and 2.45 "
          "times the best stock recipe at its own accurate step (8 fs).",
    method="""Villin (`setups.villin()`: amber14, TIP3P, PME 0.9 nm, HBonds; bonded forces in group 1), CPU. The stock recipe (`stockRecipe()`:
`constraints=HAngles`, HMR 3 amu, water O 10 and H 4 amu, bonded forces in 2 fs substeps, the O stage at the outer midpoint); rigid X-H groups
(`openmmrigid.rigidHydrogenGroups`, waters rigid too, moments raised to 0.16 amu nm^2), bonded forces in 2 fs substeps or not. Each model against
itself at 2 fs. A run: the equilibrated start, new velocities, 1 ps discarded, U, T and solute bonded U every 0.1 ps for 4 ps; a row: the mean of
3 runs, its standard error (a bias's combines the reference's); a configuration stops at its first failed step. Speed: one process, interleaved.""",
    caveats="""U is resolved to 100-200 kJ/mol: "accurate" means no bias seen at this resolution, as for stock HMR at 4 fs. T is not ruled on:
the recipe's on-step velocities read low by design (BAOAB's on-step kinetic temperature of a harmonic mode is T (1 - (omega dt/2)^2), its
positions exact). One small protein, CPU only. With six runs a row (protein_step_cap) the 2 fs substeps show a bonded-energy bias
of about +50 kJ/mol at every outer step, 1 fs substeps remove it up to 8 fs (1.65 times stock HMR 4 fs), and stock HMR at 4 fs
shows +328 kJ/mol in U: read this page's 10 fs at its resolution. protein_step_cap also measures planar groups (2.2 times at 10 fs on
villin, 1.9 on DHFR) and stock MTSLangevinIntegrator.""",
    grid=[{"system": ["villin"], "configuration": [name], "step": CONFIGURATIONS[name][2], "seed": [0, 1, 2]} for name in OWN],
    quick=[{"system": ["dipeptide"], "configuration": [name], "step": CONFIGURATIONS[name][2][:1], "seed": [0]} for name in OWN],
    measure=measure, summarize=summarize)

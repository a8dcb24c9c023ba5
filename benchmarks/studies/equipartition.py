"""Equipartition between translation and rotation of rigid water against the step (Asthagiri and Beck,
J. Chem. Theory Comput. 2024, arXiv 2308.08383: rigid SPC/E with SETTLE needs 0.5 fs for it)."""

import numpy as np
import openmm
import openmm.unit as unit

import setups
from harness import Study, Unstable, blockMean, overSeeds, pm, pyplot

NVE = ("stock-vv", "rigid-verlet", "rigid-verlet@0.04")
HELD_HALF_STEP = ("stock-middle", "rigid-langevin", "rigid-langevin@0.04")   # velocities half a step off the positions
REFERENCE = ("stock-middle", "stock-vrorv", "rigid-langevin")                 # at 1 fs, pooled: U_ref and C for T_conf
EVERY_PS, DISCARD_PS, PRODUCTION_PS = 0.02, 2.0, 8.0
MOLECULES = 400
MODELS = {"spce": "SPC/E", "tip3p": "TIP3P", "tip4pew": "TIP4P-Ew"}

# SPC/E as in the paper, every integrator over the step, four starts; TIP3P and TIP4P-Ew on a coarser grid.
GRID = [{"system": ["spce"], "integrator": ["stock-vv"], "step": [0.5, 1, 2, 3, 4, 5], "seed": range(4)},
        {"system": ["spce"], "integrator": ["rigid-verlet"], "step": [0.5, 1, 2, 3, 4, 6, 8], "seed": range(4)},
        {"system": ["spce"], "integrator": ["stock-middle", "stock-vrorv"], "step": [1, 2, 4], "seed": range(4)},
        {"system": ["spce"], "integrator": ["rigid-langevin"], "step": [1, 2, 4, 8], "seed": range(4)},
        {"system": ["spce"], "integrator": ["rigid-verlet@0.04", "rigid-langevin@0.04"], "step": [4, 8, 12], "seed": range(4)},
        # Not openmmtools' velocity Verlet with TIP4P-Ew: it heats with the virtual site (+27 kJ/mol in 1 ps at 1 fs, 216
        # waters, where stock VerletIntegrator stays within 3), so its temperatures say nothing of equipartition.
        {"system": ["tip3p"], "integrator": ["stock-vv"], "step": [1, 2, 4], "seed": range(2)},
        {"system": ["tip3p", "tip4pew"], "integrator": ["stock-middle"], "step": [1, 2, 4], "seed": range(2)},
        {"system": ["tip3p", "tip4pew"], "integrator": ["rigid-verlet", "rigid-langevin"], "step": [1, 2, 4, 8], "seed": range(2)},
        {"system": ["tip3p", "tip4pew"], "integrator": ["rigid-langevin@0.04"], "step": [8, 12], "seed": range(2)}]
QUICK = {"system": ["spce"], "integrator": ["stock-vv", "stock-middle", "rigid-langevin@0.04"], "step": [1, 4], "seed": [0]}


def measure(job, env):
    """One run: fresh velocities at 300 K, DISCARD_PS, then every EVERY_PS the waters' T_trans and T_rot
    (setups.waterTemperatures, the integrator's moments) and U per water for PRODUCTION_PS."""
    quick = env.quick
    built = setups.water(job["system"], 216 if quick else MOLECULES)
    state = setups.start(f"equipartition-{job['system']}-{len(built.waters)}", built, env.platform, env.properties)
    name, _, floor = job["integrator"].partition("@")
    floor = float(floor or 0)
    integrator = setups.makeIntegrator(name, job["step"], job["seed"], floor=floor)
    context = setups.context(built, integrator, state, env.platform, env.properties, job["seed"])
    context.setVelocitiesToTemperature(setups.TEMPERATURE*unit.kelvin, job["seed"] + 1)
    context.applyVelocityConstraints(1e-8)
    dt = job["step"]/1000
    every = max(1, int(round(EVERY_PS/dt)))
    discard, production = (0.2, 0.4) if quick else (DISCARD_PS, PRODUCTION_PS)
    samples = {"trans": [], "rot": [], "U": [], "onStep": []}
    try:
        integrator.step(int(round(discard/dt)))
        for _ in range(int(round(production/(every*dt)))):
            integrator.step(every)
            now = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
            u = now.getPotentialEnergy().value_in_unit(setups.KJ)/len(built.waters)
            if not np.isfinite(u) or u > 0:
                raise Unstable(f"U = {u:.3g} kJ/mol per water")
            box = now.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)
            trans, rot = setups.waterTemperatures(now.getPositions(asNumpy=True).value_in_unit(unit.nanometer),
                                                   now.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond),
                                                   built, floor, box)
            samples["trans"].append(trans)
            samples["rot"].append(rot)
            samples["U"].append(u)
            if hasattr(integrator, "getOnStepKineticEnergy"):   # BAOAB's on-step kinetic energy, whole system
                dof = 6*len(built.waters) - 3
                samples["onStep"].append(2*integrator.getOnStepKineticEnergy().value_in_unit(setups.KJ)/(dof*setups.BOLTZMANN))
    except openmm.OpenMMException as error:
        raise Unstable(str(error).splitlines()[0][:160])
    result = {}
    for key, values in samples.items():
        if values:
            result[key], result[key + "Error"] = (float(v) for v in blockMean(values))
    result["diff"], result["diffError"] = (float(v) for v in blockMean(np.subtract(samples["rot"], samples["trans"])))
    # Canonical fluctuation of U: the configurational heat capacity per water, Var(U_total) / (k T^2 N).
    result["heatCapacity"] = float(np.var(samples["U"])*len(built.waters)/(setups.BOLTZMANN*setups.TEMPERATURE**2))
    return result


def pooled(samples, key):
    """Mean over independent starts and its standard error (harness.overSeeds)."""
    estimates = [(sample[key], sample.get(key + "Error")) for sample in samples if sample.get(key) is not None]
    return overSeeds(estimates) if estimates else (None, None)


def summarize(results, env):
    """One row per job: T_trans, T_rot, their difference, U and T_conf = 300 K + (U - U_ref) / C, the temperature
    at which the reference would have this U per water: every Langevin run at 1 fs of the system pooled (U_ref their
    mean, C the mean of their configurational heat capacities per water, Var(U) / (k T^2 N))."""
    references = {}
    for r in results:
        if r["job"]["integrator"] in REFERENCE and r["job"]["step"] == 1:
            references.setdefault(r["job"]["system"], []).extend(r["samples"])
    rows = []
    for r in results:
        row = dict(r["job"], starts=len(r["samples"]), failed=r["failed"], blocked=r["blocked"])
        for key in ("trans", "rot", "diff", "U", "onStep"):
            row[key], row[key + "Error"] = pooled(r["samples"], key)
        reference = references.get(r["job"]["system"])
        if reference and row["U"] is not None:
            uRef, uRefError = pooled(reference, "U")
            capacity = float(np.mean([s["heatCapacity"] for s in reference]))
            row["conf"] = setups.TEMPERATURE + (row["U"] - uRef)/capacity
            row["confError"] = float(np.hypot(row["UError"] or 0, uRefError or 0)/capacity)
        rows.append(row)
    return rows


def quadraticShift(rows, system, integrator):
    """a +- its error in T_rot - T_trans = a dt^2, weighted least squares through the origin over the job's steps."""
    points = [(row["step"], row["diff"], row["diffError"]) for row in rows if row["system"] == system
              and row["integrator"] == integrator and row["diff"] is not None and row["diffError"]]
    if len(points) < 2:
        return None
    x, y, e = (np.array(column, dtype=float) for column in zip(*points))
    weights = x**4/e**2
    return float(np.sum(x**2*y/e**2)/np.sum(weights)), float(1/np.sqrt(np.sum(weights)))


def report(rows, page):
    fits = [(name, quadraticShift(rows, "spce", name)) for name in NVE + ("stock-vrorv",) + HELD_HALF_STEP]
    page.section("The shift against the step", "SPC/E, T_rot - T_trans fitted as a dt^2 over each integrator's steps "
                 "(K/fs^2; a second-order integrator's error in the momenta grows so):")
    page.table(["integrator", "a (K/fs^2)"], [[name, pm(fit, 3)] for name, fit in fits if fit])
    for system in dict.fromkeys(row["system"] for row in rows):
        page.section(MODELS.get(system, system), "T_rot - T_trans per run (K), means over independent starts +- the "
                     "standard error of their spread; T_conf: the temperature at which the reference's U matches "
                     "the run's (configurations too hot or cold); held velocities of LangevinMiddle and "
                     "RigidBodyLangevinIntegrator are half a step off the positions, so their T_trans and T_rot "
                     "are what a user reads, and T on-step is BAOAB's own on-step kinetic temperature (whole system).")
        table = []
        for row in (row for row in rows if row["system"] == system):
            status = row["failed"] or ("not run: a smaller step failed" if row["blocked"] else "")
            table.append([row["integrator"], f"{row['step']:g}", row["starts"], pm([row["trans"], row["transError"]], 1),
                          pm([row["rot"], row["rotError"]], 1), pm([row["diff"], row["diffError"]], 1),
                          pm([row.get("conf"), row.get("confError")], 1), pm([row["onStep"], row["onStepError"]], 1), status])
        page.table(["integrator", "step (fs)", "starts", "T_trans (K)", "T_rot (K)", "T_rot - T_trans (K)",
                    "T_conf (K)", "T on-step (K)", "failed"], table)
    plt = pyplot()
    figure, axes = plt.subplots(2, 2, figsize=(11, 7.5), sharex=True, sharey="row")
    spce = [row for row in rows if row["system"] == "spce" and row["diff"] is not None]
    for column, (title, names) in enumerate((("constant energy (on-step velocities)", NVE),
                                             ("Langevin (held velocities)", ("stock-middle", "stock-vrorv") + HELD_HALF_STEP[1:]))):
        for name in names:
            points = sorted((row["step"], row["diff"], row["diffError"] or 0, row.get("conf", np.nan) - setups.TEMPERATURE,
                             row.get("confError") or 0) for row in spce if row["integrator"] == name)
            if not points:
                continue
            x, diff, diffError, conf, confError = zip(*points)
            label = setups.INTEGRATORS.get(name.split("@")[0], name) + (f", moments raised to {name.split('@')[1]}" if "@" in name else "")
            axes[0, column].errorbar(x, diff, yerr=diffError, marker="o", capsize=3, label=label)
            axes[1, column].errorbar(x, conf, yerr=confError, marker="o", capsize=3, label=label)
        axes[0, column].set(title=f"SPC/E, {title}")
        axes[1, column].set(xlabel="step (fs)")
        axes[0, column].legend(fontsize=7)
        for row in (0, 1):
            axes[row, column].axhline(0, color="grey", lw=0.8)
    axes[0, 0].set_ylabel("T_rot - T_trans (K): the momenta")
    axes[1, 0].set_ylabel("T_conf - 300 K: the configurations")
    page.figure(figure, "spce", "SPC/E against the step: the kinetic partition the momenta read (top) and the temperature "
                "the configurations' U corresponds to (bottom), each integrator")


STUDY = Study(
    "equipartition", "Equipartition of rigid water between translation and rotation",
    claim="At constant energy the rotation of rigid SPC/E water reads colder than its translation as the step grows, "
          "by the same amount with SETTLE and with RigidBodyIntegrator (about 0.6 K per fs^2: 10 K at 4 fs, within 2 K at "
          "0.5 and 1 fs), as Asthagiri and Beck found, and by a fifth of it with moments raised to 0.04 amu nm^2; with a "
          "thermostat it is a reading of the momenta, not of the sampling: whatever partition the held velocities show "
          "(colder on-step, equal in LangevinMiddle, 15 K hotter in RigidBodyLangevinIntegrator at 8 fs), the "
          "configurations stay at the bath's temperature within the runs' resolution of about 4 K.",
    method=f"""
Boxes of {MOLECULES} rigid waters (SPC/E, as in Asthagiri and Beck, J. Chem. Theory Comput. 2024; TIP3P and
TIP4P-Ew; amber14 model files, PME 0.9 nm), equilibrated once with LangevinMiddleIntegrator + SETTLE (2 fs, 5 ps).
Each run draws fresh velocities at 300 K, runs {DISCARD_PS:g} ps and then samples every {EVERY_PS:g} ps for
{PRODUCTION_PS:g} ps. Every integrator's temperatures are computed by the same code from positions and velocities:
per molecule the centre-of-mass motion (T_trans, 3N - 3 degrees of freedom with the CMMotionRemover) and the rotation
about its principal axes, 1/2 sum_k I'_k w_k^2 with the moments the integrator moves it with (raised ones where
raised). Constant energy: openmmtools' VelocityVerletIntegrator + SETTLE (on-step velocities, as the paper) and
RigidBodyIntegrator. Constant temperature (1/ps): LangevinMiddleIntegrator as users run it, openmmtools' VRORV
(on-step velocities) and RigidBodyLangevinIntegrator. To separate what the momenta read from what the configurations
sample, T_conf converts each run's mean U per water into a temperature through the reference (every Langevin run at
1 fs pooled): T_conf = 300 K + (U - U_ref) / C, C = Var(U) / (k T^2 N) its configurational heat capacity per water.""",
    caveats="""
T_conf is resolved to about 3 K by four 8 ps runs (U per water to about 0.1 kJ/mol), so a configurational error
smaller than that is not excluded; it is linear in U about 300 K, and U is one scalar of the configurations, which can
be wrong in ways U does not see (nvt_accuracy compares g_OO too). At constant energy the large steps also heat the
configurations (T_conf 322 K at 8 fs with RigidBodyIntegrator): that is the energy drift of energy_drift, not
equipartition. The paper's 0.5 fs is not needed here for SETTLE to read equipartition within about 1 K: 1 fs does as well at
this resolution. openmmtools' VelocityVerletIntegrator is left out for TIP4P-Ew: with the virtual site it heats (+27
kJ/mol in 1 ps at 1 fs for 216 waters, where stock VerletIntegrator stays within 3). The TIP3P and TIP4P-Ew grids are
coarser, with two starts.""",
    grid=GRID, quick=QUICK, measure=measure, summarize=summarize, report=report)

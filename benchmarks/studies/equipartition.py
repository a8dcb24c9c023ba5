"""Equipartition between translation and rotation of rigid water against the step (Asthagiri and Beck,
J. Chem. Theory Comput. 2024, arXiv 2308.08383: rigid SPC/E with SETTLE needs 0.5 fs for it)."""

import numpy as np
import openmm
import openmm.unit as unit

import setups
from harness import Study, Unstable, blockMean, overSeeds, pyplot

NVE = ("stock-vv", "rigid-verlet", "rigid-verlet@0.04")
HELD_HALF_STEP = ("stock-middle", "rigid-langevin", "rigid-langevin@0.04")   # velocities half a step off the positions
REFERENCE = ("stock-middle", 1)                                               # U and its heat capacity: T_conf
EVERY_PS, DISCARD_PS, PRODUCTION_PS = 0.02, 2.0, 8.0
MOLECULES = 400

# SPC/E as in the paper, every integrator over the step, four starts; TIP3P and TIP4P-Ew on a coarser grid.
GRID = [{"system": ["spce"], "integrator": ["stock-vv"], "step": [0.5, 1, 2, 3, 4, 5], "seed": range(4)},
        {"system": ["spce"], "integrator": ["rigid-verlet"], "step": [0.5, 1, 2, 3, 4, 6, 8], "seed": range(4)},
        {"system": ["spce"], "integrator": ["stock-middle", "stock-vrorv"], "step": [1, 2, 4], "seed": range(4)},
        {"system": ["spce"], "integrator": ["rigid-langevin"], "step": [1, 2, 4, 8], "seed": range(4)},
        {"system": ["spce"], "integrator": ["rigid-verlet@0.04", "rigid-langevin@0.04"], "step": [4, 8, 12], "seed": range(4)},
        {"system": ["tip3p", "tip4pew"], "integrator": ["stock-vv", "stock-middle"], "step": [1, 2, 4], "seed": range(2)},
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
    """One row per job: T_trans, T_rot, their difference, U and T_conf = 300 K + (U - U_ref) / C_ref, the
    temperature at which the reference (stock LangevinMiddle, 1 fs) would have this U per water, C_ref its
    configurational heat capacity per water from the canonical fluctuation of U."""
    references = {r["job"]["system"]: r for r in results
                  if (r["job"]["integrator"], r["job"]["step"]) == REFERENCE and r["samples"]}
    rows = []
    for r in results:
        row = dict(r["job"], starts=len(r["samples"]), failed=r["failed"], blocked=r["blocked"])
        for key in ("trans", "rot", "diff", "U", "onStep"):
            row[key], row[key + "Error"] = pooled(r["samples"], key)
        reference = references.get(r["job"]["system"])
        if reference and row["U"] is not None:
            uRef, uRefError = pooled(reference["samples"], "U")
            capacity = float(np.mean([s["heatCapacity"] for s in reference["samples"]]))
            row["conf"] = setups.TEMPERATURE + (row["U"] - uRef)/capacity
            row["confError"] = float(np.hypot(row["UError"] or 0, uRefError or 0)/capacity)
        rows.append(row)
    return rows


def cell(value, error, digits=1):
    return "" if value is None else f"{value:.{digits}f} +- {error:.{digits}f}" if error is not None else f"{value:.{digits}f}"


def report(rows, page):
    for system in dict.fromkeys(row["system"] for row in rows):
        page.section(f"{system.upper()}", "T_rot - T_trans per run (K), means over independent starts +- the "
                     "standard error of their spread; T_conf: the temperature at which the reference's U matches "
                     "the run's (configurations too hot or cold); held velocities of LangevinMiddle and "
                     "RigidBodyLangevinIntegrator are half a step off the positions, so their T_trans and T_rot "
                     "are what a user reads, and T on-step is BAOAB's own on-step kinetic temperature (whole system).")
        table = []
        for row in (row for row in rows if row["system"] == system):
            status = row["failed"] or ("not run: a smaller step failed" if row["blocked"] else "")
            table.append([row["integrator"], f"{row['step']:g}", row["starts"], cell(row["trans"], row["transError"]),
                          cell(row["rot"], row["rotError"]), cell(row["diff"], row["diffError"]),
                          cell(row.get("conf"), row.get("confError")), cell(row["onStep"], row["onStepError"]), status])
        page.table(["integrator", "step (fs)", "starts", "T_trans (K)", "T_rot (K)", "T_rot - T_trans (K)",
                    "T_conf (K)", "T on-step (K)", "failed"], table)
    plt = pyplot()
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.2), sharey=True)
    spce = [row for row in rows if row["system"] == "spce" and row["diff"] is not None]
    for ax, title, names in ((axes[0], "constant energy (on-step velocities)", NVE),
                             (axes[1], "Langevin (held velocities)", ("stock-middle", "stock-vrorv") + HELD_HALF_STEP[1:])):
        for name in names:
            points = sorted((row["step"], row["diff"], row["diffError"] or 0) for row in spce if row["integrator"] == name)
            if points:
                x, y, e = zip(*points)
                ax.errorbar(x, y, yerr=e, marker="o", capsize=3, label=setups.INTEGRATORS.get(name.split("@")[0], name)
                            + (f", moments raised to {name.split('@')[1]}" if "@" in name else ""))
        ax.axhline(0, color="grey", lw=0.8)
        ax.set(title=f"SPC/E, {title}", xlabel="step (fs)")
        ax.legend(fontsize=7)
    axes[0].set_ylabel("T_rot - T_trans (K)")
    page.figure(figure, "spce", "T_rot - T_trans of SPC/E against the step, each integrator")


STUDY = Study(
    "equipartition", "Equipartition of rigid water between translation and rotation",
    claim="PENDING",
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
sample, T_conf converts each run's mean U per water into a temperature through the reference (LangevinMiddle at
1 fs): T_conf = 300 K + (U - U_ref) / C, C = Var(U) / (k T^2 N) its configurational heat capacity per water.""",
    caveats="""
T_conf is linear in U about 300 K, and U is one scalar of the configurations: configurations can be wrong in ways U
does not see (the orientational structure; nvt_accuracy compares g_OO and diffusion too). The constant-energy runs
start from fresh 300 K velocities, so their total energies differ slightly from start to start; T_rot - T_trans does
not depend on the energy. The TIP3P and TIP4P-Ew grids are coarser, with two starts.""",
    grid=GRID, quick=QUICK, measure=measure, summarize=summarize, report=report)

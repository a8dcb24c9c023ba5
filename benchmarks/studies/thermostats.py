"""Thermostats: the temperature each one reads against the step (NVT), and NPT sampling against stock."""

import numpy as np
import openmm
from openmm import app, unit

import rigidtesting
import setups
from harness import Study, Unstable, blockMean, molecularKineticEnergies, pyplot, radialDistribution

NVT, NPT = "tip3p-rf", "tip4pew-npt"
NAMES = {"rigid-bussi": "RigidBodyBussiIntegrator (0.1 ps)", "rigid-langevin": "RigidBodyLangevinIntegrator",
         "stock-middle": "LangevinMiddleIntegrator + SETTLE"}
BLOCKS, SIGMAS = {NVT: 20, NPT: 10}, 3         # block means per run; a part reads the bath within SIGMAS errors
KEYS = ("reported", "translational", "rotational", "potential", "density")
QUANTITIES = [("density", "density (g/mL)", 4), ("potential", "U/molecule (kJ/mol)", 3), ("translational", "T trans (K)", 1),
              ("rotational", "T rot (K)", 1), ("peak", "g_OO first peak", 3)]


def build(name, env):
    """(Built, equilibrated start; quick: shorter, 207 waters for NPT): NVT, 102 TIP3P waters, reaction field 0.6 nm, no
    CMMotionRemover; NPT, 478 TIP4P-Ew waters at liquid density, PME 0.9 nm, CMMotionRemover, MonteCarloBarostat."""
    if name == NVT:
        built, ps = setups.water("tip3p", None, edge=1.5, nonbondedMethod=app.CutoffPeriodic,
                                  nonbondedCutoff=0.6*unit.nanometer, removeCMMotion=False), 2 if env.quick else 10
    else:
        built, ps = setups.water("tip4pew", None, barostat=True, edge=1.87 if env.quick else 2.4646), 0.2 if env.quick else 20
    return built, setups.start(f"thermostats-{name}" + "-quick"*env.quick, built, env.platform, env.properties, picoseconds=ps)


def firstPeak(radii, g):
    """Height and position of the first maximum of g_OO(r) (rows of g: curves), between 0.25 and 0.32 nm."""
    window = (radii > 0.25) & (radii < 0.32)
    return g[..., window].max(axis=-1), radii[window][np.argmax(g[..., window], axis=-1)]


def measure(job, env):
    npt, stepFs = job["system"] == NPT, job["step"]
    blocks = 5 if env.quick and npt else BLOCKS[job["system"]]
    discard, sample = (0.2, 1.0 if npt else 0.4) if env.quick else (5, 60) if npt else (2, 20)   # ps
    built, state = build(job["system"], env)
    integrator = setups.makeIntegrator(job["integrator"], stepFs, job["seed"], friction=1 if npt else 10)
    context = setups.context(built, integrator, state, env.platform, env.properties, job["seed"])
    every, dof, n = int(round(100/stepFs)) if npt else 4, rigidtesting.degreesOfFreedom(built.system), len(built.waters)
    series, frames, boxes = {key: [] for key in KEYS}, [], []
    try:
        integrator.step(int(round(discard*1000/stepFs)))
        for count in range(int(round(sample*1000/stepFs))//every):
            integrator.step(every)
            now = context.getState(getEnergy=True, getPositions=True, getVelocities=True)
            x = now.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            box = np.diag(now.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer))
            v = now.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
            kinetic = [now.getKineticEnergy().value_in_unit(setups.KJ), *molecularKineticEnergies(v, built.masses, built.waters)]
            for key, value in zip(KEYS, [2*e/(f*setups.BOLTZMANN) for e, f in zip(kinetic, (dof, dof - 3*n, 3*n))] + [
                    now.getPotentialEnergy().value_in_unit(setups.KJ)/n, built.masses.sum()/np.prod(box)*1.66053906660e-3]):
                series[key].append(value)
            if npt and count % 2:                        # every 0.2 ps, the oxygens for g_OO
                frames.append(x[built.oxygens])
                boxes.append(box)
    except openmm.OpenMMException as error:
        raise Unstable(str(error).splitlines()[0][:120])
    if not all(np.all(np.isfinite(values)) for values in series.values()):
        raise Unstable("NaN")
    result = {key: list(blockMean(values, blocks)) for key, values in series.items()}
    if frames:
        radii, g = radialDistribution(np.array(frames), np.array(boxes), 1.0, 0.005)
        heights = firstPeak(radii, g[:len(g)//blocks*blocks].reshape(blocks, -1, g.shape[1]).mean(axis=1))[0]  # of block means
        result.update(peak=[heights.mean(), heights.std(ddof=1)/np.sqrt(blocks)], peakAt=firstPeak(radii, g.mean(0))[1])
    return result


def summarize(results, env):                         # a row per run: one seed a job, the errors from blocks in time
    return [dict(r["job"], failed=r["failed"] or ("blocked" if r["blocked"] else None),
                 **(r["samples"][0] if r["samples"] else {})) for r in results]


def pm(v, digits, target=None):                      # mean ± error (with a target: the distance from it in errors)
    return f"{v[0]:.{digits}f} ± {v[1]:.{digits}f}" + (f" ({(v[0] - target)/v[1]:+.1f} σ)" if target is not None else "")


def report(summary, page):
    nvt = sorted([r for r in summary if r["system"] == NVT], key=lambda r: r["step"])
    npt = {(r["step"], r["integrator"]): r for r in summary if r["system"] == NPT and not r["failed"]}
    page.section("The temperature each thermostat reads", f"TIP3P, 300 K; ± one standard error of {BLOCKS[NVT]} block means, "
                 f"in σ: the distance from 300 K; the bath is read if translation and rotation are within {SIGMAS} σ.")
    page.table(["integrator", "step (fs)", "T reported (K)", "T trans (K)", "T rot (K)", "U/molecule (kJ/mol)", "reads 300 K"],
               [[NAMES[r["integrator"]], r["step"]] + ([f"failed: {r['failed']}"] + [""]*5 if r["failed"] else
                [pm(r["reported"], 1), pm(r["translational"], 1, 300), pm(r["rotational"], 1, 300), pm(r["potential"], 3),
                 "yes" if all(abs(r[k][0] - 300) <= SIGMAS*r[k][1] for k in KEYS[1:3]) else "**no**"]) for r in nvt])
    figure, axes = pyplot().subplots(1, 2, figsize=(9, 3.6), sharey=True)
    for axis, key in zip(axes, KEYS[1:3]):
        for offset, name in zip((-0.12, 0, 0.12), NAMES):
            done = [r for r in nvt if r["integrator"] == name and not r["failed"]]
            axis.errorbar([r["step"] + offset for r in done], [r[key][0] for r in done], [r[key][1] for r in done],
                          marker="o", capsize=3, label=NAMES[name])
        axis.axhline(setups.TEMPERATURE, color="black", linewidth=0.8, linestyle=":")
        axis.set(title=f"{key} temperature", xlabel="step (fs)", ylabel="K (± one standard error)")
    axes[0].legend(fontsize=8)
    page.figure(figure, "temperatures", "Translational and rotational temperature of the waters against the step")
    page.section("Constant pressure against stock", f"TIP4P-Ew, MonteCarloBarostat (1 bar), 300 K, friction 1/ps; ± one "
                 f"standard error of {BLOCKS[NPT]} block means; the difference in their combined errors. g_OO peaks at "
                 + ", ".join(sorted({f"{r['peakAt']:.3f}" for r in npt.values()})) + " nm.")
    page.table(["quantity", "step (fs)", NAMES["rigid-langevin"], NAMES["stock-middle"], "difference (σ)"],
               [[title, step, pm(rigid[key], digits), pm(stock[key], digits),
                 f"{(rigid[key][0] - stock[key][0])/np.hypot(rigid[key][1], stock[key][1]):+.1f}"]
                for key, title, digits in QUANTITIES for step in sorted({step for step, _ in npt})
                for rigid, stock in [(npt.get((step, "rigid-langevin")), npt.get((step, "stock-middle")))]
                if rigid and stock and key in rigid])


STUDY = Study(
    "thermostats", "The thermostats: the temperature they read, and NPT sampling against stock",
    "RigidBodyLangevinIntegrator reads the bath's temperature in translation and rotation at every step up to 8 fs "
    "and, under a barostat, samples stock's density, energy and water structure at 2 and 4 fs (within 2.6 standard "
    "errors), while "
    "RigidBodyBussiIntegrator holds the total right by construction but splits it wrongly between translation and "
    "rotation above 4 fs, and LangevinMiddleIntegrator + SETTLE reads the rotation hot from 2 fs.",
    report,
    method="""
Each system is equilibrated once (stock LangevinMiddleIntegrator + SETTLE, 2 fs); each run discards a stretch, then samples
the temperature the integrator reports (the State's kinetic energy over the stock degrees of freedom), the waters'
translational temperature (their centres' kinetic energy over 3N, less 3 with a CMMotionRemover) and rotational one (the
rest of their kinetic energy over 3N), alike for every integrator from the State's velocities, the potential energy per
molecule and the density. RigidBodyBussiIntegrator: stochastic velocity rescaling (Bussi, Donadio and Parrinello, J. Chem.
Phys. 126, 014101 (2007)), 0.1 ps, `Verlet` splitting, on-step velocities; the Langevin integrators' velocities are half a
step off the positions. **NVT**: 102 TIP3P waters (amber14, reaction field 0.6 nm, no CMMotionRemover), friction 10/ps; 2 ps
discarded, 20 ps sampled every 4 steps. **NPT**: 478 TIP4P-Ew waters, PME 0.9 nm, MonteCarloBarostat (1 bar, every 25
steps), friction 1/ps; 5 ps discarded, 60 ps sampled every 0.1 ps, every 0.2 ps the O-O radial distribution (0.005 nm bins
to 1 nm), whose first peak is the mean of each block curve's maximum.
""",
    caveats="""
One run per cell, errors from blocks in time: the density under a Monte Carlo barostat and the temperatures at friction 1/ps
correlate over picoseconds, so 6 ps blocks may understate them (two stock runs of 60 ps have differed by 2 errors in density).
Stock's "rotation" is all its kinetic energy beyond the centres', not only a rigid rotation of the on-step positions. Small
boxes: this compares thermostats, not water models, nor other observables at large steps, nor Bussi with other splittings.
""",
    grid=[dict(system=[NVT], integrator=list(NAMES), step=[1, 2, 4, 6, 8], seed=[0]),
          dict(system=[NPT], integrator=list(NAMES)[1:], step=[2, 4], seed=[0])],
    quick=[dict(system=[NVT], integrator=list(NAMES), step=[4], seed=[0]),
           dict(system=[NPT], integrator=list(NAMES)[1:], step=[4], seed=[0])],
    measure=measure, summarize=summarize)

"""Sampling rigid water (and alanine dipeptide in water) at constant temperature (and pressure), shared by studies.

sample(system, config, step, seed, env): a run from the system's equilibrated start `seed`, velocities drawn for the
configuration's masses and moments, `discard` ps dropped, then a sample every `every` ps for `time` ps: {observable:
[mean, standard error]} (harness.blockMean) of U (potential energy per water, kJ/mol), density (g/mL), T (2 KE/(dof k),
the integrator's dof), gShell (g_OO over 0.265-0.295 nm); kinetic=True: Ttrans (centres of mass, 3N - 3 dof), Trot (the
rest of the State's kinetic energy, 3N dof: raised moments count with their inertia), Taxes (L_k^2/(2 I_k) per principal
axis, ascending moments, N dof each); dynamics=True: D, tauRot, tauU of the waters (diffusion(), rotationalTime(),
autocorrelationTime() of U). A quick run samples 0.5 ps after 0.1 ps; an unstable one raises harness.Unstable.
reduce() and compare() pool jobs into rows; timeSteps() times runs side by side.
"""

import collections
import functools
import zlib

import numpy as np
import openmm
from openmm import unit

import harness
import rigidtesting
import setups

WATERS, QUICK_WATERS = 500, 216
G_SHELL, RDF_MAX, RDF_BIN = (0.265, 0.295), 0.9, 0.005      # nm
HEAVY_HYDROGEN = 4.0     # amu: water H in stock's mass repartitioning, the oxygen lighter by as much
TOLERANCE = 0.1          # kJ/mol per water: a bias taken as accurate (about the spread of 20 ps runs)
SYSTEMS = {f"{m}-{e}": dict(model=m, npt=e == "npt") for m in ("tip3p", "tip4pew") for e in ("nvt", "npt")}
SYSTEMS["protein"] = dict(model="tip3p", npt=True, peptide=True)        # setups.dipeptideInWater: HBonds, HMR 3 amu
# setups.makeIntegrator's name and options (friction too); heavy: water H at HEAVY_HYDROGEN; masses: every mass times it.
CONFIGS = {"stock": dict(integrator="stock-middle"), "stock-heavy": dict(integrator="stock-middle", heavy=True),
           "stock-heavy-mass2": dict(integrator="stock-middle", heavy=True, masses=2.0), "rigid": dict(integrator="rigid-langevin"),
           "exact": dict(integrator="rigid-langevin", rotation="exact"), "nosquish": dict(integrator="rigid-langevin", rotation="nosquish"),
           **{f"raised-{f:g}": dict(integrator="rigid-langevin", floor=f) for f in (0.04, 0.08, 0.16)},
           "raised-0.16-mass2": dict(integrator="rigid-langevin", floor=0.16, masses=2.0)}

@functools.lru_cache(maxsize=None)
def built(name, quick):
    """The system's NPT model (setups.Built); a quick run's has QUICK_WATERS."""
    spec, count = SYSTEMS[name], QUICK_WATERS if quick else WATERS
    return setups.dipeptideInWater(count) if spec.get("peptide") else setups.water(spec["model"], count, barostat=True)

def contextFor(name, config, step, seed, env):
    """(Built, Context, integrator) of a run from start `seed` (the NPT model equilibrated 20 ps by stock with that seed;
    NVT drops the barostat) with its masses, and velocities drawn for its masses and moments."""
    model, spec = built(name, env.quick), SYSTEMS[name]
    system = openmm.XmlSerializer.clone(model.system) if spec["npt"] else setups.withoutBarostat(model.system)
    masses, water = model.masses.copy(), model.waters
    if config.get("heavy"):
        masses[water[:, 0]] -= (HEAVY_HYDROGEN - masses[water[:, 1:]]).sum(axis=1)
        masses[water[:, 1:]] = HEAVY_HYDROGEN
    for index, mass in enumerate(masses*config.get("masses", 1.0)):
        system.setParticleMass(index, mass)
    tag = f"sampling-{spec['model']}{'-peptide' * bool(spec.get('peptide'))}-{seed}{'-quick' * env.quick}"
    start = setups.start(tag, model, env.platform, env.properties, 0.2 if env.quick else 20.0, seed + 1)
    runSeed = 1000*seed + (zlib.crc32(repr(sorted(config.items())).encode()) + int(10*step)) % 1000
    integrator = setups.makeIntegrator(config["integrator"], step, runSeed, floor=config.get("floor"),
                                        friction=config.get("friction", setups.FRICTION), rotation=config.get("rotation"))
    context = setups.context(model, integrator, start, env.platform, env.properties, runSeed, system)
    context.setVelocitiesToTemperature(setups.TEMPERATURE, runSeed)
    return model, context, integrator

def sample(name, config, step, seed, env, time=20.0, discard=2.0, every=0.1, kinetic=False, dynamics=False):
    """One run (the module's docstring); config: a CONFIGS name or such a dict."""
    config = CONFIGS[config] if isinstance(config, str) else config
    model, context, integrator = contextFor(name, config, step, seed, env)
    system, water, n, kB = context.getSystem(), model.waters, len(model.waters), setups.BOLTZMANN
    rigid = config["integrator"].startswith("rigid")
    dof = harness.rigidDegreesOfFreedom(context, integrator) if rigid else rigidtesting.degreesOfFreedom(system)
    masses, every = setups.rigidtesting.particleMasses(system), max(1, round(every*1000/step))*step/1000
    series, oxygens, boxes, axes = collections.defaultdict(list), [], [], []
    time, discard = (0.5, 0.1) if env.quick else (time, discard)
    try:
        integrator.step(round(discard*1000/step))
        for _ in range(round(time/every)):
            integrator.step(round(every*1000/step))
            state = context.getState(getEnergy=True, getPositions=True, getVelocities=kinetic)
            U, K = state.getPotentialEnergy().value_in_unit(setups.KJ)/n, state.getKineticEnergy().value_in_unit(setups.KJ)
            if not np.isfinite(U + K) or U > 0:
                raise harness.Unstable(f"energy {U:.3g} kJ/mol per water")
            x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            boxes.append(np.diag(state.getPeriodicBoxVectors(asNumpy=True).value_in_unit(unit.nanometer)))
            series["U"].append(U)
            series["density"].append(masses.sum()/np.prod(boxes[-1])*1.66053906660e-3)      # amu/nm^3 in g/mL
            series["T"].append(2*K/(dof*kB))
            if kinetic:
                v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
                translational, perAxis = harness.principalKineticEnergies(x, v, masses, water)
                series["Ttrans"].append(2*translational/((3*n - 3)*kB))
                series["Trot"].append(2*(K - translational)/(3*n*kB))
                series["Taxes"].append(2*perAxis/(n*kB))
            oxygens.append(x[water[:, 0]])
            axes.append((u := x[water[:, 1:]].mean(axis=1) - oxygens[-1])/np.linalg.norm(u, axis=1)[:, None])   # dipole axes
    except openmm.OpenMMException as error:
        raise harness.Unstable(str(error).splitlines()[0][:160]) from error
    radii, g = harness.radialDistribution(oxygens, boxes, RDF_MAX, RDF_BIN)
    series["gShell"] = shellMean(radii, g)
    dynamics = dict(D=diffusion(np.array(oxygens), np.array(boxes), every), tauRot=rotationalTime(np.array(axes), every),
                    tauU=autocorrelationTime(series["U"], every)) if dynamics else {}
    return {key: [np.asarray(v).tolist() for v in harness.blockMean(np.array(values))] for key, values in series.items()} | dynamics

def diffusion(positions, boxes, every, lags=(1.0, 5.0)):
    """D (1e-5 cm^2/s) by Einstein's MSD(t) = 6 D t over lags of 1 to 5 ps, paths unwrapped by minimum-image steps."""
    path = np.cumsum([0*positions[0]] + [s - b*np.round(s/b) for s, b in zip(np.diff(positions, axis=0), boxes[1:])], axis=0)
    k = np.arange(max(1, round(lags[0]/every)), min(round(lags[1]/every), len(path)//2) + 1)
    msd = [np.mean(np.sum((path[j:] - path[:-j])**2, axis=-1)) for j in k]
    return float(np.polyfit(k*every, msd, 1)[0]/6*1e3) if len(k) > 1 else np.nan      # 1 nm^2/ps = 1e3 x 1e-5 cm^2/s

def rotationalTime(axes, every, window=10.0):
    """tau_1 (ps) of unit vectors: C_1(t) = <u(0).u(t)> fitted by exp(-t/tau_1) where 0.15 < C_1 < 0.85, lags to 10 ps."""
    k = np.arange(1, min(len(axes)//2, round(window/every)))
    c = np.array([np.mean(np.sum(axes[j:]*axes[:-j], axis=-1)) for j in k])
    return float(-1/np.polyfit(k[use]*every, np.log(c[use]), 1)[0]) if (use := (c > 0.15) & (c < 0.85)).sum() > 1 else np.nan

def autocorrelationTime(values, every, c=5.0):
    """Integrated autocorrelation time (ps), every (1/2 + sum_k rho_k) to the first k >= c tau (Sokal's window)."""
    x = np.asarray(values, dtype=float) - np.mean(values)
    tau = 0.5 + np.cumsum(np.fft.irfft(np.abs(np.fft.rfft(x, 2*len(x)))**2)[1:len(x)])/np.dot(x, x)
    stop = np.nonzero(np.arange(1, len(x)) >= c*tau)[0]
    return float(every*tau[stop[0] if len(stop) else -1])

def shellMean(radii, g, shell=G_SHELL):
    """g(r) averaged by volume over the bins centred in the shell: the pairs there over an ideal gas's (last axis)."""
    inside = (radii > shell[0]) & (radii < shell[1])
    volume = (radii[inside] + RDF_BIN/2)**3 - (radii[inside] - RDF_BIN/2)**3
    return np.asarray(g)[..., inside]@volume/volume.sum()

def timeSteps(name, runs, env, steps=100, repetitions=9, contexts=1):
    """ms/step of runs {label: (config, step)} side by side (harness.timeInterleaved), `contexts` Contexts each (two of
    one configuration differ by up to 4 %), medians of the blocks, the accuracy check on; None: unstable while timed."""
    bound = {(label, copy): contextFor(name, CONFIGS[config], step, copy, env)[1:]
             for label, (config, step) in runs.items() for copy in range(contexts)}
    try:
        wall, _ = harness.timeInterleaved({key: pair[1] for key, pair in bound.items()}, steps, repetitions)
    except harness.TimingFailure as failure:
        rest = {label: run for label, run in runs.items() if label != failure.label[0]}
        return {failure.label[0]: None} | timeSteps(name, rest, env, steps, repetitions, contexts)
    return {label: 1000*float(np.median([t for key, ts in wall.items() if key[0] == label for t in ts])) for label in runs}

def pooled(samples, key):
    """The mean over runs of their [mean, error] of `key` (arrays too), and its error sqrt(sum error^2)/n."""
    values = np.array([s[key] for s in samples], dtype=float)
    return [values[:, 0].mean(axis=0).tolist(), (np.sqrt(np.sum(values[:, 1]**2, axis=0))/len(values)).tolist()]

def reduce(results):
    """A row per job that ran (not blocked), in the order of SYSTEMS, CONFIGS and step: axes, runs, failed (the reason),
    each [mean, error] pooled over the runs, the means of any others."""
    rows = []
    for r, samples in [(r, r["samples"]) for r in results if not r["blocked"]]:
        keys = [key for key in (samples or [{}])[0] if all(key in s for s in samples)]
        rows.append(dict(r["job"], runs=len(samples), failed=r["failed"], **{key: pooled(samples, key) if isinstance(samples[0][key], list)
                                                                             else float(np.mean([s[key] for s in samples], dtype=float)) for key in keys}))
    return sorted(rows, key=lambda r: (list(SYSTEMS).index(r["system"]), list(CONFIGS).index(r["config"]), r["step"]))

def compare(rows, configs, step):
    """Each system's reference, its rows of `configs` at `step` pooled (one model), and to each row d<key>: [value -
    reference, combined error] of its scalar observables that fluctuate."""
    difference, references = lambda value, base: [value[0] - base[0], float(np.hypot(value[1], base[1]))], {}
    for system in dict.fromkeys(r["system"] for r in rows):
        runs = [r for r in rows if (r["system"], r["step"]) == (system, step) and r["config"] in configs and r["runs"] and not r["failed"]]
        ref = references[system] = {k: pooled(runs, k) for k, v in runs[0].items() if isinstance(v, list) and np.ndim(v[0]) == 0}
        for row in [r for r in rows if r["system"] == system]:
            row.update({"d" + k: d for k, v in ref.items() if k in row and (d := difference(row[k], v))[1] > 0})
    return references

def upTo(rows, stop, key="step"):
    """The rows in the order of `key` before the first for which stop(row) holds."""
    rows = sorted(rows, key=lambda r: r[key])
    return rows[:next((i for i, r in enumerate(rows) if stop(r)), len(rows))]

def runsTable(page, rows, columns):
    """A table: system, configuration, step, columns ((heading, key, digits, signed) for harness.pm(), or (heading, f(row))), failure."""
    cell = lambda r, c: c[1](r) if callable(c[1]) else harness.pm(r.get(c[1]), *c[2:])
    columns = [c for c in columns if any(cell(r, c) for r in rows if r.get("runs", 1))]     # none empty in every row
    page.table(["system", "configuration", "step (fs)"] + [c[0] for c in columns] + ["failed"], [[r["system"], r["config"], r["step"]]
               + [cell(r, c) if r.get("runs", 1) else "" for c in columns] + [(r["failed"] or "")[:90]] for r in rows])

def biasPanel(axis, rows, key, cap, x="step", spread=0.0):
    """Each configuration's `key` against `x` (2 sigma), scaled to |value| <= cap (the others: triangles at the edge)."""
    points, colors = [], {}
    for index, config in enumerate(dict.fromkeys(r["config"] for r in rows)):
        mine = [(r[x] + spread*index, r[key][0], 2*r[key][1]) for r in rows if r["config"] == config and key in r]
        colors[config] = f"C{list(CONFIGS).index(config) if config in CONFIGS else index}"      # one colour a configuration
        axis.errorbar(*zip(*mine), marker="o", capsize=3, label=config, color=colors[config]) if mine else None
        points += [p + (colors[config],) for p in mine]
    axis.axhline(0, color="black", linewidth=0.5)
    inside = [(y - e, y + e) for _, y, e, _ in points if abs(y) <= cap] or [(-cap, cap)]
    low, high = min(v[0] for v in inside), max(v[1] for v in inside)
    axis.set_ylim(low - 0.15*(high - low), high + 0.15*(high - low))
    for px, y, _, color in [p for p in points if abs(p[1]) > cap]:
        axis.plot(px, axis.get_ylim()[y > 0], "^" if y > 0 else "v", color=color, markersize=9, clip_on=False)
    return colors

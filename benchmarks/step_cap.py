#!/usr/bin/env python
"""What caps the step of rigid water once its moments of inertia are raised: rotation or translation.

Raised moments (RigidBodyLangevinIntegrator.setMinimumMomentOfInertia) slow the librations that cap
the standard rigid integrator near 8 fs; `inertia_sampling.py` finds the raised configurations
accurate to 14 fs and failing at 16 fs in every water system, with a floor of 0.04 as with 0.08 amu
nm^2. This benchmark asks which motion fails there, by changing one at a time:

- the floor raised further (0.04, then 0.16 amu nm^2: every libration twice as slow again), the mass
  of every molecule unchanged: if rotation capped the step, 16 fs would become accurate;
- every particle mass doubled, with the same floor of 0.16 amu nm^2 (the doubled molecule's own
  moments stay below it, so the rotation is the same as the line above): translation sqrt(2) times
  slower, rotation unchanged;
- the same two masses for stock LangevinMiddleIntegrator + SETTLE with water hydrogens at 4 amu (the
  mass repartitioning a stock user can do by hand), to show what the same lever gives stock.

Neither mass nor inertia enters the configurational distribution, so every configuration samples the
same U. Each run starts from `inertia_sampling.py`'s first start of the system (an equilibrated state
kept in its store), draws velocities for its own masses and moments, discards 2 ps and samples every
0.1 ps for `--time` ps, from each of `--seeds` seeds. Reported per step: the kinetic temperature as the
integrator reports it, that of the molecules' centres of mass (3N - 3 degrees of freedom) and that of
the rotation (the rest, 3N degrees of freedom: the reported kinetic energy less the translational, so
that raised moments are counted with the inertia they have), U per water against the system's
reference in `inertia_sampling.py`'s store (its pooled 2 fs runs), and whether the accuracy check of
the rigid integrator warned. A configuration stops at the first step that fails from some seed.

    python benchmarks/step_cap.py                       # TIP4P-Ew and TIP3P, NVT: about 15 minutes (1 thread each of 2 busy cores)
    python benchmarks/step_cap.py --quick               # smoke run: TIP3P, two steps, 1 ps

Writes docs/results/step_cap.md and docs/figures/step_cap_<system>.png (a quick run: both in benchmarks/results/)
and benchmarks/results/step_cap.csv.
"""

import argparse
import collections
import math
import textwrap
import time
import types
import warnings

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from benchmarking import (RESULTS, accuracyWarnings, blockMean, openRun, principalKineticEnergies, pyplot,
                          rigidDegreesOfFreedom, saveFigure, say, stamp, writeCsv)
import rigidtesting
import inertia_sampling
from nvt_accuracy import BOLTZMANN, FRICTION, TEMPERATURE

SYSTEMS = {"tip4pew-nvt": "TIP4P-Ew", "tip3p-nvt": "TIP3P"}
SAMPLE_EVERY = 0.1   # ps
DISCARD = 2.0        # ps

# minimum: the minimum moment of inertia (amu nm^2); steps in fs
Configuration = collections.namedtuple("Configuration", "description rigid heavyHydrogens massFactor minimum steps")
CONFIGURATIONS = {
    "raised-0.04": Configuration("RigidBodyLangevinIntegrator, moments >= 0.04", True, False, 1.0, 0.04, [14, 16, 18]),
    "raised-0.16": Configuration("RigidBodyLangevinIntegrator, moments >= 0.16", True, False, 1.0, 0.16, [14, 16, 18]),
    "raised-0.16, mass x2": Configuration("RigidBodyLangevinIntegrator, moments >= 0.16, every mass doubled", True, False,
                                          2.0, 0.16, [16, 18, 20, 22, 24]),
    "stock-heavy": Configuration("LangevinMiddleIntegrator + SETTLE, water H 4 amu", False, True, 1.0, 0.0, [12, 14, 16]),
    "stock-heavy, mass x2": Configuration("LangevinMiddleIntegrator + SETTLE, water H 4 amu, every mass doubled", False,
                                          True, 2.0, 0.0, [14, 16, 18, 20]),
}


def withMasses(system, factor):
    """A copy of the System with every particle mass multiplied by factor."""
    copy = openmm.XmlSerializer.deserialize(openmm.XmlSerializer.serialize(system))
    for i in range(copy.getNumParticles()):
        copy.setParticleMass(i, copy.getParticleMass(i)*factor)
    return copy


def makeIntegrator(config, stepFs, seed):
    if config.rigid:
        integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, stepFs*unit.femtoseconds)
        integrator.setMinimumMomentOfInertia(config.minimum)
    else:
        integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, stepFs*unit.femtoseconds)
    integrator.setRandomNumberSeed(seed)
    return integrator


def run(system, state, config, stepFs, seed, waters, args, platform, properties):
    """One run: block means (value, error) of [T reported, T translation, T rotation, U per water], whether
    the accuracy check warned, and the failure ('' if none)."""
    integrator = makeIntegrator(config, stepFs, seed)
    context = openmm.Context(system, integrator, platform, properties)
    context.setState(state)
    context.setVelocitiesToTemperature(TEMPERATURE, seed)
    masses = rigidtesting.particleMasses(system)
    molecules = np.flatnonzero(masses > 0).reshape(-1, 3)
    count = len(molecules)
    dof = rigidDegreesOfFreedom(context, integrator) if config.rigid else rigidtesting.degreesOfFreedom(system)
    every = max(1, int(round(SAMPLE_EVERY*1000/stepFs)))
    samples, failure = [], ""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", openmmrigid.AccuracyWarning)
        try:
            integrator.step(int(round(DISCARD*1000/stepFs)))
            for _ in range(int(round(args.time/SAMPLE_EVERY))):
                integrator.step(every)
                current = context.getState(getPositions=True, getVelocities=True, getEnergy=True)
                kinetic = current.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
                potential = current.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)/waters
                if not (np.isfinite(kinetic) and np.isfinite(potential)) or potential > 0:
                    failure = f"energy {potential:.3g} kJ/mol per water"
                    break
                translational, _ = principalKineticEnergies(
                    current.getPositions(asNumpy=True).value_in_unit(unit.nanometer),
                    current.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond), masses, molecules)
                samples.append([2*kinetic/(dof*BOLTZMANN), 2*translational/((3*count - 3)*BOLTZMANN),
                                2*(kinetic - translational)/(3*count*BOLTZMANN), potential])
        except openmm.OpenMMException as error:
            failure = textwrap.shorten(str(error).splitlines()[0], 100, placeholder=" ...")
    warned = bool(accuracyWarnings(caught))
    del context
    return (blockMean(np.array(samples)) if not failure else None), warned, failure


def reference(name):
    """U per water (mean, error) of the system's pooled 2 fs runs in inertia_sampling's store."""
    options = types.SimpleNamespace(quick=False, time=20.0, discard=2.0, equilibrate=20.0)
    store = inertia_sampling.storeOf(name, options)
    return store, inertia_sampling.resultOf(name, store, 0.1)["reference"]["potential"]


def plot(rows, title, path):
    """Bias of U per water (left) and the translational and rotational temperatures (right) of each
    configuration against its step at standard masses (a failed step marked x); the PNG's path."""
    plt = pyplot()
    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    for index, label in enumerate(dict.fromkeys(row["configuration"] for row in rows)):
        color = f"C{index}"
        mine = [row for row in rows if row["configuration"] == label]
        good = [row for row in mine if row["U_bias"] is not None]
        h = [row["standard_mass_step_fs"] for row in good]
        left.errorbar(h, [row["U_bias"] for row in good], yerr=[row["U_bias_error"] for row in good], color=color,
                      marker="o", capsize=3, label=label)
        right.plot(h, [row["T_translation"] for row in good], color=color, marker="o", label=f"{label}: translation")
        right.plot(h, [row["T_rotation"] for row in good], color=color, marker="s", linestyle="--",
                   label=f"{label}: rotation")
        failed = [row["standard_mass_step_fs"] for row in mine if row["failed"]]
        left.plot(failed, [0.0]*len(failed), color=color, marker="x", markersize=12, linestyle="none")
    left.axhspan(-0.1, 0.1, color="0.9")
    left.set_xlabel("step at standard masses (fs)")
    left.set_ylabel("U/water - reference (kJ/mol); x: failed")
    left.legend(fontsize=8)
    right.axhline(TEMPERATURE.value_in_unit(unit.kelvin), color="0.5", linewidth=0.8)
    right.set_xlabel("step at standard masses (fs)")
    right.set_ylabel("kinetic temperature (K)")
    right.legend(fontsize=6, ncol=2)
    figure.suptitle(f"{title}, 500 waters, NVT: what caps the step")
    saveFigure(figure, path)
    return path


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--systems", nargs="+", choices=list(SYSTEMS), help="default: both; quick tip3p-nvt")
    parser.add_argument("--seeds", type=int, help="runs per configuration and step (default 3; quick 1)")
    parser.add_argument("--time", type=float, help="ps sampled per run (default 20; quick 1)")
    parser.add_argument("--quick", action="store_true", help="smoke run: TIP3P, two steps of two configurations, 1 ps")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's)")
    args = parser.parse_args()
    args.systems = args.systems or (["tip3p-nvt"] if args.quick else list(SYSTEMS))
    args.seeds = args.seeds or (1 if args.quick else 3)
    args.time = args.time or (1.0 if args.quick else 20.0)
    return args


def configurations(quick):
    if not quick:
        return CONFIGURATIONS
    return {label: CONFIGURATIONS[label]._replace(steps=[16, 18]) for label in ("raised-0.16", "raised-0.16, mass x2")}


def main():
    args = parseArguments()
    platform, properties, document = openRun("step_cap", "What caps the step of rigid water with raised moments: rotation or translation", args)
    started, rows = time.time(), []
    for name in args.systems:
        stamp(f"{name}: building; reference and start from inertia_sampling's store")
        store, (referenceU, referenceError) = reference(name)
        inertia_sampling.ensureStarts(name, store, [0], types.SimpleNamespace(equilibrate=20.0), platform, properties)
        state = inertia_sampling.loadState(inertia_sampling.startPath(store, 0))
        _, topology, system, _, _ = inertia_sampling.build(name)
        heavy = inertia_sampling.heavyHydrogens(system, topology)
        waters = inertia_sampling.Waters(topology).count
        table = []
        for label, config in configurations(args.quick).items():
            model = withMasses(heavy if config.heavyHydrogens else system, config.massFactor)
            for stepFs in config.steps:
                results = []
                for seed in range(1, args.seeds + 1):
                    stamp(f"{name}: {label} at {stepFs:g} fs, seed {seed}")
                    results.append(run(model, state, config, stepFs, seed, waters, args, platform, properties))
                failures = [failure for _, _, failure in results if failure]
                good = [result for result, _, failure in results if not failure]
                warned = sum(w for _, w, _ in results)
                standardStep = stepFs/math.sqrt(config.massFactor)
                cells = [SYSTEMS[name], label, f"{stepFs:g}", f"{standardStep:.1f}"]
                row = dict(system=name, configuration=label, step_fs=stepFs, standard_mass_step_fs=standardStep,
                           runs=len(results), failed=len(failures), check_warned=warned, T_reported=None,
                           T_translation=None, T_rotation=None, U_bias=None, U_bias_error=None)
                if good:
                    means = np.mean([g[0] for g in good], axis=0)
                    errors = np.sqrt(np.sum([g[1]**2 for g in good], axis=0))/len(good)
                    bias, biasError = means[3] - referenceU, float(np.hypot(errors[3], referenceError))
                    cells += [f"{means[0]:.1f}", f"{means[1]:.1f} +- {errors[1]:.1f}", f"{means[2]:.1f} +- {errors[2]:.1f}",
                              f"{bias:+.3f} +- {biasError:.3f}"]
                    row.update(T_reported=float(means[0]), T_translation=float(means[1]), T_rotation=float(means[2]),
                               U_bias=float(bias), U_bias_error=biasError)
                else:
                    cells += ["", "", "", ""]
                cells += [(f"{len(failures)} of {len(results)}: {failures[0]}" if failures else "none"),
                          (f"{warned} of {len(results)}" if config.rigid else "")]
                table.append(cells)
                rows.append(row)
                say(" | ".join(cells))
                if failures:
                    break
        document.section(SYSTEMS[name] + ", 500 waters, NVT",
                         f"Reference U per water {referenceU:.3f} +- {referenceError:.3f} kJ/mol ({store.folder.name}'s "
                         f"pooled 2 fs runs). {args.seeds} run(s) per step, {args.time:g} ps sampled each; +- one "
                         f"standard error.")
        document.table(["model", "configuration", "step (fs)", "standard-mass step (fs)", "T reported (K)", "T translation (K)", "T rotation (K)",
                        "U/water bias (kJ/mol)", "failed", "accuracy check warned"], table)
        path = plot([row for row in rows if row["system"] == name], SYSTEMS[name],
                    document.figurePath(f"step_cap_{name}.png"))
        document.figure(path, f"{SYSTEMS[name]}: bias of U and temperatures against the step at standard masses")
    writeCsv(RESULTS/"step_cap.csv", rows)
    document.write()
    say(f"total {time.time() - started:.0f} s")


if __name__ == "__main__":
    main()

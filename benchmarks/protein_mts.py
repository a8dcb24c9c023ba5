#!/usr/bin/env python
"""A solvated protein: how far multiple time steps and rigid X-H groups take the step, and the speed there.

The system most OpenMM users run: villin headpiece (openmm's ``app/data/test.pdb``) re-solvated with
Modeller in TIP3P (amber14, PME 0.9 nm, HBonds, rigid water). Its bonded forces (HarmonicBond,
HarmonicAngle, PeriodicTorsion, CMAP) are put in force group 1, everything else in group 0; every
configuration samples the same configurational distribution, so the mean potential energy U (and the
solute's bonded energy, group 1) must agree with the reference, stock ``LangevinMiddleIntegrator`` at
2 fs, within the statistical error. The configurations:

- stock LangevinMiddleIntegrator at 2 fs (the reference) and at 4 fs with hydrogen mass
  repartitioning to 3 amu (what OpenMM users run today);
- ``RigidBodyLangevinIntegrator`` with rigid X-H groups alone: every HBonds cluster of the protein
  (and every water) a body (``openmmrigid.rigidHydrogenGroups``), moments raised to ``--floor``;
- the same integrator with multiple time steps alone: the bonded forces in substeps of about 2 fs
  (``setForceGroupSubsteps([(0, 1), (1, n)])``), the X-H bonds constrained as free particles, the
  waters' moments raised to ``--floor``;
- both together: rigid X-H groups with raised moments and the bonded forces in substeps.

- the best stock recipe, without this plugin (``stockRecipe()``, a CustomIntegrator): H-X-H and H-O-X
  angles constrained (``constraints=HAngles``), HMR 3 amu, water hydrogens made heavy (O 10, H 4 amu),
  the bonded forces in 2 fs substeps of velocity Verlet and the Ornstein-Uhlenbeck stage once, at the
  outer step's midpoint.

Rigid X-H groups fix the H-X-H angles, and the stock recipe constrains them: model changes, so their rows
are measured against the same model at 2 fs ("model reference" rows), the others against stock at 2 fs.

Each run starts from one equilibrated state (stock 2 fs, kept in benchmarks/results/), draws its
velocities, discards ``--equilibrate`` ps and samples every 0.1 ps for ``--time`` ps. A configuration
stops at its first step that fails. The biases are against the reference's mean, +- the combined
standard errors of block averages (5 blocks). Speed: every configuration that ran, timed side by side
in one process (blocks interleaved, median of ``--repetitions``); the accuracy check stays on, its
default: its episodes cost within noise of a step without it, docs/results/accuracy_check_cost.md.

    python benchmarks/protein_mts.py                 # about 30 minutes on 2 cores
    python benchmarks/protein_mts.py --quick         # smoke run: 0.5 ps, two configurations
    python benchmarks/protein_mts.py --floor 0.16 --seeds 3 --only "HMR" "X-H" --name protein_mts_floor
                                                     # the stock references, HMR 4 fs and the rigid X-H rows, 3 runs each

Writes docs/results/protein_mts.md and docs/figures/protein_mts.png (a quick run: benchmarks/results/).
"""

import argparse
import time

import numpy as np
import openmm
import openmm.app as app
import openmm.unit as unit

import openmmrigid
from benchmarking import (RESULTS, blockMean, blockSteps, nsPerDay, openRun, pyplot, rigidDegreesOfFreedom, say, saveFigure,
                          stamp, timeInterleaved, writeCsv)

TEMPERATURE, FRICTION = 300.0, 1.0
BONDED = (openmm.HarmonicBondForce, openmm.HarmonicAngleForce, openmm.PeriodicTorsionForce, openmm.CMAPTorsionForce)
KJ = unit.kilojoule_per_mole


def build(hydrogenMass=None, constraints=app.HBonds, heavyWaterHydrogens=False):
    """(topology, positions, system): villin in TIP3P, bonded forces in group 1; with heavyWaterHydrogens
    each water's O weighs 10 amu and its H 4 amu (the mass OpenMM no longer moves to water hydrogens)."""
    import os
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
    forcefield = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.deleteWater()
    modeller.addHydrogens(forcefield)
    modeller.addSolvent(forcefield, model="tip3p", padding=0.9*unit.nanometer)
    options = dict(nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer, constraints=constraints, rigidWater=True)
    if hydrogenMass:
        options["hydrogenMass"] = hydrogenMass*unit.amu
    system = forcefield.createSystem(modeller.topology, **options)
    for force in system.getForces():
        force.setForceGroup(1 if isinstance(force, BONDED) else 0)
    if heavyWaterHydrogens:
        for residue in modeller.topology.residues():
            if residue.name == "HOH":
                for atom in residue.atoms():
                    system.setParticleMass(atom.index, (10.0 if atom.element.symbol == "O" else 4.0)*unit.amu)
    return modeller.topology, modeller.positions, system


def stockRecipe(stepFs, substeps):
    """The best stock recipe, a CustomIntegrator: the bonded forces (group 1) in `substeps` inner steps of
    velocity Verlet, the rest (group 0) kicking at the outer step, one Ornstein-Uhlenbeck stage at the outer
    midpoint (V0 [V1 R V1]^(n/2) O [V1 R V1]^(n/2) V0), constraints on positions after each drift and on
    velocities after each kick; on-step velocities."""
    dt, half = stepFs*1e-3, substeps//2
    h = dt/substeps
    integrator = openmm.CustomIntegrator(dt)
    kT = (unit.MOLAR_GAS_CONSTANT_R*TEMPERATURE*unit.kelvin).value_in_unit(KJ)
    integrator.addGlobalVariable("a", np.exp(-FRICTION*dt))
    integrator.addGlobalVariable("b", np.sqrt(1.0 - np.exp(-2.0*FRICTION*dt)))
    integrator.addGlobalVariable("kT", kT)
    integrator.addPerDofVariable("x1", 0.0)
    integrator.addUpdateContextState()

    def kick(group, time):
        integrator.addComputePerDof("v", f"v + {time}*f{group}/m")
        integrator.addConstrainVelocities()

    def inner(count):
        for _ in range(count):
            kick(1, 0.5*h)
            integrator.addComputePerDof("x", f"x + {h}*v")
            integrator.addComputePerDof("x1", "x")
            integrator.addConstrainPositions()
            integrator.addComputePerDof("v", f"v + (x - x1)/{h}")
            kick(1, 0.5*h)
    kick(0, 0.5*dt)
    inner(half)
    integrator.addComputePerDof("v", "a*v + b*sqrt(kT/m)*gaussian")
    integrator.addConstrainVelocities()
    inner(substeps - half)
    kick(0, 0.5*dt)
    return integrator


def startingState(args, platform, properties):
    path = RESULTS/"protein_mts_start.xml"
    if path.exists():
        return openmm.XmlSerializer.deserialize(path.read_text())
    stamp("building and equilibrating the start (stock 2 fs)")
    topology, positions, system = build()
    integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, 0.002)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
    context.setVelocitiesToTemperature(TEMPERATURE, 1)
    integrator.step(1000)
    state = context.getState(getPositions=True, getVelocities=True, enforcePeriodicBox=True)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(openmm.XmlSerializer.serialize(state))
    return state


class Configuration:
    def __init__(self, label, steps, stock=False, hmr=False, rigidGroups=False, substepFs=None, reference=False,
                 hAngles=False):
        self.label, self.steps, self.stock, self.hmr = label, steps, stock, hmr
        self.rigidGroups, self.substepFs, self.reference, self.hAngles = rigidGroups, substepFs, reference, hAngles

    @property
    def model(self):
        """Which configurational distribution the configuration samples: rigid X-H groups fix the H-X-H
        angles (a model change), so they are measured against their own small-step reference."""
        return "rigid X-H" if self.rigidGroups else "H angles" if self.hAngles else "flexible"

    def make(self, stepFs, floor, seed):
        """(system, integrator) for a step of stepFs fs."""
        if self.hAngles:  # the stock recipe's model: H-X-H and H-O-X angles constrained, HMR, heavy water hydrogens
            topology, _, system = build(3.0, app.HAngles, heavyWaterHydrogens=True)
            if self.substepFs:
                return system, stockRecipe(stepFs, max(2, int(round(stepFs/self.substepFs))))
        else:
            topology, _, system = build(3.0 if self.hmr else None)
        if self.stock:
            integrator = openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, stepFs*1e-3)
            integrator.setRandomNumberSeed(seed)
            return system, integrator
        if self.rigidGroups:
            bodies = openmmrigid.rigidHydrogenGroups(topology, system)
            integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, stepFs*1e-3, bodies)
        else:
            integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, stepFs*1e-3)
        integrator.setMinimumMomentOfInertia(floor)
        if self.substepFs:
            integrator.setForceGroupSubsteps([(0, 1), (1, max(1, int(round(stepFs/self.substepFs))))])
        integrator.setRandomNumberSeed(seed)
        return system, integrator


def configurations(quick):
    if quick:
        return [Configuration("stock LangevinMiddle", [2], stock=True, reference=True),
                Configuration("rigid X-H + MTS (2 fs)", [6], rigidGroups=True, substepFs=2.0)]
    return [Configuration("stock LangevinMiddle", [2], stock=True, reference=True),
            Configuration("rigid X-H groups, model reference", [2], rigidGroups=True, reference=True),
            Configuration("stock LangevinMiddle, HMR 3 amu", [4], stock=True, hmr=True),
            Configuration("stock, H angles constrained, model reference", [2], stock=True, hAngles=True, reference=True),
            Configuration("stock recipe: H angles, heavy water H, bonded 2 fs, O at midpoint", [6, 8, 10], stock=True,
                          hAngles=True, substepFs=2.0),
            Configuration("rigid X-H groups", [4, 5, 6], rigidGroups=True),
            Configuration("MTS (bonded 2 fs)", [4, 6, 8], substepFs=2.0),
            Configuration("rigid X-H + MTS (bonded 2 fs)", [6, 8, 10, 12], rigidGroups=True, substepFs=2.0)]


def run(config, stepFs, state, args, platform, properties, seed):
    """(samples [U, bonded U, T] per 0.1 ps, context, integrator), or a failure message."""
    system, integrator = config.make(stepFs, args.floor, seed)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPeriodicBoxVectors(*state.getPeriodicBoxVectors())
    context.setPositions(state.getPositions())
    if config.hAngles:
        context.applyConstraints(1e-6)  # the start satisfies HBonds only
    context.setVelocitiesToTemperature(TEMPERATURE, seed)
    stride = max(1, int(round(100.0/stepFs)))
    dof = (rigidDegreesOfFreedom(context, integrator) if not config.stock else
           3*system.getNumParticles() - system.getNumConstraints() - 3)
    samples = []
    try:
        integrator.step(int(round(args.equilibrate*1000/stepFs)))
        for _ in range(int(round(args.time*10))):
            integrator.step(stride)
            total = context.getState(getEnergy=True)
            bonded = context.getState(getEnergy=True, groups={1}).getPotentialEnergy().value_in_unit(KJ)
            kinetic = total.getKineticEnergy().value_in_unit(KJ)
            temperature = 2*kinetic/(dof*unit.MOLAR_GAS_CONSTANT_R.value_in_unit(KJ/unit.kelvin))
            samples.append([total.getPotentialEnergy().value_in_unit(KJ), bonded, temperature])
            if not np.all(np.isfinite(samples[-1])):
                return f"non-finite energy at {len(samples)*0.1:.1f} ps"
    except openmm.OpenMMException as error:
        return str(error).split(";")[0]
    return np.array(samples), context, integrator


def plot(rows, path):
    plt = pyplot()
    figure, axes = plt.subplots(1, 2, figsize=(10, 4))
    for label in dict.fromkeys(row["configuration"] for row in rows):
        mine = [row for row in rows if row["configuration"] == label and row["U_bias"] is not None]
        if not mine:
            continue
        steps = [row["step_fs"] for row in mine]
        axes[0].errorbar(steps, [row["U_bias"] for row in mine], yerr=[row["U_error"] for row in mine], marker="o", label=label)
        axes[1].errorbar(steps, [row["bonded_bias"] for row in mine], yerr=[row["bonded_error"] for row in mine], marker="o",
                         label=label)
    for axis, title in zip(axes, ("U - U(reference) (kJ/mol)", "bonded U - U(reference) (kJ/mol)")):
        axis.axhline(0.0, color="grey", lw=0.8)
        axis.set_xlabel("outer step (fs)")
        axis.set_ylabel(title)
    axes[0].legend(fontsize=7)
    saveFigure(figure, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--time", type=float, help="ps sampled per run (default 4; quick 0.2)")
    parser.add_argument("--equilibrate", type=float, help="ps discarded per run (default 1; quick 0.1)")
    parser.add_argument("--floor", type=float, default=0.04, help="minimum moment of inertia, amu nm^2 (default 0.04)")
    parser.add_argument("--repetitions", type=int, default=5, help="timed blocks per configuration (default 5)")
    parser.add_argument("--seeds", type=int, default=1, help="independent runs per configuration and step (default 1): "
                        "with 2 or more, the error of a mean is the standard error of the runs' means")
    parser.add_argument("--only", nargs="+", help="run only the configurations whose labels contain one of these")
    parser.add_argument("--name", default="protein_mts", help="the results document's name (default protein_mts)")
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's)")
    args = parser.parse_args()
    args.time = args.time or (0.5 if args.quick else 4.0)
    args.equilibrate = args.equilibrate or (0.1 if args.quick else 1.0)
    platform, properties, document = openRun(args.name, "A solvated protein: multiple time steps and rigid X-H groups", args,
                                             script="protein_mts")
    started = time.time()
    state = startingState(args, platform, properties)
    rows, table, timed, references = [], [], {}, {}
    chosen = [config for config in configurations(args.quick)
              if not args.only or config.reference and config.model == "flexible" or any(word in config.label for word in args.only)]
    for config in chosen:
        for stepFs in config.steps:
            stamp(f"{config.label} at {stepFs:g} fs")
            runs = [run(config, stepFs, state, args, platform, properties, seed=7 + k) for k in range(args.seeds)]
            row = dict(configuration=config.label, step_fs=stepFs, failure="", U=None, U_bias=None, U_error=None,
                       bonded_bias=None, bonded_error=None, T=None)
            failures = [result for result in runs if isinstance(result, str)]
            if failures:
                row["failure"] = f"{len(failures)} of {len(runs)} runs: {failures[0]}"
                table.append([config.label, f"{stepFs:g}", "", "", "", "", row["failure"]])
                rows.append(row)
                say(" | ".join(table[-1]))
                break
            # Per run, block means; over runs, the mean of the runs' means with the standard error of their spread.
            perRun = np.array([[blockMean(samples[:, k]) for k in range(3)] for samples, _, _ in runs])  # (runs, 3, 2)
            if len(runs) > 1:
                means = [(perRun[:, k, 0].mean(), perRun[:, k, 0].std(ddof=1)/np.sqrt(len(runs))) for k in range(3)]
            else:
                means = [tuple(perRun[0, k]) for k in range(3)]
            if config.reference:
                references[config.model] = means
            reference = references.get(config.model, references.get("flexible"))
            against = ("stock 2 fs" if config.model not in references or config.model == "flexible" else
                       {"rigid X-H": "rigid X-H 2 fs", "H angles": "H angles 2 fs"}[config.model])
            (u, uError), (b, bError), (t, _) = means
            uBias, uBiasError = u - reference[0][0], float(np.hypot(uError, reference[0][1]))
            bBias, bBiasError = b - reference[1][0], float(np.hypot(bError, reference[1][1]))
            row.update(U=u, U_bias=uBias, U_error=uBiasError, bonded_bias=bBias, bonded_error=bBiasError, T=t)
            rows.append(row)
            table.append([config.label, f"{stepFs:g}", against, f"{uBias:+.0f} +- {uBiasError:.0f}",
                          f"{bBias:+.1f} +- {bBiasError:.1f}", f"{t:.1f}", ""])
            say(" | ".join(table[-1]))
            _, context, integrator = runs[-1]
            timed[f"{config.label}, {stepFs:g} fs"] = (stepFs, context, integrator)
    flexible = references["flexible"]
    rigidShift = ""
    if "rigid X-H" in references:
        shift = references["rigid X-H"][0][0] - flexible[0][0]
        rigidShift = (f" The rigid X-H model itself (its reference at 2 fs) differs from the flexible one by "
                      f"{shift:+.0f} kJ/mol in U: rows of rigid X-H groups are measured against it.")
    runsText = f"{args.seeds} independent runs" if args.seeds > 1 else "one run"
    document.section("Accuracy", f"{runsText} per row, {args.time:g} ps sampled per run after {args.equilibrate:g} ps; "
                     f"bias of the mean U and of the solute's bonded energy against the reference of the same model "
                     f"(stock LangevinMiddle at 2 fs: mean U {flexible[0][0]:.0f} kJ/mol); floor {args.floor:g} amu nm^2."
                     + rigidShift)
    document.table(["configuration", "step (fs)", "against", "U bias (kJ/mol)", "bonded U bias (kJ/mol)", "T (K)", "failed"],
                   table)

    stamp("timing, interleaved")
    integrators = {label: integrator for label, (_, _, integrator) in timed.items()}
    steps = {label: blockSteps(integrator, None, 2.0, 10) for label, integrator in integrators.items()}
    wall, _ = timeInterleaved(integrators, min(steps.values()), args.repetitions)
    speed, base = [], None
    for label, (stepFs, _, _) in timed.items():
        nsDay = nsPerDay(stepFs, np.median(wall[label]))
        if "HMR" in label:
            base = nsDay
        speed.append([label, nsDay])
    speedRows = [[label, f"{ns:.1f}", f"{ns/base:.2f}" if base else ""] for label, ns in speed]
    for cells in speedRows:
        say(" | ".join(cells))
    document.section("Speed", f"{args.platform}, median of {args.repetitions} interleaved blocks; ratio against stock "
                     "LangevinMiddle with HMR at 4 fs.")
    document.table(["configuration", "ns/day", "x stock HMR 4 fs"], speedRows)
    for row in rows:
        match = [ns for label, ns in speed if label == f"{row['configuration']}, {row['step_fs']:g} fs"]
        row["ns_per_day"] = match[0] if match else None
    writeCsv(RESULTS/f"{args.name}.csv", rows)
    path = document.figurePath(f"{args.name}.png")
    plot(rows, path)
    document.figure(path, "Bias of U and of the bonded energy against the outer step")
    document.write()
    say(f"total {time.time() - started:.0f} s")


if __name__ == "__main__":
    main()

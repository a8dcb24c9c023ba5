#!/usr/bin/env python
"""A solvated protein with hydrogen mass repartitioning: which step and splitting (NVE, CPU platform).

The system: the villin headpiece (HP35 N68H, 35 residues, 582 atoms, one Cl-) in 2761 TIP3P waters,
8867 atoms in a 4.92 x 4.60 x 3.89 nm box: openmm's own test structure (openmm/app/data/test.pdb).
Amber14 (amber14-all.xml + amber14/tip3p.xml), PME with a 0.9 nm cutoff and Ewald error tolerance
5e-4, constraints=HBonds (--constraints), rigidWater=True, hydrogenMass 3 amu (--hydrogen-mass; taken
from the bonded heavy atom, water untouched). RigidBodyIntegrator makes every water a rigid body and moves
the protein's atoms (and the ion) as free particles with their bonds to hydrogen constrained.

After minimization and --equilibrate ps of LangevinMiddleIntegrator at 300 K (4 fs, 1/ps), every
method runs NVE from that one state, each in its own Context, all at once: round-robin, each
Context advancing one sample interval (48 fs of simulated time) in turn, so that they share the
machine's load alike; only the integrator.step() calls are timed. Methods:

    stock 4 fs      openmm.VerletIntegrator (--stock-steps) (SETTLE for water, CCMA for the protein's H bonds)
    Verlet k fs     openmmrigid.RigidBodyIntegrator, default (Verlet) splitting, exact rotation
    Omelyan2 k fs   the same with setSplitting(RigidBodyIntegrator.Omelyan2): two force evaluations per step

for k = 4, 6, 8 (--steps); all with constraint tolerance 1e-10 (the stock starting state made to
satisfy the constraints to that tolerance first). For each run: the total energy every 48 fs; the
drift (slope of a linear fit, per degree of freedom: 3 per massive particle less the constraints
less 3 for the CMMotionRemover, counted as OpenMM counts them: the same number for every method,
since rigid water has 6 either way), the fluctuation (standard deviation about the fit), its ratio
to stock's, and ns/day (simulated time over the wall time of the step calls). A run stops at an
exception, a non-finite energy, or |E - E0| above --threshold kJ/mol per degree of freedom.

    python benchmarks/hmr_schemes.py --stock-steps 4 6   # 10 ps per run: about 15 minutes on 2 busy cores
    python benchmarks/hmr_schemes.py --constraints AllBonds --stock-steps 4 6 --verlet-steps 4 6 \
        --omelyan-steps 4 6 8 --time 6 --equilibrate 5 --output benchmarks/results/hmr_schemes_allbonds
    python benchmarks/hmr_schemes.py --quick   # a smoke check: 4 fs only, 0.24 ps per run

Writes docs/results/<name>.md (the name of --output, default hmr_schemes; a quick run:
benchmarks/results/), and <output>.csv and <output>.log (a copy of what is printed).
"""

import argparse
import os
import time
from pathlib import Path

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from benchmarking import (RESULTS, ResultsDocument, cpuProperties, header, openLog, rigidDegreesOfFreedom, say, stamp,
                          writeCsv)
import rigidtesting

SAMPLE_FS = 48  # a multiple of 4, 6 and 8 fs
CONSTRAINT_TOLERANCE = 1e-10
KJ = unit.kilojoule_per_mole


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--pdb", default=os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"),
                        help="solvated protein (default: openmm/app/data/test.pdb, villin in TIP3P)")
    parser.add_argument("--hydrogen-mass", type=float, default=3.0, help="amu (default 3)")
    parser.add_argument("--constraints", choices=["HBonds", "AllBonds", "HAngles"], default="HBonds",
                        help="the protein's constraints (default HBonds)")
    parser.add_argument("--steps", type=float, nargs="+", default=[4, 6, 8], help="rigid-body steps in fs (default 4 6 8)")
    parser.add_argument("--verlet-steps", type=float, nargs="+", help="the Verlet splitting's steps (default --steps)")
    parser.add_argument("--omelyan-steps", type=float, nargs="+", help="Omelyan2's steps (default --steps)")
    parser.add_argument("--stock-steps", type=float, nargs="+", default=[4], help="stock VerletIntegrator steps in fs (default 4)")
    parser.add_argument("--time", type=float, default=10.0, help="NVE ps per run (default 10)")
    parser.add_argument("--equilibrate", type=float, default=10.0, help="Langevin ps at 4 fs before (default 10)")
    parser.add_argument("--threshold", type=float, default=0.2,
                        help="|E - E0| in kJ/mol per degree of freedom that counts as blown up (default 0.2)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--seed", type=int, default=35)
    parser.add_argument("--threads", type=int, help="CPU platform threads (default: the platform's)")
    parser.add_argument("--quick", action="store_true", help="a smoke check: every method at 4 fs only, 0.24 ps "
                        "per run after 100 minimizer iterations and 0.2 ps of equilibration")
    parser.add_argument("--output", default=str(RESULTS / "hmr_schemes"))
    args = parser.parse_args()
    args.minimizeIterations = 100 if args.quick else 500
    if args.quick:
        args.steps, args.stock_steps, args.time, args.equilibrate = [4], [4], 0.24, 0.2
    args.verlet_steps = args.verlet_steps or args.steps
    args.omelyan_steps = args.omelyan_steps or args.steps
    for step in args.verlet_steps + args.omelyan_steps + args.stock_steps:
        if SAMPLE_FS % step:
            parser.error(f"step {step:g} fs does not divide the sample interval of {SAMPLE_FS} fs")
    return args


def buildSystem(args):
    pdb = app.PDBFile(args.pdb)
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer,
                                     ewaldErrorTolerance=5e-4, constraints=getattr(app, args.constraints), rigidWater=True,
                                     hydrogenMass=args.hydrogen_mass*unit.amu)
    return pdb, system


def equilibrate(pdb, system, platform, properties, args):
    integrator = openmm.LangevinMiddleIntegrator(300*unit.kelvin, 1/unit.picosecond, 4*unit.femtosecond)
    integrator.setRandomNumberSeed(args.seed)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(pdb.positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, args.minimizeIterations)
    context.setVelocitiesToTemperature(300*unit.kelvin, args.seed)
    steps = int(round(args.equilibrate*250))
    for done in range(0, steps, 250):
        integrator.step(min(250, steps - done))
        stamp(f"  equilibration {min(done + 250, steps)*0.004:.1f} / {args.equilibrate:g} ps")
    return context.getState(getPositions=True, getVelocities=True)


class Run:
    """One method at one step: its Context, and the energies and wall time so far."""

    def __init__(self, label, scheme, stepFs, integrator, system, state, platform, properties):
        self.label, self.scheme, self.stepFs, self.integrator = label, scheme, stepFs, integrator
        integrator.setConstraintTolerance(CONSTRAINT_TOLERANCE)
        self.context = openmm.Context(system, integrator, platform, properties)
        self.context.setState(state)
        if isinstance(integrator, openmm.VerletIntegrator):
            self.context.applyConstraints(CONSTRAINT_TOLERANCE)
            self.context.applyVelocityConstraints(CONSTRAINT_TOLERANCE)
        self.times, self.energies, self.seconds, self.failure = [], [], 0.0, ""
        self.record()

    def record(self):
        state = self.context.getState(getEnergy=True)
        self.times.append(state.getTime().value_in_unit(unit.picosecond))
        self.energies.append((state.getPotentialEnergy() + state.getKineticEnergy()).value_in_unit(KJ))

    def elapsed(self):
        return self.times[-1] - self.times[0]

    def advance(self, threshold):
        """One sample interval; returns False (with self.failure set) once the run has blown up."""
        steps = int(round(SAMPLE_FS/self.stepFs))
        start = time.perf_counter()
        try:
            self.integrator.step(steps)
        except openmm.OpenMMException as error:
            self.failure = f"exception after {self.elapsed():.2f} ps: {str(error).splitlines()[0][:60]}"
            return False
        self.seconds += time.perf_counter() - start
        self.record()
        energy = self.energies[-1]
        if not np.isfinite(energy):
            self.failure = f"non-finite energy after {self.elapsed():.2f} ps"
        elif abs(energy - self.energies[0]) > threshold:
            self.failure = f"|E - E0| = {abs(energy - self.energies[0]):.0f} kJ/mol after {self.elapsed():.2f} ps"
        return not self.failure


def makeRuns(system, state, platform, properties, args):
    runs = [Run(f"stock VerletIntegrator {stepFs:g} fs", "stock", stepFs, openmm.VerletIntegrator(stepFs*unit.femtosecond),
                system, state, platform, properties) for stepFs in args.stock_steps]
    for scheme, steps in (("Verlet", args.verlet_steps), ("Omelyan2", args.omelyan_steps)):
        for stepFs in steps:
            integrator = openmmrigid.RigidBodyIntegrator(stepFs*unit.femtosecond)
            integrator.setSplitting(getattr(openmmrigid.RigidBodyIntegrator, scheme))
            runs.append(Run(f"RigidBodyIntegrator {scheme} {stepFs:g} fs", scheme, stepFs, integrator, system, state,
                            platform, properties))
    return runs


def summarize(run, dof, stockFluctuation):
    times, energies = np.array(run.times), np.array(run.energies)
    row = {"method": run.label, "scheme": run.scheme, "step_fs": run.stepFs, "simulated_ps": times[-1] - times[0],
           "failure": run.failure}
    if len(times) >= 3:
        drift, fluctuation = rigidtesting.energyDrift(times, energies, dof)
        row.update(drift_kj_per_mol_ns_dof=drift, fluctuation_kj_per_mol=fluctuation)
        if stockFluctuation:
            row["fluctuation_to_stock"] = fluctuation/stockFluctuation
    if run.seconds > 0:
        simulatedNs = (times[-1] - times[0])*1e-3
        row["ns_per_day"] = simulatedNs/run.seconds*86400
        row["ms_per_step"] = run.seconds/((times[-1] - times[0])/(run.stepFs*1e-3))*1e3
    return row


def printTable(rows):
    stock = next(row for row in rows if row["scheme"] == "stock")
    say(f"\n{'method':<36}{'ps':>6}{'drift':>10}{'fluct.':>9}{'/ stock':>9}{'ms/step':>9}{'ns/day':>8}{'/ stock':>9}  notes")
    for row in rows:
        cells = [f"{row['method']:<36}", f"{row['simulated_ps']:>6.1f}"]
        if "fluctuation_kj_per_mol" in row:
            cells += [f"{row['drift_kj_per_mol_ns_dof']:>+10.3f}", f"{row['fluctuation_kj_per_mol']:>9.2f}",
                      f"{row.get('fluctuation_to_stock', float('nan')):>9.2f}"]
        else:
            cells += [f"{'':>10}{'':>9}{'':>9}"]
        if "ns_per_day" in row:
            cells += [f"{row['ms_per_step']:>9.2f}", f"{row['ns_per_day']:>8.2f}",
                      f"{row['ns_per_day']/stock['ns_per_day']:>9.2f}"]
        else:
            cells += [f"{'':>26}"]
        cells.append(f"  {row['failure'] or ''}")
        say("".join(cells))
    say("drift: slope of a linear fit of the total energy, kJ/mol/ns per degree of freedom; fluct.: standard\n"
        "deviation of the total energy about that fit, kJ/mol, and its ratio to stock's; ms/step and ns/day from\n"
        "the wall time of the step calls alone, interleaved with the other runs (so ratios are what to read);\n"
        "a run that blew up is summarized up to the last sample before it did.")


def main():
    args = parseArguments()
    openLog(Path(args.output + ".log"))
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = cpuProperties(platform, args.threads)
    document = ResultsDocument(Path(args.output).name, "A solvated protein with hydrogen mass repartitioning: "
                               "which step and splitting", quick=args.quick, platform=args.platform, threads=args.threads,
                               about="Method: the docstring of `benchmarks/hmr_schemes.py`.")
    for line in header(args.platform, args.threads):
        say(line)
    started = time.perf_counter()
    pdb, system = buildSystem(args)
    dof = rigidtesting.degreesOfFreedom(system)
    waters = sum(1 for residue in pdb.topology.residues() if residue.name == "HOH")
    with document.capture():
        say(f"system: {os.path.basename(args.pdb)}: {system.getNumParticles()} atoms, {waters} waters, hydrogen mass "
            f"{args.hydrogen_mass:g} amu, constraints={args.constraints} ({system.getNumConstraints()} constraints), "
            f"{dof} degrees of freedom; {args.equilibrate:g} ps of equilibration, {args.time:g} ps NVE per run")
    stamp(f"minimizing, then {args.equilibrate:g} ps of LangevinMiddleIntegrator at 4 fs")
    state = equilibrate(pdb, system, platform, properties, args)
    runs = makeRuns(system, state, platform, properties, args)
    rigid = runs[len(args.stock_steps)]
    stamp(f"{len(runs)} runs of {args.time:g} ps, round-robin in {SAMPLE_FS} fs pieces; RigidBodyIntegrator: "
          f"{rigid.integrator.getNumBodies()} bodies, {rigidDegreesOfFreedom(rigid.context, rigid.integrator)} "
          "degrees of freedom")
    active = list(runs)
    pieces = int(round(args.time*1000/SAMPLE_FS))
    for piece in range(pieces):
        active = [run for run in active if run.advance(args.threshold*dof)]
        if (piece + 1) % max(1, pieces//10) == 0:
            stamp(f"  {(piece + 1)*SAMPLE_FS/1000:.2f} / {args.time:g} ps; running: {len(active)} of {len(runs)}")
        if not active:
            break
    stockRow = summarize(runs[0], dof, None)
    rows = [summarize(run, dof, stockRow.get("fluctuation_kj_per_mol")) for run in runs]
    with document.capture():
        printTable(rows)
    fields = list(dict.fromkeys(key for row in rows for key in row))
    writeCsv(args.output + ".csv", [{key: row.get(key, "") for key in fields} for row in rows])
    document.write()
    say(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

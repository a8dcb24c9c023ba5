#!/usr/bin/env python
"""What openmmrigid.removeIntraBodyInteractions saves per step (CPU platform).

Two systems, each simulated by RigidBodyIntegrator (2 fs, explicit bodies from
openmmrigid.rigidBodiesFromTopology) with its System as built by ForceField.createSystem
("full") and with removeIntraBodyInteractions applied ("lean"), side by side in one process:

    dipeptides   a box of --molecules alanine dipeptides (amber14, ACE-ALA-NME, 22 atoms, every one a
                 rigid body), placed on a cubic grid with random orientations at --density (0.6 g/mL; a
                 denser grid makes randomly oriented molecules overlap), no solvent; PME (cutoff 0.9 nm) or, with --nonbonded CutoffPeriodic, reaction field.
                 The intra-body terms are most of the bonded ones and every nonbonded pair inside a
                 molecule.
    villin       openmm's solvated villin headpiece (openmm/app/data/test.pdb, 8867 atoms, amber14 +
                 TIP3P, PME, constraints=HBonds, rigid water): bodies are the 2761 waters and the
                 ring of each aromatic side chain (PHE, TYR, TRP, HIS: from CG out, with its
                 hydrogens), the rest flexible. The water's own terms were exclusions already, so
                 this is the saving for a typical solvated protein with a few rigid groups.

Each system is minimized once (stock, flexible), then both Contexts start from that state. After a
warm-up block each, blocks of integrator.step(n) (n chosen so that a block takes about --seconds)
are timed with time.perf_counter() (wall) and time.process_time() (CPU time of this process, which other
work on the machine does not inflate: the steadier measure on shared cores), alternating full, lean,
full, lean, ...; reported: the median ms/step of each over --repetitions blocks, and lean / full,
the median of the per-round ratios. As a
check of the model, the potential energy difference full - lean is printed at the start and at the
end (it must be the same constant: the energy of the removed terms), and the largest change of a
body's total force (relative to the largest per-atom force).

    python benchmarks/intrabody_cost.py                  # both systems: about 4 minutes on 2 busy cores
    python benchmarks/intrabody_cost.py --systems dipeptides --nonbonded CutoffPeriodic
    python benchmarks/intrabody_cost.py --quick          # a smoke check: 27 dipeptides, 3 short rounds

Writes docs/results/<name>.md (the name of --output, default intrabody_cost; a quick run:
benchmarks/results/), and <output>.csv and <output>.log (a copy of what is printed).
"""

import argparse
import os
import statistics
import time
from pathlib import Path

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from benchmarking import RESULTS, ResultsDocument, header, openLog, say, stamp, writeCsv
import rigidtesting

KJ = unit.kilojoule_per_mole
RINGS = {"PHE": "CG|CD[12]|CE[12]|CZ|HD[12]|HE[12]|HZ",
         "TYR": "CG|CD[12]|CE[12]|CZ|OH|HD[12]|HE[12]",
         "TRP": "CG|CD[12]|NE1|CE[23]|CZ[23]|CH2|HD1|HE[13]|HZ[23]|HH2",
         "HIS": "CG|ND1|CD2|CE1|NE2|HD[12]|HE[12]"}  # openmm.app.PDBFile reads HIE, HID and HIP as HIS


def dipeptideBox(args):
    pdb = rigidtesting.alanineDipeptide()
    local = np.array(pdb.positions.value_in_unit(unit.nanometer))
    local -= local.mean(axis=0)
    perSide = int(np.ceil(args.molecules**(1/3)))
    mass = 144.17/6.02214076e23  # g per molecule
    spacing = (mass/args.density*1e21)**(1/3)  # nm between grid sites
    rng = np.random.default_rng(7)
    modeller = app.Modeller(app.Topology(), [])
    for index in range(args.molecules):
        site = spacing*(np.array(np.unravel_index(index, (perSide,)*3)) + 0.5)
        modeller.add(pdb.topology, (local @ rigidtesting.randomRotation(rng).T + site)*unit.nanometer)
    edge = spacing*perSide
    modeller.topology.setPeriodicBoxVectors(np.eye(3)*edge*unit.nanometer)
    forceField = app.ForceField("amber14-all.xml")
    method = getattr(app, args.nonbonded)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=method, nonbondedCutoff=0.9*unit.nanometer,
                                     constraints=None)
    bodies = openmmrigid.rigidBodiesFromTopology(modeller.topology, ["ACE", "ALA", "NME"], mergeBonded=True,
                                                 system=system)
    description = (f"{args.molecules} rigid alanine dipeptides, box {edge:.2f} nm, {args.nonbonded}, "
                   f"{system.getNumParticles()} atoms, {len(bodies)} bodies")
    return modeller.topology, modeller.positions, system, bodies, description


def solvatedVillin(args):
    pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    system = forceField.createSystem(pdb.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.9*unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True)
    names = [name for name in RINGS if any(residue.name == name for residue in pdb.topology.residues())]
    bodies = openmmrigid.rigidBodiesFromTopology(pdb.topology, names + ["HOH"], atoms={n: RINGS[n] for n in names},
                                                 system=system)
    rings = len(bodies) - sum(1 for residue in pdb.topology.residues() if residue.name == "HOH")
    description = (f"villin in TIP3P (test.pdb), PME, {system.getNumParticles()} atoms, {len(bodies)} bodies "
                   f"({rings} aromatic rings: {', '.join(names)})")
    return pdb.topology, pdb.positions, system, bodies, description


SYSTEMS = {"dipeptides": dipeptideBox, "villin": solvatedVillin}


def terms(system):
    """Bonded terms, nonbonded exceptions and constraints of a System, for the summary line."""
    counts = {"bonded": 0, "exceptions": 0, "constraints": system.getNumConstraints()}
    for force in system.getForces():
        for method in ("getNumBonds", "getNumAngles", "getNumTorsions"):
            if hasattr(force, method) and not isinstance(force, openmm.NonbondedForce):
                counts["bonded"] += getattr(force, method)()
        if isinstance(force, openmm.NonbondedForce):
            counts["exceptions"] += force.getNumExceptions()
    return counts


def minimized(system, positions, platform):
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 300)
    context.setVelocitiesToTemperature(300*unit.kelvin, 5)
    return context.getState(getPositions=True, getVelocities=True)


def potentialEnergy(context):
    return context.getState(getEnergy=True).getPotentialEnergy().value_in_unit(KJ)


def bodyForceChange(full, lean, bodies):
    forces = [context.getState(getForces=True).getForces(asNumpy=True).value_in_unit(KJ/unit.nanometer)
              for context in (full, lean)]
    largest = max(np.abs(forces[0][body].sum(axis=0) - forces[1][body].sum(axis=0)).max() for body in bodies)
    return largest/np.abs(forces[0]).max()


def measure(name, args, platform):
    stamp(f"{name}: building and minimizing")
    topology, positions, system, bodies, description = SYSTEMS[name](args)
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    before, after = terms(system), terms(lean)
    say(f"  {description}")
    say(f"  full: {before['bonded']} bonded terms, {before['exceptions']} exceptions, {before['constraints']} constraints; "
        f"lean: {after['bonded']}, {after['exceptions']}, {after['constraints']}")
    state = minimized(system, positions, platform)
    contexts, integrators = {}, {}
    for label, model in (("full", system), ("lean", lean)):
        integrators[label] = openmmrigid.RigidBodyIntegrator(2*unit.femtosecond, bodies)
        contexts[label] = openmm.Context(model, integrators[label], platform)
        contexts[label].setState(state)
    offsetStart = potentialEnergy(contexts["full"]) - potentialEnergy(contexts["lean"])
    forceChange = bodyForceChange(contexts["full"], contexts["lean"], bodies)
    integrators["full"].step(10)
    start = time.perf_counter()
    integrators["full"].step(10)
    steps = max(5, int(round(args.seconds/((time.perf_counter() - start)/10))))
    for integrator in integrators.values():  # warm-up block
        integrator.step(steps)
    seconds = {"full": [], "lean": []}
    cpuSeconds = {"full": [], "lean": []}
    for _ in range(args.repetitions):
        for label in ("full", "lean"):
            start, cpuStart = time.perf_counter(), time.process_time()
            integrators[label].step(steps)
            seconds[label].append((time.perf_counter() - start)/steps)
            cpuSeconds[label].append((time.process_time() - cpuStart)/steps)
    # Same trajectory? Compare the energy offset at the end, on the full run's positions.
    contexts["lean"].setPositions(contexts["full"].getState(getPositions=True).getPositions())
    offsetEnd = potentialEnergy(contexts["full"]) - potentialEnergy(contexts["lean"])
    ratios = [lean/full for full, lean in zip(seconds["full"], seconds["lean"])]
    cpuRatios = [lean/full for full, lean in zip(cpuSeconds["full"], cpuSeconds["lean"])]
    row = {"system": name, "description": description, "steps_per_block": steps, "repetitions": args.repetitions,
           "full_ms_per_step": 1e3*statistics.median(seconds["full"]),
           "lean_ms_per_step": 1e3*statistics.median(seconds["lean"]),
           "lean_to_full": statistics.median(ratios), "ratio_min": min(ratios), "ratio_max": max(ratios),
           "full_cpu_ms_per_step": 1e3*statistics.median(cpuSeconds["full"]),
           "lean_cpu_ms_per_step": 1e3*statistics.median(cpuSeconds["lean"]),
           "cpu_lean_to_full": statistics.median(cpuRatios), "cpu_ratio_min": min(cpuRatios),
           "cpu_ratio_max": max(cpuRatios),
           "energy_offset_start": offsetStart, "energy_offset_end": offsetEnd, "body_force_change": forceChange,
           "bonded_full": before["bonded"], "bonded_lean": after["bonded"]}
    stamp(f"  full {row['full_ms_per_step']:.2f} ms/step, lean {row['lean_ms_per_step']:.2f} ms/step, lean / full "
          f"{row['lean_to_full']:.3f} [{row['ratio_min']:.3f}-{row['ratio_max']:.3f}]; CPU time: full "
          f"{row['full_cpu_ms_per_step']:.2f}, lean {row['lean_cpu_ms_per_step']:.2f} ms/step, lean / full "
          f"{row['cpu_lean_to_full']:.3f} [{row['cpu_ratio_min']:.3f}-{row['cpu_ratio_max']:.3f}] ({args.repetitions} "
          f"rounds of {steps} steps); E(full) - E(lean) {offsetStart:.6f} at the start, {offsetEnd:.6f} kJ/mol after "
          f"{(args.repetitions + 1)*steps + 20} steps; largest change of a body's total force "
          f"{forceChange:.1e} of the largest atomic force")
    return row


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--systems", nargs="+", choices=sorted(SYSTEMS), help="default: dipeptides villin "
                        "(quick: dipeptides)")
    parser.add_argument("--molecules", type=int, help="dipeptides in the box (default 216; quick 27)")
    parser.add_argument("--density", type=float, default=0.6, help="g/mL of the dipeptide box (default 0.6)")
    parser.add_argument("--nonbonded", choices=["PME", "CutoffPeriodic"], default="PME",
                        help="the dipeptide box's nonbonded method (default PME)")
    parser.add_argument("--repetitions", type=int, help="timed blocks per System (default 7; quick 3)")
    parser.add_argument("--seconds", type=float, help="target seconds per block (default 2; quick 0.2)")
    parser.add_argument("--threads", default=None, help="CPU platform Threads (default: the platform's)")
    parser.add_argument("--quick", action="store_true", help="a smoke check: 27 dipeptides, 3 rounds of 0.2 s")
    parser.add_argument("--output", default=str(RESULTS / "intrabody_cost"), help="path of the .csv and .log, less the suffix")
    args = parser.parse_args()
    defaults = dict(systems=(["dipeptides"], ["dipeptides", "villin"]), molecules=(27, 216), repetitions=(3, 7),
                    seconds=(0.2, 2.0))
    for key, (quick, full) in defaults.items():
        if getattr(args, key) is None:
            setattr(args, key, quick if args.quick else full)
    return args


def tabulate(rows, args):
    say(f"{'':<12}{'wall time':>40}{'CPU time of this process':>40}")
    say(f"{'system':<12}" + f"{'full ms/step':>14}{'lean ms/step':>14}{'lean / full':>12}"*2)
    for row in rows:
        say(f"{row['system']:<12}{row['full_ms_per_step']:>14.2f}{row['lean_ms_per_step']:>14.2f}{row['lean_to_full']:>12.3f}"
            f"{row['full_cpu_ms_per_step']:>14.2f}{row['lean_cpu_ms_per_step']:>14.2f}{row['cpu_lean_to_full']:>12.3f}")
    say(f"(medians of {args.repetitions} interleaved rounds; lean / full is the median of the per-round ratios. On a\n"
        "shared machine the CPU time, which other processes do not inflate, is the steadier measure.)")


def main():
    args = parseArguments()
    openLog(Path(args.output + ".log"))
    platform = openmm.Platform.getPlatformByName("CPU")
    if args.threads:
        platform.setPropertyDefaultValue("Threads", args.threads)
    threads = platform.getPropertyDefaultValue("Threads")
    document = ResultsDocument(Path(args.output).name, "What removeIntraBodyInteractions saves per step",
                               quick=args.quick, platform="CPU", threads=threads,
                               about="Method: the docstring of `benchmarks/intrabody_cost.py`.")
    for line in header("CPU", threads):
        say(line)
    with document.capture():
        rows = [measure(name, args, platform) for name in args.systems]
        say()
        tabulate(rows, args)
    writeCsv(args.output + ".csv", rows)
    document.write()


if __name__ == "__main__":
    main()

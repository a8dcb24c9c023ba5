"""What openmmrigid.removeIntraBodyInteractions saves per step: RigidBodyIntegrator on a System as ForceField built
it ("full") and without the interactions inside its bodies ("lean"), timed interleaved in one process."""

import os
import numpy as np, openmm
from openmm import app, unit
import harness, openmmrigid, rigidtesting
from harness import Study

RINGS = {"PHE": "CG|CD[12]|CE[12]|CZ|HD[12]|HE[12]|HZ", "TYR": "CG|CD[12]|CE[12]|CZ|OH|HD[12]|HE[12]",
         "TRP": "CG|CD[12]|NE1|CE[23]|CZ[23]|CH2|HD1|HE[13]|HZ[23]|HH2", "HIS": "CG|ND1|CD2|CE1|NE2|HD[12]|HE[12]"}
SYSTEMS = {"dipeptides": "rigid alanine dipeptides, PME", "dipeptides-rf": "rigid alanine dipeptides, reaction field",
           "villin": "villin in TIP3P, rigid waters and aromatic rings, PME"}

def build(name, count):
    """(positions, System, bodies): `count` amber14 alanine dipeptides, each a body, randomly oriented on a grid at 0.6 g/mL;
    or openmm's solvated villin (test.pdb, HBonds), bodies the waters and each aromatic ring (CG out, with its H)."""
    method = dict(nonbondedCutoff=0.9*unit.nanometer, nonbondedMethod=app.CutoffPeriodic if name.endswith("-rf") else app.PME)
    if name == "villin":
        pdb = app.PDBFile(os.path.join(os.path.dirname(app.__file__), "data", "test.pdb"))
        system = app.ForceField("amber14-all.xml", "amber14/tip3p.xml").createSystem(pdb.topology, constraints=app.HBonds, **method)
        rings = [n for n in RINGS if any(residue.name == n for residue in pdb.topology.residues())]
        return pdb.positions, system, openmmrigid.rigidBodiesFromTopology(pdb.topology, rings + ["HOH"], system=system,
                                                                          atoms={n: RINGS[n] for n in rings})
    pdb, rng, modeller = rigidtesting.alanineDipeptide(), np.random.default_rng(7), app.Modeller(app.Topology(), [])
    local = pdb.positions.value_in_unit(unit.nanometer) - np.mean(pdb.positions.value_in_unit(unit.nanometer), axis=0)
    side, spacing = int(np.ceil(count**(1/3))), (144.17/6.02214076e23/0.6*1e21)**(1/3)
    for index in range(count):
        site = spacing*(np.array(np.unravel_index(index, (side,)*3)) + 0.5)
        modeller.add(pdb.topology, (local @ rigidtesting.randomRotation(rng).T + site)*unit.nanometer)
    modeller.topology.setPeriodicBoxVectors(np.eye(3)*spacing*side*unit.nanometer)
    system = app.ForceField("amber14-all.xml").createSystem(modeller.topology, constraints=None, **method)
    return modeller.positions, system, openmmrigid.rigidBodiesFromTopology(modeller.topology, ["ACE", "ALA", "NME"],
                                                                           mergeBonded=True, system=system)

def measure(name, env, count, seconds, repetitions):
    """Full and lean at 2 fs from one minimized state (1 thread unless --threads); lean / full per round of blocks."""
    positions, system, bodies = build(name, count)
    properties, contexts = harness.cpuProperties(env.platformName, env.threads or 1), []
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), env.platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 300)
    context.setVelocitiesToTemperature(300, 5)
    integrators = {"full": openmmrigid.RigidBodyIntegrator(0.002, bodies), "lean": openmmrigid.RigidBodyIntegrator(0.002, bodies)}
    for label, model in (("full", system), ("lean", openmmrigid.removeIntraBodyInteractions(system, bodies))):
        contexts.append(openmm.Context(model, integrators[label], env.platform, properties))
        contexts[-1].setState(context.getState(getPositions=True, getVelocities=True))
    steps = harness.blockSteps(integrators["full"], None, seconds, 5)
    row = dict(system=name, atoms=system.getNumParticles(), bodies=len(bodies), steps=steps, repetitions=repetitions)
    for clock, times in zip(("wall", "cpu"), harness.timeInterleaved(integrators, steps, repetitions)):
        ratios = np.array(times["lean"])/times["full"]
        row[clock] = dict(full=1e3*np.median(times["full"]), lean=1e3*np.median(times["lean"]),
                          ratio=[np.median(ratios), ratios.min(), ratios.max()])
    harness.stamp(str(row))
    return row

def run(env):
    return [measure(n, env, *((27, 0.1, 3) if env.quick else (216, 3.0, 11))) for n in SYSTEMS if not (env.quick and n == "villin")]

def report(summary, page):
    page.table(["system", "atoms", "bodies", "full ms/step", "lean ms/step", "lean / full", "range", "wall: lean / full"],
               [[SYSTEMS[r["system"]], r["atoms"], r["bodies"], f"{r['cpu']['full']:.2f}", f"{r['cpu']['lean']:.2f}",
                 "**{0:.3f}**".format(*r["cpu"]["ratio"]), "{1:.3f} to {2:.3f}".format(*r["cpu"]["ratio"]),
                 f"{r['wall']['ratio'][0]:.3f}"]
                for r in summary])
    page.text("CPU time of the process per step (which other work on a shared machine inflates less than wall time), medians "
              "of the rounds; lean / full is the median of the per-round ratios, with their range.")

STUDY = Study("intrabody_cost", "What removeIntraBodyInteractions saves per step",
              "Leaving out the interactions inside rigid bodies makes a step about 13 % cheaper with reaction field, but saves no "
              "measurable time with PME, whose reciprocal-space correction of each excluded pair gives it back.", report, run=run,
              method="""
`RigidBodyIntegrator` on each System as built and with `removeIntraBodyInteractions` applied (the tests check that the
bodies' forces and torques stay): 216 alanine dipeptides, where the removed terms are most bonded terms and every pair in a
molecule, with PME and with reaction field; villin with rigid waters (whose own terms are exclusions already) and rings. CPU
platform, 1 thread; after a warm-up block each, 11 rounds of blocks of about 3 s, full then lean.""",
              caveats="One machine, one thread, one run each, CPU platform only; the dipeptide box maximizes intra-body terms.")

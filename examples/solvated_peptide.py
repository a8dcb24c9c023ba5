"""A flexible solute in rigid water: alanine dipeptide in TIP4P-Ew, RigidBodyIntegrator next to stock Verlet.

Alanine dipeptide (Ace-Ala-Nme) is built here from standard bond lengths and angles (Engh and Huber,
Acta Cryst. A47, 392 (1991), rounded) with backbone angles phi = -75, psi = 145 degrees
(polyproline II, common in water); Modeller adds its hydrogens and about 550 TIP4P-Ew waters (a
cubic box of 2.6 nm). Amber14 (amber14-all.xml + amber14/tip4pew.xml), PME, constraints=HBonds,
rigidWater=True, so RigidBodyIntegrator makes each water a rigid body (its M site a virtual site)
and moves the peptide's atoms freely by velocity Verlet, with its bonds to hydrogen constrained.

Step: 2 fs by default. The peptide's atoms are integrated as free particles with their bonds to
hydrogen constrained and no mass repartitioning: the usual 2 fs limit of a flexible solute (its
angles to hydrogen) holds for either integrator, as in any stock simulation, and rigid waters cannot
lift it (docs/guide/proteins.md: even with hydrogen mass repartitioning the peptide caps every integrator at
5 fs). The example therefore compares energy conservation and constraints at the same step.

After minimization and 2 ps of stock Langevin dynamics at 300 K, both integrators run NVE for 5 ps
at 2 fs from the same state: stock VerletIntegrator (SETTLE for the waters, CCMA for the peptide)
and RigidBodyIntegrator (Exact free rotation), both with constraint tolerance 1e-10. The script
prints the bodies and free particles the integrator found, and for each integrator the energy drift
(linear fit, per degree of freedom), the fluctuation about it, the largest violation of the peptide's
constraints and of the water geometry at the end, and the time per step.

    python examples/solvated_peptide.py [--box 2.6] [--step 2] [--time 5] [--platform CPU]

The default settings take about a minute and a half on two busy cores.
"""

import argparse
import io
import time

import numpy as np
import openmm
from openmm import app, unit

import openmmrigid
from _molecules import bodyKinds, degreesOfFreedom, energyDrift, sampleNVE

# Heavy atoms of Ace-Ala-Nme from internal coordinates: label, residue, atom name, element, the
# labels of the atoms it is bonded to / makes its angle with / its torsion with, the bond length (nm),
# angle and torsion (degrees). The first three atoms fix the frame. Torsions: omega = 180 (trans
# peptides), phi (C-N-CA-C), psi (N-CA-C-N); each carbonyl O is cis to the next CA; N-C-CA-CB =
# +122.6 gives L-alanine.
PHI, PSI = -75.0, 145.0
HEAVY_ATOMS = [
    ("ace-CH3", "ACE", "CH3", "C", (), None, None, None),
    ("ace-C", "ACE", "C", "C", ("ace-CH3",), 0.152, None, None),
    ("ala-N", "ALA", "N", "N", ("ace-C", "ace-CH3"), 0.133, 116.2, None),
    ("ala-CA", "ALA", "CA", "C", ("ala-N", "ace-C", "ace-CH3"), 0.146, 121.7, 180.0),
    ("ala-C", "ALA", "C", "C", ("ala-CA", "ala-N", "ace-C"), 0.152, 111.2, PHI),
    ("nme-N", "NME", "N", "N", ("ala-C", "ala-CA", "ala-N"), 0.133, 116.2, PSI),
    ("nme-C", "NME", "C", "C", ("nme-N", "ala-C", "ala-CA"), 0.146, 121.7, 180.0),
    ("ace-O", "ACE", "O", "O", ("ace-C", "ala-N", "ala-CA"), 0.123, 123.0, 0.0),
    ("ala-O", "ALA", "O", "O", ("ala-C", "nme-N", "nme-C"), 0.123, 123.0, 0.0),
    ("ala-CB", "ALA", "CB", "C", ("ala-CA", "ala-C", "ala-N"), 0.153, 110.1, 122.6),
]
RESIDUE_NUMBERS = {"ACE": 1, "ALA": 2, "NME": 3}


def placeAtom(a, b, c, bond, angle, torsion):
    """The position of d bonded to c with |cd| = bond, angle b-c-d and torsion a-b-c-d (degrees)."""
    bc = (c - b)/np.linalg.norm(c - b)
    normal = np.cross(b - a, bc)
    normal /= np.linalg.norm(normal)
    angle, torsion = np.radians(angle), np.radians(torsion)
    local = bond*np.array([-np.cos(angle), np.sin(angle)*np.cos(torsion), np.sin(angle)*np.sin(torsion)])
    return c + np.column_stack([bc, np.cross(normal, bc), normal]) @ local


def alanineDipeptidePdb():
    """PDB text of the heavy atoms of Ace-Ala-Nme (coordinates in Angstrom), residue by residue."""
    positions = {}
    for label, _, _, _, references, bond, angle, torsion in HEAVY_ATOMS:
        found = [positions[reference] for reference in references]
        if not found:
            positions[label] = np.zeros(3)
        elif len(found) == 1:
            positions[label] = found[0] + np.array([bond, 0.0, 0.0])
        elif len(found) == 2:  # in the plane z = 0, at `angle` to the first bond
            direction = (found[1] - found[0])/np.linalg.norm(found[1] - found[0])
            perpendicular = np.array([-direction[1], direction[0], 0.0])
            angle = np.radians(angle)
            positions[label] = found[0] + bond*(np.cos(angle)*direction + np.sin(angle)*perpendicular)
        else:
            positions[label] = placeAtom(found[2], found[1], found[0], bond, angle, torsion)
    lines = []
    atoms = sorted(HEAVY_ATOMS, key=lambda atom: RESIDUE_NUMBERS[atom[1]])
    for serial, (label, residue, name, element, *_) in enumerate(atoms, 1):
        x, y, z = 10*positions[label]
        lines.append(f"ATOM  {serial:5d} {name:<4} {residue} A{RESIDUE_NUMBERS[residue]:4d}    {x:8.3f}{y:8.3f}{z:8.3f}"
                     f"  1.00  0.00          {element:>2}")
    return "\n".join(lines + ["TER", "END"]) + "\n"


def buildSolvatedPeptide(edge, platform):
    """Topology, positions and System of alanine dipeptide in TIP4P-Ew water, and the peptide's atom indices."""
    forceField = app.ForceField("amber14-all.xml", "amber14/tip4pew.xml")
    peptide = app.PDBFile(io.StringIO(alanineDipeptidePdb()))
    modeller = app.Modeller(peptide.topology, peptide.positions)
    # addHydrogens minimizes the hydrogens on the platform given (by default the fastest one there is,
    # which may be a GPU platform whose minimizer fails, as OpenCL's on PoCL does).
    modeller.addHydrogens(forceField, platform=platform)
    solute = list(range(modeller.topology.getNumAtoms()))  # the peptide comes first, the waters after it
    modeller.addSolvent(forceField, model="tip4pew", boxSize=openmm.Vec3(edge, edge, edge)*unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME,
                                     nonbondedCutoff=min(0.9, 0.45*edge)*unit.nanometer, constraints=app.HBonds,
                                     rigidWater=True, ewaldErrorTolerance=5e-4)
    return modeller.topology, modeller.positions, system, solute


def equilibratedState(positions, system, platform, picoseconds):
    """Minimized, then stock Langevin dynamics at 300 K (2 fs) for `picoseconds`."""
    integrator = openmm.LangevinMiddleIntegrator(300*unit.kelvin, 1/unit.picosecond, 2*unit.femtosecond)
    integrator.setRandomNumberSeed(1991)
    context = openmm.Context(system, integrator, platform)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10, 200)
    context.setVelocitiesToTemperature(300*unit.kelvin, 1991)
    integrator.step(int(round(picoseconds/0.002)))
    return context.getState(getPositions=True, getVelocities=True)


def constraintViolations(system, positions, solute):
    """The largest relative violation |r - d|/d of the constraints within the solute and of those within
    the waters (their O-H and H-H distances)."""
    inSolute = set(solute)
    worst = {"solute": 0.0, "water": 0.0}
    for index in range(system.getNumConstraints()):
        i, j, distance = system.getConstraintParameters(index)
        distance = distance.value_in_unit(unit.nanometer)
        violation = abs(np.linalg.norm(positions[i] - positions[j]) - distance)/distance
        part = "solute" if i in inSolute else "water"
        worst[part] = max(worst[part], violation)
    return worst["solute"], worst["water"]


def describeBodies(integrator, system, positions):
    """Bodies (their kinds from their masses and positions), massive particles in no body, and virtual
    sites, as the integrator sees them."""
    bodies = [integrator.getBodyParticles(b) for b in range(integrator.getNumBodies())]
    inBodies = sum(len(body) for body in bodies)
    massive = sum(1 for i in range(system.getNumParticles()) if system.getParticleMass(i) > 0*unit.dalton)
    virtual = sum(1 for i in range(system.getNumParticles()) if system.isVirtualSite(i))
    kinds = set(bodyKinds(system, positions, bodies))
    return len(bodies), "/".join(sorted(kinds)), massive - inBodies, virtual


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--box", type=float, default=2.6, help="edge of the cubic box, nm (default 2.6)")
    parser.add_argument("--step", type=float, default=2.0, help="time step in fs (default 2)")
    parser.add_argument("--time", type=float, default=5.0, help="NVE time per integrator in ps (default 5)")
    parser.add_argument("--equilibrate", type=float, default=2.0, help="Langevin equilibration in ps (default 2)")
    parser.add_argument("--platform", default="CPU")
    args = parser.parse_args()
    started = time.perf_counter()

    platform = openmm.Platform.getPlatformByName(args.platform)
    topology, positions, system, solute = buildSolvatedPeptide(args.box, platform)
    waters = topology.getNumResidues() - 3
    soluteConstraints = sum(1 for k in range(system.getNumConstraints()) if system.getConstraintParameters(k)[0] < len(solute))
    print(f"alanine dipeptide ({len(solute)} atoms, {soluteConstraints} constraints on bonds to H) in {waters} TIP4P-Ew "
          f"waters; {system.getNumParticles()} particles, PME, platform {args.platform}")
    state = equilibratedState(positions, system, platform, args.equilibrate)

    dt = args.step*unit.femtosecond
    stock = openmm.VerletIntegrator(dt)
    rigid = openmmrigid.RigidBodyIntegrator(dt)
    steps = int(round(args.time/(args.step*1e-3)))
    dof = degreesOfFreedom(system)  # rigid waters (by their constraints) and the peptide's atoms less its constraints
    results = []
    for name, integrator in (("stock VerletIntegrator + SETTLE", stock), ("RigidBodyIntegrator (Exact)", rigid)):
        integrator.setConstraintTolerance(1e-10)
        context = openmm.Context(system, integrator, platform)
        context.setState(state)
        context.applyConstraints(1e-10)  # both start from the same state, its constraints tightened
        context.applyVelocityConstraints(1e-10)
        if integrator is rigid:
            start = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            bodies, kinds, free, virtual = describeBodies(rigid, system, start)
            print(f"RigidBodyIntegrator: {bodies} rigid bodies ({kinds}), {free} free particles, {virtual} virtual sites; "
                  f"{dof} degrees of freedom")
        run = sampleNVE(context, integrator, steps, max(1, steps//200))
        positions = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
        results.append((name, run, *constraintViolations(system, positions, solute)))
        del context

    print(f"\nNVE for {args.time:g} ps at {args.step:g} fs ({steps} steps) from the same state after {args.equilibrate:g} ps "
          "of Langevin dynamics at 300 K; constraint tolerance 1e-10")
    print(f"{'integrator':<34}{'drift':>14}{'fluctuation':>13}{'solute constraints':>20}{'water geometry':>16}{'ms/step':>9}")
    print(f"{'':<34}{'kJ/mol/ns/dof':>14}{'kJ/mol':>13}{'max |r-d|/d':>20}{'max |r-d|/d':>16}")
    for name, run, soluteViolation, waterViolation in results:
        if not np.all(np.isfinite(run.energies)):
            print(f"{name:<34}{'unstable (NaN)':>14}")
            continue
        drift, fluctuation = energyDrift(run.times, run.energies, dof)
        print(f"{name:<34}{drift:>+14.4f}{fluctuation:>13.3f}{soluteViolation:>20.1e}{waterViolation:>16.1e}"
              f"{run.secondsPerStep*1e3:>9.2f}")
    print("drift: slope of a linear fit of the total energy per degree of freedom; fluctuation: standard deviation "
          "about it;\nconstraints: at the end of the run.")
    print(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

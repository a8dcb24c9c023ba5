"""Liquid benzene as rigid planar molecules: explicit bodies in RigidBodyIntegrator.

A periodic box of benzene (128 molecules at 0.874 g/cm^3, 298 K: the liquid at ambient conditions)
with the all-atom OPLS-AA model of W. L. Jorgensen, D. S. Maxwell and J. Tirado-Rives, J. Am. Chem.
Soc. 118, 11225 (1996): a rigid regular hexagon (C-C 0.140 nm, C-H 0.108 nm); aromatic C: sigma
0.355 nm, epsilon 0.070 kcal/mol, charge -0.115 e; H: 0.242 nm, 0.030 kcal/mol, +0.115 e. OPLS
combines sigma and epsilon geometrically; by default this script uses NonbondedForce's
Lorentz-Berthelot rule instead, which changes only the C-H pair (sigma 0.2985 nm instead of 0.2931
nm): with --combining geometric a CustomNonbondedForce does the Lennard-Jones as OPLS prescribes,
but on the CPU platform it makes a step several times as expensive here. PME for the charges;
Lennard-Jones cutoff 1.0 nm, switched from 0.9 nm, with the long-range dispersion correction.

Each molecule is one explicit body, RigidBodyIntegrator(stepSize, bodies); no constraints and no
bonded terms. Benzene is a symmetric top (oblate: the moment about the six-fold axis is the sum of
the two equal in-plane ones), and the integrator classifies it so by its moments. Random packing of flat
molecules jams below liquid density, so the box is packed at random at about half the density and
compressed in stages of 2 % in edge, each followed by 0.1 ps of equilibration with the same
integrator and Andersen-style velocity redraws; then more equilibration and an NVE run. The script
prints the body kinds and moments (from the masses and positions), the energy drift and fluctuation,
the translational and rotational temperatures (from the velocities in the State; 3 + 3 degrees of
freedom per molecule: they must agree), and how rigid and how flat the molecules stayed. The helpers
come from examples/_molecules.py.

Step: 2 fs by default, the conventional step for rigid-molecule OPLS liquids. Benzene's moments of
inertia (0.89 and 1.78 amu nm^2) are 50 to 300 times water's, so its rotation is slow and larger
steps may hold, but this project has not measured benzene's accurate step: the example checks energy
conservation and equipartition at the ordinary one (--step 4 shows how the drift grows).

    python examples/benzene.py [--molecules 128] [--step 2] [--time 10] [--method Exact]

The default settings take about a minute on two cores.
"""

import argparse
import dataclasses
import time
from collections import Counter

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from _molecules import (RigidMolecule, bodyKinds, boxEdge, compressBox, degreesOfFreedom, energyDrift,
                        equilibrateByRedraws, principalMoments, rigidMoleculeBox, rigidTemperatures, sampleNVE,
                        shapeDeviations)

KILOJOULES_PER_KILOCALORIE = 4.184
RING, CARBON_HYDROGEN = 0.140, 0.108  # nm: C-C (the ring's radius) and C-H
_ANGLES = np.radians(60.0*np.arange(6))
OPLS_BENZENE = RigidMolecule(
    name="benzene", masses=[12.011]*6 + [1.008]*6,
    coordinates=[[r*np.cos(a), r*np.sin(a), 0.0] for r in (RING, RING + CARBON_HYDROGEN) for a in _ANGLES],
    charges=[-0.115]*6 + [0.115]*6, sigmas=[0.355]*6 + [0.242]*6,
    epsilons=[0.070*KILOJOULES_PER_KILOCALORIE]*6 + [0.030*KILOJOULES_PER_KILOCALORIE]*6,
    combining="lorentz-berthelot")
PACKING_DENSITY = 0.45  # g/cm^3


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--molecules", type=int, default=128, help="number of benzene molecules (default 128)")
    parser.add_argument("--density", type=float, default=0.874, help="g/cm^3 (default 0.874)")
    parser.add_argument("--temperature", type=float, default=298.0, help="K (default 298)")
    parser.add_argument("--step", type=float, default=2.0, help="time step in fs (default 2)")
    parser.add_argument("--equilibrate", type=float, default=6.0,
                        help="equilibration in ps after the compression (default 6)")
    parser.add_argument("--time", type=float, default=10.0, help="NVE time in ps (default 10)")
    parser.add_argument("--method", default="Exact", choices=["Exact", "NoSquish"], help="rotation method (default Exact)")
    parser.add_argument("--combining", default="lorentz-berthelot", choices=["lorentz-berthelot", "geometric"],
                        help="Lennard-Jones combining rule (default lorentz-berthelot; OPLS's own is geometric)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--seed", type=int, default=1996)
    args = parser.parse_args()
    started = time.perf_counter()

    # Packed at random at half the density (random packing jams near 0.8 g/cm^3), then compressed.
    molecule = dataclasses.replace(OPLS_BENZENE, combining=args.combining)
    system, positions, bodies = rigidMoleculeBox(molecule, args.molecules, PACKING_DENSITY, args.seed)
    integrator = openmmrigid.RigidBodyIntegrator(args.step*unit.femtosecond, bodies)
    integrator.setRotationMethod(getattr(openmmrigid.RigidBodyIntegrator, args.method))
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(args.platform))
    context.setPositions(positions)
    edge = boxEdge(OPLS_BENZENE, args.molecules, args.density)
    # The bodies' kinds and moments, from their masses and positions (the integrator classifies them the same way).
    kinds = bodyKinds(system, positions, bodies)
    dof = degreesOfFreedom(system, bodies, kinds)
    moments = principalMoments(OPLS_BENZENE.masses, OPLS_BENZENE.coordinates)
    print(f"{args.molecules} OPLS-AA benzene molecules ({args.combining} combining), {args.density:g} g/cm^3 "
          f"(box {edge:.3f} nm), {args.temperature:g} K, platform {args.platform}")
    print(f"bodies: {integrator.getNumBodies()}, kinds {dict(Counter(kinds))}; moments {np.round(moments, 5).tolist()} "
          f"amu nm^2 (I3/(I1 + I2) = {moments[2]/(moments[0] + moments[1]):.12f}); {dof} degrees of freedom")

    stages = compressBox(context, integrator, bodies, edge, args.temperature, picosecondsPerStage=0.1, seed=args.seed)
    equilibrateByRedraws(context, integrator, args.temperature, args.equilibrate, seed=args.seed)
    steps = int(round(args.time/(args.step*1e-3)))
    run = sampleNVE(context, integrator, steps, max(1, steps//500), bodies)
    drift, fluctuation = energyDrift(run.times, run.energies, dof)
    temperatures = rigidTemperatures(run, args.molecules, 3)
    change, extents = shapeDeviations(context, bodies, positions)
    print(f"\nNVE, {args.method} rotation, {args.time:g} ps at {args.step:g} fs ({steps} steps, "
          f"{run.secondsPerStep*1e3:.2f} ms/step) after compression from {PACKING_DENSITY:g} g/cm^3 "
          f"({stages} stages of 0.1 ps) and {args.equilibrate:g} ps of equilibration:")
    print(f"  energy drift {drift:+.4f} kJ/mol/ns/dof, fluctuation {fluctuation:.3f} kJ/mol")
    for name, (mean, error) in zip(("translational", "rotational", "rotational - translational"), temperatures):
        print(f"  {name} temperature {mean:.1f} +- {error:.1f} K")
    print(f"  rigidity: largest change of an intramolecular distance {change:.1e} nm; largest distance of a "
          f"molecule's atoms from its best-fit plane (RMS) {extents[:, 2].max():.1e} nm")
    print(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

"""Liquid carbon dioxide as rigid linear molecules: explicit bodies in RigidBodyIntegrator.

A periodic box of CO2 (256 molecules at 1.07 g/cm^3 and 250 K: the liquid, a little denser than at
coexistence, 1.046 g/cm^3 at 250 K) with the TraPPE
model of J. J. Potoff and J. I. Siepmann, AIChE J. 47, 1676 (2001): three Lennard-Jones sites on a
rigid line (C=O 0.116 nm; C: sigma 0.280 nm, epsilon/k 27.0 K, charge +0.70 e; O: 0.305 nm, 79.0 K,
-0.35 e), Lorentz-Berthelot combining rules. Here with PME and a Lennard-Jones cutoff of 1.0 nm
switched from 0.9 nm, with the long-range dispersion correction (TraPPE used 1.4 nm and analytic
tail corrections).

A linear molecule cannot be held rigid by constraints (the constraint equations of three collinear
sites are singular); stock OpenMM needs a workaround for it (the atoms as massless virtual sites of
two massive dummy sites chosen to carry the mass and the moment of inertia). Here each molecule is
simply one explicit body, RigidBodyIntegrator(stepSize, bodies). The box is packed
at random, equilibrated with the same integrator and Andersen-style velocity redraws, then run NVE.
The script prints the body kinds and degrees of freedom (counted from the masses and positions, as
the integrator does), the energy drift and fluctuation, the translational and rotational
temperatures (from the velocities in the State; equipartition: a linear body has 3 translational and
2 rotational degrees of freedom, and both temperatures must agree), and how rigid and how linear the
molecules stayed. The helpers come from examples/_molecules.py.

Step: 2 fs by default, the conventional step for TraPPE CO2 in molecular dynamics. The molecules are
heavy and slow to rotate (moment 0.43 amu nm^2, 70 times water's smallest), so larger steps may
hold, but this project has not measured CO2's accurate step: the example checks energy conservation
and equipartition at the ordinary one (--step 4 shows how the drift grows).

    python examples/co2_box.py [--molecules 256] [--step 2] [--time 10] [--method Exact]

The default settings take under a minute on two cores.
"""

import argparse
import time
from collections import Counter

import numpy as np
import openmm
from openmm import unit

import openmmrigid
from _molecules import (MOLAR_GAS_CONSTANT, RigidMolecule, bodyKinds, degreesOfFreedom, energyDrift,
                        equilibrateByRedraws, principalMoments, rigidMoleculeBox, rigidTemperatures, sampleNVE,
                        shapeDeviations)

BOLTZMANN = MOLAR_GAS_CONSTANT  # kJ/mol/K: TraPPE gives epsilon/k in K
CARBON_OXYGEN = 0.116  # nm
TRAPPE_CO2 = RigidMolecule(
    name="CO2", masses=[12.011, 15.999, 15.999],
    coordinates=[[0, 0, 0], [0, 0, CARBON_OXYGEN], [0, 0, -CARBON_OXYGEN]],
    charges=[0.70, -0.35, -0.35], sigmas=[0.280, 0.305, 0.305],
    epsilons=[27.0*BOLTZMANN, 79.0*BOLTZMANN, 79.0*BOLTZMANN])


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--molecules", type=int, default=256, help="number of CO2 molecules (default 256)")
    parser.add_argument("--density", type=float, default=1.07, help="g/cm^3 (default 1.07)")
    parser.add_argument("--temperature", type=float, default=250.0, help="K (default 250)")
    parser.add_argument("--step", type=float, default=2.0, help="time step in fs (default 2)")
    parser.add_argument("--equilibrate", type=float, default=5.0, help="equilibration in ps (default 5)")
    parser.add_argument("--time", type=float, default=20.0, help="NVE time in ps (default 20)")
    parser.add_argument("--method", default="Exact", choices=["Exact", "NoSquish"], help="rotation method (default Exact)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--seed", type=int, default=2001)
    args = parser.parse_args()
    started = time.perf_counter()

    system, positions, bodies = rigidMoleculeBox(TRAPPE_CO2, args.molecules, args.density, args.seed)
    integrator = openmmrigid.RigidBodyIntegrator(args.step*unit.femtosecond, bodies)
    integrator.setRotationMethod(getattr(openmmrigid.RigidBodyIntegrator, args.method))
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(args.platform))
    context.setPositions(positions)
    edge = system.getDefaultPeriodicBoxVectors()[0][0].value_in_unit(unit.nanometer)
    # The bodies' kinds and moments, from their masses and positions (the integrator classifies them the same way).
    kinds = bodyKinds(system, positions, bodies)
    dof = degreesOfFreedom(system, bodies, kinds)
    moments = principalMoments(TRAPPE_CO2.masses, TRAPPE_CO2.coordinates)
    print(f"{args.molecules} TraPPE CO2 molecules, {args.density:g} g/cm^3 (box {edge:.3f} nm), {args.temperature:g} K, "
          f"platform {args.platform}")
    print(f"bodies: {integrator.getNumBodies()}, kinds {dict(Counter(kinds))}, moments "
          f"{np.round(moments, 5).tolist()} amu nm^2; {dof} degrees of freedom (3 + 2 per body)")

    equilibrateByRedraws(context, integrator, args.temperature, args.equilibrate, seed=args.seed)
    steps = int(round(args.time/(args.step*1e-3)))
    run = sampleNVE(context, integrator, steps, max(1, steps//500), bodies)
    drift, fluctuation = energyDrift(run.times, run.energies, dof)
    (translational, translationalError), (rotational, rotationalError), (excess, excessError) = \
        rigidTemperatures(run, args.molecules, 2)
    change, extents = shapeDeviations(context, bodies, positions)
    print(f"\nNVE, {args.method} rotation, {args.time:g} ps at {args.step:g} fs ({steps} steps, "
          f"{run.secondsPerStep*1e3:.2f} ms/step) after {args.equilibrate:g} ps of equilibration:")
    print(f"  energy drift {drift:+.4f} kJ/mol/ns/dof, fluctuation {fluctuation:.3f} kJ/mol")
    print(f"  temperature: translational {translational:.1f} +- {translationalError:.1f} K, rotational "
          f"{rotational:.1f} +- {rotationalError:.1f} K (2 per molecule); difference {excess:+.1f} +- {excessError:.1f} K")
    print(f"  rigidity: largest change of a C-O or O-O distance {change:.1e} nm; largest distance of a molecule's "
          f"atoms from its axis (RMS) {extents[:, 1].max():.1e} nm")
    print(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

"""Parallel tempering of a rigid solute in rigid water with openmmtools, serially or across MPI
processes, analysed with MBAR.

Alanine dipeptide (one rigid body: its three residues merged through their bonds; read from
examples/data/alanine-dipeptide.pdb) in TIP3P water (every water a rigid body), PME, built as in
examples/rigid_solute.py. openmmtools' ParallelTemperingSampler runs replicas at temperatures spaced
geometrically from --tmin to --tmax;
each iteration applies openmmrigid.openmmtools.RigidLangevinDynamicsMove (RigidBodyLangevinIntegrator,
the exact free drift of every body) to every replica, then swaps temperatures (Gibbs sampling over
all pairs). openmmtools sees the integrator's heat bath, so no AndersenThermostat is added, and one
Context per process is reused across temperatures (ContextCache). The run is stored in a NetCDF file
(examples/output/replica_exchange.nc) and analysed with openmmtools' MultiStateSamplerAnalyzer (MBAR,
pymbar): the reduced free energies f(beta) = -ln Z(beta) of the temperatures, checked against
thermodynamic integration of the mean potential energy, d f / d beta = <U> (trapezoid rule on the
samples MBAR uses; the two agree within their errors once the run is long enough to equilibrate,
several hundred iterations, far more than the default's quick look); the neighbour swap acceptance and the round trips of the replicas in temperature; and
whether the waters are still rigid in the last stored positions.

Step: 2 fs (RigidLangevinDynamicsMove's timestep), the same at every temperature. The rigid
Langevin integrator is accurate to about 8 fs in TIP3P at 300 K with standard moments (README), but
the accurate step shrinks as the temperature rises and the replicas here go to --tmax (360 K by
default), where it has not been measured; 2 fs keeps every replica well inside its range, which is
what a replica-exchange run needs (a biased hot replica biases the cold ones through the swaps).

    python examples/replica_exchange.py [--replicas 4] [--iterations 40] [--steps 100] [--platform CPU]
    mpirun -np 2 python examples/replica_exchange.py ...     # the replicas split over the processes

Under MPI (detected by mpiplus from the launcher's environment, as openmmtools does) each process
propagates its share of the replicas and process 0 writes the file and the analysis; give each
process --threads 1 on the CPU platform when the processes share the cores. Needs openmmtools (pip
install openmmtools) and, for MPI, an MPI library and mpi4py (Debian: apt-get install mpich, then
pip install mpi4py). The default settings take about two minutes on two cores.
"""

import argparse
import logging
import time
from pathlib import Path

import mpiplus
import numpy as np
import openmm
from openmm import app, unit

# pymbar's notes (no JAX, how to read statistical inefficiencies) come as logging warnings on import and use.
logging.getLogger("pymbar").setLevel(logging.ERROR)
from openmmtools import cache, multistate, states  # noqa: E402

import openmmrigid
from openmmrigid.openmmtools import RigidLangevinDynamicsMove

KB = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)


def build(padding, platform):
    """The solvated solute, minimized with the full flexible System: (topology, lean System, bodies, positions, box)."""
    pdb = app.PDBFile(str(Path(__file__).resolve().parent / "data" / "alanine-dipeptide.pdb"))
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    modeller = app.Modeller(pdb.topology, pdb.positions)
    modeller.addSolvent(forceField, model="tip3p", padding=padding * unit.nanometer)
    system = forceField.createSystem(modeller.topology, nonbondedMethod=app.PME, nonbondedCutoff=0.8 * unit.nanometer,
                                     constraints=app.HBonds, rigidWater=True)
    bodies = openmmrigid.rigidBodiesFromTopology(modeller.topology, ["ACE", "ALA", "NME", "HOH"], mergeBonded=True,
                                                 system=system)
    lean = openmmrigid.removeIntraBodyInteractions(system, bodies)
    positions = None
    if mpiplus.get_mpicomm() is None or mpiplus.get_mpicomm().rank == 0:
        minimizer = openmm.Context(system, openmm.VerletIntegrator(0.001), platform)
        minimizer.setPositions(modeller.positions)
        openmm.LocalEnergyMinimizer.minimize(minimizer, 10, 500)
        positions = minimizer.getState(getPositions=True).getPositions(asNumpy=True)
    # Every process starts from process 0's minimum (the CPU minimizer is not bitwise repeatable).
    if mpiplus.get_mpicomm() is not None:
        positions = mpiplus.get_mpicomm().bcast(positions, root=0)
    box = lean.getDefaultPeriodicBoxVectors()
    return modeller.topology, lean, bodies, positions, box


def analyse(path, topology, say):
    """MBAR free energies against thermodynamic integration, swaps, round trips, rigidity: printed."""
    reporter = multistate.MultiStateReporter(path, open_mode="r")
    try:
        thermodynamicStates, _ = reporter.read_thermodynamic_states()
        temperatures = np.array([s.temperature.value_in_unit(unit.kelvin) for s in thermodynamicStates])
        beta = 1.0 / (KB * temperatures)
        iterations = reporter.read_last_iteration(last_checkpoint=False)
        analyzer = multistate.MultiStateSamplerAnalyzer(reporter)
        deltaF, deltaFError = analyzer.get_free_energy()
        # The samples MBAR uses: after the equilibration its detection discards (iteration 0 is the start).
        energies, _, _ = reporter.read_energies()
        replicaStates = reporter.read_replica_thermodynamic_states()
        start = max(1, analyzer.n_equilibration_iterations)
        potential = [[] for _ in temperatures]
        for i in range(start, iterations + 1):
            for replica, state in enumerate(replicaStates[i]):
                potential[state].append(energies[i, replica, state]/beta[state])
        meanU = np.array([np.mean(u) for u in potential])
        say(f"\n{iterations} iterations; MBAR by openmmtools' MultiStateSamplerAnalyzer, which discards "
            f"{analyzer.n_equilibration_iterations} as equilibration (statistical inefficiency "
            f"{analyzer.statistical_inefficiency:.2f}); <U> from the same iterations, {start} to {iterations}")
        say("  T (K)    <U> (kJ/mol)   f - f(Tmin): MBAR (kT)        thermodynamic integration of <U> d(beta) (kT)")
        integrated = 0.0
        for k, t in enumerate(temperatures):
            if k > 0:
                integrated += 0.5*(beta[k] - beta[k - 1])*(meanU[k] + meanU[k - 1])
            say(f"  {t:6.1f}   {meanU[k]:12.1f}   {deltaF[0, k]:+12.2f} +- {deltaFError[0, k]:5.2f}   {integrated:+12.2f}")
        accepted, proposed = reporter.read_mixing_statistics()
        accepted, proposed = np.sum(accepted, axis=0), np.sum(proposed, axis=0)
        rates = [accepted[k, k + 1]/max(proposed[k, k + 1], 1) for k in range(len(temperatures) - 1)]
        say("neighbour swap acceptance: " + ", ".join(f"{temperatures[k]:.0f}<->{temperatures[k + 1]:.0f} K {rate:.2f}"
                                                     for k, rate in enumerate(rates)))
        extremes = 0
        for replica in range(replicaStates.shape[1]):
            path_ = [s for s in replicaStates[:, replica] if s in (0, len(temperatures) - 1)]
            extremes += sum(1 for a, b in zip(path_, path_[1:]) if a != b)
        say(f"trips of a replica between the coldest and hottest temperature: {extremes} in all")
        last = reporter.read_sampler_states(iteration=reporter.read_last_iteration(last_checkpoint=True))
        waters = [[atom.index for atom in residue.atoms()] for residue in topology.residues() if residue.name == "HOH"]
        worst = 0.0
        for sampler in last:
            x = sampler.positions.value_in_unit(unit.nanometer)
            for o, h1, h2 in waters:
                for h in (h1, h2):
                    worst = max(worst, abs(np.linalg.norm(x[h] - x[o]) - 0.09572))
        say(f"waters in the last stored positions: largest O-H deviation from 0.09572 nm {worst:.1e} nm (rigid)")
    finally:
        reporter.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--replicas", type=int, default=4, help="temperatures (default 4)")
    parser.add_argument("--tmin", type=float, default=300.0, help="K (default 300)")
    parser.add_argument("--tmax", type=float, default=360.0, help="K (default 360)")
    parser.add_argument("--iterations", type=int, default=40, help="default 40")
    parser.add_argument("--steps", type=int, default=100, help="steps of 2 fs per iteration and replica (default 100)")
    parser.add_argument("--padding", type=float, default=0.8, help="nm of water around the solute (default 0.8)")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, default=0, help="CPU platform threads per process (default: its own choice)")
    parser.add_argument("--output", default=str(Path(__file__).parent / "output" / "replica_exchange.nc"))
    args = parser.parse_args()
    logging.getLogger("openmmtools").setLevel(logging.ERROR)  # its "experimental API" warnings, once per process
    started = time.perf_counter()
    communicator = mpiplus.get_mpicomm()
    rank, size = (0, 1) if communicator is None else (communicator.rank, communicator.size)

    def say(text):
        if rank == 0:
            print(text, flush=True)

    say(f"{size} process{'es' if size > 1 else ''} (MPI through mpiplus)" if size > 1 else "1 process (no MPI)")
    platform = openmm.Platform.getPlatformByName(args.platform)
    properties = {"Threads": str(args.threads)} if args.threads and args.platform == "CPU" else {}
    say("solvating alanine dipeptide, building and minimizing the System ...")
    topology, system, bodies, positions, box = build(args.padding, platform)
    solute = next(body for body in bodies if len(body) > 3)
    say(f"{system.getNumParticles()} atoms: the solute ({len(solute)} atoms) and {len(bodies) - 1} waters, "
        f"{len(bodies)} rigid bodies; PME, 0.8 nm cutoff")

    move = RigidLangevinDynamicsMove(timestep=2.0 * unit.femtosecond, collision_rate=1.0 / unit.picosecond,
                                     n_steps=args.steps, bodies=bodies)
    sampler = multistate.ParallelTemperingSampler(mcmc_moves=move, number_of_iterations=args.iterations)
    sampler.energy_context_cache = cache.ContextCache(platform=platform, platform_properties=properties)
    sampler.sampler_context_cache = cache.ContextCache(platform=platform, platform_properties=properties)
    Path(args.output).parent.mkdir(parents=True, exist_ok=True)
    if rank == 0 and Path(args.output).exists():
        Path(args.output).unlink()
    reporter = multistate.MultiStateReporter(args.output, checkpoint_interval=10)
    reference = states.ThermodynamicState(system, args.tmin * unit.kelvin)
    sampler.create(reference, states.SamplerState(positions, box_vectors=box), reporter,
                   min_temperature=args.tmin * unit.kelvin, max_temperature=args.tmax * unit.kelvin,
                   n_temperatures=args.replicas)
    say(f"parallel tempering: {args.replicas} replicas at "
        + ", ".join(f"{s.temperature.value_in_unit(unit.kelvin):.1f}" for s in sampler._thermodynamic_states)
        + f" K; {args.iterations} iterations of RigidLangevinDynamicsMove ({args.steps} steps of 2 fs, 1/ps)")
    running = time.perf_counter()
    sampler.run()
    elapsed = time.perf_counter() - running
    reporter.close()
    simulated = args.replicas * args.iterations * args.steps * 2e-6  # ns
    say(f"ran {args.replicas * args.iterations * args.steps} steps in all in {elapsed:.0f} s "
        f"({simulated / (elapsed / 86400):.2f} ns/day summed over replicas)")
    if rank == 0:
        analyse(args.output, topology, say)
    say(f"wrote {args.output}; total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

#!/usr/bin/env python
"""Stability stress runs of RigidBodyIntegrator (Exact and NoSquish), next to stock
VerletIntegrator + SETTLE where the System allows it.

Scenarios (built by rigidtesting.stress, shared with the test suite's tests/python/test_stress.py):

  a. Rigid water, TIP3P and TIP4P-Ew (PME, about 500 molecules; fewer with --quick), NVE from a
     300 K state: short runs (1 ps) at 4, 5, ... 12 fs find the largest stable step of each
     integrator (the first unstable one ends its scan), then a long run (20 ps) at that step; while
     the long run is unstable, the step goes down 1 fs and the long run is repeated (the unstable
     runs are reported, not counted as failures; "stable over 20 ps" is what the summary gives).
  b. Explicit bodies of extreme shapes (a rod whose principal moments span 1e6, near-spherical and
     near-symmetric tops with moments 1e-9 apart, linear CO2, a bent triatomic) among free
     Lennard-Jones atoms at 2000 K, periodic and isolated; the separatrix crossings are counted.
  c. 5000 K: TIP3P water, the same bodies in their bath, and the small-molecule cluster of the
     physics tests (every body kind, Lennard-Jones + Coulomb).
  d. A bent triatomic spinning at |omega| = 1e4 ps^-1: alone (against its exact free motion) and
     in a 2000 K Lennard-Jones bath.

Criteria (each run prints one line; a run of a rigid integrator fails if any is missed):
  - finite: no NaN or infinity in positions, velocities or energy, and no exception;
  - energy bounded: max |E(t) - E(0)| <= 1 % of the initial kinetic energy (0.005 kT per degree
    of freedom at equilibrium). Water in scenario a runs at the edge of stability by design; there
    a step is "stable" if the run stays finite with max |E(t) - E(0)| <= 5 % of the initial kinetic
    energy (had it all gone into heat, the temperature would have risen by at most about 5 %);
  - rigidity: no distance within a body changes by more than 1e-12 nm (absolute: the bodies are
    0.1 to 0.5 nm across and lie within a few nm of the origin, where double rounding is about
    1e-15 nm). For explicit bodies, every pair against the starting positions; for waters, their
    constraint distances after the first step (the starting positions come from the CPU
    platform's SETTLE, which holds H-H at the single-precision value of its distance, 4.7e-9 nm
    short; the first step projects them; stock Verlet + SETTLE keeps that offset, hence its 5e-9);
  - linear momentum: where the forces sum to zero (the Lennard-Jones pair forces here, double
    precision on both platforms), |P - P0| <= 1e-10 |P0| (every scenario drifts); with PME, whose
    forces do not sum to zero, the change of P over 50 single steps must equal the impulse of the
    net force, to 1e-10 of the summed |F| dt on Reference and to 1e-6 on CPU, whose float forces
    recomputed for a State may differ from those the step used by a rounding (stock Verlet too);
  - angular momentum (isolated systems): |L - L0| <= 1e-10 |L0|;
  - alone (no forces), Exact keeps the spinning body's energy to 1e-12 relative and follows its
    exact free motion (openmmrigid.FreeRotor from its starting state) to 1e-12 rad per radian
    turned: the rotation frequency is known to the rounding of the energy, so the angle's error
    grows with the angle turned. In the bath scenarios at least a
    few separatrix crossings must be seen.
Stock Verlet + SETTLE is measured by the same yardstick and reported, but never fails the run.

    python benchmarks/stress.py --quick     # about 1 minute on 2 cores
    python benchmarks/stress.py             # about 15 minutes
    options: --platform Reference|CPU (default CPU), --seed N, --only TEXT (scenarios whose name contains TEXT)

Exits with status 1 if any criterion fails. Writes docs/results/stress.md (the summary table; a quick
run: benchmarks/results/stress.md) and a copy of the output to benchmarks/results/stress.log.
"""

import argparse
import sys
import time

import numpy as np
import openmm

from benchmarking import RESULTS, ResultsDocument, closeLog, header, openLog, say
from rigidtesting import stress
from rigidtesting import stress as systems  # the cluster, exact rigid motion and state helpers
import rigidtesting

ENERGY_BUDGET = 0.01          # of the initial kinetic energy
STABILITY_BUDGET = 0.05       # of the initial kinetic energy: water at the edge of stability
RIGIDITY_TOLERANCE = 1e-12    # nm
MOMENTUM_TOLERANCE = 1e-10    # relative
IMPULSE_TOLERANCE = {"Reference": 1e-10, "CPU": 1e-6}
IMPULSE_STEPS = 50
FREE_ENERGY_TOLERANCE = 1e-12  # relative: the exact free rotor's invariants
SPIN_ANGLE_TOLERANCE = 1e-12  # rad per rad turned
STOCK = "Verlet+SETTLE"


class Row:
    """One run's line in the summary."""

    def __init__(self, scenario, integrator, stepSize, run, extra="", judged=True):
        self.scenario, self.integrator, self.stepSize, self.run = scenario.name, integrator, stepSize, run
        self.pme = not scenario.forcesSumToZero
        self.extra, self.judged = extra, judged
        self.failures = []


ROWS = []


def make_integrator(scenario, name, stepSize):
    if name == STOCK:
        integrator = openmm.VerletIntegrator(stepSize)
        integrator.setConstraintTolerance(1e-10)
        return integrator
    return scenario.integrator(stepSize, name)


def check(row, scenario, platform, impulse=None, spinError=None, minCrossings=None, energyBudget=ENERGY_BUDGET):
    """Apply the criteria to a run; record and return the failures."""
    run = row.run
    failures = []
    if not run.finite or run.error:
        failures.append("not finite" if not run.finite else f"raised: {run.error}")
    change = run.max_energy_change()
    if not change <= energyBudget * run.kinetic0:
        failures.append(f"energy: max |E-E0| {change:.3g} kJ/mol > {energyBudget:g} KE0")
    if not run.rigidity <= RIGIDITY_TOLERANCE:
        failures.append(f"rigidity {run.rigidity:.2g} nm")
    if scenario.forcesSumToZero and not run.relative_momentum_change() <= MOMENTUM_TOLERANCE:
        failures.append(f"momentum {run.relative_momentum_change():.2g}")
    if impulse is not None and not impulse <= IMPULSE_TOLERANCE[platform]:
        failures.append(f"impulse mismatch {impulse:.2g}")
    angular = run.relative_angular_change()
    if angular is not None and not angular <= MOMENTUM_TOLERANCE:
        failures.append(f"angular momentum {angular:.2g}")
    if spinError is not None and not spinError[0] <= spinError[1]:
        failures.append(f"spin off its free motion by {spinError[0]:.2g} rad (allowed {spinError[1]:.2g})")
    if minCrossings is not None and np.sum(run.crossings) < minCrossings:
        failures.append(f"only {np.sum(run.crossings)} separatrix crossings (want >= {minCrossings})")
    row.failures = failures
    return failures


def describe(row, scenario, impulse=None):
    run = row.run
    ps = run.steps * run.stepSize
    drift = 1000.0 * run.drift() / run.dof
    momentum = (f"dP/P0 {run.relative_momentum_change():.1e}" if scenario.forcesSumToZero
                else f"dP {run.momentumChange:.1e} (PME)" + (f", impulse {impulse:.1e}" if impulse is not None else ""))
    angular = run.relative_angular_change()
    text = (f"  {row.integrator:<13} {1000 * row.stepSize:6.3g} fs {ps:7.3g} ps: "
            f"{'finite' if run.finite and not run.error else 'NOT FINITE' if not run.finite else 'RAISED'}, "
            f"max|E-E0| {run.max_energy_change():.3g} kJ/mol ({run.max_energy_change() / run.kinetic0:.1e} KE0), "
            f"drift {drift:+.3g} kJ/mol/ns/dof, rigid {run.rigidity:.1e} nm, {momentum}"
            + (f", dL/L0 {angular:.1e}" if angular is not None else "")
            + (f", crossings {int(np.sum(run.crossings))} ({int(np.sum(run.crossings > 0))} bodies)"
               if len(run.crossings) else "")
            + (f", {row.extra}" if row.extra else ""))
    if row.judged:
        text += ": " + ("ok" if not row.failures else "FAIL (" + "; ".join(row.failures) + ")")
    return text


def one_run(scenario, name, stepSize, ps, platform, samples=200, judged=True, impulse=False, **criteria):
    steps = max(1, round(ps / stepSize))
    interval = max(1, steps // samples)
    start = time.perf_counter()
    run = stress.run(scenario, make_integrator(scenario, name, stepSize), platform, steps, interval, catch=True)
    mismatch = None
    if impulse and run.finite and not run.error and name != STOCK:
        mismatch = stress.impulse_mismatch(run.context, scenario.masses, IMPULSE_STEPS)
    run.context = None  # a PME Context holds tens of MB; the rows outlive it
    row = Row(scenario, name, stepSize, run, f"{time.perf_counter() - start:.0f} s", judged=judged and name != STOCK)
    check(row, scenario, platform, impulse=mismatch, **criteria)
    return row, mismatch


def report(row, scenario, mismatch=None, keep=True):
    say(describe(row, scenario, mismatch))
    if keep:
        ROWS.append(row)


# ---------------------------------------------------------------------------------------------------
# a. Rigid water: largest stable step

def water_scan(args, model):
    size = 1.9 if args.quick else 2.5
    scan = 0.3 if args.quick else 1.0
    long = 1.5 if args.quick else 20.0
    scenario = stress.water(model, size=size, temperature=300.0, cutoff=0.8 if args.quick else 0.9, seed=args.seed)
    say(f"\n[{scenario.name}, box {size} nm, PME] step scan ({scan} ps per step size; stable = finite and "
        f"max|E-E0| <= {STABILITY_BUDGET:g} KE0), then {long} ps at the largest stable step")

    def stable(row):
        run = row.run
        return run.finite and not run.error and run.max_energy_change() <= STABILITY_BUDGET * run.kinetic0

    largest = {}
    for name in (STOCK, "Exact", "NoSquish"):
        best = None
        for fs in range(4, 13):
            row, _ = one_run(scenario, name, fs * 1e-3, scan, args.platform, samples=30, judged=False)
            report(row, scenario, keep=False)
            if not stable(row):
                break
            best = fs
        largest[name] = best
    say("  largest stable step in the scan: " + ", ".join(f"{name} {fs} fs" for name, fs in largest.items()))
    final = {}
    for name in (STOCK, "Exact", "NoSquish"):
        fs = largest[name]
        while fs is not None and fs >= 4:
            row, mismatch = one_run(scenario, name, fs * 1e-3, long, args.platform, samples=300, impulse=True,
                                    energyBudget=STABILITY_BUDGET)
            # Stock Verlet is judged on stability alone (SETTLE holds the constraints to its tolerance).
            # Above the largest stable step, energy growth or a NaN is what the scan looks for, not a
            # failure: try 1 fs less. Any other failure (rigidity, momentum, an exception other than
            # a NaN) stays a failure.
            passed = stable(row)
            others = [f for f in row.failures if not f.startswith(("energy", "not finite"))]
            if not passed and fs > 4 and not others:
                row.judged = False
                row.extra = f"long run, unstable, step reduced; {row.extra}"
            else:
                row.extra = f"long run; {row.extra}"
            report(row, scenario, mismatch)
            if passed or others:
                break
            fs -= 1
        final[name] = fs if fs is not None and fs >= 4 else None
        if final[name] is None and name != STOCK:
            row = Row(scenario, name, 0.004, None)
            row.failures = ["no stable step of 4 fs or more"]
            ROWS.append(row)
    say(f"  largest stable step over {long} ps: " + ", ".join(f"{name} {fs} fs" for name, fs in final.items()))
    return final


# ---------------------------------------------------------------------------------------------------
# b, c. Bodies in a bath, hot systems

def bath_runs(args, temperature, periodic, stepSize, ps):
    copies, atoms = (2, 40) if args.quick else (6, 150)
    ps = 1.0 if args.quick else ps
    scenario = stress.bodies_in_bath(copies=copies, bathAtoms=atoms, temperature=temperature, periodic=periodic,
                                     seed=args.seed, spin=0.0 if periodic else 1.0)
    moments = [make().principal_moments() for make in stress.EXTREME_SHAPES]
    gaps = [np.diff(m) / m[2] for m in moments]
    say(f"\n[{scenario.name}: {copies} x (rod, near-spherical, near-symmetric, linear, bent) + {atoms} argon, "
        f"{len(scenario.masses)} particles] rod moments {moments[0][0] / moments[0][2]:.1e} of largest; "
        f"near-spherical gaps {gaps[1][0]:.1e}, {gaps[1][1]:.1e}; near-symmetric gap {gaps[2][1]:.1e}")
    for name in ("Exact", "NoSquish"):
        row, _ = one_run(scenario, name, stepSize, ps, args.platform, samples=max(200, round(ps / stepSize / 5)),
                         minCrossings=(2 if args.quick else 10) if periodic else None)
        crossings = row.run.crossings
        perShape = [int(np.sum(crossings[k * copies:(k + 1) * copies])) for k in range(len(stress.EXTREME_SHAPES))]
        row.extra = "crossings by shape " + "/".join(map(str, perShape)) + "; " + row.extra
        report(row, scenario)


def hot_water(args):
    scenario = stress.water("tip3p", size=1.7 if args.quick else 1.9, temperature=5000.0, seed=args.seed)
    ps = 0.5 if args.quick else 4.0
    say(f"\n[{scenario.name}, PME]")
    for name in (STOCK, "Exact", "NoSquish"):
        row, mismatch = one_run(scenario, name, 0.0005, ps, args.platform, impulse=True)
        report(row, scenario, mismatch)


def hot_cluster(args):
    scenario = stress.hot_cluster(5000.0, seed=args.seed, grid=(3, 3, 2) if args.quick else (4, 4, 3))
    say(f"\n[{scenario.name}: {len(scenario.bodies)} bodies of every kind + {len(scenario.free)} free ions, isolated]")
    for name in ("Exact", "NoSquish"):
        row, _ = one_run(scenario, name, 0.0005, 1.0 if args.quick else 10.0, args.platform)
        report(row, scenario)


# ---------------------------------------------------------------------------------------------------
# d. Fast spin

def spin_alone(args):
    scenario = stress.spinning_body(omega=1e4, seed=args.seed)
    stepSize, steps = 0.002, 1000 if args.quick else 20000
    exact = systems.rigid_motion(scenario.masses, scenario.positions, scenario.velocities, scenario.bodies,
                                 scenario.free)
    centre = scenario.masses @ scenario.positions / scenario.masses.sum()
    radius = np.max(np.linalg.norm(scenario.positions - centre, axis=1))
    say(f"\n[{scenario.name}, no forces: against the exact free motion]")
    for name in ("Exact", "NoSquish"):
        start = time.perf_counter()
        run = stress.run(scenario, scenario.integrator(stepSize if name == "Exact" else 1e-5, name), args.platform,
                         steps if name == "Exact" else 2000, max(1, steps // 200))
        t = run.steps * run.stepSize
        positions, velocities = systems.positions_of(run.context), systems.velocities_of(run.context)
        run.context = None
        expectedPositions, expectedVelocities = exact(t)
        angle = max(np.max(np.abs(positions - expectedPositions)) / radius,
                    np.max(np.abs(velocities - expectedVelocities)) / np.max(np.linalg.norm(expectedVelocities, axis=1)))
        turned = 1e4 * t
        extra = f"omega t {turned:.0f} rad, off exact motion by {angle:.1e} rad; {time.perf_counter() - start:.0f} s"
        row = Row(scenario, name, run.stepSize, run, extra)
        # NoSquish approximates the free rotation (at omega dt = 0.1 here): compared for information only.
        if name == "Exact":
            check(row, scenario, args.platform, spinError=(angle, SPIN_ANGLE_TOLERANCE * turned),
                  energyBudget=FREE_ENERGY_TOLERANCE)
        else:
            check(row, scenario, args.platform)
        report(row, scenario)


def spin_in_bath(args):
    scenario = stress.spinning_body(omega=1e4, bathAtoms=60 if args.quick else 150, temperature=2000.0, seed=args.seed)
    say(f"\n[{scenario.name} at 2000 K (atoms move 0.01 nm per step at 1e-5 ps)]")
    for name in ("Exact", "NoSquish"):
        row, _ = one_run(scenario, name, 1e-5, 0.02 if args.quick else 0.1, args.platform)
        report(row, scenario)


def summarize(args, start, largest):
    """The summary table of every run; returns the number of failing runs."""
    say(f"Summary ({args.platform}, {time.perf_counter() - start:.0f} s)")
    heading = (f"{'scenario':<44} {'integrator':<13} {'dt fs':>6} {'ps':>6} {'max|dE|/KE0':>11} {'drift/dof':>9} "
               f"{'finite':>6} {'rigid nm':>8} {'dP':>8} {'dL/L0':>8} {'cross':>5}  verdict")
    say(heading)
    say("-" * len(heading))
    failed = 0
    for row in ROWS:
        run = row.run
        verdict = "-" if not row.judged else ("ok" if not row.failures else "FAIL: " + "; ".join(row.failures))
        failed += bool(row.judged and row.failures)
        if run is None:
            say(f"{row.scenario[:44]:<44} {row.integrator:<13} {'':>75}  {verdict}")
            continue
        dP = "PME" if row.pme else f"{run.relative_momentum_change():.0e}"
        dL = run.relative_angular_change()
        say(f"{row.scenario[:44]:<44} {row.integrator:<13} {1000 * row.stepSize:6.3g} {run.steps * run.stepSize:6.3g} "
            f"{run.max_energy_change() / run.kinetic0:11.1e} {1000 * run.drift() / run.dof:+9.2g} "
            f"{'yes' if run.finite and not run.error else 'NO':>6} {run.rigidity:8.0e} {dP:>8} "
            f"{'-' if dL is None else f'{dL:.0e}':>8} {int(np.sum(run.crossings)):5d}  {verdict}")
    for key, steps in largest.items():
        say(f"largest stable step, {key}: " + ", ".join(f"{name} {'none' if fs is None else f'{fs} fs'}"
                                                     for name, fs in steps.items()))
    say(f"{failed} failing run(s)" if failed else "all criteria met")
    return failed


# ---------------------------------------------------------------------------------------------------

def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small systems, short runs (a couple of minutes)")
    parser.add_argument("--platform", default="CPU", choices=["Reference", "CPU"])
    parser.add_argument("--seed", type=int, default=5)
    parser.add_argument("--only", default="", help="run only the scenarios whose name contains this text")
    args = parser.parse_args()
    openLog(RESULTS / "stress.log")
    for line in header(args.platform):
        say(line)
    say(f"settings: {'quick' if args.quick else 'full'}, platform {args.platform}, seed {args.seed}")
    document = ResultsDocument("stress", "Stability under stress", quick=args.quick, platform=args.platform,
                               about="Method and criteria: the docstring of `benchmarks/stress.py`." +
                                     (f" Only the scenarios matching `{args.only}`." if args.only else ""))
    start = time.perf_counter()
    scenarios = [
        ("water-tip3p", lambda: water_scan(args, "tip3p")),
        ("water-tip4pew", lambda: water_scan(args, "tip4pew")),
        ("bath-2000K-periodic", lambda: bath_runs(args, 2000.0, True, 0.001, 5.0)),
        ("bath-2000K-isolated", lambda: bath_runs(args, 2000.0, False, 0.001, 2.5)),
        ("hot-bath-5000K", lambda: bath_runs(args, 5000.0, True, 0.0005, 4.0)),
        ("hot-water-5000K", lambda: hot_water(args)),
        ("hot-cluster-5000K", lambda: hot_cluster(args)),
        ("spin-alone", lambda: spin_alone(args)),
        ("spin-in-bath", lambda: spin_in_bath(args)),
    ]
    largest = {}
    for key, function in scenarios:
        if args.only in key:
            result = function()
            if key.startswith("water"):
                largest[key] = result

    with document.capture():
        failed = summarize(args, start, largest)
    document.write()
    closeLog()
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())

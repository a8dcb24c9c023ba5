#!/usr/bin/env python
"""How far approximate free rotation strays from the exact one, and what the exact one costs.

The exact solution of van Zon and Schofield (J. Comput. Phys. 225, 145 (2007)), openmmrigid.FreeRotor,
used as the paper uses it: as the yardstick for approximate rotation schemes.

Bodies: random asymmetric tops, seeded. Principal moments I1 < I2 < I3 drawn about the size of a
water molecule's (I1, I2 uniform in [0.005, 0.02] amu nm^2, I3 uniform in [max(I1, I2), I1 + I2]: the
triangle inequality of a real mass distribution), a uniformly random attitude, and a body-frame
angular velocity drawn from the Boltzmann distribution at 300 K (omega_k of standard deviation
sqrt(kT/I_k), about 20 rad/ps: rotation periods of a few tenths of a ps).

Part 1, accuracy. Each body is rotated freely for T = 1 ps with steps dt of 1/64 (quick: 1/16) to 16 fs by
- NO_SQUISH (Miller et al., J. Chem. Phys. 116, 8649 (2002)): the symplectic splitting of the free
  rotor into uniform rotations about the body axes 3, 2, 1, 2, 3 (half, half, full, half, half step),
  axis 3 being that of the largest moment. Written here in numpy exactly as
  openmmapi/include/numerics/NoSquish.h does it (including that L is kept in the lab frame, where
  it is conserved, and the body-frame L is A L_lab at the start of every step); and
- a plain first-order update: omega held fixed over the step at its value at the start,
  omega_body = I^-1 A L_lab, and A(t + dt) = exp(-dt W(omega_body)) A(t) (W(w) x = w x x; the body
  frame rotation on the left; it is the same matrix as A exp(-dt W(omega_lab)), the lab-frame one on the
  right). L_lab is conserved exactly, so every error is in the attitude and, through it, in omega_body.
Errors at T against FreeRotor.evolve(T): the attitude error is the angle of the rotation
A A_exact^T (= 2 asin(|A - A_exact|_F / (2 sqrt 2))), the angular velocity error
|omega_body - omega_exact| / |omega_exact|; median and 90th percentile over the bodies; the order is
the slope of log(median error) against log(dt) over the steps whose median attitude error stays
below 0.05 rad (the asymptotic regime; at larger errors the angle saturates at pi).

Part 2, the C++ integrator. The same bodies as explicit six-particle bodies (masses at +-x e1, +-y e2,
+-z e3 with x, y, z chosen to give the moments) in one System with no forces (Reference platform):
RigidBodyIntegrator with setRotationMethod(NoSquish) for T at dt = 2 fs must match the numpy
NO_SQUISH to rounding, and with Exact must match FreeRotor to rounding.

Part 3, the cost. RigidBodyIntegrator Exact against NoSquish on N (8000) such bodies with no forces,
CPU platform, one thread, interleaved blocks, medians (the timing helpers of benchmarks/benchmarking.py,
with the process's CPU time recorded next to the wall time): ns per body per step, and the accuracy
each buys at a typical step.

    python benchmarks/rotation_accuracy.py            # default: a few minutes
    python benchmarks/rotation_accuracy.py --quick    # fewer bodies and steps: under a minute

Writes docs/results/rotation_accuracy.md and docs/figures/rotation_accuracy.png (a quick run: both in
benchmarks/results/), and benchmarks/results/rotation_accuracy.csv.
"""

import sys
import os
import argparse
import datetime
import time

import numpy as np
import openmm
from openmm import unit

import openmmrigid

from benchmarking import (RESULTS, ResultsDocument, blockSteps, bodyKinds, cpuProperties, header, medianRange, pyplot,
                          say, saveFigure, timeInterleaved, writeCsv)
import rigidtesting  # tests/python, on the path benchmarking sets

plt = pyplot()
STEP = 2*unit.femtosecond
BOLTZMANN = 0.00831446261815324  # kJ/mol/K
TEMPERATURE = 300.0              # K
PARTICLE_MASS = 4.0              # amu, each of the six masses of a benchmark body
TYPICAL_STEP = 2.0               # fs, where the summary compares the methods
ERROR_TARGET = 1e-6              # rad after T, for "the step NO_SQUISH needs"
SCHEMES = ("NoSquish", "first-order")


# ---------------------------------------------------------------------------------------------------
# Bodies

def randomBodies(count, seed):
    """Moments (count, 3) ascending, attitudes (count, 3, 3) lab to body, body-frame omegas (count, 3)."""
    rng = np.random.default_rng(seed)
    moments = np.empty((count, 3))
    for row in moments:
        first, second = rng.uniform(0.005, 0.02, size=2)
        row[:] = sorted([first, second, rng.uniform(max(first, second), first + second)])
    attitudes = np.array([rigidtesting.randomRotation(rng) for _ in range(count)])
    omegas = rng.normal(size=(count, 3))*np.sqrt(BOLTZMANN*TEMPERATURE/moments)
    return moments, attitudes, omegas


def sixMassCoordinates(moments):
    """Body-frame coordinates (count, 6, 3) of six equal masses whose principal moments are `moments`.

    Masses m at +-x e1, +-y e2, +-z e3 give I1 = 2m(y^2 + z^2) and cyclic, so 4 m x^2 = I2 + I3 - I1.
    """
    half = np.sqrt((moments.sum(axis=1, keepdims=True) - 2*moments)/(4*PARTICLE_MASS))
    coordinates = np.zeros((len(moments), 6, 3))
    for k in range(3):
        coordinates[:, 2*k, k] = half[:, k]
        coordinates[:, 2*k + 1, k] = -half[:, k]
    return coordinates


# ---------------------------------------------------------------------------------------------------
# Rotation schemes, vectorised over bodies. A: (n, 3, 3) lab to body; angularMomentum: (n, 3) lab frame.

def noSquishStep(moments, dt, attitudes, angularMomentum):
    """One NO_SQUISH step, as in NoSquish.h: rotations U(-phi e_k), phi = (L_k/I_k) fraction dt, of A and L_body."""
    bodyMomentum = np.einsum("nij,nj->ni", attitudes, angularMomentum)
    for axis, fraction in ((2, 0.5), (1, 0.5), (0, 1.0), (1, 0.5), (2, 0.5)):
        i, j = (axis + 1) % 3, (axis + 2) % 3
        angle = bodyMomentum[:, axis]/moments[:, axis]*fraction*dt
        c, s = np.cos(angle), np.sin(angle)
        rowI, rowJ = attitudes[:, i, :].copy(), attitudes[:, j, :].copy()
        attitudes[:, i, :] = c[:, None]*rowI + s[:, None]*rowJ
        attitudes[:, j, :] = -s[:, None]*rowI + c[:, None]*rowJ
        li, lj = bodyMomentum[:, i].copy(), bodyMomentum[:, j].copy()
        bodyMomentum[:, i] = c*li + s*lj
        bodyMomentum[:, j] = -s*li + c*lj


def rotationMatrices(vectors):
    """exp(W(v)) for each row v of `vectors` (Rodrigues), W(v) x = v x x."""
    angle = np.linalg.norm(vectors, axis=1)
    axis = vectors/np.where(angle > 0, angle, 1.0)[:, None]
    cross = np.zeros((len(vectors), 3, 3))
    cross[:, 0, 1], cross[:, 0, 2], cross[:, 1, 2] = -axis[:, 2], axis[:, 1], -axis[:, 0]
    cross -= cross.transpose(0, 2, 1)
    return (np.eye(3) + np.sin(angle)[:, None, None]*cross
            + (1 - np.cos(angle))[:, None, None]*np.einsum("nij,njk->nik", cross, cross))


def firstOrderStep(moments, dt, attitudes, angularMomentum):
    """A <- exp(-dt W(omega_body)) A with omega_body = I^-1 A L_lab from the start of the step."""
    omega = np.einsum("nij,nj->ni", attitudes, angularMomentum)/moments
    attitudes[:] = np.einsum("nij,njk->nik", rotationMatrices(-dt*omega), attitudes)


STEPPERS = {"NoSquish": noSquishStep, "first-order": firstOrderStep}


def integrate(scheme, moments, attitudes, omegas, dt, steps):
    """Attitudes and body-frame omegas after `steps` steps of `scheme` (arrays are not modified)."""
    attitudes = attitudes.copy()
    angularMomentum = np.einsum("nji,nj->ni", attitudes, moments*omegas)  # L_lab = A^T I omega
    step = STEPPERS[scheme]
    for _ in range(steps):
        step(moments, dt, attitudes, angularMomentum)
    return attitudes, np.einsum("nij,nj->ni", attitudes, angularMomentum)/moments


def exactStates(moments, attitudes, omegas, t):
    """FreeRotor's attitudes and body-frame omegas at time t."""
    results = [openmmrigid.FreeRotor(I, w, A).evolve(t) for I, w, A in zip(moments, omegas, attitudes)]
    return np.array([a for _, a in results]), np.array([w for w, _ in results])


def attitudeAngles(attitudes, references):
    """The rotation angle of A A_ref^T for each body, from the Frobenius norm of A - A_ref (no acos)."""
    distance = np.linalg.norm(attitudes - references, axis=(1, 2))
    return 2*np.arcsin(np.minimum(distance/(2*np.sqrt(2)), 1.0))


def omegaErrors(omegas, references):
    return np.linalg.norm(omegas - references, axis=1)/np.linalg.norm(references, axis=1)


# ---------------------------------------------------------------------------------------------------
# Part 1: accuracy against FreeRotor

def measureAccuracy(moments, attitudes, omegas, total, stepsFs):
    exactAttitudes, exactOmegas = exactStates(moments, attitudes, omegas, total)
    rows = []
    for scheme in SCHEMES:
        for dtFs in stepsFs:
            steps = int(round(total/(dtFs*1e-3)))
            started = time.perf_counter()
            finalAttitudes, finalOmegas = integrate(scheme, moments, attitudes, omegas, total/steps, steps)
            angles = attitudeAngles(finalAttitudes, exactAttitudes)
            omegaError = omegaErrors(finalOmegas, exactOmegas)
            rows.append({"scheme": scheme, "dt_fs": dtFs, "steps": steps,
                         "attitude_median_rad": np.median(angles), "attitude_p90_rad": np.percentile(angles, 90),
                         "omega_median_rel": np.median(omegaError), "omega_p90_rel": np.percentile(omegaError, 90),
                         "seconds": time.perf_counter() - started})
    return rows


def order(rows, scheme, key):
    """Slope of log(median error) against log(dt) where the median attitude error is below 0.05 rad."""
    points = [(r["dt_fs"], r[key]) for r in rows if r["scheme"] == scheme and r["attitude_median_rad"] < 0.05]
    if len(points) < 2:
        return float("nan")
    dts, errors = np.log(np.array(points)).T
    return np.polyfit(dts, errors, 1)[0]


def printAccuracy(rows, total, count):
    say(f"\nPart 1: error after T = {total:g} ps of free rotation against FreeRotor; {count} random asymmetric bodies")
    say(f"{'scheme':<13}{'dt (fs)':>9}{'steps':>8}{'attitude median':>17}{'90th pct':>11}"
          f"{'omega median':>15}{'90th pct':>11}")
    for row in rows:
        say(f"{row['scheme']:<13}{row['dt_fs']:>9.4g}{row['steps']:>8}{row['attitude_median_rad']:>17.3e}"
              f"{row['attitude_p90_rad']:>11.3e}{row['omega_median_rel']:>15.3e}{row['omega_p90_rel']:>11.3e}")
    say("attitude: rotation angle of A A_exact^T (rad); omega: |omega - omega_exact|/|omega_exact| (body frame)")
    for scheme in SCHEMES:
        say(f"order of {scheme}: {order(rows, scheme, 'attitude_median_rad'):.3f} (attitude), "
              f"{order(rows, scheme, 'omega_median_rel'):.3f} (omega); fit where the median attitude error is below 0.05 rad")


# ---------------------------------------------------------------------------------------------------
# Part 2: the C++ integrator against the numpy NO_SQUISH and FreeRotor

def particleStates(moments, attitudes, omegas):
    """Lab positions and velocities (count, 6, 3) of the six masses of each body (centred at the origin)
    with the given attitudes and body-frame omegas: r = A^T b, v = (A^T omega) x r."""
    positions = np.einsum("nji,npj->npi", attitudes, sixMassCoordinates(moments))
    return positions, np.cross(np.einsum("nji,nj->ni", attitudes, omegas)[:, None, :], positions)


def bodySystem(count):
    """A System of `count` six-mass bodies with no forces, and the bodies' particle indices."""
    system = openmm.System()
    return system, [[system.addParticle(PARTICLE_MASS) for _ in range(6)] for _ in range(count)]


def integratorStates(moments, attitudes, omegas, method, dt, steps):
    """Positions and velocities (count, 6, 3) after `steps` steps of RigidBodyIntegrator (Reference platform)."""
    system, bodies = bodySystem(len(moments))
    positions, velocities = particleStates(moments, attitudes, omegas)
    integrator = openmmrigid.RigidBodyIntegrator(dt, bodies)
    integrator.setRotationMethod(method)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(positions.reshape(-1, 3))
    context.setVelocities(velocities.reshape(-1, 3))
    integrator.step(steps)
    state = context.getState(getPositions=True, getVelocities=True)
    return (state.getPositions(asNumpy=True).value_in_unit(unit.nanometer).reshape(-1, 6, 3),
            state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond).reshape(-1, 6, 3))


def compareWithIntegrator(moments, attitudes, omegas, total, dtFs):
    """The C++ integrator's deviation from the numpy NO_SQUISH (NoSquish) and from FreeRotor (Exact) after
    T: {method: (position, velocity deviations)}, each body's largest particle deviation relative to
    its size (positions) and to |omega| x size (velocities)."""
    steps = int(round(total/(dtFs*1e-3)))
    dt = total/steps
    size = np.linalg.norm(sixMassCoordinates(moments), axis=2).max(axis=1)
    expected = {openmmrigid.RigidBodyIntegrator.NoSquish: integrate("NoSquish", moments, attitudes, omegas, dt, steps),
                openmmrigid.RigidBodyIntegrator.Exact: exactStates(moments, attitudes, omegas, total)}
    results = {}
    for method, (finalAttitudes, finalOmegas) in expected.items():
        positions, velocities = particleStates(moments, finalAttitudes, finalOmegas)
        cppPositions, cppVelocities = integratorStates(moments, attitudes, omegas, method, dt, steps)
        speed = size*np.linalg.norm(finalOmegas, axis=1)
        results[method] = (np.abs(cppPositions - positions).max(axis=(1, 2))/size,
                           np.abs(cppVelocities - velocities).max(axis=(1, 2))/speed)
    return steps, results


def printComparison(steps, results, total, dtFs, count):
    say(f"\nPart 2: RigidBodyIntegrator (C++, Reference platform, no forces), {count} bodies of six masses, "
          f"{steps} steps of {dtFs:g} fs (T = {total:g} ps)")
    say(f"{'integrator method':<20}{'compared with':<26}{'positions: max':>16}{'median':>10}"
          f"{'velocities: max':>17}{'median':>10}")
    names = {openmmrigid.RigidBodyIntegrator.NoSquish: ("NoSquish", "numpy NO_SQUISH (here)"),
             openmmrigid.RigidBodyIntegrator.Exact: ("Exact", "FreeRotor.evolve(T)")}
    for method, (positionErrors, velocityErrors) in results.items():
        say(f"{names[method][0]:<20}{names[method][1]:<26}{positionErrors.max():>16.2e}{np.median(positionErrors):>10.2e}"
              f"{velocityErrors.max():>17.2e}{np.median(velocityErrors):>10.2e}")
    say("deviation of each particle relative to the body's size (positions) and to |omega| x size (velocities)")


# ---------------------------------------------------------------------------------------------------
# Part 3: cost per body per step (integrator alone)

def measureCost(count, seed, seconds, repetitions):
    moments, attitudes, omegas = randomBodies(count, seed)
    system, bodies = bodySystem(count)
    positions, _ = particleStates(moments, attitudes, omegas)
    cpu = openmm.Platform.getPlatformByName("CPU")
    integrators, contexts = {}, []
    for name, method in (("Exact", openmmrigid.RigidBodyIntegrator.Exact),
                         ("NoSquish", openmmrigid.RigidBodyIntegrator.NoSquish)):
        integrator = openmmrigid.RigidBodyIntegrator(STEP, bodies)
        integrator.setRotationMethod(method)
        context = openmm.Context(system, integrator, cpu, cpuProperties("CPU", 1))
        context.setPositions(positions.reshape(-1, 3))
        context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 7)
        integrators[name] = integrator
        contexts.append(context)
    kinds = set(bodyKinds(contexts[0], integrators["Exact"]))  # from the bodies' positions (benchmarking.bodyKind)
    steps = blockSteps(integrators["Exact"], None, seconds, 10)
    wall, cpu = timeInterleaved(integrators, steps, repetitions)
    return ({name: medianRange(samples, 1e9/count) for name, samples in wall.items()},
            {name: medianRange(samples, 1e9/count) for name, samples in cpu.items()}, steps, kinds)


def printCost(wall, cpu, steps, kinds, count, repetitions):
    say(f"\nPart 3: RigidBodyIntegrator alone, {count} six-mass asymmetric bodies (kinds found: {', '.join(sorted(kinds))}), "
          f"no forces, CPU platform, 1 thread, 2 fs; {repetitions} interleaved blocks of {steps} steps")
    widths = (27, 9, 9, 27, 9, 9)
    headings = ("wall ns/body/step: median", "min", "max", "CPU ns/body/step: median", "min", "max")
    say(f"{'method':<12}" + "".join(f"{heading:>{width}}" for heading, width in zip(headings, widths)))
    for name in wall:
        say(f"{name:<12}" + "".join(f"{value:>{width}.1f}" for value, width in zip(wall[name] + cpu[name], widths)))
    wallRatio, cpuRatio = wall["Exact"][0]/wall["NoSquish"][0], cpu["Exact"][0]/cpu["NoSquish"][0]
    say(f"Exact / NoSquish: {wallRatio:.2f} (wall), {cpuRatio:.2f} (CPU time; less sensitive to other work on the machine). "
          f"Both include the per-particle work the methods share (6 particles per body).")
    return cpuRatio


def interpolateStep(rows, scheme, target):
    """The dt (fs) at which the median attitude error of `scheme` reaches `target`, log-log interpolated
    (extrapolated along the fitted order outside the measured range)."""
    points = sorted((r["dt_fs"], r["attitude_median_rad"]) for r in rows if r["scheme"] == scheme)
    dts, errors = np.log(np.array(points)).T
    if errors[0] <= np.log(target) <= errors[-1]:
        return float(np.exp(np.interp(np.log(target), errors, dts)))
    slope = order(rows, scheme, "attitude_median_rad")
    anchor = 0 if np.log(target) < errors[0] else -1
    return float(np.exp(dts[anchor] + (np.log(target) - errors[anchor])/slope))


def printSummary(rows, ratio, comparison, total):
    typical = {r["scheme"]: r for r in rows if r["dt_fs"] == TYPICAL_STEP}
    noSquish = typical["NoSquish"]["attitude_median_rad"]
    exactError = comparison[openmmrigid.RigidBodyIntegrator.Exact][0]
    sameCost = TYPICAL_STEP/ratio
    sameCostError = noSquish*ratio**(-order(rows, "NoSquish", "attitude_median_rad"))
    needed = interpolateStep(rows, "NoSquish", ERROR_TARGET)
    say(f"\nSummary at dt = {TYPICAL_STEP:g} fs, free rotation for T = {total:g} ps (median attitude error):")
    say(f"  first-order {typical['first-order']['attitude_median_rad']:.2e} rad, NoSquish {noSquish:.2e} rad, "
          f"Exact: rounding (the C++ integrator against FreeRotor, part 2: {np.median(exactError):.1e}, "
          f"largest {exactError.max():.1e})")
    say(f"  Exact costs {ratio:.2f} x NoSquish per body per step (CPU time). NoSquish given the same CPU time "
          f"(dt = {sameCost:.2f} fs) would reach about {sameCostError:.1e} rad;")
    say(f"  for a median error of {ERROR_TARGET:g} rad after {total:g} ps NoSquish needs dt = {needed:.3g} fs: "
          f"{TYPICAL_STEP/needed:.0f} x the steps, {TYPICAL_STEP/needed/ratio:.0f} x the cost of Exact at {TYPICAL_STEP:g} fs.")
    say("  With forces both integrators are second order overall: the free-rotation error is only the part of the\n"
          "  splitting error that Exact removes (examples/rigid_water.py: equal energy conservation in liquid water).")


# ---------------------------------------------------------------------------------------------------
# Output

def plot(path, rows, exactErrors, total, count, title):
    figure, axes = plt.subplots(1, 2, figsize=(11, 4.3))
    keys = (("attitude_median_rad", "attitude_p90_rad", "attitude error after T (rad)"),
            ("omega_median_rel", "omega_p90_rel", r"relative error of $\omega$ after T"))
    for ax, (median, p90, label) in zip(axes, keys):
        for scheme, colour in zip(SCHEMES, ("C0", "C1")):
            points = [r for r in rows if r["scheme"] == scheme]
            dts = np.array([r["dt_fs"] for r in points])
            ax.loglog(dts, [r[median] for r in points], "o-", color=colour,
                      label=f"{scheme} median (order {order(rows, scheme, median):.2f})")
            ax.loglog(dts, [r[p90] for r in points], "--", color=colour, alpha=0.6, label=f"{scheme} 90th percentile")
        dts = np.array(sorted({r["dt_fs"] for r in rows}))
        for scheme, slope, style in (("NoSquish", 2, ":"), ("first-order", 1, "-.")):
            anchor = next(r[median] for r in rows if r["scheme"] == scheme and r["dt_fs"] == dts[0])
            ax.loglog(dts, 0.2*anchor*(dts/dts[0])**slope, style, color="grey", label=f"slope {slope} (guide)")
        position, velocity = exactErrors
        ax.loglog([TYPICAL_STEP], [np.median(position if median.startswith("attitude") else velocity)], "s", color="C2",
                  label="Exact (C++ integrator) median:\nrounding")
        ax.set_xlabel("dt (fs)")
        ax.set_ylabel(label)
        ax.grid(True, which="major", alpha=0.3)
        ax.legend(fontsize=7, loc="lower left")
    figure.suptitle(f"Free rotation against FreeRotor, T = {total:g} ps, {count} random asymmetric bodies; {title}", fontsize=9)
    saveFigure(figure, path)


def parseArguments():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true",
                        help="100 bodies and dt from 1/16 fs for the accuracy, 2000 bodies and shorter blocks for the cost")
    parser.add_argument("--bodies", type=int, help="bodies for the accuracy (default 1000, quick 100)")
    parser.add_argument("--cost-bodies", type=int, help="bodies for the cost (default 8000, quick 2000)")
    parser.add_argument("--time", type=float, default=1.0, help="total time T in ps (default 1)")
    parser.add_argument("--repetitions", type=int, default=5, help="timed blocks per method (default 5)")
    parser.add_argument("--seed", type=int, default=2007)
    args = parser.parse_args()
    args.bodies = args.bodies or (100 if args.quick else 1000)
    args.costBodies = args.cost_bodies or (2000 if args.quick else 8000)
    args.steps = [2.0**k for k in range(-4 if args.quick else -6, 5)]
    args.seconds = 0.3 if args.quick else 1.5
    return args


def main():
    args = parseArguments()
    document = ResultsDocument("rotation_accuracy", "Free rotation alone: approximate schemes against the exact rotor",
                               quick=args.quick, platform="Reference (parts 1, 2) and CPU (part 3)", threads=1,
                               about="Method: the docstring of `benchmarks/rotation_accuracy.py`.")
    started = time.perf_counter()
    for line in header("Reference and CPU", 1):
        say(line)
    say(f"{'quick' if args.quick else 'default'} mode, seed {args.seed}")
    moments, attitudes, omegas = randomBodies(args.bodies, args.seed)
    with document.capture():
        rows = measureAccuracy(moments, attitudes, omegas, args.time, args.steps)
        printAccuracy(rows, args.time, args.bodies)
        steps, comparison = compareWithIntegrator(moments, attitudes, omegas, args.time, TYPICAL_STEP)
        printComparison(steps, comparison, args.time, TYPICAL_STEP, args.bodies)
        wall, cpu, costSteps, kinds = measureCost(args.costBodies, args.seed + 1, args.seconds, args.repetitions)
        ratio = printCost(wall, cpu, costSteps, kinds, args.costBodies, args.repetitions)
        printSummary(rows, ratio, comparison, args.time)
    say()
    writeCsv(RESULTS / "rotation_accuracy.csv", rows)
    figure = document.figurePath("rotation_accuracy.png")
    plot(figure, rows, comparison[openmmrigid.RigidBodyIntegrator.Exact], args.time, args.bodies,
         f"{datetime.date.today()}{' (quick)' if args.quick else ''}")
    document.figure(figure, "rotation accuracy")
    document.write()
    say(f"total {time.perf_counter() - started:.0f} s")


if __name__ == "__main__":
    main()

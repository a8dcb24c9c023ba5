#!/usr/bin/env python
"""Configuration-space sampling error against step size: the near-equilibrium estimate of the KL
divergence of each integrator's sampled configurations from the Boltzmann distribution (Sivak,
Chodera and Crooks, Phys. Rev. X 3, 011007 (2013); Fass et al., Entropy 20, 318 (2018); the
estimator: openmmrigid.testing.samplingerror), plotted against ns/day.

Integrators (friction 1/ps, 300 K):

- rigid-exact, rigid-nosquish: RigidBodyLangevinIntegrator (Exact, NoSquish), shadow work from
  setMeasureShadowWork(); rigid-raised: Exact with setMinimumMomentOfInertia(`--floor`);
- stock-middle: LangevinMiddleIntegrator + SETTLE written as a CustomIntegrator (its step, as OpenMM's
  documentation writes it) that sums its shadow work: K + U before and after each step, less the
  kinetic energy its O stage adds;
- openmmtools-vrorv: openmmtools' LangevinIntegrator(splitting="V R O R V", measure_shadow_work=True)
  where openmmtools is installed.

Systems: water, rigid TIP3P with PME 0.9 nm (500 molecules: about openmmtools' WaterBox, Fass et
al.'s system); peptide, alanine dipeptide in 500 TIP3P waters (amber14, constraints=HBonds,
hydrogenMass=3 amu, as benchmarks/nvt_accuracy.py). Equilibrium configurations: `--samples` frames
`--spacing` ps apart from a run of RigidBodyLangevinIntegrator at 1 fs and friction 5/ps (after
`--equilibrate` ps), the same frames for every integrator. For each frame: velocities from
Maxwell-Boltzmann, `--protocol` ps of the integrator (shadow work w_pi), velocities drawn again,
`--protocol` ps more (w_omega); KL = (<w_pi> - <w_omega>)/2 in kT, +- the standard error of the
paired differences. The cost: at each step, the integrators a user would run (no shadow work, no
accuracy check; stock-middle as OpenMM's LangevinMiddleIntegrator) timed side by side (interleaved
blocks, medians).
An integrator that fails (NaN, an unstable drift) at a step is not run at larger ones. The rigid
integrators' accuracy check is recorded (whether it fired) and its warning not shown.

    python benchmarks/sampling_error.py --quick      # 216 waters, 3 steps, 3 frames, 0.2 ps: a smoke check of minutes
    python benchmarks/sampling_error.py              # the full run (hours on 2 cores): docs/results/sampling_error.md

Compare the ranking with the U-per-molecule reading of benchmarks/nvt_accuracy.py
(docs/results/nvt_accuracy.md).

On-step velocities: RigidBodyLangevinIntegrator and LangevinMiddleIntegrator hold velocities half a
step behind the positions (LFMiddle). Their step is BAOAB's with its closing half kick joined to the
next step's opening one, so each protocol starts from canonical on-step velocities moved half a kick
back, and its shadow work is corrected at both ends to BAOAB's (Runner.work): the same quantity that
openmmtools' VRORV (BAOAB) measures. Without that correction (as in the first reduced run of
2026-12-02) the end terms, of first order in the step, gave error bars 5 to 10 times VRORV's.
"""

import argparse
import warnings

import numpy as np
import openmm
from openmm import app, unit

import benchmarking
from benchmarking import say, stamp
import openmmrigid
from openmmrigid.testing import alanineDipeptide, waterBox
from openmmrigid.testing.samplingerror import configurationKL

KJ = unit.kilojoule_per_mole
TEMPERATURE = 300.0
FRICTION = 1.0
KT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(KJ/unit.kelvin)*TEMPERATURE
FLOOR = [0.08]  # rigid-raised's minimum moment of inertia (amu nm^2), set from --floor


def makeSystem(name, molecules):
    if name == "water":
        return waterBox("tip3p", molecules=molecules)
    forceField = app.ForceField("amber14-all.xml", "amber14/tip3p.xml")
    return waterBox("tip3p", molecules=molecules, forceField=forceField, solute=alanineDipeptide(),
                    constraints=app.HBonds, hydrogenMass=3*unit.amu)


def stockMiddle(stepPs):
    """LangevinMiddleIntegrator's step as a CustomIntegrator, with its shadow work (kJ/mol) in "work":
    each step adds K + U after the previous step less K + U before it, less the previous step's heat
    (the kinetic energy its O stage and the velocity constraints after it added)."""
    integrator = openmm.CustomIntegrator(stepPs)
    a = np.exp(-FRICTION*stepPs)
    for name, value in (("a", a), ("b", np.sqrt(1 - a*a)), ("kT", KT), ("work", 0.0), ("heat", 0.0), ("start", 0.0),
                        ("started", 0.0), ("ke", 0.0)):
        integrator.addGlobalVariable(name, value)
    integrator.addPerDofVariable("x1", 0.0)
    integrator.addUpdateContextState()
    integrator.addComputeSum("ke", "0.5*m*v*v")
    integrator.addComputeGlobal("work", "work + started*(ke + energy - start - heat)")
    integrator.addComputeGlobal("start", "ke + energy")
    integrator.addComputeGlobal("started", "1")
    integrator.addComputePerDof("v", "v + dt*f/m")
    integrator.addConstrainVelocities()
    integrator.addComputePerDof("x", "x + 0.5*dt*v")
    integrator.addComputeSum("ke", "0.5*m*v*v")
    integrator.addComputeGlobal("heat", "-ke")
    integrator.addComputePerDof("v", "a*v + b*sqrt(kT/m)*gaussian")
    integrator.addComputeSum("ke", "0.5*m*v*v")
    integrator.addComputeGlobal("heat", "heat + ke")
    integrator.addComputePerDof("x", "x + 0.5*dt*v")
    integrator.addComputePerDof("x1", "x")
    integrator.addConstrainPositions()
    integrator.addComputePerDof("v", "v + (x - x1)/dt")
    return integrator


def rigidIntegrator(kind, stepPs):
    integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, FRICTION, stepPs)
    if kind == "rigid-nosquish":
        integrator.setRotationMethod(openmmrigid.RigidBodyLangevinIntegrator.NoSquish)
    if kind == "rigid-raised":
        integrator.setMinimumMomentOfInertia(FLOOR[0])
    return integrator


def timedIntegrator(kind, stepFs):
    """The integrator a user would run, for the cost: no shadow work, no accuracy check; stock-middle
    is OpenMM's LangevinMiddleIntegrator itself."""
    stepPs = stepFs*1e-3
    if kind.startswith("rigid"):
        integrator = rigidIntegrator(kind, stepPs)
        integrator.setAccuracyCheck(False)
        return integrator
    if kind == "stock-middle":
        return openmm.LangevinMiddleIntegrator(TEMPERATURE, FRICTION, stepPs)
    from openmmtools.integrators import LangevinIntegrator
    return LangevinIntegrator(temperature=TEMPERATURE*unit.kelvin, collision_rate=FRICTION/unit.picosecond,
                              timestep=stepPs*unit.picosecond, splitting="V R O R V")


class Runner:
    """One integrator at one step on one System: shadow work (kT) of `steps` steps from a state."""

    def __init__(self, kind, stepFs, system, platform, properties, seed):
        self.kind = kind
        stepPs = stepFs*1e-3
        if kind.startswith("rigid"):
            self.integrator = rigidIntegrator(kind, stepPs)
            self.integrator.setMeasureShadowWork(True)
            self.integrator.setRandomNumberSeed(seed)
        elif kind == "stock-middle":
            self.integrator = stockMiddle(stepPs)
            self.integrator.setRandomNumberSeed(seed)
        else:
            from openmmtools.integrators import LangevinIntegrator
            self.integrator = LangevinIntegrator(temperature=TEMPERATURE*unit.kelvin, collision_rate=FRICTION/unit.picosecond,
                                                 timestep=stepPs*unit.picosecond, splitting="V R O R V",
                                                 measure_shadow_work=True)
            self.integrator.setRandomNumberSeed(seed)
        self.context = openmm.Context(system, self.integrator, platform, properties)
        self.fired = False
        masses = np.array([system.getParticleMass(i).value_in_unit(unit.dalton) for i in range(system.getNumParticles())])
        self.masses = np.where(masses > 0, masses, np.inf)  # a virtual site gets no velocity
        self.halfStepBehind = kind != "openmmtools-vrorv"

    def kinetic(self):
        return self.context.getState(getEnergy=True).getKineticEnergy().value_in_unit(KJ)

    def kick(self, time):
        """The velocities kicked by the current forces for `time` ps, then projected (onto the
        constraints; for the rigid integrators onto rigid motion, where a kick of each particle by its
        force, projected, is the kick of each body's momentum and angular momentum by its force and
        torque); returns the kinetic energy after it."""
        state = self.context.getState(getVelocities=True, getForces=True)
        velocities = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
        forces = state.getForces(asNumpy=True).value_in_unit(KJ/unit.nanometer)
        self.context.setVelocities(velocities + time*forces/self.masses[:, None])
        self.context.applyVelocityConstraints(1e-10)
        return self.kinetic()

    def work(self, positions, box, steps, velocitySeed):
        """Set the state (positions, box, on-step velocities drawn at 300 K), take `steps` steps, and
        return the shadow work in kT of the protocol with on-step velocities at both ends (BAOAB's);
        None if the run failed.

        The on-step velocities v_0: for the rigid integrators, Context.setVelocitiesToTemperature()
        (the bodies' momenta drawn for their own, possibly raised, moments, then taken half a kick
        back), K(v_0) from getOnStepKineticEnergy(); otherwise Maxwell-Boltzmann draws of every
        particle's velocity, projected (Context.applyVelocityConstraints), and for stock-middle taken
        half a kick back here. For the LFMiddle integrators (the rigid ones and stock-middle), whose
        velocity variable u is half a step behind, u_0 is v_0 less half a kick; their step is BAOAB's
        with its closing half kick joined to the next opening one, so their shadow work over the
        protocol, W (with the kinetic energies of u), is BAOAB's less the ends:
        W_BAOAB = W + [K(u_T + kick) - K(u_T)] - [K(v_0) - K(u_0)]. Those end terms are of
        first order in the step (dt/2 F.v per degree of freedom): left in, their spread would swamp
        the divergence (their mean cancels between the two halves of a protocol, their variance does
        not)."""
        context, integrator = self.context, self.integrator
        if positions is not None:
            context.setPeriodicBoxVectors(*box)
            context.setPositions(positions)
        halfStep = 0.5*integrator.getStepSize().value_in_unit(unit.picosecond)
        ends = 0.0
        if self.kind.startswith("rigid"):
            # Drawn on step for the bodies' own (possibly raised) moments and taken half a kick back by
            # the integrator (Context.setVelocitiesToTemperature()); getOnStepKineticEnergy() kicks forward.
            context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, velocitySeed)
            ends -= integrator.getOnStepKineticEnergy().value_in_unit(KJ) - self.kinetic()
        else:
            rng = np.random.default_rng(velocitySeed)
            context.setVelocities(rng.standard_normal((len(self.masses), 3))*np.sqrt(KT/self.masses)[:, None])
            context.applyVelocityConstraints(1e-10)  # before the work is counted: the constraints' share is no step's
            if self.halfStepBehind:
                onStep = self.kinetic()
                ends -= onStep - self.kick(-halfStep)
        try:
            if self.kind.startswith("rigid"):
                integrator.resetShadowWork()
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", openmmrigid.AccuracyWarning)
                    integrator.step(steps)
                self.fired = self.fired or bool(integrator.getAccuracyWarning())
                work = integrator.getShadowWork().value_in_unit(KJ)
            elif self.kind == "stock-middle":
                for name in ("work", "heat", "started"):
                    integrator.setGlobalVariableByName(name, 0.0)
                integrator.step(steps)
                state = context.getState(getEnergy=True)
                # The last step's part: K + U now less K + U before it, less its heat.
                last = (state.getKineticEnergy() + state.getPotentialEnergy()).value_in_unit(KJ) - \
                    integrator.getGlobalVariableByName("start") - integrator.getGlobalVariableByName("heat")
                work = integrator.getGlobalVariableByName("work") + last
            else:
                integrator.reset_shadow_work()
                integrator.step(steps)
                work = integrator.get_shadow_work(dimensionless=True)*KT
            if self.kind.startswith("rigid"):
                ends += integrator.getOnStepKineticEnergy().value_in_unit(KJ) - self.kinetic()
            elif self.halfStepBehind:
                halfBehind = self.kinetic()
                ends += self.kick(halfStep) - halfBehind
        except openmm.OpenMMException:
            return None
        work = (work + ends)/KT
        return work if np.isfinite(work) else None


def equilibriumFrames(system, positions, platform, properties, count, spacingPs, equilibratePs):
    """Frames of an equilibrium run: positions and box vectors."""
    integrator = openmmrigid.RigidBodyLangevinIntegrator(TEMPERATURE, 5.0, 0.001)
    integrator.setRandomNumberSeed(2)
    integrator.setAccuracyCheck(False)
    context = openmm.Context(system, integrator, platform, properties)
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
    context.setVelocitiesToTemperature(TEMPERATURE, 2)
    integrator.step(int(round(equilibratePs/0.001)))
    frames = []
    for _ in range(count):
        integrator.step(int(round(spacingPs/0.001)))
        state = context.getState(getPositions=True)
        frames.append((state.getPositions(), state.getPeriodicBoxVectors()))
    return frames


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="216 waters, steps 2 6 10 fs, 3 frames, 0.2 ps protocols")
    parser.add_argument("--systems", nargs="+", default=None, choices=["water", "peptide"])
    parser.add_argument("--integrators", nargs="+", default=None,
                        choices=["rigid-exact", "rigid-nosquish", "rigid-raised", "stock-middle", "openmmtools-vrorv"])
    parser.add_argument("--floor", type=float, default=0.08, help="rigid-raised's minimum moment (amu nm^2; default 0.08)")
    parser.add_argument("--steps", nargs="+", type=float, default=None, help="steps in fs (default 1 2 4 6 8 10)")
    parser.add_argument("--samples", type=int, default=None, help="equilibrium frames (default 50)")
    parser.add_argument("--spacing", type=float, default=2.0, help="ps between frames (default 2)")
    parser.add_argument("--equilibrate", type=float, default=20.0, help="ps before the first frame (default 20)")
    parser.add_argument("--protocol", type=float, default=None, help="ps of each half of a protocol (default 2)")
    parser.add_argument("--molecules", type=int, default=None, help="waters (default 500; 216 with --quick)")
    parser.add_argument("--threads", type=int, default=1)
    parser.add_argument("--timing-repetitions", type=int, default=5)
    args = parser.parse_args()
    quick = args.quick
    systems = args.systems or (["water"] if quick else ["water", "peptide"])
    steps = args.steps or ([2.0, 6.0, 10.0] if quick else [1.0, 2.0, 4.0, 6.0, 8.0, 10.0])
    samples = args.samples or (3 if quick else 50)
    protocol = args.protocol or (0.2 if quick else 2.0)
    molecules = args.molecules or (216 if quick else 500)
    if quick:
        args.spacing, args.equilibrate = 0.5, 1.0
    FLOOR[0] = args.floor
    kinds = args.integrators or ["rigid-exact", "rigid-nosquish", "stock-middle", "openmmtools-vrorv"]
    if "openmmtools-vrorv" in kinds:
        try:
            import openmmtools.integrators  # noqa: F401
        except ImportError:
            say("openmmtools is not installed: openmmtools-vrorv left out")
            kinds = [kind for kind in kinds if kind != "openmmtools-vrorv"]
    platform = openmm.Platform.getPlatformByName("CPU")
    properties = {"Threads": str(args.threads)}
    document = benchmarking.ResultsDocument("sampling_error", "Configuration-space sampling error against step size",
                                            quick=quick, platform="CPU", threads=args.threads,
                                            about="Method: the docstring of `benchmarks/sampling_error.py`.")
    rows, csvRows = [], []
    for systemName in systems:
        topology, positions, system = makeSystem(systemName, molecules)
        stamp(f"{systemName}: {system.getNumParticles()} particles; equilibrium frames")
        frames = equilibriumFrames(system, positions, platform, properties, samples, args.spacing, args.equilibrate)
        figureData, results = {}, []
        for kind in kinds:
            for stepFs in steps:
                runner = Runner(kind, stepFs, system, platform, properties, seed=11)
                count = int(round(protocol/(stepFs*1e-3)))
                fromEquilibrium, fromResampled, failed = [], [], False
                for i, (framePositions, box) in enumerate(frames):
                    first = runner.work(framePositions, box, count, velocitySeed=100 + 2*i)
                    second = runner.work(None, None, count, velocitySeed=101 + 2*i) if first is not None else None
                    if first is None or second is None:
                        failed = True
                        break
                    fromEquilibrium.append(first)
                    fromResampled.append(second)
                if failed:
                    stamp(f"{systemName} {kind} {stepFs:g} fs: failed (unstable); larger steps not run")
                    results.append(dict(kind=kind, stepFs=stepFs))
                    break
                kl, error = configurationKL(fromEquilibrium, fromResampled)
                fired = ("yes" if runner.fired else "no") if kind.startswith("rigid") else ""
                stamp(f"{systemName} {kind} {stepFs:g} fs: KL {kl:.4g} +- {error:.2g} kT, check fired: {fired or '-'}")
                results.append(dict(kind=kind, stepFs=stepFs, kl=float(kl), error=float(error), fired=fired))
                del runner
        # The cost: at each step, every integrator that ran there, timed side by side (interleaved
        # blocks, medians), from the first frame with velocities at 300 K.
        nsDay = {}
        for stepFs in steps:
            kindsHere = [r["kind"] for r in results if r["stepFs"] == stepFs and "kl" in r]
            if not kindsHere:
                continue
            integrators, contexts = {}, []
            for kind in kindsHere:
                integrators[kind] = timedIntegrator(kind, stepFs)
                context = openmm.Context(system, integrators[kind], platform, properties)
                context.setPeriodicBoxVectors(*frames[0][1])
                context.setPositions(frames[0][0])
                context.setVelocitiesToTemperature(TEMPERATURE*unit.kelvin, 3)
                contexts.append(context)
            wall = benchmarking.timeInterleaved(integrators, max(10, int(round(0.2/(stepFs*1e-3)))), args.timing_repetitions)[0]
            for kind, seconds in wall.items():
                nsDay[(kind, stepFs)] = benchmarking.nsPerDay(stepFs, float(np.median(seconds)))
            stamp(f"{systemName} {stepFs:g} fs, ns/day side by side: " +
                  ", ".join(f"{kind} {nsDay[(kind, stepFs)]:.2f}" for kind in kindsHere))
            del integrators, contexts
        for r in results:
            if "kl" not in r:
                rows.append([systemName, r["kind"], f"{r['stepFs']:g}", "unstable", "", ""])
                continue
            speed = nsDay[(r["kind"], r["stepFs"])]
            rows.append([systemName, r["kind"], f"{r['stepFs']:g}", f"{r['kl']:.4g} +- {r['error']:.2g}", f"{speed:.2f}", r["fired"]])
            csvRows.append(dict(system=systemName, integrator=r["kind"], stepFs=r["stepFs"], kl=r["kl"], error=r["error"],
                                nsPerDay=float(speed), checkFired=r["fired"]))
            figureData.setdefault(r["kind"], []).append((speed, r["kl"], r["error"], r["stepFs"]))
        if figureData:
            plt = benchmarking.pyplot()
            figure, axes = plt.subplots(figsize=(6, 4))
            for kind, points in figureData.items():
                points = np.array(points)
                axes.errorbar(points[:, 0], np.maximum(points[:, 1], 1e-6), yerr=points[:, 2], marker="o", label=kind)
                for x, y, _, step in points:
                    axes.annotate(f"{step:g}", (x, max(y, 1e-6)), fontsize=7)
            axes.set_xlabel("ns/day (CPU)")
            axes.set_ylabel("configuration-space KL divergence (kT)")
            axes.set_yscale("log")
            axes.set_title(f"{systemName}: sampling error against speed (labels: step in fs)")
            axes.legend(fontsize=8)
            path = document.figurePath(f"sampling_error_{systemName}.png")
            benchmarking.saveFigure(figure, path)
            document.figure(path, f"{systemName}: KL divergence against ns/day")
    document.section("KL divergence and speed",
                     f"{molecules} waters; {samples} equilibrium frames per system, {protocol:g} ps per half protocol, friction {FRICTION:g}/ps, "
                     f"{TEMPERATURE:g} K; KL in kT +- one standard error.")
    document.table(["system", "integrator", "step (fs)", "KL (kT)", "ns/day", "accuracy check fired"], rows)
    if csvRows:
        benchmarking.writeCsv(benchmarking.RESULTS/"sampling_error"/("quick" if quick else "full")/"sampling_error.csv", csvRows)
    document.write()


if __name__ == "__main__":
    main()

"""Stability under stress: the scenarios and measurements of rigidtesting.stress (shared with test_stress.py)."""
import numpy as np, openmm
from harness import Study
from rigidtesting import stress

ENERGY, STABLE, RIGID, MOMENTUM, FREE, SPIN = 0.01, 0.05, 1e-12, 1e-10, 1e-12, 1e-12   # the criteria (the method)
IMPULSE, STOCK, RIGIDS = {"Reference": 1e-10, "CPU": 1e-6}, "Verlet+SETTLE", ("Exact", "NoSquish")

def failures(row, platform, energy=ENERGY, spin=None, crossings=None):   # the criteria (the method) a row misses
    if not row["finite"] or row["error"]:
        return [f"not finite ({row['error']})" if not row["finite"] else f"raised: {row['error']}"]
    limits = dict(energy=energy, rigidity=RIGID, momentum=MOMENTUM, impulse=IMPULSE[platform], angular=MOMENTUM, spin=spin)
    return ([f"{key} {row[key]:.2g} > {limit:g}" for key, limit in limits.items()
             if limit is not None and row.get(key) is not None and not row[key] <= limit]
            + ([f"only {row['crossings']} separatrix crossings"] if crossings and row["crossings"] < crossings else []))

def runRow(scenario, name, stepPs, ps, env, samples=None, impulse=False, **criteria):
    """One integrator's run of a scenario (stress.run, sampled every 5 steps, at least 200 times): its row and Run."""
    steps = max(1, round(ps/stepPs))
    integrator = scenario.integrator(stepPs, name) if name != STOCK else openmm.VerletIntegrator(stepPs)
    integrator.setConstraintTolerance(1e-10)
    run = stress.run(scenario, integrator, env.platformName, steps, max(1, steps//(samples or max(200, steps//5))),
                     True, env.properties)
    impulse = impulse and run.finite and not run.error and name != STOCK
    row = dict(scenario=scenario.name, integrator=name, step=1000*stepPs, ps=run.steps*stepPs, finite=run.finite,
               error=run.error, energy=run.max_energy_change()/run.kinetic0, drift=1000*run.drift()/run.dof,
               rigidity=run.rigidity, momentum=run.relative_momentum_change() if scenario.forcesSumToZero else None,
               impulse=stress.impulse_mismatch(run.context, scenario.masses, 50) if impulse else None,
               angular=run.relative_angular_change(), crossings=int(np.sum(run.crossings)), judged=name != STOCK)
    return dict(row, failures=failures(row, env.platformName, **criteria)), run

def spinAlone(env, seed):
    """d. A body spinning at 1e4 rad/ps, no forces: Exact against its exact free motion (stress.rigid_motion)."""
    scenario, rows = stress.spinning_body(omega=1e4, seed=seed), []
    exact = stress.rigid_motion(scenario.masses, scenario.positions, scenario.velocities, scenario.bodies, scenario.free)
    radius = np.max(np.linalg.norm(scenario.positions - scenario.masses@scenario.positions/scenario.masses.sum(), axis=1))
    for name, stepPs, steps in (("Exact", 0.002, 1000 if env.quick else 20000), ("NoSquish", 1e-5, 2000)):
        row, run = runRow(scenario, name, stepPs, steps*stepPs, env, 200)
        x, v = exact(run.steps*stepPs)
        row["spin"] = max(np.max(np.abs(stress.positions_of(run.context) - x))/radius,
                          np.max(np.abs(stress.velocities_of(run.context) - v))/np.max(np.linalg.norm(v, axis=1)))
        if name == "Exact":   # NoSquish approximates the free rotation (omega dt = 0.1 here): for information
            row["failures"] = failures(row, env.platformName, energy=FREE, spin=SPIN*1e4*run.steps*stepPs)
        rows.append(dict(row, note=f"off the exact free motion by {row['spin']:.1e} rad"))
    return rows

def runs(make, stepPs, ps, names=RIGIDS, impulse=False, crossings=(None, None), energy=ENERGY):
    """A scenario, make(quick, seed), run by each integrator; ps and crossings: (full, quick)."""
    def measure(env, seed):
        scenario = make(env.quick, seed)
        return [runRow(scenario, name, stepPs, ps[env.quick], env, impulse=impulse, crossings=crossings[env.quick],
                       energy=energy)[0] for name in names]
    return measure

def water(model, temperature=300.0, size=(2.5, 1.9), cutoff=(0.9, 0.8)):   # a, c: rigid water, PME; (full, quick)
    return lambda quick, seed: stress.water(model, size[quick], temperature, cutoff[quick], seed)

def bath(temperature, periodic):   # b, c: copies of each extreme shape among Lennard-Jones argon; isolated: spinning
    return lambda quick, seed: stress.bodies_in_bath(2 if quick else 6, 40 if quick else 150, temperature,
                                                     periodic=periodic, seed=seed, spin=0.0 if periodic else 1.0)

SCENARIOS = {
    "tip3p-7fs": runs(water("tip3p"), 0.007, (20.0, 1.0), (STOCK,) + RIGIDS, True, energy=STABLE),
    "tip4pew-7fs": runs(water("tip4pew"), 0.007, (20.0, 1.0), (STOCK,) + RIGIDS, True, energy=STABLE),
    "bath-2000K": runs(bath(2000.0, True), 0.001, (5.0, 1.0), crossings=(10, 2)),
    "isolated-2000K": runs(bath(2000.0, False), 0.001, (2.5, 1.0)),
    "bath-5000K": runs(bath(5000.0, True), 0.0005, (4.0, 1.0), crossings=(10, 2)),
    "water-5000K": runs(water("tip3p", 5000.0, (1.9, 1.7), (0.7, 0.7)), 0.0005, (4.0, 0.2), (STOCK,) + RIGIDS, True),
    "cluster-5000K": runs(lambda q, s: stress.hot_cluster(5000.0, s, (3, 3, 2) if q else (4, 4, 3)), 0.0005, (10.0, 1.0)),
    "spin-alone": spinAlone,
    "spin-in-bath": runs(lambda q, s: stress.spinning_body(1e4, 60 if q else 150, 2000.0, seed=s), 1e-5, (0.1, 0.02))}

def report(summary, page):
    failing = sum(bool(row["judged"] and row["failures"]) for row in summary)
    e = lambda value: "-" if value is None else f"{value:.0e}"   # noqa: E731
    page.text((f"**{failing} run(s) FAIL.** " if failing else "**All criteria met.** ") + "Drift: kJ/mol/ns per degree "
              "of freedom; rigidity: the largest change of a distance in a body; verdict '-': not judged.")
    page.table(["scenario", "integrator", "step (fs)", "ps", "max abs(E - E0) / KE0", "drift", "rigidity (nm)",
                "ΔP/P0", "ΔL/L0", "crossings", "verdict"],
               [[r["scenario"], r["integrator"], f"{r['step']:.3g}", f"{r['ps']:.3g}", f"{r['energy']:.1e}",
                 f"{r['drift']:+.2g}", e(r["rigidity"]), e(r["momentum"]) if r["momentum"] is not None else "PME" + (
                     f", impulse {e(r['impulse'])}" if r.get("impulse") is not None else ""), e(r["angular"]),
                 r["crossings"], ("-" if not r["judged"] else "FAIL: " + "; ".join(r["failures"]) if r["failures"]
                                  else "ok") + (f" ({r['note']})" if r.get("note") else "")] for r in summary])

STUDY = Study(
    "stress", "Stability under stress",
    "Every stability criterion is met: 500 waters of TIP3P and TIP4P-Ew run stable for 20 ps at 7 fs, bodies of "
    "extreme shapes in baths at 2000 and 5000 K stay rigid to 1e-15 nm with momentum conserved to 1e-13, and a body "
    "spinning at 1e4 rad/ps keeps its energy to 6e-13 with the exact rotor.", report,
    method="""Scenarios of `rigidtesting.stress`, NVE: (a) rigid TIP3P and TIP4P-Ew (~500 waters, PME, 300 K), 20 ps at
7 fs; (b) explicit bodies of extreme shapes (a rod whose moments span 1e6, tops with moments 1e-9 apart, linear CO2, a
bent triatomic) among Lennard-Jones argon at 2000 K, periodic and isolated; (c) the same, TIP3P and a cluster of every
body kind at 5000 K; (d) a body spinning at 1e4 rad/ps, alone and in a 2000 K bath. A rigid integrator's run fails if
not finite or if it raises; if max |E - E0| > 1 % of the initial kinetic energy KE0 (5 % in (a)); if a distance in a
body changes by over 1e-12 nm; if |P - P0| > 1e-10 |P0| where the forces sum to zero, or with PME the change of P over
50 steps misses the net force's impulse by 1e-10 (Reference) or 1e-6 (CPU) of the summed |F| dt; isolated, if
|L - L0| > 1e-10 |L0|; in a periodic bath, with under 10 separatrix crossings; spinning alone, if Exact misses its
energy by 1e-12 relative or its free motion by 1e-12 rad per radian turned. Stock Verlet + SETTLE: measured, not judged.""",
    caveats="""One run per scenario and integrator, one seed: at 7 fs one 20 ps run of water stayed within 5 % of KE0,
no guarantee for longer runs (drift and blow-up over steps: energy_drift). CPU platform (the criteria hold on Reference).""",
    grid={"scenario": list(SCENARIOS), "seed": [5]},
    quick={"scenario": [name for name in SCENARIOS if name not in ("tip4pew-7fs", "bath-2000K", "bath-5000K")], "seed": [5]},
    measure=lambda job, env: {"rows": SCENARIOS[job["scenario"]](env, job["seed"])},
    summarize=lambda results, env: [row for job in results for sample in job["samples"] for row in sample["rows"]])

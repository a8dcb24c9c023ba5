"""A solvated protein with hydrogen mass repartitioning in NVE: which step and splitting of RigidBodyIntegrator."""
import openmm.app as app
import rigidtesting, setups
from harness import Study
from studies.energy_drift import Trajectory, rigidStart

RUNS = [("stock", 4), ("stock", 6)] + [(method, step) for method in ("Verlet", "Omelyan2") for step in (4, 6, 8)]

def measure(job, env):
    """Every run from one start, interleaved: each advances 48 fs in turn, so that all see the same load."""
    built = (setups.dipeptideInWater(216, barostat=False) if env.quick   # HBonds, 3 amu: a small stand-in
             else setups.villin(hydrogenMass=3.0, constraints=getattr(app, job["constraints"])))
    state = rigidStart(built, f"hmr_schemes-{'quick' if env.quick else 'villin'}-{job['constraints']}-{job['seed']}", env,
                       0.2 if env.quick else 10.0, job["seed"])
    dof, runs = rigidtesting.degreesOfFreedom(built.system), {}
    for method, step in [run for run in RUNS if run[1] == 4 or not env.quick]:
        integrator = setups.makeIntegrator("stock-verlet" if method == "stock" else "rigid-verlet", step,
                                            splitting=method if method == "Omelyan2" else None)
        integrator.setConstraintTolerance(1e-10)
        runs[method, step] = Trajectory(built, integrator, state, env, step, 0.2*dof)  # blown up: 0.2 kJ/mol per dof
    for _ in range(round(1000*job["picoseconds"]/48)):
        for run in [run for run in runs.values() if run.failure is None]:
            run.advance(48//run.stepFs)
    return {"seed": job["seed"], "runs": [dict(method=m, step=s, **run.result(dof)) for (m, s), run in runs.items()]}

def summarize(results, env):   # every run, its fluctuation and ns/day also relative to stock at 4 fs from its start
    rows = []
    for result, sample in [(result, sample) for result in results for sample in result["samples"]]:
        stock = sample["runs"][0]   # stock at 4 fs
        rows += [dict(run, constraints=result["job"]["constraints"], seed=sample["seed"],
                      fluctuationRatio=run.get("fluctuation") and run["fluctuation"]/stock["fluctuation"],
                      speedRatio=run.get("nsPerDay") and run["nsPerDay"]/stock["nsPerDay"]) for run in sample["runs"]]
    return rows

def report(summary, page):
    for constraints in dict.fromkeys(row["constraints"] for row in summary):
        page.section(f"constraints={constraints}", "Drift in kJ/mol/ns per degree of freedom, fluctuation in kJ/mol; "
                     "ratios to stock at 4 fs from the same start.")
        page.table(["start", "method", "step", "drift", "fluctuation", "/ stock 4 fs", "ns/day", "/ stock 4 fs"],
                   [[r["seed"] + 1, r["method"], f"{r['step']:g} fs", r["failed"] or f"{r['drift']:+.3f}"] + [
                       "" if r.get(key) is None else f"{r[key]:.2f}" for key in ("fluctuation", "fluctuationRatio",
                                                                                "nsPerDay", "speedRatio")]
                    for r in summary if r["constraints"] == constraints])

STUDY = Study(
    "hmr_schemes", "A solvated protein with hydrogen mass repartitioning: which step and splitting",
    "In villin with HMR and HBonds, `RigidBodyIntegrator` (`Verlet`) at 4 fs matches stock's energy fluctuation at about "
    "its ns/day, `Omelyan2` at 4 fs fluctuates 4 to 5 times less at half the ns/day, and at 6 fs stock and `Verlet` both "
    "fail; with AllBonds, `Omelyan2` keeps a third of stock's 4 fs fluctuation up to 6 fs.", report,
    method="""Villin in TIP3P (`setups.villin`: amber14, PME 0.9 nm, rigid water, hydrogen mass 3 amu, `constraints=HBonds`
or `AllBonds`), equilibrated once per start, made rigid to 1e-10; from it every method runs NVE in its own Context, all
interleaved in 48 fs pieces in one process: stock `VerletIntegrator` (SETTLE, CCMA), `RigidBodyIntegrator` (rigid waters,
the protein free atoms) with the `Verlet` or `Omelyan2` splitting. Drift per degree of freedom and fluctuation as in
energy_drift; ns/day of the step calls. A run stops at an exception, NaN or |E - E0| above 0.2 kJ/mol per dof.""",
    caveats="""One protein, one hydrogen mass, two starts of 10 ps. With HMR the step is limited by the protein's
heavy-atom bonds (C=O, C-N: periods near 20 fs), not by the water (alone: energy_drift). NVE, CPU platform.""",
    grid={"constraints": ["HBonds", "AllBonds"], "picoseconds": [10.0], "seed": [0, 1]},
    quick={"constraints": ["HBonds"], "picoseconds": [0.24], "seed": [0]},
    measure=measure, summarize=summarize)

import numpy as np
import openmm, openmm.unit as unit
from harness import Study, Unstable
import systems

def measure(job, env):
    built = systems.water("tip3p", 216)
    state = systems.start("smoke-tip3p-216", built, env.platform, env.properties, picoseconds=0.1)
    integ = systems.makeIntegrator(job["integrator"], job["step"], job["seed"])
    ctx = systems.context(built, integ, state, env.platform, env.properties, job["seed"])
    ctx.setVelocitiesToTemperature(300, job["seed"] + 1)
    integ.step(50)
    if job["step"] > 5: raise Unstable("too large")
    s = ctx.getState(getEnergy=True)
    return {"U": s.getPotentialEnergy().value_in_unit(unit.kilojoule_per_mole)}

def summarize(results, env):
    return [dict(r["job"], U=float(np.mean([s["U"] for s in r["samples"]])) if r["samples"] else None, failed=r["failed"], blocked=r["blocked"]) for r in results]

def report(summary, page):
    page.table(["integrator", "step", "U", "failed"], [[r["integrator"], r["step"], r["U"], r["failed"] or ("blocked" if r["blocked"] else "")] for r in summary])

STUDY = Study("_smoke", "Smoke", "It runs.", report, grid={"integrator": ["stock-middle"], "step": [2], "seed": [0]},
              quick={"integrator": ["stock-middle", "rigid-langevin"], "step": [2, 6, 8], "seed": [0, 1]}, measure=measure, summarize=summarize)

"""The ensembles openmmtools gives the rigid-body integrators, side by side with stock (issue 26)."""

import openmm
from openmm import unit

import openmmrigid
import setups
from harness import Study, blockMean
from studies.thermostats import NVT, build, pm

STEP, BATH, HOT = 2*unit.femtosecond, setups.TEMPERATURE*unit.kelvin, 330*unit.kelvin
ANDERSEN = {"found": "RigidBodyIntegrator, bodies found from the constraints",
            "explicit": "RigidBodyIntegrator, explicit bodies keeping their constraints",
            "lean": "RigidBodyIntegrator, explicit bodies without constraints (removeIntraBodyInteractions)",
            "verlet": "stock VerletIntegrator + SETTLE"}
THERMOSTATED = {"bussi": "RigidBodyBussiIntegrator (0.1 ps)", "middle": "stock LangevinMiddleIntegrator (1/ps)",
                "compound": "CompoundIntegrator[RigidBodyLangevinIntegrator (1/ps), Verlet]",
                "compound-stock": "stock CompoundIntegrator[LangevinMiddleIntegrator (1/ps), Verlet]"}


def temperature(advance, kinetic, dof, env):
    """Mean and block error of 2K/(f k_B), every 10 steps for 40 ps (quick: 0.4) after 2 ps (0.2) discarded."""
    advance(100 if env.quick else 1000)
    return list(blockMean([2*(advance(10), kinetic())[1].value_in_unit(setups.KJ)/(dof*setups.BOLTZMANN)
                           for _ in range(20 if env.quick else 2000)]))


def measure(job, env):
    from openmmtools import cache, mcmc, states
    from openmmrigid.openmmtools import RigidBussiDynamicsMove, RigidLangevinDynamicsMove
    case, (built, state) = job["case"], build(NVT, env)
    system, bodies, dof = built.system, built.waters.tolist(), 6*len(built.waters)
    hot = states.ThermodynamicState(system, HOT)
    if case == "moves":                  # the three through one ContextCache (it must tell their integrators apart)
        contexts, result = cache.ContextCache(platform=env.platform, platform_properties=env.properties), {}
        for name, move in (("RigidLangevinDynamicsMove (1/ps)", RigidLangevinDynamicsMove(n_steps=10)),
                           ("RigidBussiDynamicsMove (0.1 ps)", RigidBussiDynamicsMove(n_steps=10)),
                           ("openmmtools LangevinDynamicsMove (1/ps)",
                            mcmc.LangevinDynamicsMove(timestep=STEP, n_steps=10, collision_rate=1/unit.picosecond))):
            sampler = states.SamplerState(state.getPositions(asNumpy=True), velocities=state.getVelocities(asNumpy=True),
                                          box_vectors=state.getPeriodicBoxVectors())
            result[name] = temperature(lambda n: [move.apply(hot, sampler, context_cache=contexts) for _ in range(n//10)],
                                       lambda: sampler.kinetic_energy, dof, env)
        return result
    if case in ANDERSEN:                 # openmmtools keeps the System's AndersenThermostat for these (or adds its own)
        system = openmm.XmlSerializer.clone(system)
        system.addForce(openmm.AndersenThermostat(BATH, 5/unit.picosecond))
        system = openmmrigid.removeIntraBodyInteractions(system, bodies) if case == "lean" else system
        integrator = inner = (openmm.VerletIntegrator(STEP) if case == "verlet" else
                              openmmrigid.RigidBodyIntegrator(STEP, *[bodies]*(case != "found")))
    elif case == "bussi":
        integrator = inner = openmmrigid.RigidBodyBussiIntegrator(BATH, 0.1*unit.picosecond, STEP)
    else:
        langevin = openmmrigid.RigidBodyLangevinIntegrator if case == "compound" else openmm.LangevinMiddleIntegrator
        integrator = inner = langevin(BATH, 1/unit.picosecond, STEP)
        if case.startswith("compound"):
            integrator = openmm.CompoundIntegrator()
            integrator.addIntegrator(inner)
            integrator.addIntegrator(openmm.VerletIntegrator(STEP))
    try:
        context = states.ThermodynamicState(system, BATH).create_context(integrator, env.platform, env.properties)
    except openmm.OpenMMException as error:
        return {"refused": str(error).splitlines()[0][:300]}
    result = {}
    if case in THERMOSTATED:             # created at 300 K, applied at 330 K; its temperature from our own reference
        hot.apply_to_context(context)
        result = {"andersens": sum(isinstance(f, openmm.AndersenThermostat) for f in context.getSystem().getForces()),
                  "integratorT": inner.getTemperature().value_in_unit(unit.kelvin)}
    context.setState(state)
    return dict(result, T=temperature(integrator.step, lambda: context.getState(getEnergy=True).getKineticEnergy(), dof, env))


def summarize(results, env):
    return {r["job"]["case"]: r["samples"][0] if r["samples"] else {"refused": f"failed: {r['failed']}"} for r in results}


def report(summary, page):
    page.section("AndersenThermostat with rigid bodies", "openmmtools keeps the System's AndersenThermostat (here 5/ps) for "
                 "integrators it sees as unthermostated. Temperature read (K) for a 300 K bath, ± one standard error (σ).")
    page.table(["integrator", "temperature read (K)"], [[name, pm(summary[case]["T"], 1, 300) if "T" in summary[case] else
                f"refused when the Context is made: {summary[case]['refused']}"] for case, name in ANDERSEN.items()])
    page.section("Thermostated integrators through ThermodynamicState", "Created with `create_context` at 300 K, then "
                 "`apply_to_context` at 330 K: the AndersenThermostats openmmtools added, the integrator's temperature, "
                 "and the temperature the run reads (K).")
    page.table(["integrator", "Andersen added", "integrator's T (K)", "temperature read (K)"],
               [[name, summary[case]["andersens"], f"{summary[case]['integratorT']:.0f}", pm(summary[case]["T"], 1, 330)]
                for case, name in THERMOSTATED.items()])
    page.section("The moves at 330 K", "Through one ContextCache; temperature read (K) for a 330 K state.")
    page.table(["move", "temperature read (K)"], [[name, pm(value, 1, 330)] for name, value in summary["moves"].items()])

STUDY = Study(
    "openmmtools_ensembles", "The ensembles openmmtools gives the rigid-body integrators",
    "openmmtools drives the rigid-body integrators as it drives stock's: its AndersenThermostat holds bodies found from "
    "constraints at the bath's temperature and refuses explicit bodies without constraints, and the thermostated "
    "integrators and both rigid moves follow a state moved to 330 K.",
    report,
    method="""
Each case set up as an openmmtools user would (`ThermodynamicState.create_context`, `apply_to_context`, `ContextCache`, MCMC
moves) on the 102 TIP3P waters of [thermostats](thermostats.md), 2 fs steps: 2 ps discarded, then the kinetic energy every 10
steps for 40 ps over 6 degrees of freedom per water, ± the larger standard error of 5 or 10 block means. The integrator's
temperature is read from our own reference to it (`Context.getIntegrator()` gives a plain `openmm.Integrator`).
""",
    caveats="""
One run per case, 40 ps of a small box: mean temperatures, not the distribution of the kinetic energy nor configurational
sampling; replica exchange and alchemy are not exercised. Explicit bodies set from positions that miss their constraints
are tests/python/test_andersen_and_internal_constraints.py's.
""",
    grid={"case": [*ANDERSEN, *THERMOSTATED, "moves"], "seed": [0]},
    quick={"case": [*ANDERSEN, *THERMOSTATED, "moves"], "seed": [0]}, measure=measure, summarize=summarize)

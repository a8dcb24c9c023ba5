"""What openmmtools users meet without openmmtools itself: the AndersenThermostat it adds to the
System of an unthermostated integrator, and explicit bodies that keep internal constraints set from
ordinary positions.

- bodies found from constraints and explicit bodies that keep their constraints read the Andersen
  bath temperature, as stock Verlet + constraints does; an explicit body without its constraints
  (which the thermostat would redraw atom by atom, reading 11 % cold) is refused when the Context is made,
  as are raised moments of inertia, the message naming the integrators that thermostat instead
  (RigidBodyBussiIntegrator, RigidBodyLangevinIntegrator) and no method the API no longer has;
- explicit bodies that keep their constraints take their shape from the positions with the
  constraints applied (SHAKE), close to where stock's applyConstraints puts them; positions SHAKE
  cannot bring onto a constraint are a clear error; getNumBodies() answers before a Context is made
  and before positions are set.
"""

import numpy as np
import openmm
import openmm.unit as unit
import pytest

import openmmrigid

REFERENCE = openmm.Platform.getPlatformByName("Reference")
OH_DISTANCE = 0.09572  # TIP3P, nm


def water_gas(count, keep_constraints=True):
    """count TIP3P waters on a 0.5 nm grid with no forces but an AndersenThermostat at 300 K, 50/ps,
    so that the kinetic energy comes from the thermostat alone: (system, positions, bodies)."""
    system = openmm.System()
    positions, bodies = [], []
    side = int(np.ceil(count ** (1 / 3)))
    hydrogen = OH_DISTANCE * np.array([[np.sin(0.9119), np.cos(0.9119), 0.0], [-np.sin(0.9119), np.cos(0.9119), 0.0]])
    for n in range(count):
        origin = 0.5 * np.array([n % side, (n // side) % side, n // side**2])
        first = system.getNumParticles()
        for mass in (15.999, 1.008, 1.008):
            system.addParticle(mass)
        positions += [origin, origin + hydrogen[0], origin + hydrogen[1]]
        bodies.append([first, first + 1, first + 2])
        if keep_constraints:
            system.addConstraint(first, first + 1, OH_DISTANCE)
            system.addConstraint(first, first + 2, OH_DISTANCE)
            system.addConstraint(first + 1, first + 2, float(np.linalg.norm(hydrogen[0] - hydrogen[1])))
    system.addForce(openmm.AndersenThermostat(300.0, 50.0))
    return system, np.array(positions), bodies


def mean_temperature(context, integrator, dof, steps=3000, every=10, warmup=300):
    context.setVelocitiesToTemperature(300.0, 5)
    integrator.step(warmup)
    samples = []
    for _ in range(steps // every):
        integrator.step(every)
        kinetic = context.getState(getEnergy=True).getKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
        samples.append(2.0 * kinetic / (dof * unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole / unit.kelvin)))
    return float(np.mean(samples))


def test_andersen_thermostat_thermalizes_whole_bodies():
    """100 waters, no forces, AndersenThermostat at 300 K and 50/ps (a tenth of the molecules redrawn
    per 2 fs step): bodies found from the constraints, explicit bodies that keep their constraints,
    and stock Verlet + constraints read the bath. Each mean over 300 samples of 600 degrees of
    freedom has a standard error of about 0.6 % (single sample 5.8 %, 10 steps apart correlated by
    0.37); 4 % is over 6 of them, while a body redrawn atom by atom reads 11 % cold."""
    system, positions, bodies = water_gas(100)
    dof = 6 * len(bodies)
    cases = {"constraint bodies": openmmrigid.RigidBodyIntegrator(0.002),
             "explicit bodies with constraints": openmmrigid.RigidBodyIntegrator(0.002, bodies),
             "stock Verlet + constraints": openmm.VerletIntegrator(0.002)}
    measured = {}
    for name, integrator in cases.items():
        integrator.setConstraintTolerance(1e-8)
        context = openmm.Context(system, integrator, REFERENCE)
        context.setPositions(positions)
        measured[name] = mean_temperature(context, integrator, dof)
    for name, temperature in measured.items():
        assert abs(temperature / 300.0 - 1.0) < 0.04, f"{name}: {temperature:.1f} K for a 300 K bath ({measured})"


def test_andersen_thermostat_refused_for_bodies_it_would_split():
    """Explicit bodies without their constraints are several Andersen groups each: refused when the
    Context is made, with a message that names the body and the remedy."""
    system, positions, bodies = water_gas(8, keep_constraints=False)
    for integrator in (openmmrigid.RigidBodyIntegrator(0.002, bodies),
                       openmmrigid.RigidBodyBussiIntegrator(300.0, 0.1, 0.002, bodies),
                       openmmrigid.RigidBodyLangevinIntegrator(300.0, 1.0, 0.002, bodies)):
        name = type(integrator).__name__
        with pytest.raises(openmm.OpenMMException, match=f"^{name}: .*AndersenThermostat") as error:
            openmm.Context(system, integrator, REFERENCE)
        message = str(error.value)
        assert "body 0" in message and "particles 0 and 1" in message, message
        assert_names_the_remedy(message)


def assert_names_the_remedy(message):
    """The remedy is a class of the lean API, not a method it removed (issue 41)."""
    assert "RigidBodyBussiIntegrator" in message and "RigidBodyLangevinIntegrator" in message, message
    assert "setThermostat" not in message, message


def test_andersen_thermostat_with_raised_moments_is_refused():
    """An AndersenThermostat redraws each water for its particles' masses, whose rotation the
    projection keeps: with raised moments it heated the rotation by I'/I (floor 0.04: T_rot 974 K for
    a 300 K bath, silently). Refused when the Context is made, for bodies found from the constraints
    and explicit ones, naming the remedy; without raised moments the same Context runs."""
    system, positions, bodies = water_gas(8)
    for integrator in (openmmrigid.RigidBodyIntegrator(0.002), openmmrigid.RigidBodyIntegrator(0.002, bodies),
                       openmmrigid.RigidBodyBussiIntegrator(300.0, 0.1, 0.002),
                       openmmrigid.RigidBodyLangevinIntegrator(300.0, 1.0, 0.002)):
        integrator.setMinimumMomentOfInertia(0.04)
        name = type(integrator).__name__
        with pytest.raises(openmm.OpenMMException, match=f"^{name}: .*AndersenThermostat") as error:
            openmm.Context(system, integrator, REFERENCE)
        message = str(error.value)
        assert "raised moments" in message and "own" in message, message
        assert_names_the_remedy(message)
    integrator = openmmrigid.RigidBodyIntegrator(0.002)
    context = openmm.Context(system, integrator, REFERENCE)
    context.setPositions(positions)
    integrator.step(2)


# ------------------------------------------------------------------------------------------------
# Explicit bodies with internal constraints
# ------------------------------------------------------------------------------------------------

def test_explicit_bodies_take_their_shape_with_the_constraints_applied():
    """Waters as explicit bodies that keep their constraints, from positions whose O-H bonds are 2.5 %
    long (as a test system's positions can be): the Context takes them, the bodies' shapes satisfy
    the constraints (to 1e-9 relative), and the positions land within 1e-3 nm of those stock's
    applyConstraints gives; getNumBodies() answers before a Context is made and before positions are set."""
    system, positions, bodies = water_gas(8)
    system.removeForce(0)
    stretched = positions.copy()
    for body in bodies:
        for h in body[1:]:
            stretched[h] = positions[body[0]] + 1.025 * (positions[h] - positions[body[0]])
    integrator = openmmrigid.RigidBodyIntegrator(0.002, bodies)
    assert integrator.getNumBodies() == len(bodies)
    context = openmm.Context(system, integrator, REFERENCE)
    assert integrator.getNumBodies() == len(bodies)
    context.setPositions(stretched)
    x = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    for c in range(system.getNumConstraints()):
        i, j, distance = system.getConstraintParameters(c)
        distance = distance.value_in_unit(unit.nanometer)
        assert abs(np.linalg.norm(x[i] - x[j]) / distance - 1.0) < 1e-9
    stock = openmm.Context(system, openmm.VerletIntegrator(0.002), REFERENCE)
    stock.setPositions(stretched)
    stock.applyConstraints(1e-10)
    expected = stock.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    assert np.max(np.abs(x - expected)) < 1e-3
    integrator.step(5)


def test_constraints_that_cannot_be_applied_are_a_clear_error():
    """Two constrained particles of a body at one point: SHAKE has no direction to move them along,
    and setting the positions says which body and constraint, and what to do."""
    system, positions, bodies = water_gas(2)
    system.removeForce(0)
    positions[4] = positions[3]
    integrator = openmmrigid.RigidBodyIntegrator(0.002, bodies)
    context = openmm.Context(system, integrator, REFERENCE)
    with pytest.raises(openmm.OpenMMException, match="the constraints inside body 1 cannot be applied.*set positions closer"):
        context.setPositions(positions)
        integrator.step(1)

"""RigidStateDataReporter's translational and rotational kinetic energy and temperature columns.

The system: the isolated cluster of systems.cluster() (explicit bodies of every kind: asymmetric,
symmetric and spherical tops, linear molecules, single particles) with two free atoms joined by a
constraint, and a CMMotionRemover. Each reported value is compared with one computed here from the
State's positions, velocities and the masses (centre-of-mass velocities; rotation from the
velocities relative to the centre of mass, which are rigid motion on every step), and degrees of
freedom counted here from the bodies' geometry and the System.
"""

import csv
import io

import numpy as np
import openmm
import pytest
from openmm import app, unit

import openmmrigid
import systems

GAS_CONSTANT = unit.MOLAR_GAS_CONSTANT_R.value_in_unit(unit.kilojoule_per_mole/unit.kelvin)
COLUMNS = ["Translational Kinetic Energy (kJ/mole)", "Rotational Kinetic Energy (kJ/mole)",
           "Translational Temperature (K)", "Rotational Temperature (K)"]


def clusterSimulation(integrator=None, interval=5):
    cluster = systems.cluster(seed=8)
    system = cluster.system
    first, second = cluster.free
    system.addConstraint(first, second, float(np.linalg.norm(cluster.positions[first] - cluster.positions[second])))
    system.addForce(openmm.CMMotionRemover(3))
    topology = app.Topology()
    residue = topology.addResidue("X", topology.addChain())
    for _ in range(system.getNumParticles()):
        topology.addAtom("X", None, residue)
    if integrator is None:
        integrator = openmmrigid.RigidBodyIntegrator(0.001, cluster.bodies)
    simulation = app.Simulation(topology, system, integrator, openmm.Platform.getPlatformByName("Reference"))
    simulation.context.setPositions(cluster.positions)
    simulation.context.setVelocities(cluster.velocities)
    return simulation, cluster


def independentValues(state, cluster):
    """Translational and rotational kinetic energies (kJ/mol) and their degrees of freedom, from scratch."""
    x = state.getPositions(asNumpy=True).value_in_unit(unit.nanometer)
    v = state.getVelocities(asNumpy=True).value_in_unit(unit.nanometer/unit.picosecond)
    m = cluster.masses
    translational = rotational = 0.0
    rotationalDof = 0
    for body in cluster.bodies:
        mass = m[body].sum()
        velocity = m[body] @ v[body]/mass
        translational += 0.5*mass*velocity @ velocity
        rotational += 0.5*np.sum(m[body]*np.sum((v[body] - velocity)**2, axis=1))
        relative = x[body] - m[body] @ x[body]/mass
        rank = np.linalg.matrix_rank(relative, tol=1e-6) if len(body) > 1 else 0
        rotationalDof += {0: 0, 1: 2}.get(rank, 3)  # a point, a line, or a body in 2 or 3 dimensions
    translational += 0.5*np.sum(m[cluster.free]*np.sum(v[cluster.free]**2, axis=1))
    constraintsAmongFree = 1
    translationalDof = 3*len(cluster.bodies) + 3*len(cluster.free) - constraintsAmongFree - 3
    return translational, rotational, translationalDof, rotationalDof


def readCsv(text):
    lines = text.splitlines()
    assert lines[0].startswith('#"')
    header = next(csv.reader([lines[0][1:]]))
    rows = [[float(value) for value in row] for row in csv.reader(lines[1:])]
    return header, rows


def test_columns_match_an_independent_computation():
    simulation, cluster = clusterSimulation()
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(
        output, 5, step=True, kineticEnergy=True, temperature=True, volume=False, speed=False,
        translationalKineticEnergy=True, rotationalKineticEnergy=True, translationalTemperature=True,
        rotationalTemperature=True))
    expected = []
    for _ in range(4):
        simulation.step(5)
        state = simulation.context.getState(getPositions=True, getVelocities=True, getEnergy=True)
        expected.append(independentValues(state, cluster) + (state.getKineticEnergy().value_in_unit(unit.kilojoule_per_mole),))
    header, rows = readCsv(output.getvalue())
    assert header == ["Step", "Kinetic Energy (kJ/mole)", "Temperature (K)"] + COLUMNS
    kinds = {simulation.integrator.getBodyKind(b) for b in range(simulation.integrator.getNumBodies())}
    assert {"point", "linear", "asymmetric", "symmetric", "spherical"} <= kinds
    for row, (translational, rotational, translationalDof, rotationalDof, kinetic) in zip(rows, expected):
        step, reportedKinetic, temperature, reportedTranslational, reportedRotational, tTrans, tRot = row
        assert reportedTranslational == pytest.approx(translational, rel=1e-9)
        assert reportedRotational == pytest.approx(rotational, rel=1e-9)
        assert tTrans == pytest.approx(2*translational/(translationalDof*GAS_CONSTANT), rel=1e-9)
        assert tRot == pytest.approx(2*rotational/(rotationalDof*GAS_CONSTANT), rel=1e-9)
        # The two parts make up the whole: energy, and temperature weighted by degrees of freedom.
        assert reportedTranslational + reportedRotational == pytest.approx(kinetic, rel=1e-9)
        assert (translationalDof*tTrans + rotationalDof*tRot)/(translationalDof + rotationalDof) == \
            pytest.approx(temperature, rel=1e-9)
    assert [row[0] for row in rows] == [5, 10, 15, 20]


def test_columns_go_before_volume_and_speed_and_work_with_langevin():
    integrator = openmmrigid.RigidBodyLangevinIntegrator(300*unit.kelvin, 5/unit.picosecond, 0.001,
                                                         systems.cluster(seed=8).bodies)
    simulation, cluster = clusterSimulation(integrator)
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(
        output, 4, time=True, rotationalTemperature=True, translationalKineticEnergy=True, elapsedTime=True,
        separator="\t"))
    simulation.step(8)
    lines = output.getvalue().splitlines()
    assert lines[0] == '#"Time (ps)"\t"Translational Kinetic Energy (kJ/mole)"\t"Rotational Temperature (K)"\t' \
                       '"Elapsed Time (s)"'
    values = [float(v) for v in lines[-1].split("\t")]
    assert values[1] == pytest.approx(integrator.getTranslationalKineticEnergy().value_in_unit(unit.kilojoule_per_mole),
                                      rel=1e-12)
    rotationalDof = independentValues(simulation.context.getState(getPositions=True, getVelocities=True), cluster)[3]
    assert values[2] == pytest.approx(2*integrator.getRotationalKineticEnergy().value_in_unit(unit.kilojoule_per_mole)
                                      /(rotationalDof*GAS_CONSTANT), rel=1e-12)


def test_without_the_new_columns_it_is_a_state_data_reporter():
    simulation, _ = clusterSimulation()
    rigid, stock = io.StringIO(), io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(rigid, 5, step=True, potentialEnergy=True,
                                                                   temperature=True))
    simulation.reporters.append(app.StateDataReporter(stock, 5, step=True, potentialEnergy=True, temperature=True))
    simulation.step(10)
    assert rigid.getvalue() == stock.getvalue()


def test_rotational_temperature_is_nan_without_rotation():
    system = openmm.System()
    for _ in range(3):
        system.addParticle(1.0)
    topology = app.Topology()
    residue = topology.addResidue("X", topology.addChain())
    for _ in range(3):
        topology.addAtom("X", None, residue)
    integrator = openmmrigid.RigidBodyIntegrator(0.001, [[0]])
    simulation = app.Simulation(topology, system, integrator, openmm.Platform.getPlatformByName("Reference"))
    simulation.context.setPositions(np.eye(3))
    simulation.context.setVelocities(np.ones((3, 3)))
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(output, 1, rotationalTemperature=True,
                                                                   translationalTemperature=True))
    simulation.step(1)
    translational, rotational = (float(v) for v in output.getvalue().splitlines()[1].split(","))
    assert np.isnan(rotational)
    assert translational == pytest.approx(2*(3*0.5*3.0)/(9*GAS_CONSTANT), rel=1e-12)


def test_the_columns_need_a_rigid_body_integrator():
    simulation, _ = clusterSimulation(openmm.VerletIntegrator(0.001))
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(io.StringIO(), 1, rotationalKineticEnergy=True))
    with pytest.raises(ValueError, match="rotationalKineticEnergy need a RigidBodyIntegrator"):
        simulation.step(1)


def test_shadow_work_and_heat_columns():
    """The columns are the integrator's sums (which test_shadow_work.py checks) at the report."""
    integrator = openmmrigid.RigidBodyLangevinIntegrator(300, 5, 0.002, systems.cluster(seed=8).bodies)
    integrator.setMeasureShadowWork(True)
    integrator.setMeasureHeat(True)
    simulation, _ = clusterSimulation(integrator)
    output = io.StringIO()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(output, 5, step=True, totalEnergy=True,
                                                                   shadowWork=True, heat=True))
    simulation.step(20)
    header, rows = readCsv(output.getvalue())
    assert header[-2:] == ["Shadow Work (kJ/mole)", "Heat (kJ/mole)"]
    assert rows[-1][2] == integrator.getShadowWork().value_in_unit(unit.kilojoule_per_mole)
    assert rows[-1][3] == integrator.getHeat().value_in_unit(unit.kilojoule_per_mole)
    assert len(rows) == 4 and rows[0][3] != 0.0


def test_shadow_work_column_needs_the_measurement():
    simulation, _ = clusterSimulation()
    simulation.reporters.append(openmmrigid.RigidStateDataReporter(io.StringIO(), 1, shadowWork=True))
    with pytest.raises(ValueError, match=r"setMeasureShadowWork\(True\)"):
        simulation.step(1)

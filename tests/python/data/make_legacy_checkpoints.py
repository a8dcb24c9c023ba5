"""Writes the legacy checkpoints that test_state_coherence.py loads (run: python make_legacy_checkpoints.py PREFIX).

The files in this folder were written by this script, with OpenMM 8.6.1, numpy 2.4 and the Reference
platform: legacy_* (format 0, no header) with openmmrigid built from commit f49f08c, v1_* (format 1,
whose RigidBodyLangevinIntegrator velocities are on-step) from commit 504cec4. They must keep loading:
the test builds the same System and integrator with the functions below, loads each checkpoint into a
fresh Context, takes STEPS_AFTER steps and compares the positions with the saved ones.

The system: four TIP3P waters in a 1.2 nm periodic box (NonbondedForce, CutoffPeriodic, 0.5 nm), with
their bodies found from SETTLE-like constraints ("constraints") or given explicitly with no
constraints ("explicit"). For each body source, three integrators: RigidBodyIntegrator without
thermostat ("plain"), with its thermostat at 300 K, 0.1 ps ("thermostat": RigidBodyBussiIntegrator
since it was a class; the commits above wrote it with RigidBodyIntegrator.setThermostat()), and
RigidBodyLangevinIntegrator(300 K, 5/ps) ("langevin"; in format 1 also "langevintrap", with every
particle in a harmonic trap about the box centre). Each run: positions and velocities set from
fixed numbers, STEPS_BEFORE steps, checkpoint to legacy_<kind>_<bodies>.chk, STEPS_AFTER more steps,
positions (nm) to legacy_<kind>_<bodies>.npy (PREFIX_<kind>_<bodies> for another prefix).
"""

import pathlib

import numpy as np
import openmm
from openmm import unit

import openmmrigid

KINDS = ["plain", "thermostat", "langevin"]
# Only in format 1 (v1_*): Langevin in a harmonic trap, whose forces make on-step and half-step
# velocities differ (the four waters of the others are beyond each other's cutoff: no force at all).
V1_KINDS = KINDS + ["langevintrap"]
BODY_SOURCES = ["constraints", "explicit"]
STEPS_BEFORE = 10
STEPS_AFTER = 5
STEP_SIZE = 0.002  # ps
SEED = 1234
EDGE = 1.2  # nm
OH, HH = 0.09572, 0.15139  # TIP3P geometry, nm
HERE = pathlib.Path(__file__).resolve().parent


def water_positions():
    """Four waters at fixed centres, each turned by its own fixed rotation (numpy's PCG64 stream,
    which is stable across numpy versions)."""
    rng = np.random.default_rng(SEED)
    half = np.sqrt(OH**2 - (HH / 2)**2)
    shape = np.array([[0.0, 0.0, 0.0], [HH / 2, half, 0.0], [-HH / 2, half, 0.0]])
    centres = np.array([[0.3, 0.3, 0.3], [0.9, 0.9, 0.3], [0.9, 0.3, 0.9], [0.3, 0.9, 0.9]])
    positions = []
    for centre in centres:
        rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        positions.extend(shape @ rotation.T + centre)
    velocities = rng.normal(scale=0.5, size=(len(positions), 3))
    return np.array(positions), velocities


def bodies():
    return [[3 * k, 3 * k + 1, 3 * k + 2] for k in range(4)]


def legacy_system(bodySource, kind="plain"):
    system = openmm.System()
    system.setDefaultPeriodicBoxVectors(openmm.Vec3(EDGE, 0, 0), openmm.Vec3(0, EDGE, 0), openmm.Vec3(0, 0, EDGE))
    nonbonded = openmm.NonbondedForce()
    nonbonded.setNonbondedMethod(openmm.NonbondedForce.CutoffPeriodic)
    nonbonded.setCutoffDistance(0.5)
    for o, h1, h2 in bodies():
        system.addParticle(15.9994)
        system.addParticle(1.008)
        system.addParticle(1.008)
        nonbonded.addParticle(-0.834, 0.315061, 0.636386)
        nonbonded.addParticle(0.417, 1.0, 0.0)
        nonbonded.addParticle(0.417, 1.0, 0.0)
        for i, j in ((o, h1), (o, h2), (h1, h2)):
            nonbonded.addException(i, j, 0.0, 1.0, 0.0)
        if bodySource == "constraints":
            system.addConstraint(o, h1, OH)
            system.addConstraint(o, h2, OH)
            system.addConstraint(h1, h2, HH)
    system.addForce(nonbonded)
    if kind == "langevintrap":
        trap = openmm.CustomExternalForce("500*((x-0.6)^2 + (y-0.6)^2 + (z-0.6)^2)")
        for i in range(system.getNumParticles()):
            trap.addParticle(i, [])
        system.addForce(trap)
    return system


def legacy_integrator(kind, bodySource):
    explicit = bodies() if bodySource == "explicit" else None
    if kind.startswith("langevin"):
        integrator = (openmmrigid.RigidBodyLangevinIntegrator(300.0, 5.0, STEP_SIZE, explicit) if explicit
                      else openmmrigid.RigidBodyLangevinIntegrator(300.0, 5.0, STEP_SIZE))
    elif kind == "thermostat":
        integrator = (openmmrigid.RigidBodyBussiIntegrator(300.0, 0.1, STEP_SIZE, explicit) if explicit
                      else openmmrigid.RigidBodyBussiIntegrator(300.0, 0.1, STEP_SIZE))
    else:
        return (openmmrigid.RigidBodyIntegrator(STEP_SIZE, explicit) if explicit
                else openmmrigid.RigidBodyIntegrator(STEP_SIZE))
    integrator.setRandomNumberSeed(SEED)
    return integrator


def legacy_context(kind, bodySource, platformName="Reference"):
    system = legacy_system(bodySource, kind)
    integrator = legacy_integrator(kind, bodySource)
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName(platformName))
    return context, integrator


def stem(kind, bodySource, prefix="legacy"):
    return f"{prefix}_{kind}_{bodySource}"


def main(prefix="legacy"):
    positions, velocities = water_positions()
    for bodySource in BODY_SOURCES:
        for kind in (KINDS if prefix == "legacy" else V1_KINDS):
            context, integrator = legacy_context(kind, bodySource)
            context.setPositions(positions)
            context.setVelocities(velocities)
            integrator.step(STEPS_BEFORE)
            (HERE / f"{stem(kind, bodySource, prefix)}.chk").write_bytes(context.createCheckpoint())
            integrator.step(STEPS_AFTER)
            reached = context.getState(getPositions=True).getPositions(asNumpy=True).value_in_unit(unit.nanometer)
            np.save(HERE / f"{stem(kind, bodySource, prefix)}.npy", reached)


if __name__ == "__main__":
    import sys
    main(*sys.argv[1:2])

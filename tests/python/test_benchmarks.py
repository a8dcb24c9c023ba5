"""The benchmarks' own helpers where a figure depends on them (benchmarks/benchmarking.py)."""

import pathlib
import re
import sys

import openmm
import pytest

import openmmrigid

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
benchmarking = pytest.importorskip("benchmarking")


def headerConstant(text, name):
    match = re.search(r"static constexpr (?:double|int) " + name + r" = ([0-9.eE+-]+);", text)
    assert match, f"{name} not found in AccuracyCheck.h"
    return float(match.group(1))


def test_check_constants_are_the_integrators():
    """The duty of the accuracy check that weights the benchmarks' timings uses the check's own constants."""
    text = (ROOT/"openmmapi"/"include"/"internal"/"AccuracyCheck.h").read_text()
    assert benchmarking.CHECK_WINDOW_PS == headerConstant(text, "WindowTime")
    assert benchmarking.CHECK_MINIMUM_STEPS == headerConstant(text, "MinimumSteps")
    assert benchmarking.CHECK_PAUSE_PS == headerConstant(text, "PauseTime")


def test_check_duty():
    """Two windows of 2 ps (or 200 steps) in every 36 ps pause and episode."""
    assert benchmarking.checkDuty(2) == pytest.approx(4/40)
    assert benchmarking.checkDuty(16) == pytest.approx(6.4/42.4)
    assert benchmarking.productionSeconds(1.0, 2.0, 2) == pytest.approx(1.1)


@pytest.mark.parametrize("make", [lambda: openmmrigid.RigidBodyIntegrator(0.002),
                                  lambda: openmmrigid.RigidBodyLangevinIntegrator(300, 1, 0.004)])
def test_episode_twin(make):
    """The twin is the same integrator measuring the shadow work at every step; neither runs the check."""
    integrator = make()
    integrator.setMinimumMomentOfInertia(0.05)
    twin = benchmarking.episodeTwin(integrator)
    assert type(twin) is type(integrator)
    assert not integrator.getAccuracyCheck() and not twin.getAccuracyCheck()
    assert twin.getMeasureShadowWork() and not integrator.getMeasureShadowWork()
    assert twin.getStepSize() == integrator.getStepSize()
    assert twin.getMinimumMomentOfInertia() == integrator.getMinimumMomentOfInertia()
    # It measures: a step of a small System accumulates shadow work.
    system = openmm.System()
    for _ in range(3):
        system.addParticle(16.0)
    system.addConstraint(0, 1, 0.1)
    system.addConstraint(1, 2, 0.1)
    system.addConstraint(0, 2, 0.15)
    force = openmm.CustomExternalForce("x^2 + 2*y^2 + 3*z^2")
    for i in range(3):
        force.addParticle(i, [])
    system.addForce(force)
    context = openmm.Context(system, twin, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions([openmm.Vec3(0.3, 0.1, 0.2), openmm.Vec3(0.4, 0.1, 0.2), openmm.Vec3(0.35, 0.2, 0.25)])
    context.setVelocitiesToTemperature(300, 1)
    twin.step(10)
    assert twin.getShadowWork() != 0.0

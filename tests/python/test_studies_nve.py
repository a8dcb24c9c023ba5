"""The analysis of the energy_drift, hmr_schemes and stress studies (benchmarks/studies/) against independent
computations: the equal-accuracy interpolation on power laws whose answer is known in closed form, the means and
errors over starts, the NVE trajectory's blow-up rule and drift on a harmonic oscillator, and the stress criteria."""

import math
import sys
import types
from pathlib import Path

import numpy as np
import openmm
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
from studies import energy_drift, stress  # noqa: E402


def powerLaw(a, b, steps):
    """Fluctuation a s^2 and ns/day b s at steps s: log-linear in log s, so interpolation in logs is exact."""
    return [(a*s*s, b*s, s) for s in steps]


def test_at_fluctuation_interpolates_power_laws_exactly():
    points = powerLaw(0.5, 10.0, [1, 2, 4, 8])
    for level in (0.7, 2.0, 5.3, 31.9):
        speed, step = energy_drift.atFluctuation(points, level)
        assert step == pytest.approx(math.sqrt(level/0.5), rel=1e-12)
        assert speed == pytest.approx(10.0*math.sqrt(level/0.5), rel=1e-12)


def test_at_fluctuation_never_extrapolates():
    points = powerLaw(0.5, 10.0, [2, 4])
    assert energy_drift.atFluctuation(points, 1.0) is None                 # more accurate than any step measured
    assert energy_drift.atFluctuation(points, 100.0) == (40.0, 4)          # coarser than all: the largest step, no more
    assert energy_drift.atFluctuation([], 1.0) is None


def test_at_fluctuation_takes_a_larger_step_below_the_floor():
    """Fluctuations at the potential's floor scatter: a larger step that is as accurate wins, measured as it is."""
    points = [(2.0, 10.0, 1), (2.5, 20.0, 2), (1.9, 40.0, 4)]
    assert energy_drift.atFluctuation(points, 2.0) == (40.0, 4)
    speed, step = energy_drift.atFluctuation(points + [(7.6, 80.0, 8)], 3.8)   # and on between 4 and 8 fs: 1.9 * 2
    assert (speed, step) == (pytest.approx(40.0*2**0.5), pytest.approx(4*2**0.5))


def results(box, seed, series):
    """The harness's results for one start: series {method: [(fluctuation, ns/day, step)]}."""
    return [{"job": {"box": box, "method": method, "step": step}, "failed": None, "blocked": False,
             "samples": [dict(seed=seed, fluctuation=f, nsPerDay=n, drift=0.0, driftError=0.01)]}
            for method, points in series.items() for f, n, step in points]


def test_equal_accuracy_against_the_closed_form():
    """Stock's fluctuation 1 s^2 at ns/day 10 s; Omelyan2's 0.1 s^2 at 5 s: at stock's accuracy at step s, Omelyan2
    reaches step sqrt(10) s and ns/day 5 sqrt(10) s, a ratio of sqrt(10)/2 (where its steps bracket the level)."""
    rows = energy_drift.equalAccuracy(results("box", 0, {"stock": powerLaw(1.0, 10.0, [1, 2, 3, 4]),
                                                         "Omelyan2": powerLaw(0.1, 5.0, [1, 2, 4, 8, 16])}))
    assert [row["stockStep"] for row in rows] == [1, 2, 3, 4]
    for row in rows:
        assert row["best"] == "Omelyan2"
        assert row["bestStep"] == pytest.approx(math.sqrt(10)*row["stockStep"], rel=1e-12)
        assert row["ratio"] == pytest.approx(math.sqrt(10)/2, rel=1e-12)


def test_summary_means_and_errors_over_starts():
    job = {"box": "tip3p-500", "method": "Omelyan2", "step": 4}
    samples = [dict(seed=s, drift=d, driftError=0.01, fluctuation=f, nsPerDay=10.0) for s, d, f in
               ((0, 0.1, 1.0), (1, 0.3, 2.0), (2, 0.2, 3.0))]
    row = energy_drift.summarize([{"job": job, "samples": samples, "failed": None, "blocked": False}], None)["rows"][0]
    assert (row["drift"], row["fluctuation"], row["starts"]) == (pytest.approx(0.2), pytest.approx(2.0), 3)
    assert row["driftError"] == pytest.approx(np.std([0.1, 0.3, 0.2], ddof=1)/math.sqrt(3))   # the spread: larger
    samples = [dict(s, driftError=1.0) for s in samples]
    row = energy_drift.summarize([{"job": job, "samples": samples, "failed": None, "blocked": False}], None)["rows"][0]
    assert row["driftError"] == pytest.approx(math.sqrt(3)/3)                                 # the runs' own errors


def oscillator():
    """One particle (1 amu) on a spring (k = 100 kJ/mol/nm^2) about the origin: a `Built` stand-in and its state."""
    system = openmm.System()
    system.addParticle(1.0)
    force = openmm.CustomExternalForce("0.5*100*(x^2+y^2+z^2)")
    force.addParticle(0, [])
    system.addForce(force)
    context = openmm.Context(system, openmm.VerletIntegrator(0.001), openmm.Platform.getPlatformByName("Reference"))
    context.setPositions([(0.1, 0.0, 0.0)])
    context.setVelocities([(0.0, 1.0, 0.0)])
    env = types.SimpleNamespace(platform=openmm.Platform.getPlatformByName("Reference"), properties={})
    return types.SimpleNamespace(system=system), context.getState(getPositions=True, getVelocities=True), env


def test_trajectory_conserves_and_blows_up_as_it_should():
    built, state, env = oscillator()
    energy = 0.5*100*0.1**2 + 0.5*1.0**2                    # kJ/mol: the exact (and Verlet's mean) energy
    run = energy_drift.Trajectory(built, openmm.VerletIntegrator(0.002), state, env, 2.0, limit=1.0)
    assert all(run.advance(10) for _ in range(50))
    assert run.energies[0] == pytest.approx(energy, rel=1e-3)    # (leapfrog: its kinetic energy shifted by dt/2)
    result = run.result(dof=3)
    assert result["failed"] is None and abs(result["drift"]) < 1e-3 and 0 < result["fluctuation"] < 1e-2*energy
    assert run.times[-1] == pytest.approx(1.0) and result["nsPerDay"] > 0
    # The same oscillator at a step beyond Verlet's limit (omega dt > 2: omega = 10/ps) grows without bound.
    run = energy_drift.Trajectory(built, openmm.VerletIntegrator(0.25), state, env, 250.0, limit=1.0)
    assert not all(run.advance(1) for _ in range(50))
    assert run.failure.startswith("blew up at ") and run.result(dof=3)["failed"] == run.failure


def row(**changes):
    """A stress row that meets every criterion, with `changes`."""
    return dict(dict(finite=True, error=None, energy=1e-5, rigidity=1e-15, momentum=1e-13, impulse=None, angular=None,
                     crossings=20), **changes)


@pytest.mark.parametrize("changes, criteria, failed", [
    ({}, {}, None), ({"energy": 0.02}, {}, "energy"), ({"energy": 0.02}, {"energy": 0.05}, None),
    ({"energy": float("nan")}, {}, "energy"), ({"rigidity": 2e-12}, {}, "rigidity"), ({"momentum": 1e-9}, {}, "momentum"),
    ({"momentum": None, "impulse": 1e-7}, {}, None), ({"momentum": None, "impulse": 1e-5}, {}, "impulse"), ({"angular": 1e-9}, {}, "angular"),
    ({"spin": 2e-8}, {"spin": 1e-8}, "spin"), ({"crossings": 3}, {"crossings": 10}, "only 3"),
    ({"finite": False}, {}, "not finite"), ({"error": "boom"}, {}, "raised")])
def test_stress_criteria(changes, criteria, failed):
    found = stress.failures(row(**changes), "CPU", **criteria)
    assert found == [] if failed is None else (len(found) == 1 and found[0].startswith(failed))

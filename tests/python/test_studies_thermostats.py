"""The analysis of the thermostats and openmmtools_ensembles studies (benchmarks/studies/), against
independent computations: the first peak of g_OO(r), the equipartition temperature, the table cells."""

import sys
import types
from pathlib import Path

import numpy as np
import openmm.unit as unit
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
from studies import openmmtools_ensembles, thermostats  # noqa: E402


def test_first_peak_finds_the_maximum_in_its_window_for_each_curve():
    radii = np.arange(0.0025, 1.0, 0.005)
    # A peak at 0.2775 nm of height 3 and 3.5, and a taller one beyond the window that must be ignored.
    curves = np.array([h*np.exp(-((radii - 0.2775)/0.01)**2) + 5*np.exp(-((radii - 0.6)/0.02)**2) for h in (3.0, 3.5)])
    heights, positions = thermostats.firstPeak(radii, curves)
    np.testing.assert_allclose(heights, [3.0, 3.5], rtol=1e-12)
    np.testing.assert_allclose(positions, [0.2775, 0.2775])
    height, position = thermostats.firstPeak(radii, curves[0])
    assert height == pytest.approx(3.0) and position == pytest.approx(0.2775)


def test_temperature_is_twice_the_kinetic_energy_over_the_degrees_of_freedom_and_boltzmann():
    # A kinetic energy alternating between K - d and K + d: the mean is K's temperature, and with 20 samples
    # in blocks of 2 or 4 consecutive ones every block mean is exact, so the error is zero.
    dof, kelvin, delta = 612, 330.0, 5.0
    kinetic = 0.5*dof*0.00831446261815324*kelvin
    steps, values = [], iter([kinetic + (delta if i % 2 else -delta) for i in range(20)])
    env = types.SimpleNamespace(quick=True)
    mean, error = openmmtools_ensembles.temperature(steps.append, lambda: next(values)*unit.kilojoule_per_mole, dof, env)
    assert mean == pytest.approx(kelvin, rel=1e-12)
    assert error == pytest.approx(0.0, abs=1e-9)
    assert steps == [100] + [10]*20           # 0.2 ps discarded, then a sample every 10 steps


def test_table_cells_give_the_distance_from_the_target_in_errors():
    assert thermostats.pm([329.2, 1.7], 1) == "329.2 ± 1.7"
    assert thermostats.pm([335.5, 2.5], 1, 330) == "335.5 ± 2.5 (+2.2 σ)"
    assert thermostats.pm([-46.3714, 0.0531], 3) == "-46.371 ± 0.053"


def test_summary_rows_carry_the_job_the_first_sample_and_why_a_run_is_missing():
    results = [{"job": {"system": "tip3p-rf", "integrator": "stock-middle", "step": 6}, "samples": [],
                "failed": "NaN", "blocked": False},
               {"job": {"system": "tip3p-rf", "integrator": "stock-middle", "step": 8}, "samples": [],
                "failed": None, "blocked": True},
               {"job": {"system": "tip3p-rf", "integrator": "rigid-langevin", "step": 8},
                "samples": [{"rotational": [300.6, 1.7]}], "failed": None, "blocked": False}]
    rows = thermostats.summarize(results, None)
    assert [row["failed"] for row in rows] == ["NaN", "blocked", None]
    assert rows[2] == {"system": "tip3p-rf", "integrator": "rigid-langevin", "step": 8, "failed": None,
                       "rotational": [300.6, 1.7]}

"""The analysis of the constant-temperature sampling studies (benchmarks/studies/_sampling.py, nvt_accuracy,
inertia_sampling, step_cap) against independent computations: g_OO over its first shell on a lattice and in an ideal
gas, runs pooled and compared with a reference, the accurate step of the bias fit against its closed form, and the
rules that pick the largest agreeing step."""

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
import harness  # noqa: E402
from studies import _sampling as sampling, inertia_sampling, nvt_accuracy, step_cap  # noqa: E402


def shellOf(frames, edges):
    radii, g = harness.radialDistribution(frames, [edges]*len(frames), sampling.RDF_MAX, sampling.RDF_BIN)
    return sampling.shellMean(radii, g)


def test_shell_mean_on_a_lattice_and_in_an_ideal_gas():
    """g_OO over the shell: on a simple cubic lattice whose nearest neighbours (6 each) fall in it, the pairs over an ideal
    gas's of the same density, n^2/(2V) times the shell's volume; 1 within its statistics for an ideal gas."""
    low, high = sampling.G_SHELL
    spacing, cells = 0.5*(low + high), 8
    grid = np.arange(cells)*spacing
    lattice = np.stack(np.meshgrid(grid, grid, grid, indexing="ij"), axis=-1).reshape(-1, 3)
    edges, n = np.full(3, cells*spacing), len(lattice)
    ideal = n*n/(2*np.prod(edges))*4/3*np.pi*(high**3 - low**3)
    assert shellOf([lattice + 0.01], edges)[0] == pytest.approx(3*n/ideal, rel=1e-9)
    rng = np.random.default_rng(5)
    # An ideal gas of 500 in (2.5 nm)^3 has about 236 pairs in the shell: 20 frames give 1 +- 0.015.
    assert abs(np.mean(shellOf(rng.uniform(0, 2.5, (20, 500, 3)), np.full(3, 2.5))) - 1) < 0.06


def result(system, config, step, samples, failed=None, blocked=False):
    return {"job": dict(system=system, config=config, step=step), "samples": samples, "failed": failed, "blocked": blocked}


def run(U, error=0.1, density=(1.0, 0.0)):
    return {"U": [U, error], "density": list(density), "T": [300.0, 1.0], "D": 2.0}


def test_runs_pooled_and_compared_with_their_reference():
    """A row pools its runs (mean; error sqrt(sum error^2)/n), a blocked job has none, a failed one keeps its runs and
    its reason; the reference pools the reference configurations; deviations combine the errors (an NVT density, without
    error, has none); rows come in the order of systems, configurations and steps."""
    results = [result("tip3p-nvt", "rigid", 2, [run(-40.2, 0.3), run(-40.0, 0.4)]),
               result("tip3p-nvt", "stock", 4, [run(-39.5)], failed="NaN"),
               result("tip3p-nvt", "stock", 2, [run(-40.1, 0.2), run(-39.9, 0.2)]),
               result("tip3p-nvt", "stock", 6, [], blocked=True)]
    rows = sampling.reduce(results)
    assert [(r["config"], r["step"]) for r in rows] == [("stock", 2), ("stock", 4), ("rigid", 2)]
    assert rows[0]["U"] == pytest.approx([-40.0, np.sqrt(0.08)/2]) and rows[0]["D"] == 2.0 and rows[0]["runs"] == 2
    assert rows[1]["failed"] == "NaN" and rows[1]["runs"] == 1
    reference = sampling.compare(rows, ("stock", "rigid"), 2)["tip3p-nvt"]
    assert reference["U"] == pytest.approx([-40.05, np.hypot(np.sqrt(0.08)/2, 0.25)/2])
    assert rows[1]["dU"] == pytest.approx([-39.5 + 40.05, np.hypot(0.1, reference["U"][1])])
    assert "ddensity" not in rows[1] and "dT" in rows[1]


def test_accurate_step_of_the_bias_fit():
    """bias = a h^2 exactly: the fit gives a (and no h^4), the accurate step is the largest h on the 0.1 fs grid with
    a h^2 <= the tolerance; a step beyond the tolerance by 2 sigma ends the fit and caps the step; a failed step ends
    the configuration's points."""
    a = sampling.TOLERANCE/7.55**2
    rows = [dict(system="tip3p-nvt", config="stock", step=h, runs=2, failed=None, dU=[a*h*h, 0.01]) for h in (2, 4, 6, 8)]
    rows += [dict(system="tip3p-nvt", config="rigid", step=h, runs=2, failed=None, dU=[1e-3*h*h, 0.02]) for h in (2, 4, 6)]
    rows += [dict(system="tip3p-nvt", config="rigid", step=8, runs=2, failed=None, dU=[5.0, 0.05]),
             dict(system="tip3p-nvt", config="raised-0.04", step=4, runs=2, failed=None, dU=[0.0, 0.05]),
             dict(system="tip3p-nvt", config="raised-0.04", step=8, runs=1, failed="NaN", dU=[0.0, 0.05])]
    fits = inertia_sampling.analyse(rows)
    assert fits["stock"]["fit"] == pytest.approx([a, 0.0], abs=1e-9) and fits["stock"]["accurate"] == 7.5
    assert fits["rigid"]["accurate"] == 6.0
    assert fits["raised-0.04"]["accurate"] == 4.0 and fits["raised-0.04"]["starts"] == 2


def test_largest_agreeing_step_per_box_and_pooled():
    """A step agrees within 2 combined sigma (U, and density where there is one); the strict rule stops at the first
    step that does not, the loose one takes the largest that does; pooled deviations average the boxes, their error
    sqrt(sum sigma^2)/n, and a step unstable in one box is unstable pooled."""
    rows = []
    for system, dUs in (("tip3p-nvt", [0.0, 0.1, 0.3, 0.1]), ("tip3p-npt", [0.0, -0.1, 0.1, 0.1])):
        for step, dU in zip((1, 2, 4, 6), dUs):
            rows.append(dict(system=system, config="stock", step=step, failed=None, dU=[dU, 0.1], dT=[0.0, 1.0],
                             **({"ddensity": [0.0, 0.01]} if system.endswith("npt") else {})))
    rows.append(dict(system="tip3p-nvt", config="stock", step=8, failed="NaN"))
    nvt = [r for r in rows if r["system"] == "tip3p-nvt"]
    assert nvt_accuracy.largest(nvt) == 2 and nvt_accuracy.largest(nvt, strict=False) == 6
    boxes, pooled = nvt_accuracy.pooledBoxes(rows)
    assert boxes == ["tip3p-nvt", "tip3p-npt"] and [e["step"] for e in pooled] == [1, 2, 4, 6, 8]
    assert pooled[2]["dU"] == pytest.approx([0.2, np.sqrt(0.02)/2]) and pooled[2]["ddensity"] == pytest.approx([0.0, 0.01])
    assert pooled[-1]["failed"] and nvt_accuracy.largest(pooled) == 2 and nvt_accuracy.largest(pooled, strict=False) == 6


def test_step_cap_accurate_step_at_standard_masses():
    """Sorted by the step at standard masses: the largest with every run stable and |bias| <= TOLERANCE + one sigma."""
    rows = [dict(standardStep=s, failures=f, dU=[b, 0.05]) for s, b, f in ((11.3, -0.12, 0), (12.7, 0.0, 0), (14.0, 0.14, 0),
                                                                        (14.1, 0.2, 0), (16.0, 0.0, 1))]
    assert step_cap.accurate(rows) == 14.0
    assert step_cap.accurate(rows[:3] + [dict(standardStep=13.0, failures=1, dU=[0.0, 0.05])]) == 12.7

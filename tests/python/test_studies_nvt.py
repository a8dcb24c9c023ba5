"""The analysis of the constant-temperature sampling studies (benchmarks/studies/_sampling.py, nvt_accuracy,
inertia_sampling, step_cap) against independent computations: g_OO over its first shell on a lattice and in an ideal
gas, runs pooled and compared with a reference, the accurate step of the bias fit against its closed form, the
rules that pick the largest agreeing step, and the dynamics (D, tau_1, tau_U) of processes whose values are known."""

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
    the configuration's points; D and the taus are the means of the rows to the accurate step."""
    a = sampling.TOLERANCE/7.55**2
    rows = [dict(system="tip3p-nvt", config="stock", step=h, runs=2, failed=None, dU=[a*h*h, 0.01], D=float(h))
            for h in (2, 4, 6, 8)]
    rows += [dict(system="tip3p-nvt", config="rigid", step=h, runs=2, failed=None, dU=[1e-3*h*h, 0.02]) for h in (2, 4, 6)]
    rows += [dict(system="tip3p-nvt", config="rigid", step=8, runs=2, failed=None, dU=[5.0, 0.05]),
             dict(system="tip3p-nvt", config="raised-0.04", step=4, runs=2, failed=None, dU=[0.0, 0.05]),
             dict(system="tip3p-nvt", config="raised-0.04", step=8, runs=1, failed="NaN", dU=[0.0, 0.05])]
    fits = inertia_sampling.analyse(rows)
    assert fits["stock"]["fit"] == pytest.approx([a, 0.0], abs=1e-9) and fits["stock"]["accurate"] == 7.5
    assert fits["stock"]["D"] == pytest.approx(4.0) and np.isnan(fits["stock"]["tauU"])
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


def test_diffusion_of_a_wrapped_random_walk():
    """Gaussian steps of variance 2 D dt per axis, wrapped into the box: MSD = 6 D t, D recovered in 1e-5 cm^2/s (1 nm^2/ps
    = 1e3 of them) within its statistics (400 walkers, 40 ps: about 2 %); too short a series has no lag range (nan)."""
    rng, every, D, box = np.random.default_rng(3), 0.1, 2.3e-3, np.array([2.0, 2.2, 1.9])   # nm^2/ps: 2.3e-5 cm^2/s
    walk = np.cumsum(rng.normal(0, np.sqrt(2*D*every), (400, 400, 3)), axis=0) % box
    assert sampling.diffusion(walk, np.tile(box, (400, 1)), every) == pytest.approx(2.3, rel=0.06)
    assert np.isnan(sampling.diffusion(walk[:5], np.tile(box, (5, 1)), every))


def test_rotational_time_of_a_random_rotation():
    """Unit vectors turned by a fixed angle theta about a random axis normal to them each frame: E[u(t+1)|u(t)] = cos theta
    u(t), so C_1(n frames) = cos^n theta exactly and tau_1 = -dt/ln cos theta (here 3 ps)."""
    rng, every, tau = np.random.default_rng(4), 0.1, 3.0
    theta, u = np.arccos(np.exp(-every/tau)), [rng.normal(size=(400, 3))]
    u[0] /= np.linalg.norm(u[0], axis=1)[:, None]
    for _ in range(299):
        w = rng.normal(size=(400, 3))
        w -= np.sum(w*u[-1], axis=1)[:, None]*u[-1]
        u.append(np.cos(theta)*u[-1] + np.sin(theta)*w/np.linalg.norm(w, axis=1)[:, None])
    assert sampling.rotationalTime(np.array(u), every) == pytest.approx(tau, rel=0.06)


def test_autocorrelation_time_of_an_ar1_series():
    """x_k = phi x_(k-1) + noise: rho_k = phi^k, so the integrated time is (1/2 + phi/(1 - phi)) samples; white noise: 1/2."""
    rng, every, phi, n = np.random.default_rng(5), 0.1, 0.8, 100000
    noise, x = rng.normal(size=n), np.zeros(n)
    for k in range(1, n):
        x[k] = phi*x[k - 1] + noise[k]
    assert sampling.autocorrelationTime(x, every) == pytest.approx(every*(0.5 + phi/(1 - phi)), rel=0.08)
    assert sampling.autocorrelationTime(noise, every) == pytest.approx(every*0.5, rel=0.1)


class PageStub:
    def __init__(self):
        self.tables = {}
        self.section = lambda title, text="": setattr(self, "last", title)
        self.figure = self.text = lambda *args, **kwargs: None

    def table(self, columns, rows):
        self.tables[self.last] = rows


def test_samples_per_wall_hour_against_stock():
    """The per-wall-hour table: ns/day at the accurate step rounded down, over 2 tau_U (U samples), times D, over tau_1,
    each against stock's: raised at twice the ns/day with tau_U 1.5 times and D, tau_1 0.8 and 1.25 times stock's."""
    fit = lambda accurate, D, tauRot, tauU: dict(fit=[0.0, 0.0], accurate=accurate, starts=2, D=D, tauRot=tauRot, tauU=tauU)
    rows = [dict(system="tip3p-nvt", config=c, step=2, runs=2, failed=None, U=[-40.0, 0.03], dU=[0.0, 0.04], T=[300.0, 1.0])
            for c in ("stock", "raised-0.04")]
    summary = dict(rows=rows, references={"tip3p-nvt": {"U": [-40.0, 0.03]}},
                   fits={"tip3p-nvt": {"stock": fit(7.9, 4.0, 2.0, 0.8), "raised-0.04": fit(14.0, 3.2, 2.5, 1.2)}},
                   timing=[dict(system="tip3p-nvt", config="stock", step=7, msPerStep=10.0),
                           dict(system="tip3p-nvt", config="raised-0.04", step=14, msPerStep=10.0)])
    page = PageStub()
    inertia_sampling.report(summary, page)
    stock, raised = page.tables["Independent samples per wall-hour"]
    assert stock[2:] == ["4.00", "2.00", "0.80", f"{harness.nsPerDay(7, 0.01)*1000/24/1.6:.0f}", "1.00", "1.00", "1.00"]
    assert [float(v) for v in raised[6:]] == pytest.approx([2/1.5, 2*0.8, 2/1.25], abs=0.005)

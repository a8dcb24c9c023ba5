"""The benchmarks' own helpers where a figure depends on them (benchmarks/benchmarking.py)."""

import json
import os
import pathlib
import re
import socket
import subprocess
import sys

import numpy as np
import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT/"benchmarks"))
benchmarking = pytest.importorskip("benchmarking")


def headerConstant(text, name):
    match = re.search(r"static constexpr (?:double|int) " + name + r" = ([0-9.eE+-]+);", text)
    assert match, f"{name} not found in AccuracyCheck.h"
    return float(match.group(1))


def test_check_window_is_the_integrators():
    """The accuracy check's window that benchmarks/accuracy_check.py sizes its runs by is the check's own."""
    text = (ROOT/"openmmapi"/"include"/"internal"/"AccuracyCheck.h").read_text()
    assert benchmarking.CHECK_WINDOW_PS == headerConstant(text, "WindowTime")


def test_sample_store_grows_every_job_in_turn(tmp_path):
    """Claims go to the job with the fewest samples below the target (the first of those on ties), name
    the missing indices, and a job claimed by a live process is not given out again."""
    store = benchmarking.SampleStore(tmp_path, {"protocol": 2.0})
    keys = ["a", "b", "c"]
    store.add("a", 0, [1.0, 2.0])
    store.add("a", 2, [1.0, 2.0])
    store.add("b", 1, [3.0, 4.0])
    store.add("c", 0, [5.0, 6.0])
    assert store.claim(keys, 3) == ("b", [0, 2])       # b and c have fewest: the first of them
    assert store.claim(keys, 3) == ("c", [1, 2])       # b is claimed by this (live) process
    assert store.claim(keys, 3) == ("a", [1])
    assert store.claim(keys, 3) is None                # all claimed
    for key in keys:
        store.release(key)
    store.add("b", 0, [0.5, 0.25], fired=False)
    store.add("b", 2, [0.5, 0.25], fired=True)
    store.add("b", 3, [0.5, 0.25], fired=False)
    assert [index for index, _ in store.samples("b")] == [0, 1, 2, 3]
    assert store.read()["jobs"]["b"]["flags"] == {"fired": True}
    assert store.claim(["b"], 3) is None               # b has its 3 below the target (and one more)
    # The same folder opened again sees the same samples; another set-up is refused.
    assert benchmarking.SampleStore(tmp_path, {"protocol": 2.0}).samples("a") == [(0, [1.0, 2.0]), (2, [1.0, 2.0])]
    with pytest.raises(ValueError, match="protocol"):
        benchmarking.SampleStore(tmp_path, {"protocol": 1.0})


def test_sample_store_failure_blocks_and_claims_lapse(tmp_path):
    """A failed job is not run again, nor are the jobs it blocks; a claim of a process that has ended,
    or one made on another machine, lapses."""
    store = benchmarking.SampleStore(tmp_path, {})
    keys = ["2 fs", "4 fs", "6 fs"]
    blockers = {"2 fs": [], "4 fs": ["2 fs"], "6 fs": ["2 fs", "4 fs"]}.get
    store.fail("4 fs", 1, "NaN")
    assert store.claim(keys, 2, blockers) == ("2 fs", [0, 1])
    assert store.claim(keys, 2, blockers) is None
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    data = json.loads((tmp_path/"store.json").read_text())
    data["claims"]["2 fs"] = {"host": socket.gethostname(), "pid": int(ended.stdout), "since": 0.0}
    (tmp_path/"store.json").write_text(json.dumps(data))
    assert store.claim(keys, 2, blockers) == ("2 fs", [0, 1])
    data = json.loads((tmp_path/"store.json").read_text())
    data["claims"]["2 fs"] = {"host": socket.gethostname() + "-elsewhere", "pid": os.getpid(), "since": 0.0}
    (tmp_path/"store.json").write_text(json.dumps(data))
    assert store.claim(keys, 2, blockers) == ("2 fs", [0, 1])


ADD_SAMPLES = """
import sys
sys.path.insert(0, sys.argv[1])
import benchmarking
store = benchmarking.SampleStore(sys.argv[2])
first = int(sys.argv[3])
for index in range(first, first + 40):
    store.add("job", index, [float(index)])
"""


def test_sample_store_keeps_every_sample_of_concurrent_workers(tmp_path):
    """Processes adding at once lose nothing: each update reads and writes the whole file under the lock."""
    benchmarking.SampleStore(tmp_path, {})
    workers = [subprocess.Popen([sys.executable, "-c", ADD_SAMPLES, str(ROOT/"benchmarks"), str(tmp_path), str(40*i)])
               for i in range(3)]
    assert [worker.wait(timeout=120) for worker in workers] == [0, 0, 0]
    assert benchmarking.SampleStore(tmp_path).samples("job") == [(index, [float(index)]) for index in range(120)]


def test_shell_pair_density():
    """inertia_sampling's g_OO over its shell: exact on a simple cubic lattice whose nearest neighbours
    fall in the shell, and 1 within its statistics for an ideal gas."""
    inertia = pytest.importorskip("inertia_sampling")
    low, high = inertia.G_SHELL
    spacing, cells = 0.5*(low + high), 8
    grid = np.arange(cells)*spacing
    lattice = np.stack(np.meshgrid(grid, grid, grid, indexing="ij"), axis=-1).reshape(-1, 3)
    edges = np.full(3, cells*spacing)
    n = len(lattice)
    ideal = 0.5*n*(n - 1)/np.prod(edges)*4/3*np.pi*(high**3 - low**3)
    assert inertia.shellPairDensity(lattice + 0.01, edges) == pytest.approx(3*n/ideal, rel=1e-12)  # 6 neighbours each
    rng = np.random.default_rng(5)
    values = [inertia.shellPairDensity(rng.uniform(0, 2.5, (500, 3)), np.full(3, 2.5)) for _ in range(20)]
    # An ideal gas of 500 in (2.5 nm)^3 has about 236 pairs in the shell: 20 frames give 1 +- 0.015.
    assert abs(np.mean(values) - 1) < 0.06


def test_principal_kinetic_energies_of_rigid_motion():
    """The split of kinetic energy that langevin_axes.py and step_cap.py read: for particles moving
    rigidly, v = V + omega x r, the translational part is sum M V^2 / 2 and the rotational parts add up
    to sum omega.I.omega / 2 (I built here from the particles, not by the helper's eigenvectors); each
    axis's part is L_k^2 / (2 I_k) in the helper's ascending order of moments."""
    rng = np.random.default_rng(7)
    masses = np.tile([16.0, 1.008, 1.008], 40)
    shape = np.array([[0.0, 0.0, 0.0], [0.09572, 0.0, 0.0], [-0.024, 0.0927, 0.0]])
    molecules = np.arange(120).reshape(40, 3)
    positions, velocities, translational, rotational, axes = [], [], 0.0, 0.0, np.zeros(3)
    for _ in range(40):
        rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        x = rng.uniform(0, 3, 3) + shape@rotation.T
        velocity, omega = rng.normal(size=3), rng.normal(scale=20, size=3)
        m = masses[:3]
        centre = (m[:, None]*x).sum(axis=0)/m.sum()
        r = x - centre
        positions.append(x)
        velocities.append(velocity + np.cross(omega, r))
        inertia = sum(mi*(ri@ri*np.eye(3) - np.outer(ri, ri)) for mi, ri in zip(m, r))
        translational += 0.5*m.sum()*velocity@velocity
        rotational += 0.5*omega@inertia@omega
        moments, vectors = np.linalg.eigh(inertia)
        axes += (vectors.T@(inertia@omega))**2/(2*moments)
    kinetic, perAxis = benchmarking.principalKineticEnergies(np.concatenate(positions), np.concatenate(velocities),
                                                             masses, molecules)
    assert kinetic == pytest.approx(translational, rel=1e-12)
    assert perAxis.sum() == pytest.approx(rotational, rel=1e-10)
    assert perAxis == pytest.approx(axes, rel=1e-10)


def test_inertia_sampling_result_from_its_store(tmp_path):
    """What inertia_sampling reports from a store: each configuration with the starts all its running
    steps have, a failed step with its runs and its failure (the steps it blocks "not run"), and the
    accurate-step analysis over those."""
    inertia = pytest.importorskip("inertia_sampling")
    store = benchmarking.SampleStore(tmp_path/"tip3p-nvt", {})
    store.note("waters", 500)
    store.note("configs", {"stock": ["stock", False, False, 0.0, [2, 4, 6, 8]],
                           "raised-0.04": ["raised", True, False, 0.04, [4, 8, 12]]})
    run = lambda u: dict(potential=[u, 0.02], temperature=[300.0, 0.5], gShell=[2.4, 0.01], D=4.0, tauRot=3.0, tauU=0.5)
    for start in range(3):
        store.add("stock|2", start, run(-40.0))
    for start in range(2):
        store.add("stock|4", start, run(-40.01))
        store.add("raised-0.04|4", start, run(-40.0))
        store.add("raised-0.04|8", start, run(-39.98))
    store.add("stock|6", 0, run(-39.9))
    store.fail("stock|6", 1, "NaN")
    store.add("raised-0.04|12", 0, run(-39.95))
    result = inertia.resultOf("tip3p-nvt", store, 0.1)
    assert result["starts"] == {"stock": 2, "raised-0.04": 1}
    runs = {(r["config"], r["step"], r["start"]): r["failure"] for r in result["runs"]}
    assert [key for key in runs if key[:2] == ("stock", 2)] == [("stock", 2, 0), ("stock", 2, 1)]
    assert runs[("stock", 6, 0)] == "" and runs[("stock", 6, 1)] == "NaN"
    assert runs[("stock", 8, 0)].startswith("not run") and runs[("stock", 8, 1)].startswith("not run")
    assert sorted(key for key in runs if key[0] == "raised-0.04") == [("raised-0.04", 4, 0), ("raised-0.04", 8, 0),
                                                                      ("raised-0.04", 12, 0)]
    summary = result["summary"]
    assert [p["step"] for p in summary["stock"]["points"]] == [2, 4] and summary["stock"]["largestStable"] == 4
    assert result["reference"]["potential"][0] == pytest.approx(-40.0)
    assert summary["raised-0.04"]["points"][-1]["potential"][2] == pytest.approx(0.05)

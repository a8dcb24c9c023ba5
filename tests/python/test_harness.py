"""The validation harness (benchmarks/harness.py): the sample store, the grid of jobs and what blocks them, a
study run end to end, the committed pages against their summaries, and the helpers a figure depends on."""

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
harness = pytest.importorskip("harness")


def headerConstant(text, name):
    match = re.search(r"static constexpr (?:double|int) " + name + r" = ([0-9.eE+-]+);", text)
    assert match, f"{name} not found in AccuracyCheck.h"
    return float(match.group(1))


def test_check_window_is_the_integrators():
    """The accuracy check's window that the accuracy_check study sizes its runs by is the check's own."""
    text = (ROOT/"openmmapi"/"include"/"internal"/"AccuracyCheck.h").read_text(encoding="utf-8")
    assert harness.CHECK_WINDOW_PS == headerConstant(text, "WindowTime")


def test_sample_store_grows_every_job_in_turn(tmp_path):
    """Claims go to the job with the fewest samples below the target (the first of those on ties), name
    the missing indices, and a job claimed by a live process is not given out again."""
    store = harness.SampleStore(tmp_path, {"protocol": 2.0})
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
    assert harness.SampleStore(tmp_path, {"protocol": 2.0}).samples("a") == [(0, [1.0, 2.0]), (2, [1.0, 2.0])]
    with pytest.raises(ValueError, match="protocol"):
        harness.SampleStore(tmp_path, {"protocol": 1.0})


def test_sample_store_failure_blocks_and_claims_lapse(tmp_path):
    """A failed job is not run again, nor are the jobs it blocks; a claim of a process that has ended,
    or one made on another machine, lapses."""
    store = harness.SampleStore(tmp_path, {})
    keys = ["2 fs", "4 fs", "6 fs"]
    blockers = {"2 fs": [], "4 fs": ["2 fs"], "6 fs": ["2 fs", "4 fs"]}.get
    store.fail("4 fs", 1, "NaN")
    assert store.claim(keys, 2, blockers) == ("2 fs", [0, 1])
    assert store.claim(keys, 2, blockers) is None
    ended = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    data = json.loads((tmp_path/"store.json").read_text(encoding="utf-8"))
    data["claims"]["2 fs"] = {"host": socket.gethostname(), "pid": int(ended.stdout), "since": 0.0}
    (tmp_path/"store.json").write_text(json.dumps(data), encoding="utf-8")
    assert store.claim(keys, 2, blockers) == ("2 fs", [0, 1])
    data = json.loads((tmp_path/"store.json").read_text(encoding="utf-8"))
    data["claims"]["2 fs"] = {"host": socket.gethostname() + "-elsewhere", "pid": os.getpid(), "since": 0.0}
    (tmp_path/"store.json").write_text(json.dumps(data), encoding="utf-8")
    assert store.claim(keys, 2, blockers) == ("2 fs", [0, 1])


ADD_SAMPLES = """
import sys
sys.path.insert(0, sys.argv[1])
import harness
store = harness.SampleStore(sys.argv[2])
first = int(sys.argv[3])
for index in range(first, first + 40):
    store.add("job", index, [float(index)])
"""


def test_sample_store_keeps_every_sample_of_concurrent_workers(tmp_path):
    """Processes adding at once lose nothing: each update reads and writes the whole file under the lock."""
    harness.SampleStore(tmp_path, {})
    workers = [subprocess.Popen([sys.executable, "-c", ADD_SAMPLES, str(ROOT/"benchmarks"), str(tmp_path), str(40*i)])
               for i in range(3)]
    assert [worker.wait(timeout=120) for worker in workers] == [0, 0, 0]
    assert harness.SampleStore(tmp_path).samples("job") == [(index, [float(index)]) for index in range(120)]


def test_principal_kinetic_energies_of_rigid_motion():
    """The split of kinetic energy that the studies read: for particles moving
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
    kinetic, perAxis = harness.principalKineticEnergies(np.concatenate(positions), np.concatenate(velocities),
                                                             masses, molecules)
    assert kinetic == pytest.approx(translational, rel=1e-12)
    assert perAxis.sum() == pytest.approx(rotational, rel=1e-10)
    assert perAxis == pytest.approx(axes, rel=1e-10)


def test_grid_jobs_seeds_and_blockers():
    """A grid is every combination of its axes, a list of grids their union in order (a job in two keeps
    its first seeds); a failure blocks the same job at larger steps only."""
    study = harness.Study("toy", "Toy", "A claim.", report=lambda summary, page: None, measure=lambda job, env: {},
                          summarize=lambda results, env: [],
                          grid=[{"kind": ["a", "b"], "step": [1, 2], "seed": range(3)},
                                {"kind": ["a", "c"], "step": [2, 4], "seed": [0]}], quick={"kind": ["a"]})
    jobs = study.jobs(quick=False)
    assert [(harness.jobKey(job), len(seeds)) for job, seeds in jobs] == [
        ("kind=a step=1", 3), ("kind=a step=2", 3), ("kind=b step=1", 3), ("kind=b step=2", 3),
        ("kind=a step=4", 1), ("kind=c step=2", 1), ("kind=c step=4", 1)]
    assert study.jobs(quick=True) == [({"kind": "a"}, [0])]
    blockers = harness._blockers(jobs)
    assert blockers["kind=a step=4"] == ["kind=a step=1", "kind=a step=2"]
    assert blockers["kind=c step=4"] == ["kind=c step=2"] and blockers["kind=b step=1"] == []
    with pytest.raises(ValueError, match="toy"):
        harness.Study("toy", "Toy", "A claim.", report=None, grid={"step": [1]})


def toyStudy(calls):
    """A study whose samples are known: x = step * (seed + 1); step 3 fails at its second seed."""
    def measure(job, env):
        calls.append((job["step"], job["seed"]))
        if job["step"] == 3 and job["seed"] == 1:
            raise harness.Unstable("flung")
        return {"x": job["step"]*(job["seed"] + 1)}

    def summarize(results, env):
        return [dict(r["job"], mean=float(np.mean([s["x"] for s in r["samples"]])) if r["samples"] else None,
                     failed=r["failed"], blocked=r["blocked"]) for r in results]

    def report(rows, page):
        page.table(["step", "mean", "failed"], [[r["step"], r["mean"], r["failed"] or ("blocked" if r["blocked"] else "")]
                                                for r in rows])
        figure, axes = harness.pyplot().subplots()
        axes.plot([r["step"] for r in rows if r["mean"]], [r["mean"] for r in rows if r["mean"]])
        page.figure(figure, "mean", "The mean against the step")

    grid = {"step": [1, 2, 3, 4], "seed": range(3)}
    return harness.Study("toy", "A toy study", "The mean is twice the step.", report, method="Arithmetic.",
                         caveats="Nothing physical.", grid=grid, quick=grid, measure=measure, summarize=summarize)


@pytest.fixture
def sandbox(tmp_path, monkeypatch):
    """The harness's folders moved into tmp_path."""
    for name, sub in (("RESULTS", "results"), ("DATA", "data"), ("PAGES", "pages"), ("FIGURES", "pages/figures")):
        monkeypatch.setattr(harness, name, tmp_path/sub)
    return tmp_path


def test_study_runs_resumes_and_reports_from_its_summary(sandbox, monkeypatch):
    """A study run measures every job at every seed once, records a failure and skips the steps it blocks,
    writes its summary and page; a second run measures nothing again; the page written from the summary
    alone is the same page."""
    calls = []
    study = toyStudy(calls)
    monkeypatch.setattr(harness, "loadStudy", lambda name: study)
    argv = ["toy"]
    args = harness.parseArguments([study], argv)
    data = harness.measureStudy(study, args, argv)
    assert sorted(calls) == [(1, 0), (1, 1), (1, 2), (2, 0), (2, 1), (2, 2), (3, 0), (3, 1)]
    rows = {row["step"]: row for row in data["summary"]}
    assert rows[1]["mean"] == 2.0 and rows[2]["mean"] == 4.0 and rows[3]["mean"] == 3.0
    assert rows[3]["failed"] == "flung" and rows[4]["blocked"] and rows[4]["mean"] is None
    stored = json.loads((sandbox/"data"/"toy.json").read_text(encoding="utf-8"))
    assert stored["summary"] == data["summary"] and stored["runs"][0]["command"].endswith("toy")
    page = harness.reportStudy(study, quick=False, data=data)
    text = page.read_text(encoding="utf-8")
    assert text.startswith("# A toy study\n") and "The mean is twice the step." in text
    assert "| 3 | 3.0 | flung |" in text and "| 4 |  | blocked |" in text
    assert "![The mean against the step](figures/toy_mean.png)" in text and (sandbox/"pages"/"figures"/"toy_mean.png").exists()
    assert "## What it does not show" in text and "python benchmarks/run.py toy" in text
    calls.clear()
    again = harness.measureStudy(study, args, argv)   # its run record is new (the machine's load may differ)
    assert calls == [] and again["summary"] == data["summary"]
    text = harness.reportStudy(study, quick=False, data=again).read_text(encoding="utf-8")
    page.unlink()
    assert harness.reportStudy(study, quick=False).read_text(encoding="utf-8") == text


def test_committed_pages_are_what_their_summaries_give(sandbox):
    """Every study has its summary in benchmarks/data, and its committed page in docs/validation is the
    page that summary gives (`python benchmarks/run.py all --report`), so no table is edited by hand."""
    names = harness.studyNames()
    assert names, "no studies found"
    for name in names:
        study = harness.loadStudy(name)
        data = json.loads((ROOT/"benchmarks"/"data"/f"{name}.json").read_text(encoding="utf-8"))
        written = harness.reportStudy(study, quick=False, data=data)
        assert written.read_text(encoding="utf-8") == (ROOT/"docs"/"validation"/f"{name}.md").read_text(encoding="utf-8"), name


def test_sample_store_claims_each_job_to_its_own_target(tmp_path):
    """With a target per job, a job is claimed for its own missing indices only, and one that has its own
    number of samples is not claimed again, whatever the others' targets."""
    store = harness.SampleStore(tmp_path, {})
    store.add("few", 0, [1.0])
    assert store.claim(["few", "many"], {"few": 1, "many": 3}) == ("many", [0, 1, 2])
    assert store.claim(["few", "many"], {"few": 1, "many": 3}) is None      # few is complete, many is claimed
    store.release("many")
    for index in range(3):
        store.add("many", index, [2.0])
    assert store.claim(["few", "many"], {"few": 2, "many": 3}) == ("few", [1])

"""The validation harness: what every study shares, and the command line that runs them.

A study (benchmarks/studies/<name>.py) declares a ``Study``: a claim, a grid of jobs, and functions that
measure a job, summarize all samples and write the page from the summary alone (or ``run``, if not a grid).
``python benchmarks/run.py STUDY`` runs it, resuming its stored samples, and writes its summary
(benchmarks/data/) and page (docs/validation/), both committed; ``--quick``: a smoke run on a tiny grid, into
benchmarks/results/quick/ (with raw samples, starting states and logs); ``--report``: the pages again.
"""

import argparse
import contextlib
import datetime
import fcntl
import importlib
import itertools
import json
import multiprocessing
import os
import platform as pyplatform
import shlex
import socket
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import openmm

import openmmrigid

ROOT = Path(__file__).resolve().parent.parent
DATA = ROOT/"benchmarks"/"data"           # the studies' summaries (committed)
RESULTS = ROOT/"benchmarks"/"results"     # raw samples, starting states, logs, quick runs (git ignores it)
PAGES = ROOT/"docs"/"validation"          # the studies' pages (committed; regenerated from DATA)
FIGURES = PAGES/"figures"                 # their figures (built from DATA, not committed)
STUDIES = ROOT/"benchmarks"/"studies"

sys.path.append(str(ROOT/"tests"/"python"))  # rigidtesting, shared with the tests
from rigidtesting.bodies import rigidDegreesOfFreedom  # noqa: E402,F401 (for the studies)
from rigidtesting.stress import block_drift  # noqa: E402

# --- Progress, provenance and plots ------------------------------------------------------------------
_log = None   # the open log file that say() copies to (measureStudy opens it)


def say(text=""):
    """Print a line (flushed, so that a long run shows its progress) and copy it to the log."""
    print(text, flush=True)
    if _log is not None:
        _log.write(text + "\n")
        _log.flush()


def stamp(text):
    """say() with the wall-clock time in front: for progress lines."""
    say(f"[{datetime.datetime.now():%H:%M:%S}] {text}")


def commit():
    """The source tree's short commit, marked when tracked files other than pages and summaries differ."""
    git = ["git", "-C", str(ROOT)]
    try:
        head = subprocess.run(git + ["rev-parse", "--short", "HEAD"], capture_output=True, text=True, check=True)
        dirty = subprocess.run(git + ["status", "--porcelain", "--untracked-files=no", "--", ".", ":!docs/validation",
                                      ":!benchmarks/data"], capture_output=True, text=True, check=True)
        return head.stdout.strip() + (" (with uncommitted changes to the code)" if dirty.stdout.strip() else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def machine():
    """The processor (lscpu's model name), the architecture and the number of cores."""
    name = pyplatform.processor() or pyplatform.machine()
    with contextlib.suppress(OSError, subprocess.CalledProcessError):
        lines = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout.splitlines()
        name = next((line.split(":", 1)[1].strip() for line in lines if line.startswith("Model name:")), name)
    return f"{name}, {pyplatform.machine()}, {os.cpu_count()} cores"


def cpuProperties(platform, threads):
    """Context properties giving the CPU platform `threads` threads (none elsewhere, or for threads None)."""
    name = platform if isinstance(platform, str) else platform.getName()
    return {"Threads": str(threads)} if name == "CPU" and threads else {}


def shown(path):
    """A path as a message shows it: relative to the repository where it is inside."""
    path = Path(path)
    return path.relative_to(ROOT) if path.is_relative_to(ROOT) else path


def pyplot():
    """matplotlib.pyplot with the file-only Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


# --- Statistics, kinetic energies, the rigid integrators and their timing -----------------------------
def blockMean(values, blocks=(5, 10)):
    """Mean of a time series (first axis) and its standard error by block averaging (Flyvbjerg and Petersen,
    J. Chem. Phys. 91, 461 (1989)): the largest estimate over the numbers of blocks given (or the one int)."""
    values = np.asarray(values, dtype=float)
    errors = []
    for count in ([blocks] if np.isscalar(blocks) else blocks):
        n = len(values)//count*count
        if n < count:
            continue
        means = values[:n].reshape(count, -1, *values.shape[1:]).mean(axis=1)
        errors.append(means.std(axis=0, ddof=1)/np.sqrt(count))
    error = np.max(errors, axis=0) if errors else np.full(values.shape[1:], np.nan)
    return values.mean(axis=0), error


def overSeeds(estimates):
    """(mean, standard error) over independent runs' (mean, error): the spread of the means, or one run's."""
    means = np.array([estimate[0] for estimate in estimates], dtype=float)
    if len(means) == 1:
        return float(means[0]), None if estimates[0][1] is None else float(estimates[0][1])
    return float(means.mean()), float(means.std(ddof=1)/np.sqrt(len(means)))


def pm(value, digits, signed=False):
    """'mean +- error' of a [mean, error] ('' for none, the mean alone for no error), with (n sigma) if signed."""
    if not value or value[0] is None or value[0] != value[0]:
        return ""
    text = f"{value[0]:{'+' if signed else ''}.{digits}f}" + (f" +- {value[1]:.{digits}f}" if value[1] is not None else "")
    return text + (f" ({value[0]/value[1]:+.1f} sigma)" if signed and value[1] else "")


def slopeError(times, values, blocks=10):
    """Standard error of a series' slope from its block means (rigidtesting.stress.block_drift), or NaN."""
    if len(times)//blocks*blocks < 2*blocks:
        return float("nan")
    return float(block_drift(times, values, blocks)[1])


def medianRange(samples, scale=1.0):
    """(median, min, max) of the samples times `scale`."""
    values = [scale*value for value in samples]
    return float(np.median(values)), min(values), max(values)


def radialDistribution(frames, boxes, largest, width):
    """(bin centres, frames x bins): g(r) of frames (x atoms x 3, nm) in rectangular boxes (frames x 3 edges)
    by minimum image: pair counts over an ideal gas's, N/2 N/V 4/3 pi (r_out^3 - r_in^3), up to `largest`."""
    edges = np.arange(0.0, largest + width/2, width)
    shells = 4/3*np.pi*(edges[1:]**3 - edges[:-1]**3)
    upper = np.triu_indices(np.shape(frames)[1], k=1)
    result = []
    for positions, box in zip(frames, boxes):
        delta = positions[:, None, :] - positions[None, :, :]
        delta -= box*np.round(delta/box)
        counts, _ = np.histogram(np.sqrt(np.sum(delta**2, axis=-1))[upper], bins=edges)
        n = len(positions)
        result.append(2*counts/(n*(n/np.prod(box))*shells))
    return 0.5*(edges[1:] + edges[:-1]), np.array(result)


def molecularKineticEnergies(velocities, masses, molecules):
    """Kinetic energy (kJ/mol) of the molecules' centres of mass and the rest (for rigid molecules: the
    rotational). velocities (particles x 3, nm/ps), masses (amu), molecules (molecules x atoms: indices)."""
    m = masses[molecules]                                       # (N, k)
    v = velocities[molecules]                                   # (N, k, 3)
    centre = np.einsum("na,nak->nk", m, v)/m.sum(axis=1)[:, None]
    translational = 0.5*np.sum(m.sum(axis=1)*np.sum(centre**2, axis=1))
    total = 0.5*np.sum(m[:, :, None]*v**2)
    return translational, total - translational


def principalKineticEnergies(positions, velocities, masses, molecules):
    """Kinetic energy (kJ/mol) of rigid molecules' centres of mass, and the rotational about each principal
    axis by increasing moment, L_k^2/(2 I_k), summed over them. Positions (nm) of whole molecules; as above."""
    m = masses[molecules][:, :, None]                            # (N, k, 1)
    x, v = positions[molecules], velocities[molecules]          # (N, k, 3)
    total = m.sum(axis=1)
    centre, speed = (m*x).sum(axis=1)/total, (m*v).sum(axis=1)/total
    r, u = x - centre[:, None], v - speed[:, None]
    angular = (m*np.cross(r, u)).sum(axis=1)                    # L about the centre of mass
    inertia = (m[..., None]*(np.einsum("nki,nki->nk", r, r)[..., None, None]*np.eye(3)
                             - r[..., :, None]*r[..., None, :])).sum(axis=1)
    moments, axes = np.linalg.eigh(inertia)                     # ascending moments, axes as columns
    principal = np.einsum("nij,ni->nj", axes, angular)
    return 0.5*float(np.sum(total[:, 0]*np.sum(speed**2, axis=1))), np.sum(principal**2/(2*moments), axis=0)


#: Force evaluations per step of each splitting of RigidBodyIntegrator.setSplitting().
FORCE_EVALUATIONS = {openmmrigid.RigidBodyIntegrator.Verlet: 1, openmmrigid.RigidBodyIntegrator.Omelyan2: 2,
                     openmmrigid.RigidBodyIntegrator.Yoshida4: 3, openmmrigid.RigidBodyIntegrator.Omelyan4: 4}

#: A window of the accuracy check (ps): AccuracyCheck::WindowTime in openmmapi/include/internal/AccuracyCheck.h.
CHECK_WINDOW_PS = 2.0


def accuracyWarnings(caught):
    """The messages of the openmmrigid.AccuracyWarning among warnings.catch_warnings(record=True)'s."""
    return [str(w.message) for w in caught if issubclass(w.category, openmmrigid.AccuracyWarning)]


def nsPerDay(stepFs, secondsPerStep):
    """Simulated ns per day at a step of `stepFs` fs and a cost of `secondsPerStep` wall seconds."""
    return stepFs*1e-6*86400/secondsPerStep


def blockSteps(integrator, fixed, target, minimum):
    """Steps per timed block: `fixed` if given, else enough for `target` seconds (at least `minimum`), timed
    after two untimed steps on blocks of 1, 4, 16, ... steps until one takes a tenth of the target."""
    if fixed:
        return fixed
    integrator.step(2)
    steps = 1
    while True:
        start = time.perf_counter()
        integrator.step(steps)
        elapsed = time.perf_counter() - start
        if elapsed >= 0.1*target or steps >= 1 << 16:
            return max(minimum, int(round(target/(elapsed/steps))))
        steps *= 4


class TimingFailure(RuntimeError):
    """An integrator that failed (an unstable step) while it was timed: which one (its label) and why."""

    def __init__(self, label, error):
        super().__init__(f"{label}: {error}")
        self.label, self.error = label, error


def timeInterleaved(integrators, steps, repetitions):
    """Time {label: integrator} (own Contexts), after a warm-up block each, on `repetitions` blocks of `steps`
    taking turns (all see the same load): ({label: [wall s/step]}, {label: [this process's CPU s/step]})."""
    wall, cpu = {label: [] for label in integrators}, {label: [] for label in integrators}
    for repetition in range(repetitions + 1):
        for label, integrator in integrators.items():
            startWall, startCpu = time.perf_counter(), time.process_time()
            try:
                integrator.step(steps)
            except openmm.OpenMMException as error:
                raise TimingFailure(label, error) from error
            if repetition > 0:
                wall[label].append((time.perf_counter() - startWall)/steps)
                cpu[label].append((time.process_time() - startCpu)/steps)
    return wall, cpu


# --- Studies: their samples, jobs, summaries and pages ------------------------------------------------
class SampleStore:
    """Numbered samples (an index names a seed: none is computed twice) of jobs (string keys), kept between
    runs, that workers add to at once: `folder`/store.json, read and written whole under a lock (fcntl). A
    failed job takes no more samples, nor do the jobs it blocks. A worker claims the job with the fewest
    samples, so an interrupted run leaves an even table. `setup` (what makes samples comparable) must match."""

    def __init__(self, folder, setup=None):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path, self.lockPath = self.folder/"store.json", self.folder/"store.lock"
        if setup is not None:   # None: open the store as it is
            setup = json.loads(json.dumps(setup))  # as it reads back
            with self._locked() as data:
                if data["setup"] is None:
                    data["setup"] = setup
                elif data["setup"] != setup:
                    raise ValueError(f"the samples in {self.folder} were made with {data['setup']}, not {setup}: "
                                     "choose another folder for this set-up")

    @contextlib.contextmanager
    def _locked(self, write=True):
        with open(self.lockPath, "a") as lock:   # closing it, even on an exception, releases the lock
            fcntl.flock(lock, fcntl.LOCK_EX)
            empty = {"setup": None, "jobs": {}, "claims": {}, "runs": []}
            data = json.loads(self.path.read_text(encoding="utf-8")) if self.path.exists() else empty
            yield data
            if write:   # replaced atomically
                temporary = self.path.with_suffix(f".{os.getpid()}.tmp")
                temporary.write_text(json.dumps(data, indent=1), encoding="utf-8")
                os.replace(temporary, self.path)

    @staticmethod
    def _job(data, key):
        return data["jobs"].setdefault(key, {"samples": {}, "failed": None, "flags": {}})

    def read(self):
        """The whole store: setup, jobs ({key: {samples: {index: values}, failed, flags}}), claims, runs."""
        with self._locked(write=False) as data:
            return data

    def samples(self, key):
        """A job's samples, in index order: [(index, values)]."""
        job = self.read()["jobs"].get(key, {"samples": {}})
        return sorted(((int(index), values) for index, values in job["samples"].items()))

    @staticmethod
    def _live(claim):
        """Whether the claim's process still runs (a claim made on another machine is void)."""
        if claim["host"] != socket.gethostname():
            return False
        try:
            os.kill(claim["pid"], 0)
        except OSError as error:   # PermissionError: it runs, as another user's
            return isinstance(error, PermissionError)
        return True

    @staticmethod
    def blocked(data, key, blockers):
        """Whether one of the job's blockers (keys) has failed."""
        return any(data["jobs"].get(other, {}).get("failed") is not None for other in blockers)

    def claim(self, keys, target, blockers=lambda key: ()):
        """Claim, of `keys`, the job with the fewest samples below its target (`target`: one for all, or {key:
        target}), neither failed, blocked (blockers(key): the keys whose failure stops it) nor claimed by a live
        worker: (key, its missing indices below its target) or None."""
        targets = target if isinstance(target, dict) else dict.fromkeys(keys, target)
        now = time.time()
        with self._locked() as data:
            claims = data["claims"] = {key: claim for key, claim in data["claims"].items() if self._live(claim)}
            counts = {}
            for key in keys:
                job = data["jobs"].get(key, {"samples": {}, "failed": None})
                if key not in claims and job["failed"] is None and not self.blocked(data, key, blockers(key)):
                    counts[key] = sum(1 for index in job["samples"] if int(index) < targets[key])
            key = min((key for key in counts if counts[key] < targets[key]), key=counts.get, default=None)
            if key is None:
                return None
            claims[key] = {"host": socket.gethostname(), "pid": os.getpid(), "since": now}
            have = self._job(data, key)["samples"]
            return key, [index for index in range(targets[key]) if str(index) not in have]

    def add(self, key, index, values, **flags):
        """Record a sample (numbers, or a dict as JSON gives it back); flags (booleans) are or-ed into the job's."""
        with self._locked() as data:
            job = self._job(data, key)
            values = json.loads(json.dumps(values)) if isinstance(values, dict) else [float(v) for v in values]
            job["samples"][str(index)] = values
            for name, value in flags.items():
                job["flags"][name] = bool(job["flags"].get(name, False) or value)

    def fail(self, key, index, reason):
        with self._locked() as data:
            self._job(data, key)["failed"] = {"sample": int(index), "reason": str(reason)}

    def release(self, key):
        with self._locked() as data:
            data["claims"].pop(key, None)


class Unstable(RuntimeError):
    """Raised by measure() when a run failed (NaN, a particle flung): the job fails, those it blocks don't run."""


class Study:
    """One study: a claim, a grid of jobs and the functions that measure, summarize and report them.

    title, claim (one sentence), method, caveats (what it does not show): the page's text. grid, quick: the
    full and the smoke run's jobs (see jobs(); "seed" numbers a job's samples, and a failed job blocks it at
    every larger "step"). measure(job, env) -> one sample (a dict), or raises Unstable. summarize(results,
    env) -> a JSON-able summary of [{"job": axes but seed, "samples": in seed order, "failed": reason or None,
    "blocked": bool}]. run(env) -> a summary, instead of both. report(summary, page): the page's body.
    options: extra command-line options, {"--option": dict(argparse keywords)}."""

    def __init__(self, name, title, claim, report, method="", caveats="", grid=None, quick=None, measure=None,
                 summarize=None, run=None, options=None):
        if run is None and None in (grid, quick, measure, summarize) or run is not None and (measure or summarize):
            raise ValueError(f"study {name}: give run, or grid, quick, measure and summarize")
        self.name, self.title, self.claim, self.report = name, title, claim, report
        self.method, self.caveats = method.strip(), caveats.strip()
        self.grid, self.quickGrid, self.measure, self.summarize, self.run = grid, quick, measure, summarize, run
        self.options = options or {}

    def jobs(self, quick):
        """[(job, seeds)] in order, from a dict of axes (every combination) or a list of them (their union)."""
        grids = self.quickGrid if quick else self.grid
        result = []
        for grid in grids if isinstance(grids, list) else [grids]:
            grid = dict(grid)
            seeds = list(grid.pop("seed", [0]))
            jobs = [dict(zip(grid, values)) for values in itertools.product(*grid.values())]
            result += [(job, seeds) for job in jobs if jobKey(job) not in {jobKey(other) for other, _ in result}]
        return result


def jobKey(job):
    return " ".join(f"{axis}={value}" for axis, value in job.items())


def _blockers(jobs):
    """The keys whose failure stops each job: the same job at smaller steps."""
    jobs = [job for job, _ in jobs]
    keys = {}
    for job in jobs:
        smaller = [other for other in jobs if "step" in job and other.get("step") is not None
                   and other["step"] < job["step"]
                   and all(other[axis] == value for axis, value in job.items() if axis != "step")]
        keys[jobKey(job)] = [jobKey(other) for other in smaller]
    return keys


class Environment:
    """What a study's functions get: the platform, its Context properties, quick, a folder, the arguments."""

    def __init__(self, study, args):
        self.study, self.args, self.quick = study, args, args.quick
        self.platformName, self.threads = args.platform, args.threads
        self.folder = RESULTS/("quick" if args.quick else "")/study.name
        self.folder.mkdir(parents=True, exist_ok=True)

    @property
    def platform(self):
        return openmm.Platform.getPlatformByName(self.platformName)

    @property
    def properties(self):
        return cpuProperties(self.platformName, self.threads)


def _worker(name, args):
    """A worker process: claims jobs of the study's store and measures them until none is left."""
    study = loadStudy(name)
    env = Environment(study, args)
    jobs = study.jobs(args.quick)
    blockers = _blockers(jobs)
    byKey = {jobKey(job): (job, seeds) for job, seeds in jobs}
    store = SampleStore(env.folder/"store")
    targets = {key: len(seeds) for key, (job, seeds) in byKey.items()}
    while True:
        claim = store.claim(list(byKey), targets, blockers.get)
        if not claim:
            return
        key, missing = claim
        job, seeds = byKey[key]
        try:
            for index in missing:
                stamp(f"{study.name}: {key} seed={seeds[index]}")
                try:
                    sample = study.measure(dict(job, seed=seeds[index]), env)
                except Unstable as failure:
                    store.fail(key, index, str(failure))
                    say(f"  failed: {failure}")
                    break
                store.add(key, index, sample)
        finally:
            store.release(key)


def runWorkers(task, arguments, workers):
    """task(*arguments) here (workers 1), or in `workers` spawned processes at once (each its own OpenMM)."""
    if workers == 1:
        task(*arguments)
        return
    spawn = multiprocessing.get_context("spawn")
    processes = [spawn.Process(target=task, args=arguments) for _ in range(workers)]
    for process in processes:
        process.start()
    for process in processes:
        process.join()
    failed = [process.exitcode for process in processes if process.exitcode != 0]
    if failed:
        raise SystemExit(f"{len(failed)} of {workers} worker processes failed (exit codes {failed}); see above")


def _collect(study, env):
    """The results that summarize() gets, from the study's store."""
    jobs = study.jobs(env.quick)
    blockers = _blockers(jobs)
    data = SampleStore(env.folder/"store").read()
    results = []
    for job, seeds in jobs:
        key = jobKey(job)
        entry = data["jobs"].get(key, {"samples": {}, "failed": None})
        samples = [entry["samples"][str(i)] for i in range(len(seeds)) if str(i) in entry["samples"]]
        failed = entry["failed"]["reason"] if entry.get("failed") else None
        results.append({"job": job, "samples": samples, "failed": failed,
                        "blocked": SampleStore.blocked(data, key, blockers[key])})
    return results


def dataPath(study, quick):
    return (RESULTS/"quick" if quick else DATA)/f"{study.name}.json"


def measureStudy(study, args, argv):
    """Run the study (its jobs through the store, resuming; or its run()), write its summary and return it."""
    global _log
    env = Environment(study, args)
    started = time.perf_counter()
    if _log is not None:
        _log.close()
    _log = open(env.folder/"log.txt", "w", encoding="utf-8")
    stamp(f"{study.name}: {'quick ' if args.quick else ''}run on {args.platform}")
    if study.run is not None:
        summary = study.run(env)
    else:
        SampleStore(env.folder/"store", {"study": study.name, "quick": args.quick})
        runWorkers(_worker, (study.name, args), args.workers)
        summary = study.summarize(_collect(study, env), env)
    load = "unknown"
    with contextlib.suppress(OSError):
        load = " ".join(Path("/proc/loadavg").read_text().split()[:3])
    run = dict(date=f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}", commit=commit(), machine=machine(),
               software=f"OpenMM {openmm.version.full_version}, openmm-rigid {openmmrigid.__version__}",
               platform=args.platform + (f", {args.threads} thread(s)" if args.threads else ""),
               workers=args.workers, minutes=round((time.perf_counter() - started)/60, 1), load=load,
               command=shlex.join(["python", "benchmarks/run.py"] + list(argv)))
    # Rounded as stored, so that the page written now is the page the stored summary gives.
    data = jsonReady({"study": study.name, "runs": [run], "summary": summary})
    path = dataPath(study, args.quick)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    say(f"wrote {shown(path)}")
    _log.close()
    _log = None
    return data


def jsonReady(value, digits=6):
    """The value with floats rounded to `digits` significant digits (None if not finite), numpy types plain."""
    if isinstance(value, dict):
        return {str(k): jsonReady(v, digits) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [jsonReady(v, digits) for v in value]
    if isinstance(value, np.integer):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(f"{float(value):.{digits}g}") if np.isfinite(value) else None
    return value


class Page:
    """A study's Markdown page: claim, command, method, the body that report() adds, caveats and runs."""

    def __init__(self, study, data, quick):
        self.study, self.quick = study, quick
        self.path = (RESULTS/"quick" if quick else PAGES)/f"{study.name}.md"
        self.figures = RESULTS/"quick"/"figures" if quick else FIGURES
        self.lines = []

    def text(self, text):
        self.lines += [text.strip(), ""]

    def section(self, title, text=""):
        self.lines += [f"## {title}", ""] + ([text.strip(), ""] if text else [])

    def table(self, columns, rows):
        """A Markdown table (cells formatted by the caller); columns of numbers are right-aligned."""
        def numeric(cell):
            try:
                float(str(cell).replace("**", "").replace("x", "").split()[0])
                return True
            except (ValueError, IndexError):
                return False
        align = ["---:" if rows and all(numeric(row[i]) or row[i] in ("", None) for row in rows) else "---"
                 for i in range(len(columns))]
        self.lines += ["| " + " | ".join(columns) + " |", "| " + " | ".join(align) + " |"]
        self.lines += ["| " + " | ".join("" if cell is None else str(cell) for cell in row) + " |" for row in rows]
        self.lines += [""]

    def figure(self, figure, name, caption):
        """Save a matplotlib figure as <figures>/<study>_<name>.png and show it on the page."""
        path = self.figures/f"{self.study.name}_{name}.png"
        path.parent.mkdir(parents=True, exist_ok=True)
        figure.tight_layout()
        figure.savefig(path, dpi=120)
        pyplot().close(figure)
        say(f"wrote {shown(path)}")
        self.lines += [f"![{caption}]({os.path.relpath(path, self.path.parent)})", ""]

    def write(self, data):
        study = self.study
        head = [f"# {study.title}", "", "{.claim}", study.claim.strip(), ""]
        if self.quick:
            head += ["(A `--quick` smoke run: not a measurement.)", ""]
        figures = " and its figures" if any(line.startswith("![") for line in self.lines) else ""
        head += [f"The command that makes this page, its summary `benchmarks/data/{study.name}.json`{figures} "
                 "(`--report` writes the page again from the summary alone):", "",
                 "```bash", f"python benchmarks/run.py {study.name}", "```", ""]
        if study.method:
            head += ["## Method", "", study.method, ""]
        tail = (["## What it does not show", "", study.caveats, ""] if study.caveats else []) + ["## Runs", ""]
        for run in data["runs"]:
            tail.append("- " + ", ".join(f"{key}: `{value}`" if key == "command" else f"{key}: {value}"
                                         for key, value in run.items() if value not in (None, "")))
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text("\n".join(head + self.lines + tail).rstrip() + "\n", encoding="utf-8")
        say(f"wrote {shown(self.path)}")


def reportStudy(study, quick, data=None):
    """Write the study's page and figures from its summary (read from its data file unless given)."""
    if data is None:
        path = dataPath(study, quick)
        if not path.exists():
            raise SystemExit(f"{study.name}: no summary at {shown(path)}; run the study first")
        data = json.loads(path.read_text(encoding="utf-8"))
    page = Page(study, data, quick)
    study.report(data["summary"], page)
    page.write(data)
    return page.path


# --- The command line ---------------------------------------------------------------------------------
def studyNames():
    return sorted(path.stem for path in STUDIES.glob("*.py") if not path.stem.startswith("_"))


def loadStudy(name):
    if str(STUDIES.parent) not in sys.path:
        sys.path.insert(0, str(STUDIES.parent))
    return importlib.import_module(f"studies.{name}").STUDY


def parseArguments(studies, argv):
    """The command line's arguments, with the options that the studies add."""
    parser = argparse.ArgumentParser(prog="python benchmarks/run.py", description=__doc__.split("\n\n")[0])
    parser.add_argument("studies", nargs="*", help="study names, or all")
    parser.add_argument("--list", action="store_true", help="list the studies and their claims")
    parser.add_argument("--quick", action="store_true",
                        help="a smoke run on the study's small grid (benchmarks/results/quick/)")
    parser.add_argument("--report", action="store_true",
                        help="only write the pages and figures again from the summaries")
    parser.add_argument("--platform", default="CPU")
    parser.add_argument("--threads", type=int, default=None, help="CPU platform threads (default: the platform's)")
    parser.add_argument("--workers", type=int, default=1, help="processes measuring jobs at once")
    options = {}
    for study in studies:
        for option, settings in study.options.items():
            options.setdefault(option, settings)
    for option, settings in options.items():
        parser.add_argument(option, **settings)
    return parser.parse_args(argv)


def main(argv=None):
    """Run the studies named on the command line (all: every one), or write their pages again."""
    argv = sys.argv[1:] if argv is None else argv
    for stream in (sys.stdout, sys.stderr):   # pages and logs hold non-ASCII text; a C locale would refuse it
        with contextlib.suppress(AttributeError, ValueError):
            stream.reconfigure(encoding="utf-8")
    names = studyNames()
    words = [word for word in argv if not word.startswith("-")]
    chosen = names if "all" in words else [word for word in words if (STUDIES/f"{word}.py").exists()]
    studies = [loadStudy(name) for name in chosen]
    args = parseArguments(studies, argv)
    if args.list:
        for name in names:
            say(f"{name}: {loadStudy(name).claim.strip()}")
        return
    unknown = [word for word in args.studies if word != "all" and not (STUDIES/f"{word}.py").exists()]
    if unknown or not studies:
        raise SystemExit(f"unknown or no study {unknown}; the studies: {', '.join(names)}")
    for study in studies:
        data = None if args.report else measureStudy(study, args, argv)
        reportStudy(study, args.quick, data)

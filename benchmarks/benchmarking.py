"""What the benchmarks share: progress and logs, the run's provenance and its results document,
CSV, plots and the statistics of time series. What the benchmarks share with the tests (water boxes,
random rotations, energy drift, the bodies' kinds, kinetic energies and degrees of freedom) is in
``tests/python/rigidtesting``, which this module puts on Python's path.

Each benchmark is a program ``python benchmarks/<name>.py``; the folder of the script is on Python's
path then, so ``import benchmarking`` finds this file.

Results documents: a full run writes ``docs/results/<name>.md`` (a quick run
``benchmarks/results/<name>.md``, which git ignores), opening with the date, commit, machine,
software and command of the run (``ResultsDocument``); what the benchmark prints while a
``ResultsDocument.capture()`` is open goes into the document too.
"""

import contextlib
import csv
import datetime
import fcntl
import hashlib
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
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir, "tests", "python"))  # rigidtesting
from rigidtesting.bodies import (bodyKind, bodyKinds, integratorBodies, kineticEnergies,  # noqa: F401
                                 rigidDegreesOfFreedom, rigidKineticEnergies)
from rigidtesting.stress import block_drift

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT/"benchmarks"/"results"     # logs, CSV and plots of every run (git ignores it)
DOCUMENTS = ROOT/"docs"/"results"         # the results documents of full runs
FIGURES = ROOT/"docs"/"figures"           # the figures those documents show

# ---------------------------------------------------------------------------------------------------
# Progress and the log

_log = None
_captured = None


def openLog(path):
    """Copy every later say() line to this file (replacing an earlier one)."""
    global _log
    closeLog()
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    _log = open(path, "w")


def closeLog():
    global _log
    if _log is not None:
        _log.close()
        _log = None


def say(text=""):
    """Print a line (flushed, so that a long run shows its progress) and copy it to the log file and
    to an open ResultsDocument.capture()."""
    print(text, flush=True)
    if _log is not None:
        _log.write(text + "\n")
        _log.flush()
    if _captured is not None:
        _captured.extend(text.split("\n"))


def stamp(text):
    """say() with the wall-clock time in front: for progress lines."""
    say(f"[{datetime.datetime.now():%H:%M:%S}] {text}")


class Progress:
    """A progress bar for one long loop: redrawn in place on a terminal, a line every 20 % otherwise
    (into the log)."""

    def __init__(self, label, total):
        self.label, self.total, self.started, self.shown = label, total, time.perf_counter(), -1
        self.terminal = sys.stdout.isatty()

    def update(self, done):
        if done <= 0:
            return
        fraction = done/self.total
        elapsed = time.perf_counter() - self.started
        left = elapsed*(1 - fraction)/fraction
        bar = "#"*int(20*fraction) + "-"*(20 - int(20*fraction))
        text = f"  {self.label} [{bar}] {100*fraction:3.0f} %, {elapsed:.0f} s, about {left:.0f} s left"
        if self.terminal:
            print("\r" + text, end="\n" if done >= self.total else "", flush=True)
        elif int(5*fraction) > self.shown:
            self.shown = int(5*fraction)
            say(text)


# ---------------------------------------------------------------------------------------------------
# Provenance

def commit():
    """The source tree's commit (short), marked when tracked files other than results differ from it."""
    try:
        head = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True).stdout.strip()
        # Results documents and figures written by earlier runs do not make the code differ.
        dirty = subprocess.run(["git", "-C", str(ROOT), "status", "--porcelain", "--untracked-files=no", "--", ".",
                                ":!docs/results", ":!docs/figures"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return head + (" (with uncommitted changes to the code)" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def processorName():
    try:
        for line in subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout.splitlines():
            if line.startswith("Model name:"):
                return line.split(":", 1)[1].strip()
    except (OSError, subprocess.CalledProcessError):
        pass
    return pyplatform.processor() or pyplatform.machine()


def machine():
    return f"{processorName()}, {pyplatform.machine()}, {os.cpu_count()} cores"


def loadAverage():
    try:
        return " ".join(Path("/proc/loadavg").read_text().split()[:3])
    except OSError:
        return "unknown"


def command():
    """The command line of this run, as a user would type it from the repository root."""
    script = Path(sys.argv[0]).resolve()
    try:
        script = script.relative_to(ROOT)
    except ValueError:
        pass
    return shlex.join(["python", str(script)] + sys.argv[1:])


def cpuProperties(platform, threads):
    """Context properties giving the CPU platform `threads` threads (none for other platforms, or for
    threads None: the platform's default)."""
    name = platform if isinstance(platform, str) else platform.getName()
    return {"Threads": str(threads)} if name == "CPU" and threads else {}


def pluginBuild():
    """When the loaded plugin libraries were built, and a hash of them (the C++ may be rebuilt between runs)."""
    folder = Path(openmmrigid.__file__).parent
    digest, newest = hashlib.sha256(), 0.0
    libraries = sorted(folder.glob("*.so")) + sorted(folder.glob("*.dylib")) + sorted(folder.glob("*.dll"))
    for library in libraries:
        digest.update(library.read_bytes())
        newest = max(newest, library.stat().st_mtime)
    if not libraries:
        return "no libraries found"
    return f"built {datetime.datetime.fromtimestamp(newest):%Y-%m-%d %H:%M}, sha256 {digest.hexdigest()[:12]}"


def header(platform=None, threads=None):
    """The run's provenance, one line each: date, commit, machine, software, platform, load, command."""
    lines = [f"date: {datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}",
             f"commit: {commit()}",
             f"machine: {machine()}",
             f"software: OpenMM {openmm.version.full_version}, openmm-rigid {openmmrigid.__version__}, "
             f"Python {pyplatform.python_version()}, numpy {np.__version__}",
             f"plugin libraries: {pluginBuild()}"]
    if platform is not None:
        lines.append(f"platform: {platform}" + (f", {threads} thread(s)" if threads else ""))
    lines += [f"load average before the run: {loadAverage()} (1, 5, 15 min)", f"command: `{command()}`"]
    return lines


class ResultsDocument:
    """The Markdown record of one run: a title, the provenance header, then sections of text,
    tables, figures and captured output; write() puts it in docs/results/<name>.md (full runs) or
    benchmarks/results/<name>.md (quick runs, not to be mistaken for results)."""

    def __init__(self, name, title, quick=False, platform=None, threads=None, about="", provenance=None):
        """provenance: the header's lines, for a document assembled from several runs (default: this
        run's header())."""
        self.name, self.quick = name, quick
        self.path = (RESULTS if quick else DOCUMENTS)/f"{name}.md"
        self.lines = [f"# {title}", "",
                      f"Written by `benchmarks/{Path(sys.argv[0]).name}`"
                      f"{' (a --quick smoke run: not a measurement)' if quick else ''}.",
                      ""]
        self.lines += [f"- {line}" for line in (provenance or header(platform, threads))] + [""]
        if about:
            self.lines += [about, ""]

    def section(self, title, text=""):
        self.lines += [f"## {title}", ""] + ([text, ""] if text else [])

    def text(self, text):
        self.lines += [text, ""]

    def table(self, columns, rows):
        """A Markdown table; numbers right-aligned."""
        self.lines += markdownTable(columns, rows) + [""]

    def figure(self, path, caption):
        self.lines += [f"![{caption}]({os.path.relpath(path, self.path.parent)})", ""]

    @contextlib.contextmanager
    def capture(self):
        """Put what say() prints inside the block into the document, as preformatted text."""
        global _captured
        previous, _captured = _captured, []
        try:
            yield
        finally:
            lines, _captured = _captured, previous
            while lines and not lines[0].strip():
                lines.pop(0)
            self.lines += ["```"] + [line.rstrip() for line in lines] + ["```", ""]

    def figurePath(self, filename):
        """Where a figure of this run goes: docs/figures for a full run, benchmarks/results for a quick one."""
        return (RESULTS if self.quick else FIGURES)/filename

    def write(self):
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self.path.write_text("\n".join(self.lines).rstrip() + "\n")
        say(f"wrote {self.path.relative_to(ROOT)}")
        return self.path


def openRun(name, title, args, script=None):
    """The start of a benchmark's main(): its log in benchmarks/results/<name>.log, the platform
    args.platform with args.threads CPU threads (None: the platform's default) and the ResultsDocument
    <name> titled title (a quick run's in benchmarks/results/), whose method is the docstring of the script
    benchmarks/<script>.py (script: name unless given).
    Returns (platform, Context properties, document)."""
    openLog(RESULTS/f"{name}.log")
    platform = openmm.Platform.getPlatformByName(args.platform)
    document = ResultsDocument(name, title, quick=args.quick, platform=args.platform, threads=args.threads,
                               about=f"Method: the docstring of `benchmarks/{script or name}.py`.")
    return platform, cpuProperties(platform, args.threads), document


def markdownTable(columns, rows):
    """Lines of a Markdown table: columns are headings, rows lists of cells (numbers formatted by
    the caller); a column whose cells are all numbers is right-aligned."""
    def numeric(cell):
        try:
            float(str(cell).replace("**", "").replace("x", "").split()[0])
            return True
        except (ValueError, IndexError):
            return False
    align = ["---:" if rows and all(numeric(row[i]) or row[i] in ("", None) for row in rows) else "---"
             for i in range(len(columns))]
    return (["| " + " | ".join(columns) + " |", "| " + " | ".join(align) + " |"]
            + ["| " + " | ".join("" if cell is None else str(cell) for cell in row) + " |" for row in rows])


# ---------------------------------------------------------------------------------------------------
# Files and plots

def writeCsv(path, rows):
    """Rows (dicts with the same keys) as CSV, floats to 6 significant digits."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as stream:
        writer = csv.DictWriter(stream, fieldnames=list(rows[0]))
        writer.writeheader()
        for row in rows:
            writer.writerow({key: (f"{value:.6g}" if isinstance(value, float) else value) for key, value in row.items()})
    say(f"wrote {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")


def pyplot():
    """matplotlib.pyplot with the file-only Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def saveFigure(figure, path):
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    figure.tight_layout()
    figure.savefig(path, dpi=120)
    pyplot().close(figure)
    say(f"wrote {path.relative_to(ROOT) if path.is_relative_to(ROOT) else path}")


# ---------------------------------------------------------------------------------------------------
# Statistics of time series

def blockMean(values, blocks=(5, 10)):
    """Mean of a time series (along the first axis) and its standard error from block means: the
    largest of the estimates with each number of blocks given (an int: that one), each from the
    first multiple of that many samples. Block means are nearly independent where a block outlasts
    the correlation time, so the larger estimate is the safer one."""
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


def molecularKineticEnergies(velocities, masses, molecules):
    """Translational kinetic energy of the molecules' centres of mass and the rest (kJ/mol): for rigid
    molecules (velocities that are rigid motion, as constraints or a rigid-body integrator leave them)
    the rest is the rotational kinetic energy. velocities (particles x 3, nm/ps), masses (particles,
    amu), molecules (molecules x atoms per molecule: indices of their massive particles)."""
    m = masses[molecules]                                       # (N, k)
    v = velocities[molecules]                                   # (N, k, 3)
    centre = np.einsum("na,nak->nk", m, v)/m.sum(axis=1)[:, None]
    translational = 0.5*np.sum(m.sum(axis=1)*np.sum(centre**2, axis=1))
    total = 0.5*np.sum(m[:, :, None]*v**2)
    return translational, total - translational


def slopeError(times, values, blocks=10):
    """Standard error of the slope of a time series, from the line through the means of `blocks`
    consecutive blocks (rigidtesting.stress.block_drift; NaN with fewer than two samples a block)."""
    if len(times)//blocks*blocks < 2*blocks:
        return float("nan")
    return float(block_drift(times, values, blocks)[1])


def radialDistribution(frames, boxes, largest, width):
    """g(r) of each frame of positions (frames x atoms x 3, nm) in its rectangular box (frames x 3,
    the edges, nm), by minimum image, on bins of `width` up to `largest` nm: (bin centres, frames x bins)."""
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


def nsPerDay(stepFs, secondsPerStep):
    return stepFs*1e-6*86400/secondsPerStep


# ---------------------------------------------------------------------------------------------------
# Timing: integrators side by side

def _secondsPerStep(integrator, target):
    """A rough cost per step: blocks of 1, 4, 16, ... steps until one takes a tenth of the target
    (after two untimed steps: a Context's first step also sets things up)."""
    integrator.step(2)
    steps = 1
    while True:
        start = time.perf_counter()
        integrator.step(steps)
        elapsed = time.perf_counter() - start
        if elapsed >= 0.1*target or steps >= 1 << 16:
            return elapsed/steps
        steps *= 4


def blockSteps(integrator, fixed, target, minimum):
    """Steps per timed block: `fixed` if given, else enough for `target` seconds (at least `minimum`)."""
    if fixed:
        return fixed
    return max(minimum, int(round(target/_secondsPerStep(integrator, target))))


class TimingFailure(RuntimeError):
    """An integrator that failed (an unstable step) while it was timed: which one (its label) and why."""

    def __init__(self, label, error):
        super().__init__(f"{label}: {error}")
        self.label, self.error = label, error


def _timedStep(label, integrator, steps):
    try:
        integrator.step(steps)
    except openmm.OpenMMException as error:
        raise TimingFailure(label, error) from error


def timeInterleaved(integrators, steps, repetitions):
    """Warm up each integrator with one block, then time `repetitions` blocks of `steps` each,
    interleaved (one block of each in turn, so that all see the same load).

    integrators: {label: integrator}, each bound to its own Context. Returns ({label: [wall s/step]},
    {label: [CPU s/step]}): the process's CPU time, which other processes on a shared machine stretch
    less than the wall time. An integrator whose step fails raises TimingFailure, which names it.
    """
    for label, integrator in integrators.items():
        _timedStep(label, integrator, steps)
    wall, cpu = {label: [] for label in integrators}, {label: [] for label in integrators}
    for _ in range(repetitions):
        for label, integrator in integrators.items():
            startWall, startCpu = time.perf_counter(), time.process_time()
            _timedStep(label, integrator, steps)
            wall[label].append((time.perf_counter() - startWall)/steps)
            cpu[label].append((time.process_time() - startCpu)/steps)
    return wall, cpu


# The length of a window of the rigid integrators' accuracy check, in ps: it mirrors AccuracyCheck::WindowTime
# in openmmapi/include/internal/AccuracyCheck.h (tests/python/test_benchmarks.py compares them).
CHECK_WINDOW_PS = 2.0


def medianRange(samples, scale=1.0):
    """(median, min, max) of the samples times `scale`."""
    values = [scale*value for value in samples]
    return float(np.median(values)), min(values), max(values)


def principalKineticEnergies(positions, velocities, masses, molecules):
    """Translational kinetic energy of rigid molecules' centres of mass and, summed over the
    molecules, the rotational kinetic energy about each one's principal axes in the order of
    increasing moment, L_k^2/(2 I_k) (kJ/mol: a float and an array of 3). positions (nm) and
    velocities (nm/ps) as particles x 3, masses (amu), molecules (molecules x atoms: indices of their
    massive particles, whole, not wrapped across the box)."""
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


# ---------------------------------------------------------------------------------------------------
# Rigid bodies: what the integrators do not report (their kinds, kinetic-energy split and degrees of
# freedom: rigidtesting.bodies, imported above, computes them from the State)

#: Force evaluations per step of each splitting of RigidBodyIntegrator.setSplitting().
FORCE_EVALUATIONS = {openmmrigid.RigidBodyIntegrator.Verlet: 1, openmmrigid.RigidBodyIntegrator.Omelyan2: 2,
                     openmmrigid.RigidBodyIntegrator.Yoshida4: 3, openmmrigid.RigidBodyIntegrator.Omelyan4: 4}


def forceEvaluations(integrator):
    """Force evaluations per step of a RigidBodyIntegrator (or RigidBodyBussiIntegrator): those of its splitting."""
    return FORCE_EVALUATIONS[integrator.getSplitting()]


def accuracyWarnings(caught):
    """The messages of the openmmrigid.AccuracyWarning among warnings recorded with
    warnings.catch_warnings(record=True) (the accuracy check issues one, once, from within the step
    that fired; make it seen each time with warnings.simplefilter("always", openmmrigid.AccuracyWarning))."""
    return [str(w.message) for w in caught if issubclass(w.category, openmmrigid.AccuracyWarning)]


# ---------------------------------------------------------------------------------------------------
# Samples kept between runs

class SampleStore:
    """Independent samples of a long computation, kept between runs, sessions and machines, so that a
    benchmark too long for one sitting grows toward its target a part at a time and several worker
    processes add to it at once.

    The computation is a set of jobs (string keys); a job's samples are numbered (a sample index
    names its input, e.g. an equilibrium frame or a start, so a sample is never computed twice) and
    each is a list of numbers or a dict. A job fails at a sample (an unstable run): it then takes no more samples, and
    jobs that name it as a blocker are not run either. A worker claims one job at a time, the one with
    the fewest samples below the target (earliest in the given order on ties), so every job grows
    together and an interrupted run leaves an even table. A claim lapses with its process, and a
    claim made on another machine is void (a store travels between machines in git, not shared).

    One JSON file, `store.json` in `folder`, read and written whole under an exclusive lock (fcntl) on
    `store.lock`, replaced atomically; `setup` (a dict of what makes samples comparable) is written
    by the first run and must match in every later one."""

    def __init__(self, folder, setup=None):
        """setup None: open the store as it is (a worker, a report)."""
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        self.path, self.lockPath = self.folder/"store.json", self.folder/"store.lock"
        if setup is None:
            return
        setup = json.loads(json.dumps(setup))  # as it reads back
        with self._locked() as data:
            if data["setup"] is None:
                data["setup"] = setup
            elif data["setup"] != setup:
                raise ValueError(f"the samples in {self.folder} were made with {data['setup']}, not {setup}: "
                                 "choose another folder for this set-up")

    @contextlib.contextmanager
    def _locked(self, write=True):
        with open(self.lockPath, "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            try:
                if self.path.exists():
                    data = json.loads(self.path.read_text())
                else:
                    data = {"setup": None, "jobs": {}, "claims": {}, "runs": []}
                yield data
                if write:
                    temporary = self.path.with_suffix(f".{os.getpid()}.tmp")
                    temporary.write_text(json.dumps(data, indent=1))
                    os.replace(temporary, self.path)
            finally:
                fcntl.flock(lock, fcntl.LOCK_UN)

    @staticmethod
    def _job(data, key):
        return data["jobs"].setdefault(key, {"samples": {}, "failed": None, "flags": {}})

    def read(self):
        """The whole store as a dict: setup, jobs ({key: {samples: {index: values}, failed, flags}}),
        claims and runs."""
        with self._locked(write=False) as data:
            return data

    def samples(self, key):
        """A job's samples, in index order: [(index, values)]."""
        job = self.read()["jobs"].get(key, {"samples": {}})
        return sorted(((int(index), values) for index, values in job["samples"].items()))

    @staticmethod
    def _live(claim):
        if claim["host"] != socket.gethostname():
            return False
        try:
            os.kill(claim["pid"], 0)
        except ProcessLookupError:
            return False
        except PermissionError:
            return True
        return True

    @staticmethod
    def blocked(data, key, blockers):
        """Whether one of the job's blockers (keys) has failed."""
        return any(data["jobs"].get(other, {}).get("failed") is not None for other in blockers)

    def claim(self, keys, target, blockers=lambda key: ()):
        """Claim the next job for this process: of `keys` (in order), those neither failed, blocked
        (blockers(key): the keys whose failure stops it) nor claimed by a live worker, with fewer than
        `target` samples, the one with the fewest. Returns (key, the missing indices below target, in
        order) or None when nothing is left."""
        now = time.time()
        with self._locked() as data:
            claims = data["claims"]
            for key in [key for key, claim in claims.items() if not self._live(claim)]:
                del claims[key]
            best = None
            for order, key in enumerate(keys):
                job = data["jobs"].get(key, {"samples": {}, "failed": None})
                if key in claims or job["failed"] is not None or self.blocked(data, key, blockers(key)):
                    continue
                count = sum(1 for index in job["samples"] if int(index) < target)
                if count < target and (best is None or count < best[0]):
                    best = (count, order, key)
            if best is None:
                return None
            key = best[2]
            claims[key] = {"host": socket.gethostname(), "pid": os.getpid(), "since": now}
            have = self._job(data, key)["samples"]
            return key, [index for index in range(target) if str(index) not in have]

    def add(self, key, index, values, **flags):
        """Record a sample: a list of numbers, or a dict (kept as JSON gives it back); flags (booleans)
        are or-ed into the job's (e.g. whether a check fired)."""
        with self._locked() as data:
            job = self._job(data, key)
            job["samples"][str(index)] = json.loads(json.dumps(values)) if isinstance(values, dict) else [float(v) for v in values]
            for name, value in flags.items():
                job["flags"][name] = bool(job["flags"].get(name, False) or value)

    def fail(self, key, index, reason):
        with self._locked() as data:
            self._job(data, key)["failed"] = {"sample": int(index), "reason": str(reason)}

    def release(self, key):
        with self._locked() as data:
            data["claims"].pop(key, None)

    def note(self, key, value):
        """Keep a value beside the samples (e.g. a timing), under `key` in the store's "notes"."""
        with self._locked() as data:
            data.setdefault("notes", {})[key] = value

    def total(self):
        """How many samples the store holds, over all jobs."""
        return sum(len(job["samples"]) for job in self.read()["jobs"].values())

    def addRun(self, record):
        """Record what a run added (its provenance and counts) in the store's "runs"."""
        with self._locked() as data:
            data["runs"].append(record)

    def recordRun(self, added, seconds, platform, threads, workers):
        """addRun() for this run: date, commit, machine, platform, threads and workers, samples added,
        wall seconds and the command."""
        self.addRun(dict(date=f"{datetime.datetime.now().astimezone():%Y-%m-%d %H:%M %Z}", commit=commit(), machine=machine(),
                         platform=platform, threads=threads, workers=workers, added=added, seconds=seconds, command=command()))

    @staticmethod
    def describeRun(run):
        """One line of a run record (records of earlier runs may lack fields)."""
        where = run.get("platform", "")
        if run.get("threads"):
            where += f", {run['threads']} thread(s)"
        if run.get("workers", 1) > 1:
            where += f" x {run['workers']} workers"
        minutes = f" in {run['seconds']/60:.0f} min" if run.get("seconds") else ""
        return f"{run['date']}, commit {run['commit']}, {where.strip(', ')}: {run['added']} added{minutes}, `{run['command']}`"


def runWorkers(task, arguments, workers):
    """task(*arguments) in this process (workers 1), or in `workers` processes at once, each started
    afresh (spawned: its own OpenMM, none of this process's threads)."""
    if workers == 1:
        task(*arguments)
        return
    spawn = multiprocessing.get_context("spawn")
    processes = [spawn.Process(target=task, args=arguments) for _ in range(workers)]
    for process in processes:
        process.start()
    for process in processes:
        process.join()

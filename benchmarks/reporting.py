"""What the benchmarks print: each line to stdout and to the run's log file, both flushed at once so
that a long run shows its progress (and leaves a record if it is stopped)."""

import datetime

_log = None


def openLog(path):
    """Copy every later line to this file (replacing an earlier one)."""
    global _log
    if _log is not None:
        _log.close()
    _log = open(path, "w")


def closeLog():
    global _log
    if _log is not None:
        _log.close()
        _log = None


def say(text=""):
    """Print a line and copy it to the log file."""
    print(text, flush=True)
    if _log is not None:
        _log.write(text + "\n")
        _log.flush()


def stamp(text):
    """say() with the wall-clock time in front: for progress lines."""
    say(f"[{datetime.datetime.now():%H:%M:%S}] {text}")

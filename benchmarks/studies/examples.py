"""What each example program prints with its defaults: its output, kept so the manual shows it."""

import importlib.util
import shutil
import subprocess
import sys

from harness import ROOT, Study, commit, say

# Each example with its defaults, and with arguments small enough for a smoke run.
EXAMPLES = {
    "rigid_water.py": ["--molecules", "216", "--time", "0.1", "--equilibrate", "0.1"],
    "solvated_peptide.py": ["--time", "0.1", "--equilibrate", "0.1"],
    "co2_box.py": ["--molecules", "128", "--equilibrate", "0.2", "--time", "0.2"],
    "benzene.py": ["--molecules", "64", "--equilibrate", "0.2", "--time", "0.2"],
    "free_rotor.py": [],
    "rigid_solute.py": ["--time", "0.1"],
    "replica_exchange.py": ["--iterations", "2", "--steps", "10"],
    "large_step.py": ["--molecules", "216", "--time", "0.2", "--discard", "0.1", "--equilibrate", "0.1"],
}


def run(env):
    """Run every example (its defaults; the smoke arguments in a quick run) and keep what it prints; the
    replica exchange also under MPI (two processes) where mpirun and mpi4py are installed."""
    commands = [[sys.executable, f"examples/{name}"] + (quick if env.quick else []) for name, quick in EXAMPLES.items()]
    if shutil.which("mpirun") and importlib.util.find_spec("mpi4py") and not env.quick:
        commands.append(["mpirun", "-np", "2", sys.executable, "examples/replica_exchange.py", "--threads", "1"])
    outputs = []
    for command in commands:
        shownCommand = " ".join(word if word != sys.executable else "python" for word in command)
        say(f"running {shownCommand}")
        done = subprocess.run(command, cwd=ROOT, capture_output=True, text=True, timeout=3600)
        if done.returncode != 0:
            raise RuntimeError(f"{shownCommand} failed ({done.returncode}):\n{done.stderr[-2000:]}")
        outputs.append({"command": shownCommand, "commit": commit(), "output": done.stdout.rstrip()})
    return outputs


def report(outputs, page):
    for entry in outputs:
        page.section(f"`{entry['command']}`", f"commit {entry['commit']}" + (f"; {entry['note']}" if entry.get("note") else "") + ":")
        page.text("```\n" + entry["output"] + "\n```")


STUDY = Study(
    "examples", "What the examples print",
    claim="Each example runs as documented, and this is what it printed, with the commit it ran at.",
    method="""One run of each program in `examples/` with its defaults, CPU platform (its default threads), on the
project's 2-core build machine while other work shared it: the ms/step figures are noisy; the cost ratios are
medians over rounds run side by side.""",
    caveats="""An example is a demonstration, not a measurement: its short runs show what a user sees, and the
studies on the other pages make the claims.""",
    run=run, report=report)

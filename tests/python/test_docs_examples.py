"""Every ```python block of docs/getting-started.md and docs/guide/*.md runs (issue 42).

Each block is one test, named by its page and line. It runs as the page shows it, in a temporary
folder (the same one for every block of a session) that holds ``input.pdb``, a small box of water,
for the examples that read "your system" from a file.

How a block runs is said by an HTML comment right before it (blank lines may come between), which
the rendered page does not show:

    <!-- docs-test: OPTION; OPTION; ... -->

OPTION is one of

``standalone``
    A fresh, empty namespace (also the default for a block without a comment).
``setup=NAME``
    A fresh namespace that holds what the hidden preamble NAME (``SETUPS`` below) made: the imports of an
    openmm.app script (``sys``, ``openmm``, ``app``, ``unit``, ``openmmrigid``) and

    - ``water``: ``forcefield`` (amber14 with TIP3P-FB), ``topology``, ``positions`` (minimized) and
      ``system`` (PME, ``HBonds``, rigid water) of about 300 waters;
    - ``water-simulation``: the same, and ``integrator`` (``RigidBodyLangevinIntegrator``, 300 K, 1/ps,
      2 fs) and ``simulation`` (CPU platform) with the positions and velocities set;
    - ``peptide``: ``forcefield``, ``topology``, ``positions`` (minimized) and ``system`` (PME,
      ``HBonds``, rigid water) of alanine dipeptide (ACE-ALA-NME) in about 280 waters.
``continue``
    The namespace the previous block of the page left (that block, and the chain before it, run
    first in this test, so each test runs alone too).
``requires=MODULE``
    Skipped, with the reason, where MODULE cannot be imported (openmmtools).
``requires-platform=NAME``
    Skipped, with the reason, where the OpenMM platform NAME is absent or lacks the rigid-body
    kernels (CUDA here: no GPU).
``replace=OLD -> NEW``
    Replace the text OLD by NEW before running (to shorten a long run; may be repeated). OLD must
    occur in the block.
``note=TEXT``
    A note to the reader of the Markdown source; ignored.

So that the whole file takes seconds, ``app.Simulation.step`` takes at most ``STEP_CAP`` steps per
call and ``app.Simulation.minimizeEnergy`` at most ``MINIMIZE_CAP`` iterations (the preambles'
positions are minimized already); nothing else in a block is changed. A comment that is not
followed by a ```python block, or an option not listed here, fails the test of the page.

    POCL_CACHE_DIR=$PWD/build/pocl-cache .venv/bin/python -m pytest tests/python/test_docs_examples.py -q
"""

import copy
import importlib.util
import pathlib
import re
import sys
import warnings

import openmm
import openmm.app as app
import openmm.unit as unit
import pytest

import openmmrigid

ROOT = pathlib.Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
PAGES = [DOCS / "getting-started.md"] + sorted((DOCS / "guide").glob("*.md"))
PEPTIDE_PDB = ROOT / "examples" / "data" / "alanine-dipeptide.pdb"

STEP_CAP = 20
MINIMIZE_CAP = 50

_MARKER = re.compile(r"^\s*<!--\s*docs-test:(.*?)-->\s*$")
_FENCE = re.compile(r"^(\s*)(`{3,}|~{3,})\s*([^`\s]*)")
_OPTIONS = {"standalone", "setup", "continue", "requires", "requires-platform", "replace", "note"}


# ------------------------------------------------------------------------------------------------
# The blocks
# ------------------------------------------------------------------------------------------------

class Block:
    """A ```python block of a page: its code, the line its code starts on, and its options."""

    def __init__(self, page, line, code, options):
        self.page, self.line, self.code, self.options = page, line, code, options

    @property
    def name(self):
        return f"{self.page.relative_to(DOCS)}:{self.line}"

    def values(self, key):
        return [value for option, value in self.options if option == key]


def parseOptions(text, where):
    options = []
    for item in (part.strip() for part in text.split(";")):
        if not item:
            continue
        key, _, value = item.partition("=")
        key, value = key.strip(), value.strip()
        if key not in _OPTIONS:
            raise ValueError(f"{where}: unknown docs-test option {key!r} (known: {', '.join(sorted(_OPTIONS))})")
        if key == "replace" and "->" not in value:
            raise ValueError(f"{where}: replace needs 'OLD -> NEW', got {value!r}")
        options.append((key, value))
    return options


def parsePage(page):
    """The python blocks of a Markdown page, in order, with the options of the comment before each."""
    lines = page.read_text().splitlines()
    blocks, pending, index = [], None, 0
    while index < len(lines):
        line = lines[index]
        marker = _MARKER.match(line)
        fence = _FENCE.match(line)
        if marker:
            if pending is not None:
                raise ValueError(f"{page.name}:{pending[0]}: docs-test comment not followed by a ```python block")
            pending = (index + 1, parseOptions(marker.group(1), f"{page.name}:{index + 1}"))
        elif fence:
            indent, ticks, info = fence.groups()
            end = index + 1
            while end < len(lines) and not re.match(rf"^\s*{re.escape(ticks[0])}{{{len(ticks)},}}\s*$", lines[end]):
                end += 1
            if info == "python":
                body = [text[len(indent):] if text.startswith(indent) else text.lstrip() for text in lines[index + 1:end]]
                blocks.append(Block(page, index + 2, "\n".join(body) + "\n", pending[1] if pending else []))
            elif pending is not None:
                raise ValueError(f"{page.name}:{pending[0]}: docs-test comment before a ```{info} block, not ```python")
            pending = None
            index = end
        elif line.strip() and pending is not None:
            raise ValueError(f"{page.name}:{pending[0]}: docs-test comment not followed by a ```python block")
        index += 1
    if pending is not None:
        raise ValueError(f"{page.name}:{pending[0]}: docs-test comment at the end of the page")
    return blocks


def collect():
    blocks, errors = [], []
    for page in PAGES:
        try:
            blocks.extend(parsePage(page))
        except ValueError as error:
            errors.append(str(error))
    return blocks, errors


BLOCKS, PARSE_ERRORS = collect()


# ------------------------------------------------------------------------------------------------
# The hidden preambles
# ------------------------------------------------------------------------------------------------

def _minimized(topology, system, positions):
    context = openmm.Context(copy.deepcopy(system), openmm.VerletIntegrator(0.001),
                             openmm.Platform.getPlatformByName("CPU"))
    context.setPositions(positions)
    openmm.LocalEnergyMinimizer.minimize(context, 10.0, 500)
    return context.getState(getPositions=True).getPositions()


def _build(topology, positions, forcefield):
    system = forcefield.createSystem(topology, nonbondedMethod=app.PME, constraints=app.HBonds, rigidWater=True)
    return {"forcefield": forcefield, "topology": topology, "system": system,
            "positions": _minimized(topology, system, positions)}


@pytest.fixture(scope="session")
def workdir(tmp_path_factory):
    """The folder every block runs in, with input.pdb (the water box) in it."""
    return tmp_path_factory.mktemp("docs-examples")


@pytest.fixture(scope="session")
def systems(workdir):
    """The preambles' systems, built once: name -> dict of names."""
    forcefield = app.ForceField("amber14-all.xml", "amber14/tip3pfb.xml")
    water = app.Modeller(app.Topology(), [])
    water.addSolvent(forcefield, boxSize=openmm.Vec3(2.1, 2.1, 2.1) * unit.nanometer)
    built = {"water": _build(water.topology, water.positions, forcefield)}
    with open(workdir / "input.pdb", "w") as file:
        app.PDBFile.writeFile(water.topology, built["water"]["positions"], file)
    pdb = app.PDBFile(str(PEPTIDE_PDB))
    peptide = app.Modeller(pdb.topology, pdb.positions)
    peptide.addSolvent(forcefield, boxSize=openmm.Vec3(2.1, 2.1, 2.1) * unit.nanometer)
    built["peptide"] = _build(peptide.topology, peptide.positions, forcefield)
    return built


def _imports():
    return {"__name__": "__docs_example__", "sys": sys, "openmm": openmm, "app": app, "unit": unit,
            "openmmrigid": openmmrigid}


def _fromSystem(built):
    namespace = _imports()
    namespace.update(built)
    namespace["system"] = copy.deepcopy(built["system"])
    namespace["positions"] = list(built["positions"])
    return namespace


def _waterSimulation(systems):
    namespace = _fromSystem(systems["water"])
    integrator = openmmrigid.RigidBodyLangevinIntegrator(300 * unit.kelvin, 1 / unit.picosecond, 2 * unit.femtoseconds)
    simulation = app.Simulation(namespace["topology"], namespace["system"], integrator,
                                openmm.Platform.getPlatformByName("CPU"))
    simulation.context.setPositions(namespace["positions"])
    simulation.context.setVelocitiesToTemperature(300 * unit.kelvin)
    namespace.update(integrator=integrator, simulation=simulation)
    return namespace


SETUPS = {
    "water": lambda systems: _fromSystem(systems["water"]),
    "water-simulation": _waterSimulation,
    "peptide": lambda systems: _fromSystem(systems["peptide"]),
}


# ------------------------------------------------------------------------------------------------
# Running a block
# ------------------------------------------------------------------------------------------------

@pytest.fixture
def capped(monkeypatch):
    """Simulation.step and minimizeEnergy shortened, so that the examples run in seconds."""
    step, minimize = app.Simulation.step, app.Simulation.minimizeEnergy

    def cappedStep(self, steps):
        return step(self, min(int(steps), STEP_CAP))

    def cappedMinimize(self, tolerance=10 * unit.kilojoules_per_mole / unit.nanometer, maxIterations=0, reporter=None):
        iterations = MINIMIZE_CAP if maxIterations <= 0 else min(maxIterations, MINIMIZE_CAP)
        return minimize(self, tolerance, iterations, reporter)

    monkeypatch.setattr(app.Simulation, "step", cappedStep)
    monkeypatch.setattr(app.Simulation, "minimizeEnergy", cappedMinimize)


def chain(block):
    """The blocks to run for this one: the blocks it continues, then itself."""
    blocks = [block]
    while blocks[0].values("continue"):
        page = [other for other in BLOCKS if other.page == blocks[0].page]
        position = page.index(blocks[0])
        if position == 0:
            raise ValueError(f"{blocks[0].name}: 'continue' on the first block of its page")
        blocks.insert(0, page[position - 1])
    return blocks


def skipReason(block):
    for module in block.values("requires"):
        if importlib.util.find_spec(module) is None:
            return f"{module} is not installed"
    for name in block.values("requires-platform"):
        try:
            if not openmm.Platform.getPlatformByName(name).supportsKernels(["IntegrateRigidBodyStep"]):
                return f"the {name} platform has no rigid-body kernels here"
        except Exception:
            return f"no {name} platform here (no such GPU or driver)"
    return None


def source(block):
    code = block.code
    for replacement in block.values("replace"):
        old, _, new = (part.strip() for part in replacement.partition("->"))
        if old not in code:
            raise ValueError(f"{block.name}: replace: {old!r} does not occur in the block")
        code = code.replace(old, new)
    # Line numbers in tracebacks are the page's.
    return compile("\n" * (block.line - 1) + code, str(block.page), "exec")


def run(blocks, systems):
    first = blocks[0]
    setups = first.values("setup")
    namespace = SETUPS[setups[0]](systems) if setups else _imports()
    for block in blocks:
        exec(source(block), namespace)
    return namespace


def test_pages_parse():
    assert not PARSE_ERRORS, "\n".join(PARSE_ERRORS)
    names = {page.name for page in PAGES}
    assert {"getting-started.md", "index.md", "bodies.md"} <= names
    assert any(block.page.name == "getting-started.md" for block in BLOCKS)


@pytest.mark.parametrize("block", BLOCKS, ids=[block.name for block in BLOCKS])
def test_example_runs(block, systems, workdir, capped, monkeypatch):
    for setup in block.values("setup"):
        assert setup in SETUPS, f"{block.name}: unknown setup {setup!r} (known: {', '.join(SETUPS)})"
    blocks = chain(block)
    reasons = [reason for reason in map(skipReason, blocks) if reason]
    if reasons:
        pytest.skip(reasons[0])
    monkeypatch.chdir(workdir)
    with warnings.catch_warnings():
        run(blocks, systems)


def test_readme_example_is_the_tested_one():
    """README.md's first run is getting-started.md's, which test_example_runs runs: they must not drift apart."""
    readme = parsePage(ROOT / "README.md")
    first = next(block for block in BLOCKS if block.page.name == "getting-started.md" and block.values("standalone"))
    assert readme and readme[0].code == first.code

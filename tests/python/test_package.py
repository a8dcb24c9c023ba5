"""The package as a Python citizen (issue 41):

- step() releases the GIL: another Python thread runs while the integrator steps;
- importing openmmrigid changes nothing in openmm (no attribute of the module or of any of its classes,
  XmlSerializer, Context and Platform included) but the one wrap it makes on purpose,
  CompoundIntegrator.getIntegrator (so that tools walking a compound, openmmtools' ThermodynamicState,
  see our heat baths), and imports neither openmm.app nor the tests' helpers; what needs openmm.app
  (the reporter, the topology helpers) is imported on first use;
- the installed package holds no test or benchmark code (rigidtesting lives in tests/python).
"""

import ast
import importlib.metadata
import importlib.util
import math
import os
import pathlib
import subprocess
import sys
import textwrap
import threading
import time

import numpy as np
import openmm
import pytest

import openmmrigid
from openmmrigid import RigidBodyIntegrator, RigidBodyLangevinIntegrator

TESTS = pathlib.Path(__file__).resolve().parent


# ------------------------------------------------------------------------------------------------
# The GIL
# ------------------------------------------------------------------------------------------------

def water_lattice(count=216, spacing=0.31):
    """count TIP3P waters on a cubic lattice, rigid by constraints, PME 0.9 nm: a system whose steps
    take a measurable time on the Reference platform. (System, positions in nm)."""
    side = math.ceil(count ** (1 / 3))
    edge = side * spacing
    system = openmm.System()
    system.setDefaultPeriodicBoxVectors(openmm.Vec3(edge, 0, 0), openmm.Vec3(0, edge, 0), openmm.Vec3(0, 0, edge))
    nonbonded = openmm.NonbondedForce()
    nonbonded.setNonbondedMethod(openmm.NonbondedForce.PME)
    nonbonded.setCutoffDistance(0.9)
    half = math.sqrt(0.09572**2 - (0.15139 / 2)**2)
    shape = np.array([[0.0, 0.0, 0.0], [0.15139 / 2, half, 0.0], [-0.15139 / 2, half, 0.0]])
    positions = []
    for n in range(count):
        site = spacing * (np.array([n % side, (n // side) % side, n // side**2]) + 0.25)
        first = system.getNumParticles()
        for mass, charge, sigma, epsilon in ((15.999, -0.834, 0.315061, 0.636386), (1.008, 0.417, 1.0, 0.0),
                                             (1.008, 0.417, 1.0, 0.0)):
            system.addParticle(mass)
            nonbonded.addParticle(charge, sigma, epsilon)
        positions.extend(site + shape)
        for i, j in ((0, 1), (0, 2), (1, 2)):
            nonbonded.addException(first + i, first + j, 0.0, 1.0, 0.0)
        system.addConstraint(first, first + 1, 0.09572)
        system.addConstraint(first, first + 2, 0.09572)
        system.addConstraint(first + 1, first + 2, 0.15139)
    system.addForce(nonbonded)
    return system, np.array(positions)


def ticks_while(action):
    """(ticks, seconds): how many times a Python thread that counts in a loop with time.sleep(0.001)
    counted while action() ran in this thread, and how long action() took."""
    ticks = [0]
    stop = threading.Event()
    started = threading.Event()

    def count():
        started.set()
        while not stop.is_set():
            ticks[0] += 1
            time.sleep(0.001)

    thread = threading.Thread(target=count, daemon=True)
    thread.start()
    started.wait()
    try:
        first = ticks[0]
        begin = time.perf_counter()
        action()
        seconds = time.perf_counter() - begin
        counted = ticks[0] - first
    finally:
        stop.set()
        thread.join()
    return counted, seconds


@pytest.mark.parametrize("integratorClass", [RigidBodyLangevinIntegrator, RigidBodyIntegrator])
def test_step_releases_the_gil(integratorClass):
    """While step(n) runs for about 0.6 s on the Reference platform (216 PME waters), a Python thread
    counting with time.sleep(0.001) keeps counting: at least 30 % of what it counts during a time.sleep
    as long, and at least 100 times. A step that held the GIL would let it count once or twice."""
    system, positions = water_lattice()
    integrator = (RigidBodyIntegrator(0.001) if integratorClass is RigidBodyIntegrator
                  else RigidBodyLangevinIntegrator(300.0, 1.0, 0.001))
    context = openmm.Context(system, integrator, openmm.Platform.getPlatformByName("Reference"))
    context.setPositions(positions)
    context.setVelocitiesToTemperature(300.0, 1)
    begin = time.perf_counter()
    integrator.step(3)
    perStep = (time.perf_counter() - begin) / 3
    steps = max(3, math.ceil(0.6 / perStep))
    stepping, seconds = ticks_while(lambda: integrator.step(steps))
    sleeping, _ = ticks_while(lambda: time.sleep(seconds))
    assert context.getStepCount() == 3 + steps
    print(f"{integratorClass.__name__}: {steps} steps in {seconds:.2f} s; the thread counted {stepping} times, "
          f"{sleeping} while sleeping as long")
    assert seconds > 0.3, f"step({steps}) took {seconds:.2f} s: too short to tell"
    assert stepping >= 100 and stepping >= 0.3 * sleeping, (stepping, sleeping, seconds)


# ------------------------------------------------------------------------------------------------
# openmm is not patched; openmm.app and the tests' helpers are not imported
# ------------------------------------------------------------------------------------------------

IMPORT_CHECK = textwrap.dedent("""
    import inspect
    import json
    import sys

    import openmm
    import openmm.openmm

    def snapshot():
        found = {}
        for module in (openmm, openmm.openmm, openmm.unit):
            for name, value in list(vars(module).items()):
                found[(module.__name__, name)] = value
                if inspect.isclass(value):
                    for member, item in list(vars(value).items()):
                        found[(module.__name__, name, member)] = item
        return found

    appBefore = "openmm.app" in sys.modules
    before = snapshot()
    import openmmrigid
    after = snapshot()
    originalGetIntegrator = before[("openmm", "CompoundIntegrator", "getIntegrator")]
    wrapped = openmm.CompoundIntegrator.getIntegrator
    result = {
        "wrapKeepsOriginal": getattr(wrapped, "_openmmrigidOriginal", None) is originalGetIntegrator,
        "wrapIsOurs": wrapped.__code__.co_filename.replace("\\\\", "/").endswith("openmmrigid/integrator.py"),
        "appBefore": appBefore,
        "added": sorted(".".join(key) for key in set(after) - set(before)),
        "removed": sorted(".".join(key) for key in set(before) - set(after)),
        "replaced": sorted(".".join(key) for key in set(before) & set(after) if after[key] is not before[key]),
        "classes": sum(1 for key in before if len(key) == 2 and inspect.isclass(before[key])),
        "entries": len(before),
        "appAfterImport": "openmm.app" in sys.modules,
        "rigidtestingAfterImport": "rigidtesting" in sys.modules,
        "rigidtestingImportable": __import__("importlib.util").util.find_spec("rigidtesting") is not None,
        "loaded": sorted(name for name in sys.modules if name.split(".")[0] in ("openmmrigid", "rigidtesting")),
    }
    # The lazy names resolve on first use (and only then import openmm.app).
    reporter = openmmrigid.RigidStateDataReporter
    hydrogenGroups = openmmrigid.rigidHydrogenGroups
    import openmm.app
    result["reporterIsAStateDataReporter"] = issubclass(reporter, openmm.app.StateDataReporter)
    result["hydrogenGroupsCallable"] = callable(hydrogenGroups)
    result["topologyHelper"] = openmmrigid.rigidBodiesFromTopology.__module__
    result["lazyInDir"] = all(name in dir(openmmrigid) for name in ("RigidStateDataReporter", "rigidHydrogenGroups",
                                                                    "rigidBodiesFromTopology"))
    result["rigidtestingAtEnd"] = "rigidtesting" in sys.modules
    try:
        openmmrigid.noSuchName
        result["unknownName"] = "resolved"
    except AttributeError:
        result["unknownName"] = "AttributeError"
    print(json.dumps(result))
""")


@pytest.fixture(scope="module")
def fresh_import(tmp_path_factory):
    """IMPORT_CHECK's findings, in a new interpreter that can import rigidtesting (tests/python on its
    path), run from an empty folder."""
    environment = dict(os.environ, PYTHONPATH=str(TESTS))
    result = subprocess.run([sys.executable, "-c", IMPORT_CHECK], cwd=tmp_path_factory.mktemp("import"),
                            env=environment, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    import json
    return json.loads(result.stdout.strip().splitlines()[-1])


#: The one member of openmm that importing openmmrigid replaces, on purpose (python/openmmrigid/integrator.py,
#: _patchCompoundIntegrator), as seen from openmm and from openmm.openmm (the same class).
ALLOWED_WRAP = ["openmm.CompoundIntegrator.getIntegrator", "openmm.openmm.CompoundIntegrator.getIntegrator"]


def test_import_changes_nothing_in_openmm(fresh_import):
    """No attribute of openmm, openmm.openmm or openmm.unit, and no entry of the __dict__ of any of
    their classes (Context, XmlSerializer, CompoundIntegrator, Platform, ...), is added, removed or
    replaced by `import openmmrigid`, but CompoundIntegrator.getIntegrator, which it wraps keeping the
    original (XmlSerializer.deserialize and clone, Context.__init__ are openmm's own)."""
    assert fresh_import["classes"] > 100 and fresh_import["entries"] > 5000  # the snapshot saw openmm's classes
    assert fresh_import["added"] == []
    assert fresh_import["removed"] == []
    assert fresh_import["replaced"] == ALLOWED_WRAP
    assert fresh_import["wrapKeepsOriginal"]
    assert fresh_import["wrapIsOurs"]


def test_import_loads_neither_openmm_app_nor_the_test_helpers(fresh_import):
    assert not fresh_import["appBefore"]  # `import openmm` alone does not import it
    assert not fresh_import["appAfterImport"], "import openmmrigid imported openmm.app"
    assert fresh_import["rigidtestingImportable"]  # it could have: tests/python was on the path
    assert not fresh_import["rigidtestingAfterImport"], "import openmmrigid imported rigidtesting"
    assert not fresh_import["rigidtestingAtEnd"]
    assert all(name.split(".")[0] == "openmmrigid" for name in fresh_import["loaded"]), fresh_import["loaded"]
    assert "openmmrigid.reporters" not in fresh_import["loaded"] and "openmmrigid.topology" not in fresh_import["loaded"]


def test_lazy_names_resolve_on_first_use(fresh_import):
    assert fresh_import["reporterIsAStateDataReporter"]
    assert fresh_import["hydrogenGroupsCallable"]
    assert fresh_import["topologyHelper"] == "openmmrigid.topology"
    assert fresh_import["lazyInDir"]
    assert fresh_import["unknownName"] == "AttributeError"


def test_compound_integrator_wrap_returns_our_classes_and_others_unchanged():
    """The wrapped CompoundIntegrator.getIntegrator returns our class for ours (owned by the compound, as
    stock ones are) and the same as openmm's own for every other integrator."""
    original = openmm.CompoundIntegrator.getIntegrator._openmmrigidOriginal
    compound = openmm.CompoundIntegrator()
    stock = [openmm.VerletIntegrator(0.001), openmm.LangevinMiddleIntegrator(300, 1, 0.001), openmm.CustomIntegrator(0.001)]
    ours = [RigidBodyIntegrator(0.001), openmmrigid.RigidBodyBussiIntegrator(310, 0.1, 0.001),
            RigidBodyLangevinIntegrator(320, 1, 0.001)]
    for integrator in stock + ours:
        compound.addIntegrator(integrator)
    for index, integrator in enumerate(stock + ours):
        got = compound.getIntegrator(index)
        assert type(got) is type(integrator)
        assert type(original(compound, index)) is (type(integrator) if integrator in stock else openmm.Integrator)
        assert not got.thisown
        assert openmm.XmlSerializer.serialize(got) == openmm.XmlSerializer.serialize(integrator)
    # openmmtools finds each heat bath by asking for getTemperature().
    temperatures = [compound.getIntegrator(i).getTemperature().value_in_unit(openmm.unit.kelvin)
                    for i in range(compound.getNumIntegrators()) if hasattr(compound.getIntegrator(i), "getTemperature")]
    assert temperatures == [300.0, 310.0, 320.0]


def test_lazy_names_are_the_modules_own():
    from openmmrigid import reporters, topology
    assert openmmrigid.RigidStateDataReporter is reporters.RigidStateDataReporter
    assert openmmrigid.rigidHydrogenGroups is topology.rigidHydrogenGroups
    assert openmmrigid.rigidBodiesFromTopology is topology.rigidBodiesFromTopology
    for name in ("RigidStateDataReporter", "rigidHydrogenGroups", "rigidBodiesFromTopology"):
        assert name in openmmrigid.__all__


# ------------------------------------------------------------------------------------------------
# No test or benchmark code in the installed package
# ------------------------------------------------------------------------------------------------

INSTALLED = pathlib.Path(openmmrigid.__file__).resolve().parent
TEST_MODULES = {"pytest", "rigidtesting", "systems", "hypothesis"}


def _imports(path):
    """The top-level names of the modules a Python file imports (anywhere in it)."""
    names = set()
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"), filename=str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name.split(".")[0] for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names.add(node.module.split(".")[0])
    return names


def test_installed_package_has_no_testing_subpackage():
    assert INSTALLED.name == "openmmrigid" and (INSTALLED / "__init__.py").exists()
    assert not (INSTALLED / "testing").exists()
    assert not (INSTALLED / "testing.py").exists()
    assert importlib.util.find_spec("openmmrigid.testing") is None
    folders = {path.name for path in INSTALLED.rglob("*") if path.is_dir()}
    assert not folders & {"testing", "tests", "rigidtesting", "benchmarks", "examples"}, folders


def test_installed_modules_import_no_test_code():
    modules = [path for path in INSTALLED.rglob("*.py")]
    assert len(modules) >= 8  # the package's own modules were found
    for path in modules:
        assert not path.name.startswith(("test_", "conftest")), path
        imported = _imports(path) & TEST_MODULES
        assert not imported, f"{path.relative_to(INSTALLED)} imports {sorted(imported)}"


def test_installed_distribution_lists_no_test_or_benchmark_files():
    try:
        files = importlib.metadata.files("openmm-rigid")
    except importlib.metadata.PackageNotFoundError:
        pytest.skip("openmmrigid is not installed as a distribution")
    assert files, "the distribution lists no files"
    paths = [str(file) for file in files]
    assert any(path.startswith("openmmrigid/") for path in paths)
    offending = [path for path in paths if path.startswith("openmmrigid/") and
                 any(part in ("testing", "tests", "rigidtesting", "benchmarks") or part.startswith("test_")
                     for part in pathlib.PurePosixPath(path).parts)]
    assert not offending, offending

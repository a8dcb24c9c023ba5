"""An install that works as written (issue 42): `import openmmrigid` runs only with the OpenMM release
the plugin was built against.

The plugin is C++ linked to libOpenMM.so, whose ABI OpenMM does not keep stable across releases: a
plugin built against one release may crash with another (python/openmmrigid/_versioncheck.py). The
build records the release it compiled against (python/CMakeLists.txt writes openmmrigid/_build.py);
the import compares it with the running OpenMM before any compiled code of the package loads and
raises an ImportError that names both versions and the fix.
"""

import os
import pathlib
import subprocess
import sys
import textwrap

import openmm
import pytest

import openmmrigid
from openmmrigid import _versioncheck

ROOT = pathlib.Path(__file__).resolve().parents[2]


def test_build_recorded_the_openmm_it_was_built_against():
    """The installed package says which OpenMM it was built against: the one running now."""
    from openmmrigid import _build
    assert _build.OPENMM_VERSION == openmm.__version__ == openmm.Platform.getOpenMMVersion()
    assert openmmrigid._BUILT_AGAINST_OPENMM == _build.OPENMM_VERSION


def test_recorded_version_is_the_pinned_one():
    """pyproject.toml pins openmm to one release, for the build and at run time, and the build used it."""
    pyproject = ROOT / "pyproject.toml"
    if not pyproject.exists():
        pytest.skip("not run from a source tree")
    tomllib = pytest.importorskip("tomllib")  # Python 3.11+
    project = tomllib.loads(pyproject.read_text(encoding="utf-8"))
    from openmmrigid import _build
    pin = f"openmm=={_build.OPENMM_VERSION}"
    assert pin in project["project"]["dependencies"]
    assert pin in project["build-system"]["requires"]


def test_check_passes_the_release_built_against():
    _versioncheck.checkOpenMMVersion("8.6.1", "8.6.1")
    _versioncheck.checkOpenMMVersion(None, "8.7.0")  # a build that could not tell checks nothing
    assert _versioncheck.runningOpenMMVersion() == openmm.__version__


@pytest.mark.parametrize("running", ["8.7.0", "8.6.0", "8.6.1.1", "9.0"])
def test_check_refuses_any_other_release_in_one_sentence(running):
    with pytest.raises(ImportError) as caught:
        _versioncheck.checkOpenMMVersion("8.6.1", running)
    message = str(caught.value)
    assert "OpenMM 8.6.1" in message and f"OpenMM {running}" in message  # both versions
    assert "pip install openmm==8.6.1" in message  # the fix
    assert message.endswith(".") and ". " not in message and "\n" not in message  # one sentence


FAKE_OPENMM = """
__version__ = "{version}"
"""

IMPORT = textwrap.dedent("""
    import json, sys
    try:
        import openmmrigid
        outcome = {"imported": True}
    except ImportError as error:
        outcome = {"imported": False, "message": str(error)}
    outcome["openmm"] = sys.modules["openmm"].__file__
    outcome["compiled"] = sorted(name for name in sys.modules
                                 if name.startswith("openmmrigid.") and name.split(".")[1] not in ("_versioncheck", "_build"))
    print(json.dumps(outcome))
""")


def test_import_with_another_openmm_raises_before_loading_the_plugin(tmp_path):
    """`import openmmrigid` in a Python whose openmm is another release (here a stand-in package that
    says it is 8.7.0, first on the path) raises the ImportError, and loads none of the package's
    modules beyond the check (so no compiled code of ours meets the wrong libOpenMM)."""
    fake = tmp_path / "openmm"
    fake.mkdir()
    (fake / "__init__.py").write_text(FAKE_OPENMM.format(version="8.7.0"))
    environment = dict(os.environ, PYTHONPATH=str(tmp_path))
    result = subprocess.run([sys.executable, "-c", IMPORT], cwd=tmp_path, env=environment, capture_output=True,
                            text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    import json
    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["openmm"] == str(fake / "__init__.py")  # the stand-in was the openmm imported
    assert not outcome["imported"]
    assert outcome["message"].startswith(f"openmm-rigid was built against OpenMM {openmm.__version__} but this "
                                         f"Python imports OpenMM 8.7.0")
    assert f"pip install openmm=={openmm.__version__}" in outcome["message"]
    assert outcome["compiled"] == [], outcome["compiled"]


def test_import_with_the_right_openmm_succeeds(tmp_path):
    """The same subprocess with the real openmm imports the package (the check passes)."""
    result = subprocess.run([sys.executable, "-c", IMPORT], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    import json
    outcome = json.loads(result.stdout.strip().splitlines()[-1])
    assert outcome["imported"], outcome.get("message")
    assert "openmmrigid.integrator" in outcome["compiled"]

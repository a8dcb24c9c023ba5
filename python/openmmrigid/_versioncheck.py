"""The check, at ``import openmmrigid``, that the running OpenMM is the release the plugin was built against.

Why the pin is exact (``openmm==8.6.1`` in pyproject.toml, not ``>=``): the plugin's libraries
(libOpenMMRigid*.so and the SWIG module) are C++ compiled against OpenMM's headers and linked to its
libOpenMM.so. They use OpenMM's classes directly: their layouts, virtual tables, inline code and
mangled symbols are baked in at build time. OpenMM keeps its Python and C++ source API stable across
releases, but not its C++ ABI: a plugin built against one release may fail to load with another, or
load and then crash or compute with a misread object. Nothing at load time would say so, hence
this check, which runs before any of the package's compiled code is loaded. pip's pin normally
guarantees the match; the check catches what gets around it (``pip install --no-deps``, an openmm
upgraded or downgraded afterwards, a conda or source OpenMM earlier on the path).
"""

import openmm

__all__ = ["checkOpenMMVersion", "runningOpenMMVersion"]


def runningOpenMMVersion():
    """The version of the OpenMM library that ``import openmm`` loaded (``Platform.getOpenMMVersion()``,
    which openmm exposes as ``openmm.__version__``)."""
    return getattr(openmm, "__version__", None) or openmm.Platform.getOpenMMVersion()


def checkOpenMMVersion(built, running):
    """Raise ImportError unless `running` (OpenMM's version string) is `built`, the release the plugin
    was built against; `built` None (a build that could not tell) checks nothing."""
    if built is None or running == built:
        return
    raise ImportError(f"openmm-rigid was built against OpenMM {built} but this Python imports OpenMM {running}, "
                      f"whose C++ ABI the plugin cannot rely on: install the matching release with "
                      f"`pip install openmm=={built}`.")

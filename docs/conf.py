"""Sphinx configuration of the openmm-rigid manual.

Built by ``bash scripts/docs.sh`` (``sphinx-build -W --keep-going -E -b html docs build/docs/html``:
every warning an error), with the package as installed in ``.venv`` (autodoc imports it) and the
Doxygen XML of the public headers in ``build/docs/doxygen`` (the script runs Doxygen first; breathe
reads it).
"""

import re
import sys
from pathlib import Path

docs = Path(__file__).resolve().parent
repository = docs.parent
sys.path.insert(0, str(docs / "_ext"))

project = "openmm-rigid"
author = "the openmm-rigid developers"
copyright = "2026, " + author
try:
    import openmmrigid

    release = openmmrigid.__version__
except ImportError:  # autodoc reports each missing object; the rest of the site still builds
    release = "unknown"
version = release

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx-mathjax-offline",  # MathJax 3 copied into _static: the site reads equations offline
    "sphinx_copybutton",
    "breathe",
    "plaindocstrings",  # docs/_ext: openmmrigid's plain-text docstrings read as reStructuredText
]

# Sources: Markdown (MyST) and reStructuredText. The results documents, the architecture page, the
# GPU page and the free-rotor notes live beside the site's pages (the README and the code link them
# there) and are pulled into it by {include} from the pages that show them, so they are not pages
# of their own.
source_suffix = {".md": "markdown", ".rst": "restructuredtext"}
exclude_patterns = ["ARCHITECTURE.md", "gpu.md", "free-rotor-notes.md", "_ext", "Doxyfile"]
root_doc = "index"

myst_enable_extensions = ["dollarmath", "amsmath", "colon_fence", "deflist", "attrs_block"]
myst_heading_anchors = 3
myst_dmath_double_inline = True

# The Python API: the docstrings are numpy style (the SWIG module's come from the C++ Doxygen,
# rewritten by openmmrigid._pythonapi).
napoleon_google_docstring = False
napoleon_numpy_docstring = True
napoleon_use_rtype = False
napoleon_use_ivar = True
autodoc_member_order = "bysource"
autodoc_default_options = {
    "members": True,
    "exclude-members": "thisown, _openmmrigidPythonApi",
}
autodoc_typehints = "none"
autoclass_content = "class"

# The C++ API: Doxygen XML of the four public integrator headers and RigidBodyOptions.h (docs/Doxyfile).
breathe_projects = {"openmmrigid": str(repository / "build" / "docs" / "doxygen" / "xml")}
breathe_default_project = "openmmrigid"
breathe_default_members = ("members",)
breathe_domain_by_extension = {"h": "cpp"}
cpp_index_common_prefix = ["OpenMMRigid::"]

html_theme = "furo"
html_title = "openmm-rigid " + release
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_show_sourcelink = False
pygments_style = "friendly"
pygments_dark_style = "monokai"
highlight_language = "none"  # unlabelled blocks (benchmark output, commands) are plain text

copybutton_prompt_text = r"\$ |>>> "
copybutton_prompt_is_regexp = True


# Links written for the repository (GitHub renders docs/gpu.md, ...) point at the files the site shows
# inside its own pages: send them there.
_PAGES_OF_INCLUDED = {"ARCHITECTURE": "developer/architecture", "gpu": "developer/gpu",
                      "free-rotor-notes": "theory/free-rotor-algorithm"}


def _pageOf(target):
    return _PAGES_OF_INCLUDED.get(target)


def _redirectLinksToIncludedFiles(app, doctree):
    from sphinx import addnodes

    for node in doctree.findall(addnodes.pending_xref):
        if node.get("reftype") == "myst" and node.get("refdomain") == "doc":
            page = _pageOf(node["reftarget"])
            if page is not None:
                node["reftarget"] = page


def _resultsLayout(app, doctree):
    """On the validation pages: the plots are wide panels, small at the text's width, so each image
    gets a width, which makes Sphinx link it to the full-size file (html_scaled_image_link); the
    tables are of numbers, whose short cells _static/custom.css keeps on one line (class value)."""
    from docutils import nodes

    if not app.env.docname.startswith("validation/"):
        return
    for image in doctree.findall(nodes.image):
        if not any(key in image for key in ("width", "height", "scale")):
            image["width"] = "100%"
    for entry in doctree.findall(nodes.entry):
        if len(entry.astext()) <= 24:  # a value with its error, "112.81 ± 0.02": one line
            entry["classes"].append("value")


def _constructorSignature(app, what, name, obj, options, signature, returnAnnotation):
    """A SWIG class's signature is (*args); its overloads are listed at the top of __init__'s
    docstring ("RigidBodyIntegrator(stepSize)", "RigidBodyIntegrator(stepSize, bodies)"): show them as
    one signature with the optional tail in brackets, and none for a class that cannot be created."""
    if what != "class" or getattr(obj, "__module__", "") != "openmmrigid.openmmrigid":
        return None
    documentation = getattr(obj.__init__, "__doc__", None) or ""
    overloads = [[p.strip() for p in match.split(",") if p.strip()]
                 for match in re.findall(rf"^{obj.__name__}\((.*)\)\s*$", documentation, re.MULTILINE)]
    if not overloads:
        return "", returnAnnotation
    shortest, longest = min(overloads, key=len), max(overloads, key=len)
    if longest[:len(shortest)] != shortest:
        return "(" + ", ".join(longest) + ")", returnAnnotation
    optional = longest[len(shortest):]
    return "(" + ", ".join(shortest) + "".join(f"[, {p}]" for p in optional) + ")", returnAnnotation


def _basesInPackage(app, name, obj, options, bases):
    """Show a SWIG class's bases by the names users import (openmmrigid.X, not openmmrigid.openmmrigid.X)."""
    for index, base in enumerate(bases):
        if getattr(base, "__module__", "") == "openmmrigid.openmmrigid":
            bases[index] = f":py:class:`openmmrigid.{base.__name__}`"


def setup(app):

    app.connect("doctree-read", _redirectLinksToIncludedFiles)
    app.connect("doctree-read", _resultsLayout)
    app.connect("autodoc-process-bases", _basesInPackage)
    app.connect("autodoc-process-signature", _constructorSignature)

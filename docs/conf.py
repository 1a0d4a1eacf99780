"""Sphinx configuration of the isolator documentation: user guide, API reference, example gallery.

Build (offline: the intersphinx inventories are vendored in ``_inventories/``)::

    python -m sphinx -W --keep-going -b html docs docs/_build/html

The API reference pages are written from the packages' ``__all__`` at each build (``_api_pages.py``), the
command-line reference from the ``isolator`` parser itself (sphinx-argparse), and the gallery runs every
``examples/**/plot_*.py`` (sphinx-gallery): none of them can drift from the code.
"""

from __future__ import annotations

import os
import re
import sys
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from _api_pages import write_api_pages  # noqa: E402  (docs/ is on the path only from here)
from sphinx.errors import PycodeError  # noqa: E402
from sphinx.pycode import ModuleAnalyzer  # noqa: E402

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("ISOLATOR_QUIET", "1")  # no "compiling the model ..." lines in the examples' output

project = "isolator"
author = "the isolator developers"
copyright = "the isolator developers"
release = version = "0.1.0"

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.intersphinx",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "sphinxarg.ext",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
smartquotes = False  # options stay as typed: ``--protocol``, not an en dash
exclude_patterns = ["_build", "_inventories", "_templates", "examples", "**/GALLERY_HEADER.rst", "auto_examples/*.md"]
templates_path = ["_templates"]

# -- API reference: autosummary pages for every public name, numpydoc docstrings ---------------------------
write_api_pages(HERE / "reference")
autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"  # numpydoc: the types are in the docstrings' Parameters sections
autodoc_default_options = {"member-order": "bysource"}
numpydoc_show_class_members = False  # the class template lists the members itself
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = True  # types in Parameters/Returns link to their pages (here, numpy's, python-control's)
numpydoc_xref_aliases = {
    "ndarray": "numpy.ndarray",
    "StateSpace": "control.StateSpace",
    "control.StateSpace": "control.StateSpace",
    "Figure": "matplotlib.figure.Figure",
    "Scenario": "isolator.Scenario",
    "Response": "isolator.Response",
    "LinearModel": "isolator.LinearModel",
    "Band": "isolator.Band",
}
numpydoc_xref_ignore = {"of", "or", "optional", "default", "shape", "to", "and", "the", "a", "an", "in", "each",
                        "per", "one", "None"}
numpydoc_validation_checks: set[str] = set()

# -- Intersphinx: vendored inventories (no network at build time; see _inventories/make_inventories.py) ----
intersphinx_mapping = {
    "python": ("https://docs.python.org/3/", str(HERE / "_inventories" / "python.inv")),
    "numpy": ("https://numpy.org/doc/stable/", str(HERE / "_inventories" / "numpy.inv")),
    "scipy": ("https://docs.scipy.org/doc/scipy/", str(HERE / "_inventories" / "scipy.inv")),
    "control": ("https://python-control.readthedocs.io/en/0.10.2/", str(HERE / "_inventories" / "control.inv")),
    "matplotlib": ("https://matplotlib.org/stable/", str(HERE / "_inventories" / "matplotlib.inv")),
}

# -- MyST: the guide pages and the contract files are Markdown, readable on the repository too ---------------
myst_enable_extensions = ["colon_fence", "deflist"]
myst_heading_anchors = 4

# -- Gallery: every example runs at each build ----------------------------------------------------------------
sphinx_gallery_conf = {
    "examples_dirs": "../examples",
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"plot_",
    "ignore_pattern": r"__init__\.py",
    "within_subsection_order": "FileNameSortKey",
    "reference_url": {"isolator": None},
    "doc_module": ("isolator", "controllers", "studies"),
    "remove_config_comments": True,
    "min_reported_time": 1,
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "download_all_examples": False,
}

# The contract's TOML blocks show placeholders (``stiffness = [kx, ky, kz]``) that the TOML lexer refuses; they
# are highlighted in Pygments' relaxed mode, which is what they need, so that note is not a warning here.
suppress_warnings = ["misc.highlighting_failure"]

# -- HTML -------------------------------------------------------------------------------------------------------
html_theme = "pydata_sphinx_theme"
html_title = "isolator"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
    "header_links_before_dropdown": 6,
}
html_static_path = ["_static"]
html_css_files = ["custom.css"]
html_show_sourcelink = False


# ``|x|`` in a docstring is an absolute value (``|signal - path|``, ``|H|``), not a reStructuredText
# substitution: the docstrings are written for the terminal first, so the bars are escaped when Sphinx reads them
_LITERAL = re.compile(r"(``.*?``)")


def _escape_bars(app: object, what: str, name: str, obj: object, options: object, lines: list[str]) -> None:
    for i, line in enumerate(lines):
        if "|" in line:
            lines[i] = "".join(part if part.startswith("``") else part.replace("|", "\\|")
                               for part in _LITERAL.split(line))


def _constant_docs(app: object, what: str, name: str, obj: object, options: object, lines: list[str]) -> None:
    """A constant re-exported by a package (``controllers.feedback.SAMPLE_RATE``) gets the ``#:`` comment of
    the module that defines it, not its type's docstring ("Convert a string or number to a floating point
    number ...")."""
    type_doc = (type(obj).__doc__ or "").strip().splitlines()
    if what not in ("data", "attribute") or not type_doc or type_doc[0].strip() not in [line.strip() for line in lines]:
        return
    package, _, attribute = name.rpartition(".")
    lines[:] = []
    for module in sorted(m for m in sys.modules if m == package or m.startswith(package + ".")):
        try:
            found = ModuleAnalyzer.for_module(module).find_attr_docs().get(("", attribute))
        except PycodeError:
            continue
        if found:
            lines[:] = list(found)
            return


def setup(app: Any) -> None:
    app.connect("autodoc-process-docstring", _escape_bars)
    app.connect("autodoc-process-docstring", _constant_docs)

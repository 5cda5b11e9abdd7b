"""Sphinx configuration of pnrotor's site: the Markdown pages of docs/ (MyST), the user guide, the gallery of
examples/ (sphinx-gallery, executed at build) and the API reference from the docstrings (autodoc, napoleon).

Build: ``python -m sphinx -W docs docs/_build/html``.  ``PNROTOR_DOCS_GALLERY=0`` skips running the examples."""

import os
import re
import sys
from pathlib import Path

import pnrotor

project = "pnrotor"
author = "pnrotor developers"
release = version = pnrotor.__version__
copyright = "pnrotor developers, MIT license"

extensions = [
    "myst_parser",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.napoleon",
    "sphinx.ext.mathjax",
    "sphinx.ext.viewcode",
    "sphinx_gallery.gen_gallery",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "Thumbs.db", ".DS_Store", "auto_examples/*.ipynb", "auto_examples/*.py",
                    "auto_examples/*.zip", "auto_examples/*.md5", "auto_examples/*.pickle"]
myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3
suppress_warnings = ["myst.xref_missing"]   # links between the .md pages that GitHub renders (e.g. to src/ files)

html_theme = "furo"
html_title = f"pnrotor {release}"

default_role = "py:obj"
autodoc_default_options = {"members": True, "show-inheritance": False}
autodoc_member_order = "bysource"
autodoc_typehints = "none"
autosummary_generate = False
napoleon_numpy_docstring = True
napoleon_google_docstring = False

ROOT = Path(__file__).resolve().parents[1]
sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",
    "plot_gallery": os.environ.get("PNROTOR_DOCS_GALLERY", "1") != "0",
    "download_all_examples": False,
    "remove_config_comments": True,
    "within_subsection_order": "FileNameSortKey",
    "abort_on_example_error": True,
}
sys.path.insert(0, str(ROOT / "examples"))


_LITERAL = re.compile(r"(``.*?``|`[^`]*`)")


def _plain_bars(app, what, name, obj, options, lines):
    """The docstrings write |x| for magnitudes (plain text with Unicode math), never reStructuredText substitutions:
    bars are escaped outside literals and interpreted text, except in table rows (lines that start and end with
    one)."""
    for k, line in enumerate(lines):
        row = line.strip()
        if not (row.startswith("|") and row.endswith("|")):
            lines[k] = "".join(part if _LITERAL.fullmatch(part) else part.replace("|", "\\|")
                               for part in _LITERAL.split(line))


def setup(app):
    app.connect("autodoc-process-docstring", _plain_bars)

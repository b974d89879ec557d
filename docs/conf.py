"""Sphinx configuration of the crashsim site (``sphinx-build -W --keep-going -b html docs docs/_build/html``).

The scenario-file schema page is written at build time from ``crashsim schema --format markdown``
(the validating schema itself), so the documented and the validating schema stay one object. The
gallery's examples run at build time too (``docs/_ext/crashsim_examples.py``): a failing example
fails the build.
"""
from __future__ import annotations

import os
import re
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(DOCS / "_ext"))
os.environ.setdefault("MPLBACKEND", "Agg")

import crashsim  # noqa: E402
from crashsim.scenario import schema_document  # noqa: E402

project = "crashsim"
author = "The crashsim contributors"
copyright = "2026, the crashsim contributors"
release = version = crashsim.__version__

extensions = [
    "crashsim_examples",
    "myst_parser",
    "numpydoc",
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "_generated/*.txt", "**/README.md"]
templates_path = ["_templates"]

myst_enable_extensions = ["dollarmath", "colon_fence"]
myst_heading_anchors = 3

autosummary_generate = True
autosummary_imported_members = False
# A package's __all__ re-exports its modules' names; each name is documented once, in its own module.
autodoc_default_options = {"members": True, "undoc-members": False, "ignore-module-all": True}
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False

# The notes in docs/ link to files of the repository (src/, tests/, plots/) with paths relative to
# themselves so the links work on GitHub; on the site those are not pages. Links to pages resolve.
suppress_warnings = ["myst.xref_missing", "myst.header"]

html_theme = "pydata_sphinx_theme"
html_title = f"crashsim {release}"
html_theme_options = {
    "navigation_with_keys": False,
    "show_toc_level": 2,
}
html_static_path: list[str] = []


def _write_schema() -> None:
    out = DOCS / "_generated"
    out.mkdir(exist_ok=True)
    text = schema_document("markdown")
    # Demote the document's own title: the page gives its own.
    text = text.replace("# A crashsim scenario file (TOML)\n", "", 1)
    target = out / "schema.md"
    if not target.exists() or target.read_text() != text:
        target.write_text(text)


_ABS = re.compile(r"(?<![|\\])\|([^|\n`]{1,40})\|(?!\|)")


def _plain_bars(app, what, name, obj, options, lines) -> None:
    """The docstrings write a magnitude as ``|x|`` (plain text); reST would read a substitution."""
    lines[:] = [_ABS.sub(r"\\|\1\\|", line) for line in lines]


def _module_text_as_written(app, what, name, obj, options, lines) -> None:
    """A module docstring is plain text laid out in columns (its keys and what they mean): shown as
    written, its first paragraph a paragraph and the rest preformatted."""
    if what != "module" or len(lines) < 2:
        return
    end = next((i for i, line in enumerate(lines) if not line.strip()), len(lines))
    head, rest = lines[:end], lines[end:]
    if any(line.strip() for line in rest):
        lines[:] = head + ["", "::", ""] + ["    " + line if line.strip() else "" for line in rest]


_write_schema()


def setup(app):
    app.connect("autodoc-process-docstring", _module_text_as_written, priority=300)
    app.connect("autodoc-process-docstring", _plain_bars, priority=400)

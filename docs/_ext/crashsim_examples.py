"""Examples executed when the site is built: the ``crashsim-example`` directive.

A page writes the code a user would type (Python, run from the repository's root) in a
``crashsim-example`` block::

    ```{crashsim-example} barrier-15deg
    import crashsim

    scene = crashsim.run("scenarios/scenes/barrier_15deg.toml")
    print(scene.report())
    scene.plot()
    ```

and the build runs it, in this process, in a fresh namespace, with the repository's root as the
working directory. The page then shows the code, what it printed (its standard output) and every
matplotlib figure it left open, saved as a PNG into the build tree (``<doctrees>/_examples/``, so a
figure on the page is the one this build's run drew, never a committed file). The argument names
the example (its figures' file names: ``<name>-1.png``, ...; unique on the site).

An example that raises, or that issues a Python warning, is an error of the build: a Sphinx warning
at the directive's line, which ``sphinx-build -W`` (the CI command) turns into a failed build; the
page without ``-W`` shows the traceback in place of the output. A page that runs examples is read
again when a repository file named by a string in its code (a scenario file) changes.

:func:`run_example` is the part without Sphinx (``tests/unit/test_docs_gallery.py`` tests it).
"""

from __future__ import annotations

import ast
import contextlib
import io
import os
import re
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_-]*$")


class ExampleError(Exception):
    """An example that raised or warned while it ran; the message holds its traceback or warnings."""


@dataclass
class Example:
    """What one example did: its code, what it printed, the figures it drew (PNG files)."""

    name: str
    code: str
    output: str
    figures: list[Path] = field(default_factory=list)


@contextlib.contextmanager
def _working_directory(path: Path):
    before = os.getcwd()
    os.chdir(path)
    try:
        yield
    finally:
        os.chdir(before)


def run_example(code: str, name: str, figure_dir: Path, *, cwd: Path = ROOT, dpi: int = 110) -> Example:
    """Run ``code`` (Python) with ``cwd`` as the working directory; its standard output captured, each
    figure it leaves open saved as ``figure_dir/<name>-<n>.png`` and closed.

    Raises :class:`ExampleError` if the code raises or issues a Python warning (the traceback, or
    every warning with its file and line, in the message), and ``ValueError`` for a bad ``name``.
    """
    if not _NAME.match(name):
        raise ValueError(f"example name {name!r}: letters, digits, '-' and '_' only (it names the figure files)")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure_dir = Path(figure_dir)
    figure_dir.mkdir(parents=True, exist_ok=True)
    for old in figure_dir.glob(f"{name}-*.png"):
        old.unlink()
    plt.close("all")
    out = io.StringIO()
    namespace = {"__name__": "__example__"}
    try:
        with warnings.catch_warnings(record=True) as caught, _working_directory(cwd), \
                contextlib.redirect_stdout(out), contextlib.redirect_stderr(out):
            warnings.simplefilter("always")
            try:
                exec(compile(code, f"<example {name}>", "exec"), namespace)  # noqa: S102 - the docs' own code
            except Exception:
                raise ExampleError(f"example {name!r} raised:\n{traceback.format_exc()}\noutput before it:\n"
                                   f"{out.getvalue()}") from None
        if caught:
            said = "\n".join(f"{w.filename}:{w.lineno}: {w.category.__name__}: {w.message}" for w in caught)
            raise ExampleError(f"example {name!r} warned:\n{said}")
        figures = []
        for n, number in enumerate(plt.get_fignums(), start=1):
            path = figure_dir / f"{name}-{n}.png"
            plt.figure(number).savefig(path, dpi=dpi)
            figures.append(path)
    finally:
        plt.close("all")
    return Example(name, code, out.getvalue(), figures)


def named_files(code: str, root: Path = ROOT) -> list[Path]:
    """The repository files named by the code's string literals (the scenario files it reads)."""
    found = []
    for node in ast.walk(ast.parse(code)):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and "\n" not in node.value:
            p = root / node.value
            if len(node.value) < 300 and p.is_file():
                found.append(p)
    return found


def setup(app):
    from docutils import nodes
    from sphinx.util import logging
    from sphinx.util.docutils import SphinxDirective

    logger = logging.getLogger(__name__)

    class CrashsimExample(SphinxDirective):
        """``crashsim-example NAME``: run the body (Python) at build time; show code, output, figures."""

        required_arguments = 1
        has_content = True
        option_spec = {"alt": str}

        def run(self):
            name = self.arguments[0]
            code = "\n".join(self.content)
            figure_dir = Path(self.env.doctreedir) / "_examples"
            shown = [nodes.literal_block(code, code, language="python")]
            try:
                example = run_example(code, name, figure_dir)
            except (ExampleError, ValueError) as e:
                logger.warning("crashsim-example %s failed at build time:\n%s", name, e,
                               location=self.get_location(), type="crashsim", subtype="example")
                return shown + [nodes.literal_block(str(e), str(e), language="text")]
            for path in named_files(code):
                self.env.note_dependency(str(path))
            text = example.output.rstrip("\n")
            if text.strip():
                shown.append(nodes.paragraph("", "What it printed, when this page was built:"))
                shown.append(nodes.literal_block(text, text, language="text", classes=["crashsim-example-output"]))
            srcdir = Path(self.env.srcdir)
            alt = self.options.get("alt", f"figure of example {name}, drawn when this page was built")
            for path in example.figures:
                # "/" + a path relative to the source folder: Sphinx's rule for an image path it copies.
                uri = "/" + os.path.relpath(path, srcdir).replace(os.sep, "/")
                shown.append(nodes.image(uri=uri, alt=alt))
            return shown

    app.add_directive("crashsim-example", CrashsimExample)
    return {"version": "1", "parallel_read_safe": False, "parallel_write_safe": True}

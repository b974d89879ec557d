"""The examples in the package's docstrings run and give what they show (GUIDE habit 9; pymunk runs
its doctests as tests), as part of ``python -m pytest -q``.

Only the modules whose source holds an example (``>>>``) are imported, found by reading the files,
so that no module is imported just to look for examples (``--doctest-modules`` imports every module
under ``src/``). An example that needs a shipped scene file, or an object the docstring does not
build, is marked ``# doctest: +SKIP`` in its docstring; every other one runs here.
"""

from __future__ import annotations

import doctest
import importlib
from pathlib import Path

import pytest

import crashsim

SRC = Path(crashsim.__file__).parent
FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE


def _module(path: Path) -> str:
    parts = list(path.relative_to(SRC.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = sorted(_module(p) for p in SRC.rglob("*.py") if ">>>" in p.read_text(encoding="utf-8"))


def test_the_examples_are_found():
    assert {"crashsim.units", "crashsim.motion.simulate", "crashsim.schema"} <= set(MODULES)


@pytest.mark.parametrize("name", MODULES)
def test_docstring_examples(name):
    module = importlib.import_module(name)
    runner = doctest.DocTestRunner(optionflags=FLAGS)
    tests = doctest.DocTestFinder().find(module, name)
    for test in tests:
        runner.run(test)
    result = runner.summarize(verbose=False)
    assert result.failed == 0, f"{name}: {result.failed} of {result.attempted} examples failed (see the output above)"
    runnable = sum(1 for t in tests for ex in t.examples if not ex.options.get(doctest.SKIP))
    assert result.attempted == runnable

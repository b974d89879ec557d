"""The light face (issue "Compile once, vary by name", item 6): ``import crashsim``, ``import
crashsim.units`` and ``crashsim --version`` / ``--help`` load no numba, llvmlite, SciPy or matplotlib;
the public names still resolve, on first use (PEP 562 module ``__getattr__``).

Each import runs in a fresh interpreter (this process has loaded everything long ago). No timing
here: which modules are loaded is what a test can assert; the CPU time is benchmarks/startup.py's.
"""

from __future__ import annotations

import ast
import functools
import importlib
import os
import subprocess
import sys
from pathlib import Path

import pytest

import crashsim

ROOT = Path(__file__).resolve().parents[2]
HEAVY = ("numba", "llvmlite", "scipy", "matplotlib")
#: Prints the heavy top-level packages loaded so far, as a Python list.
REPORT = f"print(sorted(m for m in sys.modules if m.split('.')[0] in {set(HEAVY)!r}))"


def _fresh(code: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=120)


def _loaded(code: str) -> list[str]:
    out = _fresh(code)
    assert out.returncode == 0, out.stderr
    return ast.literal_eval(out.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("statement", ["import crashsim", "import crashsim.units", "import crashsim.errors",
                                       "from crashsim import __version__, ScenarioError"])
def test_an_import_loads_nothing_heavy(statement):
    assert _loaded(f"{statement}, sys; {REPORT}" if statement.startswith("import") else
                   f"{statement}; import sys; {REPORT}") == []


def test_the_check_itself_sees_a_heavy_import():
    """The same probe after a name that needs the kernels: it does list them (so an empty list above
    is the import's, not a blind probe)."""
    loaded = _loaded(f"import crashsim, sys; crashsim.run; {REPORT}")
    assert "numba" in loaded and "scipy" in loaded


@pytest.mark.parametrize("option", ["--version", "--help"])
def test_version_and_help_load_nothing_heavy(option):
    code = ("import runpy, sys\nsys.argv = ['crashsim', %r]\ntry:\n    runpy.run_module('crashsim', run_name='__main__')\n"
            "except SystemExit as exc:\n    assert exc.code in (0, None), exc.code\n%s" % (option, REPORT))
    out = _fresh(code)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.strip().splitlines()
    assert ast.literal_eval(lines[-1]) == []
    if option == "--version":
        assert lines[0] == f"crashsim {crashsim.__version__}"
    else:
        assert "usage: crashsim" in out.stdout and "run" in out.stdout


PACKAGES = ["crashsim", "crashsim.motion", "crashsim.impact", "crashsim.scene", "crashsim.reconstruct"]


@pytest.mark.parametrize("package", PACKAGES)
def test_every_public_name_resolves(package):
    mod = importlib.import_module(package)
    missing = [n for n in mod.__all__ if getattr(mod, n, None) is None]
    assert missing == []
    assert set(mod.__all__) <= set(dir(mod))
    with pytest.raises(AttributeError, match="no_such_name"):
        getattr(mod, "no_such_name")


def test_star_import_and_the_defining_modules():
    namespace: dict = {}
    exec("from crashsim import *", namespace)
    assert set(crashsim.__all__) <= set(namespace)
    from crashsim.api import run
    from crashsim.motion.runout import run_runout
    from crashsim.scene.run import run_scene

    assert crashsim.run is run and namespace["run"] is run
    assert importlib.import_module("crashsim.motion").run_runout is run_runout
    assert importlib.import_module("crashsim.reconstruct").run_scene is run_scene


def test_a_refused_scene_file_on_a_first_run_starts_no_compile(monkeypatch, tmp_path, capsys):
    """A file with an unknown key, on a machine whose kernels are not compiled: refused (exit 2)
    before a background compile, a child process or a compile here starts."""
    from crashsim import cli, first_run

    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path / "cache"))
    monkeypatch.setenv(first_run.ENV, "background")
    monkeypatch.delenv("NUMBA_CACHE_DIR", raising=False)
    calls = []
    monkeypatch.setattr(first_run, "run_interpreted", lambda argv, race=False: calls.append("child") or 0)
    monkeypatch.setattr(first_run, "start_background_compile", lambda: calls.append("compile") or None)
    monkeypatch.setattr(cli, "_first_compile", lambda bar=True: calls.append("here"))
    monkeypatch.setattr(cli, "ready", lambda: False)
    scene = (ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml").read_text()
    bad = tmp_path / "bad.toml"
    bad.write_text(scene.replace("[scenario]\n", '[scenario]\ntitel = "typo"\n', 1))
    for path, words in ((bad, "did you mean 'title'"), (tmp_path / "missing.toml", "cannot read the file")):
        assert cli.main(["run", str(path)]) == 2
        err = capsys.readouterr().err
        assert err.startswith("crashsim: input error: ") and str(path) in err and words in err, err
    assert calls == []


@functools.cache
def _pint_loads() -> frozenset[str]:
    """The heavy modules ``import pint`` loads by itself (once for every command below)."""
    return frozenset(_loaded(f"import pint, sys; {REPORT}"))


@pytest.mark.parametrize("command, extra", [("run", []), ("fit", []), ("mc", []), ("posterior", []),
                                            ("plot", ["-o", "x.png"]), ("animate", ["-o", "x.gif"]),
                                            ("export", ["--dxf", "x.dxf"]), ("report", ["-o", "x.html"])])
def test_a_refused_scene_file_loads_no_engine(tmp_path, command, extra):
    """Every scene command reads and checks the file before it imports an engine: a file with an
    unknown key is refused (exit code 2, the file and the key named) having loaded no numba and no
    more of SciPy than pint itself loads (pint's compat module imports the bare ``scipy`` package to
    learn whether it is there), and writes no output. The figure commands (plot, animate) may load
    matplotlib first: their output paths are checked before any work, and which figure formats can
    be written is matplotlib's to say."""
    scene = (ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml").read_text()
    bad = tmp_path / "bad_key.toml"
    bad.write_text(scene.replace("[scenario]\n", '[scenario]\ntitel = "typo"\n', 1))
    argv = [command, str(bad)] + [str(tmp_path / a) if a.startswith("x.") else a for a in extra]
    out = _fresh("import sys\nfrom crashsim.cli import main\nrc = main(%r)\nassert rc == 2, rc\n%s" % (argv, REPORT))
    assert out.returncode == 0, out.stderr
    assert "scenario.titel" in out.stderr and str(bad) in out.stderr
    loaded = ast.literal_eval(out.stdout.strip().splitlines()[-1])
    assert {m for m in loaded if m.split(".")[0] == "scipy"} <= _pint_loads()
    assert not any(m.split(".")[0] in ("numba", "llvmlite") for m in loaded)
    if command not in ("plot", "animate"):
        assert not any(m.split(".")[0] == "matplotlib" for m in loaded)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad_key.toml"]


def test_every_command_of_the_parser_has_its_function():
    """The parser (crashsim.cli_parser) names the commands; crashsim.cli.COMMANDS runs them: the two
    lists are the same, so that no command parses and then has nothing to run."""
    import argparse

    from crashsim import cli
    from crashsim.cli_parser import build_parser

    sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
    assert sorted(sub.choices) == sorted(cli.COMMANDS)
    assert all(callable(f) for f in cli.COMMANDS.values())

"""Suite-wide set-up: the command line compiles in this process on a machine whose kernels are not
compiled yet (``CRASHSIM_FIRST_RUN=wait``), so that commands called in-process run in-process (their
output captured); ``tests/unit/test_first_run.py`` tests the other policies in child processes."""

import os
import sys

os.environ.setdefault("CRASHSIM_FIRST_RUN", "wait")
# Bytecode caches on, for this process and the interpreters it starts (the command-line tests, the
# worker processes of Monte Carlo and posterior runs): with PYTHONDONTWRITEBYTECODE set, as some CI
# images do, each of them compiles crashsim's sources again (0.6-0.7 s of CPU per `crashsim run`,
# measured), and pytest rewrites every test module's asserts again in every run. The caches go to
# the __pycache__ directories .gitignore leaves out.
os.environ.pop("PYTHONDONTWRITEBYTECODE", None)
sys.dont_write_bytecode = False


import pytest  # noqa: E402
from hypothesis import settings  # noqa: E402

# Property tests draw the same examples on every run and every machine, so the suite's verdict is
# reproducible (a CI run went red once on an example no run before had drawn: a test's bug, but found at
# random). `pytest --hypothesis-profile=explore` draws new examples, for a developer hunting bugs.
settings.register_profile("reproducible", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile("reproducible")


@pytest.fixture
def refused_line(tmp_path, capsys):
    """``refused_line(text)`` writes ``text`` to ``case.toml``, runs ``crashsim run`` on it in-process
    and returns its one error line, after checking what every refusal of bad input must do: exit 2,
    nothing on stdout, exactly one ``input error`` line on stderr, naming the file. Other stderr lines
    (the compile notes of a first run on a fresh machine) are not the error and are passed over."""
    from crashsim.cli import main

    def run(text: str) -> str:
        f = tmp_path / "case.toml"
        f.write_text(text)
        code = main(["run", str(f)])
        out, err = capsys.readouterr()
        assert code == 2 and out == "", (code, out, err)
        lines = [ln for ln in err.splitlines() if "input error" in ln]
        assert len(lines) == 1 and "case.toml" in lines[0], err
        return lines[0]

    return run


#: The tests the developer's fast tier (``pytest -m "not slow"``) leaves to the full suite besides
#: those marked ``slow`` in their own file: one test function per line (all its parameters), written by
#: ``python benchmarks/test_tiers.py --write-slow-list`` from the durations of a fast-tier run.
SLOW_LIST = os.path.join(os.path.dirname(__file__), "slow_tests.txt")


def _slow_list() -> set[str]:
    with open(SLOW_LIST, encoding="utf-8") as fh:
        return {ln.strip() for ln in fh if ln.strip() and not ln.startswith("#")}


@pytest.hookimpl(tryfirst=True)  # before -m and -k deselect: every collected test is seen
def pytest_collection_modifyitems(config, items):
    """Mark the listed test functions ``slow``; a listed function of a collected file that no longer
    exists is an error, so the list cannot name tests that were renamed away."""
    listed = _slow_list()
    seen, files = set(), set()
    for item in items:
        file, _, rest = item.nodeid.partition("::")
        files.add(file)
        function = f"{file}::{rest.split('[')[0]}"
        if function in listed:
            seen.add(function)
            item.add_marker(pytest.mark.slow)
    missing = sorted(f for f in listed - seen if f.partition("::")[0] in files)
    whole_files = not any("::" in str(a) for a in config.args)
    if missing and whole_files:
        raise pytest.UsageError(f"{SLOW_LIST} names test functions that were not collected: {', '.join(missing)}")

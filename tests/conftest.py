"""Suite-wide set-up: the command line compiles in this process on a machine whose kernels are not
compiled yet (``CRASHSIM_FIRST_RUN=wait``), so that commands called in-process run in-process (their
output captured); ``tests/unit/test_first_run.py`` tests the other policies in child processes."""

import os

os.environ.setdefault("CRASHSIM_FIRST_RUN", "wait")


import pytest  # noqa: E402


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

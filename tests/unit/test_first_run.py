"""The first run on a machine whose kernels are not compiled (crashsim.first_run).

A single-scene command runs interpreted in a child process (the same kernel source, numba's
NUMBA_DISABLE_JIT) while a detached process compiles; commands of many scenes compile first. The
interpreted run must print what the compiled one prints, digit for digit of the report."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from crashsim import first_run
from crashsim.cli import main
from crashsim.errors import ScenarioError

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "scenes" / "barrier_15deg.toml"


def test_the_policy_comes_from_the_environment(monkeypatch):
    monkeypatch.delenv(first_run.ENV, raising=False)
    assert first_run.policy() == "background"
    monkeypatch.setenv(first_run.ENV, "Wait")
    assert first_run.policy() == "wait"
    monkeypatch.setenv(first_run.ENV, "later")
    with pytest.raises(ScenarioError) as err:
        first_run.policy()
    assert "CRASHSIM_FIRST_RUN = 'later'" in str(err.value) and "background, wait, interpret" in str(err.value)


def test_an_interpreted_first_run_prints_what_the_compiled_run_prints(tmp_path, capsys):
    assert main(["run", str(SCENE)]) == 0  # in this process: compiled (the suite's policy is "wait")
    compiled = capsys.readouterr().out
    env = dict(os.environ, CRASHSIM_CACHE_DIR=str(tmp_path / "fresh"), CRASHSIM_FIRST_RUN="interpret",
               PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    env.pop("NUMBA_CACHE_DIR", None)
    out = subprocess.run([sys.executable, "-m", "crashsim", "run", str(SCENE)], env=env, capture_output=True,
                         text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "runs interpreted" in out.stderr
    assert out.stdout == compiled
    # nothing compiled, nothing started: no ready marker, no compile log
    assert not (tmp_path / "fresh" / "compile.log").exists()
    assert not list((tmp_path / "fresh").rglob("ready-*"))


def test_single_scene_commands_run_interpreted_and_start_one_compile(monkeypatch, tmp_path):
    """Policy background: run goes to the child and the background compile; fit compiles here first."""
    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv(first_run.ENV, "background")
    calls = []
    monkeypatch.setattr(first_run, "run_interpreted", lambda argv, race=False: calls.append(("child", argv)) or 7)
    monkeypatch.setattr(first_run, "start_background_compile", lambda: calls.append(("compile",)) or tmp_path / "log")
    import crashsim.cli as cli

    monkeypatch.setattr(cli, "_first_compile", lambda bar=True: calls.append(("here",)))
    assert main(["run", str(SCENE)]) == 7
    assert calls == [("compile",), ("child", ["run", str(SCENE)])]
    calls.clear()
    argv = ["fit", str(SCENE)]
    assert cli._first_run(cli.build_parser().parse_args(argv), argv) is None  # then the command runs here
    assert calls == [("here",)]


def test_the_background_compile_is_launched_detached_without_the_interpreter_switch(monkeypatch, tmp_path):
    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv("NUMBA_DISABLE_JIT", "1")
    seen = {}

    class Popen:
        def __init__(self, cmd, **kw):
            seen["cmd"], seen["kw"] = cmd, kw

    monkeypatch.setattr(first_run.subprocess, "Popen", Popen)
    log = first_run.start_background_compile()
    assert log == tmp_path / "compile.log" and log.exists()
    assert seen["cmd"][1:] == ["-m", "crashsim.warmup"]
    assert "NUMBA_DISABLE_JIT" not in seen["kw"]["env"]
    assert seen["kw"].get("start_new_session") or os.name != "posix"


def test_one_compile_at_a_time(monkeypatch, tmp_path):
    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path))
    lock = tmp_path / "compiling.lock"
    assert not first_run.compile_in_progress()
    lock.write_text(str(os.getpid()))  # a live process holds it
    assert first_run.compile_in_progress()
    assert first_run.start_background_compile() is None
    compiled = []
    assert first_run.background_main(lambda say: compiled.append(1)) == 0 and not compiled  # left alone
    assert lock.read_text() == str(os.getpid())
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    lock.write_text(str(dead.pid))  # a compile that died
    assert not first_run.compile_in_progress()
    assert first_run._take(lock) and lock.read_text() == str(os.getpid())


def test_a_compile_that_finishes_first_stops_the_interpreted_run(monkeypatch, capsys):
    """race: once the kernels are ready, a still-running interpreted child is stopped (None: the
    caller runs the command compiled) and its held output is not passed on; without race it runs on."""
    monkeypatch.setattr(first_run, "ready", lambda: True)
    t0 = __import__("time").perf_counter()
    assert first_run.run_interpreted(["run", str(SCENE)], race=True) is None
    assert __import__("time").perf_counter() - t0 < 30.0
    assert capsys.readouterr().out == ""
    # the CLI then runs it here, compiled
    monkeypatch.setenv(first_run.ENV, "background")
    monkeypatch.setattr(first_run, "start_background_compile", lambda: None)
    monkeypatch.setattr(first_run, "compile_in_progress", lambda: True)
    import crashsim.cli as cli

    monkeypatch.setattr(cli, "ready", lambda: False)
    argv = ["run", str(SCENE)]
    assert cli._first_run(cli.build_parser().parse_args(argv), argv) is None
    assert "the scene runs compiled" in capsys.readouterr().err


def _fresh_env(tmp_path, policy: str) -> dict:
    env = dict(os.environ, CRASHSIM_CACHE_DIR=str(tmp_path / "fresh"), CRASHSIM_FIRST_RUN=policy,
               PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("NUMBA_DISABLE_JIT", None)
    return env


def test_an_interpreted_run_is_not_cut_by_the_wall_time_limit(tmp_path):
    """max_wall_time is a budget for compiled kernels: interpreted, the same scene must reach the same
    rest (it used to end NOT AT REST, exit 3, on a loaded machine). A limit far below the interpreted
    run's time shows it: lifted, and said so on stderr."""
    text = SCENE.read_text()
    assert "[runout]\n" in text
    f = tmp_path / "scene.toml"
    f.write_text(text.replace("[runout]\n", '[runout]\nmax_wall_time = "0.05 s"\n', 1))
    out = subprocess.run([sys.executable, "-m", "crashsim", "run", str(f)], env=_fresh_env(tmp_path, "interpret"),
                         capture_output=True, text=True, timeout=600)
    assert out.returncode == 0, out.stderr
    assert "wall-time limit (runout.max_wall_time = 0.05 s) is lifted" in out.stderr
    assert "NOT AT REST" not in out.stdout


def test_a_dead_background_compile_is_noticed_and_started_again(monkeypatch, tmp_path, capsys):
    """A compile that died (a reinstall under it: its log ends in a traceback) is named in one line
    by the next command, which starts the compile again."""
    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path))
    monkeypatch.setenv(first_run.ENV, "background")
    (tmp_path / "compile.log").write_text("compiling 1: kernel module\nTraceback (most recent call last):\n"
                                          "ModuleNotFoundError: No module named 'crashsim.motion.kernels'\n")
    assert "ModuleNotFoundError" in first_run.dead_compile()
    calls = []
    monkeypatch.setattr(first_run, "run_interpreted", lambda argv, race=False: 0)
    monkeypatch.setattr(first_run, "start_background_compile", lambda: calls.append("compile") or tmp_path / "l")
    assert main(["run", str(SCENE)]) == 0
    err = [ln for ln in capsys.readouterr().err.splitlines() if "stopped before it finished" in ln]
    assert len(err) == 1 and "compiling again" in err[0] and calls == ["compile"]
    (tmp_path / "compile.log").write_text("compiling 1: kernel module\ncompiled in 80.1 s\n")
    assert first_run.dead_compile() is None  # a finished one is not dead


@pytest.mark.slow
def test_a_compile_killed_under_way_is_restarted_by_the_next_command(tmp_path):
    """The README's order on a fresh machine: a first command starts the background compile; it dies
    (killed here, as a reinstall of the package under it kills it); the next command says so in one
    line, runs its scene and starts the compile again."""
    import signal
    import time

    env = _fresh_env(tmp_path, "background")
    first = subprocess.run([sys.executable, "-c", "from crashsim import first_run; print(first_run."
                            "start_background_compile())"], env=env, capture_output=True, text=True, timeout=120)
    log = Path(first.stdout.strip())
    lock = tmp_path / "fresh" / "compiling.lock"
    t0 = time.monotonic()
    while not lock.exists() and time.monotonic() - t0 < 60:
        time.sleep(0.2)
    pid = int(lock.read_text())
    os.kill(pid, signal.SIGKILL)  # dies without removing its lock or finishing its log
    time.sleep(0.5)
    try:
        out = subprocess.run([sys.executable, "-m", "crashsim", "run", str(SCENE)], env=env, capture_output=True,
                             text=True, timeout=900)
        assert out.returncode == 0, out.stderr
        notes = [ln for ln in out.stderr.splitlines() if "stopped before it finished" in ln]
        assert len(notes) == 1 and str(log) in notes[0]
        assert lock.exists() and int(lock.read_text()) != pid  # compiling again
    finally:
        try:
            os.kill(int(lock.read_text()), signal.SIGKILL)
        except (OSError, ValueError):
            pass


def test_the_ready_marker_follows_the_installed_files(tmp_path, monkeypatch):
    """numba stamps a cached kernel by its file; the marker does too (where, when written, what), so a
    reinstall is not taken for a ready cache that every process would recompile silently."""
    from crashsim import _jit

    src = tmp_path / "a" / "kernel.py"
    src.parent.mkdir()
    src.write_text("x = 1\n")
    monkeypatch.setattr(_jit, "kernel_sources", lambda impact=True: [src])
    d1 = _jit.digest()
    os.utime(src, ns=(src.stat().st_atime_ns, src.stat().st_mtime_ns + 10**9))  # the same file written again
    d2 = _jit.digest()
    other = tmp_path / "b" / "kernel.py"
    other.parent.mkdir()
    other.write_bytes(src.read_bytes())
    os.utime(other, ns=(src.stat().st_atime_ns, src.stat().st_mtime_ns))
    monkeypatch.setattr(_jit, "kernel_sources", lambda impact=True: [other])
    d3 = _jit.digest()  # the same bytes and time elsewhere (an editable install after a copy)
    assert len({d1, d2, d3}) == 3


def test_the_compile_names_its_sources_before_it_compiles(monkeypatch, tmp_path):
    """A reinstall under a long compile removed its sources before it wrote its marker (it died with
    FileNotFoundError after compiling); the marker is taken first now."""
    import crashsim.warmup as warmup

    order = []
    monkeypatch.setattr(warmup, "marker", lambda: order.append("marker") or tmp_path / "numba" / "ready-x")

    def stop():
        order.append("compile")
        raise RuntimeError("stop here")

    monkeypatch.setattr(warmup, "kernels", stop)
    with pytest.raises(RuntimeError):
        warmup.compile_kernels()
    assert order == ["marker", "compile"]


def test_a_killed_compile_not_yet_reaped_is_not_under_way(tmp_path, monkeypatch):
    """A compile killed under a parent that does not reap it (a container's init) is a zombie: it still
    answers kill(pid, 0), but it compiles nothing, so the lock it left does not count as a compile under way."""
    import signal
    import time

    monkeypatch.setattr(first_run, "cache_dir", lambda: tmp_path)
    child = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        (tmp_path / "compiling.lock").write_text(str(child.pid))
        assert first_run.compile_in_progress()
        os.kill(child.pid, signal.SIGKILL)
        t0 = time.monotonic()
        while not first_run._zombie(child.pid) and time.monotonic() - t0 < 10:
            time.sleep(0.05)
        assert first_run._zombie(child.pid)  # exited, not reaped: kill(pid, 0) still succeeds
        assert not first_run.compile_in_progress()
    finally:
        child.kill()
        child.wait()

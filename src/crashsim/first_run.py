"""What a command does on a machine whose kernels are not compiled yet (the first run).

The run-out and impact kernels are numba functions, compiled on first use and cached on disk
(:mod:`crashsim._jit`). Compiling all of them takes 1-2 minutes on one core; running one
scene with the same kernel source *interpreted* (numba's ``NUMBA_DISABLE_JIT=1``: the kernels are
then the plain Python functions they are written as) takes a few seconds, and gives the same
report to every printed digit (``tests/unit/test_first_run.py``). So a first command that runs one
scene does not wait for the compiler:

``background`` (the default, ``CRASHSIM_FIRST_RUN`` unset)
    A single-scene command (:data:`SINGLE_SCENE`: run, plot, animate, export) runs interpreted in a
    child process, while a detached process compiles the kernels into the cache for the next
    commands; should the compile finish first (a long scene), the interpreted run is stopped and the
    command runs compiled (its log: ``compile.log`` in the cache directory; one compile at a time, guarded by
    ``compiling.lock``). A command of many scenes (fit, mc, posterior) waits for a compile already
    under way, else compiles in this process first, with a progress display.
``wait``
    Every command compiles first, in this process (the behaviour before; the test suite uses it).
``interpret``
    A single-scene command runs interpreted and nothing is compiled.
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from ._jit import cache_dir, ready
from .errors import ScenarioError

__all__ = ["POLICIES", "SINGLE_SCENE", "ENV", "policy", "interpreted", "run_interpreted", "start_background_compile",
           "compile_in_progress", "wait_for_background_compile", "background_main", "dead_compile",
           "INTERPRETED_WALL_TIME"]

#: The run-out wall-time limit of an interpreted run [s] (the schema's largest): ``max_wall_time`` is a
#: budget for compiled kernels, and a result must not depend on whether they were compiled yet.
INTERPRETED_WALL_TIME = 1e6

#: Environment variable that chooses the first-run policy.
ENV = "CRASHSIM_FIRST_RUN"
POLICIES = ("background", "wait", "interpret")
#: Commands that compute one scene: cheaper interpreted than compiled on a first run.
SINGLE_SCENE = ("run", "plot", "animate", "export")
#: A lock older than this is a compile that died without removing it [s].
STALE_LOCK = 1800.0


def policy() -> str:
    """The first-run policy from ``$CRASHSIM_FIRST_RUN`` (``background`` when unset)."""
    value = os.environ.get(ENV, "background").strip().lower() or "background"
    if value not in POLICIES:
        raise ScenarioError(f"{ENV} = {value!r} is not a first-run policy; allowed {', '.join(POLICIES)}", field=ENV)
    return value


def interpreted() -> bool:
    """True in a process whose kernels run interpreted (numba's ``NUMBA_DISABLE_JIT``)."""
    from numba.core import config

    return bool(config.DISABLE_JIT)


def _lock() -> Path:
    return cache_dir() / "compiling.lock"


def compile_in_progress() -> bool:
    """True while a background compile holds the lock (a live process, a lock younger than :data:`STALE_LOCK`)."""
    lock = _lock()
    try:
        pid = int(lock.read_text().strip() or 0)
        age = time.time() - lock.stat().st_mtime
    except (OSError, ValueError):
        return False
    if age > STALE_LOCK:
        return False
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # pragma: no cover - a live process of another user
        return True
    return not _zombie(pid)


def _zombie(pid: int) -> bool:
    """True if ``pid`` has exited but is not reaped yet (Linux ``/proc``: state Z): a compile killed
    under a parent that does not reap it (a container's init) still answers ``kill(pid, 0)``."""
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat[stat.rfind(")") + 2:].startswith("Z")


def dead_compile() -> str | None:
    """One line on a background compile that stopped before it finished (its log without the closing
    "compiled in" line, no compile under way, the kernels not ready): a reinstall under it, a kill;
    None otherwise."""
    log = cache_dir() / "compile.log"
    if ready() or compile_in_progress() or not log.is_file():
        return None
    try:
        lines = [ln.strip() for ln in log.read_text(errors="replace").splitlines() if ln.strip()]
    except OSError:
        return None
    if lines and lines[-1].startswith("compiled in"):
        return None
    last = lines[-1][:160] if lines else "(empty)"
    return f"the background compile started earlier stopped before it finished (its log {log} ends: {last})"


def start_background_compile() -> Path | None:
    """Start a detached process that compiles the kernels (unless one is under way); returns its log file.

    The process outlives this command; it takes the lock itself (:func:`background_main`).
    """
    if compile_in_progress():
        return None
    log = cache_dir() / "compile.log"
    try:
        log.parent.mkdir(parents=True, exist_ok=True)
        out = open(log, "w")
    except OSError:  # a cache that cannot be written: nothing would be kept anyway
        return None
    with out:
        env = {k: v for k, v in os.environ.items() if k != "NUMBA_DISABLE_JIT"}
        kwargs = {"start_new_session": True} if os.name == "posix" else \
            {"creationflags": getattr(subprocess, "DETACHED_PROCESS", 0)}  # pragma: no cover - Windows
        subprocess.Popen([sys.executable, "-m", "crashsim.warmup"], stdin=subprocess.DEVNULL, stdout=out,
                         stderr=subprocess.STDOUT, env=env, close_fds=True, **kwargs)
    return log


def run_interpreted(argv: list[str], race: bool = False, poll: float = 0.2) -> int | None:
    """Run ``crashsim argv`` in a child process with the kernels interpreted; its exit code.

    The child's output is held and passed on when it ends, so that with ``race`` (a compile under
    way in the background) a scene that runs longer interpreted than the compile takes is stopped
    once the kernels are ready, and None is returned: the caller then runs the command compiled
    (a long scene interpreted can take longer than the compile).
    """
    env = dict(os.environ, NUMBA_DISABLE_JIT="1")
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        child = subprocess.Popen([sys.executable, "-m", "crashsim", *argv], env=env, stdout=out, stderr=err)
        while child.poll() is None:
            if race and ready():
                child.terminate()
                child.wait()
                return None
            time.sleep(poll)
        for src, dst in ((out, sys.stdout), (err, sys.stderr)):
            src.seek(0)
            dst.flush()
            data = src.read()
            if hasattr(dst, "buffer"):
                dst.buffer.write(data)
            else:  # a text stream without bytes (pytest's capture): decoded
                dst.write(data.decode())
            dst.flush()
        return child.returncode


def wait_for_background_compile(poll: float = 1.0, timeout: float = 3600.0) -> bool:
    """Wait while a background compile is under way; True if the kernels are ready afterwards."""
    t0 = time.monotonic()
    while compile_in_progress() and time.monotonic() - t0 < timeout:
        time.sleep(poll)
    return ready()


def _take(lock: Path) -> bool:
    """Create the lock with this process's id, unless a live compile holds it (a stale one is replaced)."""
    for _ in range(2):
        try:
            lock.parent.mkdir(parents=True, exist_ok=True)
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            if compile_in_progress():
                return False
            try:
                lock.unlink()
            except OSError:
                return False
            continue
        except OSError:
            return False
        with os.fdopen(fd, "w") as f:
            f.write(str(os.getpid()))
        return True
    return False


def background_main(compile_kernels) -> int:
    """The detached compile (``python -m crashsim.warmup``): take the lock, compile every kernel with
    ``compile_kernels`` (:func:`crashsim.warmup.compile_kernels`, which marks the cache ready; passed in so
    that this module, which every command reads, does not load the kernels), drop the lock."""
    lock = _lock()
    if not _take(lock):
        return 0  # another compile is under way
    try:
        t0 = time.perf_counter()

        def say(text):
            sys.stdout.write(text + "\n")
            sys.stdout.flush()

        compile_kernels(lambda i, label: say(f"compiling {i + 1}: {label}"))
        say(f"compiled in {time.perf_counter() - t0:.1f} s")
    finally:
        try:
            lock.unlink()
        except OSError:  # pragma: no cover
            pass
    return 0

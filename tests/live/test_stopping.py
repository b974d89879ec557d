"""`crashsim live` stopped by a signal: its band workers stop with it, and Ctrl+C prints no worker
tracebacks (a stranger found two band workers still running, orphaned, after a SIGTERM)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

SCENE = Path(__file__).parents[2] / "scenarios" / "scenes" / "pinned_car.toml"

pytestmark = pytest.mark.skipif(not Path("/proc").is_dir() or sys.platform != "linux",
                                reason="reads the process table from /proc (Linux)")


def _children(pid: int) -> list[int]:
    out = []
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            try:
                stat = (d / "stat").read_text()
            except OSError:
                continue
            if int(stat.rsplit(")", 1)[1].split()[1]) == pid:
                out.append(int(d.name))
    return out


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    return not Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z"


def _serve():
    """A live server with its band (two workers) started and answering."""
    assert "[uncertainty]" in SCENE.read_text()
    # Ctrl+C as a terminal sends it: the default SIGINT handling restored (a background job has it
    # ignored), the signal sent to the whole process group
    code = ("import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
            "from crashsim.cli import main; sys.exit(main(sys.argv[1:]))")
    p = subprocess.Popen([sys.executable, "-c", code, "live", str(SCENE), "--no-browser", "--workers", "2",
                          "--band-samples", "4"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         start_new_session=True)
    lines = []
    for line in p.stderr:
        lines.append(line)
        if "http://127.0.0.1:" in line:
            break
    deadline = time.monotonic() + 60
    while len(_children(p.pid)) < 2 and time.monotonic() < deadline:
        time.sleep(0.1)
    workers = _children(p.pid)
    assert len(workers) >= 2, "".join(lines)
    return p, workers


def _gone(pids, seconds=20.0) -> bool:
    """The processes ``pids`` ended within ``seconds``; any still running are killed (no orphan
    outlives a failed test)."""
    deadline = time.monotonic() + seconds
    while any(_alive(w) for w in pids) and time.monotonic() < deadline:
        time.sleep(0.1)
    left = [w for w in pids if _alive(w)]
    for w in left:
        os.kill(w, signal.SIGKILL)
    return not left


@pytest.mark.slow
@pytest.mark.parametrize("how", ["SIGTERM", "Ctrl+C"])
def test_a_stopped_server_stops_its_band_workers(how):
    p, workers = _serve()
    if how == "SIGTERM":
        p.send_signal(signal.SIGTERM)
    else:
        os.killpg(p.pid, signal.SIGINT)
    _, err = p.communicate(timeout=60)
    assert _gone(workers)
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err


@pytest.mark.slow
def test_band_workers_end_themselves_when_the_server_is_killed():
    p, workers = _serve()
    p.kill()  # SIGKILL: no handler runs, the workers are orphaned and must notice
    p.wait(timeout=30)
    assert _gone(workers)

"""A new user's first result: the README's first command on a machine whose kernels are not compiled.

    python benchmarks/first_run.py              # 3 repeats
    python benchmarks/first_run.py --repeats 1

The README opens with ``pip install . && crashsim run scenarios/scenes/intersection_car_trailer_wheels.toml``.
After the install, what a new user waits for is that ``crashsim run``: the kernels are not compiled on
their machine yet. Each repeat gives the command a cache directory of its own (``CRASHSIM_CACHE_DIR``,
empty: nothing compiled), runs it with the default first-run policy (``background``: the scene runs
interpreted while a detached process compiles), and measures

* the first result: the command's wall time, start to exit;
* the background compile, from its log (it runs on alongside and after the command), and the next
  command once it has finished (compiled, from the cache): in the first repeat (the later repeats
  stop the compile after the first result);
* for comparison, the first run with ``CRASHSIM_FIRST_RUN=wait`` (compile first, in the command: the
  behaviour before), one repeat.

Writes plots/first_run.md (medians of the repeats). Goal (issue 20): the first result within 20 s.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from _machine import cpu_name

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
SCENE = re.search(r"crashsim run (\S+)", README).group(1)
GOAL = 20.0


def _run(cache: Path, policy: str) -> tuple[float, str]:
    env = dict(os.environ, CRASHSIM_CACHE_DIR=str(cache), CRASHSIM_FIRST_RUN=policy)
    env.pop("NUMBA_CACHE_DIR", None)
    env.pop("NUMBA_DISABLE_JIT", None)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-m", "crashsim", "run", SCENE], cwd=ROOT, env=env, capture_output=True,
                         text=True)
    elapsed = time.perf_counter() - t0
    if out.returncode != 0:
        raise SystemExit(f"crashsim run failed ({out.returncode}): {out.stderr}")
    return elapsed, out.stdout


def _wait_compile(cache: Path, timeout: float = 1800.0) -> float:
    log = cache / "compile.log"
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        text = log.read_text() if log.exists() else ""
        m = re.search(r"compiled in ([\d.]+) s", text)
        if m and not (cache / "compiling.lock").exists():
            return float(m.group(1))
        time.sleep(1.0)
    raise SystemExit(f"the background compile did not finish in {timeout:.0f} s: {log}")


def _stop_compile(cache: Path) -> None:
    """End the background compile of ``cache`` (its pid is in the lock) and wait until it is gone."""
    import signal

    lock = cache / "compiling.lock"
    for _ in range(100):
        if lock.exists():
            break
        time.sleep(0.1)
    try:
        pid = int(lock.read_text().strip())
        os.kill(pid, signal.SIGTERM)
    except (OSError, ValueError):
        return
    for _ in range(300):
        try:
            os.kill(pid, 0)
        except OSError:
            return
        time.sleep(0.1)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    first, compile_, nxt, same = [], [], [], True
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(args.repeats):
            cache = Path(tmp) / f"cache{i}"
            t, out1 = _run(cache, "background")
            first.append(t)
            if i == 0:  # the compile it started, to its end, and the next command
                compile_.append(_wait_compile(cache))
                t2, out2 = _run(cache, "background")
                nxt.append(t2)
                same &= out1 == out2
            else:  # the first result alone: stop the compile it started
                _stop_compile(cache)
        t_wait, out3 = _run(Path(tmp) / "wait", "wait")
        same &= out3 == out1
    med = statistics.median
    rows = [
        ("first result (`crashsim run`, nothing compiled: interpreted, compile in the background)", med(first),
         first),
        ("the background compile (alongside and after it)", med(compile_), compile_),
        ("the next command (compiled, from the cache)", med(nxt), nxt),
        ("first result with `CRASHSIM_FIRST_RUN=wait` (compile first: the behaviour before)", t_wait, [t_wait]),
    ]
    md = ["# A new user's first result", "",
          "Regenerate: `python benchmarks/first_run.py`.", "",
          f"Command: `crashsim run {SCENE}` (the README's first command after `pip install .`), each repeat with an "
          "empty kernel cache of its own (`CRASHSIM_CACHE_DIR`).", "",
          f"Machine: {os.cpu_count()} cores ({cpu_name()}); Python {platform.python_version()}; load average at "
          f"start {load:.2f}.", "",
          "| what | median wall time | repeats |", "| --- | --- | --- |"]
    md += [f"| {name} | {m:.1f} s | {', '.join(f'{v:.1f}' for v in vals)} |" for name, m, vals in rows]
    verdict = "met" if med(first) <= GOAL else f"**missed** by {med(first) - GOAL:.1f} s"
    md += ["", f"Goal: the first result within {GOAL:.0f} s: {verdict} ({med(first):.1f} s). "
           f"The interpreted, compiled and compile-first runs print the same report: {'yes' if same else 'NO'}.", ""]
    (ROOT / "plots" / "first_run.md").write_text("\n".join(md))
    sys.stdout.write("\n".join(md) + "\n")
    return 0 if same else 1


if __name__ == "__main__":
    raise SystemExit(main())

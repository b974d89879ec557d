"""What the test suite costs: CPU minutes of the developer's fast tier and of the full suite (issue
"Compile once, vary by name", item 8 and its goal: the fast tier <= 3 CPU-minutes, the full suite
<= 12; CI's generic-CPU rerun of tests/validation, which the goal counted, is gone: it changed no
bit, plots/cpu_target_bits.md).

    python benchmarks/test_tiers.py            # both tiers, one after the other
    python benchmarks/test_tiers.py --fast     # the fast tier only
    python benchmarks/test_tiers.py --write-slow-list   # tests/slow_tests.txt from a fast-tier run's durations

Each tier runs as a child ``python -m pytest -q -p no:cacheprovider`` with the kernels already
compiled (the first compile, 4-5 minutes of one core, is a machine's once, not a test run's: run a
command first). CPU time (user + system of the child and everything it started:
``RUSAGE_CHILDREN`` around it) is what the goal counts; wall time is given beside it and waits for
the cores of a shared machine. Each tier's count of tests and its exit code come from pytest's last
line. Writes plots/test_tiers.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import sys
import time
from pathlib import Path

from _machine import cpu_name, run_cpu

ROOT = Path(__file__).resolve().parents[1]

#: (label, pytest arguments, environment changes, goal [CPU minutes] or None)
TIERS = [
    ("fast tier: `python -m pytest -m \"not slow\" -q`", ["-m", "not slow"], {}, 3.0),
    ("full suite: `python -m pytest -q` (the README's test command, CI's)", [], {}, 12.0),
]


def _run(args: list[str], env_extra: dict) -> dict:
    env = dict(os.environ, MPLBACKEND="Agg", **env_extra)
    w0 = time.perf_counter()
    cpu, out = run_cpu([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *args], cwd=ROOT,
                       env=env, capture_output=True, text=True)
    w1 = time.perf_counter()
    last = [line for line in out.stdout.strip().splitlines() if line.strip()][-1:] or [""]
    counts = dict((k, int(n)) for n, k in re.findall(r"(\d+) (passed|failed|skipped|deselected|error)", last[0]))
    failed = [line.split(" - ")[0].removeprefix("FAILED ").removeprefix("ERROR ")
              for line in out.stdout.splitlines() if line.startswith(("FAILED ", "ERROR "))]
    return {"cpu_min": cpu / 60.0,
            "wall_min": (w1 - w0) / 60.0, "code": out.returncode, "counts": counts, "summary": last[0].strip("= "),
            "failed": failed, "stdout": out.stdout}


#: A test function whose call or set-up took at least this long in a fast-tier run goes to the slow list.
SLOW_SECONDS = 0.7


def slow_functions(pytest_output: str, seconds: float = SLOW_SECONDS) -> list[str]:
    """The test functions (all parameters together) of pytest's ``--durations`` lines at or over
    ``seconds``."""
    found = set()
    for m in re.finditer(r"^\s*([\d.]+)s (?:call|setup|teardown)\s+(\S+)", pytest_output, re.M):
        if float(m.group(1)) >= seconds:
            found.add(m.group(2).split("[")[0])
    return sorted(found)


def write_slow_list() -> int:
    """Run the fast tier with durations and add its slow test functions to tests/slow_tests.txt."""
    out = _run(["-m", "not slow", "--durations=0", f"--durations-min={SLOW_SECONDS}"], {})
    path = ROOT / "tests" / "slow_tests.txt"
    old = [ln for ln in path.read_text().splitlines() if ln and not ln.startswith("#")] if path.exists() else []
    names = sorted(set(old) | set(slow_functions(out["stdout"])))
    path.write_text("\n".join([f"# Test functions the fast tier leaves to the full suite (a call or set-up of at least "
                               f"{SLOW_SECONDS:g} s in a fast-tier run).",
                               "# Written by `python benchmarks/test_tiers.py --write-slow-list`; read by tests/conftest.py.",
                               *names, ""]))
    print(f"wrote {path.relative_to(ROOT)}: {len(names)} test functions", file=sys.stderr)
    return out["code"]


def _python_pass_cpu(repeats: int = 10) -> float:
    """The least CPU time [s] of ``python -c pass`` over ``repeats`` runs: the machine's speed in this run."""
    return min(run_cpu([sys.executable, "-c", "pass"], check=True)[0] for _ in range(repeats))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fast", action="store_true", help="the fast tier only")
    ap.add_argument("--write-slow-list", action="store_true",
                    help="add the fast tier's slow test functions to tests/slow_tests.txt (no table)")
    args = ap.parse_args(argv)
    if args.write_slow_list:
        return write_slow_list()
    tiers = TIERS[:1] if args.fast else TIERS
    base = _python_pass_cpu()
    rows = []
    for label, pytest_args, env_extra, goal in tiers:
        print(f"running {label} ...", file=sys.stderr)
        rows.append((label, goal, _run(pytest_args, env_extra)))
        print(f"  {rows[-1][2]['summary']}: {rows[-1][2]['cpu_min']:.2f} CPU-min", file=sys.stderr)
    md = ["# Test suite: CPU minutes per tier", "",
          f"`python benchmarks/test_tiers.py{' --fast' if args.fast else ''}` on {cpu_name()} "
          f"({os.cpu_count()} cores, shared), Python {platform.python_version()}, the kernels compiled before "
          "the run. CPU time is user + system of pytest and all it "
          "started; wall time waits for the cores of a shared machine besides. CI runs the full suite once: "
          "its rerun compiled for a generic processor is gone (the same bits, `plots/cpu_target_bits.md`).", "",
          "| tier | tests | exit code | CPU [min] | wall [min] | goal [CPU min] | met? |",
          "|---|---|---:|---:|---:|---:|---|"]
    for label, goal, r in rows:
        c = r["counts"]
        tests = f"{c.get('passed', 0)} passed, {c.get('failed', 0)} failed, {c.get('skipped', 0)} skipped"
        verdict = "" if goal is None else ("met" if r["cpu_min"] <= goal else "**missed**")
        md.append(f"| {label} | {tests} | {r['code']} | {r['cpu_min']:.2f} | {r['wall_min']:.2f} | "
                  f"{'' if goal is None else f'<= {goal:g}'} | {verdict} |")
    for label, _, r in rows:
        if r["failed"]:
            md += ["", f"Failed in {label.split(':')[0]}: " + ", ".join(f"`{t}`" for t in r["failed"])]
    md += ["", f"The machine's speed in this run: `python -c pass` took {base:.3f} s of CPU (the least of 10); the "
           "goals are CPU minutes, so a slower day (the machines here drift 2-3x) reads as a dearer suite: "
           + "; ".join(f"{label.split(':')[0]} {r['cpu_min'] * 60 / base:,.0f} x `python -c pass`" for label, _, r in rows)
           + ".", "", "CI also installs the package and builds the documentation site; neither is counted here."]
    md.append("")
    (ROOT / "plots" / "test_tiers.md").write_text("\n".join(md))
    print("wrote plots/test_tiers.md", file=sys.stderr)
    return 0 if all(r["code"] == 0 for _, _, r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())

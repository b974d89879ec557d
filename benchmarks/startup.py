"""What a command costs before it does any work: CPU time of the light face (issue "Compile once,
vary by name", item 6).

    python benchmarks/startup.py               # 7 repeats
    python benchmarks/startup.py --repeats 3

Each command runs as a fresh process, several times; the CPU time (user + system) of each run is the
difference of ``resource.getrusage(RUSAGE_CHILDREN)`` around it, and the table gives the median, in
seconds and as a multiple of ``python -c pass`` (the interpreter's own start, the floor). CPU time,
not wall time: it is what the imports cost whatever else the machine runs (wall time on a shared
machine includes waiting for a core). The kernels' cache is as found (a refused input does not
reach them).

Goals (the issue): ``import crashsim`` <= 0.3 s CPU, ``crashsim --version`` <= 0.5 s CPU, a refused
bad input within 1 s CPU. Writes plots/startup.md.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _machine import run_cpu

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


def _cpu(cmd: list[str], env: dict) -> tuple[float, int]:
    """CPU seconds (user + system) of one run of ``cmd``, and its exit code."""
    cpu, out = run_cpu(cmd, cwd=ROOT, env=env, capture_output=True, text=True)
    return cpu, out.returncode


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args(argv)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")]))
    py = sys.executable
    with tempfile.TemporaryDirectory() as tmp:
        bad = Path(tmp) / "bad_key.toml"
        bad.write_text(SCENE.read_text().replace("[scenario]\n", '[scenario]\ntitel = "typo"\n', 1))
        odd = Path(tmp) / "bad_key_nmi.toml"  # one value in a unit outside the shipped table
        odd.write_text(bad.read_text().replace('"0 m"', '"0 nmi"', 1))
        if odd.read_text() == bad.read_text():
            raise SystemExit(f"{SCENE}: no value '0 m' to write in nmi")
        missing = Path(tmp) / "missing.toml"
        # (label, command, goal [s CPU] or None, expected exit code)
        cases = [
            ("`python -c pass`", [py, "-c", "pass"], None, 0),
            ("`python -c \"import crashsim\"`", [py, "-c", "import crashsim"], 0.3, 0),
            ("`python -c \"import crashsim.units\"`", [py, "-c", "import crashsim.units"], None, 0),
            ("`crashsim --version`", [py, "-m", "crashsim", "--version"], 0.5, 0),
            ("`crashsim --help`", [py, "-m", "crashsim", "--help"], None, 0),
            ("`python -c \"import crashsim.scenario\"` (the loader)", [py, "-c", "import crashsim.scenario"],
             None, 0),
            ("`python -c \"import crashsim.scenario, pint; pint.UnitRegistry()\"`",
             [py, "-c", "import crashsim.scenario, pint; pint.UnitRegistry()"], None, 0),
            ("`python -c \"import dask.base\"`", [py, "-c", "import dask.base"], None, 0),
            ("`crashsim run missing.toml` (refused: no such file)", [py, "-m", "crashsim", "run", str(missing)],
             1.0, 2),
            ("`crashsim run bad_key.toml` (refused: unknown key `scenario.titel`)",
             [py, "-m", "crashsim", "run", str(bad)], 1.0, 2),
            ("`crashsim run bad_key_nmi.toml` (the same, with one length in `nmi`: a unit pint reads)",
             [py, "-m", "crashsim", "run", str(odd)], None, 2),
        ]
        rows = []
        for label, cmd, goal, code in cases:
            times = []
            for _ in range(args.repeats):
                t, rc = _cpu(cmd, env)
                if rc != code:
                    raise SystemExit(f"{label}: exit code {rc}, expected {code}")
                times.append(t)
            rows.append((label, statistics.median(times), min(times), max(times), goal))
            print(f"{label}: median {rows[-1][1]:.3f} s CPU", file=sys.stderr)
    probe = ("import sys, crashsim.scenario; print(' '.join(sorted({m.split('.')[0] for m in sys.modules} & "
             "{'numba', 'llvmlite', 'scipy', 'matplotlib', 'pint', 'pymunk', 'numpy'})))")
    heavy = subprocess.run([py, "-c", probe], cwd=ROOT, env=env, capture_output=True, text=True,
                           check=True).stdout.split()
    base = rows[0][1]
    cost = {label: med for label, med, *_ in rows}
    md = ["# Startup: CPU time before any work", "",
          f"`python benchmarks/startup.py --repeats {args.repeats}` on {platform.machine()} "
          f"({os.cpu_count()} cores, shared), Python {platform.python_version()}. CPU time (user + system) "
          "of a fresh process, the median of the repeats (min-max beside it), and its ratio to "
          "`python -c pass`. The goals are the issue's (\"Compile once, vary by name\", item 6).", "",
          "| command | CPU [s] (median) | min-max [s] | x `python -c pass` | goal | met? |",
          "|---|---:|---:|---:|---:|---|"]
    for label, med, lo, hi, goal in rows:
        verdict = "" if goal is None else ("met" if med <= goal else "**missed**")
        md.append(f"| {label} | {med:.3f} | {lo:.3f}-{hi:.3f} | {med / base:.1f} | "
                  f"{'' if goal is None else f'<= {goal:g} s'} | {verdict} |")
    loader = cost["`python -c \"import crashsim.scenario\"` (the loader)"]
    registry = cost["`python -c \"import crashsim.scenario, pint; pint.UnitRegistry()\"`"] - loader
    dask = cost['`python -c "import dask.base"`']
    refused = cost["`crashsim run bad_key.toml` (refused: unknown key `scenario.titel`)"]
    gap = refused - cost["`crashsim run missing.toml` (refused: no such file)"]
    with_pint = rows[-1][1] - refused  # the same refusal with one value that only pint reads
    md += ["", f"The refusals are the scenario loader at work: `import crashsim.scenario` costs {loader:.2f} s and "
           f"loads, of the heavy libraries, only {', '.join(heavy) or 'none'} (no engine: the loader reads and "
           "checks a file, it simulates nothing; the CLI validates the file before it imports any engine). "
           f"A missing file is refused by the loader before any value is parsed; an unknown key is refused "
           f"after every value of the file is parsed: {gap:.2f} s more. Values in the documented spellings "
           "(m, ft, km/h, mph, kg, lb, deg, ...) are read from the shipped table of pint's factors "
           "(`crashsim.units.factor_table`, `src/crashsim/data/unit_factors.json`) without importing pint; "
           f"one value in another unit (`nmi`, last row) imports pint and builds its registry: {with_pint:.2f} s "
           f"more (pint's import and registry alone: {registry:.2f} s, the two loader rows' difference; "
           f"pint's import loads `dask.base` where dask is installed, {dask - base:.2f} s over the "
           "interpreter's start). Pint's own registry cache (`cache_folder`) would save part of that, but its "
           "files are written without an atomic rename, which parallel workers starting together could read "
           "half-written: left alone.", "",
           "Before the light face (main at 10c4382, measured once each on the same machine): "
           "`import crashsim` 1.33 s CPU (it loaded numba, llvmlite, scipy.integrate and scipy.optimize), "
           "`crashsim --version` 2.7 s CPU.", ""]
    (ROOT / "plots" / "startup.md").write_text("\n".join(md))
    print("wrote plots/startup.md", file=sys.stderr)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

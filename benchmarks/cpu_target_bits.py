"""Do the compiled kernels give other bits when numba compiles them for another processor?

    python benchmarks/cpu_target_bits.py

numba compiles for the host CPU by default (``NUMBA_CPU_NAME`` unset: every instruction set the
processor has); ``NUMBA_CPU_NAME=generic`` compiles for a baseline x86-64 processor. This runs
``benchmarks/results_sha.py --quick`` (every shipped scene's JSON result with the compiled run-out,
the fit and a 200-sample Monte Carlo of the shipped fit scene) twice on this machine: once with the
kernels compiled for the host, once compiled afresh for the generic processor into an empty cache,
and compares the SHA-256 of every result.

Why it matters: CI used to rerun tests/validation compiled for the generic processor (about 5 CPU
minutes, most of it the compile), to catch an expectation that holds only for this processor's
round-off. The kernels are compiled without fast-math (no reassociation, no fused multiply-add
contraction), so the processor's instruction set should not change a bit; this measures it. A
different bit on another machine comes from another libm, NumPy or LAPACK build, which no
compile flag here can imitate: the tests' tolerances carry that (see docs/contributing.md).

Writes plots/cpu_target_bits.md.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import sys
import tempfile
from pathlib import Path

from _machine import cpu_name, run_cpu

ROOT = Path(__file__).resolve().parents[1]
SHA = [sys.executable, str(ROOT / "benchmarks" / "results_sha.py"), "--quick"]
COMPILE = [sys.executable, "-c", "from crashsim.warmup import compile_kernels; compile_kernels()"]


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        host_json, generic_json = Path(tmp) / "host.json", Path(tmp) / "generic.json"
        env = dict(os.environ, MPLBACKEND="Agg")
        subprocess.run(COMPILE, env=env, check=True)  # compiled before, as a user's machine has it: not counted
        host_cpu = run_cpu([*SHA, "--out", str(host_json)], env=env, check=True, capture_output=True)[0]
        genv = dict(env, NUMBA_CPU_NAME="generic", CRASHSIM_CACHE_DIR=str(Path(tmp) / "cache"))
        genv.pop("NUMBA_CACHE_DIR", None)
        compile_cpu = run_cpu(COMPILE, env=genv, check=True)[0]
        generic_cpu = run_cpu([*SHA, "--out", str(generic_json)], env=genv, check=True, capture_output=True)[0]
        host, generic = json.loads(host_json.read_text()), json.loads(generic_json.read_text())
    differ = sorted(k for k in host if generic.get(k) != host[k])
    same = len(host) - len(differ)
    md = ["# Compiled for the host processor or a generic one: the same bits?", "",
          f"`python benchmarks/cpu_target_bits.py` on {cpu_name()} ({os.cpu_count()} cores, shared), Python "
          f"{platform.python_version()}. `benchmarks/results_sha.py --quick` twice: the kernels compiled for this "
          "processor, then compiled afresh with `NUMBA_CPU_NAME=generic` into an empty cache.", "",
          "| | CPU [min] |", "|---|---:|",
          f"| the results, host kernels | {host_cpu / 60:.2f} |",
          f"| the generic compile | {compile_cpu / 60:.2f} |",
          f"| the results, generic kernels | {generic_cpu / 60:.2f} |", "",
          f"{same} of {len(host)} results byte-identical"
          + (":" if differ else ": the processor's instruction set changes no bit of any result (the kernels use "
             "no fast-math and no fused multiply-add contraction), so a rerun of the tests compiled for another "
             "processor tests nothing the first run did not.")]
    md += [f"- differs: `{k}`" for k in differ]
    md.append("")
    (ROOT / "plots" / "cpu_target_bits.md").write_text("\n".join(md))
    print("\n".join(md))
    return 0 if not differ else 1


if __name__ == "__main__":
    raise SystemExit(main())

"""Speed of the impact solver: one impact through the public API, and batch throughput per core.

Run from the repository root (one thread: the thread limits are set below before numpy loads)::

    python benchmarks/impact_speed.py            # full run, ~2-4 min, writes plots/impact_speed.*
    python benchmarks/impact_speed.py --quick    # ~30 s smoke run, prints only (unless --out is given)

Options: ``--repeats N`` (default 7), ``--out DIR``, ``--replot`` (redraw from ``impact_speed.json``).

Goals (issue 13, item 1): one impact through the public API (``solve_impact``) in <= 50 us;
``ImpactBatch.solve`` >= 1e6 impacts per second per core. Judged on the paper's Table 6 pair
(tractor-semitrailer struck by a car: 3 bodies, a hitch, 5 unknowns; scenarios/paper/table6.toml)
and a car-car impact (3 unknowns); the paper's Table 5 pair (two tractor-semitrailers, 7
unknowns) is reported too. Each figure is shown beside the cost of the physics alone:

* single solve: the compiled kernel called on the packed numbers of one impact (numba dispatch +
  the solve), and per item inside a large batch (the arithmetic alone); the rest of
  ``solve_impact`` is the structure lookup and packing of the numbers, and the result object;
* batch: the raw kernel call (no Python around it) and, as a yardstick, numpy's batched LAPACK
  solve of the same no-slide systems (``np.linalg.solve`` on a (B, K, K) stack: the linear solve
  alone, without assembly, laws, condition number or outputs).

The reference paths are timed alongside in interleaved rounds (``solve_arrays(method="dense")``,
the numpy path of the same equations; the full single-solve path with the SVD condition number,
numpy work and admissibility). Rates per CPU second of the
process are the "per core" figures (the machine is shared; wall-clock rates are listed too).

Writes ``impact_speed.md``, ``impact_speed.png`` and ``impact_speed.json`` into ``--out``
(default ``plots/``; ``--quick`` writes only if ``--out`` is given).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "VECLIB_MAXIMUM_THREADS",
             "NUMEXPR_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from dataclasses import replace  # noqa: E402
from pathlib import Path  # noqa: E402

from _machine import cpu_name  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from crashsim import (Body, BodyState, CrushSurface, Hitch, ImpactBatch, ImpactProblem,  # noqa: E402
                      TangentialLaw, Vehicle, chain_states, solve_impact)
from crashsim.geometry import rotate  # noqa: E402
from crashsim.impact import kernel as _kernel, core  # noqa: E402
from crashsim.impact import solve as _solve  # noqa: E402
from crashsim.impact.result import ImpactResult, _body_impacts  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

SINGLE_GOAL = 50e-6      # s per solve_impact call
BATCH_GOAL = 1_000_000   # impacts per second per core
LAWS = ("no_slide", "friction", "ratio")
JUDGED = ("table6", "car_car")
PROBLEMS = ("table6", "car_car", "table5")
SIZES = (1_000, 10_000, 100_000)
QUICK_SIZES = (10_000,)
UNKNOWNS = {"table6": 5, "car_car": 3, "table5": 7}
LABEL = {"table6": "Table 6 (tractor-semitrailer + car, 5 unknowns)", "car_car": "car-car (3 unknowns)",
         "table5": "Table 5 (two tractor-semitrailers, 7 unknowns)"}


# --------------------------------------------------------------------------------------------
# The impacts
# --------------------------------------------------------------------------------------------

def table5_problem(law: str = "no_slide", value: float = 0.0) -> ImpactProblem:
    """Table 5: B (tractor + loaded trailer, heading +y) into A's empty trailer (heading +x)."""
    a = Vehicle("A", (Body("A_tractor", 9500, 21000), Body("A_trailer", 6000, 48000)), (Hitch((-3.1, 0), (3.991, 0)),))
    b = Vehicle("B", (Body("B_tractor", 9500, 21000), Body("B_trailer", 20000, 150000)), (Hitch((-3.1, 0), (3.991, 0)),))
    sa = chain_states(a, (0.0, 0.0), 0.0, (13.41, 0.0))
    pt = np.asarray(sa["A_trailer"].position) + (-2.517, -1.157)
    cg_b = pt - rotate((3.922, 0.011), math.pi / 2)  # B's front contact: 3.922 ahead, 0.011 left of its CG
    sb = chain_states(b, tuple(cg_b), math.pi / 2, (0.0, 13.41))
    return ImpactProblem((a, b), {**sa, **sb}, "A_trailer", "B_tractor",
                         CrushSurface(tuple(pt), math.pi / 2, 0.05, TangentialLaw(law, value), -1.0, -1))


def table6_problem(law: str = "no_slide", value: float = 0.0) -> ImpactProblem:
    """The paper's Table 6 scenario file's impact, with the given tangential law."""
    p = load_scenario(ROOT / "scenarios" / "paper" / "table6.toml").impact
    return replace(p, surface=replace(p.surface, tangential=TangentialLaw(law, value)))


def car_car_problem(law: str = "no_slide", value: float = 0.0) -> ImpactProblem:
    """A car (1500 kg, heading +x, 15 m/s) struck on its right front by a car (1300 kg, heading
    +y, 12 m/s) whose front is 1 m off its centre line: a 90 degree intersection impact."""
    a = Vehicle("A", (Body("A_car", 1500.0, 2500.0),))
    b = Vehicle("B", (Body("B_car", 1300.0, 2000.0),))
    point = (1.0, -0.9)
    states = {"A_car": BodyState((0.0, 0.0), 0.0, (15.0, 0.0)),
              "B_car": BodyState((1.3, -0.9 - 2.2), math.pi / 2, (0.0, 12.0))}
    return ImpactProblem((a, b), states, "A_car", "B_car",
                         CrushSurface(point, math.pi / 2, 0.1, TangentialLaw(law, value), -1.0, -1))


def problem(name: str, law: str = "no_slide", value: float = 0.0) -> ImpactProblem:
    return {"table5": table5_problem, "table6": table6_problem, "car_car": car_car_problem}[name](law, value)


def randomised_batch(name: str, law: str, n: int, seed: int = 1) -> ImpactBatch:
    """n impacts of one problem with random speeds (x 0.5-1.5 per vehicle), crush normal
    (+-10 deg), e in [0, 0.3], f in [0.2, 0.8] (friction) or mu in [-0.8, 0.8] (ratio)."""
    value = {"no_slide": 0.0, "friction": 0.5, "ratio": 0.0}[law]
    batch = ImpactBatch.from_problem(problem(name, law, value), n)
    A, S = batch.arrays, batch.structure
    rng = np.random.default_rng(seed)
    for k in range(len(S.vehicle_names)):
        scale = rng.uniform(0.5, 1.5, n)
        for b, v in enumerate(S.vehicle_index):
            if v == k:
                A.velocity[:, b] *= scale[:, None]
                A.yaw_rate[:, b] *= scale
    A.normal_angle[:] += np.radians(rng.uniform(-10.0, 10.0, n))
    A.restitution[:] = rng.uniform(0.0, 0.3, n)
    if law == "friction":
        A.law_value[:] = rng.uniform(0.2, 0.8, n)
    elif law == "ratio":
        A.law_value[:] = rng.uniform(-0.8, 0.8, n)
    return batch


# --------------------------------------------------------------------------------------------
# Timing
# --------------------------------------------------------------------------------------------

SPREAD: list[float] = []
CPU = {"cpu": 0.0, "wall": 0.0}


def _timed(fn, min_time: float) -> tuple[float, float]:
    """(wall, CPU) time per call of fn(), repeated to last >= min_time (wall)."""
    k, t0, c0 = 0, time.perf_counter(), time.process_time()
    while True:
        fn()
        k += 1
        dt = time.perf_counter() - t0
        if dt >= min_time:
            break
    dc = time.process_time() - c0
    CPU["cpu"] += dc
    CPU["wall"] += dt
    return dt / k, dc / k


def interleaved(calls: dict, repeats: int, min_time: float) -> tuple[dict, dict]:
    """Median wall and CPU time per call of each function over ``repeats`` interleaved rounds
    (after one warm-up call each)."""
    for fn in calls.values():
        fn()
    wall = {k: [] for k in calls}
    cpu = {k: [] for k in calls}
    for _ in range(repeats):
        for k, fn in calls.items():
            w, c = _timed(fn, min_time)
            wall[k].append(w)
            cpu[k].append(c)
    for ts in wall.values():
        SPREAD.append((max(ts) - min(ts)) / float(np.median(ts)))
    return ({k: float(np.median(v)) for k, v in wall.items()}, {k: float(np.median(v)) for k, v in cpu.items()})


# --------------------------------------------------------------------------------------------
# Measurements
# --------------------------------------------------------------------------------------------

SINGLE_CALLS = {
    "solve_impact": "`solve_impact(problem)`: the public API",
    "full_path": "previous full path: `compile_problem` + dense numpy solve + SVD condition number + numpy work "
                 "and admissibility + result (`solve._solve_impact_full`, still taken for refusals and borderline "
                 "cases)",
    "numbers": "structure lookup (cached per shape) + packing the numbers (`solve._structure`, `_values`, one array)",
    "compile_problem": "`compile_problem(problem)` (the same + ImpactArrays views)",
    "kernel_call": "physics: the compiled kernel on one packed impact (`core.solve_packed`: numba dispatch + "
                   "solve + outputs as floats)",
    "result": "result object: `ImpactResult.from_item` (per-body objects deferred)",
    "bodies": "first access of `result.bodies` (the per-body objects, built then)",
    "condition": "first access of `result.condition_number` (the SVD, by the dense path)",
}


def single_times(name: str, repeats: int) -> dict:
    p = problem(name)
    S = _solve._structure(p)
    vals = _solve._values(p, S)
    X = np.array(vals, dtype=float)
    y = core.solve_packed(S, X)
    inp = core.inputs(S, X.tolist())
    work = dict(zip(core.WORK_KEYS, y["work"]))
    lam = y["impulses"]
    pn, pt, nrm, tng = lam[0], lam[1], y["normal"], y["tangent"]
    px, py = pn * nrm[0] + pt * tng[0], pn * nrm[1] + pt * tng[1]

    def numbers():
        S_ = _solve._structure(p)
        return np.array(_solve._values(p, S_), dtype=float)

    calls = {
        "solve_impact": lambda: solve_impact(p),
        "full_path": lambda: _solve._solve_impact_full(p, *_solve.compile_problem(p), True),
        "numbers": numbers,
        "compile_problem": lambda: _solve.compile_problem(p),
        "kernel_call": lambda: core.solve_packed(S, X),
        "result": lambda: ImpactResult.from_item(p, S, inp, y, work, 0, 1.0),
        "bodies": lambda: _body_impacts(S, inp, y, px, py),
        "condition": lambda: _solve._condition_number(S, X),
    }
    wall, cpu = interleaved(calls, repeats, 0.05)
    return {"wall": wall, "cpu": cpu}


def raw_kernel(batch: ImpactBatch):
    """The kernel call alone (inputs prepared, no dict, no post-processing)."""
    S, A = batch.structure, batch.arrays
    args = (core.kernel_structure(S), _kernel.pack_items(A), _kernel.limits(), False)
    return lambda: _kernel.solve_batch(*args)


def lapack_solve(batch: ImpactBatch):
    """numpy's batched LAPACK solve of the batch's no-slide systems (assembled beforehand)."""
    S, A = batch.structure, batch.arrays
    S_ns = replace(S, tangential="no_slide")
    J, minv, p_ext, _, _ = core._assemble(S_ns, A)
    B, K, n, _ = J.shape
    Jf = J.reshape(B, K, 3 * n)
    W = (Jf * minv.reshape(B, 1, 3 * n)) @ np.swapaxes(Jf, 1, 2)
    rhs = np.ascontiguousarray(-(Jf @ np.concatenate([A.velocity, A.yaw_rate[..., None]], -1).reshape(B, 3 * n, 1)))
    W = np.ascontiguousarray(W)
    return lambda: np.linalg.solve(W, rhs)


BATCH_SHORT = {"batch_solve": "ImpactBatch.solve", "kernel": "kernel alone (physics)",
               "lapack": "numpy LAPACK solve alone", "dense": "numpy dense path"}
BATCH_CALLS = {
    "batch_solve": "`ImpactBatch.solve()` (public API: compiled kernel + delta-v and energy-loss arrays)",
    "kernel": "physics: the raw kernel call (`_kernel.solve_batch`, inputs prepared)",
    "lapack": "yardstick: numpy batched LAPACK solve of the same no-slide K x K systems (linear solve only)",
    "dense": "reference: `solve_arrays(method=\"dense\")` (the same equations as batched numpy K x K inverses)",
}


def batch_rates(name: str, law: str, n: int, repeats: int) -> dict:
    batch = randomised_batch(name, law, n)
    S, A = batch.structure, batch.arrays
    calls = {"batch_solve": batch.solve, "kernel": raw_kernel(batch), "lapack": lapack_solve(batch),
             "dense": lambda: core.solve_arrays(S, A, method="dense")}
    wall, cpu = interleaved(calls, repeats, 0.05 if n < 100_000 else 0.0)
    return {"wall": {k: n / t for k, t in wall.items()}, "cpu": {k: n / t for k, t in cpu.items()}}


def agreement(name: str, law: str, n: int) -> dict:
    """Compiled vs dense path on one random batch: largest deviation relative to each output's
    largest magnitude; items whose flags differ."""
    batch = randomised_batch(name, law, n, seed=7)
    S, A = batch.structure, batch.arrays
    ref = core.solve_arrays(S, A, method="dense")
    got = core.solve_arrays(S, A, method="compiled")
    dev = 0.0
    for key in ("impulses", "velocity", "yaw_rate", "ke_after", "mu", "mu_max", "separation_normal",
                "condition_1norm"):
        scale = np.nanmax(np.abs(ref[key]))
        dev = max(dev, float(np.nanmax(np.abs(got[key] - ref[key])) / scale))
    return {"max_rel_dev": dev, "ok_differs": int(np.sum(got["ok"] != ref["ok"])),
            "sliding_differs": int(np.sum(got["sliding"] != ref["sliding"])), "items": n}


def paper_agreement() -> dict:
    """solve_impact (lean path) vs the full path on every paper scenario: the largest deviation of
    any number of ``to_dict()``, relative to the largest magnitude of its kind (velocities,
    impulses, energies, ...); fields other than floats must be equal."""
    out = {}
    for f in sorted((ROOT / "scenarios" / "paper").glob("*.toml")):
        p = load_scenario(f).impact
        a = _flat(solve_impact(p).to_dict())
        b = _flat(_solve._solve_impact_full(p, *_solve.compile_problem(p), True).to_dict())
        assert a.keys() == b.keys(), f
        scale: dict = {}
        for k, v in b.items():
            if isinstance(v, float) and math.isfinite(v):
                scale[_kind(k)] = max(scale.get(_kind(k), 0.0), abs(v))
        dev = 0.0
        for k, v in b.items():
            if isinstance(v, float):
                if not (v == a[k] or (math.isnan(v) and math.isnan(a[k]))):
                    dev = max(dev, abs(a[k] - v) / max(abs(v), scale.get(_kind(k), 0.0)))
            else:
                assert a[k] == v, (f, k)
        out[f.stem] = dev
    return out


def _flat(d, pre=""):
    if isinstance(d, dict):
        return {k2: v2 for k, v in d.items() for k2, v2 in _flat(v, f"{pre}.{k}").items()}
    if isinstance(d, (list, tuple)):
        return {k2: v2 for i, v in enumerate(d) for k2, v2 in _flat(v, f"{pre}[{i}]").items()}
    return {pre: d}


def _kind(key: str) -> str:
    for kind in ("energy_loss", "kinetic_energy", "work", "impulse", "velocity", "yaw_rate", "delta_v", "speed"):
        if kind in key:
            return kind
    return key  # angles, mu, ratios: relative to themselves


# --------------------------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------------------------

def machine_info() -> dict:
    cpu = cpu_name("")
    import numba

    return {"cpu": cpu or "unknown", "os.cpu_count": os.cpu_count(), "platform": platform.platform(),
            "python": platform.python_version(), "numpy": np.__version__, "numba": numba.__version__,
            "threads": "OMP/OPENBLAS/MKL/NUMBA_NUM_THREADS=1 (one thread)",
            "load_average_at_start": [round(x, 2) for x in os.getloadavg()]}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Impact solver speed.")
    ap.add_argument("--out", type=Path, default=None, help="output directory (default plots/, none with --quick)")
    ap.add_argument("--repeats", type=int, default=None, help="timed rounds per measurement (default 7, quick 3)")
    ap.add_argument("--quick", action="store_true", help="batches of 1e4 only, 3 rounds, small agreement check")
    ap.add_argument("--replot", action="store_true", help="redraw the figure and table from impact_speed.json")
    args = ap.parse_args(argv)
    out_dir = args.out if args.out is not None else (None if args.quick else ROOT / "plots")
    if args.replot:
        out_dir = out_dir or ROOT / "plots"
        res = json.loads((out_dir / "impact_speed.json").read_text())
        write_markdown(res, out_dir / "impact_speed.md")
        write_plot(res, out_dir / "impact_speed.png")
        return 0
    t_start = time.perf_counter()
    rep = args.repeats or (3 if args.quick else 7)
    sizes = QUICK_SIZES if args.quick else SIZES
    res: dict = {"machine": machine_info(), "repeats": rep, "sizes": list(sizes), "quick": args.quick,
                 "single_goal": SINGLE_GOAL, "batch_goal": BATCH_GOAL}
    t0 = time.perf_counter()
    solve_impact(problem("table6"))                     # load (or compile) the kernels
    randomised_batch("table6", "friction", 10).solve()
    res["kernel_load_s"] = time.perf_counter() - t0
    res["single"] = {name: single_times(name, max(rep, 9)) for name in PROBLEMS}
    for name in PROBLEMS:
        print(f"{name}: solve_impact {res['single'][name]['cpu']['solve_impact'] * 1e6:.1f} us (CPU)", flush=True)
    res["batch"] = {}
    for name in PROBLEMS:
        for law in LAWS:
            for n in sizes:
                r = batch_rates(name, law, n, rep)
                res["batch"].setdefault(name, {}).setdefault(law, {})[str(n)] = r
                print(f"{name:8s} {law:9s} n={n:>7,d}  " + "  ".join(
                    f"{k} {v:>11,.0f}/s" for k, v in r["cpu"].items()) + "  (per CPU s)", flush=True)
    n_ag = 5_000 if args.quick else 20_000
    res["agreement"] = {name: {law: agreement(name, law, n_ag) for law in LAWS} for name in PROBLEMS}
    res["paper_agreement"] = paper_agreement()
    res["timing_spread"] = {"median": float(np.median(SPREAD)), "max": float(np.max(SPREAD))}
    res["cpu_share"] = CPU["cpu"] / CPU["wall"]
    res["machine"]["load_average_at_end"] = [round(x, 2) for x in os.getloadavg()]
    res["run_seconds"] = time.perf_counter() - t_start
    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "impact_speed.json").write_text(json.dumps(res, indent=1))
        write_markdown(res, out_dir / "impact_speed.md")
        write_plot(res, out_dir / "impact_speed.png")
        print((out_dir / "impact_speed.md").read_text())
    else:
        print("\n".join(verdict(res)))
    print(f"run time {res['run_seconds']:.0f} s", flush=True)
    return 0


def _us(t: float) -> str:
    return f"{t * 1e6:,.1f} us"


def _rate(x: float) -> str:
    return f"{x:,.0f}"


def _judge(ok: bool, ratio: float) -> str:
    return f"**PASSED** ({ratio:.2f}x the goal)" if ok else f"**MISSED** ({ratio:.2f}x the goal)"


def verdict(res: dict) -> list[str]:
    lines = ["## Goals", ""]
    g1 = res["single_goal"]
    lines.append(f"* One impact through the public API in <= {g1 * 1e6:.0f} us (per CPU second, median):")
    for name in PROBLEMS:
        t = res["single"][name]["cpu"]["solve_impact"]
        tw = res["single"][name]["wall"]["solve_impact"]
        judged = name in JUDGED
        lines.append(f"  * {LABEL[name]}: {_us(t)} (wall {_us(tw)}): "
                     + (_judge(t <= g1, g1 / t) if judged else f"(not judged; {g1 / t:.2f}x the goal)"))
    g2 = res["batch_goal"]
    big = str(max(res["sizes"]))
    lines.append(f"* `ImpactBatch.solve` >= {g2:,.0f} impacts/s per core (per CPU second, batches of {int(big):,d}):")
    for name in PROBLEMS:
        judged = name in JUDGED
        for law in LAWS:
            r = res["batch"][name][law][big]
            rate, raw = r["cpu"]["batch_solve"], r["cpu"]["kernel"]
            why = ""
            if rate < g2:
                why = (f"; the kernel alone does {_rate(raw)}/s, so " + (
                    "the arithmetic itself misses the goal: per item the no-slide system (and, for the ratio "
                    "law and the friction law's sliding items, a second system) is assembled, equilibrated and "
                    f"inverted in full for the exact 1-norm condition number, K = {UNKNOWNS[name]} here" if raw < g2 else
                    "the arithmetic meets the goal and the Python around it (output arrays, delta-v, energy "
                    "losses) costs the rest"))
            lines.append(f"  * {LABEL[name]}, {law}: {_rate(rate)}/s (wall {_rate(r['wall']['batch_solve'])}/s): "
                         + (_judge(rate >= g2, rate / g2) if judged else f"(not judged; {rate / g2:.2f}x the goal)")
                         + why)
    mi = res["machine"]
    lines += ["", f"Machine load: load average {mi['load_average_at_start']} at start, {mi['load_average_at_end']} at "
              f"end on {mi['os.cpu_count']} cores shared with other jobs; the timed runs got {res['cpu_share']:.0%} "
              f"of a core (CPU time / wall time). Spread of the rounds, (max - min) / median: median "
              f"{res['timing_spread']['median']:.0%}, worst {res['timing_spread']['max']:.0%}."]
    return lines


def write_markdown(res: dict, path: Path) -> None:
    mi = res["machine"]
    lines = [
        "# Impact solver speed",
        "",
        "Generated by `python benchmarks/impact_speed.py` (" + ("`--quick`, " if res.get("quick") else "")
        + f"{res['run_seconds']:.0f} s): one run, medians of {res['repeats']} interleaved rounds (single calls "
        "repeated within each round to last >= 50 ms). \"Per core\" = per CPU second of the process (median CPU "
        "time per call; the machine is shared, so wall-clock times are listed beside them).",
        "",
        f"Machine: {mi['cpu']}; os.cpu_count() = {mi['os.cpu_count']}; {mi['platform']}; Python {mi['python']}; "
        f"numpy {mi['numpy']}; numba {mi['numba']}; {mi['threads']}. Load average (1, 5, 15 min) at start "
        f"{mi['load_average_at_start']}, at end {mi['load_average_at_end']}. Loading the cached compiled kernels "
        f"(first solve of the process): {res['kernel_load_s']:.2f} s.",
        "",
        *verdict(res),
        "",
        "## One impact (public API) and its parts [us per call, median]",
        "",
        "| call | " + " | ".join(f"{LABEL[n]}: CPU | wall" for n in PROBLEMS) + " |",
        "|---|" + "---|---|" * len(PROBLEMS),
    ]
    for key, label in SINGLE_CALLS.items():
        lines.append(f"| {label} | " + " | ".join(
            f"{res['single'][n]['cpu'][key] * 1e6:,.1f} | {res['single'][n]['wall'][key] * 1e6:,.1f}"
            for n in PROBLEMS) + " |")
    lines += [
        "",
        "`solve_impact` = numbers + kernel call + result object + a few comparisons (approaching, solvable, "
        "far from the condition limit, admissible: anything else goes to the full path, which words the "
        "refusal). The per-body objects and the SVD condition number are computed on first access; "
        "`to_dict()` and the run-out read them, so a caller that uses them pays those rows once.",
        "",
        "## Batch throughput [impacts per second, one core]",
        "",
    ]
    for name in PROBLEMS:
        lines += [f"### {LABEL[name]}", "",
                  "| law | batch size | " + " | ".join(BATCH_SHORT[k] for k in BATCH_CALLS)
                  + " | same, wall clock |",
                  "|---|---|" + "---|" * len(BATCH_CALLS) + "---|"]
        for law in LAWS:
            for n in res["sizes"]:
                r = res["batch"][name][law][str(n)]
                lines.append(f"| {law} | {int(n):,d} | " + " | ".join(_rate(r["cpu"][k]) for k in BATCH_CALLS)
                             + " | " + " / ".join(_rate(r["wall"][k]) for k in BATCH_CALLS) + " |")
        lines.append("")
    lines += ["Columns (per CPU second; the last column the same in wall-clock time, in the same order): "
              + "; ".join(f"{BATCH_SHORT[k]}: {v}" for k, v in BATCH_CALLS.items()) + ".", ""]
    lines += [
        "## Agreement",
        "",
        "Compiled kernel vs the dense numpy path (`solve_arrays(method=\"compiled\")` vs `\"dense\"`), random "
        "batches (seed 7): largest deviation of impulses, velocities, yaw rates, energies, mu, mu_max, "
        "separation velocity and condition_1norm, relative to each output's largest magnitude; items whose "
        "`ok` / `sliding` flags differ.",
        "",
        "| impact | law | items | max relative deviation | `ok` differs | `sliding` differs |",
        "|---|---|---|---|---|---|",
    ]
    for name in PROBLEMS:
        for law in LAWS:
            a = res["agreement"][name][law]
            lines.append(f"| {name} | {law} | {a['items']:,d} | {a['max_rel_dev']:.1e} | {a['ok_differs']} | "
                         f"{a['sliding_differs']} |")
    pa = res["paper_agreement"]
    lines += [
        "",
        "`solve_impact` (compiled) vs the previous full path on every paper scenario (scenarios/paper/): largest "
        "deviation of any number of `to_dict()` relative to the largest magnitude of its kind: "
        + ", ".join(f"{k} {v:.1e}" for k, v in pa.items()) + ".",
        "Random scenes, barriers and singular cases: tests/properties/test_impact_fast_batch.py and "
        "tests/properties/test_impact_lean.py.",
    ]
    path.write_text("\n".join(lines) + "\n")


def write_plot(res: dict, path: Path) -> None:
    # A benchmark script, not a crashsim module: it may import matplotlib itself (Agg, no screen).
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(12.0, 5.0), layout="constrained")
    keys = list(SINGLE_CALLS)
    short = {"solve_impact": "solve_impact", "full_path": "previous full path", "numbers": "structure + numbers",
             "compile_problem": "compile_problem", "kernel_call": "kernel call (physics)", "result": "result object",
             "bodies": "bodies (on access)", "condition": "condition number (on access)"}
    y = np.arange(len(keys))
    h = 0.8 / len(PROBLEMS)
    for j, name in enumerate(PROBLEMS):
        ax1.barh(y + j * h, [res["single"][name]["cpu"][k] * 1e6 for k in keys], h, label=name, color=f"C{j}")
    ax1.axvline(res["single_goal"] * 1e6, color="k", ls="--", lw=1.0, label="goal 50 us")
    ax1.set_yticks(y + h, [short[k] for k in keys], fontsize=8)
    ax1.invert_yaxis()
    ax1.set_xscale("log")
    ax1.set_xlabel("CPU time per call [us] (median)")
    ax1.set_title("One impact: public API and its parts", fontsize=10)
    ax1.legend(fontsize=7)
    big = str(max(res["sizes"]))
    xs = np.arange(len(PROBLEMS) * len(LAWS))
    w = 0.8 / len(BATCH_CALLS)
    for j, k in enumerate(BATCH_CALLS):
        vals = [res["batch"][n][law][big]["cpu"][k] for n in PROBLEMS for law in LAWS]
        ax2.bar(xs + j * w, vals, w, label=BATCH_SHORT[k], color=f"C{j + 3}")
    ax2.axhline(res["batch_goal"], color="k", ls="--", lw=1.0, label="goal 1e6/s")
    ax2.set_xticks(xs + w * (len(BATCH_CALLS) - 1) / 2, [f"{n}\n{law}" for n in PROBLEMS for law in LAWS],
                   fontsize=7)
    ax2.set_yscale("log")
    ax2.set_ylabel("impacts per CPU second")
    ax2.set_title(f"Batches of {int(big):,d}, one core", fontsize=10)
    ax2.legend(fontsize=7)
    fig.suptitle(f"Impact solver speed (medians; shared {res['machine']['os.cpu_count']}-core machine, "
                 f"load {res['machine']['load_average_at_start'][0]}-{res['machine']['load_average_at_end'][0]})",
                 fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())

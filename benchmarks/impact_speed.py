"""Speed of the impact solver: one solve through the public API, and batch throughput.

Run from the repository root (single core; the thread limits are set below before numpy loads)::

    python benchmarks/impact_speed.py            # full run, ~2-3 min, writes plots/impact_speed.*
    python benchmarks/impact_speed.py --quick    # ~20 s smoke run, prints only (unless --out is given)

Options: ``--repeats N`` (default 7), ``--max-size N`` (default 100000), ``--out DIR``,
``--replot`` (redraw the table and figure from ``impact_speed.json``).

The impact is the paper's Table 5 (a loaded tractor-semitrailer, B, strikes the side of an empty
one, A, at its trailer wheels; geometry from docs/paper-geometry.md): 7 unknowns
(P_n, P_t, M and two hitch impulses). It measures

(a) the latency of ``solve_impact`` (the single-solve public API: dense path, SVD condition
    number, ``ImpactResult``), median over many repeats;
(b) the throughput of the shipped ``ImpactBatch.solve`` [impacts solved per second] with
    randomised inputs (speeds, directions of approach, crush-surface angle, e, and f or mu) at
    batch sizes 1e2 .. 1e5, for each tangential law: ``no_slide``; ``friction`` (about 40 % of
    the items slide); ``ratio``. Batches of at least ``core.REDUCED_MIN`` items take the
    reduced path (``core._solve_chunk_reduced``: hitch impulses eliminated by Cholesky, the
    3 x 3 contact system by pivoted elimination, both tangential systems at once); smaller
    batches the dense path. The previous path, ``solve_arrays(method="dense")`` (the
    equilibrated 7 x 7 inverses, chunked), is timed alongside in interleaved rounds, so a
    change of machine load hits both alike. Medians of ``--repeats`` rounds;
(c) the agreement of the two paths on 20,000 random items per law (max deviation relative to
    each output's scale, identical ``ok`` and ``sliding`` flags).

The machine is shared (2 cores, other processes): the load average at start and end and the
CPU share of the timed runs (process CPU time / wall time; < 100 % means the benchmark waited
for the CPU) are reported with the numbers.

Writes ``impact_speed.md`` (tables + machine), ``impact_speed.png`` (solves/s vs batch size) and
``impact_speed.json`` (raw numbers) into ``--out`` (default ``plots/``; ``--quick`` writes only
if ``--out`` is given).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "VECLIB_MAXIMUM_THREADS",
             "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import functools  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from crashsim import (Body, CrushSurface, Hitch, ImpactBatch, ImpactProblem,  # noqa: E402
                      TangentialLaw, Vehicle, chain_states, solve_impact)
from crashsim.geometry import rotate  # noqa: E402
from crashsim.impact import core  # noqa: E402
from crashsim.impact.core import solve_arrays  # noqa: E402
from crashsim.impact import solve as _solve_mod  # noqa: E402
from crashsim.impact.solve import compile_problem  # noqa: E402

TARGET = 100_000.0  # solves per second on one core
LAWS = ("no_slide", "friction", "ratio")
SIZES = (100, 1_000, 10_000, 100_000)
QUICK_SIZES = (1_000, 10_000)
NEW = "ImpactBatch.solve (shipped)"
OLD = "previous path (dense)"


# --------------------------------------------------------------------------------------------
# The impact: paper Table 5
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


def check_table5() -> dict:
    r = solve_impact(table5_problem())
    got = {
        "A tractor V_x": r.bodies["A_tractor"].velocity[0], "A trailer V_y": r.bodies["A_trailer"].velocity[1],
        "A trailer Omega": r.bodies["A_trailer"].yaw_rate, "B tractor V_x": r.bodies["B_tractor"].velocity[0],
        "P_t": r.tangential_impulse, "P_n": r.normal_impulse, "loss system": r.energy_loss["system"],
    }
    paper = {"A tractor V_x": 12.22, "A trailer V_y": 7.12, "A trailer Omega": -2.24, "B tractor V_x": 3.2,
             "P_t": -18395, "P_n": 39453, "loss system": 0.093}
    return {k: (paper[k], float(got[k])) for k in paper}


def randomised_batch(law: str, n: int, seed: int = 1) -> ImpactBatch:
    """n Table 5 impacts with random speeds, approach directions, surface angle, e, f or mu.

    Speeds: A 5-25 m/s along +x; B 8-25 m/s within +-15 deg of +y (zero yaw rates keep the pin
    velocities of each vehicle equal). Crush normal pi/2 +- 10 deg; e in [0, 0.3]; f in
    [0.2, 0.8] (friction: about 40 % of the items slide); mu in [-0.8, 0.8] (ratio). Every item
    approaches (closing velocity < 0).
    """
    value = {"no_slide": 0.0, "friction": 0.5, "ratio": 0.0}[law]
    batch = ImpactBatch.from_problem(table5_problem(law, value), n)
    A = batch.arrays
    rng = np.random.default_rng(seed)
    ia = [batch.body_index(b) for b in ("A_tractor", "A_trailer")]
    ib = [batch.body_index(b) for b in ("B_tractor", "B_trailer")]
    va = rng.uniform(5.0, 25.0, n)
    vb = rng.uniform(8.0, 25.0, n)
    dirb = math.pi / 2 + np.radians(rng.uniform(-15.0, 15.0, n))
    for i in ia:
        A.velocity[:, i, 0] = va
        A.velocity[:, i, 1] = 0.0
    for i in ib:
        A.velocity[:, i, 0] = vb * np.cos(dirb)
        A.velocity[:, i, 1] = vb * np.sin(dirb)
    A.normal_angle[:] = math.pi / 2 + np.radians(rng.uniform(-10.0, 10.0, n))
    A.restitution[:] = rng.uniform(0.0, 0.3, n)
    if law == "friction":
        A.law_value[:] = rng.uniform(0.2, 0.8, n)
    elif law == "ratio":
        A.law_value[:] = rng.uniform(-0.8, 0.8, n)
    return batch


# --------------------------------------------------------------------------------------------
# Timing helpers
# --------------------------------------------------------------------------------------------

SPREAD: list[float] = []   # (max - min) / median of every timing, for the report
CPU = {"cpu": 0.0, "wall": 0.0}  # process CPU time and wall time of every timed call


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


def _median_time(fn, repeats: int, min_time: float = 0.0) -> float:
    """Median wall time of fn() over ``repeats`` runs, after one warm-up call."""
    fn()
    times = [_timed(fn, min_time)[0] for _ in range(repeats)]
    med = float(np.median(times))
    SPREAD.append((max(times) - min(times)) / med)
    return med


def _interleaved_times(calls: dict, repeats: int, min_time: float = 0.0) -> tuple[dict, dict, dict]:
    """Median wall and CPU time per call of each function, timed in interleaved rounds after one
    warm-up call each; also the warm-up (first-call) times, which pay the page faults of fresh
    arrays."""
    first = {}
    for name, fn in calls.items():
        t0 = time.perf_counter()
        fn()
        first[name] = time.perf_counter() - t0
    wall: dict[str, list[float]] = {name: [] for name in calls}
    cpu: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(repeats):
        for name, fn in calls.items():
            w, c = _timed(fn, min_time)
            wall[name].append(w)
            cpu[name].append(c)
    out_w, out_c = {}, {}
    for name, ts in wall.items():
        med = float(np.median(ts))
        SPREAD.append((max(ts) - min(ts)) / med)
        out_w[name] = med
        out_c[name] = float(np.median(cpu[name]))
    return out_w, out_c, first


def previous_solve(batch: ImpactBatch) -> dict:
    """``ImpactBatch.solve`` as it was before the reduced path: the same call with
    ``solve_arrays`` forced to ``method="dense"`` (same post-processing: delta_v, energy loss)."""
    orig = _solve_mod.solve_arrays
    _solve_mod.solve_arrays = functools.partial(orig, method="dense")
    try:
        return batch.solve()
    finally:
        _solve_mod.solve_arrays = orig


# --------------------------------------------------------------------------------------------
# Agreement of the shipped (reduced) path with the previous (dense) path
# --------------------------------------------------------------------------------------------

def check_agreement(law: str, n: int = 20_000) -> dict:
    """Max deviation of the reduced path from the dense path, relative to each output's scale
    (its largest magnitude over the batch), and the number of differing flags."""
    batch = randomised_batch(law, n, seed=7)
    S, A = batch.structure, batch.arrays
    ref = solve_arrays(S, A, method="dense")
    got = solve_arrays(S, A, method="reduced")
    assert set(ref) == set(got), "different outputs"
    dev = 0.0
    for key in ("impulses", "velocity", "yaw_rate", "ke_after", "mu", "mu_max", "separation_normal",
                "condition_1norm"):
        scale = np.nanmax(np.abs(ref[key]))
        dev = max(dev, float(np.nanmax(np.abs(got[key] - ref[key])) / scale))
    return {"max_rel_dev": dev, "ok_differs": int(np.sum(got["ok"] != ref["ok"])),
            "sliding_differs": int(np.sum(got["sliding"] != ref["sliding"])), "items": n,
            "not_ok": int(np.sum(~ref["ok"]))}


# --------------------------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------------------------

def machine_info() -> dict:
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu or "unknown", "os.cpu_count": os.cpu_count(), "platform": platform.platform(),
        "python": platform.python_version(), "numpy": np.__version__,
        "threads": "OMP/OPENBLAS/MKL_NUM_THREADS=1 (single core)",
        "load_average_at_start": [round(x, 2) for x in os.getloadavg()],
    }


def _fmt_rate(x: float) -> str:
    return f"{x:,.0f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Impact solver speed (paper Table 5 impact).")
    ap.add_argument("--out", type=Path, default=None, help="output directory (default plots/, none with --quick)")
    ap.add_argument("--repeats", type=int, default=None, help="timed rounds per measurement (default 7, quick 3)")
    ap.add_argument("--max-size", type=int, default=100_000)
    ap.add_argument("--quick", action="store_true", help="sizes 1e3 and 1e4, 3 rounds, 5,000-item agreement check")
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
    sizes = [s for s in (QUICK_SIZES if args.quick else SIZES) if s <= args.max_size]
    rep = args.repeats or (3 if args.quick else 7)
    res: dict = {"machine": machine_info(), "target": TARGET, "sizes": sizes, "repeats": rep, "quick": args.quick,
                 "reduced_min": core.REDUCED_MIN, "reduced_chunk": core.REDUCED_CHUNK, "dense_chunk": core.CHUNK}

    res["table5"] = check_table5()
    prob = table5_problem()
    S1, A1 = compile_problem(prob)
    single_rep = max(rep, 9)
    res["single"] = {
        "solve_impact_s": _median_time(lambda: solve_impact(prob), single_rep, 0.05),
        "batch_of_1_s": _median_time(ImpactBatch.from_problem(prob, 1).solve, single_rep, 0.05),
        "solve_arrays_condition_s": _median_time(lambda: solve_arrays(S1, A1, condition=True), single_rep, 0.05),
        "solve_arrays_s": _median_time(lambda: solve_arrays(S1, A1), single_rep, 0.05),
    }
    print(f"solve_impact: {res['single']['solve_impact_s'] * 1e6:.0f} us", flush=True)

    res["agreement"] = {law: check_agreement(law, 5_000 if args.quick else 20_000) for law in LAWS}
    print("agreement (reduced vs dense):", json.dumps(res["agreement"]), flush=True)

    rates: dict = {NEW: {}, OLD: {}}
    cpu_rates: dict = {NEW: {}, OLD: {}}
    first: dict = {NEW: {}, OLD: {}}
    res["sliding_fraction"] = {law: float(np.mean(randomised_batch(law, 10_000).solve()["sliding"])) for law in LAWS}
    for law in LAWS:
        for n in sizes:
            batch = randomised_batch(law, n)
            S, A = batch.structure, batch.arrays
            calls = {NEW: batch.solve, OLD: lambda batch=batch: previous_solve(batch)}
            times, cpu_t, first_t = _interleaved_times(calls, repeats=rep, min_time=0.05 if n < 100_000 else 0.0)
            for name, t in times.items():
                rates[name].setdefault(law, {})[str(n)] = n / t
                cpu_rates[name].setdefault(law, {})[str(n)] = n / cpu_t[name]
                first[name].setdefault(law, {})[str(n)] = n / first_t[name]
            print(f"{law:9s} n={n:>7,d}  shipped {n / times[NEW]:>10,.0f}/s   previous {n / times[OLD]:>10,.0f}/s"
                  f"   ({times[OLD] / times[NEW]:.1f}x)   per CPU second: {n / cpu_t[NEW]:>10,.0f} / "
                  f"{n / cpu_t[OLD]:>10,.0f}", flush=True)
            del batch, S, A, calls
    res["rates"] = rates
    res["cpu_rates"] = cpu_rates
    res["first_call_rates"] = first
    res["timing_spread"] = {"median": float(np.median(SPREAD)), "max": float(np.max(SPREAD))}
    res["cpu_share"] = CPU["cpu"] / CPU["wall"]
    res["machine"]["load_average_at_end"] = [round(x, 2) for x in os.getloadavg()]
    res["run_seconds"] = time.perf_counter() - t_start

    if out_dir is not None:
        out_dir.mkdir(parents=True, exist_ok=True)
        (out_dir / "impact_speed.json").write_text(json.dumps(res, indent=1, default=str))
        write_markdown(res, out_dir / "impact_speed.md")
        write_plot(res, out_dir / "impact_speed.png")
        print((out_dir / "impact_speed.md").read_text())
    else:
        print("\n".join(verdict(res)))
    print(f"run time {res['run_seconds']:.0f} s", flush=True)
    return 0


def verdict(res: dict) -> list[str]:
    """The verdict, with this run's numbers."""
    sizes = [int(n) for n in res["sizes"]]
    new, old, cpu = res["rates"][NEW], res["rates"][OLD], res["cpu_rates"][NEW]
    tgt = res["target"]
    judged = [n for n in sizes if 1_000 <= n <= 100_000]

    def below(r):
        return [f"{law} at {n:,d} ({r[law][str(n)]:,.0f}/s)" for law in LAWS for n in judged if r[law][str(n)] < tgt]

    def worst(r):
        return min(r[law][str(n)] for law in LAWS for n in judged) if judged else float("nan")

    small = [n for n in sizes if n < res["reduced_min"]]
    ag = res["agreement"]
    items = ag[LAWS[0]]["items"]
    lines = [
        "## Verdict",
        "",
        f"* Target {tgt:,.0f} solves/s on one core for every law at batch sizes 1e3..1e5. Wall-clock medians: "
        + ("**met**" if not below(new) else "**not met**: " + "; ".join(below(new)))
        + f" (slowest {worst(new):,.0f}/s). Per CPU second (what one core delivers when the benchmark is not "
        "waiting for it): " + ("**met**" if not below(cpu) else "**not met**: " + "; ".join(below(cpu)))
        + f" (slowest {worst(cpu):,.0f}/s).",
        "* Gain over the previous (dense) path, wall-clock medians at " + ", ".join(f"{n:,d}" for n in judged)
        + ": " + "; ".join(f"{law} " + ", ".join(f"{new[law][str(n)] / old[law][str(n)]:.1f}x" for n in judged)
                           for law in LAWS) + ".",
        f"* Agreement with the previous path ({items:,d} random Table 5 items per law): max deviation "
        + ", ".join(f"{law} {ag[law]['max_rel_dev']:.1e}" for law in LAWS) + " of each output's scale; "
        + ("identical `ok` and `sliding` flags." if all(ag[law]["ok_differs"] == ag[law]["sliding_differs"] == 0
                                                      for law in LAWS)
           else "flags differ: " + json.dumps(ag)),
    ]
    if small:
        lines.append(
            f"* Below {res['reduced_min']:,d} items (here {', '.join(f'{n:,d}' for n in small)}) `ImpactBatch.solve` "
            "uses the dense path (the reduced path's fixed cost of a few hundred numpy calls dominates there); "
            "both columns then time the same code.")
    lines.append(
        f"* Machine load: load average {res['machine']['load_average_at_start']} at start, "
        f"{res['machine']['load_average_at_end']} at end on {res['machine']['os.cpu_count']} cores; the timed runs "
        f"got {res['cpu_share']:.0%} of a core (CPU time / wall time). Spread of the rounds, (max - min) / median: "
        f"median {res['timing_spread']['median']:.0%}, worst {res['timing_spread']['max']:.0%}.")
    return lines


def write_markdown(res: dict, path: Path) -> None:
    sizes = [int(n) for n in res["sizes"]]
    new, old = res["rates"][NEW], res["rates"][OLD]
    mi = res["machine"]
    sng = res["single"]
    lines = [
        "# Impact solver speed",
        "",
        "Generated by `python benchmarks/impact_speed.py` (" + ("`--quick`, " if res.get("quick") else "")
        + f"{res['run_seconds']:.0f} s): one run, medians of {res['repeats']} interleaved rounds "
        "(batches < 1e5 repeated within each round to last >= 50 ms).",
        "Impact: paper Table 5 (loaded tractor-semitrailer into the trailer wheels of an empty one),",
        "7 unknowns (P_n, P_t, M, two hitch impulses of 2 components), randomised speeds, directions, "
        "surface angle, e, f or mu.",
        "",
        f"Machine: {mi['cpu']}; os.cpu_count() = {mi['os.cpu_count']}; {mi['platform']}; "
        f"Python {mi['python']}; numpy {mi['numpy']}; {mi['threads']}. Load average (1, 5, 15 min) "
        f"at start {mi['load_average_at_start']}, at end {mi.get('load_average_at_end')}: the machine is shared "
        f"with other processes; the timed runs got {res['cpu_share']:.0%} of a core (process CPU time / wall "
        f"time). Spread of the rounds, (max - min) / median: median {res['timing_spread']['median']:.0%}, "
        f"worst {res['timing_spread']['max']:.0%}.",
        "",
        "Table 5 check (paper, computed): " + "; ".join(f"{k} {p} / {g:.4g}" for k, (p, g) in res["table5"].items()),
        "",
        "## Batch throughput [impacts solved per second, one core]",
        "",
        f"`ImpactBatch.solve` as shipped: batches of >= {res['reduced_min']:,d} items take the reduced path "
        f"(`core._solve_chunk_reduced`, chunks of {res['reduced_chunk']:,d}), smaller ones the dense path. "
        f"Previous path: `ImpactBatch.solve` as before, i.e. with `solve_arrays(..., method=\"dense\")` "
        f"(equilibrated 7 x 7 inverses, chunks of {res['dense_chunk']:,d}). Sliding fraction under the friction "
        f"law: {res['sliding_fraction']['friction']:.2f}. Target: {_fmt_rate(res['target'])} solves/s.",
        "",
        "| batch size | " + " | ".join(f"{law}: shipped | previous | gain" for law in LAWS) + " |",
        "|---|" + "---|---|---|" * len(LAWS),
    ]
    for n in sizes:
        cells = []
        for law in LAWS:
            a, b = new[law][str(n)], old[law][str(n)]
            cells.append(f"{_fmt_rate(a)} | {_fmt_rate(b)} | {a / b:.1f}x")
        lines.append(f"| {n:,d} | " + " | ".join(cells) + " |")
    lines += [
        "",
        "The same runs per CPU second of the process (median CPU time per call; insensitive to waiting for the "
        "CPU on the shared machine, not to sharing its caches and memory bandwidth) [solves/s]:",
        "",
        "| batch size | " + " | ".join(f"{law}: shipped | previous" for law in LAWS) + " |",
        "|---|" + "---|---|" * len(LAWS),
    ]
    for n in sizes:
        lines.append(f"| {n:,d} | " + " | ".join(
            f"{_fmt_rate(res['cpu_rates'][NEW][law][str(n)])} | {_fmt_rate(res['cpu_rates'][OLD][law][str(n)])}"
            for law in LAWS) + " |")
    fc = res["first_call_rates"][NEW]
    lines += [
        "",
        "First call of `ImpactBatch.solve` on a freshly built batch (the warm-up, one sample; includes the "
        "page faults of the fresh temporaries) [solves/s]:",
        "",
        "| batch size | " + " | ".join(LAWS) + " |",
        "|---|" + "---|" * len(LAWS),
    ]
    for n in sizes:
        lines.append(f"| {n:,d} | " + " | ".join(_fmt_rate(fc[law][str(n)]) for law in LAWS) + " |")
    ag = res["agreement"]
    lines += [
        "",
        "## Agreement of the shipped path with the previous path",
        "",
        "Same random Table 5 batches (seed 7), `solve_arrays(method=\"reduced\")` vs `method=\"dense\"`: largest "
        "deviation of impulses, velocities, yaw rates, energies, mu, mu_max, separation velocity and "
        "condition_1norm, relative to each output's largest magnitude; items whose `ok` / `sliding` flags differ.",
        "",
        "| law | items | max relative deviation | `ok` differs | `sliding` differs | not ok |",
        "|---|---|---|---|---|---|",
    ]
    for law in LAWS:
        a = ag[law]
        lines.append(f"| {law} | {a['items']:,d} | {a['max_rel_dev']:.1e} | {a['ok_differs']} | "
                     f"{a['sliding_differs']} | {a['not_ok']} |")
    lines += [
        "",
        "Random articulated scenes, barriers and singular cases: tests/properties/test_impact_fast_batch.py.",
        "",
        "## Single solve (public API, dense path)",
        "",
        "| call | median latency |",
        "|---|---|",
        f"| `solve_impact(problem)` (assembly, solve, condition number (SVD), ImpactResult) | "
        f"{sng['solve_impact_s'] * 1e6:.0f} us |",
        f"| `ImpactBatch.from_problem(problem, 1).solve()` (reused batch) | {sng['batch_of_1_s'] * 1e6:.0f} us |",
        f"| `core.solve_arrays`, batch of 1, `condition=True` (as `solve_impact` calls it) | "
        f"{sng['solve_arrays_condition_s'] * 1e6:.0f} us |",
        f"| `core.solve_arrays`, batch of 1, no condition number | {sng['solve_arrays_s'] * 1e6:.0f} us |",
        "",
        *verdict(res),
    ]
    path.write_text("\n".join(lines) + "\n")


def write_plot(res: dict, path: Path) -> None:
    # A benchmark script, not a crashsim module: it may import matplotlib itself (Agg, no screen).
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8.0, 5.0), layout="constrained")
    markers = {"no_slide": "o", "friction": "s", "ratio": "^"}
    for k, law in enumerate(LAWS):
        for name, ls, lw in ((NEW, "-", 2.0), (OLD, ":", 1.5)):
            d = res["rates"][name][law]
            ns = sorted(d, key=int)
            ax.plot([int(n) for n in ns], [d[n] for n in ns], ls, marker=markers[law], color=f"C{k}", lw=lw,
                    label=f"{law}, {name}")
    ax.axhline(res["target"], color="k", lw=1.0, ls="--", label=f"target {res['target']:,.0f}/s")
    ax.axvline(res["reduced_min"], color="0.6", lw=1.0, ls="-.")
    ax.text(res["reduced_min"] * 1.05, res["target"] * 0.55, "reduced path from here", fontsize=8, color="0.4")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("batch size [impacts]")
    ax.set_ylabel("throughput [impacts solved / s], one core")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, loc="lower right", ncol=2)
    ax.set_title("Batch impact solve, paper Table 5 impact, randomised inputs\n"
                 f"(medians; shared {res['machine']['os.cpu_count']}-core machine, {res['cpu_share']:.0%} CPU share)",
                 fontsize=10)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())

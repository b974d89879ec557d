"""Speed against accuracy of every run-out fidelity level, solver and tolerance, on the shipped scenes.

Run from the repository root::

    python benchmarks/speed_accuracy.py            # full study, ~6-9 min on a shared 2-core machine
    python benchmarks/speed_accuracy.py --quick    # smoke run, ~1 min

Writes ``plots/speed_accuracy.md`` (a README-ready summary table, then every row),
``plots/speed_accuracy.csv`` and ``plots/speed_accuracy.png``.

Cases
-----
Every movable vehicle of the four scenes this study was written for (``STUDY_SCENES`` in
``scenarios/scenes/``; 6 run-outs: two articulated trucks into barriers, a car + trailer and the
car that struck it, a tractor-semitrailer and the car of the paper's Table 6 intersection), each
run out alone from the separation states of the scene's own impact (made hitch-consistent),
with the scene's wheels and road.  The levels compare per vehicle; what running the whole scene
together (with contact) costs is measured by ``benchmarks/joint_runout.py``.

What is measured
----------------
For every level of :mod:`crashsim.motion.levels` -- ``impact``, ``energy``, ``rigid``,
``articulated``, ``load_transfer`` -- and, for the integrated levels, every solve_ivp method
(RK45, DOP853, LSODA, Radau, BDF) at rtol 1e-3 ... 1e-8 (atol = rtol/100; rigid and
load_transfer on the subsampled grid 1e-3, 1e-4, 1e-6, 1e-8 to keep the run short), the
pymunk cross-check at dt = 4, 2, 1, 0.5 ms, the compiled engine (``engine="compiled"``,
schemes dopri5 and bs3, if the installed crashsim has it) and
:func:`~crashsim.motion.run_runout` to an accuracy target (``accuracy=``) at 1 cm:

* **cost**: median CPU time (``time.process_time``) of one run-out over repeats (3, or fewer
  when a run takes over a second), and nfev.  CPU time, not wall time: the machine is shared.
  For ``impact`` the cost is the scene's impact solve; every other level's cost is the
  run-out alone (the impact is the same for all);
* **numerical error**: largest distance of a body's rest position (and heading difference)
  from the converged reference of the **same level** (LSODA, rtol 1e-10, atol 1e-12,
  eps = v_stop = 1e-3 m/s; cross-checked with DOP853 at the same tolerance, the difference is
  reported).  The energy level is a closed form: its numerical error is zero;
* **error against the full model**: the same distance from the converged reference of the
  most complete model, ``load_transfer`` -- the model error of the level plus its numerical
  error.  For ``impact`` this is how far each body is from where the full model brings it
  to rest, i.e. what an impact-only study leaves out;
* **delta-v error**: delta-v is a property of the impact, computed by a linear solve
  (no discretisation), identical for every level, method and tolerance of a scene: its
  error is **exactly zero** in every run-out row.  It changes only with the impact model, so it
  is reported per **impact-model variant** instead: as given in the scene; with a tyre-friction
  impulse during the impact (``f x N x 0.15 s`` against each body's pre-impact velocity, from
  the load on its sliding wheels, paper Table 7 style); and, for the scene that has one, without
  its velocity constraint (rolling trailer wheels).  The variants' delta-v and rest positions
  (articulated level, LSODA at the default rtol) are compared with the scene as given.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import math
import os
import platform
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import scipy

from crashsim.impact import ExternalImpulse, solve_impact, tyre_friction_impulse
from crashsim.motion import RunoutOptions, make_hitch_consistent, static_loads
from crashsim.motion.accuracy import _simulate_to_accuracy
from crashsim.motion.levels import simulate_level
from crashsim.motion.runners import LEVELS
from crashsim.scene.run import separation_states
from crashsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "plots"
METHODS = ("RK45", "DOP853", "LSODA", "Radau", "BDF")
RTOLS = (1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8)
RTOLS_SUB = (1e-3, 1e-4, 1e-6, 1e-8)
PYMUNK_DT = (4e-3, 2e-3, 1e-3, 5e-4)
SCHEMES = ("dopri5", "bs3")
REFERENCE = dict(method="LSODA", rtol=1e-10, atol=1e-12, eps=1e-3, v_stop=1e-3)
DEFAULT = RunoutOptions()
FULL = "load_transfer"
LOAD_AT_START = os.getloadavg()[0]
HAS_COMPILED = "engine" in RunoutOptions.__dataclass_fields__


# ---------------------------------------------------------------------------------------------- setup
#: The shipped scenes of this study (the later scenes exist for the whole-scene run-out).
STUDY_SCENES = ("barrier_15deg", "barrier_75deg", "car_trailer_side_impact", "intersection_car_trailer_wheels")


def load_cases():
    """Scenes and their vehicles' run-out inputs, from the shipped scene files."""
    cases, scenes = [], []
    for path in sorted(str(ROOT / "scenarios" / "scenes" / f"{n}.toml") for n in STUDY_SCENES):
        sc = load_scenario(path)
        name = Path(path).stem
        impact = solve_impact(sc.impact)
        states = separation_states(sc, impact)
        scenes.append((name, sc, impact))
        for veh in sc.vehicles:
            if veh.is_barrier:
                continue
            initial = make_hitch_consistent(veh, {b.name: states[b.name] for b in veh.bodies})
            cases.append(dict(scene=name, vehicle=veh, initial=initial, wheels=sc.runout.wheels[veh.name],
                              road=sc.runout.road, options=sc.runout.options, scenario=sc, impact=impact))
    return scenes, cases


def timed(fn, repeats, budget=1.0):
    """(last result, median CPU [s], median wall [s], n) over up to ``repeats`` calls (fewer past ``budget`` s)."""
    cpu, wall, out = [], [], None
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        out = fn()
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
        if sum(cpu) > budget and len(cpu) >= 1:
            break
    return out, statistics.median(cpu), statistics.median(wall), len(cpu)


def rest_errors(res, ref):
    """Largest rest-position distance [m] and heading difference [rad] over the bodies."""
    pos = max(math.dist(b.rest_position, ref.bodies[n].rest_position) for n, b in res.bodies.items())
    head = max(abs(b.rest_heading - ref.bodies[n].rest_heading) for n, b in res.bodies.items())
    return pos, head


# ---------------------------------------------------------------------------------------------- impact variants
def tyre_friction_variant(sc, duration=0.15):
    """The scene's impact plus a tyre-friction impulse on every body with sliding wheels at separation."""
    problem = sc.impact
    extra = []
    for veh in sc.vehicles:
        if veh.is_barrier or sc.runout is None:
            continue
        resolved = sc.runout.wheels[veh.name].resolve(veh)
        settings = resolved.at(0.0)
        loads = static_loads(veh).wheel
        for body in veh.bodies:
            n_slide = sum(n for s, spec, n in zip(settings, resolved.specs, loads) if spec.body == body.name and s.is_sliding)
            st = problem.states[body.name]
            speed = math.hypot(*st.velocity)
            if n_slide <= 0 or speed == 0:
                continue
            direction = math.atan2(-st.velocity[1], -st.velocity[0])
            imp = tyre_friction_impulse(sc.runout.road.mu, n_slide, duration, direction)
            extra.append(ExternalImpulse(body.name, st.position, tuple(imp), f"tyre friction {body.name}"))
    return dataclasses.replace(problem, external=tuple(problem.external) + tuple(extra))


def impact_variants(sc):
    out = {"as given": sc.impact, "+ tyre friction 0.15 s": tyre_friction_variant(sc)}
    if sc.impact.constraints:
        out["without velocity constraint"] = dataclasses.replace(sc.impact, constraints=())
    return out


# ---------------------------------------------------------------------------------------------- main
def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer settings and repeats (smoke run)")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    t_start = time.perf_counter()
    methods = ("LSODA", "RK45") if args.quick else METHODS
    rtols = (1e-3, 1e-6) if args.quick else RTOLS
    rtols_sub = (1e-3, 1e-6) if args.quick else RTOLS_SUB
    pm_dts = (2e-3,) if args.quick else PYMUNK_DT
    repeats = 1 if args.quick else args.repeats

    scenes, cases = load_cases()
    print(f"{len(cases)} run-outs from {len(scenes)} scenes", flush=True)

    # ---- references
    refs, ref_unc = {}, {}
    for c in cases:
        key = (c["scene"], c["vehicle"].name)
        for level in ("rigid", "articulated", "load_transfer"):
            r = simulate_level(level, c["vehicle"], c["initial"], c["wheels"], c["road"], RunoutOptions(**REFERENCE))
            assert r.success, (key, level, r.message)
            refs[key, level] = r
            if level in ("articulated", FULL):
                chk = simulate_level(level, c["vehicle"], c["initial"], c["wheels"], c["road"],
                                     RunoutOptions(**{**REFERENCE, "method": "DOP853"}))
                ref_unc[key, level] = rest_errors(chk, r)
        print(f"references {key}: done", flush=True)

    rows = []

    def add(c, level, engine, setting, res, cpu, wall, n, *, own=None, extra=None):
        key = (c["scene"], c["vehicle"].name)
        full = refs[key, FULL]
        if res is None:  # impact only: bodies stay at separation
            pos_full = max(math.dist(c["initial"][b].position, full.bodies[b].rest_position) for b in full.bodies)
            head_full = max(abs(c["initial"][b].heading - full.bodies[b].rest_heading) for b in full.bodies)
            e_own = (float("nan"), float("nan"))
            status, nfev = "n/a", 0
        else:
            pos_full, head_full = rest_errors(res, full)
            e_own = (0.0, 0.0) if own == "exact" else rest_errors(res, refs[key, own])
            status, nfev = res.status, res.nfev
        row = dict(scene=c["scene"], vehicle=c["vehicle"].name, level=level, engine=engine, setting=setting,
                   status=status, cpu_ms=cpu * 1e3, wall_ms=wall * 1e3, repeats=n, nfev=nfev,
                   pos_err_m=e_own[0], head_err_deg=math.degrees(e_own[1]), pos_err_full_m=pos_full,
                   head_err_full_deg=math.degrees(head_full), delta_v_err_m_s=0.0)
        row.update(extra or {})
        rows.append(row)
        print(f"{c['scene'][:14]:14s} {c['vehicle'].name:8s} {level:13s} {engine:8s} {setting:18s} cpu {cpu * 1e3:8.2f} ms "
              f"nfev {nfev:6d} err {e_own[0] * 1e3:9.4f} mm  vs full {pos_full:8.4f} m", flush=True)

    # ---- impact only and energy
    impact_cost = {}
    for name, sc, _ in scenes:
        _, cpu, wall, n = timed(lambda: solve_impact(sc.impact), 5 if not args.quick else 1)
        impact_cost[name] = (cpu, wall, n)
    for c in cases:
        add(c, "impact", "-", "impact solve", None, *impact_cost[c["scene"]])
        res, cpu, wall, n = timed(lambda: simulate_level("energy", c["vehicle"], c["initial"], c["wheels"], c["road"]),
                                  5 if not args.quick else 1)
        add(c, "energy", "closed form", "-", res, cpu, wall, n, own="exact")

    # ---- integrated levels: solve_ivp methods x tolerances
    for level, grid in (("articulated", rtols), ("rigid", rtols_sub), ("load_transfer", rtols_sub)):
        for method in methods:
            for rtol in grid:
                opts = RunoutOptions(method=method, rtol=rtol, atol=rtol / 100)
                for c in cases:
                    res, cpu, wall, n = timed(
                        lambda: simulate_level(level, c["vehicle"], c["initial"], c["wheels"], c["road"], opts), repeats)
                    add(c, level, "scipy", f"{method} {rtol:.0e}", res, cpu, wall, n, own=level)

    # ---- compiled engine (if this crashsim has it)
    compiled_note = "not available in this crashsim (RunoutOptions has no engine field)"
    if HAS_COMPILED:
        try:
            c0 = time.perf_counter()
            c = cases[0]
            warm = simulate_level("articulated", c["vehicle"], c["initial"], c["wheels"], c["road"],
                                  RunoutOptions(engine="compiled"))
            compiled_note = (f"available ({warm.method}); first call incl. loading/compiling "
                             f"{time.perf_counter() - c0:.1f} s, excluded from the timings")
            for level in ("articulated", "load_transfer"):
                for scheme in SCHEMES:
                    for rtol in rtols:
                        opts = RunoutOptions(engine="compiled", scheme=scheme, rtol=rtol, atol=rtol / 100)
                        for c in cases:
                            res, cpu, wall, n = timed(
                                lambda: simulate_level(level, c["vehicle"], c["initial"], c["wheels"], c["road"], opts),
                                max(repeats, 5), budget=0.5)
                            add(c, level, "compiled", f"{scheme} {rtol:.0e}", res, cpu, wall, n, own=level)
        except Exception as exc:  # the colleague's engine may be mid-change: report, do not fail the study
            compiled_note = f"failed: {type(exc).__name__}: {exc}"
            print("compiled engine:", compiled_note, flush=True)

    # ---- pymunk cross-check (articulated model, fixed step)
    from crashsim.crosscheck import simulate_runout_pymunk

    for dt in pm_dts:
        for c in cases:
            mu_max = max([c["road"].mu, *(z.mu for z in c["road"].zones)])
            chatter = mu_max * 9.80665 * dt * 1.01
            opts = RunoutOptions(eps=max(DEFAULT.eps, chatter), v_stop=max(DEFAULT.v_stop, 2 * chatter))
            res, cpu, wall, n = timed(
                lambda: simulate_runout_pymunk(c["vehicle"], c["initial"], c["wheels"], c["road"], dt=dt, options=opts),
                repeats, budget=2.0)
            add(c, "articulated", "pymunk", f"dt {dt * 1e3:g} ms", res, cpu, wall, n, own="articulated",
                extra=dict(note=f"eps {opts.eps:.3g}, v_stop {opts.v_stop:.3g}"))

    # ---- accuracy mode: "1 cm"
    for engine_opts, label in ((dict(), "scipy LSODA"), (dict(engine="compiled"), "compiled dopri5")):
        if engine_opts and (not HAS_COMPILED or not compiled_note.startswith("available")):
            continue
        for c in cases:
            c0, w0 = time.process_time(), time.perf_counter()
            res, rep = _simulate_to_accuracy(c["vehicle"], c["initial"], c["wheels"], c["road"], 0.01, None,
                                            RunoutOptions(**engine_opts))
            cpu, wall = time.process_time() - c0, time.perf_counter() - w0
            add(c, "articulated", "accuracy", f"1 cm, {label}", res, cpu, wall, 1, own="articulated",
                extra=dict(note=f"estimate {rep.estimate_position * 1e3:.3f} mm, met {rep.met}, rtol {rep.settings['rtol']:.0e}, "
                                f"eps {rep.settings['eps']:.3g}, v_stop {rep.settings['v_stop']:.3g}, {rep.n_runs} runs",
                           estimate_m=rep.estimate_position))

    # ---- delta-v per impact-model variant
    dv_rows = []
    for name, sc, impact in scenes:
        for vname, problem in impact_variants(sc).items():
            out, cpu, wall, n = timed(lambda: solve_impact(problem), 5 if not args.quick else 1)
            states = separation_states(sc, out)
            for veh in sc.vehicles:
                if veh.is_barrier:
                    continue
                initial = make_hitch_consistent(veh, {b.name: states[b.name] for b in veh.bodies})
                r = simulate_level("articulated", veh, initial, sc.runout.wheels[veh.name], sc.runout.road)
                ref_art = refs[(name, veh.name), "articulated"]
                for b in veh.bodies:
                    dv = out.bodies[b.name].delta_v
                    dv0 = impact.bodies[b.name].delta_v
                    dv_rows.append(dict(
                        scene=name, variant=vname, vehicle=veh.name, body=b.name, cpu_ms=cpu * 1e3,
                        delta_v=float(np.hypot(*dv)), delta_v_change=float(np.hypot(*(dv - dv0))),
                        rest_shift=math.dist(r.bodies[b.name].rest_position, ref_art.bodies[b.name].rest_position),
                    ))

    OUT.mkdir(exist_ok=True)
    elapsed = time.perf_counter() - t_start
    write_csv(rows, OUT / "speed_accuracy.csv")
    write_markdown(rows, dv_rows, refs, ref_unc, cases, compiled_note, args, elapsed, OUT / "speed_accuracy.md")
    plot(rows, OUT / "speed_accuracy.png")
    print(f"done in {elapsed:.0f} s", flush=True)
    return 0


# ---------------------------------------------------------------------------------------------- output
def write_csv(rows, path):
    fields = list(dict.fromkeys(k for r in rows for k in r))
    with open(path, "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields)
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def _median(xs):
    xs = [x for x in xs if not (isinstance(x, float) and math.isnan(x))]
    return statistics.median(xs) if xs else float("nan")


def _group(rows):
    """Rows grouped by (level, engine, setting), each group one row per case."""
    groups = {}
    for r in rows:
        groups.setdefault((r["level"], r["engine"], r["setting"]), []).append(r)
    return groups


def _fmt_mm(x):
    return "exact" if x == 0 else ("-" if math.isnan(x) else f"{x * 1e3:.3g}")


def write_markdown(rows, dv_rows, refs, ref_unc, cases, compiled_note, args, elapsed, path):
    n_cases = len(cases)
    groups = _group(rows)
    default_setting = f"{DEFAULT.method} {DEFAULT.rtol:.0e}"
    lines = [
        "# Speed and accuracy of the run-out levels, solvers and tolerances (shipped scenes)",
        "",
        "Generated by `python benchmarks/speed_accuracy.py" + (" --quick" if args.quick else "") + f"` in {elapsed / 60:.1f} min; "
        "cases, references and measures are described in the script's docstring.",
        "",
        f"Machine: {platform.machine()}, {os.cpu_count()} CPUs (shared), Python {platform.python_version()}, "
        f"NumPy {np.__version__}, SciPy {scipy.__version__}; load average {LOAD_AT_START:.2f} at the start, "
        f"{os.getloadavg()[0]:.2f} at the end.  Cost is CPU time (process_time) per run-out, the median over "
        f"repeats; the cases are the {n_cases} vehicle run-outs of "
        + ", ".join(sorted({c['scene'] for c in cases})) + ".",
        "",
        "Errors: the largest distance of a body's rest position from the converged reference (LSODA, rtol 1e-10, "
        "eps = v_stop = 1e-3 m/s) of the **same level** (numerical error), and from that of the **full model** "
        "(`load_transfer`: model error plus numerical error).  **Delta-v error is 0 in every run-out row**: delta-v "
        "comes from the impact's linear solve, the same for every level, method and tolerance; it changes only with "
        "the impact model (table below).",
        "",
        "## Summary: level x cost x rest error",
        "",
        f"Each level at the default setting ({default_setting}, eps 0.01 m/s, v_stop 0.03 m/s) over the {n_cases} "
        "run-outs: median and largest value.",
        "",
        "| level | model | median CPU per run-out [ms] | numerical rest error, median / max [mm] "
        "| rest error vs full model, median / max [m] |",
        "|---|---|---|---|---|",
    ]
    models = {
        "impact": "impact only (bodies left at separation)",
        "energy": "hand calculation d = v^2/(2 f g) + rotating-skid work",
        "rigid": "bodies alone, hitch ignored",
        "articulated": "full articulated run-out, static loads",
        "load_transfer": "articulated + quasi-static load transfer",
    }
    for level in LEVELS:
        key = {"impact": ("impact", "-", "impact solve"), "energy": ("energy", "closed form", "-")}.get(
            level, (level, "scipy", default_setting))
        g = groups.get(key, [])
        if not g:
            continue
        num = [r["pos_err_m"] for r in g]
        full = [r["pos_err_full_m"] for r in g]
        num_txt = "-" if all(math.isnan(x) for x in num) else f"{_fmt_mm(_median(num))} / {_fmt_mm(max(num))}"
        lines.append(
            f"| {level} | {models[level]} | {_median([r['cpu_ms'] for r in g]):.3g} | {num_txt} | "
            f"{_median(full):.3g} / {max(full):.3g} |"
        )
    # compiled engine at its default
    g = groups.get(("articulated", "compiled", f"dopri5 {DEFAULT.rtol:.0e}"))
    if g:
        lines.append(
            f"| articulated, compiled engine | same model, numba (dopri5 {DEFAULT.rtol:.0e}) | "
            f"{_median([r['cpu_ms'] for r in g]):.3g} | "
            f"{_fmt_mm(_median([r['pos_err_m'] for r in g]))} / {_fmt_mm(max(r['pos_err_m'] for r in g))} | "
            f"{_median([r['pos_err_full_m'] for r in g]):.3g} / {max(r['pos_err_full_m'] for r in g):.3g} |"
        )

    tight = groups.get(("articulated", "scipy", f"LSODA {min(r for r in RTOLS if any(g[2] == f'LSODA {r:.0e}' for g in groups)):.0e}"), [])
    if tight:
        lines += ["", f"At tight tolerances the numerical error stops falling at about "
                  f"{_median([r['pos_err_m'] for r in tight]) * 1e3:.2g} mm (median; largest "
                  f"{max(r['pos_err_m'] for r in tight) * 1e3:.2g} mm, articulated level, LSODA at the tightest rtol): "
                  "that floor is the default eps = 0.01 m/s and v_stop = 0.03 m/s against the references' 1e-3 m/s "
                  "(note sec. 3.4), not the integration.  The differences between the levels (metres) dwarf it."]

    # cheapest setting per level meeting 1 cm numerical error on every case
    lines += ["", "Cheapest setting meeting a 1 cm numerical rest error on every case (total CPU over the cases):", "",
              "| level | engine | setting | total CPU [ms] | largest numerical error [mm] | largest error vs full model [m] |",
              "|---|---|---|---|---|---|"]
    for level in ("rigid", "articulated", "load_transfer"):
        for engine in ("scipy", "compiled", "pymunk"):
            ok = [(setting, sum(r["cpu_ms"] for r in g), max(r["pos_err_m"] for r in g), max(r["pos_err_full_m"] for r in g))
                  for (lv, e, setting), g in groups.items()
                  if lv == level and e == engine and len(g) == n_cases
                  and all(r["status"] == "rest" and r["pos_err_m"] <= 0.01 for r in g)]
            if ok:
                setting, total, num, full = min(ok, key=lambda x: x[1])
                lines.append(f"| {level} | {engine} | {setting} | {total:.4g} | {num * 1e3:.3g} | {full:.3g} |")
    acc = [r for r in rows if r["engine"] == "accuracy"]
    if acc:
        lines += ["", "Accuracy mode (`simulate_to_accuracy`, target 1 cm, articulated level): the estimate against the "
                  "true error (converged reference of the same model), and the cost of all its runs:", "",
                  "| scene | vehicle | engine | estimate [mm] | true error [mm] | estimate >= true | CPU of all runs [ms] | chosen |",
                  "|---|---|---|---|---|---|---|---|"]
        for r in acc:
            lines.append(f"| {r['scene']} | {r['vehicle']} | {r['setting'].split(', ')[1]} | {r['estimate_m'] * 1e3:.3f} | "
                         f"{r['pos_err_m'] * 1e3:.3f} | {'yes' if r['pos_err_m'] <= r['estimate_m'] else 'NO'} | "
                         f"{r['cpu_ms']:.1f} | {r['note'].split(', ', 2)[2]} |")

    lines += ["", f"Compiled engine: {compiled_note}.", ""]
    lines += ["## Delta-v per impact-model variant", "",
              "Delta-v does not depend on the run-out level, method or tolerance (error 0 in every row below the "
              "summary).  What changes it is the impact model; each variant against the scene as given "
              f"(rest shift: articulated level, LSODA {DEFAULT.rtol:.0e}, against the converged reference of the scene as given, "
              "so the 'as given' rows show the default setting's numerical error):", "",
              "| scene | impact variant | body | delta-v [m/s] | delta-v change [m/s] | rest shift [m] | impact solve CPU [ms] |",
              "|---|---|---|---|---|---|---|"]
    for d in dv_rows:
        lines.append(f"| {d['scene']} | {d['variant']} | {d['body']} | {d['delta_v']:.4f} | {d['delta_v_change']:.4f} | "
                     f"{d['rest_shift']:.4f} | {d['cpu_ms']:.2f} |")

    lines += ["", "## References", "",
              "Converged references and their uncertainty (DOP853 against LSODA at rtol 1e-10):", "",
              "| scene | vehicle | level | body | rest x [m] | rest y [m] | heading [deg] | time to rest [s] | uncertainty |",
              "|---|---|---|---|---|---|---|---|---|"]
    for (key, level), r in refs.items():
        unc = ref_unc.get((key, level))
        for b in r.bodies.values():
            lines.append(f"| {key[0]} | {key[1]} | {level} | {b.name} | {b.rest_position[0]:.4f} | {b.rest_position[1]:.4f} | "
                         f"{math.degrees(b.rest_heading):.3f} | {b.time_to_rest:.3f} | "
                         + ("" if unc is None else f"{unc[0] * 1e3:.4f} mm, {math.degrees(unc[1]):.1e} deg") + " |")

    lines += ["", "## All rows", "",
              "| scene | vehicle | level | engine | setting | status | CPU [ms] | nfev | num. err [mm] | head. err [deg] "
              "| err vs full [m] | head. vs full [deg] | delta-v err [m/s] | note |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['scene']} | {r['vehicle']} | {r['level']} | {r['engine']} | {r['setting']} | {r['status']} | "
            f"{r['cpu_ms']:.3g} | {r['nfev']} | {_fmt_mm(r['pos_err_m'])} | "
            f"{'-' if math.isnan(r['head_err_deg']) else format(r['head_err_deg'], '.2g')} | {r['pos_err_full_m']:.3g} | "
            f"{r['head_err_full_deg']:.3g} | 0 | {r.get('note', '')} |"
        )
    path.write_text("\n".join(lines) + "\n")


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    groups = _group(rows)
    colors = {"impact": "0.5", "energy": "tab:purple", "rigid": "tab:orange", "articulated": "tab:blue",
              "load_transfer": "tab:green"}
    markers = {"RK45": "o", "DOP853": "D", "LSODA": "s", "Radau": "^", "BDF": "v", "pymunk": "x", "dopri5": "P",
               "bs3": "*", "closed form": "h", "-": "8", "accuracy": "X"}
    fig, axes = plt.subplots(1, 2, figsize=(14, 6.2))
    seen = set()
    for (level, engine, setting), g in groups.items():
        kind = engine if engine in ("pymunk", "closed form", "-", "accuracy") else setting.split()[0]
        t = sum(r["cpu_ms"] for r in g)
        for ax, key in zip(axes, ("pos_err_m", "pos_err_full_m")):
            e = max(r[key] for r in g)
            if math.isnan(e):
                continue
            label = f"{level} / {kind}" if (level, kind) not in seen else None
            seen.add((level, kind))
            ax.loglog(t, max(e, 1e-7), markers.get(kind, "o"), color=colors[level], ms=7, mfc="none" if engine == "compiled" else None,
                      label=label, alpha=0.85)
    for ax, title in zip(axes, ("numerical error: largest rest-position error vs same-level converged reference",
                                "error vs the full model (load_transfer, converged): model + numerical")):
        ax.axhline(0.01, color="grey", ls=":", lw=1)
        ax.set_xlabel("total CPU time of the 6 run-outs [ms] (median per run)")
        ax.set_ylabel("largest rest-position error over the 6 run-outs [m]")
        ax.set_title(title, fontsize=9)
        ax.grid(True, which="both", alpha=0.3)
    axes[0].text(0.01, 0.02, "exact (closed form) and < 1e-7 m plotted at 1e-7; dotted: 1 cm", transform=axes[0].transAxes,
                 fontsize=7)
    handles, labels = axes[0].get_legend_handles_labels()
    h2, l2 = axes[1].get_legend_handles_labels()
    for h, l in zip(h2, l2):
        if l not in labels:
            handles.append(h)
            labels.append(l)
    fig.legend(handles, labels, loc="center right", fontsize=7, ncol=1)
    fig.suptitle("Run-out levels, solvers and tolerances on the shipped scenes: cost vs rest-position error "
                 "(colour: level; marker: method/engine; open markers: compiled engine)")
    fig.tight_layout(rect=(0, 0, 0.83, 0.95))
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())

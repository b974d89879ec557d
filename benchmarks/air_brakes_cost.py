"""What the air brakes cost: a tractor-semitrailer run-out with the features off and on, both engines.

Run from the repository root::

    PYTHONPATH=src python benchmarks/air_brakes_cost.py            # ~1 min
    PYTHONPATH=src python benchmarks/air_brakes_cost.py --quick    # smoke run, a few seconds

Writes ``plots/air_brakes_cost.md`` (``--out DIR`` elsewhere).

What is measured
----------------
The tractor-semitrailer of ``tests/analytic/runout_cases.py`` leaves an impact at 22 m/s with a
little side slip and yaw, on a level road of friction 0.8, truck tyres (6 /rad, rolling
resistance 0.007):

* ``off``: every wheel braked at 60 % of its friction limit (the wheel states crashsim had
  before air brakes: no clock, the kernels' air-brake branch never taken);
* ``air brakes``: every wheel rolling, the tractor's and the trailer's air brakes applied at
  separation with the default timing of their unit types (FMVSS 121), capacities of 40/100/100 kN
  and 90 kN, the tractor with ABS (efficiency 0.85), the trailer without (its wheels lock).

Reported: the median and the minimum CPU time (``time.process_time``) of repeats after a warm-up
call, the right-hand-side evaluations and the simulated time to rest, and the ratio air brakes /
off.  The two runs are different motions (the braking differs), so the ratio mixes the cost of
the feature with the length of the run; the goal of issue 22 is a ratio of at most 1.3 with every feature on
(the last two rows: also a road of grade -4 % and cross-slope 2 % and the rollover check, at the
load-transfer level that check needs).
"""

from __future__ import annotations

import argparse
from dataclasses import replace
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(ROOT / "tests" / "analytic"))

from _machine import cpu_name  # noqa: E402
from runout_cases import tractor_semitrailer  # noqa: E402

from crashsim.motion import Road, RunoutOptions, simulate_runout  # noqa: E402
from crashsim.motion.brakes import AirBrakes, BrakeUnit  # noqa: E402
from crashsim.motion.wheels import WheelSetting, WheelSettings  # noqa: E402
from crashsim.vehicles import chain_states  # noqa: E402

TYRE = dict(cornering_coefficient=6.0, rolling_resistance=0.007)


def cases() -> dict:
    brakes = AirBrakes({"tractor": BrakeUnit((40e3, 100e3, 100e3), "tractor", abs=True),
                        "trailer": BrakeUnit((90e3,), "last_trailer")}, abs_efficiency=0.85)
    return {"off": WheelSettings(default=WheelSetting("braked", brake=0.6, **TYRE)),
            "air brakes": WheelSettings(default=WheelSetting("rolling", **TYRE), brakes=brakes)}


#: Every issue-22 feature a tractor-semitrailer can use at once: the air brakes and ABS above, a
#: road of grade -4 % and cross-slope 2 %, and the wheel-lift and rollover check (which needs the
#: load-transfer level; its baseline is that level with the features off).
SLOPED = dict(grade=-0.04, cross_slope=0.02)


def runs() -> list[tuple[str, str, object, dict, dict]]:
    """(case, baseline case, wheel settings, road keywords, option keywords) of each measured run."""
    c = cases()
    return [("off", "off", c["off"], {}, {}),
            ("air brakes", "off", c["air brakes"], {}, {}),
            ("off, load transfer", "off, load transfer", c["off"], {}, dict(load_transfer=True)),
            ("all on (air brakes, ABS, slope, rollover check), load transfer", "off, load transfer",
             c["air brakes"], SLOPED, dict(load_transfer=True, rollover=True))]


def measure(repeats: int) -> list[dict]:
    # CG heights (tractor 1.1 m, loaded semitrailer 1.6 m: assumed) for the load-transfer runs; unused by the others
    veh = tractor_semitrailer()
    veh = replace(veh, bodies=tuple(replace(b, cg_height=h) for b, h in zip(veh.bodies, (1.1, 1.6))))
    init = chain_states(veh, (0.0, 0.0), 0.0, (22.0, 1.0), yaw_rates=(0.2, 0.0))
    rows = []
    for engine in ("compiled", "scipy"):
        cases = []
        for name, base, ws, road_kw, opt_kw in runs():
            opts, road = RunoutOptions(engine=engine, **opt_kw), Road(0.8, **road_kw)
            res = simulate_runout(veh, init, ws, road, opts)  # warm-up (compile, caches)
            cases.append((name, base, ws, road, opts, res, []))
        # the repeats interleaved (one run of every case per round): a drift of the machine's load
        # weighs on every case alike, so the ratios hold on a shared machine
        for _ in range(repeats):
            for _, _, ws, road, opts, _, times in cases:
                t0 = time.process_time()
                simulate_runout(veh, init, ws, road, opts)
                times.append(time.process_time() - t0)
        for name, base, _, _, _, res, times in cases:
            rows.append(dict(engine=engine, case=name, base=base, median=statistics.median(times), min=min(times),
                             nfev=res.nfev, t_end=res.t_end))
    return rows


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="few repeats (smoke run)")
    parser.add_argument("--out", type=Path, default=ROOT / "plots")
    args = parser.parse_args(argv)
    rows = measure(5 if args.quick else 60)
    lines = ["# What the air brakes cost", "",
             f"Generated by `benchmarks/air_brakes_cost.py`{' --quick' if args.quick else ''} on {cpu_name()}, "
             f"Python {platform.python_version()}.", "",
             "| engine | case | CPU median [ms] | CPU min [ms] | nfev | time to rest [s] | ratio (median) |",
             "|---|---|---|---|---|---|---|"]
    base = {(r["engine"], r["case"]): r["median"] for r in rows}
    for r in rows:
        lines.append(f"| {r['engine']} | {r['case']} | {1e3 * r['median']:.2f} | {1e3 * r['min']:.2f} | {r['nfev']} | "
                     f"{r['t_end']:.3f} | {r['median'] / base[r['engine'], r['base']]:.2f} |")
    lines += ["", "Ratio: against the run with the features off at the same level (`off`, or `off, load transfer` "
              "for the runs at the load-transfer level the rollover check needs)."]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "air_brakes_cost.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

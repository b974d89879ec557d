"""One run-out for the whole scene against the separate run-outs of each vehicle, on both engines.

Run from the repository root::

    PYTHONPATH=src python benchmarks/joint_runout.py            # ~2 min
    PYTHONPATH=src python benchmarks/joint_runout.py --quick    # smoke run, ~30 s

Writes ``plots/joint_runout.md`` and ``plots/joint_runout.csv``.

What is measured
----------------
Cases: every shipped scene (``scenarios/scenes/*.toml``: impact solved, separation states made
hitch-consistent, the scene's run-out options) and the paper's Table 6 scene of
``benchmarks/runout_solvers.py`` (two vehicles, a friction zone, scheduled brake changes).

For each case and engine (SciPy's LSODA and the compiled dopri5, both at the default
tolerance rtol 1e-8):

* ``separate``: every vehicle run out alone with :func:`crashsim.motion.simulate_runout`, as
  before the whole-scene run-out (no contact: bodies pass through each other and the barrier);
  one timed unit for all of the scene's vehicles;
* ``joint, no contact``: all vehicles in one :func:`crashsim.motion.simulate_scene` with contact
  switched off -- the same physics as ``separate``, integrated together;
* ``joint``: the scene as ``crashsim run`` computes it, with contact between the vehicles and
  with the barrier and obstacles.

Reported: median CPU time (``time.process_time``) over repeats after a warm-up call, the
ratio joint / separate, the largest rest-position and heading difference between ``joint, no
contact`` and ``separate`` (integration error only: the equations are the same), and for
``joint`` the secondary impacts and how far contact moved the rest positions.  The target of
issue 10: a scene without later contact costs at most 1.3x its separate run-outs.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import logging
import math
import platform
import statistics
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(__file__).resolve().parent))

from crashsim import solve_impact  # noqa: E402
from crashsim.motion import (ContactModel, RunoutOptions, make_hitch_consistent, simulate_runout,  # noqa: E402
                             simulate_scene)
from crashsim.scene.run import separation_states  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402


@dataclasses.dataclass
class Case:
    name: str
    vehicles: list
    initial: dict
    wheels: dict
    road: object
    options: RunoutOptions
    contact: ContactModel | None = None
    pair_contact: dict | None = None
    obstacles: tuple = ()

    def separate(self, engine):
        o = dataclasses.replace(self.options, engine=engine)
        return {v.name: simulate_runout(v, {b.name: self.initial[b.name] for b in v.bodies}, self.wheels[v.name],
                                        self.road, o) for v in self.vehicles}

    def joint(self, engine, contact=True):
        o = dataclasses.replace(self.options, engine=engine)
        if not contact:
            return simulate_scene(self.vehicles, self.initial, self.wheels, self.road, o,
                                  contact=ContactModel(enabled=False))
        return simulate_scene(self.vehicles, self.initial, self.wheels, self.road, o, contact=self.contact,
                              pair_contact=self.pair_contact, obstacles=self.obstacles)


def shipped_cases() -> list[Case]:
    cases = []
    for path in sorted((ROOT / "scenarios" / "scenes").glob("*.toml")):
        sc = load_scenario(path)
        states = separation_states(sc, solve_impact(sc.impact))
        spec = sc.runout
        movable = [v for v in sc.vehicles if not v.is_barrier]
        initial = {}
        for v in movable:
            initial.update(make_hitch_consistent(v, {b.name: states[b.name] for b in v.bodies}))
        cases.append(Case(path.stem, movable, initial, spec.wheels, spec.road, spec.options, spec.contact,
                          spec.pair_contact, spec.obstacles))
    return cases


def table6_case() -> Case:
    from runout_solvers import build_scene, post_impact_states

    vehicles, wheels, road = build_scene()
    return Case("table6 (runout_solvers)", vehicles, post_impact_states(vehicles), wheels, road, RunoutOptions())


def _timed(fn, repeats):
    out = fn()  # warm-up: compile or cache load, prepared inputs
    cpu = []
    for _ in range(repeats):
        c0 = time.process_time()
        out = fn()
        cpu.append(time.process_time() - c0)
    return out, statistics.median(cpu)


def _rests(runouts: dict):
    return {n: (b.rest_position, b.rest_heading) for r in runouts.values() for n, b in r.bodies.items()}


def _diff(a, b):
    ra, rb = _rests(a), _rests(b)
    dp = max(math.dist(ra[n][0], rb[n][0]) for n in ra)
    dh = max(abs(math.remainder(ra[n][1] - rb[n][1], 2 * math.pi)) for n in ra)
    return dp, math.degrees(dh)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats (smoke run)")
    parser.add_argument("--out", type=Path, default=ROOT / "plots")
    args = parser.parse_args(argv)
    logging.disable(logging.WARNING)
    repeats = {"scipy": 2 if args.quick else 5, "compiled": 5 if args.quick else 30}
    cases = shipped_cases() + [table6_case()]
    rows = []
    t0 = time.perf_counter()
    for case in cases:
        for engine in ("scipy", "compiled"):
            sep, t_sep = _timed(lambda: case.separate(engine), repeats[engine])
            jnc, t_jnc = _timed(lambda: case.joint(engine, contact=False), repeats[engine])
            jnt, t_jnt = _timed(lambda: case.joint(engine), repeats[engine])
            dp0, dh0 = _diff(jnc.vehicles, sep)
            dp1, dh1 = _diff(jnt.vehicles, sep)
            touched = any(p.contact_time > 0 or p.impacts for p in jnt.pairs)
            rows.append({"case": case.name, "engine": engine, "vehicles": len(case.vehicles),
                         "cpu_separate_ms": 1e3 * t_sep, "cpu_joint_no_contact_ms": 1e3 * t_jnc,
                         "cpu_joint_ms": 1e3 * t_jnt, "ratio_no_contact": t_jnc / t_sep, "ratio_joint": t_jnt / t_sep,
                         "same_physics_dpos_m": dp0, "same_physics_dhead_deg": dh0, "impacts": len(jnt.impacts),
                         "later_contact": touched, "contact_moved_m": dp1, "contact_turned_deg": dh1,
                         "status": jnt.status})
    elapsed = time.perf_counter() - t0
    args.out.mkdir(exist_ok=True)
    with (args.out / "joint_runout.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    lines = ["# Whole-scene run-out against separate run-outs", "",
             f"Generated by `benchmarks/joint_runout.py`{' --quick' if args.quick else ''} on {platform.machine()}, "
             f"Python {platform.python_version()}; {elapsed:.0f} s.  Median CPU time of one run-out of all the "
             f"scene's vehicles (result objects included) over {repeats['scipy']} (SciPy) / {repeats['compiled']} "
             "(compiled) repeats after a warm-up; default tolerance rtol 1e-8 on both engines.", "",
             "| case | engine | vehicles | separate [ms] | joint, no contact [ms] | joint [ms] | joint no contact / "
             "separate | joint / separate | same physics: rest diff [m] / [deg] | later impacts | later contact "
             "moved the rest by [m] / [deg] |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        moved = (f"{r['contact_moved_m']:.3g} / {r['contact_turned_deg']:.3g}" if r["later_contact"] else "no contact")
        lines.append(f"| {r['case']} | {r['engine']} | {r['vehicles']} | {r['cpu_separate_ms']:.1f} | "
                     f"{r['cpu_joint_no_contact_ms']:.1f} | {r['cpu_joint_ms']:.1f} | {r['ratio_no_contact']:.2f} | "
                     f"{r['ratio_joint']:.2f} | {r['same_physics_dpos_m']:.1e} / {r['same_physics_dhead_deg']:.1e} | "
                     f"{r['impacts']} | {moved} |")
    quiet = [r for r in rows if not r["later_contact"]]
    lines += ["", "## Summary", ""]
    for engine in ("scipy", "compiled"):
        sel = [r for r in rows if r["engine"] == engine]
        nc = [r["ratio_no_contact"] for r in sel]
        q = [r["ratio_joint"] for r in quiet if r["engine"] == engine]
        lines.append(f"* {engine}: joint without contact / separate, median {statistics.median(nc):.2f}, largest "
                     f"{max(nc):.2f} over {len(sel)} scenes"
                     + (f"; scenes without later contact, joint / separate: largest {max(q):.2f}" if q else "")
                     + f"; same physics, rest positions within {max(r['same_physics_dpos_m'] for r in sel):.1e} m.")
    by = {(r["case"], r["engine"]): r for r in rows}
    speed = [by[(c.name, "scipy")]["cpu_joint_ms"] / by[(c.name, "compiled")]["cpu_joint_ms"] for c in cases]
    lines.append(f"* compiled against SciPy, joint run-out: {statistics.median(speed):.0f}x faster (median over the "
                 f"scenes; {min(speed):.0f}x to {max(speed):.0f}x).")
    lines += ["", "The target of issue 10 (a scene without later contact costs at most 1.3x its separate run-outs) is "
              "read from the joint / separate ratio of the scenes without later contact, and from the joint without "
              "contact / separate ratio of all scenes (the cost of integrating the vehicles together).  Where bodies do "
              "meet, the joint run-out costs what the contact needs: smaller steps through each impact and, in "
              "sustained contact, through the stiff penalty forces (the median-barrier slide: 8 s of contact).", ""]
    (args.out / "joint_runout.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

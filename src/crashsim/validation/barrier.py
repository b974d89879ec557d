"""A full-scale car-into-barrier crash test (MASH test 3-10): exit speed and angle, run-out, rest.

The case's ``scene.toml`` is the test's configuration with the suite's rules (``validation/rules.toml``
``[vehicle_to_barrier]``, ``[car_tyres]``): the car's front corner strikes a rigid barrier along the x
axis at the measured speed and angle, the run-out finds the later slaps, and the remote brakes act
from the published time on. Compared with the test report (``measured.toml``):

* exit speed, trajectory (direction of the CG velocity) and heading at the loss of contact, the last
  time the car leaves the barrier;
* the rest position (downstream of the impact point along the barrier, toward the traffic side) and
  the rest heading.

Bands: the nearest published repeat, TTI's test 612541-01-4 (MASH 3-20 on the same barrier system's
transition: the same vehicle class, 62.6 mph and 25.5 deg against 63.7 mph and 25.5 deg), its
difference from this test, and never narrower than the printed precision of the published value
(``validation/mash-3-10/README.md``).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..scene import run_scene
from ..scenario import load_scenario
from ..units import Kind
from .core import CaseResult, Quantity, angle_difference, quantity

__all__ = ["exit_state", "run_case"]


def exit_state(scene, body: str, barrier: str):
    """(time, speed, trajectory, heading) of ``body`` when it last leaves ``barrier`` (SI, rad), or None."""
    ends = [e for e in scene.joint.events if e.kind == "contact_end" and body in e.detail and barrier in e.detail]
    if not ends:
        return None
    t = max(e.t for e in ends)
    vname = next(v for v, r in scene.runout.items() if body in r.bodies)
    h = scene.runout[vname].bodies[body].history
    i = int(np.clip(np.searchsorted(h.t, t), 0, len(h.t) - 1))
    return t, float(math.hypot(h.vx[i], h.vy[i])), float(math.atan2(h.vy[i], h.vx[i])), float(h.heading[i])


def _band(published: dict, key: str, kind: Kind, where: str, f: Path, resolution: float):
    """The repeat's difference from this test for ``key``, at least ``resolution``."""
    a = quantity(published["test"][key], kind, f"measured.{key}", f)
    b = quantity(published["repeat"][key], kind, f"repeat.{key}", f)
    return max(abs(a - b), resolution), a


def run_case(data: dict, rules: dict, suite_folder: Path) -> CaseResult:
    """Run the scene and compare the exit and the rest with the test report (module docstring)."""
    t0 = time.process_time()
    folder = data["folder"]
    f = folder / "measured.toml"
    scenario = load_scenario(folder / data["case"]["scene"])
    scene = run_scene(scenario)
    body, barrier = scenario.impact.body1, scenario.impact.body2
    m = data["measured"]
    pub = {"test": m, "repeat": data["repeat"]}
    cid = data["case"]["id"]
    src, rsrc = m["source"], data["repeat"]["source"]
    res = {k: float(v) for k, v in data["resolution"].items() if k != "source"}
    q = []
    ex = exit_state(scene, body, barrier)
    basis = f"scatter: the difference from the nearest repeat ({rsrc}), at least the printed precision"
    if ex is None:
        raise RuntimeError(f"{cid}: the car never left the barrier in the run-out")
    t_exit, v_exit, course, heading = ex
    band, v_meas = _band(pub, "exit_speed", Kind.SPEED, "exit_speed", f, res["speed_mph"] * 0.44704)
    q.append(Quantity(cid, "exit speed", "exit speed", "speed", v_meas, v_exit, "difference", v_exit - v_meas, band,
                      basis, src, {}, "US", f"at the loss of contact, {t_exit:.3f} s after the impact"))
    for key, value, name in (("exit_trajectory", course, "exit trajectory"), ("exit_heading", heading, "exit heading")):
        band, meas = _band(pub, key, Kind.ANGLE, key, f, math.radians(res["angle_deg"]))
        q.append(Quantity(cid, name, "exit angle", "angle", meas, value, "difference", angle_difference(value, meas),
                          band, basis, src, {}, "US", "from the barrier's face (toward the traffic side positive)"))
    vname = scenario.vehicles[0].name
    b = scene.runout[vname].bodies[body]
    point = scene.impact.point
    rest = np.asarray(b.rest_position) - point
    for i, key, name in ((0, "rest_downstream", "rest position downstream"), (1, "rest_lateral", "rest position toward traffic")):
        band, meas = _band(pub, key, Kind.LENGTH, key, f, res["length_ft"] * 0.3048)
        q.append(Quantity(cid, name, "rest position", "length", meas, float(rest[i]), "difference",
                          float(rest[i]) - meas, band, basis, src, {}, "US",
                          "the CG's rest position from the impact point (the report's reference point is not stated)"))
    band, meas = _band(pub, "rest_heading", Kind.ANGLE, "rest_heading", f, math.radians(res["angle_deg"]))
    q.append(Quantity(cid, "rest heading", "rest heading", "angle", meas, float(b.rest_heading_wrapped), "difference",
                      angle_difference(b.rest_heading_wrapped, meas), band, basis, src, {}, "US",
                      "left (toward the traffic side) positive"))
    figure = {"scene": scene, "exit": ex, "rest_measured": (quantity(m["rest_downstream"], Kind.LENGTH, "", f),
                                                            quantity(m["rest_lateral"], Kind.LENGTH, "", f))}
    notes = tuple(f"{e.t:.3f} s: {e.kind} {e.detail}" for e in scene.joint.events if barrier in e.detail)
    return CaseResult(cid, data["case"]["title"], data["case"]["kind"], data["case"]["class"],
                      data["case"].get("configuration", ""), tuple(x.with_record(data["record"]) for x in q), notes,
                      figure, time.process_time() - t0, data["record"])

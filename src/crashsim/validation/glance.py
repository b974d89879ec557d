"""The full-scale tractor-semitrailer barrier test (NCHRP Report 350 test 5-12, MASH TL-5): its sequence,
its exit, and how the exit moves with the coefficients.

The published record of these tests is qualitative (``docs/validation/barrier-rollover.md``): the
tractor's front corner strikes first, the tractor is redirected along the barrier, the trailer's rear
swings in and slaps the barrier behind the trailer's CG, and the combination leaves the barrier, its exit
angle below 60 % of the impact angle (NCHRP 350's evaluation criterion M). The case runs the shipped
scene (``scenarios/scenes/barrier_glance_15deg.toml``, whose coefficients are the suite's
``[vehicle_to_barrier]`` rules) and checks each as a criterion. No published text gives the slap's time,
so the computed time is reported, not judged.

Sensitivity (the record being qualitative): the exit angles and the slap's time as each coefficient
moves alone around the rules: the first impact's restitution, the later impacts' restitution, and the
friction of both (``FACTORS``).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..scene import run_scene
from ..scenario import scenario_from_dict
from ..schema import load_toml
from ..units import Kind
from .barrier import exit_state
from .core import CaseResult, Quantity, quantity

__all__ = ["FACTORS", "sequence", "run_case"]

#: The coefficients varied one at a time, and their values (the rules' value among them).
FACTORS = {"first-impact restitution e": ("impact.restitution", (0.0, 0.1, 0.2, 0.3)),
           "later-impact restitution e": ("contacts.restitution", (0.1, 0.2, 0.3, 0.5)),
           "friction f (impact and contact)": (("impact.friction", "contacts.friction"), (0.15, 0.3, 0.45, 0.6))}


def _set(data: dict, path: str, value) -> dict:
    out = {k: (dict(v) if isinstance(v, dict) else v) for k, v in data.items()}
    top, key = path.split(".")
    out[top] = {**out.get(top, {}), key: value}
    return out


def sequence(scene, impact_angle: float) -> dict:
    """The published sequence's items on a run: who strikes first, the trailer's slaps (behind its CG,
    with friction), the exit angles at the last loss of contact, nothing touching after it [SI, rad]."""
    first = (scene.impact.body1, scene.impact.body2)
    slaps = [i for i in scene.joint.impacts if (i.body1, i.body2) == ("trailer", "barrier")]
    behind = []
    h = scene.runout["truck"].bodies["trailer"].history
    for s in slaps:
        i = int(np.clip(np.searchsorted(h.t, s.t), 0, len(h.t) - 1))
        c, sn = math.cos(h.heading[i]), math.sin(h.heading[i])
        behind.append(c * (s.point[0] - h.x[i]) + sn * (s.point[1] - h.y[i]) < 0.0)
    events = [e for e in scene.joint.events if "barrier" in e.detail and e.kind in ("contact_end", "contact", "impact")]
    exits = {b: exit_state(scene, b, "barrier") for b in ("tractor", "trailer")}
    return {"first": first, "slap_times": [s.t for s in slaps], "slap_behind_cg": behind,
            "slap_friction": [s.law == "friction" for s in slaps],
            "left_for_good": bool(events) and events[-1].kind == "contact_end",
            "exit": exits, "limit": 0.6 * impact_angle}


def run_case(data: dict, rules: dict, suite_folder: Path) -> CaseResult:
    """The criteria on the shipped scene (engine per the rules) and the one-at-a-time sensitivity."""
    t0 = time.process_time()
    f = data["folder"] / "measured.toml"
    cid = data["case"]["id"]
    scene_path = (data["folder"] / data["case"]["scene"]).resolve()
    raw = load_toml(scene_path)
    raw = _set(raw, "runout.engine", rules["runout"]["engine"])
    angle = quantity(data["test"]["impact_angle"], Kind.ANGLE, "test.impact_angle", f)
    scene = run_scene(scenario_from_dict(raw, file=str(scene_path)))
    s = sequence(scene, angle)
    src = data["test"]["source"]
    q = []

    def criterion(name, holds, source, note=""):
        q.append(Quantity(cid, name, "sequence", "dimensionless", 1.0, 1.0 if holds else 0.0, "criterion",
                          0.0 if holds else 1.0, 0.0, "stated: the published qualitative record", source, {}, "US",
                          note))

    criterion("the tractor's front corner strikes first", s["first"] == ("tractor", "barrier"), src)
    criterion("the trailer's rear slaps the barrier (behind its CG, with friction)",
              any(s["slap_behind_cg"]) and all(s["slap_friction"]), src,
              "slaps at " + ", ".join(f"{t:.3f} s" for t in s["slap_times"]) + " (no published time)")
    criterion("the combination leaves the barrier and does not come back", s["left_for_good"], src)
    for body in ("tractor", "trailer"):
        ex = s["exit"][body]
        value = ex[2] if ex is not None else math.nan
        q.append(Quantity(cid, f"exit angle, {body}", "exit angle (criterion M)", "angle", s["limit"], value, "limit",
                          value - s["limit"], 0.0, "stated: NCHRP 350 evaluation criterion M (below 60 % of the impact "
                          "angle)", data["test"]["criterion_source"], {}, "US",
                          f"direction of the CG velocity at the loss of contact ({ex[0]:.3f} s)" if ex else "never left"))
    sens = []
    for label, (paths, values) in FACTORS.items():
        for v in values:
            d = raw
            for p in (paths if isinstance(paths, tuple) else (paths,)):
                d = _set(d, p, v)
            r = run_scene(scenario_from_dict(d, file=str(scene_path)))
            ss = sequence(r, angle)
            sens.append({"factor": label, "value": v,
                         "exit_tractor": ss["exit"]["tractor"][2] if ss["exit"]["tractor"] else math.nan,
                         "exit_trailer": ss["exit"]["trailer"][2] if ss["exit"]["trailer"] else math.nan,
                         "first_slap": ss["slap_times"][0] if ss["slap_times"] else math.nan,
                         "left_for_good": ss["left_for_good"]})
    notes = ("the shipped scene scenarios/scenes/barrier_glance_15deg.toml, its coefficients the suite's "
             "[vehicle_to_barrier] rules, run on the rules' engine",)
    vb = rules["vehicle_to_barrier"]
    figure = {"sensitivity": sens, "limit": s["limit"],
              "rules": {"first-impact restitution e": vb["restitution"], "later-impact restitution e":
                        vb["contact_restitution"], "friction f (impact and contact)": vb["friction"]}}
    return CaseResult(cid, data["case"]["title"], data["case"]["kind"], data["case"]["class"],
                      data["case"].get("configuration", ""), tuple(x.with_record(data["record"]) for x in q), notes,
                      figure, time.process_time() - t0, data["record"])

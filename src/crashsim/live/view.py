"""The live view's payloads: a scene and its result as plain JSON the page draws.

Everything is world coordinates in metres (the page scales them) and every number the page
prints is formatted here, in the file's unit system (:func:`crashsim.units.format_value`), so the
page shows what ``crashsim run`` prints. The page draws; it computes nothing of the physics.
"""

from __future__ import annotations

import math

import numpy as np

from ..impact.result import clock_direction
from ..units import Kind, format_value, to_unit

__all__ = ["static_payload", "result_payload", "band_payload", "MAX_POSES"]

#: Poses per body sent for the time slider (a run-out of 3 s at 0.01 s steps).
MAX_POSES = 400
#: Points per wheel track at most.
MAX_TRACK = 300


def _r(a, digits: int = 4):
    """Rounded to 0.1 mm (world coordinates in metres) for a short message."""
    return np.round(np.asarray(a, dtype=float), digits).tolist()


def _every(n: int, most: int) -> np.ndarray:
    idx = np.unique(np.linspace(0, n - 1, min(n, most)).round().astype(int))
    return idx


def static_payload(session) -> dict:
    """What the page draws once per file (see the module notes)."""
    sc = session.scenario
    system = session.system
    per_m, lunit = to_unit(1.0, Kind.LENGTH, system)
    bodies, vehicles = {}, []
    movable = [v for v in sc.vehicles if not v.is_barrier]
    for v in sc.vehicles:
        colour = movable.index(v) if v in movable else -1
        for b in v.bodies:
            o = b.outline()
            bodies[b.name] = {"vehicle": v.name, "colour": colour, "outline": None if o is None else _r(o),
                              "axles": [[a.x, a.track] for a in b.axles], "barrier": v.is_barrier}
        vehicles.append({"name": v.name, "description": sc.descriptions.get(v.name, ""), "barrier": v.is_barrier,
                         "bodies": [b.name for b in v.bodies], "colour": colour,
                         "hitches": [{"front": v.bodies[i].name, "point": list(h.front_point)}
                                     for i, h in enumerate(v.hitches)]})
    ro = sc.runout
    zones = [{"name": z.name or f"zone {i + 1}", "friction": z.mu, "polygon": _r(z.vertices)}
             for i, z in enumerate(ro.road.zones if ro is not None else ())]
    barrier = next((v.bodies[0].name for v in sc.vehicles if v.is_barrier), None)
    obstacles = [{"name": o.name, "pieces": [_r(p) for p in o.pieces()]}
                 for o in (ro.obstacles if ro is not None else ()) if o.name != barrier]
    lines = [{"name": getattr(m, "name", "") or m.style, "style": m.style, "colour": m.color, "points": _r(m.points)}
             for m in (sc.map_lines or ())]
    ev = sc.evidence
    evidence = {"rest": [], "marks": [], "impact_point": None}
    if ev is not None:
        evidence["rest"] = [{"body": r.body, "position": list(r.position), "heading": r.heading,
                             "tolerance": r.tolerance} for r in ev.rest]
        evidence["marks"] = [{"name": m.name or f"mark {i + 1}", "points": _r(m.points), "tolerance": m.tolerance,
                              "phase": m.phase} for i, m in enumerate(ev.marks)]
        if ev.impact_point is not None:
            evidence["impact_point"] = {"position": list(ev.impact_point.position),
                                        "tolerance": ev.impact_point.tolerance}
    imp = session.data["impact"]
    return {"title": sc.title, "file": session.path.name, "units": system, "length_unit": lunit, "per_m": per_m,
            "bodies": bodies, "vehicles": vehicles, "zones": zones, "obstacles": obstacles, "map_lines": lines,
            "road_friction": ro.road.mu if ro is not None else None, "evidence": evidence,
            "point_frame": imp.get("point_frame", "world"), "normal_frame": imp.get("normal_frame", "world"),
            "controls": [c.to_dict() for c in session.controls.values()],
            "fit": session.has_fit,
            "uncertainty": session.band_inputs(), "underlay": session.underlay_info()}


def _frame_pose(sc, frame: str):
    if frame == "world":
        return [0.0, 0.0, 0.0]
    s = sc.states[frame]
    return [float(s.position[0]), float(s.position[1]), float(s.heading)]


def _runs(mask: np.ndarray):
    """(start, stop) of the runs of True in ``mask``."""
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    d = np.flatnonzero(np.diff(m.astype(int)))
    return list(zip(d[::2], d[1::2]))


def result_payload(result, session) -> dict:
    """The result of one recompute as the page draws it (see the module notes)."""
    sc = result.scenario
    system = session.system
    t_end = float(result.t_end or 0.0)
    dt = max(0.01, t_end / (MAX_POSES - 1)) if t_end > 0 else 0.01
    h = result.history(dt) if result.runout is not None else None
    poses = {}
    times = [0.0]
    if h is not None:
        times = _r(h["t"], 4)
        for v in sc.vehicles:
            for b in v.bodies:
                if f"{b.name}.x" in h:
                    poses[b.name] = np.round(np.column_stack([h[f"{b.name}.x"], h[f"{b.name}.y"],
                                                              h[f"{b.name}.heading"]]), 4).tolist()
    for name, s in sc.states.items():  # bodies without a run-out (a barrier): at their impact pose
        if name not in poses:
            poses[name] = [[float(s.position[0]), float(s.position[1]), float(s.heading)]]
    tracks = []
    for r in (result.runout or {}).values():
        for key, w in (r.wheels or {}).items():
            pts = np.asarray(w.points, dtype=float)
            if len(pts) < 2:
                continue
            idx = _every(len(pts), MAX_TRACK)
            sliding = np.asarray(w.sliding, dtype=bool)[idx] if w.sliding is not None else np.zeros(len(idx), bool)
            tracks.append({"key": key, "body": w.body, "points": _r(pts[idx], 3),
                           "sliding": [[int(a), int(b)] for a, b in _runs(sliding)]})
    approach = {}
    for vn, a in (getattr(sc, "approaches", None) or {}).items():
        for name, rows in a.bodies.items():
            rows = np.asarray(rows, dtype=float)
            idx = _every(len(rows), MAX_TRACK)
            approach[name] = _r(rows[idx][:, 1:4], 4)
    impacts = [{"event": int(i.get("event") or n + 1), "time": float(i["time"]), "point": _r(i["point"]),
                "bodies": [i["body1"], i["body2"]], "energy": format_value(i.get("energy_loss"), Kind.ENERGY, system)}
               for n, i in enumerate(result.impacts or ())]
    if not impacts:
        p = result.impact.point
        impacts = [{"event": 1, "time": 0.0, "point": _r(p), "bodies": [result.impact.body1, result.impact.body2],
                    "energy": format_value(result.impact.energy_loss_crush, Kind.ENERGY, system)}]
    checks = []
    n_pass = 0
    for c in (result.evidence.checks if result.evidence is not None else ()):
        kind = c.quantity if c.quantity in {k.value for k in Kind} else "dimensionless"
        res = format_value(c.residual, kind, system) if c.residual is not None and math.isfinite(c.residual) else "n/a"
        tol = format_value(c.tolerance, kind, system) if c.tolerance is not None else ""
        checks.append({"kind": c.kind, "name": c.name, "passed": bool(c.passed), "residual": res, "tolerance": tol,
                       "value": float(c.residual) if c.residual is not None and math.isfinite(c.residual) else None})
        n_pass += bool(c.passed)
    bodies = []
    for name, b in result.impact.bodies.items():
        if b.fixed:
            continue
        row = {"name": name, "delta_v": format_value(b.delta_v_magnitude, Kind.SPEED, system),
               "delta_v_si": float(b.delta_v_magnitude),
               "pdof": "" if b.pdof is None else f"{math.degrees(b.pdof):.1f} deg ({clock_direction(b.pdof)} o'clock)",
               "speed_after": format_value(float(np.hypot(*b.velocity)), Kind.SPEED, system)}
        bodies.append(row)
    ledger = result.energy_ledger() or {}
    energy = [[k.replace("_", " "), format_value(v, Kind.ENERGY, system)] for k, v in ledger.items()]
    warnings = [str(w) for w in (*getattr(sc, "load_warnings", ()), *result.warnings)]
    rest = {}
    for r in (result.runout or {}).values():
        for name, b in r.bodies.items():
            rest[name] = {"position": _r(b.rest_position), "heading": float(b.rest_heading),
                          "text": f"{format_value(b.rest_position[0], Kind.LENGTH, system)}, "
                                  f"{format_value(b.rest_position[1], Kind.LENGTH, system)}, "
                                  f"{math.degrees(b.rest_heading_wrapped):.1f} deg"}
    return {"times": times, "poses": poses, "tracks": tracks, "approach": approach, "impacts": impacts,
            "rest": rest, "t_end": t_end, "at_rest": bool(result.at_rest),
            "frames": {"point": _frame_pose(sc, session.data["impact"].get("point_frame", "world")),
                       "normal": _frame_pose(sc, session.data["impact"].get("normal_frame", "world"))},
            "evidence": checks, "n_passed": n_pass, "n_checks": len(checks), "bodies": bodies, "energy": energy,
            "warnings": warnings}


def band_payload(rows: list[dict], n: int, system: str) -> dict:
    """The Monte Carlo band: each sample's CG paths and rest poses, and the share that meets all
    the evidence."""
    ok = [r for r in rows if "error" not in r]
    meets = sum(1 for r in ok if r.get("all_passed"))
    return {"n": n, "n_done": len(ok), "cpu": sum(r.get("cpu", 0.0) for r in rows), "n_failed": len(rows) - len(ok), "n_meets_all": meets,
            "share_text": f"{meets} of {n} samples ({100.0 * meets / n:.0f} %) meet all the evidence" if n else "",
            "samples": [{"paths": r["paths"], "rest": r["rest"], "all_passed": r.get("all_passed", False)} for r in ok]}

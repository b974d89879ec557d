"""Which case class of the validation suite a scene belongs to, and the suite's errors for that class.

A scene's class follows from its first impact, by rule:

* the impact's other body is a barrier (a fixed body): **vehicle-to-barrier** (its cases: a small car and
  a loaded tractor-van semitrailer);
* otherwise, if a vehicle of the impact is articulated or heavier than the suite's cars
  (:data:`CAR_MASS_LIMIT`), **articulated or heavy vehicle-to-vehicle**: the suite has no staged collision of one, so
  the report quotes the classes nearest it (:func:`related_classes`): car-to-car for the impact,
  articulated kinematics for an articulated vehicle, approach and braking for a scene with an approach;
* otherwise **car-to-car**.

Between two vehicles the configuration is that of the faces that meet: each body's face is the side
of its outline nearest the impact point (front, rear or side), giving front-to-side, front-to-rear,
front-to-front, side-to-side, rear-to-side or rear-to-rear.

The suite's errors come from the table ``benchmarks/validation_suite.py`` writes into the package
(``crashsim/data/validation_errors.json``, the numbers of ``docs/validation/errors.md``): for the class,
every quantity group's mean and largest error over the class's cases, and, where the suite has cases of
the same configuration, the same over those alone. A scene of that class is told what puts it
outside the suite's cases: the related classes' errors are the nearest evidence the suite has, not a
measured error rate of that configuration.
"""

from __future__ import annotations

import json
import math
from importlib.resources import files

import numpy as np

from ..geometry import rotation
from .output import summary_value_text

__all__ = ["face_of", "scene_class", "related_classes", "load_error_table", "class_errors", "TABLE", "HEAVY_CLASS",
           "CAR_MASS_LIMIT"]

#: The packaged error table (written by benchmarks/validation_suite.py).
TABLE = "data/validation_errors.json"

#: Largest body mass of the suite's car-to-car cases, rounded up [kg]: heavier is outside them.
CAR_MASS_LIMIT = 2500.0
#: The class of an impact between vehicles one of which is articulated or heavier than CAR_MASS_LIMIT.
HEAVY_CLASS = "articulated or heavy vehicle-to-vehicle"


def face_of(body, state, point) -> str:
    """The face of ``body``'s outline nearest ``point`` (world): "front", "rear" or "side"."""
    p = rotation(-state.heading) @ (np.asarray(point, dtype=float) - np.asarray(state.position, dtype=float))
    length = body.length if body.length else 4.5
    width = body.width if body.width else 1.8
    cx = body.outline_center[0] if body.outline_center is not None else 0.0
    d = {"front": abs(cx + length / 2 - p[0]), "rear": abs(p[0] - (cx - length / 2)),
         "side": abs(width / 2 - abs(p[1]))}
    return min(d, key=d.get)


def scene_class(scene) -> dict:
    """The scene's class, configuration, and what puts its vehicles outside the suite's cases."""
    sc = scene.scenario
    imp = scene.impact
    bodies = {b.name: (v, b) for v in sc.vehicles for b in v.bodies}
    b1, b2 = imp.body1, imp.body2
    fixed = [n for n in (b1, b2) if bodies[n][1].is_fixed]
    if fixed:  # the class's cases: a small car (MASH 3-10) and a 36 t tractor-van semitrailer (NCHRP 350 5-12)
        return {"class": "vehicle-to-barrier", "configuration": None, "outside": [],
                "rule": "the impact's other body is a barrier"}
    outside = []
    for n in (b1, b2):
        v, b = bodies[n]
        if len(v.bodies) > 1:
            outside.append(f"{v.name} is articulated ({len(v.bodies)} bodies; the staged collisions are of cars)")
        if b.mass > CAR_MASS_LIMIT:
            outside.append(f"{n} weighs {b.mass:.0f} kg (the staged collisions' cars weigh at most "
                           f"{CAR_MASS_LIMIT:.0f} kg)")
    faces = []
    for n in (b1, b2):
        faces.append(face_of(bodies[n][1], sc.states[n], imp.point))
    order = {"front": 0, "rear": 1, "side": 2}
    a, b = sorted(faces, key=order.get)
    rule = f"the impact point lies nearest {b1}'s {faces[0]} and {b2}'s {faces[1]}"
    if outside:
        return {"class": HEAVY_CLASS, "configuration": f"{a}-to-{b}", "outside": outside,
                "rule": f"an articulated or heavy vehicle in the impact; {rule}", "related": related_classes(scene)}
    return {"class": "car-to-car", "configuration": f"{a}-to-{b}", "outside": outside, "rule": rule}


def related_classes(scene) -> list[tuple[str, str]]:
    """The suite's classes nearest a scene of :data:`HEAVY_CLASS`, each with why: ``(class, why)``."""
    sc = scene.scenario
    out = [("car-to-car", "the staged collisions between cars: the nearest evidence for the impact")]
    if any(len(v.bodies) > 1 for v in sc.vehicles):
        out.append(("articulated kinematics", "an articulated vehicle's run-out"))
    if sc.approaches:
        out.append(("approach and braking", "the approach and its braking"))
    return out


def load_error_table() -> dict | None:
    """The packaged error table, or None if this installation has none."""
    res = files("crashsim").joinpath(TABLE)
    if not res.is_file():
        return None
    return json.loads(res.read_text(encoding="utf-8"))


def _summarise(rows: list[dict]) -> list[dict]:
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["group"], r["metric"]), []).append(r)
    out = []
    for (group, metric), rs in groups.items():
        errs = [abs(r["error"]) for r in rs if r["error"] is not None and math.isfinite(r["error"])]
        out.append({"group": group, "metric": metric, "kind": rs[0]["kind"], "display": rs[0]["display"], "n": len(rs),
                    "cases": sorted({r["case"] for r in rs}), "mean_abs_error": sum(errs) / len(errs) if errs else None,
                    "max_abs_error": max(errs) if errs else None, "within": sum(bool(r["within"]) for r in rs)})
    return out


def _texts(rows: list[dict], system: str | None) -> list[dict]:
    return [{**r, "mean_text": summary_value_text(r, r["mean_abs_error"], system),
             "max_text": summary_value_text(r, r["max_abs_error"], system)} for r in rows]


def class_errors(scene, table: dict | None = None, system: str | None = None) -> dict:
    """What the case report quotes: the scene's class (:func:`scene_class`) and the suite's errors for it.

    Returns a dict with ``class``, ``configuration``, ``rule``, ``outside`` (list of reasons), ``version``
    and ``date`` of the table, ``class_rows`` (per group, over the class's cases) and ``configuration_rows``
    (over the cases of the same configuration, empty if the suite has none), each row with its errors as
    text in ``system`` (default: the unit system of each result's sources); ``available`` is False when the
    installation has no table.
    """
    c = scene_class(scene)
    table = load_error_table() if table is None else table
    if table is None:
        return {**c, "available": False, "class_rows": [], "configuration_rows": []}
    rows = [r for r in table["quantities"] if r["class"] == c["class"]]
    conf = [r for r in rows if c["configuration"] and r.get("configuration") == c["configuration"]]
    related = []  # (title, rows) of the classes nearest a class the suite has no case of
    for cls, why in c.get("related", []):
        these = [r for r in table["quantities"] if r["class"] == cls]
        same = [r for r in these if c["configuration"] and r.get("configuration") == c["configuration"]]
        if same:
            related.append((f"Related class {cls}, {c['configuration']} ({why})", _texts(_summarise(same), system)))
        if these:
            related.append((f"Related class {cls}, all its cases ({why})", _texts(_summarise(these), system)))
    return {**c, "available": True, "version": table.get("version"), "date": table.get("date"),
            "command": table.get("command"), "class_rows": _texts(_summarise(rows), system),
            "configuration_rows": _texts(_summarise(conf), system), "related_rows": related,
            "cases": sorted({r["case"] for r in rows})}

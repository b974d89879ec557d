"""Builder of the impact (:class:`~crashsim.impact.ImpactProblem`) of ``[impact]`` and ``[barrier]``, and the
frames a point of the file may be given in (:func:`frame_xform`, :func:`frame_point`).
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from ..errors import ScenarioError
from ..geometry import rotate
from ..impact import (CrushSurface, ExternalImpulse, ImpactProblem, TangentialLaw, VelocityConstraint,
                      tyre_friction_impulse)
from ..vehicles import Body, BodyState, Vehicle
from .problems import error_at


def frame_xform(frame: str, states: dict, key: str, file: str | None):
    """(origin, angle) of a frame named in the file."""
    if frame == "world":
        return np.zeros(2), 0.0
    if frame not in states:
        names = ["world", *states]
        near = difflib.get_close_matches(frame, names, n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise error_at(f"unknown frame {frame!r}{hint} Allowed: {', '.join(repr(n) for n in names)}", key, file)
    s = states[frame]
    return np.asarray(s.position), s.heading


def frame_point(p, frame, states, key, file):
    """The point ``p`` [m] given in ``frame`` (``"world"`` or a body's name, see :func:`frame_xform`) in world
    coordinates; the scenario loader and :mod:`crashsim.reconstruct.patch` build impact points with it."""
    origin, ang = frame_xform(frame, states, key, file)
    return tuple(origin + rotate(np.asarray(p), ang))


def barrier_extent(barrier: dict | None) -> tuple[float, float] | None:
    """:attr:`Scenario.barrier_extent` of a validated ``[barrier]`` table."""
    if barrier is None:
        return None
    return tuple(barrier["extent"]) if barrier["extent"] is not None else (-math.inf, math.inf)


def impact_problem(d: dict, vehicles: list, states: dict, file: str | None) -> ImpactProblem:
    """The [impact] (and [barrier]) of a validated file as an ImpactProblem; a barrier joins
    ``vehicles`` and ``states``."""
    imp = d["impact"]
    if d["barrier"] is not None:
        bname = d["barrier"]["name"]
        if bname in states:
            raise error_at(f"barrier name {bname!r} is also a body name", "barrier.name", file)
    elif len(vehicles) < 2:
        raise error_at(f"an impact needs two vehicles, or one and a [barrier]; got {len(vehicles)}: "
                       f"{[v.name for v in vehicles]}", "vehicles", file)
    for k in ("body1", "body2"):
        allowed = list(states) + ([d["barrier"]["name"]] if d["barrier"] is not None else [])
        if imp[k] not in allowed:
            near = difflib.get_close_matches(imp[k], allowed, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise error_at(f"unknown body {imp[k]!r}{hint} Bodies: {', '.join(map(repr, allowed))}", f"impact.{k}", file)
    same = [v for v in vehicles if {imp["body1"], imp["body2"]} <= {b.name for b in v.bodies}]
    if same:
        raise error_at(f"impact.body1 = {imp['body1']!r} and impact.body2 = {imp['body2']!r} are both bodies of vehicle "
                       f"{same[0].name!r}; the impact is between two vehicles (or one and the [barrier]): give a body of "
                       "another vehicle as impact.body2 (a vehicle's own bodies meet at their articulation stop, set by "
                       "articulation_limit)", "impact.body2", file)
    if d["barrier"] is not None and d["barrier"]["name"] not in (imp["body1"], imp["body2"]):
        raise error_at(f"the barrier {d['barrier']['name']!r} is neither impact.body1 ({imp['body1']!r}) nor impact.body2 "
                       f"({imp['body2']!r}); [barrier] is the rigid body of the impact (fixed obstacles met in the "
                       "run-out go in [[obstacles]])", "barrier.name", file)
    point = frame_point(imp["point"], imp["point_frame"], states, "impact.point_frame", file)
    _, nang = frame_xform(imp["normal_frame"], states, "impact.normal_frame", file)
    if d["barrier"] is not None:
        bname = d["barrier"]["name"]
        vehicles.append(Vehicle(bname, (Body(bname, math.inf, math.inf),)))
        states[bname] = BodyState(point, 0.0, (0.0, 0.0), 0.0)
    law = imp["tangential"]
    ep = imp["moment_restitution"]
    value = {"ratio": imp["mu"], "fraction": imp["mu_fraction"], "friction": imp["friction"]}.get(law, 0.0)
    surface = CrushSurface(point, imp["normal"] + nang, imp["restitution"], TangentialLaw(law, value), ep,
                           1 if imp["tangent"] == "ccw" else -1)
    constraints = []
    for i, c in enumerate(imp["constraints"]):
        key = f"impact.constraints[{i}]"
        origin, ang = frame_xform(c["frame"], states, f"{key}.frame", file)
        constraints.append(VelocityConstraint(c["body"], tuple(origin + rotate(np.asarray(c["point"]), ang)),
                                              c["direction"] + ang, c["value"], c["name"] or f"constraint {i + 1}"))
    external = []
    for i, x in enumerate(imp["external_impulses"]):
        key = f"impact.external_impulses[{i}]"
        origin, ang = frame_xform(x["frame"], states, f"{key}.frame", file)
        helper = [x[k] is not None for k in ("friction", "load", "duration", "direction")]
        if x["impulse"] is not None:
            if any(helper):
                raise error_at("give either impulse, or friction + load + duration + direction, not both", key, file)
            vec = rotate(np.asarray(x["impulse"]), ang)
        elif all(helper):
            vec = tyre_friction_impulse(x["friction"], x["load"], x["duration"], x["direction"] + ang)
        else:
            missing = [k for k, h in zip(("friction", "load", "duration", "direction"), helper) if not h]
            raise error_at(f"needs impulse, or all of friction, load, duration, direction (missing: {', '.join(missing)})",
                           key, file)
        external.append(ExternalImpulse(x["body"], tuple(origin + rotate(np.asarray(x["point"]), ang)), tuple(vec),
                                        x["name"] or f"impulse {i + 1}"))
    # the impact involves the two vehicles of body1 and body2; any others wait for the run-out
    owner = {b.name: v for v in vehicles for b in v.bodies}
    involved = []
    for k in ("body1", "body2"):
        v = owner[imp[k]]
        if v not in involved:
            involved.append(v)
    for i, c in enumerate(imp["constraints"]):
        if c["body"] in owner and owner[c["body"]] not in involved:
            raise error_at(f"body {c['body']!r} is not in the impact (vehicles {[v.name for v in involved]})",
                           f"impact.constraints[{i}].body", file)
    for i, x in enumerate(imp["external_impulses"]):
        if x["body"] in owner and owner[x["body"]] not in involved:
            raise error_at(f"body {x['body']!r} is not in the impact (vehicles {[v.name for v in involved]})",
                           f"impact.external_impulses[{i}].body", file)
    try:
        problem = ImpactProblem(tuple(involved), {b.name: states[b.name] for v in involved for b in v.bodies},
                                imp["body1"], imp["body2"], surface, tuple(constraints), tuple(external))
    except ScenarioError as exc:
        raise ScenarioError(str(exc), field=exc.field, file=file) from None
    return problem

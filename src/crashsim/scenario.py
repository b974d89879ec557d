"""Scenario files: one TOML file per scene, strictly validated, units written with each value.

The schema below is the single definition of the file format: :func:`load_scenario`
validates against it and ``crashsim schema`` prints it (:func:`schema_document`). Values
are converted to SI once, here; everything downstream is SI.

Frames: the world frame of the scene (X, Y, angles counter-clockwise from +X). A point or
direction may instead be given in a body's axes (origin at its CG, x forward, y left) by
naming the body in the matching ``*_frame`` / ``frame`` key.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ScenarioError
from .geometry import rotate
from .impact import (CrushSurface, ExternalImpulse, ImpactProblem, TangentialLaw, VelocityConstraint,
                     tyre_friction_impulse)
from .schema import ArrayOf, Field, Section, Table, document, load_toml, validate
from .units import Kind
from .vehicles import Body, BodyState, Hitch, Vehicle, chain_states

__all__ = ["SCHEMA", "Scenario", "load_scenario", "scenario_from_dict", "schema_document"]

# ----------------------------------------------------------------------------------------
# The schema (validates and documents)

BODY = Section("body", [
    Field("name", "str", description="Body name, unique in the scene (results are keyed by it)",
          example='tractor'),
    Field("mass", Kind.MASS, minimum=0, exclusive_minimum=True, example="9500 kg",
          description="Mass (a weight such as \"20945 lbf\" is accepted and divided by g0)"),
    Field("yaw_inertia", Kind.YAW_INERTIA, minimum=0, exclusive_minimum=True, example="21000 kg m^2",
          description="Yaw moment of inertia about the CG"),
    Field("yaw_rate", Kind.ANGULAR_VELOCITY, default="0 rad/s",
          description="Yaw rate just before the impact (counter-clockwise positive)"),
    Field("length", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="6.0 m",
          description="Overall length of the outline (plots)"),
    Field("width", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="2.5 m",
          description="Overall width of the outline (plots)"),
    Field("outline_center", Kind.LENGTH, n=2, default=["0 m", "0 m"],
          description="Centre of the outline rectangle in body axes"),
    Field("rear_hitch", Kind.LENGTH, n=2, required=False, example='["-3.1 m", "0 m"]',
          description="Pin towing the next body (fifth wheel, ball), in this body's axes; "
                      "required on every body but the last"),
    Field("front_hitch", Kind.LENGTH, n=2, required=False, example='["3.991 m", "0 m"]',
          description="Pin by which this body is towed (kingpin, drawbar eye), in this body's axes; "
                      "required on every body but the first"),
    Field("articulation", Kind.ANGLE, default="0 deg",
          description="Articulation at the front hitch: heading of the towing body minus this body's"),
    Field("articulation_limit", Kind.ANGLE, required=False, minimum=0, maximum=math.pi,
          exclusive_minimum=True, example="80 deg",
          description="Largest articulation before the bodies meet (jack-knife stop)"),
], description="One rigid body of the vehicle, front to rear")

VEHICLE = Section("vehicle", [
    Field("description", "str", default="", description="Free text for the report"),
    Field("position", Kind.LENGTH, n=2, example='["0 m", "0 m"]',
          description="CG of the first (front) body at impact, world frame"),
    Field("heading", Kind.ANGLE, example="90 deg", description="Heading of the first body at impact"),
    Field("speed", Kind.SPEED, minimum=0, example="30 mph", description="CG speed of the first body at impact"),
    Field("course", Kind.ANGLE, required=False, example="95 deg",
          description="Direction of the first body's CG velocity (default: its heading, no side slip)"),
], subsections=[ArrayOf("bodies", BODY, min_items=1, description="The bodies, front to rear, joined by hitches")],
   description="A vehicle: a chain of bodies (car; car + trailer; tractor + semitrailer; doubles)")

BARRIER = Section("barrier", [
    Field("name", "str", example='barrier', description="Name of the barrier body (use it as impact.body2)"),
    Field("description", "str", default="", description="Free text for the report"),
], required=False, description="A rigid barrier: a body of infinite mass at rest (exact, not a large number)")

CONSTRAINT = Section("constraint", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", description="Body whose velocity is constrained", example='tractor'),
    Field("point", Kind.LENGTH, n=2, example='["2 m", "0 m"]', description="Point of the body held"),
    Field("frame", "str", default="world", description="Frame of point and direction: \"world\" or a body name"),
    Field("direction", Kind.ANGLE, example="90 deg", description="Direction along which the velocity is held"),
    Field("value", Kind.SPEED, default="0 m/s", description="Velocity held along the direction after impact"),
], description="A velocity constraint with its own unknown external impulse (paper Eq. 7)")

EXTERNAL = Section("external_impulse", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", description="Body the impulse acts on", example='trailer'),
    Field("point", Kind.LENGTH, n=2, example='["-2.477 m", "0 m"]', description="Point of application"),
    Field("frame", "str", default="world",
          description="Frame of point, impulse and direction: \"world\" or a body name"),
    Field("impulse", Kind.IMPULSE, n=2, required=False, example='["0 N s", "-3260 N s"]',
          description="The impulse vector; or give friction, load, duration and direction instead"),
    Field("friction", "float", required=False, minimum=0, example="0.6",
          description="Tyre-road friction f for the helper impulse f x load x duration"),
    Field("load", Kind.FORCE, required=False, minimum=0, example="36222 N",
          description="Normal load on the sliding tyres (helper)"),
    Field("duration", Kind.TIME, required=False, minimum=0, example="0.15 s",
          description="Impact duration (helper)"),
    Field("direction", Kind.ANGLE, required=False, example="-90 deg",
          description="Direction of the helper impulse (opposite the tyres' sliding)"),
], description="A known external impulse, e.g. tyre friction over the impact")

IMPACT = Section("impact", [
    Field("body1", "str", example='trailer', description="Body of one vehicle in contact; the impulse P acts on it"),
    Field("body2", "str", example='car', description="Body of the other vehicle (or the barrier) in contact"),
    Field("point", Kind.LENGTH, n=2, example='["-2.517 m", "-1.157 m"]',
          description="Contact point: where the resultant crush impulse acts"),
    Field("point_frame", "str", default="world", description="Frame of point: \"world\" or a body name"),
    Field("normal", Kind.ANGLE, example="90 deg",
          description="Direction of the crush-surface normal n, pointing from body2 into body1"),
    Field("normal_frame", "str", default="world", description="Frame of normal: \"world\" or a body name"),
    Field("tangent", choices=("ccw", "cw"), default="ccw",
          description="Tangent t = n turned 90 deg counter-clockwise (ccw) or clockwise (cw); "
                      "mu and the tangential impulse are signed along t"),
    Field("restitution", "float", minimum=0, maximum=1, example="0.05",
          description="Coefficient of restitution e (Eq. 5)"),
    Field("moment_restitution", "float", default=-1.0, minimum=-1, maximum=1,
          description="Moment coefficient e' (Eq. 6): -1 for no moment impulse, else 0 <= e' <= 1"),
    Field("tangential", choices=("no_slide", "ratio", "friction"), example='friction',
          description="Tangential law: no sliding at separation (mu = mu_max); a given impulse ratio mu; "
                      "or friction f (stick if |mu_max| <= f, else slide with |mu| = f)"),
    Field("mu", "float", required=False, example="0.3", description="Impulse ratio P_t/P_n, for tangential = \"ratio\""),
    Field("friction", "float", required=False, minimum=0, example="0.6",
          description="Crush-surface friction f, for tangential = \"friction\""),
], subsections=[
    ArrayOf("constraints", CONSTRAINT, required=False, description="Velocity constraints"),
    ArrayOf("external_impulses", EXTERNAL, required=False, description="Known external impulses"),
], description="The impact: crush surface, coefficients, constraints, external impulses")

META = Section("scenario", [
    Field("title", "str", example='Car into trailer wheels', description="Title of the scene"),
    Field("source", "str", default="", description="Where the inputs come from (report, paper, measurement)"),
    Field("notes", "str", default="", description="Free text"),
    Field("units", choices=("SI", "US"), default="SI", description="Units of the readable report"),
], description="What the scene is")

SCHEMA = Section("scenario file", subsections=[
    META,
    Table("vehicles", VEHICLE, min_entries=1, placeholder="<vehicle>", description="The vehicles, by name"),
    BARRIER,
    IMPACT,
], description="A crashsim scenario file (TOML)")


def schema_document(fmt: str = "text") -> str:
    """The scenario-file reference, generated from the validating schema."""
    return document(SCHEMA, fmt)


# ----------------------------------------------------------------------------------------
# From validated data to typed SI objects


@dataclass(frozen=True)
class Scenario:
    """A loaded scenario: typed SI inputs, ready to run.

    Attributes
    ----------
    path : str or None
    title, source, units : str
    vehicles : tuple of Vehicle
        Including a barrier vehicle if the file has ``[barrier]``.
    states : dict of BodyState
        Every body's state at impact.
    impact : ImpactProblem
    data : dict
        The validated file contents (SI floats), for traceability.
    """

    path: str | None
    title: str
    source: str
    units: str
    vehicles: tuple[Vehicle, ...]
    states: dict
    impact: ImpactProblem
    data: dict = field(repr=False)


def _err(msg: str, key: str, file: str | None) -> ScenarioError:
    return ScenarioError(msg, field=key, file=file)


def _build_vehicle(name: str, v: dict, file: str | None) -> tuple[Vehicle, dict[str, BodyState]]:
    bodies, hitches = [], []
    raw = v["bodies"]
    for i, b in enumerate(raw):
        key = f"vehicles.{name}.bodies[{i}]"
        if i < len(raw) - 1 and b["rear_hitch"] is None:
            raise _err(f"body {b['name']!r} tows {raw[i + 1]['name']!r} but has no rear_hitch; "
                       "give the pin position in its axes, e.g. [\"-3.1 m\", \"0 m\"]", f"{key}.rear_hitch", file)
        if i > 0 and b["front_hitch"] is None:
            raise _err(f"body {b['name']!r} is towed by {raw[i - 1]['name']!r} but has no front_hitch; "
                       "give the pin position in its axes, e.g. [\"3.991 m\", \"0 m\"]", f"{key}.front_hitch", file)
        if i == len(raw) - 1 and b["rear_hitch"] is not None:
            raise _err(f"body {b['name']!r} is the last body but has a rear_hitch {b['rear_hitch']}; "
                       "add the towed body after it or remove the key", f"{key}.rear_hitch", file)
        if i == 0 and b["front_hitch"] is not None:
            raise _err(f"body {b['name']!r} is the first body but has a front_hitch {b['front_hitch']}",
                       f"{key}.front_hitch", file)
        if i == 0 and b["articulation"] != 0.0:
            raise _err("the first body has no front hitch to articulate about", f"{key}.articulation", file)
        try:
            bodies.append(Body(b["name"], b["mass"], b["yaw_inertia"], b["length"], b["width"],
                               tuple(b["outline_center"])))
        except ScenarioError as exc:
            raise _err(str(exc), key, file) from None
        if i > 0:
            hitches.append(Hitch(tuple(raw[i - 1]["rear_hitch"]), tuple(b["front_hitch"]), b["articulation_limit"]))
    try:
        veh = Vehicle(name, tuple(bodies), tuple(hitches))
    except ScenarioError as exc:
        raise _err(str(exc), f"vehicles.{name}", file) from None
    course = v["heading"] if v["course"] is None else v["course"]
    vel = v["speed"] * np.array([math.cos(course), math.sin(course)])
    states = chain_states(veh, v["position"], v["heading"], vel,
                          [b["yaw_rate"] for b in raw], [b["articulation"] for b in raw[1:]])
    return veh, states


def _frame_xform(frame: str, states: dict, key: str, file: str | None):
    """(origin, angle) of a frame named in the file."""
    if frame == "world":
        return np.zeros(2), 0.0
    if frame not in states:
        import difflib

        names = ["world", *states]
        near = difflib.get_close_matches(frame, names, n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise _err(f"unknown frame {frame!r}{hint} Allowed: {', '.join(repr(n) for n in names)}", key, file)
    s = states[frame]
    return np.asarray(s.position), s.heading


def _point(p, frame, states, key, file):
    origin, ang = _frame_xform(frame, states, key, file)
    return tuple(origin + rotate(np.asarray(p), ang))


def scenario_from_dict(data: dict[str, Any], *, file: str | None = None) -> Scenario:
    """Validate a parsed scenario (as from TOML) and build the typed SI objects."""
    d = validate(data, SCHEMA, file=file)
    vehicles, states = [], {}
    for name, v in d["vehicles"].items():
        veh, st = _build_vehicle(name, v, file)
        for bn in st:
            if bn in states:
                raise _err(f"body name {bn!r} is used twice; body names must be unique in the scene",
                           f"vehicles.{name}.bodies", file)
        vehicles.append(veh)
        states.update(st)
    imp = d["impact"]
    if d["barrier"] is not None:
        bname = d["barrier"]["name"]
        if bname in states:
            raise _err(f"barrier name {bname!r} is also a body name", "barrier.name", file)
        if len(vehicles) != 1:
            raise _err(f"a scene with a barrier has exactly one vehicle, got {len(vehicles)}: "
                       f"{[v.name for v in vehicles]}", "vehicles", file)
    elif len(vehicles) != 2:
        raise _err(f"an impact needs two vehicles, or one and a [barrier]; got {len(vehicles)}: "
                   f"{[v.name for v in vehicles]}", "vehicles", file)
    for k in ("body1", "body2"):
        allowed = list(states) + ([d["barrier"]["name"]] if d["barrier"] is not None else [])
        if imp[k] not in allowed:
            import difflib

            near = difflib.get_close_matches(imp[k], allowed, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise _err(f"unknown body {imp[k]!r}{hint} Bodies: {', '.join(map(repr, allowed))}", f"impact.{k}", file)
    point = _point(imp["point"], imp["point_frame"], states, "impact.point_frame", file)
    _, nang = _frame_xform(imp["normal_frame"], states, "impact.normal_frame", file)
    if d["barrier"] is not None:
        bname = d["barrier"]["name"]
        vehicles.append(Vehicle(bname, (Body(bname, math.inf, math.inf),)))
        states[bname] = BodyState(point, 0.0, (0.0, 0.0), 0.0)
    law = imp["tangential"]
    if law == "ratio" and imp["mu"] is None:
        raise _err('tangential = "ratio" needs mu (the impulse ratio P_t/P_n), e.g. mu = 0.3', "impact.mu", file)
    if law == "friction" and imp["friction"] is None:
        raise _err('tangential = "friction" needs friction (f >= 0), e.g. friction = 0.6', "impact.friction", file)
    for k, needed in (("mu", "ratio"), ("friction", "friction")):
        if imp[k] is not None and law != needed:
            raise _err(f"{k} = {imp[k]} is given but tangential = {law!r} does not use it "
                       f'(it belongs to tangential = "{needed}")', f"impact.{k}", file)
    ep = imp["moment_restitution"]
    if not (ep == -1.0 or 0.0 <= ep <= 1.0):
        raise _err(f"{ep} is out of range; allowed -1 (no moment impulse) or [0, 1]", "impact.moment_restitution", file)
    value = imp["mu"] if law == "ratio" else (imp["friction"] if law == "friction" else 0.0)
    surface = CrushSurface(point, imp["normal"] + nang, imp["restitution"], TangentialLaw(law, value), ep,
                           1 if imp["tangent"] == "ccw" else -1)
    constraints = []
    for i, c in enumerate(imp["constraints"]):
        key = f"impact.constraints[{i}]"
        origin, ang = _frame_xform(c["frame"], states, f"{key}.frame", file)
        constraints.append(VelocityConstraint(c["body"], tuple(origin + rotate(np.asarray(c["point"]), ang)),
                                              c["direction"] + ang, c["value"], c["name"] or f"constraint {i + 1}"))
    external = []
    for i, x in enumerate(imp["external_impulses"]):
        key = f"impact.external_impulses[{i}]"
        origin, ang = _frame_xform(x["frame"], states, f"{key}.frame", file)
        helper = [x[k] is not None for k in ("friction", "load", "duration", "direction")]
        if x["impulse"] is not None:
            if any(helper):
                raise _err("give either impulse, or friction + load + duration + direction, not both", key, file)
            vec = rotate(np.asarray(x["impulse"]), ang)
        elif all(helper):
            vec = tyre_friction_impulse(x["friction"], x["load"], x["duration"], x["direction"] + ang)
        else:
            missing = [k for k, h in zip(("friction", "load", "duration", "direction"), helper) if not h]
            raise _err(f"needs impulse, or all of friction, load, duration, direction (missing: {', '.join(missing)})",
                       key, file)
        external.append(ExternalImpulse(x["body"], tuple(origin + rotate(np.asarray(x["point"]), ang)), tuple(vec),
                                        x["name"] or f"impulse {i + 1}"))
    try:
        problem = ImpactProblem(tuple(vehicles), states, imp["body1"], imp["body2"], surface,
                                tuple(constraints), tuple(external))
    except ScenarioError as exc:
        raise ScenarioError(str(exc), field=exc.field, file=file) from None
    meta = d["scenario"]
    return Scenario(file, meta["title"], meta["source"], meta["units"], tuple(vehicles), states, problem, d)


def load_scenario(path: str | Path) -> Scenario:
    """Load and validate a scenario file (TOML); all values converted to SI.

    Raises
    ------
    ScenarioError
        Naming the file, the key, the value and what is allowed.
    """
    path = str(path)
    return scenario_from_dict(load_toml(path), file=path)

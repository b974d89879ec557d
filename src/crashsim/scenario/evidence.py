"""Builders of the scene evidence (``[evidence]``): rest positions, marks, impact points, delta-v, recorders,
rollover statements and crush profiles.
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from ..errors import ScenarioError
from ..evidence.checks import (CORNERS, DeltaVEvidence, Evidence, ImpactPointEvidence, MarkEvidence, RecorderEvidence,
                               RestEvidence, RolloverEvidence, named_body_points, register_points)
from ..evidence.crush import CrushEvidence, crush_groups
from ..motion.wheels import enumerate_wheels, select_wheels
from ..units import Kind, format_value, parse
from ..vehicles import Body
from .presets import presets
from .problems import Problems, error_at


def _rest_registration(r: dict, body: Body, key: str, file: str | None):
    """The CG and heading of a rest item given by measured points of ``body`` (a rigid least-squares fit)."""
    if r["position"] is not None:
        raise error_at("give either position (the measured CG) or points (measured points of the body), not both",
                       f"{key}.points", file)
    if r["heading"] is not None:
        raise error_at(f"heading = {math.degrees(r['heading']):.6g} deg is given with points: the points give the heading; "
                       "remove heading (heading_tolerance then applies to the derived heading)", f"{key}.heading", file)
    pts = r["points"]
    if len(pts) < 2:
        raise error_at(f"{len(pts)} measured point: at least two are needed to fix the CG and the heading",
                       f"{key}.points", file)
    named = named_body_points(body)
    labels, body_pts, measured = [], [], []
    for j, p in enumerate(pts):
        pkey = f"{key}.points[{j}]"
        if (p["at"] is None) == (p["body_point"] is None):
            raise error_at("give at (a named point of the body, e.g. \"front_left\") or body_point (in body axes), "
                           f"{'not both' if p['at'] is not None else 'one of them'}", pkey, file)
        if p["at"] is not None:
            at = p["at"]
            if at not in named:
                if at in CORNERS:
                    raise error_at(f"at = {at!r} is a corner of the outline, but body {body.name!r} has no length and "
                                   "width; give them in its [[vehicles.<v>.bodies]] entry, or give body_point",
                                   f"{pkey}.at", file)
                near = difflib.get_close_matches(at, list(named), n=2)
                hint = f"; did you mean {' or '.join(map(repr, near))}?" if near else ""
                raise error_at(f"at = {at!r} is not a named point of body {body.name!r}{hint} Named points: "
                               f"{', '.join(named) or 'none (no length, width or axles)'}", f"{pkey}.at", file)
            labels.append(at)
            body_pts.append(named[at])
        else:
            bp = tuple(p["body_point"])
            labels.append("(" + ", ".join(format_value(v, Kind.LENGTH) for v in bp) + ")")
            body_pts.append(bp)
        measured.append(tuple(p["position"]))
    try:
        return register_points(body_pts, measured, labels)
    except ValueError as exc:
        shown = "; ".join(f"{lab} at (" + ", ".join(format_value(v, Kind.LENGTH) for v in m) + ")"
                          for lab, m in zip(labels, measured))
        raise error_at(f"{exc}: {shown}", f"{key}.points", file) from None


def build_evidence(e: dict | None, states: dict, file: str | None, vehicles=(), d_approach: dict | None = None
                   ) -> Evidence:
    """The evidence items; ``d_approach``: the validated approach section of each vehicle (or None).
    Every item is checked: the errors of all of them come together."""
    if e is None:
        return Evidence()
    problems = Problems(file)

    def body(name, key):
        if name not in states:
            near = difflib.get_close_matches(name, list(states), n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise error_at(f"unknown body {name!r}{hint} Bodies: {', '.join(map(repr, states))}", key, file)
        return name

    rest = []
    by_name = {b.name: b for v in vehicles for b in v.bodies}
    for i, r in enumerate(e["rest"]):
        with problems.each():
            rest.append(_rest_item(r, i, body, by_name, file))
    marks = []
    for i, m in enumerate(e["marks"]):
        with problems.each():
            marks.append(_mark_item(m, i, body, vehicles, d_approach, file))
    poi = None
    if e["impact_point"] is not None:
        poi = ImpactPointEvidence(tuple(e["impact_point"]["position"]), e["impact_point"]["tolerance"],
                                  sigma=e["impact_point"].get("sigma"))
    dv = []
    for i, x in enumerate(e["delta_v"]):
        with problems.each():
            side = x.get("lateral_positive")
            if x["component"] == "lateral" and side is None:
                raise error_at('a lateral delta-v needs the side it is positive to: lateral_positive = "left" '
                               "(crashsim's body y axis, ISO 8855) or \"right\" (SAE J670 vehicle axes, y to the "
                               "right, as many recorder reports; check the report's sign statement)",
                               f"evidence.delta_v[{i}].lateral_positive", file)
            if x["component"] != "lateral" and side is not None:
                raise error_at(f"lateral_positive = {side!r} applies only to component = \"lateral\" (this item's "
                               f"component is {x['component']!r})", f"evidence.delta_v[{i}].lateral_positive", file)
            dv.append(DeltaVEvidence(body(x["body"], f"evidence.delta_v[{i}].body"), x["value"], x["tolerance"],
                                     x["component"], x["name"], x["impacts"], sigma=x.get("sigma"),
                                     lateral_positive=side or "left"))
    recorder = []
    for i, x in enumerate(e["recorder"]):
        with problems.each():
            recorder.append(_recorder_item(x, i, body, vehicles, d_approach, file))
    rollover = []
    units = {v.name for v in vehicles if not v.is_barrier} | {b.name for v in vehicles if not v.is_barrier
                                                               for b in v.bodies}
    for i, x in enumerate(e.get("rollover") or []):
        with problems.each():
            if x["unit"] not in units:
                near = difflib.get_close_matches(x["unit"], sorted(units), n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise error_at(f"unknown vehicle or body {x['unit']!r}{hint} Vehicles and bodies: "
                               f"{', '.join(map(repr, sorted(units)))}", f"evidence.rollover[{i}].unit", file)
            rollover.append(RolloverEvidence(x["unit"], bool(x["rolled"]), x["name"]))
    problems.raise_any()
    return Evidence(tuple(rest), tuple(marks), poi, tuple(dv), tuple(recorder), rollover=tuple(rollover))


def _rest_item(r: dict, i: int, body, by_name: dict, file: str | None) -> RestEvidence:
    """One ``[[evidence.rest]]`` item."""
    key = f"evidence.rest[{i}]"
    name = body(r["body"], f"{key}.body")
    if r["points"]:
        reg = _rest_registration(r, by_name[name], key, file)
        heading = reg.heading if r["heading_tolerance"] is not None else None
        return RestEvidence(name, reg.position, r["tolerance"], heading, r["heading_tolerance"], r["name"], reg,
                            sigma=r.get("sigma"), heading_sigma=r.get("heading_sigma"))
    if r["position"] is None:
        raise error_at(f"rest evidence of {name!r} needs position (the measured CG) or points (two or more measured "
                       "points of the body, e.g. its corners)", f"{key}.position", file)
    if (r["heading"] is None) != (r["heading_tolerance"] is None):
        raise error_at("heading and heading_tolerance go together", f"{key}.heading_tolerance", file)
    return RestEvidence(name, tuple(r["position"]), r["tolerance"], r["heading"], r["heading_tolerance"], r["name"],
                        sigma=r.get("sigma"), heading_sigma=r.get("heading_sigma"))


def _mark_item(m: dict, i: int, body, vehicles, d_approach, file: str | None) -> MarkEvidence:
    """One ``[[evidence.marks]]`` item."""
    sel = m["wheel"]
    if sel != "*":
        key = f"evidence.marks[{i}].wheel"
        vehicle = next(v for v in vehicles if body(sel.split("/")[0], key) in {b.name for b in v.bodies})
        try:  # the wheels the selector names must exist (as for wheel settings)
            select_wheels(vehicle, enumerate_wheels(vehicle), sel, key)
        except ScenarioError as exc:
            raise error_at(str(exc).removeprefix(f"{key}: "), key, file) from None
    if m["phase"] == "approach":
        owner = (sel.split("/")[0] if sel != "*" else None)
        with_approach = [v for v in vehicles if (d_approach or {}).get(v.name)]
        if not with_approach or (owner is not None and not any(owner in {b.name for b in v.bodies}
                                                               for v in with_approach)):
            raise error_at("a pre-impact mark (phase = \"approach\") needs an approach of the vehicle that left it "
                           f"({owner or 'any vehicle'}): add [vehicles.<name>.approach]",
                           f"evidence.marks[{i}].phase", file)
    return MarkEvidence(np.asarray(m["points"], dtype=float), m["tolerance"], sel, m["sliding_only"], m["name"],
                        m["phase"], sigma=m.get("sigma"))


def _recorder_item(x: dict, i: int, body, vehicles, d_approach, file: str | None) -> RecorderEvidence:
    """One ``[[evidence.recorder]]`` item."""
    key = f"evidence.recorder[{i}]"
    name = body(x["body"], f"{key}.body")
    veh = next(v for v in vehicles if name in {b.name for b in v.bodies})
    if not (d_approach or {}).get(veh.name):
        raise error_at(f"recorder samples are compared with the approach of vehicle {veh.name!r}, which has none: add "
                       f"[vehicles.{veh.name}.approach]", f"{key}.body", file)
    smp = x["samples"]
    first: dict = {}
    for j, p in enumerate(smp):
        if p["time"] in first:
            raise error_at(f"samples[{first[p['time']]}] and samples[{j}] have the same time ({p['time']:g} s); a "
                           "recorder takes one sample at a time", f"{key}.samples[{j}].time", file)
        first[p["time"]] = j
    if len(smp) == 1 and smp[0]["time"] + x["time_offset"] > 0:
        raise error_at(f"time = {smp[0]['time']:g} s is after the impact (time + time_offset = "
                       f"{smp[0]['time'] + x['time_offset']:g} s); allowed <= {-x['time_offset']:g} s: pre-crash data "
                       "end at the impact", f"{key}.samples[0].time", file)
    if not any(p["time"] + x["time_offset"] <= 0 for p in smp):
        raise error_at(f"no sample is before the impact: every time + time_offset ({x['time_offset']:g} s) is > 0; "
                       "allowed at least one sample at or before it", f"{key}.samples", file)
    return RecorderEvidence(name, tuple(p["time"] for p in smp), tuple(p["speed"] for p in smp),
                            tuple(bool(p["brake"]) for p in smp), x["tolerance"], x["time_offset"], x["name"],
                            sigma=x.get("sigma"))


def build_crush(items: list, d: dict, vehicles, file: str | None) -> tuple:
    """The ``[[evidence.crush]]`` items as CrushEvidence (A and B from the body's preset where omitted); the
    errors of every item together."""
    by_name = {b.name: b for v in vehicles for b in v.bodies}
    preset_of = {b["name"]: b.get("preset") for v in d["vehicles"].values() for b in v["bodies"]}
    out = []
    problems = Problems(file)  # every item checked: their errors come together
    for i, c in enumerate(items):
        with problems.each():
            key = f"evidence.crush[{i}]"
            name = c["body"]
            if name not in by_name or by_name[name].is_fixed:
                near = difflib.get_close_matches(name, [n for n, b in by_name.items() if not b.is_fixed], n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise error_at(f"unknown body {name!r}{hint} (a movable body of a vehicle)", f"{key}.body", file)
            profile_keys = ("A", "B", "width", "profile")
            given = [k for k in profile_keys if c[k] is not None]
            A, B, source = c["A"], c["B"], "given in the scenario"
            if c["ees"] is not None:
                if given:
                    raise error_at(f"give either ees or a crush profile (A, B, width, profile), not both (ees with "
                                   f"{', '.join(given)})", f"{key}.ees", file)
            else:
                if A is None and B is None and c["profile"] is not None:
                    preset = preset_of.get(name)
                    stiff = (presets().get(preset, {}).get("crush", {}).get(c["face"]) if preset else None)
                    if stiff is None:
                        raise error_at(f"needs A and B (CRASH3 stiffness of the {c['face']} face of {name!r}, e.g. "
                                       "A = \"50000 N/m\", B = \"600000 N/m^2\"); "
                                       + (f"preset {preset!r} has no crush stiffness for this face" if preset
                                          else "the body has no preset with crush stiffness"), f"{key}.A", file)
                    where = f"vehicles library preset {preset!r} crush.{c['face']}"
                    A = parse(stiff["A"], Kind.FORCE_PER_LENGTH, field=f"{where}.A")
                    B = parse(stiff["B"], Kind.FORCE_PER_AREA, field=f"{where}.B")
                    source = f"preset {preset!r}: {stiff['source']}"
                for k, v in (("A", A), ("B", B), ("width", c["width"]), ("profile", c["profile"])):
                    if v is None:
                        raise error_at(f"missing {k}: a crush item needs A, B, width and profile (CRASH3), or ees; "
                                       f"given: {', '.join(given) or 'none of them'}", f"{key}.{k}", file)
            if (c["tolerance"] is None) == (c["relative_tolerance"] is None):
                raise error_at("give tolerance (an energy, e.g. \"10 kJ\") or relative_tolerance (e.g. \"25 %\"), "
                               f"{'not both' if c['tolerance'] is not None else 'one of them'}", f"{key}.tolerance", file)
            out.append(CrushEvidence(name, c["face"], by_name[name].mass, A, B, c["width"],
                                     None if c["profile"] is None else tuple(c["profile"]), c["offset"], c["ees"],
                                     c["tolerance"], c["relative_tolerance"], c["impacts"], c["compare"],
                                     c["correction"] == "pdof", source, c["name"], sigma=c.get("sigma")))
    problems.raise_any()
    for which, idx in crush_groups(out):
        modes = {out[i].compare for i in idx}
        if len(modes) > 1:
            j = next(i for i in idx if out[i].compare != out[idx[0]].compare)
            raise error_at(f"compare = {out[j].compare!r}, but evidence.crush[{idx[0]}] (same impacts = {which!r}) has "
                           f"{out[idx[0]].compare!r}: the items of a group are compared together",
                           f"evidence.crush[{j}].compare", file)
    bodies_seen: dict[str, str] = {}
    for i, it in enumerate(out):
        if bodies_seen.setdefault(it.body, it.impacts) != it.impacts:
            raise error_at(f"impacts = {it.impacts!r}, but another crush item of {it.body!r} has "
                           f"{bodies_seen[it.body]!r}: a body's damage belongs to one group", f"evidence.crush[{i}].impacts",
                           file)
    return tuple(out)

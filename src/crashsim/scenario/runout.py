"""Builder of the run-out (:class:`~crashsim.scenario.types.RunoutSpec`): road, zones, solver options, level,
rollover check, wheel settings, obstacles and the contact model.
"""

from __future__ import annotations

import difflib
from dataclasses import replace as _replace

from ..errors import ScenarioError
from ..impact import ImpactProblem
from ..motion import ContactModel, FrictionZone, Obstacle, Road, RunoutOptions
from ..motion.contact import CONTACT_KEYS, WEIGHT_DEPTH
from ..motion.loads import STANDARD_GRAVITY
from ..vehicles import MAX_ROLLOVER_THRESHOLD
from .checks import outline_problem
from .problems import Problems, as_in_file, error_at, rewrap
from .types import RunoutSpec
from .vehicles import build_wheels


def _rollover_check(r: dict, level: str, vehicles, file: str | None) -> bool:
    """Whether the wheel-lift and rollover check is asked for (runout.rollover, or a body's
    rollover_threshold), and that it can be done: level load_transfer, and the CG height of every
    body whose threshold is the default."""
    asked = [("runout.rollover", "rollover = true")] if r["rollover"] else []
    for veh in vehicles:
        for i, b in enumerate(veh.bodies):
            if b.rollover_threshold is not None:
                asked.append((f"vehicles.{veh.name}.bodies[{i}].rollover_threshold",
                              f"rollover_threshold = {b.rollover_threshold:g}"))
    if not asked:
        return False
    if level != "load_transfer":
        key, text = asked[0]
        raise error_at(f"{text} asks for the wheel-lift and rollover check, which reads the load transfer: it needs "
                       f"level \"load_transfer\", but level = {level!r}", key, file)
    for veh in vehicles:
        for i, b in enumerate(veh.bodies):
            if not b.is_fixed and b.rollover_threshold is None and b.cg_height is None:
                raise error_at(f"the default rollover threshold 0.75 t / (2 h) of body {b.name!r} needs its CG height h; "
                               "give cg_height (m, > 0), or rollover_threshold in g, allowed (0, "
                               f"{MAX_ROLLOVER_THRESHOLD:g}]", f"vehicles.{veh.name}.bodies[{i}].cg_height", file)
    return True


def build_runout(r: dict, vehicles, raw_vehicles: dict, file: str | None, raw: dict | None = None) -> RunoutSpec:
    raw = raw or {}
    level = r["level"]
    if r["load_transfer"] and (level not in ("articulated", "load_transfer") or
                               (level == "articulated" and "level" in raw)):  # a level written is never overruled
        raise error_at(f"load_transfer = true asks for level \"load_transfer\", but level = {level!r}; give one of them",
                       "runout.load_transfer", file)
    if r["load_transfer"]:
        level = "load_transfer"
    if r["accuracy"] is None and r["accuracy_heading"] is not None:
        raise error_at("accuracy_heading needs accuracy (the rest-position target) too", "runout.accuracy_heading", file)
    if r["accuracy"] is not None:
        if level in ("impact", "energy"):
            raise error_at(f"accuracy = {r['accuracy']} m needs an integrated run-out; level {level!r} has no solver "
                           "settings to choose", "runout.accuracy", file)
        fixed = [k for k in ("rtol", "atol", "eps", "v_stop") if k in raw]
        if fixed:
            raise error_at(f"accuracy chooses {', '.join(fixed)} itself; remove them or remove accuracy",
                           f"runout.{fixed[0]}", file)
    for i, z in enumerate(r["zones"]):
        why = outline_problem(z["polygon"])
        if why:
            raw_zones = raw.get("zones") if isinstance(raw.get("zones"), list) else []
            shown = raw_zones[i].get("polygon") if i < len(raw_zones) and isinstance(raw_zones[i], dict) else None
            value = f"polygon = {as_in_file(shown)} " if shown is not None and len(shown) <= 8 else ""
            name = f"zone {z['name']!r}" if z["name"] else f"zone {i + 1}"
            raise error_at(f"{value}is not the outline of {name}: {why}", f"runout.zones[{i}].polygon", file)
    try:
        zones = tuple(FrictionZone(tuple(z["polygon"]), z["friction"], z["name"] or f"zone {i + 1}",
                                   z["grade"], z["cross_slope"])
                      for i, z in enumerate(r["zones"]))
        road = Road(r["road_friction"], zones, r["grade"], r["cross_slope"])
    except ScenarioError as exc:
        raise rewrap(exc, "runout.zones", file) from None
    rollover = _rollover_check(r, level, vehicles, file)
    try:
        extra = {"engine": r["engine"]} if "engine" in RunoutOptions.__dataclass_fields__ else {}
        if r["engine"] != "scipy" and not extra:
            raise ScenarioError("the compiled engine is not available in this installation", field="engine")
        options = RunoutOptions(method=r["method"], rtol=r["rtol"], atol=r["atol"], eps=r["eps"], v_stop=r["v_stop"],
                                max_step=r["max_step"], t_max=r["t_max"], sample_dt=r["sample_dt"],
                                lateral_model=r["lateral_model"], load_transfer=level == "load_transfer",
                                rollover=rollover, max_impacts=r["max_impacts"], max_wall_time=r["max_wall_time"],
                                **extra)
    except ScenarioError as exc:
        raise rewrap(exc, "runout", file) from None
    if options.load_transfer:
        for veh in vehicles:
            for i, b in enumerate(veh.bodies):
                if b.cg_height is None and not b.is_fixed:
                    raise error_at(f"level \"load_transfer\" needs the CG height of body {b.name!r}",
                                   f"vehicles.{veh.name}.bodies[{i}].cg_height", file)
    if level == "impact":
        return RunoutSpec(road, options, {}, level)
    wheels, problems = {}, Problems(file)
    for veh in vehicles:  # every vehicle's wheel errors at once
        if not veh.is_barrier:
            with problems.each():
                wheels[veh.name] = build_wheels(veh, raw_vehicles[veh.name], file)
    problems.raise_any()
    return RunoutSpec(road, options, wheels, level, r["accuracy"], r["accuracy_heading"])


def _contact_model(base: ContactModel, entry: dict, key: str, file: str | None) -> ContactModel:
    changes = {k: entry[k] for k in CONTACT_KEYS if entry.get(k) is not None}
    try:
        return base.updated(**changes)
    except ScenarioError as exc:
        raise rewrap(exc, key, file) from None


def with_contact(spec: "RunoutSpec", d: dict, vehicles, problem: ImpactProblem, file: str | None) -> "RunoutSpec":
    """The run-out's contact model, pair overrides and obstacles (the barrier of the impact first)."""
    c = d["contacts"] or {}
    contact = _contact_model(ContactModel(), c, "contacts", file)
    bodies = {b.name for v in vehicles for b in v.bodies if not b.is_fixed}
    vnames = {v.name for v in vehicles if not v.is_barrier}
    obstacles = []
    barrier = d["barrier"]
    if barrier is not None:
        surf = problem.surface
        into_vehicle = surf.normal if problem.body2 == barrier["name"] else -surf.normal
        tangent = surf.tangent
        extent = None if barrier["extent"] is None else tuple(barrier["extent"])
        if extent is not None and problem.body2 != barrier["name"]:
            extent = (-extent[1], -extent[0]) if surf.tangent_sign < 0 else extent
        obstacles.append(Obstacle.barrier(barrier["name"], surf.point, into_vehicle, tangent, extent))
    taken = bodies | vnames | {o.name for o in obstacles}
    for i, o in enumerate(d["obstacles"]):
        key = f"obstacles[{i}]"
        if o["name"] in taken:
            raise error_at(f"name {o['name']!r} is already a body, vehicle or obstacle name; names must be unique",
                           f"{key}.name", file)
        taken.add(o["name"])
        try:
            obstacles.append(Obstacle(o["name"], tuple(o["points"]), o["thickness"], o["closed"]))
        except ScenarioError as exc:
            msg = str(exc)
            if exc.field and msg.startswith(f"{exc.field}: "):
                msg = msg[len(exc.field) + 2:]
            raise error_at(msg, f"{key}.points", file) from None
    names = bodies | vnames | {o.name for o in obstacles}
    owner = {b.name: v.name for v in vehicles for b in v.bodies}
    pairs = {}
    for i, p in enumerate(c.get("pairs", []) or []):
        key = f"contacts.pairs[{i}]"
        for which in ("first", "second"):
            if p[which] not in names:
                near = difflib.get_close_matches(p[which], sorted(names), n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise error_at(f"{p[which]!r} names no body, vehicle or obstacle of the scene{hint} Names: "
                               f"{', '.join(map(repr, sorted(names)))}", f"{key}.{which}", file)
        a, b = p["first"], p["second"]
        va, vb = owner.get(a, a if a in vnames else None), owner.get(b, b if b in vnames else None)
        if a == b or (va is not None and va == vb):
            raise error_at(f"{a!r} and {b!r} are not a pair that can meet: they are the same vehicle or body "
                           "(contact is between bodies of different vehicles, or a body and an obstacle)",
                           f"{key}.second", file)
        if va is None and vb is None:
            raise error_at(f"{a!r} and {b!r} are both obstacles: obstacles do not meet each other", f"{key}.second", file)
        pairs[(a, b)] = _contact_model(contact, p, key, file)
    _check_stiffness(contact, pairs, c, vehicles, file)
    return _replace(spec, contact=contact, pair_contact=pairs, obstacles=tuple(obstacles))


def _check_stiffness(contact: ContactModel, pairs: dict, raw: dict, vehicles, file: str | None) -> None:
    """A contact stiffness must hold the heaviest vehicle's weight within WEIGHT_DEPTH."""
    movable = [v for v in vehicles if not v.is_barrier]
    if not movable:
        return
    heavy = max(movable, key=lambda v: sum(b.mass for b in v.bodies))
    weight = sum(b.mass for b in heavy.bodies) * STANDARD_GRAVITY
    least = weight / WEIGHT_DEPTH
    entries = [("contacts.stiffness", contact, raw.get("stiffness") is not None)]
    entries += [(f"contacts.pairs[{i}].stiffness", model, p.get("stiffness") is not None)
                for i, (p, model) in enumerate(zip(raw.get("pairs", []) or [], pairs.values()))]
    for key, model, given in entries:
        if given and model.enabled and model.stiffness < least:
            raise error_at(f"{model.stiffness:g} N/m lets the weight of vehicle {heavy.name!r} ({weight:.4g} N) press "
                           f"{weight / model.stiffness:.3g} m deep; allowed >= {least:.4g} N/m (that weight held within "
                           f"{WEIGHT_DEPTH:g} m)", key, file)

"""Builders of the vehicles of a validated file: bodies, axles and hitches (:func:`build_vehicle`), the states at
impact (:func:`vehicle_states`), the wheel settings and the air brakes.
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from ..errors import ScenarioError
from ..motion import ScheduledChange, WheelSetting, WheelSettings
from ..motion.brakes import AirBrakes, BrakeUnit, unit_type_default
from ..vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states
from .problems import error_at, rewrap


_WHEEL_KEYS = ("state", "brake", "steer", "cornering_coefficient", "cornering_stiffness", "rolling_resistance",
               "mu_factor", "self_steer_limit")


def _given(d: dict) -> dict:
    return {k: d[k] for k in _WHEEL_KEYS if d.get(k) is not None}


def build_wheels(vehicle: Vehicle, v: dict, file: str | None, prefix: str | None = None) -> WheelSettings:
    """The wheel settings of ``v`` (a vehicle's, or its approach's: ``prefix`` names where they are)."""
    name = vehicle.name
    prefix = prefix or f"vehicles.{name}"
    tyres = v["tyres"]
    if tyres is None:
        raise error_at("the run-out needs the wheel state and tyre data of every wheel: add a ["
                       f"{prefix}.tyres] section with at least state = \"locked\" (or rolling/braked with "
                       "cornering_coefficient and rolling_resistance)", f"{prefix}.tyres", file)
    for i, b in enumerate(v["bodies"]):
        if not b["axles"]:
            raise error_at(f"body {b['name']!r} has no axles; the run-out needs them ([[vehicles.{name}.bodies.axles]] "
                           "with x and track)", f"vehicles.{name}.bodies[{i}].axles", file)
    try:
        default = WheelSetting(**_given(tyres))
    except ScenarioError as exc:
        raise rewrap(exc, f"{prefix}.tyres", file) from None
    if not default.is_sliding:
        if default.cornering_stiffness is None and default.cornering_coefficient is None:
            raise error_at(f'state = "{default.state}" needs cornering_coefficient (cornering stiffness per unit load, '
                           "1/rad: about 8.6 for car tyres, 6 for truck tyres) or cornering_stiffness (N/rad per tyre)",
                           f"{prefix}.tyres.cornering_coefficient", file)
        if default.rolling_resistance is None:
            raise error_at(f'state = "{default.state}" needs rolling_resistance (in [0, 0.5]: about 0.012 for car tyres, '
                           "0.008 for truck tyres)", f"{prefix}.tyres.rolling_resistance", file)
    overrides = {}
    for i, w in enumerate(v["wheels"]):
        merged = {**_given(tyres), **_given(w)}
        if "state" in _given(w) and w["state"] != "braked" and w.get("brake") is None:
            merged.pop("brake", None)
        for pair in (("cornering_coefficient", "cornering_stiffness"), ("cornering_stiffness", "cornering_coefficient")):
            if w.get(pair[0]) is not None:
                merged.pop(pair[1], None)
        try:
            overrides[w["select"]] = WheelSetting(**merged)
        except ScenarioError as exc:
            raise rewrap(exc, f"{prefix}.wheels[{i}]", file) from None
    schedule = []
    for k, c in enumerate(v["wheel_changes"]):  # each change alone first: an error names its key as written
        key = f"{prefix}.wheel_changes[{k}]"
        try:
            change = ScheduledChange(c["at"], c["select"], _given(c))
            WheelSettings(default, overrides, [change]).resolve(vehicle)
        except ScenarioError as exc:
            msg = str(exc)
            if exc.field and msg.startswith(f"{exc.field}: "):
                msg = msg[len(exc.field) + 2:]
            word, _, rest = msg.partition(": ")
            if rest and word in c:  # "steer: must lie in ...": that key of the change
                raise error_at(rest, f"{key}.{word}", file) from None
            raise error_at(f"select = {c['select']!r} at {c['at']:g} s: {msg}", f"{key}.select", file) from None
        schedule.append(change)
    brakes = _build_brakes(vehicle, v.get("brakes"), file, f"{prefix}.brakes")
    try:
        ws = WheelSettings(default, overrides, schedule)
        ws.resolve(vehicle)
    except ScenarioError as exc:
        raise rewrap(exc, prefix, file) from None
    if brakes is not None:
        try:
            ws = WheelSettings(default, overrides, schedule, brakes)
            ws.resolve(vehicle)
        except ScenarioError as exc:
            if (exc.field or "").startswith("units[") and "is 'braked'" in str(exc) and \
                    (v.get("tyres") or {}).get("state") == "braked":  # the key to change: the tyres' state
                msg = str(exc).removeprefix(f"{exc.field}: ")
                raise error_at(f'state = "braked" on a body with air brakes: {msg}', f"{prefix}.tyres.state",
                               file) from None
            raise rewrap(exc, f"{prefix}.brakes", file) from None
    return ws


def _build_brakes(vehicle: Vehicle, b: dict | None, file: str | None, key: str) -> AirBrakes | None:
    """The air brakes of ``vehicle`` from its (validated) brakes table, or None."""
    if b is None:
        return None
    names = [body.name for body in vehicle.bodies]
    if b["release"] is not None and b["release"] < b["apply"]:
        raise error_at(f"release = {b['release']:g} s is before apply = {b['apply']:g} s; allowed: release >= apply",
                       f"{key}.release", file)
    if (b["tractor_abs"] or b["trailer_abs"]) and b["abs_efficiency"] is None:
        raise error_at("ABS is on (tractor_abs or trailer_abs) but abs_efficiency is missing; give it in (0, 1), e.g. "
                       "0.85 (docs/heavy-vehicles.md)", f"{key}.abs_efficiency", file)
    units = {}
    for i, u in enumerate(b["units"]):
        where = f"{key}.units[{i}]"
        if u["body"] not in names:
            near = difflib.get_close_matches(u["body"], names, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise error_at(f"body = {u['body']!r} is not a body of vehicle {vehicle.name!r}{hint} Allowed: {names}",
                           f"{where}.body", file)
        if u["body"] in units:
            raise error_at(f"body = {u['body']!r} has two entries; give one per body", f"{where}.body", file)
        index = names.index(u["body"])
        n_axles = len(vehicle.bodies[index].axles)
        if len(u["capacity"]) not in (1, n_axles):
            raise error_at(f"gives {len(u['capacity'])} values for body {u['body']!r} with {n_axles} axles; allowed: one "
                           "per axle, or one for every axle", f"{where}.capacity", file)
        try:
            units[u["body"]] = BrakeUnit(
                tuple(u["capacity"]), u["type"] or unit_type_default(len(names), index, u["body"]),
                u["delay"], u["rise"], u["release_delay"], u["fall"], u["out_of_adjustment"],
                bool(b["tractor_abs"] if index == 0 else b["trailer_abs"]))
        except ScenarioError as exc:
            raise rewrap(exc, where, file) from None
    try:
        return AirBrakes(units, b["apply"], b["release"], b["abs_efficiency"] or 0.0)
    except ScenarioError as exc:
        raise rewrap(exc, key, file) from None


def build_vehicle(name: str, v: dict, file: str | None) -> tuple[Vehicle, dict[str, BodyState]]:
    bodies, hitches = [], []
    raw = v["bodies"]
    for i, b in enumerate(raw):
        key = f"vehicles.{name}.bodies[{i}]"
        if i < len(raw) - 1 and b["rear_hitch"] is None:
            raise error_at(f"body {b['name']!r} tows {raw[i + 1]['name']!r} but has no rear_hitch; "
                           "give the pin position in its axes, e.g. [\"-3.1 m\", \"0 m\"]", f"{key}.rear_hitch", file)
        if i > 0 and b["front_hitch"] is None:
            raise error_at(f"body {b['name']!r} is towed by {raw[i - 1]['name']!r} but has no front_hitch; "
                           "give the pin position in its axes, e.g. [\"3.991 m\", \"0 m\"]", f"{key}.front_hitch", file)
        if i == len(raw) - 1 and b["rear_hitch"] is not None:
            raise error_at(f"body {b['name']!r} is the last body but has a rear_hitch {b['rear_hitch']}; "
                           "add the towed body after it or remove the key", f"{key}.rear_hitch", file)
        if i == 0 and b["front_hitch"] is not None:
            raise error_at(f"body {b['name']!r} is the first body but has a front_hitch {b['front_hitch']}",
                           f"{key}.front_hitch", file)
        if i == 0 and b["roll_coupled"]:
            raise error_at(f"body {b['name']!r} is the first body: it has no front hitch to carry roll moment (roll_coupled "
                           "belongs on the towed body, e.g. the semitrailer)", f"{key}.roll_coupled", file)
        if i == 0 and b["articulation"] != 0.0:
            raise error_at("the first body has no front hitch to articulate about", f"{key}.articulation", file)
        if b["yaw_locked"] and i < 2:
            where = ("the first body has no front hitch" if i == 0 else
                     f"the body ahead, {raw[0]['name']!r}, is the first body (a tractor or truck), not a trailer")
            raise error_at(f"yaw_locked = true: a C-dolly is yaw-locked to the trailer ahead, but {where}; allowed on "
                           f"bodies[2] or later (a body towed by a towed body)", f"{key}.yaw_locked", file)
        if b["yaw_locked"] and b["articulation"] != 0.0:
            raise error_at(f"articulation = {math.degrees(b['articulation']):.6g} deg on a yaw-locked body (C-dolly, "
                           "yaw_locked = true): it cannot articulate; allowed 0 deg", f"{key}.articulation", file)
        if b["yaw_locked"] and b["yaw_rate"] != raw[i - 1]["yaw_rate"]:
            raise error_at(f"yaw_rate = {b['yaw_rate']:.6g} rad/s on a yaw-locked body (C-dolly, yaw_locked = true) differs "
                           f"from that of {raw[i - 1]['name']!r} ({raw[i - 1]['yaw_rate']:.6g} rad/s); allowed: the same",
                           f"{key}.yaw_rate", file)
        lim = None if b["yaw_locked"] else b["articulation_limit"]
        if i > 0 and lim is not None and abs(b["articulation"]) > lim:
            raise error_at(f"articulation = {math.degrees(b['articulation']):.6g} deg exceeds the jack-knife stop of body "
                           f"{b['name']!r}; allowed [-{math.degrees(lim):.6g}, {math.degrees(lim):.6g}] deg "
                           "(articulation_limit)", f"{key}.articulation", file)
        try:
            axles = tuple(Axle(a["x"], a["track"], a["dual"], a["name"]) for a in b["axles"])
            bodies.append(Body(b["name"], b["mass"], b["yaw_inertia"], b["length"], b["width"],
                               tuple(b["outline_center"]), axles, b["cg_height"], b["rollover_threshold"],
                               bool(b["roll_coupled"]), b["contact_height"]))
        except ScenarioError as exc:
            raise error_at(str(exc), key, file) from None
        if i > 0:
            hitches.append(Hitch(tuple(raw[i - 1]["rear_hitch"]), tuple(b["front_hitch"]), lim, b["yaw_locked"]))
    try:
        veh = Vehicle(name, tuple(bodies), tuple(hitches))
    except ScenarioError as exc:
        raise error_at(str(exc), f"vehicles.{name}", file) from None
    return veh, vehicle_states(veh, v)


def vehicle_states(veh: Vehicle, v: dict) -> dict[str, BodyState]:
    """The states at impact of a vehicle's bodies from its validated table ``v`` (position, heading,
    course, speed, the bodies' yaw rates and articulations)."""
    raw = v["bodies"]
    course = v["heading"] if v["course"] is None else v["course"]
    speed = 0.0 if v["speed"] is None else v["speed"]  # None: set by the approach (scenario_from_dict)
    vel = speed * np.array([math.cos(course), math.sin(course)])
    return chain_states(veh, v["position"], v["heading"], vel,
                        [b["yaw_rate"] for b in raw], [b["articulation"] for b in raw[1:]])

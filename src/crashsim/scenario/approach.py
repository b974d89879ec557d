"""Builder of a vehicle's approach (:class:`~crashsim.scenario.types.ApproachInput`): its path or driver, or a
recorder's table, its wheels and road.
"""

from __future__ import annotations

import difflib
import math

import numpy as np

from ..errors import ScenarioError, with_file
from ..motion import Road, RunoutOptions
from ..motion.approach_spec import ApproachSpec, check_path, path_start
from ..motion.driver import DriverSpec, Path as DrivePath, steer_geometry
from ..motion.recorded import RecordedDrive, rising_speed
from ..vehicles import Vehicle
from .problems import as_in_file, error_at
from .types import ApproachInput, RunoutSpec
from .vehicles import build_wheels


def approach_input(veh: Vehicle, v: dict, runout: "RunoutSpec | None", file: str | None,
                   lines=(), path_given: bool = False, raw_recorded: dict | None = None) -> ApproachInput:
    """What the approach of ``veh`` (``v["approach"]``) needs, checked (its simulation comes later)."""
    a = v["approach"]
    key = f"vehicles.{veh.name}.approach"
    if a["speed"] is not None and v["speed"] is not None:
        raise error_at(f"both the speed at impact (vehicles.{veh.name}.speed) and the speed at the start of braking "
                       f"({key}.speed) are given: give one, the approach gives the other", f"{key}.speed", file)
    if v["course"] is not None:
        raise error_at("with an approach the direction of the velocity at impact follows from the approach; remove "
                       "course", f"vehicles.{veh.name}.course", file)
    wheels = build_wheels(veh, {"tyres": a["tyres"], "wheels": a["wheels"], "wheel_changes": a["wheel_changes"],
                                "bodies": v["bodies"], "brakes": a["brakes"]}, file, prefix=key)
    if a["road_friction"] is not None:
        road = (Road(a["road_friction"], runout.road.zones, runout.road.grade, runout.road.cross_slope)
                if runout is not None else Road(a["road_friction"]))
    elif runout is not None:
        road = runout.road
    else:
        raise error_at("the approach needs the road friction: give road_friction here or a [runout] section",
                       f"{key}.road_friction", file)
    options = runout.options if runout is not None else RunoutOptions()
    n = len(veh.bodies)
    for name, want in (("articulation", n - 1), ("yaw_rates", n)):
        if a[name] is not None and len(a[name]) != want:
            raise error_at(f"vehicle {veh.name!r} has {n} bodies: give {want} value(s), one per "
                           f"{'hitch' if name == 'articulation' else 'body'}, front to rear; got {len(a[name])}",
                           f"{key}.{name}", file)
    if a["articulation"] is not None:
        for i, (hitch, ang) in enumerate(zip(veh.hitches, a["articulation"])):
            if hitch.articulation_limit is not None and abs(ang) > hitch.articulation_limit:
                raise error_at(f"{math.degrees(ang):.2f} deg at hitch {i + 1} lies beyond its articulation stop of "
                               f"{math.degrees(hitch.articulation_limit):.2f} deg", f"{key}.articulation", file)
    if a["solve_articulation"] and n < 2:
        raise error_at(f"vehicle {veh.name!r} has no hitch: there is no articulation to solve", f"{key}.solve_articulation",
                       file)
    if a["through_impact"] and v.get("brakes") is not None:
        raise error_at("with through_impact the approach's air brakes carry on into the run-out: give the brakes once, in "
                       f"{key}.brakes, and remove vehicles.{veh.name}.brakes", f"vehicles.{veh.name}.brakes", file)
    # the schema fills in the section's defaults when it is absent: a path is given by its table in the file
    given = a["path"] is not None and (path_given or a["path"]["points"] is not None or a["path"]["line"] is not None)
    driver = _approach_driver(veh, v, a, key, lines, file) if given else None
    recorded = None
    speed = a["speed"]
    if raw_recorded is not None:
        recorded = _approach_recorded(veh, v, a, key, raw_recorded, file)
        if recorded.speed is not None:
            speed = recorded.speed[0]
    try:
        spec = ApproachSpec(wheels, speed, a["distance"], a["time"],
                            None if a["start_position"] is None else tuple(a["start_position"]), a["start_heading"],
                            a["reaction_time"], a["tolerance"], key,
                            None if a["articulation"] is None else tuple(a["articulation"]),
                            None if a["yaw_rates"] is None else tuple(a["yaw_rates"]), a["solve_articulation"], driver,
                            recorded)
    except ScenarioError as exc:
        raise with_file(exc, file) from None
    return ApproachInput(spec, road, options, v["speed"], a["through_impact"],
                         runout.wheels.get(veh.name) if runout is not None else None)


def _approach_driver(veh: Vehicle, v: dict, a: dict, key: str, lines, file: str | None) -> DriverSpec:
    """The driver of ``[vehicles.<name>.approach.path]``, its path checked against the vehicle and the
    impact position (a path the vehicle cannot follow, or that does not reach the impact, is refused)."""
    p = a["path"]
    pkey = f"{key}.path"
    if (p["points"] is None) == (p["line"] is None):
        raise error_at("give the path's points or the name of a [[map.lines]] line (one of the two)", f"{pkey}.points", file)
    if p["line"] is not None:
        names = [ln["name"] for ln in lines]
        if p["line"] not in names:
            near = difflib.get_close_matches(p["line"], names, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise error_at(f"no [[map.lines]] line is named {p['line']!r}{hint} Named lines: "
                           f"{', '.join(repr(x) for x in names if x) or 'none'}", f"{pkey}.line", file)
        pts = np.asarray(lines[names.index(p["line"])]["points"], dtype=float)
        pts = pts[::-1] if p["reverse"] else pts
    else:
        pts = np.asarray(p["points"], dtype=float)
    try:
        driver = DriverSpec(DrivePath(pts, key=pkey), p["preview_time"], p["min_preview"], p["max_steer"],
                            p["max_steer_rate"], p["update"], pkey)
        check_path(veh, driver)
        if a["distance"] is not None:
            path_start(veh, driver, np.asarray(v["position"], dtype=float), a["distance"], a["tolerance"])
    except ScenarioError as exc:
        raise with_file(exc, file) from None
    return driver


def recorded_speeds(a: dict) -> bool:
    """The approach's recorded table (if any) gives speeds: the speed at its start."""
    r = a.get("recorded")
    return bool(r and r.get("samples") and all(x.get("speed") is not None for x in r["samples"]))


def _approach_recorded(veh: Vehicle, v: dict, a: dict, key: str, raw: dict, file: str | None) -> RecordedDrive:
    """The recorder's table of ``[vehicles.<name>.approach.recorded]``: each column in every sample or in
    none, steering with its ratio, no speed rise the model has no engine for, and no other way of placing
    the approach's start given beside it."""
    r = a["recorded"]
    rkey = f"{key}.recorded"
    samples = r["samples"]
    raw_samples = raw.get("samples") if isinstance(raw.get("samples"), list) else []
    for other in ("distance", "time", "start_position"):
        if a[other] is not None:
            raise error_at(f"the recorded table places the approach's start at its first sample ({samples[0]['time']:g} s "
                           f"before the impact): remove {other}", f"{key}.{other}", file)
    if a["path"] is not None and (a["path"]["points"] is not None or a["path"]["line"] is not None):
        raise error_at("give a path or a recorded table to drive the approach, not both", f"{key}.path", file)
    if a["reaction_time"]:
        raise error_at("the recorded table starts the simulated approach at its first sample; a reaction time before it "
                       "has no place: remove reaction_time", f"{key}.reaction_time", file)
    columns = {}
    for col in ("speed", "steering"):
        have = [x[col] is not None for x in samples]
        if any(have) and not all(have):
            j = have.index(False)
            raise error_at(f"sample {j} has no {col}, others do: give {col} in every sample or in none",
                           f"{rkey}.samples[{j}].{col}", file)
        columns[col] = [x[col] for x in samples] if all(have) else None
    times = [x["time"] for x in samples]
    for j in range(1, len(times)):
        if times[j] <= times[j - 1]:
            raise error_at(f"{as_in_file(raw_samples[j].get('time')) if j < len(raw_samples) else times[j]} follows "
                           f"{as_in_file(raw_samples[j - 1].get('time')) if j < len(raw_samples) else times[j - 1]}: sample "
                           "times must increase", f"{rkey}.samples[{j}].time", file)
    if times[0] >= 0.0:
        raise error_at("the first sample must lie before the impact (a negative time)", f"{rkey}.samples[0].time", file)
    speed = columns["speed"]
    if speed is not None:
        if v["speed"] is not None:
            raise error_at("the recorded speeds give the speed at the start; the speed at impact follows from the approach: "
                           f"remove vehicles.{veh.name}.speed", f"vehicles.{veh.name}.speed", file)
        if a["speed"] is not None:
            raise error_at("the recorded speeds give the speed at the start: remove approach.speed", f"{key}.speed", file)
        rise = rising_speed(times, speed)
        if rise is not None:
            i, j = rise
            written = [as_in_file(raw_samples[k].get("speed")) if k < len(raw_samples) else f"{speed[k]:g} m/s"
                       for k in (i, j)]
            raise error_at(f"the recorded speed rises from {written[0]} (sample {i}) to {written[1]}: the approach has no "
                           "drive force (an engine), it can hold a speed but not gain one; start the table where the rise "
                           "ends, or give no speeds (the steering alone then drives, the speed given as for any approach); "
                           "a rise of up to 1 km/h, the recording's resolution, is accepted",
                           f"{rkey}.samples[{j}].speed", file)
    steer = None
    if columns["steering"] is not None:
        if r["steering_ratio"] is None:
            raise error_at("the steering samples need the overall steering ratio (steering-wheel angle over the road wheels' "
                           "steer angle, e.g. 16)", f"{rkey}.steering_ratio", file)
        sign = 1.0 if r["steering_positive"] == "left" else -1.0
        steer = tuple(sign * x / r["steering_ratio"] for x in columns["steering"])
    elif r["steering_ratio"] is not None:
        raise error_at("no sample has steering: remove steering_ratio, or give steering in every sample",
                       f"{rkey}.steering_ratio", file)
    try:
        drive = RecordedDrive(tuple(times), None if speed is None else tuple(speed), steer, r["update"],
                              r["speed_time"], rkey)
        if steer is not None:
            steer_geometry(veh, rkey)
    except ScenarioError as exc:
        raise with_file(exc, file) from None
    return drive

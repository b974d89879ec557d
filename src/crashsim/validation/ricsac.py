"""Staged car-to-car collisions (RICSAC, Calspan 1978): scene from the published data, comparison, bands.

One case is one RICSAC test (``validation/ricsac-NN/``): ``measured.toml`` holds the published
vehicle data, crush profiles, impact velocities and every measured result with its source;
``scene.toml`` is the crashsim scene built from the vehicle data, the crush profiles and the suite's
rules (``validation/rules.toml``) by :func:`scene_text` (a test checks the file is exactly that).

Frames. Vossou2018's velocities are in a frame where vehicle 1 travels in -x; the suite's frame is
that frame turned by 180 deg: vehicle 1's CG at the origin at impact, heading 0 (travelling +x), y to
its left, angles counter-clockwise. Day2004's rest positions are in each test's earth-fixed frame,
whose origin is not tabulated: :func:`day_frame` recovers it from Day2004's own range errors (their
ft and % give each vehicle's path length from impact to rest) under two stated assumptions.

Bands (``validation/README.md``, "Bands"), pooled over the suite's RICSAC tests (same instruments,
same reductions), computed from the data files by :func:`pooled_bands`:

* delta-v: the largest half-spread of the three published reductions of the accelerometer data,
  relative to their mean (the record's own scatter);
* separation velocity components: the largest difference between a corrected and the uncorrected
  delta-v (the correction for the accelerometers' positions these velocities did not get);
* separation yaw rate: no published scatter; the largest error of the impulse-momentum model that
  Vossou2018 fitted to each test (anchor);
* direction of travel: the largest half-difference between the two published measurements (the
  trajectory diagrams and the direction of the separation velocity);
* energy loss: the largest half-difference between the two reductions (Brach1987's loss and the one
  Vossou2018's velocities and Neades2011's masses give), in points of the initial energy;
* rest position and heading (tests 3 and 6): no published scatter; the larger of SIMON's and
  EDSMAC4's errors on the same test and vehicle (Day2004 Table 8; anchors).
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np
from scipy.optimize import minimize_scalar

from ..errors import ScenarioError
from ..scene import run_scene
from ..scenario import load_scenario
from ..units import Kind
from .core import CaseResult, Quantity, angle_difference, quantity, vector
from .crushgeom import Damage, Outline, place

__all__ = ["load_test", "placement", "scene_text", "pooled_bands", "loss_from_velocities", "path_lengths", "day_frame",
           "measured_rotation", "parse_mixed", "run_case"]

FT = 0.3048


def _rot180(v):
    return (-float(v[0]), -float(v[1]))


def load_test(data: dict) -> dict:
    """A RICSAC case's ``measured.toml`` (read by :func:`crashsim.validation.core.read_case`) in SI, the
    suite's frame."""
    f = data["folder"] / "measured.toml"
    out = {"id": data["case"]["id"], "number": data["test"]["number"], "friction": float(data["test"]["surface_friction"]),
           "surface_source": data["test"]["surface_source"]}
    vehicles = []
    for i, v in enumerate(data["vehicle"]):
        key = f"vehicle[{i}]"
        d = v["damage"]
        vehicles.append({
            "name": v["name"], "description": v["description"], "size": v["size"], "source": v["source"],
            "mass": quantity(v["mass"], Kind.MASS, f"{key}.mass", f),
            "yaw_inertia": quantity(v["yaw_inertia"], Kind.YAW_INERTIA, f"{key}.yaw_inertia", f),
            "outline": Outline(quantity(v["cg_to_front"], Kind.LENGTH, f"{key}.cg_to_front", f),
                               quantity(v["cg_to_rear"], Kind.LENGTH, f"{key}.cg_to_rear", f),
                               quantity(v["width"], Kind.LENGTH, f"{key}.width", f)),
            "length": quantity(v["length"], Kind.LENGTH, f"{key}.length", f),
            "damage": Damage(d["face"], quantity(d["width"], Kind.LENGTH, f"{key}.damage.width", f),
                             quantity(d["offset"], Kind.LENGTH, f"{key}.damage.offset", f),
                             vector(d["crush"], Kind.LENGTH, f"{key}.damage.crush", f, n=None)),
            "damage_written": d,
            "A": quantity(d["A"], Kind.FORCE_PER_LENGTH, f"{key}.damage.A", f),
            "B": quantity(d["B"], Kind.FORCE_PER_AREA, f"{key}.damage.B", f),
        })
    out["vehicles"] = vehicles
    imp = data["impact"]
    out["velocity"] = [_rot180(vector(imp[f"velocity{k}"], Kind.SPEED, f"impact.velocity{k}", f)) for k in (1, 2)]
    out["impact_source"] = imp["source"]
    headings = []
    for k, vel in enumerate(out["velocity"]):
        if math.hypot(*vel) > 0:
            headings.append(math.atan2(vel[1], vel[0]))
        else:
            headings.append(quantity(imp[f"heading{k + 1}"], Kind.ANGLE, f"impact.heading{k + 1}", f))
    out["heading"] = headings
    m = data["measured"]
    dv = m["delta_v"]
    out["delta_v"] = {r: vector(dv[r], Kind.SPEED, f"measured.delta_v.{r}", f)
                      for r in ("untransformed", "brach_smith_2002", "mchenry_1997")}
    out["delta_v_source"] = dv["source"]
    s = m["separation"]
    out["separation"] = [(_rot180(vector(s[f"velocity{k}"], Kind.SPEED, f"measured.separation.velocity{k}", f)),
                          quantity(s[f"yaw_rate{k}"], Kind.ANGULAR_VELOCITY, f"measured.separation.yaw_rate{k}", f))
                         for k in (1, 2)]
    out["separation_source"] = s["source"]
    dr = m["direction"]
    out["direction_diagrams"] = vector(dr["values"], Kind.ANGLE, "measured.direction.values", f)
    out["direction_checked"] = bool(dr["convention_checked"])
    out["direction_source"] = dr["source"]
    e = m["energy"]
    out["energy"] = (quantity(e["initial"], Kind.ENERGY, "measured.energy.initial", f),
                     quantity(e["loss"], Kind.ENERGY, "measured.energy.loss", f))
    out["energy_source"] = e["source"]
    if "rest" in m:
        r = m["rest"]
        out["rest"] = {"source": r["source"], "position": [vector(r[f"position{k}"], Kind.LENGTH, f"measured.rest.position{k}", f)
                                                           for k in (1, 2)],
                       "heading": [quantity(r[f"heading{k}"], Kind.ANGLE, f"measured.rest.heading{k}", f) for k in (1, 2)]}
    a = data["anchors"]
    anchors = {"pim_delta_v": vector(a["pim_delta_v"], Kind.SPEED, "anchors.pim_delta_v", f),
               "crash3_delta_v": vector(a["crash3_delta_v"], Kind.SPEED, "anchors.crash3_delta_v", f),
               "pim_direction": vector(a["pim_direction"], Kind.ANGLE, "anchors.pim_direction", f),
               "pim_loss_percent": float(a["pim_loss_percent"]),
               "fitted_separation_error": [parse_mixed(x, f"anchors.fitted_separation_error[{i}]", f)
                                           for i, x in enumerate(a["fitted_separation_error"])],
               "sources": {k: v for k, v in a.items() if k.endswith("_source")}}
    day = []
    for j, t in enumerate(a.get("day2004", [])):
        key = f"anchors.day2004[{j}]"
        day.append({"method": t["method"],
                    "position": [vector(t[f"position{k}"], Kind.LENGTH, f"{key}.position{k}", f) for k in (1, 2)],
                    "heading": [quantity(t[f"heading{k}"], Kind.ANGLE, f"{key}.heading{k}", f) for k in (1, 2)],
                    "delta_v": vector(t["delta_v"], Kind.SPEED, f"{key}.delta_v", f),
                    "range_error": vector(t["range_error"], Kind.LENGTH, f"{key}.range_error", f),
                    "range_error_percent": [float(x) for x in t["range_error_percent"]],
                    "heading_error": vector(t["heading_error"], Kind.ANGLE, f"{key}.heading_error", f)})
    anchors["day2004"] = day
    out["anchors"] = anchors
    return out


def parse_mixed(value: str, where: str, file: Path):
    """A velocity or a yaw rate, by its unit."""
    kind = Kind.ANGULAR_VELOCITY if "rad/s" in value or "deg/s" in value else Kind.SPEED
    return quantity(value, kind, where, file)


# ------------------------------------------------------------------ the scene from the data and the rules
def placement(t: dict):
    """Rules 1-3 of :mod:`crashsim.validation.crushgeom` for a test (suite frame)."""
    v1, v2 = t["vehicles"]
    return place(v1["outline"], v1["damage"], t["heading"][0], v2["outline"], v2["damage"], t["heading"][1])


def _axles(v: dict, rules: dict) -> tuple[float, float, float]:
    """Front and rear axle x [m] and track [m] of a body from its size class (rules.vehicle_data)."""
    vd = rules["vehicle_data"]
    wb = quantity(vd[f"wheelbase_{v['size']}"], Kind.LENGTH, f"vehicle_data.wheelbase_{v['size']}")
    track = quantity(vd[f"track_{v['size']}"], Kind.LENGTH, f"vehicle_data.track_{v['size']}")
    share = float(vd["front_axle_share"])
    return wb * (1.0 - share), -wb * share, track


def _m(x: float) -> str:
    return f'"{x + 0.0:.4f} m"'.replace('"-0.0000 m"', '"0.0000 m"')


def _deg(x: float) -> str:
    return f'"{math.degrees(x):.4f} deg"'.replace('"-0.0000 deg"', '"0.0000 deg"')


def scene_text(t: dict, rules: dict) -> str:
    """The crashsim scene of a RICSAC test (TOML text): the data, the crush placement, the rules."""
    p = placement(t)
    vv = rules["vehicle_to_vehicle"]
    tyres = rules["car_tyres"]
    v1, v2 = t["vehicles"]
    positions = (p.position1, p.position2)
    lines = [f"# RICSAC test {t['number']} as crashsim's scene, written by crashsim.validation.ricsac.scene_text from",
             "# measured.toml (the published vehicle data, crush profiles and impact velocities) and",
             "# ../rules.toml (the suite's rules). Do not edit by hand: tests/validation/test_validation_suite.py",
             "# checks this file is exactly what the data and the rules give. README.md says what was assumed.",
             "#",
             "# Frame: vehicle 1's CG at the origin at impact, heading 0 deg (travelling +x), y to its left.",
             f"# The point of impact and the crush-surface normal follow from the crush profiles",
             f"# (crashsim.validation.crushgeom: damage centroids, maximum engagement, the least-squares",
             f"# line of both crushed surfaces; its stations lie {p.spread * 100:.1f} cm RMS from it).",
             "", "[scenario]", f'title = "RICSAC test {t["number"]}: {v1["description"]} and {v2["description"]}"',
             f'source = "vehicle data and crush: Neades2011 App. D; impact velocities: Vossou2018 Table 1; '
             f'coefficients, axles, tyres: validation/rules.toml"', ""]
    for k, v in enumerate((v1, v2)):
        speed = math.hypot(*t["velocity"][k])
        xf, xr, track = _axles(v, rules)
        o = v["outline"]
        lines += [f"[vehicles.{v['name']}]", f'description = "{v["description"]}"',
                  f"position = [{_m(positions[k][0])}, {_m(positions[k][1])}]", f"heading = {_deg(t['heading'][k])}",
                  f'speed = "{speed:.4f} m/s"', "", f"[[vehicles.{v['name']}.bodies]]", f'name = "{v["name"]}"',
                  f'mass = "{v["mass"]:.6g} kg"', f'yaw_inertia = "{v["yaw_inertia"]:.6g} kg m^2"',
                  f"length = {_m(v['length'])}", f"width = {_m(o.width)}",
                  f"outline_center = [{_m((o.cg_to_front - o.cg_to_rear) / 2)}, \"0 m\"]",
                  f"# axles: {v['size']} class wheelbase and track, {float(rules['vehicle_data']['front_axle_share']):.0%} "
                  "of the weight on the front axle (rules.toml [vehicle_data])",
                  "axles = [", f'  {{ name = "front", x = {_m(xf)}, track = {_m(track)} }},',
                  f'  {{ name = "rear", x = {_m(xr)}, track = {_m(track)} }},', "]", "",
                  f"[vehicles.{v['name']}.tyres]", f'state = "{tyres["state"]}"',
                  f"cornering_coefficient = {tyres['cornering_coefficient']}",
                  f"rolling_resistance = {tyres['rolling_resistance']}", ""]
    lines += ["[impact]", f'body1 = "{v1["name"]}"', f'body2 = "{v2["name"]}"',
              f"point = [{_m(p.point[0])}, {_m(p.point[1])}]", f"normal = {_deg(p.normal)}", 'tangent = "ccw"',
              f"restitution = {vv['restitution']}", f"moment_restitution = {vv['moment_restitution']}",
              f'tangential = "{vv["tangential"]}"', ""]
    if "rest" in t:
        lines += ["[runout]", f'engine = "{rules["runout"]["engine"]}"',
                  f"road_friction = {t['friction']}   # {t['surface_source']}", ""]
    for v in (v1, v2):
        d = v["damage_written"]
        lines += ["[[evidence.crush]]", f'body = "{v["name"]}"', f'face = "{d["face"]}"', f'A = "{d["A"]}"',
                  f'B = "{d["B"]}"', f'width = "{d["width"]}"',
                  "profile = [" + ", ".join(f'"{c}"' for c in d["crush"]) + "]",
                  # CRASH3's delta-v is within 9-25 % at 95 % confidence on staged tests (McHenry): +-50 % in energy
                  'relative_tolerance = "50 %"', ""]
    return "\n".join(lines).rstrip() + "\n"


# ------------------------------------------------------------------ bands from the published data
def _direction_from_velocity(v) -> float:
    """Direction of a velocity from vehicle 1's initial direction of travel, clockwise [rad]."""
    return -math.atan2(v[1], v[0])


def _reference_direction(t: dict, k: int) -> tuple[float, float | None]:
    """The measured direction of travel after the impact (mean of the two measurements where the
    diagrams' convention is established) and the diagrams' value (or None)."""
    from_velocity = _direction_from_velocity(t["separation"][k][0])
    if not t["direction_checked"]:
        return from_velocity, None
    diagrams = t["direction_diagrams"][k]
    return from_velocity + angle_difference(diagrams, from_velocity) / 2, diagrams


def loss_from_velocities(t: dict) -> tuple[float, float]:
    """Initial kinetic energy and its loss from the published velocities and masses [J]."""
    e0 = e1 = 0.0
    for k, v in enumerate(t["vehicles"]):
        vel0 = t["velocity"][k]
        (vel1, w1) = t["separation"][k]
        e0 += 0.5 * v["mass"] * (vel0[0] ** 2 + vel0[1] ** 2)
        e1 += 0.5 * v["mass"] * (vel1[0] ** 2 + vel1[1] ** 2) + 0.5 * v["yaw_inertia"] * w1 ** 2
    return e0, e0 - e1


def pooled_bands(tests: list[dict]) -> dict:
    """Each band of the module docstring, pooled over ``tests`` (the suite's RICSAC tests), with the test
    and vehicle it comes from."""
    def worst(items):
        return max(items, key=lambda x: x[0])

    dv = worst(((max(r) - min(r)) / 2 / (sum(r) / 3), t["number"], k)
               for t in tests for k in (0, 1) for r in [[t["delta_v"][n][k] for n in t["delta_v"]]])
    sep = worst((abs(t["delta_v"][n][k] - t["delta_v"]["untransformed"][k]), t["number"], k)
                for t in tests for k in (0, 1) for n in ("brach_smith_2002", "mchenry_1997"))
    yaw = worst((abs(t["anchors"]["fitted_separation_error"][i]), t["number"], i // 3)
                for t in tests for i in (2, 5))
    direction = worst((abs(angle_difference(t["direction_diagrams"][k],
                                            _direction_from_velocity(t["separation"][k][0]))) / 2, t["number"], k)
                      for t in tests if t["direction_checked"] for k in (0, 1))
    energy = worst((abs(t["energy"][1] / t["energy"][0] - loss_from_velocities(t)[1] / loss_from_velocities(t)[0]) / 2,
                    t["number"], None) for t in tests)
    return {"delta_v": dv, "separation": sep, "yaw_rate": yaw, "direction": direction, "energy": energy}


# ------------------------------------------------------------------ Day2004's frame
def _interval(ft: float, percent: float, digits_ft: float = 0.05, digits_pct: float = 0.05) -> tuple[float, float]:
    """The path lengths [ft] that a range error printed as ``ft`` (+-0.05) and ``percent`` (+-0.05) allow."""
    lo = (ft - digits_ft) / ((percent + digits_pct) / 100)
    hi = (ft + digits_ft) / max((percent - digits_pct) / 100, 1e-12)
    return lo, hi


def path_lengths(t: dict) -> list[tuple[float, float, float]]:
    """Each vehicle's measured path length from impact to rest [m]: (best, low, high), the intersection of
    the intervals SIMON's and EDSMAC4's printed range errors (ft and %) allow (Day2004 Table 8)."""
    out = []
    for k in (0, 1):
        lo, hi = 0.0, math.inf
        for a in t["anchors"]["day2004"]:
            a_lo, a_hi = _interval(a["range_error"][k] / FT, a["range_error_percent"][k])
            lo, hi = max(lo, a_lo), min(hi, a_hi)
        if not lo <= hi:
            raise ScenarioError(f"RICSAC {t['number']}: Day2004's range errors of vehicle {k + 1} give no common path "
                                f"length ({lo:.1f} > {hi:.1f} ft)", field="anchors.day2004")
        out.append(((lo + hi) / 2 * FT, lo * FT, hi * FT))
    return out


def day_frame(t: dict, positions) -> dict:
    """Day2004's earth-fixed frame in the suite's frame, from three assumptions and the published data.

    1. Its x axis lies along vehicle 1's initial direction of travel (as the suite's does);
    2. vehicle 1's CG at impact lies on that axis (the test was staged along it);
    3. its handedness is the one in which each vehicle's measured rotation from impact to rest has the
       sign of its measured separation yaw rate (Vossou2018); both vehicles must agree.

    The origin's one remaining coordinate (along x) then follows from the two path lengths
    (:func:`path_lengths`): the least-squares fit of both, each weighted by its interval's half-width, from
    the vehicles' CG positions at impact (``positions``, the crush placement), among the origins that put
    each measured rest position on the side its vehicle's measured separation velocity points to. Returns the map
    ``to_suite(X, Y, psi)`` and what was found, with each path length the frame gives against its interval.
    """
    rest = t["rest"]
    yaw = [t["separation"][k][1] for k in (0, 1)]
    signs = []
    for mirror in (False, True):
        s = -1.0 if mirror else 1.0
        rot = [s * rest["heading"][k] - t["heading"][k] for k in (0, 1)]
        rot = [r - 2 * math.pi * round(r / (2 * math.pi)) for r in rot]
        signs.append([bool(np.sign(r) == np.sign(w)) for r, w in zip(rot, yaw)])
    choice = [i for i, ok in enumerate(signs) if all(ok)]
    if len(choice) != 1:
        raise ScenarioError(f"RICSAC {t['number']}: no single handedness makes both vehicles' rotations agree with "
                            f"their separation yaw rates ({signs})", field="measured.rest")
    mirror = bool(choice[0])
    h = np.diag([1.0, -1.0 if mirror else 1.0])
    lengths = path_lengths(t)
    c = [np.asarray(positions[k], dtype=float) - h @ np.asarray(rest["position"][k]) for k in (0, 1)]

    def misfit(tx):
        return sum(((math.hypot(c[k][0] - tx, c[k][1]) - lengths[k][0]) / ((lengths[k][2] - lengths[k][1]) / 2)) ** 2
                   for k in (0, 1))

    def forward(tx):  # each vehicle's measured rest lies on the side its measured separation velocity points to
        return all(float(np.dot(np.array([tx, 0.0]) - c[k], t["separation"][k][0])) > 0 for k in (0, 1))

    span = 2 * max(L for L, _, _ in lengths)
    grid = np.linspace(min(cc[0] for cc in c) - span, max(cc[0] for cc in c) + span, 4001)
    ok = [x for x in grid if forward(x)]
    if not ok:
        raise ScenarioError(f"RICSAC {t['number']}: no origin puts both measured rest positions ahead of the vehicles' "
                            "separation velocities", field="measured.rest")
    best = min(ok, key=misfit)
    step = grid[1] - grid[0]
    res = minimize_scalar(misfit, bounds=(best - step, best + step), method="bounded", options={"xatol": 1e-9})
    origin = np.array([float(res.x), 0.0])
    s = -1.0 if mirror else 1.0
    given = [float(np.linalg.norm(h @ np.asarray(rest["position"][k]) + origin - positions[k])) for k in (0, 1)]

    def to_suite(xy, psi=None):
        p = h @ np.asarray(xy, dtype=float) + origin
        return p if psi is None else (p, s * psi)

    return {"mirror": mirror, "origin": origin, "lengths": lengths, "to_suite": to_suite, "sign": s,
            "frame_lengths": given}


def measured_rotation(t: dict, frame: dict, k: int) -> float:
    """Vehicle k's measured rotation from impact to rest in the suite's frame [rad]: the rest heading's
    representative of the sign of the separation yaw rate (assumption 2 of :func:`day_frame`)."""
    r = frame["sign"] * t["rest"]["heading"][k] - t["heading"][k]
    r = r - 2 * math.pi * round(r / (2 * math.pi))
    w = t["separation"][k][1]
    if r * w < 0:
        r += 2 * math.pi * np.sign(w)
    return r


# ------------------------------------------------------------------ the comparison
def _rel(computed: float, measured: float) -> float:
    return (computed - measured) / abs(measured)


def run_case(data: dict, rules: dict, tests: list[dict]) -> CaseResult:
    """Run one RICSAC case and compare every published quantity (module docstring)."""
    t0 = time.process_time()
    t = load_test(data)
    bands = pooled_bands(tests)
    folder = data["folder"]
    cid = t["id"]
    scene_path = folder / data["case"]["scene"]
    scenario = load_scenario(scene_path)
    scene = run_scene(scenario)
    names = [v["name"] for v in t["vehicles"]]
    q = []
    dvb, sepb, yawb, dirb, enb = (bands[k] for k in ("delta_v", "separation", "yaw_rate", "direction", "energy"))
    anchors = t["anchors"]
    for k, name in enumerate(names):
        body = scene.impact.bodies[name]
        dv = float(np.linalg.norm(body.delta_v))
        refs = [t["delta_v"][r][k] for r in t["delta_v"]]
        ref = sum(refs) / 3
        an = {"PIM (Brach & Smith 2002)": _rel(anchors["pim_delta_v"][k], ref),
              "CRASH3 damage only": _rel(anchors["crash3_delta_v"][k], ref)}
        for a in anchors["day2004"]:
            an[a["method"]] = _rel(a["delta_v"][k], ref)
        each = ", ".join(f"{label} {100 * _rel(dv, x):+.1f} %" for label, x in
                         zip(("untransformed", "Brach & Smith 2002", "McHenry 1997"), refs))
        q.append(Quantity(cid, f"delta-v, {name}", "delta-v", "speed", ref, dv, "relative", _rel(dv, ref), dvb[0],
                          f"scatter: largest half-spread of the three published reductions (RICSAC {dvb[1]}, vehicle "
                          f"{dvb[2] + 1})", f"{t['delta_v_source']}: mean of {', '.join(f'{x:.2f}' for x in refs)} m/s",
                          an, note=f"against each reduction: {each}"))
        (vm, wm) = t["separation"][k]
        err = anchors["fitted_separation_error"]
        for j, axis in enumerate("xy"):
            q.append(Quantity(cid, f"separation v{axis}, {name}", "separation velocity", "speed", vm[j],
                              float(body.velocity[j]), "difference", float(body.velocity[j]) - vm[j], sepb[0],
                              f"scatter: largest accelerometer-position correction of delta-v (RICSAC {sepb[1]}, "
                              f"vehicle {sepb[2] + 1})", f"{t['separation_source']}, in the suite's frame",
                              {"PIM fitted (Vossou2018 FC2), magnitude": abs(err[3 * k + j])}))
        q.append(Quantity(cid, f"separation yaw rate, {name}", "yaw rate", "angular_velocity", wm, float(body.yaw_rate),
                          "difference", float(body.yaw_rate) - wm, yawb[0],
                          f"anchors: largest yaw-rate error of the impulse-momentum model fitted to each test "
                          f"(Vossou2018 FC2; RICSAC {yawb[1]}); no published scatter", t["separation_source"],
                          {"PIM fitted (Vossou2018 FC2), magnitude": abs(err[3 * k + 2])}))
        ref_dir, diagrams = _reference_direction(t, k)
        computed_dir = _direction_from_velocity(body.velocity)
        src = (f"mean of {math.degrees(diagrams):.0f} deg ({t['direction_source'].split(',')[0]}) and "
               f"{math.degrees(_direction_from_velocity(vm)):.1f} deg (direction of Vossou2018's separation velocity)"
               if diagrams is not None else
               f"direction of Vossou2018's separation velocity ({t['direction_source']})")
        an = {}
        if diagrams is not None:
            an["PIM (Brach, in Neades2011)"] = angle_difference(anchors["pim_direction"][k], ref_dir)
        q.append(Quantity(cid, f"direction of travel, {name}", "direction of travel", "angle", ref_dir, computed_dir,
                          "difference", angle_difference(computed_dir, ref_dir), dirb[0],
                          f"scatter: largest half-difference of the two published measurements (RICSAC {dirb[1]}, "
                          f"vehicle {dirb[2] + 1})", src, an))
    e0, loss = t["energy"]
    e0v, lossv = loss_from_velocities(t)
    ref = (loss / e0 + lossv / e0v) / 2
    computed = scene.impact.energy_loss["system"]  # a fraction of the kinetic energy before the impact
    q.append(Quantity(cid, "energy loss", "energy loss", "dimensionless", ref, computed, "difference", computed - ref,
                      enb[0], f"scatter: largest half-difference of the two reductions (RICSAC {enb[1]}), in points of "
                      "the initial kinetic energy",
                      f"{t['energy_source']}: {100 * loss / e0:.1f} %; from Vossou2018's velocities: {100 * lossv / e0v:.1f} %",
                      {"PIM fitted (Brach1987)": anchors["pim_loss_percent"] / 100 - ref}))
    figure = {"impact": scene.impact, "placement": placement(t)}
    assumptions = []
    if "rest" in t:
        rq, fig, notes = _rest_quantities(t, data, scenario, scene, names)
        q += rq
        figure.update(fig)
        assumptions += notes
    return CaseResult(cid, data["case"]["title"], "staged_collision", data["case"]["class"],
                      data["case"]["configuration"], tuple(x.with_record(data["record"]) for x in q),
                      tuple(assumptions), figure, time.process_time() - t0, data["record"])


def _rest_quantities(t, data, scenario, scene, names):
    """Rest positions and headings of the run-out from the measured separation velocities and of the whole
    scene (impact and run-out), against Day2004's Table 7, in Day's frame recovered by :func:`day_frame`."""
    cid = t["id"]
    positions = [np.asarray(scenario.states[n].position) for n in names]
    frame = day_frame(t, positions)
    measured_sep = {n: t["separation"][k] for k, n in enumerate(names)}
    runs = {"from measured separation": run_scene(scenario, separation=measured_sep), "end to end": scene}
    q = []
    day = t["anchors"]["day2004"]
    fig = {"frame": frame, "rest_runs": runs, "rest_measured": []}
    for k, name in enumerate(names):
        rest_suite, _ = frame["to_suite"](t["rest"]["position"][k], 0.0)
        fig["rest_measured"].append(rest_suite)
        length = frame["lengths"][k][0]
        rotation = measured_rotation(t, frame, k)
        range_band = max(a["range_error_percent"][k] for a in day) / 100
        heading_band = max(abs(a["heading_error"][k]) for a in day)
        an_range = {a["method"]: a["range_error_percent"][k] / 100 for a in day}
        an_heading = {a["method"]: a["heading_error"][k] for a in day}
        for label, run in runs.items():
            vname = scenario.vehicles[k].name
            b = run.runout[vname].bodies[name]
            pos = np.asarray(b.rest_position)
            d = float(np.linalg.norm(pos - rest_suite))
            lp = float(np.linalg.norm(pos - positions[k]))
            rot = float(b.rest_heading - t["heading"][k])
            src = f"{t['rest']['source']}; path length {length / FT:.1f} ft (Day2004 Table 8)"
            q.append(Quantity(cid, f"rest position, {name} ({label})", "rest position", "length", length, d, "range",
                              d / length, range_band, "anchors: the larger of SIMON's and EDSMAC4's range errors on this "
                              "test and vehicle (Day2004 Table 8); no published scatter", src, an_range, "US",
                              "computed: distance from the measured rest position; measured: the path length"))
            q.append(Quantity(cid, f"path length, {name} ({label})", "path length", "length", length, lp, "relative",
                              _rel(lp, length), range_band, "anchors: as the rest position (a path-length error is at most "
                              "the range error)", src, {}, "US", "independent of the frame's assumed origin"))
            q.append(Quantity(cid, f"rest heading change, {name} ({label})", "rest heading", "angle", rotation, rot,
                              "difference", rot - rotation, heading_band, "anchors: the larger of SIMON's and EDSMAC4's "
                              "heading errors on this test and vehicle (Day2004 Table 8)", t["rest"]["source"],
                              an_heading, "US"))
    notes = [f"Day2004's frame: x along vehicle 1's initial direction of travel through its CG at impact, handedness "
             f"{'mirrored (y to the right, as SAE)' if frame['mirror'] else 'as the suite (y to the left)'} (the one in "
             "which both vehicles' measured rotations to rest have the sign of their separation yaw rates), origin "
             "fitted to the path lengths of Day2004 Table 8 (" + ", ".join(
                 f"{lo / FT:.1f}-{hi / FT:.1f} ft, the frame gives {g / FT:.1f} ft" for (_, lo, hi), g in
                 zip(frame["lengths"], frame["frame_lengths"])) + ")"]
    return q, fig, notes

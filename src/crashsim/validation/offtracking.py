"""SAE J695 low-speed off-tracking of a tractor-semitrailer on a steady circle, against the closed form.

The closed form (SAE J695's steady state; the kinematics of a unit whose rear axle follows at
wheelbase L behind its front point): on a circle of radius R of the steer axle's centre, the tractor's
rear axle runs at sqrt(R^2 - L1^2), its fifth wheel (offset e ahead of that axle) at
sqrt(R^2 - L1^2 + e^2), and the semitrailer's axle (L2 behind the kingpin) at
sqrt(R^2 - L1^2 + e^2 - L2^2): the off-tracking is R - sqrt(R^2 - L1^2 + e^2 - L2^2).

What crashsim can run. Its approach and run-out steer by a fixed angle per wheel (no driver follows a
path: another issue adds one), so the check is the steady circle, not the 90 deg turn of a design
manoeuvre: the combination of crashsim's library (``tractor-3axle`` and ``semitrailer-53ft``) starts
straight at 5 mph with the steer wheels at fixed angles (Ackermann: each at its kinematic angle for
the circle) and coasts (rolling resistance 0: the run-out
has no drive) until the trailer has settled on its circle; the radii are fitted to the last lap of
each axle centre's path. The tandems are single axles at their centres, as the closed form takes them
(a real tandem scrubs and acts as an axle a little behind its centre).

Band (stated, not published scatter): the closed form is kinematic; at 5 mph each unit's axle slips
outward by about its lateral acceleration over its tyres' cornering coefficient, alpha_i = a_i / (C g)
(a_i = v^2 / R_i of that axle over the last lap), and the same closed form with those slip angles
(:func:`closed_form`'s ``slip``) gives less off-tracking: the difference is the band, the closed form's
own speed correction, not what crashsim reaches.
"""

from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from ..motion import Road, RunoutOptions, simulate_runout
from ..motion.wheels import WheelSetting, WheelSettings
from ..scenario import preset_geometry
from ..units import G0, Kind
from ..vehicles import Axle, Body, Hitch, Vehicle, chain_states
from .core import CaseResult, Quantity, quantity

__all__ = ["combination", "closed_form", "fit_circle", "run_case"]


def _single_axle(axles: list[dict], name: str) -> Axle:
    """The axles of a preset as one at their centre (the closed form's idealisation)."""
    x = sum(a["x"] for a in axles) / len(axles)
    return Axle(x, axles[0]["track"], axles[0]["dual"], name)


def combination(tractor: str, trailer: str):
    """The tractor-semitrailer of two presets with each rear tandem as one axle at its centre, and its
    lengths for the closed form: L1 (steer axle to the tractor's rear axle), e (fifth wheel ahead of
    that axle), L2 (kingpin to the trailer's axle) [m]."""
    g1, g2 = preset_geometry(tractor), preset_geometry(trailer)
    steer = Axle(g1["axles"][0]["x"], g1["axles"][0]["track"], False, "steer")
    rear = _single_axle(g1["axles"][1:], "drive")
    t_axle = _single_axle(g2["axles"], "axle")
    b1 = Body("tractor", g1["mass"], g1["yaw_inertia"], g1["length"], g1["width"], tuple(g1["outline_center"]),
              (steer, rear), g1["cg_height"])
    b2 = Body("trailer", g2["mass"], g2["yaw_inertia"], g2["length"], g2["width"], tuple(g2["outline_center"]),
              (t_axle,), g2["cg_height"])
    veh = Vehicle("truck", (b1, b2), (Hitch(tuple(g1["rear_hitch"]), tuple(g2["front_hitch"]),
                                            g2["articulation_limit"]),))
    lengths = {"L1": steer.x - rear.x, "e": g1["rear_hitch"][0] - rear.x, "L2": g2["front_hitch"][0] - t_axle.x}
    return veh, lengths


def closed_form(radius: float, lengths: dict, slip: tuple[float, float] = (0.0, 0.0)) -> float:
    """Steady-state off-tracking [m] on a steer-axle circle of ``radius`` [m] (module docstring).

    ``slip``: the outward slip angles [rad] of the tractor's rear axle and the trailer's axle (0: the
    low-speed closed form). A unit's rear axle slipping by alpha, its front point on a circle of radius
    R, runs on R_r = L sin(alpha) + sqrt(L^2 sin^2(alpha) + R^2 - L^2); the fifth wheel, e ahead of the
    tractor's axle, on sqrt(R_r^2 + e^2 - 2 e R_r sin(alpha)).
    """
    def rear(r_front, length, alpha):
        inner = length ** 2 * math.sin(alpha) ** 2 + r_front ** 2 - length ** 2
        if inner <= 0:
            raise ValueError(f"a radius of {r_front:.3f} m is too small for a unit of length {length:.3f} m")
        return length * math.sin(alpha) + math.sqrt(inner)

    r_r = rear(radius, lengths["L1"], slip[0])
    e = lengths["e"]
    r_k = math.sqrt(r_r ** 2 + e ** 2 - 2 * e * r_r * math.sin(slip[0]))
    return radius - rear(r_k, lengths["L2"], slip[1])


def fit_circle(x, y) -> tuple[float, float, float]:
    """Least-squares circle (Kasa) through points: centre x, centre y, radius [m]."""
    x, y = np.asarray(x, dtype=float), np.asarray(y, dtype=float)
    a = np.column_stack([x, y, np.ones_like(x)])
    c, *_ = np.linalg.lstsq(a, x * x + y * y, rcond=None)
    cx, cy = c[0] / 2, c[1] / 2
    return cx, cy, math.sqrt(c[2] + cx * cx + cy * cy)


def _axle_path(hist, x_axle: float):
    c, s = np.cos(hist.heading), np.sin(hist.heading)
    return hist.x + x_axle * c, hist.y + x_axle * s


def run_case(data: dict, rules: dict, suite_folder: Path) -> CaseResult:
    """Run the steady circle of ``measured.toml`` and compare its off-tracking with the closed form."""
    t0 = time.process_time()
    f = data["folder"] / "measured.toml"
    c = data["circle"]
    veh, lengths = combination(c["tractor"], c["trailer"])
    radius = quantity(c["steer_axle_radius"], Kind.LENGTH, "circle.steer_axle_radius", f)
    speed = quantity(c["speed"], Kind.SPEED, "circle.speed", f)
    coeff = float(c["cornering_coefficient"])
    # Ackermann steer: each steer wheel at the kinematic angle of that circle (parallel steer would
    # scrub the two wheels against each other and brake the coasting combination)
    r_rear = math.sqrt(radius ** 2 - lengths["L1"] ** 2)
    track = veh.bodies[0].axles[0].track
    steer = math.atan(lengths["L1"] / r_rear)
    angles = {"left": math.atan(lengths["L1"] / (r_rear - track / 2)), "right": math.atan(lengths["L1"] / (r_rear + track / 2))}
    tyre = dict(cornering_coefficient=coeff, rolling_resistance=0.0)
    wheels = WheelSettings(default=WheelSetting("rolling", **tyre),
                           wheels={f"tractor/steer/{side}": WheelSetting("rolling", steer=a, **tyre)
                                   for side, a in angles.items()})
    t_end = quantity(c["duration"], Kind.TIME, "circle.duration", f)
    init = chain_states(veh, (0.0, 0.0), 0.0, (speed, 0.0))
    res = simulate_runout(veh, init, wheels, Road(float(c["road_friction"])),
                          RunoutOptions(engine=rules["runout"]["engine"], t_max=t_end))
    ht, hr = res.bodies["tractor"].history, res.bodies["trailer"].history
    fx, fy = _axle_path(ht, veh.bodies[0].axles[0].x)
    tx, ty = _axle_path(hr, veh.bodies[1].axles[0].x)
    # the last lap of the steer axle: its path from one turn before the end
    turned = np.unwrap(ht.heading)
    last = turned >= turned[-1] - 2 * math.pi if abs(turned[-1] - turned[0]) > 2 * math.pi else slice(None)
    _, _, r_front = fit_circle(fx[last], fy[last])
    _, _, r_trailer = fit_circle(tx[last], ty[last])
    computed = r_front - r_trailer
    expected = closed_form(r_front, lengths)
    speed_end = float(math.hypot(hr.vx[-1], hr.vy[-1]))
    # the speed term of the last lap: each unit's axle slips out by L_i a_y,i / (C g), a_y,i = mean v^2 / R_i
    v2_t = float(np.mean(ht.vx[last] ** 2 + ht.vy[last] ** 2))
    v2_r = float(np.mean(hr.vx[last] ** 2 + hr.vy[last] ** 2))
    r_tractor = math.sqrt(r_front ** 2 - lengths["L1"] ** 2)
    slip = (v2_t / r_tractor / (coeff * G0), v2_r / r_trailer / (coeff * G0))
    shift = expected - closed_form(r_front, lengths, slip)
    band = shift / expected
    q = [Quantity(data["case"]["id"], f"steady off-tracking, steer-axle radius {c['steer_axle_radius']}", "off-tracking",
                  "length", expected, computed, "relative", (computed - expected) / expected, band,
                  f"stated: the closed form's speed correction: its slip-angle form at the last lap's speed (down to "
                  f"{speed_end / 0.44704:.1f} mph) off-tracks {100 * shift:.1f} cm less", c["source"], {}, "US",
                  f"closed form at the steer axle's fitted radius {r_front:.3f} m; steer {math.degrees(steer):.2f} deg "
                  f"(left {math.degrees(angles['left']):.2f}, right {math.degrees(angles['right']):.2f})")]
    figure = {"front": (fx, fy), "trailer": (tx, ty), "r_front": r_front, "r_trailer": r_trailer, "expected": expected,
              "last": last}
    notes = (f"tandems as single axles at their centres: L1 = {lengths['L1']:.3f} m, fifth wheel {lengths['e']:.3f} m "
             f"ahead of the tractor's axle, L2 = {lengths['L2']:.3f} m",
             f"coasting at {speed / 0.44704:.1f} mph (rolling resistance 0: the run-out has no drive); {speed_end / 0.44704:.2f} mph "
             f"after {t_end:.0f} s")
    return CaseResult(data["case"]["id"], data["case"]["title"], data["case"]["kind"], data["case"]["class"],
                      data["case"].get("configuration", ""), tuple(x.with_record(data["record"]) for x in q), notes,
                      figure, time.process_time() - t0, data["record"])

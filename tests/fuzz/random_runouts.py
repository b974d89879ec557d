"""Seeded random valid run-outs for the engine fuzz test (tests/fuzz) and its larger sweep
(``benchmarks/engine_fuzz.py``).

Every case is a valid input: plausible masses, inertias and axle layouts of a car, a car with a
trailer, a tractor-semitrailer or a tractor with two trailers; mixed wheel states (rolling,
braked, locked, jammed, with steer and mu factors), scheduled wheel changes, friction zones
placed across the expected path, load transfer on some cases, hitch-consistent initial states
with speeds up to 35 m/s, yaw rates, side slip and articulation (inside the articulation limit).
Case ``i`` of seed ``s`` depends only on ``(s, i)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from crashsim.motion import (FrictionZone, Road, RunoutOptions, ScheduledChange, WheelSetting, WheelSettings,
                             make_hitch_consistent)
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

__all__ = ["Case", "KINDS", "random_case"]

#: Vehicle kinds, each drawn equally often.
KINDS = ("car", "car+trailer", "tractor-semitrailer", "doubles")


@dataclass(frozen=True)
class Case:
    """One random run-out: inputs of :func:`crashsim.motion.simulate_runout` and a label."""

    label: str
    vehicle: Vehicle
    initial: dict
    wheels: WheelSettings
    road: Road
    options: RunoutOptions


def _u(rng, lo, hi):
    return float(rng.uniform(lo, hi))


def _car(rng, name, rear_hitch=False):
    length = _u(rng, 4.0, 5.5)
    mass = _u(rng, 1000, 2600)
    wb = _u(rng, 2.4, 3.2)
    a = wb * _u(rng, 0.38, 0.55)
    body = dict(name=name, mass=mass, yaw_inertia=mass * _u(rng, 1.3, 2.0), length=length, width=_u(rng, 1.7, 2.0),
                outline_center=(_u(rng, -0.3, 0.3), 0.0), axles=(Axle(a, 1.55, name="front"), Axle(a - wb, 1.55, name="rear")),
                cg_height=_u(rng, 0.5, 0.7))
    hitch = (-(wb - a) - _u(rng, 0.9, 1.3), 0.0) if rear_hitch else None
    return Body(**body), hitch


def _trailer(rng, name):
    length = _u(rng, 2.5, 5.0)
    mass = _u(rng, 400, 2500)
    body = Body(name, mass, mass * _u(rng, 1.0, 2.5), length, _u(rng, 1.6, 2.2), (_u(rng, -0.3, 0.2), 0.0),
                (Axle(_u(rng, -0.2, 0.3), 1.7, name="fwd"), Axle(_u(rng, -1.0, -0.6), 1.7, name="aft")),
                _u(rng, 0.5, 0.8))
    return body, (length / 2 + _u(rng, 0.8, 1.4), 0.0)


def _tractor(rng, name):
    mass = _u(rng, 7000, 9500)
    body = Body(name, mass, mass * _u(rng, 2.0, 2.8), _u(rng, 6.0, 7.0), 2.5, (_u(rng, -0.3, 0.3), 0.0),
                (Axle(_u(rng, 2.4, 2.9), 2.05, name="steer"), Axle(_u(rng, -2.8, -2.4), 1.85, True, "drive 1"),
                 Axle(_u(rng, -4.2, -3.7), 1.85, True, "drive 2")), _u(rng, 0.9, 1.2))
    return body, (_u(rng, -3.4, -3.0), 0.0)


def _semi(rng, name, length, rear_hitch):
    mass = _u(rng, 6000, 30000)
    kp = length / 2 - _u(rng, 1.0, 1.5)
    body = Body(name, mass, mass * length**2 / _u(rng, 10, 14), length, 2.55, (0.0, 0.0),
                tuple(Axle(-length / 2 + _u(rng, 1.0, 1.4) + 1.3 * k, 1.85, True, f"axle {k + 1}") for k in range(3))
                if length > 9 else (Axle(-length / 2 + _u(rng, 1.0, 2.0), 1.85, True, "axle 1"),),
                _u(rng, 1.0, 1.8))
    return body, (kp, 0.0), ((-length / 2 - _u(rng, 0.3, 0.8), 0.0) if rear_hitch else None)


def _vehicle(rng, kind):
    lim = lambda: math.radians(_u(rng, 55, 95))  # noqa: E731
    if kind == "car":
        car, _ = _car(rng, "car")
        return Vehicle("V", (car,))
    if kind == "car+trailer":
        car, h1 = _car(rng, "car", True)
        tr, h2 = _trailer(rng, "trailer")
        return Vehicle("V", (car, tr), (Hitch(h1, h2, lim()),))
    tractor, fw = _tractor(rng, "tractor")
    if kind == "tractor-semitrailer":
        semi, kp, _ = _semi(rng, "semi", _u(rng, 12.0, 14.6), False)
        return Vehicle("V", (tractor, semi), (Hitch(fw, kp, lim()),))
    semi, kp, rh = _semi(rng, "semi", _u(rng, 7.5, 9.5), True)
    pup, kp2, _ = _semi(rng, "pup", _u(rng, 7.5, 9.0), False)
    return Vehicle("V", (tractor, semi, pup), (Hitch(fw, kp, lim()), Hitch(rh, kp2, lim())))


def _setting(rng, car):
    state = str(rng.choice(["rolling", "braked", "locked", "jammed"], p=[0.4, 0.2, 0.3, 0.1]))
    tyre = dict(cornering_coefficient=_u(rng, 7.5, 9.5) if car else _u(rng, 5.0, 6.5),
                rolling_resistance=_u(rng, 0.006, 0.015))
    return WheelSetting(state, brake=_u(rng, 0.05, 1.0) if state == "braked" else 0.0,
                        steer=math.radians(_u(rng, -12, 12)) if rng.random() < 0.3 else 0.0,
                        mu_factor=_u(rng, 0.4, 1.0) if state == "jammed" else 1.0, **tyre)


def _wheels(rng, vehicle):
    car = vehicle.bodies[0].mass < 3000
    default = _setting(rng, car)
    overrides = {}
    for body in vehicle.bodies:
        for k, axle in enumerate(body.axles):
            if rng.random() < 0.3:
                overrides[f"{body.name}/{k}"] = _setting(rng, car)
    schedule = []
    for _ in range(int(rng.integers(0, 3))):
        body = vehicle.bodies[int(rng.integers(len(vehicle.bodies)))]
        s = _setting(rng, car)
        schedule.append(ScheduledChange(_u(rng, 0.2, 2.5), body.name,
                                        {"state": s.state, "brake": s.brake, "steer": s.steer,
                                         "cornering_coefficient": s.cornering_coefficient,
                                         "rolling_resistance": s.rolling_resistance}))
    return WheelSettings(default=default, wheels=overrides, schedule=schedule)


def _road(rng, start, course, speed):
    zones = []
    for z in range(int(rng.integers(0, 3))):
        d = _u(rng, 2.0, 4.0 + speed)
        cx, cy = start + d * np.array([math.cos(course), math.sin(course)]) + rng.normal(0, 3, 2)
        half = _u(rng, 1.5, 8.0)
        ang = _u(rng, 0, math.pi)
        corners = [(cx + half * math.cos(ang + k * math.pi / 2) * (1.5 if k % 2 else 1.0),
                    cy + half * math.sin(ang + k * math.pi / 2) * (1.5 if k % 2 else 1.0)) for k in range(4)]
        zones.append(FrictionZone(tuple(corners), _u(rng, 0.2, 0.9), f"zone {z + 1}"))
    return Road(_u(rng, 0.45, 0.9), tuple(zones))


def random_case(seed: int, i: int, *, engine: str = "scipy", kinds=KINDS) -> Case:
    """Random run-out ``i`` of ``seed`` (independent of every other case).

    Parameters
    ----------
    seed, i : int
    engine : {"scipy", "compiled"}
        Engine written into the options (everything else is the same for both).
    kinds : sequence of str
        Vehicle kinds to draw from.
    """
    rng = np.random.default_rng([seed, i])
    kind = kinds[int(rng.integers(len(kinds)))]
    vehicle = _vehicle(rng, kind)
    heading = _u(rng, -math.pi, math.pi)
    speed = _u(rng, 0.5, 35.0)
    slip = math.radians(_u(rng, -40, 40)) if rng.random() < 0.6 else 0.0
    course = heading + slip
    nb = len(vehicle.bodies)
    yaw = [float(rng.normal(0, 0.6)) for _ in range(nb)]
    art = [float(rng.uniform(-0.6, 0.6) * h.articulation_limit) for h in vehicle.hitches]
    states = chain_states(vehicle, (0.0, 0.0), heading, speed * np.array([math.cos(course), math.sin(course)]),
                          yaw, art)
    # perturb the rear bodies' yaw rates (hitch-consistent again after the projection)
    initial = make_hitch_consistent(vehicle, {n: BodyState(s.position, s.heading, s.velocity, s.yaw_rate)
                                              for n, s in states.items()})
    lt = nb > 0 and rng.random() < 0.25
    options = RunoutOptions(engine=engine, load_transfer=lt)
    label = f"seed {seed} case {i}: {kind}, {speed:.1f} m/s" + (", load transfer" if lt else "")
    return Case(label, vehicle, initial, _wheels(rng, vehicle), _road(rng, np.zeros(2), course, speed), options)

"""Seeded random valid run-outs for the engine fuzz test (tests/fuzz) and its larger sweep
(``benchmarks/engine_fuzz.py``).

Every case is a valid input: plausible masses, inertias and axle layouts of a car, a car with a
trailer, a tractor-semitrailer or a tractor with two trailers; mixed wheel states (rolling,
braked, locked, jammed, with steer and mu factors), scheduled wheel changes, friction zones
placed across the expected path, load transfer on some cases, a road slope on about a third of
the cases and scenes (grade within 6 %, cross-slope within 4 %, half the zones with a grade
of their own within 8 %), air brakes on about a third of the single-vehicle cases and of the
vehicles of a scene (timing, capacities below and above the tyres' limit, brakes out of
adjustment, releases, ABS; :func:`_air_braked`), the wheel-lift and
rollover check on every case with load transfer (half the bodies with a threshold of their own;
in scenes half the bodies with a contact height of their own),
hitch-consistent initial states
with speeds up to 35 m/s, yaw rates, side slip and articulation (inside the articulation limit).
Case ``i`` of seed ``s`` depends only on ``(s, i)``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from crashsim.motion import (FrictionZone, Road, RunoutOptions, ScheduledChange, WheelSetting, WheelSettings,
                             make_hitch_consistent)
from crashsim.motion.brakes import AirBrakes, BrakeUnit, unit_type_default
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

__all__ = ["Case", "KINDS", "DOLLY_KINDS", "random_case", "random_scene", "random_tangle"]

#: Vehicle kinds, each drawn equally often.
KINDS = ("car", "car+trailer", "tractor-semitrailer", "doubles")
#: Doubles with the converter dolly as a body of its own: an A-dolly (free in yaw) or a C-dolly
#: (yaw-locked to the lead trailer), its axle self-steering in most cases (limit 10-40 deg, or 0:
#: locked), sometimes locked later by a scheduled change, and sometimes a self-steering rear axle on
#: the lead trailer (drawn only when asked for: the default kinds draw what they drew before).
DOLLY_KINDS = ("doubles+dolly",)


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
    """A random vehicle of ``kind`` whose static axle loads are all positive (drawn again until so:
    a heavy semitrailer's kingpin behind the tractor's drive group can lift the steer axle)."""
    from crashsim.errors import ScenarioError
    from crashsim.motion.loads import static_loads

    for _ in range(100):
        vehicle = _draw_vehicle(rng, kind)
        try:
            static_loads(vehicle)
        except ScenarioError:
            continue
        return vehicle
    raise RuntimeError(f"no valid {kind} in 100 draws")


def _draw_vehicle(rng, kind):
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
    if kind == "doubles+dolly":
        c_dolly = rng.random() < 0.5
        dmass = _u(rng, 1000, 1800)
        dolly = Body("dolly", dmass, dmass * _u(rng, 0.6, 1.0), _u(rng, 2.8, 3.6), 2.4, (0.0, 0.0),
                     (Axle(_u(rng, -0.2, 0.2), 1.85, True, "axle"),), _u(rng, 0.8, 1.0))
        eye, fifth = (_u(rng, 2.0, 2.8), 0.0), (_u(rng, 0.0, 0.3), 0.0)
        return Vehicle("V", (tractor, semi, dolly, pup),
                       (Hitch(fw, kp, lim()), Hitch(rh, eye, None if c_dolly else lim(), yaw_locked=c_dolly),
                        Hitch(fifth, kp2, lim())))
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


def _self_steering(wheels: WheelSettings, vehicle: Vehicle, seed: int, i: int) -> tuple[WheelSettings, str]:
    """Self-steering axles on a doubles+dolly case, from a generator of their own."""
    rng = np.random.default_rng([seed, i, 52])
    overrides = dict(wheels.wheels)
    schedule = list(wheels.schedule)
    base = wheels.default
    tyre = dict(cornering_coefficient=base.cornering_coefficient or 6.0, rolling_resistance=base.rolling_resistance or 0.008)
    label = ""
    if rng.random() < 0.8:
        lim = 0.0 if rng.random() < 0.15 else math.radians(_u(rng, 10, 40))
        state = str(rng.choice(["rolling", "braked"]))
        overrides["dolly"] = WheelSetting(state, brake=_u(rng, 0.05, 0.8) if state == "braked" else 0.0,
                                          self_steer_limit=lim, **tyre)
        label = f", dolly self-steering {math.degrees(lim):.0f} deg"
        if rng.random() < 0.3:
            schedule.append(ScheduledChange(_u(rng, 0.2, 2.0), "dolly", {"self_steer_limit": 0.0}))
            label += " (locked later)"
    if rng.random() < 0.3:
        overrides[f"semi/{len(vehicle.body('semi').axles) - 1}"] = WheelSetting(
            "rolling", self_steer_limit=math.radians(_u(rng, 5, 25)), **tyre)
        label += ", self-steering lead-trailer axle"
    return WheelSettings(default=base, wheels=overrides, schedule=schedule), label


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


def _sloped(road: Road, seed: int, i: int) -> tuple[Road, str]:
    """The road with a slope in about a third of the cases (whole road, and zones of their own).

    Drawn from a generator of its own, so that the other draws of a case are those of a level
    road (the level cases are the ones the fuzz drew before slopes existed).
    """
    rng = np.random.default_rng([seed, i, 22])
    if rng.random() >= 0.35:
        return road, ""
    grade, cross = _u(rng, -0.06, 0.06), _u(rng, -0.04, 0.04)
    zones = tuple(dataclasses.replace(z, grade=_u(rng, -0.08, 0.08)) if rng.random() < 0.5 else z
                  for z in road.zones)
    return Road(road.mu, zones, grade, cross), f", grade {100 * grade:.1f} %, cross-slope {100 * cross:.1f} %"


def _air_braked(wheels: WheelSettings, vehicle, seed: int, i: int, tag: int = 121) -> tuple[WheelSettings, str]:
    """The wheel settings with air brakes in about a third of the cases: a random set of braked bodies
    with random capacities (some below, some above the tyres' limit), timing (rise and fall times of 0,
    steps of the brake force, among them), brakes out of adjustment, a release on some, ABS on some
    (tractor and trailers drawn apart).

    Drawn from a generator of its own, ``(seed, i, tag)`` (the other draws of a case stay those
    without air brakes; a scene's vehicles each have a tag of their own).
    The wheel states are made valid for them: a ``braked`` fraction becomes ``rolling`` (the air
    brakes give the force) and, where a unit has ABS, a ``locked`` wheel too.
    """
    rng = np.random.default_rng([seed, i, tag])
    if rng.random() >= 0.35:
        return wheels, ""
    tractor_abs, trailer_abs = rng.random() < 0.5, rng.random() < 0.4
    units = {}
    for bi, body in enumerate(vehicle.bodies):
        if rng.random() < 0.75 and body.axles:
            per_axle = body.mass * 9.81 / len(body.axles)
            units[body.name] = BrakeUnit(
                tuple(_u(rng, 0.2, 1.4) * per_axle for _ in body.axles),
                unit_type_default(len(vehicle.bodies), bi, body.name),
                delay=_u(rng, 0.0, 0.6), rise=_u(rng, 0.0, 0.6) if rng.random() < 0.9 else 0.0,
                release_delay=_u(rng, 0.1, 0.6), fall=_u(rng, 0.1, 0.7),
                out_of_adjustment=_u(rng, 0.0, 0.3) if rng.random() < 0.4 else 0.0,
                abs=tractor_abs if bi == 0 else trailer_abs)
    if not units:
        return wheels, ""
    apply = _u(rng, -0.5, 1.0)
    release = apply + _u(rng, 0.5, 3.0) if rng.random() < 0.3 else None
    brakes = AirBrakes(units, apply, release, _u(rng, 0.7, 0.95))
    any_abs = any(u.abs for u in units.values())

    def valid(state):
        return "rolling" if state == "braked" or (any_abs and state == "locked") else state

    def fix(ws):
        return dataclasses.replace(ws, state=valid(ws.state), brake=0.0)

    schedule = []
    for c in wheels.schedule:
        ch = dict(c.changes)
        ch["state"] = valid(ch.get("state", "rolling"))
        ch["brake"] = 0.0
        schedule.append(ScheduledChange(c.time, c.wheels, ch))
    out = WheelSettings(default=fix(wheels.default), wheels={k: fix(w) for k, w in wheels.wheels.items()},
                        schedule=schedule, brakes=brakes)
    which = ", ".join(f"{n}{' (ABS)' if u.abs else ''}" for n, u in units.items())
    return out, f", air brakes on {which} from {apply:.2f} s"


def _rollover(vehicles, options: RunoutOptions, seed: int, i: int, tag: int):
    """With load transfer, the wheel-lift and rollover check on, and about half the bodies with a threshold of
    their own (0.2-0.9 g; the others the default 0.75 t / (2 h)): ``(vehicles, options, label)``.

    Drawn from a generator of its own, so that the other draws of a case are unchanged (the check only reads
    the run; the run itself is the same as without it).
    """
    if not options.load_transfer:
        return vehicles, options, ""
    rng = np.random.default_rng([seed, i, tag])
    out = []
    for v in vehicles:
        bodies = tuple(dataclasses.replace(b, rollover_threshold=_u(rng, 0.2, 0.9)) if rng.random() < 0.5 else b
                       for b in v.bodies)
        out.append(dataclasses.replace(v, bodies=bodies))
    return tuple(out), dataclasses.replace(options, rollover=True), ", rollover check"


def _contact_heights(vehicles, options: RunoutOptions, seed: int, i: int, tag: int):
    """With load transfer, about half the bodies with a contact height of their own (0.2-1.5 times their CG
    height; the others take contact at the CG): ``(vehicles, label)``. A stream of its own, as above."""
    if not options.load_transfer:
        return vehicles, ""
    rng = np.random.default_rng([seed, i, tag])
    out, n = [], 0
    for v in vehicles:
        bodies = []
        for b in v.bodies:
            if rng.random() < 0.5:
                b = dataclasses.replace(b, contact_height=_u(rng, 0.2, 1.5) * b.cg_height)
                n += 1
            bodies.append(b)
        out.append(dataclasses.replace(v, bodies=tuple(bodies)))
    return tuple(out), f", {n} contact height(s)" if n else ""


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
    art = [0.0 if h.yaw_locked else float(rng.uniform(-0.6, 0.6) * h.articulation_limit) for h in vehicle.hitches]
    states = chain_states(vehicle, (0.0, 0.0), heading, speed * np.array([math.cos(course), math.sin(course)]),
                          yaw, art)
    # perturb the rear bodies' yaw rates (hitch-consistent again after the projection)
    initial = make_hitch_consistent(vehicle, {n: BodyState(s.position, s.heading, s.velocity, s.yaw_rate)
                                              for n, s in states.items()})
    lt = nb > 0 and rng.random() < 0.25
    options = RunoutOptions(engine=engine, load_transfer=lt)
    label = f"seed {seed} case {i}: {kind}, {speed:.1f} m/s" + (", load transfer" if lt else "")
    wheels = _wheels(rng, vehicle)
    if kind == "doubles+dolly":
        label += ", C-dolly" if vehicle.hitches[1].yaw_locked else ", A-dolly"
        wheels, more = _self_steering(wheels, vehicle, seed, i)
        label += more
    road, slope = _sloped(_road(rng, np.zeros(2), course, speed), seed, i)
    wheels, air = _air_braked(wheels, vehicle, seed, i)
    (vehicle,), options, roll = _rollover((vehicle,), options, seed, i, 23)
    return Case(label + slope + air + roll, vehicle, initial, wheels, road, options)


@dataclass(frozen=True)
class SceneCase:
    """A random scene: inputs of :func:`crashsim.motion.simulate_scene` and a label."""

    label: str
    vehicles: tuple
    initial: dict
    wheels: dict
    road: Road
    options: RunoutOptions
    obstacles: tuple


def _renamed(vehicle: Vehicle, tag: str) -> Vehicle:
    from dataclasses import replace

    return Vehicle(f"{tag}", tuple(replace(b, name=f"{tag}_{b.name}") for b in vehicle.bodies), vehicle.hitches)


def _outline_world(body, state):
    c, s = math.cos(state.heading), math.sin(state.heading)
    o = body.outline()
    return np.asarray(state.position) + o @ np.array([[c, s], [-s, c]])


def _apart(polys_a, polys_b, margin) -> bool:
    """True if every pair of convex outlines is separated by more than ``margin`` (separating axes)."""
    for p in polys_a:
        for q in polys_b:
            best = -math.inf
            for poly, other in ((p, q), (q, p)):
                d = np.roll(poly, -1, axis=0) - poly
                n = np.stack([d[:, 1], -d[:, 0]], 1) / np.hypot(d[:, 0], d[:, 1])[:, None]
                for k in range(len(poly)):
                    best = max(best, float(np.min((other - poly[k]) @ n[k])))
            if best <= margin:
                return False
    return True


def random_scene(seed: int, i: int, *, engine: str = "scipy", kinds=KINDS, n_vehicles=None,
                 air_brakes: bool = True) -> SceneCase:
    """Random scene ``i`` of ``seed``: 2 or 3 vehicles on crossing paths, some obstacles.

    Vehicles start apart (no overlap, more than 0.5 m between outlines) and move towards a
    common area, so that many scenes have impacts and contacts; some start at rest.  With
    ``air_brakes`` False the vehicles keep the wheel settings drawn for them (the scene as it was
    drawn before air brakes: every other draw is the same).
    """
    from crashsim.motion import Obstacle

    rng = np.random.default_rng([seed, i, 7])
    nv = int(n_vehicles or rng.integers(2, 4))
    for attempt in range(200):
        vehicles, initial, wheels, polys = [], {}, {}, []
        ok = True
        for k in range(nv):
            kind = kinds[int(rng.integers(len(kinds)))]
            v = _renamed(_vehicle(rng, kind), f"v{k}")
            if k == 0:
                pos, heading = np.zeros(2), _u(rng, -math.pi, math.pi)
            else:
                bearing = _u(rng, -math.pi, math.pi)
                pos = _u(rng, 8.0, 22.0) * np.array([math.cos(bearing), math.sin(bearing)])
                heading = math.atan2(-pos[1], -pos[0]) + _u(rng, -0.6, 0.6)  # towards the first vehicle
            speed = 0.0 if (k > 0 and rng.random() < 0.25) else _u(rng, 3.0, 25.0)
            slip = math.radians(_u(rng, -20, 20)) if rng.random() < 0.4 else 0.0
            course = heading + slip
            art = [float(rng.uniform(-0.3, 0.3) * h.articulation_limit) for h in v.hitches]
            yaw = [float(rng.normal(0, 0.3)) for _ in v.bodies]
            st = chain_states(v, pos, heading, speed * np.array([math.cos(course), math.sin(course)]), yaw, art)
            st = make_hitch_consistent(v, st)
            mine = [_outline_world(b, st[b.name]) for b in v.bodies]
            if any(not _apart(mine, other, 0.5) for other in polys):
                ok = False
                break
            polys.append(mine)
            vehicles.append(v)
            initial.update(st)
            wheels[v.name] = _wheels(rng, v)
        if ok:
            break
    obstacles = []
    if rng.random() < 0.5:  # a guardrail beside the area
        off = _u(rng, 6.0, 14.0)
        ang = _u(rng, 0, math.pi)
        d = np.array([math.cos(ang), math.sin(ang)])
        n = np.array([-d[1], d[0]])
        a, b = off * n - 40 * d, off * n + 40 * d
        rail = Obstacle("rail", (tuple(a), tuple(b)), thickness=0.3)
        if all(_apart(p, rail.pieces(), 0.5) for p in polys):
            obstacles.append(rail)
    if rng.random() < 0.3:  # a pole
        c = rng.normal(0, 6, 2)
        pole = Obstacle("pole", tuple(map(tuple, c + 0.2 * np.array([[1, 1], [-1, 1], [-1, -1], [1, -1]]))), closed=True)
        if all(_apart(p, pole.pieces(), 0.5) for p in polys):
            obstacles.append(pole)
    speed0 = max(float(np.hypot(*initial[v.bodies[0].name].velocity)) for v in vehicles)
    lt = rng.random() < 0.2  # every body has a CG height (the generator sets them)
    options = RunoutOptions(engine=engine, load_transfer=lt)
    label = (f"seed {seed} scene {i}: {nv} vehicles ({', '.join(str(len(v.bodies)) + ' bodies' for v in vehicles)}), "
             f"{len(obstacles)} obstacle(s), fastest {speed0:.1f} m/s" + (", load transfer" if lt else ""))
    # sloped roads as in the single cases (drawn from a stream of their own: the other draws are those of
    # the level scenes). Scene 2 of seed 20261124 is the regression case of the shared event search: its
    # pup strikes a car 0.9 ms before its semitrailer would, and a search that stopped a sub-interval
    # short of the semitrailer's root stepped over the pup's crossing (one engine or the other, by rtol);
    # its test draws it without air brakes (air_brakes=False): with them the truck brakes, the strikes part.
    road, slope = _sloped(_road(rng, np.zeros(2), 0.0, 10.0), seed, i)
    vehicles, options, roll = _rollover(tuple(vehicles), options, seed, i, 24)
    vehicles, heights = _contact_heights(vehicles, options, seed, i, 26)
    roll += heights
    air = ""
    for k, v in enumerate(vehicles if air_brakes else ()):  # on about a third of the vehicles (a stream each)
        wheels[v.name], more = _air_braked(wheels[v.name], v, seed, i, 1210 + k)
        air += more
    return SceneCase(label + slope + roll + air, tuple(vehicles), initial, wheels, road, options, tuple(obstacles))


def random_tangle(seed: int, i: int, *, engine: str = "scipy") -> SceneCase:
    """Random tangle ``i`` of ``seed``: three vehicles in contact at once at the start of the run-out.

    A first vehicle (any kind) moves off; a car lies against the side of one of its bodies, touching or
    overlapping it by up to 0.4 m (the crush of an impact), and a third vehicle lies against the car's
    other side the same way, the car pinned between them; the outer two move into it, the car drifts.
    Sometimes a guardrail lies beyond the third vehicle.  Every pair of bodies of different vehicles
    is apart except those two contacts.
    """
    from crashsim.motion import Obstacle

    rng = np.random.default_rng([seed, i, 31])
    for attempt in range(200):
        v0 = _renamed(_vehicle(rng, KINDS[int(rng.integers(len(KINDS)))]), "v0")
        h0 = _u(rng, -math.pi, math.pi)
        art = [float(rng.uniform(-0.4, 0.4) * h.articulation_limit) for h in v0.hitches]
        s0 = _u(rng, 3.0, 25.0)
        st0 = make_hitch_consistent(v0, chain_states(v0, np.zeros(2), h0, s0 * np.array([math.cos(h0), math.sin(h0)]),
                                                     [float(rng.normal(0, 0.3)) for _ in v0.bodies], art))
        host = v0.bodies[int(rng.integers(len(v0.bodies)))]
        hs = st0[host.name]
        side = 1.0 if rng.random() < 0.5 else -1.0  # left or right of the host body
        nx, ny = -math.sin(hs.heading) * side, math.cos(hs.heading) * side  # out of its side
        tx, ty = math.cos(hs.heading), math.sin(hs.heading)
        car_body, _ = _car(rng, "car")
        v1 = Vehicle("v1", (dataclasses.replace(car_body, name="v1_car"),))
        w0, w1 = host.width, car_body.width
        along = _u(rng, -0.35, 0.35) * host.length
        gap1 = -_u(rng, 0.0, 0.4) if rng.random() < 0.6 else 0.0  # overlap (crush) or touching
        h1 = hs.heading + _u(rng, -0.15, 0.15)
        c1 = np.array(hs.position) + along * np.array([tx, ty]) + (w0 / 2 + w1 / 2 + gap1) * np.array([nx, ny])
        vel1 = np.array(hs.velocity) * _u(rng, 0.0, 1.0) + _u(rng, -2.0, 2.0) * np.array([nx, ny])
        st1 = {"v1_car": BodyState(tuple(c1), h1, tuple(vel1), float(rng.normal(0, 0.3)))}
        v2 = _renamed(_vehicle(rng, KINDS[int(rng.integers(len(KINDS)))]), "v2")
        first = v2.bodies[0]
        gap2 = -_u(rng, 0.0, 0.4) if rng.random() < 0.6 else 0.0
        h2 = h1 + _u(rng, -0.3, 0.3) + (math.pi if rng.random() < 0.5 else 0.0)
        c2 = c1 + (w1 / 2 + first.width / 2 + gap2) * np.array([nx, ny]) + _u(rng, -1.0, 1.0) * np.array([tx, ty])
        s2 = _u(rng, 0.0, 15.0)
        into = -_u(rng, 0.5, 4.0) * np.array([nx, ny])  # into the car
        vel2 = s2 * np.array([math.cos(h2), math.sin(h2)]) + into
        art2 = [float(rng.uniform(-0.3, 0.3) * h.articulation_limit) for h in v2.hitches]
        st2 = make_hitch_consistent(v2, chain_states(v2, tuple(c2), h2, vel2, [0.0] * len(v2.bodies), art2))
        # the first vehicle pushes into the car too
        st0 = {n: BodyState(s.position, s.heading, tuple(np.array(s.velocity) + _u(rng, 0.5, 3.0) * np.array([nx, ny])),
                            s.yaw_rate) for n, s in st0.items()}
        st0 = make_hitch_consistent(v0, st0)
        polys = {n: _outline_world(b, st[n]) for v, st in ((v0, st0), (v1, st1), (v2, st2)) for b in v.bodies
                 for n in [b.name]}
        owner = {b.name: v.name for v in (v0, v1, v2) for b in v.bodies}
        touching = {(host.name, "v1_car"), ("v1_car", first.name)}
        ok = True
        for a in polys:
            for b in polys:
                if a < b and owner[a] != owner[b] and (a, b) not in touching and (b, a) not in touching:
                    if not _apart([polys[a]], [polys[b]], 0.3):
                        ok = False
        if ok:
            break
    vehicles = (v0, v1, v2)
    initial = {**st0, **st1, **st2}
    wheels = {v.name: _wheels(rng, v) for v in vehicles}
    obstacles = []
    if rng.random() < 0.4:  # a guardrail beyond the third vehicle
        off = np.dot(c2, [nx, ny]) + first.width / 2 + _u(rng, 1.0, 4.0)
        a = off * np.array([nx, ny]) - 40 * np.array([tx, ty])
        b = off * np.array([nx, ny]) + 40 * np.array([tx, ty])
        rail = Obstacle("rail", (tuple(a), tuple(b)), thickness=0.3)
        if all(_apart([p], rail.pieces(), 0.3) for p in polys.values()):
            obstacles.append(rail)
    lt = rng.random() < 0.3
    options = RunoutOptions(engine=engine, load_transfer=lt)
    road = _road(rng, np.zeros(2), h0, s0)
    vehicles, options, roll = _rollover(vehicles, options, seed, i, 33)
    label = (f"seed {seed} tangle {i}: {', '.join(str(len(v.bodies)) + ' bodies' for v in vehicles)}, overlaps "
             f"{-gap1:.2f} / {-gap2:.2f} m, {len(obstacles)} obstacle(s)" + (", load transfer" if lt else "") + roll)
    return SceneCase(label, vehicles, initial, wheels, road, options, tuple(obstacles))

"""The approach: a vehicle's motion before the impact (reaction, braking, possibly jack-knifing).

The approach of a vehicle is simulated with the same tyre model and engines as the run-out
(:func:`~crashsim.motion.simulate_runout`), from the **start of braking** to the impact:

* Before braking, during the driver's perception-reaction time ``reaction_time``, the vehicle
  keeps its speed (the constant-speed interval of a time-distance analysis); it is not
  simulated.
* From the start of braking (time 0 of the approach) the vehicle moves under its approach
  wheel settings: every wheel's state (locked, braked with a fraction, rolling), with
  scheduled changes at times after the start of braking (air-brake lag, trailer brakes that
  apply later, a wheel that locks later, brakes released).  An articulated vehicle can
  jack-knife on the way.
* The approach ends at the impact, found one of three ways:

  ``distance``
      the first body's CG has travelled this path length since the start of braking;
  ``time``
      this time has passed since the start of braking;
  ``start`` (a start position and heading, world frame)
      the first body's CG passes closest to its position at impact;
  ``path`` (a path to follow and a ``distance``)
      a driver (:mod:`crashsim.motion.driver`) steers the first unit along the path from the point
      ``distance`` before the impact position; the approach ends where the CG passes closest to
      its position at impact, as from a start position.

The approach may start in motion as it was: articulated at its hitches (``articulation``) and
yawing (``yaw_rates``), hitch-consistent (:func:`~crashsim.vehicles.chain_states`), e.g. a caravan
already swaying; ``solve_articulation`` finds the articulation at the start whose approach ends at
the impact configuration's articulation (Newton's method with a finite-difference Jacobian).

With ``distance`` or ``time`` the path is placed in the scene by the rigid motion that puts
the first body's CG and heading at the end of the approach on the impact configuration.  On a
uniform road the equations of motion do not change under a rigid motion of the plane, so the
placed path is itself a solution; where friction zones exist the approach is simulated again
from the placed start until the placement no longer moves (``_PLACEMENT_TOL``).  With a start
position nothing is moved: the miss of the impact position is reported, and more than
``tolerance`` is an error.

The speed at the start of braking is either given (the impact speed then follows) or solved
from the impact speed (the root of ``v_impact(v_braking) = v`` by Brent's method; the impact
speed grows with the braking speed).

Closed form (tests/analytic/test_approach.py): a straight slide on locked wheels over a
distance ``d`` at friction ``mu`` gives ``v_b^2 = v_i^2 + 2 mu g d``.
"""

from __future__ import annotations

import contextlib
import logging
import math
from dataclasses import dataclass, field, replace
from typing import Mapping

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from ..errors import ScenarioError, UnreachableImpactError
from ..vehicles import BodyState, Vehicle, chain_states
from .loads import STANDARD_GRAVITY
from .approach_spec import ApproachSpec, path_start
from .driver import SLIP_TIME, ackermann, pursuit_steer, reference_slip, steer_geometry
from .options import RunoutOptions
from .recorded import speed_demand, wheel_setting_for
from .postprocess import split_track
from .result import PATH_SAMPLES_PER_S, RunoutResult, WheelTrack, path_length
from .road import Road
from .runout import run_runout
from .wheels import ScheduledChange, WheelSettings

__all__ = ["ApproachResult", "simulate_approach", "approach_speed_at_braking", "continued_wheels"]

#: Placement of the approach path with friction zones: iterate until the start moves less than this [m].
_PLACEMENT_TOL = 1e-4


@dataclass(frozen=True, eq=False)
class ApproachResult:
    """The approach of one vehicle, from the driver's perception to the impact.

    Times ``t`` are relative to the impact (negative before it); path distances ``s`` are the
    first body's CG path length relative to the impact point (negative before it).

    Attributes
    ----------
    vehicle : str
    speed_at_braking, speed_at_impact : float
        First body's CG speed at the start of braking and at the impact [m/s].
    time_to_impact, distance : float
        Time [s] and CG path length [m] from the start of braking to the impact.
    reaction_time, reaction_distance : float
        Perception-reaction time [s] and the distance covered in it at constant speed [m].
    impact_states : dict of BodyState
        Every body's state at the impact from the approach (world; positions and headings of
        the placed path, velocities and yaw rates).
    bodies : dict of str to ndarray (n, 4)
        Per body, samples of (t, x, y, heading) of the braking phase, world frame.
    tracks : dict of str to WheelTrack
        Tyre tracks of the braking phase, world frame, times relative to the impact.
    braking_start : dict of str to (float, float)
        Each body's CG at the start of braking [m]; ``perception_point``: the first body's CG
        at the start of the reaction time.
    miss, heading_miss : float
        With a start position: distance of the closest CG pass from the impact position [m],
        and the heading difference there [rad]; 0 when the path was placed.
    articulation_at_impact : tuple of float
        Articulation angles at the end of the approach [rad] (the impact configuration in the
        file may differ: ``warnings`` says so).
    runout : RunoutResult
        The simulation (local frame, times from the start of braking, beyond the impact).
    steering : dict of str to ndarray, or None
        With a driver: at each of its updates ``t`` [s] (relative to the impact), the steer angle
        of the first axle's centre ``delta`` and of its wheels ``left``, ``right`` [rad], the
        reference point's arc length on the path ``s`` [m] and its offset from the path
        ``offset`` [m] (left positive); None without one.
    start_articulation : tuple of float
        Articulation angles at the start [rad] (given, or solved with ``solve_articulation``).
        With a recorded table's steering, ``steering`` holds ``t``, ``delta``, ``left``, ``right`` (no
        path, so no ``s`` or ``offset``).
    speed_control : dict of str to ndarray, or None
        With a recorded table's speeds: at each of the controller's updates ``t`` [s] (relative to the
        impact), the table's speed ``target`` and the first body's CG speed ``speed`` [m/s] there, and
        the longitudinal force coefficient ``demand`` [-] it set; None without one.
    """

    vehicle: str
    mode: str
    speed_at_braking: float
    speed_at_impact: float
    time_to_impact: float
    distance: float
    reaction_time: float
    reaction_distance: float
    impact_states: dict
    bodies: dict
    tracks: dict
    braking_start: dict
    perception_point: tuple
    miss: float
    heading_miss: float
    articulation_at_impact: tuple
    runout: RunoutResult = field(repr=False)
    speed_solved: bool = False
    warnings: tuple = ()
    placement: tuple = (0.0, 0.0, 0.0)  # (rotation [rad], x, y [m]): the run's frame -> the scene's
    steering: dict | None = field(default=None, repr=False)
    start_articulation: tuple = ()
    speed_control: dict | None = field(default=None, repr=False)

    def pose(self, body: str, t: float) -> tuple[tuple[float, float], float]:
        """``((x, y), heading)`` of ``body`` at time ``t`` relative to the impact [s, m, rad], scene
        frame: the braking phase from its dense output; before the start of braking the pose moves
        back at the speed at braking along the heading there (the reaction time, constant speed)."""
        phi, tx, ty = self.placement
        c, s_ = math.cos(phi), math.sin(phi)
        sol = self.runout.bodies[body].sol
        tb = float(t) + self.time_to_impact
        st = np.asarray(sol(max(tb, 0.0)), dtype=float)
        x, y = c * st[0] - s_ * st[1] + tx, s_ * st[0] + c * st[1] + ty
        if tb < 0.0:  # constant velocity before braking
            vx, vy = c * st[3] - s_ * st[4], s_ * st[3] + c * st[4]
            x, y = x + vx * tb, y + vy * tb
        return (float(x), float(y)), float(st[2] + phi)

    def speed_at(self, t, body: str | None = None) -> np.ndarray:
        """CG speed [m/s] of ``body`` (default the first) at times ``t`` relative to the impact
        (<= 0); constant before the start of braking (the reaction time and before)."""
        t = np.asarray(t, dtype=float)
        b = self.runout.bodies[body or next(iter(self.bodies))]
        tl = np.clip(t + self.time_to_impact, 0.0, self.time_to_impact)
        sv = np.asarray(b.sol(tl.ravel()))
        v = np.hypot(sv[3], sv[4]).reshape(tl.shape)
        v0 = float(np.hypot(*np.asarray(b.sol(0.0))[3:5]))
        return np.where(t < -self.time_to_impact, v0, v)

    def table(self, n: int = 201, *, dt: float | None = None) -> dict[str, np.ndarray]:
        """Time-distance-speed of the first body from perception to impact: ``t`` [s] relative to
        the impact, ``s`` [m] path distance relative to the impact point, ``v`` [m/s].

        ``n`` points over the braking phase after the perception point; or, with ``dt`` [s], every
        ``dt`` back from the impact (t = 0, -dt, -2 dt, ...) to the perception point, the reaction
        interval at constant speed included."""
        first = next(iter(self.bodies))
        sol = self.runout.bodies[first].sol
        if dt is not None:
            total = self.time_to_impact + self.reaction_time
            t = -np.arange(int(np.floor(total / dt + 1e-9)), -1, -1) * dt
            braking = t >= -self.time_to_impact
            tb = t[braking] + self.time_to_impact
            s = np.empty_like(t)
            v = np.full_like(t, self.speed_at_braking)
            if tb.size:
                s[braking] = path_length(sol, np.concatenate([[0.0], tb]))[1:] - self.distance  # from braking on
                sv = np.asarray(sol(tb))
                v[braking] = np.hypot(sv[3], sv[4])
            s[~braking] = -self.distance - (-self.time_to_impact - t[~braking]) * self.speed_at_braking
            return {"t": t, "s": s, "v": v}
        tb = np.linspace(0.0, self.time_to_impact, max(n, 2))
        s_b = path_length(sol, tb)
        t = np.concatenate([[-self.time_to_impact - self.reaction_time], tb - self.time_to_impact])
        s = np.concatenate([[-self.distance - self.reaction_distance], s_b - self.distance])
        sv = np.asarray(sol(tb))
        v = np.concatenate([[self.speed_at_braking], np.hypot(sv[3], sv[4])])
        return {"t": t, "s": s, "v": v}

    def to_dict(self) -> dict:
        return {
            "mode": self.mode,
            "speed_at_braking": self.speed_at_braking,
            "speed_solved": self.speed_solved,
            "speed_at_impact": self.speed_at_impact,
            "time_to_impact": self.time_to_impact,
            "distance": self.distance,
            "reaction_time": self.reaction_time,
            "reaction_distance": self.reaction_distance,
            "perception_point": list(self.perception_point),
            "braking_start": {k: list(v) for k, v in self.braking_start.items()},
            "miss": self.miss,
            "heading_miss": self.heading_miss,
            "articulation_at_impact": list(self.articulation_at_impact),
            "start_articulation": list(self.start_articulation),
            **({} if self.speed_control is None else {
                "max_speed_error": self.max_speed_error,
                "speed_control": {k: v.tolist() for k, v in self.speed_control.items()}}),
            **({} if self.steering is None else {
                "max_lateral_error": self.max_lateral_error,
                "max_steer": float(np.max(np.abs(self.steering["delta"]))) if len(self.steering["delta"]) else 0.0,
                "steering": {k: (v.tolist() if isinstance(v, np.ndarray) else [list(x) for x in v])
                             for k, v in self.steering.items()}}),
            "warnings": list(self.warnings),
        }

    def steer_at_impact(self) -> dict:
        """With a driver: the steered wheels' angles of its last update before the impact
        ``{wheel key: angle [rad]}``; empty without one."""
        if self.steering is None or "keys" not in self.steering:
            return {}
        k = int(np.searchsorted(self.steering["t"], 1e-12, side="right")) - 1
        return {key: float(self.steering["left" if side == "left" else "right"][max(k, 0)])
                for key, side in self.steering["keys"]}

    @property
    def max_lateral_error(self) -> float | None:
        """With a driver: the largest offset of the reference point from the path over the driver's
        updates up to the impact [m]; None without one."""
        if self.steering is None or "offset" not in self.steering:
            return None
        keep = self.steering["t"] <= 1e-12
        return float(np.max(np.abs(self.steering["offset"][keep]))) if np.any(keep) else 0.0

    @property
    def max_speed_error(self) -> float | None:
        """With a recorded table's speeds: the largest difference of the first body's CG speed from the
        table's at the controller's updates up to the impact [m/s]; None without one."""
        if self.speed_control is None:
            return None
        c = self.speed_control
        keep = c["t"] <= 1e-12
        return float(np.max(np.abs(c["speed"][keep] - c["target"][keep]))) if np.any(keep) else 0.0


def _run(vehicle: Vehicle, spec: ApproachSpec, speed: float, position, heading: float, road: Road,
         options: RunoutOptions, articulation=None) -> RunoutResult:
    """The braking phase from the start pose, long enough to reach the impact (not on to rest).

    The run is first limited to a time the impact is reached in when the vehicle brakes evenly
    (``2 d / v`` for a distance, the time itself plus a margin for a time); a run that stops on
    that limit short of the impact is run again with the limit doubled, up to ``options.t_max``.
    From a start position the run goes on to rest (the closest pass is found on it).
    """
    vel = speed * np.array([math.cos(heading), math.sin(heading)])
    init = chain_states(vehicle, position, heading, vel, spec.yaw_rates, articulation)

    if spec.mode == "distance":
        limit = 2.0 * spec.distance / speed + 0.1
    elif spec.mode == "time":
        limit = spec.time + 0.1
    else:  # from a start position: the end is the closest pass, found on the run to rest
        limit = options.t_max
    first = vehicle.bodies[0].name
    while True:
        limit = min(limit, options.t_max)
        run = run_runout([vehicle], init, {vehicle.name: spec.wheels}, road,
                         replace(options, t_max=limit)).vehicles[vehicle.name]
        if run.status != "time_limit" or limit >= options.t_max:
            return run
        if spec.mode == "time" and run.t_end >= spec.time:
            return run
        if spec.mode == "distance" and run.bodies[first].distance >= spec.distance:
            return run
        limit *= 2.0


class _TimeLimitExpected(logging.Filter):
    """Drops the engine's "did not reach rest (time_limit)" records: a driver's interval ends on its time
    limit by design."""

    def filter(self, record: logging.LogRecord) -> bool:
        return not (record.getMessage().startswith("run-out did not reach rest (time_limit)"))


@contextlib.contextmanager
def _expected_time_limits():
    log = logging.getLogger("crashsim")
    f = _TimeLimitExpected()
    log.addFilter(f)
    try:
        yield
    finally:
        log.removeFilter(f)


def continued_wheels(vehicle: Vehicle, approach: WheelSettings, t0: float, steer: Mapping[str, float] | None = None,
                     later: WheelSettings | None = None) -> WheelSettings:
    """The approach's wheel settings carried on from ``t0`` on a time line that starts there: the
    settings in force at ``t0`` (the steered wheels at ``steer``), its later changes and its air
    brakes moved by ``-t0`` (one time line through the impact: ``through_impact``), and the changes of
    ``later`` (the run-out's own, times after the impact) on top."""
    out = _segment_wheels(approach.resolve(vehicle), approach, t0, math.inf, steer or {})
    if later is None or not later.schedule:
        return out
    return replace(out, schedule=tuple(out.schedule) + tuple(later.schedule))


def _segment_wheels(resolved, wheels: WheelSettings, t0: float, t1: float, steer: Mapping[str, float],
                    control: Mapping[str, Mapping] | None = None) -> WheelSettings:
    """The wheel settings of ``[t0, t1)`` on a time line starting at ``t0``: those in force at ``t0``
    (the steered wheels at ``steer``, the wheels in ``control`` changed by it), the scheduled changes
    inside the interval and the air brakes moved by ``-t0``."""
    now = resolved.at(t0)
    control = control or {}
    base = {spec.key: replace(w, **({"steer": steer[spec.key]} if spec.key in steer else {}),
                              **control.get(spec.key, {}))
            for spec, w in zip(resolved.specs, now)}
    sched = [ScheduledChange(c.time - t0, c.wheels, c.changes) for c in wheels.schedule if t0 < c.time < t1]
    brakes = wheels.brakes
    if brakes is not None and t0 > 0.0:
        brakes = replace(brakes, apply=brakes.apply - t0, release=None if brakes.release is None else brakes.release - t0)
    return WheelSettings(wheels=base, schedule=sched, brakes=brakes)


def _steered_wheels(resolved, geom, first: str, claim: str, key: str) -> list:
    """The wheels of the first unit's steered axle, which the driver or a recorder's table steers: refused
    where the approach's own settings steer one of them too (``claim``, the message's start, takes the
    wheel's label)."""
    steered = [s for s in resolved.specs if s.body == first and s.axle_index == geom.axle]
    for t_ph, settings in resolved.phases:
        for s, w in zip(resolved.specs, settings):
            if s in steered and (w.steer != 0.0 or w.self_steer_limit is not None):
                raise ScenarioError(f"{claim.format(repr(s.label))} too (from {t_ph:g} s): remove steer / "
                                    "self_steer_limit there", field=f"{key}.wheels")
    return steered


def _decided_run(vehicle: Vehicle, start, resolved, spec: ApproachSpec, road: Road, options: RunoutOptions,
                 dt: float, decisions, t_max: float) -> RunoutResult:
    """The whole approach as one run from ``start``, the run a driven approach's result is read from:
    the file's settings with the first update's ``decisions`` (per update ``{wheel key: changes}``: steer
    angles, a speed controller's states), the later updates' as scheduled changes at ``k * dt``."""
    sched = [ScheduledChange(k * dt, key, changes) for k in range(1, len(decisions))
             for key, changes in decisions[k].items()]
    whole = _segment_wheels(resolved, spec.wheels, 0.0, math.inf, {}, decisions[0])
    whole = replace(whole, schedule=tuple(whole.schedule) + tuple(sched))
    return run_runout([vehicle], start, {vehicle.name: whole}, road, replace(options, t_max=t_max)).vehicles[
        vehicle.name]


def _driven_run(vehicle: Vehicle, spec: ApproachSpec, speed: float, target, road: Road, options: RunoutOptions,
                articulation=None) -> tuple[RunoutResult, dict]:
    """The approach steered by the driver (:mod:`crashsim.motion.driver`), and its steering record.

    Two passes: the driver's decisions first, one update interval at a time (each interval a run
    from the state at its start, the driver looking at that state), until the first body's CG has
    passed the impact position (or the vehicle rests, or the path is left behind); then the whole
    approach as one run from the start with those steer angles as scheduled wheel changes, the run
    the result is read from.  The two differ by the integrator's restarts only (its tolerance).
    """
    driver = spec.driver
    geom = steer_geometry(vehicle, driver.key)
    first = vehicle.bodies[0].name
    resolved = spec.wheels.resolve(vehicle)
    steered = _steered_wheels(resolved, geom, first, "the driver steers wheel {} along the path; its approach "
                              "settings steer it", spec.key)
    p0, h0, s_ref = path_start(vehicle, driver, target, spec.distance, spec.tolerance)
    vel = speed * np.array([math.cos(h0), math.sin(h0)])
    yaw_rates = spec.yaw_rates
    if yaw_rates is None:  # already turning with the path where it starts
        kappa = driver.path.curvature(s_ref, max(driver.min_preview, driver.preview_time * speed) / 2.0)
        yaw_rates = (speed * kappa,) * len(vehicle.bodies)
    start = chain_states(vehicle, p0, h0, vel, yaw_rates, articulation)
    dt = driver.update
    seg_opts = replace(options, t_max=dt)
    rec = {k: [] for k in ("t", "delta", "left", "right", "s", "offset")}
    wheel_angles = []
    delta_prev = None
    s_impact = s_ref + spec.distance
    state = start
    k = 0
    with _expected_time_limits():
        while True:
            t0 = k * dt
            cg = state[first]
            beta = reference_slip(geom, cg.heading, cg.velocity, cg.yaw_rate)
            slip = beta if k == 0 else slip + min(dt / SLIP_TIME, 1.0) * (beta - slip)
            raw, s_ref, offset = pursuit_steer(geom, driver, cg.position, cg.heading, float(np.hypot(*cg.velocity)),
                                               s_ref, slip)
            delta = min(max(raw, -driver.max_steer), driver.max_steer)
            if delta_prev is not None:
                step = driver.max_steer_rate * dt
                delta = min(max(delta, delta_prev - step), delta_prev + step)
            left, right = ackermann(geom, delta)
            angles = {s.key: (left if s.side == "left" else right) for s in steered}
            for key, val in zip(rec, (t0, delta, left, right, s_ref, offset)):
                rec[key].append(val)
            wheel_angles.append(angles)
            delta_prev = delta
            seg = _segment_wheels(resolved, spec.wheels, t0, t0 + dt, angles)
            run = run_runout([vehicle], state, {vehicle.name: seg}, road, seg_opts).vehicles[vehicle.name]
            state = {b.name: run.bodies[b.name].final for b in vehicle.bodies}
            k += 1
            # past the impact: the reference point (behind the CG) 2 m beyond the impact position's place on the path
            if run.status != "time_limit" or k * dt >= options.t_max or s_ref > s_impact + 2.0:
                break  # at rest, a solver failure, the time limit, or past the impact
        # the whole approach: the file's settings with the first steer angles, the driver's later ones scheduled
        run = _decided_run(vehicle, start, resolved, spec, road, options, dt,
                           [{key: {"steer": a} for key, a in angles.items()} for angles in wheel_angles], k * dt)
    out = {key: np.asarray(v, dtype=float) for key, v in rec.items()}
    out["keys"] = tuple((s.key, s.side) for s in steered)
    return run, out


def _recorded_run(vehicle: Vehicle, spec: ApproachSpec, speed: float, position, heading: float, road: Road,
                  options: RunoutOptions, articulation=None) -> tuple[RunoutResult, dict | None, dict | None]:
    """The approach driven by a recorder's table (:mod:`crashsim.motion.recorded`): ``(run, steering,
    speed_control)``, the records None where the table gives no steering or no speeds.

    Steering alone is open loop: one run with the steer angles as scheduled changes.  With speeds, the
    controller decides one ``update`` interval at a time (each a run from the state at its start), and
    the whole approach is then run once with its decisions as scheduled changes, as the path driver's.
    """
    drive = spec.recorded
    first = vehicle.bodies[0].name
    resolved = spec.wheels.resolve(vehicle)
    dt = drive.update
    n = int(math.ceil(drive.duration / dt - 1e-9)) + 1  # updates: past the impact by less than one interval
    times = np.arange(n) * dt
    angles = [{} for _ in range(n)]
    steering = None
    if drive.steer is not None:
        geom = steer_geometry(vehicle, f"{spec.key}.recorded")
        steered = _steered_wheels(resolved, geom, first, "the recorded steering steers wheel {}; the approach "
                                  "settings steer it", spec.key)
        delta = drive.steer_at(times)
        lr = [ackermann(geom, float(d)) for d in delta]
        angles = [{s.key: (left if s.side == "left" else right) for s in steered} for left, right in lr]
        steering = {"t": times.copy(), "delta": delta, "left": np.array([a for a, _ in lr]),
                    "right": np.array([b for _, b in lr]), "keys": tuple((s.key, s.side) for s in steered)}
    vel = speed * np.array([math.cos(heading), math.sin(heading)])
    start = chain_states(vehicle, position, heading, vel, spec.yaw_rates, articulation)
    controls = [{} for _ in range(n)]
    speed_control = None
    if drive.speed is not None:
        rec = {k: [] for k in ("t", "target", "speed", "demand")}
        seg_opts = replace(options, t_max=dt)
        state = start
        with _expected_time_limits():
            for k in range(n):
                t0 = float(times[k])
                cg = state[first]
                v = float(np.hypot(*cg.velocity))
                d = speed_demand(drive, t0, v)
                mu = float(road.mu_at(np.asarray([cg.position]))[0])
                controls[k] = {s.key: wheel_setting_for(d, w.rolling_resistance or 0.0, mu * w.mu_factor)
                               for s, w in zip(resolved.specs, resolved.at(t0)) if w.state in ("rolling", "braked")}
                for key, val in zip(rec, (t0, float(drive.speed_at(t0)), v, d)):
                    rec[key].append(val)
                seg = _segment_wheels(resolved, spec.wheels, t0, t0 + dt, angles[k], controls[k])
                run = run_runout([vehicle], state, {vehicle.name: seg}, road, seg_opts).vehicles[vehicle.name]
                state = {b.name: run.bodies[b.name].final for b in vehicle.bodies}
                if run.status != "time_limit":
                    n = k + 1  # at rest, or a solver failure: the whole run shows it
                    break
        speed_control = {key: np.asarray(v, dtype=float) for key, v in rec.items()}
    decisions = [{key: {**({"steer": angles[k][key]} if key in angles[k] else {}), **controls[k].get(key, {})}
                  for key in dict.fromkeys([*angles[k], *controls[k]])} for k in range(n)]
    with _expected_time_limits():
        run = _decided_run(vehicle, start, resolved, spec, road, options, dt, decisions,
                           min(max(n * dt, drive.duration + dt), options.t_max))
    if steering is not None:
        steering = {k: (v[:n] if isinstance(v, np.ndarray) else v) for k, v in steering.items()}
    return run, steering, speed_control


def _end_time(run: RunoutResult, spec: ApproachSpec, vehicle: Vehicle, target) -> tuple[float, float]:
    """(time of the impact from the start of braking, CG path length to it)."""
    first = vehicle.bodies[0].name
    b = run.bodies[first]
    t_end = run.t_end
    grid = np.linspace(0.0, t_end, max(int(t_end * PATH_SAMPLES_PER_S), 16) + 1)
    s = path_length(b.sol, grid)
    if spec.mode == "distance":
        if s[-1] < spec.distance:
            raise UnreachableImpactError(
                f"the vehicle stops {s[-1]:.2f} m after the start of braking, before the impact (distance = "
                f"{spec.distance:.2f} m): the approach does not reach the impact; raise the speed at braking or "
                "shorten the distance", field=f"{spec.key}.distance")
        ti = float(np.interp(spec.distance, s, grid))
        return ti, float(spec.distance)
    if spec.mode in ("time", "recorded"):
        if run.status == "rest" and (b.time_to_rest or t_end) < spec.time:
            raise UnreachableImpactError(
                f"the vehicle stops {b.time_to_rest or t_end:.3f} s after the start of braking, before the impact "
                f"(time = {spec.time:.3f} s): the approach does not reach the impact", field=f"{spec.key}.time")
        if spec.time > t_end:
            raise UnreachableImpactError(f"the approach simulation ended ({run.status}) at {t_end:.3f} s, before time = "
                                f"{spec.time:.3f} s", field=f"{spec.key}.time")
        return float(spec.time), float(np.interp(spec.time, grid, s))
    sv = np.asarray(b.sol(grid))
    d = np.hypot(sv[0] - target[0], sv[1] - target[1])
    k = int(np.argmin(d))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]

    if hi > lo:
        r = minimize_scalar(lambda tt: float(np.hypot(*(np.asarray(b.sol(tt))[:2] - target))), bounds=(lo, hi),
                            method="bounded", options={"xatol": 1e-9})
        ti = float(r.x)
    else:
        ti = float(grid[k])
    return ti, float(np.interp(ti, grid, s))


def _trim_track(w: WheelTrack, ti: float, R: np.ndarray, T: np.ndarray) -> WheelTrack:
    keep = w.t <= ti + 1e-12
    t = w.t[keep] - ti
    pts = w.points[keep] @ R.T + T
    sliding = w.sliding[keep]
    segs = split_track(t, pts, sliding)
    path = float(np.sum(np.hypot(*np.diff(pts, axis=0).T))) if len(pts) > 1 else 0.0
    slide = sum(s.length for s in segs if s.kind == "sliding")
    return replace(w, t=t, points=pts, sliding=sliding, load=w.load[keep], segments=segs, path_length=path,
                   sliding_length=float(slide), energy=math.nan)


def simulate_approach(vehicle: Vehicle, spec: ApproachSpec, impact_states: Mapping[str, BodyState], road: Road,
                      options: RunoutOptions, *, speed_at_impact: float | None = None) -> ApproachResult:
    """Simulate a vehicle's approach from the start of braking to the impact.

    Parameters
    ----------
    vehicle : Vehicle
    spec : ApproachSpec
    impact_states : mapping of BodyState
        The impact configuration of the vehicle's bodies (positions and headings are used).
    road : Road
    options : RunoutOptions
    speed_at_impact : float, optional
        Needed when ``spec.speed`` is None: the speed at braking is then solved from it.

    Raises
    ------
    ScenarioError
        The approach does not reach the impact (the vehicle stops first, or passes the impact
        position further than ``spec.tolerance`` away), or a speed cannot be solved.
    """
    solved = spec.speed is None
    if solved:
        if speed_at_impact is None:
            raise ScenarioError("give the speed at the start of braking (approach.speed) or the speed at impact",
                                field=f"{spec.key}.speed")
        speed = approach_speed_at_braking(vehicle, spec, impact_states, road, options, speed_at_impact)
    else:
        speed = float(spec.speed)
    res = _approach_full(vehicle, spec, impact_states, road, options, speed)
    return replace(res, speed_solved=solved)


def _approach_full(vehicle, spec, impact_states, road, options, speed) -> ApproachResult:
    """:func:`_approach`, with the articulation at the start solved where the spec asks for it."""
    if not spec.solve_articulation or len(vehicle.bodies) < 2:
        return _approach(vehicle, spec, impact_states, road, options, speed)
    return solve_start_articulation(vehicle, spec, impact_states, road, options, speed)


def impact_articulation(vehicle: Vehicle, impact_states) -> np.ndarray:
    """Articulation angles of the impact configuration [rad], front to rear."""
    return np.array([float(impact_states[a.name].heading - impact_states[b.name].heading)
                     for a, b in zip(vehicle.bodies[:-1], vehicle.bodies[1:])])


def solve_start_articulation(vehicle, spec, impact_states, road, options, speed, *, tol: float = 1e-6,
                             max_iter: int = 12) -> ApproachResult:
    """The approach whose articulation at the end is the impact configuration's, by the articulation
    at the start (``spec.articulation`` the first guess, else the impact's): Newton's method with a
    forward-difference Jacobian, each step halved while it does not reduce the miss.

    Raises
    ------
    ScenarioError
        No articulation at the start within the hitches' stops reaches it (the end articulation does
        not depend enough on the start's: give yaw_rates, or the articulation itself).
    """
    target = impact_articulation(vehicle, impact_states)
    limits = np.array([h.articulation_limit if h.articulation_limit is not None else math.pi
                       for h in vehicle.hitches])
    x = np.array(spec.articulation if spec.articulation is not None else target, dtype=float)

    def run(a):
        res = _approach(vehicle, spec, impact_states, road, options, speed, articulation=tuple(a))
        return res, np.asarray(res.articulation_at_impact) - target

    res, r = run(x)
    h = 1e-4
    for _ in range(max_iter):
        if float(np.max(np.abs(r))) < tol:
            return res
        J = np.empty((len(x), len(x)))
        for j in range(len(x)):
            dx = np.zeros_like(x)
            dx[j] = h
            J[:, j] = (run(x + dx)[1] - r) / h
        try:
            step = -np.linalg.solve(J, r)
        except np.linalg.LinAlgError:
            break
        lam = 1.0
        for _ in range(6):
            xn = np.clip(x + lam * step, -limits, limits)
            rn_res, rn = run(xn)
            if np.max(np.abs(rn)) < np.max(np.abs(r)):
                x, res, r = xn, rn_res, rn
                break
            lam *= 0.5
        else:
            break
    if float(np.max(np.abs(r))) < tol:
        return res
    raise ScenarioError(
        f"no articulation at the start within the hitches' stops ends the approach at the impact configuration's "
        f"articulation {np.round(np.degrees(target), 2).tolist()} deg (closest: "
        f"{np.round(np.degrees(target + r), 2).tolist()} deg from a start at {np.round(np.degrees(x), 2).tolist()} "
        "deg); give yaw_rates at the start, or the articulation itself without solve_articulation",
        field=f"{spec.key}.solve_articulation")


def _approach(vehicle, spec, impact_states, road, options, speed, articulation=None) -> ApproachResult:
    first = vehicle.bodies[0].name
    target = np.asarray(impact_states[first].position, dtype=float)
    h_imp = float(impact_states[first].heading)
    articulation = spec.articulation if articulation is None else articulation
    steering = speed_control = None
    if spec.mode == "start":
        p0, h0 = np.asarray(spec.start_position, float), float(spec.start_heading)
        run = _run(vehicle, spec, speed, p0, h0, road, options, articulation)
        ti, dist = _end_time(run, spec, vehicle, target)
        R, T = np.eye(2), np.zeros(2)
    elif spec.mode == "path":
        run, steering = _driven_run(vehicle, spec, speed, target, road, options, articulation)
        ti, dist = _end_time(run, spec, vehicle, target)
        steering = {k: (v - ti if k == "t" else v) for k, v in steering.items()}
        R, T = np.eye(2), np.zeros(2)
    else:
        # first guess: straight back along the impact heading; placed exactly by a rigid motion
        guess = spec.distance if spec.distance is not None else speed * spec.time
        p0 = target - guess * np.array([math.cos(h_imp), math.sin(h_imp)])
        h0 = h_imp
        for _ in range(8):
            if spec.recorded is not None:
                run, steering, speed_control = _recorded_run(vehicle, spec, speed, p0, h0, road, options,
                                                             articulation)
            else:
                run = _run(vehicle, spec, speed, p0, h0, road, options, articulation)
            ti, dist = _end_time(run, spec, vehicle, target)
            end = np.asarray(run.bodies[first].sol(ti))
            phi = h_imp - float(end[2])
            c, s_ = math.cos(phi), math.sin(phi)
            R = np.array([[c, -s_], [s_, c]])
            T = target - R @ end[:2]
            new_p0, new_h0 = R @ p0 + T, h0 + phi
            moved = float(np.hypot(*(new_p0 - p0)))
            if not road.zones or (moved < _PLACEMENT_TOL and abs(phi) < 1e-6):
                break
            p0, h0 = new_p0, new_h0
        else:
            raise ScenarioError("the approach path could not be placed on the impact configuration with the friction "
                                f"zones (the start still moved {moved:.3g} m)", field=spec.key)
        if steering is not None:
            steering = {k: (v - ti if k == "t" else v) for k, v in steering.items()}
        if speed_control is not None:
            speed_control = {k: (v - ti if k == "t" else v) for k, v in speed_control.items()}
    states, bodies, start = {}, {}, {}
    for b in vehicle.bodies:
        br = run.bodies[b.name]
        e = np.asarray(br.sol(ti))
        vel = R @ e[3:5]
        pos = R @ e[:2] + T
        head = float(e[2]) + math.atan2(R[1, 0], R[0, 0])
        states[b.name] = BodyState((float(pos[0]), float(pos[1])), head, (float(vel[0]), float(vel[1])), float(e[5]))
        h = br.history
        keep = h.t <= ti
        xy = np.column_stack([h.x[keep], h.y[keep]]) @ R.T + T
        rows = np.column_stack([h.t[keep] - ti, xy, h.heading[keep] + math.atan2(R[1, 0], R[0, 0])])
        rows = np.vstack([rows, [0.0, pos[0], pos[1], head]])
        bodies[b.name] = rows
        start[b.name] = tuple(float(v) for v in rows[0, 1:3])
    v_imp = float(np.hypot(*states[first].velocity))
    heading_first = states[first].heading
    perception = np.asarray(start[first]) - speed * spec.reaction_time * np.array(
        [math.cos(bodies[first][0, 3]), math.sin(bodies[first][0, 3])])
    miss, hmiss = 0.0, 0.0
    warnings = []
    if spec.mode in ("start", "path"):
        miss = float(np.hypot(*(np.asarray(states[first].position) - target)))
        hmiss = float((heading_first - h_imp + math.pi) % (2 * math.pi) - math.pi)
        if miss > spec.tolerance:
            where = "from start_position" if spec.mode == "start" else "along the path"
            raise UnreachableImpactError(
                f"the approach {where} passes the impact position {miss:.2f} m away at its closest "
                f"(tolerance {spec.tolerance:.2f} m): it does not reach the impact configuration",
                field=f"{spec.key}.start_position" if spec.mode == "start" else f"{spec.key}.path")
    art = tuple(float(states[a.name].heading - states[b.name].heading)
                for a, b in zip(vehicle.bodies[:-1], vehicle.bodies[1:]))
    for i, ((a, b), given) in enumerate(zip(zip(vehicle.bodies[:-1], vehicle.bodies[1:]),
                                            impact_articulation(vehicle, impact_states))):
        if abs(art[i] - given) > math.radians(2.0):
            warnings.append(f"the approach ends with articulation {math.degrees(art[i]):.1f} deg at the hitch "
                            f"{a.name}/{b.name}; the impact configuration has {math.degrees(given):.1f} deg")
    if spec.mode in ("start", "path") and abs(hmiss) > math.radians(2.0):
        warnings.append(f"the approach reaches the impact position with heading {math.degrees(hmiss):+.1f} deg off "
                        "the impact configuration")
    tracks = {k: _trim_track(w, ti, R, T) for k, w in run.wheels.items()}
    return ApproachResult(
        vehicle=vehicle.name, mode=spec.mode, speed_at_braking=speed, speed_at_impact=v_imp, time_to_impact=ti,
        distance=dist, reaction_time=spec.reaction_time, reaction_distance=speed * spec.reaction_time,
        impact_states=states, bodies=bodies, tracks=tracks, braking_start=start,
        perception_point=(float(perception[0]), float(perception[1])), miss=miss, heading_miss=hmiss,
        articulation_at_impact=art, runout=run, warnings=tuple(warnings),
        placement=(math.atan2(R[1, 0], R[0, 0]), float(T[0]), float(T[1])), steering=steering,
        start_articulation=tuple(float(a) for a in (articulation or (0.0,) * (len(vehicle.bodies) - 1))),
        speed_control=speed_control)


def approach_speed_at_braking(vehicle: Vehicle, spec: ApproachSpec, impact_states, road: Road, options: RunoutOptions,
                              speed_at_impact: float, *, xtol: float = 1e-9) -> float:
    """The speed at the start of braking [m/s] whose approach reaches the impact at ``speed_at_impact``.

    Brent's method on ``v_impact(v_b) - speed_at_impact`` (``v_impact`` grows with ``v_b``).
    """
    if not (speed_at_impact > 0.0):
        raise ScenarioError(f"solving the speed at braking needs a moving vehicle at impact, got "
                            f"{speed_at_impact} m/s", field=f"{spec.key}.speed")
    mu = max([road.mu] + [z.mu for z in road.zones])
    if spec.mode == "start":  # the path is at least the straight line to the impact position
        first = vehicle.bodies[0].name
        reach = float(np.hypot(*(np.asarray(spec.start_position) - np.asarray(impact_states[first].position))))
    else:
        reach = spec.distance

    def f(v):
        try:
            return _approach_full(vehicle, spec, impact_states, road, options, v).speed_at_impact - speed_at_impact
        except UnreachableImpactError:
            return -speed_at_impact  # stops before the impact: far too slow

    lo = speed_at_impact
    if reach is not None:
        hi = math.sqrt(speed_at_impact ** 2 + 2.0 * STANDARD_GRAVITY * 1.2 * mu * reach) + 1.0
    else:
        hi = speed_at_impact + 1.2 * mu * STANDARD_GRAVITY * spec.time + 1.0
    flo = f(lo)
    if flo >= 0.0:
        return lo
    for _ in range(20):
        fhi = f(hi)
        if fhi > 0.0:
            break
        hi *= 1.5
    else:
        raise UnreachableImpactError(f"no speed at braking up to {hi:.1f} m/s reaches the impact at {speed_at_impact:.2f} m/s",
                            field=f"{spec.key}.speed")
    return float(brentq(f, lo, hi, xtol=xtol, rtol=4 * np.finfo(float).eps))

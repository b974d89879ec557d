"""Run-out to rest with ``scipy.integrate.solve_ivp``: events, piecewise integration, results.

How a run proceeds
------------------
The time axis is cut into **segments** in which every input is constant: wheel settings
(cut at the scheduled change times), the friction zone each wheel is in, and the closed
articulation stops.  Each segment is one ``solve_ivp`` call with these terminal events:

* ``rest``: ``max over bodies of max(|v_cg|, |yaw rate| L_ref) - v_stop`` falling through
  zero (note sec. 3.3).  ``L_ref`` is half the body length, or the distance from the CG to
  its farthest contact if no length is given (at least 0.5 m).  The max runs over all
  bodies, so an articulated vehicle stops only when every body has stopped;
* ``zone``: for every friction zone, ``min over wheels of side_k * d_k + 1e-10 m``, where
  ``d_k`` is the signed distance of contact k to the zone polygon (positive inside, continuous
  across edges) and ``side_k = +1/-1`` the side the wheel is on in this segment.  It is
  positive while every wheel stays on its side and falls through zero when the first wheel
  crosses an edge (located 0.1 nm past the edge by the solver's root finder on the dense
  output); the integration then restarts with the new mu.  One event per zone instead of
  one per wheel and zone keeps the per-step cost low.  Membership at every restart is
  recomputed from the positions (a wheel within 1 nm of an edge is assigned by the
  direction it moves), so simultaneous crossings (left and right wheel of an axle) are not
  lost;
* ``stop``: the articulation angle of a hitch with ``articulation_limit`` reaching
  ``+-limit``.  **Articulation limit handling:** the stop is treated as a perfectly plastic,
  one-sided contact.  At the event the relative yaw rate is removed by an impulsive
  projection in the kinetic-energy metric (momentum-conserving, energy-dissipating, logged
  as an event with the energy lost), and a constraint row ``theta = +-limit`` is added, whose
  multiplier is the stop moment.  The stop opens again (``stop_open`` event) when that
  moment would have to pull the bodies together.  A stiff spring was not used: it needs a
  stiffness nobody knows and makes the equations stiff.

The run ends with status ``"rest"``, ``"time_limit"`` (``options.t_max`` reached while still
moving) or ``"solver_failure"`` (solve_ivp's message is kept).  Barrier vehicles (infinite
mass) are not simulated.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Callable, Iterable, Mapping

import numpy as np
from scipy.integrate import solve_ivp

from ..errors import ScenarioError, SolverError
from ..vehicles import BodyState, Vehicle
from .dynamics import RunoutModel, SegmentParams, check_pin_gaps, hitch_state, project_velocities
from .options import MAX_STILL_SEGMENTS, STOP_HYSTERESIS, RunoutOptions
from .postprocess import assemble_result, gauss_legendre_chunks
from .result import RunoutEvent, RunoutResult, limit_message
from .road import Road
from .wheels import WheelSettings

__all__ = ["simulate_runout", "simulate_scene", "check_hitch_consistency", "zone_membership"]

_log = logging.getLogger("crashsim")

# A wheel closer than this to a zone edge at a restart is "on" it [m].
_ZONE_TOL = 1e-9
# A zone event fires when a wheel is this far past an edge [m] (< _ZONE_TOL, so the restart
# assigns the new side from the direction of motion).
_ZONE_OVERSHOOT = 1e-10
# Initial pin-velocity mismatch accepted without make_hitch_consistent [m/s], relative to (1 + speed).
_PIN_VELOCITY_TOL = 1e-6
# Initial pin gap accepted [m].
_PIN_GAP_TOL = 1e-3
# The wall clock is read every this many right-hand-side evaluations.
_WALL_CHECK_EVALUATIONS = 256


def check_hitch_consistency(model: RunoutModel, y: np.ndarray) -> None:
    """Raise ScenarioError if the initial state violates a hitch (pin gap, pin velocity, articulation limit)."""
    if not model.n_hitches:
        return
    L = model.layout
    _, gaps, pin_speeds = hitch_state(model.vehicle, L, y)
    check_pin_gaps(model.vehicle, gaps, _PIN_GAP_TOL)
    allowed = _PIN_VELOCITY_TOL * (1.0 + float(np.max(np.hypot(y[L.vx], y[L.vy]))))
    names = L.bodies
    for j, mismatch in enumerate(pin_speeds):
        if mismatch > allowed:
            raise ScenarioError(
                f"pin velocities of {names[j]!r} and {names[j + 1]!r} differ by {mismatch:.4g} m/s (allowed <= "
                f"{allowed:.3g} m/s); make the states hitch-consistent first with "
                "crashsim.motion.make_hitch_consistent()",
                field=f"initial[{names[j + 1]!r}].velocity",
            )
    psi = y[L.psi]
    for j, hitch in enumerate(model.vehicle.hitches):
        if hitch.articulation_limit is None:
            continue
        theta = math.remainder(float(psi[j] - psi[j + 1]), 2 * math.pi)
        if abs(theta) > hitch.articulation_limit + 1e-9:
            raise ScenarioError(
                f"initial articulation {math.degrees(theta):.2f} deg exceeds the limit "
                f"+-{math.degrees(hitch.articulation_limit):.2f} deg (articulation_limit)",
                field=f"initial[{names[j + 1]!r}].heading",
            )


def zone_membership(model: RunoutModel, y: np.ndarray) -> np.ndarray:
    """Which friction zone every wheel is in, shape (n_wheels, n_zones).

    A wheel within ``1e-9 m`` of a zone edge is assigned by where its contact point is
    heading (1 micrometre ahead along its velocity), so a restart exactly at a crossing
    assigns the new zone.
    """
    zones = model.road.zones
    pos = model.wheel_positions(y)
    out = np.zeros((len(pos), len(zones)), dtype=bool)
    if not zones:
        return out
    vel = model.wheel_velocities(y)
    speed = np.hypot(vel[:, 0], vel[:, 1])
    ahead = pos + vel * (1e-6 / np.maximum(speed, 1e-300))[:, None]
    for z, zone in enumerate(zones):
        d = zone.signed_distance(pos)
        d_ahead = zone.signed_distance(ahead)
        near = np.abs(d) < _ZONE_TOL
        out[:, z] = np.where(near, np.where(speed > 0, d_ahead > 0, d >= 0), d > 0)
    return out


class _Event:
    """A terminal solve_ivp event with a label."""

    terminal = True

    def __init__(self, fn: Callable, direction: float, kind: str, index=None):
        self.fn = fn
        self.direction = direction
        self.kind = kind
        self.index = index

    def __call__(self, t, y):
        return self.fn(t, y)


class _ZoneDistances:
    """Signed distances of all wheels to all zones, computed once per solver state.

    solve_ivp evaluates every event function with the same ``(t, y)`` objects after a step, so
    the cache key is the time and the identity of ``y`` (a reference is kept, so the identity
    cannot be reused by another array).
    """

    def __init__(self, model: RunoutModel):
        self.model = model
        self.zones = model.road.zones
        self._t = None
        self._y = None
        self._value = None

    def __call__(self, t, y):
        if y is not self._y or t != self._t:
            pos = self.model.wheel_positions(y)
            self._value = np.stack([z.signed_distance(pos) for z in self.zones], axis=1)
            self._t, self._y = t, y
        return self._value


@dataclass
class _Run:
    """Mutable bookkeeping of one integration."""

    segments: list = field(default_factory=list)  # (t0, t1, OdeSolution, SegmentParams)
    events: list = field(default_factory=list)
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    status: str = ""
    message: str = ""


class _PiecewiseSolution:
    """Dense solution over all segments: ``sol(t)`` -> state(s).

    Times are clipped to the run, ``[0, t_end]``: before separation the initial state, after
    the end the final (rest) state.  At a segment boundary the later segment is used (the
    state after a stop impact).
    """

    def __init__(self, segments, y_end: np.ndarray, t_end: float):
        self._starts = np.array([s[0] for s in segments]) if segments else np.zeros(0)
        self._sols = [s[2] for s in segments]
        self._y_end = y_end
        self._t_end = t_end

    def __call__(self, t):
        t_arr = np.asarray(t, dtype=float)
        flat = np.clip(np.atleast_1d(t_arr).ravel(), 0.0, self._t_end)
        out = np.empty((self._y_end.size, flat.size))
        if not self._sols:
            out[:] = self._y_end[:, None]
        else:
            idx = np.clip(np.searchsorted(self._starts, flat, side="right") - 1, 0, len(self._sols) - 1)
            for i in np.unique(idx):
                mask = idx == i
                out[:, mask] = np.asarray(self._sols[i](flat[mask])).reshape(self._y_end.size, -1)
        return out[:, 0] if t_arr.ndim == 0 else out.reshape((self._y_end.size,) + t_arr.shape)


class _Budget(Exception):
    """Raised inside the right-hand side when a run-out exhausts a work limit (``kind``)."""

    def __init__(self, kind: str):
        self.kind = kind


class _Meter:
    """Counts right-hand-side evaluations over a whole run and watches the wall clock."""

    def __init__(self, options: RunoutOptions):
        self.max_evaluations = int(options.max_evaluations)
        self.deadline = time.perf_counter() + options.max_wall_time
        self.nfev = 0

    def tick(self, k: int = 1) -> None:
        self.nfev += k
        if self.nfev >= self.max_evaluations:
            raise _Budget("evaluation_limit")
        if self.nfev % _WALL_CHECK_EVALUATIONS == 1 and time.perf_counter() > self.deadline:
            raise _Budget("wall_time_limit")


def _left_stop_shift(y: np.ndarray, layout, j: int, offset: float, limit: float, shift: float) -> float:
    """Raised threshold of the stop of hitch ``j`` when it is left: past where it was left, plus STOP_HYSTERESIS."""
    excess = abs(float(y[layout.psi][j] - y[layout.psi][j + 1]) - offset) - limit
    return max(shift, excess) + STOP_HYSTERESIS


def _segment_events(model: RunoutModel, seg: SegmentParams, offsets: np.ndarray, shifts: np.ndarray) -> list[_Event]:
    L = model.layout
    v_stop = model.options.v_stop
    events = [_Event(lambda t, y: model.rest_measure(y) - v_stop, -1.0, "rest")]
    if model.road.zones:
        dist = _ZoneDistances(model)
        side = np.where(seg.membership, 1.0, -1.0)  # +1 inside, -1 outside, per wheel and zone
        for z in range(len(model.road.zones)):
            # min over wheels of side * distance is > 0 while every wheel stays on its side and
            # falls through -_ZONE_OVERSHOOT when the first wheel crosses an edge of zone z
            events.append(
                _Event(lambda t, y, z=z: float(np.min(side[:, z] * dist(t, y)[:, z])) + _ZONE_OVERSHOOT, -1.0, "zone", z)
            )
    locked = {j for j, _ in seg.locks}
    for j, hitch in enumerate(model.vehicle.hitches):
        lim = hitch.articulation_limit
        if lim is None or j in locked:
            continue
        psi = L.psi
        off = offsets[j]
        reach = lim + shifts[j]  # the stop fires past its limit plus the threshold raised when it was last left
        # bind j, off and reach now (a closure would see the last hitch's values)
        events.append(
            _Event(lambda t, y, j=j, off=off, r=reach: y[psi][j] - y[psi][j + 1] - off - r, 1.0, "stop", (j, 1.0))
        )
        events.append(
            _Event(lambda t, y, j=j, off=off, r=reach: y[psi][j] - y[psi][j + 1] - off + r, -1.0, "stop", (j, -1.0))
        )
    nh = model.n_hitches
    for n, (j, theta_lock) in enumerate(seg.locks):
        sign = math.copysign(1.0, theta_lock - offsets[j])

        def pull(t, y, n=n, sign=sign):
            return float(model.evaluate(y[:, None], seg, full=False).lam[0, 2 * nh + n]) * sign

        events.append(_Event(pull, 1.0, "release", (n, j)))
    return events


def _integrate(model: RunoutModel, y0: np.ndarray) -> tuple[_Run, float, np.ndarray, np.ndarray]:
    """Integrate segment by segment; returns the bookkeeping, end time, end state and initial state."""
    o = model.options
    L = model.layout
    run = _Run()
    t = 0.0
    y = y0.copy()
    membership = zone_membership(model, y)
    locks: list[tuple[int, float]] = []
    psi0 = y[L.psi]
    raw = psi0[:-1] - psi0[1:]
    offsets = raw - np.remainder(raw + math.pi, 2 * math.pi) + math.pi  # 2 pi k per hitch
    stops = sorted({tc for tc in model.wheels.change_times if tc < o.t_max} | {o.t_max})
    if L.accel is not None:
        y = model.consistent_accelerations(y, model.segment(t, membership, locks))
    y_initial = y.copy()
    shifts = np.zeros(model.n_hitches)
    meter = _Meter(o)
    restarts = still = 0

    def last_event():
        return run.events[-1].detail if run.events else None

    while True:
        if model.rest_measure(y) <= o.v_stop:
            run.status, run.message = "rest", f"all bodies below v_stop = {o.v_stop} m/s at t = {t:.4f} s"
            break
        if restarts >= o.max_segments:
            run.status, run.message = "event_limit", limit_message("event_limit", o, t, last_event=last_event())
            break
        if still >= MAX_STILL_SEGMENTS:
            run.status, run.message = "event_limit", limit_message("no_progress", o, t, last_event=last_event())
            break
        restarts += 1
        t_stop = next(s for s in stops if s > t)
        seg = model.segment(t, membership, locks)
        events = _segment_events(model, seg, offsets, shifts)
        first = None if o.first_step is None else min(o.first_step, t_stop - t)

        def rhs(tt, yy, seg=seg):
            meter.tick(1 if yy.ndim == 1 else yy.shape[1])
            return model.rhs(tt, yy, seg)

        try:
            sol = solve_ivp(
                rhs,
                (t, t_stop),
                y,
                method=o.method,
                rtol=o.rtol,
                atol=o.atol,
                max_step=o.max_step,
                first_step=first,
                events=events,
                dense_output=True,
                vectorized=True,
            )
        except SolverError as err:
            run.status, run.message = "solver_failure", f"{o.method}: {err} (integration stopped at segment start t = {t:.6g} s)"
            break
        except _Budget as limit:
            # the segment is lost up to the limit; the run ends at its start (both limits are failures)
            run.status, run.message = limit.kind, limit_message(limit.kind, o, t)
            run.nfev = meter.nfev
            break
        run.nfev += int(sol.nfev)
        run.njev += int(sol.njev)
        run.nlu += int(sol.nlu)
        t_new = float(sol.t[-1])
        if sol.sol is not None and t_new > t:
            run.segments.append((t, t_new, sol.sol, seg))
        still = 0 if t_new > t else still + 1
        y = sol.y[:, -1].copy()
        if sol.status == -1:
            run.status, run.message = "solver_failure", f"solve_ivp ({o.method}) failed at t = {t_new:.6g} s: {sol.message}"
            t = t_new
            break
        t = t_new
        if sol.status == 1:
            fired = [e for e, te in zip(events, sol.t_events) if len(te)]
            ev = fired[0]
            if ev.kind == "rest":
                run.status, run.message = "rest", f"all bodies below v_stop = {o.v_stop} m/s at t = {t:.4f} s"
                break
            if ev.kind == "stop":
                locks = _close_stop(model, run, y, t, ev.index, locks, membership, offsets)
                j = ev.index[0]
                if all(jl != j for jl, _ in locks):  # struck and left
                    lim = model.vehicle.hitches[j].articulation_limit
                    shifts[j] = _left_stop_shift(y, L, j, offsets[j], lim, shifts[j])
            elif ev.kind == "release":
                n, j = ev.index
                run.events.append(RunoutEvent(t, "stop_open", f"articulation stop of hitch {j} opens"))
                locks = [lk for i, lk in enumerate(locks) if i != n]
                lim = model.vehicle.hitches[j].articulation_limit
                shifts[j] = _left_stop_shift(y, L, j, offsets[j], lim, shifts[j])
        else:
            if t >= o.t_max:
                run.status, run.message = "time_limit", limit_message("time_limit", o, t, model.rest_measure(y))
                break
            run.events.append(RunoutEvent(t, "schedule", "wheel settings change"))
        new_membership = zone_membership(model, y)
        _log_zone_changes(model, run, t, membership, new_membership)
        membership = new_membership
    run.events.append(RunoutEvent(t, run.status, run.message))
    _log.debug("run-out of %s: %s after %d segments, nfev=%d", model.vehicle.name, run.status, len(run.segments), run.nfev)
    return run, t, y, y_initial


def _log_zone_changes(model, run, t, old, new):
    for k, z in zip(*np.nonzero(old != new)):
        zone = model.road.zones[z]
        kind = "zone_enter" if new[k, z] else "zone_exit"
        run.events.append(RunoutEvent(t, kind, f"wheel {model.specs[k].key} {kind[5:]}s zone {z} {zone.name!r}"))


def _close_stop(model, run, y, t, index, locks, membership, offsets):
    """Plastic impact at an articulation stop, then lock it unless the bodies separate."""
    L = model.layout
    j, side = index
    lim = model.vehicle.hitches[j].articulation_limit
    theta_lock = side * lim + offsets[j]
    trial = locks + [(j, theta_lock)]
    G, _, _ = hitch_state(model.vehicle, L, y, trial)
    ke_before = float(model.kinetic_energy(y))
    y[L.velocity] = project_velocities(model.minv, G, y[L.velocity])
    loss = ke_before - float(model.kinetic_energy(y))
    lam = model.evaluate(y[:, None], model.segment(t, membership, trial)).lam[0, -1]
    if lam * side <= 0:
        detail = f"articulation stop of hitch {j} closes at {side * lim:+.4f} rad (impact dissipates {loss:.1f} J)"
        run.events.append(RunoutEvent(t, "stop_closed", detail, energy=loss))
        return trial
    detail = f"articulation stop of hitch {j} struck at {side * lim:+.4f} rad and left (impact dissipates {loss:.1f} J)"
    run.events.append(RunoutEvent(t, "stop_impact", detail, energy=loss))
    return locks


def _sample_chunks(run: _Run, sample_dt: float, t_end: float, y_end: np.ndarray):
    chunks = []
    segs = run.segments
    for i, (t0, t1, sol, seg) in enumerate(segs):
        k0 = math.ceil(t0 / sample_dt - 1e-9)
        grid = np.arange(k0, math.floor(t1 / sample_dt) + 1) * sample_dt
        grid = grid[(grid > t0) & (grid < t1)]
        times = np.concatenate([[t0], grid])
        if i == len(segs) - 1:
            times = np.concatenate([times, [t1]])
        Y = np.asarray(sol(times)).reshape(-1, times.size)
        if i == len(segs) - 1:
            Y[:, -1] = y_end
        chunks.append((seg, times, Y))
    return chunks


def simulate_runout(
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
) -> RunoutResult:
    """Simulate the post-impact run-out of one vehicle to rest.

    Parameters
    ----------
    vehicle : Vehicle
        A movable vehicle (one body, or a chain joined by hitches).
    initial : mapping of str to BodyState
        State of every body at separation (world frame, SI).  Articulated vehicles need
        hitch-consistent velocities (equal pin velocities); use
        :func:`~crashsim.motion.make_hitch_consistent` on impact-solver output.
    wheels : WheelSettings or None
        Wheel states and tyre data; None means every wheel locked.
    road : Road
        Friction coefficient and friction zones.
    options : RunoutOptions
        Solver method, tolerances, regularisation, rest threshold, time limit, and the
        engine: ``engine="scipy"`` (default, this module) or ``"compiled"``
        (:mod:`crashsim.motion.fast`, same model and result, ~100x faster per run).

    Returns
    -------
    RunoutResult
        ``status`` says why the run stopped; ``success`` is True only at rest;
        ``method`` names the engine (``"scipy/LSODA"``, ``"compiled/dopri5"``).

    Raises
    ------
    ScenarioError
        Invalid input (names the field, value and allowed range), a barrier vehicle, or
        inconsistent initial hitch states.

    Examples
    --------
    >>> from crashsim.vehicles import Axle, Body, Vehicle, BodyState
    >>> car = Vehicle("car", (Body("car", 1500.0, 2500.0, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    >>> res = simulate_runout(car, {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(mu=0.75))
    >>> res.status, round(res.bodies["car"].rest_position[0], 2)  # v^2 / (2 mu g) = 27.19 m
    ('rest', 27.19)
    """
    if not isinstance(vehicle, Vehicle):
        raise ScenarioError(f"must be a Vehicle, got {type(vehicle).__name__}", field="vehicle")
    if not isinstance(road, Road):
        raise ScenarioError(f"must be a Road, got {type(road).__name__}", field="road")
    if not isinstance(options, RunoutOptions):
        raise ScenarioError(f"must be RunoutOptions, got {type(options).__name__}", field="options")
    if vehicle.is_barrier:
        raise ScenarioError("a barrier (infinite mass) is not simulated", field=f"{vehicle.name}.bodies")
    settings = WheelSettings.all_locked() if wheels is None else wheels
    if not isinstance(settings, WheelSettings):
        raise ScenarioError(f"must be WheelSettings or None, got {type(wheels).__name__}", field=f"wheels[{vehicle.name!r}]")
    if options.engine == "compiled":
        from .fast import simulate_runout_compiled

        return simulate_runout_compiled(vehicle, initial, settings, road, options)
    model = RunoutModel(vehicle, settings.resolve(vehicle), road, options)
    y0 = model.layout.pack(initial)
    check_hitch_consistency(model, y0)

    run, t_end, y_end, y_initial = _integrate(model, y0)
    if run.status != "rest":
        _log.warning("run-out of %s did not reach rest (%s): %s", vehicle.name, run.status, run.message)

    sol = _PiecewiseSolution(run.segments, y_end, t_end)
    samples = _sample_chunks(run, options.sample_dt, t_end, y_end)
    if not samples:
        seg = model.segment(t_end, zone_membership(model, y_end))
        samples = [(seg, np.array([t_end]), y_end[:, None])]
    quadrature = [gauss_legendre_chunks(np.asarray(s.ts), s, seg) for _, _, s, seg in run.segments]
    return assemble_result(
        model,
        samples=samples,
        quadrature=quadrature,
        status=run.status,
        message=run.message,
        t_end=t_end,
        y_initial=y_initial,
        y_final=y_end,
        sol=sol,
        events=run.events,
        nfev=run.nfev,
        njev=run.njev,
        nlu=run.nlu,
        n_segments=len(run.segments),
        method=f"scipy/{options.method}",
        check_zones=True,
    )


def simulate_scene(
    vehicles: Iterable[Vehicle],
    initial: Mapping[str, BodyState],
    wheels_by_vehicle: Mapping[str, WheelSettings | None] | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
) -> dict[str, RunoutResult]:
    """Run-outs of every movable vehicle of a scene (vehicles do not interact after separation).

    Parameters
    ----------
    vehicles : iterable of Vehicle
        All vehicles of the scene; barriers are skipped.
    initial : mapping of str to BodyState
        State of every body of every movable vehicle, by body name.
    wheels_by_vehicle : mapping of str to WheelSettings or None, optional
        Wheel settings by vehicle name; a vehicle not listed (or None) has all wheels locked.
    road : Road
    options : RunoutOptions

    Returns
    -------
    dict of str to RunoutResult
        By vehicle name, in the order given (barriers absent).
    """
    wheels_by_vehicle = dict(wheels_by_vehicle or {})
    vehicles = list(vehicles)
    names = [v.name for v in vehicles]
    for key in wheels_by_vehicle:
        if key not in names:
            raise ScenarioError(f"no vehicle named {key!r}; vehicles are {names}", field="wheels_by_vehicle")
    out = {}
    for v in vehicles:
        if v.is_barrier:
            continue
        out[v.name] = simulate_runout(v, initial, wheels_by_vehicle.get(v.name), road, options)
    return out


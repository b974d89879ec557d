"""The same run-out integrated by pymunk (Chipmunk2D): an independent cross-check.

What is shared with the SciPy engine and what is not
----------------------------------------------------
Shared (so that differences are integration differences): the vehicle, wheel settings,
static loads, road and the **tyre force function** -- every step calls
:meth:`crashsim.motion.hitches.RunoutModel.evaluate` for the per-body tyre forces and
moments (the constraint part of that evaluation is not used).  Independent: the time
integration (pymunk's fixed-step semi-implicit Euler), the hitch (a ``pymunk.PivotJoint``
solved by pymunk's iterative impulse solver with its own positional bias, *not* the
Lagrange multiplier + Baumgarte equations), the articulation stop (a
``pymunk.RotaryLimitJoint``), and zone lookup (signed distance at each step, no event
location; a step that crosses an edge uses mu weighted by the fraction of the step inside).

Setup (research note sec. 4): one ``pymunk.Body`` per body with its CG at the body origin,
``space.gravity = (0, 0)``, no shapes, one ``PivotJoint`` per hitch (``collide_bodies =
False``).  Forces enter through each body's ``velocity_func`` (symplectic Euler: pymunk
first moves every body with its old velocity, then calls ``velocity_func``, so the forces
see the new positions and the old velocities).  The "pivot joint to the static body with
max_force" friction idiom is deliberately **not** used: its clamped impulse does not point
against the slip velocity and biases slide distances (note sec. 4.2).

Expect first-order convergence in ``dt`` (about 5-10 mm rest-position error per ms of dt
for a 2 s truck run-out).  Chatter-free friction needs ``eps >= mu g dt`` and
``v_stop >= 2 mu g dt`` (note sec. 4.2); this is checked.

pymunk is imported only inside :func:`simulate_runout_pymunk`; the numeric core never
imports it.
"""

from __future__ import annotations

import math
from typing import Mapping

import numpy as np

from ..errors import ScenarioError
from ..motion.hitches import RunoutModel
from ..motion.loads import STANDARD_GRAVITY
from ..motion.options import RunoutOptions
from ..motion.postprocess import build_result, chunk_inputs
from ..motion.result import RunoutEvent, RunoutResult
from ..motion.road import Road
from ..motion.engine import check_scene_hitches
from ..motion.wheels import WheelSettings
from ..vehicles import BodyState, Vehicle

__all__ = ["simulate_runout_pymunk"]


class _LinearHistory:
    """``sol(t)``: linear interpolation of the recorded states (pymunk has no dense output)."""

    def __init__(self, t: np.ndarray, Y: np.ndarray):
        self.t, self.Y = t, Y

    def __call__(self, tq):
        tq_arr = np.asarray(tq, dtype=float)
        flat = np.atleast_1d(tq_arr).ravel()
        out = np.stack([np.interp(flat, self.t, row) for row in self.Y])
        return out[:, 0] if tq_arr.ndim == 0 else out.reshape((self.Y.shape[0],) + tq_arr.shape)


def _checked(vehicle: Vehicle, wheels: WheelSettings | None, road: Road, dt: float, t_max: float | None,
             options: RunoutOptions):
    """The step and the time limit, checked (a step too coarse for ``eps`` and ``v_stop`` makes friction
    chatter), and the vehicle's model: ``(dt, t_max, model)``."""
    dt = float(dt)
    if not (0 < dt <= 0.01):
        raise ScenarioError(f"must lie in (0, 0.01] s, got {dt!r}", field="dt")
    if options.load_transfer:
        raise ScenarioError("load transfer is not supported by the pymunk cross-check", field="options.load_transfer")
    t_max = options.t_max if t_max is None else float(t_max)
    if vehicle.is_barrier:
        raise ScenarioError("a barrier (infinite mass) is not simulated", field=f"{vehicle.name}.bodies")
    settings = WheelSettings.all_locked() if wheels is None else wheels
    model = RunoutModel(vehicle, settings.resolve(vehicle), road, options)
    mu_max = max([road.mu, *(z.mu for z in road.zones)]) * max(s.mu_factor for _, ph in model.wheels.phases for s in ph)
    chatter = mu_max * STANDARD_GRAVITY * dt
    if options.eps < chatter or options.v_stop < 2 * chatter:
        raise ScenarioError(
            f"dt = {dt} s is too coarse for eps = {options.eps} m/s and v_stop = {options.v_stop} m/s: friction chatters "
            f"unless eps >= mu g dt = {chatter:.3g} m/s and v_stop >= 2 mu g dt = {2 * chatter:.3g} m/s",
            field="dt",
        )
    return dt, t_max, model


def _space(vehicle: Vehicle, y: np.ndarray, L):
    """A pymunk space with the vehicle's bodies at the state ``y`` and its hitches as pivot joints (with
    their articulation stops, and a gear joint at a yaw-locked hitch): ``(space, bodies)``."""
    import pymunk  # lazy: only the cross-check needs it

    space = pymunk.Space()
    space.gravity = (0.0, 0.0)
    space.iterations = 20
    bodies = []
    for i, b in enumerate(vehicle.bodies):
        body = pymunk.Body(b.mass, b.yaw_inertia)
        body.position = (y[L.x][i], y[L.y][i])
        body.angle = y[L.psi][i]
        body.velocity = (y[L.vx][i], y[L.vy][i])
        body.angular_velocity = y[L.w][i]
        bodies.append(body)
        space.add(body)
    for j, hitch in enumerate(vehicle.hitches):
        pin = bodies[j].local_to_world(hitch.front_point)
        joint = pymunk.PivotJoint(bodies[j], bodies[j + 1], pin)
        joint.collide_bodies = False
        space.add(joint)
        if hitch.articulation_limit is not None:
            # pymunk limits (rear angle - front angle) = -articulation
            stop = pymunk.RotaryLimitJoint(bodies[j], bodies[j + 1], -hitch.articulation_limit, hitch.articulation_limit)
            stop.collide_bodies = False
            space.add(stop)
        if hitch.yaw_locked:  # a C-dolly: no relative rotation (a gear joint of ratio 1, phase 0)
            lock = pymunk.GearJoint(bodies[j], bodies[j + 1], 0.0, 1.0)
            lock.collide_bodies = False
            space.add(lock)
    return space, bodies


def _chunks(rec_seg: list, t_arr: np.ndarray, Y: np.ndarray, quad_y: list, quad_seg: list, dt: float):
    """The recorded states and the steps' states cut where the segment changes: the sample and
    quadrature chunks of :func:`crashsim.motion.postprocess.chunk_inputs` (each step weighs ``dt``)."""
    samples = []
    start = 0
    for k in range(1, len(rec_seg) + 1):
        if k == len(rec_seg) or rec_seg[k] is not rec_seg[start]:
            samples.append((rec_seg[start], t_arr[start:k], Y[:, start:k]))
            start = k
    quadrature = []
    if quad_y:
        QY = np.array(quad_y).T
        start = 0
        for k in range(1, len(quad_seg) + 1):
            if k == len(quad_seg) or quad_seg[k] is not quad_seg[start]:
                quadrature.append((quad_seg[start], np.full(k - start, dt), QY[:, start:k]))
                start = k
    return samples, quadrature


def _hitch_forces(f: np.ndarray, y_prev: np.ndarray, y_new: np.ndarray, masses: np.ndarray, nh: int, L,
                  dt: float) -> np.ndarray:
    """Each hitch's force on its front body over a step, from the bodies' momentum change (front to rear:
    m dv/dt = F_tyre + lam_rear - lam_front), (2 nh,)."""
    nb = L.n_bodies
    hitch = np.zeros(2 * nh)
    carried = np.zeros(2)
    for j in range(nh):
        dv = np.array([y_new[L.vx][j] - y_prev[L.vx][j], y_new[L.vy][j] - y_prev[L.vy][j]]) / dt
        carried = masses[j] * dv - np.array([f[j], f[nb + j]]) + carried
        hitch[2 * j : 2 * j + 2] = carried
    return hitch


def simulate_runout_pymunk(vehicle: Vehicle, initial: Mapping[str, BodyState], wheels: WheelSettings | None, road: Road,
                           *, dt: float = 1e-3, t_max: float | None = None, options: RunoutOptions = RunoutOptions(),
                           record_every: int = 1) -> RunoutResult:
    """Integrate the run-out with pymunk at a fixed step (cross-check of :func:`~crashsim.motion.simulate_runout`).

    Parameters
    ----------
    vehicle, initial, wheels, road
        As for :func:`~crashsim.motion.simulate_runout`.
    dt : float
        Fixed time step [s], in (0, 0.01].
    t_max : float, optional
        Time limit [s]; default ``options.t_max``.
    options : RunoutOptions
        Supplies ``eps``, ``v_stop`` (same rest criterion, checked after every step),
        ``lateral_model`` and ``sample_dt``-independent settings; solver settings are unused.
        ``load_transfer`` is not supported.
    record_every : int
        Record every n-th step in the history (all steps enter the path integrals).

    Returns
    -------
    RunoutResult
        Same structure as the SciPy result; ``method`` is ``"pymunk/dt=..."``, ``nfev`` the
        number of steps, ``sol`` a linear interpolation of the recorded states, hitch forces
        from the bodies' momentum change per step, stop moments not reported (zero).
    """
    import pymunk  # lazy: only the cross-check needs it

    dt, t_max, model = _checked(vehicle, wheels, road, dt, t_max, options)
    L = model.layout
    y = L.pack(initial)
    check_scene_hitches(model.scene, y)
    y_initial = y.copy()

    space, bodies = _space(vehicle, y, L)

    def read_state() -> np.ndarray:
        out = np.empty(L.size)
        for i, body in enumerate(bodies):
            out[L.x.start + i], out[L.y.start + i] = body.position
            out[L.psi.start + i] = body.angle
            out[L.vx.start + i], out[L.vy.start + i] = body.velocity
            out[L.w.start + i] = body.angular_velocity
        if L.clock_index is not None:  # air brakes: their force follows the time
            out[L.clock_index] = current["t"]
        return out

    state = {"step": -1, "forces": None, "seg": None, "key": None}
    nb = L.n_bodies

    phase_times = model.scene.phase_times  # the settings' changes and the kinks of the air brakes' ramps
    no_zones = np.zeros((len(model.specs), 0), dtype=bool)

    def road_mu(yy: np.ndarray) -> np.ndarray:
        """Road mu per wheel over the coming position step, blended at zone edges.

        The force computed now acts while the contact moves from p to about p + v dt; if a zone
        edge lies in between, mu is weighted by the fraction of that step inside the zone
        (linear in the signed distances), so crossings are resolved to second order instead of
        being quantised to whole steps.
        """
        pos = model.wheel_positions(yy)
        ahead = pos + model.wheel_velocities(yy) * dt
        mu = np.full(len(pos), road.mu)
        for zone in road.zones:
            d0, d1 = zone.signed_distance(pos), zone.signed_distance(ahead)
            crossing = (d0 > 0) != (d1 > 0)
            inside = np.where(crossing, np.maximum(d0, d1) / np.where(crossing, np.abs(d1 - d0), 1.0), d0 > 0)
            mu = mu * (1.0 - inside) + zone.mu * inside
        return mu

    def segment_for(t: float, yy: np.ndarray):
        phase = int(np.searchsorted(phase_times, t + 1e-12, side="right")) - 1
        mu = road_mu(yy) if road.zones else None
        key = (phase, None if mu is None else mu.tobytes())
        if key != state["key"]:
            membership = road.membership(model.wheel_positions(yy)) if road.zones else no_zones
            state["seg"] = model.segment(t, membership, road_mu=mu)
            state["key"] = key
        return state["seg"]

    def forces_now(step: int, t: float) -> np.ndarray:
        if state["step"] != step:
            yy = read_state()  # positions x_{n+1}, velocities v_n
            state["forces"] = model.tyre_body_forces(yy[:, None], segment_for(t, yy))[:, 0]
            state["step"] = step
        return state["forces"]

    def make_velocity_func(i: int):
        def velocity_func(body, gravity, damping, step_dt):
            f = forces_now(current["step"], current["t"])
            body.force = (f[i], f[nb + i])
            body.torque = f[2 * nb + i]
            pymunk.Body.update_velocity(body, gravity, damping, step_dt)

        return velocity_func

    current = {"step": 0, "t": 0.0}
    for i, body in enumerate(bodies):
        body.velocity_func = make_velocity_func(i)

    rec_t, rec_y, rec_seg, rec_hitch = [0.0], [y.copy()], [segment_for(0.0, y)], [np.zeros(2 * model.n_hitches)]
    quad_y, quad_seg = [], []
    masses = model.mass
    status, message = "", ""
    n_steps = int(math.floor(t_max / dt + 1e-9))
    y_prev = y
    t = 0.0
    if model.rest_measure(y) <= options.v_stop:
        status, message = "rest", f"all bodies below v_stop = {options.v_stop} m/s at t = 0 s"
    step = 0
    while not status:
        if step >= n_steps:
            status = "time_limit"
            message = f"t_max = {t_max} s reached before rest"
            break
        current["step"], current["t"] = step, t
        space.step(dt)
        quad_y.append(y_prev)
        quad_seg.append(state["seg"])
        step += 1
        t = step * dt
        current["t"] = t  # the recorded state's time (its clock, with air brakes)
        y_new = read_state()
        if not np.all(np.isfinite(y_new)):
            status, message = "solver_failure", f"pymunk state not finite at t = {t:.6g} s"
            break
        # hitch forces from each body's momentum change: m dv/dt = F_tyre + lam_rear - lam_front
        hitch = _hitch_forces(state["forces"], y_prev, y_new, masses, model.n_hitches, L, dt)
        y_prev = y_new
        if step % record_every == 0 or model.rest_measure(y_new) <= options.v_stop:
            rec_t.append(t)
            rec_y.append(y_new)
            rec_seg.append(state["seg"])
            rec_hitch.append(hitch)
        if model.rest_measure(y_new) <= options.v_stop:
            status, message = "rest", f"all bodies below v_stop = {options.v_stop} m/s at t = {t:.4f} s"

    t_arr = np.array(rec_t)
    Y = np.array(rec_y).T
    samples, quadrature = _chunks(rec_seg, t_arr, Y, quad_y, quad_seg, dt)
    events = [RunoutEvent(t, status, message)]
    return build_result(model, chunk_inputs(
        model, samples=samples, quadrature=quadrature, status=status, message=message, t_end=t, y_initial=y_initial,
        y_final=y_prev, sol=_LinearHistory(t_arr, Y), events=events, nfev=step, njev=0, nlu=0, n_segments=1,
        method=f"pymunk/dt={dt:g}", hitch_force=np.array(rec_hitch)))

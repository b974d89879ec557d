"""Fidelity levels of the post-impact run-out: from impact only to articulated run-out with load transfer.

A scenario chooses how much of the run-out to model.  Every level is a documented model, run
through :func:`~crashsim.motion.run_runout` (``level=``); this module registers the runners of
``impact``, ``energy`` and ``rigid`` (:mod:`crashsim.motion.runners`).  Every level gives the same
result type as :func:`~crashsim.motion.simulate_runout` per vehicle (a
:class:`~crashsim.motion.RunoutResult`: rest positions and headings, times to rest, histories,
wheel tracks), so evidence checks, reports and plots work unchanged.

=================  ===========================================================================
level              model
=================  ===========================================================================
``impact``         Impact only: no run-out is computed (``run_runout`` returns no results;
                   equivalent to a scenario without a ``[runout]`` section).
``energy``         Hand calculation by work and energy (below).  Closed form, no integration.
``rigid``          Every body of the vehicle runs out alone, the hitch ignored (below).
                   Integrated like ``articulated``.
``articulated``    The full run-out: :func:`~crashsim.motion.simulate_runout` (maximal
                   coordinates, Baumgarte-stabilised hitches, per-wheel tyre forces, friction
                   zones, articulation stops, rest event), static wheel loads.
``load_transfer``  ``articulated`` plus quasi-static longitudinal and lateral load transfer
                   (``RunoutOptions(load_transfer=True)``; needs every body's ``cg_height``).
=================  ===========================================================================

The level overrides ``options.load_transfer`` (on only for ``load_transfer``).

Level ``energy``: the hand calculation
--------------------------------------
The reconstructionist's work-energy run-out ("sliding point mass" plus "rotating skid"),
written down exactly so that it can be reproduced by hand:

1. **One rigid body.**  A vehicle of several bodies is treated as one rigid body with its
   articulation frozen at the separation value.  Its velocity is the momentum-conserving
   rigid motion: CG velocity ``v_c = sum m_i v_i / M`` and yaw rate ``w_c = H / I_c`` with
   ``H`` the angular momentum about the combined CG and ``I_c = sum (I_i + m_i |r_i - r_c|^2)``.
   Locking the articulation this way is a plastic impact of the hitch; the kinetic energy it
   removes is reported as an event ``"lock"`` (it is zero for a single body, and zero when
   the bodies already move as one).
2. **Drag factor of a wheel** moving in a direction at angle ``beta`` to its heading (the
   friction circle with braking priority, note sec. 2.3, fully saturated):

   * locked or jammed: ``f = mu``;
   * rolling or braked: ``f = f_x |cos beta| + sqrt(mu^2 - f_x^2) |sin beta|`` with the
     longitudinal drag ``f_x = min(b mu + f_r, mu)``: rolling resistance plus brake along the
     wheel, the full remaining side force across it.  This neglects the linear (unsaturated)
     range of the side force at small slip angles, where a rolling tyre resists less.

   * with air brakes (:mod:`crashsim.motion.brakes`): ``f_x = F_b / N + f_r`` with the brake
     force at full application (their timing ignored, said so in the message); ``f = mu`` where
     that reaches ``mu`` (the wheel locks), ``f_x <= eta mu`` with ABS.

   ``mu`` is the road or zone friction coefficient at the **CG** times the wheel's
   ``mu_factor``; wheel settings are those in force at separation (scheduled changes are
   ignored and said so in the message); loads are the static wheel loads (for an
   articulated vehicle, those of the coupled vehicle: the kingpin load on the tractor tyres).
3. **Rotation (rotating skid).**  The rotational kinetic energy ``I_c w_c^2 / 2`` is
   dissipated by the yaw moment of the tyre friction in a pure spin about the CG,
   ``M_f = sum_k N_k r_k f_k(beta_k)`` (``r_k`` the wheel's distance from the CG and
   ``beta_k`` the angle between the wheel heading and its spin velocity, so ``M_f`` is
   ``mu sum N_k r_k`` with locked wheels): heading change
   ``d_psi = I_c w_c^2 / (2 M_f)`` in the sense of ``w_c``, at constant angular deceleration
   ``M_f / I_c``, so the spin stops after ``t_rot = I_c |w_c| / M_f`` (note sec. 5 item 4).
   The rest heading is the separation heading plus ``d_psi``.
4. **Translation (sliding point mass).**  The CG slides along the direction of its separation
   velocity a distance ``d`` with ``M v_c^2 / 2 = M g f_mean d``, i.e. ``d = v^2 / (2 f_mean g)``,
   at constant deceleration ``f_mean g`` (time ``t_trans = v / (f_mean g)``), where ``f_mean``
   is the load-weighted drag factor ``sum N_k f_k / sum N_k`` averaged uniformly over the
   headings swept by the rotation (evaluated at the separation heading when there is no
   rotation).  Across friction zones the line is cut where it crosses a zone edge and the
   energy is spent piece by piece (piecewise constant deceleration).
5. **Time to rest** ``max(t_trans, t_rot)``.  The straight CG track and the heading follow the
   two constant-deceleration laws; wheel tracks follow from the rigid motion.  Sliding flags
   of the tracks are those of the tyre model (:func:`~crashsim.motion.tyre_forces`) at the
   kinematic states.

Assumptions and what they neglect (note sec. 5 items 5-7):

* Translation and rotation are treated as independent, each dissipated by the full friction.
  The exact work-energy identity (item 5) is ``KE_0 = sum_k mu N_k s_k`` with ``s_k`` the
  sliding path of wheel k; the model replaces ``s_k`` by ``d + r_k d_psi``, which is never
  shorter than the true wheel path (triangle inequality).  With both motions present the
  model therefore **underestimates** ``d`` and ``d_psi`` together: a spinning vehicle
  really slides farther, because friction spent on the spin is not spent on the slide
  (item 7: at fast spin the translational drag falls to about ``mu N v / (2 w r)``).
* Translation and rotation really stop at the same instant (item 6); the model stops them
  separately (``t_trans != t_rot`` in general).
* The CG path is straight: side forces that curve the path (rolling wheels, jammed wheels off
  the centre line) are not modelled; nor is the hitch (articulation frozen).
* Exact for a straight slide on locked wheels, ``d = v^2/(2 mu g)``, ``t = v/(mu g)`` (item 1),
  for a sideways slide on rolling wheels (item 3), and for a pure spin about the CG of a
  symmetric vehicle (item 4); for an articulated vehicle in line with all wheels locked it
  gives the exact ``d = v^2/(2 mu g)`` of every unit (item 8).

Level ``rigid``: bodies without the hitch
-----------------------------------------
Every body of the vehicle runs out on its own tyres with the full tyre model (the
``articulated`` engine with the hitch constraint removed and articulation stops ignored).
**Kingpin load:** each body keeps the static wheel loads it has in the coupled vehicle, so the
vertical kingpin (or drawbar) load stays on the towing body's tyres: the tractor's tyres carry
``W_1 + N_kp`` and decelerate only the tractor's mass, the trailer's tyres carry
``W_2 - N_kp`` and decelerate the whole trailer mass.  (A towed body alone is not statically
determinate, so the alternative of carrying its own weight on its own axles does not exist.)
This neglects the horizontal hitch force -- in a straight locked slide the trailer pushes the
tractor with ``mu N_kp`` (note sec. 5 item 8); without it the tractor stops after
``v^2 m_1 / (2 mu (W_1 + N_kp))`` and the trailer after ``v^2 m_2 / (2 mu (W_2 - N_kp))`` -- and
the yaw coupling through the hitch.  The bodies do not touch each other either (no contact
model): they may pass through one another.  The pins drift apart; ``RunoutResult.max_hitch_gap``
reports how far, which measures how much the hitch would have mattered.  Hitch histories
carry the articulation angle and zero force.  Each body's ``time_to_rest`` is when its own
rest measure ``max(|v_cg|, |yaw rate| L_ref)`` first falls to ``v_stop`` (the run itself ends
when every body has).  For a single-body vehicle ``rigid`` equals ``articulated``.
"""

from __future__ import annotations

import dataclasses
import logging
import math
from typing import Mapping

import numpy as np
from scipy.optimize import brentq

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from .contact import ContactModel
from .hitches import RunoutModel
from .engine import run_model
from .loads import STANDARD_GRAVITY
from .scene_model import SceneModel
from .options import RunoutOptions
from .postprocess import ResultInputs, build_result
from .result import BodyRunout, HitchHistory, RunoutEvent, RunoutResult
from .road import Road, slope_gravity
from .runners import Runout, RunoutCall, check_level, register_runner
from .simulate import simulate_runout
from .tyres import tyre_forces
from .wheels import WheelSettings

__all__: list[str] = []  # the levels register their runners (run them through run_runout)

_log = logging.getLogger("crashsim")

# Points per radian (at least 16) for the mean drag factor over the swept headings.
_SWEEP_POINTS_PER_RAD = 32


def _check_inputs(vehicle, road, options, wheels) -> WheelSettings:
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
    return settings


def _scipy_engine(options: RunoutOptions) -> RunoutOptions:
    """``options`` with the reference (SciPy) engine, if the options know several engines."""
    fields = RunoutOptions.__dataclass_fields__
    if "engine" in fields:
        default = fields["engine"].default
        if getattr(options, "engine", default) != default:
            return dataclasses.replace(options, engine=default)
    return options


def simulate_level(
    level: str,
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
) -> RunoutResult | None:
    """Run-out of one vehicle at a chosen fidelity level (see the module docstring).

    Parameters
    ----------
    level : {"impact", "energy", "rigid", "articulated", "load_transfer"}
    vehicle, initial, wheels, road, options
        As for :func:`~crashsim.motion.simulate_runout`; ``initial`` must be hitch-consistent
        (:func:`~crashsim.motion.make_hitch_consistent`).  The level decides
        ``options.load_transfer``; ``energy`` uses only ``sample_dt``, ``t_max``, ``eps``
        (for the sliding flags) and ``lateral_model`` of the options.

    Returns
    -------
    RunoutResult or None
        None for ``"impact"``.  ``method`` is ``"energy"``, ``"rigid/scipy/<method>"`` or the
        engine's name, ``options["level"]`` the level.

    Raises
    ------
    ScenarioError
        Unknown level (with the nearest valid names), invalid input, a vehicle without axles,
        ``load_transfer`` without CG heights.

    Examples
    --------
    >>> from crashsim.vehicles import Axle, Body, Vehicle, BodyState
    >>> car = Vehicle("car", (Body("car", 1500.0, 2500.0, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    >>> start = {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}
    >>> res = simulate_level("energy", car, start, None, Road(mu=0.75))
    >>> res.status, round(res.bodies["car"].rest_position[0], 3)  # v^2 / (2 mu g)
    ('rest', 27.192)
    >>> simulate_level("impact", car, start, None, Road(mu=0.75)) is None
    True
    """
    check_level(level)
    settings = _check_inputs(vehicle, road, options, wheels)
    return _ALONE[level](level, vehicle, initial, settings, road, options)


def _articulated_alone(level, vehicle, initial, settings, road, options) -> RunoutResult:
    """Levels ``articulated`` and ``load_transfer`` of one vehicle alone: :func:`~crashsim.motion.simulate_runout`."""
    opts = dataclasses.replace(options, load_transfer=(level == "load_transfer"))
    res = simulate_runout(vehicle, initial, settings, road, opts)
    return dataclasses.replace(res, options={**res.options, "level": level})


@register_runner("impact")
@register_runner("impact", accuracy=True)
def _no_runout(call: RunoutCall) -> Runout:
    """Level ``impact``'s runner: no run-out (whatever the accuracy target)."""
    return Runout(None, None, None)


@register_runner("energy", "rigid")
def _each_alone(call: RunoutCall) -> Runout:
    """The runner of the levels without contact (``energy``, ``rigid``): each movable vehicle alone."""
    runout = {}
    for veh in call.movable:
        init = {b.name: call.initial[b.name] for b in veh.bodies}
        runout[veh.name] = simulate_level(call.level, veh, init, call.wheels.get(veh.name), call.road, call.options)
    return Runout(runout, None, None)


# ---------------------------------------------------------------------------------------------- energy
def _ray_breaks(road: Road, origin: np.ndarray, direction: np.ndarray) -> np.ndarray:
    """Distances s > 0 along the ray ``origin + s direction`` where it crosses a zone edge."""
    out = []
    for zone in road.zones:
        p = zone.vertices
        e = np.roll(p, -1, axis=0) - p
        det = direction[0] * (-e[:, 1]) - direction[1] * (-e[:, 0])
        ok = np.abs(det) > 1e-15
        rel = p - origin
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (rel[:, 0] * (-e[:, 1]) - rel[:, 1] * (-e[:, 0])) / det
            t = (direction[0] * rel[:, 1] - direction[1] * rel[:, 0]) / det
        hit = ok & (s > 0) & (t >= 0) & (t <= 1)
        out.extend(s[hit].tolist())
    return np.unique(np.array(out, dtype=float))


class _RigidMotion:
    """Kinematics of the energy model: straight CG track, constant decelerations (vectorised in t)."""

    def __init__(self, layout, pos0, rel0, psi0, u, pieces, w0, alpha, t_rot, t_end):
        self.layout = layout
        self.pos0 = pos0  # body CG positions at t = 0
        self.rel0, self.psi0 = rel0, psi0  # body CG offsets from the combined CG (world, t=0), body headings
        self.u = u  # unit direction of the CG track
        # pieces: (t_start, s_start, v_start, decel)
        self.pieces = pieces
        self.w0, self.alpha, self.t_rot, self.t_end = w0, alpha, t_rot, t_end

    def cg(self, t):
        """Arc length s [m] and speed v [m/s] of the combined CG at times t."""
        t = np.asarray(t, dtype=float)
        s = np.zeros_like(t)
        v = np.zeros_like(t)
        for i, (t0, s0, v0, a) in enumerate(self.pieces):
            t1 = self.pieces[i + 1][0] if i + 1 < len(self.pieces) else math.inf
            m = (t >= t0) & (t < t1)
            tau = t[m] - t0
            if a > 0:
                tau = np.minimum(tau, v0 / a)
            s[m] = s0 + v0 * tau - 0.5 * a * tau * tau
            v[m] = np.maximum(v0 - a * tau, 0.0)
        return s, v

    def yaw(self, t):
        """Heading change [rad] and yaw rate [rad/s] of the rigid vehicle at times t."""
        t = np.asarray(t, dtype=float)
        tau = np.minimum(t, self.t_rot)
        dpsi = self.w0 * tau - 0.5 * self.alpha * tau * tau
        w = np.where(t < self.t_rot, self.w0 - self.alpha * tau, 0.0)
        return dpsi, w

    def state(self, t):
        """Full state vectors (layout order) at times t, shape (n_state,) + shape(t)."""
        t_arr = np.asarray(t, dtype=float)
        flat = np.clip(np.atleast_1d(t_arr).ravel(), 0.0, self.t_end)
        s, v = self.cg(flat)
        dpsi, w = self.yaw(flat)
        L = self.layout
        Y = np.zeros((L.size, flat.size))
        c, sn = np.cos(dpsi), np.sin(dpsi)
        for i in range(L.n_bodies):
            # r_i(t) = r_i(0) + s u + (R(dpsi) - 1) rel_i: exact at t = 0 and without rotation
            rx = c * self.rel0[i, 0] - sn * self.rel0[i, 1]
            ry = sn * self.rel0[i, 0] + c * self.rel0[i, 1]
            Y[L.x.start + i] = self.pos0[i, 0] + s * self.u[0] + (rx - self.rel0[i, 0])
            Y[L.y.start + i] = self.pos0[i, 1] + s * self.u[1] + (ry - self.rel0[i, 1])
            Y[L.psi.start + i] = self.psi0[i] + dpsi
            Y[L.vx.start + i] = v * self.u[0] - w * ry
            Y[L.vy.start + i] = v * self.u[1] + w * rx
            Y[L.w.start + i] = w
        return Y[:, 0] if t_arr.ndim == 0 else Y.reshape((L.size,) + t_arr.shape)

    __call__ = state


def _drag_factors(settings, mu_road: float, beta: np.ndarray, air=None, load=None) -> np.ndarray:
    """Drag factor of every wheel for the angles ``beta`` (n_wheels, ...) between motion and wheel heading.

    ``air`` (n_wheels, 7): the air brakes' rows (:meth:`ResolvedWheels.brake_rows`) with the loads ``load``
    [N]: a wheel with air brakes drags with its brake force at full application per unit load (a wheel
    whose brake reaches ``mu`` locks; with ABS the drag along the wheel is at most ``eta mu``)."""
    out = np.empty_like(beta, dtype=float)
    for k, s in enumerate(settings):
        mu = mu_road * s.mu_factor
        if s.is_sliding:
            out[k] = mu
        else:
            fx = min(s.brake * mu + (s.rolling_resistance or 0.0), mu)
            if air is not None and air[k, 0] != 0.0:
                fx = air[k, 5] / load[k] + (s.rolling_resistance or 0.0) if load[k] > 0 else 0.0
                if air[k, 6] > 0.0:
                    fx = min(fx, air[k, 6] * mu)
                elif fx >= mu:
                    out[k] = mu
                    continue
            out[k] = fx * np.abs(np.cos(beta[k])) + math.sqrt(max(mu * mu - fx * fx, 0.0)) * np.abs(np.sin(beta[k]))
    return out


def _wheel_tracks(model: RunoutModel, road: Road, settings, Y: np.ndarray, N: np.ndarray, times: np.ndarray,
                  opts: RunoutOptions):
    """The energy level's wheel tracks at its sampled kinematic states ``Y``: every wheel's contact point,
    its sliding flag (the tyre model at those states), its path and sliding lengths:
    ``(points (n_wheels, K, 2), sliding (n_wheels, K), path_length, sliding_length)``."""
    L = model.layout
    psi_b = Y[L.psi][model.wheel_body]  # (n_wheels, K)
    c, sn = np.cos(psi_b), np.sin(psi_b)
    rho = np.array([sp.position for sp in model.specs])
    bx = Y[L.x][model.wheel_body]
    by = Y[L.y][model.wheel_body]
    wx = bx + c * rho[:, 0:1] - sn * rho[:, 1:2]
    wy = by + sn * rho[:, 0:1] + c * rho[:, 1:2]
    wz = Y[L.w][model.wheel_body]
    cvx = Y[L.vx][model.wheel_body] - wz * (wy - by)
    cvy = Y[L.vy][model.wheel_body] + wz * (wx - bx)
    heading_k = psi_b + np.array([s.steer for s in settings])[:, None]
    ch, sh = np.cos(heading_k), np.sin(heading_k)
    u_k = ch * cvx + sh * cvy
    w_k = -sh * cvx + ch * cvy
    mu_k = road.mu_at(np.stack([wx.ravel(), wy.ravel()], 1)).reshape(wx.shape) * np.array(
        [s.mu_factor for s in settings]
    )[:, None]
    c_alpha = np.array(
        [(s.cornering_stiffness or 0.0) * sp.tyres + (s.cornering_coefficient or 0.0) * n
         for s, sp, n in zip(settings, model.specs, N)]
    )[:, None]
    _, _, sliding = tyre_forces(
        u_k, w_k, N[:, None], mu_k, np.array([s.is_sliding for s in settings])[:, None],
        np.array([s.brake for s in settings])[:, None], c_alpha,
        np.array([s.rolling_resistance or 0.0 for s in settings])[:, None], opts.eps, opts.lateral_model,
    )
    sliding = np.array(sliding, dtype=bool)
    points = np.stack([wx, wy], axis=-1)  # (n_wheels, K, 2)
    path_length, sliding_length = np.zeros(len(N)), np.zeros(len(N))
    if times.size > 1:
        seglen = np.hypot(*np.diff(points, axis=1).transpose(2, 0, 1))  # (n_wheels, K - 1)
        for k in range(len(N)):
            path_length[k] = float(seglen[k].sum())
            sliding_length[k] = float(np.sum(seglen[k] * sliding[k, :-1]))
    return points, sliding, path_length, sliding_length


def _rigid_samples(motion, t_end: float, dt_s: float, L):
    """The energy level's states every ``dt_s`` to ``t_end`` and at it, the end state, and each body's CG
    path length (its speed integrated by the trapezoid rule on a fine grid): ``(times, Y, y_end, distance)``."""
    times = np.arange(0.0, t_end, dt_s) if t_end > 0 else np.zeros(0)
    times = np.concatenate([times, [t_end]]) if (times.size == 0 or times[-1] < t_end) else times
    Y = motion.state(times)
    y_end = motion.state(t_end)
    # CG path length of every body: integrate its speed (trapezoid on a fine grid)
    distance = np.zeros(L.n_bodies)
    if t_end > 0:
        fine = np.linspace(0.0, t_end, 2001)
        yf = motion.state(fine)
        for i in range(L.n_bodies):
            distance[i] = float(np.trapezoid(np.hypot(yf[L.vx][i], yf[L.vy][i]), fine))
    return times, Y, y_end, distance


def _energy_events(name: str, nb: int, status: str, t_max: float, t_end: float, slide: tuple, turn: tuple,
                   scheduled: bool, air: bool, lock_loss: float):
    """The energy level's message and events: the articulation frozen (with the energy that removes), then
    rest or the time limit, with what the hand calculation ignores (``slide``: distance [m] and time [s];
    ``turn``: rotation [rad] and time [s]). Returns ``(message, events)``."""
    s, t_trans = slide
    dpsi_total, t_rot = turn
    notes = []
    if scheduled:
        notes.append("scheduled wheel changes ignored (wheel settings at separation used)")
    if air:
        notes.append("air brakes at full application from separation (their timing and release ignored)")
    if status == "rest":
        message = (f"energy model: slide {s:.4g} m in {t_trans:.4g} s, rotation {math.degrees(dpsi_total):.4g} deg in "
                   f"{t_rot:.4g} s")
    else:
        message = f"energy model: no rest before t_max = {t_max} s (zero or too small drag)"
    if notes:
        message += "; " + "; ".join(notes)
        _log.warning("energy run-out of %s: %s", name, "; ".join(notes))
    events = []
    if nb > 1:
        events.append(RunoutEvent(0.0, "lock", "articulation frozen (rigid vehicle) by a plastic hitch impulse",
                                  energy=lock_loss))
    events.append(RunoutEvent(t_end, status, message))
    return message, events


def _energy_runout(vehicle: Vehicle, initial: Mapping[str, BodyState], wheels: WheelSettings | None, road: Road,
                   options: RunoutOptions = RunoutOptions()) -> RunoutResult:
    """Level ``"energy"``: the work-energy hand calculation (see the module docstring).

    Returns
    -------
    RunoutResult
        Status ``"rest"`` (``"time_limit"`` only if the drag is zero or the rest time exceeds
        ``options.t_max``); ``method`` ``"energy"``; ``nfev`` 0; an event ``"lock"`` carries
        the kinetic energy removed by freezing the articulation.
    """
    settings_obj = _check_inputs(vehicle, road, options, wheels)
    opts = dataclasses.replace(_scipy_engine(options), load_transfer=False)
    model = RunoutModel(vehicle, settings_obj.resolve(vehicle), road, opts)
    L = model.layout
    nb = L.n_bodies
    y0 = L.pack(initial)
    settings = model.wheels.at(0.0)
    scheduled = bool(model.wheels.change_times)
    air = model.wheels.brake_rows(vehicle) if model.wheels.brakes is not None else None

    m = model.mass
    inertia = model.inertia
    M = float(m.sum())
    pos = np.stack([y0[L.x], y0[L.y]], 1)
    vel = np.stack([y0[L.vx], y0[L.vy]], 1)
    psi0 = y0[L.psi].copy()
    r_c = (m[:, None] * pos).sum(0) / M
    v_c = (m[:, None] * vel).sum(0) / M
    rel0 = pos - r_c
    dv = vel - v_c
    I_c = float(np.sum(inertia + m * np.sum(rel0 * rel0, 1)))
    H = float(np.sum(inertia * y0[L.w] + m * (rel0[:, 0] * dv[:, 1] - rel0[:, 1] * dv[:, 0])))
    w_c = H / I_c
    ke0 = float(model.kinetic_energy(y0))
    ke_rigid = 0.5 * M * float(v_c @ v_c) + 0.5 * I_c * w_c * w_c
    lock_loss = max(ke0 - ke_rigid, 0.0)

    # wheel geometry relative to the combined CG at separation
    wp = model.wheel_positions(y0)
    d = wp - r_c
    r = np.hypot(d[:, 0], d[:, 1])
    theta = psi0[model.wheel_body] + np.array([s.steer for s in settings])
    N = model.static_load

    # ---- rotation: pure spin about the combined CG
    mu_start = float(road.mu_at(r_c[None, :])[0])
    sloped = road.sloped
    if sloped:  # the slope at the combined CG: normal factor on the drag, in-plane gravity along the path
        N_flat = N
        N = N_flat * slope_gravity(*road.slope_from_membership(road.membership(r_c[None, :]))[0])[2]
    dpsi_total = 0.0
    t_rot = 0.0
    alpha = 0.0
    M_f = 0.0
    wheel_rot_work = np.zeros(len(N))
    if w_c != 0.0:
        spin_dir = np.arctan2(d[:, 1], d[:, 0]) + math.copysign(math.pi / 2, w_c)
        f_spin = _drag_factors(settings, mu_start, (spin_dir - theta)[:, None], air, N)[:, 0]
        M_f = float(np.sum(N * r * f_spin))
        if M_f > 0:
            wheel_rot_work = N * r * f_spin * (I_c * w_c * w_c / (2 * M_f))
            dpsi_total = math.copysign(I_c * w_c * w_c / (2 * M_f), w_c)
            t_rot = I_c * abs(w_c) / M_f
            alpha = math.copysign(M_f / I_c, w_c)
        else:
            t_rot = math.inf

    # ---- translation: straight line along v_c, drag averaged over the swept headings
    speed = float(np.hypot(*v_c))
    u = v_c / speed if speed > 0 else np.array([math.cos(psi0[0]), math.sin(psi0[0])])
    phi = math.atan2(u[1], u[0])
    sweep = np.array([0.0]) if (dpsi_total == 0.0 or not math.isfinite(dpsi_total)) else np.linspace(
        0.0, dpsi_total, max(16, int(abs(dpsi_total) * _SWEEP_POINTS_PER_RAD) + 1)
    )
    beta = phi - theta[:, None] - sweep[None, :]
    total_n = float(N.sum())

    def mean_drag(mu_here: float) -> tuple[float, np.ndarray]:
        f = _drag_factors(settings, mu_here, beta, air, N).mean(axis=1)  # per wheel, mean over the sweep
        return float(np.sum(N * f) / total_n), f

    g = STANDARD_GRAVITY
    breaks = _ray_breaks(road, r_c, u) if (road.zones and speed > 0) else np.zeros(0)
    pieces = []
    wheel_trans_work = np.zeros(len(N))
    w_gravity = 0.0
    t, s, v = 0.0, 0.0, speed
    status = "rest"
    edges = list(breaks) + [math.inf]
    while v > 0:
        s_next = edges[0] if edges else math.inf
        while edges and s_next <= s + 1e-12:
            edges.pop(0)
            s_next = edges[0] if edges else math.inf
        mu_here = float(road.mu_at((r_c + (s + 1e-6) * u)[None, :])[0]) if road.zones else road.mu
        f_mean, f_wheels = mean_drag(mu_here)
        a = f_mean * g
        if sloped:  # drag on the slope's normal load, less the in-plane gravity along the path
            inside = road.membership((r_c + (s + 1e-6) * u)[None, :])
            gx, gy, gn = slope_gravity(*road.slope_from_membership(inside)[0])
            N = N_flat * gn
            a = f_mean * g * gn - (gx * u[0] + gy * u[1])
        pieces.append((t, s, v, a))
        s_stop = s + (v * v / (2 * a) if a > 0 else math.inf)
        if not math.isfinite(min(s_stop, s_next)):  # no drag and no zone ahead: never stops
            status = "time_limit"
            break
        if s_stop <= s_next:
            dt = v / a
            wheel_trans_work += N * f_wheels * (s_stop - s)
            if sloped:
                w_gravity += M * (gx * u[0] + gy * u[1]) * (s_stop - s)
            t, s, v = t + dt, s_stop, 0.0
        else:
            v1 = math.sqrt(max(v * v - 2 * a * (s_next - s), 0.0))
            dt = (v - v1) / a if a != 0.0 else (s_next - s) / v
            wheel_trans_work += N * f_wheels * (s_next - s)
            if sloped:
                w_gravity += M * (gx * u[0] + gy * u[1]) * (s_next - s)
            t, s, v = t + dt, s_next, v1
        if t > opts.t_max:
            status = "time_limit"
            break
    if not pieces:
        pieces.append((0.0, 0.0, 0.0, 0.0))
    t_trans = t
    if t_rot > opts.t_max:
        status = "time_limit"
    t_end = opts.t_max if status == "time_limit" else max(t_trans, t_rot)

    motion = _RigidMotion(L, pos, rel0, psi0, u, pieces, w_c, alpha, t_rot, t_end)

    # ---- samples, tracks and energies
    times, Y, y_end, distance = _rigid_samples(motion, t_end, opts.sample_dt, L)
    points, sliding, path_length, sliding_length = _wheel_tracks(model, road, settings, Y, N, times, opts)
    energy = wheel_trans_work + wheel_rot_work

    message, events = _energy_events(vehicle.name, nb, status, opts.t_max, t_end, (s, t_trans), (dpsi_total, t_rot),
                                     scheduled, air is not None, lock_loss)
    return build_result(model, ResultInputs(
        t=times, Y=Y, points=points, sliding=sliding, load=np.repeat(N[:, None], times.size, axis=1),
        hitch_force=np.full((times.size, 2 * (nb - 1)), np.nan), stop_moment=np.zeros((times.size, nb - 1)),
        distance=distance, path_length=path_length, sliding_length=sliding_length, energy=energy, max_gap=0.0,
        status=status, message=message, t_end=t_end, y_initial=y0, y_final=y_end, sol=motion, events=events,
        method="energy", kinetic_energies=(ke0, float(model.kinetic_energy(y_end))), gravity_work=w_gravity,
        static_load=N, options={**opts.to_dict(), "level": "energy"}))


# ---------------------------------------------------------------------------------------------- rigid
def _own_rest_time(body: BodyRunout, l_ref: float, v_stop: float, t_end: float) -> float:
    """First time the body's own rest measure falls to v_stop (from its dense solution)."""

    def measure(t):
        st = np.asarray(body.sol(t))
        return max(math.hypot(st[3], st[4]), abs(st[5]) * l_ref) - v_stop

    h = body.history
    m = np.maximum(np.hypot(h.vx, h.vy), np.abs(h.yaw_rate) * l_ref) - v_stop
    below = np.flatnonzero(m <= 0)
    if m[0] <= 0:
        return 0.0
    if not below.size:
        return float(t_end)
    k = int(below[0])
    a, b = float(h.t[k - 1]), float(h.t[k])
    if measure(a) > 0 and measure(b) <= 0:
        return float(brentq(measure, a, b, xtol=1e-9))
    return b


def _rigid_runout(
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
) -> RunoutResult:
    """Level ``"rigid"``: every body runs out alone, the hitch ignored (see the module docstring).

    Returns
    -------
    RunoutResult
        ``method`` ``"rigid/scipy/<method>"``; hitch histories with the articulation angle
        and zero force; ``max_hitch_gap`` the largest pin separation reached.
    """
    settings = _check_inputs(vehicle, road, options, wheels)
    opts = dataclasses.replace(options, load_transfer=False)
    if len(vehicle.bodies) == 1:
        res = simulate_runout(vehicle, initial, settings, road, opts)
        return dataclasses.replace(res, options={**res.options, "level": "rigid"})
    model = SceneModel([vehicle], {vehicle.name: settings}, road, opts, contact=ContactModel(enabled=False),
                       hitches=False)
    res = run_model(model, initial).vehicles[vehicle.name]
    # each body's own time to rest (the run ends when the last body stops)
    l_ref = model.M.body[:, 2]
    bodies = {}
    for i, (name, b) in enumerate(res.bodies.items()):
        ttr = _own_rest_time(b, float(l_ref[i]), opts.v_stop, res.t_end) if res.success else None
        bodies[name] = dataclasses.replace(b, time_to_rest=ttr)
    # the hitches: the articulation and how far the pins drift apart (no force: they are ignored)
    hitches, gap = [], 0.0
    loads = model.loads[vehicle.name]
    for j, h in enumerate(vehicle.hitches):
        f, r = res.bodies[vehicle.bodies[j].name], res.bodies[vehicle.bodies[j + 1].name]
        hf, hr = f.history, r.history
        pin_f = np.stack([hf.x + np.cos(hf.heading) * h.front_point[0] - np.sin(hf.heading) * h.front_point[1],
                          hf.y + np.sin(hf.heading) * h.front_point[0] + np.cos(hf.heading) * h.front_point[1]], 1)
        pin_r = np.stack([hr.x + np.cos(hr.heading) * h.rear_point[0] - np.sin(hr.heading) * h.rear_point[1],
                          hr.y + np.sin(hr.heading) * h.rear_point[0] + np.cos(hr.heading) * h.rear_point[1]], 1)
        gap = max(gap, float(np.max(np.hypot(*(pin_f - pin_r).T))))
        hitches.append(HitchHistory(front=f.name, rear=r.name, static_load=float(loads.hitch[j]), t=hf.t,
                                    force=np.zeros((hf.t.size, 2)), force_body=np.zeros((hf.t.size, 2)),
                                    articulation=hf.heading - hr.heading, stop_moment=np.zeros(hf.t.size)))
    return dataclasses.replace(res, bodies=bodies, hitches=tuple(hitches), max_hitch_gap=gap,
                               method=f"rigid/{res.method}", options={**res.options, "level": "rigid"})


#: One vehicle alone at each level: ``fn(level, vehicle, initial, settings, road, options)`` (:func:`simulate_level`).
_ALONE = {
    "impact": lambda level, *inputs: None,
    "energy": lambda level, *inputs: _energy_runout(*inputs),
    "rigid": lambda level, *inputs: _rigid_runout(*inputs),
    "articulated": _articulated_alone,
    "load_transfer": _articulated_alone,
}

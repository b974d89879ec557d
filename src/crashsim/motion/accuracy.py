"""Run-out to a requested accuracy: the cheapest tolerance that meets it, with an error estimate.

``run_runout(..., accuracy=0.01)`` ("1 cm") answers two questions at once:
which solver settings are needed, and how large the error of the returned result is.  The
error of a rest position (against the same model integrated exactly, with ``eps`` and
``v_stop`` -> 0) has two parts, each with a share of the target:

===================================  ======  ===============================================
part                                 share   how it is estimated
===================================  ======  ===============================================
integration (``rtol``, ``atol``)      1/2    two runs a decade of rtol apart
low speed (``eps``, ``v_stop``)       1/2    analytic bounds pick them (1/4 each); one run
                                             with both halved measures their effect
===================================  ======  ===============================================

Procedure: choose ``eps`` and ``v_stop`` from the analytic bounds below; tighten rtol by
decades from ``start_rtol`` until two successive runs agree within the integration share;
make one check run at that rtol with ``eps / 2`` and ``v_stop / 2``; if the total estimate
meets the target, return the finer run of the pair, else halve ``eps`` and ``v_stop`` and
continue (from the check run).  The reported estimate is the **sum** of the two estimates
(not of the shares).  Cost: at least three runs; the report lists every run and the total
CPU time.  If ``min_rtol`` or the ``eps``/``v_stop`` floors are reached, or a run ends
without rest, the last run is returned with ``met = False`` and the reason.

Integration error (Richardson-style, with a safety factor)
----------------------------------------------------------
Runs are made at rtol = 1e-3, 1e-4, ... with ``atol = rtol * atol_ratio`` (default 1/100)
and the same ``eps`` and ``v_stop``.  For tolerance-proportional error control the global
error behaves as ``C rtol^p`` with ``p ~ 1`` (measured on the Table 6 scene: the integration
error falls ~10x per decade, ``plots/runout_benchmark.md``), so the finer run's error is
``|x_coarse - x_fine| / (10^p - 1) ~ |difference| / 9``.  We take

    e_int = max(|x_coarse - x_fine|,  rtol_fine * D)

i.e. (1) the **whole difference**, a safety factor of 9 on the Richardson estimate, which
covers ``p`` down to ~0.3 and errors that do not fall monotonically (RK45 at loose tolerance,
event location), and (2) a floor ``rtol * D``, ``D`` the longest CG path (for headings
``rtol * max(|heading change|, 1 rad)``), against two runs that agree by luck.  Positions and
headings are compared body by body; the largest difference counts.

Low-speed error: analytic bounds (note sec. 3.2, 3.3)
-----------------------------------------------------
With the regularised friction ``a(v) = a v / sqrt(v^2 + eps^2)`` a straight slide covers
``F(v) / a`` while slowing from v to 0, ``F(v) = (v sqrt(v^2 + eps^2) + eps^2 asinh(v/eps)) / 2``.

* **Rest threshold.**  The run stops when every body has ``|v_cg| <= v_stop`` and
  ``|yaw rate| L_ref <= v_stop``.  Since ``F(v) <= v^2/2 + eps v``, the travel still to come is
  at most ``(v_stop^2 + 2 eps v_stop) / (2 a_min)`` (-> the note's ``v_stop^2 / (2 a_min)``).
* **Regularisation.**  Integrating all the way down gives ``F(v_0)/a`` instead of
  ``v_0^2/(2a)``; since ``v (sqrt(v^2 + eps^2) - v) <= eps^2/2`` the bias is at most
  ``eps^2 (1/2 + asinh(v_0/eps)) / (2 a_min)`` (the note's ``O(eps^2/(mu g))`` with its log),
  ``v_0`` the largest initial speed of a body (CG speed plus ``|yaw rate| L_ref``).

``a_min`` is the **smallest** deceleration of the vehicle at low speed in any direction,
``g sum_k N_k f_k / sum_k N_k`` with ``f_k = mu_min`` for a locked/jammed wheel and
``min(b mu_min + f_r, mu_min)`` for a rolling or braked one (the weakest, along-the-wheel
direction), ``mu_min`` the smallest friction coefficient of the road and its zones (times the
wheel's ``mu_factor``), over every phase of the wheel schedule.  The heading analogues use
``omega_stop = v_stop / L_ref``, ``eps_omega = eps / r_min`` and the smallest spin deceleration
``alpha_min = sum_k N_k r_k f_k / I`` of each body (``r_k`` the wheel's distance from its CG).
``eps`` is the largest value (at most ``base_options.eps``, default 0.01 m/s, at least
1e-4 m/s) whose bound fits 1/4 of the target, then ``v_stop`` likewise (at most 0.05 m/s, the
note's range 0.02-0.05 m/s).

Low-speed error: measured
-------------------------
The bounds are exact for a straight slide and a pure spin, but **not** for slide-and-spin
motion: there contact speeds of some wheels pass close to zero while the body still moves
(the instantaneous centre sweeps past a wheel), and translation and rotation stop together
(note sec. 5 items 6-7), so the rotation left at the rest event decays more slowly than in a
pure spin.  Measured on a locked car at (1.8, 5.0) m/s and -3 rad/s: eps = 0.01 m/s moved the
rest position 0.88 mm against a straight-slide bound of 0.06 mm, and v_stop = 0.05 m/s the
heading 0.004 deg against a pure-spin bound of 0.0013 deg.  The low-speed error is therefore
also **measured**: both parts scale as the square of their speed (``eps^2`` times a slowly
varying log, ``v_stop^2``), so halving both divides their combined effect by ~4 and
``x(eps, v_stop) - x(eps/2, v_stop/2) ~ (3/4) E``.  The estimate is
``LOW_SPEED_SAFETY = 2`` times that difference (a safety of ~1.5 over Richardson, which also
absorbs the integration noise of the two runs), and never less than the analytic
``rest_threshold + regularisation``.  The two parts have opposite signs (the regularisation
lengthens the slide, the threshold shortens it); the difference measures their net effect,
which is the error.
"""

from __future__ import annotations

import dataclasses
import logging
import math
import time
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from .hitches import RunoutModel
from .levels import simulate_level
from .loads import STANDARD_GRAVITY
from .options import RunoutOptions
from .result import RunoutResult
from .road import Road
from .runners import Runout, RunoutCall, register_runner
from .simulate import simulate_scene
from .wheels import WheelSettings

__all__ = ["AccuracyReport", "AccuracyRun", "SHARES"]

_log = logging.getLogger("crashsim")

#: Shares of the target: rest threshold, regularisation, integration.
SHARES = (0.25, 0.25, 0.5)
#: Caps and floors of the chosen eps and v_stop [m/s].
V_STOP_MAX = 0.05
EPS_MIN = 1e-4
V_STOP_MIN = 1e-3
#: Safety factor on the low-speed (eps, v_stop) Richardson estimate (see the module docstring).
LOW_SPEED_SAFETY = 2.0


@dataclass(frozen=True)
class AccuracyRun:
    """One run made while searching for the tolerance.

    Attributes
    ----------
    rtol, atol : float
    eps, v_stop : float
        Regularisation speed and rest threshold of the run [m/s].
    status : str
        The run's status (``"rest"``, ``"time_limit"``, ``"solver_failure"``).
    nfev : int
    cpu_time : float
        Process time of the run [s].
    position_change, heading_change : float or None
        Largest change of a body's rest position [m] / heading [rad] from the previous run
        (None for the first run).
    """

    rtol: float
    atol: float
    eps: float
    v_stop: float
    status: str
    nfev: int
    cpu_time: float
    position_change: float | None
    heading_change: float | None


@dataclass(frozen=True)
class AccuracyReport:
    """What a run-out to an accuracy target (:func:`~crashsim.motion.run_runout`, ``accuracy=``) promised and what it cost (SI: m, rad, s).

    Attributes
    ----------
    target_position, target_heading : float, float or None
        Requested accuracy of every body's rest position [m] and heading [rad].
    estimate_position, estimate_heading : float
        Estimated error bound of the returned result: ``integration_* + low_speed_*``.
    integration_position, integration_heading : float
        Integration-error estimate (see the module docstring).
    low_speed_position, low_speed_heading : float
        Error estimate of ``eps`` and ``v_stop`` together: the larger of the measured
        (Richardson) value and the analytic ``rest_threshold_* + regularisation_*``.
    rest_threshold_position, rest_threshold_heading : float
        Analytic residual-motion bound of ``v_stop`` (straight slide / pure spin).
    regularisation_position, regularisation_heading : float
        Analytic bias bound of ``eps`` (straight slide / pure spin).
    met : bool
        True if both estimates are within their targets.
    settings : dict
        The chosen ``rtol``, ``atol``, ``eps``, ``v_stop``, with the ``engine``, ``method``,
        ``scheme`` (compiled engine) and ``level`` they were used with.
    runs : tuple of AccuracyRun
        Every run made, in order (the last is the returned one).
    cpu_time : float
        Total process time of all runs [s].
    nfev : int
        Total right-hand-side evaluations.
    a_min : float
        Smallest low-speed deceleration used in the bounds [m/s^2].
    message : str
    """

    target_position: float
    target_heading: float | None
    estimate_position: float
    estimate_heading: float
    integration_position: float
    integration_heading: float
    low_speed_position: float
    low_speed_heading: float
    rest_threshold_position: float
    rest_threshold_heading: float
    regularisation_position: float
    regularisation_heading: float
    met: bool
    settings: dict
    runs: tuple[AccuracyRun, ...]
    cpu_time: float
    nfev: int
    a_min: float
    message: str

    @property
    def n_runs(self) -> int:
        return len(self.runs)

    def to_dict(self) -> dict:
        """JSON-ready dict (SI units)."""
        d = dataclasses.asdict(self)
        d["n_runs"] = self.n_runs
        return d


# ---------------------------------------------------------------------------------------------- bounds
@dataclass(frozen=True)
class _Decel:
    a_min: float  # [m/s^2], vehicle
    alpha_min: np.ndarray  # [rad/s^2], per body
    r_min: np.ndarray  # [m], per body
    l_ref: np.ndarray  # [m], per body
    v0: float  # [m/s]
    w0: float  # [rad/s]


def _decelerations(vehicle: Vehicle, initial, settings: WheelSettings, road: Road) -> _Decel:
    model = RunoutModel(vehicle, settings.resolve(vehicle), road, RunoutOptions())
    mu_min = min([road.mu, *(z.mu for z in road.zones)])
    N = model.static_load
    f = np.full(len(N), np.inf)
    for _, phase in model.wheels.phases:
        for k, s in enumerate(phase):
            mu = mu_min * s.mu_factor
            fk = mu if s.is_sliding else min(s.brake * mu + (s.rolling_resistance or 0.0), mu)
            f[k] = min(f[k], fk)
    g = STANDARD_GRAVITY
    a_min = g * float(np.sum(N * f) / np.sum(N))
    nb = len(vehicle.bodies)
    rho = np.array([s.position for s in model.specs])
    r = np.hypot(rho[:, 0], rho[:, 1])
    alpha = np.zeros(nb)
    r_min = np.zeros(nb)
    for i in range(nb):
        on = model.wheel_body == i
        alpha[i] = float(np.sum(N[on] * r[on] * f[on])) / model.inertia[i]
        r_min[i] = max(float(np.min(r[on])), 1e-3) if on.any() else 1.0
    y0 = model.layout.pack(initial)
    L = model.layout
    speed = np.hypot(y0[L.vx], y0[L.vy])
    v0 = float(np.max(speed + np.abs(y0[L.w]) * model.l_ref))
    w0 = float(np.max(np.abs(y0[L.w])))
    return _Decel(a_min, alpha, r_min, model.l_ref.copy(), v0, w0)


def _combine(decs: list) -> _Decel:
    """The bounds of a scene: the weakest deceleration of any vehicle, every body's own."""
    return _Decel(min(d.a_min for d in decs), np.concatenate([d.alpha_min for d in decs]),
                  np.concatenate([d.r_min for d in decs]), np.concatenate([d.l_ref for d in decs]),
                  max(d.v0 for d in decs), max(d.w0 for d in decs))


def _residual(v: float, eps: float, a: float) -> float:
    """Residual travel bound (v^2 + 2 eps v) / (2 a)."""
    return (v * v + 2 * eps * v) / (2 * a) if a > 0 else math.inf


def _bias(eps: float, v0: float, a: float) -> float:
    """Regularisation bias bound eps^2 (1/2 + asinh(v0/eps)) / (2 a)."""
    if a <= 0:
        return math.inf
    return eps * eps * (0.5 + math.asinh(v0 / eps)) / (2 * a) if v0 > 0 else 0.0


def rest_bounds(dec: _Decel, eps: float, v_stop: float) -> tuple[float, float, float, float]:
    """(v_stop position, v_stop heading, eps position, eps heading) bounds [m, rad, m, rad]."""
    vs_pos = _residual(v_stop, eps, dec.a_min)
    eps_pos = _bias(eps, dec.v0, dec.a_min)
    vs_head = 0.0
    eps_head = 0.0
    for i in range(len(dec.alpha_min)):
        eps_w = eps / dec.r_min[i]
        vs_head = max(vs_head, _residual(v_stop / dec.l_ref[i], eps_w, dec.alpha_min[i]))
        eps_head = max(eps_head, _bias(eps_w, dec.w0, dec.alpha_min[i]))
    return vs_pos, vs_head, eps_pos, eps_head


def _largest(fn, lo: float, hi: float) -> float:
    """Largest x in [lo, hi] with fn(x) True (fn monotone: True below a threshold); lo if none."""
    if fn(hi):
        return hi
    if not fn(lo):
        return lo
    for _ in range(60):
        mid = math.sqrt(lo * hi)
        if fn(mid):
            lo = mid
        else:
            hi = mid
        if hi / lo < 1.001:
            break
    return lo


# ---------------------------------------------------------------------------------------------- driver
def _simulate_to_accuracy(
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    target_position: float,
    target_heading: float | None = None,
    base_options: RunoutOptions = RunoutOptions(),
    *,
    level: str | None = None,
    start_rtol: float = 1e-3,
    min_rtol: float = 1e-10,
    atol_ratio: float = 1e-2,
) -> tuple[RunoutResult, AccuracyReport]:
    """Run-out with the cheapest tolerance whose estimated rest-state error meets a target.

    Parameters
    ----------
    vehicle, initial, wheels, road
        As for :func:`~crashsim.motion.simulate_runout`.
    target_position : float
        Accuracy wanted for every body's rest position [m] (``"1 cm"`` -> 0.01), > 0.
    target_heading : float, optional
        Accuracy wanted for every body's rest heading [rad]; None: not targeted (still
        estimated and reported).
    base_options : RunoutOptions
        Everything but ``rtol``, ``atol``, ``eps`` and ``v_stop`` is kept (method, max_step,
        t_max, load_transfer, ...); ``base_options.eps`` caps the chosen eps.
    level : {"rigid", "articulated", "load_transfer"}, optional
        Fidelity level (:mod:`crashsim.motion.levels`); default ``articulated``, or
        ``load_transfer`` if ``base_options.load_transfer``.  The estimate is of the numerical
        error of that model, not of the model itself.
    start_rtol, min_rtol : float
        First and smallest rtol tried (decades in between).
    atol_ratio : float
        ``atol = rtol * atol_ratio``.

    Returns
    -------
    (RunoutResult, AccuracyReport)
        The run whose error was estimated (or the last run made if the target was not met).

    Raises
    ------
    ScenarioError
        Non-positive targets, a level without a numerical error (``impact``, ``energy``), or a
        vehicle without any low-speed deceleration (free rolling with zero rolling resistance:
        it never comes to rest, so no accuracy can be promised).

    Examples
    --------
    >>> from crashsim.vehicles import Axle, Body, Vehicle, BodyState
    >>> car = Vehicle("car", (Body("car", 1500.0, 2500.0, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    >>> res, rep = _simulate_to_accuracy(car, {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(0.75), 0.01)
    >>> rep.met, rep.estimate_position <= 0.01
    (True, True)
    """
    level = _check_targets(target_position, target_heading, base_options, level)
    settings = WheelSettings.all_locked() if wheels is None else wheels
    if not isinstance(vehicle, Vehicle) or vehicle.is_barrier:
        raise ScenarioError("needs a movable Vehicle (a barrier is not simulated)", field="vehicle")
    dec = _decelerations(vehicle, initial, settings, road)
    _check_deceleration(dec, f"wheels[{vehicle.name!r}]")

    def runner(opts):
        return simulate_level(level, vehicle, initial, settings, road, opts)

    result, report = _to_accuracy(runner, dec, target_position, target_heading, base_options, level, start_rtol,
                                  min_rtol, atol_ratio)
    if not report.met:
        _log.warning("run-out of %s: accuracy target not met: %s", vehicle.name, report.message)
    return result, report


def _scene_to_accuracy(
    vehicles, initial, wheels, road: Road, target_position: float, target_heading: float | None = None,
    base_options: RunoutOptions = RunoutOptions(), *, level: str | None = None, start_rtol: float = 1e-3,
    min_rtol: float = 1e-10, atol_ratio: float = 1e-2, **contact,
):
    """:func:`_simulate_to_accuracy` for a whole scene (:func:`~crashsim.motion.simulate_scene`, with contact).

    Every body of every vehicle counts; the bounds use the weakest deceleration of any
    vehicle.  ``contact`` takes ``simulate_scene``'s keywords (contact model, pair overrides,
    obstacles).

    Returns
    -------
    (SceneRunout, AccuracyReport)
    """
    level = _check_targets(target_position, target_heading, base_options, level)
    if level == "rigid":
        raise ScenarioError("the rigid level runs each vehicle alone; use simulate_to_accuracy per vehicle",
                            field="runout.level")
    vehicles = [v for v in vehicles if not v.is_barrier]
    wheels = dict(wheels or {})
    decs = []
    for v in vehicles:
        settings = wheels.get(v.name) or WheelSettings.all_locked()
        decs.append(_decelerations(v, {b.name: initial[b.name] for b in v.bodies}, settings, road))
        _check_deceleration(decs[-1], f"wheels[{v.name!r}]")
    lt = level == "load_transfer"

    def runner(opts):
        return _Merged(simulate_scene(vehicles, initial, wheels, road, dataclasses.replace(opts, load_transfer=lt),
                                      **contact))

    merged, report = _to_accuracy(runner, _combine(decs), target_position, target_heading, base_options, level,
                                  start_rtol, min_rtol, atol_ratio)
    if not report.met:
        _log.warning("scene run-out: accuracy target not met: %s", report.message)
    return merged.scene, report


@register_runner("energy", "rigid", accuracy=True)
def _each_to_accuracy(call: RunoutCall) -> Runout:
    """The runner of the levels without contact to an accuracy target: each movable vehicle alone
    (``energy`` refuses a target: the hand calculation has no numerical error)."""
    runout, reports = {}, {}
    for veh in call.movable:
        init = {b.name: call.initial[b.name] for b in veh.bodies}
        runout[veh.name], reports[veh.name] = _simulate_to_accuracy(
            veh, init, call.wheels.get(veh.name), call.road, call.accuracy, call.accuracy_heading, call.options,
            level=call.level)
    return Runout(runout, None, reports)


@register_runner("articulated", "load_transfer", accuracy=True)
def _joint_to_accuracy(call: RunoutCall) -> Runout:
    """The contact levels' runner to an accuracy target: the scene together (one report for every vehicle)."""
    joint, report = _scene_to_accuracy(call.movable, call.initial, call.wheels, call.road, call.accuracy,
                                       call.accuracy_heading, call.options, level=call.level, contact=call.contact,
                                       pair_contact=call.pair_contact, obstacles=call.obstacles)
    return Runout(dict(joint.vehicles), joint, {v.name: report for v in call.movable})


class _Merged:
    """A SceneRunout seen as one run-out (its bodies together) by the accuracy driver."""

    def __init__(self, scene):
        self.scene = scene
        self.bodies = {n: b for r in scene.vehicles.values() for n, b in r.bodies.items()}
        self.status = scene.status
        self.message = scene.message
        self.nfev = scene.nfev


def _check_targets(target_position, target_heading, base_options, level) -> str:
    for name, value in (("target_position", target_position), ("target_heading", target_heading)):
        if value is not None and not (math.isfinite(float(value)) and float(value) > 0):
            raise ScenarioError(f"must be a positive finite number, got {value!r}", field=f"runout.accuracy.{name}")
    if not isinstance(base_options, RunoutOptions):
        raise ScenarioError(f"must be RunoutOptions, got {type(base_options).__name__}", field="options")
    if level is None:
        level = "load_transfer" if base_options.load_transfer else "articulated"
    if level not in ("rigid", "articulated", "load_transfer"):
        raise ScenarioError(
            f"an accuracy target needs a numerically integrated level ('rigid', 'articulated', 'load_transfer'), "
            f"got {level!r} (the 'energy' hand calculation is exact for its own model; 'impact' has no run-out)",
            field="runout.accuracy",
        )
    return level


def _check_deceleration(dec: _Decel, field: str) -> None:
    if not (dec.a_min > 0 and np.all(dec.alpha_min > 0)):
        raise ScenarioError(
            "the vehicle has no deceleration at low speed (free-rolling wheels with zero rolling resistance, no "
            "locked wheel): it may never come to rest, so no accuracy can be promised; give rolling_resistance > 0",
            field=field,
        )


def _to_accuracy(runner, dec, target_position, target_heading, base_options, level, start_rtol, min_rtol, atol_ratio):
    """The search of the module docstring; ``runner(options)`` makes one run (``.bodies``, ``.status``, ``.nfev``)."""
    target_position = float(target_position)
    th = math.inf if target_heading is None else float(target_heading)
    share_v, share_e, share_i = SHARES

    # eps: as large as the analytic bound allows within its share (checked by a run below)
    def eps_ok(e):
        _, _, ep, eh = rest_bounds(dec, e, V_STOP_MIN)
        return ep <= share_e * target_position and eh <= share_e * th

    eps = _largest(eps_ok, EPS_MIN, max(base_options.eps, EPS_MIN))

    runs: list[AccuracyRun] = []

    def run(rtol, eps_run, v_stop, previous=None):
        opts = dataclasses.replace(base_options, rtol=rtol, atol=rtol * atol_ratio, eps=eps_run, v_stop=v_stop)
        c0 = time.process_time()
        res = runner(opts)
        cpu = time.process_time() - c0
        d_pos = d_head = None
        if previous is not None:
            d_pos, d_head = _rest_change(previous, res)
        runs.append(AccuracyRun(rtol, rtol * atol_ratio, eps_run, v_stop, res.status, res.nfev, cpu, d_pos, d_head))
        return res

    met = False
    message = ""
    rtol = float(start_rtol)
    result = prev = None
    e_pos = e_head = low_pos = low_head = math.inf

    def vstop_for(eps_now):
        def ok(v):
            vp, vh, _, _ = rest_bounds(dec, eps_now, v)
            return vp <= share_v * target_position and vh <= share_v * th

        return _largest(ok, max(V_STOP_MIN, eps_now / 10), V_STOP_MAX)

    v_stop = vstop_for(eps)
    room_pos, room_head = share_i * target_position, share_i * th
    while True:
        # integration: tighten rtol by decades until two runs agree within the integration share
        if prev is None:
            prev = run(rtol, eps, v_stop)
        ok_int = False
        while True:
            if prev.status != "rest":
                message = f"run at rtol {rtol:g} ended with status {prev.status!r} ({prev.message}): no rest to estimate"
                break
            if rtol / 10 < min_rtol * (1 - 1e-9):
                message = f"rtol reached min_rtol = {min_rtol:g} without meeting the target"
                break
            rtol /= 10
            cur = run(rtol, eps, v_stop, prev)
            prev = cur
            if cur.status != "rest":
                message = f"run at rtol {rtol:g} ended with status {cur.status!r} ({cur.message}): no rest to estimate"
                break
            dist, turn = _path_scales(cur)
            e_pos = max(runs[-1].position_change, rtol * dist)
            e_head = max(runs[-1].heading_change, rtol * max(turn, 1.0))
            if e_pos <= room_pos and e_head <= room_head:
                ok_int = True
                break
        result = prev
        if not ok_int:
            break

        # low-speed error (eps and v_stop): one run with both halved, Richardson with a safety factor
        vs_pos, vs_head, an_eps_pos, an_eps_head = rest_bounds(dec, eps, v_stop)
        check = run(rtol, eps / 2, v_stop / 2, result)
        if check.status != "rest":
            message = f"check run with eps/2, v_stop/2 ended with status {check.status!r} ({check.message})"
            break
        low_pos = max(LOW_SPEED_SAFETY * runs[-1].position_change, vs_pos + an_eps_pos)
        low_head = max(LOW_SPEED_SAFETY * runs[-1].heading_change, vs_head + an_eps_head)
        if e_pos + low_pos <= target_position and e_head + low_head <= th:
            met = True
            message = (f"target met at rtol {rtol:g}, eps {eps:.3g} m/s, v_stop {v_stop:.3g} m/s: rest positions within "
                       f"{e_pos + low_pos:.3g} m, headings within {e_head + low_head:.3g} rad (estimates)")
            break
        if eps / 2 < EPS_MIN * (1 - 1e-9) or v_stop / 2 < V_STOP_MIN * (1 - 1e-9):
            message = f"eps / v_stop reached their floors ({EPS_MIN}, {V_STOP_MIN} m/s) without meeting the target"
            break
        # halve both (the low-speed error falls ~4x) and continue from the check run (same rtol)
        eps, v_stop = eps / 2, v_stop / 2
        prev = check

    if result is None:
        result = prev
    report = AccuracyReport(
        target_position=target_position,
        target_heading=None if target_heading is None else float(target_heading),
        estimate_position=e_pos + low_pos,
        estimate_heading=e_head + low_head,
        integration_position=e_pos,
        integration_heading=e_head,
        low_speed_position=low_pos,
        low_speed_heading=low_head,
        rest_threshold_position=rest_bounds(dec, eps, v_stop)[0],
        rest_threshold_heading=rest_bounds(dec, eps, v_stop)[1],
        regularisation_position=rest_bounds(dec, eps, v_stop)[2],
        regularisation_heading=rest_bounds(dec, eps, v_stop)[3],
        met=met,
        settings={"engine": getattr(base_options, "engine", "scipy"), "method": base_options.method,
                  "scheme": getattr(base_options, "scheme", None), "rtol": rtol, "atol": rtol * atol_ratio, "eps": eps,
                  "v_stop": v_stop, "level": level},
        runs=tuple(runs),
        cpu_time=float(sum(r.cpu_time for r in runs)),
        nfev=int(sum(r.nfev for r in runs)),
        a_min=dec.a_min,
        message=message,
    )
    return result, report


def _rest_change(a: RunoutResult, b: RunoutResult) -> tuple[float, float]:
    """Largest change of a body's rest position [m] and heading [rad] between two runs."""
    d_pos = max((math.dist(x.rest_position, b.bodies[n].rest_position) for n, x in a.bodies.items()), default=0.0)
    d_head = max((abs(x.rest_heading - b.bodies[n].rest_heading) for n, x in a.bodies.items()), default=0.0)
    return float(d_pos), float(d_head)


def _path_scales(res: RunoutResult) -> tuple[float, float]:
    """Longest CG path [m] and largest heading change [rad] of the bodies."""
    dist = max((b.distance for b in res.bodies.values()), default=0.0)
    turn = max((abs(b.rest_heading - b.initial.heading) for b in res.bodies.values()), default=0.0)
    return float(dist), float(turn)

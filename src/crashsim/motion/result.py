"""Result objects of a run-out: what stopped it, where every body came to rest, and how it got there.

All numbers are SI (m, rad, s, m/s, rad/s, N, J) in the world frame unless a name says
otherwise.  Headings are continuous (not wrapped): a body that spun one and a half turns
ends with a heading 3 pi away from its initial one.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from ..geometry import wrap_angle
from ..vehicles import BodyState

__all__ = [
    "time_grid",
    "path_length",
    "PATH_SAMPLES_PER_S",
    "jsonable",
    "BodyHistory",
    "BodyRunout",
    "TrackSegment",
    "WheelTrack",
    "HitchHistory",
    "RunoutEvent",
    "RunoutResult",
    "STATUSES",
    "STATUS_MEANING",
    "limit_message",
]

#: Why a run-out stopped: at rest, or which limit or failure ended it (only ``"rest"`` is a success).
STATUSES = ("rest", "time_limit", "event_limit", "evaluation_limit", "wall_time_limit", "solver_failure")

#: What each status means, for reports.
STATUS_MEANING = {
    "rest": "at rest",
    "time_limit": "simulated time limit t_max reached while still moving",
    "event_limit": "too many events or restarts (event chattering)",
    "evaluation_limit": "work limit max_evaluations reached",
    "wall_time_limit": "computing-time limit max_wall_time reached",
    "solver_failure": "the integrator failed",
}


def limit_message(kind: str, options, t: float, speed: float | None = None, last_event: str | None = None) -> str:
    """The message of a run-out ended by a limit, the same for every engine.

    Parameters
    ----------
    kind : {"time_limit", "event_limit", "no_progress", "evaluation_limit", "wall_time_limit"}
    options : RunoutOptions
    t : float
        Simulated time at which the run stopped [s].
    speed : float, optional
        Rest measure at that time [m/s] (time limit).
    last_event : str, optional
        Description of the last event (event limits).
    """
    where = f"stopped at t = {t:.4g} s (simulated) before rest: "
    last = f"; last event: {last_event}" if last_event else ""
    if kind == "time_limit":
        return (f"t_max = {options.t_max} s reached before rest (max speed measure {speed:.4g} m/s > "
                f"v_stop = {options.v_stop} m/s)")
    if kind == "event_limit":
        return where + f"more than max_segments = {options.max_segments} integration segments (event chattering){last}"
    if kind == "no_progress":
        return where + f"events repeat at the same instant without progress in time (event chattering){last}"
    if kind == "evaluation_limit":
        return where + (f"max_evaluations = {options.max_evaluations} right-hand-side evaluations used up "
                        "(raise max_evaluations or loosen rtol)")
    if kind == "wall_time_limit":
        return where + f"max_wall_time = {options.max_wall_time:g} s of computing time used up"
    raise ValueError(kind)


def time_grid(t_end: float, dt: float):
    """0, dt, 2 dt, ... below ``t_end``, and ``t_end`` itself as the last time [s] (a multiple of
    dt within 1e-9 dt of ``t_end`` is replaced by it); ``dt`` > 0 is the caller's to check."""
    n = int(np.floor(t_end / dt + 1e-9))
    times = dt * np.arange(n + 1, dtype=float)
    if t_end - times[-1] > 1e-9 * dt:
        return np.append(times, t_end)
    times[-1] = t_end
    return times


def jsonable(value: Any) -> Any:
    """``value`` with NumPy arrays and scalars, tuples and dict keys turned into plain JSON types
    (lists, floats, ints, str keys); used by ``to_dict`` here and by the command line's JSON output."""
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (np.floating, float)):
        v = float(value)
        return v if math.isfinite(v) else None
    if isinstance(value, (np.integer,)):
        return int(value)
    if isinstance(value, np.bool_):
        return bool(value)
    return value


@dataclass(frozen=True, eq=False)
class BodyHistory:
    """Sampled time history of one body (arrays of equal length).

    Attributes
    ----------
    t : ndarray
        Time after separation [s].
    x, y : ndarray
        CG position [m].
    heading : ndarray
        Heading [rad], continuous.
    vx, vy : ndarray
        CG velocity [m/s].
    yaw_rate : ndarray
        [rad/s].
    """

    t: np.ndarray
    x: np.ndarray
    y: np.ndarray
    heading: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    yaw_rate: np.ndarray


@dataclass(frozen=True, eq=False)
class BodyRunout:
    """Run-out of one body.

    Attributes
    ----------
    name : str
    initial, final : BodyState
        State at separation and at the end of the run.
    rest_position : (float, float)
        CG position at the end of the run [m] (the rest position if the run ended at rest).
    rest_heading : float
        Heading at the end of the run [rad], continuous from the initial heading.
    time_to_rest : float or None
        Time from separation to rest [s]; None unless the run ended at rest.
    distance : float
        Length of the CG path [m].
    history : BodyHistory
        Sampled history.
    sol : callable
        ``sol(t)`` -> array ``(6,) + shape(t)`` of (x, y, heading, vx, vy, yaw_rate) at any
        time in the run [s] (the solver's dense output).
    """

    name: str
    initial: BodyState
    final: BodyState
    rest_position: tuple[float, float]
    rest_heading: float
    time_to_rest: float | None
    distance: float
    history: BodyHistory
    sol: Callable[[Any], np.ndarray]

    @property
    def rest_heading_wrapped(self) -> float:
        """Rest heading wrapped to (-pi, pi] [rad]."""
        return float(wrap_angle(self.rest_heading))


@dataclass(frozen=True, eq=False)
class TrackSegment:
    """A stretch of a wheel's track in which the wheel either slides or rolls.

    Attributes
    ----------
    kind : {"sliding", "rolling"}
        ``sliding``: the wheel is locked/jammed or its lateral demand is saturated (a tyre
        mark is expected); ``rolling``: partial slip (no mark expected).
    t : ndarray, shape (n,)
        Sample times [s]; consecutive segments share their boundary sample.
    points : ndarray, shape (n, 2)
        Contact positions [m].
    """

    kind: str
    t: np.ndarray
    points: np.ndarray

    @property
    def length(self) -> float:
        """Polyline length [m]."""
        return float(np.sum(np.hypot(*np.diff(self.points, axis=0).T))) if len(self.points) > 1 else 0.0


@dataclass(frozen=True, eq=False)
class WheelTrack:
    """Track of one tyre contact.

    Attributes
    ----------
    key, body, axle_index, axle_name, side : str, str, int, str, str
        Identification (see :mod:`crashsim.motion.wheels`).
    static_load : float
        Static normal load [N].
    t : ndarray
        Sample times [s].
    points : ndarray, shape (n, 2)
        Contact positions [m].
    sliding : ndarray of bool
        Sliding flag at each sample.
    load : ndarray
        Normal load at each sample [N] (equal to ``static_load`` without load transfer).
    segments : tuple of TrackSegment
        The track split into sliding and rolling stretches (split at sample resolution).
    path_length : float
        Contact-point path length ``integral |v_k| dt`` [m].
    sliding_length : float
        Part of the path travelled while sliding [m] (tyre-mark length).
    energy : float
        Energy dissipated by the tyre force ``integral -F_k . v_k dt`` [J].
    """

    key: str
    body: str
    axle_index: int
    axle_name: str
    side: str
    static_load: float
    t: np.ndarray
    points: np.ndarray
    sliding: np.ndarray
    load: np.ndarray
    segments: tuple[TrackSegment, ...]
    path_length: float
    sliding_length: float
    energy: float


@dataclass(frozen=True, eq=False)
class HitchHistory:
    """Force history of one hitch.

    Attributes
    ----------
    front, rear : str
        Body names.
    static_load : float
        Static vertical hitch load [N] (kingpin load).
    t : ndarray
        Sample times [s].
    force : ndarray, shape (n, 2)
        Horizontal hitch force **on the front body**, world frame [N] (the rear body gets
        the opposite force).
    force_body : ndarray, shape (n, 2)
        The same force in the front body's axes (longitudinal forward, lateral left) [N]:
        a positive longitudinal value means the rear body pushes the front body.
    articulation : ndarray
        Articulation angle ``heading_front - heading_rear`` [rad].
    stop_moment : ndarray
        Moment of a closed articulation stop on the front body [N m] (0 while open).
    """

    front: str
    rear: str
    static_load: float
    t: np.ndarray
    force: np.ndarray
    force_body: np.ndarray
    articulation: np.ndarray
    stop_moment: np.ndarray

    @property
    def peak_force(self) -> float:
        """Largest horizontal hitch force magnitude [N]."""
        return float(np.max(np.hypot(*self.force.T))) if len(self.force) else 0.0


@dataclass(frozen=True)
class RunoutEvent:
    """Something that happened during the run (for traceability).

    Attributes
    ----------
    t : float
        Time [s] after the first separation.
    kind : str
        ``"zone_enter"``, ``"zone_exit"``, ``"schedule"`` (wheel settings change),
        ``"stop_closed"``, ``"stop_impact"``, ``"stop_open"`` (articulation stops),
        ``"vehicle_rest"`` (a vehicle comes to rest), ``"impact"`` (a secondary impact),
        ``"contact"`` (sustained contact begins), ``"contact_pressed"`` (a pair pressed deeper
        than its crush), ``"contact_end"``, ``"armed"`` (a pair that touched at separation has
        separated), ``"zone_missed"``, and the run's end: ``"rest"`` or a limit status.
    detail : str
        Human-readable description (wheel, zone, bodies, values in SI).
    energy : float
        Kinetic energy dissipated by the event [J] (articulation-stop and secondary impacts).
    vehicles : tuple of str
        The vehicles the event concerns (empty: the whole scene).
    data : dict
        The event's numbers (SI), for reports in other units: e.g. ``{"angle_rad": ...}`` for
        a stop, ``{"speed_m_s": ...}`` for a contact.
    place : (float, float) or None
        Where it happened, world frame [m] (the wheel, the hitch pin, the contact point, the
        vehicle's first body at rest); None for events of the whole scene.
    """

    t: float
    kind: str
    detail: str
    energy: float = 0.0
    vehicles: tuple = ()
    data: dict = field(default_factory=dict, compare=False)
    place: tuple | None = None


@dataclass(frozen=True, eq=False)
class RunoutResult:
    """Result of the run-out of one vehicle.

    Attributes
    ----------
    vehicle : str
        Vehicle name.
    success : bool
        True only if the run ended at rest (``status == "rest"``); positions of a run that
        hit the time limit or failed are not rest positions.
    status : {"rest", "time_limit", "solver_failure"}
        Why the run stopped (also available as ``termination``).
    message : str
        Explanation; for a solver failure, solve_ivp's message.
    t_end : float
        Time at the end of the run [s].
    nfev, njev, nlu : int
        Right-hand-side evaluations, Jacobian evaluations and LU decompositions (solver
        work; the pymunk cross-check reports its step count as nfev).
    n_segments : int
        Number of integration segments (restarts at events and scheduled changes).
    bodies : dict of str to BodyRunout
    wheels : dict of str to WheelTrack
    hitches : tuple of HitchHistory
    events : tuple of RunoutEvent
    kinetic_energy_initial, kinetic_energy_final : float
        [J].
    energy_dissipated : float
        Sum of the wheels' dissipated energies [J]; with an ideal hitch and no stop impacts
        it equals the kinetic-energy loss.
    max_hitch_gap : float
        Largest distance between paired hitch pins over the samples [m] (constraint drift).
    method : str
        ``"scipy/<method>"`` or ``"pymunk/dt=<dt>"``.
    options : dict
        The options used.
    sol : callable
        ``sol(t)`` -> full state vector(s) (see :class:`~crashsim.motion.layout.StateLayout`).
    layout : StateLayout
    gravity_work : float
        Work of the in-plane gravity on a sloped road [J] (0 on a level road).
    rollover : dict or None
        With the wheel-lift and rollover check on (:mod:`crashsim.motion.rollover`): each body's
        threshold [g], whether a body rolled, which bodies lifted wheels, and ``valid_until_s``,
        the time from which the planar result is outside its validity (None: throughout within),
        and under ``"history"`` each body's sampled load transfer ratio and lateral acceleration [g]
        (figures only: not in the JSON); None when the check is off.
    """

    vehicle: str
    success: bool
    status: str
    message: str
    t_end: float
    nfev: int
    njev: int
    nlu: int
    n_segments: int
    bodies: dict[str, BodyRunout]
    wheels: dict[str, WheelTrack]
    hitches: tuple[HitchHistory, ...]
    events: tuple[RunoutEvent, ...]
    kinetic_energy_initial: float
    kinetic_energy_final: float
    energy_dissipated: float
    max_hitch_gap: float
    method: str
    options: dict
    sol: Callable[[Any], np.ndarray]
    layout: Any
    gravity_work: float = 0.0
    rollover: dict | None = None

    @property
    def termination(self) -> str:
        """Alias of :attr:`status`."""
        return self.status

    @property
    def energy_residual(self) -> float:
        """``(KE_0 + gravity work - KE_end - tyre dissipation - stop-impact losses) / KE_0``: spurious work (constraint drift, solver error).

        Closes only for a vehicle that meets nobody after separation; the scene's energy
        ledger (:attr:`crashsim.motion.scene_result.SceneRunout.energy`) closes always.
        """
        ke0 = self.kinetic_energy_initial
        impacts = sum(e.energy for e in self.events)
        return ((ke0 + self.gravity_work - self.kinetic_energy_final - self.energy_dissipated - impacts) / ke0
                if ke0 > 0 else 0.0)

    def table(self, times=None) -> dict[str, np.ndarray]:
        """History of every body as columns (name with unit -> array), for CSV export.

        Parameters
        ----------
        times : array_like, optional
            Times [s] to report (e.g. every 0.1 s): body states come from the dense solution
            (exact to the integration tolerance; a body at rest stays there), hitch forces are
            interpolated linearly between the stored samples.  Default: the stored samples
            (``options.sample_dt`` apart).

        Returns
        -------
        dict
            ``"t [s]"`` and, per body, ``"<body>.x [m]"``, ``".y [m]"``, ``".heading [rad]"``,
            ``".vx [m/s]"``, ``".vy [m/s]"``, ``".yaw_rate [rad/s]"``; per hitch
            ``"<front>-<rear>.force_long [N]"``, ``".force_lat [N]"``, ``".articulation [rad]"``.
        """
        first = next(iter(self.bodies.values()))
        t = first.history.t if times is None else np.asarray(times, dtype=float)
        cols: dict[str, np.ndarray] = {"t [s]": t}
        units = {"x": "m", "y": "m", "heading": "rad", "vx": "m/s", "vy": "m/s", "yaw_rate": "rad/s"}
        states = {}
        for name, body in self.bodies.items():
            states[name] = None if times is None else np.asarray(body.sol(np.clip(t, 0.0, self.t_end)))
            for i, (fld, unit) in enumerate(units.items()):
                cols[f"{name}.{fld} [{unit}]"] = getattr(body.history, fld) if times is None else states[name][i]
        for h in self.hitches:
            if times is None:
                long, lat, art = h.force_body[:, 0], h.force_body[:, 1], h.articulation
            else:
                long, lat = (np.interp(t, h.t, h.force_body[:, c]) for c in (0, 1))
                art = states[h.front][2] - states[h.rear][2]
            cols[f"{h.front}-{h.rear}.force_long [N]"] = long
            cols[f"{h.front}-{h.rear}.force_lat [N]"] = lat
            cols[f"{h.front}-{h.rear}.articulation [rad]"] = art
        return cols

    def to_dict(self, *, history: bool = True) -> dict:
        """JSON-ready dict (SI units; NaN/inf become None).

        Parameters
        ----------
        history : bool
            Include sampled histories and tracks (large); summaries are always included.
        """
        bodies = {}
        for name, b in self.bodies.items():
            d = {
                "rest_position_m": list(b.rest_position),
                "rest_heading_rad": b.rest_heading,
                "rest_heading_wrapped_rad": b.rest_heading_wrapped,
                "time_to_rest_s": b.time_to_rest,
                "distance_m": b.distance,
                "initial": {
                    "position_m": list(b.initial.position),
                    "heading_rad": b.initial.heading,
                    "velocity_m_s": list(b.initial.velocity),
                    "yaw_rate_rad_s": b.initial.yaw_rate,
                },
                "final_velocity_m_s": list(b.final.velocity),
                "final_yaw_rate_rad_s": b.final.yaw_rate,
            }
            if history:
                h = b.history
                d["history"] = {
                    "t_s": h.t,
                    "x_m": h.x,
                    "y_m": h.y,
                    "heading_rad": h.heading,
                    "vx_m_s": h.vx,
                    "vy_m_s": h.vy,
                    "yaw_rate_rad_s": h.yaw_rate,
                }
            bodies[name] = d
        wheels = {}
        for key, w in self.wheels.items():
            d = {
                "body": w.body,
                "axle_index": w.axle_index,
                "axle_name": w.axle_name,
                "side": w.side,
                "static_load_N": w.static_load,
                "path_length_m": w.path_length,
                "sliding_length_m": w.sliding_length,
                "energy_J": w.energy,
            }
            if history:
                d["segments"] = [{"kind": s.kind, "t_s": s.t, "points_m": s.points} for s in w.segments]
            wheels[key] = d
        hitches = []
        for h in self.hitches:
            d = {"front": h.front, "rear": h.rear, "static_load_N": h.static_load, "peak_force_N": h.peak_force}
            if history:
                d.update(
                    t_s=h.t,
                    force_world_N=h.force,
                    force_front_axes_N=h.force_body,
                    articulation_rad=h.articulation,
                    stop_moment_Nm=h.stop_moment,
                )
            hitches.append(d)
        return jsonable(
            {
                "vehicle": self.vehicle,
                "success": self.success,
                "status": self.status,
                "message": self.message,
                "t_end_s": self.t_end,
                "method": self.method,
                "nfev": self.nfev,
                "njev": self.njev,
                "nlu": self.nlu,
                "n_segments": self.n_segments,
                "kinetic_energy_initial_J": self.kinetic_energy_initial,
                "kinetic_energy_final_J": self.kinetic_energy_final,
                "energy_dissipated_J": self.energy_dissipated,
                **({"gravity_work_J": self.gravity_work} if self.gravity_work else {}),
                "energy_residual": self.energy_residual,
                "max_hitch_gap_m": self.max_hitch_gap,
                "options": self.options,
                "bodies": bodies,
                "wheels": wheels,
                "hitches": hitches,
                "events": [{"t_s": e.t, "kind": e.kind, "detail": e.detail, "energy_J": e.energy, **e.data}
                           for e in self.events],
                **({"rollover": {k: v for k, v in self.rollover.items() if k != "history"}}
                   if self.rollover is not None else {}),
            }
        )


#: Samples per second of the dense solution used to measure the CG path length.
PATH_SAMPLES_PER_S = 4000


def path_length(sol, t: np.ndarray) -> np.ndarray:
    """Cumulative CG path length at sorted times ``t`` from ``t[0]`` (trapezoid on a fine grid of the dense output)."""
    t = np.asarray(t, dtype=float)
    if len(t) == 0:
        return t
    n = max(int((t[-1] - t[0]) * PATH_SAMPLES_PER_S), 16)
    grid = np.union1d(np.linspace(t[0], t[-1], n + 1), t)
    sv = np.asarray(sol(grid))
    v = np.hypot(sv[3], sv[4])
    s = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]) * np.diff(grid))])
    return np.interp(t, grid, s)

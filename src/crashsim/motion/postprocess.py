"""Turn integrated states into a :class:`~crashsim.motion.result.RunoutResult`.

One builder, :func:`build_result`, from named inputs (:class:`ResultInputs`), shared by both
engines (:func:`assemble_scene`), the energy level and the pymunk cross-check
(:func:`chunk_inputs`), so all report the same quantities computed the same way.

:func:`chunk_inputs` takes its states as *chunks*: consecutive pieces of the run with constant
segment inputs (:class:`~crashsim.motion.hitches.SegmentParams`).

* sample chunks ``(seg, t, Y)``: states ``Y`` (n_state, K) at times ``t`` (K,) for the
  histories and tracks;
* quadrature chunks ``(seg, weights, Y)``: states at quadrature nodes with their weights [s]
  for path lengths and dissipated energies (Gauss-Legendre on the solver steps for SciPy,
  the step rule itself for pymunk).
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass
from typing import Callable, NamedTuple, Sequence

import numpy as np

from .hitches import RunoutModel, SegmentParams, hitch_rows
from .layout import StateLayout
from .rollover import RollMonitor, roll_summary, with_events
from .scene_model import kernels
from .summaries import contact_summaries, event_places
from .result import BodyHistory, BodyRunout, HitchHistory, RunoutEvent, RunoutResult, TrackSegment, WheelTrack
from .scene_result import PairSummary, SceneRunout

__all__ = ["ResultInputs", "build_result", "chunk_inputs", "gauss_legendre_chunks", "split_track"]

GL_NODES, GL_WEIGHTS = np.polynomial.legendre.leggauss(5)
_log = logging.getLogger("crashsim")

#: Distance from every zone edge [m] beyond which a membership disagreement at a sample is a missed crossing.
ZONE_MISS_TOL = 1e-6


def gauss_legendre_chunks(ts: np.ndarray, sol: Callable, seg: SegmentParams):
    """Quadrature chunk of 5-point Gauss-Legendre rules on each solver step of a segment.

    Parameters
    ----------
    ts : ndarray
        Step boundaries of the segment [s] (``OdeSolution.ts``).
    sol : callable
        Dense output of the segment.
    seg : SegmentParams

    Returns
    -------
    (SegmentParams, ndarray, ndarray)
        ``(seg, weights [s], states)``.
    """
    a, b = ts[:-1], ts[1:]
    half = 0.5 * (b - a)
    nodes = (0.5 * (a + b))[:, None] + half[:, None] * GL_NODES[None, :]
    weights = half[:, None] * GL_WEIGHTS[None, :]
    nodes, weights = nodes.ravel(), weights.ravel()
    return seg, weights, np.asarray(sol(nodes)).reshape(-1, nodes.size)


def split_track(t: np.ndarray, points: np.ndarray, sliding: np.ndarray, starts=None) -> tuple[TrackSegment, ...]:
    """Split a sampled track into sliding and rolling stretches sharing their boundary samples.

    ``starts`` (optional): indices ``i`` where ``sliding[i] != sliding[i - 1]``, if the caller
    has them already.  A track that never changes is one segment sharing ``t`` and ``points``.
    """
    n = len(t)
    if n == 0:
        return ()
    change = (np.flatnonzero(sliding[1:] != sliding[:-1]) + 1 if starts is None else np.asarray(starts)).tolist()
    if not change:
        return (TrackSegment(kind="sliding" if sliding[0] else "rolling", t=t, points=points),)
    out = []
    for a, b in zip([0] + change, change + [n - 1]):
        b = max(b, a)
        out.append(
            TrackSegment(kind="sliding" if sliding[a] else "rolling", t=t[a : b + 1].copy(), points=points[a : b + 1].copy())
        )
    return tuple(out)


def _missed_zone_samples(model, samples, wx, wy):
    """First (time, wheel key) at which the registered zone membership contradicts the position, or None."""
    for (seg, t, _), x, y in zip(samples, wx, wy):
        pts = np.stack([x.ravel(), y.ravel()], 1)
        for z, zone in enumerate(model.road.zones):
            inside = zone.contains(pts).reshape(x.shape)
            clear = np.abs(zone.signed_distance(pts)).reshape(x.shape) > ZONE_MISS_TOL
            bad = (inside != seg.membership[:, z : z + 1]) & clear
            if bad.any():
                k, i = np.argwhere(bad)[np.argmin(np.argwhere(bad)[:, 1])]
                return float(t[i]), model.specs[k].key
    return None


def chunk_inputs(
    model: RunoutModel,
    *,
    samples: Sequence[tuple[SegmentParams, np.ndarray, np.ndarray]],
    quadrature: Sequence[tuple[SegmentParams, np.ndarray, np.ndarray]],
    status: str,
    message: str,
    t_end: float,
    y_initial: np.ndarray,
    y_final: np.ndarray,
    sol: Callable,
    events: Sequence[RunoutEvent],
    nfev: int,
    njev: int,
    nlu: int,
    n_segments: int,
    method: str,
    hitch_force: np.ndarray | None = None,
    check_zones: bool = False,
) -> ResultInputs:
    """The :class:`ResultInputs` of a run given as chunks (see the module docstring for the chunk format).

    ``hitch_force`` (n_samples, 2 n_hitches), if given, replaces the hitch forces computed
    from the constraint multipliers (the pymunk cross-check reports its own joint forces).
    ``check_zones`` compares, at every sample, the zone membership the integration used with
    the point-in-polygon test of the sampled contact positions; samples farther than
    ``ZONE_MISS_TOL`` from every edge that disagree mean a zone was stepped over (a thin
    zone and a too large ``max_step``): a ``"zone_missed"`` event is added and a warning logged.
    """
    L = model.layout
    nb, nh = L.n_bodies, model.n_hitches
    specs = model.specs

    # ---- samples
    t_all, y_cols, wx, wy, slide, loads, lam_h, stop_m = [], [], [], [], [], [], [], []
    for seg, t, Y in samples:
        ev = model.evaluate(Y, seg)
        t_all.append(t)
        y_cols.append(Y)
        wx.append(ev.wheel_x)
        wy.append(ev.wheel_y)
        slide.append(ev.sliding)
        loads.append(ev.load)
        lam_h.append(ev.lam[:, : 2 * nh])
        moments = np.zeros((len(t), nh))
        for n, (j, _) in enumerate(seg.locks):
            moments[:, j] = ev.lam[:, 2 * nh + n]
        stop_m.append(moments)
    missed = None
    if check_zones and model.road.zones:
        missed = _missed_zone_samples(model, samples, wx, wy)
    t = np.concatenate(t_all)
    Y = np.concatenate(y_cols, axis=1)
    wx, wy, slide = np.concatenate(wx, 1), np.concatenate(wy, 1), np.concatenate(slide, 1)
    loads = np.concatenate(loads, 1)
    lam_h = np.concatenate(lam_h, 0) if hitch_force is None else np.asarray(hitch_force, dtype=float)
    stop_m = np.concatenate(stop_m, 0)

    # ---- integrals
    dist = np.zeros(nb)
    path = np.zeros(len(specs))
    slide_len = np.zeros(len(specs))
    energy = np.zeros(len(specs))
    for seg, w, Yq in quadrature:
        if w.size == 0:
            continue
        ev = model.evaluate(Yq, seg)
        dist += np.hypot(Yq[L.vx], Yq[L.vy]) @ w
        path += ev.wheel_speed @ w
        slide_len += (ev.wheel_speed * ev.sliding) @ w
        energy -= ev.tyre_power @ w

    max_gap = 0.0
    if nh:
        psi = Y[L.psi]
        _, g, _, _ = hitch_rows(
            model.front_points, model.rear_points, np.cos(psi), np.sin(psi), Y[L.x], Y[L.y], Y[L.vx], Y[L.vy], Y[L.w]
        )
        max_gap = float(np.max(np.hypot(g[0::2], g[1::2])))
    return ResultInputs(
        t=t,
        Y=Y,
        points=np.stack([wx, wy], axis=-1),
        sliding=slide,
        load=loads,
        hitch_force=lam_h,
        stop_moment=stop_m,
        distance=dist,
        path_length=path,
        sliding_length=slide_len,
        energy=energy,
        max_gap=max_gap,
        missed=missed,
        status=status,
        message=message,
        t_end=t_end,
        y_initial=y_initial,
        y_final=y_final,
        sol=sol,
        events=events,
        nfev=nfev,
        njev=njev,
        nlu=nlu,
        n_segments=n_segments,
        method=method,
    )


class ResultInputs(NamedTuple):
    """What :func:`build_result` makes a :class:`~crashsim.motion.result.RunoutResult` of: the
    computed arrays of one vehicle's run and what the run says of itself (all SI).

    t : ndarray, shape (K,)
        Sample times [s].
    Y : ndarray, shape (n_state, K)
        Sampled states.
    points : ndarray, shape (n_wheels, K, 2)
        Contact positions [m] at the samples.
    sliding, load : ndarray, shape (n_wheels, K)
        Sliding flags and normal loads [N] at the samples.
    hitch_force : ndarray, shape (K, 2 n_hitches)
        Hitch forces on the front bodies, world frame [N] (NaN where a level has none).
    stop_moment : ndarray, shape (K, n_hitches)
        Moments of closed articulation stops [N m].
    distance : ndarray, shape (n_bodies,)
        CG path lengths [m].
    path_length, sliding_length, energy : ndarray, shape (n_wheels,)
        Contact path lengths [m], their sliding parts [m], dissipated energies [J].
    max_gap : float
        Largest pin gap over the samples [m].
    status, message, t_end, y_initial, y_final, sol, events, method, nfev, njev, nlu, n_segments
        As :class:`~crashsim.motion.result.RunoutResult`.
    missed : (float, str) or None
        Time [s] and wheel key of the first sample inside a zone the integration did not
        register; adds a ``"zone_missed"`` event and logs a warning.
    kinetic_energies : (float, float), optional
        Initial and final kinetic energy [J], if already computed.
    energy_dissipated : float, optional
        Energy dissipated by all the vehicle's tyres [J] (default: the sum of ``energy``; given
        where ``energy`` holds some of the wheels only).
    gravity_work : float
        Work of the in-plane gravity [J].
    static_load : ndarray, shape (n_wheels,), optional
        The wheels' static loads [N] (default: the model's).
    options : dict, optional
        The options recorded in the result (default: the model's).
    rollover : dict, optional
        The vehicle's rollover verdict (:func:`~crashsim.motion.rollover.roll_summary`), with the
        check on.
    """

    t: np.ndarray
    Y: np.ndarray
    points: np.ndarray
    sliding: np.ndarray
    load: np.ndarray
    hitch_force: np.ndarray
    stop_moment: np.ndarray
    distance: np.ndarray
    path_length: np.ndarray
    sliding_length: np.ndarray
    energy: np.ndarray
    max_gap: float
    status: str
    message: str
    t_end: float
    y_initial: np.ndarray
    y_final: np.ndarray
    sol: Callable
    events: Sequence[RunoutEvent]
    method: str
    nfev: int = 0
    njev: int = 0
    nlu: int = 0
    n_segments: int = 0
    missed: tuple | None = None
    kinetic_energies: tuple | None = None
    energy_dissipated: float | None = None
    gravity_work: float = 0.0
    static_load: np.ndarray | None = None
    options: dict | None = None
    rollover: dict | None = None


def build_result(model, inputs: ResultInputs) -> RunoutResult:
    """The result objects of one vehicle's run: the one builder of a
    :class:`~crashsim.motion.result.RunoutResult` (both engines, the energy level and the pymunk
    cross-check).

    Parameters
    ----------
    model : RunoutModel or compatible
        Needs ``layout``, ``specs``, ``vehicle.name``, ``static_load``, ``loads.hitch``,
        ``mass``, ``inertia`` and ``options`` (or ``options_dict``).
    inputs : ResultInputs
        The computed arrays and what the run says of itself.
    """
    (t, Y, points, sliding, load, hitch_force, stop_moment, distance, path_length, sliding_length, energy, max_gap,
     status, message, t_end, y_initial, y_final, sol, events, method, nfev, njev, nlu, n_segments, missed,
     kinetic_energies, energy_dissipated, gravity_work, static_load, options, rollover) = inputs
    L = model.layout
    nh = hitch_force.shape[1] // 2  # the hitches modelled (none at the rigid level)
    specs = model.specs
    static_load = model.static_load if static_load is None else static_load
    events = list(events)
    if missed:
        t_miss, key = missed
        detail = (
            f"wheel {key} is in a friction zone the integration did not register at t = {t_miss:.4f} s: "
            "a zone narrower than speed x max_step was stepped over; reduce options.max_step"
        )
        _log.warning("run-out of %s: %s", model.vehicle.name, detail)
        events.insert(-1, RunoutEvent(t_miss, "zone_missed", detail))

    at_rest = status == "rest"
    initial = L.unpack(y_initial)
    final = L.unpack(y_final)
    bodies = {}
    for i, name in enumerate(L.bodies):

        def body_sol(tq, _i=i):
            yq = np.asarray(sol(tq))
            return np.stack([yq[getattr(L, f).start + _i] for f in L.FIELDS])

        hist = BodyHistory(
            t=t,
            x=Y[L.x][i],
            y=Y[L.y][i],
            heading=Y[L.psi][i],
            vx=Y[L.vx][i],
            vy=Y[L.vy][i],
            yaw_rate=Y[L.w][i],
        )
        bodies[name] = BodyRunout(
            name=name,
            initial=initial[name],
            final=final[name],
            rest_position=final[name].position,
            rest_heading=final[name].heading,
            time_to_rest=float(t_end) if at_rest else None,
            distance=float(distance[i]),
            history=hist,
            sol=body_sol,
        )

    wheels = {}
    # where each wheel's sliding flag changes (one vectorised pass over all wheels)
    rows, cols = np.nonzero(sliding[:, 1:] != sliding[:, :-1])
    bounds = np.searchsorted(rows, np.arange(len(specs) + 1)).tolist()
    cols = cols + 1
    for k, s in enumerate(specs):
        pts = points[k]
        wheels[s.key] = WheelTrack(
            key=s.key,
            body=s.body,
            axle_index=s.axle_index,
            axle_name=s.axle_name,
            side=s.side,
            static_load=float(static_load[k]),
            t=t,
            points=pts,
            sliding=sliding[k],
            load=load[k],
            segments=split_track(t, pts, sliding[k], cols[bounds[k] : bounds[k + 1]]),
            path_length=float(path_length[k]),
            sliding_length=float(sliding_length[k]),
            energy=float(energy[k]),
        )

    hitches = []
    if nh:
        psi = Y[L.psi]
        for j in range(nh):
            force = hitch_force[:, 2 * j : 2 * j + 2]
            cf, sf = np.cos(psi[j]), np.sin(psi[j])
            force_body = np.stack([cf * force[:, 0] + sf * force[:, 1], cf * force[:, 1] - sf * force[:, 0]], 1)
            hitches.append(
                HitchHistory(
                    front=L.bodies[j],
                    rear=L.bodies[j + 1],
                    static_load=float(model.loads.hitch[j]),
                    t=t,
                    force=force.copy(),
                    force_body=force_body,
                    articulation=psi[j] - psi[j + 1],
                    stop_moment=stop_moment[:, j].copy(),
                )
            )

    def kinetic(y):
        return 0.5 * float(
            np.dot(model.mass, y[L.vx] ** 2 + y[L.vy] ** 2) + np.dot(model.inertia, y[L.w] ** 2)
        )

    if options is None:
        options = getattr(model, "options_dict", None)
    ke0, ke1 = kinetic_energies if kinetic_energies is not None else (kinetic(y_initial), kinetic(y_final))
    return RunoutResult(
        vehicle=model.vehicle.name,
        success=at_rest,
        status=status,
        message=message,
        t_end=float(t_end),
        nfev=int(nfev),
        njev=int(njev),
        nlu=int(nlu),
        n_segments=int(n_segments),
        bodies=bodies,
        wheels=wheels,
        hitches=tuple(hitches),
        events=tuple(events),
        kinetic_energy_initial=float(ke0),
        kinetic_energy_final=float(ke1),
        energy_dissipated=float(energy.sum()) if energy_dissipated is None else float(energy_dissipated),
        gravity_work=gravity_work,
        max_hitch_gap=float(max_gap),
        method=method,
        options=dict(options) if options is not None else model.options.to_dict(),
        sol=sol,
        layout=L,
        rollover=rollover,
    )


# ============================================================================= the scene
def _sample_times(table, sample_dt: float, t_end: float):
    """Sample times (segment starts, the ``sample_dt`` grid strictly inside, the run's end) and their segment."""
    T, seg = [], []
    for g, (t0, t1, _) in enumerate(table):
        k0 = math.ceil(t0 / sample_dt - 1e-9)
        # k sample_dt strictly inside the segment (Python floats: the same products as NumPy's, without
        # its per-call cost on a few points per segment)
        grid = [t for t in (k * sample_dt for k in range(k0, math.floor(t1 / sample_dt) + 1)) if t0 < t < t1]
        T.append(t0)
        T += grid
        seg += [g] * (1 + len(grid))
    if table:
        T.append(table[-1][1])
        seg.append(len(table) - 1)
    else:
        T, seg = [t_end], [0]
    return np.array(T, dtype=float), np.array(seg, dtype=np.int64)


@dataclass(eq=False)
class _VehicleView:
    """What :func:`build_result` needs of one vehicle of a scene."""

    vehicle: object
    layout: object
    specs: tuple
    static_load: np.ndarray
    loads: object
    mass: np.ndarray
    inertia: np.ndarray
    options_dict: dict


def _vehicle_rows(model, name: str) -> np.ndarray:
    """Rows of a vehicle's state vector (its own layout) in the scene's state vector."""
    b0, b1 = model.body_range[name]
    nb = model.n_bodies
    fields = 8 if model.options.load_transfer else 6
    return np.concatenate([np.arange(f * nb + b0, f * nb + b1) for f in range(fields)])


def _lean_view(view: _VehicleView, keep: list) -> _VehicleView:
    """``view`` with the wheels ``keep`` (indices into its specs) only."""
    return _VehicleView(view.vehicle, view.layout, tuple(view.specs[i] for i in keep), view.static_load[keep],
                        view.loads, view.mass, view.inertia, view.options_dict)


def _roll_with_history(summary: dict, t, series: dict) -> dict:
    """The rollover verdict with its sampled indicators under ``"history"`` (for the figures; not in the
    JSON): ``{"t": (K,) [s], body: {"ltr": (K,), "lateral_acceleration_g": (K,)}}``."""
    history = {"t": np.asarray(t, dtype=float)}
    for name, (ltr, ay) in series.items():
        history[name] = {"ltr": np.asarray(ltr, dtype=float), "lateral_acceleration_g": np.asarray(ay, dtype=float)}
    return {**summary, "history": history}


def _vehicle_statics(model) -> dict:
    """Per vehicle of a scene model, what its results need of the model: its state rows and its
    :class:`_VehicleView`; built once per model (a model reused across runs keeps them)."""
    static = model.__dict__.get("_vehicle_statics")
    if static is None:
        o = model.options
        opts = o.to_dict()
        static = {}
        for v in model.vehicles:
            b0, b1 = model.body_range[v.name]
            w0, w1 = model.wheel_range[v.name]
            layout = StateLayout(tuple(b.name for b in v.bodies), accel_filter=o.load_transfer)
            static[v.name] = (_vehicle_rows(model, v.name),
                              _VehicleView(v, layout, model.specs[w0:w1], model.static_load[w0:w1],
                                           model.loads[v.name], model.mass[b0:b1], model.inertia[b0:b1], opts))
        model.__dict__["_vehicle_statics"] = static
    return static


def _lean_views(model, lean, static: dict) -> dict:
    """Per vehicle, the :class:`_VehicleView` of the wheels the predicate ``lean`` keeps and their
    indices in the model's wheels; kept for the last ``lean`` given (equal predicates reuse them)."""
    held = model.__dict__.get("_lean_views")
    if held is None or held[0] != lean:
        views = {}
        for v in model.vehicles:
            w0, w1 = model.wheel_range[v.name]
            keep = [w for w in range(w0, w1) if lean(model.specs[w])]
            views[v.name] = (_lean_view(static[v.name][1], [w - w0 for w in keep]), np.asarray(keep, dtype=np.int64))
        held = (lean, views)
        model.__dict__["_lean_views"] = held
    return held[1]


def mode_snapshot(phase, D):
    """A copy of the mode arrays ``D`` of one segment with its phase: a row of the segment table."""
    memb, lk_j, lk_th, lk_n, _, pstate, pref, parked = D
    return (int(phase), memb.copy(), int(lk_n[0]), lk_j.copy(), lk_th.copy(), pstate.copy(), pref.copy(), parked.copy())


def segment_arrays(table, model):
    """Stacked modes of the segments (:class:`~crashsim.motion.kernels.arrays.Segments`) for the kernels' post-processing."""
    k = kernels()
    if not table:
        D = model.fresh_mode()
        table = [(0.0, 0.0, mode_snapshot(0, D))]
    modes = [m for _, _, m in table]
    return k.Segments(np.array([m[0] for m in modes], dtype=np.int64), np.stack([m[1] for m in modes]),
                      np.array([m[2] for m in modes], dtype=np.int64), np.stack([m[3] for m in modes]),
                      np.stack([m[4] for m in modes]), np.stack([m[5] for m in modes]).astype(np.int64),
                      np.stack([m[6] for m in modes]), np.stack([m[7] for m in modes]).astype(np.int64))


def gravity_work(model, Y: np.ndarray, seg_of: np.ndarray, memb: np.ndarray) -> np.ndarray:
    """Work of the in-plane gravity on every body over the sampled run [J], shape (nb,).

    Each wheel carries its share of its body's mass (``M.wheel_mass``) under the gravity of the
    slope where it stands (its zone's, else the road's), acting at the body's CG; the work is summed
    over the sampled steps of its CG, each step under the force of the segment it starts in. Exact:
    the force is constant within a segment (zone membership changes only at segment starts, which
    are samples), so its work over a step is its dot product with the CG's displacement.  Zero on a
    level road.
    """
    nb = model.n_bodies
    out = np.zeros(nb)
    if not model.road.sloped or Y.shape[1] < 2:
        return out
    k = kernels()
    M = model.M
    gx, gy = float(M.cfg[k.C_GX]), float(M.cfg[k.C_GY])
    road_g = np.array([gx, gy])
    zone_g = M.zone_slope[:, :2]
    L = model.layout
    dx, dy = np.diff(Y[L.x], axis=1), np.diff(Y[L.y], axis=1)  # (nb, K - 1): each sampled step of the CGs
    if not memb.shape[2] or bool(np.all(zone_g == road_g)):
        # one gravity under every wheel (no zone has a slope of its own): one force per body, for every step
        fx, fy = [0.0] * nb, [0.0] * nb
        for b, m in zip(M.wheel_body.tolist(), M.wheel_mass.tolist()):  # summed wheel by wheel, as the kernels sum it
            fx[b] += m * gx
            fy[b] += m * gy
        out += np.sum(np.array(fx)[:, None] * dx + np.array(fy)[:, None] * dy, axis=1)
        return out
    force = np.zeros((memb.shape[0], nb, 2))  # per segment: the gravity force on each body [N]
    # per segment and wheel the gravity where it stands: the last zone it is in, else the road's
    inside = memb.any(axis=2)
    last = memb.shape[2] - 1 - np.argmax(memb[:, :, ::-1], axis=2)
    g = np.where(inside[:, :, None], zone_g[last], road_g)  # (nseg, nw, 2)
    for w in range(model.n_wheels):  # summed wheel by wheel, as the kernels sum it
        force[:, M.wheel_body[w]] += M.wheel_mass[w] * g[:, w]
    # the force of the segment a step starts in: a step ends at the next sample, which is the next
    # segment's start where the membership changes, so its whole displacement is under that force
    fm = force[seg_of[:-1]]  # (K - 1, nb, 2)
    out += np.sum(fm[:, :, 0].T * dx + fm[:, :, 1].T * dy, axis=1)
    return out


def assemble_scene(model, integrator, *, status, message, t_end, y_initial, y_end, quad, events, impacts, nfev, mode,
                   lean=None):
    """The :class:`~crashsim.motion.scene_result.SceneRunout` of a run (per vehicle, impacts, pairs, ledger).

    ``lean`` (optional): a predicate on the model's wheel specs (``spec.key``, ``body``,
    ``axle_index``, ``axle_name``, ``side``) for a *lean* result, the one a fit or Monte Carlo
    sample reads: each body's rest state, time to rest, path length and sampled history; the
    tracks of the wheels the predicate keeps (the same arrays as the full result's); the
    impacts, the energy ledger and the events (without their places).  Left out: the other
    wheels' tracks, the hitch histories (``hitches`` empty, ``max_hitch_gap`` NaN) and the pair
    summaries (``pairs`` empty).  Every value it has is the full result's, bit for bit.
    """
    k = kernels()
    o = model.options
    M = model.M
    table, arrays = integrator.segment_data(mode)  # (t0, t1, _) per segment; their mode arrays
    T, seg_of = _sample_times(table, o.sample_dt, t_end)
    Y = integrator.sample(T, seg_of, y_end)
    P, SL, LD, LAMH, STOPM, CF, max_gap, pen = k.evaluate_samples(np.ascontiguousarray(Y), seg_of, M, arrays)
    sol = integrator.solution(y_end, t_end)
    roll = model.options.rollover
    if roll:  # wheel lift and rollover (places set): merged into the events by time, in lean runs too
        monitor = RollMonitor.of(model)
        starts = np.array([a for a, _, _ in table], dtype=float)
        events[:] = with_events(events, monitor.events(T, seg_of, Y, arrays.memb if table else [], starts, sol))
        roll_ltr, roll_ay = monitor.series(T, seg_of, Y, arrays.memb if table else [])
    if lean is None:
        events[:] = event_places(model, sol, events)
    missed = None
    if model.road.zones and table:
        miss_t, miss_k = k.missed_zone(M, T, P, seg_of, arrays.memb)
        if miss_k >= 0:
            missed = (float(miss_t), int(miss_k))
    nb, nw = model.n_bodies, model.n_wheels
    static = _vehicle_statics(model)
    lean_views = None if lean is None else _lean_views(model, lean, static)
    w_grav = gravity_work(model, Y, seg_of, arrays.memb)

    # ---- per vehicle
    rest_time = {}
    for e in events:
        if e.kind == "vehicle_rest":
            rest_time[e.vehicles[0]] = e.t
    vehicles = {}
    parked = mode.parked
    for vi, v in enumerate(model.vehicles):
        at_rest = bool(parked[vi])
        t_v = rest_time.get(v.name, t_end) if at_rest else t_end
        keep = T <= t_v + 1e-12
        cols = np.nonzero(keep)[0]
        if cols.size == 0 or T[cols[-1]] < t_v - 1e-12:
            after = np.nonzero(T > t_v)[0]
            cols = np.concatenate([cols, after[:1]]) if after.size else cols
        Tv = T[cols].copy()
        if Tv.size:
            Tv[-1] = min(Tv[-1], t_v) if at_rest else Tv[-1]
        rows, view = static[v.name]
        b0, b1 = model.body_range[v.name]
        w0, w1 = model.wheel_range[v.name]
        h0, h1 = model.hitch_range[v.name]
        v_events = [e for e in events if not e.vehicles or v.name in e.vehicles]
        if at_rest:
            v_status, v_message = "rest", f"all bodies below v_stop = {o.v_stop} m/s at t = {t_v:.4f} s"
            v_events = [e for e in v_events if e.kind != status or e.t < t_end]
            v_events.append(RunoutEvent(t_v, "rest", v_message))
        else:
            v_status, v_message = status, message
        v_missed = None
        if missed and w0 <= missed[1] < w1:
            v_missed = (missed[0], model.specs[missed[1]].key)
        quad_b = quad[b0:b1]
        if lean is not None:  # the kept wheels' tracks only, no hitch histories (see the docstring)
            view, idx = lean_views[v.name]
            quad_w = lambda c: quad[nb + c * nw + idx]  # noqa: E731
            P_v, SL_v, LD_v = P[idx][:, cols], SL[idx][:, cols], LD[idx][:, cols]
            h1 = h0
            gap = math.nan
        else:
            quad_w = lambda c: quad[nb + c * nw + w0: nb + c * nw + w1]  # noqa: E731
            P_v, SL_v, LD_v = P[w0:w1][:, cols], SL[w0:w1][:, cols], LD[w0:w1][:, cols]
            gap = _vehicle_gap(model, Y[:, cols], h0, h1)
        vehicles[v.name] = build_result(view, ResultInputs(
            t=Tv, Y=Y[rows][:, cols], points=P_v, sliding=SL_v,
            load=LD_v, hitch_force=LAMH[cols][:, 2 * h0:2 * h1], stop_moment=STOPM[cols][:, h0:h1],
            distance=quad_b, path_length=quad_w(0), sliding_length=quad_w(1), energy=quad_w(2),
            max_gap=gap, missed=v_missed, status=v_status, message=v_message,
            t_end=t_v, y_initial=y_initial[rows], y_final=y_end[rows],
            sol=lambda tq, rows=rows: np.asarray(sol(tq))[rows], events=v_events, nfev=nfev, njev=integrator.njev,
            nlu=integrator.nlu, n_segments=len(table), method=integrator.method,
            kinetic_energies=(_ke(model, y_initial, b0, b1), _ke(model, y_end, b0, b1)),
            energy_dissipated=float(quad[nb + 2 * nw + w0: nb + 2 * nw + w1].sum()),
            gravity_work=float(w_grav[b0:b1].sum()),
            rollover=_roll_with_history(roll_summary(v_events, [b.name for b in v.bodies], monitor.thresholds[b0:b1]),
                                        Tv, {b.name: (roll_ltr[b0 + i, cols], roll_ay[b0 + i, cols])
                                             for i, b in enumerate(v.bodies)}) if roll else None))

    # ---- pairs and the ledger
    n_imp = {}
    for imp in impacts:
        n_imp[f"{imp.body1}|{imp.body2}"] = n_imp.get(f"{imp.body1}|{imp.body2}", 0) + 1
    pairs = []
    if lean is None:
        span, peak, deepest, closing, peak_t, (node_t, node_f) = contact_summaries(model, integrator, table, arrays,
                                                                                   y_end, t_end)
    for p, pair in enumerate(model.pairs if lean is None else ()):
        pairs.append(PairSummary(pair.name, pair.a, pair.b, n_imp.get(pair.name, 0), float(span[p]),
                                 float(peak[p]), float(max(pen[p], deepest[p])), float(quad[nb + 3 * nw + p]),
                                 T.copy(), CF[:, p].copy(), float(closing[p]), float(peak_t[p]),
                                 node_t.copy(), node_f[:, p].copy()))
    ke0, ke1 = model.kinetic_energy(y_initial), model.kinetic_energy(y_end)
    tyres = float(np.sum(quad[nb + 2 * nw: nb + 3 * nw]))
    stops = float(sum(e.energy for e in events if e.kind in ("stop_closed", "stop_impact")))
    hits = float(sum(i.energy_loss for i in impacts))
    contacts = 0.0 - float(np.sum(quad[nb + 3 * nw:]))  # 0.0 -: no "-0" when no contact acted
    ledger = {"initial": ke0, "impacts": hits, "tyres": tyres, "stops": stops, "contacts": contacts, "final": ke1,
              "closing_error": ke0 - (hits + tyres + stops + contacts + ke1)}
    if model.road.sloped:  # the potential energy gained on the slope (minus the gravity's work)
        ledger["potential"] = -float(w_grav.sum())
        ledger["closing_error"] -= ledger["potential"]
    if missed:
        key = model.specs[missed[1]].key
        detail = (f"wheel {key} is in a friction zone the integration did not register at t = {missed[0]:.4f} s: "
                  "a zone corner clipped by less than the zone resolution; lower options.max_step if it matters")
        events.insert(-1, RunoutEvent(missed[0], "zone_missed", detail))
    return SceneRunout(vehicles=vehicles, impacts=tuple(impacts), pairs=tuple(pairs), events=tuple(events),
                       energy=ledger, status=status, message=message, t_end=float(t_end), nfev=int(nfev),
                       n_segments=len(table), method=integrator.method, sol=sol, layout=model.layout)


def _ke(model, y, b0, b1) -> float:
    L = model.layout
    vx, vy, w = y[L.vx][b0:b1], y[L.vy][b0:b1], y[L.w][b0:b1]
    return 0.5 * float(np.dot(model.mass[b0:b1], vx**2 + vy**2) + np.dot(model.inertia[b0:b1], w**2))


def _vehicle_gap(model, Y, h0, h1) -> float:
    """Largest pin gap of a vehicle's hitches over the sampled states [m]."""
    if h1 <= h0:
        return 0.0
    L = model.layout
    hb = model.M.hitch_body
    hitch = model.M.hitch
    out = 0.0
    for j in range(h0, h1):
        f, r = hb[j]
        cf, sf = np.cos(Y[L.psi][f]), np.sin(Y[L.psi][f])
        cr, sr = np.cos(Y[L.psi][r]), np.sin(Y[L.psi][r])
        gx = Y[L.x][f] + cf * hitch[j, 0] - sf * hitch[j, 1] - Y[L.x][r] - (cr * hitch[j, 2] - sr * hitch[j, 3])
        gy = Y[L.y][f] + sf * hitch[j, 0] + cf * hitch[j, 1] - Y[L.y][r] - (sr * hitch[j, 2] + cr * hitch[j, 3])
        out = max(out, float(np.max(np.hypot(gx, gy))))
    return out

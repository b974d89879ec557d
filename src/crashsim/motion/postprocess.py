"""Turn integrated states into a :class:`~crashsim.motion.result.RunoutResult`.

Shared by the SciPy engine and the pymunk cross-check, so both report the same quantities
computed the same way.  Inputs are *chunks*: consecutive pieces of the run with constant
segment inputs (:class:`~crashsim.motion.dynamics.SegmentParams`).

* sample chunks ``(seg, t, Y)``: states ``Y`` (n_state, K) at times ``t`` (K,) for the
  histories and tracks;
* quadrature chunks ``(seg, weights, Y)``: states at quadrature nodes with their weights [s]
  for path lengths and dissipated energies (Gauss-Legendre on the solver steps for SciPy,
  the step rule itself for pymunk).
"""

from __future__ import annotations

import logging
from typing import Callable, Sequence

import numpy as np

from .dynamics import RunoutModel, SegmentParams, hitch_rows
from .result import (
    BodyHistory,
    BodyRunout,
    HitchHistory,
    RunoutEvent,
    RunoutResult,
    TrackSegment,
    WheelTrack,
)

__all__ = ["assemble_result", "build_result", "gauss_legendre_chunks", "split_track"]

_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(5)
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
    nodes = (0.5 * (a + b))[:, None] + half[:, None] * _GL_NODES[None, :]
    weights = half[:, None] * _GL_WEIGHTS[None, :]
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
    change = np.flatnonzero(sliding[1:] != sliding[:-1]) + 1 if starts is None else starts
    if len(change) == 0:
        return (TrackSegment(kind="sliding" if sliding[0] else "rolling", t=t, points=points),)
    starts = np.concatenate([[0], change])
    ends = np.concatenate([change, [n - 1]])
    out = []
    for a, b in zip(starts.tolist(), ends.tolist()):
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


def assemble_result(
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
) -> RunoutResult:
    """Build the result object (see the module docstring for the chunk format).

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
    return build_result(
        model,
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


def build_result(
    model,
    *,
    t: np.ndarray,
    Y: np.ndarray,
    points: np.ndarray,
    sliding: np.ndarray,
    load: np.ndarray,
    hitch_force: np.ndarray,
    stop_moment: np.ndarray,
    distance: np.ndarray,
    path_length: np.ndarray,
    sliding_length: np.ndarray,
    energy: np.ndarray,
    max_gap: float,
    missed: tuple[float, str] | None,
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
    kinetic_energies: tuple[float, float] | None = None,
) -> RunoutResult:
    """The result objects from the computed arrays (shared by the SciPy and compiled engines).

    Parameters
    ----------
    model : RunoutModel or compatible
        Needs ``layout``, ``specs``, ``vehicle.name``, ``static_load``, ``loads.hitch``,
        ``mass``, ``inertia`` and ``options``.
    t : ndarray, shape (K,)
        Sample times [s].
    Y : ndarray, shape (n_state, K)
        Sampled states.
    points : ndarray, shape (n_wheels, K, 2)
        Contact positions [m] at the samples.
    sliding, load : ndarray, shape (n_wheels, K)
        Sliding flags and normal loads [N] at the samples.
    hitch_force : ndarray, shape (K, 2 n_hitches)
        Hitch forces on the front bodies, world frame [N].
    stop_moment : ndarray, shape (K, n_hitches)
        Moments of closed articulation stops [N m].
    distance : ndarray, shape (n_bodies,)
        CG path lengths [m].
    path_length, sliding_length, energy : ndarray, shape (n_wheels,)
        Contact path lengths [m], their sliding parts [m], dissipated energies [J].
    max_gap : float
        Largest pin gap over the samples [m].
    missed : (float, str) or None
        Time [s] and wheel key of the first sample inside a zone the integration did not
        register; adds a ``"zone_missed"`` event and logs a warning.
    status, message, t_end, y_initial, y_final, sol, events, nfev, njev, nlu, n_segments, method
        As :class:`~crashsim.motion.result.RunoutResult`.
    kinetic_energies : (float, float), optional
        Initial and final kinetic energy [J], if already computed.
    """
    L = model.layout
    nh = len(L.bodies) - 1
    specs = model.specs
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
            static_load=float(model.static_load[k]),
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
        energy_dissipated=float(energy.sum()),
        max_hitch_gap=float(max_gap),
        method=method,
        options=dict(options) if options is not None else model.options.to_dict(),
        sol=sol,
        layout=L,
    )

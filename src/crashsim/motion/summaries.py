"""What a scene's run says beyond its states: the pairs' contact summaries and the places of its events.

:func:`contact_summaries` evaluates each pair's contact on the run's dense solution (not the
``sample_dt`` grid); :func:`event_places` finds where each event of the run happened.  Both
belong to the full result of :func:`crashsim.motion.postprocess.assemble_scene` (a lean result
of a fit or Monte Carlo sample has neither).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .scene_model import kernels

__all__ = ["contact_summaries", "event_places"]

#: Points per solver step at which a pair's contact force and depth are evaluated (the step's
#: start and quarter points; the segment's end closes the grid) for the pair summaries.
_SUMMARY_POINTS = np.array([0.0, 0.25, 0.5, 0.75])


def contact_summaries(model, integrator, table, arrays, y_end, t_end):
    """Time in sustained contact, peak contact force, deepest penetration and fastest closing in
    contact of every pair, from the solution itself (not the ``sample_dt`` grid):
    ``(span, peak, deepest, closing, peak_time, nodes)``, the first five each (npairs,);
    ``nodes`` is ``(t, force)``: the times the force was evaluated at (K,) and each pair's
    sustained-contact force there (K, npairs), zero where the pair is not in contact, so that a
    figure can draw the force the summaries saw (its largest node, and the refined peak at
    ``peak_time``, are the peak).

    The span is the time the pair spent in sustained contact, from the segments the events cut
    (so it is the span of the pair's own contact events).  Force, depth and the closing speed
    of points pressed beyond the allowance (:func:`crashsim.motion.kernels.contact_samples`) are
    evaluated on the dense solution at every step of the integrator in the segments with a
    pair in contact or disarmed (its start and quarter points), and the largest force is
    refined by the parabola through the largest node and its neighbours (in segments with a pair
    disarmed but none in contact, which have no force, at the steps only): the summaries are
    those of the solution to about the solver tolerance, and the same whatever ``sample_dt``
    says.
    """
    k = kernels()
    npr = len(model.pairs)
    span, peak, deepest, closing = np.zeros(npr), np.zeros(npr), np.zeros(npr), np.zeros(npr)
    peak_time = np.full(npr, np.nan)
    none = (np.zeros(0), np.zeros((0, npr)))
    if not npr or not table:
        return span, peak, deepest, closing, peak_time, none
    pstate = arrays.pstate
    edges = integrator.step_edges()
    T, G = [], []
    for g, (t0, t1, _) in enumerate(table):
        inside = pstate[g] == k.PS_CONTACT
        span[inside] += t1 - t0
        if not (pstate[g] != k.PS_ARMED).any() or t1 <= t0:
            continue
        e = edges[(edges > t0) & (edges < t1)]
        knots = np.concatenate([[t0], e, [t1]])
        # sustained contact: a force to find the peak of; a disarmed pair alone (no force): its
        # closing speeds at the steps
        points = _SUMMARY_POINTS if inside.any() else _SUMMARY_POINTS[:1]
        fine = (knots[:-1, None] + np.diff(knots)[:, None] * points).ravel()
        T.append(np.append(fine, t1))
        G.append(np.full(fine.size + 1, g, dtype=np.int64))
    if not T:
        return span, peak, deepest, closing, peak_time, none
    # one more node at the run's end: the samplers return the final state there
    T = np.concatenate(T + [[t_end]])
    G = np.concatenate(G + [np.array([len(table) - 1], dtype=np.int64)])
    Y = integrator.sample(T, G, y_end)[:, :-1]
    T, G = T[:-1], G[:-1]
    CF, deepest, closing = k.contact_samples(np.ascontiguousarray(Y), G, model.M, arrays)
    # closing speeds inside the segments: a segment's end is the instant of its event (an
    # impact's state before the impulse)
    ends = np.array([t1 for _, t1, _ in table])[G]
    closing = np.where((T < ends)[:, None], closing, 0.0).max(axis=0)
    F = np.where(pstate[G] == k.PS_CONTACT, CF, 0.0)
    for p in range(npr):
        f = F[:, p]
        j = int(np.argmax(f))
        peak[p], peak_time[p] = f[j], T[j]
        if 0 < j < len(f) - 1 and G[j - 1] == G[j] == G[j + 1] and T[j - 1] < T[j] < T[j + 1]:
            # the parabola through the largest node and its neighbours (times from the middle one)
            x0, x2 = T[j - 1] - T[j], T[j + 1] - T[j]
            d0, d2 = f[j - 1] - f[j], f[j + 1] - f[j]
            det = x0 * x2 * (x0 - x2)
            a, b = (d0 * x2 - d2 * x0) / det, (d2 * x0 * x0 - d0 * x2 * x2) / det
            if a < 0 and x0 <= -b / (2 * a) <= x2 and f[j] - b * b / (4 * a) > f[j]:
                peak[p], peak_time[p] = f[j] - b * b / (4 * a), T[j] - b / (2 * a)
    return span, peak, deepest, closing, peak_time, (T, F)


def event_places(model, sol, events) -> list:
    """The events with the place where each happened (``place``, world frame [m]).

    A wheel's zone entry or exit: the wheel's contact centre; an articulation stop: the hitch
    pin; a secondary impact: its contact point; sustained contact starting or pressing: the
    contact point of the pair's manifold (none once they part); a vehicle at rest: its first
    body's CG.  States come from the run's dense solution at the event's time.
    """
    L = model.layout
    want = [i for i, e in enumerate(events) if e.place is None and
            (any(key in e.data for key in ("wheel", "hitch", "pair")) or e.kind == "vehicle_rest")]
    if not want:
        return list(events)
    Y = np.asarray(sol(np.array([events[i].t for i in want])))
    out = list(events)
    specs = {s.key: s for s in model.specs}
    names = [v.name for v in model.vehicles]
    for col, i in enumerate(want):
        e, y = events[i], Y[:, col]

        def at(bi, point):
            c, s_ = np.cos(y[L.psi][bi]), np.sin(y[L.psi][bi])
            return (float(y[L.x][bi] + c * point[0] - s_ * point[1]), float(y[L.y][bi] + s_ * point[0] + c * point[1]))

        place = None
        if "wheel" in e.data and e.data["wheel"] in specs:
            spec = specs[e.data["wheel"]]
            place = at(spec.body_index, spec.position)
        elif "hitch" in e.data:
            j = [f"{a}-{b}" for a, b in model.hitch_names].index(e.data["hitch"])
            place = at(int(model.M.hitch_body[j][0]), model.M.hitch[j, :2])
        elif e.kind == "vehicle_rest" and e.vehicles and e.vehicles[0] in names:
            place = at(model.body_range[e.vehicles[0]][0], (0.0, 0.0))
        elif "pair" in e.data and e.kind != "contact_end":
            p = [q.name for q in model.pairs].index(e.data["pair"])
            _, ok, geo = kernels().pair_geometry(np.ascontiguousarray(y), model.M, p)
            if ok:
                place = (float(geo[0]), float(geo[1]))
        if place is not None:
            out[i] = replace(e, place=place)
    return out

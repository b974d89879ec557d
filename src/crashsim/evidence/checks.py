"""Scene evidence and the check users care about most: do the results agree with the scene?

Each item of evidence gets a residual (how far the computation lies from the measurement)
and a verdict against the tolerance the user stated for it. All SI, world frame.

Residuals
---------
rest position   distance between computed and measured CG rest positions [m]; heading error
                wrapped to (-pi, pi] [rad] if a heading was measured.  The measured CG and
                heading may come from two or more measured points of the body (corners, tyre
                contacts): :func:`register_points` fits the body's points to them (a least-squares
                rigid motion) and the check then compares the derived CG and heading; its details
                add the fit's RMS misfit.
tyre mark       one-sided Hausdorff distance from the measured mark (a polyline, densified to
                ``MARK_SPACING``) to the computed track of the wheel that matches it best: the
                largest distance of any point of the mark from the track [m]. Only the sliding
                parts of a track count unless the mark says otherwise (rolling tyres leave no
                mark). The mean distance and the best-matching wheel are reported too.
point of impact distance between the scenario's contact point and the measured one [m].
delta-v         computed minus recorded delta-v of a body [m/s]: its magnitude, or its
                component along the body's x (longitudinal, as event data recorders report)
                or across it (lateral: positive to the left, the body's y axis, or to the right,
                SAE J670, as the item's ``lateral_positive`` says), in the body axes at impact.
                Of the first impact (default: a recorder records one event, normally the
                first), or summed over all the body's impacts (``impacts = "all"``: a recorder
                that accumulates a whole event which includes a later impact).
crush energy    the impact model's energy loss at the crush surface minus the CRASH3 crush energy
                of the bodies [J], per group of crush items (:mod:`crashsim.evidence.crush`).
rollover        a statement that a vehicle (any of its units) or one unit did or did not roll,
                against the run-out's wheel-lift and rollover check
                (:mod:`crashsim.motion.rollover`): residual computed minus stated (1 rolls, 0
                does not), tolerance 0, so the verdict is whether they agree. A yes/no outcome
                has no gradient: the fit does not fit it; Monte Carlo counts it among the
                evidence a sample meets.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..geometry import rotate, wrap_angle
from ._polyline import nearest_on_polyline
from .crush import crush_checks
from .outcome import Check

__all__ = [
    "RestEvidence", "MarkEvidence", "ImpactPointEvidence", "DeltaVEvidence", "RolloverEvidence", "Evidence",
    "Check", "EvidenceReport", "evaluate_evidence", "distance_to_polyline", "signed_distance_to_polyline",
    "MARK_SPACING", "Registration", "register_points", "named_body_points", "CORNERS", "MIN_POINT_SPREAD",
]

#: A rest position from measured points warns when the rigid fit's RMS misfit exceeds this share of
#: the item's ``tolerance``: the points then disagree with the body's own geometry by more than the
#: evidence is trusted to (a point mislabelled or mismeasured), and the derived CG and heading are
#: doubtful.
REST_MISFIT_SHARE = 0.5

#: Spacing [m] to which measured marks are densified before their distance to a track is taken.
MARK_SPACING = 0.1


#: Outline corners a measured rest point may name, as (sign along x, sign along y) from the
#: outline centre: front/rear = +/- length/2, left/right = +/- width/2 (body axes, y left).
CORNERS = {"front_left": (1.0, 1.0), "front_right": (1.0, -1.0), "rear_left": (-1.0, 1.0),
           "rear_right": (-1.0, -1.0)}

#: Smallest RMS distance [m] of a set of points from their centroid for a rigid fit: points
#: closer together than this coincide, and fix no heading.
MIN_POINT_SPREAD = 1e-6


def named_body_points(body) -> dict[str, tuple[float, float]]:
    """The points of a body a measurement may name, in body axes [m].

    The outline corners (:data:`CORNERS`; only if the body has a length and a width) and the
    tyre contact centres ``<axle>/left`` and ``<axle>/right`` at ``(axle.x, +-track/2)``
    (as :mod:`crashsim.motion.wheels` places them), where ``<axle>`` is ``axle1``,
    ``axle2``, ... (front to rear, for every axle) or the axle's name if it has one.

    Parameters
    ----------
    body : Body

    Returns
    -------
    dict
        ``{name: (x, y)}`` in body axes [m].
    """
    out: dict[str, tuple[float, float]] = {}
    if body.length is not None and body.width is not None:
        cx, cy = body.outline_center
        for name, (sx, sy) in CORNERS.items():
            out[name] = (cx + sx * body.length / 2, cy + sy * body.width / 2)
    for k, axle in enumerate(body.axles):
        labels = [f"axle{k + 1}"] + ([axle.name] if axle.name else [])
        for label in labels:
            out[f"{label}/left"] = (float(axle.x), axle.track / 2)
            out[f"{label}/right"] = (float(axle.x), -axle.track / 2)
    return out


@dataclass(frozen=True)
class Registration:
    """A body's pose fitted to measured points of it (:func:`register_points`).

    Attributes
    ----------
    labels : tuple of str
        What each point is (``"front_left"``, ``"axle1/right"``, ``"(1.2 m, 0.8 m)"``).
    body_points, measured : ndarray (n, 2)
        The points in body axes and as measured, world [m].
    position : (float, float)
        Derived CG position, world [m].
    heading : float
        Derived heading, wrapped to (-pi, pi] [rad].
    rms : float
        RMS distance between the measured points and the fitted body's points [m].
    misfit : ndarray (n,)
        Distance of each measured point from its fitted body point [m].
    """

    labels: tuple[str, ...]
    body_points: np.ndarray
    measured: np.ndarray
    position: tuple[float, float]
    heading: float
    rms: float
    misfit: np.ndarray

    def to_dict(self) -> dict:
        return {"position": list(self.position), "heading": self.heading, "rms": self.rms,
                "points": [{"at": lab, "body_point": [float(v) for v in b], "measured": [float(v) for v in m],
                            "misfit": float(d)}
                           for lab, b, m, d in zip(self.labels, self.body_points, self.measured, self.misfit)]}


def register_points(body_points, measured, labels=None) -> Registration:
    """Least-squares rigid motion (rotation + translation, no scaling) of body points onto measured ones.

    Minimises ``sum_i |p_w,i - (c + R(psi) p_b,i)|^2`` over the CG position ``c`` and the heading
    ``psi`` (the planar Kabsch / orthogonal Procrustes problem). With centred points
    ``a_i = p_b,i - mean(p_b)`` and ``b_i = p_w,i - mean(p_w)`` the minimiser is, in closed
    form,

        psi = atan2(sum_i cross(a_i, b_i), sum_i dot(a_i, b_i)),   c = mean(p_w) - R(psi) mean(p_b)

    (Kabsch 1976, Acta Cryst. A32 922; in 2D the rotation needs no SVD).

    Parameters
    ----------
    body_points : array_like (n, 2)
        Points in body axes (origin at the CG, x forward, y left) [m].
    measured : array_like (n, 2)
        The same points as measured, world frame [m].
    labels : sequence of str, optional
        What each point is, for reports.

    Returns
    -------
    Registration

    Raises
    ------
    ValueError
        Fewer than two points, shapes that differ, or points (body or measured) that
        coincide: their RMS distance from their centroid is below :data:`MIN_POINT_SPREAD`,
        so no heading follows.

    Examples
    --------
    >>> r = register_points([[1, 0], [-1, 0]], [[5, 3], [5, 1]])
    >>> [round(v, 9) for v in r.position], round(math.degrees(r.heading), 9), round(r.rms, 12)
    ([5.0, 2.0], 90.0, 0.0)
    """
    p = np.asarray(body_points, dtype=float)
    q = np.asarray(measured, dtype=float)
    if p.ndim != 2 or p.shape[1] != 2 or p.shape != q.shape:
        raise ValueError(f"body points {p.shape} and measured points {q.shape} must both be (n, 2)")
    if len(p) < 2:
        raise ValueError(f"{len(p)} point(s): a rigid fit needs at least two")
    pm, qm = p.mean(axis=0), q.mean(axis=0)
    a, b = p - pm, q - qm
    for what, c in (("body", a), ("measured", b)):
        spread = float(np.sqrt(np.mean(np.sum(c * c, axis=1))))
        if spread < MIN_POINT_SPREAD:
            raise ValueError(f"the {what} points coincide (RMS distance from their centroid {spread:.3g} m): "
                             "they fix no heading")
    heading = math.atan2(float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0])), float(np.sum(np.sum(a * b, axis=1))))
    centre = qm - rotate(pm, heading)
    fitted = centre + rotate(p, heading)
    misfit = np.hypot(*(q - fitted).T)
    labels = tuple(labels) if labels is not None else tuple(f"point {i + 1}" for i in range(len(p)))
    return Registration(labels, p, q, (float(centre[0]), float(centre[1])), float(wrap_angle(heading)),
                        float(np.sqrt(np.mean(misfit**2))), misfit)


@dataclass(frozen=True)
class RestEvidence:
    """A measured rest position of a body's CG (and heading), world frame [m, rad].

    ``registration`` is set when the CG (and heading) were derived from measured points of the
    body (:func:`register_points`); ``position`` and ``heading`` are then the derived ones
    (``heading`` None when no ``heading_tolerance`` was given: not checked).
    """

    body: str
    position: tuple[float, float]
    tolerance: float
    heading: float | None = None
    heading_tolerance: float | None = None
    name: str = ""
    registration: Registration | None = None
    sigma: float | None = None  # measurement uncertainty of the position [m] (fit, posterior)
    heading_sigma: float | None = None  # of the heading [rad]


@dataclass(frozen=True)
class MarkEvidence:
    points: np.ndarray
    tolerance: float
    wheel: str | None = None  # "*", "<body>", "<body>/<axle>", "<body>/<axle>/<side>"
    sliding_only: bool = True
    name: str = ""
    phase: str = "runout"  # "runout": left after the impact; "approach": before it (pre-impact skid or yaw mark)
    sigma: float | None = None  # measurement uncertainty [m] (fit, posterior)


@dataclass(frozen=True)
class ImpactPointEvidence:
    position: tuple[float, float]
    tolerance: float
    name: str = "point of impact"
    sigma: float | None = None  # measurement uncertainty [m] (fit, posterior)


@dataclass(frozen=True)
class DeltaVEvidence:
    body: str
    value: float
    tolerance: float
    component: str = "magnitude"  # "magnitude", "longitudinal", "lateral"
    name: str = ""
    impacts: str = "first"  # "first": the first impact only (one recorded event); "all": the sum over the body's impacts
    sigma: float | None = None  # measurement uncertainty [m/s] (fit, posterior)
    lateral_positive: str = "left"  # lateral component: "left" (body y axis, ISO 8855) or "right" (SAE J670)

    @property
    def label(self) -> str:
        """The item's name, or one made of its body and component (with the lateral sign convention)."""
        comp = self.component if self.component != "lateral" else f"lateral, + {self.lateral_positive}"
        return self.name or f"delta-v of {self.body} ({comp})"


@dataclass(frozen=True)
class RecorderEvidence:
    """Pre-crash speed samples of a recorder (EDR, engine ECM) in a body, SI.

    ``times`` are relative to the impact after adding ``time_offset``: a sample is compared only
    where time + ``time_offset`` <= 0 (pre-crash data end at the impact), decided with the item's
    own offset at every evaluation, so that an offset fitted moves the window too; ``lower_bound``
    marks samples taken with the service brake on: wheel-speed-based recorders under-read while
    the wheels lock or the ABS cycles, so such a sample only says the speed was at least that.
    """

    body: str
    times: tuple[float, ...]
    speeds: tuple[float, ...]
    lower_bound: tuple[bool, ...]
    tolerance: float
    time_offset: float = 0.0
    name: str = ""
    sigma: float | None = None  # measurement uncertainty of a sample [m/s] (fit, posterior)


@dataclass(frozen=True)
class RolloverEvidence:
    """A vehicle (any of its units) or one unit (body) did (``rolled``) or did not roll."""

    unit: str
    rolled: bool
    name: str = ""


@dataclass(frozen=True)
class Evidence:
    """All evidence of a scene."""

    rest: tuple[RestEvidence, ...] = ()
    marks: tuple[MarkEvidence, ...] = ()
    impact_point: ImpactPointEvidence | None = None
    delta_v: tuple[DeltaVEvidence, ...] = ()
    recorder: tuple[RecorderEvidence, ...] = ()
    crush: tuple = ()  # CrushEvidence (crashsim.evidence.crush)
    rollover: tuple = ()  # RolloverEvidence

    @property
    def empty(self) -> bool:
        return not (self.rest or self.marks or self.delta_v or self.impact_point or self.recorder
                    or self.crush or self.rollover)


def recorder_window(ev: RecorderEvidence) -> np.ndarray:
    """Which samples are pre-crash (time + ``time_offset`` <= 0) with this item's own offset: the
    window moves with the offset (a fit unknown), so it is taken anew at every evaluation."""
    return np.asarray(ev.times, float) + ev.time_offset <= 0.0


def recorder_residuals(ev: RecorderEvidence, approach) -> tuple[np.ndarray, np.ndarray]:
    """(computed speeds [m/s], residuals computed - recorded) of a recorder's samples, from this
    item's own ``time_offset``; a lower-bound sample has residual 0 when the computed speed is
    above it. A sample the offset puts after the impact (outside :func:`recorder_window`) is not
    compared: computed NaN, residual 0 (the vector keeps one entry per sample of the file)."""
    t = np.asarray(ev.times, float) + ev.time_offset
    inside = t <= 0.0
    computed = np.full(t.shape, np.nan)
    if inside.any():
        computed[inside] = np.asarray(approach.speed_at(t[inside], body=ev.body), float)
    res = np.where(inside, computed - np.asarray(ev.speeds, float), 0.0)
    res = np.where(np.asarray(ev.lower_bound, bool), np.minimum(res, 0.0), res)
    return computed, res


def _check_recorder(ev: RecorderEvidence, approach, index: int) -> Check:
    name = ev.name or f"recorder in {ev.body}"
    if approach is None:
        return Check("recorder", name, math.inf, ev.tolerance, False, "speed",
                     {"reason": "no approach was computed for this body's vehicle"})
    computed, res = recorder_residuals(ev, approach)
    inside = recorder_window(ev)
    details = {"times": [float(x) for x in ev.times], "recorded": [float(x) for x in ev.speeds],
               "computed": [None if not math.isfinite(c) else float(c) for c in computed],
               "residuals": res.tolist(), "lower_bound": list(ev.lower_bound), "time_offset": ev.time_offset,
               "compared": inside.tolist(), "n_compared": int(inside.sum())}
    if not inside.any():
        details["reason"] = (f"no sample is before the impact with time_offset = {ev.time_offset:g} s "
                             "(time + time_offset <= 0)")
        return Check("recorder", name, math.inf, ev.tolerance, False, "speed", details)
    k = int(np.argmax(np.where(inside, np.abs(res), -1.0)))
    worst = float(res[k])
    r_in = res[inside]
    details.update(worst_sample=k, rms=float(np.sqrt(np.mean(r_in * r_in))))
    return Check("recorder", name, worst, ev.tolerance, bool(np.all(np.abs(r_in) <= ev.tolerance)), "speed",
                 details)


@dataclass(frozen=True)
class EvidenceReport:
    checks: tuple[Check, ...]

    @property
    def all_passed(self) -> bool:
        return all(c.passed for c in self.checks)

    @property
    def n_failed(self) -> int:
        return sum(not c.passed for c in self.checks)

    def to_dict(self) -> dict:
        return {"all_passed": self.all_passed, "n_checks": len(self.checks), "n_failed": self.n_failed,
                "checks": [c.to_dict() for c in self.checks]}


def _densify(points: np.ndarray, spacing: float) -> np.ndarray:
    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return pts
    out = [pts[:1]]
    for a, b in zip(pts[:-1], pts[1:]):
        n = max(1, int(math.ceil(np.hypot(*(b - a)) / spacing)))
        s = np.linspace(0.0, 1.0, n + 1)[1:, None]
        out.append(a + s * (b - a))
    return np.vstack(out)


#: Points x vertices from which the point-to-polyline distances are computed by the compiled loop
#: (:mod:`crashsim.evidence._polyline`, the same bits); below, by the array form.
_COMPILED_FROM = 256

#: Densified marks by evidence object: a fit or Monte Carlo run checks the same marks at every sample.
_DENSE: dict[int, tuple] = {}


def _densified(ev: MarkEvidence) -> tuple[np.ndarray, float]:
    """``_densify(ev.points, MARK_SPACING)`` (read-only) and the mark's length along its points [m],
    kept for the evidence object."""
    hit = _DENSE.get(id(ev))
    if hit is not None and hit[0] is ev:
        return hit[1], hit[2]
    pts = _densify(ev.points, MARK_SPACING)
    pts.flags.writeable = False
    length = float(np.sum(np.hypot(*np.diff(np.asarray(ev.points, float), axis=0).T)))
    if len(_DENSE) >= 64:
        _DENSE.clear()
    _DENSE[id(ev)] = (ev, pts, length)  # holds ev: its id is not reused while it is cached
    return pts, length


def _nearest_on_polyline(points, polyline) -> tuple[np.ndarray, np.ndarray]:
    """For each point (n, 2): its distance to a polyline (m, 2) [m] and the side it lies on
    (+1 left of the nearest segment's direction, -1 right; +1 for a one-vertex polyline)."""
    p = np.asarray(points, dtype=float)
    line = np.asarray(polyline, dtype=float)
    if len(line) == 1:
        return np.hypot(*(p - line[0]).T), np.ones(p.shape[0])
    if len(p) * len(line) >= _COMPILED_FROM:
        out = nearest_on_polyline(p, line)
        if out is not None:
            return out
    # one (n, m) array per coordinate (the same operations, in the same order, as on (n, m, 2) arrays,
    # at a third of the cost): the segment parameter t, the nearest point's offset, its distance
    ax, ay = line[:-1, 0], line[:-1, 1]
    abx, aby = line[1:, 0] - ax, line[1:, 1] - ay
    denom = abx * abx + aby * aby
    px, py = p[:, 0:1], p[:, 1:2]
    t = (px - ax) * abx
    t += (py - ay) * aby
    t /= np.where(denom > 0, denom, 1.0)
    np.clip(t, 0.0, 1.0, out=t)
    dist = np.hypot(px - (ax + t * abx), py - (ay + t * aby))
    j = np.argmin(dist, axis=1)
    rows = np.arange(p.shape[0])
    cross = abx[j] * (p[:, 1] - ay[j]) - aby[j] * (p[:, 0] - ax[j])
    return dist[rows, j], np.where(cross >= 0, 1.0, -1.0)


def distance_to_polyline(points, polyline) -> np.ndarray:
    """Distance of each point (n, 2) to a polyline (m, 2) [m]; a single vertex is a point."""
    return _nearest_on_polyline(points, polyline)[0]


def signed_distance_to_polyline(points, polyline) -> np.ndarray:
    """Signed distance of each point (n, 2) to a polyline (m, 2) [m]: positive on its left
    (the side of the nearest segment's direction); a one-vertex polyline gives the distance."""
    dist, side = _nearest_on_polyline(points, polyline)
    return side * dist


def wheel_matches(track, selector: str | None) -> bool:
    """True if the wheel ``track`` (a WheelTrack or a wheel spec: ``body``, ``axle_index``,
    ``axle_name``, ``side``) is one a mark's ``wheel`` selector (``"body/axle/side"``, parts
    optional; None or ``"*"``: any wheel) names."""
    if selector in (None, "*"):
        return True
    parts = selector.split("/")
    if parts[0] != track.body:
        return False
    if len(parts) >= 2 and parts[1] not in (str(track.axle_index), track.axle_name):
        return False
    if len(parts) >= 3 and parts[2] != track.side:
        return False
    return True


def _bbox_lower_bound(pts: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> float:
    """Largest distance of the points from a box: a lower bound of their one-sided
    Hausdorff distance to anything inside the box."""
    d = np.maximum(np.maximum(lo - pts, pts - hi), 0.0)
    return float(np.max(np.hypot(d[:, 0], d[:, 1])))


def _check_mark(ev: MarkEvidence, tracks: dict, index: int) -> Check:
    name = ev.name or f"mark {index + 1}"
    pts, mark_length = _densified(ev)
    candidates = []
    for key, tr in tracks.items():
        if not wheel_matches(tr, ev.wheel):
            continue
        pieces = [seg.points for seg in tr.segments if (seg.kind == "sliding" or not ev.sliding_only) and len(seg.points)]
        if not pieces:
            continue
        allp = pieces[0] if len(pieces) == 1 else np.vstack(pieces)
        candidates.append((_bbox_lower_bound(pts, allp.min(0), allp.max(0)), key, pieces))
    best = None
    for bound, key, pieces in sorted(candidates, key=lambda c: c[0]):
        if best is not None and bound >= best[0]:
            break  # no remaining wheel can match better (exact: the bound is a lower bound)
        d = np.min(np.stack([distance_to_polyline(pts, piece) for piece in pieces]), axis=0)
        cand = (float(np.max(d)), float(np.mean(d)), key)
        if best is None or cand[0] < best[0]:
            best = cand
    if best is None:
        what = "sliding track" if ev.sliding_only else "track"
        return Check("mark", name, math.inf, ev.tolerance, False, "length",
                     {"wheel": ev.wheel, "reason": f"no computed {what} of a wheel matching {ev.wheel or '*'}"})
    return Check("mark", name, best[0], ev.tolerance, best[0] <= ev.tolerance, "length",
                 {"matched_wheel": best[2], "mean_distance": best[1], "selector": ev.wheel or "*",
                  "mark_length": mark_length})


def body_impacts(body: str, impact, secondary=()) -> list:
    """The velocity changes of ``body`` in the impacts it took part in, in time order: the
    first impact (if the body was in it), then the run-out's secondary impacts.  A list of
    ``(delta_v world vector [m/s] (2,), the body's heading at that impact [rad])``."""
    own = []
    if body in impact.bodies and not impact.bodies[body].fixed:
        own.append((np.asarray(impact.bodies[body].delta_v, dtype=float), impact.bodies[body].heading))
    for s in secondary:
        if body in s.delta_v:
            own.append((np.asarray(s.delta_v[body], dtype=float), s.result.bodies[body].heading))
    return own


def approach_tracks(approaches: dict | None) -> dict:
    """The tyre tracks of every approach (world frame, times relative to the impact)."""
    out = {}
    for a in (approaches or {}).values():
        out.update(a.tracks)
    return out


def approach_of_body(approaches: dict | None, body: str):
    """The ApproachResult of the vehicle ``body`` belongs to, or None."""
    for a in (approaches or {}).values():
        if body in a.bodies:
            return a
    return None


def evaluate_evidence(evidence: Evidence, impact, runout: dict | None, contact_point, secondary=(),
                      approaches: dict | None = None, *, marks: bool = True) -> EvidenceReport:
    """Residual and verdict of every evidence item.

    Parameters
    ----------
    evidence : Evidence
    impact : ImpactResult
    secondary : sequence of SecondaryImpact
        The impacts of the run-out; a delta-v item with ``impacts = "all"`` sums the body's
        delta-v over the first impact and these (in the body's axes at the first impact).
    runout : dict of RunoutResult by vehicle, or None (rest and mark items then fail with
        an infinite residual: nothing was computed to compare).
    contact_point : (float, float)
        The scenario's contact point, world [m].
    marks : bool
        False leaves the tyre-mark items out of the report: a fit measures its own distances along
        each mark (:class:`~crashsim.reconstruct.fit.EvidenceModel`), and its lean evaluations do not
        check the marks a second time (its report's scene, run in full, does).
    """
    checks: list[Check] = []
    bodies = {}
    tracks = {}
    stopped = {}
    if runout is not None:
        for r in runout.values():
            bodies.update(r.bodies)
            tracks.update(r.wheels)
            stopped.update({name: r.status for name in r.bodies})
    if evidence.impact_point is not None:
        ev = evidence.impact_point
        d = float(np.hypot(*(np.asarray(contact_point) - np.asarray(ev.position))))
        checks.append(Check("point of impact", ev.name, d, ev.tolerance, d <= ev.tolerance, "length",
                            {"computed": list(map(float, contact_point)), "measured": list(ev.position)}))
    for i, ev in enumerate(evidence.rest):
        name = ev.name or f"rest of {ev.body}"
        b = bodies.get(ev.body)
        if b is None:
            checks.append(Check("rest", name, math.inf, ev.tolerance, False, "length",
                                {"reason": "no run-out was computed for this body"}))
            continue
        d = float(np.hypot(*(np.asarray(b.rest_position) - np.asarray(ev.position))))
        at_rest = b.time_to_rest is not None
        extra = {} if at_rest else {"reason": f"not at rest: the run-out stopped ({stopped.get(ev.body, 'unknown')}) "
                                              "with the body still moving"}
        if ev.registration is not None:
            extra["registration"] = ev.registration.to_dict()
        checks.append(Check("rest", name, d, ev.tolerance, d <= ev.tolerance and at_rest, "length",
                            {"computed": [float(v) for v in b.rest_position], "measured": list(ev.position),
                             "at_rest": at_rest, **extra}))
        if ev.heading is not None:
            err = float(wrap_angle(b.rest_heading - ev.heading))
            checks.append(Check("rest heading", f"{name} (heading)", err, ev.heading_tolerance,
                                abs(err) <= ev.heading_tolerance and at_rest, "angle",
                                {"computed": float(wrap_angle(b.rest_heading)), "measured": ev.heading,
                                 "at_rest": at_rest, **extra}))
    checked = evidence.marks if marks else ()
    pre = approach_tracks(approaches) if any(m.phase == "approach" for m in checked) else {}
    for i, ev in enumerate(checked):
        checks.append(_check_mark(ev, pre if ev.phase == "approach" else tracks, i))
    for i, ev in enumerate(evidence.delta_v):
        name = ev.label
        own = body_impacts(ev.body, impact, secondary)
        if not own:
            checks.append(Check("delta-v", name, math.inf, ev.tolerance, False, "speed",
                                {"reason": "no impact involved this body"}))
            continue
        used = own[:1] if ev.impacts == "first" else own
        dv = sum(d for d, _ in used)
        heading = own[0][1]
        n_imp = len(used)
        if ev.component == "magnitude":
            computed = float(np.hypot(*dv))
        else:
            local = rotate(dv, -heading)
            computed = float(local[0] if ev.component == "longitudinal"
                             else local[1] if ev.lateral_positive == "left" else -local[1])
        res = computed - ev.value
        checks.append(Check("delta-v", name, res, ev.tolerance, abs(res) <= ev.tolerance, "speed",
                            {"computed": computed, "measured": ev.value, "component": ev.component,
                             **({"lateral_positive": ev.lateral_positive} if ev.component == "lateral" else {}),
                             "impacts": ev.impacts, "impacts_counted": n_imp}))
    for i, ev in enumerate(evidence.recorder):
        checks.append(_check_recorder(ev, approach_of_body(approaches, ev.body), i))
    if evidence.crush:
        checks += crush_checks(evidence.crush, impact, secondary)
    for ev in evidence.rollover:
        checks.append(_check_rollover(ev, runout))
    return EvidenceReport(tuple(checks))


def _check_rollover(ev: RolloverEvidence, runout: dict | None) -> Check:
    """A rollover statement against the run-out's wheel-lift and rollover check."""
    stated = "rolls" if ev.rolled else "does not roll"
    name = ev.name or f"{ev.unit} {stated}"
    for vname, r in (runout or {}).items():
        if ev.unit != vname and ev.unit not in r.bodies:
            continue
        roll = getattr(r, "rollover", None)
        if roll is None:
            break
        computed = roll["rolled"] if ev.unit == vname else ev.unit in roll["rolled_bodies"]
        res = float(computed) - float(ev.rolled)
        return Check("rollover", name, res, 0.0, computed == ev.rolled, "dimensionless",
                     {"computed": bool(computed), "stated": bool(ev.rolled), "valid_until_s": roll["valid_until_s"],
                      "rolled_bodies": list(roll["rolled_bodies"])})
    return Check("rollover", name, math.inf, 0.0, False, "dimensionless",
                 {"reason": "no wheel-lift and rollover check was run for it (runout.rollover, level load_transfer)"})

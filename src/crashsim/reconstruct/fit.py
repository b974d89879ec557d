"""The inverse side: find the unknown inputs that make impact + run-out agree with the scene.

A fit minimises the weighted sum of squares of the evidence residuals,

    chi^2(x) = sum_i (r_i(x) / sigma_i)^2,

over the unknowns ``x`` inside their bounds (``scipy.optimize.least_squares``, bounded
trust-region), where every evaluation of ``r`` runs the whole scene (impact, then each
vehicle's run-out to rest) for a scenario built from the file with the unknowns written in
(:mod:`crashsim.reconstruct.overrides`: validated exactly like file values).

Residuals (one vector per evidence item, each component divided by its sigma)
-----------------------------------------------------------------------------
rest position    computed minus measured CG rest position, x and y [m]          (2)
rest heading     computed minus measured heading, wrapped to (-pi, pi] [rad]     (1)
point of impact  scenario contact point minus measured point, x and y [m]      (2)
delta-v          computed minus recorded delta-v (as the evidence check) [m/s]  (1)
tyre mark        signed distance of ``mark_points`` points spread evenly along the measured
                 mark to the track of the matching wheel [m], each divided by
                 ``sigma * sqrt(mark_points)`` so that the mark weighs as one measurement
                 (its points are not independent): its term of chi^2 is the mean squared
                 distance over sigma^2. Wheel chosen as the matching wheel whose sliding track
                 (any track if no matching wheel slides) gives the least sum of squares.

Uncertainty of the answer
-------------------------
At the best point the weighted Jacobian ``J`` (d r_i/sigma_i / d x_j, central differences
with step ``diff_step`` times each bound range) gives the covariance ``C = (J^T J)^-1``
(= (J^T W J)^-1 of the unweighted residuals, W = diag(1/sigma^2)): the linearised
uncertainty of the unknowns when the sigmas are the measurement uncertainties
(``covariance = "absolute"``, normal quantiles). With ``"scaled"`` C is multiplied by
chi^2/dof and Student's t quantiles are used (sigmas known only up to a common factor).
The intervals are linearised: they are good while the model is close to linear over them.
The report checks that (``LinearityProbe``): at one standard error from the best along each
axis of the covariance (both signs; shortened where a bound comes first, not probed where the
bound leaves less than ``LINEARITY_MIN_STEP`` of the step) it evaluates the scene and compares
the rise of chi^2 with the linearised model's rise ``|r + J dz|^2 - |r|^2`` (1 on a full-length
step from an interior minimum); a rise off by more than ``LINEARITY_FACTOR`` either way fails.

Warnings
--------
* An unknown no evidence item depends on (a zero column of J).
* Rank deficiency: the singular value decomposition of J with unit-norm columns; a relative
  singular value below ``RANK_TOL`` means a combination of unknowns the evidence cannot
  fix; the unknowns in that null-space direction are named. Their intervals are infinite.
* An interval wider than the unknown's bounds (poorly determined).
* A bound hit: the evidence pulls an unknown past its bound; its interval is not valid.
* chi^2 improbably large for its degrees of freedom (p < 0.01): the sigmas are too small or
  the model misses something; the absolute intervals are then too narrow.
* Starts that ended in different minima (the report says how many agreed with the best).
* A failed linearity probe: chi^2 one standard error away rises more than ``LINEARITY_FACTOR``
  times, or less than 1/``LINEARITY_FACTOR`` of, what the linearised model gives; the intervals
  are then too wide or too narrow there, and ``crashsim posterior`` is the answer to quote.
"""

from __future__ import annotations

import copy
import datetime
import logging
import math
import os
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np
from scipy.optimize import least_squares

from .._version import __version__
from ..errors import ScenarioError, SolverError, UnreachableImpactError, failure_reason, in_file
from ..evidence.checks import (approach_of_body, approach_tracks, recorder_residuals, recorder_window,
                               signed_distance_to_polyline, wheel_matches)
from ..evidence.crush import GROUP_TITLES, crush_groups
from ..geometry import wrap_angle
from ..inverse_schema import CORRELATION_WARNING, validate_fit
from ..outputs import check_workers, same_file
from ..report import fmt, table
from ..scenario import Scenario
from ..schema import in_range, interval_text
from ..units import resolve_system, system_label
from .montecarlo import DEFAULT_SAMPLE_TIME_LIMIT
from .overrides import (default_engine, file_contents, forward_data, get_value, parse_value,
                        resolve_path, set_value)
from .inputs import Scene
from .parallel import Executor, Progress
from .write_best import edit_best

__all__ = ["FitSpec", "Unknown", "FitProblem", "FitResult", "EvidenceResidual", "StartResult", "fit_scene",
           "RANK_TOL", "PENALTY", "LINEARITY_FACTOR", "LINEARITY_MIN_STEP", "LinearityProbe"]

_log = logging.getLogger("crashsim")

#: Relative singular value (columns of the weighted Jacobian scaled to unit norm) below which
#: the evidence is taken not to determine a combination of unknowns. A product a*b that alone
#: enters the residuals gives ~1e-6 with central differences; a pair correlated at 0.99995
#: (still determined, with wide intervals) gives 1e-2.
RANK_TOL = 1e-4

#: Residual (in sigmas) given to every component when a scene cannot be evaluated (a value
#: the scenario rejects in combination, a failed solver): keeps the optimiser away from it.
PENALTY = 1e3

#: The linearity check of the intervals: one standard error either side of the best point along
#: each principal axis of the covariance, chi^2 rises by what the linearised model predicts there
#: (1 for an interval inside the bounds, absolute covariance) if the model is linear over the
#: interval. A rise below 1/LINEARITY_FACTOR or above LINEARITY_FACTOR times the prediction is
#: warned about: the intervals are then about sqrt(LINEARITY_FACTOR) or more too narrow or too wide.
LINEARITY_FACTOR = 2.0
#: ... and a direction is probed only if the bounds leave at least this fraction of the step.
LINEARITY_MIN_STEP = 0.1


def _bare(exc: ScenarioError) -> str:
    """The message of a ScenarioError without its ``field: `` prefix."""
    text = str(exc)
    for part in (exc.file, exc.field):
        if part and text.startswith(f"{part}: "):
            text = text[len(part) + 2:]
    return text


# ---------------------------------------------------------------------------------------------
# Specification
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Unknown:
    """One unknown: a scenario input, its bounds and start value (SI)."""

    path: str
    name: str
    lower: float
    upper: float
    initial: float
    kind: str  # unit kind ("speed", "angle", "dimensionless", ...)

    @property
    def span(self) -> float:
        return self.upper - self.lower


def _check_bounds_allowed(target, lo: float, hi: float, raw: dict, key: str, file: str | None) -> None:
    """The bounds of an unknown must lie in the allowed range of its input (every evaluation is then valid)."""
    for which, x in (("lower", lo), ("upper", hi)):
        if not in_range(x, target.field):
            raise ScenarioError(f"{which} = {raw[which]!r} lies outside the allowed range of {target.path}, "
                                f"{interval_text(target.field, raw[which])}", field=f"{key}.{which}", file=file)


@dataclass(frozen=True)
class FitSpec:
    """A validated ``[fit]`` table: unknowns (SI) and options.

    Build it with :meth:`from_dict` from the raw table (as in the file), or directly.
    """

    unknowns: tuple[Unknown, ...]
    starts: int = 4
    screen: int = 0
    seed: int = 0
    method: str = "trf"
    max_evaluations: int = 200
    diff_step: float = 1e-3
    confidence: float = 0.95
    covariance: str = "absolute"
    sigma_from_tolerance: float | None = None
    mark_points: int = 10
    correlation_warning: float = CORRELATION_WARNING
    #: What :meth:`from_dict` found worth a warning in the table (the fit's report lists them).
    notes: tuple[str, ...] = ()

    @property
    def paths(self) -> tuple[str, ...]:
        return tuple(u.path for u in self.unknowns)

    @classmethod
    def from_dict(cls, raw: dict, data: dict | None = None, *, file: str | None = None) -> "FitSpec":
        """Validate a raw [fit] table (values with units, as in the file) and convert it to SI.

        ``data`` (the raw scenario) supplies the default start values (the file's values).
        """
        d = validate_fit(raw, file=file)
        base = forward_data(data, file=file) if data is not None else None
        unknowns, notes = [], []
        for i, u in enumerate(d["unknowns"]):
            key = f"fit.unknowns[{i}]"
            t = resolve_path(u["path"], field=f"{key}.path")
            lo = parse_value(u["lower"], t, field=f"{key}.lower")
            hi = parse_value(u["upper"], t, field=f"{key}.upper")
            if not lo < hi:
                raise ScenarioError(f"lower {u['lower']!r} must be below upper {u['upper']!r}", field=f"{key}.upper",
                                    file=file)
            _check_bounds_allowed(t, lo, hi, u, key, file)
            if u["initial"] is not None:
                x0 = parse_value(u["initial"], t, field=f"{key}.initial")
                if not lo <= x0 <= hi:
                    raise ScenarioError(f"initial {u['initial']!r} lies outside [{u['lower']}, {u['upper']}]",
                                        field=f"{key}.initial", file=file)
            raw_v = get_value(base, t) if base is not None else None
            in_file = parse_value(raw_v, t, field=t.path) if raw_v is not None else None
            if in_file is not None and not lo <= in_file <= hi:
                notes.append(f"{key}: the file's {t.path} = {raw_v!r} lies outside the bounds [{u['lower']}, "
                             f"{u['upper']}]: the fit does not consider it, and the file's own value is what "
                             "`crashsim run` of the file computes")
            if u["initial"] is None:
                x0 = in_file if in_file is not None and lo <= in_file <= hi else 0.5 * (lo + hi)
            unknowns.append(Unknown(t.path, u["name"] or t.path, lo, hi, x0, t.kind))
        return cls(tuple(unknowns), starts=d["starts"], screen=d["screen"], seed=d["seed"], method=d["method"],
                   max_evaluations=d["max_evaluations"], diff_step=d["diff_step"], confidence=d["confidence"],
                   covariance=d["covariance"], sigma_from_tolerance=d["sigma_from_tolerance"],
                   mark_points=d["mark_points"], correlation_warning=d["correlation_warning"], notes=tuple(notes))

    def to_dict(self) -> dict:
        return {"unknowns": [u.__dict__.copy() for u in self.unknowns],
                **{k: getattr(self, k) for k in ("starts", "screen", "seed", "method", "max_evaluations", "diff_step",
                                                 "confidence", "covariance", "sigma_from_tolerance", "mark_points",
                                                 "correlation_warning")}}


# ---------------------------------------------------------------------------------------------
# Evidence residuals
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class _Item:
    kind: str            # "rest", "rest heading", "point of impact", "delta-v", "mark"
    name: str
    quantity: str        # "length", "angle", "speed"
    sigma: float
    sigma_source: str    # "sigma" or "tolerance x f"
    size: int            # number of residual components
    weight_size: float   # measurements it counts as (for dof)
    index: int           # index of the evidence item in its list
    body: str | None = None
    measured: Any = None
    mark: Any = None     # MarkEvidence


def _resample(points: np.ndarray, k: int) -> np.ndarray:
    """``k`` points evenly spaced by arc length along a polyline."""
    pts = np.asarray(points, dtype=float)
    seg = np.hypot(*np.diff(pts, axis=0).T)
    s = np.concatenate([[0.0], np.cumsum(seg)])
    if s[-1] <= 0:
        return np.repeat(pts[:1], k, axis=0)
    q = np.linspace(0.0, s[-1], k)
    return np.column_stack([np.interp(q, s, pts[:, 0]), np.interp(q, s, pts[:, 1])])


def _mark_distances(item: _Item, tracks: dict, k: int, pts: np.ndarray | None = None) -> tuple[np.ndarray, str | None]:
    """Signed distances of ``k`` points spread along the mark to the best-matching wheel's track, and
    that wheel (``pts``: the mark's ``_resample(points, k)``, if already computed)."""
    ev = item.mark
    pts = _resample(ev.points, k) if pts is None else pts
    best = None
    for sliding in ((True, False) if ev.sliding_only else (False,)):
        for key, tr in tracks.items():
            if not wheel_matches(tr, ev.wheel):
                continue
            pieces = [s.points for s in tr.segments if (s.kind == "sliding" or not sliding) and len(s.points)]
            if not pieces:
                continue
            ds = np.stack([signed_distance_to_polyline(pts, piece) for piece in pieces])
            d = ds[np.argmin(np.abs(ds), axis=0), np.arange(len(pts))]
            ss = float(np.sum(d * d))
            if best is None or ss < best[0]:
                best = (ss, d, key)
        if best is not None:
            break
    if best is None:
        return np.full(k, np.nan), None
    return best[1], best[2]


class EvidenceModel:
    """The evidence of a scenario as a fixed-length vector of weighted residuals.

    Parameters
    ----------
    scenario : Scenario
        Validated; each evidence item carries its ``sigma`` (and a rest item its ``heading_sigma``).
    sigma_from_tolerance : float, optional
        Fraction of the tolerance used as sigma where an item has none.
    mark_points : int
    """

    def __init__(self, scenario, *, sigma_from_tolerance: float | None = None, mark_points: int = 10):
        ev = scenario.evidence
        self.mark_points = int(mark_points)
        items: list[_Item] = []

        def sig(s: float | None, key: str, tol: float, where: str) -> tuple[float, str]:
            if s is not None:
                return float(s), key
            if sigma_from_tolerance is not None:
                return float(sigma_from_tolerance * tol), f"tolerance x {sigma_from_tolerance:g}"
            raise ScenarioError(f"the fit needs the measurement uncertainty of every evidence item: add {key} = ... "
                                f"here, or fit.sigma_from_tolerance (e.g. 0.5: the tolerance is 2 sigma)",
                                field=f"{where}.{key}", file=scenario.path)

        if ev.impact_point is not None:
            s, src = sig(ev.impact_point.sigma, "sigma", ev.impact_point.tolerance, "evidence.impact_point")
            items.append(_Item("point of impact", ev.impact_point.name, "length", s, src, 2, 2.0, 0,
                               measured=np.asarray(ev.impact_point.position, float)))
        if ev.rest and scenario.runout is None:
            raise ScenarioError("rest-position evidence needs a run-out: add [runout]", field="evidence.rest",
                                file=scenario.path)
        if any(m.phase == "runout" for m in ev.marks) and scenario.runout is None:
            raise ScenarioError("tyre-mark evidence needs a run-out: add [runout]", field="evidence.marks",
                                file=scenario.path)
        for i, r in enumerate(ev.rest):
            name = r.name or f"rest of {r.body}"
            s, src = sig(r.sigma, "sigma", r.tolerance, f"evidence.rest[{i}]")
            items.append(_Item("rest", name, "length", s, src, 2, 2.0, i, body=r.body,
                               measured=np.asarray(r.position, float)))
            if r.heading is not None:
                s, src = sig(r.heading_sigma, "heading_sigma", r.heading_tolerance, f"evidence.rest[{i}]")
                items.append(_Item("rest heading", f"{name} (heading)", "angle", s, src, 1, 1.0, i, body=r.body,
                                   measured=float(r.heading)))
        for i, m in enumerate(ev.marks):
            s, src = sig(m.sigma, "sigma", m.tolerance, f"evidence.marks[{i}]")
            items.append(_Item("mark", m.name or f"mark {i + 1}", "length", s, src, self.mark_points, 1.0, i,
                               mark=m))
        for i, x in enumerate(ev.delta_v):
            s, src = sig(x.sigma, "sigma", x.tolerance, f"evidence.delta_v[{i}]")
            items.append(_Item("delta-v", x.label, "speed", s, src, 1, 1.0,
                               i, body=x.body, measured=float(x.value)))
        for i, x in enumerate(ev.recorder):
            s, src = sig(x.sigma, "sigma", x.tolerance, f"evidence.recorder[{i}]")
            n = len(x.times)
            items.append(_Item("recorder", x.name or f"recorder in {x.body}", "speed", s, src, n, float(n), i,
                               body=x.body, measured=x))
        if ev.crush:
            for which, idx in crush_groups(ev.crush):
                # the group's sigma: root sum of squares of its items' (independent measurements)
                parts, srcs = [], set()
                for i in idx:
                    c = ev.crush[i]
                    if c.sigma is None and c.tolerance is None and sigma_from_tolerance is not None:
                        raise ScenarioError("the fit needs this crush item's sigma (an energy): its tolerance is "
                                            "relative to an energy that changes with the fit; add sigma = ...",
                                            field=f"evidence.crush[{i}].sigma", file=scenario.path)
                    s_i, src = sig(c.sigma, "sigma", c.tolerance or 0.0, f"evidence.crush[{i}]")
                    parts.append(s_i)
                    srcs.add(src)
                items.append(_Item("crush energy", f"crush energy, {GROUP_TITLES[which]}", "energy",
                                   math.sqrt(sum(p * p for p in parts)), ", ".join(sorted(srcs)), 1, 1.0, idx[0]))
        if not items:
            raise ScenarioError("the scenario has no evidence to fit: add [evidence] items with their sigma",
                                field="evidence", file=scenario.path)
        self.items = tuple(items)
        #: Each mark's points spread along it (the same at every evaluation)
        self._mark_points = {i: _resample(it.mark.points, self.mark_points) for i, it in enumerate(items)
                             if it.kind == "mark"}
        self.size = sum(it.size for it in items)
        self.n_measurements = sum(it.weight_size for it in items)

    def checks(self, scene) -> list:
        """The evidence check (verdict against the tolerance) of each item, in item order.

        Matched by kind and order (:func:`~crashsim.evidence.checks.evaluate_evidence`
        checks the items kind by kind in file order), so equal names do not mix them up.
        """
        by_kind: dict[str, list] = {}
        for c in (scene.evidence.checks if scene.evidence is not None else ()):
            by_kind.setdefault(c.kind, []).append(c)
        seen: dict[str, int] = {}
        out = []
        for it in self.items:
            k = seen.get(it.kind, 0)
            seen[it.kind] = k + 1
            lst = by_kind.get(it.kind, [])
            out.append(lst[k] if k < len(lst) else None)
        return out

    def raw_residuals(self, scene) -> tuple[list[np.ndarray], list[dict]]:
        """Per item: the unweighted residual vector (SI) and details (computed value, matched wheel)."""
        item_checks = self.checks(scene)
        bodies, tracks = {}, {}
        for r in (scene.runout or {}).values():
            bodies.update(r.bodies)
            tracks.update(r.wheels)
        approaches = getattr(scene.scenario, "approaches", None) or {}
        pre_tracks = None
        out, det = [], []
        for i, (it, c) in enumerate(zip(self.items, item_checks)):
            if it.kind == "point of impact":
                computed = np.asarray(scene.scenario.impact.surface.point, float)
                out.append(computed - it.measured)
                det.append({"computed": computed.tolist()})
            elif it.kind == "rest":
                b = bodies[it.body]
                computed = np.asarray(b.rest_position, float)
                out.append(computed - it.measured)
                det.append({"computed": computed.tolist(), "at_rest": b.time_to_rest is not None})
                if c is not None and "registration" in c.details:  # the measured CG came from measured points
                    det[-1]["registration"] = c.details["registration"]
            elif it.kind == "rest heading":
                b = bodies[it.body]
                out.append(np.array([float(wrap_angle(b.rest_heading - it.measured))]))
                det.append({"computed": float(wrap_angle(b.rest_heading))})
            elif it.kind == "recorder":
                # this evaluation's own item: its time_offset (a fit unknown) moves the samples and
                # which of them are before the impact; the file's item is only the shape of the vector
                x = scene.scenario.evidence.recorder[it.index]
                a = approach_of_body(approaches, it.body)
                if a is None:
                    out.append(np.full(it.size, np.nan))
                    det.append({"computed": None})
                else:
                    computed, res = recorder_residuals(x, a)
                    out.append(res)
                    det.append({"computed": [None if not math.isfinite(v) else float(v) for v in computed],
                                "time_offset": float(x.time_offset), "compared": recorder_window(x).tolist()})
            elif it.kind == "mark" and it.mark.phase == "approach":
                if pre_tracks is None:
                    pre_tracks = approach_tracks(approaches)
                d, key = _mark_distances(it, pre_tracks, self.mark_points, getattr(self, "_mark_points", {}).get(i))
                out.append(d)
                det.append({"matched_wheel": key, "rms_distance": float(np.sqrt(np.mean(d * d)))})
            elif it.kind == "mark":
                d, key = _mark_distances(it, tracks, self.mark_points, getattr(self, "_mark_points", {}).get(i))
                out.append(d)
                det.append({"matched_wheel": key, "rms_distance": float(np.sqrt(np.mean(d * d)))})
            elif it.kind == "crush energy":  # loss minus crush energy; one-sided when a crushed body has no item
                r = c.residual if c.details.get("complete", True) else min(c.residual, 0.0)
                out.append(np.array([r]))
                det.append({"computed": c.details.get("computed"), "measured": c.details.get("measured")})
            else:  # delta-v: the check's signed residual (one definition of the components)
                out.append(np.array([c.residual]))
                det.append({"computed": c.details.get("computed")})
        return out, det

    def weights(self) -> np.ndarray:
        """1/sigma per residual component (marks: 1/(sigma sqrt(k)))."""
        w = []
        for it in self.items:
            scale = it.sigma * (math.sqrt(it.size) if it.kind == "mark" else 1.0)
            w += [1.0 / scale] * it.size
        return np.asarray(w)

    def weighted(self, scene) -> np.ndarray:
        raw, _ = self.raw_residuals(scene)
        r = np.concatenate(raw) * self.weights()
        return np.where(np.isfinite(r), r, PENALTY)


# ---------------------------------------------------------------------------------------------
# The problem: unknowns (scaled to [0, 1]) -> weighted residuals
# ---------------------------------------------------------------------------------------------

class NotAtRest(Exception):
    """A scene evaluation whose run-out a limit ended (a failed evaluation of the fit)."""

    def __init__(self, status: str, message: str):
        self.status = status
        super().__init__(message)


#: An unknown whose weighted sensitivity (Jacobian column norm, scaled unknowns) is below this
#: fraction of the largest is reported as one no evidence depends on.  Not zero: in a scene's
#: joint run-out all vehicles share the integrator's steps, so an unknown of one vehicle moves
#: another's rest position by integration error even when they never touch (measured: 2e-8 of
#: the largest sensitivity with the compiled engine, 8e-6 with SciPy's LSODA, on the car-car
#: test scene).  An unknown 10^4 times weaker than the strongest is undetermined in practice.
SENSITIVITY_FLOOR = 1e-4

#: Stop rule of each local fit (scipy's ``least_squares``): the relative change of chi^2 in a step
#: (``ftol``) and of the scaled unknowns (``xtol``, a share of each unknown's range).  A start that
#: stops here is 1e-5 of the range from its minimum, far inside the tolerance by which starts are
#: said to agree (1e-3 of the range or a quarter standard error) and a few 1e-5 standard errors on
#: the shipped fit scene; 1e-8 / 1e-7 (before) reached the same best point, chi^2 and uncertainties
#: to the digits reported with 30 % more evaluations (597 against 412 there).
LOCAL_FTOL = 1e-6
LOCAL_XTOL = 1e-5


class FitProblem:
    """Unknowns scaled to ``z`` in [0, 1] (``x = lower + z * (upper - lower)``) -> weighted residuals.

    Evaluations are cached (the optimiser asks for the residual and then the Jacobian at the
    same point). Not thread-safe; each worker process builds its own.
    """

    def __init__(self, data: dict, spec: FitSpec, *, engine: str | None = None, file: str | None = None,
                 sample_time_limit: float | None = None):
        self.spec = spec
        self.file = file
        self.engine = default_engine() if engine is None else engine
        self.inputs = Scene(data, engine=self.engine, file=file, max_wall_time=sample_time_limit).inputs(
            spec.paths, field="fit.unknowns")
        self.lower = np.array([u.lower for u in spec.unknowns])
        self.upper = np.array([u.upper for u in spec.unknowns])
        self.span = self.upper - self.lower
        x0 = np.array([u.initial for u in spec.unknowns])
        try:
            base = self.inputs.scenario(x0)
        except ScenarioError as exc:
            raise ScenarioError(f"the start values of the unknowns give an invalid scenario: {_bare(exc)}",
                                field=exc.field, file=file) from None
        self.evidence = EvidenceModel(base, sigma_from_tolerance=spec.sigma_from_tolerance,
                                      mark_points=spec.mark_points)
        self.nfev = 0
        self.rolled = 0  # evaluations in which a unit rolls (the wheel-lift and rollover check on)
        self.checked = False  # whether the scenes carry the check
        self.failures = 0
        self.failure_reasons: dict[str, int] = {}
        self._cache: dict[bytes, tuple[np.ndarray, Any]] = {}
        self._order: list[bytes] = []

    def check_bounds(self) -> None:
        """Build the scenario with each unknown at each bound (others at their start): invalid -> ScenarioError."""
        x0 = np.array([u.initial for u in self.spec.unknowns])
        for j, u in enumerate(self.spec.unknowns):
            for which, v in (("lower", u.lower), ("upper", u.upper)):
                x = x0.copy()
                x[j] = v
                try:
                    self.inputs.scenario(x)
                except UnreachableImpactError:
                    continue  # valid, but the motion cannot reach the impact there: those evaluations fail
                except ScenarioError as exc:
                    raise ScenarioError(f"{which} bound of {u.path} gives an invalid scenario: {exc.field}: {_bare(exc)}",
                                        field=f"fit.unknowns[{j}].{which}", file=self.file) from None

    def x_of(self, z) -> np.ndarray:
        return self.lower + np.clip(np.asarray(z, float), 0.0, 1.0) * self.span

    def z_of(self, x) -> np.ndarray:
        return (np.asarray(x, float) - self.lower) / self.span

    #: Evaluations run the lean scene (:func:`~crashsim.scene.run.run_scene` ``lean=True``:
    #: the same residuals, without what no evidence reads, and without the tyre-mark checks,
    #: whose distances :class:`EvidenceModel` measures itself); the best point's scene is run in full.
    lean = True

    def scene(self, x, *, lean: bool | None = None):
        """Run the scene at unknowns ``x`` (SI); ``lean`` default :attr:`lean`."""
        lean = self.lean if lean is None else lean
        return self.inputs.run(x, lean=lean, mark_checks=not lean)

    def full_scene(self, z):
        """The full SceneResult at scaled point ``z`` (for reports and figures), or the error that stops it."""
        try:
            return self.scene(self.x_of(np.asarray(z, float)), lean=False)
        except (ScenarioError, SolverError) as exc:
            return exc

    def evaluate(self, z) -> tuple[np.ndarray, Any]:
        """(weighted residuals, SceneResult or the error) at scaled point ``z``."""
        z = np.asarray(z, float)
        key = z.tobytes()
        hit = self._cache.get(key)
        if hit is not None:
            return hit
        self.nfev += 1
        try:
            scene = self.scene(self.x_of(z))
            if not scene.at_rest:  # a limit ended the run-out: its positions are not rest positions
                bad = next(r_ for r_ in scene.runout.values() if not r_.success)
                raise NotAtRest(bad.status, f"the run-out of {bad.vehicle!r} did not reach rest: {bad.message}")
            r = self.evidence.weighted(scene)
            out = (r, scene)
            roll = scene.rollover()
            if roll:
                self.checked = True
                self.rolled += any(v["rolled"] for v in roll.values())
        except NotAtRest as exc:
            self._fail(f"run-out: {exc.status}", exc)
            out = (np.full(self.evidence.size, PENALTY), exc)
        except (ScenarioError, SolverError) as exc:
            self._fail(failure_reason(exc), exc)
            out = (np.full(self.evidence.size, PENALTY), exc)
        self._cache[key] = out
        self._order.append(key)
        if len(self._order) > 32:
            self._cache.pop(self._order.pop(0), None)
        return out

    def _fail(self, reason: str, exc: Exception) -> None:
        self.failures += 1
        self.failure_reasons[reason] = self.failure_reasons.get(reason, 0) + 1
        _log.debug("fit evaluation failed (%s): %s", reason, exc)

    def residual(self, z) -> np.ndarray:
        return self.evaluate(z)[0]

    def cost(self, z) -> float:
        r = self.residual(z)
        return 0.5 * float(r @ r)

    def jacobian(self, z, *, central: bool = False) -> np.ndarray:
        """d(weighted residuals)/dz by finite differences, step ``diff_step`` (one-sided at a bound)."""
        z = np.asarray(z, float)
        h = self.spec.diff_step
        f0 = self.residual(z)
        J = np.empty((f0.size, z.size))
        for j in range(z.size):
            up, dn = z.copy(), z.copy()
            if central and z[j] - h >= 0.0 and z[j] + h <= 1.0:
                up[j] += h
                dn[j] -= h
                J[:, j] = (self.residual(up) - self.residual(dn)) / (2 * h)
            else:
                step = h if z[j] + h <= 1.0 else -h
                up[j] += step
                J[:, j] = (self.residual(up) - f0) / step
        return J

    def local_fit(self, z0) -> dict:
        """One bounded least-squares fit from ``z0``; a plain dict (crosses process boundaries)."""
        n0, r0 = self.nfev, self.rolled
        z0 = np.clip(np.asarray(z0, float), 1e-9, 1 - 1e-9)
        res = least_squares(self.residual, z0, jac=lambda z: self.jacobian(z), bounds=(0.0, 1.0),
                            method=self.spec.method, x_scale=1.0, ftol=LOCAL_FTOL, xtol=LOCAL_XTOL, gtol=1e-8,
                            max_nfev=self.spec.max_evaluations)
        return {"z0": z0.tolist(), "z": res.x.tolist(), "cost": float(res.cost), "status": int(res.status),
                "message": str(res.message), "nfev": int(res.nfev), "njev": int(res.njev or 0),
                "evaluations": self.nfev - n0, "rolled": self.rolled - r0, "checked": self.checked,
                "active": [int(a) for a in res.active_mask],
                "failure_reasons": dict(self.failure_reasons)}


# ---------------------------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class EvidenceResidual:
    """Residual of one evidence item at the best fit.

    ``residual`` is computed minus measured (SI, per component: x/y for positions, the
    distances along a mark); ``normalized`` = residual / sigma (a mark's RMS distance / sigma);
    ``chi2`` the item's share of chi^2; ``passed`` the verdict against its tolerance.
    """

    kind: str
    name: str
    quantity: str
    residual: tuple[float, ...]
    sigma: float
    sigma_source: str
    normalized: float
    chi2: float
    tolerance: float | None
    passed: bool | None
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {k: getattr(self, k) for k in ("kind", "name", "quantity", "residual", "sigma", "sigma_source",
                                              "normalized", "chi2", "tolerance", "passed", "details")}


@dataclass(frozen=True)
class StartResult:
    """One local fit: start and end (SI), cost (chi^2/2), whether it agrees with the best."""

    x0: tuple[float, ...]
    x: tuple[float, ...]
    cost: float
    evaluations: int
    status: int
    message: str
    same_cost: bool
    agrees: bool

    def to_dict(self) -> dict:
        return dict(self.__dict__)


@dataclass(frozen=True)
class LinearityProbe:
    """chi^2 one standard error from the best fit along a principal axis of the covariance.

    Attributes
    ----------
    step : dict of str to float
        The step from the best point, by the unknowns' paths [SI].
    predicted : float
        Rise of chi^2 the linearised model gives there, ``|r + J dz|^2 - |r|^2`` (1 for a full
        step from an interior minimum with ``covariance = "absolute"``; a step shortened by a
        bound predicts less, a best point at a bound more).
    actual : float or None
        Rise of chi^2 the scene gives there (None: the scene cannot be evaluated there).
    """

    step: dict
    predicted: float
    actual: float | None

    @property
    def ratio(self) -> float:
        """actual / predicted (NaN where the scene cannot be evaluated)."""
        return math.nan if self.actual is None else self.actual / max(self.predicted, 1e-300)

    @property
    def linear(self) -> bool:
        """Whether the rise is within LINEARITY_FACTOR of the prediction."""
        return self.actual is not None and 1.0 / LINEARITY_FACTOR <= self.ratio <= LINEARITY_FACTOR

    def to_dict(self) -> dict:
        return {"step": dict(self.step), "predicted": self.predicted, "actual": self.actual,
                "linear": self.linear}


@dataclass(frozen=True)
class FitResult:
    """Outcome of :func:`fit_scene` (SI; ``report`` for display units).

    Attributes
    ----------
    unknowns : tuple of Unknown
    x : ndarray (n,)
        Best values [SI].
    stderr : ndarray (n,)
        Standard errors (inf where the evidence does not determine the unknown).
    interval : ndarray (n, 2)
        ``confidence`` intervals (linearised; not clipped to the bounds).
    covariance, correlation : ndarray (n, n)
    residuals : tuple of EvidenceResidual
    chi2, dof, p_value : float, int, float
    singular_values : ndarray
        Of the weighted Jacobian with unit-norm columns, relative to the largest, in decreasing
        order (a zero for each unknown no evidence depends on).
    null_space : list of dict
        Each undetermined direction: ``{"singular_value", "unknowns": {path: component}}``.
    starts : tuple of StartResult
    n_agree : int
        Starts that reached the best minimum (same cost and same point).
    warnings : tuple of str
    failures, failure_reasons : int, dict
        Scene evaluations that failed (penalised), and their number by reason (an inadmissible
        impact, a run-out ended by a limit, ...), over every start and process.
    scene : SceneResult
        The scene at the best values (not in ``to_dict``).
    success : bool
        False if the best start did not converge or evaluations failed at the best point.
    """

    unknowns: tuple
    x: np.ndarray
    stderr: np.ndarray
    interval: np.ndarray
    covariance: np.ndarray
    correlation: np.ndarray
    residuals: tuple
    chi2: float
    dof: int
    p_value: float
    confidence: float
    covariance_mode: str
    singular_values: np.ndarray
    null_space: list
    starts: tuple
    n_agree: int
    n_same_cost: int
    warnings: tuple
    evaluations: int
    failures: int
    elapsed: float
    engine: str
    success: bool
    message: str
    scene: Any = field(default=None, repr=False, compare=False)
    failure_reasons: dict = field(default_factory=dict)
    source_data: Any = field(default=None, repr=False, compare=False)
    file: str | None = None
    rolled_evaluations: int | None = None  # the wheel-lift and rollover check on: evaluations in which a unit rolls
    rolled_of: int = 0  # ... of this many (the local fits' and the analysis's; not the screening's)
    linearity: tuple = ()  # LinearityProbe: chi^2 one standard error from the best, both ways along each axis
    linearity_skipped: int = 0  # ... directions not probed: a bound leaves less than LINEARITY_MIN_STEP of the step

    @property
    def values(self) -> dict:
        """Best values by path [SI]."""
        return {u.path: float(v) for u, v in zip(self.unknowns, self.x)}

    def to_dict(self) -> dict:
        n = len(self.unknowns)
        fin = lambda v: float(v) if np.isfinite(v) else None  # noqa: E731
        return {
            "success": self.success, "message": self.message, "engine": self.engine,
            "unknowns": [{"path": u.path, "name": u.name, "kind": u.kind, "value": float(self.x[i]),
                          "stderr": fin(self.stderr[i]), "interval": [fin(self.interval[i, 0]), fin(self.interval[i, 1])],
                          "lower": u.lower, "upper": u.upper, "initial": u.initial} for i, u in enumerate(self.unknowns)],
            "confidence": self.confidence, "covariance_mode": self.covariance_mode,
            "covariance": [[fin(self.covariance[i, j]) for j in range(n)] for i in range(n)],
            "correlation": [[fin(self.correlation[i, j]) for j in range(n)] for i in range(n)],
            "residuals": [r.to_dict() for r in self.residuals],
            "chi2": self.chi2, "dof": self.dof, "p_value": fin(self.p_value),
            "singular_values": [float(s) for s in self.singular_values], "null_space": self.null_space,
            "starts": [s.to_dict() for s in self.starts], "n_starts": len(self.starts), "n_agree": self.n_agree,
            "n_same_cost": self.n_same_cost, "warnings": list(self.warnings), "evaluations": self.evaluations,
            "failures": self.failures, "failure_reasons": dict(self.failure_reasons), "elapsed": self.elapsed,
            "linearity": [p.to_dict() for p in self.linearity], "linearity_factor": LINEARITY_FACTOR,
            "linearity_skipped": self.linearity_skipped,
            **({"rolled_evaluations": self.rolled_evaluations, "rolled_of": self.rolled_of,
                "rollover": self._best_rollover()}
               if self.rolled_evaluations is not None else {}),
        }

    def _best_rollover(self) -> dict:
        """The best fit's wheel-lift and rollover summary by vehicle (empty without its scene)."""
        return self.scene.rollover() if self.scene is not None and not isinstance(self.scene, Exception) else {}

    def rollover_lines(self, system: str) -> list[str]:
        """The report's rollover lines: the best fit's verdict and the evaluations that rolled (none
        without the check)."""
        if self.rolled_evaluations is None:
            return []
        lines = ["Rollover (an outcome, not a failure; wheel-lift and rollover check)"]
        for v, roll in self._best_rollover().items():
            until = roll["valid_until_s"]
            verdict = (f"rolls ({', '.join(roll['rolled_bodies'])})" if roll["rolled"] else "does not roll")
            valid = ("planar result valid throughout" if until is None else
                     f"planar result outside its validity from {fmt(until, 'time', system)}")
            lines.append(f"  best fit: vehicle {v} {verdict}; {valid}")
        lines.append(f"  a unit rolls in {self.rolled_evaluations} of the {self.rolled_of} scene evaluations of the "
                     "local fits and the analysis")
        ev = getattr(self.scene, "evidence", None) if not isinstance(self.scene, Exception) else None
        for c in (ev.checks if ev is not None else ()):
            if c.kind == "rollover":  # a statement, not fitted: its verdict at the best fit
                lines.append(f"  {'PASS' if c.passed else 'FAIL'}  evidence {c.name!r} (a verdict, not fitted)")
        return lines

    def best_scenario_dict(self) -> dict:
        """The fitted scenario file as a dict: the input file's with each unknown at its best value.

        Each unknown is written as a file value at its path, in the unit of the file's own
        value there (``"30.2 mph"`` where the file had ``"25 mph"``; a plain number stays plain,
        a percentage a percentage), or in SI where the file gave none (a preset's value, which
        the written key then overrides). The ``[fit]`` table is removed. Where the fit's
        run-out engine differs from the file's, ``runout.engine`` is set to it, so that
        ``crashsim run`` on the written file reproduces the fit's best residuals.

        Returns
        -------
        dict
            Raw file values (with units), as from :func:`crashsim.schema.load_toml`.

        Raises
        ------
        ValueError
            If this result does not hold its input (built by hand, not by :func:`fit_scene`).
        """
        if self.source_data is None:
            raise ValueError("this FitResult does not hold the scenario it was fitted to (made by fit_scene, it does)")
        data = copy.deepcopy({k: v for k, v in self.source_data.items() if k != "fit"})
        for u, x in zip(self.unknowns, self.x):
            data = set_value(data, resolve_path(u.path), float(x), like=True)
        runout = data.get("runout")
        if isinstance(runout, dict) and runout.get("engine", "scipy") != self.engine:
            runout["engine"] = self.engine
        return data

    def write_best(self, path) -> "Path":
        """Write :meth:`best_scenario_dict` as a runnable TOML scenario file.

        The input file itself with its values replaced in place (:mod:`crashsim.reconstruct.write_best`:
        comments, order and layout kept, the survey a reference, paths relative to ``path``); a
        header comment says what wrote it, from which file, the best values (with their
        intervals) and chi^2; the input's ``[fit]`` table follows at the end as comments.

        Parameters
        ----------
        path : str or Path
            The file to write; never the input file.

        Returns
        -------
        Path

        Raises
        ------
        ScenarioError
            If ``path`` is the file the fit was read from.
        """
        import tomli_w

        path = Path(path)
        if self.file is not None and same_file(path, Path(self.file)):
            raise ScenarioError(f"{str(path)!r} is the input file; the best fit is written to another file",
                                field="--write-best", file=self.file)
        data = self.best_scenario_dict()
        fit_table = (self.source_data or {}).get("fit")
        trailer = ""
        if fit_table is not None:
            trailer = ("\n# ---- The [fit] table of the input file (the fit that wrote this file) ----\n"
                       + "".join(f"# {line}\n" if line else "#\n"
                                 for line in tomli_w.dumps({"fit": fit_table}).splitlines()))
        if self.file is not None and Path(self.file).is_file():
            # the user's own file, its values replaced in place (comments, order, survey references kept)
            text = edit_best(Path(self.file), path, data, [u.path for u in self.unknowns], engine=self.engine,
                             header=_best_header(self, data), trailer=trailer)
        else:  # a scenario given as a dict: no file to edit
            text = _best_header(self, data) + tomli_w.dumps(data) + trailer
        path.write_text(text, encoding="utf-8")
        return path

    def report(self, system: str | None = None) -> str:
        """Readable report: best values with intervals, correlations, residuals, warnings
        (``system``: SI or US, any case; default the scenario's units)."""
        sc = self.scene.scenario if self.scene is not None else None
        system = resolve_system(system, sc.units if sc is not None else "SI")
        lines = [f"crashsim fit: {sc.title}" if sc is not None else "crashsim fit"]
        if sc is not None and sc.path:
            lines.append(f"file: {sc.path}")
        pct = f"{100 * self.confidence:g} %"
        lines.append(f"units: {system_label(system)}; run-out engine: {self.engine}; "
                     f"{self.evaluations} scene evaluations "
                     f"in {self.elapsed:.1f} s")
        lines.append("")
        lines.append(f"Unknowns (best fit, {pct} intervals, {'measurement sigmas' if self.covariance_mode == 'absolute' else 'scaled by chi^2/dof'})")
        rows = [["unknown", "best", "std. error", f"{pct} interval", "bounds"]]
        for i, u in enumerate(self.unknowns):
            k = u.kind
            lo, hi = self.interval[i]
            iv = (f"[{fmt(lo, k, system)}, {fmt(hi, k, system)}]" if np.isfinite(lo) and np.isfinite(hi)
                  else "not determined")
            se = fmt(self.stderr[i], k, system) if np.isfinite(self.stderr[i]) else "inf"
            rows.append([u.name, fmt(self.x[i], k, system), se, iv, f"[{fmt(u.lower, k, system)}, {fmt(u.upper, k, system)}]"])
        lines += table(rows, "lrr")
        n = len(self.unknowns)
        if n > 1:
            lines.append("")
            lines.append("Correlation of the unknowns")
            rows = [[""] + [str(j + 1) for j in range(n)]]
            for i, u in enumerate(self.unknowns):
                rows.append([f"{i + 1} {u.name}"] + [f"{self.correlation[i, j]:.3f}" if np.isfinite(self.correlation[i, j])
                                                      else "n/a" for j in range(n)])
            lines += table(rows, "l" + "r" * n)
        lines.append("")
        lines.append(f"Evidence at the best fit: chi^2 = {self.chi2:.3g} for {self.dof} degrees of freedom"
                     + (f" (p = {self.p_value:.2g})" if np.isfinite(self.p_value) else ""))
        rows = []
        for r in self.residuals:
            verdict = "" if r.passed is None else ("PASS" if r.passed else "FAIL")
            if r.kind == "mark":
                res = f"rms distance {fmt(r.normalized * r.sigma, 'length', system)}"
            else:
                res = ", ".join(fmt(v, r.quantity, system) for v in r.residual)
                res = f"residual ({res})" if len(r.residual) > 1 else f"residual {res}"
            rows.append([verdict, r.kind, r.name, res, f"sigma {fmt(r.sigma, r.quantity, system)}",
                         f"-> {r.normalized:+.2f} sigma"])
        lines += table(rows)
        lines.append("")
        same = (f"; {self.n_same_cost} reached its cost" if self.n_same_cost != self.n_agree else "")
        lines.append(f"Starts: {self.n_agree} of {len(self.starts)} agreed with the best minimum{same}")
        for k, s in enumerate(self.starts):
            mark = "*" if s.agrees else ("=" if s.same_cost else " ")
            lines.append(f"  {mark} start {k + 1}: chi^2 = {2 * s.cost:.4g}, {s.evaluations} evaluations, "
                         + ", ".join(f"{u.name} {fmt(v, u.kind, system)}" for u, v in zip(self.unknowns, s.x)))
        if self.linearity:
            lines.append("")
            lines.append("Linearity of the intervals: chi^2 one standard error from the best, along each axis of the "
                         "covariance" + (f" ({self.linearity_skipped} direction{'s' if self.linearity_skipped != 1 else ''} not "
                                         "probed: a bound leaves less than "
                                         f"{LINEARITY_MIN_STEP:g} of the step)" if self.linearity_skipped else ""))
            by_path = {u.path: u for u in self.unknowns}
            for p in self.linearity:
                step = ", ".join(f"{by_path[k].name} {'+' if v >= 0 else '-'}{fmt(abs(v), by_path[k].kind, system)}"
                                 for k, v in p.step.items())
                rise = "scene not evaluable" if p.actual is None else f"rises by {p.actual:.3g}"
                lines.append(f"  {'PASS' if p.linear else 'FAIL'}  {step}: {rise} (linearised {p.predicted:.3g})")
        roll = self.rollover_lines(system)
        if roll:
            lines += [""] + roll
        if self.warnings:
            lines.append("")
            lines.append("Warnings")
            lines += [f"  - {w_}" for w_ in self.warnings]
        return "\n".join(lines)


def _best_header(res: FitResult, data: dict) -> str:
    """The comment block at the top of a best-fit scenario file (display units of the scenario)."""
    system = resolve_system((data.get("scenario") or {}).get("units"), "SI")
    when = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%d %H:%M UTC")
    pct = f"{100 * res.confidence:g} %"
    lines = [f"Written by crashsim {__version__} (crashsim fit --write-best) on {when}",
             f"from {res.file or 'a scenario given as a dict'}: its values with the [fit] unknowns set to their "
             "best fit",
             f"chi^2 = {res.chi2:.6g} for {res.dof} degrees of freedom"
             + (f" (p = {res.p_value:.3g})" if np.isfinite(res.p_value) else "")
             + f"; fit {'converged' if res.success else 'did NOT converge: ' + res.message}",
             f"Best values ({pct} intervals, {res.covariance_mode} covariance):"]
    for i, u in enumerate(res.unknowns):
        lo, hi = res.interval[i]
        iv = f"[{fmt(lo, u.kind, system)}, {fmt(hi, u.kind, system)}]" if np.isfinite(lo) and np.isfinite(hi) \
            else "not determined"
        lines.append(f"  {u.path} = {fmt(res.x[i], u.kind, system)}  {iv}")
    lines.append("The [fit] table is removed (it follows at the end, as comments).")
    runout = data.get("runout")
    src_engine = ((res.source_data or {}).get("runout") or {}).get("engine", "scipy")
    if isinstance(runout, dict) and src_engine != res.engine:
        lines.append(f"runout.engine = \"{res.engine}\": the fit's run-out engine (the input file's was "
                     f"\"{src_engine}\"), so that crashsim run reproduces the fit's residuals.")
    if res.warnings:
        lines.append(f"The fit gave {len(res.warnings)} warning(s): see its report.")
    return "".join(f"# {line}\n" for line in lines) + "\n"


# ---------------------------------------------------------------------------------------------
# fit_scene
# ---------------------------------------------------------------------------------------------

_LOCAL = threading.local()


def _problem_for(payload: dict) -> "FitProblem":
    """A worker's fit problem, built once per thread from ``payload``."""
    cache = getattr(_LOCAL, "problems", None)
    if cache is None:
        cache = _LOCAL.problems = {}
    key = id(payload)
    p = cache.get(key)
    if p is None:
        p = cache[key] = FitProblem(payload["data"], payload["spec"], engine=payload["engine"], file=payload["file"],
                                    sample_time_limit=payload["time_limit"])
    return p


def _local_fit(problem: "FitProblem", z0):
    return problem.local_fit(z0)


def _cost(problem: "FitProblem", z):
    return problem.cost(z)


def _start_points(spec: FitSpec, ex: Executor) -> list[np.ndarray]:
    from scipy.stats import qmc

    n = len(spec.unknowns)
    first = ex.local.z_of([u.initial for u in spec.unknowns])
    if spec.starts == 1:
        return [first]
    if spec.screen > 0:
        cand = qmc.LatinHypercube(d=n, seed=spec.seed).random(spec.screen)
        costs = ex.map(_cost, list(cand))
        order = np.argsort(costs, kind="stable")
        rest = [cand[i] for i in order[:spec.starts - 1]]
    else:
        rest = list(qmc.LatinHypercube(d=n, seed=spec.seed).random(spec.starts - 1))
    return [first] + rest


def fit_scene(scenario_data: dict | Scenario, fit_spec: FitSpec | dict | None = None, *, engine: str | None = None,
              workers: int | None = None, progress: bool | Callable | None = None,
              file: str | None = None, sample_time_limit: float | None = None) -> FitResult:
    """Fit the unknowns of a scenario to its evidence (impact + run-out, weighted least squares).

    Parameters
    ----------
    scenario_data : dict or Scenario
        The raw scenario (as from TOML, e.g. :func:`crashsim.schema.load_toml`), or a Scenario
        loaded from one (its ``file_data``, not read again), with
        evidence items carrying ``sigma`` (or ``fit.sigma_from_tolerance``).
    fit_spec : FitSpec or dict, optional
        The unknowns and options: a :class:`FitSpec`, a raw [fit] table, or None for the
        scenario's own ``[fit]`` table.
    engine : {"compiled", "scipy"}, optional
        Run-out engine; default the compiled one when this crashsim has it.
    workers : int, optional
        Processes for the starts (and the screening); default all cores; 1 runs in this
        process.
    progress : bool or callable, optional
        True: a progress bar over the starts on stderr; a callable ``progress(done, total)``
        is called after each start.
    file : str, optional
        File name for messages.
    sample_time_limit : float, optional
        Wall-clock seconds allowed for the run-out of one scene evaluation (default
        :data:`crashsim.reconstruct.montecarlo.DEFAULT_SAMPLE_TIME_LIMIT`); an evaluation that
        needs longer is penalised like any failed one, and the fit goes on.

    Returns
    -------
    FitResult

    Raises
    ------
    ScenarioError
        Invalid [fit] table, path, bounds, or evidence without sigma.
    """
    scenario_data, file = file_contents(scenario_data, file)
    t0 = time.perf_counter()
    if fit_spec is None:
        if "fit" not in scenario_data:
            raise ScenarioError("the scenario has no [fit] table naming the unknowns", field="fit", file=file)
        fit_spec = scenario_data["fit"]
    with in_file(file):
        spec = fit_spec if isinstance(fit_spec, FitSpec) else FitSpec.from_dict(fit_spec, scenario_data, file=file)
    engine = default_engine() if engine is None else engine
    if sample_time_limit is None:
        sample_time_limit = DEFAULT_SAMPLE_TIME_LIMIT
    if not (sample_time_limit > 0):
        raise ScenarioError(f"the sample time limit must be > 0 s, got {sample_time_limit!r}", field="sample_time_limit")
    problem = FitProblem(scenario_data, spec, engine=engine, file=file, sample_time_limit=sample_time_limit)
    problem.check_bounds()
    # One scene in this process first: it checks that the scene runs, and it compiles the run-out
    # engine here once, so that the forked workers inherit it instead of each compiling it.
    problem.evaluate(problem.z_of([u.initial for u in spec.unknowns]))

    workers = check_workers(workers) or (os.cpu_count() or 1)
    n_tasks = max(spec.starts, 1)
    use_pool = workers > 1 and (spec.starts > 1 or spec.screen > 1)
    payload = {"data": scenario_data, "spec": spec, "engine": engine, "file": file, "time_limit": sample_time_limit}
    outcomes: list[dict] = []
    evaluations = 0
    with Progress(progress, spec.starts, desc="fit starts", unit="start", dynamic_ncols=False) as bar, \
            Executor(_problem_for, payload, "processes" if use_pool else "serial",
                     min(workers, max(n_tasks, spec.screen)), local=problem) as ex:
        starts = _start_points(spec, ex)
        evaluations += spec.screen if spec.starts > 1 else 0
        for k, outcome in enumerate(ex.submit_each(_local_fit, starts)):
            outcomes.append(outcome)
            bar.update(1, k + 1)
    evaluations += sum(o["evaluations"] for o in outcomes)
    n_before, r_before = problem.nfev, problem.rolled
    result = _analyse(problem, spec, outcomes, engine)
    evaluations += problem.nfev - n_before
    result = _replace_timing(result, evaluations, time.perf_counter() - t0, problem.failures)
    if problem.checked or any(o.get("checked") for o in outcomes):  # the check on: count what rolled
        # the local fits' evaluations (in this process or the workers) and the analysis's here; the
        # screening of the starts is not counted (its scenes are not kept)
        rolled = sum(o.get("rolled", 0) for o in outcomes) + problem.rolled - r_before
        of = sum(o["evaluations"] for o in outcomes) + problem.nfev - n_before
        result = replace(result, rolled_evaluations=int(rolled), rolled_of=int(of))

    return replace(result, source_data=scenario_data, file=file)


def _merge_reasons(tallies) -> dict[str, int]:
    out: dict[str, int] = {}
    for t in tallies:
        for k, v in t.items():
            out[k] = out.get(k, 0) + int(v)
    return out


def _replace_timing(result: FitResult, evaluations: int, elapsed: float, failures: int) -> FitResult:
    return replace(result, evaluations=evaluations, elapsed=elapsed, failures=sum(result.failure_reasons.values()))


def _analyse(problem: FitProblem, spec: FitSpec, outcomes: list[dict], engine: str) -> FitResult:
    from scipy import stats

    n = len(spec.unknowns)
    costs = np.array([o["cost"] for o in outcomes])
    best_k = int(np.argmin(costs))
    zb = np.asarray(outcomes[best_k]["z"])
    xb = problem.x_of(zb)
    r, scene = problem.evaluate(zb)
    warnings: list[str] = list(spec.notes)
    success = not isinstance(scene, Exception) and outcomes[best_k]["status"] > 0
    message = outcomes[best_k]["message"]
    if isinstance(scene, Exception):
        raise SolverError(f"the scene cannot be evaluated at the best point found: {scene}")
    if problem.lean:  # the evaluations' scenes are lean: the reported one in full (the same numbers)
        scene = problem.full_scene(zb)

    # Weighted Jacobian in the scaled unknowns z (central differences); covariance converted to SI below.
    Jz = problem.jacobian(zb, central=True)
    chi2 = float(r @ r)
    dof = int(round(problem.evidence.n_measurements)) - n

    # Identifiability: zero columns, then SVD with unit-norm columns.
    norms = np.linalg.norm(Jz, axis=0)
    big = float(np.max(norms)) if norms.size else 0.0
    undetermined = np.zeros(n, dtype=bool)
    for j in range(n):
        if norms[j] <= SENSITIVITY_FLOOR * max(big, 1e-300):
            undetermined[j] = True
            warnings.append(f"no evidence depends on {spec.unknowns[j].name} ({spec.unknowns[j].path}) beyond "
                            f"integration error (sensitivity {norms[j] / max(big, 1e-300):.1e} of the largest): "
                            "the evidence cannot determine it (its value is the start value)")
    live = ~undetermined
    null_space = []
    sv_rel = np.zeros(0)
    cov = np.full((n, n), np.nan)
    if live.any():
        Jn = Jz[:, live] / norms[live]
        U, S, Vt = np.linalg.svd(Jn, full_matrices=False)
        sv_rel_live = S / S[0] if S[0] > 0 else S
        sv_rel = np.concatenate([sv_rel_live, np.zeros(int(n - live.sum()))])
        idx_live = np.nonzero(live)[0]
        for k in np.nonzero(sv_rel_live < RANK_TOL)[0]:
            v = Vt[k]
            comp = {spec.unknowns[idx_live[j]].path: float(v[j]) for j in range(len(v)) if abs(v[j]) > 0.1}
            for j in range(len(v)):
                if abs(v[j]) > 0.1:
                    undetermined[idx_live[j]] = True
            null_space.append({"singular_value": float(sv_rel_live[k]), "unknowns": comp})
            names = " and ".join(spec.unknowns[idx_live[j]].name for j in range(len(v)) if abs(v[j]) > 0.1)
            warnings.append(f"rank deficiency: the evidence cannot determine {names} separately (relative singular "
                            f"value {sv_rel_live[k]:.1e}; only a combination of them is fixed): their intervals "
                            "are not given")
        # covariance of the determined part, in x units: pseudo-inverse without the null space
        keep = sv_rel_live >= RANK_TOL
        Sk = S[keep]
        Vk = Vt[keep]
        cov_n = (Vk.T / Sk**2) @ Vk            # in unit-norm-column variables
        scale = (norms[live] / problem.span[live])  # J_x column norms
        cov_live = cov_n / np.outer(scale, scale)
        cov[np.ix_(idx_live, idx_live)] = cov_live
    if spec.covariance == "scaled":
        factor = chi2 / dof if dof > 0 else np.nan
        cov = cov * factor
        q = stats.t.ppf(0.5 + spec.confidence / 2, dof) if dof > 0 else np.inf
    else:
        q = stats.norm.ppf(0.5 + spec.confidence / 2)
    var = np.diag(cov).copy()
    stderr = np.where(undetermined | ~np.isfinite(var), np.inf, np.sqrt(np.abs(var)))
    interval = np.column_stack([xb - q * stderr, xb + q * stderr])
    interval[~np.isfinite(stderr)] = np.nan
    with np.errstate(invalid="ignore", divide="ignore"):
        sd = np.sqrt(np.abs(np.diag(cov)))
        corr = cov / np.outer(sd, sd)
    corr[undetermined, :] = np.nan
    corr[:, undetermined] = np.nan
    for j in range(n):
        if not undetermined[j]:
            corr[j, j] = 1.0

    for i in range(n):  # pairs the evidence fixes only together ([fit] correlation_warning)
        for j in range(i + 1, n):
            rho = corr[i, j]
            if np.isfinite(rho) and abs(rho) >= spec.correlation_warning:
                _log.warning("fit: %s and %s are correlated at %.4f (correlation_warning %g)", spec.unknowns[i].name,
                             spec.unknowns[j].name, rho, spec.correlation_warning)
                warnings.append(f"{spec.unknowns[i].name} and {spec.unknowns[j].name} are correlated at {rho:.4f} "
                                f"(|r| >= correlation_warning = {spec.correlation_warning:g}): the evidence fixes only a "
                                "combination of them, and each one's interval rests on the other's bounds")
    for j, u in enumerate(spec.unknowns):
        if undetermined[j]:
            continue
        a = outcomes[best_k]["active"][j] if outcomes[best_k]["active"] else 0
        at_lo, at_hi = zb[j] <= 1e-4 or a == -1, zb[j] >= 1 - 1e-4 or a == 1
        if at_lo or at_hi:
            warnings.append(f"{u.name} ended at its {'lower' if at_lo else 'upper'} bound: the evidence pulls it "
                            "beyond the bounds; its interval is not valid (widen the bounds or check the evidence)")
        elif 2 * q * stderr[j] > u.span:
            warnings.append(f"{u.name} is poorly determined: its {100 * spec.confidence:g} % interval is wider than "
                            "its bounds")
        elif interval[j, 0] < u.lower or interval[j, 1] > u.upper:
            warnings.append(f"the interval of {u.name} reaches past its bounds (linearised; the bounds are not "
                            "part of it)")
    p_value = float(stats.chi2.sf(chi2, dof)) if dof > 0 else float("nan")
    if dof > 0 and p_value < 0.01:
        warnings.append(f"chi^2 = {chi2:.3g} is improbably large for {dof} degrees of freedom (p = {p_value:.1g}): "
                        "the sigmas are too small or the model misses something; the intervals are too narrow"
                        + (" (consider fit.covariance = \"scaled\")" if spec.covariance == "absolute" else ""))
    if dof <= 0:
        warnings.append(f"{problem.evidence.n_measurements:g} measurements for {n} unknowns: no degrees of freedom "
                        "left to check the fit (chi^2 should be ~0)")
    reasons = _merge_reasons([problem.failure_reasons] + [o.get("failure_reasons", {}) for o in outcomes])
    if reasons:
        listed = "; ".join(f"{k}: {v}" for k, v in sorted(reasons.items(), key=lambda kv: -kv[1]))
        warnings.append(f"{sum(reasons.values())} scene evaluation(s) failed and were penalised ({listed}); the fit "
                        "stayed where the scene can be evaluated")
    if scene.warnings:
        warnings += [f"at the best fit: {w_}" for w_ in scene.warnings]
    linearity, skipped = _linearity(problem, zb, r, Jz, cov, undetermined, warnings)

    starts, n_agree, n_same = _compare_starts(problem, outcomes, best_k, zb, stderr, undetermined, warnings)

    residuals = _residual_items(problem, scene)
    return FitResult(
        unknowns=spec.unknowns, x=xb, stderr=stderr, interval=interval, covariance=cov, correlation=corr,
        residuals=residuals, chi2=chi2, dof=dof, p_value=p_value, confidence=spec.confidence,
        covariance_mode=spec.covariance, singular_values=sv_rel, null_space=null_space, starts=tuple(starts),
        n_agree=n_agree, n_same_cost=n_same, warnings=tuple(warnings), evaluations=0, failures=0, elapsed=0.0,
        engine=engine, success=bool(success), message=message, scene=scene, failure_reasons=reasons,
        linearity=linearity, linearity_skipped=skipped)


def _linearity(problem: FitProblem, zb, rb, Jz, cov, undetermined, warnings: list[str]) -> tuple:
    """The linearity check (:data:`LINEARITY_FACTOR`): chi^2 at one standard error either side of the
    best point ``zb`` along each principal axis of the determined unknowns' covariance ``cov`` [SI],
    shortened at a bound, against the rise ``|rb + Jz dz|^2 - |rb|^2`` that the weighted residuals
    ``rb`` and Jacobian ``Jz`` predict there (``|Jz dz|^2`` at an interior minimum, where
    ``Jz^T rb = 0``); a warning appended if any is off by more than the factor. A direction in which
    a bound leaves less than :data:`LINEARITY_MIN_STEP` of the step is not probed (the bound's own
    warning says the interval is not valid there). Returns the LinearityProbe tuple and the number of such
    directions."""
    chi2 = float(rb @ rb)
    idx = np.nonzero(~undetermined)[0]
    if not idx.size or not np.all(np.isfinite(cov[np.ix_(idx, idx)])):
        return (), 0
    vals, vecs = np.linalg.eigh(cov[np.ix_(idx, idx)])
    paths = [problem.spec.unknowns[j].path for j in idx]
    xb = problem.x_of(zb)
    probes, skipped = [], 0
    for k in np.argsort(vals)[::-1]:
        if not vals[k] > 0.0:
            continue
        for sign in (1.0, -1.0):
            dz = np.zeros_like(zb)
            dz[idx] = sign * math.sqrt(vals[k]) * vecs[:, k] / problem.span[idx]
            room = np.where(dz > 0, 1.0 - zb, zb)  # to the bound each unknown moves toward
            moving = dz != 0
            scale = min(1.0, float(np.min(room[moving] / np.abs(dz[moving]))))  # shortened at a bound
            if scale < LINEARITY_MIN_STEP:
                skipped += 1
                continue
            z = zb + dz * scale
            r, sc = problem.evaluate(z)
            step = problem.x_of(z) - xb
            lin = rb + Jz @ (z - zb)
            probes.append(LinearityProbe({p: float(step[j]) for p, j in zip(paths, idx)}, float(lin @ lin) - chi2,
                                         None if isinstance(sc, Exception) else float(r @ r) - chi2))
    off = [p for p in probes if not p.linear]
    if off:
        worst = max(off, key=lambda p: abs(math.log(p.ratio)) if p.actual is not None and p.ratio > 0 else math.inf)
        if worst.actual is None:
            how = "the scene cannot be evaluated there: the intervals reach where it fails"
        else:
            how = (f"chi^2 rises by {worst.actual:.3g} where the linearised model gives {worst.predicted:.3g}: the "
                   + ("intervals are too narrow there (the evidence changes less than the Jacobian says)"
                      if worst.actual < worst.predicted else "intervals are too wide there"))
        warnings.append(f"the model is not linear over the intervals (linearised): at one standard error from the best "
                        f"fit ({len(off)} of {len(probes)} points) {how}; crashsim posterior gives intervals that do "
                        "not rest on the linearisation")
    return tuple(probes), skipped


#: A start whose chi^2 ends within this of the best's is at the best's cost (``_compare_starts``):
#: a twentieth of the rise of chi^2 at one standard error (1), far below any difference an interval
#: shows; a solver that stopped that close reports no "other minimum".
SAME_CHI2 = 0.05


def _compare_starts(problem: FitProblem, outcomes: list[dict], best_k: int, zb, stderr, undetermined,
                    warnings: list[str]):
    """Each start against the best: the same cost, and the same point (within a quarter standard error or
    1e-3 of the range); warnings appended for starts stuck where the scene cannot be evaluated, other
    minima and a flat minimum. Returns ``(starts, n_agree, n_same)``."""
    costs = np.array([o["cost"] for o in outcomes])
    # the same cost: within 1e-3 of it, or a chi^2 within SAME_CHI2 of the best (a start that stopped
    # that close is at the best minimum as far as any interval can tell: 1 is one standard error)
    tol_cost = max(1e-3 * max(1.0, float(costs[best_k])), 0.5 * SAME_CHI2)
    se_z = np.where(np.isfinite(stderr), stderr / problem.span, np.inf)
    tol_z = np.maximum(1e-3, 0.25 * np.where(np.isfinite(se_z), se_z, 0.0))
    starts = []
    for o in outcomes:
        z = np.asarray(o["z"])
        same_cost = bool(o["cost"] - costs[best_k] <= tol_cost)
        det = ~undetermined
        agrees = same_cost and bool(np.all(np.abs(z - zb)[det] <= tol_z[det]))
        starts.append(StartResult(tuple(problem.x_of(o["z0"]).tolist()), tuple(problem.x_of(z).tolist()),
                                  o["cost"], o["evaluations"], o["status"], o["message"], same_cost, agrees))
    n_agree = sum(s.agrees for s in starts)
    n_same = sum(s.same_cost for s in starts)
    if n_agree < len(starts):
        # a start at which every residual carries the failure penalty never left a region where the
        # scene cannot be evaluated: not a minimum
        stuck = 0.99 * problem.evidence.size * PENALTY**2
        n_stuck = sum(2 * s.cost >= stuck for s in starts if not s.same_cost)
        if n_stuck:
            warnings.append(f"{n_stuck} of {len(starts)} starts began where the scene cannot be evaluated and stayed "
                            "there (their chi^2 is the failure penalty; the failed evaluations say why); the best "
                            "was kept")
        others = sorted({round(2 * s.cost, 3) for s in starts if not s.same_cost and 2 * s.cost < stuck})
        if others:
            warnings.append(f"{len(starts) - n_same} of {len(starts)} starts ended in other minima (chi^2 "
                            f"{', '.join(f'{c:g}' for c in others[:5])}); the best was kept")
        if n_same > n_agree:
            warnings.append(f"{n_same - n_agree} start(s) reached the best cost at a different point: the minimum "
                            "is flat or not unique")
    return starts, n_agree, n_same


def _residual_items(problem: FitProblem, scene) -> tuple[EvidenceResidual, ...]:
    raw, det = problem.evidence.raw_residuals(scene)
    out = []
    for it, v, d, c in zip(problem.evidence.items, raw, det, problem.evidence.checks(scene)):
        v = np.asarray(v, float)
        if it.kind == "mark":
            rms = float(np.sqrt(np.mean(v * v)))
            normalized = rms / it.sigma
            chi2 = normalized**2
        else:
            z = v / it.sigma
            chi2 = float(z @ z)
            normalized = float(z[0]) if z.size == 1 else float(np.sqrt(chi2 / z.size))
        out.append(EvidenceResidual(it.kind, it.name, it.quantity, tuple(float(a) for a in v), it.sigma,
                                    it.sigma_source, normalized, chi2, None if c is None else c.tolerance,
                                    None if c is None else bool(c.passed), d))
    return tuple(out)

"""One run-out for the whole scene, on either engine: integration, secondary impacts, results.

How a run proceeds (both engines)
---------------------------------
The time axis is cut into **segments** in which every input is constant: the wheel-setting
phase (cut at the scheduled change times of every vehicle), the friction zone each wheel is
in, the closed articulation stops, the contact state of every pair and which vehicles are
parked.  A segment ends at the first event (:mod:`crashsim.motion.kernels`: a vehicle's rest,
a zone crossing, an articulation stop or its release, a touch, the arming or pressing of a
pair), located on the integrator's dense output, or at a scheduled change.  What happens at an
event is the kernels' :func:`~crashsim.motion.kernels.handle_event` and
:func:`~crashsim.motion.kernels.settle`, the same code for both engines.

A touch at speed stops the integration: the impact of every point touching at that instant is
solved at once (:func:`crashsim.motion.impacts.impact_instant`), the velocities jump, the pairs
enter sustained contact, and the integration goes on.  A vehicle whose bodies are all below ``v_stop`` is parked (frozen) until
a contact or an impact moves it again; the run ends when every vehicle is parked.

The engines differ only in the integrator of a segment: SciPy's ``LSODA`` (or another
solve_ivp method) stepped from Python (``engine="scipy"``), or the compiled explicit
Runge-Kutta loop of :func:`crashsim.motion.kernels.run` (``engine="compiled"``), which
returns to Python only for an impact.

Why two segment loops and not one
---------------------------------
The loop around a segment (start it, find the first event on the dense output, handle it,
settle, go on) exists twice: in Python here (:class:`_ScipyIntegrator`) and compiled in
:mod:`crashsim.motion.kernels.integrator`.  Everything that decides the physics inside it is one
source: the event functions and their values, the event handling, settle, the strike scan and
the segment bounds are the kernels' and both loops call them.  What stays twice is the stepping
and the root search: SciPy's steppers (LSODA's switching between stiff and non-stiff methods
among them) are Python objects that a compiled loop cannot call without a round trip to Python
at every step, which is what the compiled engine exists to avoid; and SciPy's dense output is
its own interpolant, on which the events are located with ``brentq`` where the compiled loop
uses its own Hermite interpolant and Brent's method (:func:`~crashsim.motion.kernels.first_root`,
the same rule).  A shared loop would either give up SciPy's methods or put Python back into the
compiled engine's step.
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass, field
from typing import Mapping, NamedTuple

import numpy as np
from numba.core import event as numba_event
from scipy.integrate import BDF, DOP853, LSODA, RK45, Radau
from scipy.optimize import brentq

from ..errors import ScenarioError, SolverError
from ..vehicles import BodyState
from .compiled_solution import CompiledSolution
from .impacts import impact_instant
from .scene_model import SceneModel, kernels
from .options import MAX_STILL_SEGMENTS
from .postprocess import GL_NODES, GL_WEIGHTS, assemble_scene, mode_snapshot, segment_arrays, split_track
from .result import BodyHistory, BodyRunout, HitchHistory, RunoutEvent, RunoutResult, limit_message
from .scene_result import PairSummary, SceneRunout, SecondaryImpact

__all__ = ["STATUS_OF_CODE"]

_log = logging.getLogger("crashsim")

# The wall clock is read every this many right-hand-side evaluations (SciPy engine).
_WALL_CHECK_EVALUATIONS = 256
# Initial pin gap [m] and pin velocity mismatch (relative to 1 + speed) [m/s] accepted.
_PIN_GAP_TOL = 1e-3
_PIN_VELOCITY_TOL = 1e-6
#: Largest initial articulation [rad] at a yaw-locked hitch (C-dolly): the pins' own tolerance over a metre.
_YAW_LOCK_TOL = 1e-3
#: Absolute tolerance of the contact work integrated with the state (SciPy engine), relative to
#: the kinetic energy at the start of the run: the ledger is to close to 1e-6 of it.
_WORK_ATOL = 1e-9


def _status_names():
    k = kernels()
    return {k.ST_REST: "rest", k.ST_TIME_LIMIT: "time_limit", k.ST_MAX_SEGMENTS: "event_limit",
            k.ST_STEP_TOO_SMALL: "solver_failure", k.ST_NONFINITE: "solver_failure", k.ST_MAX_EVAL: "evaluation_limit",
            k.ST_WALL_TIME: "wall_time_limit", k.ST_NO_PROGRESS: "event_limit"}


STATUS_OF_CODE = None  # filled on first use (importing the kernels compiles nothing, but imports numba)


class _Budget(Exception):
    def __init__(self, code: int):
        self.code = code


# ============================================================================= integrators
class _Integrator:
    """What both integrators keep: the model, the implicit solvers' work counters, a failure message."""

    def __init__(self, model: SceneModel):
        self.model = model
        self.njev = 0
        self.nlu = 0
        self.message = ""

    def segment_data(self, mode):
        """``(bounds, arrays)``: ``(t0, t1, _)`` of every segment, and their stacked mode arrays
        (:func:`~crashsim.motion.postprocess.segment_arrays`; with no segment, those of ``mode``, the run's mode at its end)."""
        table = self.segment_table()
        return table, segment_arrays(table if table else [(0.0, 0.0, mode_snapshot(0, mode))], self.model)


class _ScipyIntegrator(_Integrator):
    """Segments integrated by SciPy's ODE solvers, stepped from Python (one step at a time)."""

    def __init__(self, model: SceneModel):
        super().__init__(model)
        self.solver_cls = {"LSODA": LSODA, "RK45": RK45, "DOP853": DOP853, "Radau": Radau, "BDF": BDF}[model.options.method]
        self.segments: list[dict] = []
        self.energy_scale = None  # the kinetic energy at the start of the run [J]: the work's tolerance scale

    def integrate(self, t, y, D, offsets, clock, counters, quad, log):
        k = kernels()
        model = self.model
        M = model.M
        o = model.options
        stops = model.segment_stops
        max_eval = int(o.max_evaluations)
        while True:
            if bool(np.all(D.parked != 0)):
                return k.ST_REST, t, y, None
            if counters[0] >= o.max_segments:
                return k.ST_MAX_SEGMENTS, t, y, None
            if counters[1] >= MAX_STILL_SEGMENTS:
                return k.ST_NO_PROGRESS, t, y, None
            counters[0] += 1
            t_stop = next(s for s in stops if s > t)
            phase = int(k.phase_at(t, M.phase_times))
            ev_kind, ev_idx, ev_val, ev_dir = k.segment_events(M, D, offsets)
            g_old, r_old = k.event_values(y, M, phase, D, ev_kind, ev_idx, ev_val)
            resolution = k.event_resolutions(M, ev_kind, ev_idx)
            snapshot = mode_snapshot(phase, D)
            # pairs in contact: their work is integrated with the state (module rhs_work)
            n = y.size
            n_work = len(model.pairs) if bool(np.any(D.pstate == k.PS_CONTACT)) else 0
            if self.energy_scale is None:
                self.energy_scale = max(model.kinetic_energy(y), 1.0)

            def fun(tt, yy, phase=phase):
                n_cols = 1 if yy.ndim == 1 else yy.shape[1]
                counters[2] += n_cols
                if counters[2] >= max_eval:
                    raise _Budget(k.ST_MAX_EVAL)
                crossed = counters[2] // _WALL_CHECK_EVALUATIONS != (counters[2] - n_cols) // _WALL_CHECK_EVALUATIONS
                if (crossed or counters[2] <= n_cols) and clock.passed():
                    raise _Budget(k.ST_WALL_TIME)
                if n_work:
                    out = k.rhs_work(yy, M, phase, D, n) if yy.ndim == 1 else np.stack(
                        [k.rhs_work(np.ascontiguousarray(c), M, phase, D, n) for c in yy.T], axis=1)
                else:
                    out = k.rhs(yy, M, phase, D) if yy.ndim == 1 else k.rhs_many(np.ascontiguousarray(yy), M, phase, D)
                if not np.all(np.isfinite(out)):
                    raise _Budget(k.ST_NONFINITE)
                return out

            first = None if o.first_step is None else min(o.first_step, t_stop - t)
            t_seg0 = t
            steps = []
            fired = -1
            failure = None
            y0, atol = y, o.atol
            if n_work:
                y0 = np.concatenate([y, np.zeros(n_work)])
                atol = np.concatenate([np.full(n, o.atol), np.full(n_work, _WORK_ATOL * self.energy_scale)])
            work = np.zeros(n_work)
            try:
                solver = self.solver_cls(fun, t, y0, t_stop, rtol=o.rtol, atol=atol, max_step=o.max_step,
                                         first_step=first, vectorized=o.method in ("Radau", "BDF"))
                while solver.status == "running":
                    message = solver.step()
                    if solver.status == "failed":
                        failure = (k.ST_STEP_TOO_SMALL, message)
                        break
                    t_old, t_new = solver.t_old, solver.t
                    full = solver.dense_output()
                    dense = full if not n_work else (lambda tq, full=full: np.asarray(full(tq))[:n])
                    g_new, r_new = k.event_values(solver.y[:n], M, phase, D, ev_kind, ev_idx, ev_val)
                    root, e = _first_root(k, M, phase, D, t_old, t_new, dense, g_old, g_new, r_old, r_new,
                                          ev_kind, ev_idx, ev_val, ev_dir, resolution)
                    if e >= 0:
                        steps.append((t_old, root, dense))
                        t = root
                        y_full = np.array(full(root), dtype=float)
                        y, work = y_full[:n].copy(), y_full[n:]
                        fired = e
                        break
                    steps.append((t_old, t_new, dense))
                    t = t_new
                    y, work = np.array(solver.y[:n], dtype=float), np.array(solver.y[n:], dtype=float)
                    g_old, r_old = g_new, r_new
                self.njev += int(getattr(solver, "njev", 0) or 0)
                self.nlu += int(getattr(solver, "nlu", 0) or 0)
            except _Budget as b:
                failure = (b.code, "")
            if t > t_seg0:
                seg = dict(t0=t_seg0, t1=t, steps=steps, mode=snapshot)
                self.segments.append(seg)
                _add_quadrature(k, M, seg, quad, work if n_work else None)
                counters[1] = 0
            else:
                counters[1] += 1
            if failure is not None:
                self.message = failure[1]
                return failure[0], t, y, None
            if fired >= 0:
                impact, recs, geo = k.apply_event(fired, t, y, M, phase, D, offsets, ev_kind, ev_idx, ev_val, ev_dir)
                _log_records(model, t, recs, log)
                if impact:
                    return k.ST_IMPACT, t, y, geo
                continue
            if t >= o.t_max:
                return k.ST_TIME_LIMIT, t, y, None
            _log_records(model, t, k.schedule_change(y, M, D), log)

    # ------------------------------------------------------------------ results
    def segment_table(self):
        return [(s["t0"], s["t1"], s["mode"]) for s in self.segments]

    def sample(self, T, seg_of, y_end):
        Y = np.empty((y_end.size, T.size))
        if not self.segments:  # at rest from the start
            Y[:] = y_end[:, None]
            return Y
        for g in np.unique(seg_of):
            mask = seg_of == g
            Y[:, mask] = _segment_dense(self.segments[g])(T[mask])
        if T.size:
            Y[:, -1] = y_end
        return Y

    def step_edges(self) -> np.ndarray:
        """Start and end times of every step taken (sorted)."""
        return np.unique([t for s in self.segments for a, b, _ in s["steps"] for t in (a, b)])

    def solution(self, y_end, t_end):
        return _PiecewiseSolution([(s["t0"], _segment_dense(s)) for s in self.segments], y_end, t_end)

    @property
    def method(self):
        return f"scipy/{self.model.options.method}"


class WallClock(numba_event.Listener):
    """The wall-clock budget of a run (``RunoutOptions.max_wall_time``), without the time numba spends
    compiling the kernels on a first call: a listener of numba's ``"numba:compile"`` events (installed
    once around a run's integrations and later impacts) adds it back, so a first run on a busy machine
    is not stopped for the compiler's time."""

    def __init__(self, budget: float):
        self.start = time.perf_counter()
        self.budget = float(budget)
        self.compiling = 0.0
        self._depth = 0
        self._t0 = 0.0

    def on_start(self, event) -> None:
        if self._depth == 0:
            self._t0 = time.perf_counter()
        self._depth += 1

    def on_end(self, event) -> None:
        self._depth -= 1
        if self._depth == 0:
            self.compiling += time.perf_counter() - self._t0

    def remaining(self) -> float:
        """Seconds of the budget left [s] (negative when it is used up)."""
        return self.start + self.budget + self.compiling - time.perf_counter()

    def passed(self) -> bool:
        return self.remaining() < 0.0


class _Steps(NamedTuple):
    """The steps and segments of compiled runs: the fields of the same names of
    :class:`crashsim.motion.kernels.RunOutput` (several calls joined by :meth:`_CompiledIntegrator._joined`)."""

    st_t: np.ndarray
    st_h: np.ndarray
    st_y: np.ndarray
    st_q: np.ndarray
    sg_t: np.ndarray
    sg_s: np.ndarray
    sg_phase: np.ndarray
    sg_memb: np.ndarray
    sg_nlk: np.ndarray
    sg_lkj: np.ndarray
    sg_lkth: np.ndarray
    sg_pstate: np.ndarray
    sg_pref: np.ndarray
    sg_parked: np.ndarray


class _CompiledIntegrator(_Integrator):
    """Segments integrated by the compiled loop (:func:`crashsim.motion.kernels.run`)."""

    def __init__(self, model: SceneModel):
        super().__init__(model)
        self.parts: list[_Steps] = []

    def integrate(self, t, y, D, offsets, clock, counters, quad, log):
        k = kernels()
        model = self.model
        stops = np.array(model.segment_stops, dtype=float)
        out = k.run(float(t), np.ascontiguousarray(y, dtype=float), model.M, D, offsets, stops, GL_NODES, GL_WEIGHTS,
                    clock.remaining(), counters, quad)
        status, t_end, y_end = int(out.status), float(out.t_end), np.array(out.y_end)
        self.parts.append(_Steps(**{f: getattr(out, f) for f in _Steps._fields}))
        for tt, row in zip(out.lg_t.tolist(), out.lg_rec):
            _log_records(model, tt, row[None, :], log)
        return status, t_end, y_end, out.geo if status == k.ST_IMPACT else None

    def _joined(self):
        """The steps and segments of every kernel call so far, one :class:`_Steps` (None before the
        first call); the segments' step indices count from the first call's first step."""
        if getattr(self, "_cache", None) is not None and self._cache[0] == len(self.parts):
            return self._cache[1]
        if not self.parts:
            joined = None
        elif len(self.parts) == 1:  # one run of the kernel (no later impact): its arrays as they are
            joined = self.parts[0]
        else:
            offs = np.cumsum([0] + [len(p.st_t) for p in self.parts[:-1]])
            joined = _Steps(**{f: np.concatenate([getattr(p, f) for p in self.parts]) for f in _Steps._fields
                               if f != "sg_s"},
                            sg_s=np.concatenate([p.sg_s + off for p, off in zip(self.parts, offs)]))
        self._cache = (len(self.parts), joined)
        return joined

    def segment_table(self):
        j = self._joined()
        if j is None:
            return []
        return [(float(j.sg_t[i, 0]), float(j.sg_t[i, 1]),
                 (int(j.sg_phase[i]), j.sg_memb[i], int(j.sg_nlk[i]), j.sg_lkj[i], j.sg_lkth[i], j.sg_pstate[i],
                  j.sg_pref[i], j.sg_parked[i]))
                for i in range(len(j.sg_t))]

    def segment_data(self, mode):
        """As :meth:`_Integrator.segment_data`, from the joined segment arrays (the same arrays as
        stacking :meth:`segment_table`'s modes, without the per-segment tuples)."""
        j = self._joined()
        if j is None or not len(j.sg_t):  # no segment (at rest from the start): the mode's arrays
            return super().segment_data(mode)
        bounds = list(zip(j.sg_t[:, 0].tolist(), j.sg_t[:, 1].tolist(), [None] * len(j.sg_t)))
        i64 = np.int64
        return bounds, kernels().Segments(j.sg_phase.astype(i64), j.sg_memb.copy(), j.sg_nlk.astype(i64),
                                          j.sg_lkj.copy(), j.sg_lkth.copy(), j.sg_pstate.astype(i64),
                                          j.sg_pref.copy(), j.sg_parked.astype(i64))

    def sample(self, T, seg_of, y_end):
        j = self._joined()
        if j is None or not len(T):
            return np.repeat(y_end[:, None], len(T), axis=1)
        return kernels().interpolate_samples(T, seg_of, j.sg_s, j.st_t, j.st_h, j.st_y, j.st_q, y_end, len(T))

    def step_edges(self) -> np.ndarray:
        """Start and end times of every step taken (sorted)."""
        j = self._joined()
        return np.zeros(0) if j is None else np.unique(np.concatenate([j.st_t, j.st_t + j.st_h]))

    def solution(self, y_end, t_end):
        j = self._joined()
        if j is None:
            n = y_end.size
            return CompiledSolution(np.zeros(0), np.zeros(0), np.zeros((0, n)), np.zeros((0, n, 1)), y_end, t_end)
        return CompiledSolution(j.st_t, j.st_h, j.st_y, j.st_q, y_end, t_end)

    @property
    def method(self):
        return f"compiled/{self.model.options.scheme}"


def _segment_dense(seg):
    """Dense output of one SciPy segment: ``f(t)`` -> states (n, len(t))."""
    starts = np.array([a for a, _, _ in seg["steps"]])
    denses = [d for _, _, d in seg["steps"]]

    def f(tq):
        tq = np.atleast_1d(np.asarray(tq, dtype=float))
        idx = np.clip(np.searchsorted(starts, tq, side="right") - 1, 0, len(denses) - 1)
        out = np.empty((len(denses[0](starts[0])), tq.size))
        for i in np.unique(idx):
            mask = idx == i
            out[:, mask] = np.asarray(denses[i](tq[mask])).reshape(out.shape[0], -1)
        return out

    return f


class _PiecewiseSolution:
    """Dense solution over all segments: ``sol(t)`` -> state(s), clipped to ``[0, t_end]``.

    At a segment boundary the later segment is used (the state after a stop impact or a
    secondary impact).
    """

    def __init__(self, pieces, y_end: np.ndarray, t_end: float):
        self._starts = np.array([p[0] for p in pieces]) if pieces else np.zeros(0)
        self._sols = [p[1] for p in pieces]
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
                out[:, mask] = self._sols[i](flat[mask])
            out[:, flat >= self._t_end] = self._y_end[:, None]
        return out[:, 0] if t_arr.ndim == 0 else out.reshape((self._y_end.size,) + t_arr.shape)


def _first_root(k, M, phase, D, t, t_new, dense, g_old, g_new, r_old, r_new, ev_kind, ev_idx, ev_val, ev_dir,
                resolution):
    """The SciPy engine's :func:`crashsim.motion.kernels.first_root`: the same rule, SciPy's brentq."""
    h = t_new - t
    t_first, fired = math.inf, -1
    eps4 = 4 * np.finfo(float).eps
    for e in range(len(ev_kind)):
        a, b, d = g_old[e], g_new[e], ev_dir[e]
        reach = max(r_old[e], r_new[e]) * 1.5 * h
        n_sub = 1
        if reach > 0.0 and min(abs(a), abs(b)) < reach:
            n_sub = min(k.MAX_SUBSAMPLES, max(1, math.ceil(reach / max(resolution[e], 1e-9))))

        def g(tq, e=e):
            return k.event_value_at(e, np.asarray(dense(tq), dtype=float), M, phase, D, ev_kind, ev_idx, ev_val)

        ta, fa = t, a
        for j in range(1, n_sub + 1):
            last = j == n_sub
            if last:
                tb, fb = t_new, b
            else:
                tb = t + (t_new - t) * j / n_sub
                if tb >= t_first:  # an earlier event fires at t_first: search up to it, not past it
                    tb, last = t_first, True
                fb = g(tb)
            if (d > 0 and fa <= 0.0 <= fb) or (d < 0 and fa >= 0.0 >= fb):
                root = tb
                if fa == 0.0:
                    root = ta
                elif fb != 0.0 and (fa < 0) != (fb < 0):
                    # brentq evaluates the ends again on the dense output, which can differ from the
                    # step's own end values in the last bits: root-find only on a true sign change
                    ga, gb = g(ta), g(tb)
                    if ga == 0.0:
                        root = ta
                    elif gb != 0.0 and (ga < 0) != (gb < 0):
                        root = brentq(g, ta, tb, xtol=eps4, rtol=eps4)
                        # the crossed side of the root, as the kernels' brent returns it: the handler sees
                        # the state past a jump of the value. Where the root found lies before the jump
                        # (a value that flickers as a point arrives), bisection on [root, tb] to the
                        # tolerance: a crossed time within it of one not crossed, not the step's end

                        def crossed(v):
                            return v == 0.0 or (v < 0) == (gb < 0)

                        if not crossed(g(root)):
                            lo, hi = root, tb
                            while hi - lo > 2 * eps4 * (1 + abs(hi)):
                                mid = 0.5 * (lo + hi)
                                if crossed(g(mid)):
                                    hi = mid
                                else:
                                    lo = mid
                            root = hi
                if root < t_first:
                    t_first, fired = root, e
                break
            if last:
                break
            ta, fa = tb, fb
    return t_first, fired


def _add_quadrature(k, M, seg, quad, work=None):
    """Path integrals of a SciPy segment: 5-point Gauss-Legendre on each of its steps' dense output.

    ``work``: the contact work of every pair over the segment, integrated with the state
    (pairs in contact); it replaces the quadrature of the contact powers, which would book the
    forces of depths the dense output interpolates between the solver's own evaluations.
    """
    nodes, weights, owner = [], [], []
    for a, b, dense in seg["steps"]:
        half = 0.5 * (b - a)
        if half <= 0:
            continue
        tq = 0.5 * (a + b) + half * GL_NODES
        nodes.append(np.asarray(dense(tq)).reshape(-1, tq.size))
        weights.append(half * GL_WEIGHTS)
    if not nodes:
        if work is not None:
            quad[quad.size - work.size:] += work
        return
    Yq = np.ascontiguousarray(np.concatenate(nodes, axis=1))
    wq = np.concatenate(weights)
    arrays = segment_arrays([(seg["t0"], seg["t1"], seg["mode"])], None)
    part = k.quad_sums(Yq, wq, np.zeros(wq.size, dtype=np.int64), M, arrays)
    if work is not None:
        part[part.size - work.size:] = work
    quad += part


# ============================================================================= events and their words
def _log_records(model: SceneModel, t: float, recs, log: list) -> None:
    """Run-out events (:class:`RunoutEvent`) from the kernels' log records (rows: kind, i, j, x, energy)."""
    if not len(recs):  # most calls: nothing happened
        return
    k = kernels()
    for row in np.atleast_2d(recs):
        kind, i, j, x, e = int(row[0]), int(row[1]), int(row[2]), float(row[3]), float(row[4])
        if kind in (k.LOG_ZONE_ENTER, k.LOG_ZONE_EXIT):
            spec = model.specs[i]
            word = "enter" if kind == k.LOG_ZONE_ENTER else "exit"
            zone = model.road.zones[j]
            veh = model.vehicle_of_body(spec.body_index).name
            log.append(RunoutEvent(t, f"zone_{word}", f"wheel {spec.label} {word}s zone {j} {zone.name!r}", 0.0,
                                   (veh,), {"wheel": spec.key, "label": spec.label, "zone": zone.name, "zone_index": j,
                                            "friction": zone.mu}))
        elif kind == k.LOG_SCHEDULE:
            changing = tuple(v.name for v in model.vehicles if any(abs(tc - t) < 1e-12
                                                                  for tc in model.resolved[v.name].change_times))
            if not changing:  # a kink of the air brakes' ramps: a segment boundary, no change of settings
                continue
            changes = _wheel_changes(model, changing, t)
            labels = {w.key: w.label for w in model.specs}  # the axles' names from the file
            what = "; ".join(f"{labels.get(key, key)}: {a} -> {b}" for key, a, b in changes)
            log.append(RunoutEvent(t, "schedule", "wheel settings change" + (f" ({what})" if what else ""),
                                   0.0, changing, {"changes": [list(c) for c in changes]}))
        elif kind in (k.LOG_STOP_CLOSED, k.LOG_STOP_IMPACT, k.LOG_STOP_OPEN):
            front, rear = model.hitch_names[i]
            veh = model.vehicle_of_body(model.layout.bodies.index(front)).name
            if kind == k.LOG_STOP_OPEN:
                log.append(RunoutEvent(t, "stop_open", f"articulation stop of hitch {front}-{rear} opens", 0.0, (veh,),
                                       {"hitch": f"{front}-{rear}"}))
            else:
                how = "closes" if kind == k.LOG_STOP_CLOSED else "struck and left"
                log.append(RunoutEvent(t, "stop_closed" if kind == k.LOG_STOP_CLOSED else "stop_impact",
                                       f"articulation stop of hitch {front}-{rear} {how} at {math.degrees(x):+.1f} deg "
                                       f"(impact dissipates {e:.1f} J)", e, (veh,),
                                       {"hitch": f"{front}-{rear}", "angle_rad": x}))
        elif kind == k.LOG_REST:
            v = model.vehicles[i]
            log.append(RunoutEvent(t, "vehicle_rest", f"vehicle {v.name} at rest (all bodies below v_stop = "
                                                      f"{model.options.v_stop} m/s)", 0.0, (v.name,),
                                   {"vehicle": v.name, "v_stop_m_s": model.options.v_stop}))
        else:
            pair = model.pairs[i]
            vehs = _pair_vehicles(model, pair)
            if kind == k.LOG_ARMED:
                log.append(RunoutEvent(t, "armed", f"{pair.a} and {pair.b} have separated by "
                                                   f"{pair.contact.arm_distance:g} m: a later touch is an impact",
                                       0.0, vehs, {"pair": pair.name, "bodies": [pair.a, pair.b],
                                                   "arm_distance_m": pair.contact.arm_distance}))
            elif kind == k.LOG_CONTACT:
                log.append(RunoutEvent(t, "contact", f"{pair.a} touches {pair.b} at {abs(x):.3g} m/s (below the "
                                                     f"impulse threshold {pair.contact.velocity_threshold:g} m/s): "
                                                     "sustained contact", 0.0, vehs,
                                       {"pair": pair.name, "speed_m_s": abs(x), "bodies": [pair.a, pair.b],
                                        "threshold_m_s": pair.contact.velocity_threshold}))
            elif kind == k.LOG_PRESS:
                log.append(RunoutEvent(t, "contact_pressed", f"{pair.a} is pressed into {pair.b} beyond the crush of "
                                                             f"the impact ({x:.3g} m deep): sustained contact", 0.0,
                                       vehs, {"pair": pair.name, "depth_m": x, "bodies": [pair.a, pair.b]}))
            elif kind == k.LOG_CONTACT_END:
                log.append(RunoutEvent(t, "contact_end", f"{pair.a} and {pair.b} separate", 0.0, vehs,
                                       {"pair": pair.name, "bodies": [pair.a, pair.b]}))


def _wheel_changes(model: SceneModel, vehicles, t: float) -> list[tuple[str, str, str]]:
    """(wheel, setting before, setting after) of every wheel whose setting changes at ``t``."""
    def word(s):
        return s.state + (f" {100 * s.brake:.0f} %" if s.state == "braked" else "") + \
            (f", steer {math.degrees(s.steer):+.1f} deg" if s.steer else "")

    out = []
    for name in vehicles:
        res = model.resolved[name]
        before, after = res.at(t - 1e-9), res.at(t)
        for spec, a, b in zip(res.specs, before, after):
            if a != b:
                out.append((spec.key, word(a), word(b)))
    return out


def _pair_vehicles(model: SceneModel, pair) -> tuple:
    names = model.layout.bodies
    out = [model.vehicle_of_body(names.index(pair.a)).name]
    if not pair.obstacle:
        out.append(model.vehicle_of_body(names.index(pair.b)).name)
    return tuple(out)


# ============================================================================= the run
def check_scene_hitches(model: SceneModel, y: np.ndarray) -> None:
    """Pins together, pin velocities equal, articulation inside its limit, for every hitch (else ScenarioError)."""
    L = model.layout
    hb = model.M.hitch_body
    hitch = model.M.hitch
    for j in range(model.n_hitches):
        f, r = hb[j]
        front, rear = L.bodies[f], L.bodies[r]
        cf, sf = math.cos(y[L.psi][f]), math.sin(y[L.psi][f])
        cr, sr = math.cos(y[L.psi][r]), math.sin(y[L.psi][r])
        ax, ay = cf * hitch[j, 0] - sf * hitch[j, 1], sf * hitch[j, 0] + cf * hitch[j, 1]
        bx, by = cr * hitch[j, 2] - sr * hitch[j, 3], sr * hitch[j, 2] + cr * hitch[j, 3]
        gap = math.hypot(y[L.x][f] + ax - y[L.x][r] - bx, y[L.y][f] + ay - y[L.y][r] - by)
        if gap > _PIN_GAP_TOL:
            raise ScenarioError(f"pin points of {front!r} and {rear!r} are {gap:.4g} m apart (allowed <= {_PIN_GAP_TOL} m): "
                                "positions are not hitch-consistent", field=f"initial[{rear!r}].position")
        wf, wr = y[L.w][f], y[L.w][r]
        dvx = y[L.vx][f] - wf * ay - y[L.vx][r] + wr * by
        dvy = y[L.vy][f] + wf * ax - y[L.vy][r] - wr * bx
        speed = float(np.max(np.hypot(y[L.vx], y[L.vy])))
        allowed = _PIN_VELOCITY_TOL * (1.0 + speed)
        if math.hypot(dvx, dvy) > allowed:
            raise ScenarioError(
                f"pin velocities of {front!r} and {rear!r} differ by {math.hypot(dvx, dvy):.4g} m/s (allowed <= "
                f"{allowed:.3g} m/s); make the states hitch-consistent first with crashsim.motion.make_hitch_consistent()",
                field=f"initial[{rear!r}].velocity")
        lim = hitch[j, 4]
        if hitch[j, 5] != 0.0:  # yaw-locked (C-dolly): aligned, turning together
            theta = math.remainder(float(y[L.psi][f] - y[L.psi][r]), 2 * math.pi)
            if abs(theta) > _YAW_LOCK_TOL:
                raise ScenarioError(f"initial articulation {math.degrees(theta):.4g} deg at a yaw-locked hitch (C-dolly); "
                                    f"allowed 0 deg (within {_YAW_LOCK_TOL:g} rad)", field=f"initial[{rear!r}].heading")
            if abs(wf - wr) > allowed:
                raise ScenarioError(f"yaw rates of {front!r} and {rear!r}, joined by a yaw-locked hitch (C-dolly), differ "
                                    f"by {abs(wf - wr):.4g} rad/s (allowed <= {allowed:.3g} rad/s); make the states "
                                    "consistent first with crashsim.motion.make_hitch_consistent()",
                                    field=f"initial[{rear!r}].yaw_rate")
        if not math.isnan(lim):
            theta = math.remainder(float(y[L.psi][f] - y[L.psi][r]), 2 * math.pi)
            if abs(theta) > lim + 1e-9:
                raise ScenarioError(f"initial articulation {math.degrees(theta):.2f} deg exceeds the limit "
                                    f"+-{math.degrees(lim):.2f} deg (articulation_limit)",
                                    field=f"initial[{rear!r}].heading")


def run_model(model: SceneModel, initial: Mapping[str, BodyState], *, lean=None) -> SceneRunout:
    """Integrate the scene from separation to rest (or a limit); see the module docstring.

    ``lean``: None for the full result, or a predicate on wheel specs for the lean result of a
    fit or Monte Carlo sample (:func:`crashsim.motion.postprocess.assemble_scene`)."""
    k = kernels()
    o = model.options
    M = model.M
    y = model.pack(initial)
    check_scene_hitches(model, y)
    D = model.fresh_mode()
    k.start(y, M, D, 0.0)
    k.arming(y, M, D)
    y_initial = y.copy()
    offsets = model.offsets(y)
    log: list[RunoutEvent] = []
    _log_records(model, 0.0, k.settle_at(y, M, D), log)
    integrator = _CompiledIntegrator(model) if o.engine == "compiled" else _ScipyIntegrator(model)
    clock = WallClock(o.max_wall_time)
    counters = np.zeros(3, dtype=np.int64)
    npairs = len(model.pairs)
    quad = np.zeros(model.n_bodies + 3 * model.n_wheels + npairs)
    impacts: list[SecondaryImpact] = []
    events_done = 0  # instants solved after the first impact
    t = 0.0
    names = _status_names()
    with numba_event.install_listener("numba:compile", clock):  # once per run: compiling is not counted
        while True:
            code, t, y, geo = integrator.integrate(t, y, D, offsets, clock, counters, quad, log)
            if code != k.ST_IMPACT:
                break
            if events_done >= o.max_impacts:
                status = "event_limit"
                message = (f"stopped at t = {t:.4g} s (simulated) before rest: more than max_impacts = "
                           f"{o.max_impacts} later impacts; the last between {model.pairs[int(geo[0])].name}")
                code = None
                break
            # every point touching at this instant, solved at once (one impact event)
            events_done += 1
            impacts += impact_instant(model, t, y, geo, D, offsets, log, impacts)
            _log_records(model, t, k.settle_at(y, M, D), log)
    if code is not None:
        status = names[code]
        message = _message(code, o, t, y, k, M, log, integrator)
    log.append(RunoutEvent(t, status, message, data={"v_stop_m_s": o.v_stop} if status == "rest" else {}))
    if status != "rest":
        _log.warning("run-out did not reach rest (%s): %s", status, message)

    return assemble_scene(model, integrator, status=status, message=message, t_end=t, y_initial=y_initial, y_end=y,
                          quad=quad, events=log, impacts=impacts, nfev=int(counters[2]), mode=D, lean=lean)


def _message(code, o, t, y, k, M, log, integrator) -> str:
    last = next((e.detail for e in reversed(log) if e.kind not in ("zone_enter", "zone_exit")), None)
    if code == k.ST_REST:
        return f"all bodies below v_stop = {o.v_stop} m/s at t = {t:.4f} s"
    if code == k.ST_TIME_LIMIT:
        return limit_message("time_limit", o, t, float(k.rest_measure(y, M, -1)))
    if code == k.ST_MAX_SEGMENTS:
        return limit_message("event_limit", o, t, last_event=last)
    if code == k.ST_NO_PROGRESS:
        return limit_message("no_progress", o, t, last_event=last)
    if code == k.ST_MAX_EVAL:
        return limit_message("evaluation_limit", o, t)
    if code == k.ST_WALL_TIME:
        return limit_message("wall_time_limit", o, t)
    if code == k.ST_NONFINITE:
        return f"{integrator.method} failed at t = {t:.6g} s: non-finite state derivative"
    extra = f": {integrator.message}" if integrator.message else ": required step size is less than spacing between numbers"
    return f"{integrator.method} failed at t = {t:.6g} s{extra}"

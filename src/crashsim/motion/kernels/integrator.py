"""Kernel stage: the compiled engine's explicit Runge-Kutta integrator and its segment loop.

solve_ivp's RK driver (step, error control, initial step) re-written in numba (a rejected step
across a switch of the tyre law is retried up to the switch: :func:`kink_fraction`), and
:func:`run`, the segment loop cut into its stages (start a segment, take a step, locate
the event, record the segment, handle the event).
"""

from __future__ import annotations

import math
import time
from collections import namedtuple
from typing import NamedTuple

import numpy as np
from numba import njit, objmode

from ..options import MAX_STILL_SEGMENTS
from .jit import HOT, INLINE, JIT, STAGE
from .arrays import (C_ATOL, C_FIRST, C_MAXSTEP, C_RTOL, C_TMAX, I_LT, I_MAXEVAL, I_MAXSEG, I_ORDER, LOG_SCHEDULE,
                     MAX_FACTOR, MIN_FACTOR, N_A, N_S, SAFETY, ST_IMPACT, ST_MAX_EVAL, ST_MAX_SEGMENTS, ST_NONFINITE,
                     ST_NO_PROGRESS, ST_REST, ST_STEP_TOO_SMALL, ST_TIME_LIMIT, ST_WALL_TIME, W_M0, W_M1, W_MLOCK,
                     W_MSAT, WALL_CHECK_STEPS, EventValues, Events, Step, make_work)
from .geometry import membership
from .equations import consistent_accelerations, evaluate, phase_at, quad_integrand, segment_params
from .tyres import tyre_eval
from .events import build_events, event_rate, event_value, first_root, handle_event, interpolate, log_record, settle


@njit(**HOT)
def rms_scaled(a, y0, y1, use_both, rtol, atol):
    n = a.shape[0]
    s = 0.0
    for i in range(n):
        ref = abs(y0[i])
        if use_both:
            ref = max(ref, abs(y1[i]))
        q = a[i] / (atol + ref * rtol)
        s += q * q
    return math.sqrt(s / n)


# evaluate() compiled into rk_step itself (one call site: the stage loop)
_evaluate_inline = njit(**INLINE)(getattr(evaluate, "py_func", evaluate))  # plain function under NUMBA_DISABLE_JIT


@njit(**HOT)
def rk_step(y, h, K, y_new, ytmp, M, sw, D, W, gq):
    """One explicit RK step from ``y`` (``K[0]`` = f(y)); stages in ``K``, FSAL ``K[ns]`` = f(y_new).

    ``gq[s]`` receives the path-integral integrands (:func:`quad_integrand`) at stage ``s``
    (``gq[0]`` must hold those at ``y``): ``h sum_s b_s gq[s]`` is then the RK solution of the
    quadrature ODE ``q' = g(y)``, as accurate as the step itself.

    The scheme is the model's tableau (``M.tab_a``, ``M.tab_b``: solve_ivp's A and B).
    Returns the number of right-hand-side evaluations (``ns``) and whether all were finite.
    """
    tab_a, tab_b = M.tab_a, M.tab_b
    ns = tab_b.shape[0]
    n = y.shape[0]
    finite = True
    for s in range(1, ns + 1):
        coef = tab_a[s] if s < ns else tab_b
        target = ytmp if s < ns else y_new
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += coef[j] * K[j, i]
            target[i] = y[i] + h * acc
        _evaluate_inline(target, M, sw, D, K[s], W)
        quad_integrand(target, M, D, W, gq[s])
    for s in range(1, ns + 1):
        for i in range(n):
            if not math.isfinite(K[s, i]):
                finite = False
    return ns, finite


@njit(**HOT)
def initial_step(t0, y0, f0, t_bound, ytmp, f1, M, sw, D, W):
    """solve_ivp's ``select_initial_step`` (Hairer, Norsett & Wanner, II.4); one RHS evaluation.

    The tolerances, the largest step and the scheme's order are the model's options
    (``C_RTOL``, ``C_ATOL``, ``C_MAXSTEP``, ``I_ORDER``).
    """
    rtol = M.cfg[C_RTOL]
    atol = M.cfg[C_ATOL]
    max_step = M.cfg[C_MAXSTEP]
    order = M.icfg[I_ORDER]
    n = y0.shape[0]
    interval = abs(t_bound - t0)
    if interval == 0.0:
        return 0.0
    d0 = 0.0
    d1 = 0.0
    for i in range(n):
        sc = atol + abs(y0[i]) * rtol
        d0 += (y0[i] / sc) ** 2
        d1 += (f0[i] / sc) ** 2
    d0 = math.sqrt(d0 / n)
    d1 = math.sqrt(d1 / n)
    if d0 < 1e-5 or d1 < 1e-5:
        h0 = 1e-6
    else:
        h0 = 0.01 * d0 / d1
    h0 = min(h0, interval)
    for i in range(n):
        ytmp[i] = y0[i] + h0 * f0[i]
    evaluate(ytmp, M, sw, D, f1, W)
    d2 = 0.0
    for i in range(n):
        sc = atol + abs(y0[i]) * rtol
        d2 += ((f1[i] - f0[i]) / sc) ** 2
    d2 = math.sqrt(d2 / n) / h0
    if d1 <= 1e-15 and d2 <= 1e-15:
        h1 = max(1e-6, h0 * 1e-3)
    else:
        h1 = (0.01 / max(d1, d2)) ** (1.0 / (order + 1))
    return min(100.0 * h0, h1, interval, max_step)


@njit(**JIT)
def grow1(a, n):
    out = np.empty(n, a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(**JIT)
def grow2(a, n):
    out = np.empty((n,) + a.shape[1:], a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(**JIT)
def grow3(a, n):
    out = np.empty((n,) + a.shape[1:], a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(cache=True)  # object-mode block: no nogil
def wall_clock():
    with objmode(now="float64"):
        now = time.perf_counter()
    return now


@njit(**JIT)
def start(y, M, D, t):
    """Prepare a run at ``t``: zone membership, and with load transfer the consistent filtered accelerations."""
    W = make_work(M)
    membership(y, M, D.memb, W.trig)
    if M.icfg[I_LT] != 0:
        sw = np.zeros((M.wheel.shape[0], N_S))
        segment_params(phase_at(t, M.phase_times), D.memb, M, sw)
        consistent_accelerations(y, M, sw, D, np.zeros(y.shape[0]), W)


# ============================================================================= the segment loop, by stage
#: What the segment loop works with during a run (allocated once by :func:`run_context`):
#: segment wheel inputs ``sw`` (nw, N_S), RK stages ``K`` (ns + 1, n), path-integrand values
#: at the stages ``gq`` (ns + 1, nq + nw) and scratch ``gtmp``, scratch states ``ytmp``,
#: ``ytmp2``, the step's end ``y_new``, a derivative ``dydt``, the error estimate ``err``, new
#: zone membership ``new_memb``, log records ``rec`` and impact geometry ``geo`` (6,), the work
#: arrays ``W`` (:class:`Work`), the segment's events ``ev`` (:class:`Events`) and their values
#: ``vals`` (:class:`EventValues`), Gauss-Legendre nodes and weights ``gl_x``, ``gl_w`` on
#: [-1, 1], the path integrals ``quad`` (accumulated), the wall-clock ``deadline`` and scratch for the
#: margins of the wheels' switches at a rejected step's end ``margins`` (nw, W_M1 - W_M0; :func:`kink_fraction`).
RunContext = namedtuple("RunContext", ["sw", "K", "gq", "gtmp", "ytmp", "ytmp2", "y_new", "dydt", "err", "new_memb",
                                       "rec", "geo", "W", "ev", "vals", "gl_x", "gl_w", "quad", "deadline", "margins"])
#: The stored steps (growable): start time ``t`` [s], size ``h`` [s], start state ``y`` (n,)
#: and dense-output matrix ``q`` (n, degree) of each.
StepStore = namedtuple("StepStore", ["t", "h", "y", "q"])
#: The stored segments (growable): start and end time ``t`` (2,) [s], first and end step ``s``
#: (2,), and the segment's mode (the fields of :class:`Segments`).
SegmentStore = namedtuple("SegmentStore", ["t", "s", "phase", "memb", "nlk", "lk_j", "lk_th", "pstate", "pref",
                                           "parked"])
#: Status of :func:`integrate_segment` when the step store is full (grow it and call again).
STORE_FULL = 2
#: The event log (growable): time [s] and record row (kind, i, j, x, energy) of each record.
LogStore = namedtuple("LogStore", ["t", "rec"])


class RunOutput(NamedTuple):
    """What :func:`run` returns (numba builds and boxes it): how the call ended, its steps, its
    segments and its event log.

    ``status`` (an ``ST_*`` code), ``t_end`` [s] and ``y_end`` (n,) where the call stopped;
    the steps (``st_*``): start time [s], size [s], start state (n,) and dense-output matrix
    (n, degree) of each; the segments (``sg_*``): start and end time (2,) [s], first and end
    step (2,) and the segment's mode (the fields of :class:`Segments`); the event log
    (``lg_*``): time [s] and record row of :func:`handle_event`; and with status
    ``ST_IMPACT`` the touch ``geo`` = (pair, x, y, nx, ny, u_n).
    """

    status: int
    t_end: float
    y_end: np.ndarray
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
    lg_t: np.ndarray
    lg_rec: np.ndarray
    geo: np.ndarray


@njit(**STAGE)
def run_context(M, D, n, gl_x, gl_w, quad, deadline):
    """The arrays of the segment loop (:class:`RunContext`) for states of size ``n``."""
    nb = M.body.shape[0]
    nw = M.wheel.shape[0]
    nh = M.hitch.shape[0]
    nz = M.zone_mu.shape[0]
    npr = M.pair_body.shape[0]
    nv = D.parked.shape[0]
    ns = M.tab_b.shape[0]
    nq = nb + 3 * nw + npr  # integrated components (gq also carries the nw sliding flags)
    n_ev_max = nv + nz + 3 * nh + 3 * npr + 1
    ev = Events(np.zeros(n_ev_max, np.int64), np.zeros(n_ev_max, np.int64), np.zeros(n_ev_max), np.zeros(n_ev_max))
    vals = EventValues(np.zeros(n_ev_max), np.zeros(n_ev_max), np.zeros(n_ev_max), np.zeros(n_ev_max))
    return RunContext(np.zeros((nw, N_S)), np.zeros((ns + 1, n)), np.zeros((ns + 1, nq + nw)), np.zeros(nq + nw),
                      np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros((nw, nz), np.bool_),
                      np.zeros((nw * max(nz, 1) + nv + 8, 5)), np.zeros(6), make_work(M), ev, vals, gl_x, gl_w, quad,
                      deadline, np.full((nw, W_M1 - W_M0), np.nan))


@njit(**STAGE)
def new_step_store(cap, n, deg):
    return StepStore(np.zeros(cap), np.zeros(cap), np.zeros((cap, n)), np.zeros((cap, n, deg)))


@njit(**STAGE)
def new_segment_store(cap, M, D):
    nw = M.wheel.shape[0]
    nh = M.hitch.shape[0]
    nz = M.zone_mu.shape[0]
    npr = M.pair_body.shape[0]
    nv = D.parked.shape[0]
    return SegmentStore(np.zeros((cap, 2)), np.zeros((cap, 2), np.int64), np.zeros(cap, np.int64),
                        np.zeros((cap, nw, nz), np.bool_), np.zeros(cap, np.int64),
                        np.zeros((cap, max(nh, 1)), np.int64), np.zeros((cap, max(nh, 1))),
                        np.zeros((cap, npr), np.int64), np.zeros((cap, npr, N_A)), np.zeros((cap, nv), np.int64))


@njit(**STAGE)
def run_limit(D, M, counters):
    """Status that ends the run before a new segment (``ST_REST``: every vehicle parked; the
    segment and no-progress bounds), or -1 to go on."""
    parked = D.parked
    all_parked = True
    for v in range(parked.shape[0]):
        if parked[v] == 0:
            all_parked = False
    if all_parked:
        return ST_REST
    if counters[0] >= M.icfg[I_MAXSEG]:
        return ST_MAX_SEGMENTS
    if counters[1] >= MAX_STILL_SEGMENTS:
        return ST_NO_PROGRESS
    return -1


@njit(**STAGE)
def start_segment(t, y, M, D, offsets, stops, X):
    """Start a segment at ``(t, y)``: its end ``t_stop`` (the next scheduled change, or t_max),
    its wheel phase and inputs, its events and their values and rate bounds at ``y``.
    Returns ``(t_stop, phase, n_ev)``."""
    t_stop = M.cfg[C_TMAX]
    for s_ in stops:
        if s_ > t:
            t_stop = s_
            break
    phase = phase_at(t, M.phase_times)
    segment_params(phase, D.memb, M, X.sw)
    n_ev = build_events(M, D, offsets, X.ev)
    for e in range(n_ev):
        X.vals.g_old[e] = event_value(e, y, M, X.ev, D, X.sw, X.dydt, X.W)
        X.vals.r_old[e] = event_rate(e, y, M, X.ev, X.W)
    return t_stop, phase, n_ev


@njit(**STAGE)
def first_step(t, t_stop, y, M, D, X):
    """The right-hand side and path integrands at the segment's start (``K[0]``, ``gq[0]``) and
    the first step size: ``C_FIRST`` if set, else solve_ivp's initial step.  Returns
    ``(h_abs, evaluations)``."""
    evaluate(y, M, X.sw, D, X.K[0], X.W)
    quad_integrand(y, M, D, X.W, X.gq[0])
    if M.cfg[C_FIRST] > 0.0:
        return min(M.cfg[C_FIRST], t_stop - t), 1
    return initial_step(t, y, X.K[0], t_stop, X.ytmp, X.dydt, M, X.sw, D, X.W), 2


@njit(**INLINE)
def keep_margins(wk, margins):
    """Copy the margins of the wheels' switches of the last tyre evaluation with margins (``W.wheel_out``)
    into ``margins``."""
    for k in range(margins.shape[0]):
        for c in range(W_M1 - W_M0):
            margins[k, c] = wk[k, W_M0 + c]


#: A rejected step is aimed at a switch of the tyre law only where the switch lies in this part of it
#: (fractions of the step): one nearer its start does not spoil the step, one nearer its end is as well
#: met by the error control's own shrinking.
KINK_MIN, KINK_MAX = 0.02, 0.98


@njit(**HOT)
def kink_fraction(wk, m1):
    """Where in a step a switch of the tyre law lies, as a fraction of the step, or -1 if none.

    ``wk`` is the evaluation of the tyres at the step's start (``W.wheel_out``), ``m1`` each wheel's
    switch margins at its end (:func:`keep_margins`): a margin that changes sign (each >= 0 on its far
    side; NaN where the switch does not apply) crossed its switch, which the straight line between the
    two values places at ``m0 / (m0 - m1)``.  The lock-up margin counts only where the wheel is
    saturated at one end (it locks only then).  The earliest crossing within ``[KINK_MIN, KINK_MAX]``.

    At a switch the force law keeps its value but not its slope (the friction circle's lateral
    cut as a braked wheel nears its lock, the ABS limit taking hold, a wheel lifting, ...), so an
    explicit step across one has an error of the first order in the step; the error control
    would shrink the step by its factor again and again around it (most of the rejected steps of
    ``benchmarks/air_brakes_cost.py``'s all-on run were there).  Aimed at the switch, the step ends
    there and the next one starts on it, each on one smooth piece.
    """
    best = -1.0
    for k in range(m1.shape[0]):
        sat = (wk[k, W_MSAT] >= 0.0) or (m1[k, W_MSAT - W_M0] >= 0.0)
        for c in range(W_M1 - W_M0):
            if c == W_MLOCK - W_M0 and not sat:
                continue
            a = wk[k, W_M0 + c]
            b = m1[k, c]
            if not (a < 0.0 <= b or b < 0.0 <= a):  # no crossing (or a NaN)
                continue
            f = a / (a - b)
            if KINK_MIN <= f <= KINK_MAX and (best < 0.0 or f < best):
                best = f
    return best


@njit(**INLINE)
def attempt_step(t, t_stop, h_abs, min_step, y, M, D, X, nfev):
    """Steps from ``(t, y)`` until one is accepted (solve_ivp's RK error control, its constants
    ``SAFETY``, ``MIN_FACTOR``, ``MAX_FACTOR``): the stages in ``K``, the end state in ``y_new``.

    A step rejected at its first try across a switch of the tyre law is retried up to the switch
    (:func:`kink_fraction`; once: where that retry fails too, the error control's factor takes over,
    as the margins are not straight enough there to aim again); the step after one accepted so
    grows by the error control's factor up to the size first tried.

    Returns ``(status, t_new, h, h_abs, nfev)``: status 0 accepted, else minus the failure
    (``ST_STEP_TOO_SMALL``, ``ST_MAX_EVAL``, ``ST_NONFINITE``); ``h_abs`` the next step size.
    """
    K, tab_e = X.K, M.tab_e
    rtol = M.cfg[C_RTOL]
    atol = M.cfg[C_ATOL]
    err_exp = -1.0 / (M.icfg[I_ORDER] + 1)
    max_eval = M.icfg[I_MAXEVAL]
    ns = M.tab_b.shape[0]
    n = y.shape[0]
    t_new = t
    h = 0.0
    rejected = False
    aimed = False
    h_first = h_abs
    while True:
        if h_abs < min_step:
            return -ST_STEP_TOO_SMALL, t_new, h, h_abs, nfev
        if nfev >= max_eval:
            return -ST_MAX_EVAL, t_new, h, h_abs, nfev
        t_new = t + h_abs
        if t_new - t_stop > 0:
            t_new = t_stop
        h = t_new - t
        h_abs = abs(h)
        k_ev, finite = rk_step(y, h, K, X.y_new, X.ytmp, M, X.sw, D, X.W, X.gq)
        nfev += k_ev
        if not finite:
            return -ST_NONFINITE, t_new, h, h_abs, nfev
        for i in range(n):
            acc = 0.0
            for s in range(ns + 1):
                acc += tab_e[s] * K[s, i]
            X.err[i] = h * acc
        err_norm = rms_scaled(X.err, y, X.y_new, True, rtol, atol)
        if err_norm < 1.0:
            if err_norm == 0.0:
                factor = MAX_FACTOR
            else:
                factor = min(MAX_FACTOR, SAFETY * err_norm**err_exp)
            if aimed:
                # ended on a switch: the rest is smooth again, so the error control's factor is not held
                # to 1 as after a rejection; at most back to the size first tried
                h_abs = min(h_abs * factor, h_first)
            else:
                if rejected:
                    factor = min(1.0, factor)
                h_abs *= factor
            return 0, t_new, h, h_abs, nfev
        f = -1.0
        if not rejected:
            # the tyres' switch margins at the end, then at the start (work arrays only: the stages are
            # kept); the right-hand side does not compute them, an accepted step never needs them
            tyre_eval(X.y_new, M, X.sw, D, X.W, True)
            keep_margins(X.W.wheel_out, X.margins)
            tyre_eval(y, M, X.sw, D, X.W, True)
            f = kink_fraction(X.W.wheel_out, X.margins)
        if f > 0.0:
            h_abs *= f
            aimed = True
        else:
            h_abs *= max(MIN_FACTOR, SAFETY * err_norm**err_exp)
            aimed = False
        rejected = True


@njit(**INLINE)
def store_step(steps, n_steps, t, h, y, K, tab_p):
    """Store an accepted step (start time, size, start state, dense output ``Q = K^T P``) as
    step ``n_steps`` (the store has room: :func:`integrate_segment` sees to it)."""
    ns1 = K.shape[0]
    deg = tab_p.shape[1]
    steps.t[n_steps] = t
    steps.h[n_steps] = h
    for i in range(y.shape[0]):
        steps.y[n_steps, i] = y[i]
        for d in range(deg):
            acc = 0.0
            for s in range(ns1):
                acc += K[s, i] * tab_p[s, d]
            steps.q[n_steps, i, d] = acc


@njit(**STAGE)
def grow_steps(steps):
    """The step store with twice the room."""
    cap = 2 * steps.t.shape[0]
    return StepStore(grow1(steps.t, cap), grow1(steps.h, cap), grow2(steps.y, cap), grow3(steps.q, cap))


@njit(**INLINE)
def gauss_quadrature(mid, half, step, M, D, X):
    """Path integrals over ``[mid - half, mid + half]`` by Gauss-Legendre on the dense output of
    ``step`` (:class:`Step`), added to ``X.quad``."""
    nq = M.body.shape[0] + 3 * M.wheel.shape[0] + M.pair_body.shape[0]
    gl_x, gl_w, quad, gtmp = X.gl_x, X.gl_w, X.quad, X.gtmp
    for q in range(gl_x.shape[0]):
        interpolate(mid + half * gl_x[q], step.t_old, step.h, step.y_old, step.Q, step.ytmp)
        evaluate(step.ytmp, M, X.sw, D, X.dydt, X.W)
        quad_integrand(step.ytmp, M, D, X.W, gtmp)
        for c in range(nq):
            quad[c] += half * gl_w[q] * gtmp[c]


@njit(**INLINE)
def step_quadrature(step, M, D, X):
    """Path integrals over an accepted step without event: the RK solution of ``q' = g(y)``
    from the stage values, unless a sliding flag switches inside the step (a jump the stage
    rule, with its negative weight, integrates badly): then Gauss-Legendre on the dense output."""
    nw = M.wheel.shape[0]
    nq = M.body.shape[0] + 3 * nw + M.pair_body.shape[0]
    tab_b, gq, quad = M.tab_b, X.gq, X.quad
    ns = tab_b.shape[0]
    h = step.h
    switch = False
    for kk in range(nw):
        f0 = gq[0, nq + kk]
        for j in range(1, ns + 1):
            if gq[j, nq + kk] != f0:
                switch = True
    if switch:
        half = 0.5 * h
        gauss_quadrature(step.t_old + half, half, step, M, D, X)
    else:
        for c in range(nq):
            acc = 0.0
            for j in range(ns):
                acc += tab_b[j] * gq[j, c]
            quad[c] += h * acc


@njit(**INLINE)
def advance(y, n_ev, X):
    """Make the accepted step's end the next step's start: the state, the FSAL stage, the path
    integrands and the event values."""
    ns = X.K.shape[0] - 1
    for c in range(X.gq.shape[1]):
        X.gq[0, c] = X.gq[ns, c]
    for i in range(y.shape[0]):
        y[i] = X.y_new[i]
        X.K[0, i] = X.K[ns, i]
    for e in range(n_ev):
        X.vals.g_old[e] = X.vals.g_new[e]
        X.vals.r_old[e] = X.vals.r_new[e]


@njit(**HOT)
def integrate_segment(t, t_stop, h_abs, y, M, D, n_ev, X, steps, n_steps, nfev):
    """Integrate the segment from ``(t, y)`` with the next step size ``h_abs`` to ``t_stop`` or
    its first event (solve_ivp's RK driver; ``y`` is advanced in place).  Each accepted step is
    stored, searched for the segment's events (:func:`first_root`) and its path integrals are
    added.  Compiled without reference counting (the step loop would otherwise count references
    to every array of the bundles it reads, at every access), so it allocates nothing: when
    the step store is full it returns, the caller grows the store and calls again.

    Returns ``(status, fired, t, h_abs, n_steps, nfev)``: status 0 reached ``t_stop``, 1 event
    ``fired`` at ``t`` (the state there, the path integrals up to it), ``STORE_FULL``, or < 0
    minus the failure.
    """
    max_step = M.cfg[C_MAXSTEP]
    while t < t_stop:
        if n_steps == steps.t.shape[0]:
            return STORE_FULL, -1, t, h_abs, n_steps, nfev
        min_step = 10.0 * abs(np.nextafter(t, math.inf) - t)
        if h_abs > max_step:
            h_abs = max_step
        elif h_abs < min_step:
            h_abs = min_step
        status, t_new, h, h_abs, nfev = attempt_step(t, t_stop, h_abs, min_step, y, M, D, X, nfev)
        if status < 0:
            return status, -1, t, h_abs, n_steps, nfev
        if n_steps % WALL_CHECK_STEPS == 0 and wall_clock() > X.deadline:
            return -ST_WALL_TIME, -1, t, h_abs, n_steps, nfev
        store_step(steps, n_steps, t, h, y, X.K, M.tab_p)
        n_steps += 1
        # ---- events on the step
        for e in range(n_ev):
            X.vals.g_new[e] = event_value(e, X.y_new, M, X.ev, D, X.sw, X.dydt, X.W)
            X.vals.r_new[e] = event_rate(e, X.y_new, M, X.ev, X.W)
        t_first, fired = first_root(Step(t, h, steps.y[n_steps - 1], steps.q[n_steps - 1], X.ytmp2), t_new, M, X.ev,
                                    n_ev, X.vals, D, X.sw, X.dydt, X.W)
        dense = Step(t, h, steps.y[n_steps - 1], steps.q[n_steps - 1], X.ytmp)
        if fired >= 0:
            # path integrals over [t, t_first] by Gauss-Legendre on the dense output
            gauss_quadrature(0.5 * (t_first + t), 0.5 * (t_first - t), dense, M, D, X)
            interpolate(t_first, t, h, dense.y_old, dense.Q, y)
            return 1, fired, t_first, h_abs, n_steps, nfev
        step_quadrature(dense, M, D, X)
        t = t_new
        advance(y, n_ev, X)
    return 0, -1, t, h_abs, n_steps, nfev


@njit(**STAGE)
def record_segment(segs, n_seg, t0, t1, steps0, steps1, phase, D):
    """Store segment ``n_seg`` (its times, steps and its mode as it was during the segment);
    returns the store (a larger one when it was full)."""
    if n_seg == segs.t.shape[0]:
        cap = 2 * segs.t.shape[0]
        segs = SegmentStore(grow2(segs.t, cap), grow2(segs.s, cap), grow1(segs.phase, cap), grow3(segs.memb, cap),
                            grow1(segs.nlk, cap), grow2(segs.lk_j, cap), grow2(segs.lk_th, cap),
                            grow2(segs.pstate, cap), grow3(segs.pref, cap), grow2(segs.parked, cap))
    segs.t[n_seg, 0] = t0
    segs.t[n_seg, 1] = t1
    segs.s[n_seg, 0] = steps0
    segs.s[n_seg, 1] = steps1
    segs.phase[n_seg] = phase
    segs.memb[n_seg] = D.memb
    segs.nlk[n_seg] = D.lk_n[0]
    for q in range(D.lk_n[0]):
        segs.lk_j[n_seg, q] = D.lk_j[q]
        segs.lk_th[n_seg, q] = D.lk_th[q]
    for p in range(D.pstate.shape[0]):
        segs.pstate[n_seg, p] = D.pstate[p]
        for c in range(N_A):
            segs.pref[n_seg, p, c] = D.pref[p, c]
    for v in range(D.parked.shape[0]):
        segs.parked[n_seg, v] = D.parked[v]
    return segs


@njit(**STAGE)
def end_segment(status, fired, t, y, M, D, offsets, X):
    """The event that ended the segment (status 1), or its scheduled change, then (unless an
    impulse is needed) the new zone membership and parking (:func:`settle`).  Returns
    ``(impact, n_records)``, the records in ``X.rec``."""
    impact = False
    if status == 1:
        impact, n_rec = handle_event(fired, t, y, M, D, offsets, X.ev, X.sw, X.dydt, X.W, X.rec, X.geo)
    else:
        n_rec = log_record(X.rec, 0, LOG_SCHEDULE, 0, 0, 0.0, 0.0)
    if not impact:
        n_rec = settle(y, M, D, X.new_memb, X.W, X.rec, n_rec)
    return impact, n_rec


@njit(**STAGE)
def append_log(logs, lg_n, t, rec, n_rec):
    """Append ``n_rec`` records of ``rec`` at time ``t`` to the log; returns the store."""
    if lg_n + n_rec >= logs.t.shape[0]:
        cap = 2 * logs.t.shape[0] + n_rec
        logs = LogStore(grow1(logs.t, cap), grow2(logs.rec, cap))
    for r in range(n_rec):
        logs.t[lg_n + r] = t
        for c in range(5):
            logs.rec[lg_n + r, c] = rec[r, c]
    return logs


@njit(**JIT)
def run(t0, y0, M, D, offsets, stops, gl_x, gl_w, budget, counters, quad):
    """Integrate the scene from ``t0`` until rest, a limit, a failure, or a touch that needs an impulse.

    The segment loop of both engines (the SciPy engine's Python loop is the same, around SciPy's
    integrators): every segment has constant inputs (wheel phase, zone membership, closed
    stops, contact states, parked vehicles); it ends at the first event, located on the dense
    output (:func:`first_root`), or at a scheduled change; :func:`handle_event` and
    :func:`settle` update the state and the mode.

    Parameters
    ----------
    t0, y0 : start time [s] and state
    M, D : model bundle and mode (``D`` is updated in place)
    offsets : 2 pi k offsets of the articulation angles (per hitch)
    stops : sorted segment end times [s] (scheduled changes before t_max, then t_max)
    gl_x, gl_w : Gauss-Legendre nodes and weights on [-1, 1]
    budget : wall-clock seconds this call may take from its start (``ST_WALL_TIME`` after them); the
        clock starts here, inside the compiled code, so a first call's compilation is not counted
    counters : int64 array ``(restarts, restarts without progress, nfev)``, carried across calls
    quad : path integrals (module docstring of :func:`quad_integrand`), accumulated in place

    Bounds (each ends the run with its own status): ``max_segments`` restarts (every restart
    counts, also one that ends where it starts), ``MAX_STILL_SEGMENTS`` consecutive restarts
    without progress in time, ``max_evaluations`` right-hand-side evaluations (which also
    bounds the stored steps, so the memory), and the wall-clock ``deadline``.

    Returns
    -------
    RunOutput
        Status, end time and state; steps (start time, size, start state, dense-output matrix),
        segments (start/end time, first/end step, the mode), the event log (time, record rows of
        :func:`handle_event`) and, with status ``ST_IMPACT``, the touch ``geo`` = (pair, x, y, nx,
        ny, u_n).
    """
    n = y0.shape[0]
    t_max = M.cfg[C_TMAX]
    X = run_context(M, D, n, gl_x, gl_w, quad, wall_clock() + budget)
    steps = new_step_store(256, n, M.tab_p.shape[1])
    segs = new_segment_store(16, M, D)
    logs = LogStore(np.zeros(16), np.zeros((16, 5)))
    n_steps = 0
    n_seg = 0
    lg_n = 0
    nfev = counters[2]
    t = t0
    y = y0.copy()
    while True:
        status = run_limit(D, M, counters)
        if status >= 0:
            break
        counters[0] += 1
        t_stop, phase, n_ev = start_segment(t, y, M, D, offsets, stops, X)
        t_seg0 = t
        seg_first_step = n_steps
        h_abs, k_ev = first_step(t, t_stop, y, M, D, X)
        nfev += k_ev
        while True:
            seg_status, fired, t, h_abs, n_steps, nfev = integrate_segment(t, t_stop, h_abs, y, M, D, n_ev, X, steps,
                                                                           n_steps, nfev)
            if seg_status != STORE_FULL:
                break
            steps = grow_steps(steps)
        # ---- record the segment (its mode as it was during the segment)
        if t > t_seg0:
            segs = record_segment(segs, n_seg, t_seg0, t, seg_first_step, n_steps, phase, D)
            n_seg += 1
            counters[1] = 0
        else:
            n_steps = seg_first_step
            counters[1] += 1
        if seg_status < 0:
            status = -seg_status
            break
        if seg_status == 0 and t >= t_max:
            status = ST_TIME_LIMIT
            break
        # ---- the event, or the scheduled change, then the new zone membership and parking
        impact, n_rec = end_segment(seg_status, fired, t, y, M, D, offsets, X)
        logs = append_log(logs, lg_n, t, X.rec, n_rec)
        lg_n += n_rec
        if impact:
            status = ST_IMPACT
            break
    counters[2] = nfev
    return RunOutput(status, t, y, steps.t[:n_steps], steps.h[:n_steps], steps.y[:n_steps], steps.q[:n_steps],
                     segs.t[:n_seg], segs.s[:n_seg], segs.phase[:n_seg], segs.memb[:n_seg], segs.nlk[:n_seg],
                     segs.lk_j[:n_seg], segs.lk_th[:n_seg], segs.pstate[:n_seg], segs.pref[:n_seg],
                     segs.parked[:n_seg], logs.t[:lg_n], logs.rec[:lg_n], X.geo)

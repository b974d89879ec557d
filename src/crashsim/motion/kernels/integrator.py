"""Kernel stage: the compiled engine's explicit Runge-Kutta integrator and its segment loop.

solve_ivp's RK driver (step, error control, initial step) re-written in numba, and
:func:`run`, the segment loop cut into its stages (start a segment, take a step, locate
the event, record the segment, handle the event).
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit, objmode

from ..options import MAX_STILL_SEGMENTS
from .jit import HOT, INLINE, JIT
from .arrays import (C_ATOL, C_FIRST, C_MAXSTEP, C_RTOL, C_TMAX, I_LT, I_MAXEVAL, I_MAXSEG, I_ORDER, LOG_SCHEDULE,
    MAX_FACTOR, MIN_FACTOR, N_A, N_S, SAFETY, ST_IMPACT, ST_MAX_EVAL, ST_MAX_SEGMENTS, ST_NONFINITE, ST_NO_PROGRESS,
    ST_REST, ST_STEP_TOO_SMALL, ST_TIME_LIMIT, ST_WALL_TIME, WALL_CHECK_STEPS, make_work)
from .geometry import membership
from .equations import consistent_accelerations, evaluate, phase_at, quad_integrand, segment_params
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
def rk_step(y, h, K, y_new, ytmp, M, sw, D, W, tab_a, tab_b, gq):
    """One explicit RK step from ``y`` (``K[0]`` = f(y)); stages in ``K``, FSAL ``K[ns]`` = f(y_new).

    ``gq[s]`` receives the path-integral integrands (:func:`quad_integrand`) at stage ``s``
    (``gq[0]`` must hold those at ``y``): ``h sum_s b_s gq[s]`` is then the RK solution of the
    quadrature ODE ``q' = g(y)``, as accurate as the step itself.

    Returns the number of right-hand-side evaluations (``ns``) and whether all were finite.
    """
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
def initial_step(t0, y0, f0, t_bound, max_step, order, rtol, atol, ytmp, f1, M, sw, D, W):
    """solve_ivp's ``select_initial_step`` (Hairer, Norsett & Wanner, II.4); one RHS evaluation."""
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


@njit(**JIT)
def run(t0, y0, M, D, offsets, stops, gl_x, gl_w, deadline, counters, quad):
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
    deadline : ``time.perf_counter()`` value after which the run stops (``ST_WALL_TIME``)
    counters : int64 array ``(restarts, restarts without progress, nfev)``, carried across calls
    quad : path integrals (module docstring of :func:`quad_integrand`), accumulated in place

    Bounds (each ends the run with its own status): ``max_segments`` restarts (every restart
    counts, also one that ends where it starts), ``MAX_STILL_SEGMENTS`` consecutive restarts
    without progress in time, ``max_evaluations`` right-hand-side evaluations (which also
    bounds the stored steps, so the memory), and the wall-clock ``deadline``.

    Returns
    -------
    tuple
        ``(status, t_end, y_end, st_t, st_h, st_y, st_q, sg_t, sg_s, sg_phase, sg_memb, sg_nlk,
        sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked, lg_t, lg_rec, geo)``: steps (start time,
        size, start state, dense-output matrix), segments (start/end time, first/end step, the
        mode), the event log (time, record rows of :func:`handle_event`) and, with status
        ``ST_IMPACT``, the touch ``geo`` = (pair, x, y, nx, ny, u_n).
    """
    body, hitch, phase_t, zone_mu, cfg, icfg = M.body, M.hitch, M.phase_times, M.zone_mu, M.cfg, M.icfg
    tab_a, tab_b, tab_e, tab_p = M.tab_a, M.tab_b, M.tab_e, M.tab_p
    memb, lk_j, lk_th, lk_n, pstate, pref, parked = D.memb, D.lk_j, D.lk_th, D.lk_n, D.pstate, D.pref, D.parked
    nb = body.shape[0]
    nw = M.wheel.shape[0]
    nh = hitch.shape[0]
    nz = zone_mu.shape[0]
    npr = M.pair_body.shape[0]
    nv = parked.shape[0]
    n = y0.shape[0]
    ns = tab_b.shape[0]
    deg = tab_p.shape[1]
    rtol = cfg[C_RTOL]
    atol = cfg[C_ATOL]
    max_step = cfg[C_MAXSTEP]
    t_max = cfg[C_TMAX]
    order = icfg[I_ORDER]
    err_exp = -1.0 / (order + 1)
    max_segments = icfg[I_MAXSEG]
    max_eval = icfg[I_MAXEVAL]

    W = make_work(M)
    sw = np.zeros((nw, N_S))
    K = np.zeros((ns + 1, n))
    nq = nb + 3 * nw + npr  # integrated components (gq also carries the nw sliding flags)
    gq = np.zeros((ns + 1, nq + nw))
    gtmp = np.zeros(nq + nw)
    ytmp = np.zeros(n)
    ytmp2 = np.zeros(n)
    y_new = np.zeros(n)
    dydt = np.zeros(n)
    err = np.zeros(n)
    new_memb = np.zeros((nw, nz), np.bool_)
    n_ev_max = nv + nz + 3 * nh + 3 * npr + 1
    ev_kind = np.zeros(n_ev_max, np.int64)
    ev_idx = np.zeros(n_ev_max, np.int64)
    ev_val = np.zeros(n_ev_max)
    ev_dir = np.zeros(n_ev_max)
    g_old = np.zeros(n_ev_max)
    g_new = np.zeros(n_ev_max)
    r_old = np.zeros(n_ev_max)
    r_new = np.zeros(n_ev_max)
    rec = np.zeros((nw * max(nz, 1) + nv + 8, 5))
    geo = np.zeros(6)

    cap = 256
    st_t = np.zeros(cap)
    st_h = np.zeros(cap)
    st_y = np.zeros((cap, n))
    st_q = np.zeros((cap, n, deg))
    scap = 16
    sg_t = np.zeros((scap, 2))
    sg_s = np.zeros((scap, 2), np.int64)
    sg_phase = np.zeros(scap, np.int64)
    sg_memb = np.zeros((scap, nw, nz), np.bool_)
    sg_nlk = np.zeros(scap, np.int64)
    sg_lkj = np.zeros((scap, max(nh, 1)), np.int64)
    sg_lkth = np.zeros((scap, max(nh, 1)))
    sg_pstate = np.zeros((scap, npr), np.int64)
    sg_pref = np.zeros((scap, npr, N_A))
    sg_parked = np.zeros((scap, nv), np.int64)
    lcap = 16
    lg_t = np.zeros(lcap)
    lg_rec = np.zeros((lcap, 5))
    lg_n = 0
    n_steps = 0
    n_seg = 0
    nfev = counters[2]

    t = t0
    y = y0.copy()
    status = -1

    while True:
        all_parked = True
        for v in range(nv):
            if parked[v] == 0:
                all_parked = False
        if all_parked:
            status = ST_REST
            break
        if counters[0] >= max_segments:
            status = ST_MAX_SEGMENTS
            break
        if counters[1] >= MAX_STILL_SEGMENTS:
            status = ST_NO_PROGRESS
            break
        counters[0] += 1
        t_stop = t_max
        for s_ in stops:
            if s_ > t:
                t_stop = s_
                break
        phase = phase_at(t, phase_t)
        segment_params(phase, memb, M, sw)
        n_ev = build_events(M, D, offsets, ev_kind, ev_idx, ev_val, ev_dir)
        for e in range(n_ev):
            g_old[e] = event_value(e, y, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)
            r_old[e] = event_rate(e, y, M, ev_kind, ev_idx, W)

        # ---- integrate the segment [t, t_stop] (solve_ivp's RK driver)
        seg_first_step = n_steps
        t_seg0 = t
        evaluate(y, M, sw, D, K[0], W)
        quad_integrand(y, M, D, W, gq[0])
        nfev += 1
        if cfg[C_FIRST] > 0.0:
            h_abs = min(cfg[C_FIRST], t_stop - t)
        else:
            h_abs = initial_step(t, y, K[0], t_stop, max_step, order, rtol, atol, ytmp, dydt, M, sw, D, W)
            nfev += 1
        fired = -1
        seg_status = 0  # 0: reached t_stop, 1: event, <0: failure
        while t < t_stop:
            min_step = 10.0 * abs(np.nextafter(t, math.inf) - t)
            if h_abs > max_step:
                h_abs = max_step
            elif h_abs < min_step:
                h_abs = min_step
            rejected = False
            accepted = False
            while not accepted:
                if h_abs < min_step:
                    seg_status = -ST_STEP_TOO_SMALL
                    break
                if nfev >= max_eval:
                    seg_status = -ST_MAX_EVAL
                    break
                t_new = t + h_abs
                if t_new - t_stop > 0:
                    t_new = t_stop
                h = t_new - t
                h_abs = abs(h)
                k_ev, finite = rk_step(y, h, K, y_new, ytmp, M, sw, D, W, tab_a, tab_b, gq)
                nfev += k_ev
                if not finite:
                    seg_status = -ST_NONFINITE
                    break
                for i in range(n):
                    acc = 0.0
                    for s in range(ns + 1):
                        acc += tab_e[s] * K[s, i]
                    err[i] = h * acc
                err_norm = rms_scaled(err, y, y_new, True, rtol, atol)
                if err_norm < 1.0:
                    if err_norm == 0.0:
                        factor = MAX_FACTOR
                    else:
                        factor = min(MAX_FACTOR, SAFETY * err_norm**err_exp)
                    if rejected:
                        factor = min(1.0, factor)
                    h_abs *= factor
                    accepted = True
                else:
                    h_abs *= max(MIN_FACTOR, SAFETY * err_norm**err_exp)
                    rejected = True
            if seg_status < 0:
                break
            if n_steps % WALL_CHECK_STEPS == 0 and wall_clock() > deadline:
                seg_status = -ST_WALL_TIME
                break
            # ---- store the step (start time, size, start state, dense output Q = K^T P)
            if n_steps == st_t.shape[0]:
                cap = 2 * st_t.shape[0]
                st_t = grow1(st_t, cap)
                st_h = grow1(st_h, cap)
                st_y = grow2(st_y, cap)
                st_q = grow3(st_q, cap)
            st_t[n_steps] = t
            st_h[n_steps] = h
            for i in range(n):
                st_y[n_steps, i] = y[i]
                for d in range(deg):
                    acc = 0.0
                    for s in range(ns + 1):
                        acc += K[s, i] * tab_p[s, d]
                    st_q[n_steps, i, d] = acc
            n_steps += 1
            # ---- events on the step
            for e in range(n_ev):
                g_new[e] = event_value(e, y_new, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)
                r_new[e] = event_rate(e, y_new, M, ev_kind, ev_idx, W)
            t_first, fired = first_root(t, t_new, h, st_y[n_steps - 1], st_q[n_steps - 1], ytmp2, M, ev_kind, ev_idx,
                                        ev_val, ev_dir, n_ev, g_old, g_new, r_old, r_new, D, sw, dydt, W)
            if fired >= 0:
                # path integrals over [t, t_first] by Gauss-Legendre on the dense output
                half = 0.5 * (t_first - t)
                mid = 0.5 * (t_first + t)
                for q in range(gl_x.shape[0]):
                    interpolate(mid + half * gl_x[q], t, h, st_y[n_steps - 1], st_q[n_steps - 1], ytmp)
                    evaluate(ytmp, M, sw, D, dydt, W)
                    quad_integrand(ytmp, M, D, W, gtmp)
                    for c in range(nq):
                        quad[c] += half * gl_w[q] * gtmp[c]
                interpolate(t_first, t, h, st_y[n_steps - 1], st_q[n_steps - 1], y)
                t = t_first
                seg_status = 1
                break
            # path integrals over the step: the RK solution of q' = g(y) from the stage values,
            # unless a sliding flag switches inside the step (a jump the stage rule, with its
            # negative weight, integrates badly): then 5-point Gauss-Legendre on the dense output
            switch = False
            for kk in range(nw):
                f0 = gq[0, nq + kk]
                for j in range(1, ns + 1):
                    if gq[j, nq + kk] != f0:
                        switch = True
            if switch:
                half = 0.5 * h
                mid = t + half
                for q in range(gl_x.shape[0]):
                    interpolate(mid + half * gl_x[q], t, h, st_y[n_steps - 1], st_q[n_steps - 1], ytmp)
                    evaluate(ytmp, M, sw, D, dydt, W)
                    quad_integrand(ytmp, M, D, W, gtmp)
                    for c in range(nq):
                        quad[c] += half * gl_w[q] * gtmp[c]
            else:
                for c in range(nq):
                    acc = 0.0
                    for j in range(ns):
                        acc += tab_b[j] * gq[j, c]
                    quad[c] += h * acc
            for c in range(nq + nw):
                gq[0, c] = gq[ns, c]
            t = t_new
            for i in range(n):
                y[i] = y_new[i]
                K[0, i] = K[ns, i]
            for e in range(n_ev):
                g_old[e] = g_new[e]
                r_old[e] = r_new[e]
        # ---- record the segment (its mode as it was during the segment)
        if t > t_seg0:
            if n_seg == sg_t.shape[0]:
                scap = 2 * sg_t.shape[0]
                sg_t = grow2(sg_t, scap)
                sg_s = grow2(sg_s, scap)
                sg_phase = grow1(sg_phase, scap)
                sg_memb = grow3(sg_memb, scap)
                sg_nlk = grow1(sg_nlk, scap)
                sg_lkj = grow2(sg_lkj, scap)
                sg_lkth = grow2(sg_lkth, scap)
                sg_pstate = grow2(sg_pstate, scap)
                sg_pref = grow3(sg_pref, scap)
                sg_parked = grow2(sg_parked, scap)
            sg_t[n_seg, 0] = t_seg0
            sg_t[n_seg, 1] = t
            sg_s[n_seg, 0] = seg_first_step
            sg_s[n_seg, 1] = n_steps
            sg_phase[n_seg] = phase
            sg_memb[n_seg] = memb
            sg_nlk[n_seg] = lk_n[0]
            for q in range(lk_n[0]):
                sg_lkj[n_seg, q] = lk_j[q]
                sg_lkth[n_seg, q] = lk_th[q]
            for p in range(npr):
                sg_pstate[n_seg, p] = pstate[p]
                for c in range(N_A):
                    sg_pref[n_seg, p, c] = pref[p, c]
            for v in range(nv):
                sg_parked[n_seg, v] = parked[v]
            n_seg += 1
            counters[1] = 0
        else:
            n_steps = seg_first_step
            counters[1] += 1
        if seg_status < 0:
            status = -seg_status
            break
        # ---- the event, or the scheduled change, then the new zone membership and parking
        n_rec = 0
        impact = False
        if seg_status == 1:
            impact, n_rec = handle_event(fired, t, y, M, D, offsets, ev_kind, ev_idx, ev_val, ev_dir, sw, dydt, W,
                                         rec, geo)
        else:
            if t >= t_max:
                status = ST_TIME_LIMIT
                break
            n_rec = log_record(rec, 0, LOG_SCHEDULE, 0, 0, 0.0, 0.0)
        if not impact:
            n_rec = settle(y, M, D, new_memb, W, rec, n_rec)
        if lg_n + n_rec >= lg_t.shape[0]:
            lcap = 2 * lg_t.shape[0] + n_rec
            lg_t = grow1(lg_t, lcap)
            lg_rec = grow2(lg_rec, lcap)
        for r in range(n_rec):
            lg_t[lg_n] = t
            for c in range(5):
                lg_rec[lg_n, c] = rec[r, c]
            lg_n += 1
        if impact:
            status = ST_IMPACT
            break
    counters[2] = nfev
    return (status, t, y, st_t[:n_steps], st_h[:n_steps], st_y[:n_steps], st_q[:n_steps],
            sg_t[:n_seg], sg_s[:n_seg], sg_phase[:n_seg], sg_memb[:n_seg], sg_nlk[:n_seg], sg_lkj[:n_seg],
            sg_lkth[:n_seg], sg_pstate[:n_seg], sg_pref[:n_seg], sg_parked[:n_seg], lg_t[:lg_n], lg_rec[:lg_n], geo)

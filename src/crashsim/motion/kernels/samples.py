"""Post-processing kernels: states and quantities at sample times of a finished run.

The mode of a stored segment, path integrals at quadrature nodes, evaluation at sampled
states (contact positions, loads, hitch forces, contact forces, depths), the contact-only
audit, missed zone entries, and the test hooks evaluating one state.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .jit import JIT
from .arrays import (Mode, N_A, N_S, N_W, PS_ARMED, PS_CONTACT, PS_DISARMED, P_BRAKE, P_FROLL, P_MUF, S_DCOEF,
    S_DEMAND, S_MU, S_MULOAD, S_N0, W_LOAD, W_SLIDE, make_work)
from .geometry import body_trig, pair_gap, pin_gap, signed_distance, wheel_xy
from .contacts import pair_depth, pair_forces, strike_speed, touch_geometry
from .equations import evaluate, quad_integrand, segment_params
from .events import interpolate


@njit(**JIT)  # allocates: compiled with reference counting
def segment_mode(s, S):
    """The mode ``D`` of stored segment ``s`` of the segments ``S`` (:class:`Segments`; copies:
    evaluating must not change the record)."""
    return Mode(S.memb[s], S.lk_j[s].copy(), S.lk_th[s].copy(), np.full(1, S.nlk[s], np.int64),
                np.zeros(S.lk_j.shape[1]), S.pstate[s].copy(), S.pref[s].copy(), S.parked[s].copy())


@njit(**JIT)
def quad_sums(Yq, wq, seg_of, M, S):
    """Path integrals from states ``Yq`` (n, K) at quadrature nodes with weights ``wq`` [s] in segments ``seg_of``."""
    nb = M.body.shape[0]
    nw = M.wheel.shape[0]
    npr = M.pair_body.shape[0]
    nq = nb + 3 * nw + npr
    W = make_work(M)
    sw = np.zeros((nw, N_S))
    dydt = np.zeros(Yq.shape[0])
    yq = np.zeros(Yq.shape[0])
    g = np.zeros(nq + nw)
    out = np.zeros(nq)
    last = -1
    D = segment_mode(0, S)
    for k in range(Yq.shape[1]):
        s = seg_of[k]
        if s != last:
            D = segment_mode(s, S)
            segment_params(S.phase[s], S.memb[s], M, sw)
            last = s
        for i in range(Yq.shape[0]):
            yq[i] = Yq[i, k]
        evaluate(yq, M, sw, D, dydt, W)
        quad_integrand(yq, M, D, W, g)
        for c in range(nq):
            out[c] += wq[k] * g[c]
    return out


@njit(**JIT)
def evaluate_columns(Y, M, phase, D, road_mu):
    """Everything the model computes for the states in the columns of ``Y`` (n, K).

    ``road_mu`` (nw,): per-wheel road friction replacing the membership's (NaN: from the
    membership), for the pymunk cross-check's blending across zone edges.  Returns
    ``(dydt (n, K), wk (K, nw, N_W), lam (K, m), f (K, 3 nb))``.
    """
    nw = M.wheel.shape[0]
    W = make_work(M)
    sw = np.zeros((nw, N_S))
    segment_params(phase, D.memb, M, sw)
    phase_w = M.phase_wheels
    for k in range(nw):
        if not math.isnan(road_mu[k]):
            pw = phase_w[phase, k]
            mu = road_mu[k] * pw[P_MUF]
            dcoef = min(pw[P_BRAKE] * mu + pw[P_FROLL], mu)
            sw[k, S_MU] = mu
            sw[k, S_MULOAD] = mu * sw[k, S_N0]
            sw[k, S_DEMAND] = dcoef * sw[k, S_N0]
            sw[k, S_DCOEF] = dcoef
    n = Y.shape[0]
    K = Y.shape[1]
    nh = M.hitch.shape[0]
    m = 2 * nh + D.lk_n[0]
    out = np.zeros((n, K))
    wks = np.zeros((K, nw, N_W))
    lams = np.zeros((K, m))
    fs = np.zeros((K, 3 * M.body.shape[0]))
    dydt = np.zeros(n)
    col = np.zeros(n)
    for j in range(K):
        for i in range(n):
            col[i] = Y[i, j]
        evaluate(col, M, sw, D, dydt, W)
        for i in range(n):
            out[i, j] = dydt[i]
        wks[j] = W.wheel_out
        for a in range(m):
            lams[j, a] = W.multipliers[a]
        fs[j] = W.body_force
    return out, wks, lams, fs


@njit(**JIT)
def interpolate_samples(T, seg_of, sg_s, st_t, st_h, st_y, st_q, y_end, n_total):
    """States at sample times ``T`` from the compiled engine's steps (the last sample is ``y_end``)."""
    n = y_end.shape[0]
    Y = np.zeros((n, T.shape[0]))
    yq = np.zeros(n)
    for p in range(T.shape[0]):
        s0 = sg_s[seg_of[p], 0]
        s1 = sg_s[seg_of[p], 1]
        if p == T.shape[0] - 1 or s1 == s0:
            for i in range(n):
                Y[i, p] = y_end[i]
            continue
        lo = s0
        hi = s1
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if st_t[mid] <= T[p]:
                lo = mid
            else:
                hi = mid
        interpolate(T[p], st_t[lo], st_h[lo], st_y[lo], st_q[lo], yq)
        for i in range(n):
            Y[i, p] = yq[i]
    return Y


@njit(**JIT)
def evaluate_samples(Y, seg_of, M, S):
    """Evaluated quantities at sampled states ``Y`` (n, K) in segments ``seg_of``.

    Returns ``(P, SL, LD, LAMH, STOPM, CF, max_gap, pen)``: contact positions (nw, K, 2) [m],
    sliding flags and loads [N] (nw, K), hitch forces on the front bodies (K, 2 nh) [N], stop
    moments (K, nh) [N m], the contact force magnitude of every pair (K, np) [N], the largest
    pin gap [m], and per pair the largest depth beyond its allowance while in contact, or the
    largest overlap while armed [m] (how far bodies went into each other).
    """
    nb = M.body.shape[0]
    nw = M.wheel.shape[0]
    hitch, hbody = M.hitch, M.hitch_body
    nh = hitch.shape[0]
    npr = M.pair_body.shape[0]
    K = Y.shape[1]
    P = np.zeros((nw, K, 2))
    SL = np.zeros((nw, K), np.bool_)
    LD = np.zeros((nw, K))
    LAMH = np.zeros((K, 2 * nh))
    STOPM = np.zeros((K, nh))
    CF = np.zeros((K, npr))
    pen = np.zeros(npr)
    max_gap = 0.0
    W = make_work(M)
    wk, lam, cs = W.wheel_out, W.multipliers, W.trig
    sw = np.zeros((nw, N_S))
    dydt = np.zeros(Y.shape[0])
    yq = np.zeros(Y.shape[0])
    f_scratch = np.zeros(3 * nb)
    fc_scratch = np.zeros(2 * nb)
    last = -1
    D = segment_mode(0, S)
    for p in range(K):
        s = seg_of[p]
        if s != last:
            D = segment_mode(s, S)
            segment_params(S.phase[s], S.memb[s], M, sw)
            last = s
        for i in range(Y.shape[0]):
            yq[i] = Y[i, p]
        evaluate(yq, M, sw, D, dydt, W)
        for k in range(nw):
            px, py = wheel_xy(yq, M, k, cs)
            P[k, p, 0] = px
            P[k, p, 1] = py
            SL[k, p] = wk[k, W_SLIDE] != 0.0
            LD[k, p] = wk[k, W_LOAD]
        for a in range(2 * nh):
            LAMH[p, a] = lam[a]
        for q in range(D.lk_n[0]):
            STOPM[p, D.lk_j[q]] = lam[2 * nh + q]
        for j in range(nh):
            max_gap = max(max_gap, pin_gap(yq, cs, hitch, hbody, j, nb))
        for q in range(npr):
            st = D.pstate[q]
            if st == PS_DISARMED:  # the crush of the first impact: no force, no depth to report
                continue
            depth = -pair_gap(yq, M, cs, q) if st == PS_ARMED else pair_depth(yq, M, D, cs, q, W.contact_pts)
            pen[q] = max(pen[q], depth)
            if st == PS_CONTACT:  # the pair's force on A
                for i in range(3 * nb):
                    f_scratch[i] = 0.0
                pair_forces(yq, M, D, cs, q, f_scratch, W.contact_pts, fc_scratch)
                ia = M.pair_body[q, 0]
                CF[p, q] = math.sqrt(f_scratch[ia] ** 2 + f_scratch[nb + ia] ** 2)
    return P, SL, LD, LAMH, STOPM, CF, max_gap, pen


@njit(**JIT)
def contact_samples(Y, seg_of, M, S):
    """What the pairs do at sampled states ``Y`` (n, K) in segments ``seg_of`` (the geometry only:
    no tyre forces, no multipliers).

    Returns ``(CF, pen, closing)``: the sustained-contact force magnitude on body A of every pair
    (K, np) [N]; per pair the largest depth beyond its allowance while in contact, or the largest
    overlap while armed [m]; and the strike measure [m/s] of the points pressed beyond the
    allowance outside the crush of the first impact (closing speed less ``omega`` times the depth,
    :func:`strike_speed`; 0 for an armed pair), (K, np): while a pair is in contact or disarmed this
    stays below its impulse threshold except at the instants of its impacts (a strike there is an
    impact), an audit of the rule.
    """
    K = Y.shape[1]
    npr = M.pair_body.shape[0]
    nb = M.body.shape[0]
    CF = np.zeros((K, npr))
    closing = np.zeros((K, npr))
    pen = np.zeros(npr)
    W = make_work(M)
    cs = W.trig
    f_scratch = np.zeros(3 * nb)
    y = np.zeros(Y.shape[0])
    last = seg_of[0] if K else 0
    D = segment_mode(last, S)
    for col in range(K):
        s_ = seg_of[col]
        if s_ != last:
            D = segment_mode(s_, S)
            last = s_
        for i in range(Y.shape[0]):
            y[i] = Y[i, col]
        body_trig(y, nb, cs)
        for q in range(npr):
            st = D.pstate[q]
            if st == PS_ARMED:
                pen[q] = max(pen[q], -pair_gap(y, M, cs, q))
                continue
            closing[col, q] = strike_speed(y, M, D, cs, q, W.contact_pts, False)
            if st == PS_DISARMED:  # the crush of the first impact: no force
                continue
            pen[q] = max(pen[q], pair_depth(y, M, D, cs, q, W.contact_pts))
            for i in range(3 * nb):  # the pair's force on A
                f_scratch[i] = 0.0
            pair_forces(y, M, D, cs, q, f_scratch, W.contact_pts, W.contact_force)  # the last not read
            ia = M.pair_body[q, 0]
            CF[col, q] = math.sqrt(f_scratch[ia] ** 2 + f_scratch[nb + ia] ** 2)
    return CF, pen, closing


@njit(**JIT)
def missed_zone(M, T, P, seg_of, memb):
    """First sample inside a zone the integration did not register: ``(t, wheel)``, wheel -1 if none.

    Points outside a zone's bounding box are outside without the polygon test.
    """
    nw = M.wheel.shape[0]
    zone_ptr, edges, zone_box = M.zone_ptr, M.zone_edges, M.zone_box
    nz = zone_box.shape[0]
    for p in range(T.shape[0]):
        g = seg_of[p]
        for z in range(nz):
            for k in range(nw):
                px = P[k, p, 0]
                py = P[k, p, 1]
                if (px < zone_box[z, 0] - 1e-5 or px > zone_box[z, 2] + 1e-5
                        or py < zone_box[z, 1] - 1e-5 or py > zone_box[z, 3] + 1e-5):
                    if memb[g, k, z]:
                        return T[p], k
                    continue
                d = signed_distance(px, py, z, zone_ptr, edges)
                if abs(d) > 1e-6 and (d > 0.0) != memb[g, k, z]:
                    return T[p], k
    return 0.0, -1


@njit(**JIT)
def pair_geometry(y, M, p):
    """Gap of pair ``p`` and, where pieces overlap or touch, its contact point and normal (tests, reports;
    the points of the outlines as they are, without a crush allowance)."""
    W = make_work(M)
    cs = W.trig
    body_trig(y, M.body.shape[0], cs)
    geo = np.zeros(5)
    g = pair_gap(y, M, cs, p)
    npr = M.pair_body.shape[0]
    D = Mode(np.zeros((M.wheel.shape[0], M.zone_mu.shape[0]), np.bool_), np.zeros(1, np.int64), np.zeros(1),
             np.zeros(1, np.int64), np.zeros(1), np.full(npr, PS_CONTACT, np.int64), np.zeros((npr, N_A)),
             np.zeros(M.body_vehicle.max() + 1 if M.body_vehicle.shape[0] else 1, np.int64))
    ok = touch_geometry(y, M, D, p, cs, W.contact_pts, geo)
    return g, ok, geo

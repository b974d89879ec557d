"""Kernel stage: events of a segment, their location on dense output, and what happens at them.

Event values and rate bounds, Brent's method (as scipy's brentq), the earliest root of a
step (:func:`first_root`), the event list of a mode (:func:`build_events`), the event
handler (:func:`handle_event`), parking and zone membership after an event (:func:`settle`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..layout import SV_HEADING, SV_VX, SV_VY, SV_YAW_RATE
from ..options import STOP_HYSTERESIS
from .jit import HOT, INLINE, JIT
from .arrays import (A_CRUSH, PRESSED, C_VSTOP, C_ZRES, EPS, EV_ARM, EV_GAP, EV_PRESS, EV_RELEASE, EV_REST, EV_STOP,
    EV_STRIKE, EV_ZONE, LOG_ARMED, LOG_CONTACT, LOG_CONTACT_END, LOG_PRESS, LOG_REST, LOG_STOP_CLOSED,
    LOG_STOP_IMPACT, LOG_STOP_OPEN, LOG_ZONE_ENTER, LOG_ZONE_EXIT, MAX_SUBSAMPLES, N_A, PS_ARMED, PS_CONTACT,
    PS_DISARMED, R_ARM, R_RES, R_VTHR, ZONE_OVERSHOOT, make_work)
from .geometry import body_trig, membership, pair_gap, signed_distance, wheel_velocity, wheel_xy
from .contacts import find_strike, pair_depth, set_reference, strike_geometry, strike_speed, touch_geometry, unpark_pair
from .equations import contact_group, evaluate, group_rest_measure, kinetic_energy, project_velocities, rest_measure


@njit(**HOT)
def event_value(e, y, M, ev, D, sw, dydt, W):
    """Value of event ``e`` of the segment's events ``ev`` (:class:`Events`) at state ``y``
    (package docstring for the kinds)."""
    ev_kind, ev_idx, ev_val = ev.kind, ev.idx, ev.val
    kind = ev_kind[e]
    if kind == EV_REST:
        return group_rest_measure(y, M, D, ev_idx[e]) - M.cfg[C_VSTOP]
    nb = M.body.shape[0]
    cs = W.trig
    if kind == EV_ZONE:
        z = ev_idx[e]
        zone_ptr, edges = M.zone_ptr, M.zone_edges
        memb = D.memb
        body_trig(y, nb, cs)
        g = math.inf
        for k in range(M.wheel.shape[0]):
            px, py = wheel_xy(y, M, k, cs)
            side = 1.0 if memb[k, z] else -1.0
            g = min(g, side * signed_distance(px, py, z, zone_ptr, edges))
        return g + ZONE_OVERSHOOT
    if kind == EV_STOP:
        j = ev_idx[e]
        hbody = M.hitch_body
        # ev_val = offset + limit + shift (upper stop) or offset - limit - shift (lower stop)
        return y[SV_HEADING * nb + hbody[j, 0]] - y[SV_HEADING * nb + hbody[j, 1]] - ev_val[e]
    if kind == EV_RELEASE:
        # multiplier of closed stop n times its side, > 0 when the stop would have to pull
        n = ev_idx[e]
        nh = M.hitch.shape[0]
        evaluate(y, M, sw, D, dydt, W)
        return W.multipliers[2 * nh + n] * ev_val[e]
    body_trig(y, nb, cs)
    if kind == EV_STRIKE:
        return strike_speed(y, M, D, cs, ev_idx[e], W.contact_pts, True) - M.pair_par[ev_idx[e], R_VTHR]
    if kind == EV_PRESS:  # deeper than the allowance by the arming distance
        return pair_depth(y, M, D, cs, ev_idx[e], W.contact_pts) - M.pair_par[ev_idx[e], R_ARM]
    g = pair_gap(y, M, cs, ev_idx[e])
    if kind == EV_GAP:
        return g
    # EV_ARM
    return g - M.pair_par[ev_idx[e], R_ARM]


@njit(**HOT)
def event_rate(e, y, M, ev, W):
    """Bound on ``|d(event value)/dt|`` of a distance-like event at ``y`` [m/s] (0 for the others).

    Zones: the fastest wheel; pairs: ``|v_A - v_B| + |w_A| R_A + |w_B| R_B`` with ``R`` the
    largest bounding-circle reach of each body's pieces.  A step along which the value could
    change sign twice (``min(|g_start|, |g_end|) < rate x step``) is searched on its dense output.
    """
    kind = ev.kind[e]
    nb = M.body.shape[0]
    if kind == EV_ZONE:
        cs = W.trig
        body_trig(y, nb, cs)
        v = 0.0
        for k in range(M.wheel.shape[0]):
            vx, vy = wheel_velocity(y, M, k, cs)
            v = max(v, math.sqrt(vx * vx + vy * vy))
        return v
    if kind == EV_GAP or kind == EV_ARM or kind == EV_PRESS:
        pr_body, pr_ptr, pp, pc_info = M.pair_body, M.pair_ptr, M.piece_pairs, M.piece_info
        p = ev.idx[e]
        ia = pr_body[p, 0]
        ib = pr_body[p, 1]
        ra = 0.0
        rb = 0.0
        for q in range(pr_ptr[p], pr_ptr[p + 1]):
            a = pp[q, 0]
            ra = max(ra, math.sqrt(pc_info[a, 0] ** 2 + pc_info[a, 1] ** 2) + pc_info[a, 2])
            if ib >= 0:
                b = pp[q, 1]
                rb = max(rb, math.sqrt(pc_info[b, 0] ** 2 + pc_info[b, 1] ** 2) + pc_info[b, 2])
        dvx = y[SV_VX * nb + ia]
        dvy = y[SV_VY * nb + ia]
        rot = abs(y[SV_YAW_RATE * nb + ia]) * ra
        if ib >= 0:
            dvx -= y[SV_VX * nb + ib]
            dvy -= y[SV_VY * nb + ib]
            rot += abs(y[SV_YAW_RATE * nb + ib]) * rb
        return math.sqrt(dvx * dvx + dvy * dvy) + rot
    return 0.0


@njit(**HOT)
def event_resolution(e, M, ev):
    """Finest feature [m] a distance-like event must not step over (0 for the others)."""
    kind = ev.kind[e]
    if kind == EV_ZONE:
        return M.cfg[C_ZRES]
    if kind == EV_GAP or kind == EV_ARM or kind == EV_PRESS:
        return M.pair_par[ev.idx[e], R_RES]
    return 0.0


@njit(**HOT)
def interpolate(t, t_old, h, y_old, Q, out):
    """Dense output of one step at time ``t``: ``y_old + h Q [x, x^2, ...]``, ``x = (t - t_old)/h``."""
    x = (t - t_old) / h
    n = y_old.shape[0]
    deg = Q.shape[1]
    for i in range(n):
        s = 0.0
        p = 1.0
        for j in range(deg):
            p *= x
            s += Q[i, j] * p
        out[i] = y_old[i] + h * s


@njit(**HOT)
def event_on_step(e, tq, step, M, ev, D, sw, dydt, W):
    """Value of event ``e`` at time ``tq`` on the dense output of ``step`` (:class:`Step`; the
    state goes to ``step.ytmp``)."""
    interpolate(tq, step.t_old, step.h, step.y_old, step.Q, step.ytmp)
    return event_value(e, step.ytmp, M, ev, D, sw, dydt, W)


@njit(**HOT)
def brent(e, ta, tb, fa, fb, step, M, ev, D, sw, dydt, W):
    """Root of event ``e`` on a step's dense output in [ta, tb], values fa, fb: Brent's method as scipy's brentq.

    Tolerances ``xtol = rtol = 4 eps`` as solve_ivp's event location.  If the values do not
    differ in sign (round-off at a root on the interval end), the interval end is returned.  The
    root returned lies on the crossed side (the sign of ``fb``): of the last bracket, the end whose
    value has crossed, so that the event's handler sees the state past it (at a jump of the value,
    a point arriving or a normal turning, the state just before it has nothing to handle).
    """
    xtol = 4.0 * EPS
    rtol = 4.0 * EPS
    xpre = ta
    xcur = tb
    fpre = fa
    fcur = fb
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    if (fpre < 0.0) == (fcur < 0.0):
        return tb
    xblk = 0.0
    fblk = 0.0
    spre = 0.0
    scur = 0.0
    for _ in range(100):
        if fpre != 0.0 and fcur != 0.0 and ((fpre < 0.0) != (fcur < 0.0)):
            xblk = xpre
            fblk = fpre
            spre = xcur - xpre
            scur = spre
        if abs(fblk) < abs(fcur):
            xpre = xcur
            xcur = xblk
            xblk = xpre
            fpre = fcur
            fcur = fblk
            fblk = fpre
        delta = (xtol + rtol * abs(xcur)) / 2.0
        sbis = (xblk - xcur) / 2.0
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur if fcur == 0.0 or (fcur < 0.0) == (fb < 0.0) else xblk
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2.0 * abs(stry) < min(abs(spre), 3.0 * abs(sbis) - delta):
                spre = scur
                scur = stry
            else:
                spre = sbis
                scur = sbis
        else:
            spre = sbis
            scur = sbis
        xpre = xcur
        fpre = fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = event_on_step(e, xcur, step, M, ev, D, sw, dydt, W)
    return xcur


@njit(**INLINE)
def crosses(g0, g1, direction):
    return (direction > 0 and g0 <= 0.0 and g1 >= 0.0) or (direction < 0 and g0 >= 0.0 and g1 <= 0.0)


@njit(**HOT)
def first_root(step, t_new, M, ev, n_ev, vals, D, sw, dydt, W):
    """Earliest event of a step [t, t_new] (``step``: :class:`Step` from ``t``): ``(root time,
    event)``, event -1 if none.  ``vals`` (:class:`EventValues`) holds the values and rate
    bounds of the ``n_ev`` events at both ends of the step.

    An event fires where its value crosses zero in its direction.  For distance-like events
    (zones, contact gaps) a step long enough for the value to cross and cross back
    (``min(|g_old|, |g_new|) < rate x h``, with the larger of the rates at the two ends) is
    also searched at points of its dense output no further apart than the event's resolution
    (at most ``MAX_SUBSAMPLES``): a wheel cannot step over the corner of a zone, nor a body
    through a thin obstacle, by a step longer than the feature.  Once an event has a root, the
    others are searched up to that root (a sub-interval that reaches past it is cut there, so a
    crossing just before it is not skipped).  The root is located by Brent's method on the dense
    output.
    """
    t = step.t_old
    h = step.h
    t_first = math.inf
    fired = -1
    for e in range(n_ev):
        a = vals.g_old[e]
        b = vals.g_new[e]
        d = ev.dir[e]
        reach = max(vals.r_old[e], vals.r_new[e]) * 1.5 * h
        if reach > 0.0 and min(abs(a), abs(b)) < reach:
            res = event_resolution(e, M, ev)
            n_sub = min(MAX_SUBSAMPLES, max(1, int(math.ceil(reach / max(res, 1e-9)))))
        else:
            n_sub = 1
        ta = t
        fa = a
        for k in range(1, n_sub + 1):
            last = k == n_sub
            if last:
                tb = t_new
                fb = b
            else:
                tb = t + (t_new - t) * k / n_sub
                if tb >= t_first:  # an earlier event fires at t_first: search up to it, not past it
                    tb = t_first
                    last = True
                fb = event_on_step(e, tb, step, M, ev, D, sw, dydt, W)
            if crosses(fa, fb, d):
                root = brent(e, ta, tb, fa, fb, step, M, ev, D, sw, dydt, W)
                if root < t_first:
                    t_first = root
                    fired = e
                break
            if last:
                break
            ta = tb
            fa = fb
    return t_first, fired


@njit(**HOT)
def build_events(M, D, offsets, ev):
    """The events of a segment in mode ``D`` (filled in place into ``ev``, :class:`Events`);
    returns their number.

    Order: the rest of every moving vehicle, every zone, the stops of every hitch that has a
    limit and is not closed (each side), the release of every closed stop, then per pair the
    gap (armed), the arming distance (disarmed or in contact), the press (disarmed) and the
    strike (disarmed or in contact: a point pressed beyond the allowance closing at the
    impulse threshold or faster, less what its depth holds, :func:`strike_speed`).
    """
    hitch, zone_mu, pr_par, pr_body = M.hitch, M.zone_mu, M.pair_par, M.pair_body
    lk_j, lk_th, nlk, shift, pstate, parked = D.lk_j, D.lk_th, D.lk_n[0], D.shift, D.pstate, D.parked
    ev_kind, ev_idx, ev_val, ev_dir = ev.kind, ev.idx, ev.val, ev.dir
    n_ev = 0
    for v in range(parked.shape[0]):
        if parked[v] == 0:
            ev_kind[n_ev] = EV_REST
            ev_idx[n_ev] = v
            ev_dir[n_ev] = -1.0
            n_ev += 1
    for z in range(zone_mu.shape[0]):
        ev_kind[n_ev] = EV_ZONE
        ev_idx[n_ev] = z
        ev_dir[n_ev] = -1.0
        n_ev += 1
    for j in range(hitch.shape[0]):
        lim = hitch[j, 4]
        locked_j = False
        for q in range(nlk):
            if lk_j[q] == j:
                locked_j = True
        if math.isnan(lim) or locked_j:
            continue
        ev_kind[n_ev] = EV_STOP
        ev_idx[n_ev] = j
        ev_val[n_ev] = offsets[j] + lim + shift[j]
        ev_dir[n_ev] = 1.0
        n_ev += 1
        ev_kind[n_ev] = EV_STOP
        ev_idx[n_ev] = j
        ev_val[n_ev] = offsets[j] - lim - shift[j]
        ev_dir[n_ev] = -1.0
        n_ev += 1
    for q in range(nlk):
        ev_kind[n_ev] = EV_RELEASE
        ev_idx[n_ev] = q
        ev_val[n_ev] = math.copysign(1.0, lk_th[q] - offsets[lk_j[q]])
        ev_dir[n_ev] = 1.0
        n_ev += 1
    for p in range(pr_body.shape[0]):
        if pstate[p] == PS_ARMED:
            ev_kind[n_ev] = EV_GAP
            ev_idx[n_ev] = p
            ev_dir[n_ev] = -1.0
            n_ev += 1
        else:
            ev_kind[n_ev] = EV_ARM
            ev_idx[n_ev] = p
            ev_dir[n_ev] = 1.0
            n_ev += 1
        if pstate[p] == PS_DISARMED:
            ev_kind[n_ev] = EV_PRESS
            ev_idx[n_ev] = p
            ev_val[n_ev] = pr_par[p, R_ARM]
            ev_dir[n_ev] = 1.0
            n_ev += 1
        if pstate[p] != PS_ARMED:
            ev_kind[n_ev] = EV_STRIKE
            ev_idx[n_ev] = p
            ev_dir[n_ev] = 1.0
            n_ev += 1
    return n_ev


@njit(**INLINE)
def log_record(rec, n, kind, i, j, x, e):
    rec[n, 0] = kind
    rec[n, 1] = i
    rec[n, 2] = j
    rec[n, 3] = x
    rec[n, 4] = e
    return n + 1


@njit(**HOT)
def left_stop_shift(y, M, j, offset, lim, shift):
    """Raised threshold of the stop of hitch ``j`` when it is left: past where it was left, plus STOP_HYSTERESIS."""
    nb = M.body.shape[0]
    hbody = M.hitch_body
    excess = abs(y[SV_HEADING * nb + hbody[j, 0]] - y[SV_HEADING * nb + hbody[j, 1]] - offset) - lim
    return max(shift, excess) + STOP_HYSTERESIS


@njit(**HOT)
def handle_event(e, t, y, M, D, offsets, ev, sw, dydt, W, rec, geo):
    """Apply event ``e`` of the segment at state ``y`` (changed in place, with the mode ``D``).

    Log records go to ``rec`` (rows: kind, i, j, x, energy).  Returns ``(impact, n_records)``:
    ``impact`` is True when a touch needs an impulse (``geo`` then holds the pair, point,
    normal and approach speed: ``(p, x, y, nx, ny, u_n)``), which the caller solves with the
    impact solver (Python) before the run goes on.  Rest and zone events change nothing here:
    :func:`settle` updates zone membership and parks other resting vehicles after every event.
    """
    kind = ev.kind[e]
    idx = ev.idx[e]
    hitch, pr_par = M.hitch, M.pair_par
    lk_j, lk_th, lk_n, shift, pstate, pref = D.lk_j, D.lk_th, D.lk_n, D.shift, D.pstate, D.pref
    nh = hitch.shape[0]
    n = 0
    if kind == EV_REST:
        # the event says the vehicle and its contact partners are at rest (located to round-off
        # either side of v_stop): park them
        v_stop = M.cfg[C_VSTOP] * (1.0 + 1e-9)
        parked = D.parked
        if parked[idx] == 0:
            n = try_park(idx, y, M, D, rec, n)
        mask = contact_group(M, D, idx)
        for w in range(parked.shape[0]):
            if parked[w] == 0 and parked[idx] != 0 and (mask >> w) & 1 and rest_measure(y, M, w) <= v_stop:
                n = try_park(w, y, M, D, rec, n)
        return False, n
    if kind == EV_STOP:
        # plastic impact at the stop, then close it unless the bodies separate
        j = idx
        side = ev.dir[e]
        lim = hitch[j, 4]
        nlk = lk_n[0]
        theta_lock = side * lim + offsets[j]
        lk_j[nlk] = j
        lk_th[nlk] = theta_lock
        ke_before = kinetic_energy(y, M)
        project_velocities(y, M, lk_j, lk_th, nlk + 1, W.jacobian, W.gram, W.multipliers, W.trig)
        loss = ke_before - kinetic_energy(y, M)
        lk_n[0] = nlk + 1
        evaluate(y, M, sw, D, dydt, W)
        lam_last = W.multipliers[2 * nh + nlk]
        if lam_last * side <= 0:
            n = log_record(rec, n, LOG_STOP_CLOSED, j, 0, side * lim, loss)
        else:
            lk_n[0] = nlk
            shift[j] = left_stop_shift(y, M, j, offsets[j], lim, shift[j])
            n = log_record(rec, n, LOG_STOP_IMPACT, j, 0, side * lim, loss)
        # the stop impact changed velocities: a point in contact may now strike
        return find_strike(y, M, D, W.trig, W.contact_pts, geo), n
    if kind == EV_RELEASE:
        q0 = idx
        jq = lk_j[q0]
        n = log_record(rec, n, LOG_STOP_OPEN, jq, 0, 0.0, 0.0)
        shift[jq] = left_stop_shift(y, M, jq, offsets[jq], hitch[jq, 4], shift[jq])
        nlk = lk_n[0]
        for q in range(q0, nlk - 1):
            lk_j[q] = lk_j[q + 1]
            lk_th[q] = lk_th[q + 1]
        lk_n[0] = nlk - 1
        return False, n
    if kind == EV_GAP:
        p = idx
        cs = W.trig
        body_trig(y, M.body.shape[0], cs)
        found = touch_geometry(y, M, D, p, cs, W.contact_pts, geo[1:])
        geo[0] = p
        if found and geo[5] < -pr_par[p, R_VTHR]:
            return True, n
        pstate[p] = PS_CONTACT
        for c in range(N_A):
            pref[p, c] = 0.0
        unpark_pair(M, D, p)
        n = log_record(rec, n, LOG_CONTACT, p, 0, geo[5] if found else 0.0, 0.0)
        # slow at the middle of the touching edge, but one end may strike (a turning edge)
        return strike_geometry(y, M, D, cs, p, W.contact_pts, geo[1:]), n
    if kind == EV_STRIKE:
        p = idx
        cs = W.trig
        body_trig(y, M.body.shape[0], cs)
        geo[0] = p
        return strike_geometry(y, M, D, cs, p, W.contact_pts, geo[1:]), n
    if kind == EV_ARM:
        p = idx
        was = pstate[p]
        pstate[p] = PS_ARMED
        for c in range(N_A):  # apart: the crush of the first impact is behind the pair
            pref[p, c] = 0.0
        n = log_record(rec, n, LOG_CONTACT_END if was == PS_CONTACT else LOG_ARMED, p, 0, 0.0, 0.0)
        return False, n
    if kind == EV_PRESS:
        # pressed the arming distance beyond the crush of the first impact: sustained contact, its force
        # from zero at this configuration (every point's allowance is how deep it lies now: the bodies'
        # poses now are the allowance's reference), in which a point driven in faster than its depth
        # holds strikes like any other; one pressing on at the threshold now is an impact at once
        p = idx
        cs = W.trig
        body_trig(y, M.body.shape[0], cs)
        n = log_record(rec, n, LOG_PRESS, p, 0, pair_depth(y, M, D, cs, p, W.contact_pts), 0.0)
        pstate[p] = PS_CONTACT
        set_reference(y, M, D, p)
        unpark_pair(M, D, p)
        geo[0] = p
        hit = strike_geometry(y, M, D, cs, p, W.contact_pts, geo[1:])
        if hit:  # the impact of this instant is the crush going on (e = 0 at its points)
            pref[p, A_CRUSH] = PRESSED
        return hit, n
    return False, n


@njit(**HOT)
def try_park(v, y, M, D, rec, n):
    """Park vehicle ``v`` (freeze its bodies) unless it is in contact with a body of another
    vehicle that still moves faster than v_stop; returns the number of log records."""
    pstate, parked = D.pstate, D.parked
    bveh, pr_body, cfg = M.body_vehicle, M.pair_body, M.cfg
    v_stop = cfg[C_VSTOP] * (1.0 + 1e-9)
    for p in range(pr_body.shape[0]):
        if pstate[p] != PS_CONTACT or pr_body[p, 1] < 0:
            continue
        va = bveh[pr_body[p, 0]]
        vb = bveh[pr_body[p, 1]]
        other = vb if va == v else (va if vb == v else -1)
        if other >= 0 and other != v and parked[other] == 0 and rest_measure(y, M, other) > v_stop:
            return n
    parked[v] = 1
    return log_record(rec, n, LOG_REST, v, 0, 0.0, 0.0)


@njit(**HOT)
def settle(y, M, D, new_memb, W, rec, n):
    """After an event or a scheduled change: new zone membership (logged wheel by wheel) and
    parking of the vehicles that came to rest (logged).  Returns the number of records.

    A vehicle parks (its bodies freeze) when its rest measure is at most v_stop (to a relative
    1e-9: a rest event is located to round-off on either side of v_stop), unless it is in
    contact with a body of another vehicle that still moves faster than that.
    """
    memb, parked = D.memb, D.parked
    cfg = M.cfg
    nw = M.wheel.shape[0]
    nz = M.zone_mu.shape[0]
    if nz > 0:
        membership(y, M, new_memb, W.trig)
        for k in range(nw):
            for z in range(nz):
                if new_memb[k, z] != memb[k, z]:
                    n = log_record(rec, n, LOG_ZONE_ENTER if new_memb[k, z] else LOG_ZONE_EXIT, k, z, 0.0, 0.0)
                    memb[k, z] = new_memb[k, z]
    v_stop = cfg[C_VSTOP] * (1.0 + 1e-9)
    for v in range(parked.shape[0]):
        if parked[v] == 0 and rest_measure(y, M, v) <= v_stop:
            n = try_park(v, y, M, D, rec, n)
    return n


@njit(**JIT)
def release_stop(y, M, D, offsets, q):
    """Open closed stop ``q`` (its entry in ``D.lk_j``) at state ``y``: removed from the closed stops,
    its threshold raised past where it was left (:func:`left_stop_shift`); returns its hitch."""
    lk_j, lk_th, lk_n, shift = D.lk_j, D.lk_th, D.lk_n, D.shift
    j = lk_j[q]
    shift[j] = left_stop_shift(y, M, j, offsets[j], M.hitch[j, 4], shift[j])
    for r in range(q, lk_n[0] - 1):
        lk_j[r] = lk_j[r + 1]
        lk_th[r] = lk_th[r + 1]
    lk_n[0] -= 1
    return j


@njit(**JIT)
def settle_at(y, M, D):
    """:func:`settle` on its own (the start of a run, after an impulse); returns the log records."""
    W = make_work(M)
    rec = np.zeros((M.wheel.shape[0] * max(M.zone_mu.shape[0], 1) + D.parked.shape[0] + 8, 5))
    n = settle(y, M, D, np.zeros((M.wheel.shape[0], M.zone_mu.shape[0]), np.bool_), W, rec, 0)
    return rec[:n]

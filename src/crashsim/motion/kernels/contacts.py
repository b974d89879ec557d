"""Kernel stage: contact between bodies (and with fixed obstacles).

Penalty forces of pairs in sustained contact, the touch geometry at a gap event, the
strike scan (closing speeds of points pressed beyond the allowance) and the crush circle
of the first impact set at arming (package docstring: gap, manifold, states, strikes).
"""

from __future__ import annotations

import math

from numba import njit

from .jit import HOT, INLINE, JIT
from .arrays import (A_CX, A_CY, A_DEPTH, A_R, CRUSH_REACH, C_EPS, N_A, PS_ARMED, PS_CONTACT, PS_DISARMED, R_ARM,
    R_C, R_K, R_MU, R_VTHR, make_work)
from .geometry import body_trig, deepest_pieces, manifold, pair_gap, piece_gap, point_velocity


@njit(**INLINE)
def in_crush(y, M, D, cs, p, ia, px, py):
    """Whether the world point (px, py) lies in pair ``p``'s crush circle (body ``ia``'s axes)."""
    nb = M.body.shape[0]
    dx = px - y[ia]
    dy = py - y[nb + ia]
    lx = cs[0, ia] * dx + cs[1, ia] * dy - D.pref[p, A_CX]
    ly = -cs[1, ia] * dx + cs[0, ia] * dy - D.pref[p, A_CY]
    return lx * lx + ly * ly <= D.pref[p, A_R] * D.pref[p, A_R]


@njit(**HOT)
def pair_forces(y, M, D, cs, p, f, mf, fc):
    """Penalty forces of pair ``p`` (in contact) added to the world-frame body forces ``f`` (z order),
    and their x, y components to the contact share ``fc`` (2 nb: x.., y..) for the load transfer.

    Sustained contact as the README states it ("Contact model"; package docstring, "States"):
    at each manifold point ``F_n = max(0, k e + c e')`` on the depth ``e`` beyond the
    allowance, with Coulomb friction ``mu_c F_n`` against the tangential slip, regularised
    like the tyres (``v_t / sqrt(v_t^2 + eps^2)``).  A receives the force at each manifold point, B minus it; an obstacle receives nothing.
    ``cs`` holds the bodies' heading cosines and sines, ``mf`` (2, 3) is scratch for the
    manifold.  Returns the power of the forces on the bodies [W] (their work on the system:
    dissipation by the damper and the friction, and the spring's change of stored energy).
    The bodies of parked vehicles count as still.  The depth allowance applies within the
    pair's crush circle (the crush of the first impact); elsewhere the depth counts from the
    surface, as for any other contact.
    """
    pr_body, pr_ptr, pp, pr_par, cfg = M.pair_body, M.pair_ptr, M.piece_pairs, M.pair_par, M.cfg
    nb = M.body.shape[0]
    eps = cfg[C_EPS]
    ia = pr_body[p, 0]
    ib = pr_body[p, 1]
    k = pr_par[p, R_K]
    c = pr_par[p, R_C]
    mu = pr_par[p, R_MU]
    crush = D.pref[p, A_DEPTH]
    radius = D.pref[p, A_R]
    least = 0.0 if radius > 0.0 else crush  # the smallest allowance of any point
    # a parked body does not move: its frozen velocity (<= v_stop) neither damps nor does work
    bveh, parked = M.body_vehicle, D.parked
    still_a = parked[bveh[ia]] != 0
    still_b = ib >= 0 and parked[bveh[ib]] != 0
    power = 0.0
    for q in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[q, 0]
        b = pp[q, 1]
        if piece_gap(y, M, cs, a, b) >= -least:
            continue
        count, nx, ny = manifold(y, M, cs, a, b, mf, 0.0)
        for m in range(count):
            px = mf[m, 0]
            py = mf[m, 1]
            allowance = crush
            if radius > 0.0 and not in_crush(y, M, D, cs, p, ia, px, py):
                allowance = 0.0
            depth = mf[m, 2] - allowance
            if depth <= 0.0:
                continue
            vax, vay = (0.0, 0.0) if still_a else point_velocity(y, M, ia, px, py)
            vbx, vby = (0.0, 0.0) if still_b else point_velocity(y, M, ib, px, py)
            rvx = vax - vbx
            rvy = vay - vby
            rate = -(rvx * nx + rvy * ny)  # penetration rate
            fn = k * depth + c * rate
            if fn <= 0.0:
                continue
            tx = -ny
            ty = nx
            vt = rvx * tx + rvy * ty
            ft = -mu * fn * vt / math.sqrt(vt * vt + eps * eps)
            fx = fn * nx + ft * tx
            fy = fn * ny + ft * ty
            power += fx * rvx + fy * rvy
            f[ia] += fx
            f[nb + ia] += fy
            f[2 * nb + ia] += (px - y[ia]) * fy - (py - y[nb + ia]) * fx
            fc[ia] += fx
            fc[nb + ia] += fy
            if ib >= 0:
                f[ib] -= fx
                f[nb + ib] -= fy
                f[2 * nb + ib] -= (px - y[ib]) * fy - (py - y[nb + ib]) * fx
                fc[ib] -= fx
                fc[nb + ib] -= fy
    return power


@njit(**HOT)
def contact_forces(y, M, D, cs, f, pf, mf, fc):
    """Penalty forces of every pair in contact added to ``f``; ``pf[p]`` their power [W]; ``fc`` (2 nb)
    their world-frame x, y sums per body alone [N] (:func:`pair_forces`)."""
    pstate = D.pstate
    for i in range(fc.shape[0]):
        fc[i] = 0.0
    for p in range(M.pair_body.shape[0]):
        pf[p] = pair_forces(y, M, D, cs, p, f, mf, fc) if pstate[p] == PS_CONTACT else 0.0


@njit(**HOT)
def touch_geometry(y, M, p, cs, mf, geo):
    """Contact point, normal (from B into A) and normal relative velocity of pair ``p`` at a touch.

    The piece pair of least gap gives the manifold (points within 1 mm of touching); the point
    is the mean of its points (the middle of an edge-on contact).  ``geo`` receives
    ``(x, y, nx, ny, u_n)``, ``u_n = (v_A - v_B) . n`` at the point (< 0: approaching).
    Returns False if no manifold point was found (a touch at a vertex, numerically).
    """
    pr_body = M.pair_body
    best, qa, qb = deepest_pieces(y, M, cs, p)
    count, nx, ny = manifold(y, M, cs, qa, qb, mf, max(1e-3, -best + 1e-3))
    if count == 0:
        return False
    px = 0.0
    py = 0.0
    for m in range(count):
        px += mf[m, 0] / count
        py += mf[m, 1] / count
    put_geometry(y, M, pr_body[p, 0], pr_body[p, 1], px, py, nx, ny, geo)
    return True


@njit(**INLINE)
def put_geometry(y, M, ia, ib, px, py, nx, ny, geo):
    """``geo`` = (x, y, nx, ny, u_n) of a contact at (px, py) with normal n from B into A:
    ``u_n = (v_A - v_B) . n`` of the material points there (< 0: approaching)."""
    vax, vay = point_velocity(y, M, ia, px, py)
    vbx, vby = point_velocity(y, M, ib, px, py)
    geo[0] = px
    geo[1] = py
    geo[2] = nx
    geo[3] = ny
    geo[4] = (vax - vbx) * nx + (vay - vby) * ny


@njit(**HOT)
def strike_scan(y, M, D, cs, p, mf, margin, floor, geo, crush):
    """Closing speeds of the manifold points of pair ``p`` pressed into each other beyond their
    allowance (to within ``margin`` [m]).

    The allowance of a point: within the pair's crush circle (the crush of the first impact,
    :data:`CRUSH_REACH`) the pair's depth allowance, and while the pair is still disarmed such a
    point is left out altogether (pressing on into the crush is the first impact's crush going
    on: a press into sustained contact, not a new impact); elsewhere, for a pair with a crush
    circle, 0 (a point that meets the other body anew strikes from the surface); for any other
    pair its depth allowance.  ``crush`` False leaves out the points within the circle in every
    state (the audit of :func:`contact_samples`).

    Returns the largest closing speed ``-(v_A - v_B) . n`` [m/s] of those points (``-inf`` if
    none).  With ``floor`` finite, ``geo`` receives ``(x, y, nx, ny, u_n)`` of the piece pair
    whose point closes fastest: the mean of its points closing at ``floor`` or faster, the
    normal from B into A and the normal relative velocity at that mean point.
    """
    pr_body, pr_ptr, pp = M.pair_body, M.pair_ptr, M.piece_pairs
    ia = pr_body[p, 0]
    ib = pr_body[p, 1]
    depth_allowance = D.pref[p, A_DEPTH]
    radius = D.pref[p, A_R]
    disarmed = D.pstate[p] == PS_DISARMED
    least = 0.0 if radius > 0.0 else depth_allowance  # the smallest allowance of any point
    best = -math.inf
    for q in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[q, 0]
        b = pp[q, 1]
        if piece_gap(y, M, cs, a, b) > margin - least:
            continue
        count, nx, ny = manifold(y, M, cs, a, b, mf, margin - least)
        fastest = -math.inf
        sx = 0.0
        sy = 0.0
        n_fast = 0
        for m in range(count):
            px = mf[m, 0]
            py = mf[m, 1]
            allowance = depth_allowance
            if radius > 0.0:
                if in_crush(y, M, D, cs, p, ia, px, py):
                    if disarmed or not crush:
                        continue
                else:
                    allowance = 0.0
            if mf[m, 2] - allowance < -margin:
                continue
            vax, vay = point_velocity(y, M, ia, px, py)
            vbx, vby = point_velocity(y, M, ib, px, py)
            closing = -((vax - vbx) * nx + (vay - vby) * ny)
            if closing > fastest:
                fastest = closing
            if closing >= floor:
                sx += px
                sy += py
                n_fast += 1
        if fastest > best:
            best = fastest
            if n_fast > 0:
                put_geometry(y, M, ia, ib, sx / n_fast, sy / n_fast, nx, ny, geo)
    return best


@njit(**HOT)
def strike_speed(y, M, D, cs, p, mf, crush):
    """Largest closing speed [m/s] of the points of pair ``p`` pressed beyond its allowance
    (0 if none: a pair apart, or only in its crush allowance, does not strike).

    The strike event of a pair in sustained contact or disarmed is this minus the impulse
    threshold: it crosses zero when a point arrives at the surface (or beyond the crush of the
    first impact) closing at the threshold or faster (the value jumps there; the root is the
    arrival), or when a point already in contact is driven in that fast.  Either is an impact.
    """
    # an infinite floor writes no geometry (mf[0] only stands in for the unused argument)
    best = strike_scan(y, M, D, cs, p, mf, 0.0, math.inf, mf[0], crush)
    return best if best > 0.0 else 0.0


@njit(**HOT)
def strike_geometry(y, M, D, cs, p, mf, geo):
    """Contact point, normal and normal relative velocity of a strike of pair ``p`` (``geo`` as
    :func:`touch_geometry`), at a state where :func:`strike_speed` reaches the threshold.

    The points count that lie within 1 mm of the surface (the root of a jump is located to
    round-off on either side of the arrival) and close at the threshold or faster (to a
    relative 1e-6); the point is their mean in the piece pair of the fastest.  Returns False
    if no point closes that fast.
    """
    thr = M.pair_par[p, R_VTHR]
    floor = thr * (1.0 - 1e-6)
    geo[4] = 0.0
    best = strike_scan(y, M, D, cs, p, mf, 1e-3, floor, geo, True)
    return best >= floor and geo[4] < 0.0


@njit(**HOT)
def find_strike(y, M, D, cs, mf, geo):
    """The pair in sustained contact or disarmed whose points close fastest beyond its impulse
    threshold at ``y`` (after a velocity jump: an impulse, an articulation-stop impact), with
    its strike geometry in ``geo`` = (pair, x, y, nx, ny, u_n); False if none.

    An impulse at one point can leave another point of the same pair, or a pair of the bodies
    it moved, striking at that instant: each is an impact of its own."""
    pstate, pr_par = D.pstate, M.pair_par
    best = -math.inf
    hit = -1
    for p in range(pr_par.shape[0]):
        if pstate[p] == PS_ARMED or not strike_geometry(y, M, D, cs, p, mf, geo[1:]):
            continue
        excess = -geo[5] - pr_par[p, R_VTHR]
        if excess > best:
            best = excess
            hit = p
    if hit < 0:
        return False
    geo[0] = hit
    return strike_geometry(y, M, D, cs, hit, mf, geo[1:])


@njit(**HOT)
def unpark_pair(M, D, p):
    """Both vehicles of pair ``p`` move again (a contact force or an impulse acts on them)."""
    pr_body, bveh = M.pair_body, M.body_vehicle
    parked = D.parked
    parked[bveh[pr_body[p, 0]]] = 0
    if pr_body[p, 1] >= 0:
        parked[bveh[pr_body[p, 1]]] = 0


@njit(**JIT)
def arming(y, M, D):
    """Initial contact states: a pair closer than its arming distance (the crush of the impact,
    or bodies left touching) starts disarmed with its present depth as allowance and its crush
    circle (in body A's axes: around the contact points of its deepest pieces, reaching
    :data:`CRUSH_REACH` beyond them); the others armed."""
    pr_body, pr_par = M.pair_body, M.pair_par
    pstate, pref = D.pstate, D.pref
    W = make_work(M)
    cs = W.trig
    mf = W.manifold_pts
    nb = M.body.shape[0]
    body_trig(y, nb, cs)
    for p in range(pr_body.shape[0]):
        g = pair_gap(y, M, cs, p)
        for c in range(N_A):
            pref[p, c] = 0.0
        if g < pr_par[p, R_ARM]:
            pstate[p] = PS_DISARMED
            pref[p, A_DEPTH] = max(-g, 0.0)
            _, qa, qb = deepest_pieces(y, M, cs, p)
            count, _, _ = manifold(y, M, cs, qa, qb, mf, pr_par[p, R_ARM])
            if count == 0:
                continue
            ia = pr_body[p, 0]
            cx = 0.0
            cy = 0.0
            for m in range(count):
                cx += mf[m, 0] / count
                cy += mf[m, 1] / count
            spread = 0.0
            for m in range(count):
                spread = max(spread, math.sqrt((mf[m, 0] - cx) ** 2 + (mf[m, 1] - cy) ** 2))
            dx = cx - y[ia]
            dy = cy - y[nb + ia]
            pref[p, A_CX] = cs[0, ia] * dx + cs[1, ia] * dy
            pref[p, A_CY] = -cs[1, ia] * dx + cs[0, ia] * dy
            pref[p, A_R] = spread + pref[p, A_DEPTH] + CRUSH_REACH
        else:
            pstate[p] = PS_ARMED

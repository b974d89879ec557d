"""Kernel stage: contact between bodies (and with fixed obstacles).

The contact points of two convex pieces, the crush allowance of the first impact, penalty forces
of pairs in sustained contact, the touch geometry at a gap event, the strike scan (closing speeds
of points pressed beyond the allowance), the contact points of a simultaneous impact, and the
initial contact states (package docstring: gap, contact points, states, strikes).
"""

from __future__ import annotations

import math

from numba import njit

from ..layout import SV_X, SV_Y, SV_HEADING
from .jit import HOT, INLINE, JIT
from .arrays import (A_CRUSH, A_PA, A_PB, A_XA, A_XB, A_YA, A_YB, C_EPS, CRUSH_REACH, DAMPER_DEPTH, N_A, N_Q,
    PS_ARMED, PS_CONTACT, PS_DISARMED, Q_ALLOW, Q_CRUSH, Q_DEPTH, Q_NX, Q_NY, Q_X, Q_Y, R_ARM, R_C, R_K, R_MU,
    R_OMEGA, R_VTHR, ROW_MARGIN, make_work)
from .geometry import (body_trig, deepest_pieces, inside_depth, manifold, max_separation, pair_gap, piece_gap,
    piece_vertex, point_velocity)



@njit(**INLINE)
def body_pose(y, M, cs, i):
    """Pose ``(x, y, cos, sin)`` of body ``i`` in state ``y`` (an obstacle, ``i < 0``: the world's)."""
    if i < 0:
        return 0.0, 0.0, 1.0, 0.0
    nb = M.body.shape[0]
    return y[SV_X * nb + i], y[SV_Y * nb + i], cs[0, i], cs[1, i]


@njit(**INLINE)
def start_pose(M, pr, p, i):
    """Pose ``(x, y, cos, sin)`` of body ``i`` of pair ``p`` when the run-out started, from the pair's
    allowance row ``pr`` (an obstacle: the world's)."""
    if i < 0:
        return 0.0, 0.0, 1.0, 0.0
    c = A_XA if i == M.pair_body[p, 0] else A_XB
    return pr[c], pr[c + 1], math.cos(pr[c + 2]), math.sin(pr[c + 2])


@njit(**HOT)
def piece_points(y, M, pr, cs, p, a, b, margin, out):
    """The contact points of pieces ``a`` (of pair ``p``'s body A) and ``b`` (of body B or an obstacle)
    beyond their allowance, to within ``margin`` [m] of touching (``pr``: the pair's row of
    ``Mode.pref``).

    * A pair without a crush allowance (apart at the start of the run-out, or armed since): the
      Box2D-style manifold (:func:`~crashsim.motion.kernels.geometry.manifold`): the incident edge
      clipped to the reference face, up to two points, the normal of that face.
    * A pair with one (its outlines overlapped or lay within the arming distance at the start, the
      crush of the first impact; or it was pressed on beyond it): every vertex of either piece inside
      the other (a deep overlap has no meaningful manifold: its reference face flips and its points
      jump).  A vertex lies ``d`` deep in the other piece (the distance to its boundary; the normal
      that of the nearest face, or of the pieces' separating axis where that face is as near to within
      :data:`ROW_MARGIN`); its allowance ``d0`` is how deep that material vertex lay in the other piece
      in the poses of the allowance (``pr``), and the depth beyond it is ``d - d0``: a crushed corner
      may lie as deep again without a force, wherever it slides (a car's corner along a barrier, a
      trailer's in the pocket it crushed into a car).  Both are functions of the configuration, so the
      penalty ``k max(0, d - d0)`` at each vertex derives from a potential (its force along the
      gradient of ``d``): no contact makes energy, and no point springs out of the crush.

    ``out`` (rows, N_Q) receives ``Q_*`` columns (the depth beyond the allowance, the allowance, and
    the crush flag: the vertex's material point lay inside the other piece at the start, or within
    :data:`CRUSH_REACH` of it); returns the number of points.
    """
    if pr[A_CRUSH] == 0.0:
        count, nx, ny = manifold(y, M, cs, a, b, out, margin)
        for m in range(count):
            depth = out[m, 2]
            out[m, Q_NX] = nx
            out[m, Q_NY] = ny
            out[m, Q_DEPTH] = depth
            out[m, Q_ALLOW] = 0.0
            out[m, Q_CRUSH] = 0.0
        return count
    pc_body, pc_ptr = M.piece_body, M.piece_ptr
    sa, fa = max_separation(y, M, cs, a, b)
    sb, fb = max_separation(y, M, cs, b, a)
    n = 0
    for side in range(2):
        inc = a if side == 0 else b  # the piece whose vertices are tested
        ref = b if side == 0 else a  # the piece they press into
        # the separating axis: a face of ref if it is the pieces' face of largest separation
        prefer = (fb if sb >= sa else -1) if side == 0 else (fa if sa >= sb else -1)
        ox, oy, c, s = body_pose(y, M, cs, pc_body[ref])
        ix0, iy0, ic0, is0 = start_pose(M, pr, p, pc_body[inc])
        rx0, ry0, rc0, rs0 = start_pose(M, pr, p, pc_body[ref])
        for v in range(pc_ptr[inc], pc_ptr[inc + 1]):
            px, py = piece_vertex(y, M, cs, inc, v)
            d, fx, fy = inside_depth(M, ref, ox, oy, c, s, px, py, prefer, ROW_MARGIN)
            # the material vertex in the poses of the allowance, in the other piece as it was then
            lx = M.piece_verts[v, 0]
            ly = M.piece_verts[v, 1]
            d0, _, _ = inside_depth(M, ref, rx0, ry0, rc0, rs0, ix0 + ic0 * lx - is0 * ly, iy0 + is0 * lx + ic0 * ly,
                                    -1, 0.0)
            allowance = d0 if d0 > 0.0 else 0.0
            if d - allowance < -margin or n >= out.shape[0]:
                continue
            if side == 1:  # a vertex of B (or the obstacle) in A: the normal from B into A is minus A's face's
                fx = -fx
                fy = -fy
            out[n, Q_X] = px
            out[n, Q_Y] = py
            out[n, Q_NX] = fx
            out[n, Q_NY] = fy
            out[n, Q_DEPTH] = d - allowance
            out[n, Q_ALLOW] = allowance
            out[n, Q_CRUSH] = 1.0 if d0 >= -CRUSH_REACH else 0.0
            n += 1
    return n


@njit(**HOT)
def pair_forces(y, M, D, cs, p, f, pts, fc):
    """Penalty forces of pair ``p`` (in sustained contact) added to the world-frame body forces ``f``
    (z order), and their x, y components to the contact share ``fc`` (2 nb: x.., y..) for the load
    transfer.

    Sustained contact as the README states it ("Contact model"; package docstring, "States"):
    at each contact point (:func:`piece_points`) ``F_n = max(0, k e + c e' min(1, e / DAMPER_DEPTH))``
    on the depth ``e`` beyond the allowance, with Coulomb friction ``mu_c F_n`` against the
    tangential slip, regularised like the tyres (``v_t / sqrt(v_t^2 + eps^2)``).  A receives the
    force at each point, B minus it; an obstacle receives nothing.  ``cs`` holds the bodies' heading
    cosines and sines, ``pts`` is scratch for the points.  Returns the power of the forces on the
    bodies [W] (their work on the system: dissipation by the damper and the friction, and the
    spring's change of stored energy).  The bodies of parked vehicles count as still.
    """
    pr_body, pr_ptr, pp, pr_par, cfg = M.pair_body, M.pair_ptr, M.piece_pairs, M.pair_par, M.cfg
    nb = M.body.shape[0]
    eps = cfg[C_EPS]
    ia = pr_body[p, 0]
    ib = pr_body[p, 1]
    k = pr_par[p, R_K]
    c = pr_par[p, R_C]
    mu = pr_par[p, R_MU]
    pr = D.pref[p]
    # a parked body does not move: its frozen velocity (<= v_stop) neither damps nor does work
    bveh, parked = M.body_vehicle, D.parked
    still_a = parked[bveh[ia]] != 0
    still_b = ib >= 0 and parked[bveh[ib]] != 0
    power = 0.0
    for q in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[q, 0]
        b = pp[q, 1]
        if piece_gap(y, M, cs, a, b) >= 0.0:
            continue
        count = piece_points(y, M, pr, cs, p, a, b, 0.0, pts)
        for m in range(count):
            depth = pts[m, Q_DEPTH]
            if depth <= 0.0:
                continue
            px = pts[m, Q_X]
            py = pts[m, Q_Y]
            nx = pts[m, Q_NX]
            ny = pts[m, Q_NY]
            vax, vay = (0.0, 0.0) if still_a else point_velocity(y, M, ia, px, py)
            vbx, vby = (0.0, 0.0) if still_b else point_velocity(y, M, ib, px, py)
            rvx = vax - vbx
            rvy = vay - vby
            rate = -(rvx * nx + rvy * ny)  # penetration rate
            fn = k * depth + c * rate * min(1.0, depth / DAMPER_DEPTH)
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
            f[2 * nb + ia] += (px - y[SV_X * nb + ia]) * fy - (py - y[SV_Y * nb + ia]) * fx
            fc[ia] += fx
            fc[nb + ia] += fy
            if ib >= 0:
                f[ib] -= fx
                f[nb + ib] -= fy
                f[2 * nb + ib] -= (px - y[SV_X * nb + ib]) * fy - (py - y[SV_Y * nb + ib]) * fx
                fc[ib] -= fx
                fc[nb + ib] -= fy
    return power


@njit(**HOT)
def contact_forces(y, M, D, cs, f, pf, pts, fc):
    """Penalty forces of every pair in sustained contact added to ``f``; ``pf[p]`` their power [W];
    ``fc`` (2 nb) their world-frame x, y sums per body alone [N] (:func:`pair_forces`).  A disarmed pair
    (the crush of the first impact, not pressed on by the arming distance) has none."""
    pstate = D.pstate
    for i in range(fc.shape[0]):
        fc[i] = 0.0
    for p in range(M.pair_body.shape[0]):
        pf[p] = pair_forces(y, M, D, cs, p, f, pts, fc) if pstate[p] == PS_CONTACT else 0.0


@njit(**HOT)
def pair_depth(y, M, D, cs, p, pts):
    """Largest depth [m] of a point of pair ``p`` beyond its allowance (:func:`piece_points`); where no
    piece pair overlaps (or none of its points lies inside), minus the pair's gap (finite, so an event
    on it can be located)."""
    pr_ptr, pp = M.pair_ptr, M.piece_pairs
    pr = D.pref[p]
    best = -math.inf
    for q in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[q, 0]
        b = pp[q, 1]
        if piece_gap(y, M, cs, a, b) >= 0.0:
            continue
        count = piece_points(y, M, pr, cs, p, a, b, math.inf, pts)
        for m in range(count):
            best = max(best, pts[m, Q_DEPTH])
    if best == -math.inf:
        return -pair_gap(y, M, cs, p)
    return best


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
def strike_scan(y, M, D, cs, p, pts, margin, floor, geo, crush):
    """Strike measure of the contact points of pair ``p`` (:func:`piece_points`) pressed into each
    other beyond their allowance (to within ``margin`` [m]): each point's closing speed less the
    speed its depth holds, ``-(v_A - v_B) . n - omega max(e, 0)`` (``e`` the depth beyond the
    allowance, ``omega = sqrt(k / m_eff)`` the contact's natural frequency, ``R_OMEGA``).

    A point arriving at the surface (``e`` = 0) strikes at its closing speed.  A point already pressed
    ``e`` deep is held by its contact force, which stops a point closing at ``omega e`` within about as
    much depth again (``k e^2 / 2`` against ``m_eff v^2 / 2``): so it strikes only when it closes faster
    than that, plus the threshold.  A point driven in slowly (a car sliding along a turning tractor's
    side, forced to follow it) deepens its contact and its force instead of striking at the threshold
    again and again, each impulse leaving the force it must carry to the next (the chatter of a pinned
    car).

    A point of the crush of the first impact (``Q_CRUSH``) of a pair still disarmed is left out:
    pressing on into the crush is the first impact's crush going on, a force, not a new impact.  ``crush`` False
    leaves such points out in every state (the audit of
    :func:`~crashsim.motion.kernels.samples.contact_samples`).  Any other point counts from its
    allowance (0 for fresh material: a point that meets the other body anew strikes from the surface).

    Returns the largest strike measure of those points [m/s] (``-inf`` if none).  With ``floor``
    finite, ``geo`` receives ``(x, y, nx, ny, u_n)`` of the point whose measure is largest, if it is
    ``floor`` or more (``u_n`` its normal velocity).
    """
    pr_body, pr_ptr, pp = M.pair_body, M.pair_ptr, M.piece_pairs
    ia = pr_body[p, 0]
    ib = pr_body[p, 1]
    pr = D.pref[p]
    omega = M.pair_par[p, R_OMEGA]
    disarmed = D.pstate[p] == PS_DISARMED
    best = -math.inf
    for q in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[q, 0]
        b = pp[q, 1]
        if piece_gap(y, M, cs, a, b) > margin:
            continue
        count = piece_points(y, M, pr, cs, p, a, b, margin, pts)
        for m in range(count):
            if pts[m, Q_CRUSH] != 0.0 and (disarmed or not crush):
                continue
            px = pts[m, Q_X]
            py = pts[m, Q_Y]
            nx = pts[m, Q_NX]
            ny = pts[m, Q_NY]
            vax, vay = point_velocity(y, M, ia, px, py)
            vbx, vby = point_velocity(y, M, ib, px, py)
            closing = -((vax - vbx) * nx + (vay - vby) * ny) - omega * max(pts[m, Q_DEPTH], 0.0)
            if closing > best:
                best = closing
                if closing >= floor:
                    put_geometry(y, M, ia, ib, px, py, nx, ny, geo)
    return best


@njit(**HOT)
def touch_geometry(y, M, D, p, cs, pts, geo):
    """Contact point, normal (from B into A) and normal relative velocity of pair ``p`` at a touch:
    those of its point that closes fastest among the points within 1 mm of touching (``geo`` =
    ``(x, y, nx, ny, u_n)``, ``u_n = (v_A - v_B) . n``, < 0: approaching).  Returns False if no point
    was found (a touch at a vertex, numerically)."""
    best, _, _ = deepest_pieces(y, M, cs, p)
    return strike_scan(y, M, D, cs, p, pts, max(1e-3, -best + 1e-3), -math.inf, geo, True) > -math.inf


@njit(**HOT)
def strike_speed(y, M, D, cs, p, pts, crush):
    """Largest strike measure [m/s] of the points of pair ``p`` pressed beyond its allowance
    (:func:`strike_scan`: the closing speed less ``omega`` times the depth; 0 if none or if it is
    negative: a pair apart, or only in its crush allowance, does not strike).

    The strike event of a pair in sustained contact or disarmed is this minus the impulse
    threshold: it crosses zero when a point arrives at the surface (or beyond the crush of the
    first impact) closing at the threshold or faster (the value jumps there; the root is the
    arrival), or when a point already in contact is driven in faster than its depth holds.
    Either is an impact.
    """
    # an infinite floor writes no geometry (pts[0] only stands in for the unused argument)
    best = strike_scan(y, M, D, cs, p, pts, 0.0, math.inf, pts[0], crush)
    return best if best > 0.0 else 0.0


@njit(**HOT)
def strike_geometry(y, M, D, cs, p, pts, geo):
    """Contact point, normal and normal relative velocity of a strike of pair ``p`` (``geo`` as
    :func:`touch_geometry`), at a state where :func:`strike_speed` reaches the threshold.

    The points count that lie within 1 mm of the surface (the root of a jump is located to
    round-off on either side of the arrival) and close at the threshold or faster (to a
    relative 1e-6): the fastest of them.  Returns False if no point closes that fast.
    """
    thr = M.pair_par[p, R_VTHR]
    floor = thr * (1.0 - 1e-6)
    geo[4] = 0.0
    best = strike_scan(y, M, D, cs, p, pts, 1e-3, floor, geo, True)
    return best >= floor and geo[4] < 0.0


@njit(**HOT)
def find_strike(y, M, D, cs, pts, geo):
    """The pair in sustained contact or disarmed whose points close fastest beyond its impulse
    threshold at ``y`` (after a velocity jump: an articulation-stop impact, or round-off left by
    a simultaneous impact), with its strike geometry in ``geo`` = (pair, x, y, nx, ny, u_n); False
    if none."""
    pstate, pr_par = D.pstate, M.pair_par
    best = -math.inf
    hit = -1
    for p in range(pr_par.shape[0]):
        if pstate[p] == PS_ARMED or not strike_geometry(y, M, D, cs, p, pts, geo[1:]):
            continue
        excess = -geo[5] - pr_par[p, R_VTHR]
        if excess > best:
            best = excess
            hit = p
    if hit < 0:
        return False
    geo[0] = hit
    return strike_geometry(y, M, D, cs, hit, pts, geo[1:])


@njit(**JIT)
def contact_rows(y, M, D, out):
    """The contact points of a simultaneous impact at state ``y``: every contact point
    (:func:`piece_points`) within :data:`ROW_MARGIN` of touching beyond its allowance, of every pair
    in contact or disarmed, and of every armed pair whose gap is within that margin (a touch).
    Points of crushed material count too (in an impact the crush transmits the impulse like any
    contact).

    ``out`` (rows, 1 + N_Q) receives per point: the pair, then the ``Q_*`` columns.  Returns the number
    of points.
    """
    pstate, pr_ptr, pp = D.pstate, M.pair_ptr, M.piece_pairs
    W = make_work(M)
    cs = W.trig
    pts = W.contact_pts
    body_trig(y, M.body.shape[0], cs)
    n = 0
    for p in range(M.pair_body.shape[0]):
        if pstate[p] == PS_ARMED and pair_gap(y, M, cs, p) > ROW_MARGIN:
            continue
        for q in range(pr_ptr[p], pr_ptr[p + 1]):
            a = pp[q, 0]
            b = pp[q, 1]
            if piece_gap(y, M, cs, a, b) > ROW_MARGIN:
                continue
            count = piece_points(y, M, D.pref[p], cs, p, a, b, ROW_MARGIN, pts)
            for m in range(count):
                if n >= out.shape[0]:
                    return n
                out[n, 0] = p
                for c in range(N_Q):
                    out[n, 1 + c] = pts[m, c]
                n += 1
    return n


@njit(**HOT)
def unpark_pair(M, D, p):
    """Both vehicles of pair ``p`` move again (a contact force or an impulse acts on them)."""
    pr_body, bveh = M.pair_body, M.body_vehicle
    parked = D.parked
    parked[bveh[pr_body[p, 0]]] = 0
    if pr_body[p, 1] >= 0:
        parked[bveh[pr_body[p, 1]]] = 0


@njit(**INLINE)
def set_reference(y, M, D, p):
    """The crush allowance of pair ``p`` refers to the poses of its bodies in state ``y``."""
    nb = M.body.shape[0]
    ia = M.pair_body[p, 0]
    ib = M.pair_body[p, 1]
    pref = D.pref
    pref[p, A_CRUSH] = 1.0
    pref[p, A_XA] = y[SV_X * nb + ia]
    pref[p, A_YA] = y[SV_Y * nb + ia]
    pref[p, A_PA] = y[SV_HEADING * nb + ia]
    if ib >= 0:
        pref[p, A_XB] = y[SV_X * nb + ib]
        pref[p, A_YB] = y[SV_Y * nb + ib]
        pref[p, A_PB] = y[SV_HEADING * nb + ib]


@njit(**JIT)
def arming(y, M, D):
    """Initial contact states: a pair closer than its arming distance (the crush of the impact,
    or bodies left touching) starts disarmed, with the crush allowance of its overlap
    (:func:`piece_points`: the poses of its bodies now); the others armed."""
    pr_body, pr_par = M.pair_body, M.pair_par
    pstate, pref = D.pstate, D.pref
    W = make_work(M)
    cs = W.trig
    nb = M.body.shape[0]
    body_trig(y, nb, cs)
    for p in range(pr_body.shape[0]):
        g = pair_gap(y, M, cs, p)
        for c in range(N_A):
            pref[p, c] = 0.0
        if g < pr_par[p, R_ARM]:
            pstate[p] = PS_DISARMED
            set_reference(y, M, D, p)
        else:
            pstate[p] = PS_ARMED

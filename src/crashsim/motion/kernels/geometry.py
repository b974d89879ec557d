"""Kernel stage: geometry of the bodies, hitches, contact pieces, wheels and friction zones.

Heading trig, the hitch and stop constraint rows (Jacobian and Baumgarte terms), the
separating-axis gap of convex pieces and their Box2D-style manifold, how deep a point lies in one, bounding circles,
wheel positions and velocities, and the signed distance to a friction zone (package
docstring of :mod:`crashsim.motion.kernels` for the model arrays).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..layout import SV_X, SV_Y, SV_HEADING, SV_VX, SV_VY, SV_YAW_RATE
from .jit import HOT, INLINE
from .arrays import C_ALPHA2, C_BETA2, I_YAWLOCK, ZONE_TOL


@njit(**INLINE)
def rem2pi(a):
    """``np.remainder(a, 2 pi)``: floored modulo, computed as NumPy does (fmod, then shift)."""
    b = 2.0 * math.pi
    mod = np.fmod(a, b)
    if mod != 0.0 and ((b < 0.0) != (mod < 0.0)):
        mod += b
    return mod


@njit(**INLINE)
def wrap_angle(a):
    """``remainder(a + pi, 2 pi) - pi``: angle wrapped to [-pi, pi)."""
    return rem2pi(a + math.pi) - math.pi


@njit(**INLINE)
def body_trig(y, nb, cs):
    """``cs[0, i] = cos(psi_i)``, ``cs[1, i] = sin(psi_i)``."""
    for i in range(nb):
        psi = y[SV_HEADING * nb + i]
        cs[0, i] = math.cos(psi)
        cs[1, i] = math.sin(psi)


@njit(**INLINE)
def hitch_arms(cs, hitch, j, f, q):
    """World vectors from the CGs of hitch ``j``'s front body ``f`` and rear body ``q`` to its pin:
    ``(ax, ay, bx, by)`` (the body-frame hitch points ``hitch[j, 0:4]`` turned by the headings ``cs``)."""
    c0 = cs[0, f]
    s0 = cs[1, f]
    c1 = cs[0, q]
    s1 = cs[1, q]
    hfx, hfy, hrx, hry = hitch[j, 0], hitch[j, 1], hitch[j, 2], hitch[j, 3]
    return c0 * hfx - s0 * hfy, s0 * hfx + c0 * hfy, c1 * hrx - s1 * hry, s1 * hrx + c1 * hry


@njit(**INLINE)
def pin_gap(y, cs, hitch, hbody, j, nb):
    """Distance between the two pins of hitch ``j`` [m] (zero when the hitch holds)."""
    f = hbody[j, 0]
    q = hbody[j, 1]
    ax, ay, bx, by = hitch_arms(cs, hitch, j, f, q)
    gx = y[SV_X * nb + f] + ax - y[SV_X * nb + q] - bx
    gy = y[SV_Y * nb + f] + ay - y[SV_Y * nb + q] - by
    return math.sqrt(gx * gx + gy * gy)


@njit(**INLINE)
def constraint_rows(y, cs, M, lk_j, lk_th, nlk, G, r, with_rates):
    """Constraint Jacobian ``G`` (m, 3 nb) and, if ``with_rates``, ``r = gamma + 2 zeta w0 g' + w0^2 g`` (m,).

    Rows ``2j, 2j+1``: pin x, y of hitch j joining bodies ``hbody[j]``; then one row per closed
    articulation stop; then one row per yaw-locked hitch (a C-dolly: ``psi_front - psi_rear = 0``
    held by a moment, ``hitch[j, 5]``), in hitch order.  Returns ``m``.
    """
    body, hitch, cfg, hbody = M.body, M.hitch, M.cfg, M.hitch_body
    nb = body.shape[0]
    nh = hitch.shape[0]
    nyaw = M.icfg[I_YAWLOCK]
    m = 2 * nh + nlk + nyaw
    a2 = cfg[C_ALPHA2]
    b2 = cfg[C_BETA2]
    for a in range(m):
        for col in range(3 * nb):
            G[a, col] = 0.0
    for j in range(nh):
        f = hbody[j, 0]
        q = hbody[j, 1]
        ax, ay, bx, by = hitch_arms(cs, hitch, j, f, q)
        G[2 * j, SV_X * nb + f] = 1.0
        G[2 * j, SV_X * nb + q] = -1.0
        G[2 * j, SV_HEADING * nb + f] = -ay
        G[2 * j, SV_HEADING * nb + q] = by
        G[2 * j + 1, SV_Y * nb + f] = 1.0
        G[2 * j + 1, SV_Y * nb + q] = -1.0
        G[2 * j + 1, SV_HEADING * nb + f] = ax
        G[2 * j + 1, SV_HEADING * nb + q] = -bx
        if with_rates:
            wf = y[SV_YAW_RATE * nb + f]
            wr = y[SV_YAW_RATE * nb + q]
            gx = y[SV_X * nb + f] + ax - y[SV_X * nb + q] - bx
            gy = y[SV_Y * nb + f] + ay - y[SV_Y * nb + q] - by
            gdx = y[SV_VX * nb + f] - wf * ay - y[SV_VX * nb + q] + wr * by
            gdy = y[SV_VY * nb + f] + wf * ax - y[SV_VY * nb + q] - wr * bx
            r[2 * j] = (wr * wr * bx - wf * wf * ax) + a2 * gdx + b2 * gx
            r[2 * j + 1] = (wr * wr * by - wf * wf * ay) + a2 * gdy + b2 * gy
    for n in range(nlk):
        jl = lk_j[n]
        f = hbody[jl, 0]
        q = hbody[jl, 1]
        row = 2 * nh + n
        G[row, SV_HEADING * nb + f] = 1.0
        G[row, SV_HEADING * nb + q] = -1.0
        if with_rates:
            theta = math.atan2(cs[1, f] * cs[0, q] - cs[0, f] * cs[1, q], cs[0, f] * cs[0, q] + cs[1, f] * cs[1, q])
            g = wrap_angle(theta - lk_th[n])
            gd = y[SV_YAW_RATE * nb + f] - y[SV_YAW_RATE * nb + q]
            r[row] = a2 * gd + b2 * g
    if nyaw > 0:
        row = 2 * nh + nlk
        for j in range(nh):
            if hitch[j, 5] == 0.0:
                continue
            f = hbody[j, 0]
            q = hbody[j, 1]
            G[row, SV_HEADING * nb + f] = 1.0
            G[row, SV_HEADING * nb + q] = -1.0
            if with_rates:
                theta = math.atan2(cs[1, f] * cs[0, q] - cs[0, f] * cs[1, q], cs[0, f] * cs[0, q] + cs[1, f] * cs[1, q])
                r[row] = a2 * (y[SV_YAW_RATE * nb + f] - y[SV_YAW_RATE * nb + q]) + b2 * theta
            row += 1
    return m


@njit(**INLINE)
def solve_spd(A, b, m):
    """Solve ``A x = b`` in place (x in ``b``) for a small symmetric positive definite ``A`` (m, m).

    Closed form for m = 2 (one hitch, the common case), else Cholesky.  The system of a scene
    is block diagonal (hitches join bodies of one vehicle); Cholesky keeps the blocks' zeros.
    """
    if m == 2:
        a00 = A[0, 0]
        a01 = A[0, 1]
        a11 = A[1, 1]
        b0 = b[0]
        b1 = b[1]
        det = a00 * a11 - a01 * a01
        b[0] = (a11 * b0 - a01 * b1) / det
        b[1] = (a00 * b1 - a01 * b0) / det
        return
    for j in range(m):
        s = A[j, j]
        for k in range(j):
            s -= A[j, k] * A[j, k]
        d = math.sqrt(s)
        A[j, j] = d
        for i in range(j + 1, m):
            s = A[i, j]
            for k in range(j):
                s -= A[i, k] * A[j, k]
            A[i, j] = s / d
    for i in range(m):
        s = b[i]
        for k in range(i):
            s -= A[i, k] * b[k]
        b[i] = s / A[i, i]
    for i in range(m - 1, -1, -1):
        s = b[i]
        for k in range(i + 1, m):
            s -= A[k, i] * b[k]
        b[i] = s / A[i, i]


@njit(**INLINE)
def piece_vertex(y, M, cs, i, v):
    """World position of vertex ``v`` (global index) of piece ``i``."""
    pc_body, pc_v = M.piece_body, M.piece_verts
    b = pc_body[i]
    x = pc_v[v, 0]
    yy = pc_v[v, 1]
    if b < 0:
        return x, yy
    nb = M.body.shape[0]
    c = cs[0, b]
    s = cs[1, b]
    return y[SV_X * nb + b] + c * x - s * yy, y[SV_Y * nb + b] + s * x + c * yy


@njit(**INLINE)
def piece_normal(M, cs, i, v):
    """World outward normal of the edge from vertex ``v`` (global index) of piece ``i``."""
    pc_body, pc_n = M.piece_body, M.piece_normals
    b = pc_body[i]
    x = pc_n[v, 0]
    yy = pc_n[v, 1]
    if b < 0:
        return x, yy
    c = cs[0, b]
    s = cs[1, b]
    return c * x - s * yy, s * x + c * yy


@njit(**HOT)
def max_separation(y, M, cs, a, b):
    """Largest separation of piece ``b`` from a face of piece ``a``: (separation, face vertex index)."""
    pc_ptr = M.piece_ptr
    best = -math.inf
    face = pc_ptr[a]
    for v in range(pc_ptr[a], pc_ptr[a + 1]):
        px, py = piece_vertex(y, M, cs, a, v)
        nx, ny = piece_normal(M, cs, a, v)
        low = math.inf
        for u in range(pc_ptr[b], pc_ptr[b + 1]):
            qx, qy = piece_vertex(y, M, cs, b, u)
            d = nx * (qx - px) + ny * (qy - py)
            if d < low:
                low = d
        if low > best:
            best = low
            face = v
    return best, face


@njit(**HOT)
def piece_gap(y, M, cs, a, b):
    """Separating-axis gap of pieces ``a`` and ``b`` [m] (> 0 apart, < 0 overlapping)."""
    sa, _ = max_separation(y, M, cs, a, b)
    sb, _ = max_separation(y, M, cs, b, a)
    return max(sa, sb)


@njit(**INLINE)
def bounding_circle(y, M, cs, i):
    """World centre and radius of the bounding circle of piece ``i``."""
    pc_body, pc_info = M.piece_body, M.piece_info
    b = pc_body[i]
    cx = pc_info[i, 0]
    cy = pc_info[i, 1]
    if b >= 0:
        nb = M.body.shape[0]
        c = cs[0, b]
        s = cs[1, b]
        cx, cy = y[SV_X * nb + b] + c * cx - s * cy, y[SV_Y * nb + b] + s * cx + c * cy
    return cx, cy, pc_info[i, 2]


@njit(**HOT)
def pair_gap(y, M, cs, p):
    """Gap of pair ``p``: the least gap over its piece pairs [m] (bounding circles skip far pairs exactly)."""
    pr_ptr, pp = M.pair_ptr, M.piece_pairs
    g = math.inf
    for k in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[k, 0]
        b = pp[k, 1]
        ax, ay, ar = bounding_circle(y, M, cs, a)
        bx, by, br = bounding_circle(y, M, cs, b)
        lower = math.sqrt((ax - bx) ** 2 + (ay - by) ** 2) - ar - br  # <= the SAT gap
        if lower >= g:
            continue
        d = piece_gap(y, M, cs, a, b)
        if d < g:
            g = d
    return g


@njit(**HOT)
def manifold(y, M, cs, a, b, out, margin):
    """Contact points of pieces ``a`` (of body A) and ``b`` (of body B or an obstacle).

    Fills ``out`` (rows >= 2, >= 3 columns) with up to two points: world x, y and depth (> 0 below the
    reference face; points up to ``margin`` [m] above it count too, for the touching geometry of an
    impact); returns ``(count, nx, ny)`` with the unit normal pointing from B into A.
    The reference face is the face of largest separation (A's unless B's is larger by more
    than 1 mm, so the choice does not flip on round-off); the incident edge of the other piece
    is clipped to the reference face's side planes.
    """
    pc_ptr = M.piece_ptr
    sa, fa = max_separation(y, M, cs, a, b)
    sb, fb = max_separation(y, M, cs, b, a)
    if sb > sa + 1e-3:
        ref, inc, face, flip = b, a, fb, False  # reference face on B: its normal points from B into A
    else:
        ref, inc, face, flip = a, b, fa, True   # reference face on A: normal from B into A is -n
    nx, ny = piece_normal(M, cs, ref, face)
    nxt = face + 1 if face + 1 < pc_ptr[ref + 1] else pc_ptr[ref]
    r1x, r1y = piece_vertex(y, M, cs, ref, face)
    r2x, r2y = piece_vertex(y, M, cs, ref, nxt)
    # incident edge: the edge of inc most opposed to n
    low = math.inf
    e = pc_ptr[inc]
    for v in range(pc_ptr[inc], pc_ptr[inc + 1]):
        mx, my = piece_normal(M, cs, inc, v)
        d = mx * nx + my * ny
        if d < low:
            low = d
            e = v
    e2 = e + 1 if e + 1 < pc_ptr[inc + 1] else pc_ptr[inc]
    p1x, p1y = piece_vertex(y, M, cs, inc, e)
    p2x, p2y = piece_vertex(y, M, cs, inc, e2)
    # clip the segment p1-p2 to the slab between the side planes through r1 and r2
    tx = r2x - r1x
    ty = r2y - r1y
    tl = math.sqrt(tx * tx + ty * ty)
    tx /= tl
    ty /= tl
    lo = 0.0
    hi = 1.0
    s1 = (p1x - r1x) * tx + (p1y - r1y) * ty
    s2 = (p2x - r1x) * tx + (p2y - r1y) * ty
    ds = s2 - s1
    if ds != 0.0:
        ta = (0.0 - s1) / ds
        tb = (tl - s1) / ds
        if ta > tb:
            ta, tb = tb, ta
        lo = max(lo, ta)
        hi = min(hi, tb)
    elif s1 < 0.0 or s1 > tl:
        hi = -1.0
    count = 0
    if hi >= lo:
        for frac in (lo, hi):
            qx = p1x + frac * (p2x - p1x)
            qy = p1y + frac * (p2y - p1y)
            sep = nx * (qx - r1x) + ny * (qy - r1y)
            if sep <= margin and not (count == 1 and hi == lo):
                out[count, 0] = qx
                out[count, 1] = qy
                out[count, 2] = -sep
                count += 1
    if flip:
        nx, ny = -nx, -ny
    return count, nx, ny


@njit(**INLINE)
def inside_depth(M, piece, ox, oy, c, s, px, py, prefer, tie):
    """How deep the world point (px, py) lies inside the convex ``piece`` placed at origin
    (ox, oy) with heading cosine and sine (c, s): ``min over its faces of -n . (p - v)`` [m] (> 0
    inside: the distance to its boundary; < 0 outside: minus the largest separation from a
    face), with the outward world normal of that nearest face: ``(depth, nx, ny)``.  Where the face
    ``prefer`` (a global vertex index of ``piece``, -1: none) lies within ``tie`` [m] of the nearest,
    its normal is taken (a point at a corner of the piece pushes along the pieces' separating axis,
    not along whichever of the corner's faces comes first).  An obstacle's piece is in world
    coordinates (pass 0, 0, 1, 0)."""
    pc_ptr, pc_v, pc_n = M.piece_ptr, M.piece_verts, M.piece_normals
    best = math.inf
    bx = 0.0
    by = 0.0
    dp = math.inf
    px_ = 0.0
    py_ = 0.0
    for v in range(pc_ptr[piece], pc_ptr[piece + 1]):
        vx = ox + c * pc_v[v, 0] - s * pc_v[v, 1]
        vy = oy + s * pc_v[v, 0] + c * pc_v[v, 1]
        nx = c * pc_n[v, 0] - s * pc_n[v, 1]
        ny = s * pc_n[v, 0] + c * pc_n[v, 1]
        d = -(nx * (px - vx) + ny * (py - vy))
        if d < best:
            best = d
            bx = nx
            by = ny
        if v == prefer:
            dp = d
            px_ = nx
            py_ = ny
    if dp <= best + tie:
        return best, px_, py_
    return best, bx, by


@njit(**INLINE)
def point_velocity(y, M, i, px, py):
    """World velocity of the material point of body ``i`` at world position (px, py); zero for an obstacle."""
    if i < 0:
        return 0.0, 0.0
    nb = M.body.shape[0]
    w = y[SV_YAW_RATE * nb + i]
    return y[SV_VX * nb + i] - w * (py - y[SV_Y * nb + i]), y[SV_VY * nb + i] + w * (px - y[SV_X * nb + i])


@njit(**INLINE)
def wheel_arm(M, k, cs):
    """Body of contact ``k`` and the contact's offset from that body's CG in world axes [m]
    (``cs``: heading cosines/sines of the bodies)."""
    wheel, wbody = M.wheel, M.wheel_body
    i = wbody[k]
    c = cs[0, i]
    s = cs[1, i]
    rx = wheel[k, 0]
    ry = wheel[k, 1]
    return i, c * rx - s * ry, s * rx + c * ry


@njit(**INLINE)
def wheel_xy(y, M, k, cs):
    """World position [m] of contact ``k``."""
    nb = M.body.shape[0]
    i, dx, dy = wheel_arm(M, k, cs)
    return y[SV_X * nb + i] + dx, y[SV_Y * nb + i] + dy


@njit(**HOT)
def wheel_velocity(y, M, k, cs):
    """World velocity [m/s] of contact ``k``."""
    nb = M.body.shape[0]
    i, dx, dy = wheel_arm(M, k, cs)
    w = y[SV_YAW_RATE * nb + i]
    return y[SV_VX * nb + i] - w * dy, y[SV_VY * nb + i] + w * dx


@njit(**HOT)
def signed_distance(px, py, z, zone_ptr, edges):
    """Distance of a point to the boundary of zone ``z`` [m], positive inside (even-odd rule).

    The scalar form of :func:`crashsim.motion.road.signed_distance` (same edge arrays, same
    crossing test, so a point is inside here exactly when it is inside there).
    """
    d2min = math.inf
    hits = 0
    for e in range(zone_ptr[z], zone_ptr[z + 1]):
        rx = px - edges[e, 0]
        ry = py - edges[e, 1]
        ex = edges[e, 2]
        ey = edges[e, 3]
        s = min(max((rx * ex + ry * ey) * edges[e, 4], 0.0), 1.0)
        dx = rx - s * ex
        dy = ry - s * ey
        d2 = dx * dx + dy * dy
        if d2 < d2min:
            d2min = d2
        straddle = (ry < 0.0) != (ry - ey < 0.0)
        cross_right = rx * ey < ry * ex
        if straddle and (cross_right == (ey > 0.0)):
            hits += 1
    d = math.sqrt(d2min)
    return d if hits % 2 == 1 else -d


@njit(**HOT)
def membership(y, M, out, cs):
    """Zone membership of every wheel (nw, nz), assigning wheels on an edge by their direction of motion.

    A wheel within 1 nm of an edge is inside if the point 1 micrometre ahead along its
    velocity is inside.
    """
    wheel, zone_mu, zone_ptr, edges = M.wheel, M.zone_mu, M.zone_ptr, M.zone_edges
    nw = wheel.shape[0]
    nz = zone_mu.shape[0]
    body_trig(y, M.body.shape[0], cs)
    for k in range(nw):
        px, py = wheel_xy(y, M, k, cs)
        vx, vy = wheel_velocity(y, M, k, cs)
        speed = math.hypot(vx, vy)
        scale = 1e-6 / max(speed, 1e-300)
        qx = px + vx * scale
        qy = py + vy * scale
        for z in range(nz):
            d = signed_distance(px, py, z, zone_ptr, edges)
            if abs(d) < ZONE_TOL:
                if speed > 0:
                    out[k, z] = signed_distance(qx, qy, z, zone_ptr, edges) > 0
                else:
                    out[k, z] = d >= 0
            else:
                out[k, z] = d > 0


@njit(**HOT)
def deepest_pieces(y, M, cs, p):
    """The piece pair of pair ``p`` with the least gap: ``(gap, piece a, piece b)``."""
    pr_ptr, pp = M.pair_ptr, M.piece_pairs
    best = math.inf
    qa = pp[pr_ptr[p], 0]
    qb = pp[pr_ptr[p], 1]
    for q in range(pr_ptr[p], pr_ptr[p + 1]):
        g = piece_gap(y, M, cs, pp[q, 0], pp[q, 1])
        if g < best:
            best = g
            qa = pp[q, 0]
            qb = pp[q, 1]
    return best, qa, qb

"""The physics of the run-out of a whole scene: one source for both engines.

Everything here is nopython code on SI floats in flat arrays.  Both engines run it: the
compiled engine (:mod:`crashsim.motion.fast`) inside its own integration loop (:func:`run`),
the SciPy engine (:mod:`crashsim.motion.simulate`) through thin compiled entry points
(:func:`rhs`, :func:`event_values`, :func:`handle_event`, ...) called from its Python loop
around SciPy's integrators.  So the right-hand side, the event functions and what happens at
an event are written once; only the integrators differ.

The state vector is field-major over **all bodies of all vehicles** of the scene, in vehicle
order (:class:`~crashsim.motion.layout.StateLayout`): X.., Y.., psi.., vx.., vy.., w..,
then the filtered body-axes accelerations with load transfer.

Model bundle ``M`` (a tuple of arrays, built by :mod:`crashsim.motion.model`)::

    M = (body, wheel, wbody, hitch, transfer, minv, phase_t, phase_w, zone_mu, zone_ptr, edges,
         cfg, icfg, tab_a, tab_b, tab_c, tab_e, tab_p, zone_box,
         bveh, hbody, pc_body, pc_ptr, pc_v, pc_n, pc_info, pr_body, pr_ptr, pp, pr_par)

* ``body`` (nb, 3): mass [kg], yaw inertia [kg m^2], rest reference length L_ref [m];
  ``bveh`` (nb,) the vehicle of each body;
* ``wheel`` (nw, 3): contact x, y in body axes [m], static load [N]; ``wbody`` (nw,) body index;
* ``hitch`` (nh, 5): front pin x, y (front body axes), rear pin x, y (rear body axes) [m],
  articulation limit [rad] (NaN: none); ``hbody`` (nh, 2) front and rear body index;
* ``transfer`` (nw, 2 nb): load-transfer matrix [N per m/s^2]; ``minv`` (3 nb,) inverse masses
  and inertias in z order;
* ``phase_t`` (P,), ``phase_w`` (P, nw, 8): wheel-setting phases of the scene (``P_*`` columns);
* ``zone_mu``, ``zone_ptr``, ``edges`` (start x, y, edge x, y, 1/|edge|^2), ``zone_box``: friction
  zones (:func:`crashsim.motion.road._edges`);
* ``cfg`` (``C_*``), ``icfg`` (``I_*``): options; ``tab_*``: the explicit RK scheme's tableau;
* contact geometry: convex pieces ``pc_*`` (``pc_body`` the body, -1 for a fixed obstacle in
  world coordinates; vertices ``pc_v[pc_ptr[i]:pc_ptr[i+1]]`` counter-clockwise with the
  outward normal ``pc_n`` of the edge from each vertex to the next; ``pc_info`` (npc, 4): centre
  x, y and radius of a bounding circle (body axes, or world), thickness [m]); pairs ``pr_*``
  (``pr_body`` (np, 2): bodies A and B, B = -1 for an obstacle; piece pairs
  ``pp[pr_ptr[p]:pr_ptr[p+1]]``; parameters ``pr_par`` (np, ``R_*`` columns)).

Mode ``D`` (the discrete state, changed only at events)::

    D = (memb, lk_j, lk_th, lk_n, shift, pstate, pref, parked)

zone membership of every wheel, the closed articulation stops (hitch, locked angle, count in
``lk_n[0]``), the raised thresholds of stops that were left, the contact state of every pair
(``PS_*``) with its allowance (``A_*`` columns: the depth allowance [m] and the crush circle of
the first impact), and which vehicles are parked (at rest, frozen).

Contact (between bodies of different vehicles, and between a body and a fixed obstacle)
------------------------------------------------------------------------------------------
* **Gap.**  Per piece pair the separating-axis gap: the largest separation of one polygon from
  a face of the other, over the faces of both; > 0 apart (a lower bound of the distance),
  0 touching, < 0 overlapping (minus the smallest penetration along a face normal).  The gap
  of a pair is the least over its piece pairs: continuous, so its sign change is a solver
  event like any other.
* **Manifold** (the contact points of overlapping or touching pieces, as Box2D builds it):
  reference face = the face of largest separation; incident edge = the other polygon's edge
  most opposed to it, clipped to the reference face's side planes; the clipped points below
  the face are the contact points, each with its depth.  The normal points from B into A.
* **States.**  ``PS_DISARMED`` (overlapping at separation, the crush of the primary impact:
  no contact force until the pieces have separated by ``R_ARM`` (-> armed), or pressed more
  than ``R_ARM`` deeper than the allowance ``pref`` (-> contact, the allowance kept));
  ``PS_ARMED`` (apart: the gap event detects the next touch); ``PS_CONTACT`` (sustained
  contact: a penalty force at every manifold point, ``F_n = max(0, k e + c e')`` on the depth
  ``e`` beyond the allowance, with Coulomb friction ``mu_c F_n`` against the tangential
  slip, regularised like the tyres; left when the gap exceeds ``R_ARM``).
* **Strikes.**  A pair in contact or disarmed carries the strike event (``EV_STRIKE``,
  :func:`strike_speed`): the closing speed of its points pressed beyond the allowance (a
  disarmed pair's: the crush plus ``R_ARM``) minus ``R_VTHR``.  It crosses zero where a point
  arrives that fast (the value jumps; the root is the arrival) or a point in contact is driven
  in that fast: an impact, as the touch of an armed pair at that speed is.  After any velocity
  jump (an impulse, an articulation-stop impact) :func:`find_strike` looks for points left
  striking.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit, objmode, types
from numba.extending import overload

from .._jit import configure as _configure_cache

_configure_cache()  # a user-writable cache directory (crashsim.motion.jitcache), before any kernel is defined

from . import tyres
from .options import MAX_STILL_SEGMENTS, STOP_HYSTERESIS  # the same constants as the SciPy engine

# ----------------------------------------------------------------------------- the shared tyre law
# The tyre module is written with NumPy ufuncs and tyres._select (np.where).  For scalars
# numba compiles the ufuncs to scalar arithmetic; _select gets a scalar overload, and the two
# lateral curves are compiled from their own source.  error_model="numpy": IEEE division
# (as NumPy), no Python ZeroDivisionError checks.
_OV = {"error_model": "numpy"}


@overload(tyres._select, jit_options=_OV)
def _select_scalar(cond, if_true, if_false):
    if isinstance(cond, types.Boolean):
        return lambda cond, if_true, if_false: if_true if cond else if_false
    return None


@overload(tyres.fiala_curve, jit_options=_OV)
def _fiala_scalar(tan_alpha, mu_load, cornering_stiffness):
    return tyres.fiala_curve


@overload(tyres.linear_curve, jit_options=_OV)
def _linear_scalar(tan_alpha, mu_load, cornering_stiffness):
    return tyres.linear_curve


@overload(tyres.sliding_force, jit_options=_OV)
def _sliding_scalar(u, w, mu_load, eps):
    return tyres.sliding_force


@overload(tyres.tyre_kernel, jit_options=_OV)
def _tyre_scalar(u, w, mu_load, demand, cornering_stiffness, locked, eps, fiala):
    return tyres.tyre_kernel


_JIT = {"cache": True, "error_model": "numpy", "nogil": True}
# Hot functions that allocate nothing are compiled without NRT reference counting: numba
# otherwise increfs/decrefs every array argument (an atomic operation each) on every call,
# which cost more than the arithmetic of a right-hand side (measured 0.6 -> 0.4 us per RHS
# evaluation of the articulated truck, 0.41 -> 0.18 us for a car).  They only index arrays
# owned by their NRT-managed callers.
_HOT = dict(_JIT, _nrt=False)
# Small helpers are inlined at numba-IR level: a call passes the model and work tuples as a
# few hundred scalar arguments, which cost ~20 % of a right-hand side evaluation.
_INLINE = dict(_HOT, inline="always")

# ----------------------------------------------------------------------------- array layouts
# cfg (float options)
(C_EPS, C_ALPHA2, C_BETA2, C_TAU, C_VSTOP, C_RTOL, C_ATOL, C_MAXSTEP, C_FIRST, C_TMAX, C_SDT, C_ROADMU,
 C_ZRES) = range(13)
N_CFG = 13
# icfg (int options)
I_FIALA, I_LT, I_MAXSEG, I_ORDER, I_NSTAGES, I_MAXEVAL = range(6)
N_ICFG = 6
# phase_w columns (per phase and wheel)
P_MUF, P_BRAKE, P_FROLL, P_CFIX, P_CCOEF, P_CD, P_SD, P_LOCKED = range(8)
N_P = 8
# segment wheel columns (sw)
S_MU, S_MULOAD, S_DEMAND, S_CALPHA, S_DCOEF, S_CFIX, S_CCOEF, S_CD, S_SD, S_LOCKED = range(10)
N_S = 10
# per-wheel outputs of an evaluation (wk)
W_U, W_V, W_FX, W_FY, W_SLIDE, W_LOAD = range(6)
N_W = 6
# pair parameters (pr_par columns): contact stiffness [N/m], damping [N s/m], contact friction,
# arming distance [m], impulse threshold [m/s], event resolution [m]
R_K, R_C, R_MU, R_ARM, R_VTHR, R_RES = range(6)
N_R = 6
# pair states
PS_DISARMED, PS_ARMED, PS_CONTACT = 0, 1, 2
# pair allowance columns (D[6], one row per pair): the depth allowance [m], and the crush of the
# first impact as a circle in body A's axes: centre x, y and radius [m] (radius 0: none)
A_DEPTH, A_CX, A_CY, A_R = range(4)
N_A = 4
# Reach of the crush of the first impact beyond the extent of its overlap [m]: points of a
# disarmed pair within it are the crush (pressing on is sustained contact, not a new impact);
# points farther away meet the other body anew (a strike counts from the surface)
CRUSH_REACH = 0.5

# event kinds of a segment
EV_REST, EV_ZONE, EV_STOP, EV_RELEASE, EV_GAP, EV_ARM, EV_PRESS, EV_STRIKE = range(8)
# log record kinds
(LOG_ZONE_ENTER, LOG_ZONE_EXIT, LOG_SCHEDULE, LOG_STOP_CLOSED, LOG_STOP_IMPACT, LOG_STOP_OPEN, LOG_REST,
 LOG_ARMED, LOG_CONTACT, LOG_PRESS, LOG_CONTACT_END) = range(11)
# run status
(ST_REST, ST_TIME_LIMIT, ST_MAX_SEGMENTS, ST_STEP_TOO_SMALL, ST_NONFINITE, ST_MAX_EVAL, ST_WALL_TIME,
 ST_NO_PROGRESS, ST_IMPACT) = range(9)

# zone-crossing tolerances: identical in both engines (they run this code)
ZONE_TOL = 1e-9
ZONE_OVERSHOOT = 1e-10
# The wall clock is read every this many solver steps.
WALL_CHECK_STEPS = 256
# Largest number of points at which one step's dense output is searched for a feature the
# step could have passed through (zones, contact gaps).
MAX_SUBSAMPLES = 512
# solve_ivp's step-size controller constants (scipy.integrate._ivp.rk)
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
EPS = np.finfo(float).eps


# ============================================================================= model evaluation
@njit(**_HOT)
def segment_params(t_phase, memb, M, sw):
    """Fill ``sw`` (nw, N_S) with the inputs of wheel-setting phase ``t_phase`` and zone membership ``memb``."""
    wheel, phase_w, zone_mu, cfg = M[1], M[7], M[8], M[11]
    nw = wheel.shape[0]
    nz = zone_mu.shape[0]
    for k in range(nw):
        road_mu = cfg[C_ROADMU]
        for z in range(nz):
            if memb[k, z]:
                road_mu = zone_mu[z]
        pw = phase_w[t_phase, k]
        mu = road_mu * pw[P_MUF]
        dcoef = min(pw[P_BRAKE] * mu + pw[P_FROLL], mu)
        n = wheel[k, 2]
        sw[k, S_MU] = mu
        sw[k, S_MULOAD] = mu * n
        sw[k, S_DEMAND] = dcoef * n
        sw[k, S_CALPHA] = pw[P_CFIX] + pw[P_CCOEF] * n
        sw[k, S_DCOEF] = dcoef
        sw[k, S_CFIX] = pw[P_CFIX]
        sw[k, S_CCOEF] = pw[P_CCOEF]
        sw[k, S_CD] = pw[P_CD]
        sw[k, S_SD] = pw[P_SD]
        sw[k, S_LOCKED] = pw[P_LOCKED]


@njit(**_HOT)
def phase_at(t, phase_t):
    """Index of the wheel-setting phase in force at ``t`` (a change at ``t`` is in force)."""
    i = 0
    for p in range(phase_t.shape[0]):
        if phase_t[p] <= t:
            i = p
    return i


@njit(**_INLINE)
def _rem2pi(a):
    """``np.remainder(a, 2 pi)``: floored modulo, computed as NumPy does (fmod, then shift)."""
    b = 2.0 * math.pi
    mod = np.fmod(a, b)
    if mod != 0.0 and ((b < 0.0) != (mod < 0.0)):
        mod += b
    return mod


@njit(**_INLINE)
def _wrap(a):
    """``remainder(a + pi, 2 pi) - pi``: angle wrapped to [-pi, pi)."""
    return _rem2pi(a + math.pi) - math.pi


@njit(**_INLINE)
def body_trig(y, nb, cs):
    """``cs[0, i] = cos(psi_i)``, ``cs[1, i] = sin(psi_i)``."""
    for i in range(nb):
        psi = y[2 * nb + i]
        cs[0, i] = math.cos(psi)
        cs[1, i] = math.sin(psi)


@njit(**_INLINE)
def constraint_rows(y, cs, M, lk_j, lk_th, nlk, G, r, with_rates):
    """Constraint Jacobian ``G`` (m, 3 nb) and, if ``with_rates``, ``r = gamma + 2 zeta w0 g' + w0^2 g`` (m,).

    Rows ``2j, 2j+1``: pin x, y of hitch j joining bodies ``hbody[j]``; then one row per closed
    articulation stop.  Returns ``m``.
    """
    body, hitch, cfg, hbody = M[0], M[3], M[11], M[20]
    nb = body.shape[0]
    nh = hitch.shape[0]
    m = 2 * nh + nlk
    a2 = cfg[C_ALPHA2]
    b2 = cfg[C_BETA2]
    for a in range(m):
        for col in range(3 * nb):
            G[a, col] = 0.0
    for j in range(nh):
        f = hbody[j, 0]
        q = hbody[j, 1]
        c0 = cs[0, f]
        s0 = cs[1, f]
        c1 = cs[0, q]
        s1 = cs[1, q]
        hfx, hfy, hrx, hry = hitch[j, 0], hitch[j, 1], hitch[j, 2], hitch[j, 3]
        ax = c0 * hfx - s0 * hfy
        ay = s0 * hfx + c0 * hfy
        bx = c1 * hrx - s1 * hry
        by = s1 * hrx + c1 * hry
        G[2 * j, f] = 1.0
        G[2 * j, q] = -1.0
        G[2 * j, 2 * nb + f] = -ay
        G[2 * j, 2 * nb + q] = by
        G[2 * j + 1, nb + f] = 1.0
        G[2 * j + 1, nb + q] = -1.0
        G[2 * j + 1, 2 * nb + f] = ax
        G[2 * j + 1, 2 * nb + q] = -bx
        if with_rates:
            wf = y[5 * nb + f]
            wr = y[5 * nb + q]
            gx = y[f] + ax - y[q] - bx
            gy = y[nb + f] + ay - y[nb + q] - by
            gdx = y[3 * nb + f] - wf * ay - y[3 * nb + q] + wr * by
            gdy = y[4 * nb + f] + wf * ax - y[4 * nb + q] - wr * bx
            r[2 * j] = (wr * wr * bx - wf * wf * ax) + a2 * gdx + b2 * gx
            r[2 * j + 1] = (wr * wr * by - wf * wf * ay) + a2 * gdy + b2 * gy
    for n in range(nlk):
        jl = lk_j[n]
        f = hbody[jl, 0]
        q = hbody[jl, 1]
        row = 2 * nh + n
        G[row, 2 * nb + f] = 1.0
        G[row, 2 * nb + q] = -1.0
        if with_rates:
            theta = math.atan2(cs[1, f] * cs[0, q] - cs[0, f] * cs[1, q], cs[0, f] * cs[0, q] + cs[1, f] * cs[1, q])
            g = _wrap(theta - lk_th[n])
            gd = y[5 * nb + f] - y[5 * nb + q]
            r[row] = a2 * gd + b2 * g
    return m


@njit(**_INLINE)
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


@njit(**_INLINE)
def tyre_eval(y, M, sw, D, W):
    """Tyre forces of state ``y``: per-wheel results in ``W[0]`` (``W_*`` columns), world-frame body sums in ``W[1]``.

    Also fills ``W[5]`` with the body heading cosines and sines.  Wheels of parked vehicles
    produce no force (their bodies are frozen).
    """
    body, wheel, wbody, transfer, cfg, icfg, bveh = M[0], M[1], M[2], M[4], M[11], M[12], M[19]
    parked = D[7]
    wk, f, cs = W[0], W[1], W[5]
    nb = body.shape[0]
    nw = wheel.shape[0]
    lt = icfg[I_LT] != 0
    fiala = icfg[I_FIALA] != 0
    eps = cfg[C_EPS]
    body_trig(y, nb, cs)
    for i in range(3 * nb):
        f[i] = 0.0
    for k in range(nw):
        i = wbody[k]
        if parked[bveh[i]] != 0:
            wk[k, W_U] = 0.0
            wk[k, W_V] = 0.0
            wk[k, W_FX] = 0.0
            wk[k, W_FY] = 0.0
            wk[k, W_SLIDE] = 0.0
            wk[k, W_LOAD] = wheel[k, 2]
            continue
        c = cs[0, i]
        s = cs[1, i]
        vx = y[3 * nb + i]
        vy = y[4 * nb + i]
        w = y[5 * nb + i]
        rx = wheel[k, 0]
        ry = wheel[k, 1]
        cvx = (c * vx + s * vy) - ry * w
        cvy = (c * vy - s * vx) + rx * w
        cd = sw[k, S_CD]
        sd = sw[k, S_SD]
        u = cd * cvx + sd * cvy
        v = -sd * cvx + cd * cvy
        if lt:
            n = wheel[k, 2]
            for j in range(2 * nb):
                n += transfer[k, j] * y[6 * nb + j]
            load = max(n, 0.0)
            mu_load = sw[k, S_MU] * load
        else:
            load = wheel[k, 2]
            mu_load = sw[k, S_MULOAD]
        if sw[k, S_LOCKED] != 0.0:
            fx, fy = tyres.sliding_force(u, v, mu_load, eps)
            sliding = True
        else:
            if lt:
                demand = sw[k, S_DCOEF] * load
                c_alpha = sw[k, S_CFIX] + sw[k, S_CCOEF] * load
            else:
                demand = sw[k, S_DEMAND]
                c_alpha = sw[k, S_CALPHA]
            fx, fy, sliding = tyres.tyre_kernel(u, v, mu_load, demand, c_alpha, False, eps, fiala)
        wk[k, W_U] = u
        wk[k, W_V] = v
        wk[k, W_FX] = fx
        wk[k, W_FY] = fy
        wk[k, W_SLIDE] = 1.0 if sliding else 0.0
        wk[k, W_LOAD] = load
        bx = cd * fx - sd * fy
        by = sd * fx + cd * fy
        f[i] += bx
        f[nb + i] += by
        f[2 * nb + i] += rx * by - ry * bx
    for i in range(nb):
        sx = f[i]
        sy = f[nb + i]
        f[i] = cs[0, i] * sx - cs[1, i] * sy
        f[nb + i] = cs[1, i] * sx + cs[0, i] * sy


# ============================================================================= contact geometry
@njit(**_INLINE)
def piece_vertex(y, M, cs, i, v):
    """World position of vertex ``v`` (global index) of piece ``i``."""
    pc_body, pc_v = M[21], M[23]
    b = pc_body[i]
    x = pc_v[v, 0]
    yy = pc_v[v, 1]
    if b < 0:
        return x, yy
    nb = M[0].shape[0]
    c = cs[0, b]
    s = cs[1, b]
    return y[b] + c * x - s * yy, y[nb + b] + s * x + c * yy


@njit(**_INLINE)
def piece_normal(M, cs, i, v):
    """World outward normal of the edge from vertex ``v`` (global index) of piece ``i``."""
    pc_body, pc_n = M[21], M[24]
    b = pc_body[i]
    x = pc_n[v, 0]
    yy = pc_n[v, 1]
    if b < 0:
        return x, yy
    c = cs[0, b]
    s = cs[1, b]
    return c * x - s * yy, s * x + c * yy


@njit(**_HOT)
def _max_separation(y, M, cs, a, b):
    """Largest separation of piece ``b`` from a face of piece ``a``: (separation, face vertex index)."""
    pc_ptr = M[22]
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


@njit(**_HOT)
def piece_gap(y, M, cs, a, b):
    """Separating-axis gap of pieces ``a`` and ``b`` [m] (> 0 apart, < 0 overlapping)."""
    sa, _ = _max_separation(y, M, cs, a, b)
    sb, _ = _max_separation(y, M, cs, b, a)
    return max(sa, sb)


@njit(**_INLINE)
def _circle(y, M, cs, i):
    """World centre and radius of the bounding circle of piece ``i``."""
    pc_body, pc_info = M[21], M[25]
    b = pc_body[i]
    cx = pc_info[i, 0]
    cy = pc_info[i, 1]
    if b >= 0:
        nb = M[0].shape[0]
        c = cs[0, b]
        s = cs[1, b]
        cx, cy = y[b] + c * cx - s * cy, y[nb + b] + s * cx + c * cy
    return cx, cy, pc_info[i, 2]


@njit(**_HOT)
def pair_gap(y, M, cs, p):
    """Gap of pair ``p``: the least gap over its piece pairs [m] (bounding circles skip far pairs exactly)."""
    pr_ptr, pp = M[27], M[28]
    g = math.inf
    for k in range(pr_ptr[p], pr_ptr[p + 1]):
        a = pp[k, 0]
        b = pp[k, 1]
        ax, ay, ar = _circle(y, M, cs, a)
        bx, by, br = _circle(y, M, cs, b)
        lower = math.sqrt((ax - bx) ** 2 + (ay - by) ** 2) - ar - br  # <= the SAT gap
        if lower >= g:
            continue
        d = piece_gap(y, M, cs, a, b)
        if d < g:
            g = d
    return g


@njit(**_HOT)
def manifold(y, M, cs, a, b, out, margin):
    """Contact points of pieces ``a`` (of body A) and ``b`` (of body B or an obstacle).

    Fills ``out`` (2, 3) with up to two points: world x, y and depth (> 0 below the reference
    face; points up to ``margin`` [m] above it count too, for the touching geometry of an
    impact); returns ``(count, nx, ny)`` with the unit normal pointing from B into A.
    The reference face is the face of largest separation (A's unless B's is larger by more
    than 1 mm, so the choice does not flip on round-off); the incident edge of the other piece
    is clipped to the reference face's side planes.
    """
    pc_ptr = M[22]
    sa, fa = _max_separation(y, M, cs, a, b)
    sb, fb = _max_separation(y, M, cs, b, a)
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


@njit(**_INLINE)
def point_velocity(y, M, i, px, py):
    """World velocity of the material point of body ``i`` at world position (px, py); zero for an obstacle."""
    if i < 0:
        return 0.0, 0.0
    nb = M[0].shape[0]
    w = y[5 * nb + i]
    return y[3 * nb + i] - w * (py - y[nb + i]), y[4 * nb + i] + w * (px - y[i])


@njit(**_INLINE)
def in_crush(y, M, D, cs, p, ia, px, py):
    """Whether the world point (px, py) lies in pair ``p``'s crush circle (body ``ia``'s axes)."""
    nb = M[0].shape[0]
    dx = px - y[ia]
    dy = py - y[nb + ia]
    lx = cs[0, ia] * dx + cs[1, ia] * dy - D[6][p, A_CX]
    ly = -cs[1, ia] * dx + cs[0, ia] * dy - D[6][p, A_CY]
    return lx * lx + ly * ly <= D[6][p, A_R] * D[6][p, A_R]


@njit(**_HOT)
def pair_forces(y, M, D, cs, p, f, mf):
    """Penalty forces of pair ``p`` (in contact) added to the world-frame body forces ``f`` (z order).

    A receives the force at each manifold point, B minus it; an obstacle receives nothing.
    ``cs`` holds the bodies' heading cosines and sines, ``mf`` (2, 3) is scratch for the
    manifold.  Returns the power of the forces on the bodies [W] (their work on the system:
    dissipation by the damper and the friction, and the spring's change of stored energy).
    The bodies of parked vehicles count as still.  The depth allowance applies within the
    pair's crush circle (the crush of the first impact); elsewhere the depth counts from the
    surface, as for any other contact.
    """
    pr_body, pr_ptr, pp, pr_par, cfg = M[26], M[27], M[28], M[29], M[11]
    nb = M[0].shape[0]
    eps = cfg[C_EPS]
    ia = pr_body[p, 0]
    ib = pr_body[p, 1]
    k = pr_par[p, R_K]
    c = pr_par[p, R_C]
    mu = pr_par[p, R_MU]
    crush = D[6][p, A_DEPTH]
    radius = D[6][p, A_R]
    least = 0.0 if radius > 0.0 else crush  # the smallest allowance of any point
    # a parked body does not move: its frozen velocity (<= v_stop) neither damps nor does work
    bveh, parked = M[19], D[7]
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
            if ib >= 0:
                f[ib] -= fx
                f[nb + ib] -= fy
                f[2 * nb + ib] -= (px - y[ib]) * fy - (py - y[nb + ib]) * fx
    return power


@njit(**_HOT)
def contact_forces(y, M, D, cs, f, pf, mf):
    """Penalty forces of every pair in contact added to ``f``; ``pf[p]`` their power [W] (:func:`pair_forces`)."""
    pstate = D[5]
    for p in range(M[26].shape[0]):
        pf[p] = pair_forces(y, M, D, cs, p, f, mf) if pstate[p] == PS_CONTACT else 0.0


# ============================================================================= equations of motion
@njit(**_HOT)
def evaluate(y, M, sw, D, dydt, W):
    """Right-hand side ``dydt`` of state ``y`` for the segment inputs ``sw`` and mode ``D``.

    Leaves in the work bundle ``W = (wk, f, G, A, lam, cs, pf, mf)``: per-wheel wheel-axes
    velocity, force, sliding flag and load (``wk``), the world-frame force sums per body ``f``
    (tyres and contacts, z order), the constraint multipliers ``lam`` (hitch forces on the
    front body [N], then stop moments [N m]), the heading cosines/sines ``cs`` and the contact
    powers ``pf``.  Returns the number of multipliers ``m``.

    Tyre forces (the shared tyre kernel) and penalty contact forces, then the
    Baumgarte-stabilised multiplier solve ``(G M^-1 G^T) lam = -(G M^-1 f + gamma +
    2 zeta w0 g' + w0^2 g)``; the bodies of parked vehicles are frozen (zero derivative).
    """
    body, hitch, minv, cfg, icfg, bveh = M[0], M[3], M[5], M[11], M[12], M[19]
    lk_j, lk_th, nlk, parked = D[1], D[2], D[3][0], D[7]
    f, G, A, lam, cs = W[1], W[2], W[3], W[4], W[5]
    nb = body.shape[0]
    nh = hitch.shape[0]
    tyre_eval(y, M, sw, D, W)
    if M[26].shape[0] > 0:
        contact_forces(y, M, D, cs, f, W[6], W[7])
    n3 = 3 * nb
    m = 0
    if nh > 0:
        m = constraint_rows(y, cs, M, lk_j, lk_th, nlk, G, lam, True)
        for a in range(m):
            s = 0.0
            for col in range(n3):
                s += G[a, col] * minv[col] * f[col]
            lam[a] = -(s + lam[a])
            for b in range(a + 1):
                s = 0.0
                for col in range(n3):
                    s += G[a, col] * minv[col] * G[b, col]
                A[a, b] = s
                A[b, a] = s
        solve_spd(A, lam, m)
    for col in range(n3):
        dydt[col] = y[n3 + col]
        s = f[col]
        for a in range(m):
            s += G[a, col] * lam[a]
        dydt[n3 + col] = minv[col] * s
    lt = icfg[I_LT] != 0
    if lt:
        tau = cfg[C_TAU]
        for i in range(nb):
            c = cs[0, i]
            s = cs[1, i]
            accx = dydt[n3 + i]
            accy = dydt[n3 + nb + i]
            dydt[6 * nb + i] = ((c * accx + s * accy) - y[6 * nb + i]) / tau
            dydt[7 * nb + i] = ((c * accy - s * accx) - y[7 * nb + i]) / tau
    for i in range(nb):
        if parked[bveh[i]] != 0:
            for fld in range(8 if lt else 6):
                dydt[fld * nb + i] = 0.0
    return m


@njit(**_HOT)
def rest_measure(y, M, v):
    """``max over the bodies of vehicle v (all vehicles if v < 0) of max(|v_cg|, |yaw rate| L_ref)`` [m/s]."""
    body, bveh = M[0], M[19]
    nb = body.shape[0]
    out = 0.0
    for i in range(nb):
        if v >= 0 and bveh[i] != v:
            continue
        sp = math.sqrt(y[3 * nb + i] ** 2 + y[4 * nb + i] ** 2)
        rot = abs(y[5 * nb + i]) * body[i, 2]
        out = max(out, max(sp, rot))
    return out


@njit(**_HOT)
def contact_group(M, D, v):
    """Bit mask of the vehicles linked to vehicle ``v`` by sustained contacts, directly or
    through others (``v`` included); only ``v`` in scenes of more than 62 vehicles."""
    pstate = D[5]
    bveh, pr_body = M[19], M[26]
    mask = np.int64(1) << v
    if D[7].shape[0] > 62:
        return mask
    changed = True
    while changed:
        changed = False
        for p in range(pr_body.shape[0]):
            if pstate[p] != PS_CONTACT or pr_body[p, 1] < 0:
                continue
            va = bveh[pr_body[p, 0]]
            vb = bveh[pr_body[p, 1]]
            if ((mask >> va) & 1) != ((mask >> vb) & 1):
                mask |= (np.int64(1) << va) | (np.int64(1) << vb)
                changed = True
    return mask


@njit(**_HOT)
def group_rest_measure(y, M, D, v):
    """Rest measure of vehicle ``v`` together with every moving vehicle of its contact group
    (the largest of their rest measures) [m/s].

    A vehicle pressed by a moving one cannot park; its rest event is the group's, so that the
    group comes to rest at one instant instead of the event firing again and again while the
    partner still moves (event chattering, found by the scene fuzz).
    """
    parked = D[7]
    out = rest_measure(y, M, v)
    if M[26].shape[0] == 0:
        return out
    mask = contact_group(M, D, v)
    for w in range(parked.shape[0]):
        if w != v and (mask >> w) & 1 and parked[w] == 0:
            out = max(out, rest_measure(y, M, w))
    return out


@njit(**_HOT)
def kinetic_energy(y, M):
    body = M[0]
    nb = body.shape[0]
    e = 0.0
    for i in range(nb):
        e += body[i, 0] * (y[3 * nb + i] ** 2 + y[4 * nb + i] ** 2) + body[i, 1] * y[5 * nb + i] ** 2
    return 0.5 * e


@njit(**_INLINE)
def quad_integrand(y, M, D, W, out):
    """Integrands of the path integrals at a state just evaluated (``W`` filled by :func:`evaluate`).

    ``out`` (nb + 3 nw + np + nw): CG speeds [m/s], contact speeds [m/s], contact speeds while
    sliding [m/s], dissipated tyre power ``-F . v`` [W], the contacts' power on the bodies [W];
    then the sliding flags (1/0), which are not integrated but tell where the sliding-length
    integrand jumps.
    """
    nb = M[0].shape[0]
    nw = M[1].shape[0]
    npr = M[26].shape[0]
    wk = W[0]
    pf = W[6]
    bveh, parked = M[19], D[7]
    for i in range(nb):
        out[i] = 0.0 if parked[bveh[i]] != 0 else math.sqrt(y[3 * nb + i] ** 2 + y[4 * nb + i] ** 2)
    for k in range(nw):
        sp = math.sqrt(wk[k, W_U] ** 2 + wk[k, W_V] ** 2)
        out[nb + k] = sp
        out[nb + nw + k] = sp if wk[k, W_SLIDE] != 0.0 else 0.0
        out[nb + 2 * nw + k] = -(wk[k, W_FX] * wk[k, W_U] + wk[k, W_FY] * wk[k, W_V])
    for p in range(npr):
        out[nb + 3 * nw + p] = pf[p]
    for k in range(nw):
        out[nb + 3 * nw + npr + k] = wk[k, W_SLIDE]


@njit(**_INLINE)
def wheel_arm(M, k, cs):
    """Body of contact ``k`` and the contact's offset from that body's CG in world axes [m]
    (``cs``: heading cosines/sines of the bodies)."""
    wheel, wbody = M[1], M[2]
    i = wbody[k]
    c = cs[0, i]
    s = cs[1, i]
    rx = wheel[k, 0]
    ry = wheel[k, 1]
    return i, c * rx - s * ry, s * rx + c * ry


@njit(**_INLINE)
def wheel_xy(y, M, k, cs):
    """World position [m] of contact ``k``."""
    nb = M[0].shape[0]
    i, dx, dy = wheel_arm(M, k, cs)
    return y[i] + dx, y[nb + i] + dy


@njit(**_HOT)
def wheel_velocity(y, M, k, cs):
    """World velocity [m/s] of contact ``k``."""
    nb = M[0].shape[0]
    i, dx, dy = wheel_arm(M, k, cs)
    w = y[5 * nb + i]
    return y[3 * nb + i] - w * dy, y[4 * nb + i] + w * dx


# ============================================================================= friction zones
@njit(**_HOT)
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


@njit(**_HOT)
def membership(y, M, out, cs):
    """Zone membership of every wheel (nw, nz), assigning wheels on an edge by their direction of motion.

    A wheel within 1 nm of an edge is inside if the point 1 micrometre ahead along its
    velocity is inside.
    """
    wheel, zone_mu, zone_ptr, edges = M[1], M[8], M[9], M[10]
    nw = wheel.shape[0]
    nz = zone_mu.shape[0]
    body_trig(y, M[0].shape[0], cs)
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


# ============================================================================= events
@njit(**_HOT)
def event_value(e, y, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W):
    """Value of event ``e`` of the segment at state ``y`` (module docstring for the kinds)."""
    kind = ev_kind[e]
    if kind == EV_REST:
        return group_rest_measure(y, M, D, ev_idx[e]) - M[11][C_VSTOP]
    nb = M[0].shape[0]
    cs = W[5]
    if kind == EV_ZONE:
        z = ev_idx[e]
        zone_ptr, edges = M[9], M[10]
        memb = D[0]
        body_trig(y, nb, cs)
        g = math.inf
        for k in range(M[1].shape[0]):
            px, py = wheel_xy(y, M, k, cs)
            side = 1.0 if memb[k, z] else -1.0
            g = min(g, side * signed_distance(px, py, z, zone_ptr, edges))
        return g + ZONE_OVERSHOOT
    if kind == EV_STOP:
        j = ev_idx[e]
        hbody = M[20]
        # ev_val = offset + limit + shift (upper stop) or offset - limit - shift (lower stop)
        return y[2 * nb + hbody[j, 0]] - y[2 * nb + hbody[j, 1]] - ev_val[e]
    if kind == EV_RELEASE:
        # multiplier of closed stop n times its side, > 0 when the stop would have to pull
        n = ev_idx[e]
        nh = M[3].shape[0]
        evaluate(y, M, sw, D, dydt, W)
        return W[4][2 * nh + n] * ev_val[e]
    body_trig(y, nb, cs)
    if kind == EV_STRIKE:
        return strike_speed(y, M, D, cs, ev_idx[e], W[7], True) - M[29][ev_idx[e], R_VTHR]
    g = pair_gap(y, M, cs, ev_idx[e])
    if kind == EV_GAP:
        return g
    if kind == EV_ARM:
        return g - M[29][ev_idx[e], R_ARM]
    # EV_PRESS: deeper than the allowance plus the arming distance
    return -g - ev_val[e]


@njit(**_HOT)
def event_rate(e, y, M, ev_kind, ev_idx, W):
    """Bound on ``|d(event value)/dt|`` of a distance-like event at ``y`` [m/s] (0 for the others).

    Zones: the fastest wheel; pairs: ``|v_A - v_B| + |w_A| R_A + |w_B| R_B`` with ``R`` the
    largest bounding-circle reach of each body's pieces.  A step along which the value could
    change sign twice (``min(|g_start|, |g_end|) < rate x step``) is searched on its dense output.
    """
    kind = ev_kind[e]
    nb = M[0].shape[0]
    if kind == EV_ZONE:
        cs = W[5]
        body_trig(y, nb, cs)
        v = 0.0
        for k in range(M[1].shape[0]):
            vx, vy = wheel_velocity(y, M, k, cs)
            v = max(v, math.sqrt(vx * vx + vy * vy))
        return v
    if kind == EV_GAP or kind == EV_ARM or kind == EV_PRESS:
        pr_body, pr_ptr, pp, pc_info = M[26], M[27], M[28], M[25]
        p = ev_idx[e]
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
        dvx = y[3 * nb + ia]
        dvy = y[4 * nb + ia]
        rot = abs(y[5 * nb + ia]) * ra
        if ib >= 0:
            dvx -= y[3 * nb + ib]
            dvy -= y[4 * nb + ib]
            rot += abs(y[5 * nb + ib]) * rb
        return math.sqrt(dvx * dvx + dvy * dvy) + rot
    return 0.0


@njit(**_HOT)
def event_resolution(e, M, ev_kind, ev_idx):
    """Finest feature [m] a distance-like event must not step over (0 for the others)."""
    kind = ev_kind[e]
    if kind == EV_ZONE:
        return M[11][C_ZRES]
    if kind == EV_GAP or kind == EV_ARM or kind == EV_PRESS:
        return M[29][ev_idx[e], R_RES]
    return 0.0


@njit(**_HOT)
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


@njit(**_HOT)
def _event_on_step(e, tq, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W):
    interpolate(tq, t_old, h, y_old, Q, ytmp)
    return event_value(e, ytmp, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)


@njit(**_HOT)
def brent(e, ta, tb, fa, fb, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W):
    """Root of event ``e`` on a step's dense output in [ta, tb], values fa, fb: Brent's method as scipy's brentq.

    Tolerances ``xtol = rtol = 4 eps`` as solve_ivp's event location.  If the values do not
    differ in sign (round-off at a root on the interval end), the interval end is returned.
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
            return xcur
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
        fcur = _event_on_step(e, xcur, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)
    return xcur


@njit(**_INLINE)
def _crosses(g0, g1, direction):
    return (direction > 0 and g0 <= 0.0 and g1 >= 0.0) or (direction < 0 and g0 >= 0.0 and g1 <= 0.0)


@njit(**_HOT)
def first_root(t, t_new, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, ev_dir, n_ev, g_old, g_new, rate_old,
               rate_new, D, sw, dydt, W):
    """Earliest event of a step [t, t_new]: ``(root time, event)``, event -1 if none.

    An event fires where its value crosses zero in its direction.  For distance-like events
    (zones, contact gaps) a step long enough for the value to cross and cross back
    (``min(|g_old|, |g_new|) < rate x h``, with the larger of the rates at the two ends) is
    also searched at points of its dense output no further apart than the event's resolution
    (at most ``MAX_SUBSAMPLES``): a wheel cannot step over the corner of a zone, nor a body
    through a thin obstacle, by a step longer than the feature.  The root is located by
    Brent's method on the dense output.
    """
    t_first = math.inf
    fired = -1
    for e in range(n_ev):
        a = g_old[e]
        b = g_new[e]
        d = ev_dir[e]
        reach = max(rate_old[e], rate_new[e]) * 1.5 * h
        if reach > 0.0 and min(abs(a), abs(b)) < reach:
            res = event_resolution(e, M, ev_kind, ev_idx)
            n_sub = min(MAX_SUBSAMPLES, max(1, int(math.ceil(reach / max(res, 1e-9)))))
        else:
            n_sub = 1
        ta = t
        fa = a
        for k in range(1, n_sub + 1):
            if k == n_sub:
                tb = t_new
                fb = b
            else:
                tb = t + (t_new - t) * k / n_sub
                if tb >= t_first:
                    break
                fb = _event_on_step(e, tb, t, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)
            if _crosses(fa, fb, d):
                root = brent(e, ta, tb, fa, fb, t, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)
                if root < t_first:
                    t_first = root
                    fired = e
                break
            ta = tb
            fa = fb
    return t_first, fired


# ============================================================================= what happens at events
@njit(**_HOT)
def project_velocities(y, M, lk_j, lk_th, nlk, G, A, b, cs):
    """Velocities satisfying ``G z' = 0`` closest in the kinetic-energy metric (in place in ``y``)."""
    minv = M[5]
    nb = M[0].shape[0]
    n3 = 3 * nb
    body_trig(y, nb, cs)
    m = constraint_rows(y, cs, M, lk_j, lk_th, nlk, G, b, False)
    for a in range(m):
        s = 0.0
        for col in range(n3):
            s += G[a, col] * y[n3 + col]
        b[a] = s
        for c in range(a + 1):
            s = 0.0
            for col in range(n3):
                s += G[a, col] * minv[col] * G[c, col]
            A[a, c] = s
            A[c, a] = s
    solve_spd(A, b, m)
    for col in range(n3):
        s = 0.0
        for a in range(m):
            s += G[a, col] * b[a]
        y[n3 + col] -= minv[col] * s


@njit(**_HOT)
def consistent_accelerations(y, M, sw, D, dydt, W):
    """Set the filtered accelerations to their quasi-static fixed point (50 iterations at most, 1e-10)."""
    nb = M[0].shape[0]
    n3 = 3 * nb
    for _ in range(50):
        evaluate(y, M, sw, D, dydt, W)
        cs = W[5]
        change = 0.0
        for i in range(nb):
            c = cs[0, i]
            s = cs[1, i]
            accx = dydt[n3 + i]
            accy = dydt[n3 + nb + i]
            new_x = c * accx + s * accy
            new_y = c * accy - s * accx
            change = max(change, abs(new_x - y[6 * nb + i]), abs(new_y - y[7 * nb + i]))
            y[6 * nb + i] = new_x
            y[7 * nb + i] = new_y
        if change < 1e-10:
            break


@njit(**_HOT)
def build_events(M, D, offsets, ev_kind, ev_idx, ev_val, ev_dir):
    """The events of a segment in mode ``D`` (filled in place); returns their number.

    Order: the rest of every moving vehicle, every zone, the stops of every hitch that has a
    limit and is not closed (each side), the release of every closed stop, then per pair the
    gap (armed), the arming distance (disarmed or in contact), the press (disarmed) and the
    strike (disarmed or in contact: a point pressed beyond the allowance closing at the
    impulse threshold or faster, :func:`strike_speed`).
    """
    hitch, zone_mu, pr_par, pr_body = M[3], M[8], M[29], M[26]
    lk_j, lk_th, nlk, shift, pstate, pref, parked = D[1], D[2], D[3][0], D[4], D[5], D[6], D[7]
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
            ev_val[n_ev] = pref[p, A_DEPTH] + pr_par[p, R_ARM]
            ev_dir[n_ev] = 1.0
            n_ev += 1
        if pstate[p] != PS_ARMED:
            ev_kind[n_ev] = EV_STRIKE
            ev_idx[n_ev] = p
            ev_dir[n_ev] = 1.0
            n_ev += 1
    return n_ev


@njit(**_INLINE)
def _log(rec, n, kind, i, j, x, e):
    rec[n, 0] = kind
    rec[n, 1] = i
    rec[n, 2] = j
    rec[n, 3] = x
    rec[n, 4] = e
    return n + 1


@njit(**_HOT)
def _left_stop_shift(y, M, j, offset, lim, shift):
    """Raised threshold of the stop of hitch ``j`` when it is left: past where it was left, plus STOP_HYSTERESIS."""
    nb = M[0].shape[0]
    hbody = M[20]
    excess = abs(y[2 * nb + hbody[j, 0]] - y[2 * nb + hbody[j, 1]] - offset) - lim
    return max(shift, excess) + STOP_HYSTERESIS


@njit(**_HOT)
def deepest_pieces(y, M, cs, p):
    """The piece pair of pair ``p`` with the least gap: ``(gap, piece a, piece b)``."""
    pr_ptr, pp = M[27], M[28]
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


@njit(**_HOT)
def touch_geometry(y, M, p, cs, mf, geo):
    """Contact point, normal (from B into A) and normal relative velocity of pair ``p`` at a touch.

    The piece pair of least gap gives the manifold (points within 1 mm of touching); the point
    is the mean of its points (the middle of an edge-on contact).  ``geo`` receives
    ``(x, y, nx, ny, u_n)``, ``u_n = (v_A - v_B) . n`` at the point (< 0: approaching).
    Returns False if no manifold point was found (a touch at a vertex, numerically).
    """
    pr_body = M[26]
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


@njit(**_INLINE)
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


@njit(**_HOT)
def _strike_scan(y, M, D, cs, p, mf, margin, floor, geo, crush):
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
    pr_body, pr_ptr, pp = M[26], M[27], M[28]
    ia = pr_body[p, 0]
    ib = pr_body[p, 1]
    depth_allowance = D[6][p, A_DEPTH]
    radius = D[6][p, A_R]
    disarmed = D[5][p] == PS_DISARMED
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


@njit(**_HOT)
def strike_speed(y, M, D, cs, p, mf, crush):
    """Largest closing speed [m/s] of the points of pair ``p`` pressed beyond its allowance
    (0 if none: a pair apart, or only in its crush allowance, does not strike).

    The strike event of a pair in sustained contact or disarmed is this minus the impulse
    threshold: it crosses zero when a point arrives at the surface (or beyond the crush of the
    first impact) closing at the threshold or faster (the value jumps there; the root is the
    arrival), or when a point already in contact is driven in that fast.  Either is an impact.
    """
    # an infinite floor writes no geometry (mf[0] only stands in for the unused argument)
    best = _strike_scan(y, M, D, cs, p, mf, 0.0, math.inf, mf[0], crush)
    return best if best > 0.0 else 0.0


@njit(**_HOT)
def strike_geometry(y, M, D, cs, p, mf, geo):
    """Contact point, normal and normal relative velocity of a strike of pair ``p`` (``geo`` as
    :func:`touch_geometry`), at a state where :func:`strike_speed` reaches the threshold.

    The points count that lie within 1 mm of the surface (the root of a jump is located to
    round-off on either side of the arrival) and close at the threshold or faster (to a
    relative 1e-6); the point is their mean in the piece pair of the fastest.  Returns False
    if no point closes that fast.
    """
    thr = M[29][p, R_VTHR]
    floor = thr * (1.0 - 1e-6)
    geo[4] = 0.0
    best = _strike_scan(y, M, D, cs, p, mf, 1e-3, floor, geo, True)
    return best >= floor and geo[4] < 0.0


@njit(**_HOT)
def find_strike(y, M, D, cs, mf, geo):
    """The pair in sustained contact or disarmed whose points close fastest beyond its impulse
    threshold at ``y`` (after a velocity jump: an impulse, an articulation-stop impact), with
    its strike geometry in ``geo`` = (pair, x, y, nx, ny, u_n); False if none.

    An impulse at one point can leave another point of the same pair, or a pair of the bodies
    it moved, striking at that instant: each is an impact of its own."""
    pstate, pr_par = D[5], M[29]
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


@njit(**_HOT)
def unpark_pair(M, D, p):
    """Both vehicles of pair ``p`` move again (a contact force or an impulse acts on them)."""
    pr_body, bveh = M[26], M[19]
    parked = D[7]
    parked[bveh[pr_body[p, 0]]] = 0
    if pr_body[p, 1] >= 0:
        parked[bveh[pr_body[p, 1]]] = 0


@njit(**_HOT)
def handle_event(e, t, y, M, D, offsets, ev_kind, ev_idx, ev_val, ev_dir, sw, dydt, W, rec, geo):
    """Apply event ``e`` of the segment at state ``y`` (changed in place, with the mode ``D``).

    Log records go to ``rec`` (rows: kind, i, j, x, energy).  Returns ``(impact, n_records)``:
    ``impact`` is True when a touch needs an impulse (``geo`` then holds the pair, point,
    normal and approach speed: ``(p, x, y, nx, ny, u_n)``), which the caller solves with the
    impact solver (Python) before the run goes on.  Rest and zone events change nothing here:
    :func:`settle` updates zone membership and parks other resting vehicles after every event.
    """
    kind = ev_kind[e]
    idx = ev_idx[e]
    hitch, pr_par = M[3], M[29]
    lk_j, lk_th, lk_n, shift, pstate, pref = D[1], D[2], D[3], D[4], D[5], D[6]
    nh = hitch.shape[0]
    n = 0
    if kind == EV_REST:
        # the event says the vehicle and its contact partners are at rest (located to round-off
        # either side of v_stop): park them
        v_stop = M[11][C_VSTOP] * (1.0 + 1e-9)
        parked = D[7]
        if parked[idx] == 0:
            n = _try_park(idx, y, M, D, rec, n)
        mask = contact_group(M, D, idx)
        for w in range(parked.shape[0]):
            if parked[w] == 0 and parked[idx] != 0 and (mask >> w) & 1 and rest_measure(y, M, w) <= v_stop:
                n = _try_park(w, y, M, D, rec, n)
        return False, n
    if kind == EV_STOP:
        # plastic impact at the stop, then close it unless the bodies separate
        j = idx
        side = ev_dir[e]
        lim = hitch[j, 4]
        nlk = lk_n[0]
        theta_lock = side * lim + offsets[j]
        lk_j[nlk] = j
        lk_th[nlk] = theta_lock
        ke_before = kinetic_energy(y, M)
        project_velocities(y, M, lk_j, lk_th, nlk + 1, W[2], W[3], W[4], W[5])
        loss = ke_before - kinetic_energy(y, M)
        lk_n[0] = nlk + 1
        evaluate(y, M, sw, D, dydt, W)
        lam_last = W[4][2 * nh + nlk]
        if lam_last * side <= 0:
            n = _log(rec, n, LOG_STOP_CLOSED, j, 0, side * lim, loss)
        else:
            lk_n[0] = nlk
            shift[j] = _left_stop_shift(y, M, j, offsets[j], lim, shift[j])
            n = _log(rec, n, LOG_STOP_IMPACT, j, 0, side * lim, loss)
        # the stop impact changed velocities: a point in contact may now strike
        return find_strike(y, M, D, W[5], W[7], geo), n
    if kind == EV_RELEASE:
        q0 = idx
        jq = lk_j[q0]
        n = _log(rec, n, LOG_STOP_OPEN, jq, 0, 0.0, 0.0)
        shift[jq] = _left_stop_shift(y, M, jq, offsets[jq], hitch[jq, 4], shift[jq])
        nlk = lk_n[0]
        for q in range(q0, nlk - 1):
            lk_j[q] = lk_j[q + 1]
            lk_th[q] = lk_th[q + 1]
        lk_n[0] = nlk - 1
        return False, n
    if kind == EV_GAP:
        p = idx
        cs = W[5]
        body_trig(y, M[0].shape[0], cs)
        found = touch_geometry(y, M, p, cs, W[7], geo[1:])
        geo[0] = p
        if found and geo[5] < -pr_par[p, R_VTHR]:
            return True, n
        pstate[p] = PS_CONTACT
        for c in range(N_A):
            pref[p, c] = 0.0
        unpark_pair(M, D, p)
        n = _log(rec, n, LOG_CONTACT, p, 0, geo[5] if found else 0.0, 0.0)
        # slow at the middle of the touching edge, but one end may strike (a turning edge)
        return strike_geometry(y, M, D, cs, p, W[7], geo[1:]), n
    if kind == EV_STRIKE:
        p = idx
        cs = W[5]
        body_trig(y, M[0].shape[0], cs)
        geo[0] = p
        return strike_geometry(y, M, D, cs, p, W[7], geo[1:]), n
    if kind == EV_ARM:
        p = idx
        was = pstate[p]
        pstate[p] = PS_ARMED
        for c in range(N_A):  # apart: the crush of the first impact is behind the pair
            pref[p, c] = 0.0
        n = _log(rec, n, LOG_CONTACT_END if was == PS_CONTACT else LOG_ARMED, p, 0, 0.0, 0.0)
        return False, n
    if kind == EV_PRESS:
        p = idx
        cs = W[5]
        body_trig(y, M[0].shape[0], cs)
        pstate[p] = PS_CONTACT
        pref[p, A_DEPTH] = max(-pair_gap(y, M, cs, p), 0.0)  # the force starts from zero at this depth
        unpark_pair(M, D, p)
        n = _log(rec, n, LOG_PRESS, p, 0, pref[p, A_DEPTH], 0.0)
        # (pressing on into the crush is the first impact's crush going on, however fast: a
        # force; a point outside the crush strikes from the surface, by the strike event)
        return False, n
    return False, n


@njit(**_HOT)
def _try_park(v, y, M, D, rec, n):
    """Park vehicle ``v`` (freeze its bodies) unless it is in contact with a body of another
    vehicle that still moves faster than v_stop; returns the number of log records."""
    pstate, parked = D[5], D[7]
    bveh, pr_body, cfg = M[19], M[26], M[11]
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
    return _log(rec, n, LOG_REST, v, 0, 0.0, 0.0)


@njit(**_HOT)
def settle(y, M, D, new_memb, W, rec, n):
    """After an event or a scheduled change: new zone membership (logged wheel by wheel) and
    parking of the vehicles that came to rest (logged).  Returns the number of records.

    A vehicle parks (its bodies freeze) when its rest measure is at most v_stop (to a relative
    1e-9: a rest event is located to round-off on either side of v_stop), unless it is in
    contact with a body of another vehicle that still moves faster than that.
    """
    memb, parked = D[0], D[7]
    cfg = M[11]
    nw = M[1].shape[0]
    nz = M[8].shape[0]
    if nz > 0:
        membership(y, M, new_memb, W[5])
        for k in range(nw):
            for z in range(nz):
                if new_memb[k, z] != memb[k, z]:
                    n = _log(rec, n, LOG_ZONE_ENTER if new_memb[k, z] else LOG_ZONE_EXIT, k, z, 0.0, 0.0)
                    memb[k, z] = new_memb[k, z]
    v_stop = cfg[C_VSTOP] * (1.0 + 1e-9)
    for v in range(parked.shape[0]):
        if parked[v] == 0 and rest_measure(y, M, v) <= v_stop:
            n = _try_park(v, y, M, D, rec, n)
    return n


def mode_arrays(nw, nz, nh, npairs, nv):
    """A fresh mode tuple ``D`` (Python helper; see the module docstring)."""
    return (np.zeros((nw, nz), np.bool_), np.zeros(max(nh, 1), np.int64), np.zeros(max(nh, 1)),
            np.zeros(1, np.int64), np.zeros(max(nh, 1)), np.zeros(npairs, np.int64), np.zeros((npairs, N_A)),
            np.zeros(nv, np.int64))


# ============================================================================= explicit Runge-Kutta step
@njit(**_HOT)
def _rms_scaled(a, y0, y1, use_both, rtol, atol):
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
_evaluate_inline = njit(**_INLINE)(getattr(evaluate, "py_func", evaluate))  # plain function under NUMBA_DISABLE_JIT


@njit(**_HOT)
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


@njit(**_HOT)
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


# ============================================================================= growable storage
@njit(**_JIT)
def _grow1(a, n):
    out = np.empty(n, a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(**_JIT)
def _grow2(a, n):
    out = np.empty((n,) + a.shape[1:], a.dtype)
    out[: a.shape[0]] = a
    return out


@njit(**_JIT)
def _grow3(a, n):
    out = np.empty((n,) + a.shape[1:], a.dtype)
    out[: a.shape[0]] = a
    return out


# ============================================================================= the run
@njit(**_JIT)
def make_work(M):
    """Work arrays of one evaluation: ``(wk, f, G, A, lam, cs, pf, mf)``."""
    nb = M[0].shape[0]
    nw = M[1].shape[0]
    nh = M[3].shape[0]
    mmax = max(3 * nh, 1)
    return (
        np.zeros((nw, N_W)),
        np.zeros(3 * nb),
        np.zeros((mmax, 3 * nb)),
        np.zeros((mmax, mmax)),
        np.zeros(mmax),
        np.zeros((2, nb)),
        np.zeros(M[26].shape[0]),
        np.zeros((2, 3)),
    )


@njit(cache=True)  # object-mode block: no nogil
def _wall_clock():
    with objmode(now="float64"):
        now = time.perf_counter()
    return now


@njit(**_JIT)
def arming(y, M, D):
    """Initial contact states: a pair closer than its arming distance (the crush of the impact,
    or bodies left touching) starts disarmed with its present depth as allowance and its crush
    circle (in body A's axes: around the contact points of its deepest pieces, reaching
    :data:`CRUSH_REACH` beyond them); the others armed."""
    pr_body, pr_par = M[26], M[29]
    pstate, pref = D[5], D[6]
    W = make_work(M)
    cs = W[5]
    mf = W[7]
    nb = M[0].shape[0]
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


@njit(**_JIT)
def start(y, M, D, t):
    """Prepare a run at ``t``: zone membership, and with load transfer the consistent filtered accelerations."""
    W = make_work(M)
    membership(y, M, D[0], W[5])
    if M[12][I_LT] != 0:
        sw = np.zeros((M[1].shape[0], N_S))
        segment_params(phase_at(t, M[6]), D[0], M, sw)
        consistent_accelerations(y, M, sw, D, np.zeros(y.shape[0]), W)


@njit(**_JIT)
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
    body, hitch, phase_t, zone_mu, cfg, icfg = M[0], M[3], M[6], M[8], M[11], M[12]
    tab_a, tab_b, tab_e, tab_p = M[13], M[14], M[16], M[17]
    memb, lk_j, lk_th, lk_n, pstate, pref, parked = D[0], D[1], D[2], D[3], D[5], D[6], D[7]
    nb = body.shape[0]
    nw = M[1].shape[0]
    nh = hitch.shape[0]
    nz = zone_mu.shape[0]
    npr = M[26].shape[0]
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
                err_norm = _rms_scaled(err, y, y_new, True, rtol, atol)
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
            if n_steps % WALL_CHECK_STEPS == 0 and _wall_clock() > deadline:
                seg_status = -ST_WALL_TIME
                break
            # ---- store the step (start time, size, start state, dense output Q = K^T P)
            if n_steps == st_t.shape[0]:
                cap = 2 * st_t.shape[0]
                st_t = _grow1(st_t, cap)
                st_h = _grow1(st_h, cap)
                st_y = _grow2(st_y, cap)
                st_q = _grow3(st_q, cap)
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
                sg_t = _grow2(sg_t, scap)
                sg_s = _grow2(sg_s, scap)
                sg_phase = _grow1(sg_phase, scap)
                sg_memb = _grow3(sg_memb, scap)
                sg_nlk = _grow1(sg_nlk, scap)
                sg_lkj = _grow2(sg_lkj, scap)
                sg_lkth = _grow2(sg_lkth, scap)
                sg_pstate = _grow2(sg_pstate, scap)
                sg_pref = _grow3(sg_pref, scap)
                sg_parked = _grow2(sg_parked, scap)
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
            n_rec = _log(rec, 0, LOG_SCHEDULE, 0, 0, 0.0, 0.0)
        if not impact:
            n_rec = settle(y, M, D, new_memb, W, rec, n_rec)
        if lg_n + n_rec >= lg_t.shape[0]:
            lcap = 2 * lg_t.shape[0] + n_rec
            lg_t = _grow1(lg_t, lcap)
            lg_rec = _grow2(lg_rec, lcap)
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


@njit(**_JIT)
def reconcile_stops(y, M, D, offsets, veh_mask):
    """Closed articulation stops after an impulse on the vehicles of ``veh_mask`` (a secondary
    impact, solved with the hitches as free pins); returns the log records.

    A closed stop that the impulse turns away from its limit is released (``stop_open``).  Any
    other closed stop of those vehicles takes a plastic stop impact at the same instant, as
    an articulation that reaches its stop does: the velocities are projected onto the closed
    stops (kinetic-energy metric) and the loss is logged as a ``stop_closed`` record of the
    first of them (the stop stays closed).  The crush impulse and the stop's moment impulse
    are thus applied one after the other, not solved together.
    """
    W = make_work(M)
    lk_j, lk_th, lk_n, shift = D[1], D[2], D[3], D[4]
    hitch, hbody, bveh = M[3], M[20], M[19]
    nb = M[0].shape[0]
    rec = np.zeros((2 * max(hitch.shape[0], 1) + 2, 5))
    n = 0
    q = 0
    while q < lk_n[0]:
        j = lk_j[q]
        if veh_mask[bveh[hbody[j, 0]]] == 0:
            q += 1
            continue
        side = 1.0 if lk_th[q] - offsets[j] > 0.0 else -1.0
        rate = y[5 * nb + hbody[j, 0]] - y[5 * nb + hbody[j, 1]]
        if rate * side < 0.0:
            n = _log(rec, n, LOG_STOP_OPEN, j, 0, 0.0, 0.0)
            shift[j] = _left_stop_shift(y, M, j, offsets[j], hitch[j, 4], shift[j])
            for r in range(q, lk_n[0] - 1):
                lk_j[r] = lk_j[r + 1]
                lk_th[r] = lk_th[r + 1]
            lk_n[0] -= 1
        else:
            q += 1
    first = -1
    for q in range(lk_n[0]):
        if veh_mask[bveh[hbody[lk_j[q], 0]]] != 0:
            first = q
            break
    if first >= 0:
        ke_before = kinetic_energy(y, M)
        project_velocities(y, M, lk_j, lk_th, lk_n[0], W[2], W[3], W[4], W[5])
        j = lk_j[first]
        side = 1.0 if lk_th[first] - offsets[j] > 0.0 else -1.0
        n = _log(rec, n, LOG_STOP_CLOSED, j, 0, side * hitch[j, 4], ke_before - kinetic_energy(y, M))
    return rec[:n]


@njit(**_JIT)
def settle_at(y, M, D):
    """:func:`settle` on its own (the start of a run, after an impulse); returns the log records."""
    W = make_work(M)
    rec = np.zeros((M[1].shape[0] * max(M[8].shape[0], 1) + D[7].shape[0] + 8, 5))
    n = settle(y, M, D, np.zeros((M[1].shape[0], M[8].shape[0]), np.bool_), W, rec, 0)
    return rec[:n]


@njit(**_JIT)
def pending_strike(y, M, D):
    """After an impulse: :func:`find_strike` as ``geo`` = (pair, x, y, nx, ny, u_n); pair -1 if none."""
    W = make_work(M)
    body_trig(y, M[0].shape[0], W[5])
    geo = np.zeros(6)
    if not find_strike(y, M, D, W[5], W[7], geo):
        geo[0] = -1.0
    return geo


# ============================================================================= entry points of the SciPy engine
@njit(**_JIT)
def rhs(y, M, phase, D):
    """Right-hand side of one state in wheel phase ``phase`` and mode ``D`` (the SciPy engine's ``fun``)."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    dydt = np.zeros(y.shape[0])
    evaluate(y, M, sw, D, dydt, W)
    return dydt


@njit(**_JIT)
def rhs_work(y, M, phase, D, n):
    """:func:`rhs` of the state ``y[:n]`` followed by the contact powers of every pair [W]: the
    SciPy engine integrates the contact work with the state while pairs are in contact, so the
    work it books is that of the forces its own steps felt (the compiled engine sums the same
    powers with the Runge-Kutta weights of its stages)."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    out = np.zeros(y.shape[0])
    evaluate(y[:n], M, sw, D, out[:n], W)
    for p in range(y.shape[0] - n):
        out[n + p] = W[6][p]
    return out


@njit(**_JIT)
def rhs_many(Y, M, phase, D):
    """:func:`rhs` of the columns of ``Y`` (n, K) (SciPy's implicit methods estimate Jacobians with it)."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    out = np.zeros(Y.shape)
    dydt = np.zeros(Y.shape[0])
    col = np.zeros(Y.shape[0])
    for k in range(Y.shape[1]):
        for i in range(Y.shape[0]):
            col[i] = Y[i, k]
        evaluate(col, M, sw, D, dydt, W)
        for i in range(Y.shape[0]):
            out[i, k] = dydt[i]
    return out


@njit(**_JIT)
def segment_events(M, D, offsets):
    """The events of a segment in mode ``D``: ``(ev_kind, ev_idx, ev_val, ev_dir)`` (:func:`build_events`)."""
    n_max = D[7].shape[0] + M[8].shape[0] + 3 * M[3].shape[0] + 3 * M[26].shape[0] + 1
    ev_kind = np.zeros(n_max, np.int64)
    ev_idx = np.zeros(n_max, np.int64)
    ev_val = np.zeros(n_max)
    ev_dir = np.zeros(n_max)
    n_ev = build_events(M, D, offsets, ev_kind, ev_idx, ev_val, ev_dir)
    return ev_kind[:n_ev], ev_idx[:n_ev], ev_val[:n_ev], ev_dir[:n_ev]


@njit(**_JIT)
def event_values(y, M, phase, D, ev_kind, ev_idx, ev_val):
    """Values and rate bounds of the segment's events at ``y`` (:func:`event_value`, :func:`event_rate`)."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    dydt = np.zeros(y.shape[0])
    n_ev = ev_kind.shape[0]
    g = np.zeros(n_ev)
    r = np.zeros(n_ev)
    for e in range(n_ev):
        g[e] = event_value(e, y, M, ev_kind, ev_idx, ev_val, D, sw, dydt, W)
        r[e] = event_rate(e, y, M, ev_kind, ev_idx, W)
    return g, r


@njit(**_JIT)
def event_resolutions(M, ev_kind, ev_idx):
    out = np.zeros(ev_kind.shape[0])
    for e in range(ev_kind.shape[0]):
        out[e] = event_resolution(e, M, ev_kind, ev_idx)
    return out


@njit(**_JIT)
def event_value_at(e, y, M, phase, D, ev_kind, ev_idx, ev_val):
    """One event value (the SciPy engine's root finder calls it on its dense output)."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    return event_value(e, y, M, ev_kind, ev_idx, ev_val, D, sw, np.zeros(y.shape[0]), W)


@njit(**_JIT)
def apply_event(e, t, y, M, phase, D, offsets, ev_kind, ev_idx, ev_val, ev_dir):
    """:func:`handle_event` then (unless an impulse is needed) :func:`settle`: ``(impact, records, geo)``."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    rec = np.zeros((M[1].shape[0] * max(M[8].shape[0], 1) + D[7].shape[0] + 8, 5))
    geo = np.zeros(6)
    impact, n = handle_event(e, t, y, M, D, offsets, ev_kind, ev_idx, ev_val, ev_dir, sw, np.zeros(y.shape[0]), W,
                             rec, geo)
    if not impact:
        n = settle(y, M, D, np.zeros((M[1].shape[0], M[8].shape[0]), np.bool_), W, rec, n)
    return impact, rec[:n], geo


@njit(**_JIT)
def schedule_change(y, M, D):
    """A scheduled wheel change: the log record, then :func:`settle`."""
    W = make_work(M)
    rec = np.zeros((M[1].shape[0] * max(M[8].shape[0], 1) + D[7].shape[0] + 8, 5))
    n = _log(rec, 0, LOG_SCHEDULE, 0, 0, 0.0, 0.0)
    n = settle(y, M, D, np.zeros((M[1].shape[0], M[8].shape[0]), np.bool_), W, rec, n)
    return rec[:n]


@njit(**_JIT)  # allocates: compiled with reference counting
def segment_mode(s, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked):
    """The mode tuple ``D`` of stored segment ``s`` (copies: evaluating must not change the record)."""
    return (sg_memb[s], sg_lkj[s].copy(), sg_lkth[s].copy(), np.full(1, sg_nlk[s], np.int64),
            np.zeros(sg_lkj.shape[1]), sg_pstate[s].copy(), sg_pref[s].copy(), sg_parked[s].copy())


@njit(**_JIT)
def quad_sums(Yq, wq, seg_of, M, sg_phase, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked):
    """Path integrals from states ``Yq`` (n, K) at quadrature nodes with weights ``wq`` [s] in segments ``seg_of``."""
    nb = M[0].shape[0]
    nw = M[1].shape[0]
    npr = M[26].shape[0]
    nq = nb + 3 * nw + npr
    W = make_work(M)
    sw = np.zeros((nw, N_S))
    dydt = np.zeros(Yq.shape[0])
    yq = np.zeros(Yq.shape[0])
    g = np.zeros(nq + nw)
    out = np.zeros(nq)
    last = -1
    D = segment_mode(0, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked)
    for k in range(Yq.shape[1]):
        s = seg_of[k]
        if s != last:
            D = segment_mode(s, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked)
            segment_params(sg_phase[s], sg_memb[s], M, sw)
            last = s
        for i in range(Yq.shape[0]):
            yq[i] = Yq[i, k]
        evaluate(yq, M, sw, D, dydt, W)
        quad_integrand(yq, M, D, W, g)
        for c in range(nq):
            out[c] += wq[k] * g[c]
    return out


@njit(**_JIT)
def evaluate_columns(Y, M, phase, D, road_mu):
    """Everything the model computes for the states in the columns of ``Y`` (n, K).

    ``road_mu`` (nw,): per-wheel road friction replacing the membership's (NaN: from the
    membership), for the pymunk cross-check's blending across zone edges.  Returns
    ``(dydt (n, K), wk (K, nw, N_W), lam (K, m), f (K, 3 nb))``.
    """
    nw = M[1].shape[0]
    W = make_work(M)
    sw = np.zeros((nw, N_S))
    segment_params(phase, D[0], M, sw)
    phase_w, cfg = M[7], M[11]
    for k in range(nw):
        if not math.isnan(road_mu[k]):
            pw = phase_w[phase, k]
            mu = road_mu[k] * pw[P_MUF]
            dcoef = min(pw[P_BRAKE] * mu + pw[P_FROLL], mu)
            sw[k, S_MU] = mu
            sw[k, S_MULOAD] = mu * M[1][k, 2]
            sw[k, S_DEMAND] = dcoef * M[1][k, 2]
            sw[k, S_DCOEF] = dcoef
    n = Y.shape[0]
    K = Y.shape[1]
    nh = M[3].shape[0]
    m = 2 * nh + D[3][0]
    out = np.zeros((n, K))
    wks = np.zeros((K, nw, N_W))
    lams = np.zeros((K, m))
    fs = np.zeros((K, 3 * M[0].shape[0]))
    dydt = np.zeros(n)
    col = np.zeros(n)
    for j in range(K):
        for i in range(n):
            col[i] = Y[i, j]
        evaluate(col, M, sw, D, dydt, W)
        for i in range(n):
            out[i, j] = dydt[i]
        wks[j] = W[0]
        for a in range(m):
            lams[j, a] = W[4][a]
        fs[j] = W[1]
    return out, wks, lams, fs


# ============================================================================= post-processing
@njit(**_JIT)
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


@njit(**_JIT)
def evaluate_samples(Y, seg_of, M, sg_phase, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked):
    """Evaluated quantities at sampled states ``Y`` (n, K) in segments ``seg_of``.

    Returns ``(P, SL, LD, LAMH, STOPM, CF, max_gap, pen)``: contact positions (nw, K, 2) [m],
    sliding flags and loads [N] (nw, K), hitch forces on the front bodies (K, 2 nh) [N], stop
    moments (K, nh) [N m], the contact force magnitude of every pair (K, np) [N], the largest
    pin gap [m], and per pair the largest depth beyond its allowance while in contact, or the
    largest overlap while armed [m] (how far bodies went into each other).
    """
    nb = M[0].shape[0]
    nw = M[1].shape[0]
    hitch, hbody = M[3], M[20]
    nh = hitch.shape[0]
    npr = M[26].shape[0]
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
    wk, lam, cs = W[0], W[4], W[5]
    sw = np.zeros((nw, N_S))
    dydt = np.zeros(Y.shape[0])
    yq = np.zeros(Y.shape[0])
    f_scratch = np.zeros(3 * nb)
    last = -1
    D = segment_mode(0, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked)
    for p in range(K):
        s = seg_of[p]
        if s != last:
            D = segment_mode(s, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked)
            segment_params(sg_phase[s], sg_memb[s], M, sw)
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
        for q in range(D[3][0]):
            STOPM[p, D[1][q]] = lam[2 * nh + q]
        for j in range(nh):
            f = hbody[j, 0]
            r = hbody[j, 1]
            c0 = cs[0, f]
            sn0 = cs[1, f]
            c1 = cs[0, r]
            sn1 = cs[1, r]
            gx = yq[f] + (c0 * hitch[j, 0] - sn0 * hitch[j, 1]) - yq[r] - (c1 * hitch[j, 2] - sn1 * hitch[j, 3])
            gy = yq[nb + f] + (sn0 * hitch[j, 0] + c0 * hitch[j, 1]) - yq[nb + r] - (sn1 * hitch[j, 2] + c1 * hitch[j, 3])
            max_gap = max(max_gap, math.sqrt(gx * gx + gy * gy))
        for q in range(npr):
            st = D[5][q]
            if st == PS_DISARMED:
                continue
            g = pair_gap(yq, M, cs, q)
            depth = -g - (D[6][q, A_DEPTH] if st == PS_CONTACT else 0.0)
            pen[q] = max(pen[q], depth)
            if st == PS_CONTACT:  # the pair's force on A
                for i in range(3 * nb):
                    f_scratch[i] = 0.0
                pair_forces(yq, M, D, cs, q, f_scratch, W[7])
                ia = M[26][q, 0]
                CF[p, q] = math.sqrt(f_scratch[ia] ** 2 + f_scratch[nb + ia] ** 2)
    return P, SL, LD, LAMH, STOPM, CF, max_gap, pen


@njit(**_JIT)
def contact_samples(Y, seg_of, M, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked):
    """What the pairs do at sampled states ``Y`` (n, K) in segments ``seg_of`` (the geometry only:
    no tyre forces, no multipliers).

    Returns ``(CF, pen, closing)``: the sustained-contact force magnitude on body A of every pair
    (K, np) [N]; per pair the largest depth beyond its allowance while in contact, or the largest
    overlap while armed [m]; and the closing speed [m/s] of the fastest point pressed beyond the
    allowance outside the crush of the first impact (:func:`strike_speed`; 0 for an armed pair),
    (K, np): while a pair is in contact or disarmed this stays below its impulse threshold
    except at the instants of its impacts (a strike there is an impact), an audit of the rule.
    """
    K = Y.shape[1]
    npr = M[26].shape[0]
    nb = M[0].shape[0]
    CF = np.zeros((K, npr))
    closing = np.zeros((K, npr))
    pen = np.zeros(npr)
    W = make_work(M)
    cs = W[5]
    f_scratch = np.zeros(3 * nb)
    y = np.zeros(Y.shape[0])
    last = seg_of[0] if K else 0
    D = segment_mode(last, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked)
    for col in range(K):
        s_ = seg_of[col]
        if s_ != last:
            D = segment_mode(s_, sg_memb, sg_nlk, sg_lkj, sg_lkth, sg_pstate, sg_pref, sg_parked)
            last = s_
        for i in range(Y.shape[0]):
            y[i] = Y[i, col]
        body_trig(y, nb, cs)
        for q in range(npr):
            st = D[5][q]
            if st != PS_ARMED:
                closing[col, q] = strike_speed(y, M, D, cs, q, W[7], False)
            if st == PS_DISARMED:
                continue
            depth = -pair_gap(y, M, cs, q) - (D[6][q, A_DEPTH] if st == PS_CONTACT else 0.0)
            pen[q] = max(pen[q], depth)
            if st == PS_CONTACT:  # the pair's force on A
                for i in range(3 * nb):
                    f_scratch[i] = 0.0
                pair_forces(y, M, D, cs, q, f_scratch, W[7])
                ia = M[26][q, 0]
                CF[col, q] = math.sqrt(f_scratch[ia] ** 2 + f_scratch[nb + ia] ** 2)
    return CF, pen, closing


@njit(**_JIT)
def missed_zone(M, T, P, seg_of, sg_memb):
    """First sample inside a zone the integration did not register: ``(t, wheel)``, wheel -1 if none.

    Points outside a zone's bounding box are outside without the polygon test.
    """
    nw = M[1].shape[0]
    zone_ptr, edges, zone_box = M[9], M[10], M[18]
    nz = zone_box.shape[0]
    for p in range(T.shape[0]):
        g = seg_of[p]
        for z in range(nz):
            for k in range(nw):
                px = P[k, p, 0]
                py = P[k, p, 1]
                if (px < zone_box[z, 0] - 1e-5 or px > zone_box[z, 2] + 1e-5
                        or py < zone_box[z, 1] - 1e-5 or py > zone_box[z, 3] + 1e-5):
                    if sg_memb[g, k, z]:
                        return T[p], k
                    continue
                d = signed_distance(px, py, z, zone_ptr, edges)
                if abs(d) > 1e-6 and (d > 0.0) != sg_memb[g, k, z]:
                    return T[p], k
    return 0.0, -1


# ============================================================================= test hooks
@njit(**_JIT)
def tyre_batch(u, w, mu_load, demand, c_alpha, locked, eps, fiala, fx, fy, sliding):
    """The compiled tyre law (:func:`crashsim.motion.tyres.tyre_kernel`) over arrays, for tests."""
    for i in range(u.shape[0]):
        if locked[i]:
            a, b = tyres.sliding_force(u[i], w[i], mu_load[i], eps)
            fx[i] = a
            fy[i] = b
            sliding[i] = True
        else:
            a, b, sl = tyres.tyre_kernel(u[i], w[i], mu_load[i], demand[i], c_alpha[i], False, eps, fiala)
            fx[i] = a
            fy[i] = b
            sliding[i] = sl


@njit(**_JIT)
def evaluate_state(y, M, phase, D):
    """Right-hand side, per-wheel outputs (``W_*`` columns), multipliers and body forces of one state."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, D[0], M, sw)
    dydt = np.zeros(y.shape[0])
    m = evaluate(y, M, sw, D, dydt, W)
    return dydt, W[0].copy(), W[4][:m].copy(), W[1].copy()


@njit(**_JIT)
def pair_geometry(y, M, p):
    """Gap of pair ``p`` and, where pieces overlap or touch, its contact point and normal (tests, reports)."""
    W = make_work(M)
    cs = W[5]
    body_trig(y, M[0].shape[0], cs)
    geo = np.zeros(5)
    g = pair_gap(y, M, cs, p)
    ok = touch_geometry(y, M, p, cs, W[7], geo)
    return g, ok, geo


def _bind_cache_to_sources():
    """Make the on-disk cache of every kernel depend on this file *and* on tyres.py and options.py.

    numba invalidates a cached function only when the file defining it changes; the kernels
    here compile in the tyre law of :mod:`crashsim.motion.tyres` and constants of
    :mod:`crashsim.motion.options`, so an edit there must invalidate them too.  The cache
    index stamp (numba's stamp of this file) is extended with a SHA-256 of the three sources.
    Uses numba internals; if they change, caching falls back to numba's own rule (and the
    tests compare the compiled tyre law with the NumPy one).
    """
    import hashlib

    from numba.core.dispatcher import Dispatcher

    from . import options

    digest = hashlib.sha256()
    for path in (__file__, tyres.__file__, options.__file__):
        with open(path, "rb") as fh:
            digest.update(fh.read())
    tag = digest.hexdigest()
    for obj in list(globals().values()):
        if isinstance(obj, Dispatcher):
            try:
                cache_file = obj._cache._cache_file
                cache_file._source_stamp = (cache_file._source_stamp, tag)
            except AttributeError:  # pragma: no cover - numba internals changed
                pass


_bind_cache_to_sources()

"""numba kernels of the compiled run-out engine (see :mod:`crashsim.motion.fast` for the design).

Everything here is nopython code on SI floats in flat arrays; the layout of those arrays is
declared once below (the ``C_*``, ``I_*``, ``P_*``, ``S_*``, ``W_*`` column names) and filled by
:mod:`crashsim.motion.fast`.  The state vector has the layout of
:class:`~crashsim.motion.layout.StateLayout` (field-major: X.., Y.., psi.., vx.., vy.., w..,
then the filtered accelerations with load transfer).

The model bundle ``M`` is a tuple of arrays::

    M = (body, wheel, wbody, hitch, transfer, minv, phase_t, phase_w,
         zone_mu, zone_ptr, edges, cfg, icfg, tab_a, tab_b, tab_c, tab_e, tab_p, zone_box)

* ``body`` (nb, 3): mass [kg], yaw inertia [kg m^2], rest reference length L_ref [m];
* ``wheel`` (nw, 3): contact x, y in body axes [m], static load [N]; ``wbody`` (nw,) body index;
* ``hitch`` (nh, 5): front pin x, y [m] (front body axes), rear pin x, y [m] (rear body axes),
  articulation limit [rad] (NaN: none);
* ``transfer`` (nw, 2 nb): load-transfer matrix [N per m/s^2] (unused without load transfer);
* ``minv`` (3 nb,): inverse masses and inertias in z order;
* ``phase_t`` (P,), ``phase_w`` (P, nw, 8): wheel-setting phases (start time [s]; ``P_*`` columns);
* ``zone_mu`` (nz,), ``zone_ptr`` (nz + 1,), ``edges`` (n_edges, 5): friction zones, each edge as
  start x, y [m], edge vector x, y [m], 1/|edge|^2 [1/m^2] (the arrays of
  :func:`crashsim.motion.road._edges`);
* ``cfg`` (float, ``C_*``), ``icfg`` (int, ``I_*``): options;
* ``tab_*``: Butcher tableau, error weights and dense-output matrix of the explicit RK scheme;
* ``zone_box`` (nz, 4): bounding box of each zone, x min, y min, x max, y max [m].

The tyre force law is not written here: :func:`crashsim.motion.tyres.tyre_kernel` (the same
source the SciPy engine runs on arrays) is compiled for scalars through the overloads below.
"""

from __future__ import annotations

import math
import time

import numpy as np
from numba import njit, objmode, types
from numba.extending import overload

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
# owned by their NRT-managed callers (run, postprocess).
_HOT = dict(_JIT, _nrt=False)
# Small helpers are inlined at numba-IR level: a call passes the model and work tuples as a
# few hundred scalar arguments, which cost ~20 % of a right-hand side evaluation.
_INLINE = dict(_HOT, inline="always")

# ----------------------------------------------------------------------------- array layouts
# cfg (float options)
C_EPS, C_ALPHA2, C_BETA2, C_TAU, C_VSTOP, C_RTOL, C_ATOL, C_MAXSTEP, C_FIRST, C_TMAX, C_SDT, C_ROADMU = range(12)
N_CFG = 12
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

# event kinds of a segment
EV_REST, EV_ZONE, EV_STOP, EV_RELEASE = range(4)
# log record kinds
LOG_ZONE_ENTER, LOG_ZONE_EXIT, LOG_SCHEDULE, LOG_STOP_CLOSED, LOG_STOP_IMPACT, LOG_STOP_OPEN = range(6)
# run status
ST_REST, ST_TIME_LIMIT, ST_MAX_SEGMENTS, ST_STEP_TOO_SMALL, ST_NONFINITE, ST_MAX_EVAL, ST_WALL_TIME, ST_NO_PROGRESS = range(8)

# The wall clock is read every this many solver steps.
WALL_CHECK_STEPS = 256

# zone-crossing tolerances: identical to crashsim.motion.simulate
ZONE_TOL = 1e-9
ZONE_OVERSHOOT = 1e-10
# solve_ivp's step-size controller constants (scipy.integrate._ivp.rk)
SAFETY = 0.9
MIN_FACTOR = 0.2
MAX_FACTOR = 10.0
EPS = np.finfo(float).eps


# ============================================================================= model evaluation
@njit(**_HOT)
def segment_params(t_phase, memb, M, sw):
    """Fill ``sw`` (nw, N_S) with the segment inputs of wheel-setting phase ``t_phase`` and zone membership ``memb``.

    The same quantities as :meth:`crashsim.motion.dynamics.RunoutModel.segment`.
    """
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

    Rows ``2j, 2j+1``: pin x, y of hitch j; then one row per closed articulation stop (the
    equations of :func:`crashsim.motion.dynamics.hitch_rows`).  ``cs`` holds the bodies'
    heading cosines and sines (:func:`body_trig`).  Returns ``m``.
    """
    body, hitch, cfg = M[0], M[3], M[11]
    nb = body.shape[0]
    nh = hitch.shape[0]
    m = 2 * nh + nlk
    a2 = cfg[C_ALPHA2]
    b2 = cfg[C_BETA2]
    for a in range(m):
        for col in range(3 * nb):
            G[a, col] = 0.0
    for j in range(nh):
        c0 = cs[0, j]
        s0 = cs[1, j]
        c1 = cs[0, j + 1]
        s1 = cs[1, j + 1]
        hfx, hfy, hrx, hry = hitch[j, 0], hitch[j, 1], hitch[j, 2], hitch[j, 3]
        ax = c0 * hfx - s0 * hfy
        ay = s0 * hfx + c0 * hfy
        bx = c1 * hrx - s1 * hry
        by = s1 * hrx + c1 * hry
        G[2 * j, j] = 1.0
        G[2 * j, j + 1] = -1.0
        G[2 * j, 2 * nb + j] = -ay
        G[2 * j, 2 * nb + j + 1] = by
        G[2 * j + 1, nb + j] = 1.0
        G[2 * j + 1, nb + j + 1] = -1.0
        G[2 * j + 1, 2 * nb + j] = ax
        G[2 * j + 1, 2 * nb + j + 1] = -bx
        if with_rates:
            wf = y[5 * nb + j]
            wr = y[5 * nb + j + 1]
            gx = y[j] + ax - y[j + 1] - bx
            gy = y[nb + j] + ay - y[nb + j + 1] - by
            gdx = y[3 * nb + j] - wf * ay - y[3 * nb + j + 1] + wr * by
            gdy = y[4 * nb + j] + wf * ax - y[4 * nb + j + 1] - wr * bx
            r[2 * j] = (wr * wr * bx - wf * wf * ax) + a2 * gdx + b2 * gx
            r[2 * j + 1] = (wr * wr * by - wf * wf * ay) + a2 * gdy + b2 * gy
    for n in range(nlk):
        jl = lk_j[n]
        jr = jl + 1
        row = 2 * nh + n
        G[row, 2 * nb + jl] = 1.0
        G[row, 2 * nb + jr] = -1.0
        if with_rates:
            cj = cs[0, jl]
            sj = cs[1, jl]
            cr = cs[0, jr]
            sr = cs[1, jr]
            theta = math.atan2(sj * cr - cj * sr, cj * cr + sj * sr)
            g = _wrap(theta - lk_th[n])
            gd = y[5 * nb + jl] - y[5 * nb + jr]
            r[row] = a2 * gd + b2 * g
    return m


@njit(**_INLINE)
def solve_spd(A, b, m):
    """Solve ``A x = b`` in place (x in ``b``) for a small symmetric positive definite ``A`` (m, m).

    Closed form for m = 2 (one hitch, the common case, as the SciPy engine), else Cholesky.
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
def tyre_eval(y, M, sw, W):
    """Tyre forces of state ``y``: per-wheel results in ``W[0]`` (``W_*`` columns), world-frame body sums in ``W[1]``.

    Also fills ``W[5]`` with the body heading cosines and sines.  Locked and jammed contacts
    use the sliding branch alone (:func:`crashsim.motion.tyres.sliding_force`, bitwise the
    same force as the full kernel gives them).
    """
    body, wheel, wbody, transfer, cfg, icfg = M[0], M[1], M[2], M[4], M[11], M[12]
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


@njit(**_HOT)
def evaluate(y, M, sw, lk_j, lk_th, nlk, dydt, W):
    """Right-hand side ``dydt`` of state ``y`` for the segment inputs ``sw`` and closed stops ``lk_*``.

    Also leaves in the work bundle ``W = (wk, f, G, A, lam, cs)``: per-wheel wheel-axes
    velocity, force, sliding flag and load (``wk``, ``W_*`` columns), the world-frame tyre
    force sums per body ``f`` (z order), the constraint multipliers ``lam`` (hitch forces on
    the front body [N], then stop moments [N m]) and the heading cosines/sines ``cs``.
    Returns the number of multipliers ``m``.

    The equations of :meth:`crashsim.motion.dynamics.RunoutModel.evaluate`: per-wheel tyre
    forces from the shared tyre kernel, body sums, then the Baumgarte-stabilised multiplier
    solve ``(G M^-1 G^T) lam = -(G M^-1 f + gamma + 2 zeta w0 g' + w0^2 g)``.
    """
    body, hitch, minv, cfg, icfg = M[0], M[3], M[5], M[11], M[12]
    f, G, A, lam, cs = W[1], W[2], W[3], W[4], W[5]
    nb = body.shape[0]
    nh = hitch.shape[0]
    tyre_eval(y, M, sw, W)
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
    if icfg[I_LT] != 0:
        tau = cfg[C_TAU]
        for i in range(nb):
            c = cs[0, i]
            s = cs[1, i]
            accx = dydt[n3 + i]
            accy = dydt[n3 + nb + i]
            dydt[6 * nb + i] = ((c * accx + s * accy) - y[6 * nb + i]) / tau
            dydt[7 * nb + i] = ((c * accy - s * accx) - y[7 * nb + i]) / tau
    return m


@njit(**_HOT)
def rest_measure(y, M):
    """``max over bodies of max(|v_cg|, |yaw rate| L_ref)`` [m/s]."""
    body = M[0]
    nb = body.shape[0]
    out = 0.0
    for i in range(nb):
        sp = math.sqrt(y[3 * nb + i] ** 2 + y[4 * nb + i] ** 2)
        rot = abs(y[5 * nb + i]) * body[i, 2]
        out = max(out, max(sp, rot))
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
def quad_integrand(y, M, W, out):
    """Integrands of the path integrals at a state just evaluated (``W`` filled by :func:`tyre_eval`).

    ``out`` (nb + 4 nw): CG speeds [m/s], contact speeds [m/s], contact speeds while sliding
    [m/s], dissipated tyre power ``-F . v`` [W]; then the sliding flags (1/0), which are not
    integrated but tell where the sliding-length integrand jumps.
    """
    nb = M[0].shape[0]
    nw = M[1].shape[0]
    wk = W[0]
    for i in range(nb):
        out[i] = math.sqrt(y[3 * nb + i] ** 2 + y[4 * nb + i] ** 2)
    for k in range(nw):
        sp = math.sqrt(wk[k, W_U] ** 2 + wk[k, W_V] ** 2)
        out[nb + k] = sp
        out[nb + nw + k] = sp if wk[k, W_SLIDE] != 0.0 else 0.0
        out[nb + 2 * nw + k] = -(wk[k, W_FX] * wk[k, W_U] + wk[k, W_FY] * wk[k, W_V])
        out[nb + 3 * nw + k] = wk[k, W_SLIDE]


@njit(**_INLINE)
def wheel_xy(y, M, k, cs):
    """World position [m] of contact ``k`` (``cs``: heading cosines/sines of the bodies)."""
    body, wheel, wbody = M[0], M[1], M[2]
    nb = body.shape[0]
    i = wbody[k]
    c = cs[0, i]
    s = cs[1, i]
    rx = wheel[k, 0]
    ry = wheel[k, 1]
    return y[i] + c * rx - s * ry, y[nb + i] + s * rx + c * ry


@njit(**_HOT)
def wheel_velocity(y, M, k, cs):
    """World velocity [m/s] of contact ``k``."""
    body, wheel, wbody = M[0], M[1], M[2]
    nb = body.shape[0]
    i = wbody[k]
    c = cs[0, i]
    s = cs[1, i]
    rx = wheel[k, 0]
    ry = wheel[k, 1]
    dx = c * rx - s * ry
    dy = s * rx + c * ry
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

    As :func:`crashsim.motion.simulate.zone_membership`: a wheel within 1 nm of an edge is
    inside if the point 1 micrometre ahead along its velocity is inside.
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
def event_value(e, y, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W):
    """Value of event ``e`` of the segment at state ``y`` (the functions of :func:`crashsim.motion.simulate._segment_events`)."""
    kind = ev_kind[e]
    if kind == EV_REST:
        return rest_measure(y, M) - M[11][C_VSTOP]
    nb = M[0].shape[0]
    if kind == EV_ZONE:
        z = ev_idx[e]
        zone_ptr, edges = M[9], M[10]
        cs = W[5]
        body_trig(y, nb, cs)
        g = math.inf
        for k in range(M[1].shape[0]):
            px, py = wheel_xy(y, M, k, cs)
            side = 1.0 if memb[k, z] else -1.0
            g = min(g, side * signed_distance(px, py, z, zone_ptr, edges))
        return g + ZONE_OVERSHOOT
    if kind == EV_STOP:
        j = ev_idx[e]
        # ev_val = offset + limit (upper stop) or offset - limit (lower stop)
        return y[2 * nb + j] - y[2 * nb + j + 1] - ev_val[e]
    # EV_RELEASE: multiplier of closed stop n times its side, > 0 when the stop would have to pull
    n = ev_idx[e]
    nh = M[3].shape[0]
    evaluate(y, M, sw, lk_j, lk_th, nlk, dydt, W)
    return W[4][2 * nh + n] * ev_val[e]


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
def _event_on_step(e, tq, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W):
    interpolate(tq, t_old, h, y_old, Q, ytmp)
    return event_value(e, ytmp, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)


@njit(**_HOT)
def locate_event(e, ta, tb, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W):
    """Root of event ``e`` on the step's dense output in [ta, tb]: Brent's method as scipy's brentq.

    Tolerances ``xtol = rtol = 4 eps`` as solve_ivp's event location.  If the interpolant
    does not change sign (round-off at a root on the step end), the step end is returned.
    """
    xtol = 4.0 * EPS
    rtol = 4.0 * EPS
    xpre = ta
    xcur = tb
    fpre = _event_on_step(e, xpre, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)
    fcur = _event_on_step(e, xcur, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)
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
        fcur = _event_on_step(e, xcur, t_old, h, y_old, Q, ytmp, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)
    return xcur


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
def rk_step(y, h, K, y_new, ytmp, M, sw, lk_j, lk_th, nlk, W, tab_a, tab_b, gq):
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
        # stages 1 .. ns-1 at y + h sum_j a_sj K_j; stage ns is the new state y + h sum_j b_j K_j (FSAL)
        coef = tab_a[s] if s < ns else tab_b
        target = ytmp if s < ns else y_new
        for i in range(n):
            acc = 0.0
            for j in range(s):
                acc += coef[j] * K[j, i]
            target[i] = y[i] + h * acc
        _evaluate_inline(target, M, sw, lk_j, lk_th, nlk, K[s], W)
        quad_integrand(target, M, W, gq[s])
    for s in range(1, ns + 1):
        for i in range(n):
            if not math.isfinite(K[s, i]):
                finite = False
    return ns, finite


@njit(**_HOT)
def initial_step(t0, y0, f0, t_bound, max_step, order, rtol, atol, ytmp, f1, M, sw, lk_j, lk_th, nlk, W):
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
    evaluate(ytmp, M, sw, lk_j, lk_th, nlk, f1, W)
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


# ============================================================================= stop impacts
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
def consistent_accelerations(y, M, sw, lk_j, lk_th, nlk, dydt, W):
    """Set the filtered accelerations to their quasi-static fixed point (50 iterations at most, 1e-10)."""
    nb = M[0].shape[0]
    n3 = 3 * nb
    for _ in range(50):
        evaluate(y, M, sw, lk_j, lk_th, nlk, dydt, W)
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


# ============================================================================= the run
@njit(**_JIT)
def make_work(M):
    """Work arrays of one evaluation: ``(wk, f, G, A, lam, cs)``."""
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
    )


@njit(**_HOT)
def _left_stop_shift(y, nb, j, offset, lim, shift):
    """Raised threshold of the stop of hitch ``j`` when it is left: past where it was left, plus STOP_HYSTERESIS."""
    excess = abs(y[2 * nb + j] - y[2 * nb + j + 1] - offset) - lim
    return max(shift, excess) + STOP_HYSTERESIS


@njit(cache=True)  # object-mode block: no nogil
def _wall_clock():
    with objmode(now="float64"):
        now = time.perf_counter()
    return now


@njit(**_JIT)
def run(y0, M, stops, gl_x, gl_w, deadline):
    """Integrate one vehicle's run-out to rest: the segment loop of :func:`crashsim.motion.simulate._integrate`.

    Parameters
    ----------
    y0 : (n,) initial state
    M : model bundle (module docstring)
    stops : sorted segment end times [s] (scheduled changes before t_max, then t_max)
    gl_x, gl_w : Gauss-Legendre nodes and weights on [-1, 1] (path integrals over the part of
        a step cut short by an event)
    deadline : ``time.perf_counter()`` value after which the run stops (``ST_WALL_TIME``)

    Bounds (each ends the run with its own status): ``max_segments`` segments (every restart
    counts, also one that ends where it starts), ``MAX_STILL_SEGMENTS`` consecutive segments
    without progress in time, ``max_evaluations`` right-hand-side evaluations (which also
    bounds the stored steps, so the memory), and the wall-clock ``deadline``.

    Returns
    -------
    tuple
        ``(status, t_end, y_end, y_initial, nfev, n_steps, n_segments, quad, ke_initial, ke_end,
        st_t, st_h, st_y, st_q, sg_t, sg_s, sg_phase, sg_memb, sg_nlk, sg_lkj, sg_lkth,
        lg_n, lg_t, lg_kind, lg_i, lg_j, lg_x, lg_e)``: path integrals ``quad`` (CG path
        lengths [m], contact path lengths [m], their sliding parts [m], dissipated energies [J]),
        steps (start time, size, start state, dense-output matrix), segments (start/end time, first/end step, phase, membership,
        closed stops) and the event log.
    """
    body, hitch, phase_t, zone_mu, cfg, icfg = M[0], M[3], M[6], M[8], M[11], M[12]
    tab_a, tab_b, tab_e, tab_p = M[13], M[14], M[16], M[17]
    nb = body.shape[0]
    nw = M[1].shape[0]
    nh = hitch.shape[0]
    nz = zone_mu.shape[0]
    n = y0.shape[0]
    n3 = 3 * nb
    ns = tab_b.shape[0]
    deg = tab_p.shape[1]
    rtol = cfg[C_RTOL]
    atol = cfg[C_ATOL]
    max_step = cfg[C_MAXSTEP]
    v_stop = cfg[C_VSTOP]
    t_max = cfg[C_TMAX]
    order = icfg[I_ORDER]
    err_exp = -1.0 / (order + 1)
    max_segments = icfg[I_MAXSEG]
    max_eval = icfg[I_MAXEVAL]

    W = make_work(M)
    sw = np.zeros((nw, N_S))
    K = np.zeros((ns + 1, n))
    nq = nb + 3 * nw  # integrated components (gq also carries the nw sliding flags)
    gq = np.zeros((ns + 1, nq + nw))
    gtmp = np.zeros(nq + nw)
    quad = np.zeros(nq)
    ytmp = np.zeros(n)
    ytmp2 = np.zeros(n)
    y_new = np.zeros(n)
    dydt = np.zeros(n)
    err = np.zeros(n)
    lk_j = np.zeros(max(nh, 1), np.int64)
    lk_th = np.zeros(max(nh, 1))
    nlk = 0
    tr_j = np.zeros(max(nh, 1), np.int64)
    tr_th = np.zeros(max(nh, 1))
    memb = np.zeros((nw, nz), np.bool_)
    new_memb = np.zeros((nw, nz), np.bool_)
    n_ev_max = 1 + nz + 3 * nh
    ev_kind = np.zeros(n_ev_max, np.int64)
    ev_idx = np.zeros(n_ev_max, np.int64)
    ev_val = np.zeros(n_ev_max)
    ev_dir = np.zeros(n_ev_max)
    g_old = np.zeros(n_ev_max)
    g_new = np.zeros(n_ev_max)

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
    lcap = 16
    lg_t = np.zeros(lcap)
    lg_kind = np.zeros(lcap, np.int64)
    lg_i = np.zeros(lcap, np.int64)
    lg_j = np.zeros(lcap, np.int64)
    lg_x = np.zeros(lcap)
    lg_e = np.zeros(lcap)
    lg_n = 0
    n_steps = 0
    n_seg = 0
    nfev = 0

    t = 0.0
    y = y0.copy()
    membership(y, M, memb, W[5])
    # 2 pi k offsets of the articulation angles, as simulate._integrate
    offsets = np.zeros(max(nh, 1))
    for j in range(nh):
        raw = y[2 * nb + j] - y[2 * nb + j + 1]
        offsets[j] = raw - _rem2pi(raw + math.pi) + math.pi
    if icfg[I_LT] != 0:
        segment_params(phase_at(t, phase_t), memb, M, sw)
        consistent_accelerations(y, M, sw, lk_j, lk_th, nlk, dydt, W)
    y_initial = y.copy()
    status = -1
    shift = np.zeros(max(nh, 1))  # raised stop thresholds (STOP_HYSTERESIS)
    n_restarts = 0
    n_still = 0

    while True:
        if rest_measure(y, M) <= v_stop:
            status = ST_REST
            break
        if n_restarts >= max_segments:
            status = ST_MAX_SEGMENTS
            break
        if n_still >= MAX_STILL_SEGMENTS:
            status = ST_NO_PROGRESS
            break
        n_restarts += 1
        t_stop = t_max
        for s_ in stops:
            if s_ > t:
                t_stop = s_
                break
        phase = phase_at(t, phase_t)
        segment_params(phase, memb, M, sw)
        # ---- events of this segment (order as simulate._segment_events)
        n_ev = 0
        ev_kind[n_ev] = EV_REST
        ev_dir[n_ev] = -1.0
        n_ev += 1
        for z in range(nz):
            ev_kind[n_ev] = EV_ZONE
            ev_idx[n_ev] = z
            ev_dir[n_ev] = -1.0
            n_ev += 1
        for j in range(nh):
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
        for e in range(n_ev):
            g_old[e] = event_value(e, y, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)

        # ---- integrate the segment [t, t_stop] (solve_ivp's RK driver)
        seg_first_step = n_steps
        t_seg0 = t
        evaluate(y, M, sw, lk_j, lk_th, nlk, K[0], W)
        quad_integrand(y, M, W, gq[0])
        nfev += 1
        if cfg[C_FIRST] > 0.0:
            h_abs = min(cfg[C_FIRST], t_stop - t)
        else:
            h_abs = initial_step(t, y, K[0], t_stop, max_step, order, rtol, atol, ytmp, dydt, M, sw, lk_j, lk_th, nlk, W)
            nfev += 1
        fired = -1
        t_fire = 0.0
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
                k_ev, finite = rk_step(y, h, K, y_new, ytmp, M, sw, lk_j, lk_th, nlk, W, tab_a, tab_b, gq)
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
                g_new[e] = event_value(e, y_new, M, ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)
            t_first = math.inf
            for e in range(n_ev):
                up = g_old[e] <= 0.0 and g_new[e] >= 0.0
                down = g_old[e] >= 0.0 and g_new[e] <= 0.0
                if (up and ev_dir[e] > 0) or (down and ev_dir[e] < 0):
                    root = locate_event(e, t, t_new, t, h, st_y[n_steps - 1], st_q[n_steps - 1], ytmp2, M,
                                        ev_kind, ev_idx, ev_val, memb, sw, lk_j, lk_th, nlk, dydt, W)
                    if root < t_first:
                        t_first = root
                        fired = e
            if fired >= 0:
                # path integrals over [t, t_first] by Gauss-Legendre on the dense output
                half = 0.5 * (t_first - t)
                mid = 0.5 * (t_first + t)
                for q in range(gl_x.shape[0]):
                    interpolate(mid + half * gl_x[q], t, h, st_y[n_steps - 1], st_q[n_steps - 1], ytmp)
                    tyre_eval(ytmp, M, sw, W)
                    quad_integrand(ytmp, M, W, gtmp)
                    for c in range(nq):
                        quad[c] += half * gl_w[q] * gtmp[c]
                interpolate(t_first, t, h, st_y[n_steps - 1], st_q[n_steps - 1], y)
                t = t_first
                seg_status = 1
                break
            # path integrals over the step: the RK solution of q' = g(y) from the stage values,
            # unless a sliding flag switches inside the step (a jump the stage rule, with its
            # negative weight, integrates badly): then 5-point Gauss-Legendre on the dense output,
            # the SciPy engine's rule
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
                    tyre_eval(ytmp, M, sw, W)
                    quad_integrand(ytmp, M, W, gtmp)
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
        # ---- record the segment
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
            sg_t[n_seg, 0] = t_seg0
            sg_t[n_seg, 1] = t
            sg_s[n_seg, 0] = seg_first_step
            sg_s[n_seg, 1] = n_steps
            sg_phase[n_seg] = phase
            sg_memb[n_seg] = memb
            sg_nlk[n_seg] = nlk
            for q in range(nlk):
                sg_lkj[n_seg, q] = lk_j[q]
                sg_lkth[n_seg, q] = lk_th[q]
            n_seg += 1
            n_still = 0
        else:
            n_steps = seg_first_step
            n_still += 1
        if seg_status < 0:
            status = -seg_status
            break
        if lg_n + nw * max(nz, 1) + 2 >= lg_t.shape[0]:
            lcap = 2 * lg_t.shape[0] + nw * max(nz, 1) + 2
            lg_t = _grow1(lg_t, lcap)
            lg_kind = _grow1(lg_kind, lcap)
            lg_i = _grow1(lg_i, lcap)
            lg_j = _grow1(lg_j, lcap)
            lg_x = _grow1(lg_x, lcap)
            lg_e = _grow1(lg_e, lcap)
        if seg_status == 1:
            kind = ev_kind[fired]
            if kind == EV_REST:
                status = ST_REST
                break
            if kind == EV_STOP:
                # plastic impact at the stop, then close it unless the bodies separate (simulate._close_stop)
                j = ev_idx[fired]
                side = ev_dir[fired]
                lim = hitch[j, 4]
                theta_lock = side * lim + offsets[j]
                for q in range(nlk):
                    tr_j[q] = lk_j[q]
                    tr_th[q] = lk_th[q]
                tr_j[nlk] = j
                tr_th[nlk] = theta_lock
                ke_before = kinetic_energy(y, M)
                project_velocities(y, M, tr_j, tr_th, nlk + 1, W[2], W[3], W[4], W[5])
                loss = ke_before - kinetic_energy(y, M)
                segment_params(phase_at(t, phase_t), memb, M, sw)
                evaluate(y, M, sw, tr_j, tr_th, nlk + 1, dydt, W)
                lam_last = W[4][2 * nh + nlk]
                lg_t[lg_n] = t
                lg_i[lg_n] = j
                lg_x[lg_n] = side * lim
                lg_e[lg_n] = loss
                if lam_last * side <= 0:
                    lg_kind[lg_n] = LOG_STOP_CLOSED
                    lk_j[nlk] = j
                    lk_th[nlk] = theta_lock
                    nlk += 1
                else:
                    lg_kind[lg_n] = LOG_STOP_IMPACT
                    shift[j] = _left_stop_shift(y, nb, j, offsets[j], lim, shift[j])
                lg_n += 1
            elif kind == EV_RELEASE:
                q0 = ev_idx[fired]
                lg_t[lg_n] = t
                lg_kind[lg_n] = LOG_STOP_OPEN
                lg_i[lg_n] = lk_j[q0]
                lg_n += 1
                jq = lk_j[q0]
                shift[jq] = _left_stop_shift(y, nb, jq, offsets[jq], hitch[jq, 4], shift[jq])
                for q in range(q0, nlk - 1):
                    lk_j[q] = lk_j[q + 1]
                    lk_th[q] = lk_th[q + 1]
                nlk -= 1
        else:
            if t >= t_max:
                status = ST_TIME_LIMIT
                break
            lg_t[lg_n] = t
            lg_kind[lg_n] = LOG_SCHEDULE
            lg_n += 1
        # ---- new zone membership, crossings logged wheel by wheel (simulate._log_zone_changes)
        if nz > 0:
            membership(y, M, new_memb, W[5])
            for k in range(nw):
                for z in range(nz):
                    if new_memb[k, z] != memb[k, z]:
                        lg_t[lg_n] = t
                        lg_kind[lg_n] = LOG_ZONE_ENTER if new_memb[k, z] else LOG_ZONE_EXIT
                        lg_i[lg_n] = k
                        lg_j[lg_n] = z
                        lg_n += 1
                        memb[k, z] = new_memb[k, z]
    return (status, t, y, y_initial, nfev, n_steps, n_seg, quad, kinetic_energy(y_initial, M), kinetic_energy(y, M),
            st_t[:n_steps], st_h[:n_steps], st_y[:n_steps], st_q[:n_steps],
            sg_t[:n_seg], sg_s[:n_seg], sg_phase[:n_seg], sg_memb[:n_seg], sg_nlk[:n_seg], sg_lkj[:n_seg], sg_lkth[:n_seg],
            lg_n, lg_t[:lg_n], lg_kind[:lg_n], lg_i[:lg_n], lg_j[:lg_n], lg_x[:lg_n], lg_e[:lg_n])


# ============================================================================= post-processing
@njit(**_HOT)
def _step_index(tq, st_t, s0, s1):
    """Last step in [s0, s1) starting at or before ``tq`` (the first one if none)."""
    lo = s0
    hi = s1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if st_t[mid] <= tq:
            lo = mid
        else:
            hi = mid
    return lo


@njit(**_HOT)
def _sample_range(M, sw, lkj, lkth, nlk, p0, p1, T, Y, y_end, last, st_t, st_h, st_y, st_q, s0, s1,
                  P, SL, LD, LAMH, STOPM, yq, dydt, W, max_gap):
    """States and evaluated quantities at samples ``p0 <= p < p1`` of one segment.

    No NRT (no reference counting per sample).  The last sample of the last segment is the
    final state ``y_end`` itself, as in the SciPy engine.  Returns the largest pin gap so far [m].
    """
    nb = M[0].shape[0]
    nw = M[1].shape[0]
    hitch = M[3]
    nh = hitch.shape[0]
    n = yq.shape[0]
    wk = W[0]
    lam = W[4]
    cs = W[5]
    for p in range(p0, p1):
        if (last and p == p1 - 1) or s1 == s0:
            for i in range(n):
                yq[i] = y_end[i]
        else:
            s = _step_index(T[p], st_t, s0, s1)
            interpolate(T[p], st_t[s], st_h[s], st_y[s], st_q[s], yq)
        for i in range(n):
            Y[i, p] = yq[i]
        evaluate(yq, M, sw, lkj, lkth, nlk, dydt, W)
        for k in range(nw):
            px, py = wheel_xy(yq, M, k, cs)
            P[k, p, 0] = px
            P[k, p, 1] = py
            SL[k, p] = wk[k, W_SLIDE] != 0.0
            LD[k, p] = wk[k, W_LOAD]
        for a in range(2 * nh):
            LAMH[p, a] = lam[a]
        for q in range(nlk):
            STOPM[p, lkj[q]] = lam[2 * nh + q]
        for j in range(nh):
            c0 = cs[0, j]
            sn0 = cs[1, j]
            c1 = cs[0, j + 1]
            sn1 = cs[1, j + 1]
            gx = yq[j] + (c0 * hitch[j, 0] - sn0 * hitch[j, 1]) - yq[j + 1] - (c1 * hitch[j, 2] - sn1 * hitch[j, 3])
            gy = yq[nb + j] + (sn0 * hitch[j, 0] + c0 * hitch[j, 1]) - yq[nb + j + 1] - (sn1 * hitch[j, 2] + c1 * hitch[j, 3])
            max_gap = max(max_gap, math.sqrt(gx * gx + gy * gy))
    return max_gap


@njit(**_HOT)
def _missed_zone(M, T, P, counts, sg_memb, n_seg):
    """First sample inside a zone the integration did not register (``postprocess._missed_zone_samples``).

    Order as there: first segment, then first zone, then earliest sample, then lowest wheel.
    Points outside a zone's bounding box are outside without the polygon test.  Returns
    ``(t, wheel)``, wheel -1 if none.
    """
    nw = M[1].shape[0]
    zone_ptr, edges, zone_box = M[9], M[10], M[18]
    nz = zone_box.shape[0]
    start = 0
    for g in range(n_seg):
        for z in range(nz):
            for p in range(start, start + counts[g]):
                for k in range(nw):
                    px = P[k, p, 0]
                    py = P[k, p, 1]
                    if (px < zone_box[z, 0] - 1e-5 or px > zone_box[z, 2] + 1e-5
                            or py < zone_box[z, 1] - 1e-5 or py > zone_box[z, 3] + 1e-5):
                        if sg_memb[g, k, z]:  # clearly outside, registered inside
                            return T[p], k
                        continue
                    d = signed_distance(px, py, z, zone_ptr, edges)
                    if abs(d) > 1e-6 and (d > 0.0) != sg_memb[g, k, z]:
                        return T[p], k
        start += counts[g]
    return 0.0, -1


@njit(**_JIT)
def postprocess(M, t_end, y_end, st_t, st_h, st_y, st_q, sg_t, sg_s, sg_phase, sg_memb, sg_nlk, sg_lkj, sg_lkth,
                sample_dt, check_zones):
    """Sampled histories, wheel tracks and hitch forces of a run.

    Samples as :func:`crashsim.motion.simulate._sample_chunks` (segment start, the
    ``sample_dt`` grid strictly inside, and the end of the run), quantities as
    :func:`crashsim.motion.postprocess.assemble_result`.

    Returns
    -------
    tuple
        ``(T, Y, P, SL, LD, LAMH, STOPM, max_gap, miss_t, miss_k)``: sample times (K,),
        states (n, K), contact positions (nw, K, 2) [m], sliding flags and loads [N] (nw, K),
        hitch forces (K, 2 nh) [N], stop moments (K, nh) [N m], largest pin gap [m], and the
        first sample inside a zone the integration did not register (``miss_k = -1``: none).
    """
    wheel, hitch, zone_mu = M[1], M[3], M[8]
    nw = wheel.shape[0]
    nh = hitch.shape[0]
    nz = zone_mu.shape[0]
    n = y_end.shape[0]
    n_seg = sg_t.shape[0]
    W = make_work(M)
    sw = np.zeros((nw, N_S))
    dydt = np.zeros(n)
    yq = np.zeros(n)

    # ---- sample times: segment start, the sample_dt grid strictly inside, the end of the run
    counts = np.zeros(max(n_seg, 1), np.int64)
    total = 0
    for g in range(n_seg):
        t0 = sg_t[g, 0]
        t1 = sg_t[g, 1]
        c = 1
        for kk in range(math.ceil(t0 / sample_dt - 1e-9), math.floor(t1 / sample_dt) + 1):
            tk = kk * sample_dt
            if tk > t0 and tk < t1:
                c += 1
        if g == n_seg - 1:
            c += 1
        counts[g] = c
        total += c
    if n_seg == 0:
        total = 1
    T = np.zeros(total)
    pos = 0
    for g in range(n_seg):
        t0 = sg_t[g, 0]
        t1 = sg_t[g, 1]
        T[pos] = t0
        pos += 1
        for kk in range(math.ceil(t0 / sample_dt - 1e-9), math.floor(t1 / sample_dt) + 1):
            tk = kk * sample_dt
            if tk > t0 and tk < t1:
                T[pos] = tk
                pos += 1
        if g == n_seg - 1:
            T[pos] = t1
            pos += 1

    # ---- states and evaluated quantities at the samples
    Y = np.zeros((n, total))
    P = np.zeros((nw, total, 2))
    SL = np.zeros((nw, total), np.bool_)
    LD = np.zeros((nw, total))
    LAMH = np.zeros((total, 2 * nh))
    STOPM = np.zeros((total, nh))
    if n_seg == 0:
        # at rest from the start: the segment in force at t_end (simulate.simulate_runout)
        T[0] = t_end
        end_memb = np.zeros((nw, nz), np.bool_)
        membership(y_end, M, end_memb, W[5])
        segment_params(phase_at(t_end, M[6]), end_memb, M, sw)
        max_gap = _sample_range(M, sw, np.zeros(max(nh, 1), np.int64), np.zeros(max(nh, 1)), 0, 0, 1, T, Y, y_end, True,
                                st_t, st_h, st_y, st_q, 0, 0, P, SL, LD, LAMH, STOPM, yq, dydt, W, 0.0)
    else:
        max_gap = 0.0
        start = 0
        for g in range(n_seg):
            segment_params(sg_phase[g], sg_memb[g], M, sw)
            max_gap = _sample_range(M, sw, sg_lkj[g], sg_lkth[g], sg_nlk[g], start, start + counts[g], T, Y, y_end,
                                    g == n_seg - 1, st_t, st_h, st_y, st_q, sg_s[g, 0], sg_s[g, 1],
                                    P, SL, LD, LAMH, STOPM, yq, dydt, W, max_gap)
            start += counts[g]
    miss_t = 0.0
    miss_k = -1
    if check_zones and nz > 0 and n_seg > 0:
        miss_t, miss_k = _missed_zone(M, T, P, counts, sg_memb, n_seg)
    return T, Y, P, SL, LD, LAMH, STOPM, max_gap, miss_t, miss_k


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
def evaluate_state(y, M, phase, memb, lk_j, lk_th, nlk):
    """Right-hand side, per-wheel outputs (``W_*`` columns) and multipliers of one state, for tests."""
    W = make_work(M)
    sw = np.zeros((M[1].shape[0], N_S))
    segment_params(phase, memb, M, sw)
    dydt = np.zeros(y.shape[0])
    m = evaluate(y, M, sw, lk_j, lk_th, nlk, dydt, W)
    return dydt, W[0].copy(), W[4][:m].copy()


def _bind_cache_to_sources():
    """Make the on-disk cache of every kernel depend on this file *and* on tyres.py.

    numba invalidates a cached function only when the file defining it changes; the kernels
    here compile in the tyre law of :mod:`crashsim.motion.tyres`, so an edit there must
    invalidate them too.  The cache index stamp (numba's stamp of this file: a content hash
    in recent numba, ``(mtime, size)`` in older ones) is extended with a SHA-256 of both
    sources.  Uses numba internals; if they change, caching falls back to numba's own rule
    (and ``tests/unit/test_fast_path.py`` compares the compiled tyre law with the NumPy one).
    """
    import hashlib

    from numba.core.dispatcher import Dispatcher

    digest = hashlib.sha256()
    for path in (__file__, tyres.__file__):
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

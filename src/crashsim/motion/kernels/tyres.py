"""Kernel stage: the tyre law compiled for scalars, and the tyre forces of a state.

The tyre module (:mod:`crashsim.motion.tyres`) is written with NumPy ufuncs and
``tyres._select`` (np.where).  For scalars numba compiles the ufuncs to scalar arithmetic;
``_select`` gets a scalar overload, and the two lateral curves are compiled from their own
source, so both engines and the NumPy path evaluate one source.
"""

from __future__ import annotations

import math

from numba import njit, types
from numba.extending import overload

from ..layout import SV_VX, SV_VY, SV_YAW_RATE, SV_AX_F
from .. import tyres as law
from .jit import INLINE, JIT
from .arrays import (B_ABS, B_FALL, B_FORCE, B_OFF, B_ON, B_RISE, C_EPS, I_CASTOR, I_CLOCK, I_FIALA, I_LT, I_SLOPE, S_AIR, S_CASTOR, S_GX, S_GY, S_N0, S_CALPHA, S_CCOEF, S_CD, S_CFIX, S_DCOEF, S_DEMAND, S_LOCKED, S_MU,
    S_MULOAD, S_SD, W_FX, W_FY, W_LOAD, W_M0, W_M1, W_MABS, W_MLIFT, W_MLOCK, W_MSAT, W_SLIDE, W_U, W_V)
from .arrays import S_BBASE, S_BREF, S_BSLOPE
from .geometry import body_trig


# The tyre module is written with NumPy ufuncs and law._select (np.where).  For scalars
# numba compiles the ufuncs to scalar arithmetic; _select gets a scalar overload, and the two
# lateral curves are compiled from their own source.  error_model="numpy": IEEE division
# (as NumPy), no Python ZeroDivisionError checks.
_OV = {"error_model": "numpy"}


@overload(law._select, jit_options=_OV)
def _select_scalar(cond, if_true, if_false):
    if isinstance(cond, types.Boolean):
        return lambda cond, if_true, if_false: if_true if cond else if_false
    return None


@overload(law.fiala_curve, jit_options=_OV)
def _fiala_scalar(tan_alpha, mu_load, cornering_stiffness):
    return law.fiala_curve


@overload(law.linear_curve, jit_options=_OV)
def _linear_scalar(tan_alpha, mu_load, cornering_stiffness):
    return law.linear_curve


@overload(law.sliding_force, jit_options=_OV)
def _sliding_scalar(u, w, mu_load, eps):
    return law.sliding_force


@overload(law.castor_angle, jit_options=_OV)
def _castor_scalar(vx, vy, limit):
    return law.castor_angle


@overload(law.tyre_kernel, jit_options=_OV)
def _tyre_scalar(u, w, mu_load, demand, cornering_stiffness, locked, eps, fiala):
    return law.tyre_kernel


@overload(law.tyre_parts, jit_options=_OV)
def _tyre_parts_scalar(u, w, mu_load, demand, cornering_stiffness, locked, eps, fiala):
    return law.tyre_parts


@njit(**INLINE)
def brake_piece(t, b):
    """The piece of a brake's ramp in force from time ``t`` [s] until its next kink (``b``: its ``B_*``
    row; :func:`crashsim.motion.brakes.ramp_level`): ``(t_ref, base, slope)``, the application level
    being ``base + slope (clock - t_ref)`` on the piece.

    A kink at ``t`` belongs to the piece that starts there.  The kinks are phase boundaries of the
    run (segments end at them), so a segment evaluates one linear piece, never a kink or a jump:
    the clock, integrated with the state, may sit a rounding error off ``t`` at a segment's start,
    and a step of the ramp (``rise`` or ``fall`` 0) looked up by the clock would fall on the wrong
    side of it there.
    """
    on, rise, off, fall = b[B_ON], b[B_RISE], b[B_OFF], b[B_FALL]
    if t < off:
        if t < on:
            return on, 0.0, 0.0
        if rise > 0.0 and t < on + rise:
            return on, 0.0, 1.0 / rise
        return on, 1.0, 0.0
    # released: from the level held at t_off down to zero over fall
    if rise > 0.0:
        held = min(max((off - on) / rise, 0.0), 1.0)
    else:
        held = 1.0 if off >= on else 0.0
    if fall > 0.0 and t < off + fall:
        return off, held, -held / fall
    return off, 0.0, 0.0


@njit(**INLINE)
def air_demand(level, b, u, v, roll, mu_load, eps):
    """Longitudinal demand [N] of a rolling wheel with air brakes (``b``: its ``B_*`` row) at the brake's
    application ``level`` (in [0, 1]), and whether the wheel locks.

    The demand is ``F_b + roll`` with the brake force ``F_b = level F_full``; where it reaches the
    tyre's limit ``mu N`` the wheel locks (slides).  With ABS (``b[B_ABS] = eta > 0``) the demand is
    held to ``eta mu N sqrt(u^2 + eps^2) / sqrt(|v|^2 + eps^2)``, so that the tyre law's longitudinal
    force is ``eta`` times the sliding force's longitudinal component: the wheel never locks.

    Returns ``(demand, locked, margin)``: ``margin`` [N] is the demand minus the ABS limit (>= 0 where
    the limit holds it), NaN without ABS.
    """
    demand = level * b[B_FORCE] + roll
    eta = b[B_ABS]
    if eta > 0.0:
        cap = eta * mu_load * math.sqrt(u * u + eps * eps) / math.sqrt(u * u + v * v + eps * eps)
        return min(demand, cap), False, demand - cap
    return demand, demand >= mu_load and demand > 0.0, math.nan


@njit(**INLINE)
def redistribute_loads(M, wk):
    """Wheel loads that sum to the weight where load transfer lifts wheels (in place in ``wk[:, W_LOAD]``,
    which holds the linear loads ``N_static + T a_f``).

    Body by body (its axles are consecutive, each a left then a right wheel):

    * an axle whose load ``S = N_left + N_right`` would be negative (the body pitching over the
      others) carries none, and the other axles of the body with load give up that deficit in
      proportion to their loads (the body's vertical balance holds while any axle is on the ground);
    * an axle's roll transfer ``R = (N_right - N_left) / 2`` is at most ``S / 2`` (the inner wheel
      at zero, the outer carrying the axle); the roll moment ``(R - S/2) t`` it cannot carry goes to
      the axles of the body that can, in proportion to what each can still take, so the body's roll
      moment ``m a_y h`` is balanced until every inner wheel is off the ground.  Beyond that the unit
      rolls (the rollover check's ``unit_lift``): no planar load balances it, and the loads are those
      of all inner wheels lifted.

    So a lifted wheel carries exactly zero and the others carry the weight (clamping the negative
    loads at zero instead would add the lifted wheels' share to the weight).
    """
    wheel, wbody = M.wheel, M.wheel_body
    na = wheel.shape[0] // 2
    a0 = 0
    while a0 < na:
        i = wbody[2 * a0]
        a1 = a0
        while a1 < na and wbody[2 * a1] == i:
            a1 += 1
        deficit = 0.0
        carrying = 0.0
        for a in range(a0, a1):
            s = wk[2 * a, W_LOAD] + wk[2 * a + 1, W_LOAD]
            if s < 0.0:
                deficit -= s
            else:
                carrying += s
        if deficit > 0.0:
            keep = max(1.0 - deficit / carrying, 0.0) if carrying > 0.0 else 0.0
            for a in range(a0, a1):
                left = wk[2 * a, W_LOAD]
                right = wk[2 * a + 1, W_LOAD]
                s = left + right
                half = 0.5 * (right - left)
                s = s * keep if s > 0.0 else 0.0
                wk[2 * a, W_LOAD] = 0.5 * s - half
                wk[2 * a + 1, W_LOAD] = 0.5 * s + half
        excess = 0.0
        for a in range(a0, a1):
            left = wk[2 * a, W_LOAD]
            right = wk[2 * a + 1, W_LOAD]
            cap = 0.5 * (left + right)
            half = 0.5 * (right - left)
            if abs(half) > cap:
                track = wheel[2 * a, 1] - wheel[2 * a + 1, 1]
                held = math.copysign(cap, half)
                excess += (half - held) * track
                wk[2 * a, W_LOAD] = cap - held
                wk[2 * a + 1, W_LOAD] = cap + held
        if excess != 0.0:
            side = 1.0 if excess > 0.0 else -1.0
            room = 0.0
            for a in range(a0, a1):
                left = wk[2 * a, W_LOAD]
                right = wk[2 * a + 1, W_LOAD]
                track = wheel[2 * a, 1] - wheel[2 * a + 1, 1]
                room += (0.5 * (left + right) - side * 0.5 * (right - left)) * track
            if room > 0.0:
                frac = min(abs(excess) / room, 1.0)
                for a in range(a0, a1):
                    left = wk[2 * a, W_LOAD]
                    right = wk[2 * a + 1, W_LOAD]
                    cap = 0.5 * (left + right)
                    half = 0.5 * (right - left)
                    half += side * frac * (cap - side * half)
                    wk[2 * a, W_LOAD] = max(cap - half, 0.0)
                    wk[2 * a + 1, W_LOAD] = max(cap + half, 0.0)
        a0 = a1


@njit(**INLINE)
def tyre_eval(y, M, sw, D, W, margins=False):
    """Tyre forces of state ``y``: per-wheel results in ``W.wheel_out`` (``W_*`` columns), world-frame body sums in ``W.body_force``.

    The tyre law of the README ("Run-out model"): rolling tyres on the Fiala (or linear)
    lateral curve inside a friction circle with braking priority, locked ones sliding with
    Coulomb friction against the contact-point velocity (:func:`crashsim.motion.tyres.tyre_kernel`),
    each on its load: static (scaled by the slope's normal factor, ``S_N0``), or with load
    transfer ``N = N_static + T a_f`` (``M.load_transfer`` on the filtered accelerations).  On a
    sloped road the in-plane gravity of every body is added to its force sum (``S_GX, S_GY``).  Also fills ``W.trig`` with the body heading cosines and
    sines.  Wheels of parked vehicles produce no force (their bodies are frozen).  A
    self-steering wheel (``S_CASTOR >= 0``, only looked at when ``icfg[I_CASTOR]`` is set) takes
    the steer angle of :func:`crashsim.motion.tyres.castor_angle` instead of its fixed one.  A rolling
    wheel with air brakes (``S_AIR``) takes its longitudinal demand from :func:`air_demand` at the
    application level of the segment's piece of its ramp (``S_BREF, S_BBASE, S_BSLOPE``) at the state's clock.
    With ``margins`` it also writes each wheel's switch margins (``W_MSAT`` .. ``W_MLIFT``), which only a
    rejected step reads (:func:`crashsim.motion.kernels.integrator.kink_fraction`): not in the
    right-hand side.
    """
    body, wheel, wbody, transfer, cfg, icfg, bveh = M.body, M.wheel, M.wheel_body, M.load_transfer, M.cfg, M.icfg, M.body_vehicle
    parked = D.parked
    wk, f, cs = W.wheel_out, W.body_force, W.trig
    nb = body.shape[0]
    nw = wheel.shape[0]
    lt = icfg[I_LT] != 0
    fiala = icfg[I_FIALA] != 0
    castor = icfg[I_CASTOR] != 0
    eps = cfg[C_EPS]
    body_trig(y, nb, cs)
    for i in range(3 * nb):
        f[i] = 0.0
    if lt:
        # every wheel's linear load first, then the lifted wheels' share passed to the others
        for k in range(nw):
            n = sw[k, S_N0]
            for j in range(2 * nb):
                n += transfer[k, j] * y[SV_AX_F * nb + j]
            wk[k, W_MLIFT] = -n
            wk[k, W_LOAD] = n
        redistribute_loads(M, wk)
    for k in range(nw):
        i = wbody[k]
        if parked[bveh[i]] != 0:
            wk[k, W_U] = 0.0
            wk[k, W_V] = 0.0
            wk[k, W_FX] = 0.0
            wk[k, W_FY] = 0.0
            wk[k, W_SLIDE] = 0.0
            wk[k, W_LOAD] = wheel[k, 2]
            if margins:
                for c in range(W_M0, W_M1):
                    wk[k, c] = math.nan
            continue
        c = cs[0, i]
        s = cs[1, i]
        vx = y[SV_VX * nb + i]
        vy = y[SV_VY * nb + i]
        w = y[SV_YAW_RATE * nb + i]
        rx = wheel[k, 0]
        ry = wheel[k, 1]
        cvx = (c * vx + s * vy) - ry * w
        cvy = (c * vy - s * vx) + rx * w
        cd = sw[k, S_CD]
        sd = sw[k, S_SD]
        if castor and sw[k, S_CASTOR] >= 0.0:
            # a self-steering wheel follows its path within its limit (crashsim.motion.tyres.castor_angle)
            delta = law.castor_angle(cvx, cvy, sw[k, S_CASTOR])
            cd = math.cos(delta)
            sd = math.sin(delta)
        u = cd * cvx + sd * cvy
        v = -sd * cvx + cd * cvy
        if lt:
            load = wk[k, W_LOAD]
            mu_load = sw[k, S_MU] * load
            m_lift = wk[k, W_MLIFT]
        else:
            load = sw[k, S_N0]
            mu_load = sw[k, S_MULOAD]
            m_lift = math.nan
        locked = sw[k, S_LOCKED] != 0.0
        demand = 0.0
        c_alpha = 0.0
        m_abs = math.nan
        if not locked:
            if lt:
                demand = sw[k, S_DCOEF] * load
                c_alpha = sw[k, S_CFIX] + sw[k, S_CCOEF] * load
            else:
                demand = sw[k, S_DEMAND]
                c_alpha = sw[k, S_CALPHA]
            if sw[k, S_AIR] != 0.0:
                # the segment's piece of the ramp (brake_piece) at the state's clock
                level = min(max(sw[k, S_BBASE] + sw[k, S_BSLOPE] * (y[icfg[I_CLOCK]] - sw[k, S_BREF]), 0.0), 1.0)
                demand, locked, m_abs = air_demand(level, M.wheel_brake[k], u, v, demand, mu_load, eps)
        if locked:
            fx, fy = law.sliding_force(u, v, mu_load, eps)
            sliding = True
            if margins:
                for c in range(W_M0, W_M1):
                    wk[k, c] = math.nan
                wk[k, W_MLIFT] = m_lift
        elif margins:
            fx, fy, sliding, m_sat, m_lock = law.tyre_parts(u, v, mu_load, demand, c_alpha, False, eps, fiala)
            wk[k, W_MSAT] = m_sat
            wk[k, W_MLOCK] = m_lock
            wk[k, W_MABS] = m_abs
            wk[k, W_MLIFT] = m_lift
        else:
            fx, fy, sliding = law.tyre_kernel(u, v, mu_load, demand, c_alpha, False, eps, fiala)
        wk[k, W_U] = u
        wk[k, W_V] = v
        wk[k, W_FX] = fx
        wk[k, W_FY] = fy
        wk[k, W_SLIDE] = 1.0 if sliding and load > 0.0 else 0.0  # a lifted wheel leaves no mark
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
    if icfg[I_SLOPE] != 0:
        # in-plane gravity at each body's CG (world frame), carried by its wheels' mass shares
        for k in range(nw):
            i = wbody[k]
            if parked[bveh[i]] == 0:
                f[i] += sw[k, S_GX]
                f[nb + i] += sw[k, S_GY]


@njit(**JIT)
def tyre_batch(u, w, mu_load, demand, c_alpha, locked, eps, fiala, fx, fy, sliding):
    """The compiled tyre law (:func:`crashsim.motion.tyres.tyre_kernel`) over arrays, for tests."""
    for i in range(u.shape[0]):
        if locked[i]:
            a, b = law.sliding_force(u[i], w[i], mu_load[i], eps)
            fx[i] = a
            fy[i] = b
            sliding[i] = True
        else:
            a, b, sl = law.tyre_kernel(u[i], w[i], mu_load[i], demand[i], c_alpha[i], False, eps, fiala)
            fx[i] = a
            fy[i] = b
            sliding[i] = sl

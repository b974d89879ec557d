"""Kernel stage: the equations of motion of the scene and what is integrated along them.

Segment inputs per wheel, the right-hand side (tyres + contacts + hitch constraints by
Baumgarte-stabilised multipliers, load-transfer filter), rest measures, kinetic energy,
the path-integral integrands, and the projections used at stop impacts and at the start.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..layout import SV_VX, SV_VY, SV_YAW_RATE, SV_AX_F, SV_AY_F
from .jit import HOT, INLINE, JIT
from .arrays import (I_YAWLOCK, B_HAS, C_GN, C_GX, C_GY, C_ROADMU, C_TAU, I_BRAKE, I_CLOCK, I_LT, I_SLOPE, S_AIR, S_GX, S_GY, S_N0, PS_CONTACT, P_BRAKE, P_CCOEF, P_CD, P_CFIX, P_FROLL, P_LOCKED, P_MUF, P_CASTOR, S_CASTOR,
    P_SD, S_CALPHA, S_CCOEF, S_CD, S_CFIX, S_DCOEF, S_DEMAND, S_LOCKED, S_MU, S_MULOAD, S_SD, W_FX, W_FY, W_SLIDE,
    W_U, W_V)
from .arrays import S_BBASE, S_BREF, S_BSLOPE
from .geometry import body_trig, constraint_rows, solve_spd
from .tyres import brake_piece, tyre_eval
from .contacts import contact_forces


@njit(**HOT)
def segment_params(t_phase, memb, M, sw):
    """Fill ``sw`` (nw, N_S) with the inputs of wheel-setting phase ``t_phase`` and zone membership ``memb``.

    On a sloped road (``icfg[I_SLOPE]``) a wheel's static load is scaled by the normal factor of
    the slope under it, and ``S_GX, S_GY`` hold the in-plane gravity on its share of its body's
    mass (world frame [N]); on a level road they are 0 and the static load is used as it is.
    ``S_AIR`` is 1 for a rolling wheel of a unit with air brakes (``icfg[I_BRAKE]``): its brake force
    then follows the clock (:func:`crashsim.motion.kernels.tyres.air_demand`) on the piece of its ramp
    that the phase holds (``S_BREF, S_BBASE, S_BSLOPE``; :func:`crashsim.motion.kernels.tyres.brake_piece`:
    the ramp's kinks are phase boundaries).
    """
    wheel, phase_w, zone_mu, cfg = M.wheel, M.phase_wheels, M.zone_mu, M.cfg
    nw = wheel.shape[0]
    nz = zone_mu.shape[0]
    slope = M.icfg[I_SLOPE] != 0
    air = M.icfg[I_BRAKE] != 0
    for k in range(nw):
        road_mu = cfg[C_ROADMU]
        zk = -1
        for z in range(nz):
            if memb[k, z]:
                road_mu = zone_mu[z]
                zk = z
        pw = phase_w[t_phase, k]
        mu = road_mu * pw[P_MUF]
        dcoef = min(pw[P_BRAKE] * mu + pw[P_FROLL], mu)
        n = wheel[k, 2]
        if slope:
            if zk >= 0:
                gx, gy, gn = M.zone_slope[zk, 0], M.zone_slope[zk, 1], M.zone_slope[zk, 2]
            else:
                gx, gy, gn = cfg[C_GX], cfg[C_GY], cfg[C_GN]
            n = n * gn
            sw[k, S_GX] = M.wheel_mass[k] * gx
            sw[k, S_GY] = M.wheel_mass[k] * gy
        else:
            sw[k, S_GX] = 0.0
            sw[k, S_GY] = 0.0
        sw[k, S_N0] = n
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
        sw[k, S_CASTOR] = pw[P_CASTOR]
        sw[k, S_AIR] = 1.0 if air and M.wheel_brake[k, B_HAS] != 0.0 and pw[P_LOCKED] == 0.0 else 0.0
        if sw[k, S_AIR] != 0.0:
            sw[k, S_BREF], sw[k, S_BBASE], sw[k, S_BSLOPE] = brake_piece(M.phase_times[t_phase], M.wheel_brake[k])


@njit(**INLINE)
def specific_force(dydt, M, sw, fc, i, c, s):
    """Body-axes specific force of body ``i`` that transfers load [m/s^2]: its acceleration less the
    in-plane gravity and less the contacts' share that acts at the CG's height.

    Load moves between the wheels by the roll and pitch moments about the ground of the forces
    acting above it (quasi-static; :mod:`crashsim.motion.loads` puts the moment ``m a h`` on the
    axles).  Gravity acts at the CG: on a slope the acceleration of a coasting body is gravity's
    alone and moves no load.  The tyre forces act at the ground, the hitch forces are taken to act
    there too.  A contact force ``F_c`` (another body, an obstacle: ``fc``, world frame) acts at the
    height ``h_c``: with the inertial force ``-m a`` at the CG height ``h`` its moment about the
    ground is ``m a h - F_c h_c = m (a - (h_c / h) F_c / m) h``, so the load moves as under the
    specific force ``a - (h_c / h) F_c / m`` (``M.contact_lever[i] = h_c / h``, 1 by default: a push
    at CG height moves no load; 0 would be a push at ground level).
    """
    nb = M.body.shape[0]
    accx = dydt[SV_VX * nb + i]
    accy = dydt[SV_VY * nb + i]
    if M.icfg[I_SLOPE] != 0:
        gx = 0.0
        gy = 0.0
        for k in range(M.wheel.shape[0]):
            if M.wheel_body[k] == i:
                gx += sw[k, S_GX]
                gy += sw[k, S_GY]
        accx -= gx * M.inv_mass[i]
        accy -= gy * M.inv_mass[i]
    if M.pair_body.shape[0] > 0:
        lever = M.contact_lever[i] * M.inv_mass[i]
        accx -= lever * fc[i]
        accy -= lever * fc[nb + i]
    return c * accx + s * accy, c * accy - s * accx


@njit(**HOT)
def phase_at(t, phase_t):
    """Index of the wheel-setting phase in force at ``t`` (a change at ``t`` is in force)."""
    i = 0
    for p in range(phase_t.shape[0]):
        if phase_t[p] <= t:
            i = p
    return i


@njit(**INLINE)
def gram(G, minv, m, n3, A):
    """``A = G M^-1 G^T``: the m x m (symmetric) matrix of the multiplier solve, from the constraint
    Jacobian ``G`` (m rows over the ``n3`` coordinates) and the inverse masses ``minv``."""
    for a in range(m):
        for c in range(a + 1):
            s = 0.0
            for col in range(n3):
                s += G[a, col] * minv[col] * G[c, col]
            A[a, c] = s
            A[c, a] = s


@njit(**HOT)
def evaluate(y, M, sw, D, dydt, W):
    """Right-hand side ``dydt`` of state ``y`` for the segment inputs ``sw`` and mode ``D``.

    Leaves in the work bundle ``W`` (:class:`Work`): per-wheel wheel-axes velocity, force,
    sliding flag and load (``wheel_out``), the world-frame force sums per body ``body_force``
    (tyres and contacts, z order), the constraint multipliers ``multipliers`` (hitch forces on
    the front body [N], then stop moments [N m]), the heading cosines/sines ``trig`` and the
    contact powers ``pair_power``.  Returns the number of multipliers ``m``.

    The run-out model of the README ("Run-out model": three planar degrees of freedom per
    body, hitches as pins held by Lagrange multipliers with Baumgarte stabilisation):
    ``M z'' = f + G^T lam`` with tyre forces (the shared tyre kernel) and penalty contact
    forces in ``f`` (their share alone in ``W.contact_force``), and the multiplier solve
    ``(G M^-1 G^T) lam = -(G M^-1 f + gamma + 2 zeta w0 g' + w0^2 g)`` (:func:`constraint_rows`); with load transfer the body-axes
    accelerations are filtered, ``a_f' = (a_s - a_f) / tau``, ``a_s`` the specific force that
    transfers load (:func:`specific_force`).  The bodies of parked vehicles are
    frozen (zero derivative).
    """
    body, hitch, minv, cfg, icfg, bveh = M.body, M.hitch, M.inv_mass, M.cfg, M.icfg, M.body_vehicle
    lk_j, lk_th, nlk, parked = D.lk_j, D.lk_th, D.lk_n[0], D.parked
    f, G, A, lam, cs = W.body_force, W.jacobian, W.gram, W.multipliers, W.trig
    nb = body.shape[0]
    nh = hitch.shape[0]
    tyre_eval(y, M, sw, D, W)
    if M.pair_body.shape[0] > 0:
        contact_forces(y, M, D, cs, f, W.pair_power, W.contact_pts, W.contact_force)
    n3 = 3 * nb
    m = 0
    if nh > 0:
        m = constraint_rows(y, cs, M, lk_j, lk_th, nlk, G, lam, True)
        for a in range(m):
            s = 0.0
            for col in range(n3):
                s += G[a, col] * minv[col] * f[col]
            lam[a] = -(s + lam[a])
        gram(G, minv, m, n3, A)
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
            ax, ay = specific_force(dydt, M, sw, W.contact_force, i, cs[0, i], cs[1, i])
            dydt[SV_AX_F * nb + i] = (ax - y[SV_AX_F * nb + i]) / tau
            dydt[SV_AY_F * nb + i] = (ay - y[SV_AY_F * nb + i]) / tau
    for i in range(nb):
        if parked[bveh[i]] != 0:
            for fld in range(8 if lt else 6):
                dydt[fld * nb + i] = 0.0
    if icfg[I_BRAKE] != 0:
        dydt[icfg[I_CLOCK]] = 1.0
    return m


@njit(**HOT)
def rest_measure(y, M, v):
    """``max over the bodies of vehicle v (all vehicles if v < 0) of max(|v_cg|, |yaw rate| L_ref)`` [m/s]."""
    body, bveh = M.body, M.body_vehicle
    nb = body.shape[0]
    out = 0.0
    for i in range(nb):
        if v >= 0 and bveh[i] != v:
            continue
        sp = math.sqrt(y[SV_VX * nb + i] ** 2 + y[SV_VY * nb + i] ** 2)
        rot = abs(y[SV_YAW_RATE * nb + i]) * body[i, 2]
        out = max(out, max(sp, rot))
    return out


@njit(**HOT)
def contact_group(M, D, v):
    """Bit mask of the vehicles linked to vehicle ``v`` by sustained contacts, directly or
    through others (``v`` included); only ``v`` in scenes of more than 62 vehicles."""
    pstate = D.pstate
    bveh, pr_body = M.body_vehicle, M.pair_body
    mask = np.int64(1) << v
    if D.parked.shape[0] > 62:
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


@njit(**HOT)
def group_rest_measure(y, M, D, v):
    """Rest measure of vehicle ``v`` together with every moving vehicle of its contact group
    (the largest of their rest measures) [m/s].

    A vehicle pressed by a moving one cannot park; its rest event is the group's, so that the
    group comes to rest at one instant instead of the event firing again and again while the
    partner still moves (event chattering, found by the scene fuzz).
    """
    parked = D.parked
    out = rest_measure(y, M, v)
    if M.pair_body.shape[0] == 0:
        return out
    mask = contact_group(M, D, v)
    for w in range(parked.shape[0]):
        if w != v and (mask >> w) & 1 and parked[w] == 0:
            out = max(out, rest_measure(y, M, w))
    return out


@njit(**HOT)
def kinetic_energy(y, M):
    body = M.body
    nb = body.shape[0]
    e = 0.0
    for i in range(nb):
        e += body[i, 0] * (y[SV_VX * nb + i] ** 2 + y[SV_VY * nb + i] ** 2) + body[i, 1] * y[SV_YAW_RATE * nb + i] ** 2
    return 0.5 * e


@njit(**INLINE)
def quad_integrand(y, M, D, W, out):
    """Integrands of the path integrals at a state just evaluated (``W`` filled by :func:`evaluate`).

    ``out`` (nb + 3 nw + np + nw): CG speeds [m/s], contact speeds [m/s], contact speeds while
    sliding [m/s], dissipated tyre power ``-F . v`` [W], the contacts' power on the bodies [W];
    then the sliding flags (1/0), which are not integrated but tell where the sliding-length
    integrand jumps.
    """
    nb = M.body.shape[0]
    nw = M.wheel.shape[0]
    npr = M.pair_body.shape[0]
    wk = W.wheel_out
    pf = W.pair_power
    bveh, parked = M.body_vehicle, D.parked
    for i in range(nb):
        out[i] = 0.0 if parked[bveh[i]] != 0 else math.sqrt(y[SV_VX * nb + i] ** 2 + y[SV_VY * nb + i] ** 2)
    for k in range(nw):
        sp = math.sqrt(wk[k, W_U] ** 2 + wk[k, W_V] ** 2)
        out[nb + k] = sp
        out[nb + nw + k] = sp if wk[k, W_SLIDE] != 0.0 else 0.0
        out[nb + 2 * nw + k] = -(wk[k, W_FX] * wk[k, W_U] + wk[k, W_FY] * wk[k, W_V])
    for p in range(npr):
        out[nb + 3 * nw + p] = pf[p]
    for k in range(nw):
        out[nb + 3 * nw + npr + k] = wk[k, W_SLIDE]


@njit(**HOT)
def project_velocities(y, M, lk_j, lk_th, nlk, G, A, b, cs):
    """Velocities satisfying ``G z' = 0`` closest in the kinetic-energy metric (in place in ``y``)."""
    minv = M.inv_mass
    nb = M.body.shape[0]
    n3 = 3 * nb
    body_trig(y, nb, cs)
    m = constraint_rows(y, cs, M, lk_j, lk_th, nlk, G, b, False)
    for a in range(m):
        s = 0.0
        for col in range(n3):
            s += G[a, col] * y[n3 + col]
        b[a] = s
    gram(G, minv, m, n3, A)
    solve_spd(A, b, m)
    for col in range(n3):
        s = 0.0
        for a in range(m):
            s += G[a, col] * b[a]
        y[n3 + col] -= minv[col] * s


@njit(**JIT)
def hitch_jacobian(y, M):
    """The hitch constraint Jacobian ``G`` (m, 3 nb) at ``y``: pin x, y rows of every hitch, then one row
    per yaw-locked hitch (:func:`~crashsim.motion.kernels.geometry.constraint_rows` without closed
    stops), on the velocities in z order (vx.., vy.., w..): what a simultaneous impact keeps at zero."""
    nb = M.body.shape[0]
    m = max(2 * M.hitch.shape[0] + M.icfg[I_YAWLOCK], 1)
    G = np.zeros((m, 3 * nb))
    cs = np.zeros((2, nb))
    body_trig(y, nb, cs)
    lk = np.zeros(1, np.int64)
    th = np.zeros(1)
    r = np.zeros(m)
    n = constraint_rows(y, cs, M, lk, th, 0, G, r, False)
    return G[:n].copy()


@njit(**HOT)
def consistent_accelerations(y, M, sw, D, dydt, W):
    """Set the filtered accelerations to their quasi-static fixed point (50 iterations at most, 1e-10)."""
    nb = M.body.shape[0]
    for _ in range(50):
        evaluate(y, M, sw, D, dydt, W)
        cs = W.trig
        change = 0.0
        for i in range(nb):
            new_x, new_y = specific_force(dydt, M, sw, W.contact_force, i, cs[0, i], cs[1, i])
            change = max(change, abs(new_x - y[SV_AX_F * nb + i]), abs(new_y - y[SV_AY_F * nb + i]))
            y[SV_AX_F * nb + i] = new_x
            y[SV_AY_F * nb + i] = new_y
        if change < 1e-10:
            break

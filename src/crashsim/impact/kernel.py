"""The impact equations compiled item by item (numba): the single solve and large batches.

The same equations, unknowns, laws, ``ok`` rule and outputs as the dense path
(:func:`crashsim.impact.core._solve_chunk`, which documents them), solved per batch item in
compiled loops instead of as batched numpy arrays:

1. the rows of J (crush normal and tangent, moment, hitch pins, velocity constraints) and the
   known external impulses, entry by entry as in ``core._assemble``;
2. W = J Minv J^T, u0 = J q, u_free = J (q + Minv p_ext), the law rows (Eqs. 4-7);
3. the system equilibrated (rows, then columns to unit max-norm, as ``core._equilibrate``),
   inverted by Gaussian elimination with partial pivoting (the LU of LAPACK's ``gesv`` that
   ``numpy.linalg.inv`` calls: same pivot choice; an exactly zero pivot = singular = NaN), the
   solution x = Ms^-1 b and the exact 1-norm condition number from the inverse;
4. the tangential law (no sliding -> mu_max; ratio, fraction, friction with its fallback);
5. the velocities after, the separation velocities, the kinetic energies, and (for the
   admissibility check of the single solve) the work of each group of impulses and the
   admissibility code: :func:`impulse_work_item` and :func:`reason_item` are the only
   implementations of those (``crashsim.impact.admissible`` calls them for numpy batches too).

The numbers agree with the dense path to about cond * eps (another sequence of roundings;
tests/properties/test_impact_fast_batch.py). Importing this module defines the kernels;
numba compiles them on first use and caches them on disk (:mod:`crashsim._jit`).
"""

from __future__ import annotations

import math
from collections import namedtuple

import numpy as np
from numba import njit

from .._jit import configure as _configure_cache

_configure_cache()

__all__ = ["solve_batch", "solve_packed", "work_batch", "reason_batch", "impulse_work_item", "reason_item", "LAW_CODES",
           "Structure", "Items", "pack_items"]

_JIT = {"cache": True, "error_model": "numpy", "nogil": True}
# Helpers that allocate nothing are compiled without NRT reference counting (as in
# crashsim.motion.kernels): numba otherwise increfs/decrefs every array argument on every call.
_HOT = dict(_JIT, _nrt=False)
_INLINE = dict(_HOT, inline="always")

#: Tangential law codes of the kernels (index in core.TANGENTIAL_KINDS).
LAW_CODES = {"ratio": 0, "fraction": 1, "no_slide": 2, "friction": 3}
_RATIO, _FRACTION, _NO_SLIDE, _FRICTION = 0, 1, 2, 3

#: The groups of impulses whose work ``admissible.impulse_work`` reports (the columns of the
#: kernels' work arrays).
WORK_KEYS = ("normal", "tangential", "moment", "hitches", "constraints", "external")

#: 1-norm condition number of an equilibrated system above which its solution is not trusted
#: (double precision then leaves fewer than ~4 significant digits).
COND_LIMIT = 1e12
#: |mu_max| above which the no-sliding-at-separation solution is taken as impossible (the
#: tangential impulse cannot stop the sliding: a singular or near-singular tangential row).
MU_MAX_LIMIT = 1e6
#: Relative round-off allowances of the admissibility tests (impulses; energies relative to the
#: kinetic energy; impulse ratios), :mod:`crashsim.impact.admissible`.
REL_IMPULSE = 1e-9
REL_ENERGY = 1e-9
REL_RATIO = 1e-9

#: Layout of the ``limits`` argument (:func:`limits`): the thresholds above, defined here, below
#: the dense path (core) and the admissibility rules (admissible) that share them.
L_COND, L_MU_MAX, L_REL_IMPULSE, L_REL_RATIO, L_REL_ENERGY = range(5)


#: The structure of a batch as the kernels take it (``core._kernel_structure``): ``fixed`` (n,)
#: bool (barrier bodies), the bodies ``body1``, ``body2`` of the crush surface, the tangential
#: ``law`` code (:data:`LAW_CODES`), ``hitches`` (h, 2) front and rear body of each hitch,
#: ``cbodies`` (c,) the body of each velocity constraint, ``xbodies`` (x,) the body of each
#: known external impulse, ``locks`` (l, 2) front and rear body of each yaw-locked hitch (C-dolly).
Structure = namedtuple("Structure", ["fixed", "body1", "body2", "law", "hitches", "cbodies", "xbodies", "locks"])

#: The numbers of a batch of B items, one array per field of :class:`crashsim.impact.core.ImpactArrays`
#: (same names, shapes and SI units; C order, float64).
Items = namedtuple("Items", ["mass", "yaw_inertia", "position", "heading", "velocity", "yaw_rate", "hitch_front_point",
                             "hitch_rear_point", "point", "normal_angle", "tangent_sign", "restitution", "law_value",
                             "moment_restitution", "constraint_point", "constraint_direction", "constraint_value",
                             "external_point", "external_impulse"])


def pack_items(A) -> Items:
    """The :class:`Items` of an :class:`~crashsim.impact.core.ImpactArrays` (C-ordered float64 views or copies)."""
    out = []
    for name in Items._fields:
        a = getattr(A, name)
        out.append(a if a.flags.c_contiguous and a.dtype == np.float64 else np.ascontiguousarray(a, dtype=np.float64))
    return Items(*out)


def limits() -> np.ndarray:
    """The thresholds the kernels use (in the order of the ``L_*`` indices)."""
    return np.array([COND_LIMIT, MU_MAX_LIMIT, REL_IMPULSE, REL_RATIO, REL_ENERGY])




@njit(**_HOT)
def _rows(S, A, i, J, rowb):
    """Rows of J (K, n, 3) of batch item i (zeroed here), and the bodies of each row (ascending):
    the crush normal and tangent at the contact point, the moment row, the hitch pins (x, y),
    the velocity constraints (module docstring, item 1). Returns the normal and tangent."""
    body1, body2, hitches, cbodies = S.body1, S.body2, S.hitches, S.cbodies
    position, heading, hfp, hrp = A.position, A.heading, A.hitch_front_point, A.hitch_rear_point
    point, normal_angle, tangent_sign = A.point, A.normal_angle, A.tangent_sign
    cpoint, cdir = A.constraint_point, A.constraint_direction
    for k in range(J.shape[0]):
        for b in range(J.shape[1]):
            J[k, b, 0] = J[k, b, 1] = J[k, b, 2] = 0.0
    nx, ny = math.cos(normal_angle[i]), math.sin(normal_angle[i])
    tx, ty = tangent_sign[i] * -ny, tangent_sign[i] * nx
    r1x, r1y = point[i, 0] - position[i, body1, 0], point[i, 1] - position[i, body1, 1]
    r2x, r2y = point[i, 0] - position[i, body2, 0], point[i, 1] - position[i, body2, 1]
    lo, hi = min(body1, body2), max(body1, body2)
    for k in range(2):
        ux, uy = (nx, ny) if k == 0 else (tx, ty)
        J[k, body1, 0] += ux
        J[k, body1, 1] += uy
        J[k, body1, 2] += r1x * uy - r1y * ux
        J[k, body2, 0] += -ux
        J[k, body2, 1] += -uy
        J[k, body2, 2] += -(r2x * uy - r2y * ux)
        rowb[k, 0], rowb[k, 1] = lo, hi
    J[2, body1, 2] += 1.0
    J[2, body2, 2] -= 1.0
    rowb[2, 0], rowb[2, 1] = lo, hi
    for j in range(hitches.shape[0]):
        f, r = hitches[j, 0], hitches[j, 1]
        cf, sf = math.cos(heading[i, f]), math.sin(heading[i, f])
        cr, sr = math.cos(heading[i, r]), math.sin(heading[i, r])
        pfx, pfy, prx, pry = hfp[i, j, 0], hfp[i, j, 1], hrp[i, j, 0], hrp[i, j, 1]
        rfx, rfy = cf * pfx - sf * pfy, sf * pfx + cf * pfy
        rrx, rry = cr * prx - sr * pry, sr * prx + cr * pry
        kx, ky = 3 + 2 * j, 4 + 2 * j
        J[kx, f, 0] += 1.0
        J[kx, f, 2] += -rfy        # r x e_x = -r_y
        J[kx, r, 0] -= 1.0
        J[kx, r, 2] -= -rry
        J[ky, f, 1] += 1.0
        J[ky, f, 2] += rfx         # r x e_y = r_x
        J[ky, r, 1] -= 1.0
        J[ky, r, 2] -= rrx
        rowb[kx, 0], rowb[kx, 1] = min(f, r), max(f, r)
        rowb[ky, 0], rowb[ky, 1] = min(f, r), max(f, r)
    k0 = 3 + 2 * hitches.shape[0]
    for l in range(S.locks.shape[0]):  # yaw locks: the relative yaw rate of the two bodies
        f, r = S.locks[l, 0], S.locks[l, 1]
        J[k0 + l, f, 2] += 1.0
        J[k0 + l, r, 2] -= 1.0
        rowb[k0 + l, 0], rowb[k0 + l, 1] = min(f, r), max(f, r)
    k0 += S.locks.shape[0]
    for c in range(cbodies.shape[0]):
        b = cbodies[c]
        dx, dy = math.cos(cdir[i, c]), math.sin(cdir[i, c])
        rx, ry = cpoint[i, c, 0] - position[i, b, 0], cpoint[i, c, 1] - position[i, b, 1]
        J[k0 + c, b, 0] += dx
        J[k0 + c, b, 1] += dy
        J[k0 + c, b, 2] += rx * dy - ry * dx
        rowb[k0 + c, 0], rowb[k0 + c, 1] = b, -1
    return nx, ny, tx, ty


@njit(**_INLINE)
def _row_dot(J, rowb, k, v, w):
    """J_k . (v, w) over the (at most two) bodies of row k."""
    acc = 0.0
    for a in range(2):
        b = rowb[k, a]
        if b >= 0:
            acc += J[k, b, 0] * v[b, 0] + J[k, b, 1] * v[b, 1] + J[k, b, 2] * w[b]
    return acc


@njit(**_HOT)
def _solve_system(Mat, rhs, K, Ms, aug, x, cond_limit, sc):
    """Equilibrate Mat (rows, then columns to unit max-norm), invert by Gaussian elimination
    with partial pivoting; x = solution. Returns (ok, cond1) as ``core._solve``. ``sc`` is
    scratch space (3, K). Divisions by a scale or pivot are multiplications by its reciprocal
    (a rounding of difference from numpy's divisions; the same pivots)."""
    rinv = sc[0]
    cinv = sc[1]
    bs = sc[2]
    for i in range(K):
        m = 0.0
        for j in range(K):
            a = abs(Mat[i, j])
            if a > m or a != a:
                m = a
        rinv[i] = 1.0 if m == 0.0 else 1.0 / m
        bs[i] = rhs[i] * rinv[i]
    for j in range(K):
        m = 0.0
        for i in range(K):
            a = abs(Mat[i, j] * rinv[i])
            if a > m or a != a:
                m = a
        cinv[j] = 1.0 if m == 0.0 else 1.0 / m
    for i in range(K):
        for j in range(K):
            v = Mat[i, j] * rinv[i] * cinv[j]
            Ms[i, j] = v
            aug[i, j] = v
            aug[i, K + j] = 0.0
        aug[i, K + i] = 1.0
    # [Ms | I] -> [U | L^-1 P] by Gaussian elimination with partial pivoting
    K2 = 2 * K
    for col in range(K):
        p = col
        best = abs(aug[col, col])
        for i in range(col + 1, K):
            a = abs(aug[i, col])
            if a > best:
                best = a
                p = i
        if best == 0.0:
            for i in range(K):
                x[i] = np.nan
            return False, np.inf
        if p != col:
            for j in range(col, K2):
                t = aug[col, j]
                aug[col, j] = aug[p, j]
                aug[p, j] = t
        pinv = 1.0 / aug[col, col]
        for i in range(col + 1, K):
            f = aug[i, col] * pinv
            if f != 0.0:
                for j in range(col + 1, K2):
                    aug[i, j] -= f * aug[col, j]
    for i in range(K):            # back substitution, all columns of the inverse at once
        ii = K - 1 - i
        for j in range(ii + 1, K):
            a = aug[ii, j]
            for col in range(K, K2):
                aug[ii, col] -= a * aug[j, col]
        dinv = 1.0 / aug[ii, ii]
        for col in range(K, K2):
            aug[ii, col] *= dinv
    n_ms = 0.0
    n_inv = 0.0
    for j in range(K):
        s1 = 0.0
        s2 = 0.0
        for i in range(K):
            s1 += abs(Ms[i, j])
            s2 += abs(aug[i, K + j])
        n_ms = max(n_ms, s1)
        n_inv = max(n_inv, s2)
    finite = True
    for i in range(K):
        s = 0.0
        for j in range(K):
            s += aug[i, K + j] * bs[j]
        x[i] = s * cinv[i]
        if not math.isfinite(s):
            finite = False
    cond = n_ms * n_inv
    if not math.isfinite(cond):
        cond = np.inf
    return finite and cond < cond_limit, cond


@njit(**_HOT)
def impulse_work_item(S, A, J, rowb, v1, w1, lam, i, work):
    """Work of each group of impulses of batch item i (``admissible.impulse_work``'s formula):
    ``lambda_k (u_k^- + u_k^+) / 2`` over the non-fixed bodies of row k, and
    ``p . (v^- + v^+) / 2`` at the point of a known external impulse (velocities before: the
    items' ``velocity``, ``yaw_rate``; after: ``v1``, ``w1``). Fills ``work[i]`` (6,)."""
    fixed, hitches, xbodies = S.fixed, S.hitches, S.xbodies
    position, v0, w0, xpoint, ximp = A.position, A.velocity, A.yaw_rate, A.external_point, A.external_impulse
    K = lam.shape[1]
    k0 = K - S.cbodies.shape[0]  # the hitch pins and the yaw locks are the hitches' work
    work[i, 3] = 0.0
    work[i, 4] = 0.0
    for k in range(K):
        acc = 0.0
        for a in range(2):
            b = rowb[k, a]
            if b < 0 or fixed[b]:
                continue
            acc = acc + J[k, b, 0] * (v0[i, b, 0] + v1[i, b, 0]) + J[k, b, 1] * (v0[i, b, 1] + v1[i, b, 1]) \
                + J[k, b, 2] * (w0[i, b] + w1[i, b])
        wk = lam[i, k] * (0.5 * acc)
        if k < 3:
            work[i, k] = wk
        elif k < k0:
            work[i, 3] += wk
        else:
            work[i, 4] += wk
    ext = 0.0
    for x in range(xbodies.shape[0]):
        b = xbodies[x]
        if fixed[b]:
            continue
        rx, ry = xpoint[i, x, 0] - position[i, b, 0], xpoint[i, x, 1] - position[i, b, 1]
        ws = w0[i, b] + w1[i, b]
        vx = 0.5 * ((v0[i, b, 0] + v1[i, b, 0]) - ws * ry)
        vy = 0.5 * ((v0[i, b, 1] + v1[i, b, 1]) + ws * rx)
        ext += ximp[i, x, 0] * vx + ximp[i, x, 1] * vy
    work[i, 5] = ext


@njit(**_HOT)
def reason_item(ok, lam, law, law_value, mu_max, pn_no_slide, slip, sep_t, ke0, work, limits, i):
    """Admissibility code of one solved item (``admissible.REASONS``; rules in that module):
    0 admissible, 1 tensile P_n, 2 mu beyond mu_max (or the sliding reverses), 3 mu drives
    the sliding, 4 energy created at the crush surface, 5 not solvable.

    ``pn_no_slide`` is the normal impulse of the no-sliding solution: where it is not
    compressive, sliding cannot be stopped and mu_max is no bound; an impulse ratio must then
    oppose the initial tangential slip ``slip`` (Coulomb) and not reverse it (the tangential
    separation velocity ``sep_t`` keeps its sign)."""
    pn = lam[i, 0]
    if not (ok and math.isfinite(pn)):
        return 5
    scale = 0.0
    for k in range(lam.shape[1]):
        a = abs(lam[i, k])
        if a > scale:
            scale = a
    if pn < -limits[L_REL_IMPULSE] * scale:
        return 1
    if law == _RATIO:
        if pn_no_slide > 0.0 and abs(mu_max) <= limits[L_MU_MAX]:
            q = law_value / mu_max
            if q > 1.0 + limits[L_REL_RATIO]:
                return 2
            if q < -limits[L_REL_RATIO]:
                return 3
        else:  # sliding cannot stop: Coulomb's rule against the initial slip
            if law_value * slip > 0.0:
                return 3
            if sep_t * slip < 0.0 and abs(sep_t) > limits[L_REL_RATIO] * (1.0 + abs(slip)):
                return 2
    gain = work[i, 0] + work[i, 1] + work[i, 2]
    allowance = limits[L_REL_ENERGY] * (ke0 + abs(work[i, 5]) + abs(work[i, 4]) + 1.0)
    if gain > allowance:
        return 4
    return 0


@njit(**_JIT)
def work_batch(S, A, vel_after, yaw_after, lam):
    """:func:`impulse_work_item` over a batch (structure ``S``, items ``A``, velocities after and
    impulses of a solution): (B, 6) in the order of :data:`WORK_KEYS`."""
    B, n = A.yaw_rate.shape
    K = lam.shape[1]
    J = np.empty((K, n, 3))
    rowb = np.empty((K, 2), dtype=np.int64)
    out = np.empty((B, 6))
    for i in range(B):
        _rows(S, A, i, J, rowb)
        impulse_work_item(S, A, J, rowb, vel_after, yaw_after, lam, i, out)
    return out


@njit(**_JIT)
def reason_batch(ok, lam, law, law_value, mu_max, pn_no_slide, slip, sep_t, ke0, work, limits):
    """:func:`reason_item` over a batch: (B,) int64."""
    B = ok.shape[0]
    out = np.empty(B, dtype=np.int64)
    for i in range(B):
        out[i] = reason_item(ok[i], lam, law, law_value[i], mu_max[i], pn_no_slide[i], slip[i], sep_t[i], ke0[i], work,
                             limits, i)
    return out


@njit(**_JIT)
def _out_views(Y, B, n, K, extras):
    """The outputs as views of Y, field by field (the order of ``core.OUT_LAYOUT``)."""
    o = 0
    v_out = Y[o:o + B * n * 2].reshape((B, n, 2))
    o += B * n * 2
    w_out = Y[o:o + B * n].reshape((B, n))
    o += B * n
    lam_out = Y[o:o + B * K].reshape((B, K))
    o += B * K
    sc = Y[o:o + 9 * B].reshape((9, B))  # mu, mu_max, sliding, closing, sep_n, sep_t, ok, slip, pn_no_slide
    o += 9 * B
    ke0_out = Y[o:o + B * n].reshape((B, n))
    o += B * n
    ke1_out = Y[o:o + B * n].reshape((B, n))
    o += B * n
    normal = Y[o:o + 2 * B].reshape((B, 2))
    o += 2 * B
    tangent = Y[o:o + 2 * B].reshape((B, 2))
    o += 2 * B
    cond_out = Y[o:o + B]
    o += B
    ne = B if extras else 0
    work_out = Y[o:o + 6 * ne].reshape((ne, 6))
    o += 6 * ne
    reason_out = Y[o:o + ne]
    return v_out, w_out, lam_out, sc, ke0_out, ke1_out, normal, tangent, cond_out, work_out, reason_out


@njit(**_JIT)
def out_size(n, K, extras):
    """Floats per item of the output buffer."""
    return 5 * n + K + 9 + 4 + 1 + (7 if extras else 0)


@njit(**_JIT)
def solve_packed(meta, fixed, hitches, cbodies, xbodies, locks, X, limits, extras):
    """:func:`solve_batch` on inputs packed field by field into one float64 vector X (the order of
    ``core.ImpactArrays``' fields; ``meta`` = (n, h, c, x, body1, body2, law)): the single solve's
    entry point (four array arguments instead of nineteen)."""
    n, h, c, x = meta[0], meta[1], meta[2], meta[3]
    P = 8 * n + 4 * h + 7 + 4 * c + 4 * x
    B = X.size // P
    o = 0
    mass = X[o:o + B * n].reshape((B, n))
    o += B * n
    inertia = X[o:o + B * n].reshape((B, n))
    o += B * n
    position = X[o:o + 2 * B * n].reshape((B, n, 2))
    o += 2 * B * n
    heading = X[o:o + B * n].reshape((B, n))
    o += B * n
    velocity = X[o:o + 2 * B * n].reshape((B, n, 2))
    o += 2 * B * n
    yaw_rate = X[o:o + B * n].reshape((B, n))
    o += B * n
    hfp = X[o:o + 2 * B * h].reshape((B, h, 2))
    o += 2 * B * h
    hrp = X[o:o + 2 * B * h].reshape((B, h, 2))
    o += 2 * B * h
    point = X[o:o + 2 * B].reshape((B, 2))
    o += 2 * B
    normal_angle = X[o:o + B]
    o += B
    tangent_sign = X[o:o + B]
    o += B
    restitution = X[o:o + B]
    o += B
    law_value = X[o:o + B]
    o += B
    moment_restitution = X[o:o + B]
    o += B
    cpoint = X[o:o + 2 * B * c].reshape((B, c, 2))
    o += 2 * B * c
    cdir = X[o:o + B * c].reshape((B, c))
    o += B * c
    cval = X[o:o + B * c].reshape((B, c))
    o += B * c
    xpoint = X[o:o + 2 * B * x].reshape((B, x, 2))
    o += 2 * B * x
    ximp = X[o:o + 2 * B * x].reshape((B, x, 2))
    S = Structure(fixed, meta[4], meta[5], meta[6], hitches, cbodies, xbodies, locks)
    A = Items(mass, inertia, position, heading, velocity, yaw_rate, hfp, hrp, point, normal_angle, tangent_sign,
              restitution, law_value, moment_restitution, cpoint, cdir, cval, xpoint, ximp)
    return solve_batch(S, A, limits, extras)


#: Scratch arrays of one batch item (K unknowns, n bodies): the rows ``J`` (K, n, 3) and their
#: bodies ``rowb`` (K, 2); inverse masses ``minv`` (n, 3); known external impulses ``pext`` (n, 3);
#: free velocities ``vfree``, ``wfree``; row velocities before ``u0`` and free ``uf`` (K,); ``W``
#: = J Minv J^T and the system ``Mat``, ``rhs``; solver scratch ``Ms``, ``aug``, ``scr``; the
#: no-slide and law solutions ``lam_ns``, ``lam_r``; velocities before ``vq``, ``wq`` and after
#: ``vo``, ``wo``.
Scratch = namedtuple("Scratch", ["J", "rowb", "minv", "pext", "vfree", "wfree", "u0", "uf", "W", "Mat", "rhs", "Ms", "aug",
                                 "scr", "lam_ns", "lam_r", "vq", "wq", "vo", "wo"])
#: The outputs of a batch as views of one vector (:func:`_out_views`; ``sc`` rows: mu, mu_max,
#: sliding, closing, sep_n, sep_t, ok, slip, pn_no_slide).
Outputs = namedtuple("Outputs", ["v", "w", "lam", "sc", "ke0", "ke1", "normal", "tangent", "cond", "work", "reason"])


# The stages of one item are inlined into the item loop of solve_batch (one compiled loop, as before the cut):
# a call would pass the structure, the items and the scratch as a few hundred scalar arguments.
@njit(**_JIT)
def _scratch(n, K):
    return Scratch(np.empty((K, n, 3)), np.empty((K, 2), dtype=np.int64), np.empty((n, 3)), np.zeros((n, 3)),
                   np.empty((n, 2)), np.empty(n), np.empty(K), np.empty(K), np.empty((K, K)), np.empty((K, K)),
                   np.empty(K), np.empty((K, K)), np.empty((K, 2 * K)), np.empty((3, K)), np.empty(K), np.empty(K),
                   np.empty((n, 2)), np.empty(n), np.empty((n, 2)), np.empty(n))


@njit(**_INLINE)
def _assemble_item(S, A, i, X):
    """The equations of item i before the laws (module docstring, items 1-2): the rows of J,
    inverse masses, known external impulses, ``u0 = J q``, ``u_free = J (q + Minv p_ext)`` and
    ``W = J Minv J^T``. Returns the normal and tangent (nx, ny, tx, ty)."""
    fixed, xbodies = S.fixed, S.xbodies
    mass, inertia, velocity, yaw_rate = A.mass, A.yaw_inertia, A.velocity, A.yaw_rate
    position, xpoint, ximp = A.position, A.external_point, A.external_impulse
    J, rowb, minv, pext, vfree, wfree, u0, uf, W = X.J, X.rowb, X.minv, X.pext, X.vfree, X.wfree, X.u0, X.uf, X.W
    vq, wq = X.vq, X.wq
    n = mass.shape[1]
    K = J.shape[0]
    nxv, nyv, txv, tyv = _rows(S, A, i, J, rowb)
    for b in range(n):
        if fixed[b]:
            minv[b, 0] = minv[b, 1] = minv[b, 2] = 0.0
        else:
            minv[b, 0] = minv[b, 1] = 1.0 / mass[i, b]
            minv[b, 2] = 1.0 / inertia[i, b]
        pext[b, 0] = pext[b, 1] = pext[b, 2] = 0.0
        vq[b, 0], vq[b, 1], wq[b] = velocity[i, b, 0], velocity[i, b, 1], yaw_rate[i, b]
    for x in range(xbodies.shape[0]):
        b = xbodies[x]
        ix, iy = ximp[i, x, 0], ximp[i, x, 1]
        rx, ry = xpoint[i, x, 0] - position[i, b, 0], xpoint[i, x, 1] - position[i, b, 1]
        pext[b, 0] += ix
        pext[b, 1] += iy
        pext[b, 2] += rx * iy - ry * ix
    for b in range(n):
        vfree[b, 0] = vq[b, 0] + minv[b, 0] * pext[b, 0]
        vfree[b, 1] = vq[b, 1] + minv[b, 1] * pext[b, 1]
        wfree[b] = wq[b] + minv[b, 2] * pext[b, 2]
    for k in range(K):
        u0[k] = _row_dot(J, rowb, k, vq, wq)
        uf[k] = _row_dot(J, rowb, k, vfree, wfree)
        for l in range(k, K):      # W is symmetric
            acc = 0.0
            for a in range(2):
                b = rowb[k, a]
                if b >= 0 and (rowb[l, 0] == b or rowb[l, 1] == b):
                    acc += (J[k, b, 0] * minv[b, 0] * J[l, b, 0] + J[k, b, 1] * minv[b, 1] * J[l, b, 1]
                            + J[k, b, 2] * minv[b, 2] * J[l, b, 2])
            W[k, l] = acc
            W[l, k] = acc
    return nxv, nyv, txv, tyv


@njit(**_INLINE)
def _law_rows(S, A, i, X):
    """The system ``Mat lam = rhs`` of item i with the no-sliding tangential row (module
    docstring, item 2: the restitution rows of the normal and the moment, Eqs. 4-7, the hitch
    pins and the velocity constraints)."""
    body1, body2, cbodies = S.body1, S.body2, S.cbodies
    W, Mat, rhs, u0, uf, minv = X.W, X.Mat, X.rhs, X.u0, X.uf, X.minv
    K = W.shape[0]
    nc = cbodies.shape[0]
    k0 = K - nc
    e = A.restitution[i]
    ep = A.moment_restitution[i]
    inv_ibar = minv[body1, 2] + minv[body2, 2]
    ibar = 1.0 / inv_ibar if inv_ibar > 0 else 0.0
    g = (1.0 + ep) * ibar
    for k in range(K):
        for l in range(K):
            Mat[k, l] = W[k, l]
        rhs[k] = -uf[k]
    rhs[0] = -e * u0[0] - uf[0]
    for l in range(K):
        Mat[2, l] = -g * W[2, l]
    Mat[2, 2] += ep
    rhs[2] = g * uf[2]
    for c in range(nc):
        rhs[k0 + c] = A.constraint_value[i, c] - uf[k0 + c]


@njit(**_INLINE)
def _tangential_law(S, A, i, X, limits):
    """Solve item i's system without sliding, then apply the tangential law (module docstring,
    item 4: no sliding -> mu_max; ratio, fraction, friction with its fallback), solving again
    with the law's row where it applies. Returns ``(ok, cond, mu_max, pn_no_slide, sliding, redo)``."""
    law = S.law
    Mat, rhs, lam_ns, u0 = X.Mat, X.rhs, X.lam_ns, X.u0
    K = Mat.shape[0]
    ok, cond = _solve_system(Mat, rhs, K, X.Ms, X.aug, lam_ns, limits[L_COND], X.scr)
    mu_max = lam_ns[1] / lam_ns[0] if ok else np.nan
    pn_ns = lam_ns[0] if ok else np.nan
    sliding = False
    redo = False
    mu_used = 0.0
    if law == _RATIO:
        redo = True
        mu_used = A.law_value[i]
    elif law == _FRACTION:
        redo = True
        mu_used = A.law_value[i] * mu_max
    elif law == _FRICTION:
        f = A.law_value[i]
        # sliding can be stopped only by a compressive no-slide impulse of finite ratio
        stoppable = ok and lam_ns[0] > 0.0 and abs(mu_max) <= limits[L_MU_MAX]
        redo = not (stoppable and abs(mu_max) <= f)
        if stoppable:
            sgn = 1.0 if mu_max > 0 else (-1.0 if mu_max < 0 else 0.0)
        else:
            sgn = -1.0 if u0[1] > 0 else (1.0 if u0[1] < 0 else 0.0)
        mu_used = f * sgn
    if redo:
        for l in range(K):
            Mat[1, l] = 0.0
        Mat[1, 1] = 1.0
        Mat[1, 0] = -mu_used
        rhs[1] = 0.0
        ok, cond = _solve_system(Mat, rhs, K, X.Ms, X.aug, X.lam_r, limits[L_COND], X.scr)
        sliding = True
    return ok, cond, mu_max, pn_ns, sliding, redo


@njit(**_INLINE)
def _velocities_after(S, i, X, ok, redo, out):
    """Impulses and velocities after of item i (module docstring, item 5): ``lam`` (NaN if not
    solved), ``v+ = v- + Minv (p_ext + J^T lam)``, into the outputs ``out``."""
    J, rowb, minv, pext, vq, wq, vo, wo = X.J, X.rowb, X.minv, X.pext, X.vq, X.wq, X.vo, X.wo
    lam_out, v_out, w_out = out.lam, out.v, out.w
    K = J.shape[0]
    n = J.shape[1]
    for k in range(K):
        lam_out[i, k] = (X.lam_r[k] if redo else X.lam_ns[k]) if ok else np.nan
    for b in range(n):
        dx, dy, dw = pext[b, 0], pext[b, 1], pext[b, 2]
        for k in range(K):
            if rowb[k, 0] == b or rowb[k, 1] == b:
                lk = lam_out[i, k]
                dx += J[k, b, 0] * lk
                dy += J[k, b, 1] * lk
                dw += J[k, b, 2] * lk
        if not ok:
            dx = dy = dw = np.nan
        vo[b, 0] = vq[b, 0] + minv[b, 0] * dx
        vo[b, 1] = vq[b, 1] + minv[b, 1] * dy
        wo[b] = wq[b] + minv[b, 2] * dw
        v_out[i, b, 0], v_out[i, b, 1], w_out[i, b] = vo[b, 0], vo[b, 1], wo[b]


@njit(**_INLINE)
def _energies(S, A, i, X, out):
    """Kinetic energies of each body of item i before and after [J] (barrier bodies: 0) into
    ``out``; returns the total before."""
    fixed, mass, inertia, vq, wq, vo, wo = S.fixed, A.mass, A.yaw_inertia, X.vq, X.wq, X.vo, X.wo
    ke0 = 0.0
    for b in range(mass.shape[1]):
        m = 0.0 if fixed[b] else mass[i, b]
        inr = 0.0 if fixed[b] else inertia[i, b]
        e0 = 0.5 * m * (vq[b, 0] * vq[b, 0] + vq[b, 1] * vq[b, 1]) + 0.5 * inr * wq[b] * wq[b]
        out.ke0[i, b] = e0
        out.ke1[i, b] = 0.5 * m * (vo[b, 0] * vo[b, 0] + vo[b, 1] * vo[b, 1]) + 0.5 * inr * wo[b] * wo[b]
        ke0 += e0
    return ke0


@njit(**_JIT)
def solve_batch(S, A, limits, extras):
    """Solve every item of a batch (module docstring): structure ``S`` (:class:`Structure`),
    items ``A`` (:class:`Items`). Returns one float64 vector holding the outputs field by field
    (``core.OUT_LAYOUT``; flags as 0.0 / 1.0); ``extras``: with the work (B, 6) and the
    admissibility code (B,) of every item."""
    B, n = A.mass.shape
    K = 3 + 2 * S.hitches.shape[0] + S.locks.shape[0] + S.cbodies.shape[0]
    Y = np.empty(B * out_size(n, K, extras))
    v_out, w_out, lam_out, sc, ke0_out, ke1_out, normal, tangent, cond_out, work_out, reason_out = \
        _out_views(Y, B, n, K, extras)
    out = Outputs(v_out, w_out, lam_out, sc, ke0_out, ke1_out, normal, tangent, cond_out, work_out, reason_out)
    _solve_items(S, A, limits, extras, _scratch(n, K), out)
    return Y


@njit(**_HOT)
def _solve_items(S, A, limits, extras, X, out):
    """The item loop of :func:`solve_batch`, compiled without reference counting (it allocates
    nothing: the outputs ``out`` and the scratch ``X`` come from its caller), as the run-out's
    step loop is: with it, every read of a bundle's array in the loop paid an incref/decref."""
    sc = out.sc
    for i in range(A.mass.shape[0]):
        nxv, nyv, txv, tyv = _assemble_item(S, A, i, X)
        out.normal[i, 0], out.normal[i, 1] = nxv, nyv
        out.tangent[i, 0], out.tangent[i, 1] = txv, tyv
        _law_rows(S, A, i, X)
        ok, cond, mu_max, pn_ns, sliding, redo = _tangential_law(S, A, i, X, limits)
        _velocities_after(S, i, X, ok, redo, out)
        sn = _row_dot(X.J, X.rowb, 0, X.vo, X.wo)
        st = _row_dot(X.J, X.rowb, 1, X.vo, X.wo)
        u0 = X.u0
        if S.law == _RATIO or S.law == _FRACTION:
            sliding = abs(st) > 1e-9 * (1.0 + abs(u0[1]))
        ke0 = _energies(S, A, i, X, out)
        sc[0, i] = out.lam[i, 1] / out.lam[i, 0]  # mu
        sc[1, i] = mu_max
        sc[2, i] = 1.0 if sliding else 0.0
        sc[3, i] = u0[0]  # closing velocity
        sc[4, i] = sn  # separation, normal
        sc[5, i] = st  # separation, tangential
        sc[6, i] = 1.0 if ok else 0.0
        sc[7, i] = u0[1]  # approach slip
        sc[8, i] = pn_ns  # the no-slide solution's normal impulse
        out.cond[i] = cond
        if extras:
            impulse_work_item(S, A, X.J, X.rowb, out.v, out.w, out.lam, i, out.work)
            out.reason[i] = reason_item(ok, out.lam, S.law, A.law_value[i], mu_max, pn_ns, u0[1], st, ke0, out.work,
                                        limits, i)

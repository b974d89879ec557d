"""The impulse-momentum equations of pin-connected rigid bodies, solved on arrays.

One implementation serves the single solve and the batch: every input carries a leading
batch axis ``B`` (B = 1 for one impact). The structure of the problem (which bodies, hitches,
constraints, tangential law) is fixed across the batch; every number may vary.

Formulation
-----------
Generalised velocities q = (vx, vy, w) per body, world frame. Every unknown impulse
lambda_k acts on the bodies through a row J_k (B, n, 3) of a Jacobian, so that the final
velocities are (paper Eqs. 1, 2)

    Q = q + Minv (p_ext + J^T lambda),

with Minv = diag(1/m, 1/m, 1/I) per body (0 for a rigid barrier: exact, not a large mass).
The unknowns are, in this order,

    lambda = (P_n, P_t, M, R_1x, R_1y, ..., R_hx, R_hy, L_1, ..., L_l, C_1, ..., C_c)

(crush normal and tangential impulse on body 1, moment impulse on body 1, the impulse of
each hitch on its front body, the moment impulse of each yaw-locked hitch (a C-dolly) on its
front body, and each velocity constraint's impulse along its direction).
The same rows J_k give the velocities the conditions speak of: J_n Q is the normal
velocity of body 1's contact point relative to body 2's, J_h Q the pin-velocity mismatch.
With W = J Minv J^T and u = J (q + Minv p_ext) the conditions are linear in lambda:

    restitution (Eq. 5)      W_n lambda = -e J_n q - u_n
    no sliding at separation W_t lambda = -u_t                     (defines mu_max)
    impulse ratio (Eq. 4)    P_t - mu P_n = 0
    moment (Eq. 6)           e' M - (1 + e') Ibar J_M Q = 0        (e' = -1 gives M = 0)
    hitch pins (Eq. 3)       W_h lambda = -u_h
    yaw locks                W_l lambda = -u_l                    (no relative yaw rate after)
    constraints (Eq. 7)      W_c lambda = value - u_c

Eq. 6 is used with the sign that makes e' a restitution coefficient (see
``docs/paper-geometry.md``): e' M = -(1 + e')(Omega_2 - Omega_1) Ibar.
The system is equilibrated (rows, then columns, scaled to unit max-norm); the exact 1-norm
condition number of the equilibrated matrix is reported so an ill-posed configuration is
visible, and a solution is only returned where it is below :data:`COND_LIMIT`.

Two implementations of the same solve (:func:`solve_arrays` picks one):

* compiled (:func:`solve_compiled`, :mod:`crashsim.impact.kernel`): the dense path's
  algorithm item by item in a numba kernel (compiled on first use, cached on disk); every call
  without ``condition=True``, and the single solve (:func:`solve_packed`);
* dense (:func:`_solve_chunk`): the K x K systems formed and inverted as batched numpy arrays;
  every call with ``condition=True`` (the SVD condition number and the equilibrated matrix
  that :func:`crashsim.impact.solve.solve_impact` diagnoses when it refuses a system).

Both give the same outputs, flags and laws; the numbers agree to about cond * eps
(tests/properties/test_impact_fast_batch.py). A third, numpy elimination path for large
batches ("reduced") was removed when the compiled kernel took every batch: it had no caller.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from . import kernel
from .kernel import COND_LIMIT, MU_MAX_LIMIT, WORK_KEYS

__all__ = ["ImpactStructure", "ImpactArrays", "solve_arrays", "energy_loss_fraction", "TANGENTIAL_KINDS"]

TANGENTIAL_KINDS = ("ratio", "fraction", "no_slide", "friction")



@dataclass(frozen=True)
class ImpactStructure:
    """What is fixed across a batch: the bodies, the joints, the laws.

    Attributes
    ----------
    body_names : tuple of str
        All bodies, vehicle by vehicle, front to rear.
    vehicle_index : tuple of int
        Vehicle number (0 or 1) of each body.
    vehicle_names : tuple of str
    fixed : tuple of bool
        True for a rigid barrier body.
    body1, body2 : int
        Indices of the bodies in contact.
    hitches : tuple of (int, int)
        (front, rear) body indices of each hitch.
    hitch_names : tuple of str
    locks : tuple of (int, int)
        (front, rear) body indices of each yaw-locked hitch (C-dolly): a moment impulse keeps
        their yaw rates equal.
    constraint_bodies : tuple of int
    constraint_names : tuple of str
    external_bodies : tuple of int
    external_names : tuple of str
    tangential : str
        One of ``"ratio"``, ``"fraction"``, ``"no_slide"``, ``"friction"``.
    """

    body_names: tuple[str, ...]
    vehicle_index: tuple[int, ...]
    vehicle_names: tuple[str, ...]
    fixed: tuple[bool, ...]
    body1: int
    body2: int
    hitches: tuple[tuple[int, int], ...] = ()
    hitch_names: tuple[str, ...] = ()
    locks: tuple[tuple[int, int], ...] = ()
    constraint_bodies: tuple[int, ...] = ()
    constraint_names: tuple[str, ...] = ()
    external_bodies: tuple[int, ...] = ()
    external_names: tuple[str, ...] = ()
    tangential: str = "no_slide"

    @property
    def n_bodies(self) -> int:
        return len(self.body_names)

    @property
    def n_unknowns(self) -> int:
        return 3 + 2 * len(self.hitches) + len(self.locks) + len(self.constraint_bodies)

    def equation_labels(self) -> tuple[str, ...]:
        """Human-readable label of each equation row (for error messages)."""
        t = {"ratio": "impulse ratio P_t = mu P_n (Eq. 4)",
             "fraction": "impulse ratio P_t = (fraction x mu_max) P_n (Eq. 4)",
             "no_slide": "no sliding at separation",
             "friction": "no sliding at separation / friction limit"}[self.tangential]
        labels = ["restitution (Eq. 5)", t, "moment restitution (Eq. 6)"]
        for name in self.hitch_names:
            labels += [f"hitch {name!r} pin velocity x (Eq. 3)", f"hitch {name!r} pin velocity y (Eq. 3)"]
        labels += [f"yaw lock {self.body_names[f]}-{self.body_names[r]}" for f, r in self.locks]
        labels += [f"velocity constraint {name!r} (Eq. 7)" for name in self.constraint_names]
        return tuple(labels)


@dataclass
class ImpactArrays:
    """Every number of an impact, with a leading batch axis B (named state of the solver).

    Shapes: n bodies, h hitches, c constraints, x external impulses. SI units, world frame.
    Modify fields freely (e.g. ``arrays.restitution[:] = np.linspace(0, 1, B)``) and call
    :func:`solve_arrays`. Values of barrier bodies' masses are ignored (their inverse mass is 0).
    """

    mass: np.ndarray                 # (B, n) kg (inf for a barrier)
    yaw_inertia: np.ndarray          # (B, n) kg m^2
    position: np.ndarray             # (B, n, 2) m, CG
    heading: np.ndarray              # (B, n) rad
    velocity: np.ndarray             # (B, n, 2) m/s, CG
    yaw_rate: np.ndarray             # (B, n) rad/s
    hitch_front_point: np.ndarray    # (B, h, 2) m, pin in front-body axes
    hitch_rear_point: np.ndarray     # (B, h, 2) m, pin in rear-body axes
    point: np.ndarray                # (B, 2) m, contact point, world
    normal_angle: np.ndarray         # (B,) rad, n from body 2 into body 1
    tangent_sign: np.ndarray         # (B,) +1 or -1
    restitution: np.ndarray          # (B,) e
    law_value: np.ndarray            # (B,) mu (ratio) or f (friction)
    moment_restitution: np.ndarray   # (B,) e'
    constraint_point: np.ndarray     # (B, c, 2) m, world
    constraint_direction: np.ndarray  # (B, c) rad, world
    constraint_value: np.ndarray     # (B, c) m/s
    external_point: np.ndarray       # (B, x, 2) m, world
    external_impulse: np.ndarray     # (B, x, 2) N s, world

    @property
    def size(self) -> int:
        return self.mass.shape[0]

    def copy(self) -> "ImpactArrays":
        return replace(self, **{f.name: getattr(self, f.name).copy() for f in fields(self)})

    def repeat(self, n: int) -> "ImpactArrays":
        """n copies of a batch of one (for sweeps)."""
        if self.size != 1:
            raise ValueError(f"repeat() needs a batch of one, this batch has {self.size}")
        return replace(self, **{f.name: np.repeat(getattr(self, f.name), n, axis=0) for f in fields(self)})


def energy_loss_fraction(before, after):
    """(before - after) / before, elementwise; NaN where ``before`` is 0 (no energy to lose).

    A body nearly at rest that is struck gains energy: the fraction is then large and
    negative, -inf if ``before`` is subnormal. Used by both the single and the batch solve.
    """
    if type(before) is float and type(after) is float:  # one impact (ImpactResult): the same IEEE division
        return (before - after) / before if before > 0 else math.nan
    before = np.asarray(before, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        frac = (before - np.asarray(after, dtype=float)) / before
    return np.where(before > 0, frac, np.nan)


def _rot(vec, ang):
    c, s = np.cos(ang), np.sin(ang)
    return np.stack([c * vec[..., 0] - s * vec[..., 1], s * vec[..., 0] + c * vec[..., 1]], -1)


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _put(J, k, body, u, r, sign):
    """Row k of J gets a linear impulse u (B,2) at lever arm r (B,2) on ``body`` with ``sign``."""
    J[:, k, body, 0] += sign * u[:, 0]
    J[:, k, body, 1] += sign * u[:, 1]
    J[:, k, body, 2] += sign * _cross(r, u)


def _assemble(S: ImpactStructure, A: ImpactArrays):
    """Jacobian J (B, K, n, 3), inverse masses (B, n, 3), known-impulse velocities."""
    B, n = A.mass.shape
    K = S.n_unknowns
    fixed = np.asarray(S.fixed, dtype=bool)
    with np.errstate(divide="ignore"):
        inv_m = np.where(fixed, 0.0, 1.0 / A.mass)
        inv_i = np.where(fixed, 0.0, 1.0 / A.yaw_inertia)
    minv = np.stack([inv_m, inv_m, inv_i], -1)  # (B, n, 3)

    J = np.zeros((B, K, n, 3))
    i1, i2 = S.body1, S.body2
    nvec = np.stack([np.cos(A.normal_angle), np.sin(A.normal_angle)], -1)
    tvec = A.tangent_sign[:, None] * np.stack([-nvec[:, 1], nvec[:, 0]], -1)
    r1 = A.point - A.position[:, i1]
    r2 = A.point - A.position[:, i2]
    for k, u in ((0, nvec), (1, tvec)):
        _put(J, k, i1, u, r1, 1.0)
        _put(J, k, i2, u, r2, -1.0)
    J[:, 2, i1, 2] += 1.0
    J[:, 2, i2, 2] -= 1.0
    ex = np.broadcast_to(np.array([1.0, 0.0]), (B, 2))
    ey = np.broadcast_to(np.array([0.0, 1.0]), (B, 2))
    for j, (f, r) in enumerate(S.hitches):
        rf = _rot(A.hitch_front_point[:, j], A.heading[:, f])
        rr = _rot(A.hitch_rear_point[:, j], A.heading[:, r])
        for k, u in ((3 + 2 * j, ex), (4 + 2 * j, ey)):
            _put(J, k, f, u, rf, 1.0)
            _put(J, k, r, u, rr, -1.0)
    k0 = 3 + 2 * len(S.hitches)
    for l, (f, r) in enumerate(S.locks):
        J[:, k0 + l, f, 2] += 1.0
        J[:, k0 + l, r, 2] -= 1.0
    k0 += len(S.locks)
    for c, b in enumerate(S.constraint_bodies):
        d = np.stack([np.cos(A.constraint_direction[:, c]), np.sin(A.constraint_direction[:, c])], -1)
        _put(J, k0 + c, b, d, A.constraint_point[:, c] - A.position[:, b], 1.0)

    p_ext = np.zeros((B, n, 3))
    for x, b in enumerate(S.external_bodies):
        imp = A.external_impulse[:, x]
        r = A.external_point[:, x] - A.position[:, b]
        p_ext[:, b, 0] += imp[:, 0]
        p_ext[:, b, 1] += imp[:, 1]
        p_ext[:, b, 2] += _cross(r, imp)
    return J, minv, p_ext, nvec, tvec


def _rowmax(M):
    """max |M[..., i, :]| over the last axis, by a loop over the (few) columns: numpy's
    reduction over a short last axis is several times slower than this for large batches."""
    out = np.abs(M[..., 0])
    for j in range(1, M.shape[-1]):
        np.maximum(out, np.abs(M[..., j]), out=out)
    return out


def _equilibrate(M, b):
    """Scale rows then columns of M to unit max-norm. Returns (Ms, bs, col_scale)."""
    r = _rowmax(M)
    r[r == 0] = 1.0
    M = M / r[:, :, None]
    b = b / r
    c = _rowmax(np.swapaxes(M, 1, 2))
    c[c == 0] = 1.0
    return M / c[:, None, :], b, c




def _norm1(M):
    """1-norm (largest column sum of magnitudes) of each matrix of a batch."""
    return np.max(np.sum(np.abs(M), axis=1), axis=1)


def _solve(M, b):
    """Batched solve of equilibrated systems through their inverses.

    Returns (x, ok, Ms, cond1): ``cond1`` is the 1-norm condition number of each equilibrated
    matrix (exact, from the inverse), ``ok`` is False where a system is singular or
    ``cond1 >= COND_LIMIT`` (its x is then not to be trusted; NaN if exactly singular).
    """
    Ms, bs, cs = _equilibrate(M, b)
    try:
        Minv = np.linalg.inv(Ms)
    except np.linalg.LinAlgError:
        Minv = np.full_like(Ms, np.nan)
        for i in range(Ms.shape[0]):
            try:
                Minv[i] = np.linalg.inv(Ms[i])
            except np.linalg.LinAlgError:
                pass
    # a singular item has a NaN inverse (or an overflowing one): its x is NaN or inf and ``ok`` False
    with np.errstate(invalid="ignore", over="ignore"):
        x = (Minv @ bs[..., None])[..., 0]
        cond1 = _norm1(Ms) * _norm1(Minv)
    cond1 = np.where(np.isfinite(cond1), cond1, np.inf)
    ok = np.all(np.isfinite(x), axis=1) & (cond1 < COND_LIMIT)
    return x / cs, ok, Ms, cond1


#: Batch items solved per chunk: keeps the temporaries in cache (measured 1.5-2.7x faster than
#: one pass over 1e5-1e6 items when introduced; see the history of plots/impact_speed.md).
CHUNK = 2048



def solve_arrays(S: ImpactStructure, A: ImpactArrays, *, condition: bool = False,
                 method: str = "auto") -> dict[str, np.ndarray]:
    """Solve a batch of impacts, chunk by chunk.

    Parameters
    ----------
    S : ImpactStructure
    A : ImpactArrays
    condition : bool
        Also compute the 2-norm condition number and return the equilibrated matrix
        (dense path only; see :func:`_solve_chunk`).
    method : {"auto", "dense", "compiled"}
        ``"dense"``: :func:`_solve_chunk` (equilibrated K x K inverses, numpy), in chunks of
        :data:`CHUNK`. ``"compiled"``: :func:`solve_compiled` (the dense path's algorithm item by item in a
        numba kernel, :mod:`crashsim.impact.kernel`; compiled on first use, cached on disk):
        the same outputs, the numbers to about cond * eps. ``"auto"`` (default): compiled
        when ``condition`` is False, dense otherwise.

    Returns
    -------
    dict of ndarray
        See :func:`_solve_chunk`.
    """
    if method not in ("auto", "dense", "compiled"):
        raise ValueError(f"method must be 'auto', 'dense' or 'compiled', got {method!r}")
    if method == "compiled" and condition:
        raise ValueError(f"method={method!r} cannot compute the SVD condition number; use condition=False or 'dense'")
    B = A.size
    if method == "compiled" or (method == "auto" and not condition):
        return solve_compiled(S, A)[0]
    def solver(S_, A_):
        return _solve_chunk(S_, A_, condition)
    chunk = CHUNK
    if B <= chunk:
        return solver(S, A)
    parts = []
    for start in range(0, B, chunk):
        sl = slice(start, min(B, start + chunk))
        parts.append(solver(S, replace(A, **{f.name: getattr(A, f.name)[sl] for f in fields(A)})))
    return {k: np.concatenate([p[k] for p in parts], axis=0) for k in parts[0]}


def _tangential_solve(S: ImpactStructure, A: ImpactArrays, Mat, rhs, lam_ns, ok, Ms, cond1, mu_max, u0):
    """The ``ratio``, ``fraction`` and ``friction`` laws of :func:`_solve_chunk`: the items whose answer is
    not the no-slide one solved again with P_t = mu P_n. Returns ``(lam, ok, Ms, cond1, sliding)``."""
    B = lam_ns.shape[0]
    if S.tangential == "ratio":
        mu_used = A.law_value.copy()
        redo = np.ones(B, dtype=bool)
    elif S.tangential == "fraction":  # mu follows this impact's mu_max (NaN where it is unknown)
        mu_used = A.law_value * mu_max
        redo = np.ones(B, dtype=bool)
    else:  # friction: keep the no-slide answer where |mu_max| <= f (Eq. 8)
        stoppable = ok & (lam_ns[:, 0] > 0) & (np.abs(mu_max) <= MU_MAX_LIMIT)
        redo = ~(stoppable & (np.abs(mu_max) <= A.law_value))
        mu_used = A.law_value * np.where(stoppable, np.sign(mu_max), -np.sign(u0[:, 1]))
    lam = lam_ns.copy()
    if np.any(redo):
        idx = np.nonzero(redo)[0]
        Mr = Mat[idx].copy()
        rr = rhs[idx].copy()
        Mr[:, 1, :] = 0.0
        Mr[:, 1, 1] = 1.0
        Mr[:, 1, 0] = -mu_used[idx]
        rr[:, 1] = 0.0
        lam_r, ok_r, Ms_r, cond_r = _solve(Mr, rr)
        lam[idx] = lam_r
        ok[idx] = ok_r  # the answer rests on this solve alone
        Ms = Ms.copy()
        Ms[idx] = Ms_r
        cond1 = cond1.copy()
        cond1[idx] = cond_r
    sliding = redo.copy()
    return lam, ok, Ms, cond1, sliding


def _solve_chunk(S: ImpactStructure, A: ImpactArrays, condition: bool) -> dict[str, np.ndarray]:
    """Solve a batch of impacts.

    Parameters
    ----------
    S : ImpactStructure
    A : ImpactArrays
    condition : bool
        Also compute the 2-norm condition number of each equilibrated system (an SVD each).

    Returns
    -------
    dict of ndarray
        ``velocity`` (B, n, 2), ``yaw_rate`` (B, n), ``impulses`` (B, K) in the unknown order,
        ``normal_impulse``, ``tangential_impulse``, ``moment_impulse``, ``mu``, ``mu_max`` (B,),
        ``sliding`` (B,) bool, ``hitch_impulse`` (B, h, 2) on the front body,
        ``lock_impulse`` (B, l) the moment impulse of each yaw lock on its front body [N m s],
        ``constraint_impulse`` (B, c), ``closing_velocity`` (B,) (relative normal velocity
        before, < 0 when approaching), ``separation_normal``/``separation_tangential`` (B,)
        relative contact-point velocities after, ``ke_before``/``ke_after`` (B, n) [J],
        ``ok`` (B,) bool (False: singular or 1-norm condition >= COND_LIMIT; the item's
        impulses, velocities, separation velocities, ke_after and mu are then NaN),
        ``condition_1norm`` (B,) the exact 1-norm condition number of the equilibrated system
        whose solution is returned (inf if singular), and if ``condition``: ``condition`` (B,)
        and the equilibrated ``matrix`` (B, K, K) of the system whose solution is returned.

    Tangential laws: ``no_slide`` uses the no-sliding solution. ``ratio`` solves with
    P_t = mu P_n; mu_max is reported (NaN where the no-slide system is singular, which does
    not affect the answer). ``friction`` keeps the no-slide solution where |mu_max| <= f
    (Eq. 8), else slides with |mu| = f and the sign of mu_max; where sliding cannot be stopped
    at all (no-slide system singular, |mu_max| > MU_MAX_LIMIT, or a no-slide normal impulse
    that is not compressive: the surfaces would have to pull to stop the sliding, so mu_max
    is no bound) it slides with mu opposing the initial tangential slip, mu = -f sign(u_t),
    as Coulomb friction does.  ``approach_tangential`` (B,) is that slip u_t (the relative
    tangential velocity before) and ``no_slide_normal`` (B,) the normal impulse of the
    no-slide solution (NaN where not ok).
    """
    J, minv, p_ext, nvec, tvec = _assemble(S, A)
    B, K, n, _ = J.shape
    q = np.concatenate([A.velocity, A.yaw_rate[..., None]], -1)  # (B, n, 3)
    Jf = J.reshape(B, K, 3 * n)
    JM = Jf * minv.reshape(B, 1, 3 * n)
    W = JM @ np.swapaxes(Jf, 1, 2)  # (B, K, K)
    u0 = Jf @ q.reshape(B, 3 * n, 1)
    u0 = u0[..., 0]
    dq_ext = (minv * p_ext).reshape(B, 3 * n, 1)
    u_free = u0 + (Jf @ dq_ext)[..., 0]

    e = A.restitution
    ep = A.moment_restitution
    inv_ibar = minv[:, S.body1, 2] + minv[:, S.body2, 2]
    with np.errstate(divide="ignore"):
        ibar = np.where(inv_ibar > 0, 1.0 / inv_ibar, 0.0)

    Mat = W.copy()
    rhs = -u_free.copy()
    rhs[:, 0] = -e * u0[:, 0] - u_free[:, 0]
    Mat[:, 2, :] = -((1.0 + ep) * ibar)[:, None] * W[:, 2, :]
    Mat[:, 2, 2] += ep
    rhs[:, 2] = (1.0 + ep) * ibar * u_free[:, 2]
    k0 = 3 + 2 * len(S.hitches)
    kc = k0 + len(S.locks)
    if S.constraint_bodies:
        rhs[:, kc:] = A.constraint_value - u_free[:, kc:]

    # First pass: no sliding at separation -> mu_max (needed by every law for the report).
    lam_ns, ok, Ms, cond1 = _solve(Mat, rhs)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu_max = lam_ns[:, 1] / lam_ns[:, 0]

    mu_max = np.where(ok, mu_max, np.nan)
    pn_no_slide = np.where(ok, lam_ns[:, 0], np.nan)
    if S.tangential == "no_slide":
        lam = lam_ns
        sliding = np.zeros(B, dtype=bool)
    else:
        lam, ok, Ms, cond1, sliding = _tangential_solve(S, A, Mat, rhs, lam_ns, ok, Ms, cond1, mu_max, u0)

    lam = np.where(ok[:, None], lam, np.nan)  # an untrustworthy solve gives no numbers, not garbage
    dq = minv * (p_ext + np.einsum("bkni,bk->bni", J, lam))
    Q = q + dq
    u_after = (Jf @ Q.reshape(B, 3 * n, 1))[..., 0]
    if S.tangential in ("ratio", "fraction"):
        # sliding continues through separation unless mu happens to equal mu_max
        sliding = np.abs(u_after[:, 1]) > 1e-9 * (1.0 + np.abs(u0[:, 1]))

    fixed = np.asarray(S.fixed, dtype=bool)
    m = np.where(fixed, 0.0, A.mass)
    inertia = np.where(fixed, 0.0, A.yaw_inertia)

    def ke(v, w):
        return 0.5 * m * np.sum(v * v, -1) + 0.5 * inertia * w * w

    with np.errstate(invalid="ignore", divide="ignore"):
        mu = lam[:, 1] / lam[:, 0]
    out = {
        "velocity": Q[..., :2],
        "yaw_rate": Q[..., 2],
        "impulses": lam,
        "normal_impulse": lam[:, 0],
        "tangential_impulse": lam[:, 1],
        "moment_impulse": lam[:, 2],
        "mu": mu,
        "mu_max": mu_max,
        "sliding": sliding,
        "hitch_impulse": lam[:, 3:k0].reshape(B, len(S.hitches), 2),
        "lock_impulse": lam[:, k0:kc],
        "constraint_impulse": lam[:, kc:],
        "closing_velocity": u0[:, 0],
        "separation_normal": u_after[:, 0],
        "separation_tangential": u_after[:, 1],
        "ke_before": ke(A.velocity, A.yaw_rate),
        "ke_after": ke(Q[..., :2], Q[..., 2]),
        "normal": nvec,
        "tangent": tvec,
        "ok": ok,
        "condition_1norm": cond1,
        "approach_tangential": u0[:, 1],
        "no_slide_normal": pn_no_slide,
    }
    if condition:
        Mc = np.where(np.isfinite(Ms), Ms, 0.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            out["condition"] = np.where(ok, np.linalg.cond(Mc), np.inf)
        out["matrix"] = Mc
    return out


# --------------------------------------------------------------------------------------------
# The compiled path: the dense path's algorithm item by item (crashsim.impact.kernel)
# --------------------------------------------------------------------------------------------

def kernel_structure(S: ImpactStructure) -> tuple:
    """The structure as the kernels take it (``kernel.Structure``), kept on S after the first call."""
    meta = S.__dict__.get("_kernel_meta")
    if meta is None:
        meta = kernel.Structure(np.asarray(S.fixed, dtype=np.bool_), S.body1, S.body2, kernel.LAW_CODES[S.tangential],
                                np.asarray(S.hitches, dtype=np.int64).reshape(len(S.hitches), 2),
                                np.asarray(S.constraint_bodies, dtype=np.int64),
                                np.asarray(S.external_bodies, dtype=np.int64),
                                np.asarray(S.locks, dtype=np.int64).reshape(len(S.locks), 2))
        object.__setattr__(S, "_kernel_meta", meta)  # a cache, not a field: eq, hash, replace unaffected
    return meta


_LIMITS = None


def contiguous(a):
    """``a`` as a C-contiguous float64 array (itself if it is one already): the kernels' argument form."""
    return a if a.flags.c_contiguous and a.dtype == np.float64 else np.ascontiguousarray(a, dtype=np.float64)


def input_shapes(n: int, h: int, c: int, x: int) -> tuple:
    """(field, shape of one item) of :class:`ImpactArrays`, in field order: the layout of the
    packed input vector of ``kernel.solve_packed`` (field by field, each (B,) + shape)."""
    return (("mass", (n,)), ("yaw_inertia", (n,)), ("position", (n, 2)), ("heading", (n,)), ("velocity", (n, 2)),
            ("yaw_rate", (n,)), ("hitch_front_point", (h, 2)), ("hitch_rear_point", (h, 2)), ("point", (2,)),
            ("normal_angle", ()), ("tangent_sign", ()), ("restitution", ()), ("law_value", ()),
            ("moment_restitution", ()), ("constraint_point", (c, 2)), ("constraint_direction", (c,)),
            ("constraint_value", (c,)), ("external_point", (x, 2)), ("external_impulse", (x, 2)))


def output_shapes(n: int, K: int, extras: bool) -> tuple:
    """(key, shape of one item) of the compiled kernels' output vector, in its order
    (``kernel._out_views``; flags stored as 0.0 / 1.0)."""
    return ((("velocity", (n, 2)), ("yaw_rate", (n,)), ("impulses", (K,)), ("mu", ()), ("mu_max", ()),
             ("sliding", ()), ("closing_velocity", ()), ("separation_normal", ()), ("separation_tangential", ()),
             ("ok", ()), ("approach_tangential", ()), ("no_slide_normal", ()), ("ke_before", (n,)), ("ke_after", (n,)),
             ("normal", (2,)), ("tangent", (2,)), ("condition_1norm", ()))
            + ((("work", (6,)), ("reason", ())) if extras else ()))


def unpack(S: ImpactStructure, Y: np.ndarray, B: int, extras: bool = False):
    """The dict of :func:`_solve_chunk` from a compiled kernel's output vector Y (views), and
    the work (B, 6) and admissibility codes (B,) if ``extras`` (else None, None)."""
    h = len(S.hitches)
    K = S.n_unknowns
    out = {}
    o = 0
    for key, shape in output_shapes(S.n_bodies, K, extras):
        size = B * math.prod(shape)
        out[key] = Y[o:o + size].reshape((B,) + shape)
        o += size
    out["sliding"] = out["sliding"] != 0.0
    out["ok"] = out["ok"] != 0.0
    lam = out["impulses"]
    k0 = 3 + 2 * h
    kc = k0 + len(S.locks)
    out["normal_impulse"] = lam[:, 0]
    out["tangential_impulse"] = lam[:, 1]
    out["moment_impulse"] = lam[:, 2]
    out["hitch_impulse"] = lam[:, 3:k0].reshape(B, h, 2)
    out["lock_impulse"] = lam[:, k0:kc]
    out["constraint_impulse"] = lam[:, kc:]
    work = out.pop("work", None)
    reason = out.pop("reason", None)
    return out, work, (reason.astype(np.int64) if reason is not None else None)


def solve_compiled(S: ImpactStructure, A: ImpactArrays, extras: bool = False):
    """Solve a batch with the compiled kernel (:mod:`crashsim.impact.kernel`).

    Returns ``(out, work, reason)``: ``out`` the dict of :func:`_solve_chunk` (without the SVD
    condition number); with ``extras`` also the work of each group of impulses (B, 6), in the
    order of :data:`WORK_KEYS`, and the admissibility code (B,) of ``admissible.REASONS``
    (else None, None).
    """
    global _LIMITS
    if _LIMITS is None:
        _LIMITS = kernel.limits()
    Y = kernel.solve_batch(kernel_structure(S), kernel.pack_items(A), _LIMITS, extras)
    return unpack(S, Y, A.size, extras)


def flat_spec(shapes) -> tuple:
    """((name, start, stop), ...) of a batch of one laid out by ``shapes``; stop None for a scalar."""
    spec, o = [], 0
    for key, shape in shapes:
        size = math.prod(shape)
        spec.append((key, o, None if shape == () else o + size))
        o += size
    return tuple(spec)


def _flat_fields(spec, values: list) -> dict:
    """Split a list of numbers laid out by ``spec`` (:func:`flat_spec`) into {name: list or float}."""
    return {key: values[a] if b is None else values[a:b] for key, a, b in spec}


def solve_packed(S: ImpactStructure, X: np.ndarray) -> dict:
    """One impact by the compiled kernel, from its numbers packed as ``input_shapes`` lays them
    out (``solve._values``). Returns the outputs of :func:`output_shapes` (with work and
    admissibility code) as python floats and flat lists: the single solve's fast path.
    ``inputs(S, values)`` splits the input list the same way."""
    global _LIMITS
    if _LIMITS is None:
        _LIMITS = kernel.limits()
    meta = S.__dict__.get("_packed_meta")
    if meta is None:
        fixed, b1, b2, law, hitches, cb, xb, locks = kernel_structure(S)
        ints = np.array([S.n_bodies, len(S.hitches), len(S.constraint_bodies), len(S.external_bodies), b1, b2, law],
                        dtype=np.int64)
        meta = (ints, fixed, hitches, cb, xb, flat_spec(output_shapes(S.n_bodies, S.n_unknowns, True)),
                flat_spec(input_shapes(S.n_bodies, len(S.hitches), len(S.constraint_bodies), len(S.external_bodies))),
                locks)
        object.__setattr__(S, "_packed_meta", meta)
    Y = kernel.solve_packed(meta[0], meta[1], meta[2], meta[3], meta[4], meta[7], X, _LIMITS, True)
    return _flat_fields(meta[5], Y.tolist())


def inputs(S: ImpactStructure, values: list) -> dict:
    """The fields of ImpactArrays of a batch of one from their packed list (:func:`solve_packed`)."""
    return _flat_fields(S.__dict__["_packed_meta"][6], values)

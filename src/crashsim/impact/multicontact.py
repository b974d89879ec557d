"""Simultaneous impact of several contact points: a velocity-level complementarity problem.

Where several points of any bodies touch at one instant (a car pinned between a prime mover and a
parked van; a tractor-semitrailer tangled with a pickup and its trailer), their impulses are solved
together, not one after another.  The unknowns are the normal impulses ``lambda_n``, the friction
impulses and the moment impulses of closed articulation stops; hitches are pins that hold.

The rule at every contact point i (normal velocity ``u_n``, > 0 separating; tangential ``u_t``):

* **restitution** (Newton's kinematic law): after the impact ``u_n+ >= e_i max(-u_n-, 0)``,
  complementary to ``lambda_n >= 0``: a point that takes an impulse separates at exactly e times its
  approach speed, a point that leaves faster takes none;
* **Coulomb friction** with coefficient ``f_i``: ``|lambda_t| <= f_i lambda_n``; a point that keeps
  sliding (``u_t+ != 0``) takes ``lambda_t = -f_i lambda_n sign(u_t+)``, otherwise it sticks.  In the
  plane the friction cone has two directions (+t, -t), so the problem is an LCP exactly, in the
  formulation of Anitescu and Potra (friction impulses ``beta+, beta- >= 0`` and the sliding speed
  ``gamma``), which Lemke's method solves;
* **closed articulation stops** push only: the relative yaw rate does not go further past the stop,
  complementary to a moment impulse >= 0 (a plastic stop);
* **hitch pins** hold (equality rows, eliminated through the constrained inverse mass
  ``P = M^-1 - M^-1 G^T (G M^-1 G^T)^-1 G M^-1``).

With one contact point this is Brach's impulse-momentum impact with restitution e, the friction
law with coefficient f (no sliding at separation where ``|mu_max| <= f``, else ``|mu| = f``) and no
moment impulse: the model of a single later impact (tested against
:func:`crashsim.impact.solve_impact`).

**Strikes first, then everything at once.**  Three equal boxes in a row, the first striking the
other two that touch: solved all at once, at e = 0 all three move on at a third of the speed (the
plastic answer, exact), and at e = 1 the simultaneous law gives (-v/3, 2v/3, 2v/3), energy kept,
where a Newton's cradle of steel balls passes the pulse on from contact to contact (0, 0, v).  With
``strike`` thresholds (the run-out gives each point its pair's impulse threshold, 0.5 m/s by default)
the instant is solved in rounds: the points approaching at their threshold or faster first,
together, without the others (the strikes); then the points those strikes drove in at that speed or
faster (a tractor's front pushed into a barrier through the kingpin by its trailer's slap), each
rebounding by its own e; at most ``MAX_ROUNDS`` such rounds; and last one simultaneous solve over
every point, each leaving at e times its remaining approach speed or more, which stops whatever
still closes slower than a strike (the resting contacts of a tangle).  So the cradle at e = 1 gives
(0, 0, v); at e = 0, v/3 each.  A point struck and a point pushed are then told apart in the
result, and a pushed point's rebound is its own.  Without ``strike``, every point at once.

**Solver**: Lemke's complementary pivoting with the lexicographic ratio test (finite, no cycling),
on the problem scaled to velocities and impulses of order one.  Convergence criterion: the solution
is accepted when ``z >= -tol``, ``w >= -tol`` and ``|z_i w_i| <= tol`` for every row, with
``tol = LCP_TOL`` relative to the largest velocity of the problem (a pivoting method ends exactly up
to round-off; the check catches a ray termination or a round-off failure).

**No impact makes energy.**  Newton's law with several points and friction can, in rare
geometries, give a solution that gains kinetic energy.  The solution of a round is then replaced by
the same problem with e = 0 at every point (``"plastic"``), and if that also gains, by e = 0 without
friction (``"frictionless"``): the velocities closest to zero kinetic energy that impulses >= 0 can
reach, a non-negative least-squares problem (its optimality conditions are that LCP), which always
has a solution and can only lose energy.  The result says which law was used.  Where the points
jam (more rows than the bodies' freedoms, all of them closing), the velocities are unique and the
impulses are not: the solution found can hold large impulses that cancel.

Sources: Stewart, D.E., Trinkle, J.C., "An implicit time-stepping scheme for rigid body dynamics with
inelastic collisions and Coulomb friction", IJNME 39 (1996); Anitescu, M., Potra, F.A., "Formulating
dynamic multi-rigid-body contact problems with friction as solvable linear complementarity problems",
Nonlinear Dynamics 14 (1997); Lemke, C.E., "Bimatrix equilibrium points and mathematical
programming", Management Science 11 (1965).  Box2D and Bullet solve the same conditions
approximately by sequential impulses (projected Gauss-Seidel, a fixed number of iterations).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import nnls

__all__ = ["LCP_TOL", "ContactSolution", "constrained_inverse", "lemke", "solve_contacts"]

#: Relative tolerance of the complementarity conditions (module docstring).
LCP_TOL = 1e-9
#: A solution may gain at most this fraction of the kinetic energy before the impact (round-off).
ENERGY_TOL = 1e-12
#: Rounds of strikes solved one after another at an instant before every point is solved at once.
MAX_ROUNDS = 8


def lemke(M: np.ndarray, q: np.ndarray, tol: float = 1e-12, max_pivots: int | None = None):
    """Solve the LCP ``w = M z + q >= 0, z >= 0, z.w = 0`` by Lemke's method (covering vector of ones,
    lexicographic ratio test).  Returns ``z`` or None (ray termination, or no end within the pivots)."""
    q = np.asarray(q, dtype=float)
    n = q.size
    if n == 0 or np.all(q >= 0.0):
        return np.zeros(n)
    # tableau rows: basic variables; columns: w (n), z (n), z0, right-hand side
    T = np.hstack([np.eye(n), -np.asarray(M, dtype=float), -np.ones((n, 1)), q[:, None]])
    basis = np.arange(n)
    z0 = 2 * n
    max_pivots = max_pivots or 50 * (n + 1)

    def pivot(r, col):
        T[r] /= T[r, col]
        factor = T[:, col].copy()
        factor[r] = 0.0
        T[:] -= factor[:, None] * T[r][None, :]

    r = int(np.argmin(q))
    pivot(r, z0)
    leaving = int(basis[r])
    basis[r] = z0
    entering = leaving + n  # the complement of w_r
    for _ in range(max_pivots):
        col = T[:, entering]
        rows = np.flatnonzero(col > tol)
        if rows.size == 0:
            return None
        # lexicographic minimum of (rhs, B^-1 rows) / col over the candidate rows
        cand = rows
        ratio = T[cand, -1] / col[cand]
        for k in range(-1, n):
            vals = ratio if k < 0 else T[cand, k] / col[cand]
            best = vals.min()
            keep = vals <= best + 1e-12 * max(1.0, abs(best))
            cand = cand[keep]
            if cand.size == 1:
                break
            ratio = ratio[keep] if k < 0 else ratio
        r = int(cand[0])
        pivot(r, entering)
        leaving = int(basis[r])
        basis[r] = entering
        if leaving == z0:
            z = np.zeros(n)
            for i, b in enumerate(basis):
                if n <= b < 2 * n:
                    z[b - n] = T[i, -1]
            return z
        entering = leaving + n if leaving < n else leaving - n
    return None


@dataclass(frozen=True)
class ContactSolution:
    """What :func:`solve_contacts` returns (SI; arrays per contact point or stop row).

    Attributes
    ----------
    velocity : ndarray (n3,)
        Velocities after the impact (the DOF order of the input).
    normal, tangential : ndarray (nc,)
        Normal and friction impulses at each point [N s] (on the first body, along n and t).
    stop : ndarray (ns,)
        Moment impulse of each closed stop [N m s] (>= 0: pushes away from the stop).
    law : {"friction", "plastic", "frictionless"}
        The rule the accepted solution follows (module docstring).
    energy_before, energy_after : float
        Kinetic energy of the DOFs [J].
    work : ndarray (nc,)
        Energy each point's impulses took [J], ``-lambda . (u- + u+) / 2`` over its normal and
        tangential rows (sums with ``stop_work`` and the hitch-consistency projection to the loss).
    work_normal, work_tangential : ndarray (nc,)
        The normal and tangential parts of ``work``.
    stop_work : ndarray (ns,)
    attempts : tuple
        The laws tried and refused before the accepted one, with why (``(law, reason)``).
    inverse_mass : ndarray (n3, n3)
        The constrained inverse mass ``P`` the impulses act through (:func:`constrained_inverse`), for
        a caller that splits the velocity change by point or pair.
    """

    velocity: np.ndarray
    normal: np.ndarray
    tangential: np.ndarray
    stop: np.ndarray
    law: str
    energy_before: float
    energy_after: float
    work: np.ndarray
    work_normal: np.ndarray
    work_tangential: np.ndarray
    stop_work: np.ndarray
    attempts: tuple = ()
    inverse_mass: np.ndarray | None = None

    @property
    def energy_loss(self) -> float:
        return self.energy_before - self.energy_after


def constrained_inverse(minv: np.ndarray, G: np.ndarray):
    """The inverse mass with the rows ``G u = 0`` held, ``P = M^-1 - M^-1 G^T (G M^-1 G^T)^+ G M^-1``
    (n3, n3): the velocity change of an impulse ``J^T lambda`` is ``P J^T lambda``; and the projection
    of velocities onto ``G u = 0`` closest in the kinetic-energy metric."""
    Minv = np.diag(minv)
    if G.shape[0] == 0:
        return Minv, lambda u: u
    GM = G * minv[None, :]
    S = GM @ G.T
    Sinv = np.linalg.pinv(S, rcond=1e-13)
    P = Minv - GM.T @ Sinv @ GM
    return P, lambda u: u - GM.T @ (Sinv @ (G @ u))


def _frictional_lcp(A, b, nc, ns, target, f, m_ref, i_ref):
    """The LCP of the module docstring, scaled, with the normal velocity each point must leave at
    (``u_n+ >= target``); returns (lambda_n, lambda_t, lambda_s) or None.  Points with f = 0 take no
    friction variables (with them the problem is degenerate, and Lemke's method can end on a ray)."""
    An, At, As = slice(0, nc), slice(nc, 2 * nc), slice(2 * nc, 2 * nc + ns)
    fr = np.flatnonzero(f > 0.0)
    nf = fr.size
    tr = nc + fr  # the tangential rows of the points with friction
    bn = b[An] - target
    bt = b[tr]
    bs = b[As]
    N = nc + 3 * nf + ns
    Mx = np.zeros((N, N))
    q = np.zeros(N)
    # variables: lambda_n / m_ref, beta+ / m_ref, beta- / m_ref, gamma, lambda_s / i_ref
    iN, iP, iM, iG, iS = (slice(0, nc), slice(nc, nc + nf), slice(nc + nf, nc + 2 * nf),
                          slice(nc + 2 * nf, nc + 3 * nf), slice(nc + 3 * nf, N))
    Ann, Ant, Ans = A[An, An] * m_ref, A[An, tr] * m_ref, A[An, As] * i_ref
    Atn, Att, Ats = A[tr, An] * m_ref, A[np.ix_(tr, tr)] * m_ref, A[tr, As] * i_ref
    Asn, Ast, Ass = A[As, An] * m_ref, A[As, tr] * m_ref, A[As, As] * i_ref
    eye = np.eye(nf)
    Mx[iN, iN], Mx[iN, iP], Mx[iN, iM], Mx[iN, iS] = Ann, Ant, -Ant, Ans
    Mx[iP, iN], Mx[iP, iP], Mx[iP, iM], Mx[iP, iG], Mx[iP, iS] = Atn, Att, -Att, eye, Ats
    Mx[iM, iN], Mx[iM, iP], Mx[iM, iM], Mx[iM, iG], Mx[iM, iS] = -Atn, -Att, Att, eye, -Ats
    Mx[iG, iN][:, fr] = np.diag(f[fr])
    Mx[iG, iP], Mx[iG, iM] = -eye, -eye
    Mx[iS, iN], Mx[iS, iP], Mx[iS, iM], Mx[iS, iS] = Asn, Ast, -Ast, Ass
    q[iN], q[iP], q[iM], q[iS] = bn, bt, -bt, bs
    scale = max(float(np.max(np.abs(q))), 1e-12)
    z = lemke(Mx, q / scale)
    if z is None:
        return None
    z = z * scale
    w = Mx @ z + q
    tol = LCP_TOL * scale
    if np.any(z < -tol) or np.any(w < -tol) or np.any(np.abs(z * w) > tol * max(1.0, float(np.max(np.abs(z))))):
        return None
    z = np.maximum(z, 0.0)
    lt = np.zeros(nc)
    lt[fr] = (z[iP] - z[iM]) * m_ref
    return z[iN] * m_ref, lt, z[iS] * i_ref


def _projection(P, Jn, Js, uc, mass):
    """The frictionless plastic impact as the least kinetic energy over impulses >= 0 (non-negative
    least squares, always solvable): ``min_lambda |M^1/2 (uc + P J^T lambda)|``, whose optimality
    conditions are the LCP with e = 0 and f = 0 (``J u+ >= 0``, complementary to ``lambda >= 0``,
    since ``P M u+ = u+`` on the hitch rows).  Returns (lambda_n, lambda_s) of the rows given."""
    J = np.vstack([Jn, Js])
    root = np.sqrt(mass)
    B = root[:, None] * (P @ J.T)
    # no column scaling: where the points jam (more rows than the bodies' freedoms), the impulses are
    # not unique and grow large along the rows' null space; scaled columns let them run to 1e19
    lam, _ = nnls(B, -root * uc, maxiter=50 * (J.shape[0] + 1))
    return lam[:Jn.shape[0]], lam[Jn.shape[0]:]


def _subproblem(A, b, nc, ns, rows, e, f, m_ref, i_ref, P, Jn, Jt, Js, uc, mass, attempts):
    """One Newton LCP over the contact points ``rows`` (bool, nc) and every stop row, from the velocities
    ``uc``: each point leaves at e times its approach speed or more (``b`` = J uc).  The law's fallbacks
    (module docstring) where the solution would gain energy.  Returns ``(lambda_n, lambda_t, lambda_s,
    velocity, law)`` (zero impulses outside ``rows``)."""
    idx = np.concatenate([np.flatnonzero(rows), nc + np.flatnonzero(rows), 2 * nc + np.arange(ns)])
    k = int(rows.sum())
    As, bs = A[np.ix_(idx, idx)], b[idx]
    es, fs = e[rows], f[rows]
    approach = np.maximum(-bs[:k], 0.0)
    ke0 = 0.5 * float(np.sum(mass * uc * uc))
    for law, ee, ff in (("friction", es, fs), ("plastic", np.zeros(k), fs), ("frictionless", np.zeros(k), np.zeros(k))):
        if law == "plastic" and not np.any(es > 0.0):
            continue
        if law == "frictionless":
            pn, ps = _projection(P, Jn[rows], Js, uc, mass)
            sol = (pn, np.zeros(k), ps)
        else:
            sol = _frictional_lcp(As, bs, k, ns, ee * approach, ff, m_ref, i_ref)
        if sol is None:
            attempts.append((law, "no solution"))
            continue
        ln, lt, ls = np.zeros(nc), np.zeros(nc), sol[2]
        ln[rows], lt[rows] = sol[0], sol[1]
        up = uc + P @ (Jn.T @ ln + Jt.T @ lt + Js.T @ ls)
        if 0.5 * float(np.sum(mass * up * up)) > ke0 * (1.0 + ENERGY_TOL) + 1e-9 and law != "frictionless":
            attempts.append((law, f"gains {0.5 * float(np.sum(mass * up * up)) - ke0:.4g} J"))
            continue
        return ln, lt, ls, up, law
    raise AssertionError(f"simultaneous impact: no solution ({attempts})")  # pragma: no cover - the projection solves


def solve_contacts(minv, G, Jn, Jt, Js, u, restitution, friction, strike=None, rounds: int = MAX_ROUNDS
                   ) -> ContactSolution:
    """Impulses of an impact of several points (module docstring).

    Parameters
    ----------
    minv : ndarray (n3,)
        Inverse masses and inertias of the degrees of freedom [1/kg, 1/(kg m^2)].
    G : ndarray (m, n3)
        Hitch rows that hold (``G u = 0``).
    Jn, Jt : ndarray (nc, n3)
        Normal and tangential velocity rows of the contact points (``u_n = Jn u``).
    Js : ndarray (ns, n3)
        Rows of the closed stops (``Js u >= 0`` after the impact).
    u : ndarray (n3,)
        Velocities before the impact.
    restitution, friction : ndarray (nc,)
        e and f of each point.
    strike : ndarray (nc,), optional
        The approach speed [m/s] at which each point strikes (its pair's impulse threshold).  Given, the
        points closing at it or faster are solved first, together, without the others (the strikes);
        then those the strikes drove in at that speed (a tractor's front pushed into a barrier through
        the kingpin by its trailer's slap), which rebound by their own e, up to ``rounds`` times; then
        every point at once, each leaving at e times its approach speed or more.  None: every point at
        once.
    """
    minv = np.asarray(minv, dtype=float)
    u = np.asarray(u, dtype=float)
    G = np.asarray(G, dtype=float).reshape(-1, minv.size)
    Jn = np.asarray(Jn, dtype=float).reshape(-1, minv.size)
    Jt = np.asarray(Jt, dtype=float).reshape(-1, minv.size)
    Js = np.asarray(Js, dtype=float).reshape(-1, minv.size)
    nc, ns = Jn.shape[0], Js.shape[0]
    e = np.asarray(restitution, dtype=float).reshape(nc)
    f = np.asarray(friction, dtype=float).reshape(nc)
    mass = np.where(minv > 0.0, 1.0 / np.where(minv > 0.0, minv, 1.0), 0.0)
    ke_before = 0.5 * float(np.sum(mass * u * u))
    P, project = constrained_inverse(minv, G)
    u0 = project(u)
    J = np.vstack([Jn, Jt, Js])
    A = J @ P @ J.T
    dn = np.diag(A)[:nc]
    m_ref = 1.0 / float(np.mean(dn)) if nc and np.mean(dn) > 0 else 1.0
    ds = np.diag(A)[2 * nc:]
    i_ref = 1.0 / float(np.mean(ds)) if ns and np.mean(ds) > 0 else 1.0
    attempts: list = []
    laws = []
    ln, lt, ls = np.zeros(nc), np.zeros(nc), np.zeros(ns)
    wn, wt, wsum = np.zeros(nc), np.zeros(nc), np.zeros(ns)
    uc = u0
    steps = [None] * (rounds if strike is not None else 0) + ["all"]
    for step in steps:
        vn = Jn @ uc
        rows = np.ones(nc, dtype=bool) if step == "all" else vn < -np.asarray(strike, dtype=float)
        if step == "all" and not np.any(vn < 0.0) and not np.any(Js @ uc < 0.0):
            break  # nothing approaches after the strikes: no impulse left to give
        if not rows.any():
            continue
        rn, rt, rs, up, law = _subproblem(A, J @ uc, nc, ns, rows, e, f, m_ref, i_ref, P, Jn, Jt, Js, uc, mass,
                                          attempts)
        laws.append(law)
        # the work of this round's impulses, point by point (they sum to its loss)
        wn -= rn * (vn + Jn @ up) / 2.0
        wt -= rt * (Jt @ uc + Jt @ up) / 2.0
        wsum -= rs * (Js @ uc + Js @ up) / 2.0
        ln, lt, ls = ln + rn, lt + rt, ls + rs
        uc = up
    ke_after = 0.5 * float(np.sum(mass * uc * uc))
    law = max(laws, key=("friction", "plastic", "frictionless").index) if laws else "friction"
    return ContactSolution(uc, ln, lt, ls, law, ke_before, ke_after, wn + wt, wn, wt, wsum, tuple(attempts), P)

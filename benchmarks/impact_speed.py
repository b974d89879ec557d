"""Speed of the impact solver: one solve through the public API, and batch throughput.

Run from the repository root (single core; the thread limits are set below before numpy loads)::

    PYTHONPATH=src python benchmarks/impact_speed.py [--out plots] [--repeats 5] [--max-size 1000000]

The impact is the paper's Table 5 (a loaded tractor-semitrailer, B, strikes the side of an empty
one, A, at its trailer wheels; geometry from shared/papers/recovered-geometry.md). It measures

(a) the latency of ``solve_impact`` (the single-solve public API, which also computes the
    condition number and builds an ``ImpactResult``), median over many repeats;
(b) the throughput of ``ImpactBatch.solve`` [impacts solved per second] with randomised inputs
    (speeds, directions of approach, crush-surface angle, e, and f or mu), at batch sizes
    1e2 .. 1e6, for each tangential law: ``no_slide``; ``friction`` (a second solve for the items
    that slide, about half here); ``ratio`` (always a second solve). Median of ``--repeats`` runs;
(c) where the time goes: every stage of ``core.solve_arrays`` timed on its own (a replica of its
    code, checked against it), and
(d) the gain of the proposed changes, prototyped here and checked against ``solve_arrays``
    (``src/crashsim/impact/core.py`` is not modified):
      * ``chunked``: ImpactBatch.solve in chunks of ``CHUNK`` items (working set in cache, no page
        faults on fresh 100 MB temporaries);
      * ``chunked + fast equilibration``: also the row/column max-norms by a loop over the K
        columns instead of ``np.max(np.abs(M), axis=...)`` over a 7-long axis (same numbers);
      * ``reduced``: the algorithm proposed for core.solve_arrays (see ``reduced_solve_arrays``):
        batch-last arrays, W from the sparse rows, hitch and constraint impulses eliminated by a
        Cholesky factorisation of their SPD block, and the 3 x 3 contact system (2 x 2 when e' = -1)
        solved in closed form for each law, so the friction and ratio laws cost no second solve.

Writes ``impact_speed.md`` (tables + machine), ``impact_speed.png`` (solves/s vs batch size) and
``impact_speed.json`` (raw numbers) into ``--out`` (default ``plots/``).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "VECLIB_MAXIMUM_THREADS",
             "NUMEXPR_NUM_THREADS"):
    os.environ[_var] = "1"

import argparse  # noqa: E402
import dataclasses  # noqa: E402
import json  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

from crashsim import (Body, CrushSurface, Hitch, ImpactBatch, ImpactProblem,  # noqa: E402
                      TangentialLaw, Vehicle, chain_states, solve_impact)
from crashsim.geometry import rotate  # noqa: E402
from crashsim.impact import core  # noqa: E402
from crashsim.impact.core import ImpactArrays, ImpactStructure, solve_arrays  # noqa: E402

TARGET = 100_000.0  # solves per second on one core
CHUNK = 2048
LAWS = ("no_slide", "friction", "ratio")
SIZES = (100, 1_000, 10_000, 100_000, 1_000_000)


# --------------------------------------------------------------------------------------------
# The impact: paper Table 5
# --------------------------------------------------------------------------------------------

def table5_problem(law: str = "no_slide", value: float = 0.0) -> ImpactProblem:
    """Table 5: B (tractor + loaded trailer, heading +y) into A's empty trailer (heading +x)."""
    a = Vehicle("A", (Body("A_tractor", 9500, 21000), Body("A_trailer", 6000, 48000)), (Hitch((-3.1, 0), (3.991, 0)),))
    b = Vehicle("B", (Body("B_tractor", 9500, 21000), Body("B_trailer", 20000, 150000)), (Hitch((-3.1, 0), (3.991, 0)),))
    sa = chain_states(a, (0.0, 0.0), 0.0, (13.41, 0.0))
    pt = np.asarray(sa["A_trailer"].position) + (-2.517, -1.157)
    cg_b = pt - rotate((3.922, 0.011), math.pi / 2)  # B's front contact: 3.922 ahead, 0.011 left of its CG
    sb = chain_states(b, tuple(cg_b), math.pi / 2, (0.0, 13.41))
    return ImpactProblem((a, b), {**sa, **sb}, "A_trailer", "B_tractor",
                         CrushSurface(tuple(pt), math.pi / 2, 0.05, TangentialLaw(law, value), -1.0, -1))


def check_table5() -> dict:
    r = solve_impact(table5_problem())
    got = {
        "A tractor V_x": r.bodies["A_tractor"].velocity[0], "A trailer V_y": r.bodies["A_trailer"].velocity[1],
        "A trailer Omega": r.bodies["A_trailer"].yaw_rate, "B tractor V_x": r.bodies["B_tractor"].velocity[0],
        "P_t": r.tangential_impulse, "P_n": r.normal_impulse, "loss system": r.energy_loss["system"],
    }
    paper = {"A tractor V_x": 12.22, "A trailer V_y": 7.12, "A trailer Omega": -2.24, "B tractor V_x": 3.2,
             "P_t": -18395, "P_n": 39453, "loss system": 0.093}
    return {k: (paper[k], float(got[k])) for k in paper}


def randomised_batch(law: str, n: int, seed: int = 1) -> ImpactBatch:
    """n Table 5 impacts with random speeds, approach directions, surface angle, e, f or mu.

    Speeds: A 5-25 m/s along +x; B 8-25 m/s within +-15 deg of +y (zero yaw rates keep the pin
    velocities of each vehicle equal). Crush normal pi/2 +- 10 deg; e in [0, 0.3]; f in
    [0.2, 0.8] (friction: about half the items slide); mu in [-0.8, 0.8] (ratio). Every item
    approaches (closing velocity < 0).
    """
    value = {"no_slide": 0.0, "friction": 0.5, "ratio": 0.0}[law]
    batch = ImpactBatch.from_problem(table5_problem(law, value), n)
    A = batch.arrays
    rng = np.random.default_rng(seed)
    ia = [batch.body_index(b) for b in ("A_tractor", "A_trailer")]
    ib = [batch.body_index(b) for b in ("B_tractor", "B_trailer")]
    va = rng.uniform(5.0, 25.0, n)
    vb = rng.uniform(8.0, 25.0, n)
    dirb = math.pi / 2 + np.radians(rng.uniform(-15.0, 15.0, n))
    for i in ia:
        A.velocity[:, i, 0] = va
        A.velocity[:, i, 1] = 0.0
    for i in ib:
        A.velocity[:, i, 0] = vb * np.cos(dirb)
        A.velocity[:, i, 1] = vb * np.sin(dirb)
    A.normal_angle[:] = math.pi / 2 + np.radians(rng.uniform(-10.0, 10.0, n))
    A.restitution[:] = rng.uniform(0.0, 0.3, n)
    if law == "friction":
        A.law_value[:] = rng.uniform(0.2, 0.8, n)
    elif law == "ratio":
        A.law_value[:] = rng.uniform(-0.8, 0.8, n)
    return batch


# --------------------------------------------------------------------------------------------
# Timing helpers
# --------------------------------------------------------------------------------------------

SPREAD: list[float] = []  # (max - min) / median of every timing, for the report
FIRST: dict[str, float] = {}  # time of the first (warm-up) call of each variant, last measurement


def _median_time(fn, repeats: int, min_time: float = 0.0) -> float:
    """Median wall time of fn() over ``repeats`` runs (each run repeated to last >= min_time).

    One warm-up call first: the first call on a new batch also pays the page faults of its
    fresh temporaries (about 3x slower at 1e5 items), which is not the steady state.
    """
    fn()  # warm-up
    times = []
    for _ in range(repeats):
        k, t0 = 0, time.perf_counter()
        while True:
            fn()
            k += 1
            dt = time.perf_counter() - t0
            if dt >= min_time:
                break
        times.append(dt / k)
    med = float(np.median(times))
    SPREAD.append((max(times) - min(times)) / med)
    return med


def _interleaved_times(calls: dict, repeats: int, min_time: float = 0.0) -> dict[str, float]:
    """Median time per call of each function, timed in interleaved rounds (after one warm-up).

    The warm-up (first) call's time is kept in ``FIRST[name]``.
    """
    FIRST.clear()
    for name, fn in calls.items():
        t0 = time.perf_counter()
        fn()
        FIRST[name] = time.perf_counter() - t0
    times: dict[str, list[float]] = {name: [] for name in calls}
    for _ in range(repeats):
        for name, fn in calls.items():
            k, t0 = 0, time.perf_counter()
            while True:
                fn()
                k += 1
                dt = time.perf_counter() - t0
                if dt >= min_time:
                    break
            times[name].append(dt / k)
    out = {}
    for name, ts in times.items():
        med = float(np.median(ts))
        SPREAD.append((max(ts) - min(ts)) / med)
        out[name] = med
    return out


def _chunked(solver, chunk: int = CHUNK):
    """Solve a batch chunk by chunk (a proposal for ImpactBatch.solve / solve_arrays)."""
    names = [f.name for f in dataclasses.fields(ImpactArrays)]

    def run(S: ImpactStructure, A: ImpactArrays) -> dict:
        n = A.size
        if n <= chunk:
            return solver(S, A)
        parts = []
        for s in range(0, n, chunk):
            sub = ImpactArrays(**{f: getattr(A, f)[s:s + chunk] for f in names})
            parts.append(solver(S, sub))
        return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}

    return run


def _equilibrate_fast(M, b):
    """core._equilibrate with the max-norms by a loop over the K columns/rows (identical result)."""
    K = M.shape[1]
    A = np.abs(M)
    r = A[:, :, 0].copy()
    for j in range(1, K):
        np.maximum(r, A[:, :, j], out=r)
    r[r == 0] = 1.0
    M = M / r[:, :, None]
    b = b / r
    np.abs(M, out=A)
    c = A[:, 0, :].copy()
    for i in range(1, K):
        np.maximum(c, A[:, i, :], out=c)
    c[c == 0] = 1.0
    return M / c[:, None, :], b, c


def _with_fast_equilibration(solver):
    def run(S, A):
        orig = core._equilibrate
        core._equilibrate = _equilibrate_fast
        try:
            return solver(S, A)
        finally:
            core._equilibrate = orig

    return run


# --------------------------------------------------------------------------------------------
# (c) Where the time goes: the stages of core.solve_arrays, timed one by one
# --------------------------------------------------------------------------------------------

def profile_stages(S: ImpactStructure, A: ImpactArrays, repeats: int = 5) -> dict[str, float]:
    """Median seconds of each stage of ``core.solve_arrays`` (its code, step by step).

    The replica's impulses are checked against ``solve_arrays`` so the profile cannot drift
    from the solver unnoticed.
    """
    stages: dict[str, list[float]] = {}

    def tick(name, t0):
        t1 = time.perf_counter()
        stages.setdefault(name, []).append(t1 - t0)
        return t1

    for _ in range(repeats):
        t = time.perf_counter()
        J, minv, p_ext, nvec, tvec = core._assemble(S, A)
        t = tick("assemble J (B,K,n,3) [_assemble]", t)
        B, K, n, _ = J.shape
        q = np.concatenate([A.velocity, A.yaw_rate[..., None]], -1)
        Jf = J.reshape(B, K, 3 * n)
        JM = Jf * minv.reshape(B, 1, 3 * n)
        W = JM @ np.swapaxes(Jf, 1, 2)
        t = tick("W = J Minv J^T (batched matmul)", t)
        u0 = (Jf @ q.reshape(B, 3 * n, 1))[..., 0]
        dq_ext = (minv * p_ext).reshape(B, 3 * n, 1)
        u_free = u0 + (Jf @ dq_ext)[..., 0]
        e, ep = A.restitution, A.moment_restitution
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
        if S.constraint_bodies:
            rhs[:, k0:] = A.constraint_value - u_free[:, k0:]
        t = tick("u = J q, build Mat and rhs (copies)", t)
        Ms, bs, cs = core._equilibrate(Mat, rhs)
        t = tick("equilibrate, 1st system", t)
        lam_ns = np.linalg.solve(Ms, bs[..., None])[..., 0] / cs
        ok = np.all(np.isfinite(lam_ns), axis=1)
        t = tick("np.linalg.solve, 1st system", t)
        mu_max = lam_ns[:, 1] / lam_ns[:, 0]
        lam = lam_ns
        if S.tangential != "no_slide":
            if S.tangential == "ratio":
                mu_used = A.law_value.copy()
                redo = np.ones(B, dtype=bool)
            else:
                redo = ~(np.abs(mu_max) <= A.law_value)
                mu_used = A.law_value * np.sign(mu_max)
            lam = lam_ns.copy()
            idx = np.nonzero(redo)[0]
            Mr = Mat[idx].copy()
            rr = rhs[idx].copy()
            Mr[:, 1, :] = 0.0
            Mr[:, 1, 1] = 1.0
            Mr[:, 1, 0] = -mu_used[idx]
            rr[:, 1] = 0.0
            Ms_ = Ms.copy()
            t = tick("2nd system: gather sliding items, copies", t)
            Ms_r, bs_r, cs_r = core._equilibrate(Mr, rr)
            t = tick("equilibrate, 2nd system", t)
            lam[idx] = np.linalg.solve(Ms_r, bs_r[..., None])[..., 0] / cs_r
            Ms_[idx] = Ms_r
            t = tick("np.linalg.solve, 2nd system", t)
        dq = minv * (p_ext + np.einsum("bkni,bk->bni", J, lam))
        Q = q + dq
        u_after = (Jf @ Q.reshape(B, 3 * n, 1))[..., 0]
        t = tick("final velocities Q = q + Minv J^T lambda", t)
        fixed = np.asarray(S.fixed, dtype=bool)
        m = np.where(fixed, 0.0, A.mass)
        inertia = np.where(fixed, 0.0, A.yaw_inertia)
        ke0 = 0.5 * m * np.sum(A.velocity ** 2, -1) + 0.5 * inertia * A.yaw_rate ** 2
        ke1 = 0.5 * m * np.sum(Q[..., :2] ** 2, -1) + 0.5 * inertia * Q[..., 2] ** 2
        t = tick("kinetic energies, outputs", t)
    ref = solve_arrays(S, A)
    np.testing.assert_allclose(lam, ref["impulses"], rtol=1e-9, atol=1e-9 * np.abs(ref["impulses"]).max())
    del ok, u_after, ke0, ke1
    return {k: float(np.median(v)) for k, v in stages.items()}


# --------------------------------------------------------------------------------------------
# (d) The proposed algorithm for core.solve_arrays
# --------------------------------------------------------------------------------------------

def reduced_solve_arrays(S: ImpactStructure, A: ImpactArrays) -> dict[str, np.ndarray]:
    """The impact equations solved by elimination, batch-last (a proposal; same answers).

    1. Each unknown impulse k acts on at most two bodies: keep its row of J as a few (B,)
       vectors per body (u_x, u_y, r x u), never as a dense (B, K, n, 3) array.
    2. W = J Minv J^T entry by entry from those vectors (only pairs of rows sharing a movable
       body are non-zero), in batch-last (K, K, B) layout: every operation is one numpy call
       on a contiguous (B,) vector.
    3. Eliminate the hitch and constraint impulses: their block W_hh is symmetric positive
       definite (J_h Minv J_h^T with independent rows), so an unpivoted Cholesky factorisation
       is stable and needs no equilibration (it is invariant under diagonal scaling); a zero
       or negative pivot flags a singular item (redundant constraints) as ``ok = False``.
    4. What is left is the 3 x 3 contact system in (P_n, P_t, M) with the contact laws as
       rows (restitution; no-slide or P_t = mu P_n; moment, which is M = 0 for e' = -1),
       solved in closed form (Cramer). The friction law's second solve is the same closed form
       with the ratio row, evaluated for all items and selected with np.where: no gather, no
       second factorisation.
    """
    B, n = A.mass.shape
    fixed = S.fixed
    i1, i2 = S.body1, S.body2
    with np.errstate(divide="ignore"):
        im = [None if fixed[b] else 1.0 / A.mass[:, b] for b in range(n)]
        ii = [None if fixed[b] else 1.0 / A.yaw_inertia[:, b] for b in range(n)]
    pos = [(A.position[:, b, 0], A.position[:, b, 1]) for b in range(n)]

    # rows of J: list over unknowns of {body: (ux, uy, c)}; ux, uy may be python floats
    rows: list[dict] = []
    ca, sa = np.cos(A.normal_angle), np.sin(A.normal_angle)
    ts = A.tangent_sign
    tx, ty = -ts * sa, ts * ca
    r1 = (A.point[:, 0] - pos[i1][0], A.point[:, 1] - pos[i1][1])
    r2 = (A.point[:, 0] - pos[i2][0], A.point[:, 1] - pos[i2][1])
    for ux, uy in ((ca, sa), (tx, ty)):
        rows.append({i1: (ux, uy, r1[0] * uy - r1[1] * ux),
                     i2: (-ux, -uy, -(r2[0] * uy - r2[1] * ux))})
    rows.append({i1: (0.0, 0.0, 1.0), i2: (0.0, 0.0, -1.0)})
    for j, (f, r) in enumerate(S.hitches):
        cf, sf = np.cos(A.heading[:, f]), np.sin(A.heading[:, f])
        cr, sr = np.cos(A.heading[:, r]), np.sin(A.heading[:, r])
        pf, pr = A.hitch_front_point[:, j], A.hitch_rear_point[:, j]
        rfx, rfy = cf * pf[:, 0] - sf * pf[:, 1], sf * pf[:, 0] + cf * pf[:, 1]
        rrx, rry = cr * pr[:, 0] - sr * pr[:, 1], sr * pr[:, 0] + cr * pr[:, 1]
        rows.append({f: (1.0, 0.0, -rfy), r: (-1.0, 0.0, rry)})   # x: cross(r, ex) = -r_y
        rows.append({f: (0.0, 1.0, rfx), r: (0.0, -1.0, -rrx)})   # y: cross(r, ey) = r_x
    for c, b in enumerate(S.constraint_bodies):
        dx, dy = np.cos(A.constraint_direction[:, c]), np.sin(A.constraint_direction[:, c])
        rx, ry = A.constraint_point[:, c, 0] - pos[b][0], A.constraint_point[:, c, 1] - pos[b][1]
        rows.append({b: (dx, dy, rx * dy - ry * dx)})
    K = len(rows)

    def dot(e, v):  # e = (ux, uy, c), v = (vx, vy, w): e . v
        return e[0] * v[0] + e[1] * v[1] + e[2] * v[2]

    # W = J Minv J^T (batch-last), u0 = J q, u_free = J (q + Minv p_ext)
    W = np.zeros((K, K, B))
    for k in range(K):
        for l in range(k, K):
            acc = None
            for b, ek in rows[k].items():
                if fixed[b] or b not in rows[l]:
                    continue
                el = rows[l][b]
                term = im[b] * (ek[0] * el[0] + ek[1] * el[1]) + ii[b] * (ek[2] * el[2])
                acc = term if acc is None else acc + term
            if acc is not None:
                W[k, l] = acc
                if l != k:
                    W[l, k] = acc
    vel = [(A.velocity[:, b, 0], A.velocity[:, b, 1], A.yaw_rate[:, b]) for b in range(n)]
    pext = [[0.0, 0.0, 0.0] for _ in range(n)]
    for x, b in enumerate(S.external_bodies):
        imp = A.external_impulse[:, x]
        rx, ry = A.external_point[:, x, 0] - pos[b][0], A.external_point[:, x, 1] - pos[b][1]
        pext[b] = [pext[b][0] + imp[:, 0], pext[b][1] + imp[:, 1], pext[b][2] + rx * imp[:, 1] - ry * imp[:, 0]]
    vfree = [vel[b] if fixed[b] or not S.external_bodies else
             (vel[b][0] + im[b] * pext[b][0], vel[b][1] + im[b] * pext[b][1], vel[b][2] + ii[b] * pext[b][2])
             for b in range(n)]
    u0 = np.zeros((K, B))
    u_free = np.zeros((K, B))
    for k in range(K):
        for b, e in rows[k].items():
            u0[k] += dot(e, vel[b])
            u_free[k] += dot(e, vfree[b])

    # eliminate hitch / constraint impulses: Cholesky of W_hh, solve for [W_hc | rhs_h]
    m = K - 3
    ok = np.ones(B, dtype=bool)
    rhs_h = -u_free[3:].copy()
    k0 = 2 * len(S.hitches)
    if S.constraint_bodies:
        rhs_h[k0:] = A.constraint_value.T - u_free[3 + k0:]
    if m:
        L = np.zeros((m, m, B))
        for j in range(m):
            d = W[3 + j, 3 + j] - np.sum(L[j, :j] ** 2, axis=0)
            good = d > 1e-12 * W[3 + j, 3 + j]
            ok &= good
            L[j, j] = np.sqrt(np.where(good, d, np.nan))
            for i in range(j + 1, m):
                L[i, j] = (W[3 + i, 3 + j] - np.sum(L[i, :j] * L[j, :j], axis=0)) / L[j, j]
        R = np.concatenate([W[3:, :3], rhs_h[:, None, :]], axis=1)  # (m, 4, B)
        Y = np.empty_like(R)
        for i in range(m):  # forward: L y = R
            Y[i] = (R[i] - np.einsum("pb,pcb->cb", L[i, :i], Y[:i])) / L[i, i]
        for i in reversed(range(m)):  # backward: L^T x = y
            Y[i] = (Y[i] - np.einsum("pb,pcb->cb", L[i + 1:, i], Y[i + 1:])) / L[i, i]
        C = W[:3, :3] - np.einsum("rhb,hcb->rcb", W[:3, 3:], Y[:, :3])
        d3 = np.einsum("rhb,hb->rb", W[:3, 3:], Y[:, 3])
    else:
        C = W[:3, :3]
        d3 = np.zeros((3, B))

    e, ep = A.restitution, A.moment_restitution
    inv_ibar = (0.0 if fixed[i1] else ii[i1]) + (0.0 if fixed[i2] else ii[i2])
    with np.errstate(divide="ignore"):
        ibar = np.where(inv_ibar > 0, 1.0 / inv_ibar, 0.0)
    g = (1.0 + ep) * ibar
    # contact rows: restitution, (tangential law), moment
    a0, b0 = C[0], -e * u0[0] - u_free[0] - d3[0]
    a2 = -g * C[2]
    a2[2] += ep
    b2 = g * (u_free[2] + d3[2])

    def solve3(a1, b1):
        m00, m01, m02 = a0
        m10, m11, m12 = a1
        m20, m21, m22 = a2
        c00 = m11 * m22 - m12 * m21
        c01 = m12 * m20 - m10 * m22
        c02 = m10 * m21 - m11 * m20
        det = m00 * c00 + m01 * c01 + m02 * c02
        x0 = (b0 * c00 + m01 * (m12 * b2 - b1 * m22) + m02 * (b1 * m21 - m11 * b2)) / det
        x1 = (m00 * (b1 * m22 - m12 * b2) + b0 * c01 + m02 * (m10 * b2 - b1 * m20)) / det
        x2 = (m00 * (m11 * b2 - b1 * m21) + m01 * (b1 * m20 - m10 * b2) + b0 * c02) / det
        return np.stack([x0, x1, x2])

    with np.errstate(invalid="ignore", divide="ignore"):
        lam_ns = solve3(C[1], -u_free[1] - d3[1])
        mu_max = lam_ns[1] / lam_ns[0]
        if S.tangential == "no_slide":
            lam_c, sliding = lam_ns, np.zeros(B, dtype=bool)
        else:
            if S.tangential == "ratio":
                mu_used, sliding = A.law_value, np.ones(B, dtype=bool)
            else:
                sliding = ~(np.abs(mu_max) <= A.law_value)
                mu_used = A.law_value * np.sign(mu_max)
            zero = np.zeros(B)
            lam_r = solve3((-mu_used, np.ones(B), zero), zero)
            lam_c = np.where(sliding, lam_r, lam_ns)
    lam_h = (Y[:, 3] - np.einsum("hcb,cb->hb", Y[:, :3], lam_c)) if m else np.zeros((0, B))
    lam = np.concatenate([lam_c, lam_h])  # (K, B)
    ok &= np.all(np.isfinite(lam), axis=0)

    # final velocities
    vout = np.empty((B, n, 2))
    wout = np.empty((B, n))
    for b in range(n):
        vx, vy, w = vfree[b]
        if not fixed[b]:
            px = py = pw = 0.0
            for k in range(K):
                if b in rows[k]:
                    ux, uy, c = rows[k][b]
                    px = px + ux * lam[k]
                    py = py + uy * lam[k]
                    pw = pw + c * lam[k]
            vx, vy, w = vx + im[b] * px, vy + im[b] * py, w + ii[b] * pw
        vout[:, b, 0], vout[:, b, 1], wout[:, b] = vx, vy, w
    Q = [(vout[:, b, 0], vout[:, b, 1], wout[:, b]) for b in range(n)]
    u_after = [sum(dot(e_, Q[b]) for b, e_ in rows[k].items()) for k in (0, 1)]
    if S.tangential == "ratio":
        sliding = np.abs(u_after[1]) > 1e-9 * (1.0 + np.abs(u0[1]))
    fx = np.asarray(fixed)
    mass = np.where(fx, 0.0, A.mass)
    inertia = np.where(fx, 0.0, A.yaw_inertia)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu = lam[1] / lam[0]
    return {
        "velocity": vout, "yaw_rate": wout, "impulses": lam.T, "normal_impulse": lam[0],
        "tangential_impulse": lam[1], "moment_impulse": lam[2], "mu": mu, "mu_max": mu_max,
        "sliding": sliding, "hitch_impulse": lam[3:3 + k0].T.reshape(B, len(S.hitches), 2),
        "constraint_impulse": lam[3 + k0:].T, "closing_velocity": u0[0],
        "separation_normal": u_after[0], "separation_tangential": u_after[1],
        "ke_before": 0.5 * mass * np.sum(A.velocity ** 2, -1) + 0.5 * inertia * A.yaw_rate ** 2,
        "ke_after": 0.5 * mass * np.sum(vout ** 2, -1) + 0.5 * inertia * wout ** 2,
        "ok": ok,
    }


def check_against_reference(solver, law: str, n: int = 20_000) -> float:
    """Largest relative deviation from core.solve_arrays (impulses, velocities, yaw rates)."""
    batch = randomised_batch(law, n, seed=7)
    ref = solve_arrays(batch.structure, batch.arrays)
    got = solver(batch.structure, batch.arrays)
    dev = 0.0
    for key in ("impulses", "velocity", "yaw_rate", "ke_after"):
        scale = np.abs(ref[key]).max()
        dev = max(dev, float(np.max(np.abs(got[key] - ref[key])) / scale))
    assert np.array_equal(got["sliding"], ref["sliding"]), "sliding flags differ"
    return dev


# --------------------------------------------------------------------------------------------
# Report
# --------------------------------------------------------------------------------------------

def machine_info() -> dict:
    cpu = platform.processor() or ""
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return {
        "cpu": cpu or "unknown", "os.cpu_count": os.cpu_count(), "platform": platform.platform(),
        "python": platform.python_version(), "numpy": np.__version__,
        "threads": "OMP/OPENBLAS/MKL_NUM_THREADS=1 (single core)",
        "load_average_at_start": [round(x, 2) for x in os.getloadavg()],
    }


def _fmt_rate(x: float) -> str:
    return f"{x:,.0f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description="Impact solver speed (paper Table 5 impact).")
    ap.add_argument("--out", type=Path, default=ROOT / "plots")
    ap.add_argument("--repeats", type=int, default=9)
    ap.add_argument("--max-size", type=int, default=1_000_000)
    ap.add_argument("--replot", action="store_true", help="redraw the figure and table from impact_speed.json")
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    if args.replot:
        res = json.loads((args.out / "impact_speed.json").read_text())
        # JSON turned the batch sizes into strings
        res["rates"] = {a: {b: {int(n): v for n, v in d.items()} for b, d in x.items()}
                        for a, x in res["rates"].items()}
        res["first_call_rates"] = {b: {int(n): v for n, v in d.items()} for b, d in res["first_call_rates"].items()}
        write_markdown(res, args.out / "impact_speed.md")
        write_plot(res, args.out / "impact_speed.png")
        return 0
    sizes = [s for s in SIZES if s <= args.max_size]
    rep = max(args.repeats, 5)
    res: dict = {"machine": machine_info(), "target": TARGET, "sizes": sizes, "repeats": rep, "chunk": CHUNK}

    res["table5"] = check_table5()
    prob = table5_problem()
    t_single = _median_time(lambda: solve_impact(prob), repeats=max(rep, 15), min_time=0.05)
    b1 = ImpactBatch.from_problem(prob, 1)
    t_batch1 = _median_time(b1.solve, repeats=max(rep, 15), min_time=0.05)
    from crashsim.impact.solve import compile_problem

    S1, A1 = compile_problem(prob)
    t_cond = _median_time(lambda: solve_arrays(S1, A1, condition=True), repeats=max(rep, 15), min_time=0.05)
    t_nocond = _median_time(lambda: solve_arrays(S1, A1), repeats=max(rep, 15), min_time=0.05)
    res["single"] = {"solve_impact_s": t_single, "batch_of_1_s": t_batch1,
                     "solve_arrays_condition_s": t_cond, "solve_arrays_s": t_nocond}
    print(f"solve_impact: {t_single * 1e6:.0f} us; ImpactBatch(1).solve: {t_batch1 * 1e6:.0f} us", flush=True)

    variants = {
        "ImpactBatch.solve (current)": None,
        "chunked": _chunked(solve_arrays),
        "chunked + fast equilibration": _chunked(_with_fast_equilibration(solve_arrays)),
        "reduced (proposed algorithm)": _chunked(reduced_solve_arrays),
    }
    res["accuracy"] = {name: {law: check_against_reference(fn, law) for law in LAWS}
                       for name, fn in variants.items() if fn is not None}
    print("max relative deviation from solve_arrays:", json.dumps(res["accuracy"]), flush=True)

    rates: dict = {}
    first: dict = {}
    sliding_frac = {law: float(np.mean(randomised_batch(law, 10_000).solve()["sliding"])) for law in LAWS}
    for law in LAWS:
        for n in sizes:
            batch = randomised_batch(law, n)
            S, A = batch.structure, batch.arrays
            calls = {name: (batch.solve if fn is None else (lambda fn=fn, S=S, A=A: fn(S, A)))
                     for name, fn in variants.items()}
            # interleaved: every round times each variant once, so load changes hit all alike
            times = _interleaved_times(calls, repeats=rep, min_time=0.05 if n < 100_000 else 0.0)
            first.setdefault(law, {})[n] = n / FIRST["ImpactBatch.solve (current)"]
            for name, t in times.items():
                rates.setdefault(name, {}).setdefault(law, {})[n] = n / t
                print(f"{law:9s} n={n:>9,d} {name:32s} {n / t:>12,.0f} solves/s", flush=True)
            del batch, S, A, calls
    res["rates"] = rates
    res["first_call_rates"] = first
    res["sliding_fraction"] = sliding_frac

    big = min(100_000, sizes[-1])
    prof = {}
    for law in ("no_slide", "friction"):
        batch = randomised_batch(law, big)
        prof[law] = profile_stages(batch.structure, batch.arrays, repeats=rep)
    res["profile"] = {"n": big, "stages": prof}
    res["timing_spread"] = {"median": float(np.median(SPREAD)), "max": float(np.max(SPREAD))}
    res["machine"]["load_average_at_end"] = [round(x, 2) for x in os.getloadavg()]

    (args.out / "impact_speed.json").write_text(json.dumps(res, indent=1, default=str))
    write_markdown(res, args.out / "impact_speed.md")
    write_plot(res, args.out / "impact_speed.png")
    print((args.out / "impact_speed.md").read_text())
    return 0


def write_markdown(res: dict, path: Path) -> None:
    rates, sizes = res["rates"], res["sizes"]
    cur = rates["ImpactBatch.solve (current)"]
    mi = res["machine"]
    lines = [
        "# Impact solver speed",
        "",
        "Generated by `PYTHONPATH=src python benchmarks/impact_speed.py`: one run, medians of "
        f"{res['repeats']} repeats (batches < 1e5 repeated within each timed run to last >= 50 ms).",
        "Impact: paper Table 5 (loaded tractor-semitrailer into the trailer wheels of an empty one),",
        "7 unknowns (P_n, P_t, M, two hitch impulses of 2 components).",
        "",
        f"Machine: {mi['cpu']}; os.cpu_count() = {mi['os.cpu_count']}; {mi['platform']}; "
        f"Python {mi['python']}; numpy {mi['numpy']}; {mi['threads']}. Load average (1, 5, 15 min) "
        f"at start {mi['load_average_at_start']}, at end {mi.get('load_average_at_end')} (2 cores: other "
        "processes on the machine add noise). Spread of the repeats, (max - min) / median: median "
        f"{res['timing_spread']['median']:.0%}, worst {res['timing_spread']['max']:.0%}.",
        "",
        "Table 5 check (paper, computed): " + "; ".join(f"{k} {p} / {g:.4g}" for k, (p, g) in res["table5"].items()),
        "",
        "## Single solve (public API)",
        "",
        "| call | median latency |",
        "|---|---|",
        f"| `solve_impact(problem)` (assembly, solve, condition number (SVD), ImpactResult) | "
        f"{res['single']['solve_impact_s'] * 1e6:.0f} us |",
        f"| `ImpactBatch.from_problem(problem, 1).solve()` (reused batch) | {res['single']['batch_of_1_s'] * 1e6:.0f} us |",
        f"| `core.solve_arrays`, batch of 1, `condition=True` (as `solve_impact` calls it) | "
        f"{res['single']['solve_arrays_condition_s'] * 1e6:.0f} us |",
        f"| `core.solve_arrays`, batch of 1, no condition number | {res['single']['solve_arrays_s'] * 1e6:.0f} us |",
        "",
        "## Batch throughput, `ImpactBatch.solve` (current) [impacts solved per second, one core]",
        "",
        f"Target: {_fmt_rate(res['target'])} solves/s. Sliding fraction under the friction law: "
        f"{res['sliding_fraction'].get('friction', float('nan')):.2f} (those items need a second solve); "
        "the ratio law always solves twice.",
        "",
        "| batch size | " + " | ".join(LAWS) + " |",
        "|---|" + "---|" * len(LAWS),
    ]
    for n in sizes:
        lines.append(f"| {n:,d} | " + " | ".join(_fmt_rate(cur[law][n]) for law in LAWS) + " |")
    fc = res["first_call_rates"]
    lines += [
        "",
        "First call on a freshly built batch (the warm-up, one sample; includes the page faults of the "
        "fresh temporaries) [solves/s]:",
        "",
        "| batch size | " + " | ".join(LAWS) + " |",
        "|---|" + "---|" * len(LAWS),
    ]
    for n in sizes:
        lines.append(f"| {n:,d} | " + " | ".join(_fmt_rate(fc[law][n]) for law in LAWS) + " |")
    lines += [
        "",
        "## Proposed changes, prototyped in this file (core.py untouched) [solves/s]",
        "",
        "Max relative deviation from `core.solve_arrays` (impulses, velocities, yaw rates, energies; "
        "20,000 random items per law): " + "; ".join(
            f"{name}: {max(v.values()):.1e}" for name, v in res["accuracy"].items()) + ".",
        "",
        "| variant | law | " + " | ".join(f"{n:,d}" for n in sizes) + " |",
        "|---|---|" + "---|" * len(sizes),
    ]
    for name, by_law in rates.items():
        for law in LAWS:
            lines.append(f"| {name} | {law} | " + " | ".join(_fmt_rate(by_law[law][n]) for n in sizes) + " |")
    n = res["profile"]["n"]
    lines += [
        "",
        f"## Where the time goes: stages of `core.solve_arrays`, {n:,d} items (median seconds)",
        "",
        "| stage | no_slide [ms] | share | friction [ms] | share |",
        "|---|---|---|---|---|",
    ]
    p_ns, p_fr = res["profile"]["stages"]["no_slide"], res["profile"]["stages"]["friction"]
    tot_ns, tot_fr = sum(p_ns.values()), sum(p_fr.values())
    for stage in p_fr:
        a = p_ns.get(stage)
        lines.append(
            f"| {stage} | " + (f"{a * 1e3:.1f} | {a / tot_ns:.0%}" if a is not None else "- | -")
            + f" | {p_fr[stage] * 1e3:.1f} | {p_fr[stage] / tot_fr:.0%} |")
    lines.append(f"| **total** | {tot_ns * 1e3:.1f} | | {tot_fr * 1e3:.1f} | |")
    lines += ["", *findings(res)]
    path.write_text("\n".join(lines) + "\n")


def findings(res: dict) -> list[str]:
    """The verdict and the proposal, with this run's numbers."""
    rates, sizes = res["rates"], res["sizes"]
    cur = rates["ImpactBatch.solve (current)"]
    red = rates["reduced (proposed algorithm)"]
    chk = rates["chunked"]
    feq = rates["chunked + fast equilibration"]
    below = [f"{law} at {n:,d} ({cur[law][n]:,.0f}/s)" for law in LAWS for n in sizes if cur[law][n] < res["target"]]
    above = [n for n in sizes if all(cur[law][n] >= res["target"] for law in LAWS)]
    sng = res["single"]
    p = res["profile"]["stages"]
    share = {law: {k: v / sum(p[law].values()) for k, v in p[law].items()} for law in p}
    eq_ns = share["no_slide"]["equilibrate, 1st system"]
    eq_fr = share["friction"]["equilibrate, 1st system"] + share["friction"]["equilibrate, 2nd system"]
    sv_fr = share["friction"]["np.linalg.solve, 1st system"] + share["friction"]["np.linalg.solve, 2nd system"]
    big = [n for n in sizes if n >= 10_000]

    def gain(v, law):
        return ", ".join(f"{v[law][n] / cur[law][n]:.1f}x" for n in big)

    return [
        "## Verdict",
        "",
        f"* Target {res['target']:,.0f} solves/s on one core (median of the steady-state repeats): met by the "
        "current `ImpactBatch.solve` for every law at batch sizes "
        + (", ".join(f"{n:,d}" for n in above) or "none") + "; below target: "
        + ("; ".join(below) or "nowhere") + ". The first call on a fresh large batch is slower still (table "
        "above). Small batches are bound by the fixed cost per call "
        f"({sng['batch_of_1_s'] * 1e3:.2f} ms for a batch of one), the largest by memory traffic (dense "
        "temporaries of 0.4-0.7 GB at 1e6 items).",
        f"* Where the time goes ({res['profile']['n']:,d} items): equilibration {eq_ns:.0%} of a no_slide solve "
        f"and {eq_fr:.0%} of a friction solve (`np.max(np.abs(M), axis=1 or 2)` reduces over a 7-long axis, "
        "numpy's slow path); the batched LU (`np.linalg.solve` on (B, 7, 7)) "
        f"{share['no_slide']['np.linalg.solve, 1st system']:.0%} / {sv_fr:.0%}; the dense Jacobian "
        "(B, K, n, 3) = 84 doubles per item (at most 6 per row non-zero), its batched matmul "
        "W = J Minv J^T and the copies of the 7 x 7 systems (Mat, Ms, the gathered second system) most of "
        "the rest. Above ~1e4 items every temporary is a fresh mmap of tens to hundreds of MB: the first "
        "call on a new batch pays its page faults too.",
        "",
        "## Proposal for `core.solve_arrays` (prototyped in this file, not applied)",
        "",
        "1. Solve in chunks of ~2,000 items (a loop in `solve_arrays` or `ImpactBatch.solve`): identical "
        f"numbers, temporaries stay in cache. Gain at {', '.join(f'{n:,d}' for n in big)} items: "
        f"no_slide {gain(chk, 'no_slide')}; friction {gain(chk, 'friction')}.",
        "2. `_equilibrate`: max-norms by a loop of `np.maximum` over the K columns (rows) instead of "
        "`np.max(..., axis=)`: identical numbers. With 1.: no_slide "
        f"{gain(feq, 'no_slide')}; friction {gain(feq, 'friction')}.",
        "3. Replace the dense 7 x 7 solve by elimination (`reduced_solve_arrays`): rows of J kept as a few "
        "(B,) vectors per body, W built entry by entry in batch-last layout; the hitch/constraint block of "
        "W is SPD, so an unpivoted Cholesky eliminates those impulses without equilibration (diagonal "
        "scaling does not change Cholesky's accuracy; a non-positive pivot flags a singular item); the "
        "remaining 3 x 3 contact system (restitution, tangential law, moment) is solved in closed form, "
        "and the friction law's sliding branch is the same closed form with the ratio row, evaluated for "
        "all items and picked by `np.where` (no gather, no second factorisation). Agrees with "
        f"`solve_arrays` to {max(res['accuracy']['reduced (proposed algorithm)'].values()):.0e} relative, same "
        f"sliding flags. Gain: no_slide {gain(red, 'no_slide')}; friction {gain(red, 'friction')}; "
        f"ratio {gain(red, 'ratio')}. Below ~1,000 items its ~1,000 small numpy calls cost more than the "
        "current path: keep the current path for small batches and for `condition=True` (the SVD "
        "condition number and the dependent-equation diagnosis of `solve_impact`).",
        f"4. `solve_impact` (single solve, {sng['solve_impact_s'] * 1e6:.0f} us): the condition number (an SVD "
        f"per item) costs {(sng['solve_arrays_condition_s'] - sng['solve_arrays_s']) * 1e6:.0f} us of it, "
        f"`solve_arrays` itself {sng['solve_arrays_s'] * 1e6:.0f} us (fixed numpy call overhead of a batch of "
        "one: a few hundred small numpy calls), the rest is `compile_problem` and building the "
        "ImpactResult. Not a throughput issue; nothing there worth changing for speed.",
    ]


def write_plot(res: dict, path: Path) -> None:
    # A benchmark script, not a crashsim module: it may import matplotlib itself (Agg, no screen).
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a1, a2) = plt.subplots(1, 2, figsize=(12.0, 5.0), sharey=True, layout="constrained")
    markers = {"no_slide": "o", "friction": "s", "ratio": "^"}
    cur = res["rates"]["ImpactBatch.solve (current)"]
    for k, law in enumerate(LAWS):
        ns = sorted(cur[law], key=int)
        a1.plot([int(n) for n in ns], [cur[law][n] for n in ns], "-", marker=markers[law], color=f"C{k}", lw=2,
                label=law)
    a1.set_title("ImpactBatch.solve (current), by tangential law", fontsize=10)
    styles = {"ImpactBatch.solve (current)": ("-", 2.0), "chunked": (":", 1.5),
              "chunked + fast equilibration": ("-.", 1.5), "reduced (proposed algorithm)": ("--", 2.0)}
    for k, (name, by_law) in enumerate(res["rates"].items()):
        ns = sorted(by_law["friction"], key=int)
        ls, lw = styles.get(name, ("-", 1.5))
        a2.plot([int(n) for n in ns], [by_law["friction"][n] for n in ns], ls, marker="s", color=f"C{k + 3}", lw=lw,
                label=name)
    a2.set_title("friction law (about 40 % of items slide): current vs prototypes", fontsize=10)
    for ax in (a1, a2):
        ax.axhline(res["target"], color="k", lw=1.0, ls="--", label=f"target {res['target']:,.0f}/s")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("batch size [impacts]")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8, loc="upper left", ncol=2)
    a1.set_ylim(3e4, 4e6)
    a1.set_ylabel("throughput [impacts solved / s], one core")
    fig.suptitle("Batch impact solve, paper Table 5 impact, randomised inputs (medians; shared 2-core machine)",
                 fontsize=11)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    raise SystemExit(main())

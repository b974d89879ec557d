"""Property: the compiled batch solver gives the dense solver's answers.

``core.solve_arrays(method="compiled")`` (the default without ``condition=True``) solves by the
numba kernel of ``crashsim.impact.kernel`` (the dense algorithm item by item);
``condition=True`` goes through ``_solve_chunk`` (equilibrated K x K inverses). Both must return
the same dict: keys, shapes, dtypes, the ``ok`` rule (finite and 1-norm condition of the
equilibrated system < COND_LIMIT), NaN for not-ok items, mu_max NaN where the no-slide system
is not ok, the friction fallback (slide against the initial slip), the ratio law independent
of the no-slide system, and the same numbers.

Scenes: the shared strategies of ``impact_scenes`` (articulated vehicles, barriers with inverse
mass 0, constraints, external impulses), 1-3 scenes of one structure, replicated to 6-30
items with random perturbations of every number, and deliberately singular items:
conflicting / redundant / nearly parallel constraints on one body, and constraints that fix
the contact point's tangential velocity (no-slide system singular, ratio system regular).
Each batch is solved under all three tangential laws; the friction coefficients include
f = |mu_max| exactly (the threshold) and f = 0, the ratio-law mu includes mu = mu_max.

Tolerance
---------
Two backward-stable solves of the same system agree to about ``cond * eps`` relative, not
better, whatever the algorithms (cond = 1e10 gives ~1e-7). Measured over 2 x 1000 examples of
this file (91,000 items): deviation <= 0.85 K eps cond, and <= 1.6e-13 for every item with
cond < 1e3 (the median item has cond ~300; 9 % exceed 7e3, most of them made near-singular on
purpose). So an item agrees to

    tol = RTOL + CTOL * K * eps * cond            (RTOL = 1e-10, CTOL = 8, K unknowns)

relative to its scale, ``cond`` being the dense path's ``condition_1norm`` of the returned
system: 1e-10 for cond <~ 7e3 (K = 7), more only for the ill-conditioned items this file
generates on purpose. Scales per item: the largest linear impulse P; the moment scale
|M| + L P (L the longest lever arm); the velocity scale of ``impact_scenes.velocity_scale``
(speeds before/after plus the gross velocity change of all impulses taken one at a time);
for energies m v_scale^2. Flags (``ok``, ``sliding``) and NaN patterns must be identical,
except items whose decision lies within the tolerance of its threshold, handled explicitly:
  * friction, |mu_max| within max(1e-9, tol) of f (or of MU_MAX_LIMIT): either branch is a
    correct answer; the large-batch path's answer must be the dense path's answer of the
    branch that its own mu_max decides (stick: the no-slide solve; slide: the ratio solve with
    mu = f sign(mu_max), or -f sign(u_t) past MU_MAX_LIMIT);
  * ratio law, |separation_tangential| within tol of its sliding threshold: flag not compared;
  * condition_1norm within 2 % of COND_LIMIT (either system): ``ok`` not compared (the two
    estimates of cond differ by ~cond eps = 2e-4 there). Counted; none occurred in development.
"""

from __future__ import annotations

import math
from dataclasses import fields, replace

import numpy as np
import pytest
from hypothesis import given, note, settings
from hypothesis.errors import InvalidArgument
from hypothesis import strategies as st

from impact_scenes import EXAMPLES, KINDS, SETTINGS, scenes, structures

from crashsim import (Body, BodyState, CrushSurface, ImpactBatch, ImpactProblem, TangentialLaw, Vehicle,
                      VelocityConstraint)
from crashsim.impact import compile_problem, core
from crashsim.impact.core import CHUNK, COND_LIMIT, MU_MAX_LIMIT

EPS = float(np.finfo(float).eps)
RTOL = 1e-10
CTOL = 8.0
LAWS = ("no_slide", "ratio", "friction")
SOLVE_KEYS = ("velocity", "yaw_rate", "impulses", "normal_impulse", "tangential_impulse", "moment_impulse", "mu",
              "mu_max", "sliding", "hitch_impulse", "lock_impulse", "constraint_impulse", "closing_velocity", "separation_normal",
              "separation_tangential", "ke_before", "ke_after", "normal", "tangent", "ok", "condition_1norm",
              "approach_tangential", "no_slide_normal")


# ------------------------------------------------------------------------------------ batches

@st.composite
def batches(draw, barrier=None):
    """(ImpactStructure, ImpactArrays) of 6-30 perturbed copies of 1-3 scenes, some singular."""
    mode = draw(st.sampled_from(["random", "conflict", "tangent_lock"]))
    S = draw(structures(laws=("no_slide",), barrier=barrier))
    if mode == "conflict":
        j = draw(st.integers(0, 7))
        S = replace(S, constraint_bodies=(j, j))
    elif mode == "tangent_lock":
        cb = (S.body1,) if S.kind2 is None else (S.body1, KINDS[S.kind1] + S.body2)
        S = replace(S, constraint_bodies=cb)
    family = [draw(scenes(S, solve=False)) for _ in range(draw(st.integers(1, 3)))]
    structure, arrays = compile_problem(family[0].problem)
    base = [compile_problem(s.problem)[1] for s in family]
    n = draw(st.integers(6, 30))
    A = replace(arrays, **{f.name: np.concatenate([getattr(base[i % len(base)], f.name) for i in range(n)])
                           for f in fields(arrays)})
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    _perturb(structure, A, rng)
    _make_singular(structure, A, rng, mode)
    note(f"mode={mode}, n={n}")
    return structure, A


def _perturb(S, A, rng):
    """Every number of every item but the first, within the scenes' ranges. (Headings move
    without the CGs, so hitched bodies' pins need not meet: both paths solve the same
    equations for any numbers, which is all this file is about.)"""
    B, nb = A.mass.shape
    p = slice(1, None)
    u = lambda lo, hi, shape=(): rng.uniform(lo, hi, (B - 1,) + shape)  # noqa: E731
    A.mass[p] *= u(0.5, 2.0, (nb,))
    A.yaw_inertia[p] *= u(0.5, 2.0, (nb,))
    A.velocity[p] *= u(0.5, 1.5, (nb, 1))
    A.velocity[p] += u(-1.0, 1.0, (nb, 2))
    A.yaw_rate[p] += u(-0.5, 0.5, (nb,))
    A.heading[p] += u(-0.2, 0.2, (nb,))
    A.hitch_front_point[p] += u(-0.2, 0.2, A.hitch_front_point.shape[1:])
    A.hitch_rear_point[p] += u(-0.2, 0.2, A.hitch_rear_point.shape[1:])
    A.point[p] += u(-0.5, 0.5, (2,))
    A.normal_angle[p] += u(-0.3, 0.3)
    A.tangent_sign[p] = rng.choice([-1.0, 1.0], B - 1)
    A.restitution[p] = u(0.0, 1.0)
    A.moment_restitution[p] = np.where(rng.random(B - 1) < 0.5, -1.0, u(0.0, 1.0))
    A.constraint_point[p] += u(-1.0, 1.0, A.constraint_point.shape[1:])
    A.constraint_direction[p] += u(-0.5, 0.5, A.constraint_direction.shape[1:])
    A.constraint_value[p] += u(-1.0, 1.0, A.constraint_value.shape[1:])
    A.external_impulse[p] *= u(0.0, 2.0, A.external_impulse.shape[1:])


def _make_singular(S, A, rng, mode):
    """About half the items of a 'conflict' or 'tangent_lock' batch made (nearly) singular."""
    B = A.size
    pick = np.nonzero(rng.random(B) < 0.5)[0]
    if mode == "conflict" and len(S.constraint_bodies) == 2 and S.constraint_bodies[0] == S.constraint_bodies[1]:
        for i in pick:
            A.constraint_point[i, 1] = A.constraint_point[i, 0]
            # the same line of action (turned by 0 or pi) or nearly (turned by 1e-12..1e-2 rad),
            # with the consistent value (redundant) or another one (conflicting)
            turn = rng.choice([0.0, math.pi, 10.0 ** rng.uniform(-12, -2)])
            A.constraint_direction[i, 1] = A.constraint_direction[i, 0] + turn
            consistent = (-1.0 if turn == math.pi else 1.0) * A.constraint_value[i, 0]
            A.constraint_value[i, 1] = consistent if rng.random() < 0.5 else rng.uniform(-3.0, 3.0)
    elif mode == "tangent_lock":
        for i in pick:
            t = A.normal_angle[i] + A.tangent_sign[i] * math.pi / 2
            for c in range(len(S.constraint_bodies)):
                A.constraint_point[i, c] = A.point[i]
                A.constraint_direction[i, c] = t


def _with_law(S, A, law, rng, ns):
    """The structure under ``law`` and its law values (thresholds included)."""
    A = A.copy()
    B = A.size
    mu_max = ns["mu_max"]
    if law == "ratio":
        A.law_value[:] = rng.uniform(-1.5, 1.5, B)
        at = np.isfinite(mu_max) & (rng.random(B) < 0.5)
        A.law_value[at] = mu_max[at] * np.where(rng.random(B) < 0.5, 1.0, rng.random(B))[at]
    elif law == "friction":
        A.law_value[:] = rng.uniform(0.0, 1.5, B)
        A.law_value[rng.random(B) < 0.1] = 0.0
        at = np.isfinite(mu_max) & (rng.random(B) < 0.25)
        A.law_value[at] = np.abs(mu_max[at])  # exactly on the threshold |mu_max| = f
    else:
        A.law_value[:] = 0.0
    return replace(S, tangential=law), A


def _note(msg):
    """hypothesis' note() inside a hypothesis test, nothing elsewhere."""
    try:
        note(msg)
    except InvalidArgument:
        pass


# ------------------------------------------------------------------------------------ scales

def _lever(S, A):
    """(B,) the longest lever arm of any impulse about its body's CG, at least 1 m."""
    pos = A.position
    arms = [np.ones(A.size)]
    for b in (S.body1, S.body2):
        arms.append(np.hypot(*(A.point - pos[:, b]).T))
    arms += [np.hypot(*A.hitch_front_point[:, j].T) for j in range(len(S.hitches))]
    arms += [np.hypot(*A.hitch_rear_point[:, j].T) for j in range(len(S.hitches))]
    arms += [np.hypot(*(A.constraint_point[:, c] - pos[:, b]).T) for c, b in enumerate(S.constraint_bodies)]
    arms += [np.hypot(*(A.external_point[:, x] - pos[:, b]).T) for x, b in enumerate(S.external_bodies)]
    return np.max(arms, axis=0)


def _scales(S, A, out):
    """Per item: linear impulse P, moment M, velocity v scales (see the module docstring)."""
    K = S.n_unknowns
    L = _lever(S, A)
    lam = np.nan_to_num(out["impulses"])
    lin = np.abs(np.delete(lam, 2, axis=1)).max(axis=1)
    ext = np.abs(A.external_impulse).sum(axis=(1, 2)) if S.external_bodies else 0.0
    P = np.maximum(lin, 1e-300)
    M = np.abs(lam[:, 2]) + L * P
    fixed = np.asarray(S.fixed)
    with np.errstate(divide="ignore"):
        im = np.where(fixed, 0.0, 1.0 / A.mass).max(axis=1)
        ii = np.where(fixed, 0.0, 1.0 / A.yaw_inertia).max(axis=1)
    speed = lambda v, w: np.hypot(v[..., 0], v[..., 1]) + L[:, None] * np.abs(w)  # noqa: E731
    V = np.nan_to_num(out["velocity"])
    W = np.nan_to_num(out["yaw_rate"])
    v = (speed(A.velocity, A.yaw_rate) + speed(V, W)).max(axis=1)
    v = v + im * (K * P + ext) + ii * L * (K * L * P + M + L * ext)
    return P, M, v, L


# ------------------------------------------------------------------------------------ comparison

def _tol(K, cond):
    return RTOL + CTOL * K * EPS * np.where(np.isfinite(cond), cond, 0.0)


def _near_limit(c):
    return np.abs(np.log(np.maximum(c, 1.0) / COND_LIMIT)) < 0.02


def _assert_items_agree(S, A, ref, got, idx, tol, what):
    """Every number of items ``idx`` of ``got`` within the tolerance of ``ref``."""
    if len(idx) == 0:
        return
    P, M, v, L = _scales(S, A, ref)
    t = tol[idx]
    P, M, v, L = P[idx], M[idx], v[idx], L[idx]

    def close(key, scale, sub=None):
        a, b = ref[key][idx], got[key][idx]
        if sub is not None:
            a, b = a[:, sub], b[:, sub]
        s = (t * scale).reshape((-1,) + (1,) * (a.ndim - 1))
        bad = ~(np.abs(a - b) <= s)
        assert not bad.any(), (f"{what}: {key} differs", np.nonzero(bad), a[bad], b[bad])

    close("normal_impulse", P)
    close("tangential_impulse", P)
    close("moment_impulse", M)
    close("impulses", P, sub=[k for k in range(S.n_unknowns) if k != 2])
    close("impulses", M, sub=[2])
    close("hitch_impulse", P)
    close("constraint_impulse", P)
    close("velocity", v)
    close("yaw_rate", v / L)
    close("separation_normal", v)
    close("separation_tangential", v)
    fixed = np.asarray(S.fixed)
    m = np.where(fixed, 0.0, A.mass[idx])
    inertia = np.where(fixed, 0.0, A.yaw_inertia[idx])
    e_tol = t[:, None] * (m * v[:, None] ** 2 + inertia * (v / L)[:, None] ** 2)
    bad = ~(np.abs(ref["ke_after"][idx] - got["ke_after"][idx]) <= e_tol)
    assert not bad.any(), (f"{what}: ke_after differs", np.nonzero(bad))
    pn = np.abs(ref["normal_impulse"][idx])
    sel = pn > t * P  # mu = P_t / P_n means something
    mu_a, mu_b = ref["mu"][idx][sel], got["mu"][idx][sel]
    assert np.all(np.abs(mu_a - mu_b) <= 2 * t[sel] * P[sel] * (1 + np.abs(mu_a)) / pn[sel]), f"{what}: mu"
    c_a, c_b = ref["condition_1norm"][idx], got["condition_1norm"][idx]
    fin = np.isfinite(c_a)
    assert np.all(np.abs(c_a[fin] - c_b[fin]) <= t[fin] * c_a[fin]), (f"{what}: condition_1norm", c_a, c_b)


def check_agreement(S, A, dense, got, ns):
    """dense, got: solve_arrays(method='dense' / 'compiled') of (S, A); ns: the dense no-slide solve."""
    K = S.n_unknowns
    B = A.size
    assert set(dense) == set(got) == set(SOLVE_KEYS)
    for k in SOLVE_KEYS:
        assert got[k].shape == dense[k].shape and got[k].dtype == dense[k].dtype, k
    np.testing.assert_array_equal(got["ke_before"], dense["ke_before"])
    np.testing.assert_array_equal(got["normal"], dense["normal"])
    np.testing.assert_array_equal(got["tangent"], dense["tangent"])
    _, _, v, _ = _scales(S, A, dense)
    assert np.all(np.abs(got["closing_velocity"] - dense["closing_velocity"]) <= 1e-13 * v)

    tol = _tol(K, dense["condition_1norm"])
    tol_ns = _tol(K, ns["condition_1norm"])
    border_ok = _near_limit(dense["condition_1norm"]) | _near_limit(got["condition_1norm"]) | _near_limit(
        ns["condition_1norm"])
    border = border_ok.copy()
    mu_max = ns["mu_max"]
    band = np.maximum(1e-9, tol_ns) * (1.0 + np.abs(mu_max))
    if S.tangential == "friction":
        border |= (np.abs(np.abs(mu_max) - A.law_value) <= band) | (np.abs(np.abs(mu_max) - MU_MAX_LIMIT) <= band)
        # the sign of the no-slide normal impulse decides whether sliding can stop at all
        P_ns, _, _, _ = _scales(S, A, ns)
        border |= np.abs(ns["normal_impulse"]) <= np.maximum(1e-9, tol_ns) * P_ns
    _note(f"{S.tangential}: {int(border.sum())} of {B} items at a threshold, {int(border_ok.sum())} at COND_LIMIT")

    # flags, NaN patterns: identical away from the thresholds
    plain = np.nonzero(~border)[0]
    np.testing.assert_array_equal(got["ok"][plain], dense["ok"][plain])
    ok = dense["ok"] & got["ok"]
    if S.tangential == "ratio":
        _, _, vv, _ = _scales(S, A, dense)
        thr = 1e-9 * (1.0 + np.abs(_u0_t(S, A)))
        near = np.abs(np.abs(dense["separation_tangential"]) - thr) <= tol * vv
        flag = np.nonzero(~border & ~near)[0]
    else:
        flag = plain
    np.testing.assert_array_equal(got["sliding"][flag], dense["sliding"][flag])
    for k in ("velocity", "yaw_rate", "impulses", "mu", "separation_normal", "separation_tangential", "ke_after"):
        bad = ~dense["ok"][plain]
        assert np.all(np.isnan(got[k][plain][bad])) and np.all(np.isnan(dense[k][plain][bad])), k
    assert np.all(got["condition_1norm"][plain][~dense["ok"][plain]] >= COND_LIMIT)
    ns_plain = np.nonzero(~border_ok)[0]
    np.testing.assert_array_equal(np.isnan(got["mu_max"][ns_plain]), np.isnan(ns["mu_max"][ns_plain]))

    # mu_max, from the no-slide solve, to that solve's tolerance
    fin = np.nonzero(np.isfinite(mu_max) & np.isfinite(got["mu_max"]))[0]
    if len(fin):
        P_ns, _, _, _ = _scales(S, A, ns)
        pn = np.abs(ns["normal_impulse"][fin])
        sel = pn > tol_ns[fin] * P_ns[fin]
        a, b = mu_max[fin][sel], got["mu_max"][fin][sel]
        assert np.all(np.abs(a - b) <= 2 * tol_ns[fin][sel] * P_ns[fin][sel] * (1 + np.abs(a)) / pn[sel]), "mu_max"

    # the numbers, item by item
    same = np.nonzero(ok & ~border)[0]
    _assert_items_agree(S, A, dense, got, same, tol, "plain items")
    # friction items at a threshold: the large-batch path's answer must be the dense path's
    # answer of the branch that its own mu_max decides (Eq. 8 and the fallback)
    if S.tangential == "friction":
        edge = np.nonzero(border & ~border_ok & ok)[0]
        if len(edge):
            f = A.law_value
            mu_r = got["mu_max"]
            stop_r = np.isfinite(mu_r) & (np.abs(mu_r) <= MU_MAX_LIMIT) & (got["no_slide_normal"] > 0)
            stick_r = stop_r & (np.abs(mu_r) <= f)
            np.testing.assert_array_equal(got["sliding"][edge], ~stick_r[edge])
            _note(f"{int(np.sum(got['sliding'][edge] != dense['sliding'][edge]))} friction items took the other branch")
            Sr, Ar = replace(S, tangential="ratio"), A.copy()
            Ar.law_value[:] = f * np.where(stop_r, np.sign(np.nan_to_num(mu_r)), -np.sign(_u0_t(S, A)))
            slide = core.solve_arrays(Sr, Ar, method="dense")
            keys = [k for k in SOLVE_KEYS if k not in ("sliding", "mu_max")]
            for i in edge:
                branch = ns if stick_r[i] else slide
                _assert_items_agree(S, A, {k: branch[k] for k in keys}, {k: got[k] for k in keys}, np.array([i]),
                                    _tol(K, branch["condition_1norm"]), "threshold item, own branch")


def _u0_t(S, A):
    """Initial relative tangential velocity of the contact point (dense path's u0[:, 1])."""
    S_ns = replace(S, tangential="no_slide")
    J, minv, p_ext, nvec, tvec = core._assemble(S_ns, A)
    B, K, n, _ = J.shape
    q = np.concatenate([A.velocity, A.yaw_rate[..., None]], -1)
    return (J.reshape(B, K, 3 * n) @ q.reshape(B, 3 * n, 1))[:, 1, 0]


def _solve_all_laws(S, A, seed):
    rng = np.random.default_rng(seed)
    S_ns = replace(S, tangential="no_slide")
    ns = core.solve_arrays(S_ns, A, method="dense")
    for law in LAWS:
        S_l, A_l = _with_law(S, A, law, rng, ns)
        dense = core.solve_arrays(S_l, A_l, method="dense")
        # the compiled kernel (crashsim.impact.kernel): the dense path's algorithm item by
        # item, so the same tolerances and threshold rules
        comp = core.solve_arrays(S_l, A_l, method="compiled")
        check_agreement(S_l, A_l, dense, comp, ns)
        yield S_l, A_l, dense, comp


# ------------------------------------------------------------------------------------ tests

@SETTINGS
@given(batches(), st.integers(0, 2**32 - 1))
def test_compiled_path_agrees_with_dense_path(batch, seed):
    S, A = batch
    for _ in _solve_all_laws(S, A, seed):
        pass


@SETTINGS
@given(batches(barrier=True), st.integers(0, 2**32 - 1))
def test_compiled_path_agrees_against_barriers(batch, seed):
    """Vehicle 2 a rigid barrier (inverse mass and inertia 0), with the same singular cases."""
    S, A = batch
    assert any(S.fixed)
    for _ in _solve_all_laws(S, A, seed):
        pass


@settings(max_examples=max(10, EXAMPLES // 4), deadline=None)  # the dispatch, not the numbers
@given(batches(), st.integers(0, 2**32 - 1))
def test_batches_take_the_compiled_path(batch, seed):
    """solve_arrays / ImpactBatch.solve without a condition number give the compiled kernel's
    numbers exactly, at any size (items are independent: repeating them changes nothing);
    condition=True keeps the dense path."""
    S, A = batch
    for S_l, A_l, dense, comp in _solve_all_laws(S, A, seed):
        reps = -(-(CHUNK + 37) // A.size)  # more than one chunk of the dense path
        big = replace(A_l, **{f.name: np.concatenate([getattr(A_l, f.name)] * reps) for f in fields(A_l)})
        out = ImpactBatch(S_l, big).solve()
        for k in SOLVE_KEYS:
            np.testing.assert_array_equal(out[k], np.concatenate([comp[k]] * reps), err_msg=k)
        small = core.solve_arrays(S_l, A_l)
        for k in SOLVE_KEYS:
            np.testing.assert_array_equal(small[k], comp[k], err_msg=k)
        # condition=True: the dense path, whatever the size
        dc = core.solve_arrays(S_l, big, condition=True)
        np.testing.assert_array_equal(dc["ok"], np.concatenate([dense["ok"]] * reps))
        np.testing.assert_array_equal(dc["impulses"], np.concatenate([dense["impulses"]] * reps))
        break  # one law per example is enough for the dispatch


def _car_between_constraints(angle, law):
    """tests/unit/test_impact_extremes.py's scene: a car (heading +x, 10 m/s forward, 2 m/s
    left) strikes a wall with its front-left corner; its lateral velocity is held at zero 1 m
    ahead of and behind its CG, which fixes the contact point's tangential velocity: the
    no-slide system is singular, the ratio-law system is not. Turned by ``angle``."""
    c = Vehicle("C", (Body("C_car", 1500.0, 2800.0),))
    w = Vehicle("wall", (Body("wall", math.inf, math.inf),))

    def T(p):
        return (math.cos(angle) * p[0] - math.sin(angle) * p[1], math.sin(angle) * p[0] + math.cos(angle) * p[1])

    st_ = {"C_car": BodyState((0.0, 0.0), angle, T((10.0, 2.0)), 0.0),
           "wall": BodyState(T((2.0, 0.0)), angle, (0, 0), 0)}
    cons = (VelocityConstraint("C_car", T((-1.0, 0.0)), angle + math.pi / 2, 0.0, "rear"),
            VelocityConstraint("C_car", T((1.0, 0.0)), angle + math.pi / 2, 0.0, "front"))
    return ImpactProblem((c, w), st_, "C_car", "wall", CrushSurface(T((2.0, 0.5)), angle + math.pi, 0.1, law), cons)


def test_method_argument_is_checked():
    S, A = compile_problem(_car_between_constraints(0.3, TangentialLaw("friction", 0.5)))
    with pytest.raises(ValueError, match="method"):
        core.solve_arrays(S, A, method="lu")
    with pytest.raises(ValueError, match="condition"):
        core.solve_arrays(S, A, method="compiled", condition=True)


@pytest.mark.parametrize("law", LAWS)
def test_car_between_constraints_at_every_angle(law):
    """tests/unit/test_impact_extremes.py's scene whose no-slide system is singular in exact
    arithmetic (two constraints fix the contact point's tangential velocity), turned through
    600 angles: rounding leaves the no-slide system exactly singular at some angles and nearly
    singular (cond ~1e16) at others. Both paths (dense, compiled): no_slide not ok everywhere;
    ratio and friction solve (friction slides against the initial slip), mu_max NaN everywhere."""
    value = {"no_slide": 0.0, "ratio": 0.1, "friction": 0.5}[law]
    angles = np.linspace(0.0, 2 * math.pi, 600)
    S, A0 = compile_problem(_car_between_constraints(0.0, TangentialLaw(law, value)))
    A = A0.repeat(len(angles))
    for i, a in enumerate(angles):
        _, Ai = compile_problem(_car_between_constraints(float(a), TangentialLaw(law, value)))
        for f in fields(Ai):
            getattr(A, f.name)[i] = getattr(Ai, f.name)[0]
    dense = core.solve_arrays(S, A, method="dense")
    comp = core.solve_arrays(S, A)  # the compiled path
    np.testing.assert_array_equal(comp["ok"], dense["ok"])
    np.testing.assert_array_equal(comp["sliding"], dense["sliding"])
    assert np.all(np.isnan(comp["mu_max"])) and np.all(np.isnan(dense["mu_max"]))
    assert dense["ok"].all() == (law != "no_slide") and not (law == "no_slide" and dense["ok"].any())
    if law != "no_slide":
        ns = core.solve_arrays(replace(S, tangential="no_slide"), A, method="dense")
        check_agreement(S, A, dense, comp, ns)
    if law == "friction":
        assert dense["sliding"].all() and comp["sliding"].all()
        np.testing.assert_allclose(np.abs(dense["mu"]), value, rtol=1e-12)
        np.testing.assert_allclose(np.abs(comp["mu"]), value, rtol=1e-12)


@pytest.mark.parametrize("law", LAWS)
def test_chunks_do_not_change_the_answers(law, monkeypatch):
    """Items are independent: solving in chunks of the dense path (here 7 chunks of 97 and a
    remainder) gives the numbers of one pass, bit for bit, with solvable and singular items
    (conflicting constraints) mixed."""
    value = {"no_slide": 0.0, "ratio": 0.1, "friction": 0.5}[law]
    angles = np.linspace(0.0, 2 * math.pi, 700)
    S, A0 = compile_problem(_car_between_constraints(0.0, TangentialLaw(law, value)))
    A = A0.repeat(len(angles))
    A.velocity[:, 0] *= np.linspace(0.5, 2.0, len(angles))[:, None]
    A.law_value[:] = np.linspace(0.0, 1.0, len(angles))
    A.constraint_direction[:, 1] += np.linspace(-0.2, 0.2, len(angles))
    conflict = np.arange(len(angles)) % 3 == 0  # both constraints at one point, other values
    A.constraint_point[conflict, 1] = A.constraint_point[conflict, 0]
    A.constraint_direction[conflict, 1] = A.constraint_direction[conflict, 0]
    A.constraint_value[conflict, 1] = 0.5
    one = core.solve_arrays(S, A, method="dense")
    monkeypatch.setattr(core, "CHUNK", 97)
    chunked = core.solve_arrays(S, A, method="dense")
    for k in SOLVE_KEYS:
        np.testing.assert_array_equal(chunked[k], one[k], err_msg=k)
    assert not one["ok"].all()
    assert one["ok"].any() or law == "no_slide"  # its system is singular for every item of this scene


def test_empty_batch():
    S, A0 = compile_problem(_car_between_constraints(0.3, TangentialLaw("friction", 0.5)))
    A = A0.repeat(2)
    A = replace(A, **{f.name: getattr(A, f.name)[:0] for f in fields(A)})
    dense = core.solve_arrays(S, A, method="dense")
    comp = core.solve_arrays(S, A, method="compiled")
    for k in SOLVE_KEYS:
        assert dense[k].shape[0] == 0, k
        assert comp[k].shape == dense[k].shape and comp[k].dtype == dense[k].dtype, k

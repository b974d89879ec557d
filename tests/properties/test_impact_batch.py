"""Property: ImpactBatch gives the numbers solve_impact gives, item by item.

A family of scenes shares one structure (vehicle kinds, contact bodies, tangential law, numbers
of constraints and external impulses) while every number differs: masses, inertias, hitch
geometry, states, contact point, normal, tangent sign, e, e', mu or f, constraints, external
impulses. Their arrays are stacked into one batch; for the friction law the batch mixes
sticking and sliding items, which the solver handles on a subset.

Tolerance: a batch asked for condition numbers runs the same dense code as the single solve's
full path (``solve._solve_impact_full``, the path of its refusals) on the same numbers; only the
batched LAPACK call may round differently, so results agree to a few ulps of the answer's scale
(``1e-12`` relative to ``velocity_scale`` / ``impulse_scale`` leaves ~4500 eps). Without
condition numbers batches take the compiled kernel, as ``solve_impact`` does: checked against
it to a cond-scaled tolerance (another sequence of roundings than the dense path).
"""

from __future__ import annotations

import math
from dataclasses import fields

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from impact_scenes import EPS, EXAMPLES, SETTINGS, impulse_scale, lever_length, scenes, structures, velocity_scale

from crashsim import ImpactBatch, solve_impact as _solve_impact
from crashsim.impact import compile_problem
from crashsim.impact import solve as solve_mod

RTOL = 1e-12


def solve_impact(problem):
    """The impact equations' answer with the admissibility check off: these properties hold for
    every input the equations accept (tests/unit/test_admissibility.py covers the refusals)."""
    return _solve_impact(problem, check=False)


@st.composite
def families(draw):
    S = draw(structures())
    k = draw(st.integers(2, 5))
    return [draw(scenes(S)) for _ in range(k)]


@SETTINGS
@given(families())
def test_batch_equals_single_solves(family):
    problems = [s.problem for s in family]
    batch = ImpactBatch.from_problem(problems[0], len(problems))
    assert batch.arrays.size == len(problems)
    for i, p in enumerate(problems):
        S_i, A_i = compile_problem(p)
        assert S_i == batch.structure  # the family really shares one structure
        for f in fields(A_i):
            getattr(batch.arrays, f.name)[i] = getattr(A_i, f.name)[0]
    out = batch.solve(condition=True)
    names = batch.structure.body_names
    for i, p in enumerate(problems):
        r = solve_mod._solve_impact_full(p, *compile_problem(p), False)  # the dense path, as the batch
        vs, isc, L = velocity_scale(p, r), impulse_scale(r), lever_length(p)
        for j, name in enumerate(names):
            b = r.bodies[name]
            np.testing.assert_allclose(out["velocity"][i, j], b.velocity, rtol=0, atol=RTOL * vs)
            np.testing.assert_allclose(out["delta_v"][i, j], b.delta_v, rtol=0, atol=RTOL * vs)
            assert abs(out["yaw_rate"][i, j] - b.yaw_rate) <= RTOL * vs / L
        assert abs(out["normal_impulse"][i] - r.normal_impulse) <= RTOL * isc
        assert abs(out["tangential_impulse"][i] - r.tangential_impulse) <= RTOL * isc
        assert abs(out["moment_impulse"][i] - r.moment_impulse) <= RTOL * (isc * L + abs(r.moment_impulse))
        assert abs(out["mu"][i] - r.mu) <= RTOL * isc * (1 + abs(r.mu)) / abs(r.normal_impulse)
        assert bool(out["sliding"][i]) == r.sliding
        assert bool(out["ok"][i])
        for h, (hname, hi) in enumerate(r.hitches.items()):
            np.testing.assert_allclose(out["hitch_impulse"][i, h], hi.impulse, rtol=0, atol=RTOL * isc)
        for c, (cname, ci) in enumerate(r.constraints.items()):
            assert abs(out["constraint_impulse"][i, c] - ci.impulse) <= RTOL * isc
        ke0 = r.kinetic_energy["system"]["before"]
        assert abs(out["ke_after"][i].sum() - r.kinetic_energy["system"]["after"]) <= RTOL * 10 * (
            ke0 + r.kinetic_energy["system"]["after"])
        for v in p.vehicles:
            before, after = r.kinetic_energy[v.name]["before"], r.kinetic_energy[v.name]["after"]
            if v.is_barrier or before == 0:
                continue
            if math.isfinite(after / before):
                assert np.isclose(out[f"energy_loss.{v.name}"][i], r.energy_loss[v.name], rtol=1e-9,
                                  atol=1e-11 * (1 + after / before))
            else:  # subnormal energy before (hypothesis draws 1e-160 m/s): -inf in both
                assert out[f"energy_loss.{v.name}"][i] == r.energy_loss[v.name]
        assert np.isclose(out["energy_loss.system"][i], r.energy_loss["system"], rtol=1e-9, atol=1e-11)
        assert out["condition"][i] == np.float64(r.condition_number) or np.isclose(
            out["condition"][i], r.condition_number, rtol=1e-6)


@settings(max_examples=max(10, EXAMPLES // 4), deadline=None)  # each example solves >= 512 items
@given(families())
def test_large_batch_equals_single_solves(family):
    """Batches without condition numbers take the compiled kernel (here tiled to 512
    items): the answers of solve_impact, which solves by the same kernel unless it refuses or
    warns (then by the dense path: a different sequence of roundings, so agreement to 1e3 cond
    eps (+1e-12) of the answer's scale, as for the invariance tests)."""
    problems = [s.problem for s in family]
    n = max(512, len(problems))
    batch = ImpactBatch.from_problem(problems[0], n)
    compiled = [compile_problem(p)[1] for p in problems]
    for f in fields(compiled[0]):
        stacked = np.concatenate([getattr(A, f.name) for A in compiled], axis=0)
        setattr(batch.arrays, f.name, np.resize(stacked, (n,) + stacked.shape[1:]).copy())
    out = batch.solve()
    names = batch.structure.body_names
    for i, p in enumerate(problems):
        r = solve_impact(p)
        tol = 1e-12 + 1e3 * r.condition_number * EPS
        vs, isc, L = velocity_scale(p, r), impulse_scale(r), lever_length(p)
        for item in range(i, n, len(problems)):
            assert bool(out["ok"][item])
            for j, name in enumerate(names):
                np.testing.assert_allclose(out["velocity"][item, j], r.bodies[name].velocity, rtol=0, atol=tol * vs)
                assert abs(out["yaw_rate"][item, j] - r.bodies[name].yaw_rate) <= tol * vs / L
            assert abs(out["normal_impulse"][item] - r.normal_impulse) <= tol * isc
            assert abs(out["tangential_impulse"][item] - r.tangential_impulse) <= tol * isc
            assert abs(out["moment_impulse"][item] - r.moment_impulse) <= tol * (isc * L + abs(r.moment_impulse))
            for h, hi in enumerate(r.hitches.values()):
                np.testing.assert_allclose(out["hitch_impulse"][item, h], hi.impulse, rtol=0, atol=tol * isc)
            for c, ci in enumerate(r.constraints.values()):
                assert abs(out["constraint_impulse"][item, c] - ci.impulse) <= tol * isc
            law = p.surface.tangential
            if law.kind != "friction" or abs(abs(r.mu_max) - law.value) > 1e-6 * (1 + law.value):
                assert bool(out["sliding"][item]) == r.sliding

"""Property: the fast single solve gives the full path's answers, refusals and warnings.

``solve_impact`` solves with the compiled kernel (``crashsim.impact.kernel``) and builds the
result from plain floats, computing the per-body objects and the SVD condition number on first
access; anything not clear-cut (not approaching, not solvable, within a factor 2K of the
condition limit, inadmissible) goes to ``solve._solve_impact_full``: the dense numpy solve with
the SVD condition number, the path every refusal is worded by (the previous ``solve_impact``).

Checked here: every number of ``to_dict()`` (velocities, impulses, energies, work, angles, flags,
names, warnings) on every paper scenario to 1e-12 of its kind's scale, and on random scenes to
the same or, for ill-conditioned systems, to ``8 K eps cond`` (two backward-stable solves of one
system agree to about cond * eps relative, not better; see test_impact_fast_batch.py); the
condition number (the same SVD computation) exactly; errors of the same type and message;
the deferred attributes equal to what the full path builds at once; results that pickle; and
``compile_problem``'s cached structure equal to a fresh one.
"""

from __future__ import annotations

import math
import pickle
from dataclasses import fields, replace
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given

from impact_scenes import EPS, SETTINGS, impulse_scale, lever_length, scenes, velocity_scale

from crashsim import TangentialLaw, solve_impact
from crashsim.errors import CrashsimError, InadmissibleImpactError
from crashsim.impact import compile_problem
from crashsim.impact import solve as solve_mod
from crashsim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[2]
PAPER = sorted((ROOT / "scenarios" / "paper").glob("*.toml"))
RTOL = 1e-12


def full_path(problem, check=True):
    """The previous solve_impact: dense numpy solve, SVD condition number, eager result."""
    return solve_mod._solve_impact_full(problem, *compile_problem(problem), check)


def _flat(d, pre=""):
    if isinstance(d, dict):
        return {k2: v2 for k, v in d.items() for k2, v2 in _flat(v, f"{pre}.{k}").items()}
    if isinstance(d, (list, tuple)):
        return {k2: v2 for i, v in enumerate(d) for k2, v2 in _flat(v, f"{pre}[{i}]").items()}
    return {pre: d}


KINDS = ("fraction", "energy", "impulse", "velocity", "yaw_rate")


def _kind(key: str) -> str:
    if key.startswith(".energy_loss."):
        return "fraction"   # energy lost / energy before, per vehicle and system
    if "energy" in key or "work" in key:
        return "energy"     # J
    if "impulse" in key or key.startswith((".hitches.", ".constraints.")):
        return "impulse"
    if "yaw_rate" in key:
        return "yaw_rate"
    if "velocity" in key or "delta_v" in key or "speed" in key:
        return "velocity"
    return key  # angles, mu, ratios, condition number: each relative to itself


def assert_same_result(got, ref, rtol=RTOL, problem=None):
    """Every entry of to_dict(): non-floats equal; floats equal to ``rtol`` of the largest
    magnitude of their kind (a velocity that is 0 in exact arithmetic is compared with the
    speeds, not with itself; with ``problem``, the scales of impact_scenes: velocity_scale,
    velocity_scale / lever_length for yaw rates, impulse_scale); impulse ratios (mu) to
    ``rtol`` of the impulse scale over P_n; directions (pdof, delta-v direction; modulo 2 pi) to
    ``rtol`` of their vector's scale over its length; the rest (e.g. the condition number) to
    ``rtol`` of themselves. mu_fraction is None where mu_max is 0: either may be None if
    mu_max is 0 within the tolerance."""
    a, b = _flat(got.to_dict()), _flat(ref.to_dict())
    assert a.keys() == b.keys()
    scale: dict = {}
    for k, v in b.items():
        if isinstance(v, float) and math.isfinite(v) and _kind(k) in KINDS:
            scale[_kind(k)] = max(scale.get(_kind(k), 0.0), abs(v))
    # a fraction of the energy before is computed to round-off of that energy: of 1, even where every
    # fraction is 0 (an elastic impact, e = 1, that loses nothing)
    scale["fraction"] = max(scale.get("fraction", 0.0), 1.0)
    if problem is not None:
        vs, L = velocity_scale(problem, ref), lever_length(problem)
        scale["velocity"] = max(scale.get("velocity", 0.0), vs)
        scale["yaw_rate"] = max(scale.get("yaw_rate", 0.0), vs / L)
        scale["impulse"] = max(scale.get("impulse", 0.0), impulse_scale(ref, problem))
    tiny = 1e-300
    for k, v in b.items():
        x = a[k]
        if k == ".mu_fraction" and (x is None or v is None):
            mu_max = b[".mu_max"]
            assert x is v or abs(mu_max) <= 2 * rtol * scale["impulse"] / max(abs(b[".normal_impulse"]), tiny), k
            continue
        if not isinstance(v, float):
            assert x == v, (k, x, v)
            continue
        if math.isnan(v) or math.isinf(v):
            assert x == v or (math.isnan(x) and math.isnan(v)), (k, x, v)
            continue
        d = abs(x - v)
        allowed = rtol * max(abs(v), scale.get(_kind(k), 0.0))
        if k in (".mu", ".mu_max", ".mu_fraction"):     # ratios of impulses: their error / P_n
            allowed = 2 * rtol * (1.0 + abs(v)) * scale["impulse"] / max(abs(b[".normal_impulse"]), tiny)
        elif k.endswith(".pdof"):                       # direction of a crush impulse
            d = min(d, abs(d - 2 * math.pi))
            crush = math.hypot(b[k[:-5] + ".crush_impulse[0]"], b[k[:-5] + ".crush_impulse[1]"])
            allowed = rtol * max(1.0, scale["impulse"] / max(crush, tiny))
        elif k.endswith(".delta_v_direction"):          # direction of a velocity change
            d = min(d, abs(d - 2 * math.pi))
            allowed = rtol * max(1.0, scale["velocity"] / max(b[k.replace("direction", "magnitude")], tiny))
        assert d <= allowed, (k, x, v, d, allowed)


@pytest.mark.parametrize("path", PAPER, ids=[p.stem for p in PAPER])
def test_paper_scenarios_give_the_full_paths_numbers(path):
    """Brach, "Impact of Articulated Vehicles", Tables 1-8 (scenarios/paper/, each file cites its
    table): the fast path's results equal the full path's to 1e-12 of each kind's scale, and the
    condition number is the same SVD value."""
    p = load_scenario(path).impact
    got, ref = solve_impact(p), full_path(p)
    assert_same_result(got, ref)
    assert got.condition_number == ref.condition_number
    assert got.warnings == ref.warnings == ()


def _tolerance(problem, ref) -> float:
    """1e-12, or 8 K eps cond for an ill-conditioned system (cond: its 2-norm condition number,
    an upper bound of the 1-norm one up to a factor K)."""
    K = 3 + 2 * sum(len(v.hitches) for v in problem.vehicles) + len(problem.constraints)
    return max(RTOL, 8.0 * K * K * EPS * ref.condition_number)


@SETTINGS
@given(scenes(solve=False))
def test_random_scenes_give_the_full_paths_answer(scene):
    """Random articulated scenes (tests/properties/impact_scenes.py), with the admissibility check
    on (refusals must match) and off (the equations' answer, warnings included)."""
    p = scene.problem
    for check in (True, False):
        try:
            ref = full_path(p, check)
        except CrashsimError as exc:
            with pytest.raises(type(exc)) as info:
                solve_impact(p, check=check)
            assert str(info.value) == str(exc)
            continue
        got = solve_impact(p, check=check)
        assert_same_result(got, ref, _tolerance(p, ref), p)
        assert got.condition_number == ref.condition_number
        assert got.warnings == ref.warnings


@SETTINGS
@given(scenes(solve=False))
def test_deferred_attributes_equal_the_eager_ones(scene):
    """result.bodies (built on first access) and result.condition_number (SVD on first access)
    equal the full path's; a result pickles (as a plain dict of bodies) and compares equal."""
    p = scene.problem
    try:
        ref = full_path(p, False)
    except CrashsimError:
        return
    got = solve_impact(p, check=False)
    tol = _tolerance(p, ref)
    assert list(got.bodies) == list(ref.bodies)
    for name, b in ref.bodies.items():
        g = got.bodies[name]
        for f in fields(b):
            x, y = getattr(g, f.name), getattr(b, f.name)
            if isinstance(y, np.ndarray):
                np.testing.assert_allclose(x, y, rtol=tol, atol=tol * (1.0 + float(np.max(np.abs(y)))))
            elif isinstance(y, float) and f.name != "pdof":
                assert x == pytest.approx(y, rel=tol, abs=tol * (1.0 + abs(y))), f.name
            elif f.name != "pdof":
                assert x == y, f.name
    assert got.condition_number == ref.condition_number
    back = pickle.loads(pickle.dumps(got))
    assert type(back.bodies) is dict
    a, b = _flat(back.to_dict()), _flat(got.to_dict())
    assert a.keys() == b.keys()
    assert all(a[k] == b[k] or (isinstance(b[k], float) and math.isnan(b[k]) and math.isnan(a[k])) for k in b)


def test_an_impossible_impact_is_still_refused():
    """The reproducer of impossible impacts passing with exit 0 (tests/unit/test_admissibility.py
    covers its wording and the CLI): mu beyond mu_max, far from any threshold, is refused by the
    fast path with the full path's error, and returned with the full path's warning when the
    check is off."""
    p = load_scenario(ROOT / "scenarios" / "paper" / "table6.toml").impact
    mu_max = solve_impact(p).mu_max
    bad = replace(p, surface=replace(p.surface, tangential=TangentialLaw("ratio", 3.0 * mu_max)))
    with pytest.raises(InadmissibleImpactError) as fast:
        solve_impact(bad)
    with pytest.raises(InadmissibleImpactError) as full:
        full_path(bad)
    assert str(fast.value) == str(full.value) and "impact.mu" in str(fast.value)
    r = solve_impact(bad, check=False)
    assert r.warnings == full_path(bad, False).warnings and "inadmissible" in r.warnings[0]


def test_compile_problem_reuses_the_structure_of_a_problem_of_the_same_shape():
    """Problems that differ only in numbers (speed, e, mu) share one ImpactStructure; it equals a
    freshly built one, and the arrays hold the problem's numbers."""
    p = load_scenario(ROOT / "scenarios" / "paper" / "table6.toml").impact
    q = replace(p, surface=replace(p.surface, restitution=0.3, point=(p.surface.point[0] + 0.1, p.surface.point[1])))
    S1, A1 = compile_problem(p)
    S2, A2 = compile_problem(q)
    assert S1 is S2 and S1 == solve_mod._build_structure(q)
    assert A1.restitution[0] == 0.05 and A2.restitution[0] == 0.3
    assert A2.point[0, 0] == p.surface.point[0] + 0.1
    names = S1.body_names
    bodies = {b.name: b for v in p.vehicles for b in v.bodies}
    np.testing.assert_array_equal(A1.mass[0], [bodies[n].mass for n in names])
    np.testing.assert_array_equal(A1.velocity[0], [p.states[n].velocity for n in names])
    np.testing.assert_array_equal(A1.heading[0], [p.states[n].heading for n in names])
    np.testing.assert_array_equal(A1.hitch_front_point[0], [h.front_point for v in p.vehicles for h in v.hitches])
    other = replace(p, surface=replace(p.surface, tangential=TangentialLaw("friction", 0.5)))
    S3, _ = compile_problem(other)
    assert S3 is not S1 and S3.tangential == "friction"

"""Properties: the solution does not depend on how the scene is described.

Turning and moving the whole scene, mirroring it, exchanging the roles of the two vehicles
and adding a common velocity (Galilean boost) are changes of description, not of physics;
the solution must follow them exactly, up to rounding.

Tolerance: the transformed problem is solved from scratch, so the two answers differ by the
forward error of two solves whose inputs differ by rounding, about cond * eps relative to the
scale of the answer (``velocity_scale`` for velocities, ``impulse_scale`` for impulses). Over
several thousand random scenes the largest ratio observed was 27 cond eps (rotation, swap)
and the mirror image came out bit-identical; ``_tol`` allows 1000 cond eps + 1e-12.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from impact_scenes import (EPS, SETTINGS, galilean, impulse_scale, lever_length, mirror, rigid_motion, rot, scenes,
                           swap, velocity_scale)

from crashsim import solve_impact as _solve_impact


def solve_impact(problem):
    """The impact equations' answer with the admissibility check off: these properties hold for
    every input the equations accept (tests/unit/test_admissibility.py covers the refusals)."""
    return _solve_impact(problem, check=False)


def _tol(result):
    return 1e-12 + 1e3 * max(result.condition_number, 1.0) * EPS


def _check(p, r, r2, *, vmap, wsign=1, pt_sign=1, m_sign=1, same_bodies=True):
    """Compare r2 (transformed problem) with r mapped through the transformation."""
    tol = _tol(r)
    vs = velocity_scale(p, r)
    isc = impulse_scale(r)
    L = lever_length(p)
    for b in p.bodies:
        V_expect = vmap(r.bodies[b.name].velocity)
        np.testing.assert_allclose(r2.bodies[b.name].velocity, V_expect, rtol=0, atol=tol * vs, err_msg=b.name)
        assert abs(r2.bodies[b.name].yaw_rate - wsign * r.bodies[b.name].yaw_rate) <= tol * vs / L, b.name
    assert abs(r2.normal_impulse - r.normal_impulse) <= tol * isc
    assert abs(r2.tangential_impulse - pt_sign * r.tangential_impulse) <= tol * isc
    assert abs(r2.moment_impulse - m_sign * r.moment_impulse) <= tol * (isc * L + abs(r.moment_impulse))
    # mu = P_t / P_n: d mu = (d P_t - mu d P_n) / P_n, large where P_n is small
    assert abs(r2.mu - r.mu) <= tol * isc * (1 + abs(r.mu)) / abs(r.normal_impulse)
    ke0 = r.kinetic_energy["system"]["before"]
    assert abs(r2.kinetic_energy["system"]["after"] - r.kinetic_energy["system"]["after"]) <= tol * (
        ke0 + r.kinetic_energy["system"]["after"])
    law = p.surface.tangential
    if law.kind == "friction" and abs(abs(r.mu_max) - law.value) > 1e-6 * (1 + law.value):
        assert r2.sliding == r.sliding


@SETTINGS
@given(scenes(), st.floats(-math.pi, math.pi), st.floats(-100.0, 100.0), st.floats(-100.0, 100.0))
def test_turning_and_moving_the_scene(scene, angle, dx, dy):
    """Rotate every position, heading, velocity, the normal, constraint directions and external
    impulses by ``angle`` and translate by (dx, dy): velocities rotate, scalars are unchanged."""
    p, r = scene.problem, scene.result
    r2 = solve_impact(rigid_motion(p, angle, (dx, dy)))
    _check(p, r, r2, vmap=lambda V: rot(V, angle))
    np.testing.assert_allclose(r2.crush_impulse, rot(r.crush_impulse, angle), rtol=0,
                               atol=_tol(r) * impulse_scale(r))
    for name, h in r.hitches.items():
        np.testing.assert_allclose(r2.hitches[name].impulse, rot(h.impulse, angle), rtol=0,
                                   atol=_tol(r) * impulse_scale(r))
        assert math.isclose(r2.hitches[name].longitudinal, h.longitudinal, rel_tol=0,
                            abs_tol=_tol(r) * impulse_scale(r))


@SETTINGS
@given(scenes())
def test_mirror_image(scene):
    """Reflect y -> -y (vehicles' hitch points too; headings, yaw rates and the normal angle
    negate; tangent_sign flips so that the tangent is the mirror image of the old one):
    velocities mirror, yaw rates and the moment impulse negate, P_n, P_t and mu are unchanged."""
    p, r = scene.problem, scene.result
    r2 = solve_impact(mirror(p))
    _check(p, r, r2, vmap=lambda V: np.array([V[0], -V[1]]), wsign=-1, m_sign=-1)
    np.testing.assert_allclose(r2.tangent, [r.tangent[0], -r.tangent[1]], rtol=0, atol=4 * EPS)


@SETTINGS
@given(scenes())
def test_swapping_the_vehicles(scene):
    """Exchange body1 and body2 (and the order of the vehicles) and reverse the normal: same
    final velocities, same P_n, the same physical crush impulse on each body, M reversed."""
    p, r = scene.problem, scene.result
    r2 = solve_impact(swap(p))
    # same tangent_sign and reversed normal reverse the tangent, so P_t keeps its value
    _check(p, r, r2, vmap=np.asarray, m_sign=-1)
    tol = _tol(r) * impulse_scale(r)
    for b in (p.body1, p.body2):
        np.testing.assert_allclose(r2.bodies[b].crush_impulse, r.bodies[b].crush_impulse, rtol=0, atol=tol)
    np.testing.assert_allclose(r2.crush_impulse, -r.crush_impulse, rtol=0, atol=tol)
    for name, h in r.hitches.items():
        np.testing.assert_allclose(r2.hitches[name].impulse, h.impulse, rtol=0, atol=tol)


@SETTINGS
@given(scenes(barrier=False), st.floats(-50.0, 50.0), st.floats(-50.0, 50.0))
def test_galilean_boost(scene, ux, uy):
    """Add the same velocity U to every body (and to every constrained value, which is an
    absolute velocity): final velocities change by U, impulses and yaw rates do not."""
    p, r = scene.problem, scene.result
    U = np.array([ux, uy])
    r2 = solve_impact(galilean(p, U))
    tol = _tol(r)
    vs = velocity_scale(p, r) + float(np.hypot(ux, uy))
    isc = impulse_scale(r)
    for b in p.bodies:
        np.testing.assert_allclose(r2.bodies[b.name].velocity, np.asarray(r.bodies[b.name].velocity) + U,
                                   rtol=0, atol=tol * vs, err_msg=b.name)
        np.testing.assert_allclose(r2.bodies[b.name].delta_v, r.bodies[b.name].delta_v, rtol=0, atol=tol * vs)
        assert abs(r2.bodies[b.name].yaw_rate - r.bodies[b.name].yaw_rate) <= tol * vs / lever_length(p)
    assert abs(r2.normal_impulse - r.normal_impulse) <= tol * isc
    assert abs(r2.tangential_impulse - r.tangential_impulse) <= tol * isc
    assert abs(r2.moment_impulse - r.moment_impulse) <= tol * (isc * lever_length(p) + abs(r.moment_impulse))
    for name, h in r.hitches.items():
        np.testing.assert_allclose(r2.hitches[name].impulse, h.impulse, rtol=0, atol=tol * isc)
    for name, c in r.constraints.items():
        assert abs(r2.constraints[name].impulse - c.impulse) <= tol * isc
    assert abs(r2.closing_velocity - r.closing_velocity) <= tol * vs

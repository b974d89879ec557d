"""Eq. 6 with the sign of docs/paper-geometry.md, on the case that decides it: two bodies that
exchange only a moment impulse. With the contact on the line of centres, the normal along it
and no tangential impulse (mu = 0), the crush force has no moment about either CG, so
I1 (W1 - w1) = M, I2 (W2 - w2) = -M and the relative rotation must come back reversed and
scaled: W2 - W1 = -e' (w2 - w1); e' = 0 locks the rotations together, e' = -1 gives M = 0."""

from __future__ import annotations

import math

import pytest

from crashsim import Body, BodyState, CrushSurface, ImpactProblem, TangentialLaw, Vehicle, solve_impact


def _spinning_pair(ep, w1=2.0, w2=-1.0, I1=2800.0, I2=4000.0):
    a = Vehicle("A", (Body("a", 1500.0, I1),))
    b = Vehicle("B", (Body("b", 1800.0, I2),))
    st = {"a": BodyState((-2.0, 0.0), 0.0, (5.0, 0.0), w1), "b": BodyState((2.0, 0.0), math.pi, (-5.0, 0.0), w2)}
    return ImpactProblem((a, b), st, "a", "b", CrushSurface((0.0, 0.0), math.pi, 0.3, TangentialLaw("ratio", 0.0), ep))


@pytest.mark.parametrize("ep", [0.0, 0.25, 0.5, 1.0])
def test_relative_rotation_reverses_scaled_by_e_prime(ep):
    w1, w2, I1, I2 = 2.0, -1.0, 2800.0, 4000.0
    r = solve_impact(_spinning_pair(ep, w1, w2, I1, I2))
    W1, W2 = r.bodies["a"].yaw_rate, r.bodies["b"].yaw_rate
    assert W2 - W1 == pytest.approx(-ep * (w2 - w1), abs=1e-12)
    ibar = I1 * I2 / (I1 + I2)
    assert r.moment_impulse == pytest.approx((1 + ep) * (w2 - w1) * ibar, rel=1e-12)
    assert I1 * (W1 - w1) == pytest.approx(r.moment_impulse, rel=1e-12)
    assert I2 * (W2 - w2) == pytest.approx(-r.moment_impulse, rel=1e-12)


def test_no_moment_with_e_prime_minus_one():
    r = solve_impact(_spinning_pair(-1.0))
    assert abs(r.moment_impulse) < 1e-9
    assert r.bodies["a"].yaw_rate == pytest.approx(2.0, abs=1e-12)
    assert r.bodies["b"].yaw_rate == pytest.approx(-1.0, abs=1e-12)

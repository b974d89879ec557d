"""Unit tests of the pure tyre force laws (crashsim.motion.tyres)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crashsim.motion.tyres import lateral_force, tyre_forces

speed = st.floats(-40.0, 40.0, allow_nan=False)
load = st.floats(0.0, 60000.0)
mu_st = st.floats(0.05, 1.5)
brake_st = st.floats(0.0, 1.0)
c_alpha = st.floats(1e3, 4e5)
f_roll = st.floats(0.0, 0.05)
eps_st = st.floats(1e-4, 0.1)


@settings(max_examples=400, deadline=None)
@given(speed, speed, load, mu_st, st.booleans(), brake_st, c_alpha, f_roll, eps_st, st.sampled_from(["fiala", "linear"]))
def test_friction_circle_is_never_exceeded(u, w, n, mu, locked, b, c, fr, eps, model):
    fx, fy, _ = tyre_forces(u, w, n, mu, locked, b, c, fr, eps, model)
    assert np.hypot(fx, fy) <= mu * n * (1 + 1e-12) + 1e-9


@settings(max_examples=300, deadline=None)
@given(speed, speed, st.floats(1.0, 60000.0), mu_st, eps_st)
def test_locked_force_opposes_the_contact_velocity(u, w, n, mu, eps):
    fx, fy, sliding = tyre_forces(u, w, n, mu, True, 0.0, 0.0, 0.0, eps)
    assert sliding
    v = np.hypot(u, w)
    # antiparallel: zero cross product, negative dot product, magnitude mu N v / sqrt(v^2 + eps^2)
    assert abs(fx * w - fy * u) <= 1e-9 * mu * n * max(v, 1.0)
    assert fx * u + fy * w <= 0
    assert np.hypot(fx, fy) == pytest.approx(mu * n * v / np.hypot(v, eps), rel=1e-12, abs=1e-12)


def test_regularisation_is_finite_and_zero_at_rest():
    for locked, b in ((True, 0.0), (False, 0.0), (False, 0.7)):
        fx, fy, _ = tyre_forces(0.0, 0.0, 5000.0, 0.8, locked, b, 8e4, 0.01, 0.01)
        assert np.isfinite(fx) and np.isfinite(fy)
        assert fx == 0.0 and fy == 0.0
    # zero load (wheel lift-off): no force, no division by zero
    fx, fy, _ = tyre_forces(3.0, 1.0, 0.0, 0.8, False, 0.3, 8e4, 0.01, 0.01)
    assert fx == 0.0 and fy == 0.0


@pytest.mark.parametrize("locked, b", [(True, 0.0), (False, 0.0), (False, 0.4), (False, 1.0)])
@pytest.mark.parametrize("model", ["fiala", "linear"])
def test_force_is_continuous_in_the_velocity(locked, b, model):
    """Sweep the contact velocity around a circle of radius 2 m/s and along the axes through zero:
    no jumps larger than the Lipschitz bound of the smooth law (the lock-up switch is continuous)."""
    n, mu, c, fr, eps = 5000.0, 0.8, 8.6 * 5000.0, 0.012, 0.01
    angle = np.linspace(0, 2 * np.pi, 200001)
    paths = [
        (2.0 * np.cos(angle), 2.0 * np.sin(angle)),
        (np.linspace(-1, 1, 200001), np.full(200001, 0.3)),
        (np.full(200001, 0.3), np.linspace(-1, 1, 200001)),
    ]
    for u, w in paths:
        fx, fy, _ = tyre_forces(u, w, n, mu, locked, b, c, fr, eps, model)
        step = np.hypot(np.diff(u), np.diff(w)).max()
        jump = np.hypot(np.diff(fx), np.diff(fy)).max()
        # slope of the law is at most ~ C/eps (slip-angle regularisation) or mu N/eps (Coulomb)
        assert jump <= step * max(c, mu * n) / eps * 1.01


def test_braked_wheel_locks_when_the_brake_demand_exceeds_what_a_sliding_wheel_transmits():
    """Saturated lateral demand and b mu N > mu N |u|/|v|: the force points opposite the contact velocity."""
    n, mu, eps = 5000.0, 0.8, 1e-6
    u, w = 5.0, 5.0  # alpha = 45 deg: a locked wheel transmits mu N cos 45 = 0.707 mu N longitudinally
    fx, fy, sliding = tyre_forces(u, w, n, mu, False, 0.9, 8e4, 0.0, eps)
    assert sliding
    assert fx == pytest.approx(-mu * n / np.sqrt(2), rel=1e-9) and fy == pytest.approx(-mu * n / np.sqrt(2), rel=1e-9)
    # b = 0.5 < cos 45: the wheel keeps turning, braking priority on the friction circle
    fx, fy, sliding = tyre_forces(u, w, n, mu, False, 0.5, 8e4, 0.0, eps)
    assert sliding
    assert fx == pytest.approx(-0.5 * mu * n, rel=1e-9) and fy == pytest.approx(-np.sqrt(0.75) * mu * n, rel=1e-9)
    # a free-rolling wheel never locks: the saturated force is purely lateral
    fx, fy, sliding = tyre_forces(u, w, n, mu, False, 0.0, 8e4, 0.0, eps)
    assert sliding and fx == 0.0 and fy == pytest.approx(-mu * n, rel=1e-12)


def test_a_fully_braked_wheel_is_a_locked_wheel():
    """b = 1 (brake demand mu N) gives the locked force for every contact velocity."""
    rng = np.random.default_rng(1)
    u, w = rng.normal(0, 5, 1000), rng.normal(0, 5, 1000)
    braked = tyre_forces(u, w, 5000.0, 0.8, False, 1.0, 4e4, 0.0, 0.01)
    locked = tyre_forces(u, w, 5000.0, 0.8, True, 0.0, 4e4, 0.0, 0.01)
    assert np.allclose(braked[0], locked[0], rtol=1e-12, atol=1e-9)
    assert np.allclose(braked[1], locked[1], rtol=1e-12, atol=1e-9)


def test_partial_slip_is_not_sliding():
    """Small slip angle on a rolling wheel: rolling resistance and the Fiala side force, no tyre mark."""
    n, mu, c = 5000.0, 0.8, 8.6 * 5000.0
    u, w = 20.0, 0.2
    fx, fy, sliding = tyre_forces(u, w, n, mu, False, 0.0, c, 0.012, 0.01)
    assert not sliding
    u_reg = np.hypot(u, 0.01)
    t = w / u_reg
    assert fx == pytest.approx(-0.012 * n * u / u_reg, rel=1e-12)
    assert fy == pytest.approx(-c * t + c**2 / (3 * mu * n) * t * t - c**3 / (27 * (mu * n) ** 2) * t**3, rel=1e-12)


@pytest.mark.parametrize("model", ["fiala", "linear"])
def test_lateral_curve_slope_saturation_and_symmetry(model):
    mu_n, c = 4000.0, 40000.0
    t = np.array([1e-6, -1e-6])
    assert lateral_force(t, mu_n, c, model) == pytest.approx(-c * t, rel=1e-5)
    big = np.array([10.0, -10.0, 1e3])
    assert lateral_force(big, mu_n, c, model) == pytest.approx(-np.sign(big) * mu_n, rel=1e-12)
    grid = np.linspace(-2, 2, 4001)
    f = lateral_force(grid, mu_n, c, model)
    assert np.allclose(f, -f[::-1])  # odd
    assert np.all(np.diff(f) <= 1e-9)  # monotone non-increasing
    assert np.all(np.abs(f) <= mu_n)


def test_fiala_matches_its_polynomial_form():
    """-C tan a + C^2/(3 mu N) |tan a| tan a - C^3/(27 mu^2 N^2) tan^3 a below saturation (note sec. 2.2)."""
    mu_n, c = 4000.0, 40000.0
    t = np.linspace(-0.29, 0.29, 101)  # saturation at 3 mu N / C = 0.3
    poly = -c * t + c**2 / (3 * mu_n) * np.abs(t) * t - c**3 / (27 * mu_n**2) * t**3
    assert lateral_force(t, mu_n, c, "fiala") == pytest.approx(poly, rel=1e-12, abs=1e-9)


def test_unknown_lateral_model_is_a_scenario_error():
    from crashsim.errors import ScenarioError

    with pytest.raises(ScenarioError, match="lateral_model"):
        lateral_force(0.1, 1.0, 1.0, "magic")


@settings(max_examples=400, deadline=None)
@given(speed, speed, st.floats(1.0, 60000.0), mu_st, brake_st, c_alpha, eps_st, st.booleans())
def test_switch_margins_say_which_side_of_each_switch_the_wheel_is(u, w, n, mu, b, c, eps, fiala):
    """tyre_parts: the force of tyre_kernel, and margins whose signs are the law's own switches: saturated
    where m_sat >= 0, sliding like a locked wheel where both are >= 0 (the lock-up)."""
    from crashsim.motion.tyres import sliding_force, tyre_kernel, tyre_parts

    mu_load, demand = mu * n, b * mu * n
    fx, fy, sliding, m_sat, m_lock = tyre_parts(u, w, mu_load, demand, c, False, eps, fiala)
    assert (fx, fy, sliding) == tuple(tyre_kernel(u, w, mu_load, demand, c, False, eps, fiala))
    assert bool(sliding) == bool(m_sat >= 0.0)
    if m_sat >= 0.0 and m_lock >= 0.0:
        assert (fx, fy) == tuple(sliding_force(u, w, mu_load, eps))
    else:
        assert fx == u * (-demand / np.sqrt(u * u + eps * eps))  # the braked rolling wheel's demand

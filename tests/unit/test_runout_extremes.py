"""Extremes of the run-out: each case asserts a conservation law, a closed form or bound, or a clear error.

Closed forms use the regularised friction law of the tyre model exactly: a straight slide with
``a(v) = a v / sqrt(v^2 + eps^2)`` stopped at ``v_end`` covers ``[F(v0) - F(v_end)] / a`` in
``[T(v0) - T(v_end)] / a`` (note sec. 3.2, 5; ``tests/analytic/runout_cases.py``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import (
    FrictionZone,
    Road,
    RunoutOptions,
    WheelSetting,
    WheelSettings,
    simulate_runout,
    static_loads,
)
from crashsim.motion.levels import simulate_level
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

#: Global error allowance relative to rtol x scale for these dissipative runs (as tests/analytic).
GLOBAL = 50


def F(v, eps):
    return 0.5 * (v * math.hypot(v, eps) + eps * eps * math.asinh(v / eps))


def T(v, eps):
    return math.hypot(v, eps) - eps * math.asinh(eps / v)


def symmetric_car():
    return Vehicle("car", (Body("car", 1500.0, 2500.0, length=4.5, axles=(Axle(1.3, 1.5), Axle(-1.3, 1.5))),))


def tractor_semitrailer(limit=None):
    tractor = Body("tractor", 8000.0, 32000.0, length=6.0,
                   axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True)))
    trailer = Body("trailer", 25000.0, 330000.0, length=13.6,
                   axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True), Axle(-5.6, 1.85, True)))
    return Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0), articulation_limit=limit),))


# ---------------------------------------------------------------- zero speed
@pytest.mark.parametrize("level", ["articulated", "rigid", "energy"])
def test_zero_initial_speed_is_immediately_at_rest(level):
    veh = tractor_semitrailer()
    start = chain_states(veh, (3.0, -1.0), 0.4, (0.0, 0.0), articulation=[0.3])
    res = simulate_level(level, veh, start, None, Road(0.7))
    assert res.status == "rest" and res.success
    assert res.t_end == 0.0 and res.nfev == 0
    for name, b in res.bodies.items():
        assert b.rest_position == start[name].position and b.rest_heading == start[name].heading
        assert b.time_to_rest == 0.0 and b.distance == 0.0
    assert res.kinetic_energy_initial == 0.0 and res.energy_dissipated == 0.0


# ---------------------------------------------------------------- very fast
def test_60_m_s_and_10_rad_s_car_conserves_energy_and_stays_bounded():
    """KE_0 = tyre work + KE_end (note item 5) and the CG path <= KE_0 / (mu M g).

    The bound: static loads are in moment balance about the CG, so the CG velocity is the
    load-weighted mean of the contact velocities, |v_cg| <= sum N_k |v_k| / sum N_k, and the
    work-energy identity sum mu N_k s_k = KE_0 gives the CG path <= KE_0 / (mu sum N).
    """
    mu = 0.7
    res = simulate_runout(symmetric_car(), {"car": BodyState((0, 0), 0.0, (60.0, 0.0), 10.0)}, None, Road(mu))
    assert res.status == "rest"
    b = res.bodies["car"]
    assert np.all(np.isfinite(b.history.x)) and np.all(np.isfinite(b.history.yaw_rate))
    ke0 = res.kinetic_energy_initial
    assert ke0 == pytest.approx(0.5 * 1500 * 3600 + 0.5 * 2500 * 100)
    assert res.energy_dissipated + res.kinetic_energy_final == pytest.approx(ke0, rel=1e-6)
    assert b.distance <= ke0 / (mu * 1500 * G)
    # a spinning car slides farther than a non-spinning one (note item 7) -- but within the bound
    assert b.distance > 60.0**2 / (2 * mu * G)


@pytest.mark.parametrize("yaw_rates", [(10.0, 10.0), (10.0, -2.0)])
def test_60_m_s_articulated_conserves_energy(yaw_rates):
    veh = tractor_semitrailer()
    res = simulate_runout(veh, chain_states(veh, (0, 0), 0.0, (60.0, 0.0), yaw_rates=list(yaw_rates)), None, Road(0.7))
    assert res.status == "rest"
    assert all(np.all(np.isfinite(b.history.x)) for b in res.bodies.values())
    assert abs(res.energy_residual) < 1e-4  # Baumgarte drift at 10 rad/s: 7e-6 measured
    assert res.max_hitch_gap < 1e-3


# ---------------------------------------------------------------- pure spin
def test_pure_spin_time_to_rest_matches_the_closed_form():
    """Symmetric car spinning at 10 rad/s on locked wheels: t = I w0 / (mu sum N r) (note item 4),
    exactly ``[T(r w0) - T(v_end)] / k`` for the regularised law, ``k = mu sum N r^2 / I``."""
    mu, w0 = 0.8, 10.0
    veh = symmetric_car()
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, {"car": BodyState((0, 0), 0.0, (0.0, 0.0), w0)}, None, Road(mu), opts)
    r = math.hypot(1.3, 0.75)
    n_sum = static_loads(veh).total
    inertia = veh.bodies[0].yaw_inertia
    k = mu * n_sum * r * r / inertia
    v_end = opts.v_stop / (4.5 / 2) * r  # rest at |w| L_ref = v_stop
    t_reg = (T(w0 * r, opts.eps) - T(v_end, opts.eps)) / k
    b = res.bodies["car"]
    assert b.time_to_rest == pytest.approx(t_reg, abs=GLOBAL * opts.rtol * t_reg)
    t_ideal = inertia * w0 / (mu * n_sum * r)
    assert abs(b.time_to_rest - t_ideal) < v_end / k + 1e-3
    assert math.hypot(*b.rest_position) < 1e-9  # no net force by symmetry


# ---------------------------------------------------------------- a 60 s run-out
def test_60_s_free_roll_reports_the_time_limit_then_rest():
    """3 m/s on free-rolling wheels with f_r = 0.005: a = f_r g, about 61 s to rest (note item 2)."""
    v0, fr = 3.0, 0.005
    wheels = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=fr))
    start = {"car": BodyState((0, 0), 0.0, (v0, 0.0))}
    short = simulate_runout(symmetric_car(), start, wheels, Road(0.7), RunoutOptions(t_max=60.0))
    assert short.status == "time_limit" and not short.success
    assert short.t_end == 60.0 and short.bodies["car"].time_to_rest is None
    assert short.events[-1].kind == "time_limit"
    long = simulate_runout(symmetric_car(), start, wheels, Road(0.7), RunoutOptions(t_max=120.0))
    assert long.status == "rest" and 60.0 < long.t_end < 62.0
    a = fr * G
    o = RunoutOptions()
    b = long.bodies["car"]
    assert b.rest_position[0] == pytest.approx((F(v0, o.eps) - F(o.v_stop, o.eps)) / a, abs=5e-3)
    assert b.time_to_rest == pytest.approx((T(v0, o.eps) - T(o.v_stop, o.eps)) / a, abs=5e-3)
    assert abs(b.rest_position[1]) < 1e-9 and abs(b.rest_heading) < 1e-9


# ---------------------------------------------------------------- many zones
def test_locked_slide_across_20_friction_zones():
    """20 strips of mu 0.3 across the path of a straight locked slide on mu 0.8.

    The motion stays 1-D (symmetric left/right, no yaw), so with ``mu_eff(x) = sum_k N_k mu(x + a_k) / sum N``
    (``a_k`` the axle offsets) the rest position solves ``g int_0^X mu_eff = F(v0) - F(v_stop)`` exactly,
    a piecewise-linear equation; every crossing must be located on its edge.
    """
    v0, mu_road, mu_zone = 30.0, 0.8, 0.3
    edges = [(5.0 + 3.0 * i, 6.0 + 3.0 * i) for i in range(20)]
    zones = tuple(FrictionZone(((x0, -10.0), (x1, -10.0), (x1, 10.0), (x0, 10.0)), mu_zone, f"strip {i}")
                  for i, (x0, x1) in enumerate(edges))
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, max_step=0.02)
    veh = symmetric_car()
    res = simulate_runout(veh, {"car": BodyState((0, 0), 0.0, (v0, 0.0))}, None, Road(mu_road, zones), opts)
    assert res.status == "rest"
    assert not [e for e in res.events if e.kind == "zone_missed"]
    x_end = res.bodies["car"].rest_position[0]

    # exact rest position from the piecewise-linear work integral
    offsets = [1.3, -1.3]  # two wheels per axle, equal loads

    def mu_at(x):
        return mu_zone if any(x0 < x < x1 for x0, x1 in edges) else mu_road

    breaks = sorted({x0 - a for x0, _ in edges for a in offsets} | {x1 - a for _, x1 in edges for a in offsets} | {0.0})
    work = (F(v0, opts.eps) - F(opts.v_stop, opts.eps)) / G
    x, done = 0.0, 0.0
    for nxt in [b for b in breaks if b > 0] + [math.inf]:
        m = sum(mu_at(0.5 * (x + min(nxt, x + 1e3)) + a) for a in offsets) / len(offsets)
        if done + m * (nxt - x) >= work:
            expected = x + (work - done) / m
            break
        done += m * (nxt - x)
        x = nxt
    assert x_end == pytest.approx(expected, abs=GLOBAL * opts.rtol * expected)
    assert abs(res.bodies["car"].rest_position[1]) < 1e-9

    # every edge crossed by a wheel was located, at the edge
    crossed = [(k, e.t, e.kind) for e in res.events if e.kind in ("zone_enter", "zone_exit") for k in [e.detail.split()[1]]]
    expected_crossings = sum(
        1 for a in offsets for x0, x1 in edges for edge in (x0, x1) if a < edge < x_end + a
    ) * 2  # left and right wheel of each axle
    assert len(crossed) == expected_crossings
    edge_xs = np.array([e for pair in edges for e in pair])
    for key, t, kind in crossed:
        track = res.wheels[key]
        a = 1.3 if track.axle_index == 0 else -1.3
        xw = res.bodies["car"].sol(t)[0] + a
        assert np.min(np.abs(edge_xs - xw)) < 1e-8


# ---------------------------------------------------------------- jack-knife
@pytest.mark.parametrize("articulation_deg", [90.0, -90.0, 170.0, -170.0])
def test_jackknifed_start_without_limit_is_exact(articulation_deg):
    """Pure translation on locked wheels at any articulation: every unit decelerates at mu g and the
    articulation does not change (note item 8 generalised: the hitch force mu N_kp along the motion
    balances the trailer's moments by its static moment balance)."""
    veh = tractor_semitrailer()
    v0, mu = 12.0, 0.7
    start = chain_states(veh, (0, 0), 0.0, (v0, 0.0), articulation=[math.radians(articulation_deg)])
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, start, None, Road(mu), opts)
    assert res.status == "rest"
    d = v0**2 / (2 * mu * G)
    for name, b in res.bodies.items():
        assert b.rest_position[0] - start[name].position[0] == pytest.approx(d, abs=opts.v_stop**2 / (2 * mu * G) + 2e-4)
        assert b.rest_position[1] == pytest.approx(start[name].position[1], abs=1e-6)
    assert np.allclose(res.hitches[0].articulation, math.radians(articulation_deg), atol=1e-7)
    assert abs(res.energy_residual) < 1e-6


@pytest.mark.parametrize("articulation_deg, yaw_rates", [(170.0, (1.0, -1.0)), (-170.0, (-1.0, 1.0)), (90.0, (1.5, -1.5))])
def test_jackknife_with_limit_stays_within_it(articulation_deg, yaw_rates):
    limit = math.radians(175.0)
    veh = tractor_semitrailer(limit)
    start = chain_states(veh, (0, 0), 0.0, (12.0, 0.0), yaw_rates=list(yaw_rates), articulation=[math.radians(articulation_deg)])
    res = simulate_runout(veh, start, None, Road(0.7))
    assert res.status == "rest"
    art = res.hitches[0].articulation
    assert np.all(np.isfinite(art)) and np.max(np.abs(art)) <= limit + 1e-6
    closed = [e for e in res.events if e.kind == "stop_closed"]
    assert closed and all(e.energy > 0 for e in closed)  # the plastic stop dissipates
    assert abs(res.energy_residual) < 1e-5  # stop losses included


@pytest.mark.parametrize("articulation_deg", [90.0, -90.0, 170.0, -170.0])
def test_initial_articulation_beyond_the_limit_is_a_clear_error(articulation_deg):
    veh = tractor_semitrailer(math.radians(80.0))
    start = chain_states(veh, (0, 0), 0.0, (12.0, 0.0), articulation=[math.radians(articulation_deg)])
    with pytest.raises(ScenarioError, match=r"initial\['trailer'\]\.heading.*initial articulation .* exceeds the limit"):
        simulate_runout(veh, start, None, Road(0.7))


# ---------------------------------------------------------------- no axles
def test_vehicle_without_axles_is_a_clear_error():
    bare = Vehicle("sled", (Body("sled", 1000.0, 1500.0),))
    start = {"sled": BodyState((0, 0), 0.0, (5.0, 0.0))}
    for level in ("articulated", "rigid", "energy", "load_transfer"):
        with pytest.raises(ScenarioError, match=r"sled\.bodies.*at least one axle"):
            simulate_level(level, bare, start, None, Road(0.7))
    # a towed body without axles cannot be supported
    tractor = Body("tractor", 8000.0, 32000.0, axles=(Axle(1.9, 2.0), Axle(-1.6, 1.8, True)))
    trailer = Body("trailer", 20000.0, 200000.0)
    veh = Vehicle("ts", (tractor, trailer), (Hitch((-1.5, 0.0), (5.0, 0.0)),))
    with pytest.raises(ScenarioError, match=r"ts\.trailer\.axles.*towed body needs at least one axle"):
        simulate_runout(veh, chain_states(veh, (0, 0), 0.0, (5.0, 0.0)), None, Road(0.7))


# ---------------------------------------------------------------- mu at the bounds
@pytest.mark.parametrize("mu, mu_factor, v0", [(2.0, 1.0, 20.0), (2.0, 2.0, 20.0), (0.01, 1.0, 2.0)])
def test_mu_at_the_bounds_gives_the_straight_slide(mu, mu_factor, v0):
    """Largest road mu (2), largest wheel factor (2: mu 4 at the tyre) and a near-ice mu of 0.01."""
    wheels = WheelSettings(default=WheelSetting("locked", mu_factor=mu_factor))
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, t_max=60.0)
    res = simulate_runout(symmetric_car(), {"car": BodyState((0, 0), 0.0, (v0, 0.0))}, wheels, Road(mu), opts)
    a = mu * mu_factor * G
    b = res.bodies["car"]
    d = (F(v0, opts.eps) - F(opts.v_stop, opts.eps)) / a
    assert res.status == "rest"
    assert b.rest_position[0] == pytest.approx(d, abs=GLOBAL * opts.rtol * d)
    assert b.time_to_rest == pytest.approx((T(v0, opts.eps) - T(opts.v_stop, opts.eps)) / a, rel=1e-5)
    assert abs(b.rest_position[0] - v0**2 / (2 * a)) < opts.v_stop**2 / (2 * a) + 1e-4 * max(1.0, 0.1 / (mu * mu_factor))


@pytest.mark.parametrize("bad", [0.0, -0.1, 2.0 + 1e-9, float("nan"), float("inf")])
def test_mu_outside_the_bounds_is_a_clear_error(bad):
    with pytest.raises(ScenarioError, match=r"road\.mu: friction coefficient must lie in \(0, 2"):
        Road(bad)
    with pytest.raises(ScenarioError, match="friction coefficient must lie in"):
        FrictionZone(((0, 0), (1, 0), (1, 1)), bad, "z")
    with pytest.raises(ScenarioError, match="mu_factor"):
        WheelSetting("locked", mu_factor=bad if bad <= 0 or not math.isfinite(bad) else 2.5)

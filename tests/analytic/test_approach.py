"""The approach before impact against closed forms.

A straight slide on locked wheels at friction mu decelerates at mu g exactly (Coulomb friction
on every wheel, whatever the load distribution), so from the speed v_b at the start of braking:

    v_i^2 = v_b^2 - 2 mu g d          (distance d to the impact)
    v_i   = v_b - mu g T               (time T to the impact)

the drag-factor relation of every reconstruction textbook (Fricke & Baker, "Drag factor and
coefficient of friction in traffic accident reconstruction", Northwestern University Traffic
Institute; in US form S = sqrt(30 d f)).  Over two surfaces crossed in turn:
v_b^2 = v_i^2 + 2 g (mu_1 d_1 + mu_2 d_2).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import FrictionZone, Road, RunoutOptions
from crashsim.motion.approach import simulate_approach
from crashsim.motion.approach_spec import ApproachSpec
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.motion.wheels import WheelSetting, WheelSettings
from crashsim.vehicles import Axle, Body, Hitch, Vehicle, chain_states

ENGINES = ("scipy", "compiled")
LOCKED = WheelSettings(WheelSetting("locked"))


def car() -> Vehicle:
    return Vehicle("car", (Body("car", 1500.0, 2800.0, 4.6, 1.8, axles=(Axle(1.3, 1.55), Axle(-1.4, 1.55))),))


def semi() -> Vehicle:
    tractor = Body("tractor", 9500.0, 21000.0, 6.0, 2.5, axles=(Axle(2.6, 2.05), Axle(-2.7, 1.85, True),
                                                                  Axle(-4.0, 1.85, True)))
    trailer = Body("trailer", 20000.0, 150000.0, 12.0, 2.5, axles=(Axle(-2.0, 1.85, True), Axle(-3.3, 1.85, True)))
    return Vehicle("truck", (tractor, trailer), (Hitch((-3.1, 0.0), (3.991, 0.0)),))


def impact_pose(veh, position=(4.0, -2.0), heading=0.6):
    return chain_states(veh, position, heading, (0.0, 0.0))


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("make", [car, semi])
def test_locked_slide_over_a_distance(engine, make):
    veh, mu, vb, d = make(), 0.7, 25.0, 30.0
    res = simulate_approach(veh, ApproachSpec(LOCKED, speed=vb, distance=d), impact_pose(veh), Road(mu),
                            RunoutOptions(engine=engine))
    vi = math.sqrt(vb**2 - 2 * mu * G * d)
    assert res.speed_at_impact == pytest.approx(vi, rel=1e-6)
    assert res.time_to_impact == pytest.approx((vb - vi) / (mu * G), rel=1e-6)
    # the path ends on the impact configuration: position and heading of every body
    for name, st in impact_pose(veh).items():
        assert np.allclose(res.impact_states[name].position, st.position, atol=1e-6)
        assert res.impact_states[name].heading == pytest.approx(st.heading, abs=1e-9)
    # a straight slide starts d behind the impact along the heading
    start = np.asarray(res.braking_start[veh.bodies[0].name])
    assert np.allclose(start, np.array([4.0, -2.0]) - d * np.array([math.cos(0.6), math.sin(0.6)]), atol=1e-6)
    # velocity at impact along the heading
    v = np.asarray(res.impact_states[veh.bodies[0].name].velocity)
    assert np.allclose(v, vi * np.array([math.cos(0.6), math.sin(0.6)]), atol=1e-5)


@pytest.mark.parametrize("engine", ENGINES)
def test_locked_slide_over_a_time(engine):
    veh, mu, vb, T = car(), 0.55, 20.0, 1.2
    res = simulate_approach(veh, ApproachSpec(LOCKED, speed=vb, time=T), impact_pose(veh), Road(mu),
                            RunoutOptions(engine=engine))
    assert res.speed_at_impact == pytest.approx(vb - mu * G * T, rel=1e-6)
    assert res.distance == pytest.approx(vb * T - 0.5 * mu * G * T**2, rel=1e-6)


@pytest.mark.parametrize("engine", ENGINES)
def test_speed_at_braking_solved_from_the_impact_speed(engine):
    veh, mu, vi, d = car(), 0.7, 12.0, 22.0
    res = simulate_approach(veh, ApproachSpec(LOCKED, distance=d), impact_pose(veh), Road(mu),
                            RunoutOptions(engine=engine), speed_at_impact=vi)
    assert res.speed_solved
    assert res.speed_at_braking == pytest.approx(math.sqrt(vi**2 + 2 * mu * G * d), rel=1e-6)
    assert res.speed_at_impact == pytest.approx(vi, rel=1e-7)


def test_two_surfaces_in_turn():
    """A wet patch (mu 0.35) across the path between 10 m and 18 m before the impact."""
    veh, mu, mu2, vi, d = car(), 0.75, 0.35, 10.0, 30.0
    # impact at the origin heading +x: the path runs along the x axis from x = -30
    zone = FrictionZone(((-18.0, -10.0), (-10.0, -10.0), (-10.0, 10.0), (-18.0, 10.0)), mu2, "wet patch")
    res = simulate_approach(veh, ApproachSpec(LOCKED, distance=d), impact_pose(veh, (0.0, 0.0), 0.0),
                            Road(mu, (zone,)), RunoutOptions(), speed_at_impact=vi)
    # every wheel crosses the 8 m patch; the CG path is the same straight line
    expected = math.sqrt(vi**2 + 2 * G * (mu * (d - 8.0) + mu2 * 8.0))
    assert res.speed_at_braking == pytest.approx(expected, rel=2e-4)


def test_curved_approach_is_placed_on_the_impact_pose():
    """Steered front wheels rolling, rear locked: a curved path, placed by a rigid motion."""
    veh = car()
    ws = WheelSettings(WheelSetting("locked"), {"car/0": WheelSetting("rolling", steer=math.radians(4),
                                                                        cornering_coefficient=8.6,
                                                                        rolling_resistance=0.012)})
    pose = impact_pose(veh, (10.0, 5.0), -0.4)
    res = simulate_approach(veh, ApproachSpec(ws, speed=18.0, distance=25.0), pose, Road(0.8), RunoutOptions())
    assert np.allclose(res.impact_states["car"].position, pose["car"].position, atol=1e-6)
    assert res.impact_states["car"].heading == pytest.approx(-0.4, abs=1e-9)
    rows = res.bodies["car"]
    # the heading changed on the way (a curve), and the sampled path ends at the impact pose
    assert abs(rows[0, 3] - rows[-1, 3]) > math.radians(3)
    assert np.allclose(rows[-1, 1:3], pose["car"].position, atol=1e-9)
    # path length of the placed samples ~ the distance asked for
    assert np.sum(np.hypot(*np.diff(rows[:, 1:3], axis=0).T)) == pytest.approx(25.0, rel=2e-3)


def test_start_position_mode():
    veh, mu, vb = car(), 0.7, 22.0
    pose = impact_pose(veh, (0.0, 0.0), 0.0)
    res = simulate_approach(veh, ApproachSpec(LOCKED, speed=vb, start_position=(-20.0, 0.0), start_heading=0.0),
                            pose, Road(mu), RunoutOptions())
    assert res.miss == pytest.approx(0.0, abs=1e-6)
    assert res.speed_at_impact == pytest.approx(math.sqrt(vb**2 - 2 * mu * G * 20.0), rel=1e-6)
    with pytest.raises(ScenarioError, match="does not reach the impact configuration") as exc:
        simulate_approach(veh, ApproachSpec(LOCKED, speed=vb, start_position=(-20.0, 2.0), start_heading=0.0),
                          pose, Road(mu), RunoutOptions())
    assert exc.value.field == "approach.start_position"


def test_vehicle_that_stops_before_the_impact_is_an_error():
    veh = car()
    with pytest.raises(ScenarioError, match="before the impact") as exc:
        simulate_approach(veh, ApproachSpec(LOCKED, speed=10.0, distance=20.0), impact_pose(veh), Road(0.7),
                          RunoutOptions())  # stops after 10^2 / (2 0.7 g) = 7.3 m
    assert exc.value.field == "approach.distance"
    assert "7.28 m" in str(exc.value)


def test_speed_history_and_table():
    veh, mu, vb, d = car(), 0.7, 25.0, 30.0
    res = simulate_approach(veh, ApproachSpec(LOCKED, speed=vb, distance=d, reaction_time=1.5), impact_pose(veh),
                            Road(mu), RunoutOptions())
    T = res.time_to_impact
    t = np.array([-T - 2.0, -T - 0.5, -T / 2, 0.0])
    v = res.speed_at(t)
    assert v[0] == pytest.approx(vb) and v[1] == pytest.approx(vb)
    assert v[2] == pytest.approx(vb - mu * G * T / 2, rel=1e-6)
    tab = res.table()
    assert tab["t"][0] == pytest.approx(-T - 1.5) and tab["s"][0] == pytest.approx(-d - vb * 1.5)
    assert tab["s"][-1] == pytest.approx(0.0, abs=1e-5)
    assert res.perception_point == pytest.approx((4.0 - (d + 1.5 * vb) * math.cos(0.6),
                                                  -2.0 - (d + 1.5 * vb) * math.sin(0.6)), abs=1e-5)


def test_combined_speed_formula_in_us_units():
    """US practice: S = sqrt(S_i^2 + 30 d f) [mph, ft] (Fricke & Baker; the combined-speed rule).
    The 30 is 2 g (15/22)^2 = 29.91 rounded: with it a 100 ft skid at f = 0.7 after which 20 mph
    remain gives 50 mph; the exact constant gives 49.94 mph, which is what the model must give."""
    mph, ft = 0.44704, 0.3048
    veh = car()
    res = simulate_approach(veh, ApproachSpec(LOCKED, distance=100 * ft), impact_pose(veh), Road(0.7),
                            RunoutOptions(), speed_at_impact=20 * mph)
    exact = 2 * G / ft * (mph / ft) ** -2  # 2 g in ft/s^2 over (ft/s per mph)^2
    assert exact == pytest.approx(29.91, abs=0.005)
    s = res.speed_at_braking / mph
    assert s == pytest.approx(math.sqrt(20**2 + exact * 100 * 0.7), rel=1e-6)
    assert s == pytest.approx(math.sqrt(20**2 + 30 * 100 * 0.7), rel=2e-3)  # the rounded rule of thumb


def test_pose_at_any_time_before_the_impact():
    veh, vb = semi(), 22.0
    pose = impact_pose(veh, (3.0, 1.0), 0.4)
    res = simulate_approach(veh, ApproachSpec(LOCKED, speed=vb, distance=25.0, reaction_time=1.0), pose, Road(0.7),
                            RunoutOptions())
    for name, st in pose.items():
        (x, y), h = res.pose(name, 0.0)
        assert (x, y) == pytest.approx(st.position, abs=1e-6) and h == pytest.approx(st.heading, abs=1e-9)
        (x, y), h = res.pose(name, -res.time_to_impact)
        rows = res.bodies[name]
        assert (x, y) == pytest.approx(tuple(rows[0, 1:3]), abs=1e-9)
    # before braking: back along the heading at the speed at braking
    (x0, y0), _ = res.pose("tractor", -res.time_to_impact)
    (x1, y1), _ = res.pose("tractor", -res.time_to_impact - 1.0)
    assert (x0 - x1, y0 - y1) == pytest.approx((vb * math.cos(0.4), vb * math.sin(0.4)), abs=1e-6)
    assert (x1, y1) == pytest.approx(res.perception_point, abs=1e-6)


def test_speed_at_braking_solved_from_a_start_position():
    """From a start position the braking speed can be solved too (the upper bracket then comes from
    the distance to the impact position; with only a time it was undefined)."""
    veh, mu, vi = car(), 0.7, 12.0
    pose = impact_pose(veh, (0.0, 0.0), 0.0)
    res = simulate_approach(veh, ApproachSpec(LOCKED, start_position=(-20.0, 0.0), start_heading=0.0), pose,
                            Road(mu), RunoutOptions(), speed_at_impact=vi)
    assert res.speed_at_braking == pytest.approx(math.sqrt(vi**2 + 2 * mu * G * 20.0), rel=1e-6)
    assert res.miss == pytest.approx(0.0, abs=1e-6)

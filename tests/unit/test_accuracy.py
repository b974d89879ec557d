"""Run-out to a requested accuracy (crashsim.motion.accuracy): the estimate must bound the true error.

"True error" is measured against a converged reference of the same model: LSODA at rtol 1e-11,
atol 1e-13, eps = v_stop = 1e-4 m/s (its own eps/v_stop bias is below 0.01 mm in these cases;
the straight slide is also checked against the exact closed form).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import Road, RunoutOptions, WheelSetting, WheelSettings, make_hitch_consistent, simulate_runout
from crashsim.motion.accuracy import SHARES, AccuracyReport, _simulate_to_accuracy
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

ROOT = Path(__file__).resolve().parents[2]
REFERENCE = RunoutOptions(method="LSODA", rtol=1e-11, atol=1e-13, eps=1e-4, v_stop=1e-4)


def car():
    return Vehicle("car", (Body("car", 1500.0, 2500.0, length=4.5, axles=(Axle(1.3, 1.5), Axle(-1.3, 1.5))),))


def tractor_semitrailer():
    tractor = Body("tractor", 8000.0, 32000.0, length=6.0,
                   axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True)))
    trailer = Body("trailer", 25000.0, 330000.0, length=13.6,
                   axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True), Axle(-5.6, 1.85, True)))
    return Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0)),))


def true_errors(res, ref):
    pos = max(math.dist(b.rest_position, ref.bodies[n].rest_position) for n, b in res.bodies.items())
    head = max(abs(b.rest_heading - ref.bodies[n].rest_heading) for n, b in res.bodies.items())
    return pos, head


def check_honest(res, rep, ref):
    pos, head = true_errors(res, ref)
    assert rep.met
    assert pos <= rep.estimate_position <= rep.target_position
    assert head <= rep.estimate_heading
    if rep.target_heading is not None:
        assert rep.estimate_heading <= rep.target_heading
    return pos, head


def test_straight_slide_against_the_closed_form():
    v0, mu = 20.0, 0.75
    start = {"car": BodyState((0, 0), 0.0, (v0, 0.0))}
    res, rep = _simulate_to_accuracy(car(), start, None, Road(mu), 0.001)
    err = abs(res.bodies["car"].rest_position[0] - v0**2 / (2 * mu * G))
    assert rep.met and err <= rep.estimate_position <= 0.001
    # the report says what was chosen and what it cost
    assert rep.n_runs >= 3 and rep.runs[-1].eps == rep.settings["eps"] / 2  # the eps/v_stop check run
    assert rep.nfev == sum(r.nfev for r in rep.runs) and rep.cpu_time > 0
    assert rep.estimate_position == pytest.approx(rep.integration_position + rep.low_speed_position)
    assert rep.low_speed_position >= rep.rest_threshold_position + rep.regularisation_position
    assert rep.a_min == pytest.approx(mu * G)
    assert res.options["rtol"] == rep.settings["rtol"] and res.options["eps"] == rep.settings["eps"]
    json.dumps(rep.to_dict())
    assert SHARES == (0.25, 0.25, 0.5)


@pytest.mark.parametrize("method", ["LSODA", "RK45"])
@pytest.mark.parametrize("target", [0.01, 0.001])
def test_slide_and_spin_is_honest(method, target):
    """Slide and spin on locked wheels: the case where the straight-slide eps bound alone is 15x too small."""
    start = {"car": BodyState((-0.5, -4.1), 1.5708, (1.76, 4.95), -3.03)}
    ref = simulate_runout(car(), start, None, Road(0.75), REFERENCE)
    res, rep = _simulate_to_accuracy(car(), start, None, Road(0.75), target, math.radians(0.05),
                                    RunoutOptions(method=method))
    check_honest(res, rep, ref)


def test_articulated_rolling_and_locked_is_honest():
    veh = tractor_semitrailer()
    start = chain_states(veh, (0, 0), 0.0, (20.0, 1.0), yaw_rates=[0.3, -0.2])
    wheels = WheelSettings(default=WheelSetting("locked"),
                           wheels={"tractor/0": WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.012)})
    ref = simulate_runout(veh, start, wheels, Road(0.7), REFERENCE)
    for target in (0.01, 0.001):
        res, rep = _simulate_to_accuracy(veh, start, wheels, Road(0.7), target, math.radians(0.1))
        check_honest(res, rep, ref)


def test_free_rolling_car_chooses_a_small_v_stop():
    """a_min = f_r g ~ 0.12 m/s^2: v_stop must shrink to keep the residual roll-out within its share."""
    wheels = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.012))
    start = {"car": BodyState((0, 0), 0.0, (8.0, 0.5), 0.2)}
    ref = simulate_runout(car(), start, wheels, Road(0.75), REFERENCE)
    res, rep = _simulate_to_accuracy(car(), start, wheels, Road(0.75), 0.01)
    check_honest(res, rep, ref)
    assert rep.a_min == pytest.approx(0.012 * G)
    assert rep.settings["v_stop"] < 0.03  # below the default
    assert rep.rest_threshold_position <= SHARES[0] * 0.01 * (1 + 1e-9)


@pytest.mark.parametrize("vehicle", ["A", "B"])
def test_shipped_intersection_scene_is_honest(vehicle):
    from crashsim.impact import solve_impact
    from crashsim.scene.run import separation_states
    from crashsim.scenario import load_scenario

    sc = load_scenario(ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml")
    states = separation_states(sc, solve_impact(sc.impact))
    veh = next(v for v in sc.vehicles if v.name == vehicle)
    start = make_hitch_consistent(veh, {b.name: states[b.name] for b in veh.bodies})
    w, road = sc.runout.wheels[vehicle], sc.runout.road
    ref = simulate_runout(veh, start, w, road, REFERENCE)
    res, rep = _simulate_to_accuracy(veh, start, w, road, 0.01, math.radians(0.5), sc.runout.options)
    check_honest(res, rep, ref)
    # "1 cm" is met by the first pair of tolerances plus the check: three runs
    assert rep.n_runs == 3 and rep.settings["rtol"] == 1e-4


def test_rigid_level_and_unreachable_target():
    veh = tractor_semitrailer()
    start = chain_states(veh, (0, 0), 0.0, (15.0, 0.0), yaw_rates=[0.2, 0.2])
    res, rep = _simulate_to_accuracy(veh, start, None, Road(0.7), 0.01, level="rigid")
    assert rep.met and res.options["level"] == "rigid"
    # a micrometre with rtol stopped at 1e-4: not met, said so, and the last run is returned
    res, rep = _simulate_to_accuracy(car(), {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(0.7), 1e-6,
                                    min_rtol=1e-4)
    assert not rep.met and "min_rtol" in rep.message
    assert res.options["rtol"] == 1e-4
    assert isinstance(rep, AccuracyReport)


def test_errors():
    start = {"car": BodyState((0, 0), 0.0, (10.0, 0.0))}
    with pytest.raises(ScenarioError, match="positive"):
        _simulate_to_accuracy(car(), start, None, Road(0.7), 0.0)
    with pytest.raises(ScenarioError, match="positive"):
        _simulate_to_accuracy(car(), start, None, Road(0.7), 0.01, -1.0)
    with pytest.raises(ScenarioError, match="numerically integrated level"):
        _simulate_to_accuracy(car(), start, None, Road(0.7), 0.01, level="energy")
    no_drag = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))
    with pytest.raises(ScenarioError, match="never come to rest|no deceleration"):
        _simulate_to_accuracy(car(), start, no_drag, Road(0.7), 0.01)

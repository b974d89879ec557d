"""An approach driven by a recorder's pre-crash table (crashsim.motion.recorded, docs/approach.md).

The speed controller against closed forms (a constant deceleration, a speed held against rolling
resistance), the open-loop steering against the kinematic yaw rate ``v tan(delta) / L`` and its
sign convention, a scene file driven by its table, and the refusals of a table that cannot drive.
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import Road, RunoutOptions
from crashsim.motion.approach import simulate_approach
from crashsim.motion.approach_spec import ApproachSpec
from crashsim.motion.loads import STANDARD_GRAVITY
from crashsim.motion.recorded import RecordedDrive, rising_speed, wheel_setting_for
from crashsim.motion.wheels import WheelSetting, WheelSettings
from crashsim.report import format_approach
from crashsim.scenario import scenario_from_dict
from crashsim.units import Kind, parse
from crashsim.scene.run import simulate_approaches
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

SCENE = Path(__file__).parents[1] / "data" / "recorded_approach.toml"
CAR = Vehicle("car", (Body("car", 1500.0, 2800.0, 4.8, 1.8, (0.0, 0.0), (Axle(1.1, 1.55), Axle(-1.6, 1.55))),))
WHEELBASE = 2.7
ROLLING = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.012))
AT_IMPACT = {"car": BodyState((0.0, 0.0), 0.0, (10.0, 0.0), 0.0)}


def _approach(drive, speed=None, road=Road(0.8)):
    spec = ApproachSpec(ROLLING, speed=speed if speed is not None else drive.speed[0], recorded=drive)
    return simulate_approach(CAR, spec, AT_IMPACT, road, RunoutOptions())


def test_a_recorded_deceleration_is_followed_and_its_distance_is_the_tables():
    """25 m/s held 2 s, then 0.5 g to the impact: the CG speed stays within 0.1 m/s of the table and the
    path length is the table's integral (trapezoids of a piecewise linear speed: exact)."""
    t = np.arange(-5.0, 1e-9, 0.5)
    v = np.where(t < -3.0, 25.0, 25.0 - 0.5 * STANDARD_GRAVITY * (t + 3.0))
    a = _approach(RecordedDrive(tuple(t), speed=tuple(v)))
    assert a.mode == "recorded" and a.time_to_impact == pytest.approx(5.0, abs=1e-9)
    assert a.max_speed_error < 0.1
    assert a.speed_at_impact == pytest.approx(v[-1], abs=0.1)
    assert a.distance == pytest.approx(float(np.trapezoid(v, t)), rel=2e-3)
    # braked, not locked: the demand of 0.5 stays inside the friction of 0.8 and the wheels roll
    c = a.speed_control
    braking = c["t"] > -2.9
    assert np.all(c["demand"][braking & (c["t"] < -0.1)] == pytest.approx(0.5, abs=0.05))


def test_a_held_speed_is_held_against_rolling_resistance():
    """The model has no drive force: a flat table lowers the rolling resistance (the engine's share). Open
    loop the car would lose f_r g t = 0.59 m/s in 5 s; the controller holds it within 0.01 m/s."""
    t = np.arange(-5.0, 1e-9, 1.0)
    a = _approach(RecordedDrive(tuple(t), speed=(25.0,) * len(t)))
    assert a.max_speed_error < 0.01
    open_loop = simulate_approach(CAR, ApproachSpec(ROLLING, speed=25.0, time=5.0), AT_IMPACT, Road(0.8),
                                  RunoutOptions())
    assert 25.0 - open_loop.speed_at_impact == pytest.approx(0.012 * STANDARD_GRAVITY * 5.0, rel=0.05)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_recorded_steering_turns_at_the_kinematic_yaw_rate(sign):
    """A steering-wheel angle held at 90 deg over a ratio of 16 (5.6 deg at the road wheels) at 5 m/s: the yaw
    rate at the impact is v tan(delta) / L within 2 % (the slip angles at 0.07 g are small), left positive."""
    t = (-6.0, -5.5, 0.0)
    delta = sign * math.radians(90.0) / 16.0
    a = _approach(RecordedDrive(t, steer=(0.0, delta, delta)), speed=5.0)
    r = a.impact_states["car"].yaw_rate
    assert r == pytest.approx(a.speed_at_impact * math.tan(delta) / WHEELBASE, rel=0.02)
    assert a.steer_at_impact()  # the last angles, for a time line that carries on through the impact
    assert math.copysign(1.0, next(iter(a.steer_at_impact().values()))) == sign


def test_wheel_settings_of_a_demand():
    assert wheel_setting_for(0.5, 0.012, 0.8) == {"state": "braked", "brake": pytest.approx(0.61),
                                                  "rolling_resistance": 0.012}
    assert wheel_setting_for(0.005, 0.012, 0.8) == {"state": "rolling", "brake": 0.0, "rolling_resistance": 0.005}
    assert wheel_setting_for(-0.2, 0.012, 0.8)["rolling_resistance"] == 0.0  # no drive force
    assert wheel_setting_for(2.0, 0.012, 0.8)["brake"] == 1.0
    assert rising_speed([0, 1, 2, 3], [20.0, 19.0, 19.2, 19.25]) is None  # 0.25 m/s: within 1 km/h
    assert rising_speed([0, 1, 2, 3], [20.0, 19.0, 19.2, 19.4]) == (1, 3)


def _scene():
    return tomllib.loads(SCENE.read_text(encoding="utf-8"))


def test_a_scene_driven_by_its_table():
    from crashsim.scene.run import run_scene

    sc = simulate_approaches(scenario_from_dict(_scene(), file=str(SCENE)))
    res = run_scene(sc)
    a = sc.approaches["pickup"]
    table = _scene()["vehicles"]["pickup"]["approach"]["recorded"]["samples"]
    assert a.mode == "recorded"
    assert a.speed_at_braking == pytest.approx(parse(table[0]["speed"], Kind.SPEED, field="t"), rel=1e-12)
    assert a.speed_at_impact == pytest.approx(parse(table[-1]["speed"], Kind.SPEED, field="t"), abs=0.45)  # 1 mph
    assert a.max_speed_error < 0.45
    # the swerve: 45 deg at the wheel over 17 is the largest steer, and the pickup ends yawing left
    assert math.degrees(np.max(np.abs(a.steering["delta"]))) == pytest.approx(45.0 / 17.0, rel=1e-6)
    heading_start = a.bodies["pickup"][0, 3]
    assert heading_start < -math.radians(5.0)  # it turned left by more than 5 deg to the impact heading
    text = format_approach(sc.approaches, "US")
    assert "driven by a recorder's table" in text and "recorded speeds, followed within" in text
    d = res.to_dict()["approach"]["pickup"]
    assert d["mode"] == "recorded" and len(d["speed_control"]["t"]) == len(a.speed_control["t"])
    # the time-distance chart marks the table's samples on the speed panel, in the file's units (mph)
    import matplotlib.pyplot as plt

    from crashsim.plotting import plot_time_distance

    fig = plot_time_distance(res)
    marks = [ln for ax in fig.axes for ln in ax.lines if ln.get_gid() == "td:table:pickup"]
    assert len(marks) == 1
    assert marks[0].get_ydata()[0] == pytest.approx(45.0) and marks[0].get_ydata()[-1] == pytest.approx(24.0)
    assert "recorder's table (drives the approach)" in [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    plt.close(fig)


def _refused(edit, field, *words):
    d = _scene()
    edit(d["vehicles"]["pickup"])
    with pytest.raises(ScenarioError) as e:
        scenario_from_dict(d, file=str(SCENE))
    msg = str(e.value)
    assert field in msg and str(SCENE) in msg, msg
    for w in words:
        assert w in msg, msg
    return msg


def _samples(v):
    return v["approach"]["recorded"]["samples"]


def test_a_table_that_cannot_drive_is_refused_naming_its_key():
    def rise(v):
        _samples(v)[-1]["speed"] = "30 mph"
    _refused(rise, "vehicles.pickup.approach.recorded.samples[10].speed", '"29 mph"', '"30 mph"', "drive force")

    def partial(v):
        del _samples(v)[3]["steering"]
    _refused(partial, "recorded.samples[3].steering", "every sample or in none")

    def no_ratio(v):
        del v["approach"]["recorded"]["steering_ratio"]
    _refused(no_ratio, "recorded.steering_ratio", "ratio")

    def with_distance(v):
        v["approach"]["distance"] = "50 ft"
    _refused(with_distance, "approach.distance", "first sample")

    def unsorted(v):
        s = _samples(v)
        s[2]["time"], s[3]["time"] = s[3]["time"], s[2]["time"]
    _refused(unsorted, "recorded.samples[3].time", '"-4.0 s" follows "-3.5 s"', "increase")

    def impact_speed(v):
        v["speed"] = "24 mph"
    _refused(impact_speed, "vehicles.pickup.speed", "recorded speeds")

    def air_brakes(v):
        v["approach"]["brakes"] = {"units": [{"body": "pickup", "capacity": "20 kN"}]}
    _refused(air_brakes, "approach.brakes", "recorded speeds set the brakes")

    def with_path(v):
        v["approach"]["path"] = {"points": [["-300 ft", "0 ft"], ["50 ft", "0 ft"]]}
    _refused(with_path, "approach.path", "not both")


def test_a_wheel_the_table_steers_may_not_be_steered_by_the_file_too():
    from crashsim.scene.run import run_scene

    d = _scene()
    d["vehicles"]["pickup"]["approach"]["wheels"] = [{"select": "pickup/0", "steer": "2 deg"}]
    with pytest.raises(ScenarioError) as e:
        run_scene(scenario_from_dict(d, file=str(SCENE)))
    assert "the recorded steering steers wheel 'pickup/front/left'; the approach settings steer it too (from 0 s): " \
           "remove steer / self_steer_limit there" in str(e.value)
    assert "vehicles.pickup.approach.wheels" in str(e.value)


def test_a_table_with_a_time_after_the_impact_is_refused_by_the_schema():
    d = _scene()
    _samples(d["vehicles"]["pickup"])[-1]["time"] = "0.5 s"
    with pytest.raises(ScenarioError) as e:
        scenario_from_dict(copy.deepcopy(d), file=str(SCENE))
    assert "samples[10].time" in str(e.value)

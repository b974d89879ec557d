"""Road slope keys: read in % (or as a plain fraction, or as the angle of the surface), per zone, and refused beyond 30 % with one line."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from crashsim.schema import load_toml
from crashsim.scenario import scenario_from_dict

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
ZONE = ('\n[[runout.zones]]\nname = "ramp"\nfriction = 0.5\ngrade = "{g}"\n'
        'polygon = [["0 m", "-10 m"], ["80 m", "-10 m"], ["80 m", "-3 m"], ["0 m", "-3 m"]]\n')


def _with(text: str, grade: str, zone: str | None = None) -> str:
    out = text.replace("road_friction = 0.7\n", f'road_friction = 0.7\ngrade = "{grade}"\ncross_slope = 0.02\n', 1)
    assert out != text
    if zone is not None:
        head, sep, tail = out.partition("\n# ---- Evidence")
        out = head + ZONE.format(g=zone) + sep + tail
    return out


def test_slope_keys_are_read_for_the_road_the_zones_and_the_approach(tmp_path):
    f = tmp_path / "slope.toml"
    f.write_text(_with(SCENE.read_text(), "-6 %", zone="-8 %"))
    sc = scenario_from_dict(load_toml(f), file=str(f))
    road = sc.runout.road
    assert road.grade == pytest.approx(-0.06) and road.cross_slope == pytest.approx(0.02)
    assert road.zones[0].grade == pytest.approx(-0.08) and road.zones[0].cross_slope is None
    assert road.zone_slope(road.zones[0]) == pytest.approx((-0.08, 0.02))
    assert road.sloped


@pytest.mark.parametrize("grade, zone, key", [("-35 %", None, "runout.grade"), ("5 %", "31 %", "runout.zones[0].grade")])
def test_slope_beyond_30_percent_exits_2_with_one_line(refused_line, grade, zone, key):
    line = refused_line(_with(SCENE.read_text(), grade, zone=zone))
    assert key in line and "[-30, 30] %" in line


def test_a_slope_in_degrees_is_the_tangent_of_its_angle(tmp_path):
    """A grade written as the surface's angle is read as rise over run tan(angle): "-3.43 deg" on the road
    and "4 deg" in a zone; the same run as at the equal grade in % (the SI value is the same number)."""
    f = tmp_path / "slope.toml"
    f.write_text(_with(SCENE.read_text(), "-3.43 deg", zone="4 deg"))
    road = scenario_from_dict(load_toml(f), file=str(f)).runout.road
    assert road.grade == pytest.approx(math.tan(math.radians(-3.43)), rel=1e-12)
    assert road.zones[0].grade == pytest.approx(math.tan(math.radians(4.0)), rel=1e-12)
    g = tmp_path / "percent.toml"
    g.write_text(_with(SCENE.read_text(), f"{100 * math.tan(math.radians(-3.43))!r} %", zone=f"{math.tan(math.radians(4.0))!r}"))
    same = scenario_from_dict(load_toml(g), file=str(g)).runout.road
    assert (same.grade, same.zones[0].grade) == pytest.approx((road.grade, road.zones[0].grade), rel=1e-14)


@pytest.mark.parametrize("grade, words", [("-17 deg", ["-17 deg", "[-16.7, 16.7] deg"]),
                                          ("90 deg", ["90 deg", "between -90 and 90 deg"]),
                                          ("3 mph", ["3 mph", "is a speed", '"-3.43 deg"'])])
def test_a_slope_in_degrees_out_of_range_or_not_an_angle_exits_2_with_one_line(refused_line, grade, words):
    line = refused_line(_with(SCENE.read_text(), grade))
    assert "runout.grade" in line and all(w in line for w in words), line


def test_a_vehicle_rolling_away_down_a_grade_gets_a_hint_not_just_a_time_limit(tmp_path):
    """Free-rolling wheels on a grade steeper than their rolling resistance never stop: the time-limit
    warning says so and names the slope where the vehicle stopped, so the user looks at the wheel
    settings rather than at the solver."""
    from crashsim import api

    text = SCENE.read_text().replace('state = "locked"\n', 'state = "rolling"\ncornering_coefficient = 6.0\n'
                                                           'rolling_resistance = 0.008\n', 1)
    f = tmp_path / "roll.toml"
    f.write_text(_with(text, "-6 %").replace("[runout]\n", '[runout]\nt_max = "8 s"\n', 1))
    result = api.run(str(f))
    hints = [w for w in result.warnings if "keeps rolling" in w]
    assert len(hints) == 1 and "did not reach rest: time_limit" in hints[0] and "slope of 6.32 %" in hints[0] and "truck" in hints[0]
    level = api.run(str(f), {"runout.grade": "0 %", "runout.cross_slope": "0 %"})
    assert not any("keeps rolling" in w for w in level.warnings)

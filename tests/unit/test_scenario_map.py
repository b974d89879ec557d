"""The road layout of a scenario file, ``[[map.lines]]``: loaded in SI, validated at load (every
error names the file, the key, the value and what is allowed), documented by ``crashsim schema``,
and without effect on the physics."""

from __future__ import annotations

import copy
import dataclasses
import tomllib
from pathlib import Path

import numpy as np
import pytest

from crashsim import ScenarioError
from crashsim.cli import main
from crashsim.scenario import MAP_LINE_STYLES, MapLine, load_scenario, scenario_from_dict

ROOT = Path(__file__).resolve().parents[2]
VERGE = ROOT / "scenarios" / "scenes" / "verge_run_off.toml"
TABLE7 = ROOT / "scenarios" / "paper" / "table7.toml"


@pytest.fixture
def data():
    d = tomllib.loads(TABLE7.read_text())
    d["map"] = {"lines": [{"name": "kerb", "style": "kerb", "points": [["0 ft", "10 ft"], ["100 ft", "10 ft"]]},
                          {"style": "lane", "points": [["0 m", "0 m"], ["5 m", "0 m"], ["9 m", "1 m"]],
                           "color": "tab:orange"}]}
    return d


def error_of(d, file="case.toml") -> ScenarioError:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file=file)
    return info.value


def test_map_lines_are_loaded_in_si(data):
    sc = scenario_from_dict(data)
    kerb, lane = sc.map_lines
    assert kerb == MapLine("kerb", "kerb", kerb.points.copy(), None) != lane
    assert len({kerb, lane, MapLine("kerb", "kerb", kerb.points)}) == 2
    np.testing.assert_allclose(kerb.points, [[0.0, 3.048], [30.48, 3.048]], rtol=0, atol=1e-12)
    assert lane.name == "" and lane.style == "lane" and lane.color == "tab:orange"
    np.testing.assert_array_equal(lane.points, [[0.0, 0.0], [5.0, 0.0], [9.0, 1.0]])
    assert lane.points.shape == (3, 2) and lane.points.dtype == float
    with pytest.raises(ValueError):
        lane.points[0, 0] = 1.0  # immutable: read-only points on a frozen dataclass
    with pytest.raises(dataclasses.FrozenInstanceError):
        lane.style = "edge"


def test_no_map_is_no_lines(data):
    del data["map"]
    assert scenario_from_dict(data).map_lines == ()
    data["map"] = {}
    assert scenario_from_dict(data).map_lines == ()


def test_the_map_does_not_change_the_physics(data):
    from crashsim import solve_impact

    plain = copy.deepcopy(data)
    del plain["map"]
    a, b = scenario_from_dict(data), scenario_from_dict(plain)
    assert a.impact == b.impact and a.runout == b.runout and a.evidence == b.evidence
    ra, rb = solve_impact(a.impact), solve_impact(b.impact)
    for name in ra.bodies:
        np.testing.assert_array_equal(ra.bodies[name].delta_v, rb.bodies[name].delta_v)


def test_a_line_of_one_point(data):
    data["map"]["lines"][0]["points"] = [["0 m", "0 m"]]
    exc = error_of(data)
    assert exc.field == "map.lines[0].points"
    msg = str(exc)
    assert "case.toml" in msg and "map.lines[0].points" in msg and "at least 2 points" in msg
    assert '"0 m"' in msg  # the value given


def test_points_need_a_length_unit(data):
    data["map"]["lines"][1]["points"] = [["0 s", "0 m"], ["5 m", "0 m"]]
    exc = error_of(data)
    assert exc.field.startswith("map.lines[1].points[0]")
    assert "0 s" in str(exc)


def test_a_bad_style(data):
    data["map"]["lines"][1]["style"] = "dashed"
    exc = error_of(data)
    assert exc.field == "map.lines[1].style"
    msg = str(exc)
    assert '"dashed"' in msg and all(f"'{s}'" in msg for s in MAP_LINE_STYLES)


def test_a_bad_colour(data):
    data["map"]["lines"][1]["color"] = "notacolour"
    exc = error_of(data)
    assert exc.field == "map.lines[1].color"
    msg = str(exc)
    assert "case.toml" in msg and "'notacolour'" in msg and "hex" in msg
    for good in ("white", "#7f7f7f", "0.5", "tab:blue"):
        data["map"]["lines"][1]["color"] = good
        assert scenario_from_dict(data).map_lines[1].color == good


def test_an_unknown_key_suggests_the_nearest(data):
    data["map"]["lines"][0]["colour"] = "white"
    msg = str(error_of(data))
    assert "map.lines[0].colour" in msg and "did you mean 'color'" in msg


@pytest.mark.parametrize("bad, key", [
    ('points = [["0 m", "9 m"]]', "map.lines[0].points"),
    ('style = "dotted"', "map.lines[0].style"),
    ('color = "#12345"', "map.lines[0].color"),
])
def test_cli_exits_2_naming_the_key(tmp_path, capsys, bad, key):
    good = {"points": 'points = [["0 m", "9 m"], ["40 m", "9 m"]]', "style": 'style = "edge"', "color": ""}
    fields = dict(good)
    fields[bad.split(" ")[0]] = bad
    text = TABLE7.read_text() + "\n[[map.lines]]\n" + "\n".join(v for v in fields.values() if v) + "\n"
    f = tmp_path / "case.toml"
    f.write_text(text)
    assert main(["run", str(f)]) == 2
    out, err = capsys.readouterr()
    assert out == "" and "case.toml" in err and key in err


def test_schema_documents_the_map(capsys):
    assert main(["schema"]) == 0
    out = capsys.readouterr().out
    assert "[[map.lines]] (optional)" in out
    for key in ("map.lines[].name", "map.lines[].style", "map.lines[].points", "map.lines[].color"):
        assert key in out
    assert "'edge', 'lane', 'centre', 'kerb', 'stop', 'other'" in out
    assert "list of >= 2 points" in out


def test_the_shipped_verge_scene_has_its_layout():
    sc = load_scenario(VERGE)
    assert {ln.style for ln in sc.map_lines} >= {"edge", "centre", "kerb"}
    (zone,) = sc.runout.road.zones
    assert zone.name == "grass verge" and 0.35 <= zone.mu <= 0.45

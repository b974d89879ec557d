"""A schema that says when a key is needed, and a loader that reports every error of a file at once,
each on one line: ``cornering_coefficient`` and ``rolling_resistance`` are required where the tyres
section makes the wheels roll or brake ("required if" in the schema and in its documentation), and
errors of independent parts of a file (vehicles, the impact law, the wheels) come in one run."""

from __future__ import annotations

import copy

import pytest

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.schema import Field, ScenarioValidationError
from crashsim.scenario import scenario_from_dict, schema_document

BASE = {
    "scenario": {"title": "two cars"},
    "vehicles": {
        "A": {"position": ["0 m", "0 m"], "heading": "0 deg", "speed": "30 mph",
              "bodies": [{"name": "carA", "preset": "car-midsize"}],
              "tyres": {"state": "locked"}},
        "B": {"position": ["3.5 m", "2.0 m"], "heading": "90 deg", "speed": "20 mph",
              "bodies": [{"name": "carB", "preset": "car-midsize"}],
              "tyres": {"state": "locked"}},
    },
    "impact": {"body1": "carA", "body2": "carB", "point": ["2.57 m", "0.5 m"], "normal": "180 deg",
               "restitution": 0.1, "tangential": "no_slide"},
    "runout": {"road_friction": 0.7},
}


def _scene(**changes):
    d = copy.deepcopy(BASE)
    for path, value in changes.items():
        node = d
        *head, last = path.split("__")
        for k in head:
            node = node[k]
        if value is None:
            node.pop(last)
        else:
            node[last] = value
    return d


def test_the_base_scene_loads():
    sc = scenario_from_dict(_scene())
    assert sc.runout is not None and set(sc.runout.wheels) == {"A", "B"}


def test_rolling_wheels_need_their_tyre_data_every_missing_key_at_once():
    d = _scene(vehicles__A__tyres={"state": "rolling"}, vehicles__B__tyres={"state": "braked", "brake": 0.5},
               vehicles__B__colour="red")
    with pytest.raises(ScenarioValidationError) as info:
        scenario_from_dict(d, file="s.toml")
    got = dict(info.value.problems)
    assert set(got) == {"vehicles.A.tyres.cornering_coefficient", "vehicles.A.tyres.rolling_resistance",
                        "vehicles.B.tyres.cornering_coefficient", "vehicles.B.tyres.rolling_resistance",
                        "vehicles.B.colour"}
    assert got["vehicles.A.tyres.rolling_resistance"].startswith('missing key, required with state = "rolling"')
    assert "(or cornering_stiffness)" in got["vehicles.B.tyres.cornering_coefficient"]
    assert 'state = "braked"' in got["vehicles.B.tyres.cornering_coefficient"]
    lines = str(info.value).splitlines()
    assert len(lines) == 2 + 4  # the first problem, "4 more problems:", one line each
    assert lines[0].startswith("s.toml: ")


def test_cornering_stiffness_stands_in_for_the_coefficient():
    d = _scene(vehicles__A__tyres={"state": "rolling", "cornering_stiffness": "40000 N", "rolling_resistance": 0.012})
    assert scenario_from_dict(d).runout.wheels["A"].default.cornering_stiffness == 40000.0


def test_locked_wheels_need_no_tyre_data():
    scenario_from_dict(_scene(vehicles__A__tyres={"state": "locked"}))


def test_errors_after_the_schema_come_together():
    """A vehicle without a speed, a body towing nothing with a rear hitch, a law without its coefficient:
    three independent errors, one run."""
    d = _scene(vehicles__A__speed=None, impact__tangential="ratio")
    d["vehicles"]["B"]["bodies"][0]["rear_hitch"] = ["-2 m", "0 m"]
    with pytest.raises(ScenarioValidationError) as info:
        scenario_from_dict(d, file="s.toml")
    fields = [p for p, _ in info.value.problems]
    assert fields == ["vehicles.A.speed", "vehicles.B.bodies[0].rear_hitch", "impact.mu"]
    assert all("\n" not in text for _, text in info.value.problems)


def test_one_error_keeps_its_type_and_field():
    d = _scene(impact__tangential="friction")
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file="s.toml")
    assert not isinstance(info.value, ScenarioValidationError)
    assert info.value.field == "impact.friction"


def test_wheel_errors_of_every_vehicle_at_once():
    d = _scene()
    for v in ("A", "B"):
        d["vehicles"][v]["wheels"] = [{"select": f"car{v}/9", "state": "locked"}]
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file="s.toml")
    text = str(info.value)
    assert "carA/9" in text and "carB/9" in text


def test_the_cli_prints_every_error_one_per_line(tmp_path, capsys):
    import tomli_w

    f = tmp_path / "s.toml"
    f.write_text(tomli_w.dumps(_scene(vehicles__A__tyres={"state": "rolling"}, impact__tangential="ratio")))
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith(f"crashsim: input error: {f}: vehicles.A.tyres.cornering_coefficient: missing key")
    assert err[1] == "2 more problems:"  # the schema's two and the impact law's, found after it: one run
    assert err[2].startswith("  vehicles.A.tyres.rolling_resistance: missing key")
    assert err[3].startswith("  impact.mu: ")


def test_the_schema_documents_required_if():
    md = schema_document("markdown")
    row = next(line for line in md.splitlines() if line.startswith("| `vehicles.<vehicle>.tyres.rolling_resistance`"))
    assert "required if state = 'rolling' or 'braked'" in row
    text = schema_document("text")
    assert "required if state = 'rolling' or 'braked' (or cornering_stiffness)" in text


def test_required_if_is_for_optional_fields():
    with pytest.raises(TypeError):
        Field("x", "float", description="x", required=True, required_if=("state", ("rolling",)))
    with pytest.raises(TypeError):
        Field("x", "float", description="x", unless=("y",))


def test_evidence_and_map_errors_come_together():
    """Two evidence items on unknown bodies and a map line of no colour: three errors, one run (every
    evidence item is checked)."""
    d = _scene()
    d["evidence"] = {"rest": [{"body": "carC", "position": ["1 m", "1 m"], "tolerance": "1 m"},
                              {"body": "carD", "position": ["2 m", "2 m"], "tolerance": "1 m"}]}
    d["map"] = {"lines": [{"style": "edge", "points": [["0 m", "0 m"], ["9 m", "0 m"]], "color": "notacolour"}]}
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file="s.toml")
    text = str(info.value)
    assert [p for p, _ in info.value.problems] == ["evidence.rest[0].body", "evidence.rest[1].body",
                                                   "map.lines[0].color"], text


def _several_kinds():
    """A file with errors of every stage: the schema's (an unknown key, a value out of range, a value
    of the wrong unit), an evidence section with four bad items of three kinds, a crush item without
    its tolerance, a map line of no colour and a map north on a scene placed nowhere near a survey
    (valid: no error)."""
    d = _scene(vehicles__B__colour="red", impact__restitution=1.7)
    d["runout"]["road_friction"] = "0.7 m"
    d["evidence"] = {
        "rest": [{"body": "carC", "position": ["1 m", "1 m"], "tolerance": "1 m"},
                 {"body": "carA", "tolerance": "1 m"}],
        "delta_v": [{"body": "carZ", "value": "5 m/s", "tolerance": "1 m/s"}],
        "marks": [{"wheel": "carA/7", "points": [["0 m", "0 m"], ["5 m", "0 m"]], "tolerance": "0.3 m"}],
        "crush": [{"body": "carB", "face": "right", "ees": "30 km/h"}],
    }
    d["map"] = {"north": "15 deg",
                "lines": [{"style": "edge", "points": [["0 m", "0 m"], ["9 m", "0 m"]], "color": "notacolour"}]}
    return d


EXPECTED = {  # key -> a piece of its one line: the value as written and what is allowed
    "vehicles.B.colour": "unknown key",
    "impact.restitution": "1.7 is out of range; allowed [0, 1]",
    "runout.road_friction": "0.7 m",
    "evidence.rest[0].body": "unknown body 'carC'",
    "evidence.rest[1].position": "needs position",
    "evidence.marks[0].wheel": "no axle '7' on body 'carA'",
    "evidence.delta_v[0].body": "unknown body 'carZ'",
    "evidence.crush[0].tolerance": "give tolerance",
    "map.lines[0].color": "'notacolour' is not a colour",
}


def test_schema_and_later_errors_of_several_kinds_come_in_one_run():
    with pytest.raises(ScenarioValidationError) as info:
        scenario_from_dict(_several_kinds(), file="s.toml")
    got = dict(info.value.problems)
    assert list(got) == list(EXPECTED), str(info.value)  # the schema's first, then the later ones
    for key, piece in EXPECTED.items():
        assert piece in got[key], (key, got[key])
        assert "\n" not in got[key]


def test_a_later_error_that_repeats_a_schema_error_is_left_out():
    """A speed of the wrong unit is a schema error; the later "speed is missing" check on the same key is
    its echo and is not reported again."""
    d = _scene(vehicles__A__speed="30 m")
    d["evidence"] = {"rest": [{"body": "carC", "position": ["1 m", "1 m"], "tolerance": "1 m"}]}
    with pytest.raises(ScenarioValidationError) as info:
        scenario_from_dict(d, file="s.toml")
    fields = [p for p, _ in info.value.problems]
    assert fields.count("vehicles.A.speed") == 1
    assert "30 m" in dict(info.value.problems)["vehicles.A.speed"]


def test_the_cli_prints_errors_of_every_stage_one_per_line_and_exits_2(tmp_path, capsys):
    import tomli_w

    f = tmp_path / "s.toml"
    f.write_text(tomli_w.dumps(_several_kinds()))
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith(f"crashsim: input error: {f}: vehicles.B.colour: unknown key")
    assert err[1] == f"{len(EXPECTED) - 1} more problems:"
    assert [line.strip().split(": ")[0] for line in err[2:]] == list(EXPECTED)[1:]

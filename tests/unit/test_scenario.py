"""Scenario files: every error path names the file, the key, the value and what is allowed."""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import pytest

from crashsim import ScenarioError
from crashsim.cli import main
from crashsim.scenario import SCHEMA, load_scenario, scenario_from_dict, schema_document
from crashsim.schema import ArrayOf, Section, Table

ROOT = Path(__file__).resolve().parents[2]
TABLE7 = ROOT / "scenarios" / "paper" / "table7.toml"
TABLE3A = ROOT / "scenarios" / "paper" / "table3a.toml"


@pytest.fixture
def data():
    return tomllib.loads(TABLE7.read_text())


def error_of(d, file="case.toml") -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file=file)
    return str(info.value)


def test_loads_and_converts_to_si():
    sc = load_scenario(TABLE7)
    assert sc.title.startswith("Table 7")
    car = sc.states["car"]
    assert car.velocity == pytest.approx((0.0, 13.41), abs=1e-12)
    assert car.heading == pytest.approx(math.pi / 2)
    (x,) = sc.impact.external
    assert x.impulse == pytest.approx((0.0, -0.6 * 36222 * 0.15), abs=1e-9)
    # the trailer follows the tractor: CG 3.1 + 3.991 m behind it
    assert sc.states["trailer"].position == pytest.approx((-7.091, 0.0))


def test_unknown_key_suggests_nearest(data):
    data["impact"]["restitutoin"] = 0.1
    msg = error_of(data)
    assert "case.toml" in msg and "impact.restitutoin" in msg
    assert "restitution" in msg and "did you mean" in msg


def test_missing_key_named_with_example(data):
    del data["impact"]["restitution"]
    msg = error_of(data)
    assert "impact.restitution" in msg and "missing" in msg.lower()


def test_speed_in_kg_is_rejected(data):
    data["vehicles"]["B"]["speed"] = "1500 kg"
    msg = error_of(data)
    assert "vehicles.B.speed" in msg and "1500 kg" in msg and "speed" in msg


def test_bare_number_needs_a_unit(data):
    data["vehicles"]["B"]["speed"] = "30"
    msg = error_of(data)
    assert "vehicles.B.speed" in msg and "unit" in msg


def test_weight_in_lbf_is_a_mass(data):
    from crashsim.units import G0

    d2 = copy.deepcopy(data)
    d2["vehicles"]["B"]["bodies"][0]["mass"] = f"{1500 * G0 / 4.4482216152605} lbf"
    sc1 = scenario_from_dict(data)
    sc2 = scenario_from_dict(d2)
    m1 = sc1.vehicles[1].bodies[0].mass
    m2 = sc2.vehicles[1].bodies[0].mass
    assert m2 == pytest.approx(m1, rel=1e-12)


def test_out_of_range_restitution(data):
    data["impact"]["restitution"] = 1.5
    msg = error_of(data)
    assert "impact.restitution" in msg and "1.5" in msg and "[0, 1]" in msg


def test_moment_restitution_between_minus_one_and_zero(data):
    data["impact"]["moment_restitution"] = -0.5
    msg = error_of(data)
    assert "impact.moment_restitution" in msg and "-0.5" in msg and "-1" in msg and "[0, 1]" in msg


def test_negative_mass(data):
    data["vehicles"]["A"]["bodies"][1]["mass"] = "-6000 kg"
    msg = error_of(data)
    assert "vehicles.A.bodies[1].mass" in msg and "-6000" in msg


def test_malformed_toml_names_line(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text('[scenario]\ntitle = "x"\nspeed = = 3\n')
    with pytest.raises(ScenarioError) as info:
        load_scenario(f)
    assert "bad.toml" in str(info.value) and "line 3" in str(info.value)


def test_missing_rear_hitch(data):
    del data["vehicles"]["A"]["bodies"][0]["rear_hitch"]
    msg = error_of(data)
    assert "vehicles.A.bodies[0].rear_hitch" in msg and "tows" in msg


def test_unknown_body_suggests(data):
    data["impact"]["body1"] = "trailr"
    msg = error_of(data)
    assert "impact.body1" in msg and "'trailer'" in msg


def test_unknown_frame(data):
    data["impact"]["point_frame"] = "trailor"
    msg = error_of(data)
    assert "impact.point_frame" in msg and "did you mean 'trailer'" in msg


def test_ratio_law_needs_mu(data):
    data["impact"]["tangential"] = "ratio"
    msg = error_of(data)
    assert "impact.mu" in msg and "ratio" in msg


def test_friction_value_with_wrong_law(data):
    data["impact"]["friction"] = 0.6
    msg = error_of(data)
    assert "impact.friction" in msg and "no_slide" in msg


def test_bad_choice_lists_choices(data):
    data["impact"]["tangential"] = "slide"
    msg = error_of(data)
    assert "impact.tangential" in msg and "no_slide" in msg and "friction" in msg


def test_impulse_and_helper_both_given(data):
    data["impact"]["external_impulses"][0]["impulse"] = ["0 N s", "-1 N s"]
    msg = error_of(data)
    assert "impact.external_impulses[0]" in msg and "either" in msg


def test_helper_incomplete(data):
    del data["impact"]["external_impulses"][0]["duration"]
    msg = error_of(data)
    assert "impact.external_impulses[0]" in msg and "duration" in msg


def test_barrier_outside_the_impact_is_an_error(data):
    data["barrier"] = {"name": "wall"}
    msg = error_of(data)
    assert "barrier.name" in msg and "'wall'" in msg and "impact.body1" in msg and "[[obstacles]]" in msg


def test_barrier_impact_with_a_second_vehicle_waiting(data):
    """Two vehicles and a barrier: the vehicle of impact.body1 strikes the barrier, the other is
    not in the impact (it keeps its state and meets the scene in the run-out)."""
    data["barrier"] = {"name": "wall"}
    data["impact"]["body2"] = "wall"
    sc = scenario_from_dict(data)
    names = [v.name for v in sc.impact.vehicles]
    assert "wall" in names and len(names) == 2
    assert len(sc.vehicles) == 3


def test_non_approaching_contact_is_an_input_error(data):
    data["impact"]["normal"] = "-90 deg"
    sc = scenario_from_dict(data)
    from crashsim import solve_impact

    with pytest.raises(ScenarioError) as info:
        solve_impact(sc.impact)
    assert "impact.normal" in str(info.value) and "approaching" in str(info.value)


def test_cli_input_error_exit_code_and_message(tmp_path, capsys):
    text = TABLE3A.read_text().replace('restitution = 0.05', 'restitution = 2')
    f = tmp_path / "case.toml"
    f.write_text(text)
    code = main(["run", str(f), "--json"])
    out, err = capsys.readouterr()
    assert code == 2
    assert out == ""
    assert "case.toml" in err and "impact.restitution" in err and "2" in err


def _paths(node, prefix=""):
    if isinstance(node, Section):
        for f in node.fields:
            yield f"{prefix}{f.name}"
        for sub in node.subsections:
            if isinstance(sub, Table):
                yield from _paths(sub.entry, f"{prefix}{sub.name}.<vehicle>.")
            elif isinstance(sub, ArrayOf):
                yield from _paths(sub.entry, f"{prefix}{sub.name}[].")
            else:
                yield from _paths(sub, f"{prefix}{sub.name}.")


def test_schema_document_lists_every_key():
    doc = schema_document("text")
    paths = list(_paths(SCHEMA))
    assert len(paths) > 40
    for p in paths:
        assert p in doc, p


def test_schema_command(capsys):
    assert main(["schema", "--format", "markdown"]) == 0
    out = capsys.readouterr().out
    assert "impact.restitution" in out and "|" in out


SCENE = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


def _scene_data():
    return tomllib.loads(SCENE.read_text())


@pytest.mark.parametrize("level", ["impact", "energy", "rigid", "articulated"])
def test_runout_levels_run_end_to_end(level, capsys):
    import json

    from crashsim.reconstruct import run_scene

    d = _scene_data()
    d["runout"]["level"] = level
    scene = run_scene(scenario_from_dict(d))
    out = scene.to_dict()
    if level == "impact":
        assert scene.runout is None and "runout" not in out
        # the evidence that needs a run-out is reported as not computed, not silently dropped
        assert any(c["residual"] is None or c["residual"] == float("inf") for c in out["evidence"]["checks"])
    else:
        assert out["runout_level"] == level
        assert set(out["runout"]["bodies"]) == {"tractor", "trailer", "car"}
        for b in out["runout"]["bodies"].values():
            assert b["time_to_rest"] is not None and b["time_to_rest"] > 0


def test_accuracy_target_reports_its_estimate():
    from crashsim.reconstruct import run_scene

    d = _scene_data()
    d["runout"]["accuracy"] = "1 cm"
    scene = run_scene(scenario_from_dict(d))
    acc = scene.to_dict()["accuracy"]
    assert set(acc) == {"A", "B"}
    for rep in acc.values():
        assert rep["met"] is True
    assert "accuracy, vehicle A" in scene.report()


@pytest.mark.parametrize("extra,key,words", [
    ({"accuracy": "1 cm", "rtol": 1e-8}, "runout.rtol", "accuracy chooses"),
    ({"accuracy": "1 cm", "level": "energy"}, "runout.accuracy", "energy"),
    ({"accuracy_heading": "1 deg"}, "runout.accuracy_heading", "needs accuracy"),
    ({"load_transfer": True, "level": "rigid"}, "runout.load_transfer", "rigid"),
    # a level written is never overruled: articulated as written against load_transfer = true
    ({"load_transfer": True, "level": "articulated"}, "runout.load_transfer", "level = 'articulated'"),
    ({"level": "articulatd"}, "runout.level", "articulated"),
])
def test_runout_option_conflicts(extra, key, words):
    """Each conflict is an error naming the key (load_transfer alone, level not written, still
    asks for the load-transfer level: tests/unit/test_levels.py)."""
    d = _scene_data()
    d["runout"].update(extra)
    msg = error_of(d)
    assert key in msg and words in msg

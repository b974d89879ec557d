"""The sign convention of a lateral delta-v: stated by the file (``lateral_positive``), applied by the
check, named in its label; a lateral item without it, or the key on another component, is refused."""

from __future__ import annotations

import copy
from pathlib import Path

import pytest

from crashsim.errors import ScenarioError
from crashsim.scenario import scenario_from_dict
from crashsim.scene.run import run_scene
from crashsim.schema import load_toml

SCENE = Path(__file__).parents[2] / "scenarios" / "scenes" / "car_trailer_side_impact.toml"


def _lateral(data: dict) -> dict:
    (item,) = [x for x in data["evidence"]["delta_v"] if x.get("component") == "lateral"]
    return item


def test_a_lateral_item_without_its_convention_is_refused_naming_the_key():
    data = load_toml(SCENE)
    del _lateral(data)["lateral_positive"]
    with pytest.raises(ScenarioError) as e:
        scenario_from_dict(data, file=str(SCENE))
    msg = str(e.value)
    assert "lateral_positive" in msg and '"left"' in msg and '"right"' in msg and "SAE J670" in msg
    assert e.value.field.startswith("evidence.delta_v[") and e.value.field.endswith("].lateral_positive")


def test_the_convention_on_another_component_is_refused():
    data = load_toml(SCENE)
    (other,) = [x for x in data["evidence"]["delta_v"] if x.get("component") != "lateral"][:1]
    other["lateral_positive"] = "right"
    with pytest.raises(ScenarioError, match="applies only to component"):
        scenario_from_dict(data, file=str(SCENE))


def _lateral_check(data: dict):
    (check,) = [c for c in run_scene(scenario_from_dict(data)).evidence.checks
                if c.kind == "delta-v" and c.details["component"] == "lateral"]
    return check


def test_right_positive_flips_the_computed_component_and_the_verdict_follows():
    data = load_toml(SCENE)
    left = _lateral_check(data)
    assert left.details["lateral_positive"] == "left"
    right_data = copy.deepcopy(data)
    item = _lateral(right_data)
    item["lateral_positive"] = "right"
    right = _lateral_check(right_data)
    assert right.details["computed"] == -left.details["computed"]
    assert right.details["lateral_positive"] == "right"
    # the recorded value (12 mph, passing as "left") fails as "right": the sign is the point
    assert left.passed and not right.passed
    # the same record, entered with its sign flipped in the right-positive convention, passes again
    item["value"] = "-12 mph"
    again = _lateral_check(right_data)
    assert again.passed and again.residual == pytest.approx(-left.residual, abs=1e-12)


def test_the_default_label_names_the_convention():
    data = load_toml(SCENE)
    item = _lateral(data)
    del item["name"]
    item["lateral_positive"] = "right"
    sc = scenario_from_dict(data)
    (ev,) = [x for x in sc.evidence.delta_v if x.component == "lateral"]
    assert ev.label == "delta-v of car (lateral, + right)"

"""A yaw inertia in the wrong unit is told: "5400 lb ft^2" (pound-mass) written for a pickup whose
inertia is 5400 slug ft^2 is 32 times too small, and nothing else in the file says so (a new user's
scene ran to exit 0 with 5 evidence items failing)."""

from __future__ import annotations

import copy
import glob
from pathlib import Path

import pytest

from crashsim.scenario import load_scenario, scenario_from_dict
from crashsim.schema import load_toml

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


def _with_car_inertia(value: str):
    data = copy.deepcopy(load_toml(str(SCENE)))
    data["vehicles"]["B"]["bodies"][0]["yaw_inertia"] = value
    return scenario_from_dict(data, file="scene.toml")


def _gyration_notes(sc) -> list[str]:
    return [w for w in sc.load_warnings if "radius of gyration" in w]


def test_a_pound_mass_inertia_meant_as_slug_ft2_is_warned_of():
    right = _with_car_inertia("2000 slug ft^2")
    assert _gyration_notes(right) == []
    wrong = _with_car_inertia("2000 lb ft^2")
    notes = _gyration_notes(wrong)
    assert len(notes) == 1
    note = notes[0]
    assert note.startswith('vehicles.B.bodies[0].yaw_inertia = "2000 lb ft^2"')  # the key and the value as written
    assert "slug ft^2" in note and "pound-mass" in note
    # the warning reaches the run's warnings (what `crashsim run`, the reports and the live view print)
    from crashsim.scene.run import run_scene
    assert any("radius of gyration" in w for w in run_scene(wrong).warnings)


def test_an_inertia_beyond_half_the_diagonal_is_warned_of():
    assert len(_gyration_notes(_with_car_inertia("2e6 kg m^2"))) == 1


SCENES = sorted(glob.glob(str(ROOT / "scenarios" / "**" / "*.toml"), recursive=True)
                + glob.glob(str(ROOT / "validation" / "*" / "scene.toml")))


@pytest.mark.parametrize("path", SCENES)
def test_no_shipped_scene_is_warned_of(path):
    assert _gyration_notes(load_scenario(path)) == []

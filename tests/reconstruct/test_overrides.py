"""Inputs addressed by path: resolved against the schema, validated like file values."""

from __future__ import annotations

import copy
import math

import pytest

from crashsim.errors import ScenarioError
from crashsim.inverse_schema import FIT, UNCERTAINTY, with_inverse_sections
from crashsim.reconstruct.overrides import ScenarioOverrides, resolve_path
from crashsim.schema import document

from scenes import car_trailer


@pytest.mark.parametrize("path, kind, component", [
    ("vehicles.B.speed", "speed", None),
    ("vehicles.A.heading", "angle", None),
    ("impact.point[1]", "length", 1),
    ("impact.restitution", "dimensionless", None),
    ("runout.road_friction", "dimensionless", None),
    ("vehicles.A.tyres.brake", "dimensionless", None),
    ("vehicles.A.bodies[1].mass", "mass", None),
    ("vehicles.A.wheels[0].mu_factor", "dimensionless", None),
])
def test_paths_resolve(path, kind, component):
    t = resolve_path(path)
    assert t.kind == kind and t.component == component


@pytest.mark.parametrize("path, message", [
    ("vehicles.B.sped", "did you mean 'speed'"),
    ("impact.point", "impact.point[0]"),
    ("impact.tangential", "not a number"),
    ("vehicles.A.bodies.mass", "give the item"),
    ("vehicles.A.speed[0]", "single value"),
    ("impact.point[2]", "out of range"),
    ("runout", "ends at a table"),
])
def test_bad_paths(path, message):
    with pytest.raises(ScenarioError, match=message.replace("[", r"\[").replace("]", r"\]")):
        resolve_path(path)


def test_override_is_validated_like_a_file_value():
    data = car_trailer()
    before = copy.deepcopy(data)
    ov = ScenarioOverrides(data, ["vehicles.striking.speed", "vehicles.towing.bodies[1].mass", "impact.point[0]"])
    sc = ov.scenario([12.5, 900.0, -0.7])
    assert data == before                                  # the raw dict is not changed
    assert sc.states["striker"].velocity[1] == pytest.approx(12.5)
    assert sc.vehicles[0].bodies[1].mass == 900.0           # a preset's value overridden
    assert sc.impact.surface.point[0] == pytest.approx(-0.7)  # in the car's frame (heading 0, at the origin)
    with pytest.raises(ScenarioError) as e:
        ov.scenario([-1.0, 900.0, -0.7])
    assert e.value.field == "vehicles.striking.speed" and "out of range" in str(e.value)
    assert ov.scenario([12.5, 900.0, -0.7]) is sc            # cached
    assert math.isclose(ov.base_value(0), 11.0)


def test_missing_array_item_is_an_error():
    with pytest.raises(ScenarioError, match="names item 3"):
        ScenarioOverrides(car_trailer(), ["vehicles.towing.bodies[3].mass"])


def test_wired_schema_documents_the_new_sections():
    import crashsim.scenario as sm

    schema = with_inverse_sections(sm.SCHEMA)
    assert with_inverse_sections(schema) == schema            # idempotent
    text = document(schema)
    for key in ("fit.unknowns[].lower", "uncertainty.inputs[].distribution", "evidence.rest[].heading_sigma",
                "evidence.delta_v[].sigma", "evidence.marks[].sigma", "evidence.impact_point.sigma"):
        assert key.split(".")[-1] in text
    assert FIT.name == "fit" and UNCERTAINTY.name == "uncertainty"


def test_contact_coefficients_are_unknowns_too():
    """Fit unknowns and Monte Carlo inputs reach the contact model of later impacts: the scene
    default and a pair's override, with the file's ranges."""
    assert resolve_path("contacts.restitution").kind == "dimensionless"
    assert resolve_path("contacts.velocity_threshold").kind == "speed"
    data = car_trailer()
    data["contacts"] = {"friction": 0.5, "pairs": [{"first": "trailer", "second": "striker", "restitution": 0.1}]}
    ov = ScenarioOverrides(data, ["contacts.friction", "contacts.pairs[0].restitution"])
    sc = ov.scenario([0.3, 0.35])
    assert sc.runout.contact.friction == pytest.approx(0.3)
    assert sc.runout.pair_contact[("trailer", "striker")].restitution == pytest.approx(0.35)
    with pytest.raises(ScenarioError) as e:
        ov.scenario([0.3, 1.5])
    assert "contacts.pairs[0].restitution" in str(e.value) and "1.5" in str(e.value)

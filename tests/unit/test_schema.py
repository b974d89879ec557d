"""Unit tests of crashsim.schema: validation messages, defaults, TOML loading, documentation."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from crashsim.errors import ScenarioError
from crashsim.schema import (
    ArrayOf,
    Field,
    ScenarioValidationError,
    Section,
    Table,
    document,
    load_toml,
    validate,
)
from crashsim.units import G0, Kind

LB = 0.45359237

BODY = Section(
    "body",
    [
        Field("mass", Kind.MASS, minimum=0, exclusive_minimum=True, example="9500 kg",
              description="Mass of the body"),
        Field("yaw_inertia", Kind.YAW_INERTIA, minimum=0, exclusive_minimum=True,
              description="Yaw moment of inertia about the centre of mass"),
        Field("cg", Kind.LENGTH, n=2, default=["0 m", "0 m"],
              description="Centre of mass in the vehicle frame"),
    ],
    description="One rigid body of the vehicle",
)
VEHICLE = Section(
    "vehicle",
    [
        Field("speed", Kind.SPEED, minimum=0, example="30 mph",
              description="Initial speed along the heading"),
        Field("heading", "angle", default="0 deg", description="Initial heading"),
        Field("loaded", "bool", default=False, description="Whether the trailer is loaded"),
        Field("axles", "int", minimum=1, default=2, description="Number of axles"),
        Field("label", "str", required=False, description="Label used in plots"),
    ],
    subsections=[Table("bodies", BODY, min_entries=1, description="Bodies, tractor first")],
    description="One vehicle",
)
CONSTRAINT = Section(
    "constraint",
    [
        Field("kind", choices=("hitch", "barrier"), description="What the constraint is"),
        Field("friction", "float", minimum=0, default=0.6, description="Friction coefficient"),
    ],
    description="One extra constraint",
)
IMPACT = Section(
    "impact",
    [
        Field("restitution", "float", minimum=0, maximum=1,
              description="Coefficient of restitution e"),
        Field("model", choices=("rigid", "sticking"), default="rigid", description="Impact model"),
        Field("normal", "dimensionless", n=2, default=["1", "0"],
              description="Crush-surface normal | world frame"),
    ],
    subsections=[ArrayOf("constraints", CONSTRAINT, required=False, max_items=2,
                         description="Extra constraints")],
    description="Impact parameters",
)
OUTPUT = Section(
    "output",
    [Field("units", choices=("SI", "US"), default="SI", description="Units of the report")],
    required=False,
    description="Output options",
)
BARRIER = Section(
    "barrier",
    [Field("angle", Kind.ANGLE, description="Barrier angle")],
    required=False,
    description="A rigid barrier, if the case has one",
)
SCHEMA = Section(
    "scenario",
    [Field("title", "str", description="Title of the case")],
    subsections=[
        Table("vehicles", VEHICLE, min_entries=1, description="The vehicles, by name"),
        IMPACT,
        OUTPUT,
        BARRIER,
    ],
    description="crashsim scenario",
)


def good() -> dict:
    return {
        "title": "Table 2, loaded",
        "vehicles": {
            "A": {
                "speed": "30 mph",
                "heading": "90 deg",
                "bodies": {
                    "tractor": {"mass": "9500 kg", "yaw_inertia": "21000 kg m^2"},
                    "trailer": {"mass": "44096 lbf", "yaw_inertia": "110550 ft-lb-s^2",
                                "cg": ["-6 m", "0 ft"]},
                },
            }
        },
        "impact": {"restitution": 0.05, "constraints": [{"kind": "barrier", "friction": 0.2}]},
    }


def problems(data: dict, schema: Section = SCHEMA,
             file: str | None = None) -> ScenarioValidationError:
    with pytest.raises(ScenarioValidationError) as info:
        validate(data, schema, file=file)
    return info.value


def only(data: dict) -> str:
    """The single problem in ``data``, as 'path: message'."""
    exc = problems(data)
    assert len(exc.problems) == 1, exc.problems
    return str(exc)


# ------------------------------------------------------------------------------- valid


def test_valid_document_is_converted_to_si_with_defaults_filled():
    out = validate(good(), SCHEMA)
    a = out["vehicles"]["A"]
    assert a["speed"] == pytest.approx(13.4112)
    assert a["heading"] == pytest.approx(math.pi / 2)
    assert (a["loaded"], a["axles"], a["label"]) == (False, 2, None)
    assert list(a["bodies"]) == ["tractor", "trailer"]
    tractor, trailer = a["bodies"]["tractor"], a["bodies"]["trailer"]
    assert tractor == {"mass": 9500.0, "yaw_inertia": 21000.0, "cg": (0.0, 0.0)}
    assert trailer["mass"] == pytest.approx(44096 * LB)  # a weight read as mass
    assert trailer["yaw_inertia"] == pytest.approx(110550 * 1.3558179483314, rel=1e-12)
    assert trailer["cg"] == (-6.0, 0.0)
    assert out["impact"] == {
        "restitution": 0.05,
        "model": "rigid",
        "normal": (1.0, 0.0),
        "constraints": [{"kind": "barrier", "friction": 0.2}],
    }
    assert out["output"] == {"units": "SI"}  # optional section, all defaults
    assert out["barrier"] is None  # optional section with a required key
    assert list(out) == ["title", "vehicles", "impact", "output", "barrier"]


def test_optional_array_absent_is_empty_and_optional_section_present_is_validated():
    data = good()
    del data["impact"]["constraints"]
    data["barrier"] = {"angle": "15 deg"}
    out = validate(data, SCHEMA)
    assert out["impact"]["constraints"] == []
    assert out["barrier"] == {"angle": pytest.approx(math.radians(15))}


def test_kind_may_be_given_as_its_string_value():
    assert Field("v", "speed", description="d").kind is Kind.SPEED


def test_input_is_not_modified():
    data = good()
    validate(data, SCHEMA)
    assert data == good()


# ------------------------------------------------------------------------------ errors


def test_unknown_key_suggests_the_nearest_valid_key():
    data = good()
    data["impact"]["restitutoin"] = 0.05
    assert only(data) == (
        "impact.restitutoin: unknown key; did you mean 'restitution'? "
        "Valid keys: restitution, model, normal, constraints"
    )


def test_unknown_key_without_a_close_match_lists_the_valid_keys():
    data = good()
    data["colour"] = "red"
    assert only(data) == (
        "colour: unknown key; valid keys: title, vehicles, impact, output, barrier"
    )


def test_unknown_key_inside_a_named_table_entry():
    data = good()
    data["vehicles"]["A"]["bodies"]["tractor"]["mas"] = "1 kg"
    assert only(data).startswith(
        "vehicles.A.bodies.tractor.mas: unknown key; did you mean 'mass'? Valid keys: mass,"
    )


def test_missing_required_key_names_its_description_and_an_example():
    data = good()
    del data["vehicles"]["A"]["speed"]
    assert only(data) == (
        "vehicles.A.speed: missing required key: Initial speed along the heading "
        '(speed [m/s]); e.g. speed = "30 mph"'
    )


def test_missing_required_key_without_a_written_example_uses_the_kind_example():
    data = good()
    del data["vehicles"]["A"]["bodies"]["tractor"]["yaw_inertia"]
    assert only(data) == (
        "vehicles.A.bodies.tractor.yaw_inertia: missing required key: Yaw moment of inertia "
        'about the centre of mass (yaw inertia [kg m^2]); e.g. yaw_inertia = "21000 kg m^2"'
    )


def test_missing_plain_and_choice_keys():
    data = good()
    del data["title"]
    del data["impact"]["restitution"]
    data["impact"]["constraints"] = [{}]
    exc = problems(data)
    assert exc.problems == (
        ("title", "missing required key: Title of the case (string)"),
        ("impact.restitution", "missing required key: Coefficient of restitution e (number)"),
        ("impact.constraints[0].kind", "missing required key: What the constraint is "
                                       "(one of 'hitch', 'barrier'); e.g. kind = \"hitch\""),
    )


@pytest.mark.parametrize(
    ("remove", "message"),
    [
        ("vehicles", "vehicles: missing required table of named entries [vehicles.<name>]: "
                     "The vehicles, by name"),
        ("impact", "impact: missing required table [impact]: Impact parameters"),
    ],
)
def test_missing_required_sections(remove, message):
    data = good()
    del data[remove]
    assert only(data) == message


def test_missing_required_array_of_tables():
    schema = Section("s", subsections=[ArrayOf("points", CONSTRAINT)], description="s")
    assert str(problems({}, schema)) == (
        "points: missing required array of tables [[points]]: One extra constraint"
    )


def test_speed_given_in_kg_is_rejected():
    data = good()
    data["vehicles"]["A"]["speed"] = "1500 kg"
    assert only(data) == (
        'vehicles.A.speed: "1500 kg" is a mass; expected a speed (m/s, km/h, mph, ft/s)'
    )


def test_bare_number_where_a_unit_is_required():
    data = good()
    data["vehicles"]["A"]["speed"] = 30
    assert only(data) == (
        'vehicles.A.speed: 30 has no unit; write a speed such as "30 mph" or "13.41 m/s"'
    )


def test_vector_component_errors_name_the_component():
    data = good()
    data["vehicles"]["A"]["bodies"]["trailer"]["cg"] = ["-6 m", "0"]
    assert only(data) == (
        'vehicles.A.bodies.trailer.cg[1]: "0" has no unit; write a length such as "12.5 m" '
        'or "41 ft"'
    )
    data["vehicles"]["A"]["bodies"]["trailer"]["cg"] = ["-6 m"]
    assert only(data) == 'vehicles.A.bodies.trailer.cg: ["-6 m"] has 1 component; expected 2'


def test_out_of_range_plain_number():
    data = good()
    data["impact"]["restitution"] = 1.5
    assert only(data) == "impact.restitution: 1.5 is out of range; allowed [0, 1]"


def test_out_of_range_quantity_shows_the_range_in_the_users_unit_and_in_si():
    data = good()
    data["vehicles"]["A"]["bodies"]["tractor"]["mass"] = "-5 lbf"
    assert only(data) == (
        'vehicles.A.bodies.tractor.mass: "-5 lbf" is out of range; allowed (0, inf) lbf ((0, inf) kg)'
    )
    data["vehicles"]["A"]["bodies"]["tractor"]["mass"] = "-5 g"  # an SI unit other than the display one
    assert only(data) == 'vehicles.A.bodies.tractor.mass: "-5 g" is out of range; allowed (0, inf) g ((0, inf) kg)'



def test_exclusive_minimum_rejects_the_bound_itself():
    data = good()
    data["vehicles"]["A"]["bodies"]["tractor"]["mass"] = "0 kg"
    assert only(data) == (
        'vehicles.A.bodies.tractor.mass: "0 kg" is out of range; allowed (0, inf) kg'
    )


def test_inclusive_bounds_accept_the_bounds():
    for e in (0, 1, 0.0, 1.0):
        data = good()
        data["impact"]["restitution"] = e
        got = validate(data, SCHEMA)["impact"]["restitution"]
        assert got == e and type(got) is float  # a TOML integer becomes a float


def test_exclusive_maximum():
    schema = Section("s", [Field("f", "float", maximum=1, exclusive_maximum=True,
                                 description="d")], description="s")
    assert validate({"f": 0.999}, schema) == {"f": 0.999}
    assert str(problems({"f": 1.0}, schema)) == "f: 1.0 is out of range; allowed (-inf, 1)"


@given(e=st.floats(allow_nan=False, allow_infinity=False))
def test_range_check_matches_the_interval(e):
    data = good()
    data["impact"]["restitution"] = e
    if 0 <= e <= 1:
        assert validate(data, SCHEMA)["impact"]["restitution"] == e
    else:
        with pytest.raises(ScenarioError, match="is out of range; allowed \\[0, 1\\]"):
            validate(data, SCHEMA)


def test_bad_choice_lists_the_choices_and_suggests():
    data = good()
    data["impact"]["model"] = "rigd"
    assert only(data) == (
        "impact.model: \"rigd\" is not a valid choice; did you mean 'rigid'? "
        "allowed: 'rigid', 'sticking'"
    )
    data["impact"]["model"] = "plastic"
    assert only(data) == (
        "impact.model: \"plastic\" is not a valid choice; allowed: 'rigid', 'sticking'"
    )


@pytest.mark.parametrize(
    ("key", "value", "message"),
    [
        ("title", 3, "title: 3 is not a string; write it in quotes"),
        ("vehicles.A.loaded", "yes",
         'vehicles.A.loaded: "yes" is not a boolean; write true or false'),
        ("vehicles.A.loaded", 1, "vehicles.A.loaded: 1 is not a boolean; write true or false"),
        ("vehicles.A.axles", 2.5, "vehicles.A.axles: 2.5 is not an integer"),
        ("vehicles.A.axles", True, "vehicles.A.axles: true is not an integer"),
        ("vehicles.A.axles", 0, "vehicles.A.axles: 0 is out of range; allowed [1, inf)"),
        ("impact.restitution", "0.05", 'impact.restitution: "0.05" is not a number; write a '
                                       "plain number such as 0.6 (no quotes, no unit)"),
        ("impact.restitution", False, "impact.restitution: false is not a number; write a "
                                      "plain number such as 0.6 (no quotes, no unit)"),
        ("impact.restitution", math.nan, "impact.restitution: nan is not a finite number"),
        ("impact.model", 1, "impact.model: 1 is not a string; write it in quotes"),
        ("vehicles", "A", 'vehicles: "A" is not a table; write [vehicles.<name>]'),
        ("impact", 3, "impact: 3 is not a table; write [impact] and its keys"),
        ("impact.constraints", {"kind": "hitch"},
         "impact.constraints: a table is not an array of tables; write [[impact.constraints]]"),
        ("vehicles.A.bodies.tractor", 5, "vehicles.A.bodies.tractor: 5 is not a table; "
                                         "write [vehicles.A.bodies.tractor] and its keys"),
    ],
)
def test_type_errors(key, value, message):
    data = good()
    *parents, last = key.split(".")
    target = data
    for part in parents:
        target = target[part]
    target[last] = value
    assert only(data) == message


def test_named_table_needs_its_minimum_number_of_entries():
    data = good()
    data["vehicles"]["A"]["bodies"] = {}
    assert only(data) == (
        "vehicles.A.bodies: 0 entries; at least 1 required, each as "
        "[vehicles.A.bodies.<name>]"
    )


def test_array_of_tables_item_count_and_item_paths():
    data = good()
    data["impact"]["constraints"] = [{"kind": "hitch"}, {"kind": "barrier"}, {"kind": "hitchh"}]
    exc = problems(data)
    assert exc.problems == (
        ("impact.constraints", "3 items; allowed 0 to 2"),
        ("impact.constraints[2].kind", "\"hitchh\" is not a valid choice; did you mean "
                                       "'hitch'? allowed: 'hitch', 'barrier'"),
    )


def test_every_problem_is_reported_first_one_is_the_main_message():
    data = good()
    data["impact"]["restitutoin"] = 0.05
    data["impact"]["restitution"] = 1.5
    data["vehicles"]["A"]["speed"] = "1500 kg"
    data["vehicles"]["B"] = {"speed": "30", "bodies": {"x": {"mass": "1 kg"}}}
    exc = problems(data, file="case.toml")
    assert isinstance(exc, ScenarioError) and isinstance(exc, ValueError)
    assert exc.file == "case.toml"
    assert exc.field == "vehicles.A.speed"
    assert [p for p, _ in exc.problems] == [
        "vehicles.A.speed",
        "vehicles.B.speed",
        "vehicles.B.bodies.x.yaw_inertia",
        "impact.restitutoin",
        "impact.restitution",
    ]
    lines = str(exc).splitlines()
    assert lines[0] == (
        'case.toml: vehicles.A.speed: "1500 kg" is a mass; expected a speed '
        "(m/s, km/h, mph, ft/s)"
    )
    assert lines[1] == "4 more problems:"
    assert lines[2] == (
        '  vehicles.B.speed: "30" has no unit; write a speed such as "30 mph" or "13.41 m/s"'
    )
    assert lines[-1] == "  impact.restitution: 1.5 is out of range; allowed [0, 1]"
    assert len(lines) == 6


def test_weight_in_lbf_is_accepted_as_mass():
    data = good()
    data["vehicles"]["A"]["bodies"]["tractor"]["mass"] = "20945 lbf"
    mass = validate(data, SCHEMA)["vehicles"]["A"]["bodies"]["tractor"]["mass"]
    assert mass == pytest.approx(20945 * 4.4482216152605 / G0, rel=1e-13)


# ----------------------------------------------------------------- schema definition


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(kind="float", description=" "), "a description is required"),
        (dict(kind="float", description="d", required=True, default=1.0),
         "a required field cannot have a default"),
        (dict(description="d"), "give kind="),
        (dict(kind="str", choices=("a",), description="d"), "choices= goes with kind='choice'"),
        (dict(kind="choice", description="d"), "choices= goes with kind='choice'"),
        (dict(kind="str", minimum=0, description="d"), "minimum/maximum need a numeric"),
        (dict(kind="bool", n=2, description="d"), "n= \\(a vector\\) needs"),
        (dict(kind="velocity", description="d"), "unknown kind 'velocity'"),
    ],
)
def test_schema_definition_mistakes_are_type_errors(kwargs, message):
    with pytest.raises(TypeError, match=message):
        Field("f", **kwargs)


def test_section_rejects_repeated_keys():
    with pytest.raises(TypeError, match=r"repeated keys \['a'\]"):
        Section("s", [Field("a", "str", description="d")],
                subsections=[Section("a", description="d")], description="s")


def test_invalid_default_is_a_schema_bug_not_a_scenario_error():
    schema = Section("s", [Field("v", Kind.SPEED, default="0", description="d")],
                     description="s")
    with pytest.raises(ValueError, match='schema default of v is invalid: "0" has no unit') as info:
        validate({}, schema)
    assert not isinstance(info.value, ScenarioError)


def test_optional_field_and_default_flags():
    assert Field("a", "float", description="d").required is True
    assert Field("a", "float", default=1.0, description="d").required is False
    assert Field("a", "float", required=False, description="d").required is False


# -------------------------------------------------------------------------------- TOML


SCENARIO_TOML = """\
title = "Table 2, loaded"

[vehicles.A]
speed = "30 mph"

[vehicles.A.bodies.tractor]
mass = "20945 lbf"
yaw_inertia = "15478 ft-lb-s^2"

[impact]
restitution = 0.05

[[impact.constraints]]
kind = "barrier"
"""


def test_load_toml_and_validate(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(SCENARIO_TOML, encoding="utf-8")
    out = validate(load_toml(path), SCHEMA, file=str(path))
    assert out["vehicles"]["A"]["bodies"]["tractor"]["mass"] == pytest.approx(20945 * LB)
    assert out["impact"]["constraints"] == [{"kind": "barrier", "friction": 0.6}]


def test_validation_error_names_the_file(tmp_path):
    path = tmp_path / "case.toml"
    path.write_text(SCENARIO_TOML.replace("restitution", "restitutoin"), encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        validate(load_toml(path), SCHEMA, file=str(path))
    assert str(info.value).startswith(
        f"{path}: impact.restitutoin: unknown key; did you mean 'restitution'?"
    )
    assert info.value.file == str(path)


def test_malformed_toml_names_file_line_and_column(tmp_path):
    path = tmp_path / "bad.toml"
    path.write_text('title = "x"\n[impact]\nrestitution 0.05\n', encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        load_toml(path)
    assert str(info.value) == (
        f"{path}: invalid TOML at line 3, column 13: Expected '=' after a key in a "
        "key/value pair"
    )
    assert info.value.file == str(path)


def test_duplicate_key_in_toml_names_the_line(tmp_path):
    path = tmp_path / "dup.toml"
    path.write_text("[impact]\nrestitution = 0.05\nrestitution = 0.1\n", encoding="utf-8")
    with pytest.raises(ScenarioError, match="invalid TOML at line 3, column 18: Cannot overwrite"):
        load_toml(path)


def test_unterminated_toml_at_end_of_file(tmp_path):
    path = tmp_path / "eof.toml"
    path.write_text('title = "x', encoding="utf-8")
    with pytest.raises(ScenarioError) as info:
        load_toml(str(path))
    assert str(info.value) == f"{path}: invalid TOML at the end of the file: Unterminated string"


def test_missing_and_non_utf8_files(tmp_path):
    with pytest.raises(ScenarioError) as info:
        load_toml(tmp_path / "nope.toml")
    missing = tmp_path / "nope.toml"
    assert str(info.value) == f"{missing}: cannot read the file: No such file or directory"
    path = tmp_path / "latin1.toml"
    path.write_bytes('title = "Caf\xe9"\n'.encode("latin-1"))
    with pytest.raises(ScenarioError, match="not UTF-8 text"):
        load_toml(path)


# ----------------------------------------------------------------------- documentation


def test_text_documentation_lists_every_key_from_the_same_objects():
    text = document(SCHEMA)
    assert text.startswith("crashsim scenario\n=================\n")
    for expected in [
        "[vehicles.<name>]",
        "  vehicles.<name>.speed\n"
        '      speed [m/s]; accepts m/s, km/h, mph, ft/s; e.g. "30 mph", "13.41 m/s"\n'
        "      required\n"
        "      allowed [0, inf) m/s\n"
        '      Initial speed along the heading (example: "30 mph")',
        "[vehicles.<name>.bodies.<name>]",
        "vehicles.<name>.bodies.<name>.mass",
        "mass [kg]; accepts kg, t, lb, slug (= lbf s^2/ft, lb-s^2/ft); or a weight in N, kN, lbf, kip",
        "allowed (0, inf) kg",
        'optional, default ["0 m", "0 m"]',
        "list of 2 x length [m]",
        "[[impact.constraints]] (optional)",
        "impact.constraints[].kind\n      one of 'hitch', 'barrier'\n      required",
        "optional, default 0.6",
        "allowed [0, 1]",
        "[output] (optional)",
        'optional, default "SI"',
        "optional, default false",
        "Coefficient of restitution e",
    ]:
        assert expected in text, expected


def test_every_field_appears_once_in_the_documentation():
    text = document(SCHEMA)
    for path in ["title", "vehicles.<name>.heading", "vehicles.<name>.label",
                 "vehicles.<name>.bodies.<name>.cg", "impact.normal", "impact.model",
                 "output.units", "barrier.angle"]:
        assert text.count(f"  {path}\n") == 1, path


def test_markdown_documentation():
    md = document(SCHEMA, "markdown")
    assert md.startswith("# crashsim scenario\n")
    assert "## `[vehicles.<name>]`\n\nThe vehicles, by name\n" in md
    assert "| Key | Type | Required | Allowed | Description |" in md
    assert ("| `impact.restitution` | number | required | [0, 1] | "
            "Coefficient of restitution e |") in md
    assert "Crush-surface normal \\| world frame" in md  # pipes escaped in cells
    assert "## `[[impact.constraints]]` (optional)" in md


def test_document_rejects_unknown_format():
    with pytest.raises(ValueError, match="unknown format 'html'"):
        document(SCHEMA, "html")  # type: ignore[arg-type]

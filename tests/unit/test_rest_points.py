"""Rest evidence from measured points of a body ([[evidence.rest]] points): file keys, checks, errors.

Every bad input is a one-line ScenarioError naming the file, the key and the value.
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from crashsim import ScenarioError
from crashsim.geometry import rotate
from crashsim.evidence.checks import Evidence, evaluate_evidence, named_body_points
from crashsim.scenario import load_scenario, scenario_from_dict

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"
TABLE7 = ROOT / "scenarios" / "paper" / "table7.toml"


@pytest.fixture(scope="module")
def car():
    """The scene's car body (car-midsize preset: length, width, outline centre, axles "front" and "rear")."""
    sc = load_scenario(SCENE)
    return next(b for v in sc.vehicles for b in v.bodies if b.name == "car")


def _m(v) -> str:
    return f"{float(v)!r} m"


def _with_points(points, **extra) -> dict:
    d = tomllib.loads(SCENE.read_text())
    item = {"body": "car", "tolerance": "0.5 m", "points": points, **extra}
    d["evidence"]["rest"] = [item]
    return d


def _measured(car, names, position, heading_deg):
    named = named_body_points(car)
    body = np.array([named[n] for n in names])
    world = np.asarray(position) + rotate(body, math.radians(heading_deg))
    return [{"at": n, "position": [_m(x), _m(y)]} for n, (x, y) in zip(names, world)]


def error_of(d, file="case.toml") -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file=file)
    msg = str(info.value)
    assert "\n" not in msg, msg
    return msg


def test_corners_give_the_cg_and_heading(car):
    pts = _measured(car, ["front_left", "front_right", "rear_left", "rear_right"], (-7.3, -0.7), -25.0)
    sc = scenario_from_dict(_with_points(pts, heading_tolerance="10 deg"), file="case.toml")
    (r,) = sc.evidence.rest
    assert r.position == pytest.approx((-7.3, -0.7), abs=1e-9)
    assert r.heading == pytest.approx(math.radians(-25.0), abs=1e-12)
    assert r.heading_tolerance == pytest.approx(math.radians(10.0))
    assert r.registration.rms < 1e-9 and r.registration.labels[0] == "front_left"


def test_tyre_contacts_by_axle_name_or_index_and_body_points(car):
    named = named_body_points(car)
    # the preset names its axles "front" and "rear"; axle1 and axle2 name them too
    assert named["front/left"] == named["axle1/left"] == (1.10, 0.775)
    assert named["rear/right"] == named["axle2/right"] == (-1.60, -0.775)
    pts = _measured(car, ["front/left", "axle2/right"], (3.0, 4.0), 120.0)
    c, s = math.cos(math.radians(120)), math.sin(math.radians(120))
    pts.append({"body_point": ["2.55 m", "0 m"], "position": [_m(3.0 + 2.55 * c), _m(4.0 + 2.55 * s)]})  # mid-front
    sc = scenario_from_dict(_with_points(pts), file="case.toml")
    (r,) = sc.evidence.rest
    assert r.position == pytest.approx((3.0, 4.0), abs=1e-9)
    assert r.heading is None  # no heading_tolerance: the derived heading is not checked
    assert r.registration.heading == pytest.approx(math.radians(120.0), abs=1e-12)
    assert r.registration.labels[2] == "(2.55 m, 0 m)"


def test_the_check_reports_the_registration(car):
    """The residual is the CG distance and heading difference as for a measured CG; details add the fit."""
    pts = _measured(car, ["front_left", "rear_left", "rear_right"], (-7.3, -0.7), -25.0)
    pts[0]["position"][0] = _m(float(pts[0]["position"][0].split()[0]) + 0.06)  # a measurement error
    sc = scenario_from_dict(_with_points(pts, heading_tolerance="10 deg"), file="case.toml")
    (ev,) = sc.evidence.rest
    reg = ev.registration
    assert 0.0 < reg.rms < 0.06

    class Rest:  # a computed rest pose exactly at the measured CG, 5 deg off in heading
        rest_position = (-7.3, -0.7)
        rest_heading = math.radians(-20.0)
        time_to_rest = 1.0

    class Run:
        bodies = {"car": Rest()}
        wheels = {}
        status = "rest"

    rep = evaluate_evidence(Evidence(rest=sc.evidence.rest), None, {"B": Run()}, (0.0, 0.0))
    pos, head = rep.checks
    assert pos.residual == pytest.approx(float(np.hypot(*(np.asarray(reg.position) - (-7.3, -0.7)))), abs=1e-12)
    assert head.residual == pytest.approx(math.radians(-20.0) - reg.heading, abs=1e-12)
    assert pos.details["registration"]["rms"] == reg.rms
    assert [p["at"] for p in pos.details["registration"]["points"]] == ["front_left", "rear_left", "rear_right"]


def test_report_of_a_scene_gives_the_derived_pose(car):
    from crashsim.scene.run import _format_registrations

    pts = _measured(car, ["front_left", "rear_right"], (-7.3, -0.7), -25.0)
    sc = scenario_from_dict(_with_points(pts), file="case.toml")
    text = _format_registrations(sc.evidence, "US")
    assert "rest of car: CG (-23.95 ft, -2.297 ft), heading -25.0 deg from 2 measured points" in text
    assert "RMS misfit 0 ft" in text


@pytest.mark.parametrize("points, extra, key, words", [
    ([{"at": "front_left", "position": ["1 m", "2 m"]}], {}, "evidence.rest[0].points",
     ["1 measured point", "at least two"]),
    ([{"at": "front_left", "position": ["1 m", "2 m"]}, {"at": "rear_left", "position": ["-3 m", "2 m"]}],
     {"position": ["0 m", "0 m"]}, "evidence.rest[0].points", ["either position", "not both"]),
    ([{"at": "front_lft", "position": ["1 m", "2 m"]}, {"at": "rear_left", "position": ["-3 m", "2 m"]}],
     {}, "evidence.rest[0].points[0].at", ["'front_lft'", "did you mean 'front_left'", "Named points: front_left",
                                           "axle1/left", "front/left"]),
    ([{"at": "front_left", "position": ["1 m", "2 m"]}, {"at": "rear_left", "position": ["1 m", "2 m"]}],
     {}, "evidence.rest[0].points", ["measured points coincide", "front_left at (1 m, 2 m)"]),
    ([{"at": "front_left", "position": ["1 m", "2 m"]}, {"at": "front_left", "position": ["5 m", "2 m"]}],
     {}, "evidence.rest[0].points", ["body points coincide"]),
    ([{"at": "front_left", "body_point": ["1 m", "0 m"], "position": ["1 m", "2 m"]},
      {"at": "rear_left", "position": ["-3 m", "2 m"]}], {}, "evidence.rest[0].points[0]", ["not both"]),
    ([{"position": ["1 m", "2 m"]}, {"at": "rear_left", "position": ["-3 m", "2 m"]}], {},
     "evidence.rest[0].points[0]", ["give at", "or body_point"]),
    ([{"at": "front_left", "position": ["1 m", "2 m"]}, {"at": "rear_left", "position": ["-3 m", "2 m"]}],
     {"heading": "10 deg", "heading_tolerance": "5 deg"}, "evidence.rest[0].heading", ["heading = 10 deg", "points"]),
    ([], {}, "evidence.rest[0].position", ["needs position", "or points"]),
])
def test_bad_points_are_one_line_errors(points, extra, key, words):
    msg = error_of(_with_points(points, **extra))
    assert msg.startswith(f"case.toml: {key}: "), msg
    for w in words:
        assert w in msg, (w, msg)


def test_corners_of_a_body_without_length_and_width():
    d = tomllib.loads(TABLE7.read_text())  # the paper's car: mass and yaw inertia only
    d["evidence"] = {"rest": [{"body": "car", "tolerance": "1 m", "points": [
        {"at": "front_right", "position": ["1 m", "2 m"]}, {"at": "rear_right", "position": ["-3 m", "2 m"]}]}]}
    msg = error_of(d, file="t7.toml")
    assert msg.startswith("t7.toml: evidence.rest[0].points[0].at: at = 'front_right' is a corner")
    assert "no length and width" in msg and "body_point" in msg
    # body points work for any body
    d["evidence"]["rest"][0]["points"] = [{"body_point": ["2 m", "0 m"], "position": ["1 m", "2 m"]},
                                          {"body_point": ["-2 m", "0 m"], "position": ["-3 m", "2 m"]}]
    (r,) = scenario_from_dict(d, file="t7.toml").evidence.rest
    assert r.position == pytest.approx((-1.0, 2.0)) and r.registration.heading == pytest.approx(0.0, abs=1e-15)


def test_schema_documents_the_points():
    from crashsim.scenario import schema_document

    doc = schema_document()
    assert "evidence.rest[].points[].at" in doc and "axle1, axle2" in doc and "body_point" in doc


def test_the_cli_exits_2_with_the_message(tmp_path, capsys):
    from crashsim.cli import main

    import tomli_w

    d = _with_points([{"at": "front_left", "position": ["1 m", "2 m"]}])
    f = tmp_path / "one_point.toml"
    f.write_text(tomli_w.dumps(d))
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err
    assert f"{f}: evidence.rest[0].points: 1 measured point" in err


def test_a_large_rigid_fit_misfit_warns(car):
    """Two measured points 2.1 m further apart than the body's corners: the fit cannot place the
    body on both; the scene warns (report and JSON), a consistent pair does not."""
    from crashsim.evidence.checks import REST_MISFIT_SHARE
    from crashsim.scene.run import run_scene

    good = _measured(car, ["front_left", "rear_right"], (-7.3, -0.7), -25.0)
    scene = run_scene(scenario_from_dict(_with_points(good)))
    assert not [w for w in scene.warnings if "misfit" in w]
    bad = copy.deepcopy(good)
    bad[1]["position"][0] = _m(float(bad[1]["position"][0].split()[0]) - 4.2)  # RMS misfit 2.1 m
    scene = run_scene(scenario_from_dict(_with_points(bad)))
    (w,) = [w for w in scene.warnings if "misfit" in w]
    reg = scene.scenario.evidence.rest[0].registration
    assert reg.rms > REST_MISFIT_SHARE * 0.5
    assert w.startswith("rest of car: the measured points fit the body with an RMS misfit of ") and "doubtful" in w
    assert w in scene.to_dict()["warnings"] and "RMS misfit" in scene.report().split("Warnings")[-1]

"""The approach in scenario files: schema, errors, report, JSON, pre-impact evidence."""

from __future__ import annotations

import copy
import json
import math

import pytest
import tomli_w

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.scene.run import run_scene, simulate_approaches
from crashsim.scenario import scenario_from_dict


def scene() -> dict:
    """A car A brakes (locked wheels) 18 m before striking the side of car B."""
    return {
        "scenario": {"title": "approach test"},
        "vehicles": {
            "A": {"position": ["0 m", "0 m"], "heading": "0 deg",
                  "bodies": [{"name": "carA", "preset": "car-midsize"}], "tyres": {"state": "locked"},
                  "approach": {"speed": "50 mph", "distance": "18 m", "reaction_time": "1.5 s",
                               "tyres": {"state": "locked"}}},
            "B": {"position": ["-0.4 m", "-3.15 m"], "heading": "90 deg", "speed": "10 m/s",
                  "bodies": [{"name": "carB", "preset": "car-midsize"}], "tyres": {"state": "locked"}},
        },
        "impact": {"body1": "carA", "body2": "carB", "point": ["-0.4 m", "-0.9 m"], "normal": "90 deg",
                   "tangent": "cw", "restitution": 0.1, "tangential": "friction", "friction": 0.5},
        "runout": {"road_friction": 0.75},
    }


def _write(tmp_path, data, name="s.toml"):
    p = tmp_path / name
    p.write_text(tomli_w.dumps(data))
    return p


def test_impact_velocity_comes_from_the_approach():
    sc = simulate_approaches(scenario_from_dict(scene()))
    a = sc.approaches["A"]
    vb = 50 * 0.44704
    vi = math.sqrt(vb**2 - 2 * 0.75 * 9.80665 * 18.0)
    assert a.speed_at_impact == pytest.approx(vi, rel=1e-6)
    assert sc.states["carA"].velocity == pytest.approx((vi, 0.0), abs=1e-5)
    assert sc.impact.states["carA"].velocity == pytest.approx((vi, 0.0), abs=1e-5)
    assert a.reaction_distance == pytest.approx(1.5 * vb)


def test_report_json_and_units(tmp_path, capsys):
    p = _write(tmp_path, scene())
    assert main(["run", str(p), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    a = out["approach"]["A"]
    assert a["speed_at_braking"] == pytest.approx(50 * 0.44704)
    assert a["distance"] == pytest.approx(18.0)
    assert a["time_to_impact"] > 0
    assert main(["run", str(p), "--units", "us"]) == 0
    text = capsys.readouterr().out
    assert "Approach before the impact" in text
    assert "speed at the start of braking        50 mph" in text
    assert "from the start of braking to impact" in text and "59.06 ft" in text


@pytest.mark.parametrize("edit, key, words", [
    (lambda d: d["vehicles"]["A"].update(speed="30 mph"), "vehicles.A.approach.speed", "give one"),
    (lambda d: d["vehicles"]["A"]["approach"].pop("speed"), "vehicles.A.approach.speed", "speed at the start"),
    (lambda d: d["vehicles"]["A"].update(course="5 deg"), "vehicles.A.course", "remove course"),
    (lambda d: d["vehicles"]["A"]["approach"].update(speed="20 mph"), "vehicles.A.approach.distance",
     "before the impact"),
    (lambda d: d["vehicles"]["A"]["approach"].update(time="1 s"), "vehicles.A.approach", "exactly one"),
    (lambda d: d["vehicles"]["A"]["approach"].pop("tyres"), "vehicles.A.approach.tyres", "tyres"),
    (lambda d: d.update(evidence={"recorder": [{"body": "carA", "tolerance": "1 mph",
                                                "samples": [{"time": "0.5 s", "speed": "40 mph"}]}]}),
     "evidence.recorder[0].samples[0].time", "0.5 s is after the impact"),
    (lambda d: d.update(evidence={"recorder": [{"body": "carB", "tolerance": "1 mph",
                                                "samples": [{"time": "-1 s", "speed": "20 mph"}]}]}),
     "evidence.recorder[0].body", "has none"),
    (lambda d: d.update(evidence={"marks": [{"wheel": "carB", "phase": "approach", "tolerance": "0.3 m",
                                             "points": [["0 m", "0 m"], ["1 m", "0 m"]]}]}),
     "evidence.marks[0].phase", "needs an approach"),
])
def test_bad_input_names_the_key(tmp_path, capsys, edit, key, words):
    data = scene()
    edit(data)
    with pytest.raises(ScenarioError) as exc:  # at load, or (a vehicle that stops short) when its approach runs
        simulate_approaches(scenario_from_dict(data, file="x.toml"))
    assert key in str(exc.value) and words in str(exc.value)
    p = _write(tmp_path, data)
    assert main(["run", str(p)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert str(p) in err[0] and key in err[0]


def test_the_loader_does_not_simulate():
    """A file whose vehicle stops before the impact loads (the loader reads and checks the file, nothing
    runs); the refusal comes when its approach is simulated, and names the key."""
    data = scene()
    data["vehicles"]["A"]["approach"].update(speed="20 mph")
    sc = scenario_from_dict(data, file="x.toml")
    assert sc.approaches == {}
    with pytest.raises(ScenarioError, match="vehicles.A.approach.distance"):
        run_scene(sc)


def test_solved_speed_and_pre_impact_evidence():
    data = scene()
    a = data["vehicles"]["A"]
    a["speed"] = "15 m/s"
    del a["approach"]["speed"]
    sc = simulate_approaches(scenario_from_dict(data))
    ap = sc.approaches["A"]
    assert ap.speed_solved
    assert ap.speed_at_braking == pytest.approx(math.sqrt(15.0**2 + 2 * 0.75 * 9.80665 * 18.0), rel=1e-6)
    # a pre-impact skid along the rear left wheel's track passes; moved 1 m sideways it fails
    tr = ap.tracks["carA/1/left"]
    pts = [[f"{float(x)!r} m", f"{float(y)!r} m"] for x, y in tr.points[::10]]
    ok = copy.deepcopy(data)
    ok["evidence"] = {"marks": [{"wheel": "carA", "phase": "approach", "tolerance": "0.2 m", "points": pts}],
                      "recorder": [{"body": "carA", "tolerance": "0.5 mph",
                                    "samples": [{"time": "-3 s", "speed": f"{ap.speed_at_braking!r} m/s"}]}]}
    res = run_scene(scenario_from_dict(ok))
    assert all(c.passed for c in res.evidence.checks), res.evidence.checks
    off = copy.deepcopy(ok)
    off["evidence"]["marks"][0]["points"] = [[x, f"{float(y.split()[0]) + 1.0!r} m"] for x, y in pts]
    res = run_scene(scenario_from_dict(off))
    mark = next(c for c in res.evidence.checks if c.kind == "mark")
    assert not mark.passed and mark.residual == pytest.approx(1.0 - 0.0, abs=0.35)
    # a run-out mark is not compared with the approach's tracks
    run_mark = copy.deepcopy(ok)
    run_mark["evidence"]["marks"][0]["phase"] = "runout"
    res = run_scene(scenario_from_dict(run_mark))
    assert not next(c for c in res.evidence.checks if c.kind == "mark").passed


def test_articulated_approach_jackknife_warns():
    """Tractor drive axles locked, the rest braked: an articulated vehicle may jack-knife on the way;
    the articulation at the end of the approach is reported, and a difference from the impact
    configuration beyond 2 deg is a warning."""
    data = {
        "scenario": {"title": "truck approach"},
        "vehicles": {
            "truck": {"position": ["0 m", "0 m"], "heading": "0 deg",
                      "bodies": [{"name": "tractor", "preset": "tractor-3axle"},
                                 {"name": "trailer", "preset": "semitrailer-loaded"}],
                      "tyres": {"state": "locked"},
                      "approach": {"speed": "55 mph", "distance": "40 m",
                                   "tyres": {"state": "rolling", "cornering_coefficient": 6.0,
                                             "rolling_resistance": 0.008, "steer": "1 deg"},
                                   "wheels": [{"select": "tractor/1", "state": "locked"},
                                              {"select": "tractor/2", "state": "locked"}]}},
            "car": {"position": ["7 m", "-3.0 m"], "heading": "90 deg", "speed": "5 m/s",
                    "bodies": [{"name": "car", "preset": "car-midsize"}], "tyres": {"state": "locked"}},
        },
        "impact": {"body1": "tractor", "body2": "car", "point": ["3.9 m", "0 m"], "point_frame": "tractor",
                   "normal": "180 deg", "tangent": "ccw", "restitution": 0.1, "tangential": "no_slide",
                   "contact_tolerance": "3 m"},
        "runout": {"road_friction": 0.75},
    }
    sc = simulate_approaches(scenario_from_dict(data))
    a = sc.approaches["truck"]
    art = math.degrees(a.articulation_at_impact[0])
    assert abs(art) > 2.0  # locked drive axles with a steer input: the tractor yaws against the trailer
    res = run_scene(sc)
    assert any("approach of truck" in w and "articulation" in w for w in res.warnings)


def test_monte_carlo_outputs_of_an_approach():
    """Each sample records the speed at impact that the approach gave, and the approach's own numbers."""
    from crashsim.reconstruct.montecarlo import OUTPUT_KINDS, scene_outputs

    res = run_scene(scenario_from_dict(scene()))
    out = scene_outputs(res)
    a = res.scenario.approaches["A"]
    assert out["speed.A"] == pytest.approx(a.speed_at_impact)
    assert out["speed.B"] == pytest.approx(10.0)
    assert out["speed_at_braking.A"] == pytest.approx(50 * 0.44704)
    assert out["braking_distance.A"] == pytest.approx(18.0)
    assert out["perception_distance.A"] == pytest.approx(18.0 + 1.5 * 50 * 0.44704)
    assert out["time_to_impact.A"] == pytest.approx(a.time_to_impact)
    assert out["mu.impact"] == pytest.approx(res.impact.mu)
    for key in out:
        assert key.split(".", 1)[0] in OUTPUT_KINDS


def test_csv_of_the_approach(tmp_path):
    import csv

    res = run_scene(scenario_from_dict(scene()))
    written = res.write_csv(tmp_path, system="US")
    path = tmp_path / "A_approach.csv"
    assert path in written
    rows = list(csv.reader(path.open()))
    assert rows[0] == ["t from impact [s]", "distance from impact [ft]", "speed [mph]"]
    a = res.scenario.approaches["A"]
    first, last = [float(x) for x in rows[1]], [float(x) for x in rows[-1]]
    half = 0.5e-4 + 1e-12  # 4 decimals of s, ft and mph in the CSV (CSV_DECIMALS): half a unit of the last
    assert first == pytest.approx([-a.time_to_impact - 1.5, -(18.0 + 1.5 * 50 * 0.44704) / 0.3048, 50.0], abs=half)
    assert last[:2] == pytest.approx([0.0, 0.0], abs=1e-4)
    assert last[2] == pytest.approx(a.speed_at_impact / 0.44704, abs=half)


def test_mc_histograms_show_the_speed_at_braking():
    from types import SimpleNamespace

    import numpy as np

    from crashsim.reconstruct.mc_plots import default_histogram_keys, output_label

    outputs = {"delta_v.carA": np.array([1.0, 2.0]), "speed.A": np.array([10.0, 11.0]),
               "speed_at_braking.A": np.array([20.0, 21.0]), "perception_distance.A": np.array([50.0, 60.0]),
               "braking_distance.A": np.array([18.0, 18.0])}
    keys = default_histogram_keys(SimpleNamespace(outputs=outputs))
    assert "speed_at_braking.A" in keys and "perception_distance.A" in keys
    assert "braking_distance.A" not in keys  # given, not varied
    assert output_label("speed_at_braking.A") == "speed at the start of braking, A"

"""A scene from survey files is the scene typed by hand: the same typed objects (to 1e-9 m after
the survey's frame and units), every check applying; bad mappings are one-line input errors; the
files are read once per load."""

from __future__ import annotations

import copy
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.scenario import scenario_from_dict
from crashsim.schema import load_toml
from crashsim.survey import expand_survey, mapping

ezdxf = pytest.importorskip("ezdxf")
ROOT = Path(__file__).resolve().parents[2]
FT = 1200 / 3937
ORIGIN = np.array([2_000_000.0, 600_000.0])  # survey feet
ROT = math.radians(-25.0)
CAR_REST = ((4.4, 1.1), math.radians(22.0))


def to_survey(p):
    p = np.asarray(p, dtype=float).reshape(-1, 2)
    c, s = math.cos(ROT), math.sin(ROT)
    return ORIGIN + np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]]) / FT


def _m(a):
    return [[f"{float(x)!r} m", f"{float(y)!r} m"] for x, y in np.asarray(a, dtype=float)]


def _car_corners(sc_dict):
    from crashsim.scenario import presets  # noqa: F401  (the car has an explicit length and width)

    car = sc_dict["vehicles"]["car"]["bodies"][0]
    from crashsim.units import Kind, parse

    ln, wd = (parse(car[k], Kind.LENGTH, field=k) for k in ("length", "width"))
    oc = [parse(v, Kind.LENGTH, field="oc") for v in car.get("outline_center", ["0 m", "0 m"])]
    (x, y), h = CAR_REST
    local = np.array([[oc[0] + ln / 2, oc[1] + wd / 2], [oc[0] - ln / 2, oc[1] + wd / 2],
                      [oc[0] - ln / 2, oc[1] - wd / 2], [oc[0] + ln / 2, oc[1] - wd / 2]])
    c, s = math.cos(h), math.sin(h)
    return np.array([x, y]) + local @ np.array([[c, s], [-s, c]])


GUARDRAIL = np.array([[-50.0, -16.0], [0.0, -16.5], [60.0, -16.0]])


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """(typed by hand, from the survey): verge_run_off with its zone, map lines, point of impact,
    marks and the car's rest (as measured corners) in a DXF in US survey feet, a turned frame and
    a guardrail obstacle added to both."""
    tmp = tmp_path_factory.mktemp("survey")
    hand = load_toml(ROOT / "scenarios" / "scenes" / "verge_run_off.toml")
    car = hand["vehicles"]["car"]["bodies"][0]
    if "length" not in car:  # the scene's car is a preset: give its outline explicitly to both files
        from crashsim.scenario import presets

        p = presets()[car["preset"]]
        car.update(length=p["length"], width=p["width"], outline_center=p.get("outline_center", ["0 m", "0 m"]))
    corners = _car_corners(hand)
    hand["evidence"]["rest"][2] = {"body": "car", "tolerance": "0.5 m", "heading_tolerance": "5 deg",
                                   "points": [{"at": a, "position": q} for a, q in
                                              zip(("front_left", "rear_left", "rear_right", "front_right"),
                                                  _m(corners))]}
    hand["obstacles"] = [{"name": "guardrail", "points": _m(GUARDRAIL), "thickness": "0.4 m"}]
    from crashsim.units import Kind, parse

    def xy(points):
        return np.array([[parse(v, Kind.LENGTH, field="p") for v in q] for q in points])

    doc = ezdxf.new("R2013")
    doc.header["$INSUNITS"] = 21
    msp = doc.modelspace()
    zone = xy(hand["runout"]["zones"][0]["polygon"])
    msp.add_lwpolyline(to_survey(zone).tolist(), close=True, dxfattribs={"layer": "VERGE"})
    for i, ln in enumerate(hand["map"]["lines"]):
        msp.add_lwpolyline(to_survey(xy(ln["points"])).tolist(), dxfattribs={"layer": f"LINE-{i}"})
    msp.add_point(to_survey(xy([hand["evidence"]["impact_point"]["position"]]))[0].tolist(),
                  dxfattribs={"layer": "POI"})
    for i, mk in enumerate(hand["evidence"]["marks"]):
        msp.add_lwpolyline(to_survey(xy(mk["points"])).tolist(), dxfattribs={"layer": f"MARK-{i}"})
    msp.add_lwpolyline(to_survey(corners).tolist(), close=True, dxfattribs={"layer": "REST-CAR"})
    msp.add_lwpolyline(to_survey(GUARDRAIL).tolist(), dxfattribs={"layer": "RAIL"})
    doc.saveas(tmp / "scene.dxf")

    surv = copy.deepcopy(hand)
    z = surv["runout"].pop("zones")[0]
    lines = surv.pop("map")["lines"]
    poi = surv["evidence"].pop("impact_point")
    marks = surv["evidence"].pop("marks")
    surv["evidence"]["rest"].pop(2)
    surv.pop("obstacles")
    fmap = [{"match": "VERGE", "kind": "zone", "friction": z["friction"], "name": z["name"]}]
    fmap += [{"match": f"LINE-{i}", "kind": "line", "style": ln["style"], "name": ln["name"]}
             for i, ln in enumerate(lines)]
    fmap += [{"match": "POI", "kind": "impact_point", "tolerance": poi["tolerance"]}]
    fmap += [{"match": f"MARK-{i}", "kind": "mark", "name": m["name"], "wheel": m["wheel"],
              "tolerance": m["tolerance"], **({"sliding_only": m["sliding_only"]} if "sliding_only" in m else {})}
             for i, m in enumerate(marks)]
    fmap += [{"match": "rest-car", "kind": "rest", "body": "car", "at": "front_left, rear_left, rear_right, front_right",
              "tolerance": "0.5 m", "heading_tolerance": "5 deg", "name": ""}]
    fmap += [{"match": "RAIL", "kind": "obstacle", "name": "guardrail", "thickness": "0.4 m"}]
    surv["survey"] = {"origin": [f"{float(ORIGIN[0])!r} survey_foot", f"{float(ORIGIN[1])!r} survey_foot"],
                      "rotation": f"{math.degrees(ROT)!r} deg",
                      "files": [{"file": str(tmp / "scene.dxf"), "map": fmap}]}
    return hand, surv, tmp


def _close(a, b, tol=1e-9):
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    assert a.shape == b.shape
    assert np.max(np.abs(a - b), initial=0.0) <= tol


def test_imported_scene_equals_the_scene_typed_by_hand(pair):
    hand, surv, _ = pair
    a, b = scenario_from_dict(hand), scenario_from_dict(surv)
    assert [(m.name, m.style) for m in a.map_lines] == [(m.name, m.style) for m in b.map_lines]
    for x, y in zip(a.map_lines, b.map_lines):
        _close(x.points, y.points)
    (za,), (zb,) = a.runout.road.zones, b.runout.road.zones
    assert (za.name, za.mu) == (zb.name, zb.mu)
    _close(za.polygon, zb.polygon)
    oa = [o for o in a.runout.obstacles if o.name == "guardrail"]
    ob = [o for o in b.runout.obstacles if o.name == "guardrail"]
    assert len(oa) == len(ob) == 1 and oa[0].thickness == ob[0].thickness == pytest.approx(0.4, abs=0)
    _close(oa[0].points, ob[0].points)
    ea, eb = a.evidence, b.evidence
    _close(ea.impact_point.position, eb.impact_point.position)
    assert ea.impact_point.tolerance == eb.impact_point.tolerance
    assert [(m.name, m.wheel, m.tolerance, m.sliding_only, m.phase) for m in ea.marks] == \
        [(m.name, m.wheel, m.tolerance, m.sliding_only, m.phase) for m in eb.marks]
    for x, y in zip(ea.marks, eb.marks):
        _close(x.points, y.points)
    ra = {r.body: r for r in ea.rest}
    rb = {r.body: r for r in eb.rest}
    assert set(ra) == set(rb)
    for body in ra:
        _close(ra[body].position, rb[body].position)
        assert ra[body].heading == pytest.approx(rb[body].heading, abs=1e-9)
        assert ra[body].tolerance == rb[body].tolerance
    # the car's rest came through the rigid fit of its four corners: the CG and heading typed
    _close(rb["car"].position, CAR_REST[0], 1e-9)
    assert rb["car"].heading == pytest.approx(CAR_REST[1], abs=1e-9)
    # every item traced to its source
    rec = b.data["survey"]["imported"]
    targets = {r["target"]: r for r in rec if r["target"]}
    assert targets["evidence.rest[2]"]["layer"] == "REST-CAR" and targets["evidence.rest[2]"]["type"] == "LWPOLYLINE"
    assert targets["runout.zones[0]"]["layer"] == "VERGE"
    assert targets["obstacles[0]"]["ref"]  # a DXF handle
    assert len([t for t in targets if t.startswith("map.lines")]) == len(a.map_lines)


def test_the_report_and_json_name_the_sources(pair):
    from crashsim.reconstruct import run_scene

    _, surv, _ = pair
    data = copy.deepcopy(surv)
    data["runout"]["t_max"] = "0.2 s"  # the sources, not the run, are under test
    scene = run_scene(scenario_from_dict(data))
    text = scene.report("SI")
    assert "Survey sources (" in text and "REST-CAR" in text and "evidence.marks[1]" in text
    d = scene.to_dict()
    assert {r["target"] for r in d["survey"]} >= {"evidence.impact_point", "runout.zones[0]", "obstacles[0]"}


def test_expanded_once_and_never_read_again(pair, monkeypatch):
    _, surv, _ = pair
    calls = []
    real = mapping.read_survey_file

    def counting(*a, **k):
        calls.append(1)
        return real(*a, **k)

    monkeypatch.setattr(mapping, "read_survey_file", counting)
    mapping._CACHE.clear()
    expanded = expand_survey(surv)
    assert len(calls) == 1 and "imported" in expanded["survey"] and "imported" not in surv["survey"]
    assert expand_survey(expanded) is expanded
    # what a fit or Monte Carlo sample does: a changed copy of the expanded dict, rebuilt in full
    from crashsim.api import with_overrides

    for v in ("0.6", "0.7", "0.8"):
        scenario_from_dict(with_overrides(expanded, {"runout.road_friction": v}))
    assert len(calls) == 1


def _map_error(surv, change, match):
    data = copy.deepcopy(surv)
    change(data["survey"]["files"][0]["map"])
    mapping._CACHE.clear()
    with pytest.raises(ScenarioError, match=match) as info:
        scenario_from_dict(data, file="scene.toml")
    assert "\n" not in str(info.value)
    return str(info.value)


def test_bad_mappings(pair):
    _, surv, _ = pair
    msg = _map_error(surv, lambda m: m.append({"match": "RAILS-OLD", "kind": "obstacle"}),
                     r"has no layer or code matching 'RAILS-OLD'; nearest: 'RAIL'")
    assert msg.startswith("scene.toml: survey.files[0].map[") and "It has: 'LINE-0'" in msg
    _map_error(surv, lambda m: m.__setitem__(0, {**m[0], "friction": None} if False else
                                             {k: v for k, v in m[0].items() if k != "friction"}),
               r"map\[0\]\.friction: kind = 'zone' needs friction")
    _map_error(surv, lambda m: m[1].__setitem__("style", "kreb"), r"style = 'kreb'.*did you mean 'kerb'")
    _map_error(surv, lambda m: m[1].__setitem__("wheel", "car"), r"map\[1\]\.wheel: wheel does not apply to kind")
    _map_error(surv, lambda m: m.insert(0, {"match": "*", "kind": "ignore"}),
               r"every entity of .VERGE. is taken by an earlier map entry")
    _map_error(surv, lambda m: m[-2].__setitem__("at", "front_left, rear_left"),
               r"4 points on 'REST-CAR' .* but at names 2")
    _map_error(surv, lambda m: m.__setitem__(0, {**m[0], "match": "MARK-0"}),
               r"not a closed outline; a friction zone needs one")


def test_units_in_the_scene_file_contradicting_the_drawing(pair):
    _, surv, _ = pair
    data = copy.deepcopy(surv)
    data["survey"]["files"][0]["units"] = "m"
    mapping._CACHE.clear()
    with pytest.raises(ScenarioError, match=r"survey.files\[0\].units: .*units = 'm', but the drawing's header says "
                                            r"\$INSUNITS = 21 \(us_ft\)") as info:
        scenario_from_dict(data, file="scene.toml")
    assert "remove units" not in str(info.value)  # that advice moved the scene without a word


def test_unsupported_entities_warned_once_in_the_sources(pair, tmp_path, caplog):
    _, surv, tmp = pair
    doc = ezdxf.readfile(tmp / "scene.dxf")
    for _ in range(3):
        doc.modelspace().add_3dface([(0, 0), (1, 0), (1, 1)], dxfattribs={"layer": "TIN"})
    doc.modelspace().add_line((0, 0), (1, 1), dxfattribs={"layer": "TREES"})  # a layer the mapping leaves out
    doc.saveas(tmp_path / "with_tin.dxf")
    data = copy.deepcopy(surv)
    data["survey"]["files"][0]["file"] = str(tmp_path / "with_tin.dxf")
    mapping._CACHE.clear()
    with caplog.at_level("WARNING", logger="crashsim"):
        sc = scenario_from_dict(data)
    notes = [r["note"] for r in sc.data["survey"]["imported"] if r["kind"] == "note"]
    # TIN faces are read (kind = "surface" would take them); unmapped, they are named with the layers left out
    assert "4 entities on layers or codes no map entry matches were not imported: TIN (3), TREES (1)" in notes
    doc.modelspace().add_hatch(dxfattribs={"layer": "HATCHED"}).paths.add_polyline_path([(0, 0), (1, 0), (1, 1)])
    doc.saveas(tmp_path / "with_hatch.dxf")
    data["survey"]["files"][0]["file"] = str(tmp_path / "with_hatch.dxf")
    mapping._CACHE.clear()
    with caplog.at_level("WARNING", logger="crashsim"):
        sc = scenario_from_dict(data)
    notes = [r["note"] for r in sc.data["survey"]["imported"] if r["kind"] == "note"]
    assert any("1 entities of types the importer does not take were left out: 1 HATCH" in n for n in notes)
    assert sum("HATCH" in r.getMessage() for r in caplog.records) == 1


def test_samples_from_an_unexpanded_file_read_it_once(pair, monkeypatch):
    """fit, Monte Carlo and posterior build their samples through ScenarioOverrides: given the
    file's contents before the survey is read (as a script may pass them), it reads the survey
    once and every sample rebuilds from the items."""
    from crashsim.reconstruct.overrides import ScenarioOverrides

    _, surv, _ = pair
    calls = []
    real = mapping.read_survey_file
    monkeypatch.setattr(mapping, "read_survey_file", lambda *a, **k: calls.append(1) or real(*a, **k))
    mapping._CACHE.clear()
    ov = ScenarioOverrides(surv, ["runout.road_friction"], fast=False)
    for v in (0.6, 0.7, 0.8):
        sc = ov.scenario((v,))
        assert sc.runout.road.mu == pytest.approx(v)
    assert len(calls) == 1

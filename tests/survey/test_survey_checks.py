"""Survey mistakes that used to pass or mislead (issue 31, item 3): a truncated DXF, a listing of
a drawing without units or with a TIN, US survey feet on an R12 drawing that can only say feet."""

from __future__ import annotations

import pytest

ezdxf = pytest.importorskip("ezdxf")

from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.survey.dxf import read_dxf  # noqa: E402
from crashsim.survey.frame import UNIT_METRES  # noqa: E402
from crashsim.survey.inspect import read_any, summary  # noqa: E402


def _drawing(path, version="R2010", insunits=None, faces=0):
    doc = ezdxf.new(version)
    doc.header["$INSUNITS"] = 0 if insunits is None else insunits  # 0: unitless
    msp = doc.modelspace()
    msp.add_lwpolyline([(1000.0, 2000.0), (1100.0, 2000.0), (1100.0, 2050.0)], dxfattribs={"layer": "EDGE"})
    msp.add_point((1050.0, 2020.0), dxfattribs={"layer": "POI"})
    for i in range(faces):
        msp.add_3dface([(i, 0, 0), (i + 1, 0, 0.1), (i + 1, 1, 0.12)], dxfattribs={"layer": "TIN"})
    doc.saveas(path)
    return path


def test_a_truncated_drawing_is_damaged_at_its_line(tmp_path):
    full = _drawing(tmp_path / "full.dxf", insunits=6)
    lines = full.read_text().splitlines()
    cut = tmp_path / "cut.dxf"
    cut.write_text("\n".join(lines[: len(lines) // 2]) + "\n")
    with pytest.raises(ScenarioError, match=rf"damaged at line {len(lines) // 2}"):
        read_dxf(str(cut))
    with pytest.raises(ScenarioError, match="damaged at line"):
        read_any(str(cut))  # crashsim survey says so too, not "0 entities"


def test_listing_needs_no_units_and_names_every_type(tmp_path):
    p = _drawing(tmp_path / "tin.dxf", faces=3)
    with pytest.raises(ScenarioError, match="does not state its units"):
        read_dxf(str(p))  # a scene needs them
    text = summary(read_any(str(p)))
    assert "does not state its units" in text and "note:" in text
    tin = next(ln for ln in text.splitlines() if ln.strip().startswith("TIN"))
    assert "3 3DFACE" in tin
    assert any(ln.strip().startswith("EDGE") and "LWPOLYLINE" in ln for ln in text.splitlines())


def test_us_survey_feet_on_an_r12_drawing_in_feet(tmp_path):
    """R12 has no $INSUNITS code for the US survey foot: units = "us_ft" on a drawing whose header
    says feet is taken (the scene file knows better), with a note; other contradictions stay errors."""
    p = _drawing(tmp_path / "ft.dxf", insunits=2)
    d = read_dxf(str(p), "us_ft")
    assert d.unit == "us_ft"
    e = next(e for e in d.entities if e.layer == "POI")
    assert e.points[0, 0] == pytest.approx(1050.0 * UNIT_METRES["us_ft"], rel=1e-15)
    assert any("no $INSUNITS code for the US survey foot" in n for n in d.notes)
    with pytest.raises(ScenarioError, match=r"\$INSUNITS = 2 \(ft\): one of them is wrong") as info:
        read_dxf(str(p), "m")
    assert "remove units" not in str(info.value)


def test_point_file_mistakes_name_their_rows(tmp_path):
    from crashsim.survey.points import read_points

    p = tmp_path / "ts.txt"
    p.write_text("501,1000.0,2000.0,10.0,TRREST\n502,1001.0,2000.0,10.0,TRREST\n502,1002.0,2001.0,10.0,EP\n")
    with pytest.raises(ScenarioError, match=r"rows 2 and 3 have the same point number '502'"):
        read_points(str(p), "m", "PNEZD")
    p.write_text("501,1000.0,2000.0,10.0\n502,1001.0,2000.0,10.0\n")
    with pytest.raises(ScenarioError, match=r"the rows have 4 fields where columns = 'PNEZD' declares 5"):
        read_points(str(p), "m", "PNEZD")
    with pytest.raises(ScenarioError, match=r"gives both N/E and X/Y"):
        read_points(str(p), "m", "PNEZX")
    d = read_points(str(p), "m", "PNEZ")
    assert "no D (description, the code) column" in d.empty_layers


def test_a_geojson_layer_property_no_feature_has(tmp_path):
    import json

    from crashsim.survey.geojson import read_geojson

    p = tmp_path / "r.geojson"
    p.write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"FEATCODE": "EP", "OFFSET_FT": 0},
         "geometry": {"type": "LineString", "coordinates": [[500000, 4300000], [500010, 4300000]]}}]}))
    d = read_geojson(str(p), "EPSG:32617", crs="EPSG:32617", layer_property="FEATURECODE")
    assert "no feature has a property 'FEATURECODE'" in d.empty_layers and "FEATCODE, OFFSET_FT" in d.empty_layers


def _shipped(tmp_path, *changes):
    import shutil
    from pathlib import Path

    root = Path(__file__).resolve().parents[2] / "scenarios" / "survey"
    shutil.copytree(root / "files", tmp_path / "files")
    text = (root / "truck_brakes_survey.toml").read_text()
    for old, new in changes:
        assert old in text
        text = text.replace(old, new, 1)
    f = tmp_path / "scene.toml"
    f.write_text(text)
    return f


def test_an_item_far_from_every_vehicle_is_a_warning_naming_it(tmp_path):
    """Swapped N/E columns put the car's rest corners thousands of km off: a warning naming the
    item and its source, in the run's warnings; the other items are where they belong."""
    from crashsim.scenario import load_scenario
    from crashsim.scene.run import run_scene

    f = _shipped(tmp_path, ('file = "files/points.csv"         # PNEZD', 'file = "files/points.csv"\ncolumns = "PENZD"'))
    scene = run_scene(load_scenario(f))
    far = [w for w in scene.warnings if "km from every vehicle" in w]
    assert far and all("files/points.csv" in w for w in far), scene.warnings
    assert any("evidence.rest[" in w for w in far)


def test_a_survey_placed_off_the_scene_is_an_error_at_its_origin(tmp_path):
    from crashsim.scenario import load_scenario

    f = _shipped(tmp_path, ('origin = ["1455000 survey_foot", "538400 survey_foot"]',
                            'origin = ["538400 survey_foot", "1455000 survey_foot"]'))
    with pytest.raises(ScenarioError, match=r"survey.origin: every item imported from the survey \(\d+\) lies at "
                                            r"least [\d.]+ km from every vehicle"):
        load_scenario(f)


def test_an_angle_beyond_a_turn_is_a_warning(tmp_path):
    from crashsim.scenario import load_scenario

    f = _shipped(tmp_path, ('heading = "90 deg"', 'heading = "1.5708 rad"'), ('rotation = "30 deg"',
                                                                             'rotation = "390 deg"'))
    assert load_scenario(f).load_warnings == ("survey.rotation = '390 deg' is 1.083 turns (more than 2 pi rad)",)
    f = _shipped(tmp_path / "b", ('heading = "90 deg"', 'heading = "192 rad"'))
    (w,) = load_scenario(f).load_warnings
    assert w.startswith("vehicles.car.heading = '192 rad' is 30.56 turns") and 'did you mean "192 deg"' in w


def test_errors_of_imported_items_name_the_key_as_written(tmp_path):
    """A mistake in a map entry is named by the map entry's key (the generated item in brackets)."""
    from crashsim.scenario import load_scenario

    f = _shipped(tmp_path, ('at = "front_left, rear_left, rear_right, front_right"',
                            'at = "front_left, rear_left, rear_middle, front_right"'))
    with pytest.raises(ScenarioError) as info:
        load_scenario(f)
    import re

    assert re.fullmatch(r"survey\.files\[\d+\]\.map\[\d+\]\.at", info.value.field), info.value.field
    assert "imported as evidence.rest[" in str(info.value) and "rear_middle" in str(info.value)
    f = _shipped(tmp_path / "r", ('body = "tractor"\ntime = "Time (sec)"', 'body = "car"\ntime = "Time (sec)"'))
    with pytest.raises(ScenarioError) as info:
        load_scenario(f)
    assert info.value.field == "survey.recorders[0].body" and "imported as evidence.recorder[0].body" in str(info.value)


def test_a_tin_gives_the_roads_grade_and_cross_slope(tmp_path):
    """kind = "surface": the plane through a TIN's 3DFACE vertices, in the scene frame (turned 30 deg
    from the survey's axes here), is runout.grade and runout.cross_slope; listed as 3DFACE by layer."""
    import math

    import numpy as np

    from crashsim.scenario import load_scenario

    f = _shipped(tmp_path, ('  {match = "EDGE", kind = "line", style = "edge"},',
                            '  {match = "EDGE", kind = "line", style = "edge"},\n  {match = "TIN", kind = "surface"},'))
    dxf = tmp_path / "files" / "scene.dxf"
    doc = ezdxf.readfile(dxf)
    gx, gy = 0.03, -0.05  # dz/dE, dz/dN of the road plane in the survey's axes
    e0, n0 = 1455000.0, 538400.0
    rng = np.random.default_rng(3)
    for _ in range(12):
        c = np.array([e0, n0]) + rng.uniform(-150, 150, 2)
        tri = [c, c + (20, 0), c + (0, 20)]
        doc.modelspace().add_3dface([(x, y, 100 + gx * (x - e0) + gy * (y - n0)) for x, y in tri],
                                    dxfattribs={"layer": "TIN"})
    doc.saveas(dxf)
    sc = load_scenario(f)
    r = math.radians(30)
    want_grade = gx * math.cos(r) + gy * math.sin(r)  # along the scene's +x (30 deg north of east)
    want_cross = -gx * math.sin(r) + gy * math.cos(r)
    assert sc.runout.road.grade == pytest.approx(want_grade, abs=1e-9)
    assert sc.runout.road.cross_slope == pytest.approx(want_cross, abs=1e-9)
    assert any(r["kind"] == "surface" and "12 faces" in r["ref"] for r in sc.data["survey"]["imported"])
    assert "12 3DFACE" in summary(read_any(str(dxf)))
    # the file's own grade beside the TIN: one of them
    g = _shipped(tmp_path / "b", ('  {match = "EDGE", kind = "line", style = "edge"},',
                                  '  {match = "EDGE", kind = "line", style = "edge"},\n  {match = "TIN", kind = "surface"},'),
                 ("road_friction = 0.7\n", 'road_friction = 0.7\ngrade = "2 %"\n'))
    (tmp_path / "b" / "files" / "scene.dxf").write_bytes(dxf.read_bytes())
    with pytest.raises(ScenarioError, match=r"kind = 'surface' gives runout.grade .* the file gives runout.grade too"):
        load_scenario(g)


def _rec_spec(**kw):
    base = {"time": "t", "speed": "v", "time_unit": "s", "speed_unit": "mph", "brake": None, "abs": None,
            "accelerator": None, "steering": None, "yaw_rate": None, "on": "on, 1", "time_offset": 0.0}
    base.update(kw)
    return base


def test_recorder_tables_that_misled(tmp_path):
    """A header without rows, decimal commas, two samples at one time: each said as what it is (they
    were all 'no pre-crash samples')."""
    from crashsim.survey.recorder import read_recorder

    p = tmp_path / "r.csv"
    p.write_text("t,v\n")
    with pytest.raises(ScenarioError, match="a header row but no data rows"):
        read_recorder(str(p), _rec_spec())
    p.write_text("t;v\n-2,0;55\n-1,0;54,5\n0,0;50\n")
    samples, notes = read_recorder(str(p), _rec_spec())
    assert [s[0] for s in samples] == [-2.0, -1.0, 0.0] and samples[1][1] == pytest.approx(54.5 * 0.44704)
    assert any("decimal commas" in n for n in notes)
    p.write_text("t,v\n-2,55\n-1,54\n-1,53\n")
    with pytest.raises(ScenarioError, match=r"rows 3 and 4 have the same time '-1'"):
        read_recorder(str(p), _rec_spec())


def test_a_damaged_underlay_is_refused_before_the_run(tmp_path, monkeypatch, capsys):
    import crashsim.cli as cli
    import crashsim.scene

    f = _shipped(tmp_path)
    (tmp_path / "files" / "ortho.png").write_text("not an image\n")

    def refuse(*a, **k):
        raise AssertionError("the run started before the underlay was read")

    monkeypatch.setattr(crashsim.scene, "run_scene", refuse)  # where the plot command takes it from
    assert cli.main(["plot", str(f), "-o", str(tmp_path / "p.png")]) == 2
    err = capsys.readouterr().err
    assert "survey.underlay.image" in err and "cannot read the underlay image" in err and "files/ortho.png" in err

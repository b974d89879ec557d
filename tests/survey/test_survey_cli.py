"""crashsim survey and crashsim export, and bad survey input as one line with exit code 2."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from crashsim.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml"
FILES = ROOT / "scenarios" / "survey" / "files"


def test_survey_lists_layers_counts_and_extents(capsys, tmp_path):
    code = main(["survey", str(FILES / "scene.dxf"), "-o", str(tmp_path / "preview.png")])
    out = capsys.readouterr().out.splitlines()
    assert code == 0
    assert out[0].endswith("dxf, 20 entities, coordinates in us_ft")
    rows = {ln.split()[0]: ln for ln in out[2:] if ln.startswith("  ") and not ln.startswith("  note")}
    assert "1 LWPOLYLINE, 1 TEXT" in rows["SKID-TRACTOR-L"] and "4 POINT" in rows["DEBRIS"]
    assert "2 ARC" in rows["KERB"] and "1 CIRCLE" in rows["SIGN"]  # the sign is an INSERT of a block
    assert (tmp_path / "preview.png").stat().st_size > 5000
    code = main(["survey", str(FILES / "points.csv"), "--units", "us_ft"])
    out = capsys.readouterr().out
    assert code == 0 and "CAR REST  1 string" in out and "EP        1 string" in out


def test_export_writes_dxf_and_geojson(capsys, tmp_path):
    code = main(["export", str(SCENE), "--dxf", str(tmp_path / "r.dxf"), "--geojson", str(tmp_path / "r.geojson"),
                 "--times", "0.5 s"])
    out = capsys.readouterr().out.splitlines()
    assert code == 0 and len(out) == 2
    assert out[0].startswith(f"wrote {tmp_path / 'r.dxf'} (") and out[0].endswith("entities, us_ft)")
    code = main(["survey", str(tmp_path / "r.dxf")])
    listing = capsys.readouterr().out
    assert code == 0 and "CRASHSIM-T0.5-car" in listing and "CRASHSIM-EVIDENCE-PASS" in listing


def test_export_says_a_geojson_without_crs_is_not_on_a_map(capsys, tmp_path):
    """Without survey.crs the GeoJSON holds the scene's own axes (RFC 7946 wants WGS 84): the line says so."""
    scene = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"
    code = main(["export", str(scene), "--geojson", str(tmp_path / "r.geojson")])
    out = capsys.readouterr().out.splitlines()
    assert code == 0 and len(out) == 1
    assert "m in the scene's own axes: not on a map" in out[0] and "give survey.crs for WGS 84" in out[0]


def _error(capsys) -> str:
    """stderr without the one-time kernel compile messages (a first run in a fresh installation)."""
    lines = capsys.readouterr().err.strip().splitlines()
    return "\n".join(ln for ln in lines if not ln.startswith("crashsim: compil"))


def _bad(tmp_path, capsys, edit, match):
    shutil.copytree(FILES, tmp_path / "files")
    text = SCENE.read_text()
    p = tmp_path / "scene.toml"
    p.write_text(edit(text))
    code = main(["run", str(p)])
    err = _error(capsys)
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert err.startswith(f"crashsim: input error: {p}: survey.")
    assert match in err, err
    return err


def test_bad_survey_input_is_one_line_exit_2(tmp_path, capsys):
    err = _bad(tmp_path, capsys, lambda t: t.replace('{match = "KERB", kind = "line", style = "kerb"}',
                                                     '{match = "KERBS", kind = "line", style = "kerb"}'),
               "has no layer or code matching 'KERBS'; nearest: 'KERB'")
    assert "It has: 'CENTRE', 'DEBRIS'" in err


@pytest.mark.parametrize("edit, match", [
    (lambda t: t.replace('file = "files/scene.dxf"          # $INSUNITS 21: US survey feet',
                         'file = "files/scene.dxf"\nunits = "m"'),
     "units = 'm', but the drawing's header says $INSUNITS = 21 (us_ft)"),
    (lambda t: t.replace('speed = "Vehicle Speed (MPH)"', 'speed = "Vehicle Speed (KPH)"'),
     "has no column 'Vehicle Speed (KPH)'; nearest: 'Vehicle Speed (MPH)'"),
])
def test_more_bad_input(tmp_path, capsys, edit, match):
    _bad(tmp_path, capsys, edit, match)


def test_unknown_crs_of_a_geojson_survey(tmp_path, capsys):
    shutil.copytree(FILES, tmp_path / "files")
    (tmp_path / "files" / "x.geojson").write_text('{"type": "FeatureCollection", "features": []}')
    text = SCENE.read_text().replace('[[survey.recorders]]', '[[survey.files]]\nfile = "files/x.geojson"\n'
                                     'map = [{match = "*", kind = "ignore"}]\n\n[[survey.recorders]]')
    text = text.replace('rotation = "30 deg"', 'rotation = "30 deg"\ncrs = "EPSG:999999"')
    p = tmp_path / "scene.toml"
    p.write_text(text)
    assert main(["run", str(p)]) == 2
    err = _error(capsys)
    assert len(err.splitlines()) == 1 and "survey.crs = 'EPSG:999999' is not a coordinate reference system" in err


def test_underlay_that_does_not_fit_fails_at_load(tmp_path, capsys):
    """Control points that a similarity cannot fit within the tolerance: the run stops before any
    computation, naming the point and its residual; good ones are reported with their residuals."""
    good = ('control = [{pixel = [0.0, 0.0], position = ["1454842.6 survey_foot", "538508.5 survey_foot"]}, '
            '{pixel = [600.0, 0.0], position = ["1455142.6 survey_foot", "538508.5 survey_foot"]}, '
            '{pixel = [0.0, 400.0], position = ["1454842.6 survey_foot", "538308.5 survey_foot"]}]')
    bad = good.replace('"538308.5 survey_foot"', '"538318.5 survey_foot"')
    edit = lambda c: (lambda t: t.replace('image = "files/ortho.png"         # its world file files/ortho.pgw is '
                                          'found beside it', f'image = "files/ortho.png"\n{c}'))  # noqa: E731
    err = _bad(tmp_path, capsys, edit(bad), "lies ")
    assert "survey.underlay.control" in err and "from where the similarity fit puts it (tolerance 0.1 m" in err
    shutil.rmtree(tmp_path / "files")
    shutil.copytree(FILES, tmp_path / "files")
    (tmp_path / "scene.toml").write_text(edit(good)(SCENE.read_text()))
    from crashsim.scenario import load_scenario

    rec = [r for r in load_scenario(tmp_path / "scene.toml").data["survey"]["imported"] if r["kind"] == "underlay"]
    assert len(rec) == 1 and "similarity fit to 3 control points" in rec[0]["note"]
    assert "control point residuals" in rec[0]["note"]


def test_expanded_file_written_elsewhere_keeps_its_underlay(tmp_path):
    """What fit --write-best writes (the expanded file, sources included) loads and draws from
    another folder: the items are in it and the underlay image is named by its absolute path."""
    import tomli_w

    from crashsim.scenario import load_scenario
    from crashsim.survey.mapping import load_scene_data
    from crashsim.survey.underlay import scene_underlay

    data = load_scene_data(SCENE)
    assert Path(data["survey"]["underlay"]["image"]).is_absolute()
    out = tmp_path / "elsewhere" / "best.toml"
    out.parent.mkdir()
    out.write_text(tomli_w.dumps(data))
    sc = load_scenario(out)
    assert len(sc.evidence.rest) == 3 and len(sc.map_lines) == 13
    image, g, _, _ = scene_underlay(sc)
    assert image.shape[:2] == (490, 586) and g.how == "world file ortho.pgw"


def test_export_of_a_scene_without_a_survey_is_in_its_own_metres(tmp_path, capsys):
    from crashsim.scenario import load_scenario
    from crashsim.survey.dxf import read_dxf

    scene = ROOT / "scenarios" / "scenes" / "verge_run_off.toml"
    assert main(["export", str(scene), "--dxf", str(tmp_path / "v.dxf")]) == 0
    assert capsys.readouterr().out.strip().endswith("entities, m)")
    d = read_dxf(str(tmp_path / "v.dxf"))
    assert d.unit == "m"
    impact = {e.layer: e for e in d.entities}["CRASHSIM-IMPACT-car"]
    st = load_scenario(scene).states["car"]
    assert impact.points.mean(axis=0) == pytest.approx(st.position, abs=0.5)  # the outline around its CG

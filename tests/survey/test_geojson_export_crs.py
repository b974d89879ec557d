"""GeoJSON export on the map: with ``survey.crs`` it is RFC 7946 (WGS 84 longitude/latitude, no
``crs`` member), and read back through pyproj it lands on the DXF export's points.

The failing case of issue 31: a survey in US survey feet (``units = "us_ft"``) on a CRS in metres
(EPSG:32617). The export used to declare EPSG:32617 and write US survey feet, 9,800 km off.
"""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest

pyproj = pytest.importorskip("pyproj")

from crashsim.scenario import load_scenario  # noqa: E402
from crashsim.scene.run import run_scene  # noqa: E402
from crashsim.survey.dxf import read_dxf  # noqa: E402
from crashsim.survey.export import export_frame, export_items, write_dxf, write_geojson  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
US_FT = 1200.0 / 3937.0


def _coords(g) -> np.ndarray:
    if g["type"] == "Point":
        return np.asarray([g["coordinates"]], dtype=float)
    if g["type"] == "Polygon":
        return np.asarray(g["coordinates"][0][:-1], dtype=float)
    return np.asarray(g["coordinates"], dtype=float)


def test_geojson_in_wgs84_lands_on_the_dxf_points(tmp_path):
    src = ROOT / "scenarios" / "survey"
    shutil.copytree(src / "files", tmp_path / "files")
    text = (src / "truck_brakes_survey.toml").read_text()
    assert 'units = "us_ft"' in text
    text = text.replace("[survey]\n", '[survey]\ncrs = "EPSG:32617"\n', 1)
    (tmp_path / "scene.toml").write_text(text)
    scenario = load_scenario(tmp_path / "scene.toml")
    frame, unit = export_frame(scenario)
    assert unit == "us_ft"
    items = export_items(run_scene(scenario), [0.5])
    dxf = read_dxf(write_dxf(items, tmp_path / "out.dxf", frame, unit))
    doc = json.loads(Path(write_geojson(items, tmp_path / "out.geojson", frame, unit, "EPSG:32617")).read_text())
    assert "crs" not in doc  # RFC 7946: WGS 84 only, no crs member
    to_utm = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:32617", always_xy=True)
    lines = [e for e in dxf.entities if e.geometry != "text"]
    feats = [f for f in doc["features"] if "text" not in f["properties"]]
    assert len(lines) == len(feats) > 10
    worst = 0.0
    for e, f in zip(lines, feats):
        assert e.layer == f["properties"]["layer"]
        lonlat = _coords(f["geometry"])
        assert np.all(np.abs(lonlat[:, 0]) <= 180) and np.all(np.abs(lonlat[:, 1]) <= 90)
        x, y = to_utm.transform(lonlat[:, 0], lonlat[:, 1])
        utm = np.column_stack([x, y])  # metres of EPSG:32617
        worst = max(worst, float(np.max(np.abs(utm - e.points))))  # read_dxf: us_ft to metres
    assert worst < 1e-3


def test_geojson_without_a_crs_stays_in_the_survey_unit(tmp_path):
    from crashsim.survey.export import ExportItem
    from crashsim.survey.frame import SceneFrame

    frame = SceneFrame((1000.0, 2000.0), 0.0)
    items = [ExportItem("L", "point", np.array([[3.0, 4.0]]))]
    doc = json.loads(Path(write_geojson(items, tmp_path / "o.geojson", frame, "us_ft")).read_text())
    assert "crs" not in doc and doc["crashsim_units"] == "us_ft"
    assert np.allclose(doc["features"][0]["geometry"]["coordinates"], np.array([1003.0, 2004.0]) / US_FT,
                       rtol=0, atol=1e-9)

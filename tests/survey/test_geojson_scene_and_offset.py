"""A GeoJSON survey in a scene (lon/lat projected into the survey's CRS and frame), and the
recorder's clock offset as an input a fit or Monte Carlo can vary (its path in the expanded file)."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest

from crashsim.scenario import scenario_from_dict
from crashsim.schema import load_toml
from crashsim.survey import expand_survey

pyproj = pytest.importorskip("pyproj")
ROOT = Path(__file__).resolve().parents[2]


def test_geojson_lonlat_survey_becomes_map_lines_in_the_scene_frame(tmp_path):
    """Edges drawn in lon/lat 100 m apart; with the scene origin on the first vertex (in UTM 33N),
    the imported line starts at (0, 0) within 1 cm and the second line lies where its twin,
    projected by pyproj, lies."""
    t = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:32633", always_xy=True)
    a = np.array([[16.3725, 48.2082], [16.3745, 48.2082]])
    b = a + [0.0, 0.0009]
    ua = np.column_stack(t.transform(a[:, 0], a[:, 1]))
    ub = np.column_stack(t.transform(b[:, 0], b[:, 1]))
    (tmp_path / "edges.geojson").write_text(json.dumps({"type": "FeatureCollection", "features": [
        {"type": "Feature", "properties": {"kind": "edge"}, "geometry": {"type": "LineString", "coordinates": a.tolist()}},
        {"type": "Feature", "properties": {"kind": "edge"}, "geometry": {"type": "LineString", "coordinates": b.tolist()}},
    ]}))
    data = load_toml(ROOT / "scenarios" / "scenes" / "verge_run_off.toml")
    data.pop("map")
    data["survey"] = {"crs": "EPSG:32633", "origin": [f"{float(ua[0, 0])!r} m", f"{float(ua[0, 1])!r} m"],
                      "files": [{"file": str(tmp_path / "edges.geojson"), "layer_property": "kind",
                                 "map": [{"match": "edge", "kind": "line", "style": "edge"}]}]}
    sc = scenario_from_dict(data)
    assert len(sc.map_lines) == 2
    np.testing.assert_allclose(sc.map_lines[0].points[0], [0.0, 0.0], atol=0.01)
    np.testing.assert_allclose(sc.map_lines[1].points, ub - ua[0], atol=0.01)
    assert 95 < sc.map_lines[1].points[0, 1] < 105  # 0.0009 deg of latitude: about 100 m north
    src = [r for r in sc.data["survey"]["imported"] if r["kind"] == "line"]
    assert [r["ref"] for r in src] == ["#0", "#1"] and src[0]["type"] == "LineString"


def test_recorder_clock_offset_is_an_input_of_the_expanded_file():
    from crashsim.api import with_overrides
    from crashsim.reconstruct.overrides import resolve_path
    from crashsim.survey.mapping import load_scene_data

    data = load_scene_data(ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml")
    target = resolve_path("evidence.recorder[0].time_offset")
    assert target.field.kind.value == "time"
    shifted = with_overrides(data, {"evidence.recorder[0].time_offset": "-0.3 s"})
    assert shifted["evidence"]["recorder"][0]["time_offset"] == "-0.3 s"
    assert data["evidence"]["recorder"][0]["time_offset"] == "0 s"
    assert expand_survey(shifted) is shifted  # a sample never reads the files again

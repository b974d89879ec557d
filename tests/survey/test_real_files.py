"""The importers on files written by other people's programs (``../shared/real-scene-data``,
beside the clone; see its SOURCES.md). Each test checks counts and coordinates against what the
file holds, read here independently of the importer. Skipped where the folder is absent; none of
these files is copied into the repository."""

from __future__ import annotations

import csv
import json
import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT.parent / "shared" / "real-scene-data"
pytestmark = pytest.mark.skipif(not DATA.is_dir(), reason=f"real scene data not found at {DATA}")
FTUS = 1200 / 3937


def _group_pairs(path):
    lines = Path(path).read_text(errors="replace").splitlines()
    start = next(i for i, ln in enumerate(lines) if ln.strip() == "0")  # 999 comments before SECTION
    return [(int(lines[i].strip()), lines[i + 1].strip()) for i in range(start, len(lines) - 1, 2)]


def test_cloudcompare_dxflib_r12_polyline():
    from crashsim.survey.dxf import read_dxf

    path = DATA / "dxf" / "ezdxf_cloudcompare_dxflib_polyline.dxf"
    # the file's own VERTEX records (group codes 10, 20), read here by hand
    pairs = _group_pairs(path)
    verts, cur = [], None
    for code, value in pairs:
        if code == 0:
            if cur is not None:
                verts.append(cur)
            cur = [None, None] if value == "VERTEX" else None
        elif cur is not None and code in (10, 20):
            cur[code // 10 - 1] = float(value)
    d = read_dxf(str(path), "m")  # the file states no units
    (e,) = d.entities
    assert (e.layer, e.dxftype, e.geometry) == ("POLYLINE_001", "POLYLINE", "line")
    np.testing.assert_array_equal(e.points, np.array(verts))
    assert "AC1009" in d.notes[0]
    with pytest.raises(ScenarioError, match="does not state its units"):
        read_dxf(str(path))


def test_binary_dxf_read_and_its_3dfaces_named():
    from crashsim.survey.dxf import read_dxf

    path = DATA / "dxf" / "bezitopo_tinytin_binary.dxf"
    assert path.read_bytes().startswith(b"AutoCAD Binary DXF")
    d = read_dxf(str(path))
    assert d.unit == "in" and not d.entities
    # its 4 TIN faces, read with their elevations (kind = "surface" makes them the road's plane)
    assert len(d.faces) == 4 and all(v.shape in ((3, 3), (4, 3)) for _, _, v in d.faces)
    assert not d.skipped and d.skipped_warning() is None


def _pnezd():
    path = DATA / "total_station" / "bezitopo_topo0_pnezd.asc"
    with open(path, newline="") as fh:
        return path, [r for r in csv.reader(fh) if r]


def test_total_station_survey_in_us_feet():
    from crashsim.survey.points import read_points

    path, rows = _pnezd()
    d = read_points(str(path), "us_ft")
    assert sum(len(e.points) for e in d.entities) == len(rows) == 1311
    codes = Counter(r[4].strip() for r in rows)
    assert codes["EP"] == 29 and codes["BC"] == 27 and codes["BOC"] == 22
    per_code = Counter()
    for e in d.entities:
        per_code[e.layer] += len(e.points)
    # the crew's control words: "BC B" begins a BC string, "BC E" (or "EP          E") ends one
    words = Counter(" ".join(r[4].split()) for r in rows)
    assert words["BC B"] == 3 and words["BC E"] == 1 and words["EP E"] == 1
    for code in ("EP", "BC", "BOC", "SW", "TOPWALL"):
        assert per_code[code] == words[code] + words[f"{code} B"] + words[f"{code} E"]
    # coordinates: point 1 at N 538542.57, E 1455644.371 US survey feet
    first = {e.ref.split("-")[0]: e for e in d.entities}["1"]
    np.testing.assert_allclose(first.points[0], [1455644.371 * FTUS, 538542.57 * FTUS], rtol=1e-15)
    # strings: a run of EP points in file order is one polyline through them
    ep = [e for e in d.entities if e.layer == "EP" and e.geometry == "line"]
    assert ep and all(len(e.points) >= 2 for e in ep)
    lo, hi = d.extents()
    assert lo / FTUS == pytest.approx([1454147, 538403], abs=1.0) and hi / FTUS == pytest.approx([1455710, 539260],
                                                                                                   abs=1.0)


def test_breaklines_of_the_survey():
    from crashsim.survey.points import read_points

    path, rows = _pnezd()
    brk = DATA / "total_station" / "bezitopo_topo0_breaklines.brk"
    chains = [ln.strip().split("-") for ln in brk.read_text().splitlines() if ln.strip()]
    d = read_points(str(path), "us_ft", breaklines=str(brk))
    lines = [e for e in d.entities if e.geometry == "line"]
    assert len(lines) == len(chains) == 35
    closed = [c for c in chains if len(c) > 2 and c[0] == c[-1]]
    assert sum(e.closed for e in lines) == len(closed) >= 1
    byn = {r[0]: (float(r[2]), float(r[1])) for r in rows}
    c = chains[9]  # 875-876-877
    e = next(x for x in lines if x.ref == f"{c[0]}-{c[-1]}")
    np.testing.assert_allclose(e.points, np.array([byn[n] for n in c]) * FTUS, rtol=1e-15)
    # every point once: in a chain (a point may join two chains) or alone
    in_chains = {n for c in chains for n in c}
    alone = [e for e in d.entities if e.geometry == "point"]
    assert len(in_chains) + len(alone) == 1311


def test_leica_export_raw_rows_and_undotted_coordinates_flagged():
    from crashsim.survey.points import read_points

    path = DATA / "total_station" / "totalopenstation_Leica1200.rw5.csv"
    d = read_points(str(path), "ft", "--PD-----NEZ")
    (e,) = d.entities
    assert (e.layer, e.ref) == ("FENCE1", "108")
    np.testing.assert_array_equal(e.points, [[942130662 * 0.3048, 16556174237 * 0.3048]])
    assert any(n.startswith("row 1 is a header: Rec_Desc") for n in d.notes)
    assert any("9 rows without coordinates" in n for n in d.notes)
    assert any("without a decimal point" in n and "16556174237" in n for n in d.notes)


@pytest.mark.parametrize("name, roads, junctions", [("osm2streets_tiny_roundabout", 4, 4),
                                                    ("osm2streets_perth_stretched_lights", 39, 32),
                                                    ("osm2streets_quad_intersection", 92, 84)])
def test_osm_geojson_junctions(name, roads, junctions):
    pyproj = pytest.importorskip("pyproj")
    from crashsim.survey.geojson import read_geojson

    path = DATA / "geojson" / f"{name}.geojson"
    doc = json.loads(path.read_text())
    lon, lat = doc["features"][0]["geometry"]["coordinates"][0][0]
    zone = int((lon + 180) // 6) + 1
    crs = f"EPSG:{32600 + zone if lat >= 0 else 32700 + zone}"
    d = read_geojson(str(path), crs, layer_property="type")
    layers = d.layers()
    assert sum(layers["road"].values()) == roads and sum(layers["intersection"].values()) == junctions
    assert all(e.closed for e in d.entities)
    ring = doc["features"][0]["geometry"]["coordinates"][0]
    assert len(d.entities[0].points) == len(ring) - 1  # the repeated closing vertex dropped
    t = pyproj.Transformer.from_crs("EPSG:4326", crs, always_xy=True)
    np.testing.assert_allclose(d.entities[0].points[0], t.transform(lon, lat), atol=1e-6)


def test_geotiff_orthophoto_and_its_world_file_agree(tmp_path):
    rasterio = pytest.importorskip("rasterio", reason="the geotiff extra (rasterio) is not installed")
    import shutil

    from crashsim.survey.frame import SceneFrame
    from crashsim.survey.underlay import georef_from_section, load_image

    src = DATA / "ortho" / "weitsicht_vienna_44_2_op_2023_30cm.tif"
    with rasterio.open(src) as ds:
        t, shape, bounds = ds.transform, (ds.height, ds.width), ds.bounds
    shutil.copy(src, tmp_path / "ortho.tif")
    u = {"image": "ortho.tif", "world_file": None, "units": "m", "fit": "similarity", "tolerance": 0.1,
         "opacity": 0.6, "clip": True, "control": []}
    frame = SceneFrame((-1500.0, 338500.0), 0.0)
    g = georef_from_section(u, frame, str(tmp_path / "scene.toml"))
    assert g.how == "GeoTIFF transform" and g.pixel_size == pytest.approx(0.29994, abs=1e-4)
    np.testing.assert_allclose(g.to_scene([[0, 0]])[0], [bounds.left + 1500, bounds.top - 338500], atol=1e-6)
    assert bounds.left == pytest.approx(-1750, abs=0.5)  # negative eastings
    img = load_image(u, str(tmp_path / "scene.toml"))
    assert img.shape[:2] == shape == (1667, 1667)
    # the same image with a world file written from its transform (pixel centres): the same map
    (tmp_path / "ortho.tfw").write_text("\n".join(map(repr, (t.a, t.d, t.b, t.e, t.c + t.a / 2, t.f + t.e / 2))))
    g2 = georef_from_section(u, frame, str(tmp_path / "scene.toml"))
    assert g2.how == "world file ortho.tfw"
    np.testing.assert_allclose(g2.matrix, g.matrix, atol=1e-9)


def test_nhtsa_recorder_series_through_the_csv_path(tmp_path):
    """NHTSA CISS pre-crash series (2 Hz, 10 Hz) written as the CSV a download tool gives, read
    back: every pre-crash sample, speeds converted from km/h, the brake as a lower bound."""
    from crashsim.survey.recorder import read_recorder

    for name, n in (("drivetslm_ciss_2022_25581_v1", 11), ("drivetslm_ciss_2022_25493_v1", 50)):
        ch = json.loads((DATA / "edr" / f"{name}.json").read_text())["channels"]
        sp = ch["speed"]
        brake = next((c for k, c in ch.items() if "brake" in k), None)
        rows = ["Time (s),Speed (km/h),Service brake"]
        for i, (t, v) in enumerate(zip(sp["t"], sp["v"])):
            b = brake["v"][i] if brake is not None and i < len(brake["v"]) else 0
            rows.append(f"{t},{v},{'On' if b in (1, 1.0, 'On', 'on') else 'Off'}")
        p = tmp_path / f"{name}.csv"
        p.write_text("\n".join(rows) + "\n")
        spec = {"time": "Time (s)", "speed": "Speed (km/h)", "brake": "Service brake", "abs": None,
                "accelerator": None, "steering": None, "yaw_rate": None, "time_unit": "s", "speed_unit": "km/h",
                "on": "on", "time_offset": 0.0}
        samples, _ = read_recorder(str(p), spec)
        assert len(samples) == len(sp["t"]) == n
        np.testing.assert_allclose([s[1] for s in samples], np.asarray(sp["v"]) / 3.6, rtol=1e-15)


def test_sgo_incident_table_is_not_a_recorder_series():
    from crashsim.survey.recorder import read_recorder

    spec = {"time": "Time (s)", "speed": "SV Precrash Speed (MPH)", "brake": None, "abs": None, "accelerator": None,
            "steering": None, "yaw_rate": None, "time_unit": "s", "speed_unit": "mph", "on": "on", "time_offset": 0.0}
    with pytest.raises(ScenarioError, match=r"has no column 'Time \(s\)'; nearest: .*Columns: 'Report ID'"):
        read_recorder(str(DATA / "edr" / "nhtsa_sgo_2021-01_incident_reports_ADS.csv"), spec)


def test_survey_command_on_a_lonlat_geojson_picks_its_utm_zone(capsys):
    from crashsim.cli import main

    path = DATA / "geojson" / "osm2streets_perth_stretched_lights.geojson"
    assert main(["survey", str(path), "--layer-property", "type"]) == 0
    out = capsys.readouterr().out
    assert "UTM zone 50S (EPSG:32750)" in out  # Perth: 115.9 E, 32.0 S
    assert "intersection  32 Polygon" in out and "road          39 Polygon" in out

"""Survey readers on the project's own fixtures: a DXF written by hand to the DXF reference (R12),
DXF written by ezdxf (every entity type taken, blocks, units), point files (string conventions)
and GeoJSON (projection)."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.survey.dxf import read_dxf
from crashsim.survey.geojson import read_geojson
from crashsim.survey.points import read_points, split_code

ezdxf = pytest.importorskip("ezdxf")
HAND = Path(__file__).resolve().parents[1] / "data" / "survey" / "r12_by_hand.dxf"


def _by_ref(data):
    return {e.ref: e for e in data.entities}


def test_r12_written_by_hand():
    d = read_dxf(str(HAND))
    assert d.unit == "m" and not d.skipped
    e = _by_ref(d)
    assert set(e) == {"20", "21", "26", "27", "28", "29"}  # VERTEX/SEQEND belong to the POLYLINE
    np.testing.assert_array_equal(e["20"].points, [[100, 200], [150, 200]])
    # the bulge 1 between (120, 196) and (130, 196) is a half circle of radius 5 about (125, 196)
    kerb = e["21"].points
    np.testing.assert_array_equal(kerb[0], [100, 196])
    np.testing.assert_allclose(kerb[-1], [130, 196], atol=1e-12)
    arc = kerb[2:-1]
    assert len(arc) >= 5
    np.testing.assert_allclose(np.hypot(*(arc - [125, 196]).T), 5.0, atol=1e-9)
    # chords of the flattened circle and arc stay within the 1 cm chord tolerance
    circle = e["27"].points
    assert e["27"].closed
    np.testing.assert_allclose(np.hypot(*(circle - [140, 205]).T), 0.5, atol=1e-12)
    step = 2 * math.pi / len(circle)
    assert 0.5 * (1 - math.cos(step / 2)) <= 0.01
    arc = e["28"].points
    np.testing.assert_allclose(np.hypot(*(arc - [150, 190]).T), 6.0, atol=1e-9)
    np.testing.assert_allclose(arc[[0, -1]], [[156, 190], [150, 196]], atol=1e-9)
    assert e["29"].geometry == "text" and e["29"].text == "north edge"
    assert e["26"].geometry == "point"


def _doc(insunits=6):
    doc = ezdxf.new("R2018")
    doc.header["$INSUNITS"] = insunits
    return doc, doc.modelspace()


def test_ezdxf_entities_blocks_and_unsupported(tmp_path):
    doc, msp = _doc(6)
    msp.add_lwpolyline([(0, 0), (10, 0), (10, 5)], close=True, dxfattribs={"layer": "ZONE"})
    msp.add_polyline3d([(0, 0, 1), (1, 1, 2), (2, 0, 3)], dxfattribs={"layer": "3D"})
    msp.add_mtext("rest\\Pof car", dxfattribs={"layer": "T", "insert": (3, 4)})
    msp.add_ellipse((0, 0), major_axis=(2, 0), ratio=0.5, dxfattribs={"layer": "E"})
    msp.add_spline([(0, 0), (1, 2), (3, 1), (4, 4)], dxfattribs={"layer": "S"})
    blk = doc.blocks.new("POST")
    blk.add_circle((0, 0), 0.1)                          # layer 0: takes the INSERT's layer
    blk.add_line((0, 0), (1, 0), dxfattribs={"layer": "OWN"})
    msp.add_blockref("POST", (50, 60), dxfattribs={"layer": "POSTS", "xscale": 2, "yscale": 2, "rotation": 90})
    hatch = msp.add_hatch(dxfattribs={"layer": "H"})
    hatch.paths.add_polyline_path([(0, 0), (1, 0), (1, 1)])
    msp.add_3dface([(0, 0), (1, 0), (1, 1)], dxfattribs={"layer": "H"})
    msp.add_3dface([(0, 0), (1, 0), (1, 1)], dxfattribs={"layer": "H"})
    p = tmp_path / "a.dxf"
    doc.saveas(p)
    d = read_dxf(str(p))
    kinds = {(e.layer, e.dxftype) for e in d.entities}
    assert {("ZONE", "LWPOLYLINE"), ("3D", "POLYLINE"), ("T", "MTEXT"), ("E", "ELLIPSE"), ("S", "SPLINE"),
            ("POSTS", "CIRCLE"), ("OWN", "LINE")} == kinds
    assert d.skipped == {"HATCH": 1} and len(d.faces) == 2  # 3DFACEs are TIN faces (kind = "surface")
    warn = d.skipped_warning()
    assert "1 entities" in warn and "1 HATCH" in warn
    ents = {e.layer: e for e in d.entities}
    assert ents["ZONE"].closed and len(ents["ZONE"].points) == 3
    np.testing.assert_array_equal(ents["3D"].points, [[0, 0], [1, 1], [2, 0]])  # z dropped
    assert ents["T"].text == "rest\nof car"
    # the block's circle: radius 0.1 scaled by 2 about the insertion point
    np.testing.assert_allclose(np.hypot(*(ents["POSTS"].points - [50, 60]).T), 0.2, atol=1e-12)
    # the block's line (1, 0) turned by 90 deg and scaled by 2: from (50, 60) to (50, 62)
    np.testing.assert_allclose(ents["OWN"].points, [[50, 60], [50, 62]], atol=1e-12)
    assert ents["POSTS"].ref.endswith("/1") and ents["OWN"].ref.endswith("/2")
    # the ellipse: x^2/4 + y^2 = 1 on every vertex
    q = ents["E"].points
    np.testing.assert_allclose(q[:, 0] ** 2 / 4 + q[:, 1] ** 2, 1.0, atol=1e-9)


@pytest.mark.parametrize("code, unit, metres", [(1, "in", 0.0254), (2, "ft", 0.3048), (4, "mm", 1e-3),
                                                (21, "us_ft", 1200 / 3937)])
def test_drawing_units_from_the_header(tmp_path, code, unit, metres):
    doc, msp = _doc(code)
    msp.add_line((1000.0, 2000.0), (1001.0, 2000.0))
    p = tmp_path / "u.dxf"
    doc.saveas(p)
    d = read_dxf(str(p))
    assert d.unit == unit
    np.testing.assert_allclose(d.entities[0].points, np.array([[1000.0, 2000.0], [1001.0, 2000.0]]) * metres,
                               rtol=1e-15)
    assert read_dxf(str(p), unit).unit == unit  # the same unit given again: agreed


def test_units_contradicting_the_header_and_units_missing(tmp_path):
    doc, msp = _doc(6)
    msp.add_point((0, 0))
    p = tmp_path / "m.dxf"
    doc.saveas(p)
    with pytest.raises(ScenarioError, match=r"units = 'ft'.*\$INSUNITS = 6 \(m\)"):
        read_dxf(str(p), "ft")
    doc, msp = _doc(0)
    msp.add_point((0, 0))
    q = tmp_path / "none.dxf"
    doc.saveas(q)
    with pytest.raises(ScenarioError, match=r"does not state its units"):
        read_dxf(str(q))
    assert read_dxf(str(q), "mm").entities[0].points.shape == (1, 2)
    with pytest.raises(ScenarioError, match=r"unknown survey unit 'metre'"):
        read_dxf(str(q), "metre")


def test_not_a_dxf(tmp_path):
    p = tmp_path / "x.dxf"
    p.write_text("this is not a drawing\n")
    with pytest.raises(ScenarioError, match="DXF"):
        read_dxf(str(p))


# --------------------------------------------------------------------------- total-station points

def test_control_words():
    assert split_code("EP") == ("EP", None)
    assert split_code("EP TOP") == ("EP TOP", None)
    assert split_code("EP BEG") == ("EP", "begin")
    assert split_code("KERB --END") == ("KERB", "end")
    assert split_code("ISLAND clo") == ("ISLAND", "close")


def _write(tmp_path, rows, name="p.csv"):
    p = tmp_path / name
    p.write_text("\n".join(rows) + "\n")
    return str(p)


def test_strings_runs_controls_and_closing(tmp_path):
    rows = ["1,100.0,200.0,5,EP", "2,101.0,200.0,5,EP", "3,102.0,200.0,5,EP",
            "4,50.0,50.0,5,TREE",                                           # ends the EP run
            "5,103.0,200.0,5,EP", "6,104.0,200.0,5,EP END", "7,105.0,200.0,5,EP",
            "8,0,0,5,ISL BEG", "9,0,10,5,ISL", "10,10,10,5,ISL CLO"]
    d = read_points(_write(tmp_path, rows), "m")
    lines = [(e.layer, e.ref, len(e.points), e.closed) for e in d.entities if e.geometry == "line"]
    assert lines == [("EP", "1-3", 3, False), ("EP", "5-6", 2, False), ("ISL", "8-10", 3, True)]
    pts = [(e.layer, e.ref) for e in d.entities if e.geometry == "point"]
    assert pts == [("TREE", "4"), ("EP", "7")]
    # PNEZD: N is y, E is x
    first = next(e for e in d.entities if e.ref == "1-3")
    np.testing.assert_array_equal(first.points[0], [200.0, 100.0])
    # join = "code": the TREE shot does not end the EP string
    d = read_points(_write(tmp_path, rows), "m", join="code")
    assert [(e.layer, e.ref) for e in d.entities if e.geometry == "line" and e.layer == "EP"] == \
        [("EP", "1-6")]


def test_units_columns_header_and_quoting(tmp_path):
    rows = ['Pt,X,Y,Z,Desc', '1,10.5,20.25,1,"TFW 6"" CONC"', '2,11.5,20.25,1,"TFW 6"" CONC"']
    d = read_points(_write(tmp_path, rows), "ft", "PXYZD")
    assert d.notes[0].startswith("row 1 is a header")
    (e,) = d.entities
    assert e.layer == 'TFW 6" CONC'
    np.testing.assert_allclose(e.points, np.array([[10.5, 20.25], [11.5, 20.25]]) * 0.3048, rtol=1e-15)
    with pytest.raises(ScenarioError, match="columns = 'PQZD'"):
        read_points(_write(tmp_path, rows), "ft", "PQZD")
    with pytest.raises(ScenarioError, match=r"row 3: easting or x 'y', northing or y 'x' are not numbers"):
        read_points(_write(tmp_path, ["1,1,1,0,A", "2,2,2,0,A", "3,x,y,0,A"]), "m")


def test_breaklines(tmp_path):
    rows = [f"{i},{i}.0,{2 * i}.0,0,WALL" for i in range(1, 7)]
    brk = tmp_path / "b.brk"
    brk.write_text("1-2-3\n4-5-6-4\n")
    d = read_points(_write(tmp_path, rows), "m", breaklines=str(brk))
    lines = sorted((e.ref, len(e.points), e.closed) for e in d.entities)
    assert lines == [("1-3", 3, False), ("4-6", 3, True)]
    brk.write_text("1-9\n")
    with pytest.raises(ScenarioError, match="point 9 is not in"):
        read_points(_write(tmp_path, rows), "m", breaklines=str(brk))


# --------------------------------------------------------------------------- GeoJSON

pyproj = pytest.importorskip("pyproj")


def _feature(geom, **props):
    return {"type": "Feature", "properties": props, "geometry": geom}


def test_geojson_lonlat_lands_on_its_projected_twin(tmp_path):
    """The same junction in lon/lat and in UTM 33N (its twin, projected here by pyproj): both
    imported into UTM 33N land within 1 cm (the test asks 1 mm)."""
    lonlat = np.array([[16.3725, 48.2082], [16.3731, 48.2085], [16.3740, 48.2081]])
    t = pyproj.Transformer.from_crs("EPSG:4326", "EPSG:32633", always_xy=True)
    utm = np.column_stack(t.transform(lonlat[:, 0], lonlat[:, 1]))
    a = tmp_path / "ll.geojson"
    a.write_text(json.dumps({"type": "FeatureCollection", "features": [
        _feature({"type": "LineString", "coordinates": lonlat.tolist()}, layer="kerb"),
        _feature({"type": "Point", "coordinates": lonlat[0].tolist()}, layer="poi")]}))
    b = tmp_path / "utm.geojson"
    b.write_text(json.dumps({"type": "FeatureCollection",
                             "crs": {"type": "name", "properties": {"name": "urn:ogc:def:crs:EPSG::32633"}},
                             "features": [_feature({"type": "LineString", "coordinates": utm.tolist()}, layer="kerb"),
                                          _feature({"type": "Point", "coordinates": utm[0].tolist()}, layer="poi")]}))
    da, db = read_geojson(str(a), "EPSG:32633"), read_geojson(str(b), "EPSG:32633")
    assert [e.layer for e in da.entities] == [e.layer for e in db.entities] == ["kerb", "poi"]
    for ea, eb in zip(da.entities, db.entities):
        assert np.max(np.hypot(*(ea.points - eb.points).T)) < 1e-3
    # a rough scale check that it is metres: about 45 m between the first two vertices
    assert 40 < np.hypot(*(da.entities[0].points[1] - da.entities[0].points[0])) < 60


def test_geojson_feet_crs_converted_to_metres(tmp_path):
    p = tmp_path / "ft.geojson"
    p.write_text(json.dumps({"type": "FeatureCollection", "features": [
        _feature({"type": "Point", "coordinates": [1455000.0, 538400.0]}, layer="a")]}))
    d = read_geojson(str(p), "EPSG:2264", crs="EPSG:2264")  # NC State Plane, US survey feet
    np.testing.assert_allclose(d.entities[0].points, [[1455000.0 * 1200 / 3937, 538400.0 * 1200 / 3937]],
                               rtol=1e-12)


def test_geojson_polygon_holes_and_bad_crs(tmp_path):
    p = tmp_path / "h.geojson"
    ring = [[0, 0], [10, 0], [10, 10], [0, 10], [0, 0]]
    hole = [[2, 2], [3, 2], [3, 3], [2, 2]]
    p.write_text(json.dumps({"type": "FeatureCollection", "features": [
        _feature({"type": "Polygon", "coordinates": [ring, hole]}, kind="island")]}))
    d = read_geojson(str(p), None, crs="EPSG:32633", layer_property="kind")
    (e,) = d.entities
    assert e.closed and len(e.points) == 4 and e.layer == "island"
    assert any("1 holes" in n for n in d.notes)
    with pytest.raises(ScenarioError, match=r"'EPSG:999999' is not a coordinate reference system"):
        read_geojson(str(p), "EPSG:999999")
    with pytest.raises(ScenarioError, match="is not a projected CRS"):
        read_geojson(str(p), "EPSG:4326")
    with pytest.raises(ScenarioError, match="longitude/latitude"):
        read_geojson(str(p), None)


@pytest.mark.parametrize("bulge", [0.3, -0.3, 1.0, 2.0, -2.5])
def test_bulged_segments_are_exact_arcs(tmp_path, bulge):
    """Against ezdxf's own bulge_to_arc (centre and radius of the DXF reference's bulge): every
    flattened point on the circle to round-off, the ends kept, chords within the tolerance."""
    from ezdxf.math import bulge_to_arc

    doc, msp = _doc(6)
    msp.add_lwpolyline([(0, 0, bulge), (4, 1, 0)], format="xyb")
    p = tmp_path / "b.dxf"
    doc.saveas(p)
    pts = read_dxf(str(p), chord_tolerance=0.001).entities[0].points
    c, _, _, r = bulge_to_arc((0, 0), (4, 1), bulge)
    np.testing.assert_allclose(np.hypot(*(pts - [c.x, c.y]).T), r, atol=1e-12)
    np.testing.assert_allclose(pts[[0, -1]], [[0, 0], [4, 1]], atol=1e-12)
    half = np.hypot(*np.diff(pts, axis=0).T) / 2
    assert np.max(r - np.sqrt(r * r - half * half)) <= 0.001 + 1e-12


def test_fast_path_gives_the_entities_ezdxf_gives(tmp_path):
    """The fast reader of simple ASCII drawings against the full ezdxf reading, entity by entity
    (coordinates equal to the last bit); a drawing with another type goes through ezdxf."""

    from crashsim.survey import dxf as m

    rng = np.random.default_rng(3)
    doc, msp = _doc(2)
    base = np.array([1_455_000.0, 538_400.0])
    for i in range(300):
        p = base + rng.uniform(0, 300, 2)
        msp.add_line(p, p + rng.normal(0, 3, 2), dxfattribs={"layer": f"L{i % 7}"})
        msp.add_lwpolyline((p + np.cumsum(rng.normal(0, 1, (4, 2)), axis=0)).tolist(), close=bool(i % 2),
                           dxfattribs={"layer": f"P{i % 3}"})
        msp.add_point(p, dxfattribs={"layer": "PTS"})
        msp.add_arc(p, 2.5, 10.0 + i % 150, 200.0, dxfattribs={"layer": "ARC"})
        msp.add_circle(p, 0.3 + i / 1000, dxfattribs={"layer": "POLE"})
        msp.add_text(f"t{i}", dxfattribs={"layer": "T", "insert": p})
    doc.paperspace().add_line((0, 0), (1, 1))  # paper space: not part of the scene
    path = tmp_path / "simple.dxf"
    doc.saveas(path)
    fast = read_dxf(str(path))
    full = read_dxf(str(path), fast=False)
    assert len(fast.entities) == len(full.entities) == 1800
    for a, b in zip(fast.entities, full.entities):
        assert (a.layer, a.ref, a.geometry, a.closed, a.text, a.dxftype) == \
            (b.layer, b.ref, b.geometry, b.closed, b.text, b.dxftype)
        np.testing.assert_array_equal(a.points, b.points)
    assert fast.unit == full.unit == "ft" and fast.notes == full.notes
    # its speed against ezdxf's document is measured by benchmarks/survey_import.py, not here
    # the fast path declines what it does not read, and ezdxf reads it
    msp.add_blockref("X", (0, 0)) if "X" in doc.blocks else (doc.blocks.new("X").add_point((0, 0)),
                                                             msp.add_blockref("X", (0, 0)))
    doc.saveas(path)
    with pytest.raises(m._NotFast):
        m._read_fast(str(path), 0.01, lambda h: ("ft", 0.3048))
    assert len(read_dxf(str(path)).entities) == 1801

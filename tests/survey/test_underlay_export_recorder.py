"""Underlay georeferencing (world file against control points), CAD export round trips and the
recorder table import."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.survey.frame import SceneFrame
from crashsim.survey.underlay import Georef, fit_control_points, georef_from_section, read_world_file

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml"


def _section(**kw):
    base = {"image": "ortho.png", "world_file": None, "units": "m", "fit": "similarity", "tolerance": 0.1,
            "opacity": 0.6, "clip": True, "control": []}
    base.update(kw)
    return base


def _world(tmp_path, a=0.05, d=0.01, b=0.01, e=-0.05, c=1000.0, f=2000.0):
    p = tmp_path / "ortho.pgw"
    p.write_text("\n".join(map(str, (a, d, b, e, c, f))) + "\n")
    (tmp_path / "ortho.png").write_bytes(b"")  # only its name is used here
    return p


@pytest.mark.parametrize("how", ["similarity", "affine"])
def test_world_file_and_control_points_of_one_image_agree(tmp_path, how):
    """A world file with a rotation, and control points measured on the same image (five, with
    2 mm of scatter): both place every pixel of a 2000 x 1500 image within 5 mm of each other."""
    _world(tmp_path)
    frame = SceneFrame((1000.0, 2000.0), math.radians(10.0))
    base = str(tmp_path / "scene.toml")
    g_world = georef_from_section(_section(), frame, base)
    m = read_world_file(str(tmp_path / "ortho.pgw"))
    pix = np.array([[10.0, 20.0], [1900.0, 40.0], [1850.0, 1400.0], [30.0, 1450.0], [1000.0, 700.0]])
    rng = np.random.default_rng(1)
    pos = pix @ m[:, :2].T + m[:, 2] + rng.normal(0, 0.002, pix.shape)
    ctl = [{"pixel": tuple(p), "position": tuple(q)} for p, q in zip(pix, pos)]
    g_ctl = georef_from_section(_section(control=ctl, fit=how), frame, base)
    grid = np.array([[c, r] for c in (0, 1000, 2000) for r in (0, 750, 1500)], dtype=float)
    assert np.max(np.hypot(*(g_world.to_scene(grid) - g_ctl.to_scene(grid)).T)) < 0.005
    assert g_ctl.residuals.max() < 0.01 and len(g_ctl.residuals) == 5
    assert g_world.pixel_size == pytest.approx(math.sqrt(0.05 * 0.05 + 0.01 * 0.01), rel=1e-12)
    # the centre of the top left pixel is (C, F) of the world file, in the scene frame
    np.testing.assert_allclose(g_world.to_scene([[0.5, 0.5]])[0], frame.to_scene([[1000.0, 2000.0]])[0], atol=1e-9)
    np.testing.assert_allclose(g_world.to_pixels(g_world.to_scene(grid)), grid, atol=1e-9)


def test_bad_control_points_and_world_files(tmp_path):
    _world(tmp_path)
    frame, base = SceneFrame(), str(tmp_path / "scene.toml")
    good = [{"pixel": (0.0, 0.0), "position": (0.0, 0.0)}, {"pixel": (100.0, 0.0), "position": (5.0, 0.0)},
            {"pixel": (0.0, 100.0), "position": (0.0, -5.0)}]
    bad = good + [{"pixel": (100.0, 100.0), "position": (5.5, -5.0)}]  # 0.5 m off
    with pytest.raises(ScenarioError, match=r"control point 3 \(100, 100\) lies 0\.25 m from where the similarity "
                                            r"fit puts it \(tolerance 0\.1 m"):
        georef_from_section(_section(control=bad), frame, base)
    line = [{"pixel": (float(i), 2.0 * i), "position": (float(i), 0.0)} for i in (0, 10, 20)]
    with pytest.raises(ScenarioError, match="lie on one line"):
        georef_from_section(_section(control=line, fit="affine"), frame, base)
    with pytest.raises(ScenarioError, match="a similarity needs at least 2"):
        georef_from_section(_section(control=good[:1]), frame, base)
    with pytest.raises(ScenarioError, match="not both"):
        georef_from_section(_section(control=good, world_file="ortho.pgw"), frame, base)
    (tmp_path / "ortho.pgw").write_text("1\n0\n0\n")
    with pytest.raises(ScenarioError, match="six numbers"):
        georef_from_section(_section(), frame, base)
    (tmp_path / "ortho.pgw").unlink()
    with pytest.raises(ScenarioError, match="no world file beside it"):
        georef_from_section(_section(), frame, base)
    m, res = fit_control_points([c["pixel"] for c in good], [c["position"] for c in good], "affine")
    np.testing.assert_allclose(res, 0.0, atol=1e-12)


def test_world_file_units_converted(tmp_path):
    _world(tmp_path, a=0.5, d=0.0, b=0.0, e=-0.5, c=100.0, f=200.0)
    g = georef_from_section(_section(units="us_ft"), SceneFrame(), str(tmp_path / "scene.toml"))
    assert g.pixel_size == pytest.approx(0.5 * 1200 / 3937, rel=1e-12)


def test_underlay_under_the_shipped_scene_figure():
    """The shipped survey scene's figure carries the orthophoto (gid "underlay") under every other
    artist, placed by its world file: the road's centre line (y = 1.8 m in the scene) over the
    image's yellow line pixels."""
    import matplotlib

    matplotlib.use("Agg")
    from crashsim.reconstruct import run_scene
    from crashsim.scenario import load_scenario
    from crashsim.plotting import plot_scene
    from crashsim.survey.underlay import scene_underlay

    sc = load_scenario(SHIPPED)
    image, g, opacity, clip = scene_underlay(sc)
    assert g.how == "world file ortho.pgw" and opacity == 0.7
    # pixels of the scene point (x, 1.8 m) are yellow (the generator's centre line colour)
    for x in (-30.0, 0.0, 20.0):
        c, r = g.to_pixels([[x, 1.8]])[0]
        rgb = image[int(r), int(c), :3]
        assert rgb[0] > 0.8 and rgb[1] > 0.7 and rgb[2] < 0.4, (x, rgb)
    data = dict(sc.data)
    import dataclasses

    quick = dataclasses.replace(sc, runout=None)  # the figure's underlay, not the run, under test
    ax = plot_scene(run_scene(quick), approach=False)
    art = [a for a in ax.get_images() if a.get_gid() == "underlay"]
    assert len(art) == 1 and art[0].get_zorder() < min(p.get_zorder() for p in ax.patches)
    assert art[0].get_alpha() == 0.7
    # clipped to the view and half its span around it (the animation widens the view later), as far
    # as the image reaches
    c0, c1, r1, r0 = art[0].get_extent()
    corners = g.to_scene([[c0, r0], [c1, r0], [c1, r1], [c0, r1]])
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    k = 0.3048  # the figure is in feet
    whole = g.to_scene([[0, 0], [image.shape[1], 0], [image.shape[1], image.shape[0]], [0, image.shape[0]]])
    for lo_hi, axis in (((x0, x1), 0), ((y0, y1), 1)):
        span = (lo_hi[1] - lo_hi[0]) * k
        want_lo = max(lo_hi[0] * k - 0.4 * span, whole[:, axis].min() + 1.0)
        want_hi = min(lo_hi[1] * k + 0.4 * span, whole[:, axis].max() - 1.0)
        assert corners[:, axis].min() <= want_lo and corners[:, axis].max() >= want_hi
    import matplotlib.pyplot as plt

    plt.close(ax.figure)
    assert data  # the scenario's data were not changed by drawing


def test_clip_draws_the_view_and_half_its_span_around_it():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from crashsim.survey.underlay import draw_underlay

    g = Georef(np.array([[0.1, 0.0, 0.0], [0.0, -0.1, 100.0]]), "test")  # 0.1 m pixels, north up
    image = np.zeros((1000, 1000, 3))
    fig, ax = plt.subplots()
    ax.set_xlim(40, 60)
    ax.set_ylim(40, 50)
    art = draw_underlay(ax, image, g, opacity=0.5, clip=True)
    c0, c1, r1, r0 = art.get_extent()
    # x 30..70 m and y 35..55 m, a pixel either side
    assert (c0, c1) == (299, 701) and (r0, r1) == (449, 651)
    assert ax.get_xlim() == (40, 60) and ax.get_ylim() == (40, 50)
    whole = draw_underlay(ax, image, g, clip=False)
    assert tuple(whole.get_extent()) == (0, 1000, 1000, 0)
    plt.close(fig)


# --------------------------------------------------------------------------- export

ezdxf = pytest.importorskip("ezdxf")


@pytest.fixture(scope="module")
def shipped_scene():
    from crashsim.reconstruct import run_scene
    from crashsim.scenario import load_scenario

    return run_scene(load_scenario(SHIPPED))


def test_export_dxf_round_trip(shipped_scene, tmp_path):
    """Export -> import gives the same geometry to 1e-9 m: every outline, path, track and evidence
    item, through the survey's frame (turned 30 deg, origin at 1.45e6 ft) and US survey feet."""
    from crashsim.survey.dxf import read_dxf
    from crashsim.survey.export import export_frame, export_items, write_dxf

    frame, unit = export_frame(shipped_scene.scenario)
    assert unit == "us_ft" and frame.rotation == pytest.approx(math.radians(30))
    items = export_items(shipped_scene, times=(0.5, 1.0))
    path = write_dxf(items, tmp_path / "out.dxf", frame, unit)
    back = read_dxf(path)
    assert back.unit == "us_ft" and not back.skipped
    assert len(back.entities) == len(items)
    for it, e in zip(items, back.entities):
        assert e.layer == it.layer and e.closed == it.closed and e.text == it.text
        assert np.max(np.abs(frame.to_scene(e.points) - it.points)) < 1e-9
    layers = {it.layer for it in items}
    for body in ("tractor", "trailer", "car"):
        assert {f"CRASHSIM-IMPACT-{body}", f"CRASHSIM-REST-{body}", f"CRASHSIM-CG-{body}",
                f"CRASHSIM-T0.5-{body}", f"CRASHSIM-T1-{body}"} <= layers
    assert {"CRASHSIM-TRACK-SLIDING", "CRASHSIM-IMPACTS", "CRASHSIM-EVIDENCE-PASS"} <= layers
    # the outline at rest is the body's outline at its rest pose
    rest = next(it for it in items if it.layer == "CRASHSIM-REST-car")
    br = shipped_scene.runout_body("car")
    assert np.mean(rest.points, axis=0) == pytest.approx(
        np.asarray(br.rest_position) + 0.15 * np.array([math.cos(br.rest_heading), math.sin(br.rest_heading)]),
        abs=1e-9)
    # the verdict texts say what the report says
    texts = [it.text for it in items if it.geometry == "text" and it.layer.startswith("CRASHSIM-EVIDENCE")]
    assert any(t.startswith("pre-impact skid, tractor/1/left: PASS") for t in texts)


@pytest.mark.parametrize("name, unit", [("truck_brakes_into_car", "ft"), ("barrier_15deg", "m")])
def test_a_scene_without_a_survey_exports_in_its_report_units(name, unit, tmp_path):
    """No [survey]: the scene's own axes, in feet for a scene in US units ($INSUNITS 2) and metres
    otherwise (6); read back, the same geometry."""
    import ezdxf

    from crashsim.reconstruct import run_scene
    from crashsim.scenario import load_scenario
    from crashsim.survey.dxf import read_dxf
    from crashsim.survey.export import export_frame, export_items, write_dxf

    scene = run_scene(load_scenario(ROOT / "scenarios" / "scenes" / f"{name}.toml"))
    frame, got = export_frame(scene.scenario)
    assert got == unit and frame == SceneFrame()
    items = export_items(scene)
    path = write_dxf(items, tmp_path / "out.dxf", frame, got)
    assert ezdxf.readfile(path).header["$INSUNITS"] == {"ft": 2, "m": 6}[unit]
    back = read_dxf(path)
    for it, e in zip(items, back.entities):
        assert np.max(np.abs(frame.to_scene(e.points) - it.points)) < 1e-9


def test_export_geojson_round_trip(shipped_scene, tmp_path):
    from crashsim.survey.export import export_frame, export_items, write_geojson

    frame, unit = export_frame(shipped_scene.scenario)
    items = export_items(shipped_scene)
    path = write_geojson(items, tmp_path / "out.geojson", frame, unit)
    doc = json.loads(Path(path).read_text())
    assert len(doc["features"]) == len(items) and doc["crashsim_units"] == "us_ft"
    k = 1200 / 3937
    for it, f in zip(items, doc["features"]):
        g = f["geometry"]
        coords = np.asarray(g["coordinates"][0] if g["type"] == "Polygon" else
                            [g["coordinates"]] if g["type"] == "Point" else g["coordinates"], dtype=float)
        if g["type"] == "Polygon":
            coords = coords[:-1]
        assert np.max(np.abs(frame.to_scene(coords * k) - it.points)) < 1e-9


# --------------------------------------------------------------------------- recorder

def _spec(**kw):
    base = {"time": "t", "speed": "v", "time_unit": "s", "speed_unit": "km/h", "brake": None, "abs": None,
            "accelerator": None, "steering": None, "yaw_rate": None, "on": "on, 1", "time_offset": 0.0}
    base.update(kw)
    return base


def test_recorder_table(tmp_path):
    from crashsim.survey.recorder import read_recorder

    p = tmp_path / "r.csv"
    p.write_text("t;Speed (km/h);brk;ABS\n-1000;90;0;0\n-500;72;1;0\n;;;\n-100;60;0;1\n100;10;1;1\n")
    samples, notes = read_recorder(str(p), _spec(speed="Speed (km/h)", time_unit="ms", brake="brk", abs="ABS"))
    # the sample 0.1 s after the impact is kept (a fitted time_offset may bring it before the impact)
    # but not compared at the file's offset, and the notes say so
    assert [s[0] for s in samples] == pytest.approx([-1.0, -0.5, -0.1, 0.1], abs=0)
    assert [s[1] for s in samples] == pytest.approx([25.0, 20.0, 60 / 3.6, 10 / 3.6], rel=1e-15)
    assert [s[2] for s in samples] == [False, True, True, True]  # brake or ABS on: a lower bound
    assert any("1 samples after the impact with time_offset = 0 s are kept but not compared" in n for n in notes)
    p.write_text("t;Speed (km/h)\n-1000;90\n5001;10\n")
    samples, notes = read_recorder(str(p), _spec(speed="Speed (km/h)", time_unit="ms"))
    assert len(samples) == 1 and any("1 samples more than 5 s after the impact were left out" in n for n in notes)
    with pytest.raises(ScenarioError, match=r"has no column 'Speed \(mph\)'; nearest: 'Speed \(km/h\)'. Columns: 't', 'Speed"):
        read_recorder(str(p), _spec(speed="Speed (mph)"))
    with pytest.raises(ScenarioError, match=r"speed_unit = 'knots'"):
        read_recorder(str(p), _spec(speed="Speed (km/h)", speed_unit="knots"))


def test_shipped_recorder_is_the_typed_record():
    """The shipped scene's ECM table gives the samples typed in truck_brakes_into_car.toml (plus
    the sample at the impact, 31 mph with the brake on)."""
    from crashsim.scenario import load_scenario

    (rec,) = load_scenario(SHIPPED).evidence.recorder
    mph = 0.44704
    assert rec.times == pytest.approx((-5, -4, -3, -2, -1, 0), abs=0)
    assert np.asarray(rec.speeds) == pytest.approx(np.array([55, 54, 55, 55, 44, 31]) * mph, rel=1e-15)
    assert rec.lower_bound == (False, False, False, False, True, True)

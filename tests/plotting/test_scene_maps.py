"""The road layout on the scene diagram: friction zones and ``[[map.lines]]``, under Agg.

What is checked: every zone and map line is drawn (found by gid in the axes and in an SVG), a
zone's label names its friction and lies inside the zone, each line style is drawn in its own
way, and a zone or line reaching far from the scene does not pull the view away from the
vehicles (the limits stay within the region of interest).
"""

from __future__ import annotations

import dataclasses
import functools
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crashsim.motion import FrictionZone, Road  # noqa: E402
from crashsim.motion.road import points_in_polygon  # noqa: E402
from crashsim.plotting import plot_scene, save_scene_figures  # noqa: E402
from crashsim.plotting.road import clip_polygon, clip_polyline  # noqa: E402
from crashsim.plotting.style import MAP_STYLES  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import MAP_LINE_STYLES, MapLine, load_scenario  # noqa: E402
from crashsim.units import Kind, to_unit  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
VERGE = ROOT / "scenarios" / "scenes" / "verge_run_off.toml"
INTERSECTION = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


def _with_layout(scene, zones=(), lines=()):
    """The same computed scene with another road layout (drawing only: the run is not redone)."""
    sc = scene.scenario
    runout = dataclasses.replace(sc.runout, road=Road(sc.runout.road.mu, tuple(zones)))
    return dataclasses.replace(scene, scenario=dataclasses.replace(sc, runout=runout, map_lines=tuple(lines)))


def _by_gid(ax, gid):
    found = [a for a in [*ax.patches, *ax.lines, *ax.texts] if a.get_gid() == gid]
    assert len(found) <= 1
    return found[0] if found else None


def _limits(ax):
    return np.array([ax.get_xlim(), ax.get_ylim()]).T  # [[x0, y0], [x1, y1]]


def _vehicle_box(scene):
    """Box around every body outline at impact and at rest [m]."""
    from crashsim.geometry import to_world

    pts = []
    for v in scene.scenario.vehicles:
        for b in v.bodies:
            if b.outline() is None:
                continue
            st = scene.scenario.states[b.name]
            pts.append(to_world(b.outline(), st.position, st.heading))
            br = scene.runout_body(b.name)
            pts.append(to_world(b.outline(), br.rest_position, br.rest_heading))
    pts = np.vstack(pts)
    return pts.min(axis=0), pts.max(axis=0)


# ------------------------------------------------------------------------------------ geometry

def test_clip_polygon_to_a_box():
    square = np.array([[-1.0, -1.0], [3.0, -1.0], [3.0, 3.0], [-1.0, 3.0]])
    part = clip_polygon(square, np.array([0.0, 0.0]), np.array([2.0, 1.0]))
    x, y = part[:, 0], part[:, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert area == pytest.approx(2.0)  # the whole box
    assert part.min(axis=0) == pytest.approx([0.0, 0.0]) and part.max(axis=0) == pytest.approx([2.0, 1.0])
    # a triangle half inside: the clipped area is that of the part inside
    tri = np.array([[0.0, 0.0], [2.0, 0.0], [0.0, 2.0]])  # area 2; the part with x >= 1: (1,0) (2,0) (1,1)
    part = clip_polygon(tri, np.array([1.0, -5.0]), np.array([5.0, 5.0]))
    x, y = part[:, 0], part[:, 1]
    assert 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))) == pytest.approx(0.5)
    assert len(clip_polygon(square + 10.0, np.array([0.0, 0.0]), np.array([2.0, 1.0]))) == 0


def test_clip_polyline_to_a_box():
    lo, hi = np.array([0.0, 0.0]), np.array([10.0, 10.0])
    # in, out through the top, back in, out through the right: two pieces
    line = np.array([[5.0, 5.0], [5.0, 15.0], [8.0, 15.0], [8.0, 5.0], [20.0, 5.0]])
    pieces = clip_polyline(line, lo, hi)
    assert len(pieces) == 2
    np.testing.assert_allclose(pieces[0], [[5.0, 5.0], [5.0, 10.0]])
    np.testing.assert_allclose(pieces[1], [[8.0, 10.0], [8.0, 5.0], [10.0, 5.0]])
    assert clip_polyline(np.array([[-5.0, 20.0], [30.0, 20.0]]), lo, hi) == []
    # a segment along a side of the box is kept
    (edge,) = clip_polyline(np.array([[-5.0, 0.0], [30.0, 0.0]]), lo, hi)
    np.testing.assert_allclose(edge, [[0.0, 0.0], [10.0, 0.0]])


# ------------------------------------------------------------------------- the shipped scene

def test_zones_and_map_lines_in_the_svg(tmp_path):
    scene = _scene(VERGE)
    zones, lines = scene.scenario.runout.road.zones, scene.scenario.map_lines
    assert len(zones) == 1 and len(lines) == 7
    (path,) = save_scene_figures(scene, tmp_path / "verge.svg", dpi=60)
    svg = path.read_text()
    for i in range(len(zones)):
        assert f'id="zone:{i}"' in svg and f'id="zone-label:{i}"' in svg
    for i, ln in enumerate(lines):
        assert f'id="map:{i}"' in svg
        assert (f'id="map-label:{i}"' in svg) == bool(ln.name)
    assert "friction zone: grass verge, f = 0.4" in svg  # the legend entry (text kept as a comment)


def test_zone_label_names_the_friction_and_lies_inside_the_zone():
    scene = _scene(VERGE)
    ax = plot_scene(scene)
    (zone,) = scene.scenario.runout.road.zones
    label = _by_gid(ax, "zone-label:0")
    assert label.get_text() == f"grass verge, f = {zone.mu:g}" == "grass verge, f = 0.4"
    anchor = np.asarray(label.xy)
    assert points_in_polygon(anchor[None], zone.vertices)[0]
    (x0, y0), (x1, y1) = _limits(ax)
    assert x0 < anchor[0] < x1 and y0 < anchor[1] < y1
    # its text box does not cover any vehicle outline
    ax.figure.draw_without_rendering()
    bb = label.get_window_extent()
    for patch in ax.patches:
        if (patch.get_gid() or "").startswith(("outline:impact:", "outline:rest:")):
            assert not bb.overlaps(patch.get_window_extent()), patch.get_gid()
    # the zone is drawn under everything else, in a legend entry of its own
    patch = _by_gid(ax, "zone:0")
    assert patch.get_zorder() < min(a.get_zorder() for a in [*ax.lines, *ax.patches] if a is not patch)
    np.testing.assert_allclose(patch.get_xy()[:4], zone.vertices)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "friction zone: grass verge, f = 0.4" in texts
    assert "road surface outside the zones: f = 0.75" in texts


def test_the_view_keeps_the_vehicles_large():
    """The verge is 200 m long and the lines 200 m: the diagram stays on the 50 m of the scene."""
    scene = _scene(VERGE)
    ax = plot_scene(scene)
    (x0, y0), (x1, y1) = _limits(ax)
    lo, hi = _vehicle_box(scene)
    assert x0 < lo[0] and hi[0] < x1 and y0 < lo[1] and hi[1] < y1
    assert x1 - x0 < 1.6 * (hi[0] - lo[0])
    # the zone and the lines are cut by the axes
    assert np.ptp(_by_gid(ax, "zone:0").get_xy()[:, 0]) > 2 * (x1 - x0)


# ---------------------------------------------------------------- huge and far-away layouts

def test_a_huge_zone_does_not_shrink_the_vehicles():
    scene = _scene(INTERSECTION)
    base = _limits(plot_scene(scene, ax=plt.subplots()[1], legend=False))
    huge = FrictionZone(((-1000.0, -1000.0), (1000.0, -1000.0), (1000.0, 1000.0), (-1000.0, 1000.0)), 0.35,
                        "grass verge")
    road = MapLine("far edge", "edge", np.array([[-2000.0, 3.0], [2000.0, 3.0]]))
    ax = plot_scene(_with_layout(scene, [huge], [road]), ax=plt.subplots()[1], legend=False)
    lim = _limits(ax)
    span = float(np.ptp(base, axis=0).max())
    margin = max(3.0, 0.15 * span)  # the region of interest around the scene
    assert np.all(lim[0] >= base[0] - 1.2 * margin) and np.all(lim[1] <= base[1] + 1.2 * margin)
    assert np.all(np.ptp(lim, axis=0) < 2.0 * np.ptp(base, axis=0))
    assert _by_gid(ax, "zone:0") is not None and _by_gid(ax, "map:0") is not None
    assert _by_gid(ax, "zone-label:0").get_text() == "grass verge, f = 0.35"
    # and in US units the same view, in feet
    k, _ = to_unit(1.0, Kind.LENGTH, "US")
    ax_us = plot_scene(_with_layout(scene, [huge], [road]), ax=plt.subplots()[1], legend=False, system="US")
    np.testing.assert_allclose(_by_gid(ax_us, "zone:0").get_xy()[:4], k * huge.vertices)
    assert np.all(np.ptp(_limits(ax_us), axis=0) < 2.0 * k * np.ptp(base, axis=0))


def test_a_far_zone_and_line_leave_the_view_alone():
    scene = _scene(INTERSECTION)
    base = _limits(plot_scene(scene, ax=plt.subplots()[1], legend=False))
    far = FrictionZone(((500.0, 500.0), (600.0, 500.0), (600.0, 600.0)), 0.5, "gravel")
    line = MapLine("far kerb", "kerb", np.array([[500.0, -400.0], [900.0, -400.0]]))
    ax = plot_scene(_with_layout(scene, [far], [line]), ax=plt.subplots()[1], legend="best")
    np.testing.assert_allclose(_limits(ax), base, atol=1e-9)
    assert _by_gid(ax, "zone:0") is not None and _by_gid(ax, "map:0") is not None
    assert _by_gid(ax, "zone-label:0") is None and _by_gid(ax, "map-label:0") is None  # not in view
    assert "friction zone: gravel, f = 0.5" in [t.get_text() for t in ax.get_legend().get_texts()]


def test_a_near_line_widens_the_view_by_at_most_the_margin():
    scene = _scene(INTERSECTION)
    base = _limits(plot_scene(scene, ax=plt.subplots()[1], legend=False))
    lo, hi = _vehicle_box(scene)
    y = max(hi[1] + 2.0, base[1][1] + 0.5)  # 2 m from the vehicles, beyond the view without it
    line = MapLine("", "edge", np.array([[lo[0] - 1000.0, y], [hi[0] + 1000.0, y]]))
    ax = plot_scene(_with_layout(scene, (), [line]), ax=plt.subplots()[1], legend=False)
    (x0, y0), (x1, y1) = _limits(ax)
    assert y1 > y > base[1][1]  # the line is now in the view
    assert x1 - x0 < 1.5 * np.ptp(base[:, 0])
    assert _by_gid(ax, "map-label:0") is None  # no name, no label


# ------------------------------------------------------------------------------- line styles

def test_every_style_is_drawn_its_own_way():
    assert set(MAP_STYLES) == set(MAP_LINE_STYLES)
    scene = _scene(INTERSECTION)
    lines = [MapLine(f"{s} line", s, np.array([[-10.0, 2.0 * k], [10.0, 2.0 * k]]))
             for k, s in enumerate(MAP_LINE_STYLES)]
    lines.append(MapLine("painted", "edge", np.array([[-10.0, -3.0], [10.0, -3.0]]), "tab:orange"))
    ax = plot_scene(_with_layout(scene, (), lines), ax=plt.subplots()[1], legend="best")
    drawn = {ln.style: _by_gid(ax, f"map:{i}") for i, ln in enumerate(lines[:-1])}
    for art, ln in zip(drawn.values(), lines):
        np.testing.assert_allclose(np.column_stack(art.get_data()), ln.points)
        assert art.get_zorder() < 2  # under the vehicles, tracks and barriers
    assert drawn["lane"].get_linestyle() == "--"
    assert all(drawn[s].get_linestyle() == "-" for s in ("edge", "centre", "kerb", "stop", "other"))
    assert drawn["kerb"].get_linewidth() > 3 * drawn["edge"].get_linewidth() / 1.6 > drawn["other"].get_linewidth()
    assert drawn["stop"].get_linewidth() >= drawn["kerb"].get_linewidth()
    assert drawn["centre"].get_path_effects(), "a double line: a wide stroke under a white one"
    assert not drawn["edge"].get_path_effects()
    assert matplotlib.colors.same_color(_by_gid(ax, f"map:{len(lines) - 1}").get_color(), "tab:orange")
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    for s in MAP_LINE_STYLES:
        assert MAP_STYLES[s][0] in texts
    assert "road edge (painted)" in texts


def test_one_colour_and_one_legend_entry_per_zone_name():
    """Two zones named "grass verge" (either side of the road) are one colour and one legend entry;
    a zone of another name has another colour and its own entry. The label of each zone is in its
    zone's colour (darkened)."""
    from matplotlib.colors import to_rgb

    from crashsim.plotting.style import darker

    scene = _scene(INTERSECTION)
    lo, hi = _vehicle_box(scene)
    x0, x1 = lo[0] - 2.0, hi[0] + 2.0
    north = FrictionZone(((x0, hi[1] + 1.0), (x1, hi[1] + 1.0), (x1, hi[1] + 6.0), (x0, hi[1] + 6.0)), 0.4,
                         "grass verge")
    gravel = FrictionZone(((x0, lo[1] - 1.0), (0.5 * (x0 + x1), lo[1] - 1.0), (0.5 * (x0 + x1), lo[1] - 6.0),
                           (x0, lo[1] - 6.0)), 0.55, "gravel")
    south = FrictionZone(((0.5 * (x0 + x1), lo[1] - 1.0), (x1, lo[1] - 1.0), (x1, lo[1] - 6.0),
                          (0.5 * (x0 + x1), lo[1] - 6.0)), 0.4, "grass verge")
    ax = plot_scene(_with_layout(scene, [north, gravel, south]), ax=plt.subplots(figsize=(10, 7))[1],
                    legend="best")
    fills = [to_rgb(_by_gid(ax, f"zone:{i}").get_facecolor()) for i in range(3)]
    edges = [to_rgb(_by_gid(ax, f"zone:{i}").get_edgecolor()) for i in range(3)]
    assert fills[0] == fills[2] and edges[0] == edges[2]  # one name, one colour
    assert fills[1] != fills[0] and edges[1] != edges[0]
    leg = ax.get_legend()
    texts = [t.get_text() for t in leg.get_texts()]
    zone_entries = [t for t in texts if t.startswith("friction zone:")]
    assert zone_entries == ["friction zone: grass verge, f = 0.4", "friction zone: gravel, f = 0.55"]
    # the legend swatch of each entry is its zones' colour
    for text, handle in zip(texts, leg.legend_handles):
        if text == "friction zone: grass verge, f = 0.4":
            assert to_rgb(handle.get_facecolor()) == fills[0]
        elif text == "friction zone: gravel, f = 0.55":
            assert to_rgb(handle.get_facecolor()) == fills[1]
    for i in (0, 2):  # each grass label (where drawn) in the grass colour
        label = _by_gid(ax, f"zone-label:{i}")
        if label is not None:
            assert np.allclose(to_rgb(label.get_color()), darker(edges[0]))
    plt.close("all")


def test_zones_of_one_name_with_different_friction_list_each_in_their_entry():
    scene = _scene(INTERSECTION)
    a = FrictionZone(((0.0, 20.0), (5.0, 20.0), (5.0, 25.0)), 0.5, "gravel")
    b = FrictionZone(((10.0, 20.0), (15.0, 20.0), (15.0, 25.0)), 0.6, "gravel")
    ax = plot_scene(_with_layout(scene, [a, b]), ax=plt.subplots()[1], legend="best")
    texts = [t.get_text() for t in ax.get_legend().get_texts() if t.get_text().startswith("friction zone:")]
    assert texts == ["friction zone: gravel, f = 0.5 | f = 0.6"]
    plt.close("all")


SURVEY = ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml"


def test_lines_from_a_survey_carry_their_layer_or_code():
    sc = load_scenario(SURVEY)
    by_layer = {}
    for ln in sc.map_lines:
        by_layer.setdefault(ln.layer, set()).add((ln.style, ln.imported_as))
    # the DXF layers and the point file's code, as mapped in the file
    assert by_layer["EDGE"] == {("edge", "line")} and by_layer["EP"] == {("edge", "line")}
    assert by_layer["GOUGE"] == {("other", "gouge")} and by_layer["DEBRIS"] == {("other", "debris")}
    assert "" not in by_layer  # every line of this file comes from the survey


def test_legend_names_the_survey_layers_not_a_colour_code():
    """A gouge drawn from layer GOUGE is "gouge (GOUGE)" in the legend, not "other line (#8c564b)";
    the road edges of the DXF layer EDGE and of the point code EP look alike and share one entry."""
    scene = _scene(SURVEY)
    ax = plot_scene(scene)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert "gouge (GOUGE)" in texts and "debris (DEBRIS)" in texts
    assert "road edge (EDGE, EP)" in texts
    assert "centre line (CENTRE)" in texts and "kerb / verge edge (KERB)" in texts
    assert not any("other line" in t or "#" in t for t in texts), texts
    # each entry's swatch is drawn as its lines are
    leg = ax.get_legend()
    for i, ln in enumerate(scene.scenario.map_lines):
        if ln.imported_as == "gouge":
            handle = leg.legend_handles[texts.index("gouge (GOUGE)")]
            assert matplotlib.colors.same_color(handle.get_color(), _by_gid(ax, f"map:{i}").get_color())
    plt.close("all")


def test_written_lines_keep_their_names_or_colours_in_the_legend():
    scene = _scene(INTERSECTION)
    lines = [MapLine("", "other", np.array([[-10.0, -3.0], [10.0, -3.0]]), "#8c564b"),
             MapLine("", "edge", np.array([[-10.0, 3.0], [10.0, 3.0]])),
             MapLine("old paint", "lane", np.array([[-10.0, 5.0], [10.0, 5.0]]), "tab:orange"),
             MapLine("", "edge", np.array([[-10.0, 7.0], [10.0, 7.0]]), None, "EOP", "line")]
    ax = plot_scene(_with_layout(scene, (), lines), ax=plt.subplots()[1], legend="best")
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    # a written line of its own colour without a name can only say its colour; a layer is named
    assert "other line (#8c564b)" in texts and "lane line (old paint)" in texts
    assert "road edge" in texts and "road edge (EOP)" in texts
    plt.close("all")

"""Detail views of a scene figure, measured on the rendered figure: ``view=`` frames the window
given, ``zoom="impact"`` the bodies in the first impact, an overview whose impact is small gets an
inset of it, and ``crashsim plot --view`` refuses a bad window before anything is read or run.

Sizes and positions are the artists' window extents from the renderer (pixels at the figure's
size), not numbers taken from the placement code.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
from matplotlib.transforms import Bbox  # noqa: E402

import crashsim.plotting  # noqa: E402
import crashsim.scene  # noqa: E402
from crashsim.cli import main  # noqa: E402
from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.plotting.detail import INSET_BELOW, INSET_MARGIN, impact_window  # noqa: E402
from crashsim.plotting import plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
TRUCK = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"  # US units, a long approach
INTERSECTION = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"  # SI
FT = 0.3048


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


def _extent(ax, gid_prefix):
    """Union of the window extents of the patches of ``ax`` whose gid starts with ``gid_prefix``."""
    r = ax.figure.canvas.get_renderer()
    boxes = [p.get_window_extent(r) for p in ax.patches if (p.get_gid() or "").startswith(gid_prefix)]
    assert boxes, gid_prefix
    return Bbox.union(boxes)


def _impact_gids(scene):
    return [f"outline:impact:{n}" for n in (scene.impact.body1, scene.impact.body2)
            if any(b.name == n and b.outline() is not None for v in scene.scenario.vehicles for b in v.bodies)]


def _inset(ax):
    found = [a for a in ax.child_axes if a.get_gid() == "inset:impact"]
    return found[0] if found else None


def _labels(fig, ax):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    return [(t.get_text(), t.get_window_extent(r)) for t in ax.texts if t.get_visible() and t.get_text()]


def test_view_frames_the_window_given_and_keeps_labels_inside():
    scene = _scene(INTERSECTION)
    window = (-14.0, -6.0, 2.0, 4.0)  # m: part of the trailer and the car at impact
    ax = plot_scene(scene, view=window)
    fig = ax.figure
    fig.canvas.draw()
    assert ax.get_xlim() == pytest.approx(window[0::2], abs=1e-9)
    assert ax.get_ylim() == pytest.approx(window[1::2], abs=1e-9)
    frame = ax.get_window_extent(fig.canvas.get_renderer()).padded(1.0)
    labels = _labels(fig, ax)
    assert labels
    for text, bb in labels:
        assert frame.x0 <= bb.x0 and bb.x1 <= frame.x1 and frame.y0 <= bb.y0 and bb.y1 <= frame.y1, text
    # every label anchored in the window, none outside it
    for t in ax.texts:
        if (t.get_gid() or "").startswith("label:"):
            x, y = t.xy
            assert window[0] <= x <= window[2] and window[1] <= y <= window[3], t.get_text()
    assert _inset(ax) is None  # a detail view has no inset


@pytest.mark.parametrize("path", [TRUCK, INTERSECTION], ids=lambda p: p.stem)
def test_zoom_impact_fills_the_axes_with_the_bodies_in_the_impact(path):
    scene = _scene(path)
    over = plot_scene(scene, inset=False)
    zoom = plot_scene(scene, zoom="impact")
    ratios = []
    for ax in (over, zoom):
        ax.figure.canvas.draw()
        frame = ax.get_window_extent(ax.figure.canvas.get_renderer())
        bodies = Bbox.union([_extent(ax, g) for g in _impact_gids(scene)])
        ratios.append(max(bodies.width / frame.width, bodies.height / frame.height))
    frame = zoom.get_window_extent(zoom.figure.canvas.get_renderer())
    bodies = Bbox.union([_extent(zoom, g) for g in _impact_gids(scene)])
    # whole inside the axes, with a margin on every side, and filling most of one direction
    assert frame.x0 < bodies.x0 and bodies.x1 < frame.x1 and frame.y0 < bodies.y0 and bodies.y1 < frame.y1
    assert ratios[1] > 0.6, ratios
    assert ratios[1] > ratios[0], ratios
    # the window is the one impact_window states (display units of the figure)
    k = 1.0 / FT if scene.scenario.units == "US" else 1.0
    lo, hi = impact_window(scene)
    assert zoom.get_xlim() == pytest.approx((k * lo[0], k * hi[0]))
    assert zoom.get_ylim() == pytest.approx((k * lo[1], k * hi[1]))


def test_a_long_overview_gets_an_inset_that_enlarges_the_impact():
    scene = _scene(TRUCK)
    ax = plot_scene(scene)
    fig = ax.figure
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    frame = ax.get_window_extent(r)
    window = ax.patches[[p.get_gid() for p in ax.patches].index("inset-window")].get_window_extent(r)
    assert window.width / frame.width < INSET_BELOW  # why it has one: the impact is small on the overview
    inset = _inset(ax)
    assert inset is not None
    box = inset.get_window_extent(r)
    assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    assert not box.overlaps(window)  # it does not cover what it enlarges
    # the bodies in the impact, copied into the inset, drawn larger than on the overview
    for gid in _impact_gids(scene):
        on_overview = _extent(ax, gid)
        copied = [p for p in inset.patches if p.get_gid() == f"inset:{gid}"]
        assert copied, gid
        full = copied[0].get_window_extent(r)  # at the inset's scale (the inset's frame cuts it)
        assert Bbox.intersection(full, box) is not None, gid  # seen in the inset
        assert full.width > 2.0 * on_overview.width and full.height > 2.0 * on_overview.height, gid
    # its scale bar states a length that matches its drawn length at the inset's scale
    bar = next(ln for ln in inset.lines if ln.get_gid() == "inset:scalebar")
    label = next(t for t in inset.texts if t.get_gid() == "inset:scalelabel").get_text()
    value, unit = label.split()
    assert unit == "ft"
    xs = bar.get_xdata()
    assert xs[1] - xs[0] == pytest.approx(float(value))
    # no label of the overview sits on the inset
    for text, bb in _labels(fig, ax):
        assert not bb.overlaps(box), text


def test_a_short_overview_has_no_inset_when_the_impact_is_not_small():
    scene = _scene(INTERSECTION)
    ax = plot_scene(scene)
    ax.figure.canvas.draw()
    r = ax.figure.canvas.get_renderer()
    lo, hi = impact_window(scene, INSET_MARGIN)
    width = ax.transData.transform([hi[0], 0.0])[0] - ax.transData.transform([lo[0], 0.0])[0]
    has = _inset(ax) is not None
    assert not has or width / ax.get_window_extent(r).width < INSET_BELOW


def test_view_and_zoom_are_checked():
    scene = _scene(INTERSECTION)
    with pytest.raises(ScenarioError, match="X1 = 1 m is not above X0 = 2 m") as info:
        plot_scene(scene, view=(2.0, 0.0, 1.0, 5.0))
    assert info.value.field == "view"
    with pytest.raises(ScenarioError, match="not both"):
        plot_scene(scene, view=(0, 0, 1, 1), zoom="impact")
    with pytest.raises(ScenarioError, match="allowed: impact"):
        plot_scene(scene, zoom="rest")


@pytest.mark.parametrize("view, message", [
    (["5", "0", "5", "3"], "X1 = 5 is not above X0 = 5; allowed: X1 > X0"),
    (["0", "4", "5", "-3"], "Y1 = -3 is not above Y0 = 4; allowed: Y1 > Y0"),
    (["0", "north", "5", "3"], "Y0 = 'north' is not a number"),
    (["0", "0", "nan", "3"], "X1 = 'nan' is not a number"),
])
def test_cli_refuses_a_bad_view_before_reading_the_file(view, message, tmp_path, capsys, monkeypatch):
    import crashsim.cli

    def never(*a, **k):
        raise AssertionError("the file was read")

    monkeypatch.setattr(crashsim.cli, "_load", never)
    with pytest.raises(SystemExit) as info:
        main(["plot", str(INTERSECTION), "-o", str(tmp_path / "s.png"), "--view", *view])
    assert info.value.code == 2
    err = capsys.readouterr().err
    assert "--view" in err and message in err, err
    assert not (tmp_path / "s.png").exists()


def test_cli_view_is_in_the_file_s_length_unit(tmp_path, capsys, monkeypatch):
    seen = {}

    def fake_save(scene, path, **kw):
        seen.update(kw)
        return [path]

    monkeypatch.setattr(crashsim.scene, "run_scene", lambda scenario: _scene(TRUCK))
    monkeypatch.setattr(crashsim.plotting, "save_scene_figures", fake_save)
    assert main(["plot", str(TRUCK), "-o", str(tmp_path / "s.png"), "--view", "-40", "-20", "60", "30"]) == 0
    assert seen["view"] == pytest.approx((-40 * FT, -20 * FT, 60 * FT, 30 * FT))  # a US file: ft
    assert main(["plot", str(TRUCK), "-o", str(tmp_path / "s.png"), "--zoom", "impact"]) == 0
    assert seen["zoom"] == "impact" and seen["view"] is None
    with pytest.raises(SystemExit):  # not both
        main(["plot", str(TRUCK), "-o", str(tmp_path / "s.png"), "--zoom", "impact", "--view", "0", "0", "1", "1"])

"""Figures as exhibits, under Agg: labels that never overlap, a view framed on the scene (not on
a long barrier), print sheets at a stated scale, hidden label kinds, the time-distance chart's
recorder samples and legend, and an animation whose tracks grow with the clock.

Overlap is measured independently of the placement code: the figure is drawn, then every
visible text's window extent (and its disc or box, if it has one) is taken from the renderer.
"""

from __future__ import annotations

import dataclasses
import functools
import itertools
import re
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crashsim.animation import animate_scene, scene_animation  # noqa: E402
from crashsim.cli import main  # noqa: E402
from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.plotting import (LABEL_KINDS, PAPER_SIZES, parse_scale, plot_scene,  # noqa: E402
                               plot_time_distance, print_sheet)
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402
from crashsim.units import Kind, to_unit  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = (sorted((ROOT / "scenarios" / "scenes").glob("*.toml"))
           + sorted((ROOT / "scenarios" / "survey").glob("*.toml")))
GLANCE = ROOT / "scenarios" / "scenes" / "barrier_glance_15deg.toml"
TRUCK = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
WAITING = ROOT / "scenarios" / "scenes" / "third_vehicle_waiting_car.toml"


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


def _text_boxes(fig):
    """(text, window extent) of every visible, non-empty text in the figure's axes, measured
    after a full draw; a text's bbox patch (the impact discs) counts as part of it."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    out = []
    for ax in fig.axes:
        for t in ax.texts:
            if not t.get_visible() or not t.get_text():
                continue
            from matplotlib.text import Text
            from matplotlib.transforms import Bbox

            bb = Text.get_window_extent(t, r)
            patch = t.get_bbox_patch()
            if patch is not None:
                bb = Bbox.union([bb, patch.get_window_extent(r)])
            out.append((t.get_text(), bb))
    return out


def _overlaps(fig):
    boxes = _text_boxes(fig)
    return [(a, b) for (a, ba), (b, bb) in itertools.combinations(boxes, 2) if ba.overlaps(bb)]


def test_every_shipped_scene_is_checked():
    assert len(SHIPPED) >= 11 and any(p.parent.name == "survey" for p in SHIPPED)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_no_two_labels_overlap_on_a_shipped_scene(path):
    ax = plot_scene(_scene(path))
    assert len(ax.texts) > 3
    assert _overlaps(ax.figure) == []
    # every label inside the axes
    r = ax.figure.canvas.get_renderer()
    frame = ax.get_window_extent(r).padded(1.0)
    for text, bb in _text_boxes(ax.figure):
        assert frame.contains(bb.x0, bb.y0) and frame.contains(bb.x1, bb.y1), text
    # the compact legend (the default): outside the axes, whole inside the figure, one line per entry
    leg = ax.get_legend().get_window_extent(r)
    fig = ax.figure.bbox
    assert not leg.overlaps(ax.get_window_extent(r))
    assert fig.x0 <= leg.x0 and leg.x1 <= fig.x1 and fig.y0 <= leg.y0 and leg.y1 <= fig.y1, (leg, fig)
    assert all("\n" not in t.get_text() for t in ax.get_legend().get_texts())


@pytest.mark.parametrize("legend", ["inside", "none"])
def test_no_overlap_with_the_legend_inside_or_none(legend):
    ax = plot_scene(_scene(WAITING), legend=legend)
    assert _overlaps(ax.figure) == []
    leg = ax.get_legend()
    if legend == "none":
        assert leg is None
    else:
        r = ax.figure.canvas.get_renderer()
        lb = leg.get_window_extent(r)
        assert ax.get_window_extent(r).contains(lb.x0 + 1, lb.y0 + 1)  # inside the axes
        assert not any(lb.overlaps(bb) for t, bb in _text_boxes(ax.figure) if t not in ("+X", "+Y"))
        # one line per entry: the residual details are left to the report
        assert all("\n" not in t.get_text() for t in leg.get_texts())


def test_impacts_close_together_are_numbered_apart_with_leaders():
    """The scene figure numbers impact events (the report's numbers): one number at each pair of an event
    (a trailer and a tractor slapping the barrier at one instant: both marked with the event's number,
    its bounces not again), anchored at the pair's impulse centre; close numbers move apart on leaders."""
    ax = plot_scene(_scene(GLANCE))
    numbers = [t for t in ax.texts if (t.get_gid() or "") == "label:impacts"]
    scene = _scene(GLANCE)
    expect = [(1, scene.impact.point)]
    for ev in scene.joint.impact_events():
        firsts = {}
        for r in ev.records:
            firsts.setdefault((r.body1, r.body2), r.point)
        expect += [(ev.number, p) for p in firsts.values()]
    assert [t.get_text() for t in numbers] == [str(n) for n, _ in expect]
    assert len({n for n, _ in expect}) >= 3
    assert any((t.get_gid() or "").startswith("leader:") for t in ax.texts)
    # each number's anchor is its impact point (the drawn data equal the computed data)
    np.testing.assert_allclose([t.xy for t in numbers], [p for _, p in expect], atol=1e-9)


def _with_barrier_extent(scene, extent):
    sc = scene.scenario
    data = dict(sc.data)
    data["barrier"] = dict(data["barrier"], extent=extent)
    # the figures read the typed field (Scenario.barrier_extent, read at load), not the file's dict
    return dataclasses.replace(scene, scenario=dataclasses.replace(sc, data=data,
                                                                   barrier_extent=None if extent is None else tuple(extent)))


def test_view_does_not_grow_with_the_barrier_extent():
    scene = _scene(GLANCE)
    short = plot_scene(_with_barrier_extent(scene, (-5.0, 5.0)))
    long = plot_scene(_with_barrier_extent(scene, (-200.0, 400.0)))
    endless = plot_scene(_with_barrier_extent(scene, None))
    lim = [np.array([a.get_xlim(), a.get_ylim()]) for a in (short, long, endless)]
    np.testing.assert_allclose(lim[1], lim[0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(lim[2], lim[0], rtol=0, atol=1e-9)
    # the long barrier is drawn across the view (cut at half a view beyond it)
    face = next(ln for ln in long.lines if (ln.get_gid() or "").startswith("barrier-face:"))
    x = face.get_xdata()
    x0, x1 = long.get_xlim()
    assert x.min() <= x0 and x.max() >= x1 and x.max() - x.min() <= 2.0 * (x1 - x0) + 1e-6


def test_hide_label_kinds():
    scene = _scene(TRUCK)
    kinds = {(t.get_gid() or "").split(":")[1] for t in plot_scene(scene).texts
             if (t.get_gid() or "").startswith("label:")}
    assert {"names", "pdof", "delta-v", "impacts", "approach"} <= kinds
    ax = plot_scene(scene, hide="pdof,names")
    left = {(t.get_gid() or "").split(":")[1] for t in ax.texts if (t.get_gid() or "").startswith("label:")}
    assert left == kinds - {"pdof", "names"}
    ax = plot_scene(scene, hide=["labels"])
    assert not any((t.get_gid() or "").startswith(("label:", "zone-label", "map-label")) for t in ax.texts)
    with pytest.raises(ScenarioError, match=r"^hide: unknown label kind\(s\) 'pdfo'; allowed: labels \(all\)"):
        plot_scene(scene, hide="pdfo")


def test_print_sheet_is_at_the_stated_scale():
    scene = _scene(WAITING)
    ax = plot_scene(scene, paper="A4", scale=200)
    fig = ax.figure
    w, h = fig.get_size_inches()
    assert sorted((round(w * 25.4, 3), round(h * 25.4, 3))) == sorted(PAPER_SIZES["A4"])
    # 1:200: an axes box of b inches shows b * 0.0254 * 200 metres
    box = ax.get_position()
    x0, x1 = ax.get_xlim()
    assert (x1 - x0) == pytest.approx(box.width * w * 0.0254 * 200.0, rel=1e-9)
    y0, y1 = ax.get_ylim()
    assert (y1 - y0) == pytest.approx(box.height * h * 0.0254 * 200.0, rel=1e-9)
    bar = next(a for a in ax.artists if a.get_gid() == "scalebar")
    assert "scale 1:200 on A4" in bar.txt_label.get_text()
    assert _overlaps(fig) == []
    # US units: the same sheet and scale, the view in feet
    us = plot_scene(scene, paper="A4", scale=200, system="US")
    k = to_unit(1.0, Kind.LENGTH, "US")[0]
    assert np.ptp(us.get_xlim()) == pytest.approx(k * (x1 - x0), rel=1e-9)


def test_print_sheet_picks_a_scale_or_refuses_one_too_large():
    sheet = print_sheet("letter", (0.0, 0.0), (120.0, 20.0), 1.0)
    room = np.array(sheet.box[2:]) * 0.0254  # metres of paper in the drawing box
    # the largest standard scale that holds 120 m: 1:250 does not, 1:500 does
    assert 120.0 / room[0] > 250 and sheet.orientation == "landscape" and sheet.scale == 500
    assert np.all(sheet.hi - sheet.lo >= [120.0, 20.0])
    too_large = r"^scale: scale 1:200 is too large .* fits at 1:N with N >= 463 \(e.g. 1:500\)"
    with pytest.raises(ScenarioError, match=too_large):
        print_sheet("A4", (0.0, 0.0), (120.0, 20.0), 1.0, 200.0)
    with pytest.raises(ScenarioError, match=r"^paper: paper 'B5' is unknown"):
        print_sheet("B5", (0.0, 0.0), (1.0, 1.0), 1.0)
    assert parse_scale("1:500") == 500.0 and parse_scale("250") == 250.0
    with pytest.raises(ScenarioError, match="allowed 1:N with N >= 1"):
        parse_scale("1:0")


@pytest.mark.parametrize("suffix", [".pdf", ".svg"])
def test_cli_vector_sheet(tmp_path, capsys, suffix):
    out = tmp_path / f"scene{suffix}"
    code = main(["plot", str(WAITING), "-o", str(out), "--paper", "A4", "--scale", "1:200", "--legend", "outside",
                 "--hide", "times"])
    assert code == 0, capsys.readouterr().err
    data = out.read_bytes()
    a4 = np.array(PAPER_SIZES["A4"]) / 25.4 * 72.0  # points
    if suffix == ".pdf":
        box = re.search(rb"/MediaBox \[ *0 0 ([\d.]+) ([\d.]+) *\]", data)
    else:
        box = re.search(rb'width="([\d.]+)pt" height="([\d.]+)pt"', data)
    np.testing.assert_allclose([float(box.group(1)), float(box.group(2))], a4, atol=1e-3)


def test_cli_refuses_a_scale_too_large_for_the_page_naming_the_option(tmp_path, capsys):
    out = tmp_path / "s.pdf"
    assert main(["plot", str(GLANCE), "-o", str(out), "--paper", "A4", "--scale", "1:200"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("crashsim: input error: --scale: scale 1:200 is too large for the scene on A4")
    assert "e.g. 1:1000" in err and not out.exists()


def test_cli_refuses_an_unknown_label_kind(tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        main(["plot", str(WAITING), "-o", str(tmp_path / "s.png"), "--hide", "names,colour"])
    assert exc.value.code == 2
    assert "unknown label kind(s) 'colour'" in capsys.readouterr().err


# -- time-distance ----------------------------------------------------------------------------

def test_time_distance_draws_the_recorder_beside_the_computed_speed():
    scene = _scene(TRUCK)
    fig = plot_time_distance(scene, system="US")
    ax_s, ax_v = fig.axes[:2]
    rec = scene.scenario.evidence.recorder[0]
    k = to_unit(1.0, Kind.SPEED, "US")[0]
    t = np.asarray(rec.times) + rec.time_offset
    v = k * np.asarray(rec.speeds)
    low = np.asarray(rec.lower_bound)
    plain = next(ln for ln in ax_v.lines if ln.get_gid() == "td:recorder:0:recorded")
    bound = next(ln for ln in ax_v.lines if ln.get_gid() == "td:recorder:0:lower")
    np.testing.assert_allclose(np.column_stack(plain.get_data()), np.column_stack([t[~low], v[~low]]), atol=1e-12)
    np.testing.assert_allclose(np.column_stack(bound.get_data()), np.column_stack([t[low], v[low]]), atol=1e-12)
    labels = [x.get_text() for x in ax_s.get_legend().get_texts()]
    assert "recorded speed (bar: tolerance)" in labels and "recorded, braking: a lower bound" in labels
    assert "perception" in labels and "start of braking" in labels


def test_time_distance_legend_only_of_what_is_drawn_and_impact_labels_apart():
    scene = _scene(WAITING)  # no approach, no recorder; impacts close together
    fig = plot_time_distance(scene)
    labels = [x.get_text() for x in fig.axes[0].get_legend().get_texts()]
    assert not {"perception", "start of braking", "recorded speed (bar: tolerance)"} & set(labels)
    assert "at rest" in labels
    impacts = [t for t in fig.axes[0].texts if (t.get_gid() or "").startswith("td:impact:")]
    # every impact under one label (impacts close in time share one: "impacts 2-3")
    shown = sorted(n for t in impacts for n in t.crashsim_impacts)
    assert shown == [1] + [ev.number for ev in scene.joint.impact_events()] and len(shown) >= 3
    assert _overlaps(fig) == []


# -- animation --------------------------------------------------------------------------------

def test_animation_tracks_grow_and_rest_outlines_appear_at_rest():
    scene = _scene(WAITING)
    anim = scene_animation(scene, dt=0.1)
    S = anim._S
    assert S.timed and S.appear
    ends = {vn: float(r.t_end) for vn, r in scene.runout.items()}
    mid = len(anim) // 3
    anim.frame(mid)
    t = float(anim.times[mid])
    for line, tt, xy in S.timed:
        x, y = line.get_data()
        n = int(np.searchsorted(tt, t, side="right"))
        assert len(x) in (n, n + 1)  # the samples up to the clock (and the point at the clock)
        if n:
            np.testing.assert_allclose(np.column_stack([x, y])[:n], xy[:n], atol=1e-12)
    for artist, t_on in S.appear:
        assert artist.get_visible() == (t >= t_on)
    # every impact's number appears at its time: the first at the impact (t = 0), the later ones later
    numbers = {a.get_text(): on for a, on in S.appear if (a.get_gid() or "") == "label:impacts"}
    assert numbers == {"1": 0.0, **{str(n): pytest.approx(float(i.t))
                                    for n, i in enumerate(scene.joint.impacts, start=2)}}
    assert any(t < e for e in ends.values())  # some vehicle still moving at that frame
    anim.frame(len(anim) - 1)
    assert all(a.get_visible() for a, _ in S.appear)
    for line, tt, xy in S.timed:
        np.testing.assert_allclose(np.column_stack(line.get_data()), xy, atol=1e-12)
    assert _overlaps(anim.fig) == []


def test_animation_reports_progress_and_prints_nothing(tmp_path, capsys):
    seen = []
    animate_scene(_scene(WAITING), tmp_path / "a.gif", dt=1.0, dpi=30, progress=lambda k, n: seen.append((k, n)))
    n = seen[-1][1]
    assert seen == [(k, n) for k in range(1, n + 1)]
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""


def test_cli_animate_shows_a_progress_bar_on_stderr(tmp_path, capsys):
    code = main(["animate", str(WAITING), "-o", str(tmp_path / "a.gif"), "--dt", "1 s", "--dpi", "30"])
    assert code == 0
    out = capsys.readouterr()
    assert "rendering" in out.err and "frame" in out.err
    assert main(["animate", str(WAITING), "-o", str(tmp_path / "b.gif"), "--dt", "1 s", "--dpi", "30",
                 "--quiet"]) == 0
    assert "rendering" not in capsys.readouterr().err


def test_label_kinds_are_documented():
    assert set(LABEL_KINDS) == {"impacts", "names", "pdof", "delta-v", "approach", "obstacles", "zones", "map",
                                "times"}
    plt.close("all")


# -- labels off the lines ---------------------------------------------------------------------

def _ink_under(ax, texts) -> int:
    """Samples of the drawn lines and outlines (line_ink) under the given labels' text boxes."""
    from crashsim.plotting import line_ink, text_box

    ax.figure.draw_without_rendering()
    r = ax.figure.canvas.get_renderer()
    ink = line_ink(ax)
    total = 0
    for t in texts:
        bb = text_box(t, r)
        total += int(np.count_nonzero((ink[:, 0] >= bb.x0) & (ink[:, 0] <= bb.x1) & (ink[:, 1] >= bb.y0)
                                      & (ink[:, 1] <= bb.y1)))
    return total


def test_a_label_on_a_line_moves_off_it_and_others_stay():
    from crashsim.plotting import place_labels

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.set_xlim(-10, 10)
    ax.set_ylim(-10, 10)
    ax.plot([-10, 10], [0, 0], "-", lw=2)  # a track through both anchors
    shy = ax.annotate("PDOF car\n-17 deg", xy=(-4, 0), xytext=(0, 0), textcoords="offset points", ha="center",
                      va="center", fontsize=7, gid="label:pdof")
    name = ax.annotate("car", xy=(4, 0), xytext=(0, 0), textcoords="offset points", ha="center", va="center",
                       fontsize=7, gid="label:names")
    assert _ink_under(ax, [shy]) > 0 and _ink_under(ax, [name]) > 0
    assert place_labels(ax, [shy, name], lines=False) == 0
    assert _ink_under(ax, [shy]) > 0, "without lines=True nothing moves: each label is free of the other"
    assert place_labels(ax, [shy, name]) == 0
    assert _ink_under(ax, [shy]) == 0, "the PDOF label left the track"
    assert np.hypot(*shy.xyann) <= 26.0, "to a place near its anchor"
    assert name.xyann == (0, 0) and _ink_under(ax, [name]) > 0, "a body's name stays on its body"


def test_shipped_scene_labels_cover_fewer_lines(monkeypatch):
    """The Δv, PDOF, approach and obstacle labels of the shipped scenes lie over fewer drawn lines than
    when they are kept clear of each other only."""
    import crashsim.plotting.scene as scene_module  # plot_scene calls place_labels there
    from crashsim.plotting import LINE_SHY

    def shy_ink(lines: bool) -> int:
        total = 0
        for path in SHIPPED:
            if not lines:
                monkeypatch.setattr(scene_module, "place_labels", functools.partial(ORIGINAL, lines=False))
            ax = plot_scene(_scene(path))
            monkeypatch.setattr(scene_module, "place_labels", ORIGINAL)
            texts = [t for t in ax.texts if (t.get_gid() or "").removeprefix("label:") in LINE_SHY]
            total += _ink_under(ax, texts)
            plt.close(ax.figure)
        return total

    ORIGINAL = scene_module.place_labels
    before, after = shy_ink(False), shy_ink(True)
    assert after < 0.6 * before, (before, after)


# -- US sheets: an engineer's scale -----------------------------------------------------------------

def _drawn_ft_per_inch(ax) -> tuple[float, float]:
    """Feet of the view per inch of paper, across and up (the view is in ft), as the sheet is drawn."""
    w, h = ax.figure.get_size_inches()
    box = ax.get_position()
    return float(np.ptp(ax.get_xlim()) / (box.width * w)), float(np.ptp(ax.get_ylim()) / (box.height * h))


def test_a_us_sheet_states_the_engineer_s_scale_it_is_drawn_at():
    """A US sheet whose scale is picked is drawn at an engineer's scale (1" = 10', 20', 30', 40', 50', 60',
    100', ...) and its scale bar says so ("1\\" = 40'"), not 1:500; measured on the figure: the feet of
    view per inch of paper are the stated feet."""
    from crashsim.plotting import ENGINEER_SCALES_FT

    scene = _scene(TRUCK)  # a US scene
    assert scene.scenario.units == "US"
    for paper in ("letter", "tabloid"):
        ax = plot_scene(scene, paper=paper)
        bar = next(a for a in ax.artists if a.get_gid() == "scalebar")
        m = re.search(r"""scale 1" = (\d+(?:\.\d+)?)' on """ + paper, bar.txt_label.get_text())
        assert m, bar.txt_label.get_text()
        ft = float(m[1])
        assert ft in ENGINEER_SCALES_FT and "1:" not in bar.txt_label.get_text()
        across, up = _drawn_ft_per_inch(ax)
        assert across == pytest.approx(ft, rel=1e-9) and up == pytest.approx(ft, rel=1e-9)
        plt.close("all")
    # a scale given as 1:N is drawn at 1:N and stated as it is (feet per inch beside 1:N)
    ax = plot_scene(scene, paper="tabloid", scale=1000)
    text = next(a for a in ax.artists if a.get_gid() == "scalebar").txt_label.get_text()
    assert """scale 1" = 83.3' (1:1000) on tabloid""" in text
    assert _drawn_ft_per_inch(ax)[0] == pytest.approx(1000 / 12, rel=1e-9)
    plt.close("all")
    # given as an engineer's scale, drawn at it
    ax = plot_scene(scene, paper="tabloid", scale=parse_scale("1\" = 100'"))
    text = next(a for a in ax.artists if a.get_gid() == "scalebar").txt_label.get_text()
    assert """scale 1" = 100' on tabloid""" in text
    assert _drawn_ft_per_inch(ax)[0] == pytest.approx(100.0, rel=1e-9)
    plt.close("all")


def test_an_si_sheet_keeps_its_1_to_n_scale():
    ax = plot_scene(_scene(TRUCK), paper="A3", system="SI")
    text = next(a for a in ax.artists if a.get_gid() == "scalebar").txt_label.get_text()
    n = float(re.search(r"scale 1:(\d+) on A3", text)[1])
    w = ax.figure.get_size_inches()[0] * ax.get_position().width
    assert np.ptp(ax.get_xlim()) == pytest.approx(w * 0.0254 * n, rel=1e-9)  # metres of view
    plt.close("all")


def test_engineer_scales_parse_and_print():
    from crashsim.plotting import ENGINEER_SCALES_FT, engineer_scale_text

    assert {10.0, 20.0, 30.0, 40.0, 50.0, 60.0, 100.0, 200.0} <= set(ENGINEER_SCALES_FT)
    assert parse_scale("1\" = 40'") == parse_scale("1 in = 40 ft") == 480.0
    assert engineer_scale_text(480) == "1\" = 40'" and engineer_scale_text(500) == "1\" = 41.7' (1:500)"
    with pytest.raises(ScenarioError, match="engineer's scale"):
        parse_scale("1\" = 0'")

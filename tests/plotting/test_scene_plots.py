"""Smoke and geometry tests of the scene diagram and the run-out histories, under Agg.

Every scene in scenarios/scenes/ is drawn (globbed, so new scenes are covered), plus an
impact-only paper table (Table 6, no outline data) and a barrier table (Table 4-a).
"""

from __future__ import annotations

import dataclasses
import functools
import math
import re
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.geometry import rotate  # noqa: E402
from crashsim.plotting import (SCENE_FIGURE_SUFFIXES, history_panels, plot_histories, plot_scene,  # noqa: E402
                               save_scene_figures)
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.report import format_joint  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402
from crashsim.units import Kind, to_unit  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENES = sorted((ROOT / "scenarios" / "scenes").glob("*.toml"))
TABLE6 = ROOT / "scenarios" / "paper" / "table6.toml"    # impact only, no outline data
TABLE4A = ROOT / "scenarios" / "paper" / "table4a.toml"  # barrier, impact only
INTERSECTION = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


def _gids(ax, prefix: str):
    return [p for p in ax.patches if (p.get_gid() or "").startswith(prefix)]


def _scalebar_text(ax) -> str:
    bars = [a for a in ax.artists if a.get_gid() == "scalebar"]
    assert len(bars) == 1
    return bars[0].txt_label.get_text()


def _legend_texts(ax) -> list[str]:
    leg = ax.get_legend()
    assert leg is not None
    return [t.get_text() for t in leg.get_texts()]


def _centroid(patch) -> np.ndarray:
    xy = np.asarray(patch.get_xy(), dtype=float)
    if np.allclose(xy[0], xy[-1]) and len(xy) > 4:
        xy = xy[:-1]
    return xy.mean(axis=0)


def _moving_bodies(scene):
    return [b for v in scene.scenario.vehicles if not v.is_barrier for b in v.bodies]


def test_scenes_are_found():
    assert INTERSECTION in SCENES


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_runout_scene_diagram(path):
    scene = _scene(path)
    assert scene.runout is not None, "scenes/ holds run-out scenes"
    ax = plot_scene(scene, system="SI")  # SI whatever the scene's own units (one is US)
    assert ax.figure is not None
    assert ax.get_aspect() == 1.0
    bodies = _moving_bodies(scene)
    drawn = [b for b in bodies if b.outline() is not None]
    # impact and rest outline of every body with outline data, plus ghosts
    assert len(_gids(ax, "outline:")) >= 2 * len(drawn)
    for b in drawn:
        assert len(_gids(ax, f"outline:impact:{b.name}")) == 1
        assert len(_gids(ax, f"outline:rest:{b.name}")) == 1
    assert len(_gids(ax, "outline:ghost:")) >= 1
    texts = _legend_texts(ax)
    assert len(texts) == len(set(texts)), "legend entries are deduplicated"
    assert any(t.startswith("tyre track, sliding") for t in texts)
    assert _scalebar_text(ax).endswith(" m")
    assert ax.get_xlabel() == "X [m]" and ax.get_ylabel() == "Y [m]"
    assert ax.get_title().replace("\n", " ") == scene.scenario.title
    # one delta-v arrow per moving body, a PDOF arrow per movable body in contact
    assert len(_gids(ax, "arrow:delta-v:")) == sum(1 for b in scene.impact.bodies.values()
                                                     if not b.fixed and b.delta_v_magnitude > 0)
    in_contact = [n for n in (scene.impact.body1, scene.impact.body2) if not scene.impact.bodies[n].fixed]
    assert len(_gids(ax, "arrow:pdof:")) == len(in_contact)
    if scene.evidence is not None:
        n = len(scene.evidence.checks)
        assert ax.get_legend().get_title().get_text().endswith(f"of {n} items within tolerance")


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_rest_outline_is_at_the_rest_position(path):
    scene = _scene(path)
    ax = plot_scene(scene, system="SI")
    for r in scene.runout.values():
        for name, br in r.bodies.items():
            body = next(b for b in _moving_bodies(scene) if b.name == name)
            if body.outline() is None:
                continue
            (patch,) = _gids(ax, f"outline:rest:{name}")
            expected = np.asarray(br.rest_position) + rotate(np.asarray(body.outline_center), br.rest_heading)
            np.testing.assert_allclose(_centroid(patch), expected, atol=1e-9)
            # and the impact outline at the impact state
            st = scene.scenario.states[name]
            (patch,) = _gids(ax, f"outline:impact:{name}")
            expected = np.asarray(st.position) + rotate(np.asarray(body.outline_center), st.heading)
            np.testing.assert_allclose(_centroid(patch), expected, atol=1e-9)


def test_us_units_scale_coordinates():
    scene = _scene(INTERSECTION)
    ax = plot_scene(scene, system="US")
    k, label = to_unit(1.0, Kind.LENGTH, "US")
    assert label == "ft"
    assert ax.get_xlabel() == "X [ft]" and ax.get_ylabel() == "Y [ft]"
    assert _scalebar_text(ax).endswith(" ft")
    br = scene.runout_body("car")
    body = next(b for b in _moving_bodies(scene) if b.name == "car")
    (patch,) = _gids(ax, "outline:rest:car")
    expected = k * (np.asarray(br.rest_position) + rotate(np.asarray(body.outline_center), br.rest_heading))
    np.testing.assert_allclose(_centroid(patch), expected, atol=1e-9)
    assert any("mph" in t for t in _legend_texts(ax))


def test_ghost_times_interval_and_explicit():
    scene = _scene(INTERSECTION)
    ax = plot_scene(scene, times=[0.5, 1.0, 2.0])
    ends = {n: r.t_end for r in scene.runout.values() for n in r.bodies}
    expected = sum(sum(1 for t in (0.5, 1.0, 2.0) if t < ends[b.name]) for b in _moving_bodies(scene))
    assert len(_gids(ax, "outline:ghost:")) == expected
    ax = plot_scene(scene, interval=0.25)
    assert len(_gids(ax, "outline:ghost:car:")) == math.floor((ends["car"] - 0.0625) / 0.25)
    ax = plot_scene(scene, times=())
    assert not _gids(ax, "outline:ghost:")
    # default: 4 to 6 ghosts per vehicle
    ax = plot_scene(scene)
    for r in scene.runout.values():
        first = next(iter(r.bodies))
        assert 4 <= len(_gids(ax, f"outline:ghost:{first}:")) <= 6
    with pytest.raises(ScenarioError, match="interval"):
        plot_scene(scene, interval=-1.0)


def test_draws_on_given_axes_without_new_figure():
    scene = _scene(INTERSECTION)
    fig, ax = plt.subplots()
    n = len(plt.get_fignums())
    out = plot_scene(scene, ax=ax, legend="best", arrows=False, evidence=False)
    assert out is ax
    assert len(plt.get_fignums()) == n
    assert not _gids(ax, "arrow:") and not _gids(ax, "evidence:")
    assert ax.get_legend() is not None


def test_evidence_overlay_and_verdict_colours():
    scene = _scene(INTERSECTION)
    ax = plot_scene(scene)
    rest_items = scene.scenario.evidence.rest
    assert len(_gids(ax, "evidence:rest:")) == sum(1 for r in rest_items if r.heading is not None)
    # fail one check: the legend says so in red and the summary counts it
    checks = list(scene.evidence.checks)
    i = next(k for k, c in enumerate(checks) if c.kind == "rest")
    checks[i] = dataclasses.replace(checks[i], residual=5.0, passed=False)
    bad = dataclasses.replace(scene, evidence=dataclasses.replace(scene.evidence, checks=tuple(checks)))
    ax = plot_scene(bad, legend="outside")  # the full legend: each item with its verdict
    leg = ax.get_legend()
    body = next(r.body for r in rest_items if (r.name or f"rest of {r.body}") == checks[i].name)
    (text,) = [t for t in leg.get_texts() if t.get_text().startswith(f"measured rest, {body}: FAIL")]
    assert matplotlib.colors.same_color(text.get_color(), "#c62828")
    n = len(checks)
    assert leg.get_title().get_text() == f"Evidence: {n - 1} of {n} items within tolerance"
    # the compact default: the evidence as one entry, its title counting the failure in red
    compact = plot_scene(bad).get_legend()
    assert not [t for t in compact.get_texts() if t.get_text().startswith("measured rest")]
    assert compact.get_title().get_text() == f"Evidence: {n - 1} of {n} items within tolerance"
    assert matplotlib.colors.same_color(compact.get_title().get_color(), "#c62828")


def test_impact_only_paper_table():
    scene = _scene(TABLE6)
    assert scene.runout is None
    ax = plot_scene(scene)
    assert ax.get_aspect() == 1.0
    assert not _gids(ax, "outline:ghost:") and not _gids(ax, "outline:rest:")
    assert len(_gids(ax, "arrow:delta-v:")) == 3
    assert {p.get_gid() for p in _gids(ax, "arrow:pdof:")} == {"arrow:pdof:trailer", "arrow:pdof:car"}
    texts = _legend_texts(ax)
    assert any(t.startswith("impact only") for t in texts)
    assert any(t.startswith("no outline data") for t in texts)  # Table 6 gives no body dimensions
    assert _scalebar_text(ax)


def test_pdof_arrows_point_along_the_crush_force():
    scene = _scene(TABLE6)
    ax = plot_scene(scene)
    p0 = np.asarray(scene.impact.point)
    for name in ("trailer", "car"):
        b = scene.impact.bodies[name]
        (arrow,) = _gids(ax, f"arrow:pdof:{name}")
        v = arrow.get_path().vertices
        tip = v[np.argmax(np.hypot(*(v - p0).T))]
        d = (tip - p0) / np.hypot(*(tip - p0))
        np.testing.assert_allclose(d, b.crush_impulse / np.hypot(*b.crush_impulse), atol=1e-6)
        # SAE J224: the force comes from pdof (clockwise from the heading)
        ang = b.heading - b.pdof + math.pi
        np.testing.assert_allclose(d, [math.cos(ang), math.sin(ang)], atol=1e-6)


def test_barrier_table():
    scene = _scene(TABLE4A)
    ax = plot_scene(scene)
    (barrier,) = _gids(ax, "barrier:")
    # the face passes through the contact point along the crush-surface tangent
    face = [ln for ln in ax.get_lines() if ln.get_linewidth() == 4.0]
    assert len(face) == 1
    xy = np.column_stack(face[0].get_data())
    p0, t = np.asarray(scene.impact.point), scene.impact.tangent
    along = (xy - p0) @ t
    off = (xy - p0) @ np.array([-t[1], t[0]])
    np.testing.assert_allclose(off, 0.0, atol=1e-9)
    assert along.min() < 0 < along.max()
    assert [p.get_gid() for p in _gids(ax, "arrow:pdof:")] == ["arrow:pdof:tractor"]
    assert any(t.startswith("barrier face") for t in _legend_texts(ax))


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_histories(path):
    scene = _scene(path)
    fig = plot_histories(scene, system="SI")
    # the panels (the roll panel's right-hand axis, sharing its box, is not one)
    axes = [a for a in fig.axes if a.get_ylabel() != "load transfer ratio |LTR|"]
    roll = bool(scene.rollover())
    assert len(axes) == history_panels(scene) == 3 + any(p.sustained for p in scene.joint.pairs) + roll
    assert len(fig.axes) == len(axes) + roll
    assert axes[0].get_ylabel() == "CG speed [m/s]"
    assert axes[1].get_ylabel() == "yaw rate [deg/s]"
    assert axes[2].get_ylabel() == "articulation [deg]"
    assert axes[-1].get_xlabel() == "time after separation [s]"
    n_bodies = sum(len(r.bodies) for r in scene.runout.values())
    labelled = [ln.get_label() for ln in axes[0].get_lines() if not ln.get_label().startswith("_")]
    assert sorted(labelled) == sorted(f"{n} ({v})" for v, r in scene.runout.items() for n in r.bodies)
    assert len(labelled) == n_bodies
    assert axes[0].get_legend() is not None and axes[1].get_legend() is not None
    fig = plot_histories(scene, system="US")
    assert fig.axes[0].get_ylabel() == "CG speed [mph]"


def test_histories_of_articulation_match_headings():
    scene = _scene(INTERSECTION)
    fig = plot_histories(scene)
    (line,) = [ln for ln in fig.axes[2].get_lines() if ln.get_label().startswith("tractor")]
    tr, tl = scene.runout_body("tractor").history, scene.runout_body("trailer").history
    np.testing.assert_allclose(line.get_ydata(), np.degrees(tr.heading - tl.heading), atol=1e-9)


def test_articulation_limits_once_each_and_only_where_reached():
    """Each articulation limit is named once in the panel's legend; its lines are drawn only where a hitch's
    articulation reaches LIMIT_SHOWN_FROM of it, else the legend says it is off the scale. A C-dolly's
    yaw-locked hitch says so in its label."""
    from crashsim.plotting import LIMIT_SHOWN_FROM

    scene = _scene(ROOT / "scenarios" / "scenes" / "doubles_c_dolly.toml")
    ax = plot_histories(scene).axes[2]
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    limit_labels = [t for t in labels if t.startswith("articulation limit")]
    limits = {h.articulation_limit for v in scene.scenario.vehicles for h in v.hitches
              if h.articulation_limit is not None}
    assert len(limit_labels) == len(limits) >= 1
    assert any("yaw-locked" in t for t in labels)
    peaks = {}
    for r in scene.runout.values():
        for v in scene.scenario.vehicles:
            for i, h in enumerate(v.hitches):
                hh = next((x for x in r.hitches if (x.front, x.rear) == (v.bodies[i].name, v.bodies[i + 1].name)), None)
                if hh is not None and h.articulation_limit is not None:
                    peaks[h.articulation_limit] = max(peaks.get(h.articulation_limit, 0.0),
                                                      float(np.max(np.abs(hh.articulation))))
    flat = [ln for ln in ax.get_lines() if len(ln.get_ydata()) == 2 and ln.get_ydata()[0] == ln.get_ydata()[1] != 0]
    for lim, peak in peaks.items():
        drawn = [ln for ln in flat if abs(abs(ln.get_ydata()[0]) - math.degrees(lim)) < 1e-9]
        assert len(drawn) == (2 if peak >= LIMIT_SHOWN_FROM * lim else 0)
        label = next(t for t in limit_labels if f"{math.degrees(lim):.0f} deg" in t)
        assert ("off the scale" in label) == (peak < LIMIT_SHOWN_FROM * lim)


def test_contact_force_panel_and_impact_lines():
    """The median-barrier slide: both bodies stay in sustained contact; the fourth panel draws
    each pair's force on the samples and on the solution's own steps (every sample is on the line,
    the report's peak force is its top, marked) and every panel marks each later impact event (#2
    the trailer's side slap, then the re-strikes) with a vertical line at its time."""
    scene = _scene(ROOT / "scenarios" / "scenes" / "median_barrier_slide.toml")
    fig = plot_histories(scene)
    assert len(fig.axes) == 4 and fig.axes[3].get_ylabel() == "contact force [N]"
    pairs = {p.name.replace("|", " \N{EN DASH} "): p for p in scene.joint.pairs if p.sustained}
    lines = {ln.get_label(): ln for ln in fig.axes[3].get_lines()
             if not ln.get_label().startswith(("_", "peak "))}
    assert lines.keys() == pairs.keys()
    for name, ln in lines.items():
        p = pairs[name]
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        assert np.all(np.diff(x) >= 0)
        for tq, fq in zip(p.t, p.force):  # every sample on the line
            assert np.any((x == tq) & (y == fq)), (name, tq)
        assert max(y) == p.peak_force
        (mark,) = [m for m in fig.axes[3].get_lines() if m.get_gid() == f"histories:peak:{p.name}"]
        assert (mark.get_xdata()[0], mark.get_ydata()[0]) == (p.peak_time, p.peak_force)
    events = scene.joint.impact_events()
    assert len(events) >= 2
    for ax in fig.axes:
        for ev in events:
            assert any(np.allclose(ln.get_xdata(), ev.t) for ln in ax.get_lines())
    assert sorted(t.get_text() for t in fig.axes[0].texts) == sorted(f"#{ev.number}" for ev in events)


@pytest.mark.parametrize("name", ["median_barrier_slide", "third_vehicle_waiting_car"])
def test_contact_force_panel_peak_is_the_reports(name):
    """The contact-force panel's top is the peak force the report prints, to the report's four
    digits, in US units: the sampled force (10 ms) topped out 25 % (median slide, trailer) and 40 %
    (third vehicle) below it."""
    scene = _scene(ROOT / "scenarios" / "scenes" / f"{name}.toml")
    text = format_joint(scene, "US")
    reported = {m[1]: float(m[2]) for m in re.finditer(r"^ +(\S+\|\S+): .*peak force ([-+.e\d]+) lbf", text, re.M)}
    assert reported
    fig = plot_histories(scene, system="US")
    for pair, peak in reported.items():
        (ln,) = [ln for ln in fig.axes[3].get_lines() if ln.get_label() == pair.replace("|", " \N{EN DASH} ")]
        drawn = max(ln.get_ydata())
        digits = 10.0 ** (np.floor(np.log10(peak)) - 3)  # the report's last digit
        assert abs(drawn - peak) <= 0.5 * digits, (pair, drawn, peak)
    plt.close(fig)


def test_contact_force_panel_starts_at_the_press():
    """A pair pressed into the barrier between two samples (10 ms apart) has its force drawn from the
    instant the run reports it pressed (contact_pressed), not from the next sample."""
    scene = _scene(ROOT / "scenarios" / "scenes" / "barrier_glance_15deg.toml")
    fig = plot_histories(scene)
    for e in (e for e in scene.joint.events if e.kind == "contact_pressed"):
        pair = e.data["pair"]
        (p,) = [p for p in scene.joint.pairs if p.name == pair]
        assert p.sustained
        (ln,) = [ln for ln in fig.axes[3].get_lines() if ln.get_label() == pair.replace("|", " \N{EN DASH} ")]
        x, y = np.asarray(ln.get_xdata()), np.asarray(ln.get_ydata())
        first = x[(y > 0) & (x >= e.t - 1e-9)][0]
        sampled = p.t[(p.force > 0) & (p.t >= e.t - 1e-9)][0]
        assert first - e.t < 1e-3 < sampled - e.t, (pair, e.t, first, sampled)
    plt.close(fig)


def test_histories_need_a_runout():
    with pytest.raises(ScenarioError, match="no run-out"):
        plot_histories(_scene(TABLE6))


@pytest.mark.parametrize("suffix", SCENE_FIGURE_SUFFIXES)
def test_save_scene_figures(tmp_path, suffix):
    scene = _scene(INTERSECTION)
    before = plt.get_fignums()
    out = save_scene_figures(scene, tmp_path / "sub" / f"scene{suffix}",
                             histories_path=tmp_path / f"hist{suffix}", dpi=60)
    assert out == [tmp_path / "sub" / f"scene{suffix}", tmp_path / f"hist{suffix}"]
    magic = {".png": b"\x89PNG", ".pdf": b"%PDF", ".svg": b"<?xml"}[suffix]
    for p in out:
        assert p.stat().st_size > 1000
        assert p.read_bytes().startswith(magic)
    assert plt.get_fignums() == before, "figures are closed"


def test_save_impact_only_scene(tmp_path):
    out = save_scene_figures(_scene(TABLE4A), tmp_path / "barrier.png", dpi=60)
    assert out == [tmp_path / "barrier.png"] and out[0].stat().st_size > 1000
    with pytest.raises(ScenarioError, match="no run-out"):
        save_scene_figures(_scene(TABLE4A), tmp_path / "b.png", histories_path=tmp_path / "h.png")


@pytest.mark.parametrize("bad", ["scene.jpg", "scene", "scene.PNG.txt"])
def test_save_rejects_other_suffixes(tmp_path, bad):
    before = plt.get_fignums()
    target = tmp_path / bad
    with pytest.raises(ScenarioError) as exc:
        save_scene_figures(_scene(INTERSECTION), target)
    msg = str(exc.value)
    assert str(target) in msg
    assert all(s in msg for s in (".png", ".svg", ".pdf"))
    assert not target.exists()
    assert plt.get_fignums() == before
    with pytest.raises(ScenarioError, match="histories_path"):
        save_scene_figures(_scene(INTERSECTION), tmp_path / "ok.png", histories_path=tmp_path / "h.gif")
    assert not (tmp_path / "ok.png").exists()


def test_unknown_unit_system():
    with pytest.raises(ScenarioError, match="unit system"):
        plot_scene(_scene(INTERSECTION), system="imperial")


def test_cli_plot_writes_both_figures(tmp_path, capsys):
    from crashsim.cli import main

    scene = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "barrier_15deg.toml"
    out, hist = tmp_path / "s.svg", tmp_path / "h.png"
    assert main(["plot", str(scene), "-o", str(out), "--histories", str(hist), "--units", "US",
                 "--interval", "0.05 s"]) == 0
    assert out.stat().st_size > 1000 and hist.stat().st_size > 1000
    assert "wrote" in capsys.readouterr().out


def test_cli_plot_rejects_bad_suffix(tmp_path, capsys):
    from crashsim.cli import main

    scene = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "barrier_15deg.toml"
    assert main(["plot", str(scene), "-o", str(tmp_path / "s.bmp")]) == 2
    assert ".bmp" in capsys.readouterr().err


def test_labels_of_impacts_close_in_time_do_not_cover_each_other():
    """The histories' impact labels: two impact events closer than IMPACT_LABEL_GAP of the time axis are
    on different rows (the pinned car's: the tractor strikes it again 4 ms before it strikes the van)."""
    from crashsim.plotting import IMPACT_LABEL_GAP

    scene = _scene(ROOT / "scenarios" / "scenes" / "pinned_car.toml")
    ax = plot_histories(scene).axes[0]
    labels = sorted((a.xy[0], a.xyann[1]) for a in ax.texts if (a.get_gid() or "").startswith("histories:impact:"))
    assert len(labels) == len(scene.joint.impact_events()) >= 2
    t_span = ax.get_xlim()[1] / 1.02
    close = [(a, b) for i, a in enumerate(labels) for b in labels[i + 1:] if abs(a[0] - b[0]) < IMPACT_LABEL_GAP * t_span]
    assert close, "the scene should have impacts close in time"
    assert all(a[1] != b[1] for a, b in close)

"""The approach on the scene figure and the time-distance chart: the drawn data are the computed ones."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "unit"))

from test_approach_scenario import scene as approach_scene  # noqa: E402

from crashsim.plotting import plot_scene, plot_time_distance, save_scene_figures  # noqa: E402
from crashsim.scene.run import run_scene  # noqa: E402
from crashsim.scenario import scenario_from_dict  # noqa: E402

FT = 0.3048


@pytest.fixture(scope="module")
def result():
    return run_scene(scenario_from_dict(approach_scene()))


def _line(ax, gid):
    found = [ln for ln in ax.lines if ln.get_gid() == gid]
    assert found, f"no line {gid!r}"
    return found[0]


def test_scene_figure_draws_the_approach(result):
    ax = plot_scene(result, system="US")
    a = result.scenario.approaches["A"]
    path = np.asarray(_line(ax, "approach:path:carA").get_xydata())
    assert np.allclose(path[-1] * FT, result.scenario.states["carA"].position, atol=1e-6)
    assert np.allclose(path[0] * FT, a.braking_start["carA"], atol=1e-6)
    assert any((p.get_gid() or "") == "outline:braking:carA" for p in ax.patches)
    mark = np.asarray(_line(ax, "approach:perception:A").get_xydata())[0]
    assert np.allclose(mark * FT, a.perception_point, atol=1e-6)
    tracks = [ln for ln in ax.lines if (ln.get_gid() or "").startswith("approach:track:carA/")]
    assert len(tracks) >= 4  # four locked wheels leave sliding tracks


@pytest.mark.parametrize("system, k", [("SI", 1.0), ("US", 1 / FT)])
def test_time_distance_chart(result, system, k):
    fig = plot_time_distance(result, system=system)
    ax_s, ax_v = fig.axes[:2]
    a = result.scenario.approaches["A"]
    xy = np.asarray(_line(ax_s, "td:approach:A").get_xydata())
    assert xy[0, 0] == pytest.approx(-a.time_to_impact - a.reaction_time)
    assert xy[0, 1] == pytest.approx(-k * (a.distance + a.reaction_distance), rel=1e-9)
    assert xy[-1] == pytest.approx([0.0, 0.0], abs=1e-4)
    run = np.asarray(_line(ax_s, "td:runout:A").get_xydata())
    assert run[0] == pytest.approx([0.0, 0.0], abs=1e-9)
    body = result.runout["A"].bodies["carA"]
    assert run[-1, 1] == pytest.approx(k * body.distance, rel=2e-3)
    # a vehicle without approach starts at the impact
    assert not [ln for ln in ax_s.lines if ln.get_gid() == "td:approach:B"]
    assert np.asarray(_line(ax_s, "td:runout:B").get_xydata())[0, 0] == 0.0
    assert "distance from the impact [" + ("m" if system == "SI" else "ft") + "]" == ax_s.get_ylabel()


def test_save_writes_the_chart(result, tmp_path):
    out = save_scene_figures(result, tmp_path / "s.png", time_distance_path=tmp_path / "td.svg")
    assert [p.name for p in out] == ["s.png", "td.svg"]
    assert (tmp_path / "td.svg").read_text().count("<svg") == 1


def test_scene_figure_without_the_approach(result):
    ax = plot_scene(result, approach=False)
    assert not [ln for ln in ax.lines if (ln.get_gid() or "").startswith("approach:")]
    assert not any((p.get_gid() or "").startswith("outline:braking:") for p in ax.patches)
    # the view then holds the impact and run-out only: the start of braking (18 m back) is outside
    assert ax.get_xlim()[0] > result.scenario.approaches["A"].braking_start["carA"][0]


def test_shipped_scene_legend_has_every_verdict():
    """Recorder and crush-energy checks have no place on the map: their verdicts are in the legend."""
    from crashsim.scenario import load_scenario

    path = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
    res = run_scene(load_scenario(path))
    ax = plot_scene(res, legend="outside")  # the full legend (the compact default counts the verdicts)
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    for c in res.evidence.checks:
        if c.kind in ("recorder", "crush energy"):
            entry = next(t for t in texts if c.name in t.replace("\n", " ") or c.name[:30] in t)
            assert ("PASS" if c.passed else "FAIL") in entry


def test_animation_starts_at_the_start_of_braking(result):
    """Frames before the impact: the braking car on its approach, the other at constant velocity
    back from its state at impact; from the impact on, the run-out as before."""
    from crashsim.animation import scene_animation
    from crashsim.geometry import to_world

    anim = scene_animation(result, dt=0.1)
    a = result.scenario.approaches["A"]
    t = anim.times
    assert t[0] == pytest.approx(-a.time_to_impact) and 0.0 in t and t[-1] == pytest.approx(result.t_end)
    assert np.all(np.diff(t) > 0)
    k = int(np.flatnonzero(t < 0)[len(np.flatnonzero(t < 0)) // 2])
    anim.frame(k)
    poses = anim.poses(t[k])
    assert poses["carA"] == a.pose("carA", t[k])
    st = result.scenario.states["carB"]
    assert poses["carB"][0] == pytest.approx(tuple(np.asarray(st.position) + np.asarray(st.velocity) * t[k]))
    corners = anim._S.body_of["carA"].outline()
    assert np.allclose(anim.outlines["carA"].get_xy()[:4], to_world(corners, *a.pose("carA", t[k]))[:4])
    assert anim.clock_text(k).endswith(", before impact")
    only_runout = scene_animation(result, dt=0.1, approach=False)
    assert only_runout.times[0] == 0.0
    assert len(anim.times) - len(only_runout.times) == int(np.sum(t < 0))


def test_recorder_samples_before_the_approach_get_the_assumed_constant_speed():
    """The shipped truck scene's recorder starts 5 s before the impact, before the modelled approach: the
    chart draws the constant speed the recorder check assumes there, from the earliest sample to the start
    of the approach (perception or braking), at the speed of braking; a scene whose recorder starts inside
    the approach has no such line."""
    from crashsim.scenario import load_scenario

    path = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
    res = run_scene(load_scenario(path))
    a = res.scenario.approaches["truck"]
    earliest = min(t + x.time_offset for x in res.scenario.evidence.recorder for t in x.times)
    start = -a.time_to_impact - a.reaction_time
    assert earliest < start
    fig = plot_time_distance(res, system="SI")
    ax_s, ax_v = fig.axes[:2]
    xy = np.asarray(_line(ax_s, "td:constant:truck").get_xydata())
    assert xy[0, 0] == pytest.approx(earliest) and xy[1, 0] == pytest.approx(start)
    assert (xy[1, 1] - xy[0, 1]) / (xy[1, 0] - xy[0, 0]) == pytest.approx(a.speed_at_braking, rel=1e-12)
    assert xy[1, 1] == pytest.approx(-a.distance - a.reaction_distance)
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend() is not None]
    assert "constant speed before the approach (assumed)" in [t.get_text() for lg in legends for t in lg.get_texts()]
    no_early = plot_time_distance(run_scene(scenario_from_dict(approach_scene())), system="SI")
    assert not [ln for ln in no_early.axes[0].lines if (ln.get_gid() or "").startswith("td:constant:")]

"""Charts that stay readable with 40 impacts: a shipped scene whose joint run-out is given 39
later impacts (synthetic: its own impact records, renumbered and moved in time and place), drawn
as the scene, the histories and the time-distance chart. No two labels overlap (pairwise window
extents) and every impact is represented: on the time-distance chart by a line each and a label
that names it ("impacts 5-12"), on the scene by its number, on the histories by a line each.
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
from matplotlib.text import Text  # noqa: E402
from matplotlib.transforms import Bbox  # noqa: E402

from crashsim.plotting.events import group_label, group_times  # noqa: E402
from crashsim.plotting import plot_histories, plot_scene, plot_time_distance  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
WAITING = ROOT / "scenarios" / "scenes" / "third_vehicle_waiting_car.toml"
N = 40


def _times(n_later: int) -> np.ndarray:
    """Impact times [s]: a burst right after the first impact, a dense cluster, a few apart."""
    burst = np.linspace(0.02, 0.3, 7)
    cluster = np.linspace(0.5, 0.9, n_later - 7 - 3)
    return np.concatenate([burst, cluster, [1.5, 2.0, 2.4]])


@functools.lru_cache(maxsize=None)
def _scene():
    scene = run_scene(load_scenario(WAITING))
    base = scene.joint.impacts[0]
    t_end = min(r.t_end for r in scene.runout.values())
    times = _times(N - 1) * (0.9 * t_end / 2.4)
    p0 = np.asarray(base.point, dtype=float)
    rng = np.random.default_rng(1)
    records = tuple(dataclasses.replace(base, event=i + 2, t=float(t), point=tuple(p0 + rng.uniform(-3.0, 3.0, 2)))
                    for i, t in enumerate(times))
    return dataclasses.replace(scene, joint=dataclasses.replace(scene.joint, impacts=records))


def _boxes(fig, axes=None):
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    out = []
    for ax in axes or fig.axes:
        for t in ax.texts:
            if t.get_visible() and t.get_text():
                bb = Text.get_window_extent(t, r)
                patch = t.get_bbox_patch()
                out.append((t, Bbox.union([bb, patch.get_window_extent(r)]) if patch is not None else bb))
    return out


def _no_overlap(boxes):
    bad = [(a.get_text(), b.get_text()) for (a, ba), (b, bb) in itertools.combinations(boxes, 2) if ba.overlaps(bb)]
    assert bad == []


def _numbers(text: str) -> list[int]:
    """The impact numbers a label names: "impact" (the first), "impact 7", "impacts 5-12, 14"."""
    if text == "impact":
        return [1]
    out = []
    for a, b in re.findall(r"(\d+)(?:-(\d+))?", text):
        out += list(range(int(a), int(b or a) + 1))
    return out


def test_the_synthetic_scene_has_40_impacts():
    assert 1 + len(_scene().joint.impact_events()) == N


def test_time_distance_names_every_impact_and_no_labels_overlap():
    scene = _scene()
    fig = plot_time_distance(scene)
    ax_s, ax_v = fig.axes[:2]
    boxes = _boxes(fig)
    _no_overlap(boxes)
    labels = [(t, bb) for t, bb in boxes if (t.get_gid() or "").startswith("td:impact:")]
    named = sorted(n for t, _ in labels for n in _numbers(t.get_text()))
    assert named == list(range(1, N + 1))  # each impact named once, none dropped
    assert len(labels) < N / 3  # grouped: far fewer labels than impacts
    page, frame = fig.bbox, ax_s.get_window_extent(fig.canvas.get_renderer())
    for t, bb in labels:  # inside the distance panel, where they are drawn
        assert frame.x0 - 1 <= bb.x0 and bb.x1 <= page.x1 and frame.y0 <= bb.y0 and bb.y1 <= frame.y1 + 1, t.get_text()
    for ax in (ax_s, ax_v):  # one line per impact on both panels
        lines = {ln.get_gid() for ln in ax.lines if (ln.get_gid() or "").startswith("td:impact-line:")}
        assert lines == {f"td:impact-line:{n}" for n in range(1, N + 1)}


def test_the_scene_numbers_every_impact_without_overlap():
    scene = _scene()
    ax = plot_scene(scene)
    boxes = _boxes(ax.figure, [ax])
    _no_overlap(boxes)
    numbers = sorted(int(t.get_text()) for t, _ in boxes if t.get_gid() == "label:impacts")
    assert numbers == list(range(1, N + 1))
    frame = ax.get_window_extent(ax.figure.canvas.get_renderer()).padded(1.0)
    for t, bb in boxes:
        assert frame.x0 <= bb.x0 and bb.x1 <= frame.x1 and frame.y0 <= bb.y0 and bb.y1 <= frame.y1, t.get_text()


def test_the_histories_mark_every_later_impact_without_overlap():
    scene = _scene()
    fig = plot_histories(scene)
    _no_overlap(_boxes(fig))
    times = sorted(ev.t for ev in scene.joint.impact_events())
    for ax in fig.axes:
        if not ax.lines:
            continue
        marked = sorted(ln.get_xdata()[0] for ln in ax.lines if ln.get_linestyle() == ":" and ln.get_color() == "0.45")
        assert marked == pytest.approx(times), ax.get_ylabel()


def test_grouping_joins_times_closer_than_the_gap():
    t = [0.0, 0.01, 0.05, 0.5, 0.52, 2.0]
    groups = group_times(t, 0.1)
    assert [i for g in groups for i in g] == list(range(len(t)))
    for g in groups:
        assert t[g[-1]] - t[g[0]] < 0.1
    for a, b in zip(groups, groups[1:]):
        assert t[b[0]] - t[a[0]] >= 0.1
    assert _numbers(group_label([5, 6, 7, 9])) == [5, 6, 7, 9]

"""The downhill arrow of a scene on a sloped road (``runout.grade``, ``runout.cross_slope``), under Agg:
it points down the slope on the screen and says how steep; a level road has none; a zone's own slope
is in its label."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from crashsim.plotting import plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
DOWNGRADE = ROOT / "scenarios" / "scenes" / "truck_downgrade_abs.toml"
LEVEL = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


def _downhill(ax):
    return [a for a in ax.texts if a.get_gid() == "downhill-arrow"]


def test_the_arrow_points_down_the_slope_and_says_how_steep():
    scene = run_scene(load_scenario(DOWNGRADE))
    road = scene.scenario.runout.road
    ax = plot_scene(scene)
    found = _downhill(ax)
    arrow = [a for a in found if a.arrow_patch is not None]
    text = [a.get_text() for a in found if a.get_text()]
    assert len(arrow) == 1 and len(text) == 1
    tail = -np.asarray(arrow[0].xyann, dtype=float)  # the head is at xy, the tail at xyann points from it
    down = -np.array([road.grade, road.cross_slope])
    np.testing.assert_allclose(tail / np.hypot(*tail), down / np.hypot(*down), atol=1e-12)
    assert text[0] == f"downhill {100 * np.hypot(road.grade, road.cross_slope):.3g} %"


def test_a_level_road_has_no_arrow():
    assert not _downhill(plot_scene(run_scene(load_scenario(LEVEL))))

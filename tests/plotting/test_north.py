"""The north arrow of a scene not placed on a survey (``[map] north``), under Agg.

``north`` is the bearing of the scene's +Y axis, clockwise from north: north lies that angle
counter-clockwise from +Y. The arrow is drawn (gid ``"north-arrow"``) on the scene figure and on
the animation; a scene placed on a survey keeps its grid north and refuses the key.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from crashsim.animation import scene_animation  # noqa: E402
from crashsim.cli import main  # noqa: E402
from crashsim.errors import ScenarioError  # noqa: E402
from crashsim.plotting import north_direction, plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
INTERSECTION = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"
SURVEY = ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml"


def _with_north(tmp_path, north: str, source: Path = INTERSECTION) -> Path:
    # the survey scene's files are relative to it: beside it; the intersection has none
    path = (tmp_path if source == INTERSECTION else source.parent) / f"_north_{tmp_path.name}.toml"
    path.write_text(source.read_text() + f'\n[map]\nnorth = "{north}"\n')
    return path


@pytest.fixture
def north_file(tmp_path, request):
    path = _with_north(tmp_path, request.param)
    yield path
    path.unlink()


def _arrow(ax) -> np.ndarray:
    """Direction the north arrow points on the screen (unit vector), from its annotation."""
    found = [a for a in ax.texts if a.get_gid() == "north-arrow" and a.arrow_patch is not None]
    assert len(found) == 1
    tail = -np.asarray(found[0].xyann, dtype=float)  # the head is at xy, the tail at xyann points from it
    return tail / np.hypot(*tail)


@pytest.mark.parametrize("north_file, expected", [("0 deg", (0.0, 1.0)), ("90 deg", (-1.0, 0.0)),
                                                  ("-30 deg", (0.5, math.sqrt(3) / 2))],
                         indirect=["north_file"], ids=["Y north", "Y east", "Y 30 deg west of north"])
def test_map_north_draws_the_arrow_on_the_figure_and_the_animation(north_file, expected):
    scene = run_scene(load_scenario(north_file))
    u, what = north_direction(scene.scenario)
    assert what == "north"
    np.testing.assert_allclose(u, expected, atol=1e-12)
    np.testing.assert_allclose(_arrow(plot_scene(scene)), expected, atol=1e-12)
    anim = scene_animation(scene, dt=1.0)
    np.testing.assert_allclose(_arrow(anim.ax), expected, atol=1e-12)
    n = next(t for t in anim.ax.texts if t.get_gid() == "north-arrow" and t.get_text() == "N")
    assert n.get_visible()


def test_no_arrow_without_north_or_survey():
    scene = run_scene(load_scenario(INTERSECTION))
    assert north_direction(scene.scenario) is None
    assert not [t for t in plot_scene(scene).texts if t.get_gid() == "north-arrow"]


def test_survey_scene_keeps_its_grid_north():
    sc = load_scenario(SURVEY)
    u, what = north_direction(sc)
    rot = float(sc.data["survey"]["rotation"])
    assert what == "grid north"
    np.testing.assert_allclose(u, (math.sin(rot), math.cos(rot)), atol=1e-12)


def test_map_north_on_a_survey_scene_is_refused_naming_the_key(tmp_path, capsys):
    path = _with_north(tmp_path, "12 deg", SURVEY)
    try:
        with pytest.raises(ScenarioError, match=r"map\.north: 12 deg is given for a scene placed on a survey.*"
                                                r"remove map\.north") as exc:
            load_scenario(path)
        assert exc.value.file is not None
        assert main(["run", str(path)]) == 2
        err = capsys.readouterr().err
        assert "map.north" in err and len(err.strip().splitlines()) == 1
    finally:
        path.unlink()


@pytest.mark.parametrize("value", ["400 deg", "-361 deg", "12 m"])
def test_map_north_out_of_range_or_not_an_angle(tmp_path, value):
    path = _with_north(tmp_path, value)
    try:
        with pytest.raises(ScenarioError, match=r"map\.north"):
            load_scenario(path)
    finally:
        path.unlink()

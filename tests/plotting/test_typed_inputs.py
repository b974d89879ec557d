"""Figures read the scene's typed inputs (vehicle descriptions, the survey frame), not its dict."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crashsim.plotting import plot_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402
from crashsim.scene import run_scene  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


def _texts(ax):
    legend = ax.get_legend()
    return [t.get_text() for t in ax.texts] + ([t.get_text() for t in legend.get_texts()] if legend else [])


def test_descriptions_and_north_arrow_come_from_the_typed_scenario():
    sc = load_scenario(ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml")
    assert sc.descriptions["truck"] == "tractor + loaded semitrailer" and sc.survey_frame is not None
    bare = dataclasses.replace(sc, data={k: v for k, v in sc.data.items() if k not in ("vehicles", "survey")})
    scene = dataclasses.replace(run_scene(sc), scenario=bare)
    ax = plot_scene(scene)
    texts = _texts(ax)
    assert any("tractor + loaded semitrailer" in t for t in texts)
    assert "N" in texts  # the grid north arrow of a scene placed on its survey
    plt.close(ax.figure)
    # a scene not placed on a survey has no north arrow
    unplaced = dataclasses.replace(scene, scenario=dataclasses.replace(bare, survey_frame=None))
    ax = plot_scene(unplaced)
    assert "N" not in _texts(ax)
    plt.close(ax.figure)


def test_map_north_and_the_barrier_extent_come_from_the_typed_scenario(tmp_path):
    """[map] north and the [barrier] extent are read into the Scenario at load: a scenario whose dict has
    lost them still draws the north arrow and the barrier face over its extent."""
    import numpy as np

    from crashsim.plotting import north_direction

    src = ROOT / "scenarios" / "scenes" / "barrier_15deg.toml"
    f = tmp_path / "north.toml"
    f.write_text(src.read_text() + '\n[map]\nnorth = "90 deg"\n')
    sc = load_scenario(f)
    assert sc.north == np.pi / 2 and sc.barrier_extent is not None
    bare = dataclasses.replace(sc, data={k: v for k, v in sc.data.items() if k not in ("map", "barrier")})
    u, what = north_direction(bare)
    assert what == "north" and np.allclose(u, (-1.0, 0.0), atol=1e-12)
    assert bare.barrier_extent == sc.barrier_extent

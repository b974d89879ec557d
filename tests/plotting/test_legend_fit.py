"""Legends that fit: every legend mode of ``crashsim plot --legend`` (and each on a print sheet),
rendered on busy scenes, puts the whole legend inside the figure (and, outside the axes, off
the drawing; inside, within the axes). Measured with the renderer's window extents.
"""

from __future__ import annotations

import functools
from pathlib import Path

import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from crashsim.figure_options import LEGEND_MODES  # noqa: E402
from crashsim.plotting import plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
BUSY = [ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml",  # survey layers, approach, recorder, 3 impacts
        ROOT / "scenarios" / "scenes" / "third_vehicle_waiting_car.toml",  # three vehicles
        ROOT / "scenarios" / "scenes" / "verge_run_off.toml"]  # zones and map lines


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


@pytest.mark.parametrize("path", BUSY, ids=lambda p: p.stem)
@pytest.mark.parametrize("sheet", [None, "A4"], ids=["screen", "A4"])
@pytest.mark.parametrize("mode", LEGEND_MODES)
def test_the_legend_lies_inside_the_figure(path, mode, sheet):
    ax = plot_scene(_scene(path), legend=mode, paper=sheet)
    fig = ax.figure
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    leg = ax.get_legend() or (fig.legends[0] if fig.legends else None)
    if mode == "none":
        assert leg is None
        return
    assert leg is not None and len(leg.get_texts()) >= 5
    box, page, frame = leg.get_window_extent(r), fig.bbox, ax.get_window_extent(r)
    assert page.x0 <= box.x0 and box.x1 <= page.x1 and page.y0 <= box.y0 and box.y1 <= page.y1, (mode, box, page)
    for t in leg.get_texts():  # every entry's text, too (a legend's frame can be narrower than a long text)
        tb = t.get_window_extent(r)
        assert page.x0 <= tb.x0 and tb.x1 <= page.x1 and page.y0 <= tb.y0 and tb.y1 <= page.y1, t.get_text()
    if mode == "inside":
        assert frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    else:
        assert not box.overlaps(frame), (mode, box, frame)

"""The histories' roll panel, where the wheel-lift and rollover check ran: each body's lateral
acceleration with its rollover threshold line, its load transfer ratio with the wheel lift at 1,
measured on the rendered figure (lines' window extents inside the panel, the threshold line at
the threshold of the report's verdict); none where the check is off; the sampled indicators stay
out of the JSON.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from crashsim.plotting import history_panels, plot_histories  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.scenario import load_scenario  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
ROLL = ROOT / "scenarios" / "scenes" / "truck_downgrade_abs.toml"  # [runout] rollover = true
PLAIN = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"  # the check off


@functools.lru_cache(maxsize=None)
def _scene(path: Path):
    return run_scene(load_scenario(path))


def _line(fig, gid):
    for ax in fig.axes:
        for ln in ax.lines:
            if ln.get_gid() == gid:
                return ax, ln
    raise AssertionError(f"no line {gid!r}")


def test_the_roll_panel_draws_each_threshold_and_the_wheel_lift_inside_it():
    scene = _scene(ROLL)
    roll = scene.rollover()
    assert roll and history_panels(scene) == 3 + 1 + any(p.sustained for p in scene.joint.pairs)
    fig = plot_histories(scene)
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    bodies = {b: thr for v in roll.values() for b, thr in v["thresholds_g"].items()}
    assert len(bodies) == 3
    panel = None
    for body, thr in bodies.items():
        ax, ln = _line(fig, f"roll:threshold:{body}")
        panel = panel or ax
        assert ax is panel  # one panel
        assert ln.get_ydata()[0] == pytest.approx(thr)
        frame, bb = ax.get_window_extent(r), ln.get_window_extent(r)
        assert frame.y0 < bb.y0 < frame.y1  # on the scale, not at its edge
        # the curve of |a_y| under it: its peak is the largest sampled lateral acceleration
        _, ay = _line(fig, f"roll:ay:{body}")
        hist = next(x.rollover["history"] for x in scene.runout.values()
                    if x.rollover is not None and body in x.rollover["history"])
        assert np.max(ay.get_ydata()) == pytest.approx(np.max(np.abs(hist[body]["lateral_acceleration_g"])))
        assert frame.y0 <= ay.get_window_extent(r).y1 <= frame.y1
        tw, ltr = _line(fig, f"roll:ltr:{body}")
        assert tw is not panel and tw.get_window_extent(r).bounds == pytest.approx(frame.bounds)  # a twin of the panel
        assert tw.get_window_extent(r).y0 <= ltr.get_window_extent(r).y1 <= tw.get_window_extent(r).y1
    tw, lift = _line(fig, "roll:lift")
    assert lift.get_ydata()[0] == 1.0
    frame = tw.get_window_extent(r)
    assert frame.y0 < lift.get_window_extent(r).y0 < frame.y1
    assert panel.get_ylabel() == "lateral acceleration [g]" and tw.get_ylabel() == "load transfer ratio |LTR|"
    assert panel is fig.axes[history_panels(scene) - 1]  # the last panel
    # the legend inside the panel and over no threshold line: the lines lie under its bottom
    leg = panel.get_legend().get_window_extent(r)
    assert frame.x0 <= leg.x0 and leg.x1 <= frame.x1 and leg.y1 <= frame.y1
    for body in bodies:
        assert _line(fig, f"roll:threshold:{body}")[1].get_window_extent(r).y1 < leg.y0, body


def test_no_roll_panel_without_the_check_and_no_samples_in_the_json():
    plain = _scene(PLAIN)
    assert not plain.rollover()
    fig = plot_histories(plain)
    assert len(fig.axes) == history_panels(plain) == 3 + any(p.sustained for p in plain.joint.pairs)
    assert not [ln for ax in fig.axes for ln in ax.lines if (ln.get_gid() or "").startswith("roll:")]
    text = json.dumps(_scene(ROLL).to_dict())
    assert '"rollover"' in text and "lateral_acceleration_g\": [" not in text and '"history"' not in text

"""The wheel time line (crashsim.plotting.timeline): every wheel's set state, air-brake level, computed
sliding and steering on one time axis from the approach to rest, measured on the figure's data."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import matplotlib
import numpy as np
import pytest

from crashsim.plotting.timeline import plot_wheel_timeline, wheel_rows
from crashsim.scenario import load_scenario
from crashsim.scene.run import run_scene

ROOT = Path(__file__).resolve().parents[2]
TRUCK = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
ABS = ROOT / "scenarios" / "scenes" / "truck_downgrade_abs.toml"
RECORDED = ROOT / "tests" / "data" / "recorded_approach.toml"


def _scene(path):
    return run_scene(load_scenario(path))


def test_every_wheel_has_its_set_states_on_the_impacts_time_axis():
    scene = _scene(TRUCK)
    rows = wheel_rows(scene)
    a = scene.scenario.approaches["truck"]
    assert len(rows) == 10 + 4  # tractor 3 axles, trailer 2, the car 2; a row per wheel
    changes = {c["select"]: c["at"] for c in
               tomllib.loads(TRUCK.read_text())["vehicles"]["truck"]["approach"]["wheel_changes"]}
    for r in rows:
        if r["vehicle"] != "truck":
            continue
        unit = r["key"].split("/")[0]
        at = float(changes[unit].split()[0])
        pre = [b for b in r["bars"] if b[1] <= 1e-12]
        # braked at 30 % from the start of braking, locked from the file's change on
        assert pre[0][2] == "braked" and pre[0][3] == "braked 30%"
        assert pre[0][0] == pytest.approx(-a.time_to_impact, abs=1e-9)
        assert pre[1][2] == "locked" and pre[1][0] == pytest.approx(at - a.time_to_impact, abs=1e-9)
        # a locked wheel slides: the computed sliding covers the locked stretch
        slid = sum(t1 - t0 for t0, t1 in r["sliding"] if t1 <= 1e-9)
        assert slid == pytest.approx(pre[1][1] - pre[1][0], abs=0.02)
    # the later impacts of the run-out are lines at their times
    fig = plot_wheel_timeline(scene)
    drawn = sorted(ln.get_xdata()[0] for ln in fig.axes[0].lines if ln.get_gid() == "tl:later-impact")
    assert drawn == pytest.approx(sorted(ev.t for ev in scene.joint.impact_events()))
    assert len(drawn) >= 1
    matplotlib.pyplot.close(fig)


def test_air_brakes_draw_their_ramp_and_every_text_is_legible():
    scene = _scene(ABS)
    fig = plot_wheel_timeline(scene)
    lines = [ln for ln in fig.axes[0].lines if (ln.get_gid() or "").startswith("tl:brake:")]
    assert lines, "no air-brake level drawn"
    ramp = scene.scenario.approach_inputs["truck"].spec.wheels.brakes
    t_on, rise, _, _ = ramp.times("tractor")
    t_pre = scene.scenario.approaches["truck"].time_to_impact
    ln = next(ln for ln in lines if ln.get_gid().startswith("tl:brake:tractor/"))
    t, y = ln.get_xdata(), ln.get_ydata()
    row_lo = float(np.min(y))
    # the level leaves 0 at t_on and is full rise later (on the row's 0.76 height)
    assert np.interp(t_on - t_pre - 0.01, t, y) == pytest.approx(row_lo, abs=1e-6)
    assert np.interp(t_on + rise - t_pre + 0.01, t, y) == pytest.approx(row_lo + 0.76, abs=1e-3)
    fig.canvas.draw()
    small = [t.get_text() for t in fig.findobj(matplotlib.text.Text) if t.get_visible() and t.get_text().strip()
             and t.get_fontsize() < 7.0]
    assert not small, small
    matplotlib.pyplot.close(fig)


def test_a_recorded_tables_steering_and_controlled_brakes():
    scene = _scene(RECORDED)
    rows = {r["key"]: r for r in wheel_rows(scene)}
    front = rows["pickup/0/left"]
    t, ang = front["steer"]
    assert math.degrees(np.max(ang)) == pytest.approx(
        math.degrees(np.max(scene.scenario.approaches["pickup"].steering["left"])), rel=1e-9)
    assert rows["pickup/1/left"]["steer"] is None  # the rear axle is not steered
    pre = [b for b in front["bars"] if b[1] <= 1e-12]
    # rolling while the table holds 45 mph, then braked by the controller (a range of fractions)
    assert [b[2] for b in pre] == ["rolling", "braked"]
    assert pre[1][0] == pytest.approx(-2.5, abs=0.051)
    assert pre[1][3].startswith("braked ") and "-" in pre[1][3]

"""Messages in the user's terms: one test per message that misled (issue 19)."""

from __future__ import annotations

from pathlib import Path

import pytest

import crashsim
from crashsim.errors import ScenarioError

ROOT = Path(__file__).resolve().parents[2]
TABLE1A = str(ROOT / "scenarios" / "paper" / "table1a.toml")
SCENE = str(ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml")


def test_no_slide_law_says_no_sliding_once():
    text = crashsim.run(TABLE1A).report()
    line = next(ln for ln in text.splitlines() if "impulse ratio mu" in ln)
    assert line.count("no sliding at separation") == 1
    assert line.endswith("(law no_slide: no sliding at separation)")


def test_vehicle_at_rest_before_the_impact_has_no_loss_share():
    text = crashsim.run(TABLE1A, vehicles__vehicle1__speed="0 m/s").report()
    assert "nan" not in text
    row = next(ln for ln in text.splitlines() if ln.strip().startswith("vehicle1 "))
    assert row.rstrip().endswith("n/a (at rest before)")
    assert next(ln for ln in text.splitlines() if ln.strip().startswith("system ")).rstrip().endswith("6.2 %")


def test_us_report_gives_the_stop_reason_in_us_units():
    text = crashsim.run(SCENE, runout__t_max="1 s").report("US")
    stops = [ln for ln in text.splitlines() if "t_max" in ln]
    assert len(stops) >= 3  # run-out status, event, warning
    for ln in stops:
        assert "m/s" not in ln and "mph > v_stop = 0.06711 mph" in ln, ln
    assert "m/s > v_stop" in crashsim.run(SCENE, runout__t_max="1 s").report("SI")

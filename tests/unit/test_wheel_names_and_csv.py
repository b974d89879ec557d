"""Wheels named as the file names them (the axle's name) in reports and CSV files; ``--dt`` for every
history CSV (bodies, wheel tracks, approach); CSV numbers at the documented decimals."""

from __future__ import annotations

import csv
import re
from pathlib import Path

import numpy as np
import pytest

from crashsim.motion.wheels import enumerate_wheels, select_wheels, wheel_labels
from crashsim.reconstruct import run_scene
from crashsim.scene.run import CSV_DECIMALS, csv_number
from crashsim.scenario import load_scenario
from crashsim.vehicles import Axle, Body, Vehicle

ROOT = Path(__file__).resolve().parents[2]
TRUCK = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"


@pytest.fixture(scope="module")
def truck():
    return run_scene(load_scenario(TRUCK))


def test_labels_use_the_axle_names_where_they_select_the_wheel():
    body = Body("b", 1000.0, 1000.0, 4.0, 2.0, axles=(Axle(1.0, 1.5, name="front"), Axle(-1.0, 1.5, name=""),
                                                      Axle(-1.5, 1.5, name="7"), Axle(-1.8, 1.5, name="tag"),
                                                      Axle(-1.9, 1.5, name="tag")))
    veh = Vehicle("v", (body,))
    labels = wheel_labels([veh])
    assert labels["b/0/left"] == "b/front/left"
    assert labels["b/1/right"] == "b/1/right"  # no name
    assert labels["b/2/left"] == "b/2/left"  # a number as name would read as an index
    assert labels["b/3/left"] == "b/3/left" and labels["b/4/left"] == "b/4/left"  # not unique
    specs = enumerate_wheels(veh)
    for key, label in labels.items():  # every label selects its own wheel
        idx, _ = select_wheels(veh, specs, label, "test")
        assert [specs[i].key for i in idx] == [key]


def test_the_report_names_wheels_by_axle_and_keeps_the_users_text(truck):
    text = truck.report("SI")
    assert "closest track: tractor/drive 1/left" in text and "closest track: tractor/1/left" not in text
    assert "pre-impact skid, tractor/1/left" in text  # the evidence item's name as the file wrote it


def _read(path):
    with open(path, newline="") as fh:
        rows = list(csv.reader(fh))
    return rows[0], rows[1:]


def test_tracks_and_approach_at_dt(truck, tmp_path):
    truck.write_csv(tmp_path, system="SI", dt=0.1)
    head, rows = _read(tmp_path / "truck_tracks.csv")
    assert head == ["wheel", "t [s]", "x [m]", "y [m]", "sliding"]
    wheels = {r[0] for r in rows}
    assert "tractor/steer/left" in wheels and "trailer/axle 2/right" in wheels
    t = np.array([float(r[1]) for r in rows if r[0] == "tractor/steer/left"])
    assert np.allclose(t, 0.1 * np.arange(len(t)), atol=1e-9)
    # the contact point at a time that is also a stored sample equals the stored track (to the CSV's 0.1 mm)
    r = truck.runout["truck"]
    tr = r.wheels["tractor/0/left"]
    k = int(np.argmin(np.abs(tr.t - 0.5)))
    assert tr.t[k] == pytest.approx(0.5, abs=1e-12)
    row = next(x for x in rows if x[0] == "tractor/steer/left" and float(x[1]) == pytest.approx(0.5))
    assert (float(row[2]), float(row[3])) == pytest.approx(tuple(tr.points[k]), abs=1.01e-4)
    head, rows = _read(tmp_path / "truck_approach.csv")
    t = np.array([float(x[0]) for x in rows])
    assert t[-1] == 0 and np.allclose(np.diff(t), 0.1, atol=1e-9)
    a = truck.scenario.approaches["truck"]
    assert float(rows[-1][1]) == pytest.approx(0.0, abs=0.02)  # at the impact (path-length quadrature)
    assert float(rows[-1][2]) == pytest.approx(a.speed_at_impact, abs=1e-4)
    assert float(rows[0][2]) == pytest.approx(a.speed_at_braking, abs=1e-4)  # the reaction interval
    assert t[0] >= -(a.time_to_impact + a.reaction_time) - 1e-9


def test_csv_numbers_carry_the_documented_decimals(truck, tmp_path):
    truck.write_csv(tmp_path, system="US")
    head, rows = _read(tmp_path / "truck_history.csv")
    units = [re.search(r"\[(.+)\]", h)[1] for h in head]
    kind = {"s": "time", "ft": "length", "deg": "angle", "mph": "speed", "deg/s": "angular_velocity", "lbf": "force"}
    for r in rows[:50]:
        for value, unit in zip(r, units):
            decimals = len(value.split(".")[1]) if "." in value else 0
            assert decimals <= CSV_DECIMALS["US"][kind[unit]], (unit, value)
    assert max(len(v.split(".")[1]) for r in rows for v in r if "." in v) > 2  # not rounded to nothing


def test_csv_number():
    assert csv_number(1.23456789, "length", "SI") == "1.2346"
    assert csv_number(0.3048, "length", "US") == "1"
    assert csv_number(-1e-9, "length", "SI") == "0"
    assert csv_number(float("nan"), "speed", "SI") == "" and csv_number(None, "speed", "SI") == ""

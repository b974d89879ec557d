"""The reconstructionist's workflow: units everywhere, events with their place, CSV at any time
step, the Python API, and the one-time kernel compile."""

from __future__ import annotations

import csv
import math
import re
from pathlib import Path

import numpy as np
import pytest

import crashsim
from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.report import table
from crashsim.units import convert, resolve_system

ROOT = Path(__file__).resolve().parents[2]
SCENES = ROOT / "scenarios" / "scenes"
SIDE = SCENES / "car_trailer_side_impact.toml"   # a trailer's articulation stop closes and opens
SWING = SCENES / "trailer_swings_into_car.toml"  # a later impact, vehicles at rest at different times


@pytest.fixture(scope="module")
def side():
    return crashsim.run(SIDE)


@pytest.fixture(scope="module")
def swing():
    return crashsim.run(SWING)


# ------------------------------------------------------------------ units
SI_TOKENS = re.compile(r"\d (m/s|m|J|N|N s|N m s|kg|rad/s)(?![\w/^])")


def test_us_report_has_no_si_quantity(side, swing):
    for scene in (side, swing):
        text = scene.report("US")
        found = SI_TOKENS.findall(text)
        assert not found, found
        assert "mph" in text and " ft" in text and "lbf s" in text and "ft lbf" in text
        assert "lbf ft s" in text  # the moment impulse carries its unit


def test_units_any_case_and_the_scenarios_own(tmp_path, capsys):
    assert resolve_system("us") == "US" and resolve_system(None, "si") == "SI"
    with pytest.raises(ScenarioError, match="'metric'"):
        resolve_system("metric")
    text = SWING.read_text()
    assert "units" not in text.split("[vehicles")[0]
    path = tmp_path / "us.toml"
    path.write_text(text.replace("[scenario]\n", '[scenario]\nunits = "us"\n', 1))
    assert main(["run", str(path)]) == 0
    out = capsys.readouterr().out
    assert "units: US" in out and "mph" in out
    assert main(["run", str(path), "--units", "si"]) == 0
    out = capsys.readouterr().out
    assert "units: SI" in out and "mph" not in out


def test_columns_align_for_any_name_length():
    rows = [["body", "velocity"], ["a", "(1, 2) m/s"], ["a_body_with_a_very_long_name_indeed", "(3, 4) m/s"]]
    lines = table(rows)
    starts = {ln.index(cell) for ln, cell in zip(lines, ("velocity", "(1, 2)", "(3, 4)"))}
    assert len(starts) == 1


def test_report_tables_align(side):
    text = side.report("SI")
    block = text.split("\n\n")[2].splitlines()  # the impact's body table
    assert block[0].strip().startswith("body")
    col = block[0].index("velocity after")
    assert all(ln[col] == "(" for ln in block[1:]), block


# ------------------------------------------------------------------ events
def test_events_carry_their_place(side, swing):
    joint = swing.joint
    impact = next(e for e in joint.events if e.kind == "impact")
    np.testing.assert_allclose(impact.place, joint.impacts[0].point, atol=1e-12)
    for e in joint.events:
        if e.kind == "vehicle_rest":
            lead = next(iter(swing.runout[e.vehicles[0]].bodies.values()))
            np.testing.assert_allclose(e.place, lead.rest_position, atol=1e-6)
    # the articulation stop: the hitch pin, the same point from both bodies' poses
    stop = next(e for e in side.joint.events if e.kind == "stop_closed")
    veh = side.scenario.vehicles[[v.name for v in side.scenario.vehicles].index(stop.vehicles[0])]
    hitch = veh.hitches[0]
    bodies = side.runout[veh.name].bodies
    front, rear = (bodies[b.name] for b in veh.bodies[:2])
    for body, point in ((front, hitch.front_point), (rear, hitch.rear_point)):
        x, y, h = np.asarray(body.sol(stop.t))[:3]
        pin = (x + math.cos(h) * point[0] - math.sin(h) * point[1], y + math.sin(h) * point[0] + math.cos(h) * point[1])
        np.testing.assert_allclose(stop.place, pin, atol=1e-6)
    assert stop.energy > 0


def test_event_lines_in_the_report(side):
    si, us = side.report("SI"), side.report("US")
    stop = next(e for e in side.joint.events if e.kind == "stop_closed")
    assert f"dissipates {stop.energy:.4g} J" in si
    assert f"dissipates {convert(stop.energy, 'J', 'ft lbf'):.4g} ft lbf" in us
    line = next(ln for ln in us.splitlines() if "stop_closed" in ln)
    x, y = (convert(v, "m", "ft") for v in stop.place)
    assert f"({x:.4g}, {y:.4g}) ft" in line


def test_zone_events_lie_on_the_zone_edge():
    from crashsim.warmup import _tiny_scene  # a scene with a friction zone, built from the schema
    from crashsim.reconstruct import run_scene

    scene = run_scene(_tiny_scene())
    zone = scene.scenario.runout.road.zones[0]
    poly = np.asarray(zone.polygon)
    events = [e for e in scene.joint.events if e.kind in ("zone_enter", "zone_exit")]
    assert len(events) >= 4
    for e in events:
        p = np.asarray(e.place)
        d = min(_segment_distance(p, poly[i], poly[(i + 1) % len(poly)]) for i in range(len(poly)))
        assert d < 1e-3, (e, d)


def _segment_distance(p, a, b):
    t = np.clip(np.dot(p - a, b - a) / np.dot(b - a, b - a), 0.0, 1.0)
    return float(np.hypot(*(a + t * (b - a) - p)))


# ------------------------------------------------------------------ CSV and histories
def test_csv_in_us_units_at_a_chosen_step(swing, tmp_path):
    written = swing.write_csv(tmp_path, system="US", dt=0.25)
    hist = next(p for p in written if p.name == "truck_history.csv")
    with hist.open() as fh:
        rows = list(csv.reader(fh))
    head = rows[0]
    assert "tractor.x [ft]" in head and "tractor.vx [mph]" in head and "tractor.heading [deg]" in head
    assert "tractor-trailer.force_long [lbf]" in head
    t = np.array([float(r[0]) for r in rows[1:]])
    np.testing.assert_allclose(t[:-1], 0.25 * np.arange(len(t) - 1), atol=1e-12)
    half = 0.5e-4 + 1e-12  # the CSV carries 4 decimals of s, ft, mph and deg (CSV_DECIMALS): half a unit of the last
    assert t[-1] == pytest.approx(swing.t_end, abs=half)
    tractor = swing.runout["truck"].bodies["tractor"]
    k = 5
    x, y, h, vx = np.asarray(tractor.sol(t[k]))[:4]
    row = dict(zip(head, map(float, rows[1 + k])))
    assert row["tractor.x [ft]"] == pytest.approx(convert(x, "m", "ft"), abs=half)
    assert row["tractor.vx [mph]"] == pytest.approx(convert(vx, "m/s", "mph"), abs=half)
    assert row["tractor.heading [deg]"] == pytest.approx(math.degrees(h), abs=half)
    imp = next(p for p in written if p.name == "impact.csv").read_text().splitlines()[0]
    assert "delta_v [mph]" in imp and "pdof [deg]" in imp


def test_csv_dt_from_the_command_line(tmp_path, capsys):
    assert main(["run", str(SWING), "--csv", str(tmp_path), "--dt", "0.5 s", "--units", "US"]) == 0
    rows = (tmp_path / "car_history.csv").read_text().splitlines()
    assert rows[0].startswith("t [s],car.x [ft]")
    assert [float(r.split(",")[0]) for r in rows[1:4]] == [0.0, 0.5, 1.0]
    capsys.readouterr()
    assert main(["run", str(SWING), "--dt", "0.5 s"]) == 2
    assert "--dt" in capsys.readouterr().err
    assert main(["run", str(SWING), "--csv", str(tmp_path / "x"), "--dt", "-1 s"]) == 2
    assert "--dt = '-1 s'" in capsys.readouterr().err


def test_history_arrays_are_the_dense_solution(swing):
    h = swing.history(0.1)
    assert h["t"][0] == 0.0 and h["t"][-1] == pytest.approx(swing.t_end)
    car = swing.runout["car"].bodies["car"]
    np.testing.assert_allclose(h["car.x"][3], np.asarray(car.sol(0.3))[0], rtol=1e-12)
    after = h["t"] > car.time_to_rest
    np.testing.assert_allclose(h["car.x"][after], car.rest_position[0], atol=1e-9)  # at rest, stays
    np.testing.assert_allclose(h["car.speed"], np.hypot(h["car.vx"], h["car.vy"]))
    pd = pytest.importorskip("pandas")
    frame = swing.history_frame(0.1)
    assert isinstance(frame, pd.DataFrame) and frame.index.name == "t [s]"
    np.testing.assert_allclose(frame["car.y"].to_numpy(), h["car.y"])


# ------------------------------------------------------------------ the API
def test_top_level_api(swing, tmp_path):
    import matplotlib

    matplotlib.use("Agg")
    assert isinstance(crashsim.load(SWING), crashsim.scenario.Scenario)
    faster = crashsim.run(SWING, vehicles__car__speed="40 mph")
    same = crashsim.run(crashsim.load(SWING), {"vehicles.car.speed": "40 mph"})
    assert faster.impact.bodies["car"].delta_v_magnitude == pytest.approx(same.impact.bodies["car"].delta_v_magnitude)
    assert faster.impact.bodies["car"].velocity_before[1] == pytest.approx(convert(40, "mph", "m/s"))
    assert swing.impact.bodies["car"].velocity_before[1] != pytest.approx(convert(40, "mph", "m/s"))
    with pytest.raises(ScenarioError, match="vehicles.car.sped"):
        crashsim.run(SWING, vehicles__car__sped="40 mph")
    ax = swing.plot()
    assert ax.get_aspect() == 1.0 and len(ax.patches) > 0
    gif = swing.animate(tmp_path / "s.gif", dt=0.5, dpi=40)
    assert gif.exists() and gif.stat().st_size > 0
    assert swing.report(units="us").count("mph") > 5
    doc = crashsim.__doc__
    for name in ("load(path)", "run(scenario_or_path", "fit(", "monte_carlo("):
        assert name in doc
    assert {"load", "run", "fit", "monte_carlo"} <= set(crashsim.__all__)


# ------------------------------------------------------------------ first compile
def test_cache_directory_and_marker(tmp_path, monkeypatch, capsys):
    from crashsim import _jit, warmup

    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path / "cache"))
    assert _jit.cache_dir() == tmp_path / "cache"
    assert not _jit.ready()
    steps = []
    where = warmup.compile_kernels(lambda i, label: steps.append(label))  # kernels already in memory here
    assert steps == list(warmup.COMPILE_STEPS)
    assert where.parent == tmp_path / "cache" and _jit.ready()
    # the command line says so before a first run, and not after
    monkeypatch.setenv("CRASHSIM_CACHE_DIR", str(tmp_path / "other"))
    from crashsim.cli import _first_compile

    _first_compile(bar=False)
    err = capsys.readouterr().err
    assert "compiling the run-out kernels" in err and str(tmp_path / "other") in err
    assert all(f"{i + 1}/{len(steps)}" in err for i in range(len(steps)))
    _first_compile(bar=False)
    assert capsys.readouterr().err == ""

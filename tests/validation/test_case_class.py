"""A scene's case class (crashsim.validation.classify) and the known error the case report quotes for it."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

import crashsim
from crashsim.casereport import render_case_report
from crashsim.cli import main
from crashsim.validation import class_errors, scene_class
from crashsim.validation.classify import HEAVY_CLASS, load_error_table

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.parametrize("path, cls, configuration, outside", [
    ("validation/ricsac-03/scene.toml", "car-to-car", "front-to-rear", False),
    ("validation/ricsac-06/scene.toml", "car-to-car", "front-to-side", False),
    ("validation/ricsac-11/scene.toml", "car-to-car", "front-to-front", False),
    ("validation/mash-3-10/scene.toml", "vehicle-to-barrier", None, False),
    ("scenarios/scenes/barrier_glance_15deg.toml", "vehicle-to-barrier", None, False),
    # an articulated or heavy vehicle: not the class of the staged car-to-car collisions (it said car-to-car)
    ("scenarios/scenes/truck_brakes_into_car.toml", HEAVY_CLASS, "front-to-side", True),
    ("scenarios/scenes/tractor_tanker_struck.toml", HEAVY_CLASS, "front-to-side", True),
])
def test_the_class_of_a_scene(path, cls, configuration, outside):
    scene = crashsim.run(ROOT / path)
    c = scene_class(scene)
    assert (c["class"], c["configuration"], bool(c["outside"])) == (cls, configuration, outside), c


def test_the_class_errors_are_the_packaged_table_s():
    """The errors quoted for the front-to-side configuration are recomputed here from the table's rows."""
    table = load_error_table()
    assert table is not None and table["command"] == "python benchmarks/validation_suite.py"
    scene = crashsim.run(ROOT / "validation/ricsac-06/scene.toml")
    e = class_errors(scene, table)
    rows = [r for r in table["quantities"] if r["class"] == "car-to-car" and r["configuration"] == "front-to-side"
            and r["group"] == "delta-v"]
    conf = {r["group"]: r for r in e["configuration_rows"]}
    assert conf["delta-v"]["n"] == len(rows) == 6
    assert conf["delta-v"]["mean_abs_error"] == pytest.approx(sum(abs(r["error"]) for r in rows) / 6, rel=1e-12)
    assert conf["delta-v"]["max_abs_error"] == pytest.approx(max(abs(r["error"]) for r in rows), rel=1e-12)
    assert conf["delta-v"]["within"] == sum(r["within"] for r in rows)
    assert set(e["cases"]) == {r["case"] for r in table["quantities"] if r["class"] == "car-to-car"}


@pytest.mark.slow  # 5-21 s (tests/validation --durations, 2-core machine)
def test_the_case_report_quotes_the_class_error(tmp_path, capsys):
    out = tmp_path / "case.html"
    assert main(["report", str(ROOT / "scenarios/scenes/truck_brakes_into_car.toml"), "-o", str(out)]) == 0
    html = out.read_text()
    section = html[html.index('id="known-error"'):]
    section = section[:section.index("</section>")]
    assert f"{HEAVY_CLASS}</b>, front-to-side" in section and "The suite has no case of this class." in section
    assert "Outside the validation suite's cases" in section and "articulated" in section
    # the related classes the suite has: the car-to-car collisions, off-tracking, the truck's stop
    for cls in ("car-to-car, front-to-side", "car-to-car, all its cases", "articulated kinematics",
                "approach and braking"):
        assert f"Related class {cls}" in section, cls
    table = load_error_table()
    dv = [abs(r["error"]) for r in table["quantities"] if r["configuration"] == "front-to-side" and r["group"] == "delta-v"]
    assert f"{100 * max(dv):.1f} %" in section  # the largest delta-v error of the configuration, as the table has it
    assert re.search(r"ricsac-01, ricsac-06, ricsac-08", section)
    # a US scene: the car-to-car speed errors in mph, as the rest of its report (they were in m/s)
    sep = [abs(r["error"]) for r in table["quantities"] if r["configuration"] == "front-to-side"
           and r["group"] == "separation velocity"]
    assert f"{max(sep) / 0.44704:.3g} mph" in section and "m/s" not in section and "rad/s" not in section



def test_a_report_without_the_table_says_so():
    scene = crashsim.run(ROOT / "validation/ricsac-11/scene.toml")
    v = class_errors(scene, table={"quantities": [], "version": "x", "date": "y"})
    html = render_case_report(scene, input_files=[ROOT / "validation/ricsac-11/scene.toml"], figures=False,
                              validation=v)
    assert "The suite has no case of this class." in html
    v = dict(v, available=False)
    html = render_case_report(scene, input_files=[ROOT / "validation/ricsac-11/scene.toml"], figures=False,
                              validation=v)
    assert "carries no validation table" in html
    assert 'id="known-error"' not in render_case_report(scene, input_files=[ROOT / "validation/ricsac-11/scene.toml"],
                                                        figures=False)
    json.dumps(v)  # what the report quotes is plain data

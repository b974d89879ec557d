"""Wheel-lift and rollover keys: read from the file, and refused with one line (file, key, value, range; exit 2)."""

from __future__ import annotations

from pathlib import Path

import pytest

from crashsim.schema import load_toml
from crashsim.scenario import scenario_from_dict

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "verge_run_off.toml"
RUNOUT = "[runout]\nroad_friction = 0.75\n"


def _with(runout: str = "", trailer: str = "", car: str = "") -> str:
    text = SCENE.read_text()
    out = text.replace(RUNOUT, RUNOUT + runout, 1)
    out = out.replace('preset = "semitrailer-empty"\n', 'preset = "semitrailer-empty"\n' + trailer, 1)
    out = out.replace('preset = "car-midsize"\n', 'preset = "car-midsize"\n' + car, 1)
    assert (out != text) == bool(runout or trailer or car)
    return out


def test_the_keys_are_read(tmp_path):
    f = tmp_path / "case.toml"
    f.write_text(_with('level = "load_transfer"\nrollover = true\n', trailer="rollover_threshold = 0.42\n"))
    sc = scenario_from_dict(load_toml(f), file=str(f))
    assert sc.runout.options.rollover and sc.runout.options.load_transfer
    trailer = [b for v in sc.vehicles for b in v.bodies if b.name == "trailer"][0]
    assert trailer.rollover_threshold == pytest.approx(0.42)


def test_a_threshold_alone_turns_the_check_on(tmp_path):
    f = tmp_path / "case.toml"
    f.write_text(_with('level = "load_transfer"\n', trailer="rollover_threshold = 0.42\n"))
    assert scenario_from_dict(load_toml(f), file=str(f)).runout.options.rollover


def test_without_the_check_the_options_are_as_before(tmp_path):
    f = tmp_path / "case.toml"
    f.write_text(_with('level = "load_transfer"\n'))
    opts = scenario_from_dict(load_toml(f), file=str(f)).runout.options
    assert not opts.rollover and "rollover" not in opts.to_dict()


@pytest.mark.parametrize("value", ["0", "-0.2", "1.6"])
def test_a_threshold_out_of_range_exits_2(tmp_path, refused_line, value):
    line = refused_line(_with('level = "load_transfer"\n',
                                                    trailer=f"rollover_threshold = {value}\n"))
    assert "vehicles.truck.bodies[1].rollover_threshold" in line and value in line and "(0, 1.5]" in line


def test_the_check_at_a_level_without_load_transfer_exits_2(tmp_path, refused_line):
    line = refused_line(_with("rollover = true\n"))
    assert "runout.rollover" in line and 'level "load_transfer"' in line and "'articulated'" in line
    line = refused_line(_with(car="rollover_threshold = 1.1\n"))
    assert "vehicles.car.bodies[0].rollover_threshold" in line and "1.1" in line


def test_the_default_threshold_without_a_cg_height_exits_2(tmp_path, refused_line):
    # a body written out in full without cg_height: its default threshold 0.75 t / (2 h) has no h
    text = _with('level = "load_transfer"\nrollover = true\n')
    text = text.replace('name = "car"\npreset = "car-midsize"\n',
                        'name = "car"\nmass = "1500 kg"\nyaw_inertia = "2500 kg m^2"\nlength = "4.8 m"\n'
                        'width = "1.8 m"\naxles = [{ x = "1.2 m", track = "1.55 m" }, { x = "-1.5 m", track = "1.55 m" }]\n',
                        1)
    line = refused_line(text)
    assert "vehicles.car.bodies[0].cg_height" in line and "0.75 t / (2 h)" in line and "(0, 1.5]" in line
    # with its own threshold it needs no CG height for the threshold (the load transfer still does)
    line = refused_line(text.replace('width = "1.8 m"\n', 'width = "1.8 m"\nrollover_threshold = 0.9\n'))
    assert "vehicles.car.bodies[0].cg_height" in line and 'level "load_transfer" needs the CG height' in line


def test_a_rollover_statement_without_the_check_exits_2(tmp_path, refused_line):
    text = _with('level = "load_transfer"\n').replace(
        "\n[evidence.impact_point]", '\n[[evidence.rollover]]\nunit = "truck"\nrolled = false\n\n[evidence.impact_point]', 1)
    line = refused_line(text)
    assert "evidence.rollover[0].unit" in line and "runout.rollover = true" in line


def test_a_rollover_statement_about_an_unknown_unit_exits_2(tmp_path, refused_line):
    text = _with('level = "load_transfer"\nrollover = true\n').replace(
        "\n[evidence.impact_point]", '\n[[evidence.rollover]]\nunit = "trailr"\nrolled = true\n\n[evidence.impact_point]', 1)
    line = refused_line(text)
    assert "evidence.rollover[0].unit" in line and "'trailr'" in line and "did you mean 'trailer'" in line


def test_roll_coupled_is_read_and_refused_on_the_first_body(tmp_path, refused_line):
    f = tmp_path / "case.toml"
    f.write_text(_with('level = "load_transfer"\n', trailer="roll_coupled = true\n"))
    sc = scenario_from_dict(load_toml(f), file=str(f))
    assert [b.roll_coupled for v in sc.vehicles if v.name == "truck" for b in v.bodies] == [False, True]
    text = SCENE.read_text().replace('preset = "tractor-3axle"\n', 'preset = "tractor-3axle"\nroll_coupled = true\n', 1)
    line = refused_line(text)
    assert "vehicles.truck.bodies[0].roll_coupled" in line and "first body" in line


def test_a_contact_height_is_read_in_the_files_units(tmp_path):
    f = tmp_path / "case.toml"
    f.write_text(_with('level = "load_transfer"\n', car='contact_height = "20 in"\n'))
    sc = scenario_from_dict(load_toml(f), file=str(f))
    car = [b for v in sc.vehicles for b in v.bodies if b.name == "car"][0]
    assert car.contact_height == pytest.approx(0.508, rel=1e-12)
    # absent: None, the CG height in the load transfer
    f.write_text(_with('level = "load_transfer"\n'))
    sc = scenario_from_dict(load_toml(f), file=str(f))
    assert all(b.contact_height is None for v in sc.vehicles for b in v.bodies)


@pytest.mark.parametrize("value, shown", [('"0 m"', "0 m"), ('"-0.5 m"', "-0.5 m"), ('"20 ft"', "20 ft")])
def test_a_contact_height_out_of_range_exits_2(tmp_path, refused_line, value, shown):
    line = refused_line(_with('level = "load_transfer"\n', trailer=f"contact_height = {value}\n"))
    assert "vehicles.truck.bodies[1].contact_height" in line and shown in line and "5" in line

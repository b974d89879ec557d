"""Air-brake keys: read per unit with defaults by unit type; bad values exit 2 with one line naming
the file, the key, the value in the file's units and the allowed range."""

from __future__ import annotations

from pathlib import Path

import pytest

from crashsim.motion.brakes import DEFAULT_TIMING
from crashsim.schema import load_toml
from crashsim.scenario import scenario_from_dict

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml"

BRAKES = '''
[vehicles.truck.brakes]
apply = "{apply}"
tractor_abs = {tabs}
abs_efficiency = 0.85

[[vehicles.truck.brakes.units]]
body = "tractor"
capacity = ["40 kN", "110 kN", "110 kN"]
delay = "{delay}"

[[vehicles.truck.brakes.units]]
body = "trailer"
capacity = ["{cap}"]
out_of_adjustment = {ooa}
'''


def _scene(tmp_path, *, apply="0 s", tabs="true", delay="0.3 s", cap="100 kN", ooa="0.25", tyres="rolling") -> Path:
    text = SCENE.read_text()
    old = '[vehicles.truck.tyres]\nstate = "locked"\n'
    assert old in text
    new = (f'[vehicles.truck.tyres]\nstate = "{tyres}"\ncornering_coefficient = 6.0\nrolling_resistance = 0.008\n'
           + BRAKES.format(apply=apply, tabs=tabs, delay=delay, cap=cap, ooa=ooa))
    f = tmp_path / "case.toml"
    f.write_text(text.replace(old, new))
    return f


def test_brake_keys_are_read_with_defaults_by_unit_type(tmp_path):
    f = _scene(tmp_path)
    sc = scenario_from_dict(load_toml(f), file=str(f))
    brakes = sc.runout.wheels["truck"].brakes
    tractor, trailer = brakes.units["tractor"], brakes.units["trailer"]
    assert tractor.delay == pytest.approx(0.3) and tractor.rise == DEFAULT_TIMING["tractor"]["rise"]
    assert tractor.capacity == pytest.approx((40e3, 110e3, 110e3)) and tractor.abs
    assert trailer.unit_type == "last_trailer" and trailer.delay == DEFAULT_TIMING["last_trailer"]["delay"]
    assert trailer.out_of_adjustment == 0.25 and not trailer.abs and brakes.abs_efficiency == 0.85


@pytest.mark.parametrize("kw, key, words", [
    (dict(delay="-0.1 s"), "vehicles.truck.brakes.units[0].delay", ["-0.1 s", "[0, 10] s"]),
    (dict(cap="-5 kN"), "vehicles.truck.brakes.units[1].capacity", ["-5 kN", "[0, 500] kN"]),
    (dict(ooa="1.5"), "vehicles.truck.brakes.units[1].out_of_adjustment", ["1.5", "[0, 1]"]),
])
def test_bad_brake_values_exit_2_with_one_line(tmp_path, refused_line, kw, key, words):
    line = refused_line(_scene(tmp_path, **kw).read_text())
    assert key in line, line
    for w in words:
        assert w in line, line


def test_abs_on_a_wheel_locked_by_schedule_exits_2(tmp_path, refused_line):
    f = _scene(tmp_path)
    text = f.read_text().replace('[vehicles.car]', '[[vehicles.truck.wheel_changes]]\nat = "1 s"\nselect = '
                                 '"tractor/drive 1"\nstate = "locked"\n\n[vehicles.car]', 1)
    f.write_text(text)
    line = refused_line(f.read_text())
    assert "vehicles.truck.brakes.tractor_abs" in line and "locked" in line and "tractor_abs = false" in line, line


def test_braked_fraction_on_an_air_braked_unit_exits_2(tmp_path, refused_line):
    f = _scene(tmp_path, tyres="braked")
    f.write_text(f.read_text().replace('state = "braked"\n', 'state = "braked"\nbrake = 0.5\n', 1))
    line = refused_line(f.read_text())
    # the key to change is the tyres' state (not the brakes' internal units['tractor'])
    assert "vehicles.truck.tyres.state" in line and "rolling" in line and "units[" not in line, line


def test_one_capacity_may_be_written_without_a_list(tmp_path):
    """The schema says "one value: every axle": "80 kN" reads as ["80 kN"]."""
    f = _scene(tmp_path)
    f.write_text(f.read_text().replace('capacity = ["100 kN"]', 'capacity = "100 kN"'))
    assert 'capacity = "100 kN"' in f.read_text()
    sc = scenario_from_dict(load_toml(f), file=str(f))
    assert sc.runout.wheels["truck"].brakes.units["trailer"].capacity == pytest.approx((100e3,))

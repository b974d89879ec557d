"""C-dolly and self-steering keys: read from the file, and refused with one line naming file, key, value, range."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.schema import load_toml
from crashsim.scenario import scenario_from_dict
from crashsim.vehicles import Axle, Body, Hitch, Vehicle

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "doubles_c_dolly.toml"


def test_the_shipped_c_dolly_is_yaw_locked_and_self_steering():
    sc = scenario_from_dict(load_toml(SCENE), file=str(SCENE))
    truck = next(v for v in sc.vehicles if v.name == "truck")
    assert [h.yaw_locked for h in truck.hitches] == [False, True, False]
    assert truck.hitches[1].articulation_limit is None
    settings = sc.runout.wheels["truck"].resolve(truck)
    for spec, s in zip(settings.specs, settings.at(0.0)):
        expect = math.radians(20.0) if spec.body == "dolly" else None
        assert s.self_steer_limit == (pytest.approx(expect) if expect else None)


@pytest.mark.parametrize("value", ["-5 deg", "95 deg"])
def test_a_steer_limit_outside_0_90_deg_exits_2_with_one_line(refused_line, value):
    line = refused_line(SCENE.read_text().replace('self_steer_limit = "20 deg"', f'self_steer_limit = "{value}"'))
    assert "vehicles.truck.wheels[0].self_steer_limit" in line and value.split()[0] in line
    assert "90" in line and "deg" in line


def test_a_c_dolly_behind_the_tractor_exits_2_with_one_line(refused_line):
    """yaw_locked on the body towed by the tractor: no trailer ahead to lock to."""
    text = SCENE.read_text().replace('preset = "pup-28ft"\nmass = "11000 kg"\nyaw_inertia = "72900 kg m^2"      # m (L^2 + W^2) / 12 of the loaded box',
                                     'preset = "pup-28ft"\nyaw_locked = true\nmass = "11000 kg"\nyaw_inertia = "72900 kg m^2"', 1)
    line = refused_line(text)
    assert "vehicles.truck.bodies[1].yaw_locked" in line and "true" in line and "bodies[2] or later" in line


def test_a_c_dolly_with_an_articulation_exits_2_with_one_line(refused_line):
    text = SCENE.read_text().replace('preset = "dolly-c"', 'preset = "dolly-c"\narticulation = "5 deg"', 1)
    line = refused_line(text)
    assert "vehicles.truck.bodies[2].articulation" in line and "5 deg" in line and "allowed 0 deg" in line


def test_a_yaw_locked_first_hitch_is_refused_by_the_vehicle():
    car = Body("car", 1500.0, 2800.0, axles=(Axle(1.1, 1.5), Axle(-1.6, 1.5)))
    tr = Body("trailer", 700.0, 1200.0, axles=(Axle(-0.2, 1.6),))
    with pytest.raises(ScenarioError, match="not a trailer"):
        Vehicle("V", (car, tr), (Hitch((-2.5, 0.0), (2.8, 0.0), yaw_locked=True),))
    with pytest.raises(ScenarioError, match="articulation_limit"):
        Hitch((-2.5, 0.0), (2.8, 0.0), 1.5, yaw_locked=True)


def test_the_report_and_the_json_give_the_lock_moment_impulse(capsys):
    import json

    assert main(["run", str(SCENE), "--json"]) == 0
    hitches = json.loads(capsys.readouterr().out)["impact"]["hitches"]
    assert "lock_moment_impulse" in hitches["lead-dolly"]
    assert all("lock_moment_impulse" not in h for n, h in hitches.items() if n != "lead-dolly")
    assert main(["run", str(SCENE)]) == 0
    text = capsys.readouterr().out
    assert sum("yaw lock (C-dolly): moment" in line for line in text.splitlines()) == 1

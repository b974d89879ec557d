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


def test_run_changes_any_input_by_its_path():
    scene = crashsim.run(SCENE, runout__engine="compiled", runout__level="rigid")
    assert scene.scenario.runout.options.engine == "compiled" and scene.scenario.runout.level == "rigid"
    moved = crashsim.run(SCENE, runout__level="impact", vehicles__B__position=["-9.6063 m", "-3.17 m"])
    assert moved.scenario.states["car"].position[1] == pytest.approx(-3.17)
    with pytest.raises(ScenarioError, match=r"runout\.engine") as exc:
        crashsim.run(SCENE, runout__engine="fastest")
    assert "only numbers" not in str(exc.value)


def test_impact_between_two_bodies_of_one_vehicle(tmp_path, capsys):
    from crashsim.cli import main

    text = Path(SCENE).read_text().replace('body2 = "car"', 'body2 = "tractor"')
    f = tmp_path / "one_vehicle.toml"
    f.write_text(text)
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err
    assert str(f) in err and "impact.body2" in err and "both bodies of vehicle 'A'" in err
    assert "got 1" not in err and "exactly 2" not in err


def test_fit_unknown_path_error_names_the_file(tmp_path, capsys):
    from crashsim.cli import main

    fit = ROOT / "scenarios" / "fit" / "intersection_fit.toml"
    f = tmp_path / "bad_fit.toml"
    f.write_text(fit.read_text().replace('path = "vehicles.A.speed"', 'path = "vehicles.A.sped"', 1))
    assert main(["fit", str(f), "--workers", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"crashsim: input error: {f}: fit.unknowns[0].path: 'vehicles.A.sped'")
    assert "did you mean 'speed'" in err


def test_posterior_steps_range_is_the_real_minimum():
    from crashsim.inverse_schema import MIN_KEPT_STEPS, MIN_STEPS_DEFAULT_BURN, POSTERIOR
    from crashsim.reconstruct.posterior import PosteriorSpec

    steps = next(f for f in POSTERIOR.fields if f.name == "steps")
    assert steps.minimum == MIN_KEPT_STEPS and f"{MIN_STEPS_DEFAULT_BURN} with the default burn-in" in steps.description
    PosteriorSpec(steps=MIN_STEPS_DEFAULT_BURN).check(1)  # the documented minimum works
    with pytest.raises(ScenarioError, match=rf"allowed steps >= {MIN_STEPS_DEFAULT_BURN} "):
        PosteriorSpec(steps=MIN_STEPS_DEFAULT_BURN - 1).check(1)
    with pytest.raises(ScenarioError, match=rf"steps = 1 keeps 1 steps.*allowed steps >= {MIN_STEPS_DEFAULT_BURN} "):
        PosteriorSpec(steps=1).check(1)


SIDE = ROOT / "scenarios" / "scenes" / "car_trailer_side_impact.toml"


def _load_error(tmp_path, text):
    from crashsim.scenario import load_scenario

    f = tmp_path / "scene.toml"
    f.write_text(text)
    with pytest.raises(ScenarioError) as exc:
        load_scenario(f)
    return str(exc.value), str(f)


def test_wheel_change_errors_name_the_key_as_written(tmp_path):
    extra = '\n[[vehicles.towing.wheel_changes]]\nat = "1 s"\nselect = "car/middle"\nstate = "locked"\n'
    text = SIDE.read_text().replace("\n[vehicles.striking]", extra + "\n[vehicles.striking]")
    msg, f = _load_error(tmp_path, text)
    assert msg.startswith(f"{f}: vehicles.towing.wheel_changes[0].select: select = 'car/middle' at 1 s: no axle 'middle'")
    assert "schedule[" not in msg and "wheels['" not in msg
    extra = '\n[[vehicles.towing.wheel_changes]]\nat = "1 s"\nselect = "trailer"\nsteer = "100 deg"\n'
    text = SIDE.read_text().replace("\n[vehicles.striking]", extra + "\n[vehicles.striking]")
    msg, f = _load_error(tmp_path, text)
    assert msg == f"{f}: vehicles.towing.wheel_changes[0].steer: must lie in [-90, 90] deg, got 100 deg"


def test_a_bow_tie_zone_is_a_self_intersecting_outline(tmp_path):
    zone = ('\n[[runout.zones]]\nname = "gravel"\nfriction = 0.5\n'
            'polygon = [["0 m", "0 m"], ["10 m", "10 m"], ["10 m", "0 m"], ["0 m", "10 m"]]\n')
    text = SIDE.read_text().replace("road_friction = 0.75\n", "road_friction = 0.75\n" + zone)
    msg, f = _load_error(tmp_path, text)
    assert msg.startswith(f'{f}: runout.zones[0].polygon: polygon = [["0 m", "0 m"], ["10 m", "10 m"]')
    assert "zone 'gravel'" in msg and "intersects itself" in msg and "points 1-2 and points 3-4" in msg
    assert "zero area" not in msg and "zones.zone" not in msg
    flat = zone.replace('["10 m", "10 m"], ["10 m", "0 m"], ["0 m", "10 m"]', '["10 m", "0 m"], ["20 m", "0 m"]')
    msg, _ = _load_error(tmp_path, SIDE.read_text().replace("road_friction = 0.75\n", "road_friction = 0.75\n" + flat))
    assert "runout.zones[0].polygon" in msg and "on one line: it has no area" in msg

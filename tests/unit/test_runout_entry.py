"""The one run-out entry (crashsim.motion.run_runout): levels, engines and accuracy targets are its
options, and each option gives, bit for bit, the model it names."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.impact import solve_impact
from crashsim.motion import Road, RunoutOptions, Runout, make_hitch_consistent, run_runout, simulate_scene
from crashsim.motion.accuracy import _scene_to_accuracy, _simulate_to_accuracy
from crashsim.motion.levels import simulate_level
from crashsim.scenario import load_scenario
from crashsim.scene import run_scene
from crashsim.scene.run import separation_states
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

ROOT = Path(__file__).resolve().parents[2]


def _car(name):
    return Vehicle(name, (Body(name, 1500.0, 2500.0, 4.5, 1.8, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))


def _same(a, b):
    """Two run-outs of a vehicle with the same numbers (rest states, times, histories), bit for bit."""
    assert a.status == b.status and a.t_end == b.t_end and a.method == b.method
    for name, ba in a.bodies.items():
        bb = b.bodies[name]
        assert ba.rest_position == bb.rest_position and ba.rest_heading == bb.rest_heading
        assert ba.time_to_rest == bb.time_to_rest and ba.distance == bb.distance
        assert np.array_equal(ba.history.x, bb.history.x) and np.array_equal(ba.history.yaw_rate, bb.history.yaw_rate)


@pytest.fixture(scope="module")
def intersection():
    sc = load_scenario(ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml")
    states = separation_states(sc, solve_impact(sc.impact))
    initial = {}
    for v in sc.vehicles:
        initial.update(make_hitch_consistent(v, {b.name: states[b.name] for b in v.bodies}))
    return sc, initial


def test_the_contact_levels_run_the_scene_together(intersection):
    sc, initial = intersection
    spec = sc.runout
    run = run_runout(sc.vehicles, initial, spec.wheels, spec.road, spec.options, level="articulated",
                     contact=spec.contact, pair_contact=spec.pair_contact, obstacles=spec.obstacles)
    assert isinstance(run, Runout) and run.accuracy is None
    joint = simulate_scene(sc.vehicles, initial, spec.wheels, spec.road, spec.options, contact=spec.contact,
                           pair_contact=spec.pair_contact, obstacles=spec.obstacles)
    assert set(run.vehicles) == set(joint.vehicles) == {"A", "B"}
    for name in joint.vehicles:
        _same(run.vehicles[name], joint.vehicles[name])
    assert run.joint.energy == joint.energy
    # the scene run comes through the same entry: the same numbers
    scene = run_scene(sc)
    for name in joint.vehicles:
        _same(scene.runout[name], joint.vehicles[name])


@pytest.mark.parametrize("level", ["energy", "rigid"])
def test_the_other_levels_run_each_vehicle_alone(intersection, level):
    sc, initial = intersection
    spec = sc.runout
    run = run_runout(sc.vehicles, initial, spec.wheels, spec.road, spec.options, level=level)
    assert run.joint is None and run.accuracy is None
    for v in sc.vehicles:
        alone = simulate_level(level, v, {b.name: initial[b.name] for b in v.bodies}, spec.wheels[v.name], spec.road,
                               spec.options)
        _same(run.vehicles[v.name], alone)


def test_the_impact_level_has_no_runout():
    start = {"a": BodyState((0, 0), 0.0, (10.0, 0.0))}
    assert run_runout([_car("a")], start, None, Road(0.7), level="impact") == (None, None, None)


def test_engine_is_an_option():
    start = {"a": BodyState((0, 0), 0.0, (20.0, 0.0))}
    scipy = run_runout([_car("a")], start, None, Road(0.75), engine="scipy").vehicles["a"]
    compiled = run_runout([_car("a")], start, None, Road(0.75), engine="compiled").vehicles["a"]
    given = run_runout([_car("a")], start, None, Road(0.75), RunoutOptions(engine="compiled")).vehicles["a"]
    assert scipy.method.startswith("scipy/") and compiled.method.startswith("compiled/")
    _same(compiled, given)
    # a locked straight slide: v^2 / (2 mu g) on both engines
    for r in (scipy, compiled):
        assert r.bodies["a"].rest_position[0] == pytest.approx(20.0**2 / (2 * 0.75 * 9.80665), abs=1e-3)
    with pytest.raises(ScenarioError, match="runout.engine"):
        run_runout([_car("a")], start, None, Road(0.75), engine="fast")
    with pytest.raises(ScenarioError, match="runout.level"):
        run_runout([_car("a")], start, None, Road(0.75), level="full")


def test_an_accuracy_target_is_an_option():
    start = {"a": BodyState((0, 0), 0.0, (20.0, 0.0)), "b": BodyState((30, 5), 1.0, (0.0, 3.0))}
    cars = [_car("a"), _car("b")]
    opts = RunoutOptions()
    run = run_runout(cars, start, None, Road(0.75), opts, accuracy=0.01)
    joint, report = _scene_to_accuracy(cars, start, None, Road(0.75), 0.01, None, opts)
    assert set(run.accuracy) == {"a", "b"} and run.accuracy["a"] is run.accuracy["b"] and report.met
    _same_report(run.accuracy["a"], report)
    for name in ("a", "b"):
        _same(run.vehicles[name], joint.vehicles[name])
    alone = run_runout(cars, start, None, Road(0.75), opts, level="rigid", accuracy=0.01)
    res, rep = _simulate_to_accuracy(cars[0], {"a": start["a"]}, None, Road(0.75), 0.01, None, opts, level="rigid")
    _same(alone.vehicles["a"], res)
    _same_report(alone.accuracy["a"], rep)


def _same_report(a, b):
    assert (a.met, a.estimate_position, a.estimate_heading, a.message) == (b.met, b.estimate_position,
                                                                         b.estimate_heading, b.message)




def test_every_level_has_one_runner_of_each_kind_registered_where_it_is_defined():
    """run_runout dispatches through the registry (crashsim.motion.runners), which holds every level."""
    from crashsim.motion.runners import ACCURACY_RUNNERS, LEVELS, RUNNERS, register_runner

    assert sorted(RUNNERS) == sorted(LEVELS) and sorted(ACCURACY_RUNNERS) == sorted(LEVELS)
    where = {level: fn.__module__.rsplit(".", 1)[1] for level, fn in RUNNERS.items()}
    assert where == {"impact": "levels", "energy": "levels", "rigid": "levels", "articulated": "simulate",
                     "load_transfer": "simulate"}
    where = {level: fn.__module__.rsplit(".", 1)[1] for level, fn in ACCURACY_RUNNERS.items()}
    assert where == {"impact": "levels", "energy": "accuracy", "rigid": "accuracy", "articulated": "accuracy",
                     "load_transfer": "accuracy"}
    with pytest.raises(ValueError, match="already has a runner"):
        register_runner("energy")(lambda call: None)
    assert RUNNERS["energy"].__name__ == "_each_alone"


def test_the_runout_entry_points_are_run_runout_and_its_two_conveniences():
    import crashsim.motion as motion
    from crashsim.motion import accuracy, engine, levels, runout, simulate

    runs = {name for mod in (motion, accuracy, engine, levels, runout, simulate) for name in mod.__all__
            if callable(getattr(mod, name)) and ("runout" in name or "simulate" in name or name.startswith("run"))}
    assert runs == {"run_runout", "simulate_runout", "simulate_scene"}

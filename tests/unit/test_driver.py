"""The path-following driver of the approach (crashsim.motion.driver, docs/approach.md).

Closed forms of its geometry (a sampled arc, Ackermann, pure pursuit on a circle); SAE J695's
steady-state off-tracking of a driven tractor-semitrailer; the lateral path error on a 400 m curve
at 90 km/h; an approach that starts articulated and one whose articulation at the start is solved;
and the refusals of a path that cannot be followed or does not reach the impact.
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path as FilePath

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import Road, RunoutOptions, simulate_runout
from crashsim.motion.approach import simulate_approach
from crashsim.motion.approach_spec import ApproachSpec
from crashsim.motion.driver import DriverSpec, Path, ackermann, pursuit_steer, steer_geometry
from crashsim.motion.wheels import WheelSetting, WheelSettings
from crashsim.scenario import scenario_from_dict
from crashsim.validation.offtracking import _axle_path, closed_form, combination, fit_circle
from crashsim.scene.run import run_scene, simulate_approaches
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

SCENE = FilePath(__file__).parents[1] / "data" / "driven_curve.toml"


def _arc(radius, start, sweep, n, centre=(0.0, 0.0)):
    a = np.linspace(start, start + sweep, n)
    return np.column_stack([centre[0] + radius * np.cos(a), centre[1] + radius * np.sin(a)])


def _clothoid_curve(radius, spiral, arc, before=100.0, after=150.0, ds=1.0):
    """A straight, a spiral into a curve of ``radius``, the curve, a spiral out and a straight (as roads
    for 90 km/h are built), sampled every ``ds`` [m]."""
    kappa = np.concatenate([np.zeros(int(before / ds)), np.linspace(0, 1 / radius, int(spiral / ds)),
                            np.full(int(arc / ds), 1 / radius), np.linspace(1 / radius, 0, int(spiral / ds)),
                            np.zeros(int(after / ds))])
    head = np.concatenate([[0.0], np.cumsum(kappa * ds)])
    return np.column_stack([np.concatenate([[0.0], np.cumsum(np.cos(head[:-1]) * ds)]),
                            np.concatenate([[0.0], np.cumsum(np.sin(head[:-1]) * ds)])])


def test_path_geometry_of_a_sampled_arc():
    r = 50.0
    path = Path(_arc(r, 0.0, math.pi / 2, 181))
    assert path.length == pytest.approx(r * math.pi / 2, rel=1e-4)  # chords of 0.5 deg
    radius, _ = path.min_radius()
    assert radius == pytest.approx(r, rel=1e-4)
    # the polyline turns in steps of 0.5 deg: over a 10 m window (23 chords) the mean is within one step
    assert path.curvature(path.length / 2, 5.0) == pytest.approx(1 / r, rel=1 / 23)
    # a point 2 m outside the arc at 45 deg: its place on the path and its offset (right of travel: negative)
    s, off = path.locate((52.0 * math.cos(math.pi / 4), 52.0 * math.sin(math.pi / 4)))
    assert s == pytest.approx(r * math.pi / 4, rel=1e-4)
    assert off == pytest.approx(-2.0, abs=1e-3)
    assert path.heading(s) == pytest.approx(math.pi / 4 + math.pi / 2, abs=0.01)
    # beyond the end: along the last segment's line
    end = path.point(path.length + 10.0)
    assert end[0] == pytest.approx(-10.0, abs=0.1) and end[1] == pytest.approx(r, abs=0.1)  # heading -x there


def test_ackermann_turns_both_wheels_about_one_centre():
    car = Vehicle("car", (Body("car", 1500.0, 2800.0, 4.8, 1.8, (0.0, 0.0), (Axle(1.1, 1.55), Axle(-1.6, 1.55))),))
    geom = steer_geometry(car)
    radius = 12.0  # of the rear axle's centre
    left, right = ackermann(geom, math.atan(geom.wheelbase / radius))
    assert math.tan(left) == pytest.approx(geom.wheelbase / (radius - geom.track / 2), rel=1e-12)
    assert math.tan(right) == pytest.approx(geom.wheelbase / (radius + geom.track / 2), rel=1e-12)


@pytest.mark.parametrize("preview", [3.0, 10.0, 30.0])
def test_pure_pursuit_on_a_circle_steers_the_circle(preview):
    """The reference point on a circle, heading along it: the goal point lies on the circle, so the arc
    through both is the circle and the steer angle is the kinematic atan(L / R), whatever the preview."""
    r = 40.0
    body = Body("car", 1500.0, 2800.0, 4.8, 1.8, (0.0, 0.0), (Axle(1.1, 1.55), Axle(-1.6, 1.55)))
    geom = steer_geometry(Vehicle("car", (body,)))
    path = Path(_arc(r, -math.pi / 2, 2 * math.pi, 3601))
    driver = DriverSpec(path, preview_time=1.0, min_preview=preview)
    # rear axle at the circle's bottom, heading +x: the CG 1.6 m ahead
    delta, s, off = pursuit_steer(geom, driver, (1.6, -r), 0.0, 0.1, 0.0)
    assert off == pytest.approx(0.0, abs=1e-9)
    # the polyline's chords (0.1 deg) put the goal point a hair inside the circle
    assert delta == pytest.approx(math.atan(geom.wheelbase / r), rel=2e-3)


@pytest.mark.slow
def test_driven_tractor_semitrailer_offtracks_as_sae_j695():
    """A tractor-semitrailer driven at 5 mph onto a 60 ft steer-axle circle (the validation case's
    combination, validation/j695-offtracking) settles on SAE J695's steady-state off-tracking."""
    veh, lengths = combination("tractor-3axle", "semitrailer-53ft")
    r_steer = 60 * 0.3048
    r_ref = math.sqrt(r_steer ** 2 - lengths["L1"] ** 2)  # the reference point (rear axle) circle
    circle = _arc(r_ref, -math.pi / 2, 8 * math.pi, 2881, centre=(0.0, r_ref))
    way_out = np.column_stack([np.linspace(1.0, 40.0, 40), np.zeros(40)])
    path = Path(np.vstack([[[-30.0, 0.0]], circle, way_out]))
    s_impact = path.length - 15.0
    target = path.point(s_impact)
    wheels = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=6.0, rolling_resistance=0.0))
    spec = ApproachSpec(wheels, speed=5 * 0.44704, distance=s_impact - 5.0, tolerance=1.0,
                        driver=DriverSpec(path, update=0.2))
    impact = {b.name: BodyState(tuple(target), 0.0, (0.0, 0.0), 0.0) for b in veh.bodies}
    res = simulate_approach(veh, spec, impact, Road(0.9), RunoutOptions(t_max=400.0))
    ht, hr = res.runout.bodies["tractor"].history, res.runout.bodies["trailer"].history
    turned = np.unwrap(ht.heading)
    lap = (turned >= 4 * math.pi) & (turned <= 6 * math.pi)  # the third lap: settled
    fx, fy = _axle_path(ht, veh.bodies[0].axles[0].x)
    tx, ty = _axle_path(hr, veh.bodies[1].axles[0].x)
    r_front = fit_circle(fx[lap], fy[lap])[2]
    r_trailer = fit_circle(tx[lap], ty[lap])[2]
    assert r_front == pytest.approx(r_steer, abs=0.1)
    expected = closed_form(r_front, lengths)
    assert (r_front - r_trailer) == pytest.approx(expected, rel=0.05)
    assert res.max_lateral_error < 0.15
    assert res.miss < 0.1


@pytest.mark.slow
@pytest.mark.parametrize("unit", ["tractor-semitrailer", "car"])
def test_driver_holds_a_400_m_curve_at_90_kmh_within_0_2_m(unit):
    if unit == "car":
        veh = Vehicle("car", (Body("car", 1500.0, 2800.0, 4.8, 1.8, (0.15, 0.0), (Axle(1.1, 1.55), Axle(-1.6, 1.55)),
                                   0.55),))
        coeff = 8.6
    else:
        veh, _ = combination("tractor-3axle", "semitrailer-53ft")
        coeff = 6.0
    path = Path(_clothoid_curve(400.0, 100.0, 150.0))
    s_impact = path.length - 50.0
    target = path.point(s_impact)
    wheels = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=coeff, rolling_resistance=0.0))
    spec = ApproachSpec(wheels, speed=25.0, distance=s_impact - 10.0, tolerance=0.5, driver=DriverSpec(path))
    impact = {b.name: BodyState(tuple(target), path.heading(s_impact), (0.0, 0.0), 0.0) for b in veh.bodies}
    res = simulate_approach(veh, spec, impact, Road(0.9), RunoutOptions())
    assert res.max_lateral_error < 0.2
    st = res.steering
    # the curve itself needed steering: the driver did follow it (tan(delta) ~ L / R at least)
    geom = steer_geometry(veh)
    assert np.max(st["delta"]) > 0.8 * math.atan(geom.wheelbase / 400.0)
    assert not res.warnings


def _scene():
    return tomllib.loads(SCENE.read_text())


def test_driven_scene_runs_and_reports_the_driver():
    sc = simulate_approaches(scenario_from_dict(_scene(), file=str(SCENE)))
    a = sc.approaches["truck"]
    assert a.mode == "path"
    assert a.steering is not None and len(a.steering["t"]) > 10
    # the impact is where the approach ends; its velocity follows from the driven approach
    assert a.miss <= 1.0
    assert a.to_dict()["max_lateral_error"] == pytest.approx(a.max_lateral_error)
    # the driver steered left into the left curve
    assert np.mean(a.steering["delta"][a.steering["t"] < -1.0]) > 0.01


@pytest.mark.parametrize("edit, key, words", [
    (lambda d: d["map"]["lines"][0].__setitem__("points", [["-80 m", "0 m"], ["-30 m", "0 m"], ["-28 m", "4 m"],
                                                           ["-26 m", "0 m"], ["20 m", "0 m"]]),
     "vehicles.truck.approach.path.points", "tighter than the smallest radius"),
    (lambda d: d["map"]["lines"][0].__setitem__("points", [["-100 m", "30 m"], ["40 m", "30 m"]]),
     "vehicles.truck.approach.path.points", "must reach the impact position"),
    (lambda d: d["vehicles"]["truck"]["approach"].__setitem__("distance", "400 m"),
     "vehicles.truck.approach.path.points", "needs the path to reach back"),
    (lambda d: d["vehicles"]["truck"]["approach"]["path"].__setitem__("line", "eastbound lane centr"),
     "vehicles.truck.approach.path.line", "did you mean 'eastbound lane centre'"),
    (lambda d: (d["vehicles"]["truck"]["approach"].pop("distance"),
                d["vehicles"]["truck"]["approach"].__setitem__("time", "3 s")),
     "vehicles.truck.approach.distance", "with a path give distance"),
    (lambda d: d["vehicles"]["truck"]["approach"].__setitem__("articulation", ["5 deg", "1 deg"]),
     "vehicles.truck.approach.articulation", "give 1 value"),
    (lambda d: d["vehicles"]["truck"]["approach"].__setitem__("path", {}),
     "vehicles.truck.approach.path.points", "give the path's points or the name"),
    (lambda d: d["vehicles"]["truck"]["approach"].__setitem__("articulation", ["120 deg"]),
     "vehicles.truck.approach.articulation", "beyond its articulation stop"),
])
def test_a_path_that_cannot_be_followed_is_refused_in_one_line(edit, key, words):
    d = copy.deepcopy(_scene())
    edit(d)
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(d, file=str(SCENE))
    msg = str(err.value)
    assert key in msg and words in msg and str(SCENE) in msg
    assert "\n" not in msg


def test_a_wheel_the_driver_steers_may_not_be_steered_by_the_file_too():
    d = copy.deepcopy(_scene())
    d["vehicles"]["truck"]["approach"]["wheels"] = [{"select": "tractor/0", "steer": "2 deg"}]
    with pytest.raises(ScenarioError) as err:
        run_scene(scenario_from_dict(d, file=str(SCENE)))
    msg = str(err.value)
    assert "the driver steers wheel 'tractor/steer/left' along the path; its approach settings steer it too " \
           "(from 0 s): remove steer / self_steer_limit there" in msg
    assert "vehicles.truck.approach.wheels" in msg


def _car_caravan():
    car = Body("car", 1600.0, 2900.0, 4.8, 1.8, (0.15, 0.0), (Axle(1.2, 1.55), Axle(-1.5, 1.55)), 0.55)
    caravan = Body("caravan", 1300.0, 2600.0, 6.0, 2.2, (-0.5, 0.0), (Axle(-0.3, 1.9),), 1.0)
    return Vehicle("rig", (car, caravan), (Hitch((-2.9, 0.0), (3.6, 0.0), math.radians(90.0)),))


def test_an_approach_starts_articulated_and_yawing():
    veh = _car_caravan()
    tyre = WheelSetting("rolling", cornering_coefficient=7.0, rolling_resistance=0.01)
    spec = ApproachSpec(WheelSettings(default=tyre), speed=27.0, distance=40.0, articulation=(math.radians(8.0),),
                        yaw_rates=(0.0, math.radians(-10.0)))
    impact = {"car": BodyState((0.0, 0.0), 0.0, (0.0, 0.0), 0.0), "caravan": BodyState((-6.5, 0.0), 0.0, (0, 0), 0.0)}
    res = simulate_approach(veh, spec, impact, Road(0.8), RunoutOptions())
    assert res.start_articulation == pytest.approx((math.radians(8.0),))
    # the first sample of the braking phase: the caravan's heading is 8 deg behind the car's
    first = res.bodies["car"][0, 3] - res.bodies["caravan"][0, 3]
    assert first == pytest.approx(math.radians(8.0), abs=1e-9)
    # it sways on: the articulation at the end is not the straight impact configuration's
    assert res.warnings and "articulation" in res.warnings[0]


def test_a_swaying_caravan_ends_at_the_impact_articulation_when_solved():
    veh = _car_caravan()
    tyre = WheelSetting("rolling", cornering_coefficient=7.0, rolling_resistance=0.01)
    given = math.radians(14.0)
    # the impact configuration: the caravan 14 deg off the car's heading (articulation = car - caravan)
    hitch = np.array([-2.9, 0.0])
    front = np.array([3.6, 0.0])
    h2 = -given
    pos2 = hitch - np.array([math.cos(h2) * front[0] - math.sin(h2) * front[1],
                             math.sin(h2) * front[0] + math.cos(h2) * front[1]])
    impact = {"car": BodyState((0.0, 0.0), 0.0, (0.0, 0.0), 0.0), "caravan": BodyState(tuple(pos2), h2, (0, 0), 0.0)}
    spec = ApproachSpec(WheelSettings(default=tyre), speed=27.0, distance=15.0, articulation=(math.radians(5.0),),
                        solve_articulation=True)
    res = simulate_approach(veh, spec, impact, Road(0.8), RunoutOptions())
    assert res.articulation_at_impact[0] == pytest.approx(given, abs=1e-5)
    assert not res.warnings
    assert res.start_articulation[0] != pytest.approx(given, abs=1e-3)  # it was solved, not copied


def test_one_time_line_carries_the_approach_braking_through_the_impact():
    """A truck brakes (the tractor locks 0.3 s after the start of braking, the trailer 1.5 s after it,
    after the impact) and strikes a light object: with through_impact the run-out continues the
    approach's schedule on one time line, so the stopping distance is that of one uninterrupted
    braking run from the start of braking (the object changes it by its momentum only)."""
    d = tomllib.loads((FilePath(__file__).parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml").read_text())
    d.pop("evidence", None)
    d.pop("uncertainty", None)
    d.pop("fit", None)
    a = d["vehicles"]["truck"]["approach"]
    a.update(distance="15 m", reaction_time="0 s", through_impact=True,
             tyres={"state": "rolling", "cornering_coefficient": 6.0, "rolling_resistance": 0.008},
             wheel_changes=[{"at": "0.3 s", "select": "tractor", "state": "locked"},
                            {"at": "1.5 s", "select": "trailer", "state": "locked"}])
    car = d["vehicles"]["car"]
    car["bodies"][0].update(mass="2 kg", yaw_inertia="1 kg m^2")
    sc = simulate_approaches(scenario_from_dict(d))
    res = run_scene(sc)
    ap = sc.approaches["truck"]
    assert 0.3 < ap.time_to_impact < 1.5  # the trailer locks after the impact
    total = ap.distance + res.runout["truck"].bodies["tractor"].distance
    # the same braking as one run from the start of braking
    ai = sc.approach_inputs["truck"]
    veh = next(v for v in sc.vehicles if v.name == "truck")
    start = ap.runout.bodies["tractor"].initial
    init = chain_states(veh, start.position, start.heading, start.velocity)
    one = simulate_runout(veh, init, ai.spec.wheels, ai.road, ai.options)
    assert one.status == "rest"
    # a 2 kg object against a 40 t truck at 23 m/s: it and the truck's later touches of it shorten
    # the stop by millimetres (a 20 kg one, pushed along, by 7 cm)
    assert total == pytest.approx(one.bodies["tractor"].distance, abs=0.05)
    # without the one time line the run-out takes the file's own wheels (all locked from the impact)
    a["through_impact"] = False
    apart = scenario_from_dict(d)
    res_apart = run_scene(apart)
    total_apart = res_apart.scenario.approaches["truck"].distance + res_apart.runout["truck"].bodies["tractor"].distance
    assert abs(total_apart - one.bodies["tractor"].distance) > 1.0
    # and the trailer's wheels locked 1.5 s after the start of braking, on the run-out's time line
    wheels = sc.runout.wheels["truck"]
    assert any(abs(c.time - (1.5 - ap.time_to_impact)) < 1e-9 for c in wheels.schedule)

"""The compiled run-out engine (``RunoutOptions(engine="compiled")``, crashsim.motion.compiled_solution).

Three kinds of evidence:

* the closed forms of the analytic tier run again on the compiled engine: the very test
  functions of ``tests/analytic`` (straight locked slide, partial braking, scheduled brake
  change, pure spin, sideways slide, zone crossing at a line and a thin strip, all-locked
  combination, reduced-coordinate oracle, hitch work, load transfer, articulation stop,
  work-energy identity), with their ``simulate_runout`` switched to the compiled engine;
* the model: the compiled tyre law against the NumPy one on random inputs; the right-hand side
  (one source for both engines) keeps the hitch constraint rows and conserves momentum on
  random states (zones, closed stops, steer, load transfer);
* the API: options validation, statuses, errors, the dense output, the result types.

The kernels compile once per environment (numba's on-disk cache); the first session pays it.
"""

from __future__ import annotations

import dataclasses
import inspect
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import (
    FrictionZone,
    Road,
    RunoutOptions,
    RunoutResult,
    ScheduledChange,
    WheelSetting,
    WheelSettings,
    make_hitch_consistent,
    simulate_runout,
)
from crashsim import warmup
from crashsim.motion import tyres
from crashsim.motion.hitches import RunoutModel
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "analytic"))

import test_articulated  # noqa: E402
import test_load_transfer_and_stops  # noqa: E402
import test_spin_and_sideways  # noqa: E402
import test_straight_slide  # noqa: E402
import test_work_energy  # noqa: E402
import test_zone_crossing  # noqa: E402
from runout_cases import CAR_TYRE, TRUCK_TYRE, car, tractor_semitrailer  # noqa: E402

COMPILED = RunoutOptions(engine="compiled")


# ----------------------------------------------------------------------------- analytic tier, compiled
_ANALYTIC = (
    test_straight_slide,
    test_spin_and_sideways,
    test_zone_crossing,
    test_articulated,
    test_load_transfer_and_stops,
    test_work_energy,
)
_CALLS: list[str] = []


def _compiled_simulate_runout(vehicle, initial, wheels, road, options=RunoutOptions()):
    res = simulate_runout(vehicle, initial, wheels, road, dataclasses.replace(options, engine="compiled"))
    assert res.method.startswith("compiled/")
    _CALLS.append(res.method)
    return res


for _mod in _ANALYTIC:
    for _name, _fn in list(vars(_mod).items()):
        if _name.startswith("test_") and inspect.isfunction(_fn):
            globals()[f"test_compiled_{_mod.__name__[5:]}__{_name[5:]}"] = _fn


@pytest.fixture(autouse=True)
def _analytic_tests_use_the_compiled_engine(monkeypatch):
    """Inside this module the analytic tier's ``simulate_runout`` is the compiled engine."""
    for mod in _ANALYTIC:
        monkeypatch.setattr(mod, "simulate_runout", _compiled_simulate_runout)
    yield


def test_the_analytic_functions_really_ran_compiled():
    _CALLS.clear()
    test_straight_slide.test_equal_partial_braking(0.3)
    assert _CALLS == ["compiled/dopri5"]


# ----------------------------------------------------------------------------- same model
@pytest.mark.parametrize("fiala", [True, False])
def test_compiled_tyre_law_is_the_numpy_tyre_law(fiala):
    from crashsim.motion import kernels as k

    rng = np.random.default_rng(7)
    n = 20000
    u = rng.normal(0, 5, n) * rng.choice([1.0, 1e-3], n)
    w = rng.normal(0, 5, n) * rng.choice([1.0, 1e-3], n)
    mu_load = rng.uniform(0, 3e4, n) * (rng.random(n) > 0.02)  # some lifted wheels
    demand = rng.uniform(0, 1, n) * mu_load
    c_alpha = rng.uniform(1e3, 4e5, n)
    locked = rng.random(n) < 0.3
    fx, fy, sliding = np.empty(n), np.empty(n), np.empty(n, dtype=bool)
    k.tyre_batch(u, w, mu_load, demand, c_alpha, locked, 0.01, fiala, fx, fy, sliding)
    ref_x, ref_y, ref_s = tyres.tyre_forces_core(u, w, mu_load, demand, c_alpha, locked, 0.01, "fiala" if fiala else "linear")
    if fiala:  # the same source compiled: the same bits
        assert np.array_equal(fx, ref_x) and np.array_equal(fy, ref_y)
    else:  # arctan of libm vs NumPy's: last-bit differences
        assert np.allclose(fx, ref_x, rtol=1e-13, atol=1e-9) and np.allclose(fy, ref_y, rtol=1e-13, atol=1e-9)
    assert np.array_equal(sliding, ref_s)


def _truck_case(limit=math.radians(50)):
    veh = tractor_semitrailer(articulation_limit=limit)
    wheels = WheelSettings(
        default=WheelSetting("rolling", **TRUCK_TYRE),
        wheels={
            "tractor/0": WheelSetting("rolling", steer=0.2, cornering_stiffness=2.5e5, rolling_resistance=0.01),
            "tractor/1": WheelSetting("braked", brake=0.4, **TRUCK_TYRE),
            "trailer/2/right": WheelSetting("jammed", mu_factor=0.6),
        },
        schedule=[ScheduledChange(0.5, "trailer/0", {"state": "locked"})],
    )
    zone = FrictionZone(((-5.0, -5.0), (5.0, -5.0), (5.0, 5.0), (-5.0, 5.0)), 0.3, "wet")
    return veh, wheels, Road(0.8, (zone,))


@pytest.mark.parametrize("load_transfer", [False, True])
def test_the_right_hand_side_keeps_the_hitch_and_conserves_momentum(load_transfer):
    """The one right-hand side both engines integrate, on random states (zones, both wheel
    phases, a closed stop): the accelerations satisfy the Baumgarte-stabilised constraint rows
    (computed independently by ``dynamics.hitch_rows``), the hitch forces are internal (the
    momentum changes by the tyre forces alone), and a closed stop holds the articulation."""
    from crashsim.motion.hitches import hitch_rows

    veh, wheels, road = _truck_case()
    for body in veh.bodies:  # load transfer needs CG heights
        object.__setattr__(body, "cg_height", 1.1)
    options = RunoutOptions(engine="compiled", load_transfer=load_transfer)
    model = RunoutModel(veh, wheels.resolve(veh), road, options)
    L = model.layout
    rng = np.random.default_rng(3)
    nw = len(model.specs)
    a2 = 2 * options.baumgarte_zeta * options.baumgarte_omega
    b2 = options.baumgarte_omega**2
    for trial in range(40):
        y = rng.normal(0, 3, L.size)
        y[L.psi] = rng.uniform(-3, 3, 2)
        memb = rng.random((nw, 1)) < 0.5
        locks = [(0, float(y[L.psi][0] - y[L.psi][1] + rng.normal(0, 0.1)))] if trial % 3 == 0 else []
        seg = model.segment(0.0 if trial % 2 == 0 else 0.6, memb, locks)
        ev = model.evaluate(y[:, None], seg)
        col = y[:, None]
        psi = col[L.psi]
        G, g, g_dot, gamma = hitch_rows(model.front_points, model.rear_points, np.cos(psi), np.sin(psi), col[L.x],
                                        col[L.y], col[L.vx], col[L.vy], col[L.w], locks)
        acc = ev.y_dot[L.velocity, 0]
        residual = G[0] @ acc + gamma[:, 0] + a2 * g_dot[:, 0] + b2 * g[:, 0]
        assert np.allclose(residual, 0.0, atol=1e-8 * (1 + np.max(np.abs(acc)))), trial
        f = ev.body_force[:, 0]
        m = model.mass
        assert np.allclose(np.sum(m * acc[:2]), np.sum(f[:2]), rtol=1e-10, atol=1e-6)  # sum m a_x = sum F_x
        assert np.allclose(np.sum(m * acc[2:4]), np.sum(f[2:4]), rtol=1e-10, atol=1e-6)
        assert np.all((ev.load >= 0) & np.isfinite(ev.load))
        assert ev.sliding.shape == (nw, 1)


# ----------------------------------------------------------------------------- options and errors
def test_engine_and_scheme_are_validated():
    with pytest.raises(ScenarioError, match="options.engine"):
        RunoutOptions(engine="numba")
    with pytest.raises(ScenarioError, match="options.scheme"):
        RunoutOptions(scheme="rk4")
    assert RunoutOptions().engine == "scipy"
    assert RunoutOptions(engine="compiled").to_dict()["engine"] == "compiled"


def test_input_errors_are_the_scipy_engines():
    veh = tractor_semitrailer()
    init = chain_states(veh, (0.0, 0.0), 0.0, (10.0, 0.0))
    s = init["trailer"]
    init["trailer"] = BodyState(s.position, s.heading, (s.velocity[0], s.velocity[1] + 1.0), s.yaw_rate)
    messages = []
    for engine in ("scipy", "compiled"):
        with pytest.raises(ScenarioError) as err:
            simulate_runout(veh, init, None, Road(0.7), RunoutOptions(engine=engine))
        messages.append(str(err.value))
    assert messages[0] == messages[1] and "make_hitch_consistent" in messages[0]
    barrier = Vehicle("wall", (Body("wall", math.inf, math.inf),))
    with pytest.raises(ScenarioError, match="barrier"):
        simulate_runout(barrier, {}, None, Road(0.7), COMPILED)
    with pytest.raises(ScenarioError, match="WheelSettings"):
        simulate_runout(car(), {"car": BodyState((0, 0), 0, (1, 0))}, "locked", Road(0.7), COMPILED)
    with pytest.raises(ScenarioError, match="no initial state"):
        simulate_runout(car(), {}, None, Road(0.7), COMPILED)


def test_statuses_time_limit_max_segments_and_rest_at_start():
    start = {"car": BodyState((0.0, 0.0), 0.0, (20.0, 0.0))}
    res = simulate_runout(car(), start, None, Road(0.7), dataclasses.replace(COMPILED, t_max=0.5))
    ref = simulate_runout(car(), start, None, Road(0.7), RunoutOptions(t_max=0.5))
    assert res.status == ref.status == "time_limit" and not res.success
    assert res.t_end == 0.5 and res.bodies["car"].time_to_rest is None
    assert res.message.split("(")[0] == ref.message.split("(")[0]
    wheels = WheelSettings(default=WheelSetting("locked"), schedule=[ScheduledChange(0.2, "car", {"state": "jammed"})])
    res = simulate_runout(car(), start, wheels, Road(0.7), dataclasses.replace(COMPILED, max_segments=1))
    assert res.status == "event_limit" and "max_segments" in res.message
    still = simulate_runout(car(), {"car": BodyState((1.0, 2.0), 0.5, (0.0, 0.0))}, None, Road(0.7), COMPILED)
    assert still.status == "rest" and still.n_segments == 0 and still.t_end == 0.0
    assert still.bodies["car"].rest_position == (1.0, 2.0)
    assert len(still.bodies["car"].history.t) == 1


def test_result_is_a_complete_runout_result():
    veh, wheels, road = _truck_case(limit=None)
    init = make_hitch_consistent(veh, chain_states(veh, (-8.0, 0.0), 0.0, (14.0, 1.0), yaw_rates=[0.3, 0.0]))
    res = simulate_runout(veh, init, wheels, road, COMPILED)
    ref = simulate_runout(veh, init, wheels, road, RunoutOptions())
    assert isinstance(res, RunoutResult) and res.success
    assert res.method == "compiled/dopri5" and res.nfev > 0 and res.njev == 0 and res.nlu == 0
    assert res.options == COMPILED.to_dict()
    assert set(res.wheels) == set(ref.wheels) and set(res.bodies) == set(ref.bodies)
    json.dumps(res.to_dict())
    table = res.table()
    assert set(table) == set(ref.table())
    # the dense output reproduces the samples and clips to the run
    for name, body in res.bodies.items():
        h = body.history
        assert np.allclose(body.sol(h.t)[0], h.x, atol=1e-12) and np.allclose(body.sol(h.t)[2], h.heading, atol=1e-12)
        assert np.allclose(body.sol(-1.0), body.sol(0.0)) and np.allclose(body.sol(res.t_end + 5.0)[:2], body.rest_position)
        assert body.sol(np.zeros((2, 3))).shape == (6, 2, 3)
    assert res.sol(0.0)[0] == init["tractor"].position[0]
    # zone crossings, the schedule, tracks split into sliding and rolling stretches
    kinds = [e.kind for e in res.events]
    assert "schedule" in kinds and "zone_exit" in kinds and kinds[-1] == "rest"
    assert [e.kind for e in res.events] == [e.kind for e in ref.events]
    track = res.wheels["trailer/0/left"]
    assert track.segments[-1].kind == "sliding" and track.sliding[-1]
    assert sum(len(s.t) for s in track.segments) == len(track.t) + len(track.segments) - 1
    assert abs(res.energy_residual) < 1e-4


@pytest.mark.parametrize("scheme, rtol", [("dopri5", 1e-6), ("bs3", 1e-6), ("dopri5", 1e-9)])
def test_schemes_and_tolerances_converge_to_the_scipy_reference(scheme, rtol):
    veh, wheels, road = _truck_case()
    init = make_hitch_consistent(veh, chain_states(veh, (-8.0, 0.0), 0.0, (14.0, 1.0), yaw_rates=[0.3, 0.0]))
    ref = simulate_runout(veh, init, wheels, road, RunoutOptions(method="DOP853", rtol=1e-10, atol=1e-12))
    res = simulate_runout(veh, init, wheels, road, RunoutOptions(engine="compiled", scheme=scheme, rtol=rtol, atol=rtol / 100))
    assert res.method == f"compiled/{scheme}"
    err = max(math.dist(b.rest_position, ref.bodies[n].rest_position) for n, b in res.bodies.items())
    assert err < 1e-3 * (rtol / 1e-6) ** 0.5


def test_linear_lateral_model_and_first_step():
    opts = RunoutOptions(lateral_model="linear", first_step=1e-3, max_step=0.05)
    wheels = WheelSettings(default=WheelSetting("rolling", **CAR_TYRE), wheels={"car/0": WheelSetting("locked")})
    start = {"car": BodyState((0.0, 0.0), 0.0, (15.0, 2.0), 1.0)}
    ref = simulate_runout(car(), start, wheels, Road(0.8), opts)
    res = simulate_runout(car(), start, wheels, Road(0.8), dataclasses.replace(opts, engine="compiled"))
    assert math.dist(res.bodies["car"].rest_position, ref.bodies["car"].rest_position) < 1e-3
    assert res.options["lateral_model"] == "linear"


def test_prepared_inputs_are_not_confused_between_calls():
    """Cached set-up is keyed by the input objects: other wheels or another road give other results."""
    start = {"car": BodyState((0.0, 0.0), 0.0, (15.0, 0.0))}
    locked = simulate_runout(car(), start, None, Road(0.8), COMPILED)
    half = WheelSettings(default=WheelSetting("braked", brake=0.5, **CAR_TYRE))
    braked = simulate_runout(car(), start, half, Road(0.8), COMPILED)
    wet = simulate_runout(car(), start, None, Road(0.4), COMPILED)
    x = [r.bodies["car"].rest_position[0] for r in (locked, braked, wet)]
    assert x[0] < x[1] and x[0] < x[2]
    assert x[2] == pytest.approx(2 * x[0], rel=2e-3)


def test_compile_report():
    warmup.compile_runout()
    report = warmup.compile_report()
    assert report["seconds"] is not None and report["seconds"] >= 0
    assert warmup.compile_runout() == 0.0  # once per process


def test_many_bodies_and_a_dolly():
    """A three-body chain (car, dolly, trailer): the general multiplier solve (4 rows) and two stops."""
    bodies = (
        Body("truck", 9000.0, 30000.0, length=8.0, axles=(Axle(2.0, 2.0), Axle(-2.5, 1.9, True))),
        Body("dolly", 800.0, 600.0, length=2.5, axles=(Axle(0.0, 1.9),)),
        Body("trailer", 7000.0, 40000.0, length=8.0, axles=(Axle(-2.0, 1.9, True), Axle(-3.2, 1.9, True))),
    )
    hitches = (Hitch((-4.5, 0.0), (2.0, 0.0), math.radians(60)), Hitch((0.3, 0.0), (3.5, 0.0), math.radians(45)))
    veh = Vehicle("road train", bodies, hitches)
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.0, (15.0, 0.0), yaw_rates=[0.4, 0.0, -0.2]))
    wheels = WheelSettings(default=WheelSetting("rolling", **TRUCK_TYRE), wheels={"truck/1": WheelSetting("locked")})
    ref = simulate_runout(veh, init, wheels, Road(0.7), RunoutOptions())
    res = simulate_runout(veh, init, wheels, Road(0.7), COMPILED)
    assert res.status == ref.status == "rest"
    for name, body in ref.bodies.items():
        assert math.dist(res.bodies[name].rest_position, body.rest_position) < 1e-3
    assert [e.kind for e in res.events] == [e.kind for e in ref.events]
    assert res.max_hitch_gap < 1e-5


def test_unpack_fast_path_builds_the_same_body_states():
    from crashsim.motion.layout import StateLayout

    layout = StateLayout(("a", "b"), accel_filter=True)
    y = np.linspace(-3.0, 5.0, layout.size)
    got = layout.unpack(y)
    want = {
        n: BodyState(
            (y[layout.x][i], y[layout.y][i]), y[layout.psi][i], (y[layout.vx][i], y[layout.vy][i]), y[layout.w][i]
        )
        for i, n in enumerate(layout.bodies)
    }
    assert got == want
    assert all(type(v) is float for s in got.values() for v in (*s.position, s.heading, *s.velocity, s.yaw_rate))
    y[layout.vx][1] = np.inf
    with pytest.raises(ScenarioError, match="velocity"):
        layout.unpack(y)

"""Unit tests of the run-out API: hitch consistency, statuses, result objects and scenes."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crashsim.errors import ScenarioError
from crashsim.motion import (
    Road,
    RunoutOptions,
    WheelSetting,
    WheelSettings,
    make_hitch_consistent,
    simulate_runout,
    simulate_scene,
)
from crashsim.motion import hitches as dynamics
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

CAR = Vehicle("car", (Body("car", 1500.0, 2800.0, length=4.6, axles=(Axle(1.1, 1.5), Axle(-1.5, 1.5))),))
TS = Vehicle(
    "ts",
    (
        Body("tractor", 8000.0, 32000.0, axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True))),
        Body("trailer", 25000.0, 330000.0, axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True))),
    ),
    (Hitch((-2.0, 0.0), (6.0, 0.0)),),
)
MASS = np.array([8000.0, 25000.0])
INERTIA = np.array([32000.0, 330000.0])

finite = st.floats(-20.0, 20.0)


@settings(max_examples=100, deadline=None)
@given(finite, finite, st.floats(-2, 2), st.floats(-2, 2), finite, finite, st.floats(-1.2, 1.2), st.floats(-3, 3))
def test_make_hitch_consistent_is_the_momentum_conserving_projection(vx, vy, w1, w2, dvx, dvy, art, heading):
    states = chain_states(TS, (3.0, -2.0), heading, (vx, vy), yaw_rates=[w1, w2], articulation=[art])
    # disturb the trailer velocity: the pins now move apart
    s2 = states["trailer"]
    states["trailer"] = BodyState(s2.position, s2.heading, (s2.velocity[0] + dvx, s2.velocity[1] + dvy), s2.yaw_rate)
    out = make_hitch_consistent(TS, states)

    def momenta(st_):
        p = sum(m * np.array(st_[n].velocity) for m, n in zip(MASS, ("tractor", "trailer")))
        h = sum(
            i * st_[n].yaw_rate + m * (st_[n].position[0] * st_[n].velocity[1] - st_[n].position[1] * st_[n].velocity[0])
            for m, i, n in zip(MASS, INERTIA, ("tractor", "trailer"))
        )
        return p, h

    (p0, h0), (p1, h1) = momenta(states), momenta(out)
    assert np.allclose(p0, p1, atol=1e-6 * (1 + np.abs(p0).max()))
    assert h1 == pytest.approx(h0, abs=1e-6 * (1 + abs(h0)))
    # pins now move together
    a = np.array([math.cos(heading), math.sin(heading)]) * -2.0
    psi2 = heading - art
    b = np.array([math.cos(psi2), math.sin(psi2)]) * 6.0
    perp = lambda v: np.array([-v[1], v[0]])  # noqa: E731
    pin1 = np.array(out["tractor"].velocity) + out["tractor"].yaw_rate * perp(a)
    pin2 = np.array(out["trailer"].velocity) + out["trailer"].yaw_rate * perp(b)
    assert np.allclose(pin1, pin2, atol=1e-9 * (1 + np.abs(pin1).max()))
    # idempotent, and positions untouched
    again = make_hitch_consistent(TS, out)
    assert np.allclose(again["trailer"].velocity, out["trailer"].velocity, atol=1e-9)
    assert out["trailer"].position == states["trailer"].position


def test_inconsistent_initial_states_are_rejected_with_advice():
    states = chain_states(TS, (0.0, 0.0), 0.0, (13.04, -0.12), yaw_rates=[0.16, -0.8])
    s2 = states["trailer"]
    states["trailer"] = BodyState(s2.position, s2.heading, (s2.velocity[0], 2.56), s2.yaw_rate)
    with pytest.raises(ScenarioError, match="make_hitch_consistent"):
        simulate_runout(TS, states, None, Road(0.7))
    states["trailer"] = BodyState((s2.position[0] - 0.5, 0.0), s2.heading, s2.velocity, s2.yaw_rate)
    with pytest.raises(ScenarioError, match="0.5 m apart"):
        make_hitch_consistent(TS, states)


def test_time_limit_is_not_rest():
    res = simulate_runout(CAR, {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(0.7), RunoutOptions(t_max=1.0))
    assert res.status == res.termination == "time_limit" and not res.success
    assert res.t_end == pytest.approx(1.0)
    assert res.bodies["car"].time_to_rest is None
    assert res.kinetic_energy_final > 0.5 * 1500 * 0.03**2


def test_non_finite_derivative_stops_with_a_solver_failure(monkeypatch):
    """An integrator can loop forever on NaN; the SciPy engine checks every right-hand side and
    the run reports why it stopped (the compiled engine checks every RK stage)."""
    from crashsim.motion import kernels as _kernels

    real = _kernels.rhs

    def broken(y, M, phase, D):
        out = real(y, M, phase, D)
        if y[0] > 5.0:
            out[:] = np.nan
        return out

    monkeypatch.setattr(_kernels, "rhs", broken)  # the SciPy engine's right-hand side
    res = simulate_runout(CAR, {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(0.7), RunoutOptions(method="RK45"))
    assert res.status == "solver_failure" and not res.success
    assert "non-finite state derivative" in res.message
    assert res.events[-1].kind == "solver_failure"


def test_integrator_failure_message_is_kept(monkeypatch):
    from scipy.integrate import LSODA

    real = LSODA._step_impl
    calls = {"n": 0}

    def failing(self):
        calls["n"] += 1
        if calls["n"] > 5:
            return False, "Required step size is less than spacing between numbers."
        return real(self)

    monkeypatch.setattr(LSODA, "_step_impl", failing)
    res = simulate_runout(CAR, {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(0.7))
    assert res.status == "solver_failure" and not res.success
    assert "scipy/LSODA failed" in res.message and "Required step size" in res.message


def test_initial_rest_and_barriers():
    res = simulate_runout(CAR, {"car": BodyState((1, 2), 0.5, (0.0, 0.01))}, None, Road(0.7))
    assert res.status == "rest" and res.t_end == 0.0 and res.bodies["car"].rest_position == (1.0, 2.0)
    wall = Vehicle("wall", (Body("wall", math.inf, math.inf),))
    with pytest.raises(ScenarioError, match="barrier"):
        simulate_runout(wall, {"wall": BodyState((0, 0), 0.0, (0, 0))}, None, Road(0.7))
    out = simulate_scene(
        [wall, CAR], {"wall": BodyState((0, 0), 0.0, (0, 0)), "car": BodyState((0, 0), 0.0, (5.0, 0.0))}, None, Road(0.7)
    )
    assert list(out.vehicles) == ["car"] and out.vehicles["car"].success and out.success
    with pytest.raises(ScenarioError, match="no vehicle named 'cart'"):
        simulate_scene([CAR], {"car": BodyState((0, 0), 0.0, (5.0, 0.0))}, {"cart": None}, Road(0.7))


def test_result_exports_and_tracks():
    wheels = WheelSettings(
        default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.012),
        wheels={"car/1": WheelSetting("locked")},
    )
    res = simulate_runout(CAR, {"car": BodyState((0, 0), 0.0, (12.0, 4.0), 1.5)}, wheels, Road(0.75))
    assert res.success
    d = res.to_dict()
    json.dumps(d)  # JSON-ready
    assert d["bodies"]["car"]["rest_position_m"] == list(res.bodies["car"].rest_position)
    assert set(d["wheels"]) == {"car/0/left", "car/0/right", "car/1/left", "car/1/right"}
    small = res.to_dict(history=False)
    assert "history" not in small["bodies"]["car"] and len(json.dumps(small)) < len(json.dumps(d))
    table = res.table()
    n = len(table["t [s]"])
    assert all(len(col) == n for col in table.values())
    assert {"car.x [m]", "car.heading [rad]", "car.yaw_rate [rad/s]"} <= set(table)
    # history and dense solution agree; the history ends at the rest state
    body = res.bodies["car"]
    assert np.allclose(body.sol(body.history.t)[0], body.history.x)
    assert body.history.x[-1] == body.rest_position[0] and body.history.t[-1] == res.t_end
    # locked rear wheels slide throughout; their tracks are one sliding segment
    rear = res.wheels["car/1/left"]
    assert [s.kind for s in rear.segments] == ["sliding"]
    assert rear.segments[0].length == pytest.approx(rear.path_length, rel=1e-2)
    # track segments cover the track and share boundary samples
    front = res.wheels["car/0/left"]
    assert sum(len(s.t) for s in front.segments) == len(front.t) + len(front.segments) - 1
    assert res.energy_residual == pytest.approx(0.0, abs=1e-4)

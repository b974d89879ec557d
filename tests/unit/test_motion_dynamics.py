"""Unit tests of the equations of motion (crashsim.motion.hitches)."""

from __future__ import annotations

import numpy as np
import pytest

from crashsim.motion import Road, RunoutOptions, WheelSetting, WheelSettings, make_hitch_consistent, simulate_runout
from crashsim.motion.hitches import RunoutModel
from crashsim.motion.simulate import zone_membership
from crashsim.vehicles import Axle, Body, Hitch, Vehicle, chain_states

TYRE = dict(cornering_coefficient=6.0, rolling_resistance=0.007)


def _ts():
    tractor = Body("tractor", 8000.0, 32000.0, axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True)))
    trailer = Body("trailer", 25000.0, 330000.0, axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True)))
    return Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.3), (6.0, -0.2)),))


def _model(veh, wheels):
    return RunoutModel(veh, wheels.resolve(veh), Road(0.7), RunoutOptions())


def test_single_hitch_fast_path_equals_the_general_constraint_solve():
    """The scalar two-body path of the right-hand side against the batched general path."""
    veh = _ts()
    wheels = WheelSettings(default=WheelSetting("braked", brake=0.4, steer=0.05, **TYRE), wheels={"trailer": WheelSetting("locked")})
    model = _model(veh, wheels)
    rng = np.random.default_rng(7)
    states = []
    for _ in range(20):
        s = chain_states(veh, rng.normal(0, 5, 2), rng.uniform(-3, 3), rng.normal(0, 8, 2),
                         yaw_rates=rng.normal(0, 1, 2), articulation=[rng.uniform(-1, 1)])
        y = model.layout.pack(s)
        y[model.layout.x][1] += rng.normal(0, 1e-3)  # small constraint drift exercises the Baumgarte terms
        y[model.layout.vy][1] += rng.normal(0, 1e-2)
        states.append(y)
    seg = model.segment(0.0, zone_membership(model, states[0]))
    batch = np.stack(states, axis=1)
    general = model.evaluate(batch, seg, full=False)  # K = 20 takes the general path
    for k, y in enumerate(states):
        fast = model.evaluate(y[:, None], seg, full=False)
        assert np.allclose(fast.y_dot[:, 0], general.y_dot[:, k], rtol=1e-10, atol=1e-9)
        assert np.allclose(fast.lam[0], general.lam[k], rtol=1e-10, atol=1e-6)


def test_tyre_map_transposes_to_body_forces():
    """Virtual power: sum over wheels of F_k . v_k equals sum over bodies of F_i . v_i + M_i w_i."""
    veh = _ts()
    wheels = WheelSettings(default=WheelSetting("rolling", steer=0.2, **TYRE))
    model = _model(veh, wheels)
    rng = np.random.default_rng(3)
    y = model.layout.pack(chain_states(veh, (0, 0), 0.4, (10.0, 3.0), yaw_rates=[0.5, -0.2], articulation=[0.3]))
    y[model.layout.velocity] += rng.normal(0, 1, 6)
    seg = model.segment(0.0, zone_membership(model, y))
    ev = model.evaluate(y[:, None], seg)
    L = model.layout
    f = ev.body_force[:, 0]
    body_power = f[0:2] @ y[L.vx] + f[2:4] @ y[L.vy] + f[4:6] @ y[L.w]
    assert body_power == pytest.approx(ev.tyre_power[:, 0].sum(), rel=1e-12)


def test_three_body_chain_runs_and_keeps_its_hitches():
    """Tractor + semitrailer + dolly + semitrailer (doubles) on the general multi-hitch path."""
    tractor = Body("tractor", 8000.0, 30000.0, length=6.0, axles=(Axle(1.5, 2.0), Axle(-2.0, 1.8, True)))
    trailer1 = Body("trailer1", 12000.0, 100000.0, length=8.5, axles=(Axle(-3.5, 1.8, True),))
    dolly = Body("dolly", 1200.0, 800.0, length=3.0, axles=(Axle(0.0, 1.8, True),))
    trailer2 = Body("trailer2", 12000.0, 100000.0, length=8.5, axles=(Axle(-3.5, 1.8, True),))
    veh = Vehicle(
        "doubles",
        (tractor, trailer1, dolly, trailer2),
        (Hitch((-1.8, 0.0), (4.0, 0.0)), Hitch((-5.0, 0.0), (2.5, 0.0)), Hitch((0.1, 0.0), (4.0, 0.0))),
    )
    init = make_hitch_consistent(veh, chain_states(veh, (0, 0), 0.0, (20.0, 1.0), yaw_rates=[0.2, 0.0, -0.3, 0.1]))
    wheels = WheelSettings(default=WheelSetting("braked", brake=0.5, **TYRE), wheels={"tractor/0": WheelSetting("rolling", **TYRE)})
    res = simulate_runout(veh, init, wheels, Road(0.7), RunoutOptions(rtol=1e-8, atol=1e-10))
    assert res.status == "rest"
    assert res.max_hitch_gap < 1e-6
    assert len(res.hitches) == 3
    assert abs(res.energy_residual) < 1e-5


def test_rest_state_is_frame_invariant():
    """Rotating and translating the whole scene (initial states and friction zones) rotates and
    translates the rest states: the equations contain no preferred world direction."""
    from crashsim.geometry import rotate
    from crashsim.motion import FrictionZone
    from crashsim.vehicles import BodyState

    veh = _ts()
    wheels = WheelSettings(default=WheelSetting("rolling", **TYRE), wheels={"tractor/1": WheelSetting("locked"), "trailer": WheelSetting("braked", brake=0.5, **TYRE)})
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.1, (14.0, 1.0), yaw_rates=[0.3, -0.1]))
    patch = ((6.0, -4.0), (14.0, -4.0), (16.0, 0.0), (14.0, 4.0), (6.0, 4.0))
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    base = simulate_runout(veh, init, wheels, Road(0.75, (FrictionZone(patch, 0.4),)), opts)
    phi, shift = 2.2, np.array([-30.0, 45.0])

    def move(p):
        return rotate(np.asarray(p, dtype=float), phi) + shift

    moved_init = {
        n: BodyState(tuple(move(s.position)), s.heading + phi, tuple(rotate(np.asarray(s.velocity), phi)), s.yaw_rate)
        for n, s in init.items()
    }
    moved_road = Road(0.75, (FrictionZone(tuple(map(tuple, move(patch))), 0.4),))
    moved = simulate_runout(veh, moved_init, wheels, moved_road, opts)
    assert [e.kind for e in moved.events] == [e.kind for e in base.events]
    for name, body in base.bodies.items():
        assert np.allclose(moved.bodies[name].rest_position, move(body.rest_position), atol=1e-6)
        assert moved.bodies[name].rest_heading == pytest.approx(body.rest_heading + phi, abs=1e-8)
    assert moved.t_end == pytest.approx(base.t_end, abs=1e-6)

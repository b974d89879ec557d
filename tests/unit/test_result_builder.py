"""One result builder (crashsim.motion.postprocess.build_result) from named inputs (ResultInputs):
both engines, the energy level and the pymunk cross-check build their RunoutResult through it."""

from __future__ import annotations

import numpy as np
import pytest

from crashsim.motion import Road, RunoutOptions, WheelSettings
from crashsim.motion.hitches import RunoutModel
from crashsim.motion.levels import _energy_runout
from crashsim.motion.postprocess import ResultInputs, build_result
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states


def _inputs(model, K=4):
    L = model.layout
    nb, nw, nh = L.n_bodies, len(model.specs), model.n_hitches
    t = np.linspace(0.0, 1.5, K)
    Y = np.zeros((L.size, K))
    Y[L.x] = np.linspace(0.0, 3.0, K)[None, :]
    return ResultInputs(
        t=t, Y=Y, points=np.zeros((nw, K, 2)), sliding=np.ones((nw, K), bool), load=np.ones((nw, K)),
        hitch_force=np.zeros((K, 2 * nh)), stop_moment=np.zeros((K, nh)), distance=np.full(nb, 3.0),
        path_length=np.full(nw, 3.0), sliding_length=np.full(nw, 3.0), energy=np.full(nw, 10.0), max_gap=0.0,
        status="rest", message="at rest", t_end=1.5, y_initial=Y[:, 0], y_final=Y[:, -1], sol=lambda tq: Y[:, -1],
        events=[], method="test")


def _model():
    car = Vehicle("car", (Body("car", 1500.0, 2500.0, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    return RunoutModel(car, WheelSettings.all_locked().resolve(car), Road(0.7), RunoutOptions())


def test_named_inputs_build_the_result_and_the_old_keywords_are_gone():
    model = _model()
    inputs = _inputs(model)
    new = build_result(model, inputs)
    assert new.bodies["car"].distance == 3.0
    assert new.energy_dissipated == 40.0
    assert new.bodies["car"].time_to_rest == 1.5 and new.success
    assert [w.static_load for w in new.wheels.values()] == list(model.static_load)
    with pytest.raises(TypeError):
        build_result(model, **inputs._asdict())


def test_static_loads_and_options_can_be_given():
    model = _model()
    res = build_result(model, _inputs(model)._replace(static_load=np.arange(4.0), options={"level": "x"}))
    assert [w.static_load for w in res.wheels.values()] == [0.0, 1.0, 2.0, 3.0]
    assert res.options == {"level": "x"}


def test_the_energy_level_builds_through_the_one_builder():
    """A tractor-semitrailer in line, every wheel locked: the energy level's exact d = v^2/(2 mu g)
    (research note sec. 5 item 8), with the builder's hitch histories (no force: NaN), static loads
    and energy ledger."""
    tractor = Body("tractor", 8000.0, 32000.0, length=6.0,
                   axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True)))
    trailer = Body("trailer", 25000.0, 330000.0, length=13.6,
                   axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True), Axle(-5.6, 1.85, True)))
    ts = Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0)),))
    start = chain_states(ts, (0.0, 0.0), 0.0, (15.0, 0.0))
    res = _energy_runout(ts, start, None, Road(0.7))
    d = 15.0**2 / (2 * 0.7 * G)
    for name, b in res.bodies.items():
        assert b.rest_position[0] - b.initial.position[0] == pytest.approx(d, rel=1e-12)
        assert b.distance == pytest.approx(d, rel=1e-6)
    (h,) = res.hitches
    assert np.isnan(h.force).all() and np.isnan(h.force_body).all() and not h.stop_moment.any()
    assert res.method == "energy" and res.options["level"] == "energy"
    assert res.energy_dissipated == pytest.approx(res.kinetic_energy_initial, rel=1e-9)
    for w in res.wheels.values():
        assert np.all(w.load == w.static_load) and w.path_length == pytest.approx(d, rel=1e-9)

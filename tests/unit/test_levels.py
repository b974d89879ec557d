"""Fidelity levels of the run-out (crashsim.motion.levels): each level's documented model.

Closed forms are the research note's sec. 5 items 1, 3, 4 and 8; the energy model's
documented conservatism (item 7) and the rigid level's kingpin-load treatment are checked
against the articulated engine.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion import (
    FrictionZone,
    Road,
    RunoutOptions,
    RunoutResult,
    WheelSetting,
    WheelSettings,
    make_hitch_consistent,
    simulate_runout,
    static_loads,
)
from crashsim.motion.levels import simulate_level
from crashsim.motion.runners import LEVEL_DESCRIPTIONS, LEVELS
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

ROOT = Path(__file__).resolve().parents[2]
TYRE = dict(cornering_coefficient=8.6, rolling_resistance=0.012)


def symmetric_car(cg_height=None):
    """CG midway between the axles: four equal loads at equal distance from the CG."""
    body = Body("car", 1500.0, 2500.0, length=4.5, axles=(Axle(1.3, 1.5), Axle(-1.3, 1.5)), cg_height=cg_height)
    return Vehicle("car", (body,))


def tractor_semitrailer(limit=None, cg=False):
    h1, h2 = (1.1, 1.6) if cg else (None, None)
    tractor = Body("tractor", 8000.0, 32000.0, length=6.0, cg_height=h1,
                   axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True)))
    trailer = Body("trailer", 25000.0, 330000.0, length=13.6, cg_height=h2,
                   axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True), Axle(-5.6, 1.85, True)))
    return Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0), articulation_limit=limit),))


def test_levels_and_descriptions():
    assert LEVELS == ("impact", "energy", "rigid", "articulated", "load_transfer")
    assert set(LEVEL_DESCRIPTIONS) == set(LEVELS)


def test_unknown_level_suggests_the_nearest():
    start = {"car": BodyState((0, 0), 0.0, (10.0, 0.0))}
    with pytest.raises(ScenarioError, match=r"runout\.level.*best matches are \['articulated'\]"):
        simulate_level("articulted", symmetric_car(), start, None, Road(0.7))
    with pytest.raises(ScenarioError, match="must be one of"):
        simulate_level("full", symmetric_car(), start, None, Road(0.7))


def test_impact_level_has_no_runout():
    start = {"car": BodyState((0, 0), 0.0, (10.0, 0.0))}
    assert simulate_level("impact", symmetric_car(), start, None, Road(0.7)) is None


# ---------------------------------------------------------------- energy: closed forms
def test_energy_straight_slide_item_1():
    v0, mu = 20.0, 0.75
    res = simulate_level("energy", symmetric_car(), {"car": BodyState((1.0, 2.0), 0.4, (v0 * math.cos(0.4), v0 * math.sin(0.4)))},
                         None, Road(mu))
    b = res.bodies["car"]
    d = v0**2 / (2 * mu * G)
    assert res.status == "rest" and res.success and res.method == "energy" and res.nfev == 0
    assert math.dist(b.rest_position, (1.0 + d * math.cos(0.4), 2.0 + d * math.sin(0.4))) < 1e-9
    assert b.rest_heading == pytest.approx(0.4, abs=1e-12)
    assert b.time_to_rest == pytest.approx(v0 / (mu * G), rel=1e-12)
    assert b.distance == pytest.approx(d, rel=1e-6)
    # straight track, energy fully dissipated by the wheels, locked wheels leave marks
    h = b.history
    assert np.max(np.abs(-np.sin(0.4) * (h.x - 1.0) + np.cos(0.4) * (h.y - 2.0))) < 1e-9
    assert res.energy_dissipated == pytest.approx(res.kinetic_energy_initial, rel=1e-12)
    assert abs(res.energy_residual) < 1e-12
    for tr in res.wheels.values():
        assert tr.sliding.all() and tr.sliding_length == pytest.approx(d, rel=1e-6)


def test_energy_pure_spin_item_4():
    mu, w0 = 0.7, -4.0
    veh = symmetric_car()
    res = simulate_level("energy", veh, {"car": BodyState((0, 0), 0.2, (0.0, 0.0), w0)}, None, Road(mu))
    b = res.bodies["car"]
    r = math.hypot(1.3, 0.75)
    n_sum = static_loads(veh).total
    inertia = veh.bodies[0].yaw_inertia
    assert b.rest_heading - 0.2 == pytest.approx(-inertia * w0**2 / (2 * mu * n_sum * r), rel=1e-12)
    assert b.time_to_rest == pytest.approx(inertia * abs(w0) / (mu * n_sum * r), rel=1e-12)
    assert b.rest_position == (0.0, 0.0)
    # the integrated model agrees with the closed form to its eps/v_stop bounds (note item 4)
    sim = simulate_level("articulated", veh, {"car": BodyState((0, 0), 0.2, (0.0, 0.0), w0)}, None, Road(mu))
    assert sim.bodies["car"].rest_heading == pytest.approx(b.rest_heading, abs=2e-3)


def test_energy_sideways_slide_on_rolling_wheels_item_3_and_free_roll():
    v0, mu = 12.0, 0.8
    roll0 = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))
    res = simulate_level("energy", symmetric_car(), {"car": BodyState((0, 0), 0.0, (0.0, v0))}, roll0, Road(mu))
    assert res.bodies["car"].rest_position[1] == pytest.approx(v0**2 / (2 * mu * G), rel=1e-12)
    # along the heading only rolling resistance decelerates: d = v^2 / (2 f_r g)
    roll = WheelSettings(default=WheelSetting("rolling", **TYRE))
    res = simulate_level("energy", symmetric_car(), {"car": BodyState((0, 0), 0.0, (3.0, 0.0))}, roll, Road(mu))
    assert res.bodies["car"].rest_position[0] == pytest.approx(9.0 / (2 * 0.012 * G), rel=1e-12)
    # without rolling resistance it never stops: time limit, not rest
    res = simulate_level("energy", symmetric_car(), {"car": BodyState((0, 0), 0.0, (3.0, 0.0))}, roll0, Road(mu),
                         RunoutOptions(t_max=7.0))
    assert res.status == "time_limit" and not res.success and res.t_end == 7.0
    assert res.bodies["car"].time_to_rest is None
    assert res.bodies["car"].rest_position[0] == pytest.approx(21.0)


def test_energy_articulated_in_line_item_8_and_lock_event():
    veh = tractor_semitrailer()
    v0, mu = 20.0, 0.75
    res = simulate_level("energy", veh, chain_states(veh, (0, 0), 0.0, (v0, 0.0)), None, Road(mu))
    d = v0**2 / (2 * mu * G)
    assert res.bodies["tractor"].rest_position[0] == pytest.approx(d, rel=1e-12)
    assert res.bodies["trailer"].rest_position[0] == pytest.approx(d - 8.0, rel=1e-12)
    lock = [e for e in res.events if e.kind == "lock"]
    assert len(lock) == 1 and lock[0].energy == pytest.approx(0.0, abs=1e-6)
    assert np.all(res.hitches[0].articulation == 0.0)
    # different yaw rates: the plastic lock conserves momentum and reports the energy it removes
    start = chain_states(veh, (0, 0), 0.0, (v0, 1.0), yaw_rates=[0.5, -0.3], articulation=[0.2])
    res = simulate_level("energy", veh, start, None, Road(mu))
    loss = next(e.energy for e in res.events if e.kind == "lock")
    assert loss > 0
    assert abs(res.energy_residual) < 1e-9
    art = res.hitches[0].articulation
    assert np.allclose(art, 0.2)  # frozen


def test_energy_across_a_friction_line():
    """Slide from mu1 onto mu2 beyond x0 (hand calculation at the CG): d = x0 + (v^2 - 2 mu1 g x0)/(2 mu2 g)."""
    v0, x0, mu1, mu2 = 15.0, 6.0, 0.8, 0.4
    zone = FrictionZone(((x0, -50.0), (500.0, -50.0), (500.0, 50.0), (x0, 50.0)), mu2)
    res = simulate_level("energy", symmetric_car(), {"car": BodyState((0, 0), 0.0, (v0, 0.0))}, None,
                         Road(mu1, (zone,)))
    b = res.bodies["car"]
    assert b.rest_position[0] == pytest.approx(x0 + (v0**2 - 2 * mu1 * G * x0) / (2 * mu2 * G), rel=1e-12)
    t1 = (v0 - math.sqrt(v0**2 - 2 * mu1 * G * x0)) / (mu1 * G)
    assert b.time_to_rest == pytest.approx(t1 + math.sqrt(v0**2 - 2 * mu1 * G * x0) / (mu2 * G), rel=1e-12)


def test_energy_is_conservative_for_slide_and_spin_item_7():
    """Translation and rotation each dissipated by the full friction: both come out short of the simulation."""
    start = {"car": BodyState((0, 0), 0.0, (15.0, 3.0), 2.0)}
    e = simulate_level("energy", symmetric_car(), start, None, Road(0.75)).bodies["car"]
    s = simulate_level("articulated", symmetric_car(), start, None, Road(0.75)).bodies["car"]
    assert math.dist(e.rest_position, (0, 0)) < math.dist(s.rest_position, (0, 0))
    assert abs(e.rest_heading) < abs(s.rest_heading)
    # the straight CG track points along the separation velocity
    assert math.atan2(e.rest_position[1], e.rest_position[0]) == pytest.approx(math.atan2(3.0, 15.0), abs=1e-12)


def test_energy_result_has_the_runout_interface():
    veh = tractor_semitrailer()
    start = chain_states(veh, (0, 0), 0.3, (12.0, 2.0), yaw_rates=[0.4, 0.4])
    res = simulate_level("energy", veh, start, None, Road(0.7))
    assert isinstance(res, RunoutResult)
    json.dumps(res.to_dict())
    cols = res.table()
    assert len({len(c) for c in cols.values()}) == 1
    st = res.sol(res.t_end / 2)
    assert st.shape == (res.layout.size,) and np.all(np.isfinite(st))
    b = res.bodies["trailer"]
    assert np.allclose(b.sol(b.time_to_rest)[:2], b.rest_position)
    assert b.rest_heading == pytest.approx(res.bodies["tractor"].rest_heading - 0.0, abs=1e-12)  # frozen, in line


# ---------------------------------------------------------------- rigid
def test_rigid_single_body_equals_articulated():
    start = {"car": BodyState((0, 0), 0.0, (15.0, 3.0), 2.0)}
    a = simulate_level("rigid", symmetric_car(), start, None, Road(0.75))
    b = simulate_level("articulated", symmetric_car(), start, None, Road(0.75))
    assert a.bodies["car"].rest_position == b.bodies["car"].rest_position
    assert a.options["level"] == "rigid" and b.options["level"] == "articulated"


def test_rigid_articulated_slide_keeps_the_kingpin_load_on_the_tractor():
    """No hitch force: the tractor's tyres carry W1 + N_kp, the trailer's W2 - N_kp (module docstring)."""
    veh = tractor_semitrailer(limit=0.3)  # the stop is ignored at this level
    v0, mu = 20.0, 0.75
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_level("rigid", veh, chain_states(veh, (0, 0), 0.0, (v0, 0.0)), None, Road(mu), opts)
    n_kp = static_loads(veh).hitch[0]
    m1, m2 = (b.mass for b in veh.bodies)
    a1 = mu * (m1 * G + n_kp) / m1
    a2 = mu * (m2 * G - n_kp) / m2
    tol = opts.v_stop**2 / (2 * min(a1, a2)) + 1e-4  # residual travel + eps bias
    assert res.bodies["tractor"].rest_position[0] == pytest.approx(v0**2 / (2 * a1), abs=tol)
    assert res.bodies["trailer"].rest_position[0] - (-8.0) == pytest.approx(v0**2 / (2 * a2), abs=tol)
    assert res.bodies["tractor"].time_to_rest == pytest.approx(v0 / a1, abs=0.01)
    assert res.bodies["trailer"].time_to_rest == pytest.approx(v0 / a2, abs=0.01)
    assert res.max_hitch_gap == pytest.approx(v0**2 / (2 * a2) - v0**2 / (2 * a1), abs=2 * tol)
    assert not [e for e in res.events if e.kind.startswith("stop")]
    assert res.hitches[0].peak_force == 0.0
    assert abs(res.energy_residual) < 1e-6
    # the articulated engine keeps them together (note item 8): both at v^2 / (2 mu g)
    art = simulate_level("articulated", veh, chain_states(veh, (0, 0), 0.0, (v0, 0.0)), None, Road(mu), opts)
    assert art.bodies["tractor"].rest_position[0] == pytest.approx(v0**2 / (2 * mu * G), abs=tol)


# ---------------------------------------------------------------- articulated and load transfer
def test_articulated_and_load_transfer_are_the_engine():
    veh = tractor_semitrailer(cg=True)
    start = chain_states(veh, (0, 0), 0.0, (15.0, 1.0), yaw_rates=[0.3, -0.1])
    wheels = WheelSettings(default=WheelSetting("locked"), wheels={"tractor/0": WheelSetting("rolling", **TYRE)})
    opts = RunoutOptions(load_transfer=True)  # the level decides
    a = simulate_level("articulated", veh, start, wheels, Road(0.7), opts)
    ref = simulate_runout(veh, start, wheels, Road(0.7), RunoutOptions())
    assert a.bodies["trailer"].rest_position == ref.bodies["trailer"].rest_position
    assert a.options["load_transfer"] is False
    lt = simulate_level("load_transfer", veh, start, wheels, Road(0.7))
    ref_lt = simulate_runout(veh, start, wheels, Road(0.7), RunoutOptions(load_transfer=True))
    assert lt.bodies["trailer"].rest_position == ref_lt.bodies["trailer"].rest_position
    assert lt.options["level"] == "load_transfer"
    with pytest.raises(ScenarioError, match="cg_height"):
        simulate_level("load_transfer", tractor_semitrailer(), start, wheels, Road(0.7))


# ---------------------------------------------------------------- every level on a shipped scene
def test_every_level_on_the_shipped_intersection_scene():
    from crashsim.impact import solve_impact
    from crashsim.scene.run import separation_states
    from crashsim.scenario import load_scenario

    sc = load_scenario(ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml")
    states = separation_states(sc, solve_impact(sc.impact))
    initial = {}
    for v in sc.vehicles:
        initial.update(make_hitch_consistent(v, {b.name: states[b.name] for b in v.bodies}))
    results = {}
    for level in LEVELS[1:]:
        # each vehicle alone (the levels compared without the contact of a scene run)
        out = {v.name: simulate_level(level, v, initial, sc.runout.wheels.get(v.name), sc.runout.road,
                                      sc.runout.options) for v in sc.vehicles if not v.is_barrier}
        assert set(out) == {"A", "B"}
        for r in out.values():
            assert r.status == "rest"
            for b in r.bodies.values():
                assert np.all(np.isfinite(b.rest_position)) and math.isfinite(b.rest_heading)
                assert b.time_to_rest is not None and 0 < b.time_to_rest < 10
        results[level] = out
    # the hitch-free bodies drift apart; the articulated ones stay pinned
    assert results["rigid"]["A"].max_hitch_gap > 1.0
    assert results["articulated"]["A"].max_hitch_gap < 1e-3
    # the default scene equals the articulated level
    assert results["articulated"]["A"].bodies["trailer"].rest_position == pytest.approx((12.298, 2.583), abs=2e-3)

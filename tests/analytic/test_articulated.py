"""Articulated closed forms: all-locked straight slide of a tractor-semitrailer (note sec. 5 item 8),
and the reduced-coordinate oracle against the maximal-coordinate engine (item 11)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import GLOBAL, TRUCK_TYRE, G, regularised_slide, tractor_semitrailer

from crashsim.motion import (
    Road,
    RunoutOptions,
    WheelSetting,
    WheelSettings,
    make_hitch_consistent,
    simulate_runout,
    static_loads,
)
from reduced_oracle import simulate_reduced
from crashsim.vehicles import chain_states


@pytest.mark.parametrize("articulation", [0.0, 0.35])
def test_all_locked_straight_combination(articulation):
    """All wheels locked, moving straight along the tractor heading, zero yaw rates.

    Every unit decelerates at mu g r(v) (r(v) = v/sqrt(v^2+eps^2), the regularisation), the articulation
    angle does not change, and the trailer pushes the tractor with lambda = mu N_kp r(v): the kingpin
    load sits on the tractor tyres (note item 8; the trap is to expect lambda = 0).  With an articulation
    angle the trailer's own friction is still along the common velocity, so the same holds.
    """
    v0, mu = 20.0, 0.75
    veh = tractor_semitrailer()
    init = chain_states(veh, (0.0, 0.0), 0.0, (v0, 0.0), articulation=[articulation])
    # the trailer moves with the tractor (no yaw): its CG velocity equals the tractor's
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, init, None, Road(mu), opts)
    assert res.status == "rest"
    x_reg, t_reg = regularised_slide(v0, opts.v_stop, opts.eps, mu * G)
    for name, body in res.bodies.items():
        start = np.array(init[name].position)
        moved = np.subtract(body.rest_position, start)
        assert moved[0] == pytest.approx(x_reg, abs=GLOBAL * opts.rtol * x_reg)
        assert abs(moved[1]) < GLOBAL * opts.rtol * x_reg
    hitch = res.hitches[0]
    assert np.max(np.abs(hitch.articulation - articulation)) < 1e-9
    # hitch force on the tractor along +x: mu N_kp r(v), compared while v >> eps
    n_kp = static_loads(veh).hitch[0]
    speed = np.hypot(res.bodies["tractor"].history.vx, res.bodies["tractor"].history.vy)
    fast = speed > 1.0
    expected = mu * n_kp * speed[fast] / np.hypot(speed[fast], opts.eps)
    assert np.allclose(hitch.force[fast, 0], expected, rtol=GLOBAL * opts.rtol, atol=GLOBAL * opts.rtol * expected.max())
    assert np.max(np.abs(hitch.force[fast, 1])) < GLOBAL * opts.rtol * expected.max()
    assert res.bodies["tractor"].time_to_rest == pytest.approx(t_reg, abs=GLOBAL * opts.rtol * t_reg)
    assert res.max_hitch_gap < 1e-9


def _braked_case():
    """The note's sec. 1.5 case: steer axle free rolling, every other wheel braked at 50 % of mu N."""
    veh = tractor_semitrailer()
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.0, (15.0, 2.0), yaw_rates=[0.5, 0.0]))
    wheels = WheelSettings(
        default=WheelSetting("braked", brake=0.5, **TRUCK_TYRE),
        wheels={"tractor/steer": WheelSetting("rolling", **TRUCK_TYRE)},
    )
    return veh, init, wheels


def test_reduced_oracle_agrees_with_maximal_coordinates():
    """Maximal coordinates + multiplier + Baumgarte vs reduced coordinates (constraint exact by construction):
    rest positions within 0.05 mm, headings within the corresponding angle, on an articulated braked case."""
    veh, init, wheels = _braked_case()
    road = Road(0.75)
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    full = simulate_runout(veh, init, wheels, road, opts)
    oracle = simulate_reduced(veh, init, wheels, road, opts)
    assert full.status == oracle.status == "rest"
    for name, body in full.bodies.items():
        gap = math.dist(body.rest_position, oracle.final[name].position)
        assert gap < 5e-5
        assert abs(body.rest_heading - oracle.final[name].heading) < 5e-5 / 3.0
    assert full.t_end == pytest.approx(oracle.t_end, abs=1e-4)
    # the run is not trivial: the combination yawed and the articulation changed
    assert abs(full.bodies["tractor"].rest_heading) > 0.05
    assert np.ptp(full.hitches[0].articulation) > 0.01
    assert full.max_hitch_gap < 1e-6


def test_hitch_does_no_work():
    """Work-energy identity for the articulated braked case: KE_0 - KE_end = sum of tyre dissipations.

    An ideal hitch does no net work; Baumgarte stabilisation and solver error show up as a residual of
    the order of the tolerance (note sec. 5 item 5).
    """
    veh, init, wheels = _braked_case()
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, init, wheels, Road(0.75), opts)
    assert abs(res.energy_residual) < GLOBAL * opts.rtol

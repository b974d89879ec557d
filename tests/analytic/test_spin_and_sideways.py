"""Pure spin about the CG and a sideways slide on free-rolling wheels (note sec. 5, items 3-4)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import CAR_TYRE, GLOBAL, G, car, regularised_slide, symmetric_car

from crashsim.geometry import cross
from crashsim.motion import Road, RunoutOptions, WheelSetting, WheelSettings, simulate_runout, static_loads
from crashsim.vehicles import BodyState


@pytest.mark.parametrize("w0", [3.0, -6.0])
def test_pure_spin_about_cg(w0):
    """Symmetric layout, equal loads, all locked: the CG stays put and the spin stops at t = I w0 / (mu sum N r).

    The contact speed ``v = |w| r`` obeys ``v' = -k v / sqrt(v^2 + eps^2)`` with ``k = mu sum(N) r^2 / I``,
    the same regularised law as a straight slide, so t and the heading change have exact
    closed forms; the rest event fires at ``|w| L_ref = v_stop``.
    """
    mu = 0.75
    veh = symmetric_car()
    body = veh.bodies[0]
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, {"car": BodyState((2.0, -1.0), 0.3, (0.0, 0.0), w0)}, None, Road(mu), opts)
    r = math.hypot(1.3, 0.75)
    n_sum = static_loads(veh).total
    k = mu * n_sum * r * r / body.yaw_inertia
    l_ref = body.length / 2
    v_end = opts.v_stop / l_ref * r
    arc, t_reg = regularised_slide(abs(w0) * r, v_end, opts.eps, k)
    out = res.bodies["car"]
    assert out.time_to_rest == pytest.approx(t_reg, abs=GLOBAL * opts.rtol * t_reg)
    assert out.rest_heading - 0.3 == pytest.approx(math.copysign(arc / r, w0), abs=GLOBAL * opts.rtol * arc / r)
    # the net force is zero by symmetry: the CG does not move (round-off only)
    assert np.hypot(out.rest_position[0] - 2.0, out.rest_position[1] + 1.0) < 1e-9
    # ideal closed forms of the note, within the v_stop and eps bounds
    t_ideal = body.yaw_inertia * abs(w0) / (mu * n_sum * r)
    dpsi_ideal = body.yaw_inertia * w0**2 / (2 * mu * n_sum * r)
    arc_eps, t_eps = regularised_slide(abs(w0) * r, 1e-12, opts.eps, k)
    assert abs(out.time_to_rest - t_ideal) <= v_end / k + abs(t_eps - t_ideal) + GLOBAL * opts.rtol * t_ideal
    dpsi = abs(out.rest_heading - 0.3)
    assert abs(dpsi - dpsi_ideal) <= (v_end**2 / (2 * k) + abs(arc_eps - dpsi_ideal * r)) / r + GLOBAL * opts.rtol * dpsi


@pytest.mark.parametrize("direction", [+1, -1])
def test_sideways_slide_on_rolling_wheels(direction):
    """Velocity perpendicular to the heading on free-rolling wheels (f_r = 0): the saturated lateral forces
    oppose the velocity, so a = mu g (regularised like a locked slide) and d = v0^2/(2 mu g) with no yaw
    (note item 3).

    With u = 0 the Fiala demand is mu N once ``C |w| / eps >= 3 mu N`` (every speed above ~3 mm/s, below
    v_stop), so the force is the friction circle ``mu N |w| / sqrt(w^2 + eps^2)``: the regularised locked
    law; the yaw moment mu (N_f a - N_r b) vanishes by the static moment balance.
    """
    v0, mu = 12.0, 0.8
    tyre = dict(CAR_TYRE, rolling_resistance=0.0)
    wheels = WheelSettings(default=WheelSetting("rolling", **tyre))
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    heading = 0.4
    v = direction * v0 * np.array([-math.sin(heading), math.cos(heading)])
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), heading, tuple(v))}, wheels, Road(mu), opts)
    out = res.bodies["car"]
    d_expected, _ = regularised_slide(v0, opts.v_stop, opts.eps, mu * G)
    assert abs(d_expected - v0**2 / (2 * mu * G)) < opts.v_stop**2 / (2 * mu * G) + 1e-4
    travelled = np.dot(out.rest_position, v / v0)
    assert travelled == pytest.approx(d_expected, abs=GLOBAL * opts.rtol * d_expected)
    assert abs(cross(out.rest_position, v / v0)) < 1e-9  # no drift off the line of motion
    assert abs(out.rest_heading - heading) < 1e-9  # no yaw
    # saturated lateral demand: every wheel slides sideways and leaves a mark
    for track in res.wheels.values():
        assert track.sliding[:-1].all()
        assert track.sliding_length == pytest.approx(travelled, rel=1e-6)

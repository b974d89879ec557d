"""Straight slides: locked wheels, equal partial braking, and a scheduled brake change (note sec. 5, items 1-2).

Two comparisons per case:

* against the closed form of the *regularised* model (friction ``mu N v / sqrt(v^2 + eps^2)``,
  stopped by the rest event at ``v = v_stop``), which the integrator must match to its tolerance;
  the allowance is ``GLOBAL * rtol * scale`` (see ``runout_cases.GLOBAL``);
* against the ideal closed form ``d = v^2/(2 a)``, ``t = v/a``, within the bound the note derives
  for the low-speed treatment: the residual travel ``v_stop^2 / (2 a)`` and time ``v_stop / a``
  after the rest event, plus the regularisation effect (exact difference of the two closed forms).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import CAR_TYRE, GLOBAL, G, car, regularised_slide
from scipy.optimize import brentq

from crashsim.motion import Road, RunoutOptions, ScheduledChange, WheelSetting, WheelSettings, simulate_runout
from crashsim.vehicles import BodyState


@pytest.mark.parametrize("method", ["LSODA", "RK45", "DOP853"])
@pytest.mark.parametrize("v0, mu", [(20.0, 0.75), (8.0, 0.4)])
def test_locked_slide_matches_closed_form(method, v0, mu):
    opts = RunoutOptions(method=method, rtol=1e-9, atol=1e-11)
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None, Road(mu), opts)
    assert res.status == "rest" and res.success
    body = res.bodies["car"]
    x_reg, t_reg = regularised_slide(v0, opts.v_stop, opts.eps, mu * G)
    assert body.rest_position[0] == pytest.approx(x_reg, abs=GLOBAL * opts.rtol * x_reg)
    assert body.time_to_rest == pytest.approx(t_reg, abs=GLOBAL * opts.rtol * t_reg + 1e-9)
    # straight: no lateral motion, no yaw (exact by symmetry of the forces)
    assert abs(body.rest_position[1]) < 1e-12 and abs(body.rest_heading) < 1e-12
    # against the ideal d = v^2/(2 mu g), t = v/(mu g): within the v_stop and eps bounds
    a = mu * G
    d_ideal, t_ideal = v0**2 / (2 * a), v0 / a
    x_eps_only, t_eps_only = regularised_slide(v0, 1e-12, opts.eps, a)  # regularisation alone
    bound_d = opts.v_stop**2 / (2 * a) + abs(x_eps_only - d_ideal) + GLOBAL * opts.rtol * d_ideal
    bound_t = opts.v_stop / a + abs(t_eps_only - t_ideal) + GLOBAL * opts.rtol * t_ideal
    assert abs(body.rest_position[0] - d_ideal) <= bound_d
    assert abs(body.time_to_rest - t_ideal) <= bound_t
    # the CG path length is the slide distance; every wheel slid it
    assert body.distance == pytest.approx(body.rest_position[0], rel=1e-7)
    for track in res.wheels.values():
        assert track.sliding.all()
        assert track.sliding_length == pytest.approx(body.rest_position[0], rel=1e-7)


def test_default_options_meet_the_documented_bounds():
    """Default tolerances: rest position within v_stop^2/(2 mu g) + O(eps) of the ideal closed form."""
    v0, mu = 20.0, 0.75
    opts = RunoutOptions()
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None, Road(mu), opts)
    a = mu * G
    x_eps_only, _ = regularised_slide(v0, 1e-12, opts.eps, a)
    bound = opts.v_stop**2 / (2 * a) + abs(x_eps_only - v0**2 / (2 * a)) + GLOBAL * opts.rtol * v0**2 / (2 * a)
    assert abs(res.bodies["car"].rest_position[0] - v0**2 / (2 * a)) <= bound


@pytest.mark.parametrize("brake", [0.3, 0.8])
def test_equal_partial_braking(brake):
    """All wheels braked at b mu N plus rolling resistance f_r N, straight: a = (b mu + f_r) g (note item 2)."""
    v0, mu = 15.0, 0.8
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    wheels = WheelSettings(default=WheelSetting("braked", brake=brake, **CAR_TYRE))
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, wheels, Road(mu), opts)
    a = (brake * mu + CAR_TYRE["rolling_resistance"]) * G
    x_reg, t_reg = regularised_slide(v0, opts.v_stop, opts.eps, a)
    body = res.bodies["car"]
    assert body.rest_position[0] == pytest.approx(x_reg, abs=GLOBAL * opts.rtol * x_reg)
    assert body.time_to_rest == pytest.approx(t_reg, abs=GLOBAL * opts.rtol * t_reg + 1e-9)
    # braked but not saturated: no tyre marks
    assert not any(track.sliding.any() for track in res.wheels.values())


def test_scheduled_brake_release_is_integrated_piecewise():
    """Locked until t1, then braked at b = 0.3: two closed-form phases joined at exactly t1."""
    v0, mu, t1, brake = 15.0, 0.8, 0.5, 0.3
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    wheels = WheelSettings(
        default=WheelSetting("locked"),
        schedule=[ScheduledChange(t1, "car", {"state": "braked", "brake": brake, **CAR_TYRE})],
    )
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, wheels, Road(mu), opts)
    a1, a2 = mu * G, (brake * mu + CAR_TYRE["rolling_resistance"]) * G
    # speed at t1 of the regularised locked slide: t(v0 -> v1) = t1
    v1 = brentq(lambda v: regularised_slide(v0, v, opts.eps, a1)[1] - t1, 1.0, v0)
    x1, _ = regularised_slide(v0, v1, opts.eps, a1)
    x2, t2 = regularised_slide(v1, opts.v_stop, opts.eps, a2)
    body = res.bodies["car"]
    assert body.rest_position[0] == pytest.approx(x1 + x2, abs=GLOBAL * opts.rtol * (x1 + x2))
    assert body.time_to_rest == pytest.approx(t1 + t2, abs=GLOBAL * opts.rtol * (t1 + t2))
    assert [e.t for e in res.events if e.kind == "schedule"] == [t1]
    # the tracks are sliding before t1 and not after
    track = res.wheels["car/0/left"]
    assert track.sliding[track.t < t1].all() and not track.sliding[track.t > t1].any()
    assert [s.kind for s in track.segments] == ["sliding", "rolling"]
    assert math.isclose(track.segments[0].t[-1], t1, abs_tol=opts.sample_dt)
    assert np.all(np.diff(track.t) > 0)

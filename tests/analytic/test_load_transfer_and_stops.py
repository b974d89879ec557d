"""Quasi-static load transfer (note sec. 2.6) and the articulation stop (jack-knife limit)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import CAR_TYRE, GLOBAL, TRUCK_TYRE, G, car, regularised_slide, tractor_semitrailer

from crashsim.motion import Road, RunoutOptions, WheelSetting, WheelSettings, make_hitch_consistent, simulate_runout
from crashsim.vehicles import BodyState, chain_states


def test_longitudinal_load_transfer_on_a_locked_slide():
    """All wheels locked: the total friction mu sum(N) does not depend on how the load is shared, so the
    slide distance is the closed form; the front axle gains m |a_x| h / L = m mu g r(v) h / L."""
    v0, mu, h = 20.0, 0.75, 0.55
    veh = car(cg_height=h)
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, load_transfer=True)
    res = simulate_runout(veh, {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None, Road(mu), opts)
    x_reg, _ = regularised_slide(v0, opts.v_stop, opts.eps, mu * G)
    assert res.bodies["car"].rest_position[0] == pytest.approx(x_reg, abs=GLOBAL * opts.rtol * x_reg)
    front = res.wheels["car/0/left"]
    rear = res.wheels["car/1/left"]
    hist = res.bodies["car"].history
    speed = np.hypot(hist.vx, hist.vy)
    fast = speed > 2.0
    shift = veh.mass * mu * G * speed[fast] / np.hypot(speed[fast], opts.eps) * h / 2.6 / 2  # per wheel
    # the lag state trails the quasi-static value by tau |da/dt| / |a| = tau eps^2 mu g / v^3 <= 2e-5 at v > 2 m/s
    lag = opts.load_transfer_tau * opts.eps**2 * mu * G / 2.0**3
    assert np.allclose(front.load[fast] - front.static_load, shift, rtol=1.5 * lag)
    assert np.allclose(rear.load[fast] - rear.static_load, -shift, rtol=1.5 * lag)


def test_lateral_load_transfer_on_a_sideways_slide():
    """Sideways on free-rolling wheels (f_r = 0): a = mu g as without transfer, the yaw stays zero, and each
    axle's outer (leading-side) wheels lose m a_y h / track times the axle's static share."""
    v0, mu, h = 12.0, 0.8, 0.55
    veh = car(cg_height=h)
    wheels = WheelSettings(default=WheelSetting("rolling", **dict(CAR_TYRE, rolling_resistance=0.0)))
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, load_transfer=True)
    res = simulate_runout(veh, {"car": BodyState((0.0, 0.0), 0.0, (0.0, v0))}, wheels, Road(mu), opts)
    out = res.bodies["car"]
    d_expected, _ = regularised_slide(v0, opts.v_stop, opts.eps, mu * G)
    assert out.rest_position[1] == pytest.approx(d_expected, rel=GLOBAL * opts.rtol)
    assert abs(out.rest_heading) < 1e-9
    # moving left (+y), friction decelerates to the right: a_y = -mu g, the right wheels unload
    fast = np.abs(out.history.vy) > 1.0
    total = veh.mass * G
    for axle, share in ((0, 1.5 / 2.6), (1, 1.1 / 2.6)):
        left = res.wheels[f"car/{axle}/left"]
        right = res.wheels[f"car/{axle}/right"]
        dn = share * veh.mass * mu * G * h / 1.5
        assert np.allclose(left.load[fast] - total * share / 2, dn, rtol=1e-3)
        assert np.allclose(right.load[fast] - total * share / 2, -dn, rtol=1e-3)


def _jackknife(limit):
    """Tractor drive axles locked, steer and trailer free rolling: the tractor jack-knifes (note item 9)."""
    veh = tractor_semitrailer(articulation_limit=limit)
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.0, (16.0, 0.0), yaw_rates=[0.25, 0.0]))
    wheels = WheelSettings(
        default=WheelSetting("rolling", **TRUCK_TYRE),
        wheels={"tractor/1": WheelSetting("locked"), "tractor/2": WheelSetting("locked")},
    )
    return veh, init, wheels


def test_articulation_grows_without_a_stop():
    veh, init, wheels = _jackknife(None)
    res = simulate_runout(veh, init, wheels, Road(0.75))
    assert res.status == "rest"
    assert np.max(np.abs(res.hitches[0].articulation)) > math.radians(60)


def test_articulation_stop_holds_the_limit_and_conserves_momentum():
    limit = math.radians(40)
    veh, init, wheels = _jackknife(limit)
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, init, wheels, Road(0.75), opts)
    assert res.status == "rest"
    theta = res.hitches[0].articulation
    assert np.max(np.abs(theta)) <= limit + 1e-6
    closed = [e for e in res.events if e.kind == "stop_closed"]
    assert closed, [e.kind for e in res.events]
    impact = closed[0]
    assert impact.energy > 0
    # the plastic stop impact conserves linear and angular momentum of the combination
    L = res.layout
    masses = np.array([b.mass for b in veh.bodies])
    inertias = np.array([b.yaw_inertia for b in veh.bodies])

    def momenta(y):
        p = np.array([masses @ y[L.vx], masses @ y[L.vy]])
        h = inertias @ y[L.w] + masses @ (y[L.x] * y[L.vy] - y[L.y] * y[L.vx])
        return p, h

    before = res.sol(np.nextafter(impact.t, 0.0))
    after = res.sol(impact.t)
    (p0, h0), (p1, h1) = momenta(before), momenta(after)
    assert np.allclose(p0, p1, rtol=1e-9, atol=1e-6)
    assert h1 == pytest.approx(h0, rel=1e-9)
    # the energy lost in the impact is what the kinetic energy dropped by
    ke = lambda y: 0.5 * (masses @ (y[L.vx] ** 2 + y[L.vy] ** 2) + inertias @ y[L.w] ** 2)  # noqa: E731
    assert ke(before) - ke(after) == pytest.approx(impact.energy, rel=1e-6)
    # the book-keeping closes: tyres + stop impacts account for the kinetic energy
    assert abs(res.energy_residual) < GLOBAL * opts.rtol
    # while closed, the stop pushes the bodies apart (never pulls)
    moment = res.hitches[0].stop_moment
    engaged = moment != 0
    assert engaged.any()
    assert np.all(moment[engaged] * np.sign(theta[engaged]) <= 1e-6)

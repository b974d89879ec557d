"""Wheel lift and rollover against closed forms (crashsim.motion.rollover).

* A rigid body on one track width: its load transfer ratio is ``LTR = 2 h a_y / (g t)`` (the
  lateral roll moment ``m a_y h`` over the weight times half the track), so all its inner wheels
  lift at the lateral acceleration ``a_y = g t / (2 h)`` (the static stability factor).  A car
  spinning on locked wheels sweeps its body-axes lateral acceleration up through that value;
  the ``unit_lift`` event must sit at it to the root search's precision, and the
  ``rollover_threshold`` event at the default threshold ``0.75 t / (2 h)``.
* A steady turn on rolling wheels: the loads' LTR against ``2 h a_y / (g t)`` with ``a_y`` the
  turn's kinematic lateral acceleration ``dv/dt + u r`` (body axes), within the lag of the
  load-transfer filter, ``tau |d a_y / dt|``.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from runout_cases import CAR_TYRE, G, car, tractor_semitrailer

from crashsim.motion import Road, RunoutOptions, simulate_runout
from crashsim.motion.rollover import (DEFAULT_THRESHOLD_FACTOR, default_rollover_threshold, static_stability_factor)
from crashsim.motion.wheels import WheelSetting, WheelSettings
from crashsim.vehicles import BodyState, chain_states

H, TRACK = 0.9, 1.5  # car(): both axles 1.5 m track


def _spin(engine, threshold=None):
    veh = car(cg_height=H)
    if threshold is not None:
        veh = dataclasses.replace(veh, bodies=(dataclasses.replace(veh.bodies[0], rollover_threshold=threshold),))
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, load_transfer=True, rollover=True, engine=engine)
    return simulate_runout(veh, {"car": BodyState((0.0, 0.0), 0.0, (15.0, 0.0), 1.5)}, None, Road(1.0), opts)


def _first(res, kind):
    (e,) = [e for e in res.events if e.kind == kind]
    return e


def test_default_threshold_is_the_reduced_static_stability_factor():
    body = car(cg_height=H).bodies[0]
    assert static_stability_factor(body) == pytest.approx(TRACK / (2 * H), rel=1e-15)
    assert default_rollover_threshold(body) == pytest.approx(DEFAULT_THRESHOLD_FACTOR * TRACK / (2 * H), rel=1e-15)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_a_rigid_unit_lifts_at_t_over_2h(engine):
    res = _spin(engine)
    assert res.status == "rest"
    lift = _first(res, "unit_lift")
    # the load transfer ratio reaches 1 where the lateral acceleration is t / (2 h) g
    assert abs(lift.data["lateral_acceleration_g"]) == pytest.approx(TRACK / (2 * H), abs=1e-8)
    assert abs(lift.data["ltr"]) == pytest.approx(1.0, abs=1e-8)
    thr = _first(res, "rollover_threshold")
    assert abs(thr.data["lateral_acceleration_g"]) == pytest.approx(0.75 * TRACK / (2 * H), abs=1e-8)
    assert thr.t < lift.t
    # the place is the CG at that time, the speed its speed
    st = res.sol(lift.t)
    assert lift.place == pytest.approx((st[0], st[1]), abs=1e-12)
    assert lift.data["speed_m_s"] == pytest.approx(np.hypot(st[3], st[4]), rel=1e-12)
    # the planar result is valid up to the first of them (here the rear axle's inner wheel)
    first = min(e.t for e in res.events if e.kind in ("wheel_lift", "unit_lift", "rollover_threshold"))
    assert res.rollover["valid_until_s"] == first and res.rollover["rolled"]
    assert res.to_dict(history=False)["rollover"]["valid_until_s"] == first


def test_the_events_agree_between_engines():
    a, b = _spin("scipy"), _spin("compiled")
    ka = [(e.kind, e.data["body"]) for e in a.events if "ltr" in e.data]
    kb = [(e.kind, e.data["body"]) for e in b.events if "ltr" in e.data]
    assert ka == kb and len(ka) == 3
    for ea, eb in zip([e for e in a.events if "ltr" in e.data], [e for e in b.events if "ltr" in e.data]):
        # both engines at rtol 1e-9: the events agree to far better than the 10 ms sample grid
        assert ea.t == pytest.approx(eb.t, abs=1e-6)
        assert ea.place == pytest.approx(eb.place, abs=1e-5)


def test_a_given_threshold_is_used():
    res = _spin("compiled", threshold=0.8)
    assert res.rollover["thresholds_g"] == {"car": 0.8}
    thr, lift = _first(res, "rollover_threshold"), _first(res, "unit_lift")
    assert abs(thr.data["lateral_acceleration_g"]) == pytest.approx(0.8, abs=1e-8)
    assert thr.t < lift.t  # 0.8 g comes before t / (2 h) = 0.833 g


def test_no_check_no_rollover_output():
    veh = car(cg_height=H)
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, load_transfer=True, engine="compiled")
    res = simulate_runout(veh, {"car": BodyState((0.0, 0.0), 0.0, (15.0, 0.0), 1.5)}, None, Road(1.0), opts)
    assert res.rollover is None and "rollover" not in res.to_dict(history=False)
    assert "rollover" not in res.options
    on = _spin("compiled")
    # the run itself is the same: the check only reads it
    assert np.array_equal(on.bodies["car"].history.x, res.bodies["car"].history.x)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_steady_turn_load_transfer_ratio_is_the_quasi_static_formula(engine):
    h = 0.55
    veh = car(cg_height=h)
    tau = 0.05
    wheels = WheelSettings(default=WheelSetting("rolling", **CAR_TYRE),
                           wheels={"car/0": WheelSetting("rolling", steer=0.06, **CAR_TYRE)})
    opts = RunoutOptions(rtol=1e-9, atol=1e-11, load_transfer=True, load_transfer_tau=tau, rollover=True,
                         engine=engine, t_max=6.0)
    res = simulate_runout(veh, {"car": BodyState((0.0, 0.0), 0.0, (20.0, 0.0))}, wheels, Road(0.9), opts)
    hist = res.bodies["car"].history
    c, s = np.cos(hist.heading), np.sin(hist.heading)
    u = c * hist.vx + s * hist.vy
    v = -s * hist.vx + c * hist.vy
    ay = np.gradient(v, hist.t) + u * hist.yaw_rate
    right = sum(res.wheels[f"car/{a}/right"].load for a in (0, 1))
    left = sum(res.wheels[f"car/{a}/left"].load for a in (0, 1))
    ltr = (right - left) / (right + left)
    formula = 2 * h * ay / (G * TRACK)
    steady = (hist.t > 1.0) & (hist.t < hist.t[-1] - 0.1)
    assert np.abs(ay[steady]).max() > 2.0  # a real turn: more than 0.2 g
    # the filter lags the acceleration by tau: |LTR - formula| <= 2 h tau |d a_y / dt| / (g t) (+ the
    # finite difference's error on the 10 ms grid)
    lag = 2 * h * tau * np.abs(np.gradient(ay, hist.t)) / (G * TRACK)
    assert np.all(np.abs(ltr - formula)[steady] <= 1.5 * lag[steady] + 2e-4)
    # a car turning at well below t / (2 h) g neither lifts nor passes 0.75 t / (2 h)
    assert np.abs(ay[steady]).max() / G < 0.75 * TRACK / (2 * h)
    assert res.rollover["valid_until_s"] is None and not res.rollover["rolled"]


def test_tractor_semitrailer_records_events_per_unit():
    veh = tractor_semitrailer()
    veh = dataclasses.replace(veh, bodies=tuple(dataclasses.replace(b, cg_height=hh)
                                                for b, hh in zip(veh.bodies, (1.1, 2.0))))
    states = chain_states(veh, (0.0, 0.0), 0.0, (0.0, 8.0))
    opts = RunoutOptions(rtol=1e-8, atol=1e-10, load_transfer=True, rollover=True, engine="compiled")
    res = simulate_runout(veh, states, None, Road(0.8), opts)
    # sliding sideways on locked wheels at 0.8 g: beyond the semitrailer's 0.75 t / (2 h) = 0.35 g
    rolled = {e.data["body"] for e in res.events if e.kind == "rollover_threshold"}
    assert "trailer" in rolled
    assert res.rollover["thresholds_g"]["trailer"] == pytest.approx(0.75 * 1.85 / (2 * 2.0), rel=1e-12)
    assert res.rollover["valid_until_s"] == pytest.approx(0.0, abs=1e-12)


def _combination(coupled: bool):
    """Tractor and semitrailer on one track width (the closed forms then need no track weighting)."""
    from crashsim.vehicles import Axle, Body, Hitch, Vehicle

    t = 1.85
    tractor = Body("tractor", 8000.0, 32000.0, length=6.0, cg_height=1.1,
                   axles=(Axle(1.9, t, name="steer"), Axle(-1.6, t, True, "drive 1"), Axle(-2.9, t, True, "drive 2")))
    trailer = Body("trailer", 25000.0, 330000.0, length=13.6, cg_height=2.0, roll_coupled=coupled,
                   axles=(Axle(-3.0, t, True, "t1"), Axle(-4.3, t, True, "t2"), Axle(-5.6, t, True, "t3")))
    return Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0)),)), t


@pytest.mark.parametrize("coupled", [False, True])
def test_roll_coupled_fifth_wheel_shares_the_semitrailers_roll_moment(coupled):
    """One lateral acceleration a on both units, no longitudinal one: with a roll-stiff fifth wheel the
    semitrailer's own axles transfer 2 h a / (g t) (its rigid-body ratio) and the tractor's axles the rest of
    the roll moment; free in roll, the semitrailer's axles carry all of it on W - N_kp."""
    from crashsim.motion.loads import load_transfer_matrix, static_loads
    from crashsim.motion.wheels import enumerate_wheels

    veh, t = _combination(coupled)
    loads = static_loads(veh)
    A = load_transfer_matrix(veh, loads)
    a = 0.3 * G
    dN = A @ np.array([0.0, 0.0, a, a])
    specs = enumerate_wheels(veh)
    side = np.array([1.0 if s.side == "right" else -1.0 for s in specs])
    body = np.array([s.body_index for s in specs])
    n_kp = float(loads.hitch[0])
    tractor, trailer = veh.bodies
    ltr = [float((side * (loads.wheel + dN))[body == i].sum() / loads.wheel[body == i].sum()) for i in (0, 1)]
    # the roll moments balance: sum of (dN_right - dN_left) t / 2 over every axle = sum of m h a
    assert float((side * dN).sum()) * t / 2 == pytest.approx((tractor.mass * 1.1 + trailer.mass * 2.0) * a, rel=1e-12)
    w2 = trailer.mass * G
    if coupled:
        assert ltr[1] == pytest.approx(2 * 2.0 * a / (G * t), rel=1e-12)
        assert ltr[0] == pytest.approx(2 * (tractor.mass * 1.1 + n_kp / G * 2.0) * a / (t * (tractor.mass * G + n_kp)),
                                       rel=1e-12)
    else:
        assert ltr[1] == pytest.approx(2 * trailer.mass * 2.0 * a / (t * (w2 - n_kp)), rel=1e-12)
        assert ltr[0] == pytest.approx(2 * tractor.mass * 1.1 * a / (t * (tractor.mass * G + n_kp)), rel=1e-12)


def test_roll_coupling_moves_only_the_semitrailers_roll_column():
    """The coupling changes where the semitrailer's roll moment goes and nothing else: the pitch columns and
    the tractor's own roll column are bit for bit those of the free fifth wheel."""
    from crashsim.motion.loads import load_transfer_matrix, static_loads

    free, _ = _combination(False)
    stiff, _ = _combination(True)
    a_free = load_transfer_matrix(free, static_loads(free))
    a_stiff = load_transfer_matrix(stiff, static_loads(stiff))
    assert np.array_equal(a_free[:, :3], a_stiff[:, :3])
    assert not np.allclose(a_free[:, 3], a_stiff[:, 3])

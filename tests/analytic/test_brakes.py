"""Air brakes: delay, linear build-up, brake capacity, lock-up, ABS and release against closed forms.

A straight stop whose deceleration is zero for a delay ``T_d``, rises linearly to ``a`` over
``T_r`` and then stays (:func:`crashsim.motion.brakes.ramp_stopping_distance`)::

    d = v0 T_d + (v0 T_r - a T_r^2 / 6) + v1^2 / (2 a),   v1 = v0 - a T_r / 2

The car (CG midway between its axles: four equal loads, so every wheel reaches its limit at
the same instant) rolls without rolling resistance, so the brake force alone decelerates it:
``a = sum F_b / m`` while the brakes stay below the tyres' limit; with a capacity above it the
wheels lock where ``F_b`` reaches ``mu N`` (the ramp to ``mu g`` is then shorter by the factor
``mu m g / sum F``); with ABS they hold ``eta mu N`` and never lock.  Both engines are compared
with the closed form within the low-speed bound ``v_stop^2 / (2 a)`` (the rest event fires at
``v_stop``) plus the solver's tolerance.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import GLOBAL, G, symmetric_car, tractor_semitrailer

from crashsim.motion import Road, RunoutOptions, simulate_runout
from crashsim.motion.brakes import DEFAULT_TIMING, AirBrakes, BrakeUnit, ramp_level, ramp_stopping_distance
from crashsim.motion.hitches import RunoutModel
from crashsim.motion.kernels.tyres import brake_piece
from crashsim.motion.levels import simulate_level
from crashsim.motion.wheels import WheelSetting, WheelSettings
from crashsim.vehicles import BodyState, chain_states

MASS = 1500.0  # the symmetric car of runout_cases
ROLL = WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0)


def _run(engine, brakes, v0=20.0, mu=0.8, rtol=1e-9):
    opts = RunoutOptions(engine=engine, rtol=rtol, atol=1e-11)
    ws = WheelSettings(default=ROLL, brakes=brakes)
    return simulate_runout(symmetric_car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, ws, Road(mu), opts), opts


def _check(res, opts, d, t, a):
    body = res.bodies["car"]
    assert res.status == "rest" and res.success
    bound = opts.v_stop ** 2 / (2 * a) + GLOBAL * opts.rtol * d
    assert abs(body.rest_position[0] - d) <= bound
    assert abs(body.time_to_rest - t) <= opts.v_stop / a + 1e-6
    assert abs(body.rest_position[1]) < 1e-9 and abs(body.rest_heading) < 1e-9


def test_ramp_level_and_closed_form():
    t = np.array([0.0, 0.3, 0.55, 0.8, 2.0, 2.1, 2.3, 3.0])
    r = ramp_level(t, 0.3, 0.5, 2.0, 0.2)
    assert r == pytest.approx([0.0, 0.0, 0.5, 1.0, 1.0, 0.5, 0.0, 0.0])
    # released before full: falls from the level reached
    assert ramp_level(0.5, 0.3, 0.5, 0.4, 0.2) == pytest.approx(0.2 * 0.5)
    # the closed form against a direct integration of the same deceleration history
    a, td, tr = 4.0, 0.3, 0.5
    dt = 1e-5
    tt = np.arange(0.0, 10.0, dt)
    acc = a * np.clip((tt - td) / tr, 0.0, 1.0)
    for v0 in (20.0, 0.5):  # a stop after the rise, and one inside it
        v = v0 - np.concatenate([[0.0], np.cumsum(0.5 * (acc[1:] + acc[:-1]) * dt)])
        stop = np.argmax(v <= 0)
        d_num = np.sum(0.5 * (v[1:stop] + v[:stop - 1]) * dt)
        d, t_stop = ramp_stopping_distance(v0, a, td, tr)
        assert d == pytest.approx(d_num, abs=1e-4) and t_stop == pytest.approx(tt[stop], abs=2 * dt)
    assert ramp_stopping_distance(0.5, a, td, tr)[1] < td + tr


def test_default_timing_meets_the_clauses():
    """The default ramps put the 60 psi point (60 % of full) at the application time and 5 psi at the release time."""
    for kind, (ta, trel) in {"tractor": (0.45, 0.55), "towing_trailer": (0.50, 1.00), "dolly": (0.55, 1.10),
                             "last_trailer": (0.60, 1.20)}.items():
        tm = DEFAULT_TIMING[kind]
        assert ramp_level(ta, tm["delay"], tm["rise"], math.inf, 1.0) == pytest.approx(0.6, rel=1e-12)
        # released from full at time 0: 5 % left at T_r
        assert ramp_level(trel, -10.0, tm["rise"], tm["release_delay"], tm["fall"]) == pytest.approx(0.05, rel=1e-12)


@pytest.mark.parametrize("timing", [(0.3, 0.5, 2.0, 0.2), (0.3, 0.0, 2.0, 0.0), (0.3, 0.5, 0.4, 0.2),
                                    (-0.2, 0.5, 0.1, 0.0), (0.3, 0.0, 0.2, 0.3)])
def test_each_piece_of_the_ramp_is_linear_between_its_kinks(timing):
    """The kernels' piece from a phase start (``brake_piece``: the kinks are phase boundaries) is the
    ramp there and up to the next kink, a kink belonging to the piece it starts: rises and falls of
    zero (steps), a release before full application, brakes applied before the run."""
    on, rise, off, fall = timing
    row = np.array([1.0, on, rise, off, fall, 1.0, 0.0])
    kinks = sorted({on, on + rise, off, off + fall})
    starts = [0.0] + [k for k in kinks if k > 0.0]
    ends = starts[1:] + [5.0]
    for t0, t1 in zip(starts, ends):
        ref, base, slope = brake_piece(t0, row)
        tt = np.linspace(t0, t1, 41)[:-1]
        assert base + slope * (tt - ref) == pytest.approx(ramp_level(tt, on, rise, off, fall), abs=1e-12)


def test_a_step_of_the_ramp_is_taken_by_the_phase_not_the_clock():
    """A rise time of 0 is a step of the brake force at t_on: the segment that starts there brakes
    fully even where the clock (integrated with the state) is a rounding error short of t_on, and
    the one that ends there does not brake even a rounding error past it.  (Looked up by the clock,
    the first evaluation after the step fell on the side before it: the compiled engine's
    Runge-Kutta error estimate weighs that first stage almost equally in its two solutions, so the
    wrong force went unnoticed into the step, 1e-6 of the energy in a fuzz scene.)"""
    a, t_on = 0.4 * G, 0.3
    car = symmetric_car()
    ws = WheelSettings(default=ROLL, brakes=AirBrakes({"car": BrakeUnit((a * MASS / 2,), "tractor", delay=t_on,
                                                                         rise=0.0)}))
    for engine in ("scipy", "compiled"):  # both engines end a segment there (their loops stop at segment_stops)
        model = RunoutModel(car, ws.resolve(car), Road(0.8), RunoutOptions(engine=engine))
        assert t_on in model.scene.phase_times and t_on in model.scene.segment_stops
    y = model.layout.pack({"car": BodyState((0.0, 0.0), 0.0, (20.0, 0.0))})
    no_zones = np.zeros((len(model.specs), 0), dtype=bool)
    for t_seg, clock, force in ((t_on, math.nextafter(t_on, -1.0), -a * MASS), (0.0, math.nextafter(t_on, 1.0), 0.0)):
        y[model.layout.clock_index] = clock
        fx = model.evaluate(y[:, None], model.segment(t_seg, no_zones)).body_force[0, 0]
        # the tyre law's regularised direction u / sqrt(u^2 + eps^2) is 1 - 1.25e-7 at 20 m/s (eps 0.01 m/s)
        assert fx == pytest.approx(force, abs=1e-6 * a * MASS)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_brake_ramp_below_the_tyre_limit(engine):
    """Capacity 0.4 g (mu 0.8): the wheels keep rolling, deceleration ramps to 0.4 g after the delay."""
    a = 0.4 * G
    cap = a * MASS / 2  # per axle: two axles
    brakes = AirBrakes({"car": BrakeUnit((cap,), "tractor", delay=0.3, rise=0.5)})
    res, opts = _run(engine, brakes)
    d, t = ramp_stopping_distance(20.0, a, 0.3, 0.5)
    _check(res, opts, d, t, a)
    assert not any(np.any(w.sliding) for w in res.wheels.values())


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_out_of_adjustment_scales_the_capacity(engine):
    a = 0.4 * G
    cap = a * MASS / 2 / 0.75
    brakes = AirBrakes({"car": BrakeUnit((cap,), "tractor", delay=0.2, rise=0.4, out_of_adjustment=0.25)})
    res, opts = _run(engine, brakes)
    d, t = ramp_stopping_distance(20.0, a, 0.2, 0.4)
    _check(res, opts, d, t, a)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_capacity_above_the_limit_locks_the_wheels(engine):
    """Capacity 1.2 g on mu 0.6: the wheels lock when the ramp reaches mu N (at rise * 0.6 / 1.2) and slide."""
    mu = 0.6
    brakes = AirBrakes({"car": BrakeUnit((1.2 * G * MASS / 2,), "tractor", delay=0.25, rise=0.4)})
    res, opts = _run(engine, brakes, mu=mu)
    a = mu * G
    # sliding at mu g: the regularised friction mu N v / sqrt(v^2 + eps^2) differs from mu N by O(eps^2 / v^2)
    d, t = ramp_stopping_distance(20.0, a, 0.25, 0.4 * mu / 1.2)
    _check(res, opts, d, t, a)
    t_lock = 0.25 + 0.4 * mu / 1.2
    for w in res.wheels.values():
        assert not np.any(w.sliding[w.t < t_lock - 1e-6])
        assert np.all(w.sliding[(w.t > t_lock + 1e-3) & (w.t < t - 0.05)])
        # the skid mark: the path slid from the lock to rest
        # the skid mark: the path slid from the lock (after 20 t_lock - a T_r^2 / 6 of travel) to rest
        d_lock = 20.0 * t_lock - a * (0.4 * mu / 1.2) ** 2 / 6
        assert w.sliding_length == pytest.approx(d - d_lock, abs=0.01)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_abs_holds_eta_mu_and_leaves_no_mark(engine):
    mu, eta = 0.8, 0.85
    brakes = AirBrakes({"car": BrakeUnit((1.5 * G * MASS / 2,), "tractor", delay=0.25, rise=0.4, abs=True)},
                       abs_efficiency=eta)
    res, opts = _run(engine, brakes, mu=mu)
    a = eta * mu * G
    d, t = ramp_stopping_distance(20.0, a, 0.25, 0.4 * eta * mu / 1.5)
    # ABS holds eta mu N sqrt(u^2 + eps^2) / sqrt(u^2 + eps^2): exactly eta mu N on a straight stop
    _check(res, opts, d, t, a)
    assert not any(np.any(w.sliding) for w in res.wheels.values())


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_release_ramp(engine):
    """Brakes released at 1 s: the force falls to zero over the fall time; the car then rolls on freely (f_r = 0)."""
    a = 0.3 * G
    brakes = AirBrakes({"car": BrakeUnit((a * MASS / 2,), "tractor", delay=0.1, rise=0.2, release_delay=0.2,
                                         fall=0.3)}, release=1.0)
    opts = RunoutOptions(engine=engine, rtol=1e-9, atol=1e-11, t_max=3.0)
    res = simulate_runout(symmetric_car(), {"car": BodyState((0.0, 0.0), 0.0, (20.0, 0.0))}, WheelSettings(default=ROLL,
                          brakes=brakes), Road(0.8), opts)
    # speed lost: a times the area under the level: rise 0.2 s (half), full from 0.3 s to 1.2 s, fall 0.3 s (half)
    dv = a * (0.1 + 0.9 + 0.15)
    tab = res.table(times=[2.0, 3.0])
    for t in (0, 1):
        assert tab["car.vx [m/s]"][t] == pytest.approx(20.0 - dv, abs=GLOBAL * opts.rtol * 20.0 + 1e-6)


def test_trailer_lag_on_an_articulated_vehicle_engines_agree():
    """A tractor-semitrailer with default timing (trailer later than tractor) stops straight; both engines agree."""
    tyre = WheelSetting("rolling", cornering_coefficient=6.0, rolling_resistance=0.007)
    brakes = AirBrakes({"tractor": BrakeUnit((40e3, 100e3, 100e3), "tractor"),
                        "trailer": BrakeUnit((90e3,), "last_trailer")})
    veh = tractor_semitrailer()
    init = chain_states(veh, (0.0, 0.0), 0.0, (22.0, 0.0))
    rest = {}
    for engine in ("scipy", "compiled"):
        res = simulate_runout(veh, init, WheelSettings(default=tyre, brakes=brakes), Road(0.8),
                              RunoutOptions(engine=engine))
        assert res.status == "rest"
        rest[engine] = np.array([res.bodies[b].rest_position for b in ("tractor", "trailer")])
        assert np.all(np.abs(rest[engine][:, 1]) < 1e-6)
    assert np.max(np.abs(rest["scipy"] - rest["compiled"])) < 0.01


@pytest.mark.parametrize("abs_on, cap_g, expect_g", [(False, 0.4, 0.4), (False, 1.2, 0.8), (True, 1.5, 0.85 * 0.8)])
def test_energy_level_uses_the_full_application(abs_on, cap_g, expect_g):
    """The energy level brakes at the full application from separation: below the limit F/m, at it the wheels
    lock (mu g), with ABS eta mu g."""
    brakes = AirBrakes({"car": BrakeUnit((cap_g * G * MASS / 2,), "tractor", abs=abs_on)},
                       abs_efficiency=0.85 if abs_on else 0.0)
    res = simulate_level("energy", symmetric_car(), {"car": BodyState((0.0, 0.0), 0.0, (20.0, 0.0))},
                         WheelSettings(default=ROLL, brakes=brakes), Road(0.8))
    assert res.bodies["car"].rest_position[0] == pytest.approx(20.0 ** 2 / (2 * expect_g * G), rel=1e-12)
    assert "air brakes at full application" in res.message

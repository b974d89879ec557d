"""SciPy engine vs the pymunk cross-check (note sec. 4, sec. 5 item 11).

pymunk integrates the same tyre forces with a fixed-step semi-implicit Euler scheme and its own
iterative joint solver, so its error is first order in dt.  Tolerances:

* straight locked slide: the Euler position update ``x_{n+1} = x_n + v_n dt`` of a uniformly
  decelerating body overshoots the exact stopping distance by ``v0 dt / 2`` (sum of v_n dt over the
  slide), so the pymunk rest position must lie ``v0 dt / 2`` ahead, within a factor 2;
* other cases: a Richardson estimate.  With first-order error ``e(dt) ~ C dt``,
  ``|x(dt) - x(dt/2)| ~ C dt/2 ~ e(dt/2)``, so ``|x(dt/2) - x_scipy| <= 2 |x(dt) - x(dt/2)|`` (factor 2
  for the pre-asymptotic part) plus the reference's own tolerance;
* convergence: errors at dt = 4, 1, 0.25 ms strictly decrease, with a fitted order in [0.7, 1.4].
"""

from __future__ import annotations

import math
import os
import subprocess
import sys

import numpy as np
import pytest
from runout_cases import CAR_TYRE, TRUCK_TYRE, car, tractor_semitrailer

from crashsim.crosscheck import simulate_runout_pymunk
from crashsim.motion import (
    FrictionZone,
    Road,
    RunoutOptions,
    WheelSetting,
    WheelSettings,
    make_hitch_consistent,
    simulate_runout,
)
from crashsim.vehicles import BodyState, chain_states

REF = dict(rtol=1e-10, atol=1e-12)


def _rest_errors(res, ref):
    pos = max(math.dist(b.rest_position, ref.bodies[n].rest_position) for n, b in res.bodies.items())
    head = max(abs(b.rest_heading - ref.bodies[n].rest_heading) for n, b in res.bodies.items())
    return pos, head


def _richardson_check(vehicle, init, wheels, road, opts, dt):
    ref = simulate_runout(vehicle, init, wheels, road, RunoutOptions(**REF, eps=opts.eps, v_stop=opts.v_stop))
    coarse = simulate_runout_pymunk(vehicle, init, wheels, road, dt=dt, options=opts)
    fine = simulate_runout_pymunk(vehicle, init, wheels, road, dt=dt / 2, options=opts)
    assert ref.status == coarse.status == fine.status == "rest"
    step_pos, step_head = _rest_errors(coarse, fine)
    err_pos, err_head = _rest_errors(fine, ref)
    assert err_pos <= 2 * step_pos + 1e-6
    assert err_head <= 2 * step_head + 1e-6
    assert fine.t_end == pytest.approx(ref.t_end, abs=2 * abs(coarse.t_end - fine.t_end) + dt)
    return ref, fine


def test_pymunk_is_imported_lazily():
    """The numeric core and the cross-check package import without pymunk (fresh interpreter)."""
    code = "import sys, crashsim.motion, crashsim.crosscheck; assert 'pymunk' not in sys.modules"
    subprocess.run([sys.executable, "-c", code], check=True, env={**os.environ, "PYTHONPATH": os.pathsep.join(sys.path)})


def test_straight_locked_slide():
    v0, mu, dt = 15.0, 0.75, 1e-3
    init = {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}
    ref = simulate_runout(car(), init, None, Road(mu), RunoutOptions(**REF))
    pm = simulate_runout_pymunk(car(), init, None, Road(mu), dt=dt)
    overshoot = pm.bodies["car"].rest_position[0] - ref.bodies["car"].rest_position[0]
    assert 0.5 * (v0 * dt / 2) <= overshoot <= 2 * (v0 * dt / 2)
    assert abs(pm.bodies["car"].rest_position[1]) < 1e-9 and abs(pm.bodies["car"].rest_heading) < 1e-9
    assert pm.t_end == pytest.approx(ref.t_end, abs=2 * dt)


def test_spinning_car_with_mixed_wheels():
    wheels = WheelSettings(default=WheelSetting("rolling", **CAR_TYRE), wheels={"car/rear": WheelSetting("locked")})
    init = {"car": BodyState((0.0, 0.0), 0.0, (8.0, 2.0), 5.0)}
    ref, fine = _richardson_check(car(), init, wheels, Road(0.75), RunoutOptions(), 1e-3)
    assert abs(ref.bodies["car"].rest_heading) > 2.0  # it did spin


def test_tractor_semitrailer_with_mixed_wheels_crossing_a_zone():
    """Steer axle rolling, drive axles locked, trailer rolling, crossing a low-friction patch."""
    veh = tractor_semitrailer()
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.0, (12.0, 0.5), yaw_rates=[0.15, 0.0]))
    wheels = WheelSettings(
        default=WheelSetting("rolling", **TRUCK_TYRE),
        wheels={"tractor/1": WheelSetting("locked"), "tractor/2": WheelSetting("locked")},
    )
    patch = FrictionZone(((4.0, -6.0), (12.0, -6.0), (14.0, 0.0), (12.0, 6.0), (4.0, 6.0)), 0.35, "wet patch")
    road = Road(0.75, (patch,))
    ref, fine = _richardson_check(veh, init, wheels, road, RunoutOptions(), 1e-3)
    assert any(e.kind == "zone_enter" for e in ref.events) and any(e.kind == "zone_exit" for e in ref.events)
    # the hitch forces agree as well (pymunk: from momentum change; scipy: the multiplier)
    assert fine.hitches[0].peak_force == pytest.approx(ref.hitches[0].peak_force, rel=0.05)
    assert fine.max_hitch_gap < 1e-3


def test_first_order_convergence():
    wheels = WheelSettings(default=WheelSetting("rolling", **CAR_TYRE), wheels={"car/rear": WheelSetting("locked")})
    init = {"car": BodyState((0.0, 0.0), 0.0, (8.0, 2.0), 5.0)}
    # eps >= mu g dt and v_stop >= 2 mu g dt at the coarsest step (4 ms) keep the friction chatter-free
    opts = RunoutOptions(eps=0.03, v_stop=0.06)
    ref = simulate_runout(car(), init, wheels, Road(0.75), RunoutOptions(**REF, eps=opts.eps, v_stop=opts.v_stop))
    dts = np.array([4e-3, 1e-3, 0.25e-3])
    errors = np.array(
        [_rest_errors(simulate_runout_pymunk(car(), init, wheels, Road(0.75), dt=dt, options=opts), ref)[0] for dt in dts]
    )
    assert np.all(np.diff(errors) < 0)
    order = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert 0.7 <= order <= 1.4


def test_c_dolly_with_a_self_steering_axle_against_pymunk():
    """A double on a C-dolly (yaw lock: a pymunk GearJoint) whose axle steers itself within 25 deg:
    pymunk converges on the same rest, first order, and keeps the dolly aligned with its trailer."""
    from crashsim.vehicles import Axle, Body, Hitch, Vehicle

    truck = Body("truck", 9000.0, 30000.0, axles=(Axle(2.2, 2.05), Axle(-2.4, 1.85, True)))
    lead = Body("lead", 8000.0, 60000.0, axles=(Axle(-2.5, 1.85, True),))
    dolly = Body("dolly", 1500.0, 1200.0, axles=(Axle(0.1, 1.85, True),))
    second = Body("second", 9000.0, 55000.0, axles=(Axle(-3.0, 1.85, True),))
    veh = Vehicle("D", (truck, lead, dolly, second), (Hitch((-3.2, 0.0), (3.5, 0.0)),
                                                     Hitch((-4.2, 0.0), (2.3, 0.0), yaw_locked=True),
                                                     Hitch((0.15, 0.0), (3.6, 0.0), 1.5)))
    init = make_hitch_consistent(veh, chain_states(veh, (0.0, 0.0), 0.0, (11.0, 0.8), yaw_rates=[0.1, -0.2, -0.2, 0.3],
                                                   articulation=[0.1, 0.0, -0.15]))
    wheels = WheelSettings(default=WheelSetting("braked", brake=0.5, **TRUCK_TYRE),
                           wheels={"dolly": WheelSetting("rolling", self_steer_limit=math.radians(25), **TRUCK_TYRE)})
    ref, fine = _richardson_check(veh, init, wheels, Road(0.75), RunoutOptions(), 1e-3)
    assert abs(fine.bodies["lead"].rest_heading - fine.bodies["dolly"].rest_heading) < 1e-3

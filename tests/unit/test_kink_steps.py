"""The compiled integrator aims a rejected step at a switch of the tyre law (kernels.integrator.kink_fraction).

Where a wheel's force law switches branch (saturation, lock-up, the ABS limit, lift) the force is
continuous but its slope is not; a step across such a switch fails the error control until it is
small.  A rejected step whose start and end lie on the two sides of a switch is retried up to the
switch, placed on the straight line between the margins at its ends.
"""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "analytic"))
from runout_cases import GLOBAL, tractor_semitrailer  # noqa: E402

from crashsim.motion import Road, RunoutOptions, simulate_runout  # noqa: E402
from crashsim.motion.brakes import AirBrakes, BrakeUnit  # noqa: E402
from crashsim.motion.kernels import arrays as A  # noqa: E402
from crashsim.motion.kernels import integrator  # noqa: E402
from crashsim.motion.wheels import WheelSetting, WheelSettings  # noqa: E402
from crashsim.vehicles import chain_states  # noqa: E402

kink_fraction = getattr(integrator.kink_fraction, "py_func", integrator.kink_fraction)
NM = A.W_M1 - A.W_M0


def _ends(start, end):
    """The tyres' evaluation at a step's start (nw, N_W) and the margins at its end (nw, NM), from rows
    of (sat, lock, abs, lift)."""
    m1 = np.array(end, dtype=float)
    wk = np.zeros((m1.shape[0], A.N_W))
    wk[:, A.W_M0:A.W_M1] = np.array(start, dtype=float)
    return wk, m1


def test_a_crossing_is_placed_on_the_line_between_the_margins():
    nan = math.nan
    m0, wk = _ends([[nan, nan, -30.0, nan]], [[nan, nan, 10.0, nan]])  # the ABS limit takes hold
    assert kink_fraction(m0, wk) == pytest.approx(0.75)
    m0, wk = _ends([[nan, nan, nan, 5.0]], [[nan, nan, nan, -15.0]])  # a lifted wheel lands
    assert kink_fraction(m0, wk) == pytest.approx(0.25)


def test_the_earliest_crossing_of_all_wheels_counts():
    nan = math.nan
    m0, wk = _ends([[-1.0, -5.0, nan, -9.0], [-2.0, -5.0, nan, -9.0]], [[3.0, -5.0, nan, -9.0], [2.0, -5.0, nan, -9.0]])
    assert kink_fraction(m0, wk) == pytest.approx(0.25)


def test_no_crossing_nan_or_a_crossing_at_an_end_is_not_aimed_at():
    nan = math.nan
    assert kink_fraction(*_ends([[-1.0, -1.0, -1.0, -1.0]], [[-2.0, -0.5, -3.0, -1.0]])) == -1.0
    assert kink_fraction(*_ends([[nan, nan, nan, nan]], [[1.0, 1.0, 1.0, 1.0]])) == -1.0
    # the switch at 1 % of the step: the step is not spoilt by it (KINK_MIN)
    assert kink_fraction(*_ends([[nan, nan, -1.0, nan]], [[nan, nan, 99.0, nan]])) == -1.0
    assert kink_fraction(*_ends([[nan, nan, -99.0, nan]], [[nan, nan, 1.0, nan]])) == -1.0


def test_the_lock_up_counts_only_for_a_saturated_wheel():
    # the braked wheel's demand passes the locked wheel's longitudinal force while its lateral demand is
    # inside the circle: no switch of the force law (it locks only saturated)
    assert kink_fraction(*_ends([[-50.0, -10.0, math.nan, -1.0]], [[-40.0, 10.0, math.nan, -1.0]])) == -1.0
    assert kink_fraction(*_ends([[5.0, -10.0, math.nan, -1.0]], [[6.0, 10.0, math.nan, -1.0]])) == pytest.approx(0.5)


def test_braking_into_lock_with_abs_and_load_transfer_stays_accurate():
    """The air-brake benchmark's all-on run (tractor ABS limits, trailer wheels locking during the ramp, a
    sloped road, load transfer): the compiled engine, whose steps are aimed at those switches, against a
    reference at rtol 1e-11: the rest positions agree within the global error allowance of the analytic
    tests (``GLOBAL`` rtol times the distance travelled), as the SciPy engine's do (it cannot aim its steps)."""
    veh = tractor_semitrailer()
    veh = replace(veh, bodies=tuple(replace(b, cg_height=h) for b, h in zip(veh.bodies, (1.1, 1.6))))
    init = chain_states(veh, (0.0, 0.0), 0.0, (22.0, 1.0), yaw_rates=(0.2, 0.0))
    brakes = AirBrakes({"tractor": BrakeUnit((40e3, 100e3, 100e3), "tractor", abs=True),
                        "trailer": BrakeUnit((90e3,), "last_trailer")}, abs_efficiency=0.85)
    tyre = WheelSetting("rolling", cornering_coefficient=6.0, rolling_resistance=0.007)
    ws = WheelSettings(default=tyre, brakes=brakes)
    road = Road(0.8, grade=-0.04, cross_slope=0.02)
    rest, dist = {}, 0.0
    for engine, rtol in (("compiled", 1e-8), ("compiled", 1e-11), ("scipy", 1e-8)):
        res = simulate_runout(veh, init, ws, road, RunoutOptions(engine=engine, rtol=rtol, atol=rtol * 1e-2,
                                                                   load_transfer=True, rollover=True))
        assert res.status == "rest"
        assert any(w.sliding_length > 0 for k, w in res.wheels.items() if k.startswith("trailer"))  # locked
        rest[engine, rtol] = np.array([res.bodies[b].rest_position for b in ("tractor", "trailer")])
        dist = max(dist, res.bodies["tractor"].distance)
    ref = rest["compiled", 1e-11]
    bound = GLOBAL * 1e-8 * dist  # 2e-5 m on the tractor's 40 m
    assert np.max(np.abs(rest["compiled", 1e-8] - ref)) < bound
    assert np.max(np.abs(rest["scipy", 1e-8] - ref)) < bound

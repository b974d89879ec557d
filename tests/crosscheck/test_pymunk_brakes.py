"""pymunk cross-check with air brakes: the brake force follows the time there too (the state's clock).

A straight stop of a symmetric car whose brakes build after a delay along a linear ramp to 0.4 g:
pymunk (first-order, dt = 1 ms and 0.5 ms) stops within its O(dt) error of the closed form
(:func:`crashsim.motion.brakes.ramp_stopping_distance`) and of the SciPy engine; halving dt
halves its error.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "analytic"))
from runout_cases import G, symmetric_car  # noqa: E402

from crashsim.motion import Road, RunoutOptions, simulate_runout  # noqa: E402
from crashsim.motion.brakes import AirBrakes, BrakeUnit, ramp_stopping_distance  # noqa: E402
from crashsim.motion.wheels import WheelSetting, WheelSettings  # noqa: E402
from crashsim.vehicles import BodyState  # noqa: E402

pytest.importorskip("pymunk")
from crashsim.crosscheck.pymunk_runout import simulate_runout_pymunk  # noqa: E402


def test_pymunk_brake_ramp_converges_to_the_closed_form():
    ws = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0),
                       brakes=AirBrakes({"car": BrakeUnit((0.4 * G * 1500 / 2,), "tractor", delay=0.3, rise=0.5)}))
    init = {"car": BodyState((0.0, 0.0), 0.0, (20.0, 0.0))}
    d, _ = ramp_stopping_distance(20.0, 0.4 * G, 0.3, 0.5)
    ref = simulate_runout(symmetric_car(), init, ws, Road(0.8), RunoutOptions()).bodies["car"].rest_position[0]
    assert ref == pytest.approx(d, abs=1e-3)
    err = {}
    for dt in (0.001, 0.0005):
        r = simulate_runout_pymunk(symmetric_car(), init, ws, Road(0.8), options=RunoutOptions(), dt=dt)
        err[dt] = r.bodies["car"].rest_position[0] - d
    assert abs(err[0.001]) < 0.05
    assert err[0.0005] == pytest.approx(err[0.001] / 2, rel=0.3)

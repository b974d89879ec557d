"""The NumPy kinematics kept outside the runs (README "Architecture": why) agree with the compiled
geometry of the kernels, to round-off."""

from __future__ import annotations

import numpy as np

from crashsim.motion import Road, RunoutOptions, WheelSettings, simulate_runout
from crashsim.motion.hitches import RunoutModel
from crashsim.vehicles import Axle, Body, Hitch, Vehicle, chain_states


def test_wheel_positions_match_the_kernels_sampled_tracks():
    tractor = Body("tractor", 8000.0, 32000.0, length=6.0,
                   axles=(Axle(1.9, 2.05), Axle(-1.6, 1.85, True), Axle(-2.9, 1.85, True)))
    trailer = Body("trailer", 25000.0, 330000.0, length=13.6,
                   axles=(Axle(-3.0, 1.85, True), Axle(-4.3, 1.85, True)))
    ts = Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0)),))
    start = chain_states(ts, (0.0, 0.0), 0.3, (12.0, 4.0), (0.6, 0.2))
    opts = RunoutOptions(engine="compiled")
    res = simulate_runout(ts, start, None, Road(0.7), opts)
    model = RunoutModel(ts, WheelSettings.all_locked().resolve(ts), Road(0.7), opts)
    t = res.bodies["tractor"].history.t
    Y = np.asarray(res.sol(t))
    assert len(t) > 10
    for j in range(0, len(t), 5):
        pos = model.wheel_positions(Y[:, j])  # NumPy
        for k, spec in enumerate(model.specs):  # the kernels' positions (samples.evaluate_samples)
            assert np.allclose(pos[k], res.wheels[spec.key].points[j], rtol=0, atol=1e-9)

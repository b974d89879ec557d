"""A locked slide crossing from mu1 to mu2 at a known line (friction zones located by events).

With static loads in moment balance about the CG (sum N_k x_k = 0), the friction work done while the
axles straddle the line equals that of a sharp change at the CG, so the ideal rest position is

    d = x0 + (v^2 - 2 mu1 g x0) / (2 mu2 g)

and, for the regularised law stopped at v_stop, ``v^2/2`` is replaced by
``integral_{v_stop}^{v0} sqrt(v^2 + eps^2) dv`` exactly (see ``runout_cases.regularised_slide``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import GLOBAL, G, car, regularised_work

from crashsim.motion import FrictionZone, Road, RunoutOptions, simulate_runout
from crashsim.vehicles import BodyState


@pytest.mark.parametrize("mu1, mu2", [(0.8, 0.4), (0.3, 0.9)])
def test_locked_slide_across_a_friction_line(mu1, mu2):
    v0, x0 = 15.0, 6.0
    # zone: everything beyond x = x0 (a non-convex polygon, to exercise the general inside test)
    notched = ((x0, -50.0), (500.0, -50.0), (500.0, 50.0), (x0, 50.0), (x0, 30.0), (x0 + 20.0, 20.0), (x0, 10.0))
    zone = FrictionZone(notched, mu2)
    opts = RunoutOptions(rtol=1e-9, atol=1e-11)
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None, Road(mu1, (zone,)), opts)
    assert res.status == "rest"
    x_end = res.bodies["car"].rest_position[0]
    expected = x0 + (regularised_work(v0, opts.v_stop, opts.eps) - mu1 * G * x0) / (mu2 * G)
    assert x_end == pytest.approx(expected, abs=GLOBAL * opts.rtol * expected)
    ideal = x0 + (v0**2 - 2 * mu1 * G * x0) / (2 * mu2 * G)
    assert abs(x_end - ideal) <= abs(expected - ideal) + GLOBAL * opts.rtol * expected
    assert abs(expected - ideal) < opts.v_stop**2 / (2 * mu2 * G) + 1e-3  # the regularisation is a small effect

    # every wheel crossed exactly once, at the line, located by the event (not by step-size luck)
    enters = [e for e in res.events if e.kind == "zone_enter"]
    assert len(enters) == len(res.wheels)
    for e in enters:
        key = e.detail.split()[1]
        track = res.wheels[key]
        axle = car().bodies[0].axles[track.axle_index]
        x, _, psi = res.bodies["car"].sol(e.t)[:3]
        assert x + math.cos(psi) * axle.x == pytest.approx(x0, abs=1e-9)
    assert not [e for e in res.events if e.kind == "zone_exit"]


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_a_thin_strip_is_not_stepped_over_whatever_the_step(engine):
    """A 0.3 m strip of low friction (a painted line) crossed at 15 m/s.  Each wheel enters and
    leaves (two events per wheel) and the car slides farther by exactly width (mu - mu_strip)/mu.
    A solver step that could carry a wheel across the strip and back is searched on its dense
    output at points no further apart than the zone resolution (2 cm), so the strip is found with a
    0.01 s step and with a 0.1 s step alike (it used to be stepped over at 0.1 s)."""
    strip = FrictionZone(((10.0, -5.0), (10.3, -5.0), (10.3, 5.0), (10.0, 5.0)), 0.1, "paint")
    start = {"car": BodyState((0.0, 0.0), 0.0, (15.0, 0.0))}
    res = simulate_runout(car(), start, None, Road(0.8, (strip,)), RunoutOptions(max_step=0.01, engine=engine))
    kinds = [e.kind for e in res.events]
    assert kinds.count("zone_enter") == 4 and kinds.count("zone_exit") == 4
    assert "zone_missed" not in kinds
    plain = simulate_runout(car(), start, None, Road(0.8))
    extra = res.bodies["car"].rest_position[0] - plain.bodies["car"].rest_position[0]
    assert extra == pytest.approx(0.3 * (0.8 - 0.1) / 0.8, rel=1e-3)
    assert np.all(np.diff([e.t for e in res.events]) >= 0)

    coarse = simulate_runout(car(), start, None, Road(0.8, (strip,)), RunoutOptions(max_step=0.1, engine=engine))
    kinds = [e.kind for e in coarse.events]
    assert kinds.count("zone_enter") == 4 and kinds.count("zone_exit") == 4 and "zone_missed" not in kinds
    assert coarse.bodies["car"].rest_position[0] == pytest.approx(res.bodies["car"].rest_position[0], abs=1e-4)

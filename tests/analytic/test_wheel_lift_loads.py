"""Wheel loads where load transfer lifts wheels: the lifted wheels carry nothing, the others the weight.

* A box on a 1.5 m track with its CG 1.5 m high (static stability factor t / (2 h) = 0.5), knocked
  sideways to 17.45 m/s on locked wheels with f = 0.6: the road's friction (0.6 g) exceeds the
  threshold, so its inner wheels lift at once and it slides on its outer wheels.  Those carry the
  whole weight, so the friction is f m g and it stops in ``v^2 / (2 f g)`` = 25.87 m, the distance
  of any locked slide.  (Clamping the inner loads at zero while the outer wheels keep the linear
  share gives 1.25 m g of normal load here and 20.71 m: a stop shorter than the road allows.)
* At every sample of that run, and of a tall box sliding sideways down a cross-slope, the loads sum
  to the weight's normal component, and the lifted wheels carry exactly zero and leave no mark.
* A body whose axles have different tracks: the narrower axle's inner wheel lifts first and the
  roll moment it cannot carry goes to the wider axle, so the body's loads balance its roll moment
  until every inner wheel is off the ground.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import GLOBAL, G

from crashsim.motion import Road, RunoutOptions, simulate_runout
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

M, TRACK, H, F = 1800.0, 1.5, 1.5, 0.6


def _box(tracks=(TRACK, TRACK), height=H):
    body = Body("box", M, 2500.0, length=4.0, width=max(tracks) + 0.1,
                axles=(Axle(1.5, tracks[0], name="front"), Axle(-1.5, tracks[1], name="rear")), cg_height=height)
    return Vehicle("box", (body,))


def _run(engine, velocity=(0.0, 17.45), road=Road(F), tracks=(TRACK, TRACK), height=H, rtol=1e-9):
    opts = RunoutOptions(engine=engine, rtol=rtol, atol=rtol / 100, load_transfer=True, rollover=True, sample_dt=0.01)
    return simulate_runout(_box(tracks, height), {"box": BodyState((0.0, 0.0), 0.0, velocity, 0.0)}, None, road, opts)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_a_lifted_box_stops_in_the_locked_slide_distance(engine):
    v = 17.45
    res = _run(engine)
    assert res.status == "rest"
    d = math.dist(res.bodies["box"].rest_position, (0.0, 0.0))
    expect = v * v / (2 * F * G)
    assert d == pytest.approx(expect, abs=GLOBAL * 1e-9 * expect + 1e-3)  # + the rest threshold's creep
    kinds = {e.kind for e in res.events}
    assert "unit_lift" in kinds  # the planar result is outside its validity from here, and says so


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_loads_sum_to_the_weight_and_lifted_wheels_do_nothing(engine):
    res = _run(engine)
    tracks = list(res.wheels.values())
    total = np.sum([w.load for w in tracks], axis=0)
    moving = np.hypot(*np.array([res.bodies["box"].history.vx, res.bodies["box"].history.vy])) > 0.5
    assert total[moving] == pytest.approx(M * G, rel=1e-12)
    lifted = [w for w in tracks if w.side == "right"]  # moving to +y (left): the right wheels are inner
    for w in lifted:
        late = w.t > 0.5  # the load-transfer filter (tau 0.2 s) has settled
        assert np.all(w.load[late & moving] == 0.0)
        assert not np.any(w.sliding[late & moving])  # no mark
    for w in tracks:
        if w.side == "left":
            assert np.all(w.load[moving & (w.t > 0.5)] == pytest.approx(M * G / 2, rel=1e-12))


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_a_unit_sliding_down_a_slope_on_its_downhill_wheels(engine):
    """A box 2.8 m high (t / (2 h) = 0.27) knocked sideways down a 30 % cross-slope: the friction up the
    slope (f g cos theta, f = 1) exceeds its threshold, the uphill wheels lift, and the downhill ones
    carry the weight's normal component m g cos(theta) while it slides."""
    slope, h = 0.3, 2.8
    theta = math.atan(slope)
    res = _run(engine, velocity=(0.0, -8.0), road=Road(1.0, cross_slope=slope), height=h)
    tracks = list(res.wheels.values())
    total = np.sum([w.load for w in tracks], axis=0)
    hist = res.bodies["box"].history
    sel = (np.hypot(hist.vx, hist.vy) > 0.5) & (tracks[0].t > 0.5)
    assert sel.sum() > 10
    assert total[sel] == pytest.approx(M * G * math.cos(theta), rel=1e-9)
    up = [w for w in tracks if np.all(w.load[sel] == 0.0)]
    assert sorted(w.side for w in up) == ["left", "left"]  # +y is uphill: the left wheels (heading 0)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_the_narrow_axle_passes_its_roll_moment_to_the_wide_one(engine):
    """Tracks 1.2 m (front) and 1.8 m (rear), CG 1.15 m high, sliding sideways at f g = 0.6 g: the
    front axle alone can carry at most N t / 2 = 0.3 m g of roll moment against its share 0.345 m g, the
    body 0.75 m g against 0.69 m g.  So the front inner wheel lifts, the rear inner one still carries
    load, and the loads balance the roll moment: sum over the axles of (N_outer - N_inner) t / 2 =
    m a_y h with m a_y the friction f m g (once the load-transfer filter, tau 0.2 s, has settled)."""
    h = 1.15
    res = _run(engine, tracks=(1.2, 1.8), height=h)
    w = res.wheels
    t = w["box/0/left"].t
    sel = (t > 2.0) & (t < 2.6)
    assert sel.sum() > 10
    moment = ((w["box/0/left"].load - w["box/0/right"].load) * 1.2 / 2
              + (w["box/1/left"].load - w["box/1/right"].load) * 1.8 / 2)[sel]
    assert np.all(w["box/0/right"].load[sel] == 0.0)
    assert np.all(w["box/1/right"].load[sel] > 0.05 * M * G / 2)
    assert moment == pytest.approx(M * F * G * h, rel=1e-3)

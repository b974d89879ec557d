"""Validation (qualitative): the tractor-semitrailer barrier glance says its planar result is outside its
validity while the trailer is at the barrier.

Full-scale barrier tests of loaded tractor-trailers at about 80 km/h and 15 deg (NCHRP Report 350 test
5-12 and MASH test level 5; MASH test level 6 with a tank trailer) show the trailer rolling toward the
barrier as its rear swings in, in some tests onto or over the barrier's top (``docs/validation/
barrier-rollover.md`` gives the sources and what they publish). No public text found gives the time
history of the trailer's roll, so the time is not compared: what is checked is that crashsim, on the
shipped configuration of that test with the wheel-lift and rollover check on, declares the trailer
rolling (all the inner wheels of the trailer off the ground, or the trailer past its rollover threshold)
before the combination has left the barrier, on both engines, at the same time. On this configuration
(fifth wheel free in roll) the trailer's inner wheels all lift about 0.2 s after the slap, and its lateral
acceleration then comes within 1 % of its default threshold without passing it: since a lifted
unit's wheels carry its weight and no more, the outer wheels' side forces are smaller than they were
when the unclamped loads on them summed to more than the weight.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import crashsim
from crashsim.units import G0

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "barrier_glance_15deg.toml"


def _run(engine, tmp):
    path = tmp / f"glance_roll_{engine}.toml"
    text = SCENE.read_text().replace("[runout]\n", f'[runout]\nengine = "{engine}"\nlevel = "load_transfer"\n'
                                     "rollover = true\n", 1)
    path.write_text(text)
    return crashsim.run(path)


@pytest.fixture(scope="module")
def scenes(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("glance_roll")
    return {e: _run(e, tmp) for e in ("scipy", "compiled")}


def _first(scene, kind, body):
    return min((e for e in scene.joint.events if e.kind == kind and e.data.get("body") == body), key=lambda e: e.t)


def _rolled(scene, body):
    kinds = ("unit_lift", "rollover_threshold")
    return min((e for e in scene.joint.events if e.kind in kinds and e.data.get("body") == body), key=lambda e: e.t)


def test_the_trailer_is_declared_rolling_before_the_truck_leaves_the_barrier(scenes):
    for scene in scenes.values():
        rolled = _rolled(scene, "trailer")
        slaps = [i.t for i in scene.joint.impacts if i.body1 == "trailer"]
        left = max(e.t for e in scene.joint.events if e.kind == "contact_end" and "trailer" in e.detail)
        assert slaps and min(slaps) < rolled.t < left
        roll = scene.runout["truck"].rollover
        assert roll["rolled"] and "trailer" in roll["rolled_bodies"]
        assert roll["valid_until_s"] <= rolled.t
        j = scene.joint
        t = np.linspace(0.0, left, 4001)
        ay = np.asarray(j.sol(t))[j.layout.accel][j.layout.n_bodies + 1] / G0  # the trailer's a_y [g]
        thr = roll["thresholds_g"]["trailer"]
        assert 0.95 * thr < float(np.abs(ay).max())  # the threshold check, marginal here, is close
    a, b = (_rolled(s, "trailer") for s in scenes.values())
    assert a.kind == b.kind and a.t == pytest.approx(b.t, abs=1e-3)


def test_with_a_roll_coupled_fifth_wheel_the_verdict_is_marginal(tmp_path):
    """The same scene with the semitrailer's fifth wheel stiff in roll (``roll_coupled``): the tyre loads, and
    so the run-out, change, and the trailer's peak lateral acceleration comes within a few percent of its
    threshold (1.0 % below it here): the verdict on this configuration is marginal, and depends on the
    coupling model; the docs say so."""
    path = tmp_path / "glance_coupled.toml"
    text = SCENE.read_text().replace("[runout]\n", '[runout]\nengine = "compiled"\nlevel = "load_transfer"\n'
                                     "rollover = true\n", 1)
    text = text.replace('cg_height = "1.80 m"\n', 'cg_height = "1.80 m"\nroll_coupled = true\n', 1)
    path.write_text(text)
    scene = crashsim.run(path)
    roll = scene.runout["truck"].rollover
    j = scene.joint
    t = np.linspace(0.0, 3.0, 3001)
    nb = j.layout.n_bodies  # filtered accelerations: a_x of every body, then a_y; the trailer is body 1
    ay = np.asarray(j.sol(t))[j.layout.accel][nb + 1] / G0  # [g]
    peak = float(np.abs(ay).max())
    thr = roll["thresholds_g"]["trailer"]
    assert 0.9 * thr < peak < thr and "trailer" not in roll["rolled_bodies"]

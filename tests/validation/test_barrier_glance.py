"""Validation: a loaded tractor-semitrailer glancing off a rigid barrier at 80 km/h and 15 deg.

The configuration of the full-scale barrier test of a tractor-trailer (NCHRP Report 350, test
5-12: a 36,000 kg tractor-van trailer at 80 km/h and 15 deg; the same test in AASHTO's MASH);
``scenarios/scenes/barrier_glance_15deg.toml`` states the vehicle and coefficients, which are
typical values, not one test's data.  What such tests publish, and what is checked here on both
engines:

1. the tractor's front corner strikes first (the scene's impact);
2. the barrier redirects the tractor: it runs along the face within a few degrees;
3. the trailer's rear swings in and slaps the barrier (a later impact of the trailer, at a point
   behind its CG), solved as an impulse with friction (no frictionless fallback);
4. the combination leaves the barrier and does not come back, at an exit angle below 60 % of
   the impact angle (NCHRP 350's evaluation criterion M, measured when contact is lost).

What this does not show: the test's accelerations, roll and the barrier's damage (a planar
rigid-body model has none), nor agreement with one measured trajectory.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import crashsim

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "barrier_glance_15deg.toml"
IMPACT_ANGLE = 15.0  # deg


def _run(engine, tmp):
    path = tmp / f"glance_{engine}.toml"
    path.write_text(SCENE.read_text().replace("[runout]\n", f"[runout]\nengine = \"{engine}\"\n"))
    return crashsim.run(path)


@pytest.fixture(scope="module", params=["scipy", "compiled"])
def scene(request, tmp_path_factory):
    return _run(request.param, tmp_path_factory.mktemp("glance"))


def _state(scene, body, t):
    h = scene.runout["truck"].bodies[body].history
    i = int(np.clip(np.searchsorted(h.t, t), 0, len(h.t) - 1))
    return h, i


def test_the_tractor_corner_strikes_first_and_is_redirected(scene):
    assert (scene.impact.body1, scene.impact.body2) == ("tractor", "barrier")
    slaps = [i for i in scene.joint.impacts if i.body1 == "trailer"]
    h, i = _state(scene, "tractor", slaps[-1].t)
    assert abs(math.degrees(h.heading[i])) < 3.0  # running along the face when the trailer slaps


def test_the_trailer_slaps_the_barrier_with_friction(scene):
    slaps = [i for i in scene.joint.impacts if (i.body1, i.body2) == ("trailer", "barrier")]
    assert slaps
    rear = []
    for s in slaps:
        h, i = _state(scene, "trailer", s.t)
        c, sn = math.cos(h.heading[i]), math.sin(h.heading[i])
        rear.append(c * (s.point[0] - h.x[i]) + sn * (s.point[1] - h.y[i]) < 0.0)  # behind the trailer CG
        assert s.law == "friction" and abs(s.tangential_impulse) > 0
    assert any(rear)


def test_the_combination_leaves_below_60_percent_of_the_impact_angle(scene):
    events = [e for e in scene.joint.events if "barrier" in e.detail and e.kind in ("contact_end", "contact", "impact")]
    last = events[-1]
    assert last.kind == "contact_end"  # nothing touches the barrier after the last separation
    for body in ("tractor", "trailer"):
        h, i = _state(scene, body, last.t)
        exit_angle = math.degrees(math.atan2(h.vy[i], h.vx[i]))  # the face runs along +x, the truck above it
        assert 0.0 <= exit_angle < 0.6 * IMPACT_ANGLE, (body, exit_angle)
    pairs = {p.name: p for p in scene.joint.pairs}
    for body in ("tractor", "trailer"):
        assert pairs[f"{body}|barrier"].max_closing < 0.5  # every re-strike was an impact


def test_both_engines_report_the_same_sequence(tmp_path):
    runs = [_run(e, tmp_path) for e in ("scipy", "compiled")]
    assert [r.runout["truck"].method.split("/")[0] for r in runs] == ["scipy", "compiled"]
    seq = [[(i.body1, i.body2, i.t) for i in r.joint.impacts] for r in runs]
    assert [s[:2] for s in seq[0]] == [s[:2] for s in seq[1]]
    assert all(abs(a[2] - b[2]) <= 1e-3 for a, b in zip(*seq))

"""Vehicles that tangle: several bodies touching at once run to rest, and no contact makes energy.

* The two scenes of a user's report (``tests/regression/``): a tractor-semitrailer tangled with a
  pickup and its trailer (it chattered through 100 impulses, one pair after another, to the event
  limit, far from rest), and a tractor with two trailers whose first trailer lies 1.44 m deep in a
  car at separation (the contact then put 1.25 MJ into a scene of 0.79 MJ).  Both run to rest on
  both engines, with the same impact events, every line of the energy ledger >= 0 and no point in
  contact closing at the impulse threshold outside an impact.
* Three equal boxes in a row, the first striking the other two that touch: one impact event of both
  pairs at one instant, at e = 0 all three moving on at v/3, at e = 1 at (0, 0, v), Newton's cradle.
* A box between two walls rammed by a third body reaches rest with a bounded number of impacts.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim.motion import ContactModel, Obstacle, Road, RunoutOptions, simulate_scene
from crashsim.motion.wheels import WheelSetting, WheelSettings
from crashsim.scenario import load_scenario
from crashsim.scene.run import run_scene
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

HERE = Path(__file__).resolve().parent
TANGLES = [HERE.parent / "regression" / f"{n}.toml" for n in ("tangle_event_limit", "deep_crush_creates_energy")]
ENGINES = ("scipy", "compiled")
LINES = ("impacts", "tyres", "stops", "contacts", "final")


def _scene(path, engine):
    sc = load_scenario(path)
    opts = dataclasses.replace(sc.runout.options, engine=engine, max_wall_time=120.0)
    return run_scene(dataclasses.replace(sc, runout=dataclasses.replace(sc.runout, options=opts)))


@pytest.mark.parametrize("path", TANGLES, ids=[p.stem for p in TANGLES])
def test_the_reported_tangles_run_to_rest_and_make_no_energy(path):
    runs = {e: _scene(path, e).joint for e in ENGINES}
    for engine, j in runs.items():
        assert j.status == "rest", (engine, j.status, j.message)
        e = j.energy
        for line in LINES:
            assert e[line] >= -1e-6 * e["initial"], (engine, line, e)
        assert abs(e["closing_error"]) <= 1e-6 * e["initial"]
        for p in j.pairs:
            assert p.max_closing < ContactModel().velocity_threshold, (engine, p.name, p.max_closing)
        assert len({m.t for m in j.impacts}) < 40  # instants solved: no chatter
    a, b = (runs[e].impact_events() for e in ENGINES)
    assert [ev.pairs for ev in a] == [ev.pairs for ev in b]
    assert [ev.t for ev in a] == pytest.approx([ev.t for ev in b], abs=1e-3)


def _box(name, x, v, mass=1000.0, length=2.0, width=1.0):
    body = Body(name, mass, mass * (length**2 + width**2) / 12, length, width,
                axles=(Axle(0.6, 0.8), Axle(-0.6, 0.8)))
    return Vehicle(name, (body,)), BodyState((x, 0.0), 0.0, (v, 0.0))


FREE = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("e", [0.0, 1.0])
def test_newtons_cradle_in_a_run_out(engine, e):
    """Box b rolls into box c at 0.3 m/s (below the impulse threshold: sustained contact), which stands on
    locked wheels, and both come to rest pressed together; then box a strikes b at 5 m/s: one impact
    event of both pairs at one instant (frictionless contacts; tyre forces take no part in an impulse).  The strike a|b is solved first, then b|c, which it drives in,
    then every point at once: at e = 1 the pulse passes on (c leaves at a's speed, energy and momentum
    kept, as in Newton's cradle); at e = 0 all three move on at their mean velocity."""
    (va, sa), (vb, sb), (vc, sc) = _box("a", -4.0, 5.0), _box("b", 2.5, 0.3), _box("c", 4.6, 0.0)
    wheels = {"a": FREE, "b": FREE, "c": WheelSettings(default=WheelSetting("locked"))}
    run = simulate_scene([va, vb, vc], {"a": sa, "b": sb, "c": sc}, wheels, Road(0.7),
                         RunoutOptions(engine=engine, t_max=1.5),
                         contact=ContactModel(restitution=e, friction=0.0))
    assert [ev.kind for ev in run.events if ev.kind in ("contact", "impact")][:1] == ["contact"]  # b|c first
    (first, *_) = run.impact_events()
    assert set(first.pairs) == {"a|b", "b|c"} and first.instants == 1
    bodies = {}
    for r in first.records:
        bodies.update({n: b for n, b in r.result.bodies.items()})
    before = np.array([bodies[n].velocity_before[0] for n in "abc"])
    after = np.array([bodies[n].velocity[0] for n in "abc"])
    assert after.sum() == pytest.approx(before.sum(), abs=1e-9)  # momentum (equal masses)
    if e == 1.0:
        assert after[2] == pytest.approx(before[0], abs=1e-9)  # c leaves at a's speed
        assert (after**2).sum() == pytest.approx((before**2).sum(), rel=1e-9)  # energy kept
    else:
        assert after == pytest.approx(np.full(3, before.mean()), abs=1e-9)


def _wedged(engine):
    """A box 1.9 m wide, turned 4 deg, across a 2.2 m corridor between two walls (its corners 8 cm from
    them, beyond the arming distance), rammed along the corridor by a 2.5 t box at 8 m/s; both on locked
    wheels."""
    wall_l = Obstacle("left", ((-20.0, 1.25), (40.0, 1.25)), thickness=0.3)  # faces at y = +-1.1
    wall_r = Obstacle("right", ((-20.0, -1.25), (40.0, -1.25)), thickness=0.3)
    length, width = 2.0, 1.9
    body = Body("wedge", 900.0, 900.0 * (length**2 + width**2) / 12, length, width,
                axles=(Axle(0.6, 1.4), Axle(-0.6, 1.4)))
    rammer, s_r = _box("rammer", -4.0, 8.0, mass=2500.0, length=4.0, width=1.6)
    states = {"wedge": BodyState((0.0, 0.0), math.radians(4.0), (0.0, 0.0)), "rammer": s_r}
    locked = WheelSettings(default=WheelSetting("locked"))
    return simulate_scene([Vehicle("wedge", (body,)), rammer], states, {"wedge": locked, "rammer": locked}, Road(0.7),
                          RunoutOptions(engine=engine), obstacles=[wall_l, wall_r])


def test_a_box_between_two_walls_rammed_by_a_third_body_comes_to_rest():
    """The rammed box strikes both walls in turn, the rammer glances off one: every contact resolves,
    the impacts stay few, every ledger line is >= 0, no point closes at the threshold outside an
    impact, nothing passes through a wall, and both engines see the same impact events."""
    runs = {e: _wedged(e) for e in ENGINES}
    for engine, run in runs.items():
        assert run.status == "rest", (engine, run.message)
        assert len({m.t for m in run.impacts}) <= 30
        touched = {p.name for p in run.pairs if p.impacts or p.contact_time > 0}
        assert {"wedge|left", "wedge|right", "wedge|rammer"} <= touched, touched
        for line in LINES:
            assert run.energy[line] >= -1e-6 * run.energy["initial"], (line, run.energy)
        for p in run.pairs:
            assert p.max_closing < ContactModel().velocity_threshold, (p.name, p.max_closing)
        y = np.array([b.rest_position[1] for r in run.vehicles.values() for b in r.bodies.values()])
        assert np.all(np.abs(y) < 1.1)  # nothing went through a wall
    a, b = (runs[e].impact_events() for e in ENGINES)
    assert [ev.pairs for ev in a] == [ev.pairs for ev in b]
    assert [ev.t for ev in a] == pytest.approx([ev.t for ev in b], abs=1e-3)


@pytest.mark.parametrize("table, key, value, words", [
    ("contacts", "restitution", "-0.2", ("-0.2", "[0, 1]")),
    ("contacts", "friction", "-1.0", ("-1", "0")),
    ("contacts", "velocity_threshold", '"0 m/s"', ("0 m/s", "(0, 50] m/s")),
    ("contacts.pairs", "restitution", "1.5", ("1.5", "[0, 1]")),
])
def test_contact_settings_the_simultaneous_solve_cannot_use_are_refused(tmp_path, table, key, value, words):
    """A negative e or f, or a threshold of zero, refused in one message naming the file, the key as
    written, the value in the file's units and the range."""
    from crashsim.errors import ScenarioError

    text = TANGLES[0].read_text()
    if table == "contacts":
        text += f"\n[contacts]\n{key} = {value}\n"
    else:
        text += f'\n[[contacts.pairs]]\nfirst = "A"\nsecond = "B"\n{key} = {value}\n'
    path = tmp_path / "bad_contact.toml"
    path.write_text(text)
    with pytest.raises(ScenarioError) as info:
        load_scenario(path)
    msg = str(info.value)
    assert "bad_contact.toml" in msg and key in msg and len(msg.strip().splitlines()) == 1, msg
    for w in words:
        assert w in msg, (w, msg)

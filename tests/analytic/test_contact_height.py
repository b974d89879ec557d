"""The height of contact forces in the load transfer, against closed forms (level ``load_transfer``).

Load moves between a body's wheels by the roll and pitch moments about the ground of the forces
acting above it: the inertial force ``-m a`` at the CG height ``h`` and a contact force ``F_c`` at
its height ``h_c`` (``Body.contact_height``, default ``h``); tyre forces act at the ground.  The
loads therefore follow the specific force ``a - g_plane - (h_c / h) F_c / m``
(:func:`crashsim.motion.kernels.equations.specific_force`), and for a body on one track width ``t``
the unit's load transfer ratio is ``LTR = 2 h a_s,y / (g_n g t)``.

* **A side push at the CG moves no load.**  A car rolls along a wall on a cross-slope ``s`` (rise
  over run) on free-rolling wheels pointing along the wall, no rolling resistance, no wall
  friction: the wall holds it against the in-plane gravity ``m g sin(phi)`` with a constant
  contact force, and the tyres carry no side force.  With the wall's force at the CG's height the
  two forces act at one height and move no load: ``LTR = 0``; at ``h_c`` they form a roll couple
  ``F (h - h_c)``, so ``LTR = 2 (h - h_c) tan(phi) / t``: at the ground, the quasi-static
  ``dN = F h / t`` of a body whose tyres held it (``F = m g sin(phi)``).
* **A side push at the CG against tyre forces at the ground.**  A car held against a wall by its
  steered wheels (each tyre's side force saturated at ``mu N``, steer ``delta``) slides along it:
  no lateral acceleration, the wall's force ``N_w = mu m g cos(delta)`` against the tyres' equal
  side force at the ground, a roll couple ``N_w h_c``: ``|LTR| = 2 mu cos(delta) h_c / t`` (0 for a
  push at ground level, the model before the contact height entered it).  Along the wall its
  deceleration is ``g mu (|sin delta| + f_w cos delta)``; the wall's friction ``f_w N_w`` acts at
  ``h_c`` too, so the filtered longitudinal specific force is ``-g mu (|sin delta| + f_w cos delta
  (1 - h_c / h))``.

Both engines run every case.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from crashsim.motion import ContactModel, Obstacle, Road, RunoutOptions, WheelSetting, WheelSettings, simulate_scene
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.motion.scene_model import contact_levers
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

ENGINES = ("scipy", "compiled")
H, TRACK, M = 0.55, 1.5, 1500.0


def car(contact_height=None):
    return Vehicle("car", (Body("car", M, 2500.0, 4.5, 1.8, axles=(Axle(1.3, TRACK), Axle(-1.3, TRACK)),
                                cg_height=H, contact_height=contact_height),))


def ltr(run):
    """The car's load transfer ratio (right minus left over the total) at every sample, and the times."""
    wheels = run.vehicles["car"].wheels.values()
    t = next(iter(wheels)).t
    right = sum(w.load for w in wheels if w.side == "right")
    left = sum(w.load for w in wheels if w.side == "left")
    return t, (right - left) / (right + left)


def _cross_slope_wall(engine, contact_height, slope=0.08):
    """Rolling along a wall at the foot of a cross-slope (the road rises toward +y)."""
    free = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))
    wall = Obstacle("wall", ((-10.0, -1.0), (200.0, -1.0)), thickness=0.2)  # face at y = -0.9
    states = {"car": BodyState((0.0, 0.1), 0.0, (10.0, 0.0))}  # 0.1 m from the face, beyond the arming distance
    opts = RunoutOptions(engine=engine, load_transfer=True, t_max=5.0, rtol=1e-9, atol=1e-11)
    return simulate_scene([car(contact_height)], states, {"car": free}, Road(0.7, cross_slope=slope), opts,
                          contact=ContactModel(friction=0.0), obstacles=[wall])


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("contact_height", [None, 0.2, 1e-6])
def test_a_constant_side_push_at_the_cg_moves_no_load(engine, contact_height):
    slope = 0.08
    run = _cross_slope_wall(engine, contact_height, slope)
    assert not run.impacts and [e.kind for e in run.events if e.kind.startswith("contact")] == ["contact"]
    pair = run.pairs[0]
    t, r = ltr(run)
    # the contact settled (after the drift onto the wall: 15 times the filter's lag tau = 0.2 s)
    on = t > pair.t[pair.force > 0].min() + 3.0
    assert on.sum() > 50
    h_c = H if contact_height is None else contact_height
    phi = math.atan(slope)
    # the wall's force is the in-plane gravity m g sin(phi), constant
    force = np.interp(t[on], pair.t, pair.force)
    assert force == pytest.approx(M * G * math.sin(phi), rel=1e-4)
    expected = 2.0 * (H - h_c) * math.tan(phi) / TRACK  # load moves downhill (-y: the right side)
    assert r[on] == pytest.approx(expected, abs=1e-6)
    if contact_height is None:
        assert np.abs(r[on]).max() < 1e-6
    else:  # the quasi-static dN = F (h - h_c) / t over the body's right wheels, of m g cos(phi)
        right = sum(w.load for w in run.vehicles["car"].wheels.values() if w.side == "right")[on]
        dn = M * G * math.sin(phi) * (H - h_c) / TRACK
        assert right - M * G * math.cos(phi) / 2 == pytest.approx(dn, rel=1e-4)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("contact_height", [None, 0.3, 1e-6])
def test_a_car_pressed_on_a_wall_by_its_tyres_rolls_by_the_walls_height(engine, contact_height):
    mu, f_wall, delta = 0.7, 0.4, math.radians(-30.0)
    wheels = WheelSettings(default=WheelSetting("rolling", steer=delta, cornering_coefficient=8.6,
                                                rolling_resistance=0.0))
    wall = Obstacle("wall", ((-10.0, -1.0), (200.0, -1.0)), thickness=0.2)  # face at y = -0.9
    states = {"car": BodyState((0, 0.05), 0.0, (20.0, 0.0))}
    opts = RunoutOptions(engine=engine, load_transfer=True, max_step=0.01, rtol=1e-9, atol=1e-11)
    run = simulate_scene([car(contact_height)], states, {"car": wheels}, Road(mu), opts,
                         contact=ContactModel(friction=f_wall, velocity_threshold=5.0), obstacles=[wall])
    assert run.status == "rest" and not run.impacts
    h_c = H if contact_height is None else contact_height
    pair = run.pairs[0]
    t, r = ltr(run)
    h = run.vehicles["car"].bodies["car"].history
    speed = np.hypot(h.vx, h.vy)
    steady = (t > pair.t[pair.force > 0].min() + 1.5) & (speed > 3.0)
    assert steady.sum() > 50
    # the tyres push the car toward the wall (-y) at the ground, the wall pushes back at h_c: the
    # couple rolls the car away from the wall, loading its left (+y) wheels
    assert r[steady] == pytest.approx(-2.0 * mu * math.cos(delta) * h_c / TRACK, abs=2e-4)
    acc = np.asarray(run.sol(t[steady]))[run.layout.accel]  # filtered a_x, a_y of the one body
    expected_x = -G * mu * (abs(math.sin(delta)) + f_wall * math.cos(delta) * (1.0 - h_c / H))
    assert acc[0] == pytest.approx(expected_x, abs=2e-3)
    assert acc[1] == pytest.approx(-G * mu * math.cos(delta) * h_c / H, abs=2e-3)


def test_the_lever_is_the_contact_height_over_the_cg_height():
    body = car(0.3).bodies[0]
    assert contact_levers([body], True) == pytest.approx([0.3 / H], rel=1e-15)
    assert contact_levers([car().bodies[0]], True) == pytest.approx([1.0])
    assert contact_levers([body], False) == pytest.approx([1.0])  # not read without load transfer
    no_cg = dataclasses.replace(body, cg_height=None)
    assert contact_levers([no_cg], True) == pytest.approx([1.0])


@pytest.mark.parametrize("engine", ENGINES)
def test_without_contact_the_height_changes_nothing(engine):
    """A car spinning out alone: the contact height is not read, the run is bit-identical."""
    free = WheelSettings(default=WheelSetting("locked"))
    opts = RunoutOptions(engine=engine, load_transfer=True)
    runs = [simulate_scene([car(hc)], {"car": BodyState((0, 0), 0.0, (12.0, 2.0), 1.0)}, {"car": free}, Road(0.7),
                           opts) for hc in (None, 0.2)]
    a, b = (r.vehicles["car"].bodies["car"].final for r in runs)
    assert a.position == b.position and a.heading == b.heading and runs[0].t_end == runs[1].t_end


@pytest.mark.parametrize("engine", ENGINES)
def test_the_rollover_check_follows_the_contact_height(engine):
    """The wall case above with a rollover threshold of 0.05 g (below the cross-slope's tan(phi) = 0.08):
    with the wall's force at the ground its lateral specific force is tan(phi) g, the threshold is passed
    and the planar result is declared outside its validity; at the CG's height it is 0 and nothing fires."""
    slope = 0.08
    free = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))
    wall = Obstacle("wall", ((-10.0, -1.0), (200.0, -1.0)), thickness=0.2)
    out = {}
    for label, hc in (("cg", None), ("ground", 1e-6)):
        veh = car(hc)
        veh = dataclasses.replace(veh, bodies=(dataclasses.replace(veh.bodies[0], rollover_threshold=0.05),))
        opts = RunoutOptions(engine=engine, load_transfer=True, rollover=True, t_max=5.0, rtol=1e-9, atol=1e-11)
        # 1.1 cm from the wall (arming distance 1 cm): it touches before its tyres, holding it on the slope
        # until then, build their side force (0.03 g of 0.08 g)
        run = simulate_scene([veh], {"car": BodyState((0.0, 0.011), 0.0, (10.0, 0.0))}, {"car": free},
                             Road(0.7, cross_slope=slope), opts,
                             contact=ContactModel(friction=0.0, arm_distance=0.01), obstacles=[wall])
        out[label] = (run, [e for e in run.events if e.kind == "rollover_threshold"])
    run, fired = out["ground"]
    contact = next(e.t for e in run.events if e.kind == "contact")
    assert len(fired) == 1 and fired[0].t > contact
    assert abs(fired[0].data["lateral_acceleration_g"]) == pytest.approx(0.05, abs=1e-6)
    assert run.vehicles["car"].rollover["valid_until_s"] == fired[0].t
    run, fired = out["cg"]
    assert not fired and run.vehicles["car"].rollover["valid_until_s"] is None

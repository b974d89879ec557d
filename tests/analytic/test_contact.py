"""Contact in the run-out against closed forms: secondary impacts and sustained contact.

The bodies roll on free wheels with zero rolling resistance, moving along their headings, so
no tyre force acts before a contact and the velocities at the instant of contact are known
exactly.  Both engines run every case.

* Two equal cars, central impact: the touch at ``t = gap / v``; after it ``v_A = v (1 - e)/2``,
  ``v_B = v (1 + e)/2`` (momentum and the restitution law), ``P_n = m (1 + e) v / 2``.
* A car's front face against a rigid wall at an angle: the normal velocity of the CG reverses
  by e (the contact point is on the CG's normal line), and with f below the no-sliding ratio
  the tangential impulse is ``f P_n`` against the sliding, turning the car by
  ``f P_n (length / 2) / I``.
* A car pressed against a wall by its steered wheels (saturated side force mu N at steer delta)
  slides along it with the deceleration ``g mu (|sin delta| + f_wall cos delta)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.motion import (ContactModel, Obstacle, Road, RunoutOptions, WheelSetting, WheelSettings,
                             simulate_scene)
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

ENGINES = ("scipy", "compiled")
FREE = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))


def box(name, m=1500.0, inertia=2500.0, length=4.5, width=1.8):
    return Vehicle(name, (Body(name, m, inertia, length, width, axles=(Axle(1.3, 1.5), Axle(-1.3, 1.5))),))


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("e", [0.0, 0.3, 1.0])
def test_two_equal_cars_central_impact(engine, e):
    v, gap = 10.0, 1.0
    states = {"a": BodyState((0, 0), 0.0, (v, 0.0)), "b": BodyState((4.5 + gap, 0), 0.0, (0.0, 0.0))}
    run = simulate_scene([box("a"), box("b")], states, {"a": FREE, "b": FREE}, Road(0.7),
                         RunoutOptions(engine=engine, t_max=0.3), contact=ContactModel(restitution=e, friction=0.5))
    assert len(run.impacts) == 1
    hit = run.impacts[0]
    assert hit.t == pytest.approx(gap / v, abs=1e-9)
    assert (hit.body1, hit.body2) == ("a", "b")
    assert hit.point == pytest.approx([4.5 / 2 + gap, 0.0], abs=1e-9)
    assert hit.normal == pytest.approx([-1.0, 0.0], abs=1e-12)  # from b into a
    assert hit.delta_v["a"][0] == pytest.approx(-v * (1 + e) / 2, rel=1e-9)
    assert hit.delta_v["b"][0] == pytest.approx(v * (1 + e) / 2, rel=1e-9)
    assert hit.normal_impulse == pytest.approx(1500 * (1 + e) * v / 2, rel=1e-9)
    assert hit.tangential_impulse == pytest.approx(0.0, abs=1e-6)
    assert hit.energy_loss == pytest.approx(0.5 * 1500 * v**2 * (1 - e**2) / 2, rel=1e-9)
    a, b = run.vehicles["a"].bodies["a"], run.vehicles["b"].bodies["b"]
    # no tyre force acts afterwards; with e = 0 the cars stay touching (sustained contact), and
    # the penalty force trades tiny impulses between them (momentum still conserved exactly)
    tol = 1e-4 if e == 0.0 else 1e-9
    assert a.final.velocity[0] == pytest.approx(v * (1 - e) / 2, rel=tol, abs=tol)
    assert b.final.velocity[0] == pytest.approx(v * (1 + e) / 2, rel=tol, abs=tol)
    assert a.final.velocity[0] + b.final.velocity[0] == pytest.approx(v, rel=1e-9)


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("e, f", [(0.2, 0.0), (0.2, 0.03), (0.0, 0.3)])
def test_face_on_wall_impact_two_corners_at_once(engine, e, f):
    """A car heading straight at a wall, moving along its heading at 15 deg to the wall normal
    (the wheels steered 15 deg so that no tyre force acts): its front face meets the wall face
    on, both front corners at once.  Solved together, each corner separates at e times its
    approach speed (Newton's law at each point), so the face stays parallel to the wall: the yaw
    rate stays 0 and the CG's normal velocity reverses by e (P_n = m (1 + e) v_n).  Stopping the
    slip v_t takes P_stop = m v_t: below f P_n the corners stick (P_t = P_stop), else they slide
    with P_t = f P_n.  The friction's moment P_t L / 2 about the CG is taken by the corners' normal
    impulses (P_1 - P_2 = P_t L / W, both >= 0 while P_t / P_n <= W / L), which moves the centre of
    the normal impulse P_t L / (2 P_n) along the face."""
    m, inertia, length, width = 1500.0, 2500.0, 4.5, 1.8
    beta = math.radians(15.0)
    v = 8.0
    steer = WheelSettings(default=WheelSetting("rolling", steer=beta, cornering_coefficient=8.6,
                                               rolling_resistance=0.0))
    wall = Obstacle("wall", ((length / 2 + 0.5, -20.0), (length / 2 + 0.5, 20.0)), thickness=0.2)
    states = {"car": BodyState((0, 0), 0.0, (v * math.cos(beta), v * math.sin(beta)))}
    run = simulate_scene([box("car", m, inertia, length)], states, {"car": steer}, Road(0.7),
                         RunoutOptions(engine=engine, t_max=0.5), contact=ContactModel(restitution=e, friction=f),
                         obstacles=[wall])
    hit = run.impacts[0]
    vn, vt = v * math.cos(beta), v * math.sin(beta)
    assert hit.t == pytest.approx(0.4 / vn, rel=1e-9)  # the face reaches the wall face (0.5 - 0.1 m away)
    assert hit.points == 2
    pn = m * (1 + e) * vn
    p_stop = m * vt
    pt = min(p_stop, f * pn)
    assert pt / pn <= width / length  # both corners take an impulse (the closed form's premise)
    assert hit.point[0] == pytest.approx(length / 2 + 0.4, abs=1e-9)
    # the impulses' centre: the face's middle, moved along the face by the friction's moment
    assert hit.point[1] - vt * hit.t == pytest.approx(pt * length / (2 * pn), abs=1e-9)
    r = hit.result.bodies["car"]
    assert (p_stop < f * pn) == (hit.result.sliding is False) or f == 0.0
    assert hit.normal_impulse == pytest.approx(pn, rel=1e-9)
    assert abs(hit.tangential_impulse) == pytest.approx(pt, rel=1e-9, abs=1e-9)
    assert r.velocity[0] == pytest.approx(-e * vn, rel=1e-9, abs=1e-12)
    assert r.velocity[1] == pytest.approx(vt - pt / m, rel=1e-9, abs=1e-12)
    assert r.yaw_rate == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("engine", ENGINES)
def test_sliding_along_a_wall_decelerates_as_road_and_wall_friction_say(engine):
    """Steer -30 deg on every wheel of a car moving along a wall: each tyre's side force is
    saturated at mu N, perpendicular to its wheel, pushing the car into the wall with mu m g
    cos(delta) and braking it with mu m g |sin(delta)|; the wall's friction f_w adds f_w times
    the normal force.  The contact is sustained (a slow approach below the impulse threshold),
    so the speed falls at g mu (|sin delta| + f_w cos delta)."""
    mu, f_wall, delta = 0.7, 0.4, math.radians(-30.0)
    wheels = WheelSettings(default=WheelSetting("rolling", steer=delta, cornering_coefficient=8.6,
                                                rolling_resistance=0.0))
    car = Vehicle("car", (Body("car", 1500.0, 2500.0, 4.5, 1.8, axles=(Axle(1.3, 1.5), Axle(-1.3, 1.5))),))
    wall = Obstacle("wall", ((-10.0, -1.0), (200.0, -1.0)), thickness=0.2)  # face at y = -0.9
    states = {"car": BodyState((0, 0.05), 0.0, (20.0, 0.0))}  # 5 cm from the face
    run = simulate_scene([car], states, {"car": wheels}, Road(mu), RunoutOptions(engine=engine, max_step=0.01),
                         contact=ContactModel(friction=f_wall, velocity_threshold=5.0), obstacles=[wall])
    assert run.status == "rest" and not run.impacts
    assert [e.kind for e in run.events if e.kind.startswith("contact")] == ["contact"]
    h = run.vehicles["car"].bodies["car"].history
    # speed against time over the middle of the slide (the contact settled, well above rest)
    sel = (h.t > 0.5) & (np.hypot(h.vx, h.vy) > 3.0)
    slope = np.polyfit(h.t[sel], np.hypot(h.vx, h.vy)[sel], 1)[0]
    expected = G * mu * (abs(math.sin(delta)) + f_wall * math.cos(delta))
    assert -slope == pytest.approx(expected, rel=0.01)
    pair = run.pairs[0]
    # pressed with N = mu m g cos(delta) (after the first touch, damped without a bounce); the
    # contact force is N with the wall friction f_w N across it; never deeper than the largest
    # force over the stiffness of the two corner contacts
    steady = (pair.t > 0.5) & (pair.t < pair.t[pair.force > 0].max() - 0.5)
    normal = mu * 1500 * G * math.cos(delta)
    assert np.median(pair.force[steady]) == pytest.approx(normal * math.hypot(1.0, f_wall), rel=0.01)
    assert pair.max_penetration < pair.peak_force / 1e7 + 1e-3
    assert abs(h.heading).max() < math.radians(1.0)  # the wall holds the car straight
    assert run.energy["closing_error"] == pytest.approx(0.0, abs=1e-6 * run.energy["initial"])


@pytest.mark.parametrize("engine", ENGINES)
def test_a_pair_that_never_touches_changes_nothing(engine):
    """Contact modelled or not, two cars far apart run out identically (to the integration)."""
    locked = WheelSettings(default=WheelSetting("locked"))
    states = {"a": BodyState((0, 0), 0.3, (12.0, 2.0), 0.5), "b": BodyState((0, 30), 0.0, (10.0, -1.0), -0.4)}
    runs = [simulate_scene([box("a"), box("b")], states, {"a": locked, "b": locked}, Road(0.7),
                           RunoutOptions(engine=engine), contact=ContactModel(enabled=on)) for on in (True, False)]
    assert not runs[0].impacts and [p.impacts for p in runs[0].pairs] == [0]
    for name, v in (("a", "a"), ("b", "b")):
        p0 = runs[0].vehicles[v].bodies[name].rest_position
        p1 = runs[1].vehicles[v].bodies[name].rest_position
        assert np.hypot(*np.subtract(p0, p1)) < 1e-6


def _bounce_along_wall(engine, e, f, v_n=2.0, gap=0.1):
    """A car sliding along a wall at 20 m/s with every wheel steered -30 deg: the saturated side
    forces push it into the wall with a_n = mu g cos(30 deg) (the sliding case above), and it
    starts ``gap`` from the face moving into it at ``v_n``."""
    mu, delta = 0.7, math.radians(-30.0)
    wheels = WheelSettings(default=WheelSetting("rolling", steer=delta, cornering_coefficient=8.6,
                                                rolling_resistance=0.0))
    wall = Obstacle("wall", ((-10.0, -1.0), (200.0, -1.0)), thickness=0.2)  # face at y = -0.9
    states = {"car": BodyState((0, gap), 0.0, (20.0, -v_n))}
    run = simulate_scene([box("car")], states, {"car": wheels}, Road(mu), RunoutOptions(engine=engine, t_max=10.0),
                         contact=ContactModel(restitution=e, friction=f), obstacles=[wall])
    return run, G * mu * math.cos(delta)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_restrike_within_the_arming_distance_is_an_impact(engine):
    """The re-strike rule: a car pushed into a wall bounces off (e = 0.3) and is pushed back
    before it has left the arming distance (apex (e c_1)^2 / (2 a_n) = 4 cm < 5 cm).  It arrives
    at e c_1 >= the 0.5 m/s threshold, so that is an impact, not a penalty force; the next
    arrival (e^2 c_1 = 0.2 m/s) is sustained contact.  Frictionless face-on contact: the flight
    between the impacts is a parabola under the constant push, c_1 = sqrt(v_n^2 + 2 a_n gap),
    the second impact comes 2 e c_1 / a_n later at e c_1, and each separates at e times its
    closing speed."""
    e = 0.3
    run, a_n = _bounce_along_wall(engine, e, 0.0)
    hits = run.impacts
    assert [(h.body1, h.body2) for h in hits] == [("car", "wall")] * 2
    c1 = math.sqrt(2.0**2 + 2 * a_n * 0.1)
    assert hits[0].closing_speed == pytest.approx(c1, rel=1e-6)
    assert hits[1].closing_speed == pytest.approx(e * c1, rel=1e-6)
    assert hits[1].t - hits[0].t == pytest.approx(2 * e * c1 / a_n, rel=1e-6)
    assert (e * c1) ** 2 / (2 * a_n) < ContactModel().arm_distance  # never re-armed in between
    between = [ev.kind for ev in run.events if hits[0].t < ev.t < hits[1].t]
    assert "armed" not in between and "contact_end" not in between
    for h in hits:
        r = h.result
        assert r.separation_normal_velocity == pytest.approx(-e * r.closing_velocity, rel=1e-9)
        assert h.tangential_impulse == pytest.approx(0.0, abs=1e-9 * h.normal_impulse)
    assert run.status == "rest"
    assert run.energy["closing_error"] == pytest.approx(0.0, abs=1e-6 * run.energy["initial"])


@pytest.mark.parametrize("engine", ENGINES)
def test_restrikes_with_friction_obey_e_and_f(engine):
    """The same with wall friction f = 0.3: the car slides along the face at 20 m/s, so every
    impact slides throughout (Coulomb): P_t = -f P_n sign(u_t), and the normal separation
    velocity is e times the closing speed, at the first impact and at every re-strike."""
    e, f = 0.3, 0.3
    run, _ = _bounce_along_wall(engine, e, f, v_n=3.0)
    assert len(run.impacts) >= 2
    for h in run.impacts:
        r = h.result
        assert r.sliding  # the slip (about 20 m/s) is slowed, not stopped: it keeps its sign
        sign = math.copysign(1.0, r.separation_tangential_velocity)
        assert h.tangential_impulse == pytest.approx(-f * h.normal_impulse * sign, rel=1e-9)
        assert r.separation_normal_velocity == pytest.approx(-e * r.closing_velocity, rel=1e-9)

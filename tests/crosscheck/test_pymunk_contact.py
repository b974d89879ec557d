"""One secondary impact against pymunk: two boxes, a corner into a face.

crashsim: the run-out detects the touch (separating-axis gap event), takes the penetrating
corner and the face normal as contact point and crush normal, and solves Brach's equations
(e, the friction law with f, no moment impulse).  pymunk (Chipmunk2D): the same two boxes as
polygons, elasticity e and friction f for the pair (pymunk multiplies the two shapes' values, so
one side carries 1), sequential impulses with 100 iterations and a 1e-5 s step, no ground
friction, until the contact ends.  For a single-point contact the two are the same mechanics
(research note: a Brach point impact with no moment impulse), so the velocities after the
impact must agree; the issue asks for 2 %, they agree to about 0.01 %.

The boxes roll on free wheels (zero rolling resistance, moving along their headings), so no
tyre force acts before the touch; the comparison uses the impulse solver's velocities at the
impact.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.motion import ContactModel, Road, RunoutOptions, WheelSetting, WheelSettings, simulate_scene
from crashsim.vehicles import Axle, Body, BodyState, Vehicle

pymunk = pytest.importorskip("pymunk")

FREE = WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.6, rolling_resistance=0.0))
SPEED = 8.0
BOXES = {"a": (1500.0, 2500.0, 4.5, 1.8), "b": (1200.0, 1800.0, 4.2, 1.7)}


def _scene(angle_deg):
    """Box a at the origin moving +x; box b at rest, turned, a corner 0.5 m ahead of a's front face."""
    rot = math.radians(angle_deg)
    _, _, lb, wb = BOXES["b"]
    corners = np.array([[lb / 2, wb / 2], [-lb / 2, wb / 2], [-lb / 2, -wb / 2], [lb / 2, -wb / 2]])
    R = np.array([[math.cos(rot), -math.sin(rot)], [math.sin(rot), math.cos(rot)]])
    world = corners @ R.T
    lead = world[np.argmin(world[:, 0])]
    pos_b = np.array([BOXES["a"][2] / 2 + 0.5, 0.4]) - lead
    return rot, pos_b


def _pymunk(e, f, rot, pos_b):
    space = pymunk.Space()
    space.iterations = 100
    space.collision_slop = 1e-5
    bodies = {}
    for name, pos, ang, vel in (("a", (0.0, 0.0), 0.0, (SPEED, 0.0)), ("b", tuple(pos_b), rot, (0.0, 0.0))):
        m, inertia, length, width = BOXES[name]
        body = pymunk.Body(m, inertia)
        body.position, body.angle, body.velocity = pos, ang, vel
        shape = pymunk.Poly(body, [(length / 2, width / 2), (-length / 2, width / 2), (-length / 2, -width / 2),
                                   (length / 2, -width / 2)])
        shape.elasticity = e if name == "a" else 1.0  # pair values: the product (research note)
        shape.friction = f if name == "a" else 1.0
        space.add(body, shape)
        bodies[name] = body
    t, touched = 0.0, False
    while t < 0.3:
        space.step(1e-5)
        t += 1e-5
        arbiters = []
        bodies["a"].each_arbiter(arbiters.append)
        touched = touched or bool(arbiters)
        if touched and not arbiters:
            break
    assert touched
    return {n: np.array([*b.velocity, b.angular_velocity]) for n, b in bodies.items()}


@pytest.mark.parametrize("angle, e, f, sliding", [(25.0, 0.2, 0.2, False), (25.0, 0.1, 0.6, False),
                                                  (25.0, 0.4, 0.0, True), (40.0, 0.2, 0.05, True)])
def test_a_corner_impact_matches_pymunk(angle, e, f, sliding):
    rot, pos_b = _scene(angle)
    vehicles = [Vehicle(n, (Body(n, m, i, length, width, axles=(Axle(1.2, 1.5), Axle(-1.2, 1.5))),))
                for n, (m, i, length, width) in BOXES.items()]
    states = {"a": BodyState((0, 0), 0.0, (SPEED, 0.0)), "b": BodyState(tuple(pos_b), rot, (0.0, 0.0))}
    run = simulate_scene(vehicles, states, {"a": FREE, "b": FREE}, Road(0.7), RunoutOptions(engine="compiled", t_max=0.3),
                         contact=ContactModel(restitution=e, friction=f))
    assert len(run.impacts) == 1
    hit = run.impacts[0]
    assert hit.result.sliding == sliding  # both regimes of the friction law are covered
    assert hit.normal == pytest.approx([-1.0, 0.0], abs=1e-12)  # a's front face is the reference face
    mine = {n: np.array([*hit.result.bodies[n].velocity, hit.result.bodies[n].yaw_rate]) for n in BOXES}
    ref = _pymunk(e, f, rot, pos_b)
    for n in BOXES:
        scale = np.array([SPEED, SPEED, SPEED / BOXES[n][2]])
        assert np.all(np.abs(mine[n] - ref[n]) <= 1e-3 * scale), (n, mine[n], ref[n])

"""Planar frames: body <-> world, and the crush-surface (n, t) frame.

Conventions (used everywhere in crashsim)
-----------------------------------------
* World frame X, Y; angles counter-clockwise positive from +X, in radians.
* Body axes: x forward along the heading, y to the left; origin at the body's CG.
* ``perp(a)`` rotates a vector by +90 deg; the planar cross product is
  ``cross(a, b) = a_x b_y - a_y b_x``.
* The velocity of a point at world offset ``d`` from a CG moving with ``v`` and yaw rate
  ``w`` is ``v + w * perp(d)``.

All functions broadcast over leading dimensions; the last axis holds (x, y).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["rotation", "rotate", "perp", "cross", "unit", "to_body", "to_world", "wrap_angle"]


def rotation(angle):
    """Rotation matrix R(angle), shape ``angle.shape + (2, 2)``."""
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([np.stack([c, -s], -1), np.stack([s, c], -1)], -2)


def rotate(vec, angle):
    """Rotate vectors ``vec[..., 2]`` counter-clockwise by ``angle`` [rad]."""
    vec = np.asarray(vec, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    return np.stack([c * vec[..., 0] - s * vec[..., 1], s * vec[..., 0] + c * vec[..., 1]], -1)


def perp(vec):
    """Rotate ``vec[..., 2]`` by +90 deg: (x, y) -> (-y, x)."""
    vec = np.asarray(vec, dtype=float)
    return np.stack([-vec[..., 1], vec[..., 0]], -1)


def cross(a, b):
    """Planar cross product a_x b_y - a_y b_x."""
    a = np.asarray(a, dtype=float)
    b = np.asarray(b, dtype=float)
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def unit(angle):
    """Unit vector at ``angle`` [rad] from +X."""
    return np.stack([np.cos(angle), np.sin(angle)], -1)


def to_world(point_body, position, heading):
    """Body-axes point -> world point for a body at ``position`` with ``heading``."""
    return np.asarray(position, dtype=float) + rotate(point_body, heading)


def to_body(point_world, position, heading):
    """World point -> body axes of a body at ``position`` with ``heading``."""
    return rotate(np.asarray(point_world, dtype=float) - np.asarray(position, dtype=float), -np.asarray(heading))


def wrap_angle(angle):
    """Wrap an angle to (-pi, pi]. A python float gives a python float (the same arithmetic:
    numpy's mod of floats is Python's %), anything else an array."""
    if type(angle) is float:
        a = (angle + math.pi) % (2 * math.pi) - math.pi
        return math.pi if a == -math.pi else a
    a = np.mod(np.asarray(angle, dtype=float) + np.pi, 2 * np.pi) - np.pi
    return np.where(a == -np.pi, np.pi, a)

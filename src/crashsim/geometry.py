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

__all__ = ["rotation", "rotate", "perp", "cross", "unit", "to_body", "to_world", "wrap_angle",
           "circular_mean", "unwrap_about_mean", "circular_percentiles"]


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


def circular_mean(angles) -> float:
    """Circular mean of angles [rad], in (-pi, pi]: the direction of the sum of their unit vectors
    (NaN if there are none or they cancel)."""
    a = np.asarray(angles, dtype=float).ravel()
    a = a[np.isfinite(a)]
    if a.size == 0:
        return float("nan")
    s, c = float(np.sum(np.sin(a))), float(np.sum(np.cos(a)))
    if math.hypot(s, c) <= 1e-12 * a.size:
        return float("nan")
    return wrap_angle(math.atan2(s, c))


def unwrap_about_mean(angles) -> np.ndarray:
    """Angles [rad] as one continuous arc around their circular mean.

    Each angle is moved by whole turns into (mean - pi, mean + pi], the mean in (-pi, pi]; a cloud
    across +-180 deg (179 and -179 deg) becomes 179 and 181 deg, not two clouds 358 deg apart. Linear
    statistics of the result (percentiles, a histogram, a standard deviation) are then those of the
    arc, and agree with the linear ones of a cloud that does not cross the wrap. NaN stays NaN; if
    the angles have no mean direction (they cancel), they are returned wrapped to (-pi, pi].
    """
    a = np.asarray(angles, dtype=float)
    m = circular_mean(a)
    if not np.isfinite(m):
        return wrap_angle(a)
    return m + wrap_angle(a - m)


def circular_percentiles(angles, q) -> np.ndarray:
    """Percentiles ``q`` (0-100) of angles [rad] on their arc around the circular mean
    (:func:`unwrap_about_mean`): for samples from 191 to 231 deg, p5 about -167 and p50 about
    -149 deg (not the -139 and 109 deg of the wrapped numbers). Values may pass +-pi where the
    cloud crosses it (p95 of 175..185 deg is about 184.5 deg), so that p5 <= p50 <= p95."""
    a = np.asarray(angles, dtype=float).ravel()
    a = a[np.isfinite(a)]
    return np.percentile(unwrap_about_mean(a), q)

"""motion.road.point_distance: one point's signed distance, bit for bit the array function's."""

from __future__ import annotations

import numpy as np

from crashsim.motion.road import point_distance, signed_distance


def test_one_point_at_a_time_equals_the_array_function_bit_for_bit():
    rng = np.random.default_rng(20261126)
    for _ in range(200):
        n = int(rng.integers(3, 9))
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))  # a star-shaped (simple) polygon around a centre
        poly = rng.normal(size=2) * 5 + rng.uniform(0.5, 4.0, n)[:, None] * np.stack([np.cos(ang), np.sin(ang)], 1)
        pts = rng.normal(size=(20, 2)) * 4 + poly.mean(axis=0)
        pts[0] = poly[0]  # on a vertex
        pts[1] = 0.5 * (poly[0] + poly[1])  # on an edge
        want = signed_distance(pts, poly)
        f = point_distance(poly)
        got = np.array([f(float(x), float(y)) for x, y in pts])
        assert np.array_equal(got, want)

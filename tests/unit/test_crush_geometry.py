"""The impact geometry from crush profiles (crashsim.validation.crushgeom): closed forms of the damage
centroid, the placement's rules (the two impulse centres coincide, the normal points into vehicle 1),
and the total-least-squares contact plane on profiles whose answer is known."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.validation.crushgeom import Damage, Outline, crushed_stations, damage_centroid, impulse_centre, place

CAR = Outline(2.5, 2.3, 1.8)


def test_a_uniform_profile_has_its_centroid_at_the_damage_centre_and_half_depth():
    s, depth = damage_centroid(Damage("front", 1.2, 0.3, (0.2,) * 6))
    assert s == pytest.approx(0.0, abs=1e-15) and depth == pytest.approx(0.1, rel=1e-12)


def test_a_wedge_profile_has_its_centroid_at_two_thirds():
    # crush rising linearly from 0 at station -L/2 to c at +L/2: the triangle's centroid lies L/6 from the centre
    # toward the deep end, at a depth of c/3
    s, depth = damage_centroid(Damage("front", 1.5, 0.0, (0.0, 0.12)))
    assert s == pytest.approx(1.5 / 6, rel=1e-12) and depth == pytest.approx(0.04, rel=1e-12)


def test_a_profile_without_area_is_refused():
    with pytest.raises(ValueError, match="no area"):
        damage_centroid(Damage("front", 1.0, 0.0, (0.0, 0.0, 0.0, 0.0)))


@pytest.mark.parametrize("face, offset, expect", [
    ("front", 0.4, (2.5 - 0.2, -0.4)),   # D positive to the right: -y
    ("rear", 0.4, (-2.3 + 0.2, -0.4)),
    ("right", 0.5, (0.5, -0.9 + 0.2)),   # on the sides D is positive forward
    ("left", -0.5, (-0.5, 0.9 - 0.2)),
])
def test_faces_and_offsets_follow_the_crash3_conventions(face, offset, expect):
    c = impulse_centre(CAR, Damage(face, 1.0, offset, (0.2,) * 4))
    assert c == pytest.approx(expect, abs=1e-12)


def test_stations_run_left_to_right_on_the_front():
    pts = crushed_stations(CAR, Damage("front", 1.0, 0.0, (0.1, 0.2, 0.3, 0.4)))
    assert np.all(np.diff(pts[:, 1]) < 0)  # y falls: from the left to the right
    assert pts[:, 0] == pytest.approx(2.5 - np.array([0.1, 0.2, 0.3, 0.4]))


def test_a_square_rear_end_impact_is_placed_on_the_line_of_centres():
    """Car 1's full-width front into car 2's full-width rear, both uniformly crushed, headings equal: the
    centres coincide on the axis, car 2's CG stands its CG-to-rear less its crush ahead of car 1's crushed front,
    the normal points back into car 1, and the two crushed faces are one line."""
    d1 = Damage("front", 1.8, 0.0, (0.1,) * 6)
    d2 = Damage("rear", 1.8, 0.0, (0.15,) * 6)
    p = place(CAR, d1, 0.0, CAR, d2, 0.0)
    assert p.point == pytest.approx((2.4, 0.0), abs=1e-12)
    assert p.position2 == pytest.approx((2.4 + 2.3 - 0.15, 0.0), abs=1e-12)
    assert math.cos(p.normal) == pytest.approx(-1.0, abs=1e-12)  # from car 2 into car 1
    assert p.spread == pytest.approx(0.0, abs=1e-12)  # at maximum engagement the crushed faces coincide


def test_placement_is_frame_invariant():
    """Turning the whole configuration turns its answer: same point relative to car 1, normal turned alike."""
    d1 = Damage("front", 1.2, 0.3, (0.1, 0.14, 0.18, 0.26, 0.31, 0.38))
    d2 = Damage("right", 2.9, 0.55, (0.01, 0.3, 0.27, 0.3, 0.23, 0.1))
    a = place(CAR, d1, 0.0, CAR, d2, math.radians(-120))
    turn = math.radians(37)
    b = place(CAR, d1, turn, CAR, d2, math.radians(-120) + turn, position1=(5.0, -3.0))
    rot = np.array([[math.cos(turn), -math.sin(turn)], [math.sin(turn), math.cos(turn)]])
    assert b.point - np.array([5.0, -3.0]) == pytest.approx(rot @ a.point, abs=1e-12)
    assert b.position2 - np.array([5.0, -3.0]) == pytest.approx(rot @ a.position2, abs=1e-12)
    assert math.remainder(b.normal - a.normal - turn, 2 * math.pi) == pytest.approx(0.0, abs=1e-12)

"""The point of impact and the contact plane of a two-vehicle impact from the vehicles' crush profiles.

The staged-collision cases of the validation suite give what a reconstructionist measures: each
vehicle's damaged face, its damage width L, the offset D of the damage's centre and N = 2, 4 or 6
residual crush depths C_1..C_N equally spaced over L (CRASH3's measurement), the headings at impact
and the vehicles' dimensions. The impact geometry crashsim needs (where the impulse acts, the
crush-surface normal, where the second vehicle stands) follows by three rules, one for every case
(``validation/README.md``, "Rules"):

1. **The impulse centre on each vehicle** lies at the station of its *damage centroid* (the centroid
   of the area between the undamaged face and the crushed profile, the point of application CRASH
   assumes, McHenry's "Algorithms of CRASH"), on the crushed surface there (the face moved in by the
   crush at that station): where the two vehicles' crushed structures meet.
2. **The vehicles stand at maximum engagement**: vehicle 2 is placed so that its impulse centre
   coincides with vehicle 1's, at the measured headings (their undamaged outlines then overlap by
   about the two crushes).
3. **The contact plane** is the total-least-squares line through the crushed-surface stations of
   both vehicles in that placement (the principal axis of the 2N points): the common crushed surface
   both profiles describe; its normal points from vehicle 2 into vehicle 1 (crashsim's convention).

Conventions of the profile (CRASH3 / NASS, and crashsim's ``[[evidence.crush]]``): stations run from
the vehicle's left to its right on the front and the rear, from front to rear on the sides; the
offset D is positive to the vehicle's right on the front and the rear, positive forward (from the
centre of mass) on the sides. Body axes: x forward, y left, origin at the centre of mass. SI inside.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..geometry import rotation

__all__ = ["Damage", "Outline", "crushed_stations", "damage_centroid", "impulse_centre", "Placement", "place"]

FACES = ("front", "rear", "left", "right")


@dataclass(frozen=True)
class Outline:
    """The undamaged outline of a body in its axes [m]: CG to front, CG to rear, width."""

    cg_to_front: float
    cg_to_rear: float
    width: float


@dataclass(frozen=True)
class Damage:
    """A measured crush profile [m]: face, damage width L, offset D, depths C_1..C_N."""

    face: str
    width: float
    offset: float
    crush: tuple[float, ...]

    def __post_init__(self):
        if self.face not in FACES:
            raise ValueError(f"face {self.face!r}; allowed {', '.join(FACES)}")
        if len(self.crush) not in (2, 4, 6):
            raise ValueError(f"{len(self.crush)} crush depths; allowed 2, 4 or 6")
        if not self.width > 0 or any(c < 0 for c in self.crush):
            raise ValueError(f"damage width {self.width} m and crush {self.crush} m; allowed width > 0, depths >= 0")


def _frame(outline: Outline, damage: Damage):
    """The face's station coordinate: origin (body axes) of station s = 0 at the damage centre, the
    direction s runs in (left to right, front to rear), the inward normal of the face."""
    f, r, w = outline.cg_to_front, outline.cg_to_rear, outline.width
    d = damage.offset
    if damage.face == "front":
        return np.array([f, -d]), np.array([0.0, -1.0]), np.array([-1.0, 0.0])
    if damage.face == "rear":
        return np.array([-r, -d]), np.array([0.0, -1.0]), np.array([1.0, 0.0])
    if damage.face == "right":
        return np.array([d, -w / 2]), np.array([-1.0, 0.0]), np.array([0.0, 1.0])
    return np.array([d, w / 2]), np.array([-1.0, 0.0]), np.array([0.0, -1.0])  # left


def _stations(damage: Damage) -> np.ndarray:
    n = len(damage.crush)
    return np.linspace(-damage.width / 2, damage.width / 2, n)


def crushed_stations(outline: Outline, damage: Damage) -> np.ndarray:
    """The crushed-surface points of the profile's stations in body axes, shape (N, 2) [m]."""
    origin, along, inward = _frame(outline, damage)
    s = _stations(damage)
    c = np.asarray(damage.crush, dtype=float)
    return origin + s[:, None] * along + c[:, None] * inward


def damage_centroid(damage: Damage) -> tuple[float, float]:
    """Station s (along the face, from the damage centre, in the stations' direction) and depth of the
    centroid of the crushed area (piecewise linear between stations) [m]."""
    s = _stations(damage)
    c = np.asarray(damage.crush, dtype=float)
    area = s_moment = d_moment = 0.0
    for i in range(len(c) - 1):
        w = s[i + 1] - s[i]
        a, b = c[i], c[i + 1]
        seg = w * (a + b) / 2
        if seg <= 0.0:
            continue
        s_moment += seg * (s[i] + w * (a + 2 * b) / (3 * (a + b)))
        d_moment += seg * (a * a + a * b + b * b) / (3 * (a + b))
        area += seg
    if area <= 0.0:
        raise ValueError("the crush profile has no area (every depth 0): no damage centroid")
    return s_moment / area, d_moment / area


def impulse_centre(outline: Outline, damage: Damage) -> np.ndarray:
    """Rule 1: the crushed-surface point at the damage centroid's station, body axes [m]."""
    origin, along, inward = _frame(outline, damage)
    s_bar, _ = damage_centroid(damage)
    depth = float(np.interp(s_bar, _stations(damage), np.asarray(damage.crush, dtype=float)))
    return origin + s_bar * along + depth * inward


@dataclass(frozen=True)
class Placement:
    """The impact geometry from the crush profiles (world frame, SI).

    Attributes
    ----------
    position2 : ndarray (2,)
        Vehicle 2's CG, vehicle 1's at ``position1``.
    point : ndarray (2,)
        The impulse centre (rule 1, both vehicles' coincide: rule 2).
    normal : float
        Direction of the crush-surface normal, from vehicle 2 into vehicle 1 [rad] (rule 3).
    stations : ndarray (2N, 2)
        Both vehicles' crushed-surface stations, world frame (the points rule 3's line is fitted to).
    spread : float
        RMS distance of those stations from the fitted line [m] (how plane the common surface is).
    """

    position1: np.ndarray
    position2: np.ndarray
    point: np.ndarray
    normal: float
    stations: np.ndarray
    spread: float


def place(outline1: Outline, damage1: Damage, heading1: float, outline2: Outline, damage2: Damage,
          heading2: float, position1=(0.0, 0.0)) -> Placement:
    """Rules 1-3 (module docstring): vehicle 2's position, the impulse centre and the contact plane."""
    p1 = np.asarray(position1, dtype=float)
    r1, r2 = rotation(heading1), rotation(heading2)
    point = p1 + r1 @ impulse_centre(outline1, damage1)
    p2 = point - r2 @ impulse_centre(outline2, damage2)
    pts = np.vstack([p1 + crushed_stations(outline1, damage1) @ r1.T, p2 + crushed_stations(outline2, damage2) @ r2.T])
    centred = pts - pts.mean(axis=0)
    _, sv, vt = np.linalg.svd(centred, full_matrices=False)
    n = vt[1]  # the line's normal: the direction of least spread
    if float(np.dot(n, p1 - point)) < 0.0:  # from vehicle 2 into vehicle 1: toward vehicle 1's CG
        n = -n
    spread = float(sv[1] / math.sqrt(len(pts)))
    return Placement(p1, p2, point, math.atan2(n[1], n[0]), pts, spread)

"""A driver that follows a path: pure pursuit, sampled at the driver's update interval.

The approach (:mod:`crashsim.motion.approach`) can be driven along a path instead of steered by
fixed angles.  The driver model is **pure pursuit** (R. C. Coulter, *Implementation of the Pure
Pursuit Path Tracking Algorithm*, Carnegie Mellon University, CMU-RI-TR-92-01, 1992; the
geometric preview steering of the vehicle-dynamics literature):

* the **reference point** P is the centre of the first unit's rear axle (the mean of its axles
  behind the first one: a tandem's centre);
* the **goal point** G lies on the path a preview distance ``L_d = max(preview_time v, min_preview)``
  ahead of P's nearest point on the path (v: the first unit's CG speed);
* the arc through P tangent to the unit's heading and through G has curvature
  ``kappa = 2 y_G / |PG|^2`` (y_G: G's lateral offset in the unit's frame); the steer angle of the
  first axle's centre is ``delta = atan(L kappa)``, L the wheelbase from the first axle to P,
  limited to ``max_steer`` and, from one update to the next, to ``max_steer_rate``;
* each steered wheel takes its Ackermann angle for that centre angle,
  ``tan(delta_side) = tan(delta) / (1 -+ tan(delta) t / (2 L))`` (t: the axle's track; left +,
  right -), so the two wheels turn about one centre.

The driver acts as a sampled-data controller with a zero-order hold: it looks at the vehicle
every ``update`` seconds and holds its steer angle until it looks again (a human driver corrects
in steps of about a tenth of a second; the hold makes every steer angle a scheduled wheel change
of the run, so the simulated approach is an ordinary run with a steering schedule, on either
engine).  On a circle of radius R the goal point lies on the circle and the arc through P and G
is that circle, so a vehicle without tyre slip tracks a circle exactly; tyre slip leaves a small
steady error, which the approach reports (``max_lateral_error``).

Pure functions of SI values; the run itself is :mod:`crashsim.motion.approach`'s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ScenarioError
from ..vehicles import Vehicle

__all__ = ["Path", "DriverSpec", "SteerGeometry", "steer_geometry", "pursuit_steer", "reference_slip", "ackermann",
           "SLIP_TIME"]

#: Below this speed of the reference point [m/s] its heading stands for its direction of travel.
_MIN_SPEED = 0.5
#: Time constant of the driver's estimate of the reference point's slip [s] (module docstring).
SLIP_TIME = 0.3
#: Points of a path closer than this are one point [m].
_SAME_POINT = 1e-9


@dataclass(frozen=True, eq=False)
class Path:
    """A polyline to follow, world frame, in the direction of travel [m].

    Parameters
    ----------
    points : array_like, shape (n, 2)
        At least two distinct points; consecutive duplicates are dropped.
    key : str
        Where it came from in the file, for messages.
    """

    points: np.ndarray
    key: str = "path"
    s: np.ndarray = field(init=False, repr=False)

    def __post_init__(self):
        p = np.asarray(self.points, dtype=float)
        if p.ndim != 2 or p.shape[1] != 2 or not np.all(np.isfinite(p)):
            raise ScenarioError("must be a list of finite [x, y] points", field=f"{self.key}.points")
        keep = np.concatenate([[True], np.hypot(*np.diff(p, axis=0).T) > _SAME_POINT])
        p = p[keep]
        if len(p) < 2:
            raise ScenarioError("needs at least two distinct points", field=f"{self.key}.points")
        object.__setattr__(self, "points", p)
        object.__setattr__(self, "s", np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(p, axis=0).T))]))

    @property
    def length(self) -> float:
        """Length of the polyline [m]."""
        return float(self.s[-1])

    def point(self, s: float) -> np.ndarray:
        """The point at arc length ``s`` [m]; beyond either end, on the end segment's line."""
        k = int(np.clip(np.searchsorted(self.s, s, side="right") - 1, 0, len(self.s) - 2))
        a, b = self.points[k], self.points[k + 1]
        return a + (s - self.s[k]) / (self.s[k + 1] - self.s[k]) * (b - a)

    def heading(self, s: float) -> float:
        """Direction of the path at arc length ``s`` [rad]."""
        k = int(np.clip(np.searchsorted(self.s, s, side="right") - 1, 0, len(self.s) - 2))
        d = self.points[k + 1] - self.points[k]
        return math.atan2(d[1], d[0])

    def curvature(self, s: float, h: float) -> float:
        """Mean curvature of the path over ``[s - h, s + h]`` [1/m] (its heading change over ``2 h``,
        left turns positive)."""
        s0, s1 = max(s - h, 0.0), min(s + h, self.length)
        if s1 <= s0:
            return 0.0
        turn = (self.heading(s1 - 1e-9) - self.heading(s0) + math.pi) % (2 * math.pi) - math.pi
        return turn / (s1 - s0)

    def locate(self, p, s_from: float = -math.inf, s_to: float = math.inf) -> tuple[float, float]:
        """``(s, offset)``: arc length of the nearest point of the path to ``p`` among the segments
        reaching into ``[s_from, s_to]``, and ``p``'s signed distance from it (left of the direction
        of travel positive) [m].  The first and last segments extend beyond the ends."""
        p = np.asarray(p, dtype=float)
        a, b = self.points[:-1], self.points[1:]
        lo = max(int(np.searchsorted(self.s, s_from, side="right")) - 1, 0)
        hi = min(int(np.searchsorted(self.s, s_to, side="left")), len(a) - 1)
        if hi < lo:
            lo = hi = min(max(lo, 0), len(a) - 1)
        a, b = a[lo:hi + 1], b[lo:hi + 1]
        d = b - a
        seg = np.hypot(d[:, 0], d[:, 1])
        t = np.einsum("ij,ij->i", p - a, d) / seg ** 2
        t_lo = np.where(np.arange(lo, hi + 1) == 0, -np.inf, 0.0)
        t_hi = np.where(np.arange(lo, hi + 1) == len(self.points) - 2, np.inf, 1.0)
        t = np.clip(t, t_lo, t_hi)
        q = a + t[:, None] * d
        dist = np.hypot(*(p - q).T)
        j = int(np.argmin(dist))
        cross = d[j, 0] * (p[1] - a[j, 1]) - d[j, 1] * (p[0] - a[j, 0])
        return float(self.s[lo + j] + t[j] * seg[j]), float(math.copysign(dist[j], cross))

    def min_radius(self) -> tuple[float, float]:
        """``(radius, s)``: the tightest turn of the polyline [m] and where it is.

        At each interior vertex the radius of the largest arc tangent to both segments that fits in
        the shorter half-segment, ``(l/2) / tan(dtheta/2)``: on a polyline sampled from an arc it is the
        arc's radius; at a sharp corner between long segments it is the tightest rounding of the corner
        a vehicle could drive.  Infinite for a straight path."""
        p = self.points
        if len(p) < 3:
            return math.inf, 0.0
        d = np.diff(p, axis=0)
        lengths = np.hypot(d[:, 0], d[:, 1])
        ang = np.arctan2(d[:, 1], d[:, 0])
        turn = np.abs((np.diff(ang) + math.pi) % (2 * math.pi) - math.pi)
        half = 0.5 * np.minimum(lengths[:-1], lengths[1:])
        with np.errstate(divide="ignore"):
            r = np.where(turn > 1e-12, half / np.tan(0.5 * np.minimum(turn, math.pi - 1e-9)), math.inf)
        k = int(np.argmin(r))
        return float(r[k]), float(self.s[k + 1])


@dataclass(frozen=True)
class DriverSpec:
    """The path-following driver of an approach (SI; module docstring).

    Parameters
    ----------
    path : Path
    preview_time : float
        Preview (look-ahead) time [s]: the goal point lies ``preview_time * v`` ahead.
    min_preview : float
        Shortest preview distance [m] (at low speed).
    max_steer : float
        Largest steer angle of the first axle's centre [rad].
    max_steer_rate : float
        Largest change of that angle per second [rad/s].
    update : float
        The driver's update interval [s] (zero-order hold between updates).
    key : str
        Where it came from in the file.
    """

    path: Path
    preview_time: float = 1.0
    min_preview: float = 4.0
    max_steer: float = math.radians(40.0)
    max_steer_rate: float = math.radians(30.0)
    update: float = 0.1
    key: str = "path"

    def __post_init__(self):
        for name, lo, hi in (("preview_time", 0.05, 10.0), ("min_preview", 0.5, 200.0),
                             ("max_steer", math.radians(1.0), math.radians(60.0)),
                             ("max_steer_rate", math.radians(1.0), math.radians(720.0)), ("update", 0.01, 1.0)):
            v = float(getattr(self, name))
            if not (math.isfinite(v) and lo <= v <= hi):
                raise ScenarioError(f"must lie in [{lo:.4g}, {hi:.4g}] (SI), got {v!r}", field=f"{self.key}.{name}")
            object.__setattr__(self, name, v)


@dataclass(frozen=True)
class SteerGeometry:
    """What the driver steers: the first unit's first axle, about the centre of its rear axles.

    Attributes
    ----------
    body : str
        The first unit.
    axle : int
        Index of the steered axle (0).
    x_front, x_rear : float
        Body-frame x of the steered axle and of the reference point (the rear axles' centre) [m].
    track : float
        Track of the steered axle [m].
    """

    body: str
    axle: int
    x_front: float
    x_rear: float
    track: float

    @property
    def wheelbase(self) -> float:
        return self.x_front - self.x_rear

    def min_radius(self, max_steer: float) -> float:
        """Smallest radius the reference point can follow at the steer limit [m]."""
        return self.wheelbase / math.tan(max_steer)


def steer_geometry(vehicle: Vehicle, key: str = "path") -> SteerGeometry:
    """The steered axle and the reference point of ``vehicle``'s first unit.

    Raises
    ------
    ScenarioError
        The first unit has fewer than two axles (nothing to steer about).
    """
    body = vehicle.bodies[0]
    if len(body.axles) < 2:
        raise ScenarioError(f"a driver steers the first unit's first axle about its rear axles; body {body.name!r} has "
                            f"{len(body.axles)} axle(s)", field=key)
    x_rear = float(np.mean([a.x for a in body.axles[1:]]))
    front = body.axles[0]
    if not front.x > x_rear:
        raise ScenarioError(f"the first axle of body {body.name!r} must lie ahead of its rear axles to steer it",
                            field=key)
    return SteerGeometry(body.name, 0, float(front.x), x_rear, float(front.track))


def pursuit_steer(geom: SteerGeometry, driver: DriverSpec, position, heading: float, speed: float,
                  s_hint: float, slip: float = 0.0) -> tuple[float, float, float]:
    """The unlimited pure-pursuit steer angle of the first axle's centre (module docstring).

    Parameters
    ----------
    position, heading, speed
        The first unit's CG [m], heading [rad] and CG speed [m/s].
    s_hint : float
        Arc length of the reference point at the previous update [m] (the search for the nearest
        point starts there, so a path that crosses itself is followed in order).
    slip : float
        The reference point's slip angle [rad], its direction of travel from its heading (the
        driver's smoothed estimate, :func:`reference_slip`): the arc starts along that direction.
    Returns
    -------
    (delta, s, offset)
        Steer angle [rad], the reference point's arc length on the path [m] and its signed
        offset from the path (left positive) [m].
    """
    c, sn = math.cos(heading), math.sin(heading)
    p = np.asarray(position, dtype=float) + geom.x_rear * np.array([c, sn])
    preview = max(driver.preview_time * speed, driver.min_preview)
    s, offset = driver.path.locate(p, s_hint - 2.0 * preview - 1.0, s_hint + 4.0 * preview + 1.0)
    g = driver.path.point(s + preview) - p
    if slip:
        # the reference point's direction of travel: its heading turned by its (smoothed) slip
        c, sn = math.cos(heading + slip), math.sin(heading + slip)
    xg, yg = c * g[0] + sn * g[1], -sn * g[0] + c * g[1]
    kappa = 2.0 * yg / (xg * xg + yg * yg)
    return math.atan(geom.wheelbase * kappa), s, offset


def reference_slip(geom: SteerGeometry, heading: float, velocity, yaw_rate: float) -> float:
    """The reference point's slip angle [rad]: its velocity's direction (the CG's velocity plus the
    yaw rate's share) less the heading; 0 below 0.5 m/s."""
    c, sn = math.cos(heading), math.sin(heading)
    vp = np.asarray(velocity, dtype=float) + yaw_rate * geom.x_rear * np.array([-sn, c])
    if float(np.hypot(*vp)) <= _MIN_SPEED:
        return 0.0
    return float((math.atan2(vp[1], vp[0]) - heading + math.pi) % (2 * math.pi) - math.pi)


def ackermann(geom: SteerGeometry, delta: float) -> tuple[float, float]:
    """(left, right) wheel angles [rad] turning about one centre with the axle's centre at ``delta``."""
    t = math.tan(delta)
    q = t * geom.track / (2.0 * geom.wheelbase)
    return math.atan(t / (1.0 - q)), math.atan(t / (1.0 + q))

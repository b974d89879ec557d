"""Road surface: a friction coefficient, a slope, and polygonal friction zones (world coordinates).

A wheel inside a zone polygon uses the zone's mu; zones listed later take precedence where
zones overlap; elsewhere the road's mu applies.  Polygons may be non-convex but must be
simple (no self-intersection).  The integrator locates every crossing of a zone edge by
a wheel with a solve_ivp event on :meth:`FrictionZone.signed_distance`, which is continuous
across edges and zero exactly on the boundary (positive inside).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import ScenarioError
from ..units import G0

__all__ = ["FrictionZone", "MAX_SLOPE", "Road", "point_distance", "points_in_polygon", "signed_distance",
           "slope_gravity"]

# Allowed friction coefficients: (0, _MU_MAX].
_MU_MAX = 2.0
#: Largest grade or cross-slope (rise over run) a road may have: 30 %, beyond the steepest public
#: roads (about 20 % for sustained grades, with short ramps steeper).
MAX_SLOPE = 0.30
#: Standard gravity [m/s^2] (the static loads use it too).
G = G0


def _check_slope(value, where: str) -> float:
    s = float(value)
    if not (-MAX_SLOPE <= s <= MAX_SLOPE):
        raise ScenarioError(f"slope must lie in [-{MAX_SLOPE:g}, {MAX_SLOPE:g}] (rise over run, "
                            f"-{100 * MAX_SLOPE:g} % to {100 * MAX_SLOPE:g} %), got {value!r}", field=where)
    return s


def slope_gravity(grade: float, cross_slope: float) -> tuple[float, float, float]:
    """Gravity on a plane road: its in-plane components and the normal factor.

    The road is the plane ``z = grade x + cross_slope y`` (rise over run along world x and y);
    the run-out's plane coordinates are measured in the road surface, x along the grade line and
    y square to it in the surface.  With the unit normal ``n = (-g_x, -g_y, 1) / s``,
    ``s = sqrt(1 + g_x^2 + g_y^2)``, gravity ``(0, 0, -g)`` splits into a normal part ``g / s``
    (per unit mass) and an in-plane part with components ``a_x = -g g_x / c`` along x
    (``c = sqrt(1 + g_x^2)``, i.e. ``-g sin(theta)`` for a grade angle theta) and
    ``a_y = -g g_y / (s c)`` along y (``-g sin(phi)`` for a cross-slope phi alone).

    Parameters
    ----------
    grade, cross_slope : float
        Rise over run along world x and y (0.05 for a 5 % grade up toward +x).

    Returns
    -------
    ax, ay : float
        In-plane gravity per unit mass [m/s^2].
    normal : float
        Normal load per unit weight on level ground, ``1 / s`` (``cos(theta)`` for one slope).
    """
    gx, gy = float(grade), float(cross_slope)
    c = math.sqrt(1.0 + gx * gx)
    s = math.sqrt(1.0 + gx * gx + gy * gy)
    return -G * gx / c, -G * gy / (s * c), 1.0 / s


def _check_mu(value, where: str) -> float:
    mu = float(value)
    if not (0.0 < mu <= _MU_MAX):
        raise ScenarioError(f"friction coefficient must lie in (0, {_MU_MAX}], got {value!r}", field=where)
    return mu


def _edges(polygon) -> tuple[np.ndarray, ...]:
    """Edge data of a polygon: start x, start y, edge x, edge y and 1/|edge|^2, each shape (n,)."""
    start = np.asarray(polygon, dtype=float)
    vec = np.roll(start, -1, axis=0) - start
    return start[:, 0].copy(), start[:, 1].copy(), vec[:, 0].copy(), vec[:, 1].copy(), 1.0 / np.sum(vec * vec, axis=1)


def _inside_rel(rx, ry, ex, ey) -> np.ndarray:
    """Even-odd rule from the points' offsets (rx, ry) to every edge start and the edge vectors."""
    straddle = (ry < 0) != (ry - ey < 0)  # the edge spans the point's y
    # the edge crosses the horizontal through the point at x_start + (py - y_start) ex / ey
    cross_right = rx * ey < ry * ex  # px < x_cross, written without division (sign of ey handled below)
    hits = straddle & (cross_right == (ey > 0))
    return (np.count_nonzero(hits, axis=-1) % 2) == 1


def _relative(pts: np.ndarray, x0: np.ndarray, y0: np.ndarray):
    return pts[..., 0:1] - x0, pts[..., 1:2] - y0


def _signed_distance(pts: np.ndarray, x0, y0, ex, ey, inv_len2) -> np.ndarray:
    rx, ry = _relative(pts, x0, y0)  # (..., n)
    s = np.minimum(np.maximum((rx * ex + ry * ey) * inv_len2, 0.0), 1.0)
    dx = rx - s * ex
    dy = ry - s * ey
    dist = np.sqrt(np.min(dx * dx + dy * dy, axis=-1))
    return np.where(_inside_rel(rx, ry, ex, ey), dist, -dist)


def points_in_polygon(points, polygon) -> np.ndarray:
    """Even-odd (crossing-number) point-in-polygon test; works for non-convex polygons.

    Parameters
    ----------
    points : array_like, shape (..., 2)
        Query points [m].
    polygon : array_like, shape (n, 2)
        Polygon vertices [m], either orientation, not repeated at the end.

    Returns
    -------
    ndarray of bool, shape (...)
        True strictly inside (points exactly on an edge may go either way; the run-out
        never relies on that, see :func:`signed_distance`).
    """
    x0, y0, ex, ey, _ = _edges(polygon)
    return _inside_rel(*_relative(np.asarray(points, dtype=float), x0, y0), ex, ey)


def signed_distance(points, polygon) -> np.ndarray:
    """Distance to the polygon boundary, positive inside and negative outside [m].

    Continuous everywhere (the sign flips only where the distance is zero), so a root of
    it is exactly a boundary crossing.

    Parameters
    ----------
    points : array_like, shape (..., 2)
    polygon : array_like, shape (n, 2)

    Returns
    -------
    ndarray, shape (...)
    """
    return _signed_distance(np.asarray(points, dtype=float), *_edges(polygon))


def point_distance(polygon):
    """``f(x, y)``: :func:`signed_distance` of one point to ``polygon`` [m], bit for bit, for a
    caller that asks it of one point at a time (the contact-point check of a Monte Carlo or fit
    sample): the same operations on Python floats, without NumPy's per-call overhead.

    Examples
    --------
    >>> square = [(0, 0), (2, 0), (2, 2), (0, 2)]
    >>> f = point_distance(square)
    >>> f(1.0, 0.5), f(3.0, 1.0), float(signed_distance([[3.0, 1.0]], square)[0])
    (0.5, -1.0, -1.0)
    """
    edges = list(zip(*(a.tolist() for a in _edges(polygon))))

    def distance(x: float, y: float) -> float:
        best = math.inf
        crossings = 0
        for x0, y0, ex, ey, inv in edges:
            rx, ry = x - x0, y - y0
            s = min(max((rx * ex + ry * ey) * inv, 0.0), 1.0)
            dx, dy = rx - s * ex, ry - s * ey
            best = min(best, dx * dx + dy * dy)
            if ((ry < 0) != (ry - ey < 0)) and ((rx * ey < ry * ex) == (ey > 0)):
                crossings += 1
        dist = math.sqrt(best)
        return dist if crossings % 2 == 1 else -dist

    return distance


def _segments_intersect(p1, p2, q1, q2) -> bool:
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    return (d1 * d2 < 0) and (d3 * d4 < 0)


@dataclass(frozen=True)
class FrictionZone:
    """A polygonal area of the road with its own friction coefficient.

    Parameters
    ----------
    polygon : array_like, shape (n, 2)
        Vertices in world coordinates [m], n >= 3, a simple (non-self-intersecting)
        polygon, convex or not, either orientation.
    mu : float
        Friction coefficient in the zone, in (0, 2].
    name : str
        Label for reports ("gravel shoulder").
    grade, cross_slope : float or None
        The zone's slope (rise over run along world x and y, within +-0.30); None: the road's.
    """

    polygon: tuple[tuple[float, float], ...]
    mu: float
    name: str = ""
    grade: float | None = None
    cross_slope: float | None = None

    def __post_init__(self):
        where = f"zone {self.name!r}"
        poly = np.asarray(self.polygon, dtype=float)
        if poly.ndim != 2 or poly.shape[1] != 2 or poly.shape[0] < 3 or not np.all(np.isfinite(poly)):
            raise ScenarioError(
                f"polygon must be a finite (n >= 3, 2) array of world points [m], got shape {poly.shape}",
                field=f"{where}.polygon",
            )
        if np.allclose(poly[0], poly[-1]):
            poly = poly[:-1]
            if poly.shape[0] < 3:
                raise ScenarioError("polygon needs at least 3 distinct vertices", field=f"{where}.polygon")
        x, y = poly[:, 0], poly[:, 1]
        area = 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
        if abs(area) < 1e-9:
            raise ScenarioError("polygon has zero area", field=f"{where}.polygon")
        if np.any(np.all(np.isclose(np.roll(poly, -1, axis=0), poly), axis=1)):
            raise ScenarioError("polygon has repeated consecutive vertices", field=f"{where}.polygon")
        n = len(poly)
        for i in range(n):
            for j in range(i + 2, n):
                if i == 0 and j == n - 1:
                    continue
                if _segments_intersect(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n]):
                    raise ScenarioError(
                        f"polygon edges {i} and {j} cross: the polygon must be simple", field=f"{where}.polygon"
                    )
        object.__setattr__(self, "polygon", tuple((float(a), float(b)) for a, b in poly))
        object.__setattr__(self, "mu", _check_mu(self.mu, f"{where}.mu"))
        for key in ("grade", "cross_slope"):
            if getattr(self, key) is not None:
                object.__setattr__(self, key, _check_slope(getattr(self, key), f"{where}.{key}"))
        object.__setattr__(self, "_edge_arrays", _edges(poly))

    @property
    def vertices(self) -> np.ndarray:
        """Polygon vertices, shape (n, 2) [m]."""
        return np.asarray(self.polygon)

    def contains(self, points) -> np.ndarray:
        """True for points inside the zone."""
        x0, y0, ex, ey, _ = self._edge_arrays
        return _inside_rel(*_relative(np.asarray(points, dtype=float), x0, y0), ex, ey)

    def signed_distance(self, points) -> np.ndarray:
        """Signed distance to the zone boundary [m], positive inside."""
        return _signed_distance(np.asarray(points, dtype=float), *self._edge_arrays)


@dataclass(frozen=True)
class Road:
    """The road surface of a run-out.

    Parameters
    ----------
    mu : float
        Tyre-road friction coefficient outside every zone, in (0, 2] (dry asphalt 0.7-0.8
        for cars; case-specific skid tests preferred).
    zones : sequence of FrictionZone
        Areas with their own mu (and slope, if given); later zones take precedence where zones
        overlap.
    grade, cross_slope : float
        Rise over run of the road surface along world x and y, within +-0.30 (0.05: 5 % up
        toward +x); see :func:`slope_gravity`.  Zero: a level road.
    """

    mu: float
    zones: tuple[FrictionZone, ...] = field(default=())
    grade: float = 0.0
    cross_slope: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "mu", _check_mu(self.mu, "road.mu"))
        object.__setattr__(self, "grade", _check_slope(self.grade, "road.grade"))
        object.__setattr__(self, "cross_slope", _check_slope(self.cross_slope, "road.cross_slope"))
        zones = tuple(self.zones)
        for z in zones:
            if not isinstance(z, FrictionZone):
                raise ScenarioError(f"must be a FrictionZone, got {type(z).__name__}", field="road.zones")
        object.__setattr__(self, "zones", zones)

    @property
    def sloped(self) -> bool:
        """Whether any part of the road is not level."""
        return (self.grade != 0.0 or self.cross_slope != 0.0
                or any((z.grade or 0.0) != 0.0 or (z.cross_slope or 0.0) != 0.0 for z in self.zones))

    def zone_slope(self, zone: FrictionZone) -> tuple[float, float]:
        """The grade and cross-slope inside ``zone`` (its own, or the road's where it gives none)."""
        return (self.grade if zone.grade is None else zone.grade,
                self.cross_slope if zone.cross_slope is None else zone.cross_slope)

    def slope_from_membership(self, inside: np.ndarray) -> np.ndarray:
        """Grade and cross-slope per point from zone membership flags, shape (n_points, 2)."""
        out = np.empty((inside.shape[0], 2))
        out[:, 0] = self.grade
        out[:, 1] = self.cross_slope
        for z, zone in enumerate(self.zones):
            out[inside[:, z]] = self.zone_slope(zone)
        return out

    def mu_from_membership(self, inside: np.ndarray) -> np.ndarray:
        """Friction coefficient per point from zone membership flags.

        Parameters
        ----------
        inside : ndarray of bool, shape (n_points, n_zones)

        Returns
        -------
        ndarray, shape (n_points,)
        """
        mu = np.full(inside.shape[0], self.mu)
        for z, zone in enumerate(self.zones):
            mu[inside[:, z]] = zone.mu
        return mu

    def membership(self, points) -> np.ndarray:
        """Zone membership of points, shape (n_points, n_zones), by the inside test."""
        pts = np.asarray(points, dtype=float).reshape(-1, 2)
        if not self.zones:
            return np.zeros((pts.shape[0], 0), dtype=bool)
        return np.stack([z.contains(pts) for z in self.zones], axis=1)

    def mu_at(self, points) -> np.ndarray:
        """Friction coefficient at world points [m], shape (n_points,)."""
        return self.mu_from_membership(self.membership(points))


"""Contact between vehicles, and between a vehicle and fixed obstacles, during the run-out.

What is modelled (the equations are in :mod:`crashsim.motion.kernels`)
----------------------------------------------------------------------
Every body with an outline (``Body.length`` and ``width``, a rectangle about
``outline_center``) takes part; a body without one cannot be touched.  Pairs are the bodies of
different vehicles, and every body with every fixed obstacle.

* **Detection** is an integration event on the separating-axis gap of the outlines (and of the
  obstacles' pieces): the instant of the first touch is located on the solver's dense output,
  and a step long enough to carry a body through a thin obstacle (or a corner through a
  corner) is searched at points no further apart than a fraction of the thinner piece, so
  nothing tunnels.
* **The rule: a point that closes at ``velocity_threshold`` or faster is an impact**, whatever
  the pair was doing: apart (the touch), in sustained contact (a new point arriving), or
  overlapped by the crush of the first impact (pressed ``arm_distance`` beyond that crush).  A
  point already pressed ``d`` deep counts its closing speed less ``omega d`` (``omega =
  sqrt(k / m)``, the contact's natural frequency): its force stops that much within about as much
  depth again, so a point driven in slowly deepens its contact instead of striking again and
  again.  **Every point touching at that instant is solved with it, at once** (:mod:`crashsim.motion.impacts`, :func:`crashsim.impact.multicontact.solve_contacts`):
  Newton's restitution e and Coulomb friction f at each point, the hitches as pins that hold, the
  closed articulation stops as one-sided rows, no moment impulse; with one point this is crashsim's
  impulse solver (Brach's equations with the friction law).  The points that strike are solved
  first, then those they drive in, then every point at once.  A car pinned between two vehicles is
  one problem of two pairs, not impulses chattering from one pair to the other.
* **Sustained contact** (below the threshold: resting and sliding contact): a penalty force at
  each contact point on the depth ``d`` beyond its allowance,
  ``F_n = max(0, k d + c d' min(1, d / DAMPER_DEPTH))`` with ``c = 2 zeta sqrt(k m)`` (``m`` the
  pair's reduced mass; ``zeta = 1``: no bounce; the damper takes hold over the first 2 mm, so a
  slow touch starts from zero force), and Coulomb friction ``f F_n`` against the sliding.  This is
  the force model of SMAC-type programs (EDSMAC, HVE's DyMESH) used only below the impulse
  threshold, so a car pinned against a trailer or a truck sliding along a guardrail does not
  chatter into thousands of impulses.  Bodies in contact stay within ``F_n / k`` of each other:
  1 cm per 100 kN of contact force at the default stiffness.  The pair leaves contact when the gap
  exceeds ``arm_distance``.
* **The crush of the impact that starts the run-out** is not a contact: a pair that overlaps
  (or nearly touches) at separation is *disarmed* (no force); it is armed once its outlines have
  separated by ``arm_distance``, and if instead it is pressed ``arm_distance`` deeper into the
  crush, it enters sustained contact with the crush as an allowance attached to the material
  (:func:`crashsim.motion.kernels.contacts.piece_points`), the force starting from zero there,
  or, closing at the threshold there, strikes.

Defaults and where they come from
---------------------------------
* ``restitution = 0.2``: secondary impacts are mostly at low speed; barrier tests give e of
  about 0.33 at low speed falling to about 0.15 beyond 0.2 m of crush (SAE 2010-01-0069,
  "Front and Rear Car Crush Coefficients for Energy Calculations"); 0.2 is inside that range.
* ``friction = 0.6``: the crush-surface friction coefficient of Brach's barrier examples
  (*Impact of Articulated Vehicles*, the rigid-barrier collisions, f = 0.6).
* ``velocity_threshold = 0.5 m/s``: below it a touch is resting contact, not an impact (game
  and robotics engines use 0.5-1 m/s thresholds for restitution; Box2D 1 m/s).
* ``stiffness = 1e7 N/m`` per contact point: a numerical choice, stiff enough that bodies in
  sustained contact stay within centimetres of each other, soft enough for the integrators.
  A scene may not set it below the heaviest vehicle's weight over ``WEIGHT_DEPTH`` (0.1 m).
* ``arm_distance = 0.05 m``.

Every value can be set for the scene and overridden per pair (scenario ``[contacts]``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..errors import ScenarioError

__all__ = ["ContactModel", "Obstacle", "CONTACT_KEYS", "WEIGHT_DEPTH", "convex_pieces", "polygon_is_simple"]

#: Deepest a contact may let the heaviest vehicle's weight press [m]: a stiffness below
#: weight / WEIGHT_DEPTH lets bodies sink through each other (the scenario refuses it).
WEIGHT_DEPTH = 0.1
#: Thickness of the fixed barrier of an impact behind its face [m] (a pier or wall is solid).
BARRIER_THICKNESS = 1.0
#: Half length of a barrier face given without an extent [m] ("an endless line").
BARRIER_HALF_LENGTH = 500.0


@dataclass(frozen=True)
class ContactModel:
    """How two bodies (or a body and an obstacle) meet during the run-out (module docstring).

    Parameters
    ----------
    restitution : float
        Coefficient of restitution e of a secondary impact, in [0, 1].
    friction : float
        Crush-surface friction f of a secondary impact (the friction law: no sliding at
        separation if |mu_max| <= f, else sliding with |mu| = f), and the Coulomb friction of
        sustained contact; >= 0.
    velocity_threshold : float
        Approach speed [m/s] at or above which a touch is an impact (impulse); below it the
        bodies go into sustained contact.  > 0.
    stiffness : float
        Penalty stiffness of sustained contact per contact point [N/m], > 0.
    damping_ratio : float
        Damping of sustained contact relative to critical, >= 0 (1: no bounce).
    arm_distance : float
        Gap [m] at which a pair leaves sustained contact or is armed after the crush, > 0.
    enabled : bool
        False: the pair passes through each other, as before crashsim modelled contact.
    """

    restitution: float = 0.2
    friction: float = 0.6
    velocity_threshold: float = 0.5
    stiffness: float = 1.0e7
    damping_ratio: float = 1.0
    arm_distance: float = 0.05
    enabled: bool = True

    def __post_init__(self):
        checks = (("restitution", 0.0, 1.0, False), ("friction", 0.0, 5.0, False),
                  ("velocity_threshold", 0.0, 50.0, True), ("stiffness", 0.0, 1e12, True),
                  ("damping_ratio", 0.0, 100.0, False), ("arm_distance", 0.0, 10.0, True))
        for name, lo, hi, open_lo in checks:
            v = float(getattr(self, name))
            ok = (v > lo if open_lo else v >= lo) and v <= hi and math.isfinite(v)
            if not ok:
                raise ScenarioError(f"must lie in {'(' if open_lo else '['}{lo:g}, {hi:g}], got {getattr(self, name)!r}",
                                    field=f"contacts.{name}")
            object.__setattr__(self, name, v)
        object.__setattr__(self, "enabled", bool(self.enabled))

    def updated(self, **changes) -> "ContactModel":
        """A copy with some values changed (validated)."""
        return replace(self, **changes)

    def to_dict(self) -> dict:
        return {f.name: getattr(self, f.name) for f in fields(self)}


#: The keys of a contact model, in order (scenario ``[contacts]`` and its pair overrides).
CONTACT_KEYS = tuple(f.name for f in fields(ContactModel))


def _orientation(poly: np.ndarray) -> float:
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def _segments_cross(p1, p2, q1, q2) -> bool:
    def orient(a, b, c):
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    d1, d2 = orient(q1, q2, p1), orient(q1, q2, p2)
    d3, d4 = orient(p1, p2, q1), orient(p1, p2, q2)
    return (d1 * d2 < 0) and (d3 * d4 < 0)


def polygon_is_simple(poly) -> tuple[int, int] | None:
    """None if the polygon's edges do not cross, else the first pair of crossing edges."""
    poly = np.asarray(poly, dtype=float)
    n = len(poly)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            if _segments_cross(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n]):
                return i, j
    return None


def _is_convex(poly: np.ndarray) -> bool:
    d = np.roll(poly, -1, axis=0) - poly
    cross = d[:, 0] * np.roll(d, -1, axis=0)[:, 1] - d[:, 1] * np.roll(d, -1, axis=0)[:, 0]
    return bool(np.all(cross >= -1e-12))


def convex_pieces(poly) -> list[np.ndarray]:
    """A simple polygon as convex pieces, each counter-clockwise: itself if convex, else triangles (ear clipping)."""
    poly = np.asarray(poly, dtype=float)
    if _orientation(poly) < 0:
        poly = poly[::-1]
    if _is_convex(poly):
        return [poly.copy()]
    idx = list(range(len(poly)))
    out = []
    guard = 0
    while len(idx) > 3 and guard < 10_000:
        guard += 1
        for k in range(len(idx)):
            a, b, c = poly[idx[k - 1]], poly[idx[k]], poly[idx[(k + 1) % len(idx)]]
            if (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]) <= 1e-12:
                continue  # reflex or flat vertex: not an ear
            tri = np.array([a, b, c])
            others = [poly[j] for j in idx if j not in (idx[k - 1], idx[k], idx[(k + 1) % len(idx)])]
            if any(_inside_triangle(p, tri) for p in others):
                continue
            out.append(tri)
            del idx[k]
            break
    out.append(poly[idx])
    return out


def _inside_triangle(p, tri) -> bool:
    def side(a, b):
        return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])

    return side(tri[0], tri[1]) > 0 and side(tri[1], tri[2]) > 0 and side(tri[2], tri[0]) > 0


def piece_thickness(piece: np.ndarray) -> float:
    """Smallest width of a convex piece [m] (its extent along its thinnest face normal)."""
    d = np.roll(piece, -1, axis=0) - piece
    n = np.stack([d[:, 1], -d[:, 0]], 1) / np.hypot(d[:, 0], d[:, 1])[:, None]
    proj = piece @ n.T  # (vertices, faces)
    return float(np.min(proj.max(0) - proj.min(0)))


@dataclass(frozen=True)
class Obstacle:
    """A fixed obstacle of the scene: a guardrail, a wall, a pole, a pier (world frame, SI).

    Parameters
    ----------
    name : str
        Unique in the scene (it names the contact pairs and impacts).
    points : sequence of (x, y)
        Its centre line as a polyline (>= 2 points) [m]; with ``closed`` its outline (>= 3
        points, simple).
    thickness : float
        Width of a polyline obstacle [m]: its faces lie ``thickness / 2`` either side of the
        centre line.  Unused for a closed outline.
    closed : bool
        The points are the outline of a solid obstacle (a pier, a building corner).
    contact : ContactModel or None
        How vehicles meet it (None: the scene's contact model).
    """

    name: str
    points: tuple
    thickness: float = 0.3
    closed: bool = False
    contact: ContactModel | None = None

    def __post_init__(self):
        where = f"obstacles[{self.name!r}]"
        if not self.name or not isinstance(self.name, str):
            raise ScenarioError(f"an obstacle needs a name, got {self.name!r}", field="obstacles.name")
        pts = np.asarray(self.points, dtype=float)
        need = 3 if self.closed else 2
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < need or not np.all(np.isfinite(pts)):
            raise ScenarioError(f"needs at least {need} finite points (x, y) [m], got {len(pts) if pts.ndim == 2 else pts.shape}",
                                field=f"{where}.points")
        if np.any(np.hypot(*np.diff(pts, axis=0).T) < 1e-6):
            raise ScenarioError("two consecutive points coincide", field=f"{where}.points")
        if self.closed:
            if abs(_orientation(pts)) < 1e-9:
                raise ScenarioError("the outline has zero area", field=f"{where}.points")
            crossing = polygon_is_simple(pts)
            if crossing:
                raise ScenarioError(f"the outline crosses itself (edges {crossing[0]} and {crossing[1]})",
                                    field=f"{where}.points")
        t = float(self.thickness)
        if not (0.0 < t <= 50.0):
            raise ScenarioError(f"must lie in (0, 50] m, got {self.thickness!r}", field=f"{where}.thickness")
        object.__setattr__(self, "points", tuple((float(a), float(b)) for a, b in pts))
        object.__setattr__(self, "thickness", t)

    def pieces(self) -> list[np.ndarray]:
        """Convex pieces in world coordinates, counter-clockwise."""
        pts = np.asarray(self.points)
        if self.closed:
            return convex_pieces(pts)
        out = []
        h = self.thickness / 2
        for a, b in zip(pts[:-1], pts[1:]):
            d = (b - a) / np.hypot(*(b - a))
            n = np.array([-d[1], d[0]])
            out.append(np.array([a - h * n, b - h * n, b + h * n, a + h * n]))
        return out

    @classmethod
    def barrier(cls, name: str, point, normal, tangent, extent=None, contact: ContactModel | None = None) -> "Obstacle":
        """The rigid barrier of an impact: its face through ``point`` along ``tangent``, solid behind it.

        ``normal`` points from the barrier into the vehicle; ``extent`` (from, to) along the
        tangent from the point [m] (default: a long face, 2 x ``BARRIER_HALF_LENGTH``).
        """
        p = np.asarray(point, dtype=float)
        n = np.asarray(normal, dtype=float)
        t = np.asarray(tangent, dtype=float)
        lo, hi = (-BARRIER_HALF_LENGTH, BARRIER_HALF_LENGTH) if extent is None else (float(extent[0]), float(extent[1]))
        back = -BARRIER_THICKNESS * n
        outline = [p + lo * t, p + hi * t, p + hi * t + back, p + lo * t + back]
        if _orientation(np.array(outline)) < 0:
            outline = outline[::-1]
        return cls(name, tuple(map(tuple, outline)), closed=True, contact=contact)

"""Typed description of one impact: who collides, where, and under which laws.

Everything here is SI and in the world frame of the scene. The equation numbers refer to
Brach's "Impact of Articulated Vehicles".
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, Mapping

import numpy as np

from ..errors import ScenarioError
from ..geometry import perp, rotate, unit
from ..vehicles import BodyState, Vehicle

__all__ = [
    "TangentialLaw",
    "CrushSurface",
    "VelocityConstraint",
    "ExternalImpulse",
    "ImpactProblem",
    "tyre_friction_impulse",
]

G0 = 9.80665  # standard gravity [m/s^2] (CGPM 1901); used by the tyre-friction helper only


@dataclass(frozen=True)
class TangentialLaw:
    """How the tangential impulse is found (Eqs. 4 and 8).

    kind
        ``"ratio"``: P_t = mu P_n with the given ``value`` = mu (Eq. 4).
        ``"fraction"``: P_t = mu P_n with mu = ``value`` x mu_max of this very impact (the
        PIM practice of giving the impulse ratio as a share of the critical one, "mu = 85 %
        of mu_0"); 1 is no sliding at separation, 0 a frictionless crush surface.
        ``"no_slide"``: no relative tangential velocity at separation (mu = mu_max).
        ``"friction"``: the paper's rule with Coulomb coefficient ``value`` = f: solve with
        no sliding at separation; if |mu_max| <= f that solution stands (Eq. 8), otherwise
        the surfaces slide throughout and mu = f sign(mu_max).
    value
        mu (any sign) for ``"ratio"``, the share 0 <= mu / mu_max <= 1 for ``"fraction"``,
        f >= 0 for ``"friction"``, unused for ``"no_slide"``.
    """

    kind: Literal["ratio", "fraction", "no_slide", "friction"] = "no_slide"
    value: float = 0.0

    def __post_init__(self):
        if self.kind not in ("ratio", "fraction", "no_slide", "friction"):
            raise ScenarioError(
                f"unknown tangential law {self.kind!r}; allowed 'ratio', 'fraction', 'no_slide', 'friction'",
                field="impact.tangential",
            )
        v = float(self.value)
        if not math.isfinite(v):
            raise ScenarioError(f"must be finite, got {self.value!r}", field=f"impact.{self.kind}")
        if self.kind == "friction" and v < 0:
            raise ScenarioError(f"friction f must be >= 0, got {v}", field="impact.friction")
        if self.kind == "fraction" and not 0.0 <= v <= 1.0:
            raise ScenarioError(f"mu_fraction = {v:g} is out of range; allowed 0 <= mu_fraction <= 1 (a share of "
                                "mu_max: 1 is no sliding at separation, 0 no tangential impulse)",
                                field="impact.mu_fraction")
        object.__setattr__(self, "value", v)


@dataclass(frozen=True)
class CrushSurface:
    """The crush surface between body 1 and body 2 (paper Fig. 2).

    Parameters
    ----------
    point : (float, float)
        Contact point (the "point" of the resultant crush impulse), world frame [m].
    normal_angle : float
        Direction of the surface normal n [rad], pointing from body 2 into body 1.
        The impulse P = P_n n + P_t t acts on body 1, -P on body 2.
    tangent_sign : {+1, -1}
        t = n rotated by +90 deg (``+1``) or by -90 deg (``-1``). The paper's examples use both:
        its barrier figure has t = n rotated +90 deg, its intersection figure t = -90 deg.
    restitution : float
        e in [0, 1] (Eq. 5).
    tangential : TangentialLaw
        The tangential law.
    moment_restitution : float
        e' in [0, 1], or -1 for no moment impulse (Eq. 6).
    """

    point: tuple[float, float]
    normal_angle: float
    restitution: float
    tangential: TangentialLaw = field(default_factory=TangentialLaw)
    moment_restitution: float = -1.0
    tangent_sign: int = 1

    def __post_init__(self):
        p = np.asarray(self.point, dtype=float)
        if p.shape != (2,) or not np.all(np.isfinite(p)):
            raise ScenarioError(f"must be a finite (x, y) point in metres, got {self.point!r}", field="impact.point")
        object.__setattr__(self, "point", (float(p[0]), float(p[1])))
        if not math.isfinite(float(self.normal_angle)):
            raise ScenarioError(f"must be finite, got {self.normal_angle!r}", field="impact.normal")
        object.__setattr__(self, "normal_angle", float(self.normal_angle))
        e = float(self.restitution)
        if not (0.0 <= e <= 1.0):
            raise ScenarioError(f"{self.restitution!r} is out of range; allowed [0, 1]", field="impact.restitution")
        object.__setattr__(self, "restitution", e)
        ep = float(self.moment_restitution)
        if not (ep == -1.0 or 0.0 <= ep <= 1.0):
            raise ScenarioError(
                f"{self.moment_restitution!r} is out of range; allowed -1 (no moment) or [0, 1]",
                field="impact.moment_restitution",
            )
        object.__setattr__(self, "moment_restitution", ep)
        if self.tangent_sign not in (1, -1):
            raise ScenarioError(f"must be +1 or -1, got {self.tangent_sign!r}", field="impact.tangent")

    @property
    def normal(self) -> np.ndarray:
        return unit(self.normal_angle)

    @property
    def tangent(self) -> np.ndarray:
        return unit(self.normal_angle + self.tangent_sign * math.pi / 2)


@dataclass(frozen=True)
class VelocityConstraint:
    """A velocity constraint with its own unknown external impulse (Eq. 7).

    The velocity of ``point`` (world frame, attached to ``body``) along the unit ``direction``
    is held at ``value`` after the impact; an unknown impulse along ``direction`` at ``point``
    enforces it. Holding a tractor's lateral velocity at two points fixes its lateral
    velocity and yaw rate (the paper's Table 8).
    """

    body: str
    point: tuple[float, float]
    direction: float
    value: float = 0.0
    name: str = ""

    def __post_init__(self):
        p = np.asarray(self.point, dtype=float)
        if p.shape != (2,) or not np.all(np.isfinite(p)):
            raise ScenarioError(f"must be a finite (x, y) point, got {self.point!r}", field=f"constraint {self.name!r}.point")
        object.__setattr__(self, "point", (float(p[0]), float(p[1])))
        for attr in ("direction", "value"):
            v = float(getattr(self, attr))
            if not math.isfinite(v):
                raise ScenarioError(f"must be finite, got {v!r}", field=f"constraint {self.name!r}.{attr}")
            object.__setattr__(self, attr, v)


@dataclass(frozen=True)
class ExternalImpulse:
    """A known external impulse (tyre friction over the impact, a kerb) on one body.

    ``impulse`` is the world-frame impulse vector [N s] acting at world ``point`` [m].
    """

    body: str
    point: tuple[float, float]
    impulse: tuple[float, float]
    name: str = ""

    def __post_init__(self):
        for attr in ("point", "impulse"):
            p = np.asarray(getattr(self, attr), dtype=float)
            if p.shape != (2,) or not np.all(np.isfinite(p)):
                raise ScenarioError(
                    f"must be a finite 2-vector, got {getattr(self, attr)!r}", field=f"external {self.name!r}.{attr}"
                )
            object.__setattr__(self, attr, (float(p[0]), float(p[1])))


def tyre_friction_impulse(friction: float, load: float, duration: float, direction: float) -> np.ndarray:
    """Impulse of tyre friction over an impact: f x load x duration, along ``direction``.

    Parameters
    ----------
    friction : float
        Tyre-road friction coefficient f (>= 0).
    load : float
        Normal load on the sliding tyres [N] (a weight: m g0 for a fully loaded body).
    duration : float
        Impact duration [s] (0.1-0.2 s is typical).
    direction : float
        World direction of the impulse [rad] (opposite the tyres' sliding velocity).

    Returns
    -------
    ndarray (2,)
        Impulse vector [N s]. Paper Table 7: 0.6 x 36222 N x 0.15 s = 3260 N s.
    """
    for name, v in (("friction", friction), ("load", load), ("duration", duration)):
        if not (math.isfinite(float(v)) and float(v) >= 0):
            raise ScenarioError(f"must be a finite number >= 0, got {v!r}", field=f"tyre_friction.{name}")
    return float(friction) * float(load) * float(duration) * unit(float(direction))


@dataclass(frozen=True)
class ImpactProblem:
    """One two-vehicle (or vehicle-barrier) impact, ready to solve.

    Parameters
    ----------
    vehicles : tuple of Vehicle
        The two vehicles; a rigid barrier is a one-body vehicle of infinite mass.
    states : mapping body name -> BodyState
        State of every body just before the impact (world frame). Bodies of one vehicle
        must have equal pin velocities (see ``crashsim.vehicles.chain_states``).
    body1, body2 : str
        The bodies in contact; the crush normal points from body2 into body1.
    surface : CrushSurface
    constraints : tuple of VelocityConstraint
    external : tuple of ExternalImpulse
    """

    vehicles: tuple[Vehicle, ...]
    states: Mapping[str, BodyState]
    body1: str
    body2: str
    surface: CrushSurface
    constraints: tuple[VelocityConstraint, ...] = ()
    external: tuple[ExternalImpulse, ...] = ()

    def __post_init__(self):
        object.__setattr__(self, "vehicles", tuple(self.vehicles))
        object.__setattr__(self, "constraints", tuple(self.constraints))
        object.__setattr__(self, "external", tuple(self.external))
        object.__setattr__(self, "states", dict(self.states))
        if len(self.vehicles) != 2:
            raise ScenarioError(f"an impact needs exactly 2 vehicles (one may be a barrier), got {len(self.vehicles)}",
                                field="vehicles")
        names = [b.name for v in self.vehicles for b in v.bodies]
        if len(set(names)) != len(names):
            raise ScenarioError(f"body names must be unique across the scene, got {names}", field="vehicles")
        vnames = [v.name for v in self.vehicles]
        if len(set(vnames)) != len(vnames):
            raise ScenarioError(f"vehicle names must be unique, got {vnames}", field="vehicles")
        for n in names:
            if n not in self.states:
                raise ScenarioError(f"no state given for body {n!r}", field=f"states.{n}")
        for n in self.states:
            if n not in names:
                raise ScenarioError(f"state for unknown body {n!r}; bodies are {names}", field=f"states.{n}")
        owner = {b.name: v.name for v in self.vehicles for b in v.bodies}
        for which, n in (("body1", self.body1), ("body2", self.body2)):
            if n not in owner:
                raise ScenarioError(f"unknown body {n!r}; bodies are {names}", field=f"impact.{which}")
        if owner[self.body1] == owner[self.body2]:
            raise ScenarioError(
                f"body1 {self.body1!r} and body2 {self.body2!r} belong to the same vehicle {owner[self.body1]!r}",
                field="impact.body2",
            )
        if all(v.is_barrier for v in self.vehicles):
            raise ScenarioError("both vehicles are barriers (infinite mass): nothing can move", field="vehicles")
        fixed = {b.name for v in self.vehicles for b in v.bodies if b.is_fixed}
        for c in self.constraints:
            if c.body not in owner:
                raise ScenarioError(f"unknown body {c.body!r}; bodies are {names}", field=f"constraint {c.name!r}.body")
            if c.body in fixed:
                raise ScenarioError(f"body {c.body!r} is a barrier; its velocity cannot be constrained",
                                    field=f"constraint {c.name!r}.body")
        for what, items in (("constraint", self.constraints), ("external impulse", self.external)):
            named = [it.name for it in items if it.name]
            dup = sorted({n for n in named if named.count(n) > 1})
            if dup:
                raise ScenarioError(f"{what} names must be unique (results are keyed by name); repeated: {dup}",
                                    field=f"impact.{what.replace(' ', '_')}s")
        for x in self.external:
            if x.body not in owner:
                raise ScenarioError(f"unknown body {x.body!r}; bodies are {names}", field=f"external {x.name!r}.body")
        for v in self.vehicles:
            _check_pins(v, self.states)

    @property
    def bodies(self):
        return tuple(b for v in self.vehicles for b in v.bodies)

    def vehicle_of(self, body: str) -> Vehicle:
        for v in self.vehicles:
            if any(b.name == body for b in v.bodies):
                return v
        raise KeyError(body)


def _check_pins(vehicle: Vehicle, states: Mapping[str, BodyState], tol_pos: float = 1e-3, tol_vel: float = 1e-3):
    """Bodies of one vehicle must meet at their pins, with equal pin velocities."""
    for front, rear, hitch in zip(vehicle.bodies[:-1], vehicle.bodies[1:], vehicle.hitches):
        sf, sr = states[front.name], states[rear.name]
        a = rotate(hitch.front_point, sf.heading)
        b = rotate(hitch.rear_point, sr.heading)
        gap = np.asarray(sf.position) + a - np.asarray(sr.position) - b
        if np.hypot(*gap) > tol_pos:
            raise ScenarioError(
                f"pin positions of {front.name!r} and {rear.name!r} are {np.hypot(*gap):.4g} m apart; "
                f"allowed <= {tol_pos} m (place the bodies with crashsim.vehicles.chain_states)",
                field=f"states.{rear.name}.position",
            )
        dv = (np.asarray(sf.velocity) + sf.yaw_rate * perp(a)) - (np.asarray(sr.velocity) + sr.yaw_rate * perp(b))
        if np.hypot(*dv) > tol_vel:
            raise ScenarioError(
                f"pin velocities of {front.name!r} and {rear.name!r} differ by {np.hypot(*dv):.4g} m/s; "
                f"allowed <= {tol_vel} m/s before the impact",
                field=f"states.{rear.name}.velocity",
            )

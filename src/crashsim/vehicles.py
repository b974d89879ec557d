"""Vehicle description: rigid bodies joined by hitch pins in a chain.

All quantities are SI (kg, kg m^2, m, rad) and expressed in body axes: origin at the body's
CG, x forward, y left. Instances are frozen; a missing physical parameter is an error at
construction, never a silent default.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from .errors import ScenarioError
from .geometry import rotate, perp

__all__ = ["Axle", "Body", "Hitch", "Vehicle", "BodyState", "chain_states", "MAX_ROLLOVER_THRESHOLD"]


#: Largest rollover threshold accepted [g]: a rigid body's t / (2 h) is about 1.2-1.5 for the
#: lowest sports cars; a heavy truck's tilt-table threshold is 0.25-0.6.
MAX_ROLLOVER_THRESHOLD = 1.5


def _positive(name: str, value: float, *, allow_inf: bool = False) -> float:
    v = float(value)
    if not (v > 0) or (math.isinf(v) and not allow_inf) or math.isnan(v):
        allowed = "(0, inf]" if allow_inf else "(0, inf)"
        raise ScenarioError(f"must be a positive number in {allowed}, got {value!r}", field=name)
    return v


def _point(name: str, value) -> tuple[float, float]:
    if type(value) is tuple and len(value) == 2 and all(type(c) in (float, np.float64) for c in value):
        x, y = float(value[0]), float(value[1])  # the common case, without NumPy's per-call cost
        if math.isfinite(x) and math.isfinite(y):
            return (x, y)
    arr = np.asarray(value, dtype=float)
    if arr.shape != (2,) or not np.all(np.isfinite(arr)):
        raise ScenarioError(f"must be a finite 2-vector (x, y) in metres, got {value!r}", field=name)
    return (float(arr[0]), float(arr[1]))


@dataclass(frozen=True)
class Axle:
    """One axle of a body (each axle of a tandem group is its own Axle).

    Parameters
    ----------
    x : float
        Longitudinal position of the axle from the body CG [m], forward positive.
    track : float
        Distance between the left and right tyre contact centres [m].
    dual : bool
        Dual tyres on each side (modelled as one contact per side with the summed load
        and cornering stiffness).
    name : str
        Label for reports ("steer", "drive 1", ...).
    """

    x: float
    track: float
    dual: bool = False
    name: str = ""

    def __post_init__(self):
        if not math.isfinite(float(self.x)):
            raise ScenarioError(f"must be finite, got {self.x!r}", field=f"axle {self.name!r}.x")
        _positive(f"axle {self.name!r}.track", self.track)


@dataclass(frozen=True)
class Body:
    """A rigid body of a vehicle (a car, a tractor, a semitrailer, a dolly).

    Parameters
    ----------
    name : str
        Unique name within the scene.
    mass : float
        Mass [kg]; ``math.inf`` for a rigid barrier.
    yaw_inertia : float
        Yaw moment of inertia about the CG [kg m^2]; ``math.inf`` for a barrier.
    length, width : float, optional
        Overall outline dimensions [m] (plots, evidence), centred on ``outline_center``.
    outline_center : (float, float)
        Centre of the outline rectangle in body axes [m] (the CG is rarely at mid-length).
    axles : tuple of Axle
        Axles for the run-out (may be empty for an impact-only study).
    cg_height : float, optional
        CG height above ground [m], used only by the load-transfer option.
    rollover_threshold : float, optional
        Lateral acceleration [g] at which the body rolls (its static rollover threshold, e.g.
        from a tilt table), in (0, :data:`MAX_ROLLOVER_THRESHOLD`]; None: the default
        ``0.75 t / (2 h)`` when the rollover check is on (:mod:`crashsim.motion.rollover`).
    roll_coupled : bool
        The hitch by which this body is towed carries roll moment (a fifth wheel, stiff in roll):
        with load transfer, the body's roll moment is shared with the towing body in proportion to
        the hitch's static vertical load (:func:`crashsim.motion.loads.load_transfer_matrix`).
        Default False: free in roll (a ball, a drawbar eye).
    contact_height : float, optional
        Height above ground [m] at which contact forces (other vehicles, obstacles) act on this
        body, used only by the load-transfer option: their roll and pitch moments about the ground
        against the CG's move load between the wheels (:func:`crashsim.motion.kernels.equations.specific_force`).
        None: at the CG height (a push there moves no load).
    """

    name: str
    mass: float
    yaw_inertia: float
    length: float | None = None
    width: float | None = None
    outline_center: tuple[float, float] = (0.0, 0.0)
    axles: tuple[Axle, ...] = ()
    cg_height: float | None = None
    rollover_threshold: float | None = None
    roll_coupled: bool = False
    contact_height: float | None = None

    def __post_init__(self):
        if not self.name or not isinstance(self.name, str):
            raise ScenarioError(f"body name must be a non-empty string, got {self.name!r}", field="name")
        object.__setattr__(self, "mass", _positive(f"{self.name}.mass", self.mass, allow_inf=True))
        object.__setattr__(
            self, "yaw_inertia", _positive(f"{self.name}.yaw_inertia", self.yaw_inertia, allow_inf=True)
        )
        if math.isinf(self.mass) != math.isinf(self.yaw_inertia):
            raise ScenarioError(
                f"mass={self.mass} and yaw_inertia={self.yaw_inertia}: a barrier needs both infinite, "
                "a movable body both finite",
                field=f"{self.name}.mass",
            )
        for attr in ("length", "width", "cg_height", "contact_height"):
            v = getattr(self, attr)
            if v is not None:
                object.__setattr__(self, attr, _positive(f"{self.name}.{attr}", v))
        thr = self.rollover_threshold
        if thr is not None and not (0.0 < thr <= MAX_ROLLOVER_THRESHOLD):
            raise ScenarioError(f"rollover threshold {thr!r} g outside (0, {MAX_ROLLOVER_THRESHOLD:g}] g",
                                field=f"{self.name}.rollover_threshold")
        object.__setattr__(self, "outline_center", _point(f"{self.name}.outline_center", self.outline_center))
        object.__setattr__(self, "axles", tuple(self.axles))

    @property
    def is_fixed(self) -> bool:
        """True for a rigid barrier (infinite mass: its velocity cannot change)."""
        return math.isinf(self.mass)

    def outline(self) -> np.ndarray | None:
        """Outline rectangle corners in body axes, shape (4, 2), or None if no size given."""
        if self.length is None or self.width is None:
            return None
        cx, cy = self.outline_center
        hl, hw = self.length / 2, self.width / 2
        return np.array([[cx + hl, cy + hw], [cx - hl, cy + hw], [cx - hl, cy - hw], [cx + hl, cy - hw]])


@dataclass(frozen=True)
class Hitch:
    """A pin joining two consecutive bodies of a vehicle (fifth wheel, ball, drawbar eye).

    Parameters
    ----------
    front_point : (float, float)
        Pin position in the front body's axes [m] (e.g. fifth wheel 3.1 m behind the tractor CG
        is ``(-3.1, 0)``).
    rear_point : (float, float)
        Pin position in the rear body's axes [m] (kingpin ahead of the trailer CG, ``(3.991, 0)``).
    articulation_limit : float, optional
        Largest |articulation angle| [rad] before the bodies meet (jack-knife stop).
    yaw_locked : bool
        The joint is locked in yaw at zero articulation (a C-dolly's two drawbars on the trailer
        ahead): a weld in the plane, free in pitch.  The run-out holds ``psi_front - psi_rear = 0``
        by one more multiplier row (a moment on both bodies); ``articulation_limit`` is then
        meaningless and must be None.  See ``docs/heavy-vehicles.md`` ("C-dollies").
    """

    front_point: tuple[float, float]
    rear_point: tuple[float, float]
    articulation_limit: float | None = None
    yaw_locked: bool = False

    def __post_init__(self):
        object.__setattr__(self, "front_point", _point("hitch.front_point", self.front_point))
        object.__setattr__(self, "rear_point", _point("hitch.rear_point", self.rear_point))
        if self.articulation_limit is not None:
            lim = float(self.articulation_limit)
            if not (0 < lim <= math.pi):
                raise ScenarioError(
                    f"must lie in (0, pi] rad, got {self.articulation_limit!r}", field="hitch.articulation_limit"
                )
            object.__setattr__(self, "articulation_limit", lim)
        object.__setattr__(self, "yaw_locked", bool(self.yaw_locked))
        if self.yaw_locked and self.articulation_limit is not None:
            raise ScenarioError("a yaw-locked hitch (C-dolly) does not articulate: it has no articulation_limit",
                                field="hitch.articulation_limit")


@dataclass(frozen=True)
class Vehicle:
    """A chain of bodies, front to rear; ``hitches[i]`` joins ``bodies[i]`` and ``bodies[i+1]``."""

    name: str
    bodies: tuple[Body, ...]
    hitches: tuple[Hitch, ...] = field(default=())

    def __post_init__(self):
        object.__setattr__(self, "bodies", tuple(self.bodies))
        object.__setattr__(self, "hitches", tuple(self.hitches))
        if not self.bodies:
            raise ScenarioError("a vehicle needs at least one body", field=f"{self.name}.bodies")
        if len(self.hitches) != len(self.bodies) - 1:
            raise ScenarioError(
                f"{len(self.bodies)} bodies need {len(self.bodies) - 1} hitches, got {len(self.hitches)}",
                field=f"{self.name}.hitches",
            )
        names = [b.name for b in self.bodies]
        if len(set(names)) != len(names):
            raise ScenarioError(f"body names must be unique, got {names}", field=f"{self.name}.bodies")
        if self.hitches and self.hitches[0].yaw_locked:
            raise ScenarioError(
                f"the hitch of {self.bodies[1].name!r} is yaw-locked (a C-dolly), but the body ahead, "
                f"{self.bodies[0].name!r}, is the first body, not a trailer; a C-dolly is locked to the trailer "
                "ahead (allowed on the hitch of the third body or later)",
                field=f"{self.name}.hitches",
            )
        if any(b.is_fixed for b in self.bodies) and len(self.bodies) > 1:
            raise ScenarioError("a barrier (infinite mass) must be a vehicle of one body", field=f"{self.name}.bodies")

    @property
    def is_barrier(self) -> bool:
        return self.bodies[0].is_fixed

    @property
    def mass(self) -> float:
        return float(sum(b.mass for b in self.bodies))

    def body(self, name: str) -> Body:
        for b in self.bodies:
            if b.name == name:
                return b
        raise ScenarioError(f"no body named {name!r}; bodies are {[b.name for b in self.bodies]}", field=self.name)


@dataclass(frozen=True)
class BodyState:
    """Planar state of one body in the world frame (SI: m, rad, m/s, rad/s)."""

    position: tuple[float, float]
    heading: float
    velocity: tuple[float, float]
    yaw_rate: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "position", _point("position", self.position))
        object.__setattr__(self, "velocity", _point("velocity", self.velocity))
        for attr in ("heading", "yaw_rate"):
            v = float(getattr(self, attr))
            if not math.isfinite(v):
                raise ScenarioError(f"must be finite, got {v!r}", field=attr)
            object.__setattr__(self, attr, v)


def chain_states(
    vehicle: Vehicle,
    position,
    heading: float,
    velocity,
    yaw_rates=None,
    articulation=None,
) -> dict[str, BodyState]:
    """States of all bodies of a vehicle from its first body's state, hitch-consistent.

    Parameters
    ----------
    position, heading, velocity
        State of the first (front) body: CG [m], heading [rad], CG velocity [m/s].
    yaw_rates : sequence of float, optional
        Yaw rate of each body [rad/s] (default all zero).
    articulation : sequence of float, optional
        Articulation angle at each hitch [rad], front heading minus rear heading (default 0).

    Returns
    -------
    dict
        Body name -> BodyState, with the pins coinciding and equal pin velocities
        (rear CG velocity = front pin velocity - w_rear x rear pin offset).
    """
    n = len(vehicle.bodies)
    yaw_rates = [0.0] * n if yaw_rates is None else [float(w) for w in yaw_rates]
    articulation = [0.0] * (n - 1) if articulation is None else [float(a) for a in articulation]
    if len(yaw_rates) != n:
        raise ScenarioError(f"needs {n} yaw rates, got {len(yaw_rates)}", field=f"{vehicle.name}.yaw_rates")
    if len(articulation) != n - 1:
        raise ScenarioError(
            f"needs {n - 1} articulation angles, got {len(articulation)}", field=f"{vehicle.name}.articulation"
        )
    pos = np.asarray(position, dtype=float)
    vel = np.asarray(velocity, dtype=float)
    psi = float(heading)
    out = {vehicle.bodies[0].name: BodyState(tuple(pos), psi, tuple(vel), yaw_rates[0])}
    for i, hitch in enumerate(vehicle.hitches):
        a = rotate(hitch.front_point, psi)
        pin = pos + a
        pin_vel = vel + yaw_rates[i] * perp(a)
        psi = psi - articulation[i]
        b = rotate(hitch.rear_point, psi)
        pos = pin - b
        vel = pin_vel - yaw_rates[i + 1] * perp(b)
        out[vehicle.bodies[i + 1].name] = BodyState(tuple(pos), psi, tuple(vel), yaw_rates[i + 1])
    return out

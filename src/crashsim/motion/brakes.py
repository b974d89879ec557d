"""Air brakes of a heavy vehicle: timing and build-up per unit, brake capacity, ABS.

Model (docs/heavy-vehicles.md, "Air-brake timing, brake capacity and ABS")
--------------------------------------------------------------------------
The driver moves the brake control at ``apply`` (and lets go at ``release``), both on the
time line of the wheel settings they belong to (the run-out: after separation, negative
for brakes applied before the impact; the approach: after the start of braking).  The
brake force of every braked wheel of a unit is a ramp of the application level ``r(t)``::

    r(t) = clip((t - t_on) / rise, 0, 1)                       t < t_off
    r(t) = r(t_off) (1 - clip((t - t_off) / fall, 0, 1))       t >= t_off
    t_on = apply + delay,   t_off = release + release_delay

and the wheel's brake force is ``F_b = r(t) C (1 - phi) / 2`` with ``C`` the brake capacity
of its axle (the brake force at the road the axle's brakes develop at full application,
both sides) and ``phi`` the unit's fraction of brakes out of adjustment (taken as
delivering no force).  The tyre law (:mod:`crashsim.motion.tyres`) gets the longitudinal
demand ``min(F_b + f_r N, mu N)``: below the tyre's limit the wheel brakes and keeps
rolling, at the limit it locks.

**ABS.**  A wheel of a unit with ABS never locks: its demand is held to ``eta`` times the
longitudinal component of the sliding force, ``min(F_b + f_r N, eta mu N |u| / |v|)``
(``eta`` the modulation efficiency, ``|u| / |v|`` the cosine of the slip angle, both
regularised like the tyre law), so the tyre law's lock-up condition ``|F_x| >= mu N |u| /
|v|`` is never met and the wheel keeps the lateral force the friction circle leaves.  It
leaves no locked-wheel mark; it slides (and marks) only where its lateral demand saturates.

Defaults of the timing (per unit type; :data:`DEFAULT_TIMING`): the pressure in a brake
chamber is zero for ``delay`` and then rises linearly to the full-application pressure
(taken as 100 psi, the initial reservoir pressure of FMVSS 121's timing test) over ``rise``;
``delay`` is half the application time ``T_a`` of the unit and the 60 psi point falls at
``T_a``: ``delay = T_a / 2``, ``rise = (T_a / 2) / 0.6``.  Release likewise: the pressure
holds for ``release_delay = T_r / 2`` and falls to 5 psi (5 %) at ``T_r``: ``fall = (T_r / 2)
/ 0.95``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Mapping

import numpy as np

from ..errors import ScenarioError

__all__ = [
    "UNIT_TYPES",
    "APPLICATION_TIMES",
    "DEFAULT_TIMING",
    "BrakeUnit",
    "AirBrakes",
    "unit_type_default",
    "ramp_level",
    "ramp_stopping_distance",
    "MAX_BRAKE_TIME",
    "MAX_CAPACITY",
]

#: Unit types with their own brake timing.
UNIT_TYPES = ("tractor", "towing_trailer", "dolly", "last_trailer")

#: Application and release times ``(T_a, T_r)`` [s] per unit type: from the first movement of
#: the brake control until each brake chamber of the unit reaches 60 psi (application), and
#: until it falls to 5 psi from a full application (release).  The tractor's are FMVSS 121
#: S5.3.3 and S5.3.4 (49 CFR 571.121: 0.45 s and 0.55 s); the towed units' are the air-timing
#: chart of a brake manufacturer for combinations (Bendix, trailer ABS service data A-18:
#: towing trailer 0.50 / 1.00 s, converter dolly 0.55 / 1.10 s, last trailer 0.60 / 1.20 s).
APPLICATION_TIMES = MappingProxyType({
    "tractor": (0.45, 0.55),
    "towing_trailer": (0.50, 1.00),
    "dolly": (0.55, 1.10),
    "last_trailer": (0.60, 1.20),
})

#: Full-application chamber pressure [psi] taken for the ramp, the 60 psi and 5 psi marks of the
#: standard's timing clauses as fractions of it.
_FULL_PSI = 100.0
_APPLY_MARK = 60.0 / _FULL_PSI
_RELEASE_MARK = 1.0 - 5.0 / _FULL_PSI


def _timing(ta: float, tr: float) -> dict[str, float]:
    return {"delay": ta / 2.0, "rise": (ta / 2.0) / _APPLY_MARK,
            "release_delay": tr / 2.0, "fall": (tr / 2.0) / _RELEASE_MARK}


#: Default ``delay``, ``rise``, ``release_delay``, ``fall`` [s] per unit type (module docstring).
DEFAULT_TIMING = MappingProxyType({k: MappingProxyType(_timing(*v)) for k, v in APPLICATION_TIMES.items()})

#: Largest delay, rise or fall time accepted [s] (a longer one is a typing slip).
MAX_BRAKE_TIME = 10.0
#: Largest brake capacity of one axle [N] (500 kN: several times what a loaded axle can use).
MAX_CAPACITY = 5.0e5


def unit_type_default(n_bodies: int, index: int, name: str) -> str:
    """The unit type of body ``index`` of ``n_bodies`` when the file does not give it: the first body
    is the tractor (the power unit), the last a last trailer, a body named like a dolly a dolly, any
    other a towing trailer."""
    if index == 0:
        return "tractor"
    if index == n_bodies - 1:
        return "last_trailer"
    return "dolly" if "dolly" in name.lower() else "towing_trailer"


def _time(value, key: str, lo: float = 0.0) -> float:
    v = float(value)
    if not (math.isfinite(v) and lo <= v <= MAX_BRAKE_TIME):
        raise ScenarioError(f"must lie in [{lo:g}, {MAX_BRAKE_TIME:g}] s, got {value!r} s", field=key)
    return v


@dataclass(frozen=True)
class BrakeUnit:
    """The air brakes of one body (unit).

    Parameters
    ----------
    capacity : tuple of float
        Brake capacity of each axle of the body, front to rear [N]: the brake force at the road its
        brakes develop at full application (both sides; 0 for an unbraked axle).
    unit_type : {"tractor", "towing_trailer", "dolly", "last_trailer"}
        Which default timing applies.
    delay, rise, release_delay, fall : float, optional
        Timing [s] (None: :data:`DEFAULT_TIMING` of ``unit_type``).
    out_of_adjustment : float
        Fraction in [0, 1] of the unit's brake capacity lost to brakes out of adjustment.
    abs : bool
        Whether the unit's wheels have ABS.
    """

    capacity: tuple[float, ...]
    unit_type: str
    delay: float | None = None
    rise: float | None = None
    release_delay: float | None = None
    fall: float | None = None
    out_of_adjustment: float = 0.0
    abs: bool = False

    def __post_init__(self):
        if self.unit_type not in UNIT_TYPES:
            raise ScenarioError(f"must be one of {UNIT_TYPES}, got {self.unit_type!r}", field="type")
        cap = tuple(float(c) for c in self.capacity)
        for c in cap:
            if not (math.isfinite(c) and 0.0 <= c <= MAX_CAPACITY):
                raise ScenarioError(f"must lie in [0, {MAX_CAPACITY:g}] N per axle, got {c!r} N", field="capacity")
        object.__setattr__(self, "capacity", cap)
        default = DEFAULT_TIMING[self.unit_type]
        for key in ("delay", "rise", "release_delay", "fall"):
            value = getattr(self, key)
            object.__setattr__(self, key, default[key] if value is None else _time(value, key))
        phi = float(self.out_of_adjustment)
        if not (0.0 <= phi <= 1.0):
            raise ScenarioError(f"must lie in [0, 1], got {self.out_of_adjustment!r}", field="out_of_adjustment")
        object.__setattr__(self, "out_of_adjustment", phi)
        object.__setattr__(self, "abs", bool(self.abs))


@dataclass(frozen=True)
class AirBrakes:
    """The air brakes of a vehicle: when the control moves and what each unit does.

    Parameters
    ----------
    units : mapping of body name to BrakeUnit
        The braked bodies; a body without an entry has no air brakes (its wheels keep their
        tyre state, e.g. FMVSS 121's unbraked control trailer).
    apply : float
        Time of the first movement of the brake control [s] on the time line of the wheel
        settings (may be negative in a run-out: brakes applied before the impact).
    release : float, optional
        Time the control is let go [s] (None: held).
    abs_efficiency : float
        Modulation efficiency ``eta`` in (0, 1) of ABS (read only where a unit has ABS).
    """

    units: Mapping[str, BrakeUnit] = field(default_factory=dict)
    apply: float = 0.0
    release: float | None = None
    abs_efficiency: float = 0.0

    def __post_init__(self):
        object.__setattr__(self, "units", MappingProxyType(dict(self.units)))
        a = float(self.apply)
        if not (math.isfinite(a) and abs(a) <= 60.0):
            raise ScenarioError(f"must lie in [-60, 60] s, got {self.apply!r} s", field="apply")
        object.__setattr__(self, "apply", a)
        if self.release is not None:
            r = float(self.release)
            if not (math.isfinite(r) and a <= r <= 600.0):
                raise ScenarioError(f"must lie in [apply = {a:g} s, 600] s, got {self.release!r} s", field="release")
            object.__setattr__(self, "release", r)
        if any(u.abs for u in self.units.values()):
            eta = float(self.abs_efficiency)
            if not (0.0 < eta < 1.0):
                raise ScenarioError(f"ABS needs abs_efficiency in (0, 1), got {self.abs_efficiency!r}",
                                    field="abs_efficiency")
            object.__setattr__(self, "abs_efficiency", eta)

    def times(self, body: str) -> tuple[float, float, float, float]:
        """``(t_on, rise, t_off, fall)`` [s] of ``body``'s brakes (``t_off`` infinite without a release)."""
        u = self.units[body]
        t_off = math.inf if self.release is None else self.release + u.release_delay
        return self.apply + u.delay, u.rise, t_off, u.fall


def ramp_level(t, t_on, rise, t_off, fall):
    """Application level ``r(t)`` in [0, 1] of a brake (module docstring); NumPy arrays or floats."""
    t = np.asarray(t, dtype=float)
    up = np.clip((t - t_on) / rise, 0.0, 1.0) if rise > 0 else (t >= t_on).astype(float)
    held = np.clip((t_off - t_on) / rise, 0.0, 1.0) if rise > 0 else float(t_off >= t_on)
    down = np.clip((t - t_off) / fall, 0.0, 1.0) if fall > 0 else (t >= t_off).astype(float)
    return np.where(t < t_off, up, held * (1.0 - down))


def ramp_stopping_distance(v0: float, decel: float, delay: float, rise: float) -> tuple[float, float]:
    """Stopping distance [m] and time [s] of a straight stop from ``v0`` [m/s] whose deceleration is
    zero for ``delay`` [s], rises linearly to ``decel`` [m/s^2] over ``rise`` [s] and then stays.

    ``d = v0 T_d + (v0 T_r - a T_r^2 / 6) + v1^2 / (2 a)`` with ``v1 = v0 - a T_r / 2`` when the
    vehicle is still moving at the end of the rise; else the stop falls inside it, at
    ``t = sqrt(2 v0 T_r / a)`` after the delay, ``d = v0 T_d + v0 t - a t^3 / (6 T_r)``.
    """
    if decel <= 0:
        raise ValueError("decel must be > 0")
    v1 = v0 - decel * rise / 2.0
    if v1 > 0:
        return (v0 * delay + v0 * rise - decel * rise * rise / 6.0 + v1 * v1 / (2.0 * decel),
                delay + rise + v1 / decel)
    ts = math.sqrt(2.0 * v0 * rise / decel)
    return v0 * delay + v0 * ts - decel * ts**3 / (6.0 * rise), delay + ts

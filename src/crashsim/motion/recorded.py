"""An approach driven by a recorder's pre-crash table: steering and speed as they were recorded.

An event data recorder keeps the last seconds before the trigger as samples at fixed times
(typically 0.1-0.5 s apart, times relative to the trigger): speed, brake switch, accelerator and,
in newer vehicles, the steering-wheel angle.  ``[vehicles.<name>.approach.recorded]`` gives such a
table; the approach then runs from its first sample to the impact (``time`` = minus the first
sample's time) and is driven by it:

* **steering** -- the steering-wheel angle divided by the overall steering ratio is the steer
  angle of the first unit's first axle's centre, linear between samples, held from the last
  sample to the impact; its wheels take the Ackermann angles of
  :func:`~crashsim.motion.driver.ackermann`.  Open loop: the angles are scheduled changes of
  one run.
* **speed** -- a speed controller sets, every ``update``, one longitudinal force coefficient
  ``d`` (force over load) on every rolling or braked wheel of the vehicle so that the first
  body's CG speed follows the table:

  .. math::  d = \\frac{1}{g}\\left(-\\dot v_\\text{table} + \\frac{v - v_\\text{table}}{\\tau}\\right)

  with the table's slope over the interval and the time constant ``tau``.  Above a wheel's
  rolling resistance ``f_r`` the wheel is braked with ``b = (d - f_r) / mu`` (the tyre model's
  demand ``min(b mu + f_r, mu) N``); below it the wheel rolls with its resistance lowered to
  ``max(d, 0)``: crashsim's model has no drive force, so the engine's share of holding a speed is
  taken as cancelling rolling resistance, and a recorded rise of speed (which needs the engine)
  is refused where the table is read.  The wheels the file locks or jams stay as they are.

Like the path driver (:func:`crashsim.motion.approach._driven_run`) the controller runs one
interval at a time and the whole approach is then run once with its decisions as scheduled
wheel changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ScenarioError
from .loads import STANDARD_GRAVITY

__all__ = ["RecordedDrive", "SPEED_RISE_TOLERANCE", "speed_demand"]

#: A recorded speed may rise above the lowest speed recorded before it by this much [m/s] (1 km/h,
#: the resolution 49 CFR 563 asks of a recorded speed) before the table is refused: no drive force.
SPEED_RISE_TOLERANCE = 1.0 / 3.6


@dataclass(frozen=True)
class RecordedDrive:
    """A recorder's table driving the approach (SI).

    Parameters
    ----------
    t : tuple of float
        Sample times relative to the impact [s], increasing, the first < 0.
    speed : tuple of float, optional
        Recorded CG speed of the first body at each sample [m/s]; None: the file's wheel settings
        brake the vehicle (the speed at the start is then given or solved as for any approach).
    steer : tuple of float, optional
        Steer angle of the first axle's centre at each sample [rad], counter-clockwise positive
        (the steering-wheel angle over the steering ratio); None: the file's settings steer.
    update : float
        Interval of the speed controller's decisions and of the steering's steps [s].
    speed_time : float
        Time constant ``tau`` of the speed controller [s].
    key : str
        Where it came from in the file, for messages.
    """

    t: tuple
    speed: tuple | None = None
    steer: tuple | None = None
    update: float = 0.05
    speed_time: float = 0.3
    key: str = "approach.recorded"

    def __post_init__(self):
        t = np.asarray(self.t, dtype=float)
        if t.ndim != 1 or len(t) < 2 or not np.all(np.isfinite(t)):
            raise ScenarioError("a recorded table needs at least two samples with finite times",
                                field=f"{self.key}.samples")
        if np.any(np.diff(t) <= 0.0):
            j = int(np.argmax(np.diff(t) <= 0.0)) + 1
            raise ScenarioError(f"sample times must increase: {t[j]:g} s follows {t[j - 1]:g} s",
                                field=f"{self.key}.samples[{j}].time")
        if t[0] >= 0.0:
            raise ScenarioError(f"the first sample lies at {t[0]:g} s: the table must start before the impact "
                                "(negative times)", field=f"{self.key}.samples[0].time")
        for name in ("speed", "steer"):
            v = getattr(self, name)
            if v is not None and len(v) != len(t):
                raise ScenarioError(f"{len(v)} {name} values for {len(t)} samples", field=f"{self.key}.samples")
        if self.speed is None and self.steer is None:
            raise ScenarioError("the table drives nothing: give speed or steering in its samples",
                                field=f"{self.key}.samples")
        if not (self.update > 0.0 and self.speed_time > 0.0):
            raise ScenarioError("update and speed_time must be > 0 s", field=self.key)

    @property
    def duration(self) -> float:
        """From the first sample to the impact [s]: the approach's ``time``."""
        return -float(self.t[0])

    def steer_at(self, t) -> np.ndarray:
        """Steer angle of the first axle's centre [rad] at times ``t`` from the first sample."""
        return np.interp(np.asarray(t, dtype=float) + float(self.t[0]), self.t, self.steer)

    def speed_at(self, t) -> np.ndarray:
        """The table's speed [m/s] at times ``t`` from the first sample (held after the last)."""
        return np.interp(np.asarray(t, dtype=float) + float(self.t[0]), self.t, self.speed)


def speed_demand(drive: RecordedDrive, t0: float, speed: float) -> float:
    """The longitudinal force coefficient ``d`` [-] of the interval starting ``t0`` [s] after the first
    sample, with the first body's CG speed ``speed`` [m/s] there (the module docstring's law)."""
    dt = drive.update
    v0, v1 = (float(v) for v in drive.speed_at([t0, t0 + dt]))
    return ((v0 - v1) / dt + (speed - v0) / drive.speed_time) / STANDARD_GRAVITY


def wheel_setting_for(demand: float, rolling_resistance: float, mu: float) -> dict:
    """The changes of a rolling or braked wheel that give it the longitudinal coefficient ``demand``:
    braked with ``b = (d - f_r) / mu`` above its rolling resistance ``f_r``, rolling with the resistance
    lowered to ``max(d, 0)`` below it."""
    if demand > rolling_resistance:
        return {"state": "braked", "brake": min((demand - rolling_resistance) / mu, 1.0) if mu > 0 else 1.0,
                "rolling_resistance": rolling_resistance}
    return {"state": "rolling", "brake": 0.0, "rolling_resistance": max(demand, 0.0)}


def rising_speed(t, speed, tolerance: float = SPEED_RISE_TOLERANCE) -> tuple[int, int] | None:
    """``(i, j)``: the first sample ``j`` whose speed exceeds the lowest before it (at sample ``i``) by
    more than ``tolerance`` [m/s]; None where the speed never rises that much."""
    low, at = math.inf, 0
    for j, v in enumerate(speed):
        if v > low + tolerance:
            return at, j
        if v < low:
            low, at = v, j
    return None

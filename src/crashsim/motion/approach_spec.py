"""What a vehicle's approach to the impact is (:class:`ApproachSpec`) and the checks of a driven path a
scenario file is refused by (:func:`path_start`, :func:`check_path`): the light half of the approach,
read by the scenario loader without the run-out engines it is simulated with
(:mod:`crashsim.motion.approach`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import ScenarioError
from ..vehicles import Vehicle
from .driver import DriverSpec, steer_geometry
from .recorded import RecordedDrive
from .wheels import WheelSettings

__all__ = ["ApproachSpec", "path_start", "check_path"]


@dataclass(frozen=True)
class ApproachSpec:
    """How one vehicle approached the impact (SI).

    Parameters
    ----------
    speed : float or None
        CG speed of the first body at the start of braking [m/s]; None: solved from the
        vehicle's speed at impact.
    distance, time : float or None
        Path length of the first body's CG [m], or time [s], from the start of braking to the
        impact (exactly one of ``distance``, ``time`` and ``start_position``).
    start_position, start_heading : optional
        First body's CG [m] and heading [rad] at the start of braking, world frame.
    reaction_time : float
        Perception-reaction time before braking [s] (constant speed).
    wheels : WheelSettings
        Wheel states during the approach; scheduled changes at times after the start of braking.
    tolerance : float
        With a start position: the largest miss of the impact position [m].
    key : str
        Where it came from in the file (``vehicles.<name>.approach``), for messages.
    articulation : tuple of float, optional
        Articulation angle at each hitch at the start [rad] (front heading minus rear heading,
        front to rear); None: straight.
    yaw_rates : tuple of float, optional
        Yaw rate of each body at the start [rad/s]; None: none.
    solve_articulation : bool
        Solve the articulation at the start (``articulation`` is the first guess) so that the
        approach ends at the impact configuration's articulation.
    driver : DriverSpec, optional
        A driver that steers along a path (with ``distance``: the start lies that far before the
        impact position along the path).
    recorded : RecordedDrive, optional
        A recorder's table that steers and brakes the vehicle (:mod:`crashsim.motion.recorded`);
        the approach then runs from its first sample (``time`` is minus that sample's time, and is
        set from it when not given).
    """

    wheels: WheelSettings
    speed: float | None = None
    distance: float | None = None
    time: float | None = None
    start_position: tuple[float, float] | None = None
    start_heading: float | None = None
    reaction_time: float = 0.0
    tolerance: float = 0.5
    key: str = "approach"
    articulation: tuple | None = None
    yaw_rates: tuple | None = None
    solve_articulation: bool = False
    driver: DriverSpec | None = None
    recorded: RecordedDrive | None = None

    def __post_init__(self):
        if self.recorded is not None:
            if self.driver is not None or self.distance is not None or self.start_position is not None:
                raise ScenarioError("a recorded table drives the approach from its first sample: give neither a path, "
                                    "distance nor start_position", field=f"{self.key}.recorded")
            if self.recorded.speed is not None and self.wheels.brakes is not None:
                raise ScenarioError("the recorded speeds set the brakes; the approach's air brakes would too: remove "
                                    f"{self.key}.brakes", field=f"{self.key}.brakes")
            if self.time is None:
                object.__setattr__(self, "time", self.recorded.duration)
            elif abs(self.time - self.recorded.duration) > 1e-9:
                raise ScenarioError(f"time = {self.time:g} s, but the recorded table starts {self.recorded.duration:g} s "
                                    "before the impact: remove time", field=f"{self.key}.time")
        if self.driver is not None and (self.distance is None or self.time is not None
                                        or self.start_position is not None):
            raise ScenarioError("with a path give distance (how far before the impact position the approach starts, "
                                "along the path), and neither time nor start_position", field=f"{self.key}.distance")
        given = [k for k in ("distance", "time", "start_position") if getattr(self, k) is not None]
        if len(given) != 1:
            raise ScenarioError("give exactly one of distance (from the start of braking to the impact), time, or "
                                f"start_position with start_heading; got {given or 'none'}", field=self.key)
        if (self.start_position is None) != (self.start_heading is None):
            raise ScenarioError("start_position and start_heading go together", field=f"{self.key}.start_heading")

    @property
    def mode(self) -> str:
        if self.driver is not None:
            return "path"
        if self.recorded is not None:
            return "recorded"
        return "distance" if self.distance is not None else "time" if self.time is not None else "start"


def path_start(vehicle: Vehicle, driver: DriverSpec, target, distance: float, tolerance: float):
    """``(position, heading, s)``: the first unit's CG and heading at the start of a driven approach
    and the reference point's arc length there: the reference point on the path ``distance`` before
    the point of the path nearest the impact position ``target``, the unit along the path.

    Raises
    ------
    ScenarioError
        The path passes the impact position further than ``tolerance`` plus 2 m (the CG sits a
        little inside a curve of the reference point's path), or does not reach back ``distance``.
    """
    geom = steer_geometry(vehicle, driver.key)
    path = driver.path
    s_imp, off = path.locate(target)
    if abs(off) > tolerance + 2.0:
        raise ScenarioError(f"passes {abs(off):.2f} m from the first body's position at impact; the path must reach the "
                            f"impact position (within {tolerance + 2.0:.2f} m: the tolerance plus 2 m)",
                            field=f"{driver.key}.points")
    if s_imp > path.length + 1e-9 or s_imp < -1e-9:
        raise ScenarioError("does not reach the impact position: the point nearest it lies beyond the path's "
                            f"{'end' if s_imp > 0 else 'start'}; extend the path past the impact",
                            field=f"{driver.key}.points")
    s0 = s_imp - distance
    if s0 < -1e-9:
        raise ScenarioError(f"starts only {s_imp:.2f} m before the impact position along it; the approach's distance of "
                            f"{distance:.2f} m needs the path to reach back that far: extend the path or shorten distance",
                            field=f"{driver.key}.points")
    h0 = path.heading(max(s0, 0.0))
    p_ref = path.point(max(s0, 0.0))
    cg = p_ref - geom.x_rear * np.array([math.cos(h0), math.sin(h0)])
    return cg, h0, max(s0, 0.0)


def check_path(vehicle: Vehicle, driver: DriverSpec) -> None:
    """Refuse a path the vehicle cannot follow: a turn tighter than its smallest radius at ``max_steer``."""
    geom = steer_geometry(vehicle, driver.key)
    r_path, s_at = driver.path.min_radius()
    r_min = geom.min_radius(driver.max_steer)
    if r_path < r_min:
        raise ScenarioError(
            f"turns at a radius of {r_path:.2f} m ({s_at:.1f} m along it), tighter than the smallest radius of "
            f"{vehicle.name!r} at max_steer = {math.degrees(driver.max_steer):.1f} deg: {r_min:.2f} m (wheelbase "
            f"{geom.wheelbase:.2f} m / tan(max_steer)); ease the turn to at least {r_min:.2f} m or raise max_steer to "
            f"{math.degrees(math.atan(geom.wheelbase / r_path)):.1f} deg", field=f"{driver.key}.points")

"""The typed SI objects a scenario file becomes: :class:`Scenario`, :class:`RunoutSpec`, :class:`ApproachInput`,
:class:`MapLine`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..errors import ScenarioError
from ..evidence.checks import Evidence
from ..impact import ImpactProblem
from ..motion import ContactModel, Road, RunoutOptions
from ..survey.frame import SceneFrame
from ..survey.schema import MAP_LINE_STYLES
from ..vehicles import Vehicle


@dataclass(frozen=True, eq=False)
class MapLine:
    """A line of the road layout (``[[map.lines]]``): drawn on the scene figure, no physics.

    Attributes
    ----------
    name : str
        Label ("" for none).
    style : str
        One of :data:`MAP_LINE_STYLES`.
    points : ndarray, shape (n, 2)
        The polyline in the world frame [m], n >= 2 (read-only).
    color : str or None
        A matplotlib colour replacing the style's own; None for the style's.
    layer : str
        The survey file's layer or point code the line was imported from (``survey.imported``);
        "" for a line written in the scenario file. The figure's legend names it.
    imported_as : str
        What the survey mapping made of that layer: ``"line"``, ``"gouge"`` or ``"debris"``
        (``survey.files.map.kind``); "" for a line written in the scenario file.
    """

    name: str
    style: str
    points: np.ndarray
    color: str | None = None
    layer: str = ""
    imported_as: str = ""

    def __post_init__(self) -> None:
        pts = np.array(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
            raise ScenarioError(f"a map line needs at least 2 points (x, y), got shape {pts.shape}", field="points")
        if self.style not in MAP_LINE_STYLES:
            raise ScenarioError(f"unknown style {self.style!r}; allowed {', '.join(MAP_LINE_STYLES)}", field="style")
        pts.flags.writeable = False
        object.__setattr__(self, "points", pts)

    def _key(self) -> tuple:
        return (self.name, self.style, self.color, self.layer, self.imported_as, self.points.shape,
                self.points.tobytes())

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, MapLine):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


@dataclass(frozen=True)
class Scenario:
    """A loaded scenario: typed SI inputs, ready to run.

    Attributes
    ----------
    path : str or None
    title, source, units : str
        ``units`` is "SI" or "US"; with ``[scenario] speed_unit`` a :class:`crashsim.units.DisplaySystem`
        (equal to that string) carrying it, which every output of the scene reads.
    vehicles : tuple of Vehicle
        Including a barrier vehicle if the file has ``[barrier]``.
    states : dict of BodyState
        Every body's state at impact.
    impact : ImpactProblem
    runout : RunoutSpec or None
        Road, solver options and wheel settings; None for an impact-only scenario.
    evidence : Evidence
        What was measured at the scene (possibly empty).
    data : dict
        The validated file contents (SI floats), for traceability.
    map_lines : tuple of MapLine
        The road layout of ``[[map.lines]]`` (drawing only; empty without a ``[map]``).
    approaches : dict of ApproachResult
        By vehicle name: the simulated approach of each vehicle with ``[vehicles.<name>.approach]``
        (its velocity and yaw rates at impact are in ``states``); empty until the approaches are
        simulated (by the scene run, or :func:`crashsim.scene.run.simulate_approaches`; the loader does
        not simulate).
    approach_inputs : dict of ApproachInput
        By vehicle name: what each vehicle's approach needs (its spec, road and options, the
        speed at impact if the file gives it), built and checked at load.
    descriptions : dict of str
        By vehicle name: the file's ``description`` of each vehicle ("" if none), for figures and reports.
    survey_frame : SceneFrame or None
        Where the scene lies on its survey (``[survey]`` with files, an underlay or a CRS); None
        for a scene not placed on a survey.
    north : float or None
        ``[map] north``: the bearing of the scene's +Y axis, clockwise from north [rad]; None if the
        file does not give it.
    barrier_extent : (float, float) or None
        (from, to) along the crush tangent [m] of the ``[barrier]`` face, from the contact point;
        (-inf, inf) for an endless one; None without a barrier.
    load_warnings : tuple of str
        Doubtful values the loader accepted; the run's warnings carry them.
    file_data : dict or None
        The raw file contents the loader built this scenario from (see the field's comment).
    """

    path: str | None
    title: str
    source: str
    units: str
    vehicles: tuple[Vehicle, ...]
    states: dict
    impact: ImpactProblem
    runout: "RunoutSpec | None"
    evidence: Evidence
    data: dict = field(repr=False)
    map_lines: tuple[MapLine, ...] = ()
    approaches: dict = field(default_factory=dict)
    approach_inputs: dict = field(default_factory=dict)
    descriptions: dict = field(default_factory=dict)
    survey_frame: SceneFrame | None = None
    north: float | None = None
    barrier_extent: tuple[float, float] | None = None
    #: Doubtful values the loader accepted (an angle of more than a turn: "192 rad" meant as
    #: degrees?); the run's warnings carry them
    load_warnings: tuple[str, ...] = ()
    #: The file contents (raw, as from TOML) the loader built this scenario from (None for one built
    #: another way): what fit, Monte Carlo and posterior samples vary. :func:`dataclasses.replace`
    #: keeps them, so a scenario changed by ``replace`` is still varied as its file gives it.
    file_data: dict | None = field(default=None, repr=False, compare=False)

    @property
    def approaches_simulated(self) -> bool:
        """True when every vehicle's approach has been simulated (its states at impact are final)."""
        return len(self.approaches) == len(self.approach_inputs)


@dataclass(frozen=True)
class RunoutSpec:
    """What the run-out needs besides the separation states (all SI)."""

    road: Road
    options: RunoutOptions
    wheels: dict  # vehicle name -> WheelSettings
    level: str = "articulated"
    accuracy: float | None = None
    accuracy_heading: float | None = None
    contact: ContactModel = field(default_factory=ContactModel)
    pair_contact: dict = field(default_factory=dict)  # (name, name) -> ContactModel
    obstacles: tuple = ()  # Obstacle, the barrier of the impact first


@dataclass(frozen=True)
class ApproachInput:
    """What a vehicle's approach needs, built and checked at load (SI).

    Attributes
    ----------
    spec : ApproachSpec
    road : Road
        The approach's road (the run-out's unless ``approach.road_friction`` is given).
    options : RunoutOptions
    speed_at_impact : float or None
        The file's speed at impact (``vehicles.<name>.speed``); None when the approach gives
        the speed at the start of braking.
    through_impact : bool
        The approach's wheel settings carry on into the run-out on one time line
        (:func:`crashsim.motion.approach.continued_wheels`).
    runout_wheels : WheelSettings or None
        The file's own run-out wheel settings of the vehicle (with ``through_impact`` their
        scheduled changes apply on top of the continued ones).
    """

    spec: Any
    road: Road
    options: RunoutOptions
    speed_at_impact: float | None
    through_impact: bool = False
    runout_wheels: Any = None

"""Post-impact run-out to rest of single and articulated vehicles.

Public API
----------
run_runout, Runout
    The one run-out entry: a scene's movable vehicles at a fidelity level (``level=``), on an
    engine (``engine=`` or ``RunoutOptions.engine``), optionally to an accuracy target
    (``accuracy=``); what the scene run, the approach and the warm-up call.
simulate_runout, simulate_scene
    Integrate the run-out of one vehicle / of a whole scene (every vehicle together, with
    contact between them and with fixed obstacles: secondary impacts by the impulse solver,
    sustained contact as a force), with SciPy's integrators (``RunoutOptions(engine="scipy")``,
    the default) or the numba-compiled engine (``engine="compiled"``: same model, events and
    result, for fits and Monte Carlo).
ContactModel, Obstacle
    How bodies meet (restitution, friction, thresholds), and fixed obstacles.
make_hitch_consistent
    Project impact-solver velocities onto the hitch constraints.
RunoutOptions, Road, FrictionZone, WheelSettings, WheelSetting, ScheduledChange
    Inputs.
SceneRunout, RunoutResult, SecondaryImpact, PairSummary, BodyRunout, WheelTrack, TrackSegment,
HitchHistory, RunoutEvent, BodyHistory
    Results.
StateLayout
    The named state vector.
tyre_forces, lateral_force
    Pure tyre force laws (shared with the pymunk cross-check).
static_loads, StaticLoads
    Static wheel, axle and hitch loads.

The numeric core never imports pymunk, matplotlib or file formats; numba is imported only
when the compiled engine is first used.
"""

from .contact import ContactModel, Obstacle
from .hitches import make_hitch_consistent
from .layout import StateLayout
from .loads import StaticLoads, static_loads
from .options import ENGINES, METHODS, SCHEMES, RunoutOptions
from .result import (BodyHistory, BodyRunout, HitchHistory, PairSummary, RunoutEvent, RunoutResult, SceneRunout,
                     SecondaryImpact, TrackSegment, WheelTrack)
from .road import FrictionZone, Road
from .runout import Runout, run_runout
from .simulate import simulate_runout, simulate_scene
from .tyres import LATERAL_MODELS, lateral_force, tyre_forces
from .wheels import WHEEL_STATES, ScheduledChange, WheelSetting, WheelSettings

__all__ = [
    "run_runout",
    "Runout",
    "simulate_runout",
    "simulate_scene",
    "make_hitch_consistent",
    "ContactModel",
    "Obstacle",
    "SceneRunout",
    "SecondaryImpact",
    "PairSummary",
    "RunoutOptions",
    "METHODS",
    "ENGINES",
    "SCHEMES",
    "Road",
    "FrictionZone",
    "WheelSettings",
    "WheelSetting",
    "ScheduledChange",
    "WHEEL_STATES",
    "RunoutResult",
    "BodyRunout",
    "BodyHistory",
    "WheelTrack",
    "TrackSegment",
    "HitchHistory",
    "RunoutEvent",
    "StateLayout",
    "tyre_forces",
    "lateral_force",
    "LATERAL_MODELS",
    "static_loads",
    "StaticLoads",
]

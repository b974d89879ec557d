"""Post-impact run-out to rest of single and articulated vehicles.

Public API
----------
run_runout, Runout
    The one run-out door: a scene's movable vehicles at a fidelity level (``level=``), on an
    engine (``engine=`` or ``RunoutOptions.engine``), optionally to an accuracy target
    (``accuracy=``); what the scene run, the approach and the warm-up call.  The levels are
    dispatched through a registry (:mod:`crashsim.motion.runners`).
simulate_runout, simulate_scene
    Conveniences: integrate the run-out of one vehicle / of a whole scene (every vehicle together, with
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

The numeric core never imports pymunk, matplotlib or file formats. Every name above is
imported from its module on first use (PEP 562), so ``import crashsim.motion`` loads nothing
heavy. numba is imported when the kernels are first needed: the first run-out on either engine
(the SciPy engine calls the same kernels, interpreted by numba's dispatchers or compiled), the
first scene packed for them (:mod:`.scene_model`), or the first hitch projection
(:func:`make_hitch_consistent`). The inputs (``RunoutOptions``, ``Road``, ``ContactModel``,
``WheelSettings``, ...) and the result types load numpy only.
"""

from .._lazy import lazy_exports

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

__getattr__, __dir__ = lazy_exports(__name__, {
    **dict.fromkeys(("ContactModel", "Obstacle"), ".contact"),
    "make_hitch_consistent": ".hitches",
    "StateLayout": ".layout",
    **dict.fromkeys(("StaticLoads", "static_loads"), ".loads"),
    **dict.fromkeys(("ENGINES", "METHODS", "SCHEMES", "RunoutOptions"), ".options"),
    **dict.fromkeys(("BodyHistory", "BodyRunout", "HitchHistory", "RunoutEvent", "RunoutResult", "TrackSegment",
                     "WheelTrack"), ".result"),
    **dict.fromkeys(("PairSummary", "SceneRunout", "SecondaryImpact"), ".scene_result"),
    **dict.fromkeys(("FrictionZone", "Road"), ".road"),
    "Runout": ".runners",
    "run_runout": ".runout",
    **dict.fromkeys(("simulate_runout", "simulate_scene"), ".simulate"),
    **dict.fromkeys(("LATERAL_MODELS", "lateral_force", "tyre_forces"), ".tyres"),
    **dict.fromkeys(("WHEEL_STATES", "ScheduledChange", "WheelSetting", "WheelSettings"), ".wheels"),
})

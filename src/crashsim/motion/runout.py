"""The one entry point of the run-out: every level, engine and accuracy option through one call.

:func:`run_runout` runs the run-out of the movable vehicles of a scene from their states at
separation to rest.  The fidelity level (:mod:`crashsim.motion.levels`), the engine
(``RunoutOptions.engine``, or ``engine=``) and an accuracy target (:mod:`crashsim.motion.accuracy`)
are its options; the scene run (:func:`crashsim.scene.run_scene`), the approach, the warm-up and
the API all come through it.

What it calls, one model each (public, and documented where they are):

* ``articulated`` / ``load_transfer``: every vehicle together with contact, the scene packed once
  (:class:`~crashsim.motion.scene_model.SceneModel`) and integrated by
  :func:`~crashsim.motion.engine.run_model` (the same as :func:`~crashsim.motion.simulate_scene`);
  with an accuracy target, :func:`~crashsim.motion.accuracy.scene_to_accuracy`;
* ``energy`` / ``rigid``: each vehicle alone, without contact (:func:`~crashsim.motion.levels.simulate_level`;
  with an accuracy target, :func:`~crashsim.motion.accuracy.simulate_to_accuracy`);
* ``impact``: no run-out.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable, Mapping, NamedTuple, Sequence

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from .accuracy import scene_to_accuracy, simulate_to_accuracy
from .contact import ContactModel, Obstacle
from .engine import run_model
from .levels import check_level, simulate_level
from .options import ENGINES, RunoutOptions
from .result import SceneRunout
from .road import Road
from .scene_model import SceneModel
from .simulate import check_common
from .wheels import WheelSettings

__all__ = ["CONTACT_LEVELS", "Runout", "run_runout"]

#: Fidelity levels whose run-out models contact between vehicles and with obstacles (every vehicle
#: runs together); the others run each vehicle alone.
CONTACT_LEVELS = ("articulated", "load_transfer")


class Runout(NamedTuple):
    """What :func:`run_runout` returns.

    vehicles : dict of str to RunoutResult, or None
        Per movable vehicle (None at the ``impact`` level).
    joint : SceneRunout or None
        The joint run of the contact levels (secondary impacts, pairs, events, energy ledger);
        None at the other levels.
    accuracy : dict of str to AccuracyReport, or None
        Per vehicle, when an accuracy target was given (the contact levels share one report).
    """

    vehicles: dict | None
    joint: SceneRunout | None
    accuracy: dict | None


def run_runout(
    vehicles: Iterable[Vehicle],
    initial: Mapping[str, BodyState],
    wheels_by_vehicle: Mapping[str, WheelSettings | None] | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
    *,
    level: str = "articulated",
    engine: str | None = None,
    contact: ContactModel | None = None,
    pair_contact: Mapping | None = None,
    obstacles: Sequence[Obstacle] = (),
    accuracy: float | None = None,
    accuracy_heading: float | None = None,
    model: SceneModel | None = None,
    lean=None,
) -> Runout:
    """The run-out of a scene's movable vehicles at a level, on an engine, optionally to an accuracy.

    Parameters
    ----------
    vehicles : iterable of Vehicle
        All vehicles of the scene; barriers are skipped (give a barrier as an obstacle).
    initial : mapping of str to BodyState
        State of every body of every movable vehicle at separation (world frame, SI),
        hitch-consistent (:func:`~crashsim.motion.make_hitch_consistent`).
    wheels_by_vehicle : mapping of str to WheelSettings or None, optional
        Wheel settings by vehicle name; a vehicle not listed (or None) has all wheels locked.
    road : Road
    options : RunoutOptions
    level : {"impact", "energy", "rigid", "articulated", "load_transfer"}
        The fidelity level (:mod:`crashsim.motion.levels`).
    engine : {"scipy", "compiled"}, optional
        Overrides ``options.engine``.
    contact, pair_contact, obstacles
        Contact model, per-pair overrides and fixed obstacles (the contact levels only).
    accuracy : float, optional
        Target of every body's rest position [m] (:mod:`crashsim.motion.accuracy`): the
        cheapest tolerance whose estimated error meets it.
    accuracy_heading : float, optional
        Target of every rest heading [rad] (with ``accuracy``).
    model : SceneModel, optional
        The scene already packed for the kernels (a cached one, reused across samples); built
        from the inputs when None.  Contact levels without an accuracy target only.
    lean : callable, optional
        A lean result's wheel filter (:func:`crashsim.motion.postprocess.assemble_scene`).

    Returns
    -------
    Runout
        ``(vehicles, joint, accuracy)``.

    Examples
    --------
    >>> from crashsim.vehicles import Axle, Body, Vehicle, BodyState
    >>> car = Vehicle("car", (Body("car", 1500.0, 2500.0, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    >>> start = {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}
    >>> run = run_runout([car], start, None, Road(0.75), level="energy")
    >>> round(run.vehicles["car"].bodies["car"].rest_position[0], 3), run.joint is None
    (27.192, True)
    """
    check_level(level)
    check_common(road, options)
    if engine is not None:
        if engine not in ENGINES:
            raise ScenarioError(f"must be one of {ENGINES}, got {engine!r}", field="runout.engine")
        if engine != options.engine:
            options = dataclasses.replace(options, engine=engine)
    vehicles = list(vehicles)
    for v in vehicles:
        if not isinstance(v, Vehicle):
            raise ScenarioError(f"must be a Vehicle, got {type(v).__name__}", field="vehicles")
    wheels_by_vehicle = dict(wheels_by_vehicle or {})
    movable = [v for v in vehicles if not v.is_barrier]
    if level == "impact":
        return Runout(None, None, None)
    if level in CONTACT_LEVELS:
        if accuracy is None:
            if model is None:
                model = SceneModel(movable, wheels_by_vehicle, road, options, contact=contact,
                                   pair_contact=pair_contact, obstacles=obstacles)
            joint = run_model(model, initial, lean=lean)
            return Runout(dict(joint.vehicles), joint, None)
        joint, report = scene_to_accuracy(movable, initial, wheels_by_vehicle, road, accuracy, accuracy_heading,
                                          options, level=level, contact=contact, pair_contact=pair_contact,
                                          obstacles=obstacles)
        return Runout(dict(joint.vehicles), joint, {v.name: report for v in movable})
    runout, reports = {}, ({} if accuracy is not None else None)
    for veh in movable:
        init = {b.name: initial[b.name] for b in veh.bodies}
        wheels = wheels_by_vehicle.get(veh.name)
        if accuracy is not None:
            runout[veh.name], reports[veh.name] = simulate_to_accuracy(
                veh, init, wheels, road, accuracy, accuracy_heading, options, level=level)
        else:
            runout[veh.name] = simulate_level(level, veh, init, wheels, road, options)
    return Runout(runout, None, reports)


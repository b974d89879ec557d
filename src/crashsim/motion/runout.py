"""The one entry point of the run-out: every level, engine and accuracy option through one call.

:func:`run_runout` runs the run-out of the movable vehicles of a scene from their states at
separation to rest.  The fidelity level (:mod:`crashsim.motion.levels`), the engine
(``RunoutOptions.engine``, or ``engine=``) and an accuracy target (:mod:`crashsim.motion.accuracy`)
are its options; the scene run (:func:`crashsim.scene.run_scene`), the approach, the warm-up and
the API all come through it.  :func:`~crashsim.motion.simulate_runout` (one vehicle) and
:func:`~crashsim.motion.simulate_scene` (a scene, with contact) are the documented shortcuts of
its contact levels.

It checks the inputs and hands them, as a :class:`~crashsim.motion.runners.RunoutCall`, to the
runner registered for the level (:mod:`crashsim.motion.runners`; with an accuracy target, the
level's accuracy runner):

* ``articulated`` / ``load_transfer``: every vehicle together with contact, the scene packed once
  (:class:`~crashsim.motion.scene_model.SceneModel`) and integrated by the engine
  (:mod:`crashsim.motion.engine`), as :func:`~crashsim.motion.simulate_scene` (registered in
  :mod:`crashsim.motion.simulate`; to an accuracy target in :mod:`crashsim.motion.accuracy`);
* ``energy`` / ``rigid``: each vehicle alone, without contact (registered in
  :mod:`crashsim.motion.levels`; to an accuracy target in :mod:`crashsim.motion.accuracy`);
* ``impact``: no run-out.
"""

from __future__ import annotations

import dataclasses
from typing import Iterable, Mapping, Sequence

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from . import accuracy as _accuracy  # noqa: F401  (registers the accuracy runners; levels and simulate: the others)
from .contact import ContactModel, Obstacle
from .options import ENGINES, RunoutOptions
from .road import Road
from .runners import ACCURACY_RUNNERS, RUNNERS, Runout, RunoutCall, check_level
from .scene_model import SceneModel
from .simulate import check_common
from .wheels import WheelSettings

__all__ = ["CONTACT_LEVELS", "Runout", "run_runout"]

#: Fidelity levels whose run-out models contact between vehicles and with obstacles (every vehicle
#: runs together); the others run each vehicle alone.
CONTACT_LEVELS = ("articulated", "load_transfer")


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
    call = RunoutCall(movable=[v for v in vehicles if not v.is_barrier], initial=initial,
                      wheels=dict(wheels_by_vehicle or {}), road=road, options=options, level=level, contact=contact,
                      pair_contact=pair_contact, obstacles=obstacles, accuracy=accuracy,
                      accuracy_heading=accuracy_heading, model=model, lean=lean)
    return (RUNNERS if accuracy is None else ACCURACY_RUNNERS)[level](call)


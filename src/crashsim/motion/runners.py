"""The registry of the run-out's fidelity levels: level name -> the function that runs it.

:func:`~crashsim.motion.run_runout` is the one door of the run-out; it checks its inputs, bundles
them in a :class:`RunoutCall` and hands that to the runner registered for the level
(:data:`RUNNERS`, or with an accuracy target :data:`ACCURACY_RUNNERS`).  Each runner is
registered where it is defined, with :func:`register_runner`:

=================================  ==========================================  ======================================
level                              runner (no accuracy target)                 with an accuracy target
=================================  ==========================================  ======================================
``impact``                         :mod:`crashsim.motion.levels` (no run-out)  the same
``energy``, ``rigid``              :mod:`crashsim.motion.levels` (each         :mod:`crashsim.motion.accuracy` (each
                                   vehicle alone)                              vehicle alone; ``energy`` refuses it)
``articulated``, ``load_transfer`` :mod:`crashsim.motion.simulate` (every      :mod:`crashsim.motion.accuracy` (the
                                   vehicle together, with contact)             scene together)
=================================  ==========================================  ======================================

Every runner returns a :class:`Runout`.  The registry holds every level of
:data:`LEVELS` once :mod:`crashsim.motion.runout` is imported (it imports
the modules that register).
"""

from __future__ import annotations

import difflib
from typing import Callable, Mapping, NamedTuple, Sequence

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from .contact import ContactModel, Obstacle
from .options import RunoutOptions
from .scene_result import SceneRunout
from .road import Road
from .wheels import WheelSettings

__all__ = ["LEVELS", "LEVEL_DESCRIPTIONS", "check_level", "Runout", "RunoutCall", "RUNNERS", "ACCURACY_RUNNERS",
           "register_runner"]

#: Fidelity levels, cheapest first.
LEVELS = ("impact", "energy", "rigid", "articulated", "load_transfer")

#: One line per level, for schema descriptions and reports.
LEVEL_DESCRIPTIONS = {
    "impact": "impact only, no run-out",
    "energy": "hand calculation: sliding point mass d = v^2/(2 f g) plus rotating-skid work, closed form",
    "rigid": "each body runs out alone on its tyres, hitch ignored (kingpin load stays on the towing body)",
    "articulated": "full articulated run-out with per-wheel tyre forces (simulate_runout)",
    "load_transfer": "articulated run-out with quasi-static load transfer (needs cg_height)",
}


def check_level(level: str) -> str:
    """``level`` if it is one of :data:`LEVELS`, else a ScenarioError naming the nearest (field ``runout.level``)."""
    if level not in LEVELS:
        close = difflib.get_close_matches(str(level), LEVELS, n=3)
        hint = f"; best matches are {close}" if close else ""
        raise ScenarioError(f"must be one of {LEVELS}, got {level!r}{hint}", field="runout.level")
    return level


class Runout(NamedTuple):
    """What :func:`~crashsim.motion.run_runout` returns.

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


class RunoutCall(NamedTuple):
    """The inputs of one :func:`~crashsim.motion.run_runout` call, checked, as a runner gets them.

    ``movable`` are the scene's vehicles without its barriers, ``wheels`` the wheel settings by
    vehicle name (a dict, possibly empty), ``options`` with the engine already applied; the rest
    are :func:`~crashsim.motion.run_runout`'s keywords of the same names.
    """

    movable: list[Vehicle]
    initial: Mapping[str, BodyState]
    wheels: dict[str, WheelSettings | None]
    road: Road
    options: RunoutOptions
    level: str
    contact: ContactModel | None
    pair_contact: Mapping | None
    obstacles: Sequence[Obstacle]
    accuracy: float | None
    accuracy_heading: float | None
    model: object
    lean: Callable | None


#: Level name -> the function running a :class:`RunoutCall` at that level without an accuracy target.
RUNNERS: dict[str, Callable[[RunoutCall], Runout]] = {}
#: Level name -> the function running a :class:`RunoutCall` at that level to its accuracy target.
ACCURACY_RUNNERS: dict[str, Callable[[RunoutCall], Runout]] = {}


def register_runner(*levels: str, accuracy: bool = False):
    """Decorator: register the function as the runner of ``levels`` (in :data:`ACCURACY_RUNNERS`
    with ``accuracy``, else :data:`RUNNERS`); a level has one runner of each kind."""
    table = ACCURACY_RUNNERS if accuracy else RUNNERS

    def register(fn):
        for level in levels:
            old = table.get(level)
            if old is not None and (old.__module__, old.__qualname__) != (fn.__module__, fn.__qualname__):
                raise ValueError(f"level {level!r} already has a runner: {old.__module__}.{old.__qualname__}")
            table[level] = fn
        return fn

    return register

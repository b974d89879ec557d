"""Run-out to rest: the conveniences for one vehicle and for a whole scene with contact.

:func:`simulate_runout` and :func:`simulate_scene` are the documented shortcuts; the one door
of the run-out is :func:`~crashsim.motion.run_runout`, and this module registers its runner of
the contact levels (``articulated``, ``load_transfer``: every vehicle together, with contact).

The run-out of a scene integrates every movable vehicle together, from the first separation
until every vehicle is at rest, with contact between bodies of different vehicles and with
fixed obstacles (:mod:`crashsim.motion.contact`): secondary impacts solved by the impulse
solver, sustained contact as a penalty force.  How a run proceeds, its events and limits:
:mod:`crashsim.motion.engine`; the equations: :mod:`crashsim.motion.kernels` (one source for
both engines); the articulation stops:

**Articulation limit handling.**  A hitch with ``articulation_limit`` has a stop at
``+-limit``, treated as a perfectly plastic one-sided contact.  When the articulation reaches
it, the relative yaw rate is removed by an impulsive projection in the kinetic-energy metric
(momentum-conserving, energy-dissipating, logged with the energy lost), and a constraint row
``theta = +-limit`` is added, whose multiplier is the stop moment.  The stop opens again when
that moment would have to pull the bodies together.  A stop that is left engages again only
past a threshold raised slightly above where it was left (``STOP_HYSTERESIS``), so an
articulation resting on its limit cannot fire the stop again at the same instant.

Each run ends with status ``"rest"``, ``"time_limit"`` (``options.t_max`` reached while
still moving), ``"event_limit"``, ``"evaluation_limit"``, ``"wall_time_limit"`` or
``"solver_failure"``.  Barrier vehicles (infinite mass) are not simulated; a scene's barrier
is a fixed obstacle.
"""

from __future__ import annotations

import logging
from typing import Iterable, Mapping, Sequence

import numpy as np

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from .contact import ContactModel, Obstacle
from .engine import run_model
from .scene_model import SceneModel
from .options import RunoutOptions
from .result import RunoutResult
from .scene_result import SceneRunout
from .road import Road
from .runners import Runout, RunoutCall, register_runner
from .wheels import WheelSettings

__all__ = ["simulate_runout", "simulate_scene", "zone_membership"]

_log = logging.getLogger("crashsim")


def check_common(road, options):
    """Type checks of the inputs every run-out entry shares: ``road`` a :class:`Road`, ``options`` a
    :class:`RunoutOptions` (raises :class:`~crashsim.errors.ScenarioError`)."""
    if not isinstance(road, Road):
        raise ScenarioError(f"must be a Road, got {type(road).__name__}", field="road")
    if not isinstance(options, RunoutOptions):
        raise ScenarioError(f"must be RunoutOptions, got {type(options).__name__}", field="options")


def simulate_scene(
    vehicles: Iterable[Vehicle],
    initial: Mapping[str, BodyState],
    wheels_by_vehicle: Mapping[str, WheelSettings | None] | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
    *,
    contact: ContactModel | None = None,
    pair_contact: Mapping | None = None,
    obstacles: Sequence[Obstacle] = (),
) -> SceneRunout:
    """The run-out of every movable vehicle of a scene, integrated together, with contact.

    Parameters
    ----------
    vehicles : iterable of Vehicle
        All vehicles of the scene; barriers are skipped (give a barrier as an obstacle).
    initial : mapping of str to BodyState
        State of every body of every movable vehicle at separation, by body name (world
        frame, SI); hitch-consistent (:func:`~crashsim.motion.make_hitch_consistent`).
    wheels_by_vehicle : mapping of str to WheelSettings or None, optional
        Wheel settings by vehicle name; a vehicle not listed (or None) has all wheels locked.
    road : Road
    options : RunoutOptions
        Solver, tolerances, limits, and the engine (``"scipy"`` or ``"compiled"``).
    contact : ContactModel, optional
        The scene's contact model (default :class:`~crashsim.motion.contact.ContactModel`());
        ``ContactModel(enabled=False)`` lets bodies pass through each other.
    pair_contact : mapping, optional
        Per-pair overrides ``{(name, name): ContactModel}`` (body, vehicle or obstacle names).
    obstacles : sequence of Obstacle
        Fixed obstacles (a barrier, guardrails, walls, poles).

    Returns
    -------
    SceneRunout
        Per-vehicle results, the secondary impacts, the pairs, the events and the energy ledger.

    Raises
    ------
    ScenarioError
        Invalid input, or initial states that are not hitch-consistent.

    Examples
    --------
    >>> from crashsim.vehicles import Axle, Body, Vehicle, BodyState
    >>> car = lambda n: Vehicle(n, (Body(n, 1500.0, 2500.0, 4.5, 1.8, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    >>> states = {"a": BodyState((0, 0), 0.0, (10.0, 0.0)), "b": BodyState((10, 0), 0.0, (0.0, 0.0))}
    >>> run = simulate_scene([car("a"), car("b")], states, None, Road(0.75))
    >>> len(run.impacts), run.impacts[0].body2, run.status
    (1, 'b', 'rest')
    """
    check_common(road, options)
    vehicles = list(vehicles)
    for v in vehicles:
        if not isinstance(v, Vehicle):
            raise ScenarioError(f"must be a Vehicle, got {type(v).__name__}", field="vehicles")
    model = SceneModel(vehicles, wheels_by_vehicle, road, options, contact=contact, pair_contact=pair_contact,
                       obstacles=obstacles)
    return run_model(model, initial)


@register_runner("articulated", "load_transfer")
def _run_joint(call: RunoutCall) -> Runout:
    """The contact levels' runner: every movable vehicle together, with contact (the scene packed
    once, or ``call.model`` reused), as :func:`simulate_scene`."""
    model = call.model
    if model is None:
        model = SceneModel(call.movable, call.wheels, call.road, call.options, contact=call.contact,
                           pair_contact=call.pair_contact, obstacles=call.obstacles)
    joint = run_model(model, call.initial, lean=call.lean)
    return Runout(dict(joint.vehicles), joint, None)


def simulate_runout(
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
) -> RunoutResult:
    """Simulate the post-impact run-out of one vehicle to rest (nothing to meet).

    Parameters
    ----------
    vehicle : Vehicle
        A movable vehicle (one body, or a chain joined by hitches).
    initial : mapping of str to BodyState
        State of every body at separation (world frame, SI).  Articulated vehicles need
        hitch-consistent velocities (equal pin velocities); use
        :func:`~crashsim.motion.make_hitch_consistent` on impact-solver output.
    wheels : WheelSettings or None
        Wheel states and tyre data; None means every wheel locked.
    road : Road
        Friction coefficient and friction zones.
    options : RunoutOptions
        Solver method, tolerances, regularisation, rest threshold, limits, and the engine:
        ``engine="scipy"`` (default) or ``"compiled"`` (same model and result, ~100x faster
        per run).

    Returns
    -------
    RunoutResult
        ``status`` says why the run stopped; ``success`` is True only at rest;
        ``method`` names the engine (``"scipy/LSODA"``, ``"compiled/dopri5"``).

    Raises
    ------
    ScenarioError
        Invalid input (names the field, value and allowed range), a barrier vehicle, or
        inconsistent initial hitch states.

    Examples
    --------
    >>> from crashsim.vehicles import Axle, Body, Vehicle, BodyState
    >>> car = Vehicle("car", (Body("car", 1500.0, 2500.0, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))
    >>> res = simulate_runout(car, {"car": BodyState((0, 0), 0.0, (20.0, 0.0))}, None, Road(mu=0.75))
    >>> res.status, round(res.bodies["car"].rest_position[0], 2)  # v^2 / (2 mu g) = 27.19 m
    ('rest', 27.19)
    """
    if not isinstance(vehicle, Vehicle):
        raise ScenarioError(f"must be a Vehicle, got {type(vehicle).__name__}", field="vehicle")
    if vehicle.is_barrier:
        raise ScenarioError("a barrier (infinite mass) is not simulated", field=f"{vehicle.name}.bodies")
    if wheels is not None and not isinstance(wheels, WheelSettings):
        raise ScenarioError(f"must be WheelSettings or None, got {type(wheels).__name__}",
                            field=f"wheels[{vehicle.name!r}]")
    run = simulate_scene([vehicle], initial, {vehicle.name: wheels}, road, options)
    return run.vehicles[vehicle.name]


def zone_membership(model, y: np.ndarray) -> np.ndarray:
    """Which friction zone every wheel of a :class:`~crashsim.motion.hitches.RunoutModel` is in, (n_wheels, n_zones).

    A wheel within ``1e-9 m`` of a zone edge is assigned by where its contact point is
    heading (1 micrometre ahead along its velocity), so a restart exactly at a crossing
    assigns the new zone (the kernels' rule).
    """
    return model.membership(y)

"""Overrides applied to a built scenario: the fast path of :class:`~crashsim.reconstruct.overrides.ScenarioOverrides`.

A fit or Monte Carlo sample changes a few inputs of one scenario.  Rebuilding the whole
scenario from the file dict (schema validation of every key, presets, every object) costs
a few milliseconds per sample, more than the impact it feeds.  For the inputs that samples
vary most, this module rebuilds only the objects the input reaches, from a scenario built
once the full way (:func:`crashsim.scenario.scenario_from_dict`), with
:func:`dataclasses.replace` and the constructors and helpers the full build uses, so that
the result is the same scenario, value for value (``tests/reconstruct/test_patch.py``
compares both for every supported path):

====================================  ===============================================================
path                                  objects rebuilt
====================================  ===============================================================
``vehicles.<name>.speed``             the vehicle's body states, the impact problem
``impact.restitution``                the crush surface, the impact problem
``impact.mu`` / ``mu_fraction`` /     the crush surface's tangential law (only where the file's
``friction``                          ``tangential`` law uses that key), the impact problem
``impact.normal``                     the crush surface, the impact problem (not with a ``[barrier]``,
                                      whose obstacle is built from the surface)
``impact.point[i]``                   the crush surface, the impact problem, the contact-point check
                                      (not with a ``[barrier]``)
``runout.road_friction``              the road of the run-out
====================================  ===============================================================

A vehicle with an approach (``[vehicles.<name>.approach]``) is simulated in the scene run
(:func:`crashsim.scene.run.simulate_approaches`), from the inputs the scenario carries:
its speed at impact (``vehicles.<name>.speed``), at the start of braking
(``vehicles.<name>.approach.speed``) or its reaction time changes only those inputs, and the road friction also the
road of every approach that runs on the run-out's road; the run re-runs the approach.  The
impact's coefficients, normal and point do not reach an approach (it ends at the impact
positions).

Each value is taken as the SI float it is (the full build's file-text round trip,
``parse_value(format_value(x))``, is the identity for SI units) and checked against its
field's allowed range (:class:`~crashsim.reconstruct.variants.ScenarioVariant` applies the
values; this module says which objects a path reaches).  Anything else (another path, a value
out of range, an error in a constructor) returns None and the caller builds the scenario the
full way, which gives the same scenario or the same error as before.

The objects a sample does not change keep their identity (the vehicles, the wheel settings,
the contact model, the obstacles, the run-out options), which lets the run-out reuse its
compiled scene model (:mod:`crashsim.scene.run`).
"""

from __future__ import annotations

__all__ = ["patch_kind", "set_validated", "LAW_KEY", "APPROACH_KEYS"]

#: The tangential-law key that carries the law's value, by law.
LAW_KEY = {"ratio": "mu", "fraction": "mu_fraction", "friction": "friction"}

#: The keys of ``[vehicles.<name>.approach]`` a sample may change in the approach's spec (its field
#: of the same name), by their patch kind.
APPROACH_KEYS = {"speed": "approach_speed", "reaction_time": "approach_reaction_time"}


def patch_kind(target, data: dict) -> str | None:
    """The kind of fast patch of a :class:`~crashsim.reconstruct.overrides.Target` in a scenario
    whose validated dict is ``data`` (``"speed"``, ``"restitution"``, ``"law"``, ``"normal"``,
    ``"point"``, ``"road_friction"``), or None where the full build is needed."""
    keys = tuple(k for k, _ in target.steps)
    index = target.steps[-1][1]
    vehicles = data.get("vehicles") or {}
    if len(keys) == 3 and keys[0] == "vehicles" and keys[2] == "speed":
        if keys[1] not in vehicles:
            return None
        a = vehicles[keys[1]].get("approach")
        if a is None:
            return "speed"
        # with an approach: the speed at impact its simulation starts from (in the run); none when the
        # approach gives the speed at braking (both given: the full build's error)
        return "approach_impact_speed" if a.get("speed") is None else None
    if len(keys) == 4 and keys[0] == "vehicles" and keys[2] == "approach" and keys[3] in APPROACH_KEYS:
        v = vehicles.get(keys[1])
        if v is None or v.get("approach") is None:
            return None
        # the speed at braking with the speed at impact given too: the full build's error
        return APPROACH_KEYS[keys[3]] if keys[3] != "speed" or v["speed"] is None else None
    if keys == ("runout", "road_friction"):
        return "road_friction" if data.get("runout") is not None else None
    if len(keys) != 2 or keys[0] != "impact":
        return None
    key = keys[1]
    if key == "restitution":
        return "restitution"
    if key in LAW_KEY.values():
        return "law" if LAW_KEY.get(data["impact"]["tangential"]) == key else None
    if key in ("normal", "point") and data.get("barrier") is None:
        return key if (key == "normal") == (index is None) else None
    return None


def set_validated(d: dict, target, x: float) -> dict:
    """A copy of the validated dict ``d`` with ``x`` at ``target`` (only the dicts along the path copied)."""
    out = dict(d)
    node = out
    for key, _ in target.steps[:-1]:
        node[key] = dict(node[key])
        node = node[key]
    key, index = target.steps[-1]
    if index is None:
        node[key] = x
    else:
        vec = list(node[key])
        vec[index] = x
        node[key] = type(node[key])(vec) if isinstance(node[key], tuple) else vec
    return out

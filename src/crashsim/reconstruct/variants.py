"""Typed scene variants: a scenario built once, and the SI values a sample changes in it.

A fit, Monte Carlo or posterior sample changes a few inputs of one scenario.  A
:class:`ScenarioVariant` is made once from a scenario built the full way
(:func:`crashsim.scenario.scenario_from_dict`) and the paths the samples change: each path is
resolved once (its schema field and SI range, and which objects it reaches:
:func:`crashsim.reconstruct.patch.patch_kind`), and everything a sample does not change is
prepared once (the paths' frames, the world outlines of the contacting bodies for the
contact-point check).  Per sample, :meth:`ScenarioVariant.scenario` takes the SI floats,
checks each against its field's range, and rebuilds only the objects they reach with
:func:`dataclasses.replace`: no text round trip, no validation of what did not change.

The result is the scenario of the full build, value for value (``tests/reconstruct/test_patch.py``
compares them for every path kind).  The values are used as given: the file-text round trip
the full build sees (``"13.41 m/s"`` written with ``repr`` and read back) is the identity for
the SI units (a factor of exactly 1; tested for every kind), so dropping it changes no digit.

A vehicle's approach is simulated in the scene run (the loader does not simulate it): a sample
that changes an approach's speed, or the road friction it runs on, changes its inputs
(``Scenario.approach_inputs``) and the run re-runs only that approach.

What it cannot vouch for it leaves to the full build (``scenario`` returns None): a path it
cannot patch (see :mod:`crashsim.reconstruct.patch`), a value out of its field's range, a
contact point outside the bodies' outlines, an error in a constructor.  The full build then
gives the same scenario or the same error, with the same text, as a value written in the file.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Sequence

from ..errors import ScenarioError
from ..motion.road import point_distance
from ..scenario import contact_outlines, frame_point, frame_xform, vehicle_states
from ..schema import in_range
from .patch import LAW_KEY, patch_kind, set_validated

__all__ = ["ScenarioVariant", "patch_scenario"]


def _unchecked(obj, **changes):
    """A copy of the frozen dataclass ``obj`` with ``changes``, its ``__post_init__`` checks skipped.

    For an :class:`~crashsim.impact.problem.ImpactProblem` whose vehicles, bodies, names and
    constraints are those of a validated problem: only states (built by ``chain_states``,
    pin-consistent by construction) and the crush surface (validated by its own constructor)
    change, which its structural checks do not concern.
    """
    new = object.__new__(type(obj))
    new.__dict__.update(obj.__dict__)
    new.__dict__.update(changes)
    return new


class ScenarioVariant:
    """A scenario built once, with SI values of some of its inputs changed per sample.

    Parameters
    ----------
    base : Scenario
        Built the full way (its ``data`` the validated dict).
    targets : sequence of Target
        The inputs a sample changes (:func:`crashsim.reconstruct.overrides.resolve_path`), in
        the order of the values given to :meth:`scenario`.
    file : str, optional
        For error messages.

    Attributes
    ----------
    kinds : tuple
        Per target its patch kind (:func:`~crashsim.reconstruct.patch.patch_kind`), None where
        the full build is needed.
    patchable : bool
        Every target can be patched: :meth:`scenario` builds scenarios (else it returns None).
    """

    def __init__(self, base, targets: Sequence, file: str | None = None):
        self.base = base
        self.targets = tuple(targets)
        self.file = file
        d = base.data
        self.kinds = tuple(patch_kind(t, d) for t in self.targets)
        if base.approaches and any((k or "").startswith("approach_") or
                                   (k == "road_friction" and base.approach_inputs) for k in self.kinds):
            self.kinds = (None,)  # approaches already simulated (simulate_approaches was called): the full build
        self.patchable = None not in self.kinds
        if not self.patchable:
            return
        self._in_range = in_range
        self._vehicle_states = vehicle_states
        kinds = set(self.kinds)
        self._speeds = tuple(v for v in base.vehicles
                             if any(k in ("speed", "approach_impact_speed") and t.steps[1][0] == v.name
                                    for t, k in zip(self.targets, self.kinds)))
        # the approaches whose inputs a sample changes: (vehicle name, what), in target order
        self._approach = tuple((t.steps[1][0], t.steps[-1][0], k) for t, k in zip(self.targets, self.kinds)
                               if (k or "").startswith("approach_"))
        # with the road friction: the approaches that run on the run-out's road
        self._on_runout_road = tuple(n for n in base.approach_inputs
                                     if (d["vehicles"][n]["approach"] or {}).get("road_friction") is None)
        imp = d["impact"]
        problem = base.impact
        # the frames of the point and the normal: bodies' positions and headings, which no
        # patchable path changes (a speed changes the velocities only)
        self._point = None
        self._normal_turn = None
        if "point" in kinds:
            self._point = lambda p: frame_point(p, imp["point_frame"], base.states, "impact.point_frame", file)
            # each outline with its edges prepared once (its distance is signed_distance's, bit for bit)
            self._outlines = [point_distance(world) for _, world in contact_outlines(problem, base.states)]
        if "normal" in kinds:
            self._normal_turn = frame_xform(imp["normal_frame"], base.states, "impact.normal_frame", file)[1]
        self._body_names = tuple(b.name for v in problem.vehicles for b in v.bodies)

    def scenario(self, values: Sequence[float]):
        """The scenario with ``values`` (SI, one per target), or None where the full build is needed.

        Raises nothing for a value the full build would reject: it returns None, and the full
        build raises the error a file with that value gives.
        """
        if not self.patchable:
            return None
        base = self.base
        d = base.data
        for t, x in zip(self.targets, values):
            x = float(x)
            if not math.isfinite(x) or not self._in_range(x, t.field):
                return None
            d = set_validated(d, t, x)
        kinds = self.kinds
        try:
            states = base.states
            if self._speeds:
                states = dict(states)
                for veh in self._speeds:
                    states.update(self._vehicle_states(veh, d["vehicles"][veh.name]))
            problem = base.impact
            imp = d["impact"]
            surface_changes = {}
            if "restitution" in kinds:
                surface_changes["restitution"] = imp["restitution"]
            if "law" in kinds:
                surface_changes["tangential"] = replace(problem.surface.tangential, value=imp[LAW_KEY[imp["tangential"]]])
            if "normal" in kinds:
                surface_changes["normal_angle"] = imp["normal"] + self._normal_turn
            if "point" in kinds:
                surface_changes["point"] = self._point(imp["point"])
            if self._speeds or surface_changes:
                surface = replace(problem.surface, **surface_changes) if surface_changes else problem.surface
                problem = _unchecked(problem, states={n: states[n] for n in self._body_names}, surface=surface)
            if "point" in kinds:  # the contact point in or near both outlines (else the full build's error)
                px, py = problem.surface.point
                tol = imp["contact_tolerance"]
                if any(max(0.0, -distance(px, py)) > tol for distance in self._outlines):
                    return None
            runout = base.runout
            inputs = base.approach_inputs
            if "road_friction" in kinds:
                runout = replace(runout, road=replace(runout.road, mu=d["runout"]["road_friction"]))  # zones, slope kept
                if self._on_runout_road:
                    inputs = dict(inputs)
                    for n in self._on_runout_road:
                        inputs[n] = replace(inputs[n], road=runout.road)
            if self._approach:
                inputs = dict(inputs)
                for n, key, k in self._approach:
                    a = inputs[n]
                    if k == "approach_impact_speed":
                        inputs[n] = replace(a, speed_at_impact=d["vehicles"][n]["speed"])
                    else:  # a field of the approach's spec (APPROACH_KEYS), validated by its constructor
                        inputs[n] = replace(a, spec=replace(a.spec, **{key: d["vehicles"][n]["approach"][key]}))
        except ScenarioError:
            return None
        # not built from file contents (those are the base's, without the sample's values): no file_data
        return replace(base, states=states, impact=problem, runout=runout, data=d, approach_inputs=inputs,
                       file_data=None)


def patch_scenario(base, targets: Sequence, values: Sequence[float], file: str | None = None):
    """``base`` with ``values`` (SI, one per target) at ``targets``, or None if the full build is needed.

    One sample of a :class:`~crashsim.reconstruct.variants.ScenarioVariant` (which prepares
    what the samples share once: build it once where many samples follow).

    Parameters
    ----------
    base : Scenario
        Built the full way from the same file dict (its ``data`` the validated dict).
    targets : sequence of Target
    values : sequence of float
    file : str, optional

    Returns
    -------
    Scenario or None
    """
    return ScenarioVariant(base, targets, file).scenario(values)

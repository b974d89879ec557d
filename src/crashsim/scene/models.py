"""The run-out's scene model, reused across the samples of one scene.

Building a :class:`~crashsim.motion.scene_model.SceneModel` (wheels, loads, contact pieces and
pairs as kernel arrays) costs about as much as a compiled run-out of the shipped scenes.
The samples of a fit or Monte Carlo run that change only speeds, impact coefficients, the
point of impact or the road friction share the vehicles, wheel settings, contact model,
obstacles and options *objects* (:mod:`crashsim.reconstruct.patch` keeps them), so their
model is built once and, where only the road friction differs, copied with the new
coefficient (:meth:`~crashsim.motion.scene_model.SceneModel.with_road`).

The model is kept by whoever runs the samples (a :class:`ModelReuse`, owned by the
:class:`~crashsim.reconstruct.inputs.SceneInputs` of a fit, a Monte Carlo run or the live view),
not in a cache of the process: it holds the objects it was built from and is reused only for a
scene whose model inputs *are* those objects (an identity test, not a key of object ids). A
scenario built the full way has new objects and gets a new model (the result is the same either
way: ``tests/reconstruct/test_patch.py``).
"""

from __future__ import annotations

from ..motion.scene_model import SceneModel
from ..motion.simulate import check_common

__all__ = ["ModelReuse", "scene_model"]


def _inputs(movable, spec) -> tuple:
    """The objects a scene model is built from."""
    return (tuple(movable), spec.wheels, spec.contact, spec.pair_contact, spec.obstacles, spec.options, spec.road.zones)


def _same(a: tuple, b: tuple) -> bool:
    return len(a[0]) == len(b[0]) and all(x is y for x, y in zip(a[0], b[0])) and all(
        x is y for x, y in zip(a[1:], b[1:]))


class ModelReuse:
    """The scene model of the last scene run through it, reused by the next scene that shares its
    model inputs (see the module docstring). Not shared between threads: each runner owns one."""

    def __init__(self):
        self._held: tuple | None = None
        self._model: SceneModel | None = None

    def model(self, movable, spec) -> SceneModel:
        """The model of ``movable`` vehicles under run-out ``spec``: the kept one (on this road friction)
        where its inputs are this scene's, else a new one, kept from now on."""
        held = _inputs(movable, spec)
        if self._held is not None and _same(self._held, held):
            model = self._model
            if model.road is spec.road or model.road.mu == spec.road.mu:  # the zones are the inputs'
                return model
            return model.with_road(spec.road)
        model = scene_model(movable, spec)
        self._held, self._model = held, model
        return model


def scene_model(movable, spec, reuse: ModelReuse | None = None) -> SceneModel:
    """The :class:`~crashsim.motion.scene_model.SceneModel` of ``movable`` vehicles under run-out ``spec``
    (as :func:`crashsim.motion.simulate_scene` builds it): ``reuse``'s where it can, else a new one.

    Parameters
    ----------
    movable : sequence of Vehicle
        The movable vehicles of the scene.
    spec : RunoutSpec
    reuse : ModelReuse, optional
    """
    if reuse is not None:
        return reuse.model(movable, spec)
    check_common(spec.road, spec.options)
    return SceneModel(list(movable), spec.wheels, spec.road, spec.options, contact=spec.contact,
                      pair_contact=spec.pair_contact, obstacles=spec.obstacles)

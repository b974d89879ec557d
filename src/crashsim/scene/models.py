"""The run-out's scene model, reused across the scenes of a fit or a Monte Carlo run.

Building a :class:`~crashsim.motion.scene_model.SceneModel` (wheels, loads, contact pieces and
pairs as kernel arrays) costs about as much as a compiled run-out of the shipped scenes.
The samples of a fit or Monte Carlo run that change only speeds, impact coefficients, the
point of impact or the road friction share the vehicles, wheel settings, contact model,
obstacles and options *objects* (:mod:`crashsim.reconstruct.patch` keeps them), so their
model is built once and, where only the road friction differs, copied with the new
coefficient (:meth:`~crashsim.motion.scene_model.SceneModel.with_road`).

The cache is keyed by the identity of those objects and holds them, so a key cannot be
reused by other objects while its entry lives; a scenario built the full way has new
objects and gets a new model (the result is the same either way).
"""

from __future__ import annotations

import threading
from collections import OrderedDict

from ..motion.scene_model import SceneModel
from ..motion.simulate import check_common

__all__ = ["scene_model", "clear"]

#: Scene models kept (a fit or Monte Carlo run needs one).
SIZE = 4

_CACHE: OrderedDict = OrderedDict()
_LOCK = threading.Lock()


def clear() -> None:
    """Forget every cached model."""
    with _LOCK:
        _CACHE.clear()


def scene_model(movable, spec):
    """The :class:`~crashsim.motion.scene_model.SceneModel` of ``movable`` vehicles under run-out ``spec``
    (as :func:`crashsim.motion.simulate_scene` builds it), from the cache where it holds one.

    Parameters
    ----------
    movable : sequence of Vehicle
        The movable vehicles of the scene.
    spec : RunoutSpec
    """
    held = (tuple(movable), spec.wheels, spec.contact, spec.pair_contact, spec.obstacles, spec.options,
            spec.road.zones)
    key = tuple(id(o) for o in held[0]) + tuple(id(o) for o in held[1:])
    with _LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
    if hit is not None:
        model = hit[1]
        if model.road is spec.road or model.road.mu == spec.road.mu:  # the zones are the key's
            return model
        return model.with_road(spec.road)
    check_common(spec.road, spec.options)
    model = SceneModel(list(movable), spec.wheels, spec.road, spec.options, contact=spec.contact,
                       pair_contact=spec.pair_contact, obstacles=spec.obstacles)
    with _LOCK:
        _CACHE[key] = (held, model)
        while len(_CACHE) > SIZE:
            _CACHE.popitem(last=False)
    return model

"""The physics of the run-out of a whole scene: one source for both engines.

Everything here is nopython code on SI floats in flat arrays.  Both engines run it: the
compiled engine (:mod:`crashsim.motion.compiled_solution`) inside its own integration loop (:func:`~crashsim.motion.kernels.integrator.run`),
the SciPy engine (:mod:`crashsim.motion.simulate`) through thin compiled entry points
(:mod:`~crashsim.motion.kernels.scipy_calls`) called from its Python loop
around SciPy's integrators.  So the right-hand side, the event functions and what happens at
an event are written once; only the integrators differ.

The state vector is field-major over **all bodies of all vehicles** of the scene, in vehicle
order (:class:`~crashsim.motion.layout.StateLayout`): X.., Y.., psi.., vx.., vy.., w..,
then the filtered body-axes accelerations with load transfer.

The arrays are named (:mod:`crashsim.motion.kernels.arrays`): the model ``M``
(:class:`~crashsim.motion.kernels.arrays.KernelModel`, built by :mod:`crashsim.motion.scene_model`:
bodies, wheels, hitches, load transfer, wheel-setting phases, friction zones, options, the RK
tableau, contact pieces and pairs), the mode ``D`` (:class:`~crashsim.motion.kernels.arrays.Mode`:
zone membership of every wheel, the closed articulation stops (hitch, locked angle, count in
``lk_n[0]``), the raised thresholds of stops that were left, the contact state of every pair
(``PS_*``) with its allowance (``A_*`` columns: the depth allowance [m] and the crush circle of
the first impact), and which vehicles are parked (at rest, frozen)), and the work arrays ``W``
(:class:`~crashsim.motion.kernels.arrays.Work`).

One module per stage:

* :mod:`~crashsim.motion.kernels.arrays`: the named bundles, column indices and constants;
* :mod:`~crashsim.motion.kernels.geometry`: body trig, hitch constraint rows, contact pieces
  (vertices, gaps, manifold), wheel positions, friction zones;
* :mod:`~crashsim.motion.kernels.tyres`: the tyre law compiled for scalars, the tyre forces;
* :mod:`~crashsim.motion.kernels.contacts`: pair forces, touch geometry, strike scan, crush;
* :mod:`~crashsim.motion.kernels.equations`: the right-hand side, rest measures, path integrands;
* :mod:`~crashsim.motion.kernels.events`: event values and rates, Brent, the earliest root,
  the events of a mode, the event handler, settling after an event;
* :mod:`~crashsim.motion.kernels.integrator`: the compiled engine's RK steps and segment loop;
* :mod:`~crashsim.motion.kernels.scipy_calls`: the entry points the SciPy engine calls;
* :mod:`~crashsim.motion.kernels.samples`: post-processing at sample times.

Every public name of the stage modules is also an attribute of this package
(``kernels.run``, ``kernels.PS_CONTACT``, ...).

Contact (between bodies of different vehicles, and between a body and a fixed obstacle)
------------------------------------------------------------------------------------------
* **Gap.**  Per piece pair the separating-axis gap: the largest separation of one polygon from
  a face of the other, over the faces of both; > 0 apart (a lower bound of the distance),
  0 touching, < 0 overlapping (minus the smallest penetration along a face normal).  The gap
  of a pair is the least over its piece pairs: continuous, so its sign change is a solver
  event like any other.
* **Contact points** (:func:`~crashsim.motion.kernels.contacts.piece_points`).  A pair without a
  crush allowance: the Box2D-style manifold of touching or shallowly overlapping pieces
  (reference face = the face of largest separation; incident edge = the other polygon's edge most
  opposed to it, clipped to the reference face's side planes; the clipped points below the face,
  each with its depth).  A pair with one (the crush of the first impact): every vertex of either
  piece inside the other, its depth beyond the allowance of its material (how deep it lay there
  when the allowance was set), so that the penalty derives from a potential.  The normal points
  from B into A.
* **States.**  ``PS_DISARMED`` (overlapping or within ``R_ARM`` at separation, the crush of the
  primary impact: no contact force; armed once the pieces have separated by ``R_ARM``; pressed
  ``R_ARM`` beyond the crush allowance -> contact, the allowance set again where the bodies are
  then, so the force starts from zero); ``PS_ARMED`` (apart: the gap event detects the next touch);
  ``PS_CONTACT`` (sustained contact: a penalty force at every contact point,
  ``F_n = max(0, k e + c e' min(1, e / DAMPER_DEPTH))`` on the depth ``e`` beyond the allowance,
  with Coulomb friction ``mu_c F_n`` against the tangential slip, regularised like the tyres; left
  when the gap exceeds ``R_ARM``).
* **Strikes.**  A pair in contact or disarmed carries the strike event (``EV_STRIKE``,
  :func:`~crashsim.motion.kernels.contacts.strike_speed`): the largest closing speed of its points
  pressed beyond the allowance, each less ``R_OMEGA`` times its depth (a disarmed pair's points of
  the crush left out: pressing on into it is the crush going on), minus ``R_VTHR``.  It crosses zero
  where a point arrives that fast (the value jumps; the root is the arrival, located on the crossed
  side) or a point in contact is driven in faster than its depth holds: an impact, as the touch of
  an armed pair at that speed is.  The impact is solved in
  Python for every point touching at that instant at once
  (:func:`~crashsim.motion.kernels.contacts.contact_rows`, :mod:`crashsim.motion.impacts`).
"""

from __future__ import annotations

import hashlib

from ..._jit import kernel_sources
from . import jit  # noqa: F401  (first: the cache directory, before any kernel is defined)
from . import arrays, geometry, tyres, contacts, equations, events, integrator, scipy_calls, samples

#: The stage modules, in import order.
STAGES = (arrays, geometry, tyres, contacts, equations, events, integrator, scipy_calls, samples)


def _public(module):
    """The public names a stage module defines (not those it imports)."""
    out = {}
    for name, obj in vars(module).items():
        if name.startswith("_"):
            continue
        owner = getattr(getattr(obj, "py_func", obj), "__module__", None)
        if owner == module.__name__ or (name.isupper() and not callable(obj)):
            out[name] = obj
    return out


__all__ = []
for _stage in STAGES:
    _names = _public(_stage)
    globals().update(_names)
    __all__ += sorted(n for n in _names if n not in __all__)
del _stage, _names


def _bind_cache_to_sources():
    """Make the on-disk cache of every kernel depend on every source the kernels compile in.

    numba invalidates a cached function only when the file defining it changes; the kernels
    call (and inline) kernels of the other stage modules, compile in the tyre law of
    :mod:`crashsim.motion.tyres` and constants of :mod:`crashsim.motion.options`, so an edit
    in any of them must invalidate all.  The cache index stamp of every kernel (numba's stamp
    of its file) is extended with a SHA-256 of those sources (:func:`crashsim._jit.kernel_sources`).
    Uses numba internals; if they change, caching falls back to numba's own rule (and the
    tests compare the compiled tyre law with the NumPy one).
    """
    from numba.core.dispatcher import Dispatcher

    digest = hashlib.sha256()
    for path in kernel_sources(impact=False):
        with open(path, "rb") as fh:
            digest.update(fh.read())
    tag = digest.hexdigest()
    seen = set()
    for stage in STAGES:
        for obj in list(vars(stage).values()):
            if isinstance(obj, Dispatcher) and id(obj) not in seen:
                seen.add(id(obj))
                try:
                    cache_file = obj._cache._cache_file
                    cache_file._source_stamp = (cache_file._source_stamp, tag)
                except AttributeError:  # pragma: no cover - numba internals changed
                    pass


_bind_cache_to_sources()

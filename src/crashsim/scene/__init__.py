"""One run of a scene: impact -> run-out of every vehicle to rest -> evidence checks -> SceneResult.

:func:`run_scene` (:mod:`crashsim.scene.run`) takes a validated :class:`~crashsim.scenario.Scenario`
(:func:`simulate_approaches`: its approaches alone, which the loader does not run);
:mod:`crashsim.scene.models` caches the compiled scene models that repeated runs (fits, Monte Carlo)
share. This layer sits above the physics (impact, motion), the evidence checks and the views of a
result (plotting, animation, report), and below the scenario files and the reconstruction. The names
are imported on first use (PEP 562).
"""

from .._lazy import lazy_exports

__all__ = ["SceneResult", "run_scene", "simulate_approaches", "rest_misfit_warnings"]

__getattr__, __dir__ = lazy_exports(__name__, dict.fromkeys(__all__, ".run"))

"""Scenes from impact to rest, evidence residuals, fits and uncertainty.

The reconstruction layer: fit (:mod:`.fit`), Monte Carlo (:mod:`.montecarlo`) and posterior
(:mod:`.posterior`) of a scenario, run through one door (:class:`.inputs.Scene`: a scene built
once, its inputs varied by name; below it the path overrides, :mod:`.overrides`, :mod:`.patch`,
:mod:`.variants`), the inverse sections' schema and their plots. One run of a
scene is the layer below (:mod:`crashsim.scene`); ``SceneResult`` and ``run_scene`` are
re-exported here from it. The names are imported on first use (PEP 562).
"""

from .._lazy import lazy_exports

__all__ = ["Scene", "SceneInputs", "SceneResult", "run_scene", "fit_scene", "FitResult", "monte_carlo", "MCResult", "run_posterior",
           "PosteriorResult"]

__getattr__, __dir__ = lazy_exports(__name__, {
    **dict.fromkeys(("SceneResult", "run_scene"), "..scene"),
    **dict.fromkeys(("Scene", "SceneInputs"), ".inputs"),
    **dict.fromkeys(("FitResult", "fit_scene"), ".fit"),
    **dict.fromkeys(("MCResult", "monte_carlo"), ".montecarlo"),
    **dict.fromkeys(("PosteriorResult", "run_posterior"), ".posterior"),
})

"""Scenes from impact to rest, evidence residuals, fits and uncertainty.

The reconstruction layer: fit (:mod:`.fit`), Monte Carlo (:mod:`.montecarlo`) and posterior
(:mod:`.posterior`) of a scenario, with the path overrides they sample through
(:mod:`.overrides`, :mod:`.patch`), the inverse sections' schema and their plots. One run of a
scene is the layer below (:mod:`crashsim.scene`); ``SceneResult`` and ``run_scene`` are
re-exported here from it.
"""

from ..scene import SceneResult, run_scene
from .fit import FitResult, fit_scene
from .montecarlo import MCResult, monte_carlo
from .posterior import PosteriorResult, run_posterior

__all__ = ["SceneResult", "run_scene", "fit_scene", "FitResult", "monte_carlo", "MCResult", "run_posterior",
           "PosteriorResult"]

"""Scenes from impact to rest, evidence residuals, fits and uncertainty."""

from ..scene import SceneResult, run_scene

__all__ = ["SceneResult", "run_scene", "fit_scene", "FitResult", "monte_carlo", "MCResult", "run_posterior",
           "PosteriorResult"]


def __getattr__(name):
    # fit and Monte Carlo are imported on first use (they pull in process pools and tqdm)
    if name in ("fit_scene", "FitResult"):
        from . import fit

        return getattr(fit, name)
    if name in ("monte_carlo", "MCResult"):
        from . import montecarlo

        return getattr(montecarlo, name)
    if name in ("run_posterior", "PosteriorResult"):
        from . import posterior

        return getattr(posterior, name)
    raise AttributeError(name)

"""Scenes from impact to rest, evidence residuals, fits and uncertainty."""

from .scene import SceneResult, run_scene

__all__ = ["SceneResult", "run_scene"]

"""Independent cross-checks of the run-out (pymunk); pymunk is imported lazily inside the functions."""

from .pymunk_runout import simulate_runout_pymunk

__all__ = ["simulate_runout_pymunk"]

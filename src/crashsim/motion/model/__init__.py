"""Deprecated path: use :mod:`crashsim.motion.scene_model` (renamed: it holds SceneModel, the scene packed for the kernels)."""

import warnings as _warnings

import crashsim.motion.scene_model as _new
from crashsim.motion.scene_model import *  # noqa: F401,F403

_warnings.warn("crashsim.motion.model is deprecated; import crashsim.motion.scene_model instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

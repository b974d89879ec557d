"""Deprecated path: use :mod:`crashsim.scene.run` (moved there when the package was cut into layers)."""

import warnings as _warnings

import crashsim.scene.run as _new
from crashsim.scene.run import *  # noqa: F401,F403

_warnings.warn("crashsim.reconstruct.scene is deprecated; import crashsim.scene.run instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

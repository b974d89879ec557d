"""Deprecated path: use :mod:`crashsim.motion.hitches` (renamed: it holds the hitch rows and the one-vehicle RunoutModel; the equations of motion are in crashsim.motion.kernels.equations)."""

import warnings as _warnings

import crashsim.motion.hitches as _new
from crashsim.motion.hitches import *  # noqa: F401,F403

_warnings.warn("crashsim.motion.dynamics is deprecated; import crashsim.motion.hitches instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

"""Deprecated path: use :mod:`crashsim._jit` (moved there when the package was cut into layers)."""

import warnings as _warnings

import crashsim._jit as _new
from crashsim._jit import *  # noqa: F401,F403

_warnings.warn("crashsim.motion.jitcache is deprecated; import crashsim._jit instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

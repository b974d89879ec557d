"""Deprecated path: use :mod:`crashsim.motion.compiled_solution` (renamed: it holds the compiled engine's solution object, not the engine)."""

import warnings as _warnings

import crashsim.motion.compiled_solution as _new
from crashsim.motion.compiled_solution import *  # noqa: F401,F403

_warnings.warn("crashsim.motion.fast is deprecated; import crashsim.motion.compiled_solution instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

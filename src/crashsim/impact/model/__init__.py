"""Deprecated path: use :mod:`crashsim.impact.problem` (renamed: it holds ImpactProblem and its laws, the description of one impact)."""

import warnings as _warnings

import crashsim.impact.problem as _new
from crashsim.impact.problem import *  # noqa: F401,F403

_warnings.warn("crashsim.impact.model is deprecated; import crashsim.impact.problem instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

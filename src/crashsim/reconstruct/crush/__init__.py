"""Deprecated path: use :mod:`crashsim.evidence.crush` (moved there when the package was cut into layers)."""

import warnings as _warnings

import crashsim.evidence.crush as _new
from crashsim.evidence.crush import *  # noqa: F401,F403

_warnings.warn("crashsim.reconstruct.crush is deprecated; import crashsim.evidence.crush instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

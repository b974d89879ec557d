"""Deprecated path: use :mod:`crashsim.evidence.checks` (moved there when the package was cut into layers)."""

import warnings as _warnings

import crashsim.evidence.checks as _new
from crashsim.evidence.checks import *  # noqa: F401,F403

_warnings.warn("crashsim.reconstruct.evidence is deprecated; import crashsim.evidence.checks instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

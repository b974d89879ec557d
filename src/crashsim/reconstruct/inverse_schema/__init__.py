"""Deprecated path: use :mod:`crashsim.inverse_schema` (moved there when the package was cut into layers)."""

import warnings as _warnings

import crashsim.inverse_schema as _new
from crashsim.inverse_schema import *  # noqa: F401,F403

_warnings.warn("crashsim.reconstruct.inverse_schema is deprecated; import crashsim.inverse_schema instead",
               DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

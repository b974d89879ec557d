"""Deprecated path: use :mod:`crashsim.scene.models` (moved there when the package was cut into layers)."""

import warnings as _warnings

import crashsim.scene.models as _new
from crashsim.scene.models import *  # noqa: F401,F403

_warnings.warn("crashsim.reconstruct.models is deprecated; import crashsim.scene.models instead", DeprecationWarning, stacklevel=2)


def __getattr__(name):
    return getattr(_new, name)

"""Lazy public names of a package (PEP 562), as scipy's ``__init__`` loads its subpackages.

A package's ``__init__`` lists its public names and the module of each; a name is imported from
its module on first use (``crashsim.run``, ``from crashsim.motion import run_runout``, ``import *``)
and kept in the package's namespace from then on. So ``import crashsim`` or ``import
crashsim.units`` loads neither numpy nor the numba kernels, SciPy or matplotlib: a command that
only prints a version or refuses a file starts in tenths of a second
(``tests/unit/test_light_import.py``, ``benchmarks/startup.py``).
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable, Mapping

__all__ = ["lazy_exports"]


def lazy_exports(package: str, exports: Mapping[str, str]) -> tuple[Callable[[str], object], Callable[[], list]]:
    """The module ``__getattr__`` and ``__dir__`` of ``package`` whose public names ``exports`` maps
    to the module that defines each (relative to the package, ``".api"``).

    Examples
    --------
    In a package's ``__init__.py``::

        __getattr__, __dir__ = lazy_exports(__name__, {"run": ".api", "load": ".api"})
    """
    exports = dict(exports)

    def __getattr__(name: str):
        try:
            module = exports[name]
        except KeyError:
            raise AttributeError(f"module {package!r} has no attribute {name!r}") from None
        value = getattr(importlib.import_module(module, package), name)
        setattr(sys.modules[package], name, value)  # resolved once: later look-ups find it directly
        return value

    def __dir__() -> list:
        return sorted(set(vars(sys.modules[package])) | set(exports))

    return __getattr__, __dir__

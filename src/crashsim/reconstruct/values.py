"""File values at a scenario path: read into SI and written back as the file writes them.

:func:`parse_value` and :func:`format_value` take a resolved path (a
:class:`~crashsim.reconstruct.overrides.Target`: its ``field`` says the quantity kind), so the
overrides, the fast patch path and the command line read and write values one way.
"""

from __future__ import annotations

from typing import Any

from ..units import Kind, parse, si_unit, write_like

__all__ = ["parse_value", "format_value"]


def parse_value(value: Any, target, *, field: str) -> float:
    """Read a value written like the file's value at ``target`` (``"25 mph"``, ``"0.05"``) into SI.

    Quantities need their unit; plain numbers may be written as numbers or strings (``"5 %"``
    is 0.05). Range checks are left to the scenario validation (the value is validated when
    it is written into the file dict).
    """
    f = target.field
    if isinstance(f.kind, Kind) and f.kind is not Kind.DIMENSIONLESS:
        return parse(value, f.kind, field=field)
    return parse(value, Kind.DIMENSIONLESS, field=field)


def format_value(x: float, target, like: Any = None) -> Any:
    """An SI value written as the file writes it at ``target`` (``"13.41 m/s"``, or a number).

    With ``like`` (a file value) in the unit of ``like`` (:func:`crashsim.units.write_like`).
    """
    f = target.field
    if like is not None:
        return write_like(x, f.kind if isinstance(f.kind, Kind) else Kind.DIMENSIONLESS, like)
    if isinstance(f.kind, Kind) and si_unit(f.kind):
        return f"{float(x)!r} {si_unit(f.kind)}"
    return float(x)

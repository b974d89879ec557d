"""The road layout of ``[map]``: its lines (:class:`~crashsim.scenario.types.MapLine`) and north.
"""

from __future__ import annotations

import math

import numpy as np

from ..figure_options import is_color
from ..survey.mapping import is_placed
from .problems import error_at
from .types import MapLine


def build_map_lines(m: dict, file: str | None, survey: dict | None = None) -> tuple[MapLine, ...]:
    """The ``[[map.lines]]`` of a validated file (points already in m); colours checked here. A line
    imported from a survey file carries the layer or code it came from (its ``survey.imported``
    record, whose target is ``map.lines[i]``)."""
    source = {}
    for rec in ((survey or {}).get("imported") or ()):
        target = rec.get("target") or ""
        if target.startswith("map.lines[") and rec.get("layer") is not None:
            source.setdefault(target, (rec["layer"], rec.get("kind") or ""))
    lines = []
    for i, ln in enumerate(m["lines"]):
        color = ln["color"]
        if color is not None:
            if not is_color(color):
                raise error_at(f"{color!r} is not a colour; use a matplotlib colour name (\"white\", \"tab:orange\") "
                               "or a hex code (\"#7f7f7f\")", f"map.lines[{i}].color", file)
        layer, kind = source.get(f"map.lines[{i}]", ("", ""))
        lines.append(MapLine(ln["name"], ln["style"], np.asarray(ln["points"], dtype=float), color, layer, kind))
    return tuple(lines)


def check_north(d: dict, file: str | None) -> None:
    """``[map] north`` is for scenes not placed on a survey (a placed scene's grid north is the survey's +y)."""
    north = (d.get("map") or {}).get("north")
    if north is not None and is_placed(d.get("survey")):
        raise error_at(f"{math.degrees(north):g} deg is given for a scene placed on a survey, whose north arrow is the "
                       "survey's grid north (its +y, turned by survey.rotation); allowed only without a placed [survey]: "
                       "remove map.north", "map.north", file)

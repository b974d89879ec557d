"""The option vocabularies of the figures and animations, and their checks, without the drawing.

What ``crashsim plot`` and ``crashsim animate`` offer (legend modes, paper sizes, label kinds,
views) and the checks of ``--hide`` and ``--scale``, apart from :mod:`crashsim.plotting` and
:mod:`crashsim.animation` (which import them from here), so that the command line builds its
parser, prints ``--help`` or ``--version``, or refuses an option, without loading numpy, the run-out or
matplotlib.
"""

from __future__ import annotations

import math
import re

from .errors import ScenarioError

__all__ = ["SCENE_FIGURE_SUFFIXES", "LEGEND_MODES", "PAPER_SIZES", "LABEL_KINDS", "VIEWS", "ANIMATION_LEGENDS", "ZOOMS",
           "check_hide", "check_view", "parse_scale", "NARROW_FIGURE", "title_chars", "is_color"]

#: A figure narrower than this [in] gets its legends under its panels, not beside them (the
#: time-distance chart, the wheel time line).
NARROW_FIGURE = 8.0


def title_chars(width: float, most: int) -> int:
    """Characters a line of a 10-pt title holds in a figure ``width`` inches wide (about 12 to the
    inch, less the margins), at most ``most`` (what a wide figure wraps at)."""
    return max(30, min(most, int(12.5 * (width - 0.8))))

#: Where the legend of a scene figure goes: compact (one line per entry, the evidence as one entry)
#: under or beside the diagram, in full under or beside it, small inside it, or none.
LEGEND_MODES = ("compact", "outside", "inside", "none")

#: Paper sizes of a print sheet, portrait (width, height) [mm]: ISO 216 A4 and A3, US letter and tabloid.
PAPER_SIZES = {"A4": (210.0, 297.0), "A3": (297.0, 420.0), "letter": (215.9, 279.4), "tabloid": (279.4, 431.8)}

#: Kinds of text label on a scene figure (``hide=`` of :func:`crashsim.plotting.plot_scene`, ``--hide`` of
#: ``crashsim plot``), in the order :func:`crashsim.plotting.place_labels` places them (earlier kinds keep
#: their place, later ones move): ``"labels"`` hides all of them.
LABEL_KINDS = ("impacts", "names", "pdof", "delta-v", "approach", "obstacles", "zones", "map", "times")

#: Views of an animation: a camera framed on the vehicles at each frame, or the whole scene still.
VIEWS = ("follow", "scene")

#: Detail windows of a scene figure by name (``crashsim plot --zoom``): the impact configuration.
ZOOMS = ("impact",)

#: Legends of an animation: compact, outside the view (:func:`crashsim.plotting.plot_scene`'s
#: ``legend="compact"``), or none.
ANIMATION_LEGENDS = ("compact", "none")


def check_hide(hide) -> frozenset:
    """The label kinds to hide (``"names,pdof"`` or a sequence), each one of :data:`LABEL_KINDS`
    or ``"labels"`` (all of them).

    Raises
    ------
    ScenarioError
        For an unknown kind (field ``hide``), naming the kinds allowed.

    Examples
    --------
    >>> sorted(check_hide("names, pdof"))
    ['names', 'pdof']
    """
    items = hide.split(",") if isinstance(hide, str) else list(hide or ())
    kinds = frozenset(str(k).strip() for k in items if str(k).strip())
    unknown = sorted(kinds - set(LABEL_KINDS) - {"labels"})
    if unknown:
        raise ScenarioError(f"unknown label kind(s) {', '.join(map(repr, unknown))}; allowed: labels (all), "
                            f"{', '.join(LABEL_KINDS)}", field="hide")
    return kinds


#: The formats a scene figure (and its histories, time-distance and wheel charts) is written in.
SCENE_FIGURE_SUFFIXES = (".png", ".svg", ".pdf")

_ENGINEER = re.compile(r"""^1\s*(?:"|in|inch)\s*=\s*([0-9.eE+]+)\s*(?:'|ft|feet|foot)$""")


def parse_scale(text, *, field: str = "scale") -> float:
    """The denominator N of a drawing scale ``"1:200"`` (or ``"200"``, or a number), or of an engineer's
    scale ``1" = 40'`` (also ``1 in = 40 ft``): N = 12 x the feet per inch (480).

    Raises
    ------
    ScenarioError
        Unless N is a finite number >= 1.

    Examples
    --------
    >>> parse_scale("1:200")
    200.0
    >>> parse_scale("1 in = 40 ft")
    480.0
    """
    raw = str(text).strip()
    eng = _ENGINEER.match(raw.lower())
    body = raw.split(":", 1)[1] if raw.startswith("1:") else raw
    try:
        n = 12.0 * float(eng[1]) if eng else float(body)
    except ValueError:
        n = float("nan")
    if not (math.isfinite(n) and n >= 1.0):
        raise ScenarioError(f"scale {raw!r} is not a drawing scale; allowed 1:N with N >= 1, e.g. \"1:200\", "
                            "or an engineer's scale 1\" = F' with F > 0 feet, e.g. 1\" = 40'", field=field)
    return n


def check_view(values, *, field: str = "view", unit: str = "m") -> tuple[float, float, float, float]:
    """The window ``X0 Y0 X1 Y1`` of a detail view as four floats (strings as written on the
    command line, or numbers), with X1 > X0 and Y1 > Y0, in ``unit`` (named in the message; ""
    for the file's length unit, not known yet).

    Raises
    ------
    ScenarioError
        For other than four finite numbers, or an empty window (field ``field``).

    Examples
    --------
    >>> check_view(["-5", "0", "20", "12.5"])
    (-5.0, 0.0, 20.0, 12.5)
    """
    u = f" {unit}" if unit else ""
    where = f"[{unit}]" if unit else "(in the file's length unit)"
    items = [str(v).strip() for v in values] if not isinstance(values, str) else values.replace(",", " ").split()
    shown = " ".join(items)
    if len(items) != 4:
        raise ScenarioError(f"view {shown!r} has {len(items)} value(s); allowed: four numbers X0 Y0 X1 Y1 {where} "
                            "with X1 > X0 and Y1 > Y0, e.g. -5 0 20 12", field=field)
    out = []
    for name, text in zip(("X0", "Y0", "X1", "Y1"), items):
        try:
            v = float(text)
        except ValueError:
            v = float("nan")
        if not math.isfinite(v):
            raise ScenarioError(f"view {name} = {text!r} is not a number; allowed: four numbers X0 Y0 X1 Y1 "
                                f"{where} with X1 > X0 and Y1 > Y0", field=field)
        out.append(v)
    x0, y0, x1, y1 = out
    for a, b, lo_name, hi_name in ((x0, x1, "X0", "X1"), (y0, y1, "Y0", "Y1")):
        if not b > a:
            raise ScenarioError(f"view {shown!r}: {hi_name} = {b:g}{u} is not above {lo_name} = {a:g}{u}; "
                                f"allowed: {hi_name} > {lo_name}", field=field)
    return x0, y0, x1, y1


def is_color(value) -> bool:
    """Whether ``value`` is a colour matplotlib understands (a name such as ``"white"`` or
    ``"tab:orange"``, a hex code, a grey level string ``"0.5"``); used to check scenario files."""
    from matplotlib.colors import is_color_like

    return bool(is_color_like(value))

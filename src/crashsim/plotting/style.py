"""The look shared by every figure: colour families, evidence and verdict colours, z-order of the
scene layers, friction-zone and map-line styles, halos, title wrapping, 1-2-2.5-5 steps, figure
widths, and the lazy import of matplotlib.pyplot (``import crashsim.plotting`` stays
matplotlib-free).
"""

from __future__ import annotations

import textwrap

import numpy as np

from ..units import resolve_system

__all__ = ["pyplot", "FAMILIES", "EVIDENCE_COLOR", "PASS_COLOR", "FAIL_COLOR", "Z_ZONE", "Z_MAP", "Z_BARRIER", "Z_TRACK",
           "Z_GHOST", "Z_IMPACT", "Z_REST", "Z_EVIDENCE", "Z_ARROW", "Z_TEXT", "ZONE_COLORS", "MAP_STYLES",
           "figure_system", "nice_steps", "nice_at_most", "halo", "wrap", "darker", "FIGURE_WIDTH", "MIN_WIDTH",
           "MAX_WIDTH"]


def pyplot():
    """matplotlib.pyplot, imported on first use (keeps ``import crashsim`` matplotlib-free)."""
    import matplotlib.pyplot as plt

    return plt


#: Colour family of each vehicle, in scenario order: (fill at impact, line, dark).
#: Red and green are kept free for the evidence and its verdicts.
FAMILIES = (
    ("#c6dbef", "#2171b5", "#08306b"),  # blue
    ("#dadaeb", "#6a51a3", "#3f007d"),  # purple
    ("#f6e8c3", "#8c510a", "#543005"),  # brown
    ("#d9d9d9", "#525252", "#000000"),  # grey
    ("#c7eae5", "#01665e", "#003c30"),  # teal
)

EVIDENCE_COLOR = "#d62728"   # measured items

PASS_COLOR = "#1a7f37"

FAIL_COLOR = "#c62828"

_NICE = (1.0, 2.0, 2.5, 5.0)

# z-order of the layers, bottom to top (friction zones under the grid, which sits at 0.5)
Z_ZONE, Z_MAP = 0.3, 1.0

Z_BARRIER, Z_TRACK, Z_GHOST, Z_IMPACT, Z_REST, Z_EVIDENCE, Z_ARROW, Z_TEXT = 2, 3, 4, 5, 6, 7, 8, 9

#: Friction zones, in scenario order: (pale fill, hatch and edge). Green, tan, grey-blue, sand.
ZONE_COLORS = (("#e2efcf", "#7da453"), ("#f0e2c4", "#a27c3f"), ("#dde5ee", "#637a92"), ("#f3efc9", "#a39a3c"))

#: Drawing of each map-line style (crashsim.scenario.MAP_LINE_STYLES): legend text, colour, width,
#: dashes (None: solid) and whether it is a double line (two strokes with a white gap).
MAP_STYLES = {
    "edge": ("road edge", "0.25", 1.6, None, False),
    "lane": ("lane line", "0.35", 1.1, (6.0, 5.0), False),
    "centre": ("centre line", "0.2", 1.0, None, True),
    "kerb": ("kerb / verge edge", "0.35", 4.5, None, False),
    "stop": ("stop line", "0.1", 5.0, None, False),
    "other": ("other line", "0.6", 0.8, None, False),
}


def figure_system(scene, system):
    """The figure's unit system: ``system`` (SI or US, any case) or the scenario's units."""
    return resolve_system(system, scene.scenario.units, field="system")


def nice_steps(lo: float, hi: float):
    """The 1-2-2.5-5 numbers between lo and hi, ascending."""
    out = []
    for e in range(int(np.floor(np.log10(lo))) - 1, int(np.ceil(np.log10(hi))) + 1):
        out += [m * 10.0 ** e for m in _NICE if lo <= m * 10.0 ** e <= hi]
    return out


def nice_at_most(x: float) -> float:
    """Largest 1-2-2.5-5 number <= x (x > 0)."""
    steps = nice_steps(x / 20.0, x)
    return steps[-1] if steps else x


def halo(width: float = 2.5):
    from matplotlib import patheffects

    return [patheffects.withStroke(linewidth=width, foreground="white")]


def wrap(text: str, width: int) -> str:
    return "\n".join(textwrap.wrap(text, width, break_on_hyphens=False)) if text else text


def darker(color, factor: float = 0.6):
    """``color`` darkened towards black (labels in a zone's or line's colour, readable on white)."""
    from matplotlib.colors import to_rgb

    return tuple(factor * c for c in to_rgb(color))


#: Width of a new scene figure laid out with the legend under it [in] (:func:`layout_scene_figure`).
FIGURE_WIDTH = 10.0

#: The range of :func:`plot_scene`'s ``width`` [in].
MIN_WIDTH, MAX_WIDTH = 3.0, 40.0

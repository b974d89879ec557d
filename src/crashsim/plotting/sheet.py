"""The scene figure on paper and its map furniture: print sheets at a stated scale 1:N
(:func:`print_sheet`, :func:`check_sheet`, :func:`layout_print`), engineer's scales of US sheets,
the scale bar, the north and downhill arrows and the +X/+Y axes indicator.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from ..errors import ScenarioError
from ..figure_options import PAPER_SIZES
from ..geometry import rotate
from .drawing import SceneDrawing, scene_drawing
from .style import Z_TEXT, halo, nice_at_most

__all__ = ["ENGINEER_SCALES_FT", "SHEET_EDGE", "engineer_scale_text", "PrintSheet", "print_sheet", "check_sheet",
           "layout_print", "scale_bar", "replace_scale_bar", "north_direction", "north_arrow", "downhill_arrow",
           "axes_indicator"]


#: Scales a print sheet picks from when none is given (1:N), the largest drawing that fits.
_SCALES = (10, 20, 25, 50, 100, 200, 250, 500, 1000, 2000, 2500, 5000, 10000)

#: Engineer's scales of US drawings, as feet per inch (1" = 10', 20', 30', 40', 50', 60', 100', ...):
#: the divisions of an engineer's scale rule (10 to 60 parts to the inch) times a power of ten.
ENGINEER_SCALES_FT = tuple(float(d * 10 ** k) for k in range(0, 4) for d in (1, 2, 3, 4, 5, 6))

#: Margins of a print sheet [in]: paper edge, and room for the tick labels and axis labels.
SHEET_EDGE, _SHEET_LEFT, _SHEET_BOTTOM = 12.0 / 25.4, 0.55, 0.45


def engineer_scale_text(n: float) -> str:
    """A drawing scale 1:N as a US sheet states it: ``1" = 40'`` (N = 480, an engineer's scale of
    :data:`ENGINEER_SCALES_FT`); a scale that is none of them as its exact feet per inch to 3 significant
    digits beside 1:N (``1" = 41.7' (1:500)``): the text always says how the sheet is drawn."""
    ft = float(n) / 12.0
    if any(math.isclose(ft, e, rel_tol=1e-9) for e in ENGINEER_SCALES_FT):
        return f"1\" = {ft:g}'"
    return f"1\" = {ft:.3g}' (1:{float(n):g})"


class PrintSheet(NamedTuple):
    """A scene figure laid out on paper at a stated scale (see :func:`print_sheet`)."""

    paper: str            # key of PAPER_SIZES
    orientation: str      # "landscape" or "portrait"
    size: tuple           # (width, height) of the sheet [in]
    scale: float          # N of 1:N
    box: tuple            # (left, bottom, width, height) of the drawing on the sheet [in]
    lo: np.ndarray        # view limits [display units], lower left
    hi: np.ndarray        # upper right


def print_sheet(paper: str, lo, hi, per_metre: float, scale=None, *, legend_height: float = 1.4,
                system: str = "SI") -> PrintSheet:
    """The sheet, scale and view of a scene figure printed on ``paper``: the view centred on the
    framed extent ``[lo, hi]`` and as large as the drawing box at scale 1:N.

    Parameters
    ----------
    paper : str
        One of :data:`PAPER_SIZES` (any case); landscape when the extent is wider than high.
    lo, hi : array_like, shape (2,)
        The extent the view must hold [display units].
    per_metre : float
        Display units per metre (1 for m, 1/0.3048 for ft).
    scale : float, optional
        N of 1:N; default the largest drawing of :data:`_SCALES` (US: of the engineer's scales
        :data:`ENGINEER_SCALES_FT`, N = 12 x feet per inch) that holds the extent.
    legend_height : float
        Room kept under the drawing for the legend [in].
    system : {"SI", "US"}
        Which standard scales a scale not given is picked from.

    Raises
    ------
    ScenarioError
        Unknown paper (field ``paper``), or a scale at which the extent does not fit the sheet
        (field ``scale``; the message names the largest scale that fits).
    """
    key = next((k for k in PAPER_SIZES if k.lower() == str(paper).lower()), None)
    if key is None:
        raise ScenarioError(f"paper {paper!r} is unknown; allowed {', '.join(PAPER_SIZES)}", field="paper")
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    ext_m = (hi - lo) / per_metre  # extent in metres
    w_mm, h_mm = PAPER_SIZES[key]
    landscape = ext_m[0] > ext_m[1]
    size = np.array((h_mm, w_mm) if landscape else (w_mm, h_mm)) / 25.4
    title = 0.45
    box_w = size[0] - 2 * SHEET_EDGE - _SHEET_LEFT
    box_h = size[1] - 2 * SHEET_EDGE - _SHEET_BOTTOM - title - legend_height
    room = np.array([box_w, box_h]) * 0.0254  # metres of paper
    need = float(max(ext_m / room))  # the smallest N that holds the extent
    us = str(system) == "US"
    standard = tuple(12.0 * f for f in ENGINEER_SCALES_FT) if us else _SCALES
    fits = [n for n in standard if n >= need * (1.0 - 1e-9)]
    if scale is None:
        scale = float(fits[0]) if fits else float(math.ceil(need))
    elif scale < need * (1.0 - 1e-9):
        hint = (engineer_scale_text(fits[0]) if us else f"1:{fits[0]:g}") if fits else f"1:{math.ceil(need)}"
        raise ScenarioError(f"scale 1:{scale:g} is too large for the scene on {key}: its framed extent "
                            f"{ext_m[0]:.1f} m x {ext_m[1]:.1f} m fits at 1:N with N >= {need:.0f} (e.g. {hint}), "
                            "or on "
                            "larger paper", field="scale")
    centre = 0.5 * (lo + hi)
    half = 0.5 * room * float(scale) * per_metre
    box = (SHEET_EDGE + _SHEET_LEFT, SHEET_EDGE + _SHEET_BOTTOM + legend_height, box_w, box_h)
    return PrintSheet(key, "landscape" if landscape else "portrait", (float(size[0]), float(size[1])), float(scale),
                      box, centre - half, centre + half)


def check_sheet(scenario, paper: str, scale: float | None, *, approach: bool = True, field: str = "scale") -> None:
    """Refuse a paper and scale before the run when what is known before it already does not fit.

    The extent of the scene figure is known only after the run-out (rest positions, tracks); the
    vehicles at impact and the evidence (rest positions, marks, the point of impact) are known at
    load, the approaches' paths once they are simulated (not by the loader: a loaded scenario has
    none yet, and a scale that only an approach's path outgrows is refused by the figure, after the
    run), and a figure always holds them. Their extent, padded as
    :func:`plot_scene` pads (without the room of the legend), is a lower bound of the figure's: a
    scale refused here is refused by the figure too, a second and not minutes later.

    Raises
    ------
    ScenarioError
        Field ``field``: the scale, the extent known so far and the smallest N it needs.
    """
    pts = []
    for v in scenario.vehicles:
        for b in v.bodies:
            st = scenario.states.get(b.name) if not b.is_fixed else None
            if st is None:
                continue
            o = b.outline()
            pts.append(np.asarray(st.position, dtype=float)[None] if o is None else
                       np.asarray(st.position, dtype=float) + rotate(np.asarray(o, dtype=float), st.heading))
    ev = scenario.evidence
    if ev.impact_point is not None:
        pts.append(np.asarray(ev.impact_point.position, dtype=float)[None])
    for r in ev.rest:
        pts.append(np.asarray(r.position, dtype=float)[None])
    for m in ev.marks:
        pts.append(np.asarray(m.points, dtype=float).reshape(-1, 2))
    if approach:
        for a in (getattr(scenario, "approaches", None) or {}).values():
            for tr in a.tracks.values():
                if len(tr.points):
                    pts.append(np.asarray(tr.points, dtype=float).reshape(-1, 2))
    if not pts:
        return
    p = np.vstack(pts)
    lo, hi = p.min(axis=0), p.max(axis=0)
    span = float(max((hi - lo).max(), 5.0))
    pad = 0.03 * span + 0.6
    lo, hi = lo - pad, hi + pad
    lo[1] -= 0.05 * span
    hi[1] += 0.05 * span
    try:
        print_sheet(paper, lo, hi, 1.0, scale, legend_height=0.0)
    except ScenarioError as exc:
        if exc.field != "scale":
            raise
        text = str(exc).removeprefix("scale: ").replace(
            "its framed extent", "what is known before the run (the vehicles at impact, the evidence"
            + (", the approaches" if approach else "") + ") spans at least").replace(
            " fits at 1:N with N >= ", ", which needs 1:N with N >= ")
        raise ScenarioError(text, field=field) from None


def layout_print(ax, sheet: PrintSheet) -> None:
    """Size the figure to the sheet and put the axes on its drawing box (exactly 1:N)."""
    fig = ax.figure
    fig.set_size_inches(*sheet.size)
    left, bottom, w, h = sheet.box
    W, H = sheet.size
    ax.set_position([left / W, bottom / H, w / W, h / H])
    fig.draw_without_rendering()


def scale_bar(S: SceneDrawing, width: float, sheet=None):
    """Scale bar at the lower left (a 1-2-2.5-5 length near a fifth of the view); on a print sheet
    its label also states the scale and the paper ("1:200 on A4"; a US sheet its engineer's scale,
    ``1" = 40' on letter``: :func:`engineer_scale_text`)."""
    from matplotlib.font_manager import FontProperties
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    length = nice_at_most(width / 5.0)
    label = f"{length:g} {S.lunit}"
    if sheet is not None:
        shown = engineer_scale_text(sheet.scale) if S.system == "US" else f"1:{sheet.scale:g}"
        label += f"   scale {shown} on {sheet.paper} {sheet.orientation}"
    bar = AnchoredSizeBar(S.ax.transData, length, label, "lower left", pad=0.5, sep=3,
                          borderpad=0.6, frameon=True, size_vertical=0.0, color="black",
                          fontproperties=FontProperties(size=8))
    bar.patch.set(facecolor="white", alpha=0.85, edgecolor="0.6", lw=0.5)
    # the bar itself: a thick line (size_vertical would be in data units)
    bar.size_bar.get_children()[0].set_linewidth(3.0)
    bar.set_gid("scalebar")
    bar.crashsim_length = length
    bar.set_zorder(Z_TEXT + 1)
    S.ax.add_artist(bar)
    return bar


def replace_scale_bar(ax):
    """The scale bar of a scene figure (gid ``"scalebar"``) drawn again for the axes' current
    x limits when its 1-2-2.5-5 length changes (the animation's moving view); returns the bar."""
    S = scene_drawing(ax)
    x0, x1 = ax.get_xlim()
    old = next((a for a in ax.artists if a.get_gid() == "scalebar"), None)
    length = nice_at_most((x1 - x0) / 5.0)
    if old is not None and getattr(old, "crashsim_length", None) == length:
        return old
    if old is not None:
        old.remove()
    bar = scale_bar(S, x1 - x0)
    bar.crashsim_length = length
    return bar


def north_direction(sc) -> tuple[np.ndarray, str] | None:
    """North in the scene frame, a unit vector, and what it is: ``"grid north"`` for a scene
    placed on a survey (the survey's +y; the scene's +X is turned ``survey.rotation`` from its
    +x), else ``"north"`` from ``[map] north`` (the bearing of the scene's +Y, clockwise from
    north: north lies that angle counter-clockwise from +Y); None when the file says neither."""
    if getattr(sc, "survey_frame", None) is not None:
        rot = float(sc.survey_frame.rotation)
        return np.array([math.sin(rot), math.cos(rot)]), "grid north"
    bearing = getattr(sc, "north", None)
    if bearing is None:
        return None
    return np.array([-math.sin(bearing), math.cos(bearing)]), "north"


def north_arrow(S: SceneDrawing) -> list:
    """The north arrow, right of the +X/+Y arrows (:func:`north_direction`): grid north of a scene
    placed on a survey, else the north of ``[map] north``; none when the file says neither (the
    scene's own axes say nothing of north). Returns the texts drawn."""
    got = north_direction(S.sc)
    if got is None:
        return []
    u, _ = got
    from matplotlib.transforms import offset_copy

    base = (0.03, 1.0)
    corner = offset_copy(S.ax.transAxes, fig=S.ax.figure, x=80, y=-34, units="points")
    arrow = dict(arrowstyle="-|>", lw=1.4, color="black", shrinkA=0, shrinkB=0, mutation_scale=12)
    S.ax.annotate("", xy=base, xycoords=corner, xytext=tuple(-26 * u), textcoords="offset points",
                  arrowprops=arrow, zorder=Z_TEXT + 1, gid="north-arrow")
    t = S.ax.annotate("N", xy=base, xycoords=corner, xytext=tuple(9 * u), textcoords="offset points",
                      fontsize=9, fontweight="bold", ha="center", va="center", zorder=Z_TEXT + 1,
                      path_effects=halo(), gid="north-arrow")
    return [t]


def downhill_arrow(S: SceneDrawing, x: float) -> list:
    """An arrow pointing down the road's slope (``runout.grade`` and ``cross_slope``), with its
    steepness, ``x`` points right of the +X/+Y arrows; none on a level road (a zone's own slope is
    in its label). Returns the texts drawn."""
    spec = S.sc.runout
    if spec is None or (spec.road.grade == 0.0 and spec.road.cross_slope == 0.0):
        return []
    g = np.array([spec.road.grade, spec.road.cross_slope])
    steep = float(np.hypot(*g))
    u = -g / steep
    from matplotlib.transforms import offset_copy

    base = (0.03, 1.0)
    corner = offset_copy(S.ax.transAxes, fig=S.ax.figure, x=x, y=-34, units="points")
    head = offset_copy(S.ax.transAxes, fig=S.ax.figure, x=x + 13 * u[0], y=-34 + 13 * u[1], units="points")
    arrow = dict(arrowstyle="-|>", lw=1.4, color="0.25", shrinkA=0, shrinkB=0, mutation_scale=12)
    S.ax.annotate("", xy=base, xycoords=head, xytext=tuple(-26 * u), textcoords="offset points",
                  arrowprops=arrow, zorder=Z_TEXT + 1, gid="downhill-arrow")
    t = S.ax.annotate(f"downhill {100 * steep:.3g} %", xy=base, xycoords=corner, xytext=(0, -16),
                      textcoords="offset points", fontsize=7.5, ha="center", va="top", zorder=Z_TEXT + 1,
                      path_effects=halo(), gid="downhill-arrow")
    return [t]


def axes_indicator(ax) -> list:
    """+X / +Y arrows near the top left corner (equal aspect: screen and world directions agree);
    returns the two texts."""
    from matplotlib.transforms import offset_copy

    out = []
    # the origin 48 points under the top of the axes, whatever their height
    base = (0.03, 1.0)
    corner = offset_copy(ax.transAxes, fig=ax.figure, y=-48, units="points")
    arrow = dict(arrowstyle="<|-", lw=1.2, color="black", shrinkA=0, shrinkB=0, mutation_scale=10)
    for off, text, ha, va, toff in (((26, 0), "+X", "left", "center", (30, 0)),
                                    ((0, 26), "+Y", "center", "bottom", (0, 29))):
        ax.annotate("", xy=base, xycoords=corner, xytext=off, textcoords="offset points",
                    arrowprops=arrow, zorder=Z_TEXT + 1, gid="axes-indicator")
        out.append(ax.annotate(text, xy=base, xycoords=corner, xytext=toff, textcoords="offset points",
                               fontsize=8, ha=ha, va=va, zorder=Z_TEXT + 1, path_effects=halo(),
                               gid="axes-indicator"))
    return out

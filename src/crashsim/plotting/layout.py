"""The layout of a scene figure: the legend (:func:`scene_legend`, its modes), the figure sized to the
equal-aspect view and the legend (:func:`layout_scene_figure`), the limits widened to hold every
label, and the band a legend inside the view gets.
"""

from __future__ import annotations

import numpy as np

from .drawing import SceneDrawing
from .layers import CRUSH_KEY
from .sheet import SHEET_EDGE
from .style import EVIDENCE_COLOR, FAIL_COLOR, FIGURE_WIDTH, PASS_COLOR, Z_TEXT

__all__ = ["OUTSIDE_LEGENDS", "legend_mode", "layout_scene_figure", "fit_texts", "legend_headroom", "scene_legend"]


#: Legend modes that put the legend outside the axes (the figure sized to hold it).
OUTSIDE_LEGENDS = ("compact", "outside")


def legend_mode(legend) -> str:
    """``"compact"``, ``"outside"``, ``"inside"``, ``"none"`` or a matplotlib location (inside,
    there) from :func:`plot_scene`'s ``legend`` (True: outside; False or None: none)."""
    if legend is True:
        return "outside"
    if legend is False or legend is None:
        return "none"
    return str(legend)


def layout_scene_figure(ax, leg, below: bool, width: float = FIGURE_WIDTH, height: float = 7.0,
                        max_width: float | None = None) -> None:
    """Size a figure made by :func:`plot_scene` and place its axes: the axes box gets exactly
    the aspect of the limits (equal scale, no wasted band), the legend its measured size.

    A wide scene is ``width`` inches wide with the legend under it; a tall one has axes
    ``height`` inches high (lower if the figure would be wider than ``max_width``) and the legend
    at the right.
    """
    fig = ax.figure
    r = fig.canvas.get_renderer()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    aspect = (y1 - y0) / (x1 - x0)
    leg_w = leg_h = 0.0
    if leg is not None:
        bb = leg.get_window_extent(r)
        leg_w, leg_h = bb.width / fig.dpi, bb.height / fig.dpi
    left, right, bottom = 0.8, 0.2, 0.6  # y tick labels + label; margin; x tick labels + label
    top = ax.title.get_window_extent(r).height / fig.dpi + 0.3
    if below:
        w_ax = width - left - right
        h_ax = w_ax * aspect
        w_fig = width
        h_fig = top + h_ax + bottom + (leg_h + 0.25 if leg is not None else 0.0)
    else:
        h_ax = height
        w_ax = h_ax / aspect
        if w_ax > width:  # very wide but with the legend at the right (legend= a location): cap
            w_ax, h_ax = width, width * aspect
        if max_width is not None:  # the axes narrower (and lower) so that the figure fits max_width
            room = max_width - left - right - (leg_w + 0.3 if leg is not None else 0.0)
            if w_ax > room > 0.5:
                w_ax, h_ax = room, room * aspect
        w_fig = left + w_ax + right + (leg_w + 0.3 if leg is not None else 0.0)
        # never narrower than the title (a tall scene without a legend at its right)
        half = 0.5 * ax.title.get_window_extent(r).width / fig.dpi + 0.1  # the title is centred on the axes
        centre = left + 0.5 * w_ax
        if centre - half < 0.0:
            left += half - centre
            w_fig += half - centre
            centre = half
        w_fig = max(w_fig, centre + half)
        h_fig = max(top + h_ax + bottom, top + leg_h + 0.2)
    fig.set_size_inches(w_fig, h_fig)
    fig.draw_without_rendering()  # the renderer follows the new size
    ax.set_position([left / w_fig, (h_fig - top - h_ax) / h_fig, w_ax / w_fig, h_ax / h_fig])


def fit_texts(S: SceneDrawing) -> None:
    """Widen the limits so that every data-anchored label lies inside the axes."""
    ax = S.ax
    fig = ax.figure
    if not S.texts:
        return
    fig.draw_without_rendering()
    inv = ax.transData.inverted()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    lo, hi = np.array([x0, y0]), np.array([x1, y1])
    r = fig.canvas.get_renderer()
    for t in S.texts:
        bb = t.get_window_extent(r)
        corners = inv.transform([[bb.x0, bb.y0], [bb.x1, bb.y1]])
        lo = np.minimum(lo, corners.min(axis=0))
        hi = np.maximum(hi, corners.max(axis=0))
    margin = 0.01 * float((hi - lo).max())
    if np.any(lo < [x0, y0]) or np.any(hi > [x1, y1]):
        ax.set_xlim(lo[0] - margin if lo[0] < x0 else x0, hi[0] + margin if hi[0] > x1 else x1)
        ax.set_ylim(lo[1] - margin if lo[1] < y0 else y0, hi[1] + margin if hi[1] > y1 else y1)


def legend_headroom(ax, leg, below: bool, **size) -> None:
    """A legend inside a new figure: a band at the top of the view, added above everything drawn
    (the figure grows to keep the scale), so that it covers none of the scene; the axes
    indicator and north arrow go under it if it would cover them."""
    from matplotlib.transforms import ScaledTranslation

    fig = ax.figure
    r = fig.canvas.get_renderer()
    # centred between the axes indicator (top left) and the animation's clock (top right)
    leg.set_loc("upper center")
    leg.set_bbox_to_anchor((0.14, 0.0, 0.72, 1.0), transform=ax.transAxes)
    fig.draw_without_rendering()
    height = leg.get_window_extent(r).height
    frac = (height + 6.0) / ax.get_window_extent(r).height
    if frac >= 0.9:
        return  # a legend as high as the view: leave it where it is
    y0, y1 = ax.get_ylim()
    # a wide figure keeps its width (and scale): add the legend's height; a tall one keeps its
    # height: the view grows so that the legend's share of it is free
    extra = frac * (y1 - y0) if below else (y1 - y0) * frac / (1.0 - frac)
    ax.set_ylim(y0, y1 + extra)
    layout_scene_figure(ax, None, below, **size)
    fig.draw_without_rendering()
    marks = [a for a in ax.texts if a.get_gid() in ("axes-indicator", "north-arrow", "downhill-arrow")]
    lb = leg.get_window_extent(r)
    if any(lb.overlaps(a.get_window_extent(r)) for a in marks):
        down = ScaledTranslation(0.0, -(lb.height + 6.0) / fig.dpi, fig.dpi_scale_trans)
        for a in marks:
            a.xycoords = a.xycoords + down


def scene_legend(S: SceneDrawing, mode: str, below: bool, compact: bool = False):
    """The legend: ``"outside"`` under the diagram (``below``, in as many columns as fit) or at its
    right; ``"inside"`` small, in the corner that covers least (matplotlib's "best")."""
    labels = list(S.handles)
    handles = [S.handles[k] for k in labels]
    size = 6.5 if compact or mode != "outside" else 7.5
    keys = list(labels)
    if mode != "outside":
        # inside: compact. One line per entry, the evidence items as one entry (the title counts
        # their verdicts; each residual is in the report)
        evidence = ("measured ", "recorded ", "crush energy")

        def is_item(k):  # an evidence item with its verdict (the crush hatch is a key to the drawing)
            return k.startswith(evidence) and k != CRUSH_KEY

        n_ev = sum(is_item(k) for k in keys)
        keep = [k for k in keys if not is_item(k)]
        if n_ev:
            from matplotlib.lines import Line2D

            S.handles.setdefault("measured evidence (red)",
                                 Line2D([], [], ls=(0, (4, 2)), color=EVIDENCE_COLOR, lw=1.2, marker="x", ms=5, mew=1.3))
            keep.append("measured evidence (red)")
        keys = keep
        handles = [S.handles[k] for k in keys]
        labels = [k.split("\n  ")[0].replace("\n", " ") for k in keys]
    if mode in OUTSIDE_LEGENDS and compact:  # a print sheet: under the drawing, as many columns as the page holds
        fig = S.ax.figure
        r = fig.canvas.get_renderer()
        room = fig.get_size_inches()[0] * fig.dpi - 2 * SHEET_EDGE * fig.dpi
        for ncol in (3, 2, 1):
            leg = fig.legend(handles, labels, loc="lower center",
                             bbox_to_anchor=(0.5 * fig.get_size_inches()[0], SHEET_EDGE),
                             bbox_transform=fig.dpi_scale_trans, fontsize=size, frameon=False, handlelength=2.2,
                             ncol=ncol, columnspacing=1.2, borderaxespad=0.0)
            if leg.get_window_extent(r).width <= room or ncol == 1:
                break
            leg.remove()
    elif mode == "compact" and below:
        from matplotlib.transforms import offset_copy

        # under the axes in as many columns (at most 4) as the figure's width holds, centred on the axes
        # (layout_scene_figure: 0.8 in left of them, 0.2 in right): 0.6 in less than the width, and a margin
        # (S.width: the figure's width, 10 in unless plot_scene was given one)
        under = offset_copy(S.ax.transAxes, fig=S.ax.figure, y=-40, units="points")
        fig = S.ax.figure
        r = fig.canvas.get_renderer()
        room = (S.width - 0.8) * fig.dpi
        for ncol in (4, 3, 2, 1):
            leg = S.ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=under,
                              borderaxespad=0.0, fontsize=size, frameon=False, handlelength=2.0, ncol=ncol,
                              columnspacing=1.2, labelspacing=0.3)
            if leg.get_window_extent(r).width <= room or ncol == 1:
                break
            leg.remove()
    elif mode == "compact":
        leg = S.ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
                          fontsize=size, frameon=False, handlelength=2.0, labelspacing=0.3)
    elif mode == "outside" and below:
        from matplotlib.transforms import offset_copy

        # anchored 40 pt under the axes: below the tick labels and the axis label
        under = offset_copy(S.ax.transAxes, fig=S.ax.figure, y=-40, units="points")
        leg = S.ax.legend(handles, labels, loc="upper center", bbox_to_anchor=(0.5, 0.0), bbox_transform=under,
                          borderaxespad=0.0, fontsize=size, frameon=False, handlelength=2.2, ncol=3 if compact else 2,
                          columnspacing=1.5)
    elif mode == "outside":
        leg = S.ax.legend(handles, labels, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0,
                          fontsize=size, frameon=False, handlelength=2.2)
    else:
        loc = "best" if mode == "inside" else mode
        x0, x1 = S.ax.get_xlim()
        y0, y1 = S.ax.get_ylim()
        wide = (x1 - x0) > 1.8 * (y1 - y0)
        leg = S.ax.legend(handles, labels, loc=loc, fontsize=size, framealpha=0.9, handlelength=2.0,
                          borderpad=0.3, labelspacing=0.25, ncol=2 if wide and len(labels) > 8 else 1,
                          columnspacing=1.0)
    n = len(S.scene.evidence.checks) if S.scene.evidence is not None else 0
    for text, full in zip(leg.get_texts(), keys):  # colours by the full label
        c = S.label_colors.get(full)
        if c is not None:
            text.set_color(c)
    if n:
        failed = S.scene.evidence.n_failed
        leg.set_title(f"Evidence: {n - failed} of {n} items within tolerance", prop={"size": 8, "weight": "bold"})
        leg.get_title().set_color(PASS_COLOR if failed == 0 else FAIL_COLOR)
    leg.set_zorder(Z_TEXT + 2)
    return leg

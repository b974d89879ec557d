"""Detail views of a scene figure: the window around the impact and the inset that enlarges it.

A scene whose run-out (or approach) is long draws the impact small: the bodies in contact, the
crush and the contact point take a few percent of the axes. :func:`impact_window` is the box
around the outlines at impact of the bodies in the first impact (plus a margin), the window of
``crashsim plot --zoom impact``; :func:`add_impact_inset` copies what the overview drew in that
window into an inset axes in the corner that covers least, with its own scale bar, and marks the
window on the overview. Pure geometry in SI metres, except for the drawing step, which works in
the axes' display units.
"""

from __future__ import annotations

import numpy as np

from ..geometry import to_world

__all__ = ["IMPACT_MARGIN", "INSET_MARGIN", "MIN_ENLARGEMENT", "INSET_BELOW", "impact_window", "needs_inset", "add_impact_inset"]

#: Margin of the impact window around the outlines at impact: at least this many metres, and at least
#: this fraction of the outlines' larger span.
IMPACT_MARGIN = (2.0, 0.15)

#: An inset is drawn only if it enlarges the window at least this much (else the overview shows it as well).
MIN_ENLARGEMENT = 2.0

#: The margin of the inset's window: tighter than the zoom's, the inset being small.
INSET_MARGIN = (1.0, 0.08)

#: The overview gets an inset of the impact when the impact window is narrower than this fraction of
#: the axes width.
INSET_BELOW = 0.15


def impact_window(scene, margin=IMPACT_MARGIN) -> tuple[np.ndarray, np.ndarray]:
    """The box around the outlines at impact of the bodies in the first impact and its contact
    point, plus :data:`IMPACT_MARGIN`, as (lower-left, upper-right) corners in the ground frame [m].

    A body without outline data counts with its CG; a barrier with its contact point only.
    """
    sc = scene.scenario
    names = {scene.impact.body1, scene.impact.body2}
    pts = [np.atleast_2d(np.asarray(scene.impact.point, dtype=float))]
    for v in sc.vehicles:
        if v.is_barrier:
            continue
        for b in v.bodies:
            if b.name not in names or b.name not in sc.states:
                continue
            st = sc.states[b.name]
            corners = b.outline()
            pts.append(np.atleast_2d(np.asarray(st.position, dtype=float)) if corners is None
                       else to_world(corners, st.position, st.heading))
    pts = np.vstack(pts)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    m = max(margin[0], margin[1] * float((hi - lo).max()))
    return lo - m, hi + m


def needs_inset(window_lo, window_hi, xlim) -> bool:
    """Whether a window [display units] is small on axes with these x limits: narrower than
    :data:`INSET_BELOW` of their width."""
    return (float(window_hi[0]) - float(window_lo[0])) / (xlim[1] - xlim[0]) < INSET_BELOW


def _nice_length(x: float) -> float:
    """Largest 1-2-5 number <= x (x > 0)."""
    e = 10.0 ** np.floor(np.log10(x))
    return float(max(m * e for m in (1.0, 2.0, 5.0) if m * e <= x * (1 + 1e-12)))


def _copy_into(ax, inset) -> int:
    """Copy the data-anchored patches and lines of ``ax`` into ``inset``; the number copied."""
    from matplotlib.artist import Artist
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch, PathPatch

    n = 0
    for p in ax.patches:
        if isinstance(p, FancyArrowPatch) or Artist.get_transform(p) is not ax.transData or not p.get_visible():
            continue
        path = p.get_path().transformed(p.get_patch_transform())
        inset.add_patch(PathPatch(path, facecolor=p.get_facecolor(), edgecolor=p.get_edgecolor(),
                                  lw=p.get_linewidth(), ls=p.get_linestyle(), hatch=p.get_hatch(),
                                  zorder=p.get_zorder(), gid=f"inset:{p.get_gid() or ''}"))
        n += 1
    for ln in ax.lines:
        if ln.get_transform() is not ax.transData or not ln.get_visible():
            continue
        inset.add_line(Line2D(ln.get_xdata(), ln.get_ydata(), color=ln.get_color(), lw=ln.get_linewidth(),
                              ls=ln.get_linestyle(), marker=ln.get_marker(), ms=ln.get_markersize(),
                              mfc=ln.get_markerfacecolor(), mec=ln.get_markeredgecolor(), alpha=ln.get_alpha(),
                              zorder=ln.get_zorder(), solid_capstyle=ln.get_solid_capstyle(),
                              gid=f"inset:{ln.get_gid() or ''}"))
        n += 1
    return n


def add_impact_inset(ax, lo, hi, *, avoid=None, fixed=(), unit: str = "m", size: float = 0.28):
    """An inset of the window [``lo``, ``hi``] (display units) of the scene axes ``ax``, in the corner
    (along the top or the bottom edge) where it covers none of the ``fixed`` artists' boxes and not the
    window itself if it can, and the fewest of the points ``avoid``;
    ``size`` of the axes' width (or less, to keep it under 62 % of their height); the window is
    marked on ``ax`` (gid ``"inset-window"``). The figure must be laid out at its final size.

    Returns
    -------
    matplotlib Axes or None
        None when it would enlarge the window less than :data:`MIN_ENLARGEMENT` times. Equal aspect, no ticks, gid ``"inset:impact"``; its scale bar is the line with gid
        ``"inset:scalebar"`` and its length in ``unit`` in the text beside it.
    """
    from matplotlib.patches import Rectangle

    fig = ax.figure
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    frame = ax.get_window_extent(fig.canvas.get_renderer())
    aspect = (hi[1] - lo[1]) / (hi[0] - lo[0])  # of the window: the inset keeps it (equal scale)
    w = size
    h = w * frame.width * aspect / frame.height
    if h > 0.62:
        w, h = w * 0.62 / h, 0.62
    if w * (x1 - x0) / (hi[0] - lo[0]) < MIN_ENLARGEMENT:
        return None
    r = fig.canvas.get_renderer()
    boxes = [a.get_window_extent(r) for a in fixed]
    pts = None if avoid is None or len(avoid) == 0 else ax.transAxes.inverted().transform(
        ax.transData.transform(np.asarray(avoid, dtype=float)))
    m = 0.015
    best = None
    xs = np.linspace(m, 1 - m - w, 9)
    for cx, cy in [(x, y) for y in (1 - m - h, m) for x in xs[::-1]]:
        cx0, cy0 = frame.x0 + cx * frame.width, frame.y0 + cy * frame.height
        cx1, cy1 = cx0 + w * frame.width, cy0 + (h + 0.04) * frame.height  # its title above it
        hits = sum(1 for b in boxes if b.x0 < cx1 and b.x1 > cx0 and b.y0 < cy1 and b.y1 > cy0)
        cover = 0 if pts is None else int(np.sum((pts[:, 0] > cx) & (pts[:, 0] < cx + w)
                                                 & (pts[:, 1] > cy) & (pts[:, 1] < cy + h)))
        window = not (lo[0] > x0 + (cx + w) * (x1 - x0) or hi[0] < x0 + cx * (x1 - x0)
                      or lo[1] > y0 + (cy + h) * (y1 - y0) or hi[1] < y0 + cy * (y1 - y0))
        key = (hits + int(window), cover)
        if best is None or key < best[0]:
            best = (key, (cx, cy))
    cx, cy = best[1]
    inset = ax.inset_axes([cx, cy, w, h], zorder=20)
    inset.set_gid("inset:impact")
    _copy_into(ax, inset)
    inset.set_xlim(lo[0], hi[0])
    inset.set_ylim(lo[1], hi[1])
    inset.set_aspect("equal", adjustable="datalim")
    inset.set_xticks([])
    inset.set_yticks([])
    inset.set_facecolor("white")
    for s in inset.spines.values():
        s.set(lw=1.0, color="0.25")
    inset.set_title("impact, enlarged", fontsize=7, pad=2)
    length = _nice_length(0.3 * (hi[0] - lo[0]))
    bx, by = lo[0] + 0.05 * (hi[0] - lo[0]), lo[1] + 0.06 * (hi[1] - lo[1])
    inset.plot([bx, bx + length], [by, by], "-", color="black", lw=2.5, solid_capstyle="butt", zorder=30,
               gid="inset:scalebar")
    inset.text(bx + 0.5 * length, by, f"{length:g} {unit}", fontsize=6.5, ha="center", va="bottom", zorder=30,
               gid="inset:scalelabel", bbox=dict(boxstyle="square,pad=0.1", facecolor="white", edgecolor="none",
                                                 alpha=0.8))
    ax.add_patch(Rectangle(tuple(lo), *(hi - lo), facecolor="none", edgecolor="0.25", lw=0.9, ls="--",
                           zorder=19, gid="inset-window"))
    return inset

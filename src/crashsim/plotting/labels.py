"""Text labels of a figure kept clear of each other: the text box of a label, the ink of the drawn
lines (:func:`line_ink`), and :func:`place_labels`, which moves labels (in :data:`LABEL_KINDS` order)
to the nearest free place around their anchor.
"""

from __future__ import annotations

import numpy as np

from ..figure_options import LABEL_KINDS

__all__ = ["text_box", "LINE_SHY", "line_ink", "place_labels"]


#: Distances from its anchor [points] at which :func:`place_labels` tries a label that overlaps
#: another, 12 directions each; a label moved this far or more gets a leader line to its anchor.
_RINGS = (8.0, 13.0, 19.0, 26.0, 34.0, 44.0, 56.0, 70.0, 88.0)

_LEADER_FROM = 13.0


def _label_kind(t) -> str:
    gid = t.get_gid() or ""
    if gid.startswith(("zone-label", "map-label")):
        return "zones" if gid.startswith("zone") else "map"
    return gid.split(":")[1] if gid.startswith("label:") else "other"


def text_box(t, renderer):
    """Window extent of a text artist's text alone [pixels] (an annotation's arrow left out)."""
    from matplotlib.text import Text
    from matplotlib.transforms import Bbox

    if not t.get_text():
        return None
    if hasattr(t, "update_positions"):  # an annotation: place its text for the current offset first
        t.update_positions(renderer)
    bb = Text.get_window_extent(t, renderer)
    patch = t.get_bbox_patch()
    if patch is not None:  # a disc (impact numbers) or box around the text: its outer square
        pad = patch.get_boxstyle().pad * t.get_fontsize() * t.get_figure(root=True).dpi / 72.0
        half = 0.5 * max(bb.width, bb.height) + pad
        cx, cy = 0.5 * (bb.x0 + bb.x1), 0.5 * (bb.y0 + bb.y1)
        bb = Bbox([[cx - half, cy - half], [cx + half, cy + half]])
    return bb


#: Label kinds kept off the drawn lines and outlines where a free place near their anchor allows
#: (names, impact numbers and ghost times belong on their body or point; zone and map labels lie
#: along their own line by design).
LINE_SHY = ("pdof", "delta-v", "approach", "obstacles")

#: Farthest a label otherwise free moves to get off a line [points] (a ring of :data:`_RINGS`).
_SHY_REACH = 26.0

#: Spacing of the samples along drawn lines that a label is kept off [pixels].
_INK_STEP = 2.0


def line_ink(ax, exclude=()) -> np.ndarray:
    """Pixel positions along every line and outline edge drawn in the axes, shape (n, 2): the
    vertices of each Line2D and patch (leader lines, the inset's window and ``exclude`` left out) and points every
    :data:`_INK_STEP` pixels between them, inside the axes."""
    from matplotlib.lines import Line2D

    frame = ax.get_window_extent(ax.figure.canvas.get_renderer())
    out = []
    for a in [*ax.lines, *ax.patches]:
        if not a.get_visible() or a in exclude or (a.get_gid() or "").startswith(("leader:", "inset-window")):
            continue  # leaders, and the inset's dashed window (a guide a label may cross)
        if isinstance(a, Line2D):
            if a.get_linestyle() in ("None", "none", "", " "):
                continue  # markers only
            xy = a.get_transform().transform(np.column_stack(a.get_data()).astype(float))
            polys = [xy]
        else:
            polys = a.get_path().to_polygons(a.get_transform())
        for xy in polys:
            xy = xy[np.all(np.isfinite(xy), axis=1)]
            if len(xy) < 2:
                continue
            seg = np.diff(xy, axis=0)
            n = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / _INK_STEP), 1).astype(int)
            f = np.concatenate([np.arange(k) / k for k in n])
            start = np.repeat(xy[:-1], n, axis=0)
            out.append(start + f[:, None] * np.repeat(seg, n, axis=0))
    if not out:
        return np.empty((0, 2))
    pts = np.vstack(out)
    keep = (pts[:, 0] >= frame.x0) & (pts[:, 0] <= frame.x1) & (pts[:, 1] >= frame.y0) & (pts[:, 1] <= frame.y1)
    return pts[keep]


def place_labels(ax, texts, fixed=(), avoid=None, lines: bool = True) -> int:
    """Move labels so that no two text boxes overlap: labels in :data:`LABEL_KINDS` order keep
    their place while free, else go to the nearest free place around their anchor.

    Parameters
    ----------
    ax : matplotlib Axes
        The figure must be laid out at its final size (positions are measured in pixels).
    texts : sequence of matplotlib Annotation
        Labels anchored in data coordinates (``xycoords="data"``).
    fixed : sequence of artists
        Kept clear of and never moved (axes indicator, scale bar, a legend inside the axes).
    avoid : ndarray, shape (n, 2), optional
        Points drawn [data units]: among free places at the same distance, the one covering
        fewest of them wins.
    lines : bool
        Keep labels of the :data:`LINE_SHY` kinds off the drawn lines and outline edges
        (:func:`line_ink`) where they can: such a label that covers a line moves to the nearest
        free place within :data:`_SHY_REACH` points that covers none (else it stays), and among
        free places at one distance the one covering the least line wins.

    Returns
    -------
    int
        Labels for which no free place inside the axes was found (left where they were).

    Notes
    -----
    Overlap is measured with the renderer's window extents (the boxes the text occupies at
    the figure's size and dpi), 1.5 pixels apart. A label is tried at its own place first,
    then at :data:`_RINGS` points from its anchor in 12 directions, aligned away from the
    anchor (its nearest corner or edge towards it); the first distance with a free place
    wins, and a label moved :data:`_LEADER_FROM` points or more gets a thin leader line. It
    is a greedy step (deterministic, no iteration): labels placed earlier are never moved.
    Labels of the :data:`LINE_SHY` kinds are also kept off the drawn lines where they can (see
    ``lines``).
    """
    fig = ax.figure
    for old in [a for a in ax.texts if (a.get_gid() or "").startswith("leader:")]:
        old.remove()  # leaders of an earlier placement (the animation places again after widening)
    r = fig.canvas.get_renderer()
    frame = ax.get_window_extent(r)
    placed = []
    for a in fixed:
        bb = text_box(a, r) if hasattr(a, "get_text") else a.get_window_extent(r)
        if bb is not None:
            placed.append(bb)
    px = None if avoid is None or len(avoid) == 0 else ax.transData.transform(np.asarray(avoid, dtype=float))
    order = sorted((t for t in texts if t.get_visible() and t.get_text()),
                   key=lambda t: LABEL_KINDS.index(k) if (k := _label_kind(t)) in LABEL_KINDS else len(LABEL_KINDS))
    pad = 1.5

    def free(bb):
        if bb.x0 < frame.x0 or bb.y0 < frame.y0 or bb.x1 > frame.x1 or bb.y1 > frame.y1:
            return False
        big = bb.padded(pad)
        return not any(big.overlaps(q) for q in placed)

    def covered(bb):
        if px is None:
            return 0
        return int(np.count_nonzero((px[:, 0] >= bb.x0) & (px[:, 0] <= bb.x1) & (px[:, 1] >= bb.y0)
                                    & (px[:, 1] <= bb.y1)))

    ink = line_ink(ax) if lines and any(_label_kind(t) in LINE_SHY for t in order) else None

    def on_lines(bb):
        return int(np.count_nonzero((ink[:, 0] >= bb.x0) & (ink[:, 0] <= bb.x1) & (ink[:, 1] >= bb.y0)
                                    & (ink[:, 1] <= bb.y1)))

    lost = 0
    angles = np.radians(np.arange(0.0, 360.0, 30.0) + 90.0)  # above first, then round
    for t in order:
        bb = text_box(t, r)
        shy = ink is not None and len(ink) > 0 and _label_kind(t) in LINE_SHY
        was_free = free(bb)
        if was_free and (not shy or on_lines(bb) == 0):
            placed.append(bb)
            continue
        start = (t.xyann, t.anncoords, t.get_ha(), t.get_va())
        best = None
        for ring in _RINGS:
            if was_free and ring > _SHY_REACH:
                break  # free but on a line: only a near place off the lines is worth the move
            for a in angles:
                c, s = np.cos(a), np.sin(a)
                t.set_anncoords("offset points")
                t.xyann = (ring * c, ring * s)
                t.set_ha("left" if c > 0.3 else "right" if c < -0.3 else "center")
                t.set_va("bottom" if s > 0.3 else "top" if s < -0.3 else "center")
                cand = text_box(t, r)
                if free(cand):
                    score = (on_lines(cand) if shy else 0, covered(cand))
                    if (was_free and score[0] > 0) or (best is not None and score >= best[0]):
                        continue
                    best = (score, ring, (ring * c, ring * s), t.get_ha(), t.get_va(), cand)
            if best is not None:
                break
        if best is None and was_free:  # no near place off the lines: it stays where it was
            t.xyann, _, ha, va = start
            t.set_anncoords(start[1])
            t.set_ha(ha)
            t.set_va(va)
            placed.append(text_box(t, r))
            continue
        if best is None:
            t.xyann, _, ha, va = start
            t.set_anncoords(start[1])
            t.set_ha(ha)
            t.set_va(va)
            placed.append(text_box(t, r))
            lost += 1
            continue
        _, ring, off, ha, va, cand = best
        t.set_anncoords("offset points")
        t.xyann = off
        t.set_ha(ha)
        t.set_va(va)
        placed.append(cand)
        if ring >= _LEADER_FROM:
            ax.annotate("", xy=t.xy, xytext=off, textcoords="offset points", zorder=t.get_zorder() - 0.1,
                        arrowprops=dict(arrowstyle="-", lw=0.6, color=t.get_color(), shrinkA=0.0, shrinkB=1.5),
                        gid=f"leader:{_label_kind(t)}")
    return lost

"""The road layout of a scene figure: friction zones and map lines under everything else, their
labels where they cover least (:func:`label_road_layout`), the region of interest that road geometry
may add to the view, and the clipping of polygons and polylines to a box.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..motion.road import points_in_polygon, signed_distance
from ..units import format_value
from .drawing import SceneDrawing
from .style import MAP_STYLES, ZONE_COLORS, Z_MAP, Z_TEXT, Z_ZONE, darker, halo

__all__ = ["friction_text", "region_of_interest", "clip_polygon", "clip_polyline", "zone_colors", "draw_zones",
           "map_line_legend_texts", "draw_map_lines", "label_road_layout"]


#: Margin of the region of interest around the scene: at least this many metres, and at least
#: this fraction of the scene's larger span.
_ROI_MARGIN, _ROI_FRACTION = 3.0, 0.15


class _Roi(NamedTuple):
    """Region of interest of a scene figure (display units): what road-layout geometry may add
    to the axis limits, and what its labels must keep clear of."""

    lo: np.ndarray       # lower-left corner of the box
    hi: np.ndarray       # upper-right corner
    drawn: np.ndarray    # every point drawn before the road layout, shape (n, 2)
    shapes: list         # outlines and obstacles (polygons) a label must not sit in


def region_of_interest(S: SceneDrawing) -> _Roi:
    """The box around everything drawn so far (vehicles, tracks, evidence, obstacles, arrows,
    impacts) plus a margin (:data:`_ROI_MARGIN`, :data:`_ROI_FRACTION`)."""
    pts = np.vstack(S.points)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    margin = max(_ROI_MARGIN * S.k, _ROI_FRACTION * float((hi - lo).max()))
    kinds = ("outline", "evidence", "obstacle", "barrier")
    shapes = []
    for p in S.ax.patches:
        if (p.get_gid() or "").split(":")[0] in kinds and hasattr(p, "get_xy"):
            xy = np.asarray(p.get_xy(), dtype=float)
            keep = np.any(xy != np.roll(xy, -1, axis=0), axis=1)  # no zero-length edges (closing vertex)
            if keep.sum() >= 3:
                shapes.append(xy[keep])
    return _Roi(lo - margin, hi + margin, pts, shapes)


def clip_polygon(polygon, lo, hi) -> np.ndarray:
    """The part of a polygon inside the box [lo, hi] (Sutherland-Hodgman), shape (m, 2); m is 0
    when they do not overlap."""
    out = np.asarray(polygon, dtype=float)
    for axis in (0, 1):
        for bound, inside in ((lo[axis], np.greater_equal), (hi[axis], np.less_equal)):
            if len(out) == 0:
                return out.reshape(0, 2)
            kept = []
            prev = out[-1]
            for cur in out:
                if inside(cur[axis], bound) != inside(prev[axis], bound):
                    kept.append(prev + (bound - prev[axis]) / (cur[axis] - prev[axis]) * (cur - prev))
                if inside(cur[axis], bound):
                    kept.append(cur)
                prev = cur
            out = np.asarray(kept, dtype=float).reshape(-1, 2)
    return out


def clip_polyline(points, lo, hi) -> list[np.ndarray]:
    """The pieces of a polyline inside the box [lo, hi] (Liang-Barsky on each segment), each of
    shape (m >= 2, 2)."""
    pts = np.asarray(points, dtype=float)
    pieces, cur = [], []
    for a, b in zip(pts[:-1], pts[1:]):
        d = b - a
        t0, t1 = 0.0, 1.0
        for p, q in ((-d[0], a[0] - lo[0]), (d[0], hi[0] - a[0]), (-d[1], a[1] - lo[1]), (d[1], hi[1] - a[1])):
            if p == 0.0:
                if q < 0.0:
                    t0, t1 = 1.0, 0.0  # parallel to this side and outside it
            elif p < 0.0:
                t0 = max(t0, q / p)
            else:
                t1 = min(t1, q / p)
        if t0 > t1:
            if cur:
                pieces.append(np.asarray(cur))
                cur = []
            continue
        pa, pb = a + t0 * d, a + t1 * d
        if not (cur and np.allclose(cur[-1], pa)):
            if cur:
                pieces.append(np.asarray(cur))
            cur = [pa]
        cur.append(pb)
    if cur:
        pieces.append(np.asarray(cur))
    return pieces


def _zones(S: SceneDrawing) -> tuple:
    spec = S.sc.runout
    return spec.road.zones if spec is not None else ()


def friction_text(mu: float) -> str:
    """A friction coefficient to three significant digits, ``"f = 0.72"`` (a Monte Carlo median such
    as 0.720011 without its float noise)."""
    return f"f = {format_value(float(mu), 'dimensionless', digits=3)}"


def _zone_label(zone) -> str:
    slope = [f"{what} {100 * v:.3g} %" for what, v in (("grade", zone.grade), ("cross-slope", zone.cross_slope))
             if v is not None]
    return ", ".join([f"{zone.name}, {friction_text(zone.mu)}", *slope])


def zone_colors(zones) -> list[tuple[str, str]]:
    """(fill, edge) of each friction zone: one pair per distinct zone name, in the order the names
    first appear (:data:`ZONE_COLORS`, repeating after four names), so that two zones of one
    name ("grass verge" either side of the road) look alike and share one legend entry."""
    order: dict[str, int] = {}
    for z in zones:
        order.setdefault(z.name, len(order))
    return [ZONE_COLORS[order[z.name] % len(ZONE_COLORS)] for z in zones]


def _zone_legend_texts(zones) -> dict[str, str]:
    """Zone name -> its legend text: ``"friction zone: grass verge, f = 0.4"``; zones of one name
    whose friction or slope differ list each distinct value set (``"gravel, f = 0.5 | f = 0.6"``)."""
    parts: dict[str, list[str]] = {}
    for z in zones:
        rest = _zone_label(z).removeprefix(f"{z.name}, ")
        got = parts.setdefault(z.name, [])
        if rest not in got:
            got.append(rest)
    return {name: f"friction zone: {name}, {' | '.join(rest)}" for name, rest in parts.items()}


def draw_zones(S: SceneDrawing, roi: _Roi) -> None:
    """Every friction zone of the road as a pale hatched polygon under everything else, one colour
    and one legend entry per zone name (:func:`zone_colors`); only its part inside the region of
    interest counts toward the axis limits."""
    from matplotlib.patches import Patch, Polygon

    zones = _zones(S)
    legend = _zone_legend_texts(zones)
    for i, (z, (fill, edge)) in enumerate(zip(zones, zone_colors(zones))):
        xy = S.d(z.vertices)
        S.ax.add_patch(Polygon(xy, closed=True, facecolor=fill, edgecolor=edge, lw=0.8, hatch=".",
                               zorder=Z_ZONE, gid=f"zone:{i}"))
        inside = clip_polygon(xy, roi.lo, roi.hi)
        if len(inside):
            S.add(inside)
        S.legend_entry(legend[z.name], Patch(facecolor=fill, edgecolor=edge, hatch=".", lw=0.8))
    if zones:
        S.legend_entry(f"road surface outside the zones: {friction_text(S.sc.runout.road.mu)}",
                       Patch(facecolor="white", edgecolor="0.6", lw=0.8))


def _map_line_look(line) -> tuple[str, str]:
    """(what it is, colour) of a map line: its style's legend text, or for a gouge or debris drawn
    from a survey "gouge"/"debris"; its own colour or the style's."""
    text, color = MAP_STYLES[line.style][:2]
    if line.imported_as in ("gouge", "debris"):
        text = line.imported_as
    return text, line.color or color


def map_line_legend_texts(lines) -> list[str]:
    """The legend text of each map line, one text for the lines that look alike (one style, one
    colour), naming where they come from: the survey file's layers or codes (``"road edge (EDGE,
    EP)"``, ``"gouge (GOUGE)"``), else the name or colour given to a line of its own colour
    (``"road edge (painted)"``); a plain line of a style written in the scenario file is its
    style's text alone (``"road edge"``), in an entry apart from the surveyed ones."""
    groups: dict[tuple, list[str]] = {}
    keys = []
    for line in lines:
        text, color = _map_line_look(line)
        key = (line.style, text, color, bool(line.layer))  # a written line is not said to come from a layer
        keys.append(key)
        names = groups.setdefault(key, [])
        if line.layer:
            name = line.layer
        elif line.color is not None:
            name = line.name or line.color
        else:
            name = ""
        if name and name not in names:
            names.append(name)
    return [f"{key[1]} ({', '.join(groups[key])})" if groups[key] else key[1] for key in keys]


def _map_line_artist_kw(line) -> tuple[str, dict]:
    """(legend text, Line2D keywords) of a map line in its style (and its own colour, if given)."""
    from matplotlib import patheffects

    _, _, lw, dashes, double = MAP_STYLES[line.style]
    _, color = _map_line_look(line)
    if double:  # two strokes with a white gap: a wide stroke under a narrow white line
        kw = dict(color="white", lw=lw, solid_capstyle="butt",
                  path_effects=[patheffects.Stroke(linewidth=3.6 * lw, foreground=color), patheffects.Normal()])
    else:
        kw = dict(color=color, lw=lw, solid_capstyle="butt")
        if dashes is not None:
            kw.update(ls="--", dashes=dashes)
    return map_line_legend_texts([line])[0], kw


def draw_map_lines(S: SceneDrawing, roi: _Roi) -> None:
    """The road layout of ``[[map.lines]]`` under the vehicles, each in its style; only the parts
    inside the region of interest count toward the axis limits."""
    from matplotlib.lines import Line2D

    lines = getattr(S.sc, "map_lines", ())
    for i, (line, text) in enumerate(zip(lines, map_line_legend_texts(lines))):
        _, kw = _map_line_artist_kw(line)
        xy = S.d(line.points)
        S.ax.plot(xy[:, 0], xy[:, 1], zorder=Z_MAP, gid=f"map:{i}", **kw)
        for piece in clip_polyline(xy, roi.lo, roi.hi):
            S.add(piece)
        S.legend_entry(text, Line2D([], [], **kw))


class _LabelPlacer:
    """Chooses where road-layout labels go: among candidate anchors, the one whose text box
    (estimated from its length and font size at the current scale) covers the fewest drawn
    points, vehicle outlines, obstacles, placed labels and axes corners (axes indicator, scale
    bar), and then keeps clearest of what is drawn."""

    def __init__(self, S: SceneDrawing, roi: _Roi, lo, hi):
        from scipy.spatial import cKDTree

        self.S, self.roi = S, roi
        self.lo, self.hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
        fig, ax = S.ax.figure, S.ax
        fig.draw_without_rendering()
        inv = ax.transData.inverted()
        r = fig.canvas.get_renderer()
        self.boxes = []  # (lower-left, upper-right) of the labels placed so far, data units
        for t in S.texts:
            c = inv.transform(t.get_window_extent(r).get_points())
            self.boxes.append((c.min(axis=0), c.max(axis=0)))
        self.per_point = float(abs(inv.transform([[fig.dpi / 72.0, 0.0]])[0, 0] - inv.transform([[0.0, 0.0]])[0, 0]))
        self.tree = cKDTree(roi.drawn)

    def _blocked(self, q: np.ndarray, pad: float) -> np.ndarray:
        """Which points q (m, 2) are covered by something drawn or kept free."""
        bad = np.isfinite(self.tree.query(q, distance_upper_bound=pad)[0])
        for shape in self.roi.shapes:
            bad |= points_in_polygon(q, shape)
        for a, b in self.boxes:
            bad |= np.all((q >= a) & (q <= b), axis=1)
        frac = (q - self.lo) / (self.hi - self.lo)
        bad |= np.any((frac < 0.0) | (frac > 1.0), axis=1)
        bad |= (frac[:, 0] < 0.25) & ((frac[:, 1] > 0.72) | (frac[:, 1] < 0.12))
        return bad

    def best(self, candidates, text: str, fontsize: float, *, angles=None, offset: float = 0.0,
             allowed=None, room=None) -> int | None:
        """Index of the best anchor among ``candidates`` (n, 2) for ``text``, or None if none.

        Parameters
        ----------
        angles : array_like, optional
            Text direction at each candidate [deg] (default horizontal).
        offset : float
            Distance of the text from its anchor across its direction [points] (text above the
            anchor); 0: centred on it.
        allowed : callable, optional
            ``allowed(points) -> bool array``: where the text may lie (e.g. inside its zone).
        room : array_like, optional
            Free space around each candidate in its own region; caps the clearance score.
        """
        cand = np.asarray(candidates, dtype=float).reshape(-1, 2)
        if len(cand) == 0:
            return None
        ang = np.radians(np.zeros(len(cand)) if angles is None else np.asarray(angles, dtype=float))
        u = np.column_stack([np.cos(ang), np.sin(ang)])
        nrm = np.column_stack([-u[:, 1], u[:, 0]])
        w = len(text) * 0.55 * fontsize * self.per_point
        h = 1.25 * fontsize * self.per_point
        centre = cand + nrm * (offset * self.per_point + 0.5 * h if offset else 0.0)
        s, t = np.meshgrid(np.linspace(-0.5 * w, 0.5 * w, 9), np.linspace(-0.5 * h, 0.5 * h, 3))
        q = (centre[:, None, :] + u[:, None, :] * s.ravel()[None, :, None]
             + nrm[:, None, :] * t.ravel()[None, :, None])  # (n, 27, 2) samples of each text box
        flat = q.reshape(-1, 2)
        bad = self._blocked(flat, 0.5 * h)
        if allowed is not None:
            bad |= ~np.asarray(allowed(flat), dtype=bool)
        conflicts = bad.reshape(len(cand), -1).sum(axis=1)
        clear = self.tree.query(cand)[0]
        if room is not None:
            clear = np.minimum(clear, 2.0 * np.asarray(room, dtype=float))
        order = np.lexsort((-clear, conflicts))  # fewest conflicts, then clearest
        k = int(order[0])
        box = q[k]
        self.boxes.append((box.min(axis=0), box.max(axis=0)))
        return k


def label_road_layout(S: SceneDrawing, roi: _Roi, lo, hi) -> None:
    """Label each friction zone inside its visible part ("grass verge, f = 0.35") and each named
    map line along its visible part, where the text covers least of the scene (:class:`_LabelPlacer`)."""
    zones = _zones(S)
    lines = [ln for ln in getattr(S.sc, "map_lines", ()) if ln.name]
    if not zones and not lines:
        return
    place = _LabelPlacer(S, roi, lo, hi)
    inset = 0.03 * (np.asarray(hi) - np.asarray(lo))
    vlo, vhi = lo + inset, hi - inset  # anchors inside the axes
    polys = [S.d(z.vertices) for z in zones]
    colors = zone_colors(zones)
    for i, z in enumerate(zones):
        part = clip_polygon(polys[i], vlo, vhi)
        if len(part) < 3:
            continue
        a, b = part.min(axis=0), part.max(axis=0)
        gx, gy = np.meshgrid(np.linspace(a[0], b[0], 31), np.linspace(a[1], b[1], 31))
        cand = np.column_stack([gx.ravel(), gy.ravel()])

        def effective(q, i=i):  # inside zone i and not in a later zone (later zones win)
            inside = points_in_polygon(q, polys[i])
            for later in polys[i + 1:]:
                inside &= ~points_in_polygon(q, later)
            return inside

        cand = cand[effective(cand)]
        if len(cand) == 0:
            continue
        text = _zone_label(z)
        k = place.best(cand, text, 7.5, allowed=effective, room=signed_distance(cand, polys[i]))
        edge = colors[i][1]
        S.text(cand[k], text, kind="zones", gid=f"zone-label:{i}", fontsize=7.5, ha="center", va="center",
                   style="italic", color=darker(edge),
                   path_effects=halo(2.2), zorder=Z_TEXT - 0.5)
        S.labels.append(cand[k])
    step = 0.015 * float((np.asarray(hi) - np.asarray(lo)).max())
    for i, line in enumerate(getattr(S.sc, "map_lines", ())):
        if not line.name:
            continue
        cand, angle = [], []
        for piece in clip_polyline(S.d(line.points), vlo, vhi):
            for p, q in zip(piece[:-1], piece[1:]):
                n = max(2, int(np.ceil(np.hypot(*(q - p)) / step)))
                cand += list(p + np.linspace(0.0, 1.0, n)[:, None] * (q - p))
                deg = np.degrees(np.arctan2(q[1] - p[1], q[0] - p[0]))
                angle += [(deg + 90.0) % 180.0 - 90.0] * n  # readable: never upside down
        k = place.best(np.asarray(cand).reshape(-1, 2), line.name, 6.5, angles=angle, offset=3.0)
        if k is None:
            continue
        deg = angle[k]
        off = 3.0 * np.array([-np.sin(np.radians(deg)), np.cos(np.radians(deg))])
        color = darker(line.color or MAP_STYLES[line.style][1])
        S.text(cand[k], line.name, kind="map", gid=f"map-label:{i}", xytext=tuple(off), textcoords="offset points",
                   fontsize=6.5, ha="center",
                   va="bottom", rotation=deg, rotation_mode="anchor", color=color, path_effects=halo(2.0),
                   zorder=Z_TEXT - 0.5)
        S.labels.append(cand[k])

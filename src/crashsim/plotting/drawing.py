"""The drawing state of a scene figure (:class:`SceneDrawing`): display units, the legend entries,
the labels and the extent drawn so far, shared by the layers that :func:`crashsim.plotting.plot_scene`
draws; :func:`scene_drawing` finds it again from the axes.
"""

from __future__ import annotations

import weakref

import numpy as np

from ..geometry import rotate, to_body, to_world
from ..units import Kind, to_unit
from .style import FAMILIES, FIGURE_WIDTH, Z_IMPACT, Z_TEXT, halo

__all__ = ["scene_drawing", "SceneDrawing"]


#: The drawing state of each scene figure's axes (:func:`scene_drawing`); entries go with the axes.
_DRAWINGS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def scene_drawing(ax) -> "SceneDrawing | None":
    """The :class:`SceneDrawing` that :func:`plot_scene` drew on ``ax`` (its labels, the artists
    that change with time), or None."""
    return _DRAWINGS.get(ax)


class SceneDrawing:
    """State shared by the drawing steps of :func:`plot_scene` (display units, legend, extent)."""

    def __init__(self, scene, ax, system):
        self.scene = scene
        self.sc = scene.scenario
        self.ax = ax
        self.system = system
        self.k, self.lunit = to_unit(1.0, Kind.LENGTH, system)  # display length per metre
        self.points: list[np.ndarray] = []   # everything drawn, display units, for the limits
        self.handles: dict[str, object] = {}  # legend: label -> proxy artist (ordered, deduplicated)
        self.label_colors: dict[str, str] = {}
        self.labels: list[np.ndarray] = []  # positions of the text labels placed so far
        self.texts: list = []  # labels anchored in data coordinates
        self.no_outline: set[str] = set()  # bodies drawn as a skeleton
        self.approach = True  # draw the approaches (and pre-impact marks)
        self.width = FIGURE_WIDTH  # width of a new figure [in] (plot_scene's width)
        self.hide: frozenset = frozenset()  # label kinds left out (LABEL_KINDS)
        self.far: list[np.ndarray] = []  # obstacle pieces: in the extent only near the scene
        self.fixed: list = []  # artists the labels keep clear of (axes indicator, scale bar, ...)
        self.unplaced = 0  # labels place_labels found no free place for
        self.timed: list = []  # (Line2D, times [s] (n,), points (n, 2) display units): paths and tracks
        self.appear: list = []  # (artist, time [s]): outlines etc. at rest, from their rest; the impact's results
        # (delta-v and PDOF arrows, the contact point, numbered impacts) from the impact they belong to
        self.body_of = {b.name: b for v in self.sc.vehicles for b in v.bodies}
        self.vehicle_of = {b.name: v for v in self.sc.vehicles for b in v.bodies}
        movable = [v for v in self.sc.vehicles if not v.is_barrier]
        self.family = {v.name: FAMILIES[i % len(FAMILIES)] for i, v in enumerate(movable)}

    # -- helpers ---------------------------------------------------------------------------
    def keep(self) -> None:
        """Make this the drawing :func:`scene_drawing` returns for its axes (the figure is finished)."""
        _DRAWINGS[self.ax] = self

    def d(self, xy) -> np.ndarray:
        """World SI point(s) -> display units."""
        return self.k * np.asarray(xy, dtype=float)

    def add(self, xy):
        self.points.append(np.atleast_2d(np.asarray(xy, dtype=float)))

    def legend_entry(self, label: str, handle, color: str | None = None):
        if label not in self.handles:
            self.handles[label] = handle
            if color is not None:
                self.label_colors[label] = color

    def colors(self, body_name: str):
        return self.family.get(self.vehicle_of[body_name].name, FAMILIES[-1])

    # -- vehicles --------------------------------------------------------------------------
    def outline(self, body, position, heading, *, gid: str, fill, edge, lw: float, ls="-", alpha=1.0,
                zorder=Z_IMPACT):
        """Outline rectangle of ``body`` at a pose; None if the body has no outline data."""
        from matplotlib.patches import Polygon

        corners = body.outline()
        if corners is None:
            return None
        xy = self.d(to_world(corners, position, heading))
        patch = Polygon(xy, closed=True, facecolor=fill if fill is not None else "none", edgecolor=edge,
                        lw=lw, ls=ls, alpha=alpha, zorder=zorder, gid=gid)
        self.ax.add_patch(patch)
        self.add(xy)
        return patch

    def axle_lines(self, body, position, heading, color, lw, alpha=1.0, zorder=Z_IMPACT):
        for a in body.axles:
            xy = self.d(to_world(np.array([[a.x, -a.track / 2], [a.x, a.track / 2]]), position, heading))
            self.ax.plot(xy[:, 0], xy[:, 1], "-", color=color, lw=lw, alpha=alpha, zorder=zorder,
                         solid_capstyle="butt")

    def pins(self, vehicle, poses: dict, color, size, alpha=1.0, zorder=Z_IMPACT):
        """Hitch pins of a vehicle at the given body poses (pin position from the front body)."""
        for i, h in enumerate(vehicle.hitches):
            front = vehicle.bodies[i].name
            if front not in poses:
                continue
            p = self.d(to_world(h.front_point, *poses[front]))
            self.ax.plot(*p, "o", ms=size, mfc="white", mec=color, mew=1.0, alpha=alpha, zorder=zorder + 0.5)

    def skeleton(self, body, position, heading, color):
        """A body without outline data: CG symbol, heading tick, links to its pins and the contact."""
        vehicle = self.vehicle_of[body.name]
        self.no_outline.add(body.name)
        pts = []
        for i, h in enumerate(vehicle.hitches):
            if vehicle.bodies[i].name == body.name:
                pts.append(h.front_point)
            if vehicle.bodies[i + 1].name == body.name:
                pts.append(h.rear_point)
        if body.name in (self.scene.impact.body1, self.scene.impact.body2):
            pts.append(to_body(self.scene.impact.point, position, heading))
        c = self.d(position)
        for p in pts:
            w = self.d(to_world(p, position, heading))
            self.ax.plot([c[0], w[0]], [c[1], w[1]], "-", color=color, lw=2.0, zorder=Z_IMPACT,
                         solid_capstyle="round")
            self.add(w)
        tick = c + self.d(rotate(np.array([1.5, 0.0]), heading))
        self.ax.plot([c[0], tick[0]], [c[1], tick[1]], "-", color=color, lw=1.0, zorder=Z_IMPACT)
        self.ax.plot(*c, "o", ms=7, mfc="white", mec=color, mew=1.5, zorder=Z_IMPACT + 0.5)
        self.ax.plot(*c, "+", ms=7, color=color, mew=1.0, zorder=Z_IMPACT + 0.6)
        self.add(np.vstack([c, tick]))
        from matplotlib.lines import Line2D

        self.legend_entry("no outline data: CG, heading tick, links to pins and contact",
                          Line2D([], [], color="0.3", lw=2.0, marker="o", mfc="white", mec="0.3"))

    def text(self, xy, text, *, kind: str, **kw):
        """A label of ``kind`` (one of :data:`LABEL_KINDS`) anchored at a data point, kept inside
        the axes limits by :func:`fit_texts` and clear of the other labels by :func:`place_labels`;
        None (nothing drawn) when that kind is hidden."""
        if kind in self.hide or "labels" in self.hide:
            return None
        kw.setdefault("zorder", Z_TEXT)
        kw.setdefault("gid", f"label:{kind}")
        t = self.ax.annotate(text, xy=tuple(xy), **kw)
        self.texts.append(t)
        return t

    def label_hits(self, anchor, direction, n_chars: int, n_lines: int, fontsize: float = 7.0) -> int:
        """How many placed labels a text anchored at ``anchor`` and extending along the signs of
        ``direction`` would roughly cover (scale estimated from the extent drawn so far)."""
        pts = np.vstack(self.points)
        per_inch = float(max(np.ptp(pts[:, 0]), np.ptp(pts[:, 1]), 5.0 * self.k)) / 9.0
        w = n_chars * 0.55 * fontsize / 72.0 * per_inch
        h = n_lines * 1.2 * fontsize / 72.0 * per_inch
        x0, x1 = sorted((anchor[0], anchor[0] + np.copysign(w, direction[0])))
        y0, y1 = sorted((anchor[1], anchor[1] + np.copysign(h, direction[1])))
        pad = 0.3 * h
        return sum(1 for q in self.labels if x0 - pad <= q[0] <= x1 + pad and y0 - pad <= q[1] <= y1 + pad)

    def body_label(self, name, position, *, suffix="", offset=0.0):
        p = self.d(position)
        self.labels.append(p)
        if offset:  # above (offset > 0) or below the point, leaving a CG or evidence marker visible
            self.text(p, name + suffix, kind="names", xytext=(0, offset), textcoords="offset points", fontsize=7,
                      ha="center",
                      va="bottom" if offset > 0 else "top", color="0.1", path_effects=halo(2.0))
        else:
            self.text(p, name + suffix, kind="names", fontsize=7, ha="center", va="center", color="0.1",
                      path_effects=halo(2.0))

"""Figures. The only module of crashsim that imports matplotlib (lazily, on first use).

Every function draws on a given Axes (``ax=None``: a new figure) and returns what it drew
on; nothing here calls ``plt.show()``, so the module works under any backend, including
Agg on a machine without a screen. Inputs are the SI dicts and arrays of the numeric core;
degrees and percent appear only on the axes.
"""

from __future__ import annotations

import logging
import math
import re
import textwrap
import weakref
from pathlib import Path
from typing import NamedTuple

import numpy as np

from .errors import ScenarioError
from .evidence.crush import profile_outline
from .figure_options import (LABEL_KINDS, LEGEND_MODES, NARROW_FIGURE, PAPER_SIZES, check_hide, check_view,
                             parse_scale, title_chars)
from .geometry import rotate, to_body, to_world
from .motion.approach import path_length
from .motion.road import points_in_polygon, signed_distance
from .plot_events import mark_impacts
from .plot_loads import draw_roll_panel, has_roll_panel
from .plot_timeline import plot_wheel_timeline
from .plot_detail import INSET_MARGIN, add_impact_inset, impact_window, needs_inset
from .report import fmt
from .survey.underlay import draw_underlay, scene_underlay
from .units import Kind, convert, resolve_system, to_unit

_log = logging.getLogger("crashsim")

__all__ = ["is_color", "LABEL_KINDS", "LINE_SHY", "line_ink", "LEGEND_MODES", "PAPER_SIZES", "PrintSheet", "place_labels", "check_hide",
           "legend_mode", "parse_scale", "replace_scale_bar", "north_direction", "print_sheet", "scene_drawing", "text_box", "BarrierAxes",
           "plot_barrier_sweep", "plot_barrier_figures", "plot_scene", "plot_histories",
           "history_panels", "save_scene_figures", "SCENE_FIGURE_SUFFIXES", "check_sheet", "zone_colors",
           "map_line_legend_texts", "engineer_scale_text", "ENGINEER_SCALES_FT"]


def _plt():
    """matplotlib.pyplot, imported on first use (keeps ``import crashsim`` matplotlib-free)."""
    import matplotlib.pyplot as plt

    return plt


def _new_axes(ax):
    if ax is not None:
        return ax
    _, ax = _plt().subplots(figsize=(7.0, 5.6), layout="constrained")
    return ax


# --------------------------------------------------------------------------------------------
# Barrier sweeps: paper Figures 4 and 5
# --------------------------------------------------------------------------------------------

#: Captions of the paper's figures, by Table 2 truck.
_BARRIER_TITLES = {
    "loaded": "Fig. 4. 48 km/hr inelastic (e = {e:g}) barrier impact, fully loaded trailer",
    "empty": "Fig. 5. 48 km/hr inelastic (e = {e:g}) barrier impact, empty trailer",
}

_CONTACT_LABELS = {
    "fixed": "contact fixed at the Table 3 point (3.924, 0.240) m",
    "corner": "contact at the front corner (3.884, 1.205) m (Table 4)",
    "interpolate": "contact moving from the Table 3 point (15\N{DEGREE SIGN}) to the corner (75\N{DEGREE SIGN})",
}


class BarrierAxes(NamedTuple):
    """The two y axes of a barrier-sweep plot (they share the x axis)."""

    energy: object  # matplotlib Axes: energy loss [%]
    mu: object      # matplotlib Axes (twin): impulse ratio


def _runs(mask: np.ndarray):
    """(start, stop) index pairs of the runs of True in ``mask``."""
    m = np.concatenate([[False], np.asarray(mask, dtype=bool), [False]])
    d = np.diff(m.astype(int))
    return list(zip(np.nonzero(d == 1)[0], np.nonzero(d == -1)[0]))


def plot_barrier_sweep(sweep: dict, ax=None, *, title: str | None = None, mu_limit: float = 2.0,
                       colors=None) -> BarrierAxes:
    """Energy loss and impulse ratio against barrier angle, as in the paper's Figs. 4 and 5.

    Parameters
    ----------
    sweep : dict
        Output of :func:`crashsim.impact.sweeps.barrier_angle_sweep` (keys ``"angle"`` [rad],
        ``"friction"`` (F,), ``"energy_loss"``, ``"mu_max"``, ``"mu"``, ``"sliding"``,
        ``"approaching"`` (F, N), ``"truck"``, ``"contact_rule"``, ``"restitution"``).
    ax : matplotlib Axes, optional
        Axes for the energy loss; the impulse ratio goes on a twin y axis. New figure if None.
    title : str, optional
        Default: the paper's caption for a ``"loaded"`` (Fig. 4) or ``"empty"`` (Fig. 5) truck.
    mu_limit : float
        Upper limit of the impulse-ratio axis (|mu_max| grows without bound towards 90 deg).
    colors : sequence of colours, optional
        One per friction coefficient.

    Returns
    -------
    BarrierAxes
        ``(energy, mu)`` axes.

    Notes
    -----
    For each f the energy loss is solid while the no-sliding solution stands (|mu_max| <= f,
    Eq. 8) and dashed where the surfaces slide throughout. On the right axis the solid rising
    black curve is |mu_max| (the paper's "solid rising curve") and the coloured horizontal
    segments are |mu| = f where sliding (its "solid horizontal curve").
    """
    ax = _new_axes(ax)
    g = np.degrees(np.asarray(sweep["angle"], dtype=float))
    fr = np.atleast_1d(sweep["friction"])
    el = 100.0 * np.asarray(sweep["energy_loss"], dtype=float)
    sliding = np.asarray(sweep["sliding"], dtype=bool)
    approaching = np.asarray(sweep["approaching"], dtype=bool)
    mu = np.abs(np.asarray(sweep["mu"], dtype=float))
    mu_max = np.abs(np.asarray(sweep["mu_max"], dtype=float))
    if colors is None:
        colors = [f"C{k}" for k in range(len(fr))]

    axm = ax.twinx()
    for k, f in enumerate(fr):
        c = colors[k % len(colors)]
        y = np.where(approaching[k], el[k], np.nan)
        stick = ~sliding[k]
        first = True
        for style, mask in (("-", stick), ("--", sliding[k])):
            for a, b in _runs(mask):
                # a dashed run starts at the last sticking sample so the two pieces join
                a0 = max(a - 1, 0) if style == "--" else a
                ax.plot(g[a0:b], y[a0:b], style, color=c, lw=2.0,
                        label=f"energy loss, f = {f:g}" if first else None)
                first = False
        slide = np.where(sliding[k] & approaching[k], mu[k], np.nan)
        axm.plot(g, slide, "-", color=c, lw=1.2, alpha=0.8, label=f"|\N{GREEK SMALL LETTER MU}| = f = {f:g} (sliding)")
    axm.plot(g, mu_max[0], "-", color="k", lw=1.5,
             label="|\N{GREEK SMALL LETTER MU}$_{max}$| (sliding ends before separation)")

    ax.plot([], [], "--", color="0.4", lw=2.0, label="dashed: sliding throughout")
    ax.set_xlabel("barrier angle \N{GREEK CAPITAL LETTER GAMMA} [deg]")
    ax.set_ylabel("kinetic energy loss, system [%]")
    axm.set_ylabel("impulse ratio |\N{GREEK SMALL LETTER MU}| = |P$_t$/P$_n$| [-]")
    ax.set_xlim(g.min(), g.max())
    ax.set_ylim(0.0, 105.0)
    axm.set_ylim(0.0, mu_limit)
    ax.grid(True, alpha=0.4)
    e = sweep.get("restitution", float("nan"))
    if title is None:
        title = _BARRIER_TITLES.get(sweep.get("truck"), "Barrier impact (e = {e:g})").format(e=e)
    ax.set_title(title, fontsize=10)
    h1, l1 = ax.get_legend_handles_labels()
    h2, l2 = axm.get_legend_handles_labels()
    rule = sweep.get("contact_rule")
    ax.legend(h1 + h2, l1 + l2, loc="upper center", bbox_to_anchor=(0.5, -0.13), ncol=2, fontsize=8,
              title=_CONTACT_LABELS.get(rule, f"contact: {rule}"), title_fontsize=8, frameon=False)
    return BarrierAxes(ax, axm)


def plot_barrier_figures(loaded: dict, empty: dict, axes=None, **kwargs):
    """Figures 4 (fully loaded trailer) and 5 (empty trailer) side by side.

    Parameters
    ----------
    loaded, empty : dict
        Outputs of :func:`crashsim.impact.sweeps.barrier_angle_sweep`.
    axes : pair of matplotlib Axes, optional
        New 1 x 2 figure if None.
    **kwargs
        Passed to :func:`plot_barrier_sweep`.

    Returns
    -------
    matplotlib Figure
    """
    if axes is None:
        _, axes = _plt().subplots(1, 2, figsize=(14.0, 6.0), layout="constrained")
    for ax, sw in zip(axes, (loaded, empty)):
        plot_barrier_sweep(sw, ax, **kwargs)
    return axes[0].figure


# --------------------------------------------------------------------------------------------
# Scene diagram, run-out histories
# --------------------------------------------------------------------------------------------

#: File suffixes :func:`save_scene_figures` writes (matplotlib picks the format from them).
SCENE_FIGURE_SUFFIXES = (".png", ".svg", ".pdf")

#: Colour family of each vehicle, in scenario order: (fill at impact, line, dark).
#: Red and green are kept free for the evidence and its verdicts.
_FAMILIES = (
    ("#c6dbef", "#2171b5", "#08306b"),  # blue
    ("#dadaeb", "#6a51a3", "#3f007d"),  # purple
    ("#f6e8c3", "#8c510a", "#543005"),  # brown
    ("#d9d9d9", "#525252", "#000000"),  # grey
    ("#c7eae5", "#01665e", "#003c30"),  # teal
)
_EVIDENCE = "#d62728"   # measured items
_PASS = "#1a7f37"
_FAIL = "#c62828"
_NICE = (1.0, 2.0, 2.5, 5.0)

# z-order of the layers, bottom to top (friction zones under the grid, which sits at 0.5)
_Z_ZONE, _Z_MAP = 0.3, 1.0
_Z_BARRIER, _Z_TRACK, _Z_GHOST, _Z_IMPACT, Z_REST, _Z_EVIDENCE, _Z_ARROW, Z_TEXT = 2, 3, 4, 5, 6, 7, 8, 9

#: Friction zones, in scenario order: (pale fill, hatch and edge). Green, tan, grey-blue, sand.
_ZONE_COLORS = (("#e2efcf", "#7da453"), ("#f0e2c4", "#a27c3f"), ("#dde5ee", "#637a92"), ("#f3efc9", "#a39a3c"))

#: Drawing of each map-line style (crashsim.scenario.MAP_LINE_STYLES): legend text, colour, width,
#: dashes (None: solid) and whether it is a double line (two strokes with a white gap).
_MAP_STYLES = {
    "edge": ("road edge", "0.25", 1.6, None, False),
    "lane": ("lane line", "0.35", 1.1, (6.0, 5.0), False),
    "centre": ("centre line", "0.2", 1.0, None, True),
    "kerb": ("kerb / verge edge", "0.35", 4.5, None, False),
    "stop": ("stop line", "0.1", 5.0, None, False),
    "other": ("other line", "0.6", 0.8, None, False),
}


def is_color(value) -> bool:
    """Whether ``value`` is a colour matplotlib understands (a name such as ``"white"`` or
    ``"tab:orange"``, a hex code, a grey level string ``"0.5"``); used to check scenario files."""
    from matplotlib.colors import is_color_like

    return bool(is_color_like(value))


def figure_system(scene, system):
    """The figure's unit system: ``system`` (SI or US, any case) or the scenario's units."""
    return resolve_system(system, scene.scenario.units, field="system")


def _nice_steps(lo: float, hi: float):
    """The 1-2-2.5-5 numbers between lo and hi, ascending."""
    out = []
    for e in range(int(np.floor(np.log10(lo))) - 1, int(np.ceil(np.log10(hi))) + 1):
        out += [m * 10.0 ** e for m in _NICE if lo <= m * 10.0 ** e <= hi]
    return out


def _nice_at_most(x: float) -> float:
    """Largest 1-2-2.5-5 number <= x (x > 0)."""
    steps = _nice_steps(x / 20.0, x)
    return steps[-1] if steps else x


def _halo(width: float = 2.5):
    from matplotlib import patheffects

    return [patheffects.withStroke(linewidth=width, foreground="white")]


def _wrap(text: str, width: int) -> str:
    return "\n".join(textwrap.wrap(text, width, break_on_hyphens=False)) if text else text


def _ghost_times(t_end: float, interval: float) -> np.ndarray:
    """Multiples of ``interval`` inside the run, not closer than interval/4 to its end."""
    n = int(np.floor((t_end - 0.25 * interval) / interval + 1e-9))
    return interval * np.arange(1, max(n, 0) + 1)


def _default_intervals(ends: dict) -> dict:
    """Ghost interval per vehicle: one 1-2-2.5-5 step that gives every vehicle 4-6 ghosts if
    there is one (ghosts of all vehicles then show the same instants), else one per vehicle."""
    ends = {k: v for k, v in ends.items() if v > 0}
    if not ends:
        return {}
    steps = _nice_steps(min(ends.values()) / 50.0, max(ends.values()))
    for s in reversed(steps):
        if all(4 <= len(_ghost_times(t, s)) <= 6 for t in ends.values()):
            return dict.fromkeys(ends, s)
    out = {}
    for k, t in ends.items():
        cand = [s for s in _nice_steps(t / 50.0, t) if 4 <= len(_ghost_times(t, s)) <= 6]
        out[k] = cand[-1] if cand else _nice_at_most(t / 5.0)
    return out


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
        self.width = _FIGURE_WIDTH  # width of a new figure [in] (plot_scene's width)
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
        self.family = {v.name: _FAMILIES[i % len(_FAMILIES)] for i, v in enumerate(movable)}

    # -- helpers ---------------------------------------------------------------------------
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
        return self.family.get(self.vehicle_of[body_name].name, _FAMILIES[-1])

    # -- vehicles --------------------------------------------------------------------------
    def outline(self, body, position, heading, *, gid: str, fill, edge, lw: float, ls="-", alpha=1.0,
                zorder=_Z_IMPACT):
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

    def axle_lines(self, body, position, heading, color, lw, alpha=1.0, zorder=_Z_IMPACT):
        for a in body.axles:
            xy = self.d(to_world(np.array([[a.x, -a.track / 2], [a.x, a.track / 2]]), position, heading))
            self.ax.plot(xy[:, 0], xy[:, 1], "-", color=color, lw=lw, alpha=alpha, zorder=zorder,
                         solid_capstyle="butt")

    def pins(self, vehicle, poses: dict, color, size, alpha=1.0, zorder=_Z_IMPACT):
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
            self.ax.plot([c[0], w[0]], [c[1], w[1]], "-", color=color, lw=2.0, zorder=_Z_IMPACT,
                         solid_capstyle="round")
            self.add(w)
        tick = c + self.d(rotate(np.array([1.5, 0.0]), heading))
        self.ax.plot([c[0], tick[0]], [c[1], tick[1]], "-", color=color, lw=1.0, zorder=_Z_IMPACT)
        self.ax.plot(*c, "o", ms=7, mfc="white", mec=color, mew=1.5, zorder=_Z_IMPACT + 0.5)
        self.ax.plot(*c, "+", ms=7, color=color, mew=1.0, zorder=_Z_IMPACT + 0.6)
        self.add(np.vstack([c, tick]))
        from matplotlib.lines import Line2D

        self.legend_entry("no outline data: CG, heading tick, links to pins and contact",
                          Line2D([], [], color="0.3", lw=2.0, marker="o", mfc="white", mec="0.3"))

    def text(self, xy, text, *, kind: str, **kw):
        """A label of ``kind`` (one of :data:`LABEL_KINDS`) anchored at a data point, kept inside
        the axes limits by :func:`_fit_texts` and clear of the other labels by :func:`place_labels`;
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
                      va="bottom" if offset > 0 else "top", color="0.1", path_effects=_halo(2.0))
        else:
            self.text(p, name + suffix, kind="names", fontsize=7, ha="center", va="center", color="0.1",
                      path_effects=_halo(2.0))


def _check_map(scene) -> dict:
    """Evidence checks keyed by (kind, index of the evidence item), walking the report in the
    order :func:`crashsim.evidence.checks.evaluate_evidence` writes it; each key is
    confirmed by the check's kind and its (default) name."""
    ev = scene.scenario.evidence
    rep = scene.evidence
    if rep is None:
        return {}
    out = {}
    checks = list(rep.checks)
    by_name = {(c.kind, c.name): c for c in checks}

    def take(kind, index, name):
        c = by_name.get((kind, name))
        if c is not None:
            out[(kind, index)] = c

    if ev.impact_point is not None:
        take("point of impact", 0, ev.impact_point.name)
    for i, r in enumerate(ev.rest):
        name = r.name or f"rest of {r.body}"
        take("rest", i, name)
        take("rest heading", i, f"{name} (heading)")
    for i, m in enumerate(ev.marks):
        take("mark", i, m.name or f"mark {i + 1}")
    for i, x in enumerate(ev.delta_v):
        take("delta-v", i, x.name or f"delta-v of {x.body} ({x.component})")
    for i, x in enumerate(getattr(ev, "recorder", ())):
        take("recorder", i, x.name or f"recorder in {x.body}")
    return out


def _verdict(checks) -> tuple[str, str]:
    """('PASS'/'FAIL', colour) of one or more checks (all must pass)."""
    checks = [c for c in checks if c is not None]
    if not checks:
        return "not checked", "0.3"
    ok = all(c.passed for c in checks)
    return ("PASS", _PASS) if ok else ("FAIL", _FAIL)


def _residual_text(c, system) -> str:
    if c is None:
        return ""
    if np.isinf(c.residual):
        return "nothing computed"
    if c.quantity == "angle":
        return (f"{convert(c.residual, 'rad', 'deg', Kind.ANGLE):+.1f}\N{DEGREE SIGN} "
                f"(tol. {convert(c.tolerance, 'rad', 'deg', Kind.ANGLE):.0f}\N{DEGREE SIGN})")
    return f"{fmt(abs(c.residual), c.quantity, system, 2)} (tol. {fmt(c.tolerance, c.quantity, system, 2)})"


_CRUSH_KEY = "measured crush (to scale)"


def _draw_crush(S, sc) -> None:
    """Each measured crush profile (``[[evidence.crush]]``) on the damaged face of its body's outline at
    impact, to scale (gid ``"crush:<body>:<face>"``)."""
    from matplotlib.patches import Patch, Polygon

    drawn = False
    for it in sc.evidence.crush:
        body = S.body_of.get(it.body)
        poly = None if body is None else profile_outline(body, it)
        if poly is None:
            continue
        st = sc.states[it.body]
        xy = S.d(to_world(poly, st.position, st.heading))
        _, _, dark = S.colors(it.body)
        S.ax.add_patch(Polygon(xy, closed=True, facecolor="none", edgecolor=dark, hatch="xxxx", lw=1.0,
                               zorder=_Z_IMPACT + 0.5, gid=f"crush:{it.body}:{it.face}"))
        S.add(xy)
        drawn = True
    if drawn:
        S.legend_entry(_CRUSH_KEY, Patch(facecolor="none", edgecolor="0.2", hatch="xxxx", lw=1.0))


#: Legend modes that put the legend outside the axes (the figure sized to hold it).
_OUTSIDE = ("compact", "outside")

#: Scales a print sheet picks from when none is given (1:N), the largest drawing that fits.
_SCALES = (10, 20, 25, 50, 100, 200, 250, 500, 1000, 2000, 2500, 5000, 10000)

#: Engineer's scales of US drawings, as feet per inch (1" = 10', 20', 30', 40', 50', 60', 100', ...):
#: the divisions of an engineer's scale rule (10 to 60 parts to the inch) times a power of ten.
ENGINEER_SCALES_FT = tuple(float(d * 10 ** k) for k in range(0, 4) for d in (1, 2, 3, 4, 5, 6))

#: Margins of a print sheet [in]: paper edge, and room for the tick labels and axis labels.
_SHEET_EDGE, _SHEET_LEFT, _SHEET_BOTTOM = 12.0 / 25.4, 0.55, 0.45


def legend_mode(legend) -> str:
    """``"compact"``, ``"outside"``, ``"inside"``, ``"none"`` or a matplotlib location (inside,
    there) from :func:`plot_scene`'s ``legend`` (True: outside; False or None: none)."""
    if legend is True:
        return "outside"
    if legend is False or legend is None:
        return "none"
    return str(legend)


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
    box_w = size[0] - 2 * _SHEET_EDGE - _SHEET_LEFT
    box_h = size[1] - 2 * _SHEET_EDGE - _SHEET_BOTTOM - title - legend_height
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
    box = (_SHEET_EDGE + _SHEET_LEFT, _SHEET_EDGE + _SHEET_BOTTOM + legend_height, box_w, box_h)
    return PrintSheet(key, "landscape" if landscape else "portrait", (float(size[0]), float(size[1])), float(scale),
                      box, centre - half, centre + half)


def check_sheet(scenario, paper: str, scale: float | None, *, approach: bool = True, field: str = "scale") -> None:
    """Refuse a paper and scale before the run when what is known before it already does not fit.

    The extent of the scene figure is known only after the run-out (rest positions, tracks); the
    vehicles at impact, the evidence (rest positions, marks, the point of impact) and the
    approaches' paths are known at load, and a figure always holds them. Their extent, padded as
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


def plot_scene(scene, ax=None, *, interval: float | None = None, times=None, evidence: bool = True,
               arrows: bool = True, system: str | None = None, legend="compact", axles: bool = True,
               approach: bool = True, hide=(), paper: str | None = None, scale: float | None = None,
               view=None, zoom: str | None = None, inset: bool | None = None, width: float | None = None):
    """Scale diagram of a reconstructed scene in the ground frame: impact, run-out, evidence.

    Parameters
    ----------
    scene : SceneResult
        From :func:`crashsim.reconstruct.run_scene` (with or without a run-out).
    ax : matplotlib Axes, optional
        New figure, sized to the scene, if None.
    interval : float, optional
        Time between intermediate ("ghost") outlines [s]. Default: a 1-2-2.5-5 step giving
        4 to 6 ghosts per vehicle (the same step for all vehicles when one fits them all).
    times : sequence of float, optional
        Explicit ghost times after separation [s] (overrides ``interval``); times past a
        vehicle's end of run are skipped for it. ``times=()`` draws no ghosts.
    evidence : bool
        Overlay the scene evidence and its verdicts (PASS green, FAIL red).
    arrows : bool
        Delta-v arrows at the CGs (one scale for all, stated in the legend) and principal
        direction of force arrows at the contact point.
    system : {"SI", "US"}, optional
        Display units: coordinates in m or ft, speeds in m/s or mph. Default: the scenario's.
    legend : bool or str
        ``"compact"`` (the default): one line per entry and the evidence as one entry (its title
        counts the verdicts; each residual is in the report), outside the axes in small type:
        under the diagram in as many columns as fit for a new figure of a wide scene, else at its
        right.
        ``"outside"`` or True: the full legend (each evidence item with its residual) outside the
        axes (at the right; under the diagram for a new figure of a wide scene or a print sheet,
        with the figure sized to hold it); ``"inside"``:
        small, in the corner that covers least; a matplotlib location string (``"upper left"``):
        inside, there; ``"none"`` or False: none.
    axles : bool
        Draw the axles (at impact and at rest) as thin cross lines.
    approach : bool
        Draw the vehicles' approaches (``[vehicles.<name>.approach]``): tyre tracks, CG paths, the
        outlines at the start of braking and the perception point. False leaves them out (a
        close view of the impact and run-out when the approach is long).
    hide : str or sequence of str
        Label kinds left out (:data:`LABEL_KINDS`, or ``"labels"`` for all): ``"names,pdof"``.
    paper : str, optional
        Print sheet (:data:`PAPER_SIZES`: ``"A4"``, ``"A3"``, ``"letter"``, ``"tabloid"``): the
        figure is the sheet (landscape for a wide scene) and the drawing is at scale 1:``scale``,
        stated beside the scale bar; vector output (.pdf, .svg) then prints to scale at 100 %.
        Needs ``ax=None``.
    scale : float, optional
        N of the scale 1:N (default: the largest of 1:10 ... 1:10000 at which the framed view fits
        the sheet; in US units the largest engineer's scale, 1" = 10', 20', ... 6000'); A4 if no
        ``paper`` is given. The scale bar states it: "1:200", on a US sheet ``1" = 40'``
        (:func:`engineer_scale_text`).
    width : float, optional
        Width of the new figure [in]: a wide scene's figure (legend under it) is this wide, a tall
        one's at most this (its axes lower than 7 in if need be), the title wrapped to fit. Default:
        10 in for a wide scene; a tall one as wide as its 7-in-high axes and the legend need. For
        a figure shown at a known size (the case report's column) so that its type keeps its size.
        Needs ``ax=None`` and no ``paper`` or ``scale``.

    Returns
    -------
    matplotlib Axes
        Equal aspect. Patches carry gids: ``"outline:impact:<body>"``, ``"outline:rest:<body>"``,
        ``"outline:ghost:<body>:<t>"``, ``"evidence:rest:<body>"``, ``"zone:<i>"`` (friction zone
        i of ``runout.road.zones``); lines ``"map:<i>"`` (``scenario.map_lines[i]``); texts
        ``"zone-label:<i>"`` and ``"map-label:<i>"``; the scale bar is the artist with gid
        ``"scalebar"``. Text labels carry gids ``"label:<kind>"`` (:data:`LABEL_KINDS`); no two
        labels' boxes overlap (:func:`place_labels`; leader lines have gid ``"leader:<kind>"``).

    Notes
    -----
    Outlines are ``Body.outline()`` placed by the body pose: the CG position and heading at
    impact (``scenario.states``), from the run-out's dense output at the ghost times, and
    ``rest_position``/``rest_heading`` at the end of the run. Wheel tracks come from
    ``RunoutResult.wheels``: sliding stretches bold and dark (tyre marks expected), rolling
    stretches thin and dashed. The PDOF arrow of each body in contact starts at the contact
    point and points along the crush impulse on that body (SAE J224: its tail lies on the
    side the force comes from). A barrier is drawn as a thick line through the contact point
    along the crush-surface tangent (over ``scenario.barrier_extent`` when given).

    The road layout lies under everything else: each friction zone as a pale hatched polygon
    labelled inside with its name and friction ("grass verge, f = 0.35"), and each line of
    ``[[map.lines]]`` in its style (solid edge, dashed lane line, double centre line, thick kerb
    and stop bar, thin grey other). They count toward the axis limits only inside the region of
    interest (everything else drawn, plus a margin of 3 m or 15 % of its span, whichever is
    larger): a zone or line reaching far away is cut by the axes instead of shrinking the scene.
    So are fixed obstacles; a barrier face is drawn over its extent cut to the view: the view is
    framed on the vehicles' paths, the evidence and the impacts, never stretched by a long
    barrier, guardrail or zone.

    With a scene placed on a survey (``[survey]`` with files, an underlay or a CRS) a north
    arrow shows grid north (the survey's +y); the orthophoto (``[survey.underlay]``) lies under
    everything. A scene not on a survey shows the north of ``[map] north`` (the bearing of its
    +Y axis), if the file gives it (:func:`north_direction`).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    system = figure_system(scene, system)
    window = _detail_window(scene, view, zoom)
    new = ax is None
    if width is not None:
        if not new or paper is not None or scale is not None:
            raise ScenarioError("width sizes a new figure: leave ax=None, and paper and scale unset", field="width")
        if not (isinstance(width, (int, float)) and MIN_WIDTH <= width <= MAX_WIDTH):
            raise ScenarioError(f"width = {width!r} in is outside the allowed {MIN_WIDTH:g} to {MAX_WIDTH:g} in",
                                field="width")
    if new:
        # laid out by layout_scene_figure (exact equal-aspect box plus legend), not by a layout engine
        ax = _plt().figure(figsize=(10.0, 6.0)).add_subplot()
    S = SceneDrawing(scene, ax, system)
    S.approach = approach
    S.width = _FIGURE_WIDTH if width is None else float(width)
    S.hide = check_hide(hide)
    sc = S.sc
    runout = scene.runout or {}

    # -- at impact ---------------------------------------------------------------------------
    for v in sc.vehicles:  # the colour key first in the legend
        if not v.is_barrier:
            fill, line, _ = S.family[v.name]
            desc = sc.descriptions.get(v.name, "")
            S.legend_entry(_wrap(f"vehicle {v.name}" + (f": {desc}" if desc else ""), 60),
                           Patch(facecolor=fill, edgecolor=line, lw=1.2))
    for v in sc.vehicles:
        if v.is_barrier:
            continue
        fill, line, dark = S.family[v.name]
        poses = {}
        for b in v.bodies:
            st = sc.states[b.name]
            poses[b.name] = (st.position, st.heading)
            p = S.outline(b, st.position, st.heading, gid=f"outline:impact:{b.name}", fill=fill, edge=line, lw=1.4,
                          alpha=0.9, zorder=_Z_IMPACT)
            if p is None:
                S.skeleton(b, st.position, st.heading, line)
            elif axles:
                S.axle_lines(b, st.position, st.heading, line, 1.0, zorder=_Z_IMPACT)
            S.add(S.d(st.position))
        S.pins(v, poses, line, 4.0, zorder=_Z_IMPACT)
    if any((p.get_gid() or "").startswith("outline:impact:") for p in ax.patches):
        S.legend_entry("at impact", Patch(facecolor="0.85", edgecolor="0.3", lw=1.4))
    if evidence and sc.evidence.crush:
        _draw_crush(S, sc)

    # -- approach: tracks, CG paths, the start of braking and the perception point -------------
    if approach and getattr(sc, "approaches", None):
        _draw_approaches(S)

    # -- run-out: tracks, CG paths, ghosts, rest -----------------------------------------------
    if runout:
        # body names go at the CGs at impact and at rest: keep the ghost time labels off them
        S.labels += [S.d(sc.states[n].position) for n in S.body_of if n in sc.states and not S.body_of[n].is_fixed]
        S.labels += [S.d(br.rest_position) for r in runout.values() for br in r.bodies.values()]
        if times is not None:
            tt = np.sort(np.asarray(times, dtype=float).ravel())
            ghost = {vn: tt[(tt > 0) & (tt < r.t_end)] for vn, r in runout.items()}
            # no legend entry for ghosts that are not drawn (times=(): the animation's static layer)
            ghost_note = "intermediate, at the given times" if any(len(g) for g in ghost.values()) else None
        else:
            if interval is not None:
                if not (np.isfinite(interval) and interval > 0):
                    raise ScenarioError(f"must be a positive time in s, got {interval!r}", field="interval")
                steps = dict.fromkeys(runout, float(interval))
            else:
                steps = _default_intervals({vn: r.t_end for vn, r in runout.items()})
            ghost = {vn: _ghost_times(r.t_end, steps[vn]) if vn in steps else np.array([])
                     for vn, r in runout.items()}
            uniq = sorted(set(steps.values()))
            if not uniq:
                ghost_note = "intermediate: none (no motion after separation)"
            elif len(uniq) == 1:
                ghost_note = f"intermediate, every {uniq[0]:g} s"
            else:
                ghost_note = "intermediate, every " + ", ".join(f"{steps[vn]:g} s ({vn})" for vn in runout)
        for vn, r in runout.items():
            v = next(x for x in sc.vehicles if x.name == vn)
            fill, line, dark = S.family[vn]
            for tr in r.wheels.values():
                _draw_track(S, tr, line, dark, gid=f"track:{tr.key}")
            for name, br in r.bodies.items():
                h = br.history
                xy = S.d(np.column_stack([h.x, h.y]))
                (ln,) = ax.plot(xy[:, 0], xy[:, 1], ":", color=dark, lw=1.0, zorder=_Z_TRACK, gid=f"path:{name}")
                S.timed.append((ln, np.asarray(h.t, dtype=float), xy))
                S.add(xy)
            # ghosts
            for j, t in enumerate(ghost.get(vn, ())):
                poses = {}
                for name, br in r.bodies.items():
                    st = np.asarray(br.sol(float(t)), dtype=float)
                    poses[name] = ((st[0], st[1]), st[2])
                    p = S.outline(S.body_of[name], poses[name][0], poses[name][1], gid=f"outline:ghost:{name}:{t:g}",
                                  fill=None, edge=line, lw=0.7, alpha=0.55, zorder=_Z_GHOST)
                    if p is None:
                        c = S.d(poses[name][0])
                        ax.plot(*c, "o", ms=3, color=line, alpha=0.6, zorder=_Z_GHOST)
                S.pins(v, poses, line, 2.5, alpha=0.6, zorder=_Z_GHOST)
                # time label at the lead body's CG, unless it would sit on another label
                lead = next(iter(r.bodies))
                c = S.d(poses[lead][0])
                if all(np.hypot(*(c - q)) > 1.6 * S.k for q in S.labels):
                    S.text(c, f"{t:g} s", kind="times", fontsize=6.5, color=dark, ha="center", va="center",
                           path_effects=_halo(1.8))
                    S.labels.append(c)
            # at rest (or at the end of a run that did not reach rest)
            before = (len(ax.patches), len(ax.lines), len(S.texts))
            poses = {}
            for name, br in r.bodies.items():
                poses[name] = (br.rest_position, br.rest_heading)
                p = S.outline(S.body_of[name], br.rest_position, br.rest_heading, gid=f"outline:rest:{name}",
                              fill=fill, edge=dark, lw=1.8, alpha=0.55 if r.success else 0.3, zorder=Z_REST)
                if p is None:
                    S.skeleton(S.body_of[name], br.rest_position, br.rest_heading, dark)
                elif axles:
                    S.axle_lines(S.body_of[name], br.rest_position, br.rest_heading, dark, 1.0, zorder=Z_REST)
                S.body_label(name, np.asarray(br.rest_position), suffix="" if r.success else " (run stopped)",
                             offset=6.0 if name in S.no_outline else -5.0)
            S.pins(v, poses, dark, 4.0, zorder=Z_REST)
            rest = [*ax.patches[before[0]:], *ax.lines[before[1]:], *S.texts[before[2]:]]
            S.appear += [(a, float(r.t_end)) for a in rest]
        if ghost_note:
            S.legend_entry(ghost_note, Patch(facecolor="none", edgecolor="0.4", lw=0.7, alpha=0.7))
        S.legend_entry("at rest (end of run)", Patch(facecolor="0.8", edgecolor="0.1", lw=1.8))
        S.legend_entry("tyre track, sliding (mark expected)", Line2D([], [], color="0.15", lw=2.2))
        S.legend_entry("tyre track, rolling", Line2D([], [], color="0.4", lw=0.7, ls="--", dashes=(4, 3)))
        S.legend_entry("CG path", Line2D([], [], color="0.2", lw=1.0, ls=":"))
    else:
        S.legend_entry("impact only: no run-out computed", Line2D([], [], ls="none"))
    for v in sc.vehicles:
        if not v.is_barrier:
            for b in v.bodies:
                pos = np.asarray(sc.states[b.name].position)
                if runout:
                    rest = np.asarray(scene.runout_body(b.name).rest_position)
                    if np.hypot(*(rest - pos)) < 1.5:  # named at rest already
                        continue
                S.body_label(b.name, pos, offset=6.0 if b.name in S.no_outline else 0.0)
    if any(v.hitches for v in sc.vehicles):
        S.legend_entry("hitch pin", Line2D([], [], ls="none", marker="o", ms=4, mfc="white", mec="0.2"))

    # -- evidence ---------------------------------------------------------------------------
    checks = _check_map(scene) if evidence else {}
    if evidence and not sc.evidence.empty:
        _draw_evidence(S, checks)

    # -- arrows -----------------------------------------------------------------------------
    if arrows:
        _draw_arrows(S)

    # -- obstacles and numbered impacts -------------------------------------------------------
    _draw_obstacles(S)
    _draw_impacts(S)

    # -- road layout and obstacles: counted in the extent only near the scene --------------------
    roi = _region_of_interest(S)
    for piece in S.far:  # obstacles: their part inside the region of interest
        inside = _clip_polygon(piece, roi.lo, roi.hi)
        if len(inside):
            S.add(inside)
    _draw_zones(S, roi)
    _draw_map_lines(S, roi)

    # -- frame, limits, decorations ---------------------------------------------------------
    pts = np.vstack(S.points)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = float(max((hi - lo).max(), 5.0 * S.k))
    pad = 0.03 * span + 0.6 * S.k
    lo, hi = lo - pad, hi + pad
    # room at the bottom for the scale bar and at the top for the axes indicator
    lo[1] -= 0.05 * span
    hi[1] += 0.05 * span
    if window is not None:  # a detail view: the window as given, what lies outside cut off
        lo, hi = S.d(window[0]), S.d(window[1])
        _drop_texts_outside(S, lo, hi)
    mode = legend_mode(legend)
    sheet = None
    for w in tuple(getattr(scene, "warnings", ()) or ()):
        S.legend_entry(_wrap("warning: " + w, 60), Line2D([], [], ls="none"), color="#b35900")
    if paper is not None or scale is not None:
        if not new:
            raise ScenarioError("a print sheet (paper, scale) needs a new figure: leave ax=None", field="ax")
        # the page first (its size from the paper alone), then the legend under the drawing, measured,
        # then the drawing box and the view at scale
        probe = print_sheet(paper or "A4", lo, hi, S.k, 1e9, system=S.system)
        ax.figure.set_size_inches(*probe.size)
        leg = _scene_legend(S, mode, True, compact=True) if mode != "none" else None
        room = 0.0
        if mode in _OUTSIDE:
            fig = ax.figure
            room = leg.get_window_extent(fig.canvas.get_renderer()).height / fig.dpi + 0.15
        sheet = print_sheet(paper or "A4", lo, hi, S.k, scale, legend_height=room, system=S.system)
        lo, hi = sheet.lo, sheet.hi
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    # -- barrier (a face along the crush tangent, cut to the frame: it never widens the view) ---
    _draw_barrier(S, lo, hi)
    _label_road_layout(S, roi, lo, hi)
    ax.set_xlabel(f"X [{S.lunit}]")
    ax.set_ylabel(f"Y [{S.lunit}]")
    ax.grid(True, color="0.9", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    # a figure of a given width: the title wrapped within it (title_chars)
    ax.set_title(_wrap(sc.title, 100 if width is None else title_chars(width, 100)), fontsize=10)
    north = _north_arrow(S)
    fixed = _axes_indicator(ax) + north + _downhill_arrow(S, 130 if north else 80)
    # a new figure of a wide scene: legend under the diagram; else at the right
    below = new and (hi[1] - lo[1]) / (hi[0] - lo[0]) < 0.75
    if sheet is None:
        leg = _scene_legend(S, mode, below) if mode != "none" else None
    outside = leg if mode in _OUTSIDE else None
    if sheet is not None:
        layout_print(ax, sheet)
    else:
        size = {} if width is None else {"width": S.width, "max_width": S.width}
        if new:
            layout_scene_figure(ax, outside, below, **size)
        if window is None:
            _fit_texts(S)
        if new:
            layout_scene_figure(ax, outside, below, **size)
        if new and mode == "inside":
            _legend_headroom(ax, leg, below, **size)
    _draw_scene_underlay(S)
    xl = ax.get_xlim()
    fixed.append(_scale_bar(S, xl[1] - xl[0], sheet))
    if leg is not None and mode not in _OUTSIDE:
        fixed.append(leg)
    ax.figure.draw_without_rendering()
    if (new if inset is None else inset) and window is None:
        w_lo, w_hi = (S.d(c) for c in impact_window(scene, INSET_MARGIN))
        if needs_inset(w_lo, w_hi, ax.get_xlim()):
            inset_ax = add_impact_inset(ax, w_lo, w_hi, avoid=np.vstack(S.points), fixed=fixed, unit=S.lunit)
            if inset_ax is not None:
                fixed.append(inset_ax)
    S.fixed = fixed
    S.unplaced = place_labels(ax, S.texts, fixed, np.vstack(S.points))
    _DRAWINGS[ax] = S
    if S.unplaced:
        _log.info("scene figure: %d label(s) found no free place and may overlap others", S.unplaced)
    return ax


def _detail_window(scene, view, zoom):
    """The window of a detail view [m] as (lower-left, upper-right), or None for the framed scene."""
    if view is not None and zoom is not None:
        raise ScenarioError("give a view or a zoom, not both", field="zoom")
    if zoom is not None:
        if zoom != "impact":
            raise ScenarioError(f"unknown zoom {zoom!r}; allowed: impact", field="zoom")
        return impact_window(scene)
    if view is None:
        return None
    x0, y0, x1, y1 = check_view(view, field="view")
    return np.array([x0, y0]), np.array([x1, y1])


def _drop_texts_outside(S: SceneDrawing, lo, hi) -> None:
    """Leave out the labels anchored outside the box [lo, hi] (display units) of a detail view."""
    keep = []
    for t in S.texts:
        x, y = t.xy
        if lo[0] <= x <= hi[0] and lo[1] <= y <= hi[1]:
            keep.append(t)
        else:
            t.remove()
    S.texts[:] = keep


def _legend_headroom(ax, leg, below: bool, **size) -> None:
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


def _draw_scene_underlay(S: SceneDrawing) -> None:
    """The survey's orthophoto ([survey.underlay]) under everything, in the figure's units."""
    got = scene_underlay(S.sc)
    if got is not None:
        image, georef, opacity, clip = got
        draw_underlay(S.ax, image, georef, scale=S.k, opacity=opacity, clip=clip)


def _draw_track(S: SceneDrawing, track, line, dark, gid: str | None = None) -> None:
    """A wheel's track: sliding stretches bold and dark (a tyre mark expected), rolling ones thin and dashed."""
    for seg in track.segments:
        if len(seg.points) < 2:
            continue
        xy = S.d(seg.points)
        if seg.kind == "sliding":
            (ln,) = S.ax.plot(xy[:, 0], xy[:, 1], "-", color=dark, lw=2.2, alpha=0.85, zorder=_Z_TRACK,
                              solid_capstyle="butt", gid=gid)
        else:
            (ln,) = S.ax.plot(xy[:, 0], xy[:, 1], "--", color=line, lw=0.7, alpha=0.8, zorder=_Z_TRACK, dashes=(4, 3),
                              gid=gid)
        S.timed.append((ln, np.asarray(seg.t, dtype=float), xy))
        S.add(xy)


def _draw_approaches(S: SceneDrawing) -> None:
    """The approach of each vehicle before the impact: its tyre tracks (sliding bold: pre-impact
    marks expected), the CG paths (dash-dot), the outlines at the start of braking (thin,
    dashed) and the first body's CG at perception (open diamond, joined by a dotted line)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    ax = S.ax
    for vn, a in S.sc.approaches.items():
        v = next(x for x in S.sc.vehicles if x.name == vn)
        fill, line, dark = S.family[vn]
        for tr in a.tracks.values():
            _draw_track(S, tr, line, dark, gid=f"approach:track:{tr.key}")
        poses = {}
        for name, rows in a.bodies.items():
            xy = S.d(rows[:, 1:3])
            (ln,) = ax.plot(xy[:, 0], xy[:, 1], "-.", color=dark, lw=0.9, zorder=_Z_TRACK, gid=f"approach:path:{name}")
            S.timed.append((ln, np.asarray(rows[:, 0], dtype=float), xy))
            S.add(xy)
            poses[name] = ((rows[0, 1], rows[0, 2]), rows[0, 3])
            S.outline(S.body_of[name], poses[name][0], poses[name][1], gid=f"outline:braking:{name}", fill=None,
                      edge=line, lw=0.8, ls="--", alpha=0.8, zorder=_Z_GHOST)
        S.pins(v, poses, line, 2.5, alpha=0.7, zorder=_Z_GHOST)
        first = next(iter(a.bodies))
        start = S.d(a.bodies[first][0, 1:3])
        S.text(start, f"braking starts, {fmt(a.speed_at_braking, 'speed', S.system)}", kind="approach", fontsize=6.5,
               color=dark,
               ha="center", va="bottom", path_effects=_halo(1.8))
        S.labels.append(start)
        if a.reaction_time > 0:
            pp = S.d(a.perception_point)
            ax.plot([pp[0], start[0]], [pp[1], start[1]], ":", color=dark, lw=1.0, zorder=_Z_TRACK)
            ax.plot(*pp, "D", ms=5, mfc="white", mec=dark, zorder=_Z_IMPACT, gid=f"approach:perception:{vn}")
            S.text(pp, f"perception ({a.reaction_time:g} s before braking)", kind="approach", fontsize=6.5, color=dark,
                   ha="center",
                   va="bottom", path_effects=_halo(1.8))
            S.labels.append(pp)
            S.add(pp)
    S.legend_entry("approach: CG path from the start of braking", Line2D([], [], color="0.2", lw=0.9, ls="-."))
    S.legend_entry("at the start of braking", Patch(facecolor="none", edgecolor="0.3", lw=0.8, ls="--"))
    if any(a.reaction_time > 0 for a in S.sc.approaches.values()):
        S.legend_entry("perception point (reaction at constant speed)",
                       Line2D([], [], ls=":", color="0.2", marker="D", ms=5, mfc="white", mec="0.2"))


def plot_time_distance(scene, axes=None, *, system: str | None = None):
    """Time-distance and speed-time chart of every vehicle, from the start of its approach to rest.

    The time axis has the first impact at 0 (negative before it); the distance axis is the path
    length of each vehicle's first body's CG, 0 at the first impact (negative before it), as
    reconstruction reports draw it.  The approach (if the vehicle has one) shows the
    perception-reaction interval at constant speed and the braking phase; the run-out follows
    to rest.  Vertical lines mark the impacts (the first at 0, later ones of the run-out at
    their times, labels stacked when close); markers show perception (open diamond) and the
    start of braking (filled). The recorder samples (``[[evidence.recorder]]``) are drawn on the
    speed panel with their tolerance (open circles; open triangles for samples taken while
    braking, which only bound the speed from below). The legend lists only what is drawn.

    Parameters
    ----------
    scene : SceneResult
    axes : (Axes, Axes), optional
        Distance and speed panels; a new figure (shared time axis) if None.
    system : {"SI", "US"}, optional
        Display units (m or ft, km/h... as the units module shows speeds: m/s or mph).

    Returns
    -------
    matplotlib Figure
    """
    system = figure_system(scene, system)
    plt = _plt()
    if axes is None:
        fig, axes = plt.subplots(2, 1, figsize=(10.5, 6.5), sharex=True, layout="constrained")
    else:
        fig = axes[0].figure
    ax_s, ax_v = axes
    kl, lu = to_unit(1.0, Kind.LENGTH, system)
    kv, vu = to_unit(1.0, Kind.SPEED, system)
    sc = scene.scenario
    movable = [v for v in sc.vehicles if not v.is_barrier]
    drawn = {"perception": False, "braking": False, "rest": False, "recorded": False, "lower": False,
             "constant": False, "table": False}
    colors = {v.name: _FAMILIES[i % len(_FAMILIES)][2] for i, v in enumerate(movable)}
    for v in movable:
        c = colors[v.name]
        first = v.bodies[0].name
        a = sc.approaches.get(v.name)
        if a is not None:
            tab = a.table()
            ax_s.plot(tab["t"], kl * tab["s"], "-", color=c, lw=1.6, gid=f"td:approach:{v.name}")
            ax_v.plot(tab["t"], kv * tab["v"], "-", color=c, lw=1.6)
            tb, sb = -a.time_to_impact, -a.distance
            for axx, y in ((ax_s, kl * sb), (ax_v, kv * a.speed_at_braking)):
                axx.plot(tb, y, "o", color=c, ms=5, zorder=5)
            if a.reaction_time > 0:
                tp = tb - a.reaction_time
                for axx, y in ((ax_s, kl * (sb - a.reaction_distance)), (ax_v, kv * a.speed_at_braking)):
                    axx.plot(tp, y, "D", mfc="white", mec=c, ms=5, zorder=5)
            # recorder samples from before the modelled motion: the constant speed the recorder check
            # assumes there, dotted back to the earliest of them
            t0, s0 = tb - a.reaction_time, sb - a.reaction_distance
            early = [t + x.time_offset for x in getattr(sc.evidence, "recorder", ())
                     if any(b.name == x.body for b in v.bodies) for t in x.times]
            if early and min(early) < t0:
                te = min(early)
                ax_s.plot([te, t0], [kl * (s0 - a.speed_at_braking * (t0 - te)), kl * s0], ":", color=c, lw=1.3,
                          gid=f"td:constant:{v.name}")
                ax_v.plot([te, t0], [kv * a.speed_at_braking] * 2, ":", color=c, lw=1.3)
                drawn["constant"] = True
            inp = getattr(sc, "approach_inputs", {}).get(v.name)
            table = None if inp is None else inp.spec.recorded
            if table is not None and table.speed is not None:  # the recorder's table the approach was driven by
                ax_v.plot(table.t, kv * np.asarray(table.speed), "x", color="0.15", ms=5, mew=1.2, zorder=6,
                          gid=f"td:table:{v.name}")
                drawn["table"] = True
            ax_s.annotate(f"{v.name}: braking {fmt(a.speed_at_braking, 'speed', system)}", (tb, kl * sb),
                          xytext=(4, -10), textcoords="offset points", fontsize=7, color=c)
        if scene.runout and v.name in scene.runout:
            br = scene.runout[v.name].bodies[first]
            t_end = scene.runout[v.name].t_end
            t = np.linspace(0.0, t_end, 400)
            sv = np.asarray(br.sol(t))
            ax_s.plot(t, kl * path_length(br.sol, t), "-", color=c, lw=1.6, label=f"vehicle {v.name} ({first})",
                      gid=f"td:runout:{v.name}")
            ax_v.plot(t, kv * np.hypot(sv[3], sv[4]), "-", color=c, lw=1.6)
            if br.time_to_rest is not None:
                ax_s.plot(br.time_to_rest, kl * br.distance, "s", color=c, ms=5)
        else:
            ax_s.plot([], [], "-", color=c, label=f"vehicle {v.name} ({first})")
    # recorder samples on the speed panel, beside the computed speed they are checked against
    for i, x in enumerate(getattr(sc.evidence, "recorder", ())):
        vn = next((v.name for v in movable if any(b.name == x.body for b in v.bodies)), None)
        if vn is None:
            continue
        t = np.asarray(x.times, dtype=float) + x.time_offset
        keep = t <= 0.0  # the samples the check compares (pre-crash with the item's own offset)
        t = t[keep]
        v = kv * np.asarray(x.speeds, dtype=float)[keep]
        low = np.asarray(x.lower_bound, dtype=bool)[keep]
        ax_v.errorbar(t, v, yerr=kv * x.tolerance, fmt="none", ecolor=_EVIDENCE, elinewidth=0.8, capsize=2.5,
                      alpha=0.6, zorder=6)
        for mask, marker, key in ((~low, "o", "recorded"), (low, "^", "lower")):
            if mask.any():
                ax_v.plot(t[mask], v[mask], marker, ls="none", ms=5.5, mfc="white", mec=_EVIDENCE, mew=1.4, zorder=7,
                          gid=f"td:recorder:{i}:{key}")
                drawn[key] = True
    for v in movable:
        a = sc.approaches.get(v.name)
        if a is not None:
            drawn["braking"] = True
            drawn["perception"] |= a.reaction_time > 0
        if scene.runout and v.name in scene.runout:
            drawn["rest"] |= scene.runout[v.name].bodies[v.bodies[0].name].time_to_rest is not None
    impacts = [(1, 0.0)] + [(ev.number, ev.t) for ev in (scene.joint.impact_events() if scene.joint is not None else ())]
    ax_s.axhline(0.0, color="0.6", lw=0.6)
    ax_s.set_ylabel(f"distance from the impact [{lu}]")
    ax_v.set_ylabel(f"speed [{vu}]")
    ax_v.set_xlabel("time from the first impact [s]")
    for axx in (ax_s, ax_v):
        axx.grid(True, color="0.9", lw=0.6)
    ax_v.set_ylim(bottom=0.0)
    from matplotlib.lines import Line2D

    handles, labels = ax_s.get_legend_handles_labels()
    extra = [(Line2D([], [], ls="none", marker="D", mfc="white", mec="0.2"), "perception", "perception"),
             (Line2D([], [], ls="none", marker="o", color="0.2"), "start of braking", "braking"),
             (Line2D([], [], ls="none", marker="s", color="0.2"), "at rest", "rest"),
             (Line2D([], [], ls="none", marker="o", ms=5.5, mfc="white", mec=_EVIDENCE, mew=1.4),
              "recorded speed (bar: tolerance)", "recorded"),
             (Line2D([], [], ls="none", marker="^", ms=5.5, mfc="white", mec=_EVIDENCE, mew=1.4),
              "recorded, braking: a lower bound", "lower"),
             (Line2D([], [], ls=":", color="0.2", lw=1.3), "constant speed before the approach (assumed)", "constant"),
             (Line2D([], [], ls="none", marker="x", color="0.15", ms=5, mew=1.2),
              "recorder's table (drives the approach)", "table")]
    extra = [(h, t) for h, t, key in extra if drawn[key]]
    width = float(fig.get_size_inches()[0])
    if width >= NARROW_FIGURE:  # beside the panels: never over the impact labels or the curves
        ax_s.legend(handles + [h for h, _ in extra], labels + [t for _, t in extra], fontsize=7, loc="upper left",
                    bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, frameon=False)
    else:  # a narrow figure (the case report's): under the panels, the panels keeping the width
        fig.legend(handles + [h for h, _ in extra], labels + [t for _, t in extra], fontsize=7,
                   loc="outside lower center", ncol=2, frameon=False)
    # every impact a line; impacts close in time one band with one label ("impacts 5-12"), measured
    # once the layout is final (plot_events)
    fig.draw_without_rendering()
    mark_impacts(ax_s, (ax_s, ax_v), impacts, halo=_halo(2.0), text_box=text_box)
    ax_s.set_title(_wrap(f"Time-distance: {sc.title}", title_chars(width, 100)), fontsize=10)
    return fig


def _draw_evidence(S: SceneDrawing, checks: dict) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import Circle, Polygon

    ax, ev, system = S.ax, S.sc.evidence, S.system
    for i, r in enumerate(ev.rest):
        c_pos, c_head = checks.get(("rest", i)), checks.get(("rest heading", i))
        verdict, color = _verdict([c_pos, c_head])
        p = S.d(r.position)
        body = S.body_of.get(r.body)
        if r.heading is not None and body is not None and body.outline() is not None:
            xy = S.d(to_world(body.outline(), r.position, r.heading))
            ax.add_patch(Polygon(xy, closed=True, facecolor="none", edgecolor=_EVIDENCE, lw=1.2, ls=(0, (4, 2)),
                                 zorder=_Z_EVIDENCE, gid=f"evidence:rest:{r.body}"))
            S.add(xy)
        ax.add_patch(Circle(p, S.k * r.tolerance, facecolor="none", edgecolor=_EVIDENCE, lw=0.6, ls=":",
                            zorder=_Z_EVIDENCE))
        ax.plot(*p, "x", color=_EVIDENCE, ms=7, mew=1.8, zorder=_Z_EVIDENCE + 0.5)
        S.add(p)
        S.labels.append(p)
        detail = _residual_text(c_pos, system)
        if c_head is not None:
            detail += f", heading {_residual_text(c_head, system)}"
        label = f"measured rest, {r.body}: {verdict}" + (f"\n  {detail}" if detail else "")
        S.legend_entry(label, Line2D([], [], ls=(0, (4, 2)), color=_EVIDENCE, lw=1.2, marker="x", ms=6, mew=1.5),
                       color)
    for i, m in enumerate(ev.marks):
        if m.phase == "approach" and not S.approach:
            continue  # a pre-impact mark belongs to the approach, left out of this view
        c = checks.get(("mark", i))
        verdict, color = _verdict([c])
        xy = S.d(m.points)
        ax.plot(xy[:, 0], xy[:, 1], "-", color=_EVIDENCE, lw=1.4, marker="o", ms=2.5, zorder=_Z_EVIDENCE)
        S.add(xy)
        name = m.name or f"mark {i + 1}"
        detail = _residual_text(c, system)
        if c is not None and "matched_wheel" in c.details:
            detail += f", nearest {c.details['matched_wheel']}"
        S.legend_entry(_wrap(f"measured mark \u201c{name}\u201d: {verdict}", 52) + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], color=_EVIDENCE, lw=1.4, marker="o", ms=2.5), color)
    if ev.impact_point is not None:
        c = checks.get(("point of impact", 0))
        verdict, color = _verdict([c])
        p = S.d(ev.impact_point.position)
        # above the PDOF arrows (it lies at the contact point), below the contact-point dot
        ax.plot(*p, "*", ms=13, mfc=_EVIDENCE, mec="white", mew=0.8, zorder=_Z_ARROW + 0.3)
        S.add(p)
        detail = _residual_text(c, system)
        S.legend_entry(f"measured point of impact: {verdict}" + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], ls="none", marker="*", ms=11, mfc=_EVIDENCE, mec="white"), color)
    for i, x in enumerate(ev.delta_v):
        c = checks.get(("delta-v", i))
        verdict, color = _verdict([c])
        name = x.name or f"delta-v of {x.body} ({x.component})"
        detail = _residual_text(c, system)
        S.legend_entry(_wrap(f"recorded \u0394v \u201c{name}\u201d: {verdict}", 52)
                       + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], ls="none"), color)
    for c in (S.scene.evidence.checks if S.scene.evidence is not None else ()):
        if c.kind == "crush energy":  # one check per group of crush items (drawn on the faces)
            verdict, color = _verdict([c])
            S.legend_entry(_wrap(f"{c.name}: {verdict}", 52) + f"\n  |model loss - crush| {_residual_text(c, system)}",
                           Line2D([], [], ls="none"), color)
    for i, x in enumerate(getattr(ev, "recorder", ())):
        c = checks.get(("recorder", i))
        verdict, color = _verdict([c])
        name = x.name or f"recorder in {x.body}"
        detail = ""
        if c is not None and "times" in c.details:
            detail = (f"{c.details.get('n_compared', len(x.times))} pre-crash speeds, worst "
                      f"{_residual_text(c, system)}")
        S.legend_entry(_wrap(f"recorded speeds \u201c{name}\u201d: {verdict}", 52)
                       + (f"\n  {detail}" if detail else ""),
                       Line2D([], [], ls="none"), color)


def _draw_arrows(S: SceneDrawing) -> None:
    from matplotlib.lines import Line2D
    from matplotlib.patches import FancyArrowPatch

    ax, imp, system, sc = S.ax, S.scene.impact, S.system, S.sc
    moving = [b for b in imp.bodies.values() if not b.fixed]
    if not moving:
        return
    # results of the impact: in the animation they appear at the impact (t = 0), not before it
    first = (len(ax.patches), len(ax.lines), len(S.texts))
    # one arrow scale for all bodies: display length per display speed, a 1-2-2.5-5 number,
    # such that the largest delta-v is drawn about 6 m (20 ft) long
    ref_len = to_unit(6.0, Kind.LENGTH, system)[0]
    dv_max = max(to_unit(b.delta_v_magnitude, Kind.SPEED, system)[0] for b in moving)
    sunit = to_unit(1.0, Kind.SPEED, system)[1]
    if dv_max > 0:
        scale = _nice_at_most(ref_len / dv_max)  # display length per display speed unit
        for b in moving:
            dv, _ = to_unit(b.delta_v_magnitude, Kind.SPEED, system)
            if dv <= 0:
                continue
            tail = S.d(sc.states[b.name].position)
            vec = np.asarray(b.delta_v, dtype=float) / b.delta_v_magnitude * dv * scale
            dark = S.colors(b.name)[2]
            ax.add_patch(FancyArrowPatch(tail, tail + vec, arrowstyle="-|>", mutation_scale=12, lw=1.6, color=dark,
                                         shrinkA=0, shrinkB=0, zorder=_Z_ARROW, gid=f"arrow:delta-v:{b.name}"))
            S.add(tail + vec)
            # label beyond the tip, on the arrow's line
            u = vec / np.hypot(*vec)
            tip = tail + vec + u * 0.5 * S.k
            S.text(tip, f"\u0394v {b.name}\n{fmt(b.delta_v_magnitude, Kind.SPEED, system, 3)}", kind="delta-v",
                    fontsize=7, color=dark, ha="left" if u[0] >= 0 else "right", va="bottom" if u[1] >= 0 else "top",
                    zorder=Z_TEXT, path_effects=_halo())
        per = 1.0 / scale
        S.legend_entry(f"\u0394v at the CG (1 {S.lunit} of arrow = {per:.3g} {sunit})",
                       Line2D([], [], color="0.15", lw=1.6, marker=">", markevery=[1], ms=5))
    # principal direction of force at the contact point
    length = 3.0 * S.k
    p0 = S.d(imp.point)
    ax.plot(*p0, "o", ms=5, mfc="black", mec="white", mew=0.8, zorder=_Z_ARROW + 0.5)
    S.add(p0)
    S.legend_entry("contact point (crush impulse centre)",
                   Line2D([], [], ls="none", marker="o", ms=5, mfc="black", mec="white"))
    for name in (imp.body1, imp.body2):
        b = imp.bodies[name]
        if b.fixed or b.crush_impulse is None or b.pdof is None:
            continue
        f = np.asarray(b.crush_impulse, dtype=float)
        if not np.hypot(*f) > 0:
            continue
        u = f / np.hypot(*f)
        tip = p0 + length * u
        dark = S.colors(name)[2]
        ax.add_patch(FancyArrowPatch(p0, tip, arrowstyle="simple,head_width=0.9,head_length=0.9,tail_width=0.35",
                                     mutation_scale=14, facecolor="white", edgecolor=dark, lw=1.2, shrinkA=0,
                                     shrinkB=0, zorder=_Z_ARROW, gid=f"arrow:pdof:{name}"))
        S.add(tip)
        deg = convert(b.pdof, "rad", "deg", Kind.ANGLE)
        text = f"PDOF {name}\n{deg:.0f}\N{DEGREE SIGN} ({b.clock} o'clock)"
        # beyond the tip, or beyond the tail (the side the force comes from) if that covers fewer labels
        best = None
        for anchor, d in ((tip + u * 0.4 * S.k, u), (p0 - u * 0.4 * S.k, -u)):
            hits = S.label_hits(anchor, d, 17, 2)
            if best is None or hits < best[0]:
                best = (hits, anchor, d)
        _, lab, d = best
        S.text(lab, text, kind="pdof", fontsize=7, color=dark, ha="left" if d[0] >= 0 else "right",
               va="bottom" if d[1] >= 0 else "top", zorder=Z_TEXT, path_effects=_halo())
        S.labels.append(lab)
    S.legend_entry("PDOF: crush force on each body in contact",
                   Line2D([], [], ls="none", marker=r"$\Rightarrow$", ms=12, color="0.15"))
    S.appear += [(a, 0.0) for a in (*ax.patches[first[0]:], *ax.lines[first[1]:], *S.texts[first[2]:])]


def _draw_obstacles(S: SceneDrawing) -> None:
    """Fixed obstacles of the scene (guardrails, walls, poles), hatched, with their names."""
    from matplotlib.patches import Patch, Polygon

    spec = S.sc.runout
    barrier = next((v.bodies[0].name for v in S.sc.vehicles if v.is_barrier), None)
    obstacles = [o for o in (spec.obstacles if spec is not None else ()) if o.name != barrier]
    for o in obstacles:
        for piece in o.pieces():
            xy = S.d(piece)
            S.ax.add_patch(Polygon(xy, closed=True, facecolor="0.78", edgecolor="0.25", lw=0.8, hatch="xxx",
                                   zorder=_Z_BARRIER, gid=f"obstacle:{o.name}"))
            S.far.append(xy)  # a long guardrail counts toward the view only near the scene
        # its name at the point of the obstacle nearest the scene (a long guardrail's middle may lie
        # far outside the view)
        centre = np.vstack(S.points).mean(axis=0) if S.points else np.zeros(2)
        line = S.d(np.asarray(o.points, dtype=float))
        mid = line[int(np.argmin(np.hypot(*(line - centre).T)))]
        S.text(mid, o.name, kind="obstacles", fontsize=7, color="0.15", ha="center", va="bottom", zorder=Z_TEXT,
               path_effects=_halo())
    if obstacles:
        S.legend_entry("fixed obstacle", Patch(facecolor="0.78", edgecolor="0.25", hatch="xxx", lw=0.8))


def _draw_impacts(S: SceneDrawing) -> None:
    """Every impact as a numbered marker at its contact point, in time order (1 = the first impact)."""
    from matplotlib.lines import Line2D

    joint = getattr(S.scene, "joint", None)
    marks = [(1, S.scene.impact.point, 0.0)]
    for ev in (joint.impact_events() if joint is not None else ()):
        seen = set()
        for r in ev.records:  # an event's number once at each of its pairs (not at every bounce)
            if (r.body1, r.body2) not in seen:
                seen.add((r.body1, r.body2))
                marks.append((ev.number, r.point, float(r.t)))
    if len(marks) < 2:
        return
    for n, p, t_mark in marks:
        xy = S.d(np.asarray(p, dtype=float))
        first = (len(S.ax.lines), len(S.texts))
        # the point itself, and its number in a yellow disc on it (moved aside with a leader line
        # by place_labels when impacts lie close together)
        S.ax.plot(*xy, "o", ms=3.5, mfc="0.1", mec="#ffd54f", mew=0.8, zorder=_Z_ARROW + 1, gid=f"impact:{n}")
        S.text(xy, str(n), kind="impacts", fontsize=7, fontweight="bold", ha="center", va="center",
               zorder=_Z_ARROW + 2, bbox=dict(boxstyle="circle,pad=0.25", facecolor="#ffd54f", edgecolor="0.1", lw=1.0))
        S.add(xy)
        # each impact appears (in the animation) when it happens: the first at t = 0
        S.appear += [(a, t_mark) for a in (*S.ax.lines[first[0]:], *S.texts[first[1]:])]
    S.legend_entry("impacts in time order (1: the first; the report lists them)",
                   Line2D([], [], ls="none", marker="o", ms=9, mfc="#ffd54f", mec="0.1"))


def _draw_barrier(S: SceneDrawing, lo, hi) -> None:
    """The barrier face through the contact point along the crush tangent, over its extent
    (endless: across the view), cut to the view widened by half its span on each side (so it
    never widens the view, and a later widening, as the animation's, stays covered)."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Polygon

    sc = S.sc
    if not any(v.is_barrier for v in sc.vehicles):
        return
    surf = sc.impact.surface
    p0 = np.asarray(surf.point, dtype=float)
    t = np.asarray(surf.tangent, dtype=float)
    n = np.asarray(surf.normal, dtype=float)  # from the barrier into the vehicle
    lo, hi = np.asarray(lo, dtype=float), np.asarray(hi, dtype=float)
    half = 0.5 * (hi - lo)
    blo, bhi = lo - half, hi + half
    reach = float(np.hypot(*(bhi - blo))) / S.k + float(np.hypot(*p0))  # metres: beyond the box either way
    extent = getattr(sc, "barrier_extent", None) or (-np.inf, np.inf)
    a, b = (max(float(extent[0]), -reach), min(float(extent[1]), reach))
    ends = S.d(np.array([p0 + a * t, p0 + b * t]))
    depth = 0.6 * S.k
    back = ends - depth * n
    name = next(v.bodies[0].name for v in sc.vehicles if v.is_barrier)
    poly = _clip_polygon(np.vstack([ends, back[::-1]]), blo, bhi)
    if len(poly) >= 3:
        S.ax.add_patch(Polygon(poly, closed=True, facecolor="0.85", edgecolor="0.35", lw=0.0, hatch="////",
                               zorder=_Z_BARRIER, gid=f"barrier:{name}"))
    for piece in _clip_polyline(ends, blo, bhi):
        S.ax.plot(piece[:, 0], piece[:, 1], "-", color="0.15", lw=4.0, solid_capstyle="butt", zorder=_Z_BARRIER + 0.5,
                  gid=f"barrier-face:{name}")
    S.legend_entry(f"barrier face ({name})", Line2D([], [], color="0.15", lw=4.0))


# --------------------------------------------------------------------------------------------
# Road layout: friction zones and map lines
# --------------------------------------------------------------------------------------------

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


def _region_of_interest(S: SceneDrawing) -> _Roi:
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


def _clip_polygon(polygon, lo, hi) -> np.ndarray:
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


def _clip_polyline(points, lo, hi) -> list[np.ndarray]:
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


def _zone_label(zone) -> str:
    slope = [f"{what} {100 * v:.3g} %" for what, v in (("grade", zone.grade), ("cross-slope", zone.cross_slope))
             if v is not None]
    return ", ".join([f"{zone.name}, f = {zone.mu:g}", *slope])


def zone_colors(zones) -> list[tuple[str, str]]:
    """(fill, edge) of each friction zone: one pair per distinct zone name, in the order the names
    first appear (:data:`_ZONE_COLORS`, repeating after four names), so that two zones of one
    name ("grass verge" either side of the road) look alike and share one legend entry."""
    order: dict[str, int] = {}
    for z in zones:
        order.setdefault(z.name, len(order))
    return [_ZONE_COLORS[order[z.name] % len(_ZONE_COLORS)] for z in zones]


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


def _draw_zones(S: SceneDrawing, roi: _Roi) -> None:
    """Every friction zone of the road as a pale hatched polygon under everything else, one colour
    and one legend entry per zone name (:func:`zone_colors`); only its part inside the region of
    interest counts toward the axis limits."""
    from matplotlib.patches import Patch, Polygon

    zones = _zones(S)
    legend = _zone_legend_texts(zones)
    for i, (z, (fill, edge)) in enumerate(zip(zones, zone_colors(zones))):
        xy = S.d(z.vertices)
        S.ax.add_patch(Polygon(xy, closed=True, facecolor=fill, edgecolor=edge, lw=0.8, hatch=".",
                               zorder=_Z_ZONE, gid=f"zone:{i}"))
        inside = _clip_polygon(xy, roi.lo, roi.hi)
        if len(inside):
            S.add(inside)
        S.legend_entry(legend[z.name], Patch(facecolor=fill, edgecolor=edge, hatch=".", lw=0.8))
    if zones:
        S.legend_entry(f"road surface outside the zones: f = {S.sc.runout.road.mu:g}",
                       Patch(facecolor="white", edgecolor="0.6", lw=0.8))


def _map_line_look(line) -> tuple[str, str]:
    """(what it is, colour) of a map line: its style's legend text, or for a gouge or debris drawn
    from a survey "gouge"/"debris"; its own colour or the style's."""
    text, color = _MAP_STYLES[line.style][:2]
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

    _, _, lw, dashes, double = _MAP_STYLES[line.style]
    _, color = _map_line_look(line)
    if double:  # two strokes with a white gap: a wide stroke under a narrow white line
        kw = dict(color="white", lw=lw, solid_capstyle="butt",
                  path_effects=[patheffects.Stroke(linewidth=3.6 * lw, foreground=color), patheffects.Normal()])
    else:
        kw = dict(color=color, lw=lw, solid_capstyle="butt")
        if dashes is not None:
            kw.update(ls="--", dashes=dashes)
    return map_line_legend_texts([line])[0], kw


def _draw_map_lines(S: SceneDrawing, roi: _Roi) -> None:
    """The road layout of ``[[map.lines]]`` under the vehicles, each in its style; only the parts
    inside the region of interest count toward the axis limits."""
    from matplotlib.lines import Line2D

    lines = getattr(S.sc, "map_lines", ())
    for i, (line, text) in enumerate(zip(lines, map_line_legend_texts(lines))):
        _, kw = _map_line_artist_kw(line)
        xy = S.d(line.points)
        S.ax.plot(xy[:, 0], xy[:, 1], zorder=_Z_MAP, gid=f"map:{i}", **kw)
        for piece in _clip_polyline(xy, roi.lo, roi.hi):
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


def _label_road_layout(S: SceneDrawing, roi: _Roi, lo, hi) -> None:
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
        part = _clip_polygon(polys[i], vlo, vhi)
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
                   style="italic", color=_darker(edge),
                   path_effects=_halo(2.2), zorder=Z_TEXT - 0.5)
        S.labels.append(cand[k])
    step = 0.015 * float((np.asarray(hi) - np.asarray(lo)).max())
    for i, line in enumerate(getattr(S.sc, "map_lines", ())):
        if not line.name:
            continue
        cand, angle = [], []
        for piece in _clip_polyline(S.d(line.points), vlo, vhi):
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
        color = _darker(line.color or _MAP_STYLES[line.style][1])
        S.text(cand[k], line.name, kind="map", gid=f"map-label:{i}", xytext=tuple(off), textcoords="offset points",
                   fontsize=6.5, ha="center",
                   va="bottom", rotation=deg, rotation_mode="anchor", color=color, path_effects=_halo(2.0),
                   zorder=Z_TEXT - 0.5)
        S.labels.append(cand[k])


def _darker(color, factor: float = 0.6):
    """``color`` darkened towards black (labels in a zone's or line's colour, readable on white)."""
    from matplotlib.colors import to_rgb

    return tuple(factor * c for c in to_rgb(color))


def _scale_bar(S: SceneDrawing, width: float, sheet=None):
    """Scale bar at the lower left (a 1-2-2.5-5 length near a fifth of the view); on a print sheet
    its label also states the scale and the paper ("1:200 on A4"; a US sheet its engineer's scale,
    ``1" = 40' on letter``: :func:`engineer_scale_text`)."""
    from matplotlib.font_manager import FontProperties
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    length = _nice_at_most(width / 5.0)
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
    length = _nice_at_most((x1 - x0) / 5.0)
    if old is not None and getattr(old, "crashsim_length", None) == length:
        return old
    if old is not None:
        old.remove()
    bar = _scale_bar(S, x1 - x0)
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


def _north_arrow(S: SceneDrawing) -> list:
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
                      path_effects=_halo(), gid="north-arrow")
    return [t]


def _downhill_arrow(S: SceneDrawing, x: float) -> list:
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
                      path_effects=_halo(), gid="downhill-arrow")
    return [t]


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


def _axes_indicator(ax) -> list:
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
                               fontsize=8, ha=ha, va=va, zorder=Z_TEXT + 1, path_effects=_halo(),
                               gid="axes-indicator"))
    return out


#: Width of a new scene figure laid out with the legend under it [in] (:func:`layout_scene_figure`).
_FIGURE_WIDTH = 10.0
#: The range of :func:`plot_scene`'s ``width`` [in].
MIN_WIDTH, MAX_WIDTH = 3.0, 40.0


def layout_scene_figure(ax, leg, below: bool, width: float = _FIGURE_WIDTH, height: float = 7.0,
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


def _fit_texts(S: SceneDrawing) -> None:
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


def _scene_legend(S: SceneDrawing, mode: str, below: bool, compact: bool = False):
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
            return k.startswith(evidence) and k != _CRUSH_KEY

        n_ev = sum(is_item(k) for k in keys)
        keep = [k for k in keys if not is_item(k)]
        if n_ev:
            from matplotlib.lines import Line2D

            S.handles.setdefault("measured evidence (red)",
                                 Line2D([], [], ls=(0, (4, 2)), color=_EVIDENCE, lw=1.2, marker="x", ms=5, mew=1.3))
            keep.append("measured evidence (red)")
        keys = keep
        handles = [S.handles[k] for k in keys]
        labels = [k.split("\n  ")[0].replace("\n", " ") for k in keys]
    if mode in _OUTSIDE and compact:  # a print sheet: under the drawing, as many columns as the page holds
        fig = S.ax.figure
        r = fig.canvas.get_renderer()
        room = fig.get_size_inches()[0] * fig.dpi - 2 * _SHEET_EDGE * fig.dpi
        for ncol in (3, 2, 1):
            leg = fig.legend(handles, labels, loc="lower center",
                             bbox_to_anchor=(0.5 * fig.get_size_inches()[0], _SHEET_EDGE),
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
        leg.get_title().set_color(_PASS if failed == 0 else _FAIL)
    leg.set_zorder(Z_TEXT + 2)
    return leg


def history_panels(scene) -> int:
    """Panels of :func:`plot_histories` for ``scene``: 3, one more when bodies stayed in sustained
    contact during the run-out (the contact-force panel), one more where the rollover check ran (the
    lateral-acceleration and load-transfer panel, :func:`crashsim.plot_loads.draw_roll_panel`)."""
    joint = getattr(scene, "joint", None)
    contact = joint is not None and any(p.sustained for p in joint.pairs)
    return 3 + int(contact) + int(has_roll_panel(scene))


#: Impacts closer in time than this share of the histories' time axis get their labels on separate rows.
IMPACT_LABEL_GAP = 0.03

#: An articulation limit is drawn on the histories' articulation panel once a hitch's articulation
#: reaches this share of it (below, the legend names it without the lines).
LIMIT_SHOWN_FROM = 0.3


def plot_histories(scene, axes=None, *, system: str | None = None):
    """Run-out time histories: CG speed, yaw rate and articulation angle after separation, and
    the sustained-contact forces when bodies stayed in contact.

    Parameters
    ----------
    scene : SceneResult
        With a run-out (``scene.runout`` not None).
    axes : sequence of matplotlib Axes, optional
        Panels for speed, yaw rate and articulation (and contact force: as many as
        :func:`history_panels` says); a new figure (shared time axis) if None.
    system : {"SI", "US"}, optional
        Speed in m/s or mph; yaw rate in deg/s and articulation in deg in both. Default: the
        scenario's units.

    Returns
    -------
    matplotlib Figure if ``axes`` is None, else ``axes`` (as an array of 3 Axes).

    Raises
    ------
    ScenarioError
        If the scene has no run-out (an impact-only scenario).

    Notes
    -----
    One line per body (colour family per vehicle as in :func:`plot_scene`; solid for the
    first body of a vehicle, dashed and dotted for the towed ones) from the sampled
    ``BodyRunout.history``; a dot marks the time to rest. The articulation at each hitch is
    ``HitchHistory.articulation`` (heading of the front body minus that of the rear body);
    a hitch's articulation limit, if set, is drawn as thin grey lines.  Secondary impacts are
    thin vertical lines, numbered as in the report (#2, #3, ...); the contact-force panel
    shows each pair's sampled sustained-contact force (``PairSummary.force``).
    """
    system = figure_system(scene, system)
    if not scene.runout:
        raise ScenarioError(f"scene {scene.scenario.title!r} has no run-out (impact only): there are no time "
                            "histories to plot; add a [runout] section to the scenario", field="runout")
    n_panels = history_panels(scene)
    roll = has_roll_panel(scene)
    contact = n_panels - int(roll) == 4
    new = axes is None
    if new:
        fig, axes = _plt().subplots(n_panels, 1, figsize=(8.0, 2.85 * n_panels), sharex=True, layout="constrained")
    axes = np.asarray(axes, dtype=object).ravel()
    if len(axes) != n_panels:
        what = "speed, yaw rate, articulation" + (", contact force" if contact else "") + (", roll" if roll else "")
        raise ScenarioError(f"needs {n_panels} axes ({what}), got {len(axes)}", field="axes")
    ax_v, ax_w, ax_a = axes[:3]
    kv, vunit = to_unit(1.0, Kind.SPEED, system)
    kw = convert(1.0, "rad/s", "deg/s", Kind.ANGULAR_VELOCITY)
    ka = convert(1.0, "rad", "deg", Kind.ANGLE)
    styles = ("-", "--", ":", "-.")
    movable = [v for v in scene.scenario.vehicles if not v.is_barrier]
    family = {v.name: _FAMILIES[i % len(_FAMILIES)] for i, v in enumerate(movable)}
    limits, locked = {}, set()
    for v in movable:
        for i, h in enumerate(v.hitches):
            limits[(v.bodies[i].name, v.bodies[i + 1].name)] = h.articulation_limit
            if h.yaw_locked:
                locked.add((v.bodies[i].name, v.bodies[i + 1].name))
    reached: dict[float, float] = {}  # articulation limit -> the largest |articulation| of its hitches
    t_max = 0.0
    n_hitch = 0
    for vn, r in scene.runout.items():
        _, line, dark = family.get(vn, _FAMILIES[-1])
        at_rest = r.success
        for j, (name, b) in enumerate(r.bodies.items()):
            h = b.history
            color = dark if j == 0 else line
            ls = styles[j % len(styles)]
            speed = kv * np.hypot(h.vx, h.vy)
            ax_v.plot(h.t, speed, ls, color=color, lw=1.5, label=f"{name} ({vn})")
            ax_w.plot(h.t, kw * h.yaw_rate, ls, color=color, lw=1.5, label=f"{name} ({vn})")
            if at_rest and b.time_to_rest is not None:
                ax_v.plot(h.t[-1], speed[-1], "o", color=color, ms=4)
            t_max = max(t_max, float(h.t[-1]))
        for k, hh in enumerate(r.hitches):
            n_hitch += 1
            color = dark if k == 0 else line
            lock = ", yaw-locked" if (hh.front, hh.rear) in locked else ""
            ax_a.plot(hh.t, ka * hh.articulation, styles[k % len(styles)], color=color, lw=1.5,
                      label=f"{hh.front} \N{MINUS SIGN} {hh.rear} ({vn}{lock})")
            lim = limits.get((hh.front, hh.rear))
            if lim is not None:
                peak = float(np.max(np.abs(hh.articulation))) if len(hh.articulation) else 0.0
                reached[lim] = max(reached.get(lim, 0.0), peak)
    # each limit once; its lines only where an articulation comes within reach of it (else they would
    # squeeze a few degrees of articulation into a hair), the legend names it either way
    for lim, peak in sorted(reached.items()):
        shown = peak >= LIMIT_SHOWN_FROM * lim
        if shown:
            for sgn in (1, -1):
                ax_a.axhline(sgn * ka * lim, color="0.6", lw=0.8, ls="--")
        ax_a.plot([], [], ls="--" if shown else "none", color="0.6", lw=0.8,
                  label=f"articulation limit \N{PLUS-MINUS SIGN}{ka * lim:.0f} deg" + ("" if shown else " (off the scale)"))
    ax_v.set_ylabel(f"CG speed [{vunit}]")
    ax_w.set_ylabel("yaw rate [deg/s]")
    ax_a.set_ylabel("articulation [deg]")
    axes[-1].set_xlabel("time after separation [s]")
    joint = getattr(scene, "joint", None)
    if roll:
        draw_roll_panel(axes[-1], scene, {vn: (f[2], f[1]) for vn, f in family.items()}, styles)
    if contact:
        ax_f = axes[3]
        kf, funit = to_unit(1.0, Kind.FORCE, system)
        for k, p in enumerate(q for q in joint.pairs if q.sustained):
            ax_f.plot(p.t, kf * np.asarray(p.force), styles[k % len(styles)], lw=1.3, label=p.name.replace("|", " \N{EN DASH} "))
        ax_f.set_ylabel(f"contact force [{funit}]")
        ax_f.set_ylim(bottom=0.0)
        ax_f.legend(fontsize=8, loc="best", title="sustained contact", title_fontsize=7)
    if joint is not None:
        # impacts closer in time than a label's width: each label one row lower than the one it would cover
        near = IMPACT_LABEL_GAP * (t_max if t_max > 0 else 1.0)
        rows: list[tuple[float, int]] = []
        for ev in joint.impact_events():
            n = ev.number
            for ax in axes:
                ax.axvline(ev.t, color="0.45", lw=0.7, ls=":")
            taken = {r for t, r in rows if abs(ev.t - t) < near}
            row = next(r for r in range(len(rows) + 1) if r not in taken)
            rows.append((ev.t, row))
            ax_v.annotate(f"#{n}", (ev.t, 1.0), xycoords=("data", "axes fraction"), xytext=(2, -10 - 9 * row),
                          textcoords="offset points", fontsize=7, color="0.3", gid=f"histories:impact:{n}")
    for ax in axes:
        ax.grid(True, alpha=0.4)
        ax.set_xlim(0.0, t_max * 1.02 if t_max > 0 else 1.0)
        ax.axhline(0.0, color="0.3", lw=0.6)
    ax_v.set_ylim(bottom=0.0)
    ax_v.legend(fontsize=8, loc="upper right", title="\N{BLACK CIRCLE} time to rest", title_fontsize=7)
    ax_w.legend(fontsize=8, loc="best")
    if n_hitch:
        ax_a.legend(fontsize=8, loc="best", title="front \N{MINUS SIGN} rear heading", title_fontsize=7)
    else:
        ax_a.text(0.5, 0.5, "no articulated vehicle in this scene", transform=ax_a.transAxes, ha="center",
                  va="center", color="0.4")
    ax_v.set_title(_wrap(f"{scene.scenario.title}: run-out after separation",
                         title_chars(float(ax_v.figure.get_size_inches()[0]), 90)), fontsize=10)
    return axes[0].figure if new else axes


def save_scene_figures(scene, path, *, histories_path=None, dpi: int = 150, interval: float | None = None,
                       system: str | None = None, time_distance_path=None, approach: bool = True, legend="compact",
                       hide=(), paper: str | None = None, scale: float | None = None, view=None,
                       zoom: str | None = None, wheels_path=None) -> list:
    """Write the scene diagram (and optionally the histories) to files; closes its figures.

    Parameters
    ----------
    scene : SceneResult
    path : str or Path
        Scene diagram; the format follows the suffix: ``.png``, ``.svg`` or ``.pdf``.
    histories_path : str or Path, optional
        Run-out histories (:func:`plot_histories`), same suffixes; needs a run-out.
    time_distance_path : str or Path, optional
        Time-distance and speed-time chart (:func:`plot_time_distance`), same suffixes.
    wheels_path : str or Path, optional
        The wheel time line (:func:`crashsim.plot_timeline.plot_wheel_timeline`): every wheel's state,
        air-brake level, sliding and steering from the approach to rest, same suffixes.
    approach : bool
        Draw the approaches on the scene diagram (see :func:`plot_scene`).
    legend, hide, paper, scale, view, zoom
        Legend, hidden label kinds, print sheet and detail view of the scene diagram (see
        :func:`plot_scene`).
    dpi : int
        Resolution of raster output [dots per inch].
    interval : float, optional
        Ghost-outline interval [s] (see :func:`plot_scene`).
    system : {"SI", "US"}, optional
        Display units; default the scenario's.

    Returns
    -------
    list of Path
        The files written, scene diagram first. Parent directories are created.

    Raises
    ------
    ScenarioError
        For a suffix other than .png/.svg/.pdf (before anything is drawn or written), or
        histories asked of a scene without a run-out.
    """
    named = [(Path(path), "path")] + ([(Path(histories_path), "histories_path")] if histories_path is not None else [])
    named += [(Path(time_distance_path), "time_distance_path")] if time_distance_path is not None else []
    named += [(Path(wheels_path), "wheels_path")] if wheels_path is not None else []
    targets = [p for p, _ in named]
    for p, key in named:
        if p.suffix.lower() not in SCENE_FIGURE_SUFFIXES:
            raise ScenarioError(f"cannot write a figure to {str(p)!r}: unsupported suffix {p.suffix!r}; allowed "
                                f"{', '.join(SCENE_FIGURE_SUFFIXES)}", field=key)
    if histories_path is not None and not scene.runout:
        raise ScenarioError(f"cannot write histories to {str(histories_path)!r}: scene "
                            f"{scene.scenario.title!r} has no run-out (impact only)", field="histories_path")
    check_hide(hide)
    if paper is not None:
        print_sheet(paper, (0.0, 0.0), (1.0, 1.0), 1.0)  # a known paper, before anything is drawn
    plt = _plt()
    written = []
    if view is not None:
        check_view(view, field="view")  # before anything is drawn
    ax = plot_scene(scene, interval=interval, system=system, approach=approach, legend=legend, hide=hide, paper=paper,
                    scale=scale, view=view, zoom=zoom)
    try:
        targets[0].parent.mkdir(parents=True, exist_ok=True)
        ax.figure.savefig(targets[0], dpi=dpi)
        written.append(targets[0])
    finally:
        plt.close(ax.figure)
    for p, key in named[1:]:
        if key == "wheels_path":
            fig = plot_wheel_timeline(scene)
        else:
            fig = (plot_histories if key == "histories_path" else plot_time_distance)(scene, system=system)
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
            fig.savefig(p, dpi=dpi)
            written.append(p)
        finally:
            plt.close(fig)
    return written

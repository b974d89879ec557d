"""The scene diagram (:func:`plot_scene`): the vehicles at impact, their run-out with ghost outlines
and rest, and the layers, sheet and layout of the other modules of :mod:`crashsim.plotting`, in
the order they are drawn.
"""

from __future__ import annotations

import logging

import numpy as np

from ..errors import ScenarioError
from ..figure_options import check_hide, check_view, title_chars
from .detail import INSET_MARGIN, add_impact_inset, impact_window, needs_inset
from .drawing import SceneDrawing
from .labels import place_labels
from .layers import (check_map, draw_approaches, draw_arrows, draw_barrier, draw_crush, draw_evidence, draw_impacts,
                     draw_obstacles, draw_scene_underlay, draw_track)
from .layout import OUTSIDE_LEGENDS, fit_texts, layout_scene_figure, legend_headroom, legend_mode, scene_legend
from .road import clip_polygon, draw_map_lines, draw_zones, label_road_layout, region_of_interest
from .sheet import axes_indicator, downhill_arrow, layout_print, north_arrow, print_sheet, scale_bar
from .style import FIGURE_WIDTH, MAX_WIDTH, MIN_WIDTH, Z_GHOST, Z_IMPACT, Z_REST, Z_TRACK, figure_system, halo, nice_at_most, nice_steps, pyplot, wrap

__all__ = ["plot_scene"]


_log = logging.getLogger("crashsim")


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
    steps = nice_steps(min(ends.values()) / 50.0, max(ends.values()))
    for s in reversed(steps):
        if all(4 <= len(_ghost_times(t, s)) <= 6 for t in ends.values()):
            return dict.fromkeys(ends, s)
    out = {}
    for k, t in ends.items():
        cand = [s for s in nice_steps(t / 50.0, t) if 4 <= len(_ghost_times(t, s)) <= 6]
        out[k] = cand[-1] if cand else nice_at_most(t / 5.0)
    return out


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

    system = figure_system(scene, system)
    window = _detail_window(scene, view, zoom)
    new = ax is None
    _check_width(width, new, paper, scale)
    if new:
        # laid out by layout_scene_figure (exact equal-aspect box plus legend), not by a layout engine
        ax = pyplot().figure(figsize=(10.0, 6.0)).add_subplot()
    S = _new_drawing(scene, ax, system, approach, width, hide)
    sc = S.sc
    runout = scene.runout or {}
    _draw_at_impact(S, axles)
    if evidence and sc.evidence.crush:
        draw_crush(S, sc)
    if approach and getattr(sc, "approaches", None):  # tracks, CG paths, start of braking, perception
        draw_approaches(S)
    _draw_runout(S, runout, times, interval, axles)
    _name_bodies_at_impact(S, runout)
    _draw_results(S, evidence, arrows)
    roi = _draw_road(S)
    lo, hi = _framed_extent(S, window)
    mode = legend_mode(legend)
    for w in tuple(getattr(scene, "warnings", ()) or ()):
        S.legend_entry(wrap("warning: " + w, 60), Line2D([], [], ls="none"), color="#b35900")
    sheet = leg = None
    if paper is not None or scale is not None:
        sheet, leg = _print_sheet(S, mode, paper, scale, new, lo, hi)
        lo, hi = sheet.lo, sheet.hi
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal", adjustable="box")
    draw_barrier(S, lo, hi)  # a face along the crush tangent, cut to the frame: it never widens the view
    label_road_layout(S, roi, lo, hi)
    fixed = _decorate(S, width)
    # a new figure of a wide scene: legend under the diagram; else at the right
    below = new and (hi[1] - lo[1]) / (hi[0] - lo[0]) < 0.75
    if sheet is None:
        leg = scene_legend(S, mode, below) if mode != "none" else None
    _lay_out(S, leg, mode, sheet, new, below, width, window)
    draw_scene_underlay(S)
    xl = ax.get_xlim()
    fixed.append(scale_bar(S, xl[1] - xl[0], sheet))
    if leg is not None and mode not in OUTSIDE_LEGENDS:
        fixed.append(leg)
    ax.figure.draw_without_rendering()
    if (new if inset is None else inset) and window is None:
        _add_inset(S, fixed)
    S.fixed = fixed
    S.unplaced = place_labels(ax, S.texts, fixed, np.vstack(S.points))
    S.keep()
    if S.unplaced:
        _log.info("scene figure: %d label(s) found no free place and may overlap others", S.unplaced)
    return ax


def _new_drawing(scene, ax, system: str, approach: bool, width, hide) -> SceneDrawing:
    """The drawing state of :func:`plot_scene` on ``ax``: with or without the approaches, the width of a
    new figure and the label kinds hidden."""
    S = SceneDrawing(scene, ax, system)
    S.approach = approach
    S.width = FIGURE_WIDTH if width is None else float(width)
    S.hide = check_hide(hide)
    return S


def _check_width(width, new: bool, paper, scale) -> None:
    """Refuse a ``width`` of :func:`plot_scene` that sizes no new figure or is out of range."""
    if width is not None:
        if not new or paper is not None or scale is not None:
            raise ScenarioError("width sizes a new figure: leave ax=None, and paper and scale unset", field="width")
        if not (isinstance(width, (int, float)) and MIN_WIDTH <= width <= MAX_WIDTH):
            raise ScenarioError(f"width = {width!r} in is outside the allowed {MIN_WIDTH:g} to {MAX_WIDTH:g} in",
                                field="width")


def _draw_at_impact(S: SceneDrawing, axles: bool) -> None:
    """The colour key (first in the legend), and every vehicle at impact: outlines (or skeletons), axles, pins."""
    from matplotlib.patches import Patch

    sc = S.sc
    for v in sc.vehicles:  # the colour key first in the legend
        if not v.is_barrier:
            fill, line, _ = S.family[v.name]
            desc = sc.descriptions.get(v.name, "")
            S.legend_entry(wrap(f"vehicle {v.name}" + (f": {desc}" if desc else ""), 60),
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
                          alpha=0.9, zorder=Z_IMPACT)
            if p is None:
                S.skeleton(b, st.position, st.heading, line)
            elif axles:
                S.axle_lines(b, st.position, st.heading, line, 1.0, zorder=Z_IMPACT)
            S.add(S.d(st.position))
        S.pins(v, poses, line, 4.0, zorder=Z_IMPACT)
    if any((p.get_gid() or "").startswith("outline:impact:") for p in S.ax.patches):
        S.legend_entry("at impact", Patch(facecolor="0.85", edgecolor="0.3", lw=1.4))


def _ghost_plan(runout: dict, times, interval) -> tuple[dict, str | None]:
    """The ghost times of each vehicle's run-out and their legend text (None: no entry)."""
    if times is not None:
        tt = np.sort(np.asarray(times, dtype=float).ravel())
        ghost = {vn: tt[(tt > 0) & (tt < r.t_end)] for vn, r in runout.items()}
        # no legend entry for ghosts that are not drawn (times=(): the animation's static layer)
        ghost_note = "intermediate, at the given times" if any(len(g) for g in ghost.values()) else None
        return ghost, ghost_note
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
    return ghost, ghost_note


def _draw_runout(S: SceneDrawing, runout: dict, times, interval, axles: bool) -> None:
    """The run-out: tracks, CG paths, ghosts and rest of every vehicle, and their legend entries."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    if not runout:
        S.legend_entry("impact only: no run-out computed", Line2D([], [], ls="none"))
        return
    sc = S.sc
    # body names go at the CGs at impact and at rest: keep the ghost time labels off them
    S.labels += [S.d(sc.states[n].position) for n in S.body_of if n in sc.states and not S.body_of[n].is_fixed]
    S.labels += [S.d(br.rest_position) for r in runout.values() for br in r.bodies.values()]
    ghost, ghost_note = _ghost_plan(runout, times, interval)
    for vn, r in runout.items():
        _draw_vehicle_runout(S, vn, r, ghost.get(vn, ()), axles)
    if ghost_note:
        S.legend_entry(ghost_note, Patch(facecolor="none", edgecolor="0.4", lw=0.7, alpha=0.7))
    S.legend_entry("at rest (end of run)", Patch(facecolor="0.8", edgecolor="0.1", lw=1.8))
    S.legend_entry("tyre track, sliding (mark expected)", Line2D([], [], color="0.15", lw=2.2))
    S.legend_entry("tyre track, rolling", Line2D([], [], color="0.4", lw=0.7, ls="--", dashes=(4, 3)))
    S.legend_entry("CG path", Line2D([], [], color="0.2", lw=1.0, ls=":"))


def _draw_vehicle_runout(S: SceneDrawing, vn: str, r, ghost_times, axles: bool) -> None:
    """One vehicle's run-out: its tracks and CG paths, the ghost outlines with their times, and its rest."""
    ax = S.ax
    v = next(x for x in S.sc.vehicles if x.name == vn)
    fill, line, dark = S.family[vn]
    for tr in r.wheels.values():
        draw_track(S, tr, line, dark, gid=f"track:{tr.key}")
    for name, br in r.bodies.items():
        h = br.history
        xy = S.d(np.column_stack([h.x, h.y]))
        (ln,) = ax.plot(xy[:, 0], xy[:, 1], ":", color=dark, lw=1.0, zorder=Z_TRACK, gid=f"path:{name}")
        S.timed.append((ln, np.asarray(h.t, dtype=float), xy))
        S.add(xy)
    # ghosts
    for j, t in enumerate(ghost_times):
        poses = {}
        for name, br in r.bodies.items():
            st = np.asarray(br.sol(float(t)), dtype=float)
            poses[name] = ((st[0], st[1]), st[2])
            p = S.outline(S.body_of[name], poses[name][0], poses[name][1], gid=f"outline:ghost:{name}:{t:g}",
                          fill=None, edge=line, lw=0.7, alpha=0.55, zorder=Z_GHOST)
            if p is None:
                c = S.d(poses[name][0])
                ax.plot(*c, "o", ms=3, color=line, alpha=0.6, zorder=Z_GHOST)
        S.pins(v, poses, line, 2.5, alpha=0.6, zorder=Z_GHOST)
        # time label at the lead body's CG, unless it would sit on another label
        lead = next(iter(r.bodies))
        c = S.d(poses[lead][0])
        if all(np.hypot(*(c - q)) > 1.6 * S.k for q in S.labels):
            S.text(c, f"{t:g} s", kind="times", fontsize=6.5, color=dark, ha="center", va="center",
                   path_effects=halo(1.8))
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


def _name_bodies_at_impact(S: SceneDrawing, runout: dict) -> None:
    """Each body's name at its CG at impact (unless named at rest nearby already); the hitch pins' legend entry."""
    from matplotlib.lines import Line2D

    sc = S.sc
    for v in sc.vehicles:
        if not v.is_barrier:
            for b in v.bodies:
                pos = np.asarray(sc.states[b.name].position)
                if runout:
                    rest = np.asarray(S.scene.runout_body(b.name).rest_position)
                    if np.hypot(*(rest - pos)) < 1.5:  # named at rest already
                        continue
                S.body_label(b.name, pos, offset=6.0 if b.name in S.no_outline else 0.0)
    if any(v.hitches for v in sc.vehicles):
        S.legend_entry("hitch pin", Line2D([], [], ls="none", marker="o", ms=4, mfc="white", mec="0.2"))


def _draw_results(S: SceneDrawing, evidence: bool, arrows: bool) -> None:
    """The evidence with its verdicts, the delta-v and PDOF arrows, the obstacles and the numbered impacts."""
    checks = check_map(S.scene) if evidence else {}
    if evidence and not S.sc.evidence.empty:
        draw_evidence(S, checks)
    if arrows:
        draw_arrows(S)
    draw_obstacles(S)
    draw_impacts(S)


def _draw_road(S: SceneDrawing):
    """The road layout (zones, map lines) and the obstacles, counted in the extent only near the scene
    (inside the region of interest, which is returned)."""
    roi = region_of_interest(S)
    for piece in S.far:  # obstacles: their part inside the region of interest
        inside = clip_polygon(piece, roi.lo, roi.hi)
        if len(inside):
            S.add(inside)
    draw_zones(S, roi)
    draw_map_lines(S, roi)
    return roi


def _framed_extent(S: SceneDrawing, window) -> tuple[np.ndarray, np.ndarray]:
    """(lower-left, upper-right) of the view [display units]: everything drawn, padded, with room at the
    bottom for the scale bar and at the top for the axes indicator; a detail view's window as given (the
    labels outside it dropped)."""
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
    return lo, hi


def _print_sheet(S: SceneDrawing, mode: str, paper, scale, new: bool, lo, hi):
    """(sheet, legend) of a scene figure on a print sheet: the page first (its size from the paper
    alone), then the legend under the drawing, measured, then the drawing box and the view at scale."""
    if not new:
        raise ScenarioError("a print sheet (paper, scale) needs a new figure: leave ax=None", field="ax")
    ax = S.ax
    probe = print_sheet(paper or "A4", lo, hi, S.k, 1e9, system=S.system)
    ax.figure.set_size_inches(*probe.size)
    leg = scene_legend(S, mode, True, compact=True) if mode != "none" else None
    room = 0.0
    if mode in OUTSIDE_LEGENDS:
        fig = ax.figure
        room = leg.get_window_extent(fig.canvas.get_renderer()).height / fig.dpi + 0.15
    sheet = print_sheet(paper or "A4", lo, hi, S.k, scale, legend_height=room, system=S.system)
    return sheet, leg


def _decorate(S: SceneDrawing, width) -> list:
    """Axis labels, grid, title (wrapped within a given width), the north, axes and downhill arrows;
    returns the texts of the arrows (labels keep clear of them)."""
    ax = S.ax
    ax.set_xlabel(f"X [{S.lunit}]")
    ax.set_ylabel(f"Y [{S.lunit}]")
    ax.grid(True, color="0.9", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    # a figure of a given width: the title wrapped within it (title_chars)
    ax.set_title(wrap(S.sc.title, 100 if width is None else title_chars(width, 100)), fontsize=10)
    north = north_arrow(S)
    return axes_indicator(ax) + north + downhill_arrow(S, 130 if north else 80)


def _lay_out(S: SceneDrawing, leg, mode: str, sheet, new: bool, below: bool, width, window) -> None:
    """The figure sized and the axes placed: on the print sheet, or to the view and the legend (the
    limits widened to hold every label), with a band for a legend inside a new figure."""
    ax = S.ax
    outside = leg if mode in OUTSIDE_LEGENDS else None
    if sheet is not None:
        layout_print(ax, sheet)
        return
    size = {} if width is None else {"width": S.width, "max_width": S.width}
    if new:
        layout_scene_figure(ax, outside, below, **size)
    if window is None:
        fit_texts(S)
    if new:
        layout_scene_figure(ax, outside, below, **size)
    if new and mode == "inside":
        legend_headroom(ax, leg, below, **size)


def _add_inset(S: SceneDrawing, fixed: list) -> None:
    """The enlarged inset of the impact where the impact is small in the view (appended to ``fixed``)."""
    w_lo, w_hi = (S.d(c) for c in impact_window(S.scene, INSET_MARGIN))
    if needs_inset(w_lo, w_hi, S.ax.get_xlim()):
        inset_ax = add_impact_inset(S.ax, w_lo, w_hi, avoid=np.vstack(S.points), fixed=fixed, unit=S.lunit)
        if inset_ax is not None:
            fixed.append(inset_ax)


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

"""Animation of a reconstructed scene: the scene diagram with the bodies moving over it.

An edge module like :mod:`crashsim.plotting` (matplotlib imported lazily, on first use). The
fixed layer of every frame is :func:`crashsim.plotting.plot_scene` without ghost outlines
(outlines at impact, obstacles, evidence, arrows, a compact legend outside the view, scale bar);
per frame the moving outlines, the hitch pins and a clock change, the tyre tracks and CG paths
grow to the clock, the outlines at rest appear when their vehicle comes to rest, and the results
of an impact (the delta-v and PDOF arrows with their labels, the contact point, the impact's
number) when it happens: a frame before the impact (the approach) shows none of them.

Two views (:data:`VIEWS`): ``"follow"`` (the default) is a camera framed on the vehicles at
each frame, its centre and size smoothed over :data:`CAMERA_WINDOW` seconds of scene time
(:func:`camera_limits`), so a long approach or run-out does not shrink the vehicles to a strip;
``"scene"`` holds the whole scene still (every pose of every frame in view). The scene view is
drawn once and only what changes is drawn over it per frame (blitting); the follow view's limits
change with every frame, so each frame is drawn whole.

Frames are at scene times 0, dt, 2 dt, ... after separation and at the end of the run-out;
playback runs at ``fps = speed / dt`` frames per second, so ``speed = 1`` is real time and
the last frame is held for about :data:`HOLD` seconds.
"""

from __future__ import annotations

import logging
import math
from pathlib import Path

import numpy as np

from .errors import ScenarioError
from .figure_options import ANIMATION_LEGENDS, VIEWS
from .geometry import to_world
from .motion.result import time_grid
from .plotting import (Z_REST, Z_TEXT, figure_system, layout_scene_figure, place_labels, plot_scene,
                       replace_scale_bar, scene_drawing)
from .units import Kind, to_unit

__all__ = ["animate_scene", "scene_animation", "SceneAnimation", "animation_formats", "check_animation_path",
           "frame_times", "camera_limits", "MAX_FRAMES", "HOLD", "VIEWS", "ANIMATION_LEGENDS", "CAMERA_WINDOW"]

_log = logging.getLogger("crashsim")

#: Largest number of frames of an animation (a smaller dt is refused).
MAX_FRAMES = 2000

#: How long the last frame is held at the end of playback [s of playback].
HOLD = 1.0

#: GIF frame delays are whole centiseconds and most viewers slow down delays under 20 ms.
_GIF_MIN_DELAY_MS = 20

#: Half-width of the follow camera's smoothing window [s of scene time] (:func:`camera_limits`).
CAMERA_WINDOW = 0.5

#: Margin of the follow camera around the vehicles: a fraction of their box's larger side plus
#: a length [m]; and the narrowest view [m].
_CAMERA_MARGIN, _CAMERA_PAD, _CAMERA_MIN_WIDTH = 0.1, 3.0, 20.0

#: Height over width of the follow view's figure: the median shape of the framed vehicles, within these.
_ASPECTS = (0.5, 1.4)


def animation_formats() -> tuple[str, ...]:
    """File suffixes :func:`animate_scene` can write on this machine.

    ``.gif`` always (matplotlib's PillowWriter); ``.mp4`` only where matplotlib finds ffmpeg
    (``matplotlib.animation.writers.is_available("ffmpeg")``).
    """
    from matplotlib import animation

    return (".gif",) + ((".mp4",) if animation.writers.is_available("ffmpeg") else ())


def check_animation_path(path, *, field: str = "path") -> Path:
    """The output path as a Path, if its format can be written here; cheap, so call it before
    running anything long.

    Parameters
    ----------
    path : str or Path
        Output file; the format follows the suffix (``.gif``, ``.mp4``).
    field : str
        Name of the argument in the error message (``"-o"`` on the command line).

    Raises
    ------
    ScenarioError
        For a suffix other than .gif/.mp4, or .mp4 where ffmpeg is not available; the message
        names the formats that can be written on this machine.
    """
    p = Path(path)
    allowed = animation_formats()
    suffix = p.suffix.lower()
    if suffix not in allowed:
        why = ("ffmpeg, which matplotlib needs for .mp4, is not available on this machine" if suffix == ".mp4"
               else f"unsupported suffix {p.suffix!r}")
        raise ScenarioError(f"cannot write an animation to {str(p)!r}: {why}; formats that can be written here: "
                            f"{', '.join(allowed)}", field=field)
    return p


def frame_times(t_end: float, dt: float, *, field: str = "dt") -> np.ndarray:
    """Frame times 0, dt, 2 dt, ... below ``t_end``, and ``t_end`` itself as the last one [s].

    Parameters
    ----------
    t_end : float
        End of the animation [s] (>= 0).
    dt : float
        Time between frames [s]; > 0 and giving at most :data:`MAX_FRAMES` frames.
    field : str
        Name of ``dt`` in the error message (``"--dt"`` on the command line).

    Returns
    -------
    ndarray, shape (n,)
        Ascending; ``n = ceil(t_end / dt) + 1`` (a multiple of dt within 1e-9 dt of ``t_end``
        is replaced by ``t_end``), 1 if ``t_end == 0``.

    Raises
    ------
    ScenarioError
        If dt is not a positive finite time or gives more than :data:`MAX_FRAMES` frames; the
        message states the smallest dt allowed for this ``t_end``.
    """
    t_end = float(t_end)
    dt_min = t_end / (MAX_FRAMES - 1)
    allowed = (f"allowed dt >= {dt_min:.3g} s (at most {MAX_FRAMES} frames for {t_end:.4g} s)" if dt_min > 0
               else 'allowed a time > 0 s, e.g. "0.05 s"')
    if not (isinstance(dt, (int, float, np.floating)) and math.isfinite(dt) and dt > 0):
        shown = f"{dt:g} s" if isinstance(dt, (int, float, np.floating)) else repr(dt)
        raise ScenarioError(f"time between frames {shown} is not a positive time; {allowed}", field=field)

    times = time_grid(t_end, dt)
    if len(times) > MAX_FRAMES:
        raise ScenarioError(f"time between frames {dt:g} s gives {len(times)} frames; {allowed}", field=field)
    return times


def _decimals(dt: float) -> int:
    """Decimals that show every multiple of ``dt`` exactly (at most 6)."""
    for d in range(7):
        if abs(round(dt, d) - dt) <= 1e-9 * max(1.0, dt):
            return d
    return 6


def camera_limits(times, boxes, aspect: float, *, window: float = CAMERA_WINDOW, pad: float = 0.0,
                  margin: float = _CAMERA_MARGIN, min_width: float = 0.0) -> np.ndarray:
    """Limits of a camera framed on a box that moves from frame to frame, smoothed in time.

    Parameters
    ----------
    times : array_like, shape (n,)
        Frame times [s], ascending.
    boxes : array_like, shape (n, 4)
        What frame k must show: ``(x0, y0, x1, y1)`` [display units].
    aspect : float
        Height over width of the view (the axes box's, equal scale).
    window : float
        Half-width of the smoothing window [s]: the centre is the mean of the boxes' padded
        centres over ``|t_j - t_k| <= window``; the half-width is the largest half-width needed
        within ``window``, then its mean over the window.
    pad : float
        Added on every side of a box [display units], besides ``margin`` times its larger side.
    margin : float
        Fraction of a box's larger side added on every side.
    min_width : float
        Narrowest view [display units].

    Returns
    -------
    ndarray, shape (n, 4)
        ``(x0, x1, y0, y1)`` per frame, each of height ``aspect`` times its width, holding its
        padded box: every half-width averaged for frame k is the largest needed over a window
        that contains frame k, so the mean is never below what frame k needs.
    """
    t = np.asarray(times, dtype=float)
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)
    grow = margin * np.maximum(b[:, 2] - b[:, 0], b[:, 3] - b[:, 1]) + pad
    lo = b[:, :2] - grow[:, None]
    hi = b[:, 2:] + grow[:, None]
    near = np.abs(t[:, None] - t[None, :]) <= window + 1e-12  # (k, j): frame j within the window of frame k
    count = near.sum(axis=1)
    centre = (near @ (0.5 * (lo + hi))) / count[:, None]
    need = np.maximum(np.maximum(centre[:, 0] - lo[:, 0], hi[:, 0] - centre[:, 0]),
                      np.maximum(centre[:, 1] - lo[:, 1], hi[:, 1] - centre[:, 1]) / aspect)
    need = np.maximum(need, 0.5 * min_width)
    widest = np.where(near, need[None, :], -np.inf).max(axis=1)
    half = (near @ widest) / count
    half = np.maximum(half, need)  # the mean of maxima is >= need already; this guards round-off only
    return np.column_stack([centre[:, 0] - half, centre[:, 0] + half,
                            centre[:, 1] - aspect * half, centre[:, 1] + aspect * half])


class SceneAnimation:
    """The figure of an animation and its moving artists, set to any frame by :meth:`frame`.

    Made by :func:`scene_animation`; :func:`animate_scene` writes it to a file.

    Attributes
    ----------
    scene : SceneResult
    fig, ax : matplotlib Figure and Axes
        The scene figure (:func:`crashsim.plotting.plot_scene` without ghosts); in the scene view
        the axis limits are fixed and contain every pose of every frame, in the follow view
        :meth:`frame` sets them to ``limits[k]``.
    times : ndarray, shape (n,)
        Frame times after separation [s].
    outlines : dict of str to matplotlib artist
        Body name -> its moving outline (a Polygon with gid ``"anim:outline:<body>"``; a CG
        marker Line2D with gid ``"anim:cg:<body>"`` for a body without outline data).
    pins : dict of str to matplotlib Line2D
        Vehicle name -> markers at its hitch pins (gid ``"anim:pins:<vehicle>"``).
    clock : matplotlib Text
        ``"t = 1.25 s"`` (gid ``"anim:clock"``).
    view : str
        ``"follow"`` or ``"scene"`` (:data:`VIEWS`).
    limits : ndarray, shape (n, 4) or None
        The follow view's ``(x0, x1, y0, y1)`` per frame [display units] (:func:`camera_limits`);
        None for the scene view, whose limits hold every frame.
    """

    def __init__(self, scene, fig, ax, times, S, outlines, pins, clock, decimals, end_note):
        self.scene = scene
        self.fig = fig
        self.ax = ax
        self.times = times
        self.outlines = outlines
        self.pins = pins
        self.clock = clock
        self._S = S
        self._decimals = decimals
        self._end_note = end_note
        self.before_impact = False  # frames before the impact show the approach (scene_animation sets it)
        self._leaders: list = []  # (leader line, time): leaders of labels that appear at a time
        self.view = "scene"
        self.limits = None

    def __len__(self) -> int:
        return len(self.times)

    def poses(self, t: float) -> dict:
        """Body name -> ``((x, y), heading)`` at scene time ``t`` [s, m, rad].

        From separation on: the dense output ``BodyRunout.sol``, ``t`` clamped to ``[0, t_end]``
        of the body's run (a body at rest stays where it stopped). Before the impact (``t < 0``)
        when the animation shows the approach (``before_impact``): a vehicle with an approach
        from it (:meth:`~crashsim.motion.approach.ApproachResult.pose`); any other at constant
        velocity back from its state at impact (the file gives nothing else about its motion).
        """
        out = {}
        t = float(t)
        before = self.before_impact and t < 0.0
        approaches = self.scene.scenario.approaches if before else {}
        states = self.scene.scenario.states if before else {}
        for vn, r in self.scene.runout.items():
            a = approaches.get(vn)
            for name, br in r.bodies.items():
                if a is not None:
                    out[name] = a.pose(name, t)
                elif before:
                    st = states[name]
                    out[name] = ((float(st.position[0] + st.velocity[0] * t),
                                  float(st.position[1] + st.velocity[1] * t)), float(st.heading + st.yaw_rate * t))
                else:
                    st = np.asarray(br.sol(min(max(t, 0.0), float(r.t_end))), dtype=float)
                    out[name] = ((float(st[0]), float(st[1])), float(st[2]))
        return out

    def clock_text(self, k: int) -> str:
        """The clock of frame ``k``: ``"t = 1.25 s"`` (the last frame of a whole run-out adds
        ", at rest" or ", run stopped")."""
        v, unit = to_unit(float(self.times[k]), Kind.TIME, self._S.system)
        text = f"t = {v:.{self._decimals}f} {unit}" + (", before impact" if v < 0 else "")
        return text + self._end_note if k == len(self.times) - 1 and self._end_note else text

    def frame(self, k: int) -> list:
        """Move the outlines, pins and clock to frame ``k`` (the follow view: the limits too);
        returns the artists changed."""
        S = self._S
        if self.limits is not None:
            x0, x1, y0, y1 = self.limits[k]
            self.ax.set_xlim(x0, x1)
            self.ax.set_ylim(y0, y1)
            replace_scale_bar(self.ax)
        poses = self.poses(self.times[k])
        for name, artist in self.outlines.items():
            pos, heading = poses[name]
            corners = S.body_of[name].outline()
            if corners is None:
                artist.set_data(*([c] for c in S.d(pos)))
            else:
                artist.set_xy(S.d(to_world(corners, pos, heading)))
        for vn, line in self.pins.items():
            xy = _pin_points(S, vn, poses)
            line.set_data(xy[:, 0], xy[:, 1])
        self.clock.set_text(self.clock_text(k))
        t = float(self.times[k])
        for line, tt, xy in S.timed:  # tracks and CG paths as far as the clock has come
            n = int(np.searchsorted(tt, t, side="right"))
            if n == 0:
                line.set_data([], [])
            elif n == len(tt) or tt[n - 1] == t:
                line.set_data(xy[:n, 0], xy[:n, 1])
            else:  # up to the clock, the last point interpolated
                f = (t - tt[n - 1]) / (tt[n] - tt[n - 1])
                end = xy[n - 1] + f * (xy[n] - xy[n - 1])
                line.set_data(np.append(xy[:n, 0], end[0]), np.append(xy[:n, 1], end[1]))
        for artist, t_on in [*S.appear, *self._leaders]:  # outlines at rest once at rest; impacts once they happen
            artist.set_visible(t >= t_on)
        return self.changing

    @property
    def changing(self) -> list:
        """Every artist :meth:`frame` changes (drawn per frame over a fixed background)."""
        S = self._S
        return [*self.outlines.values(), *self.pins.values(), self.clock, *(a for a, _, _ in S.timed),
                *(a for a, _ in S.appear), *(a for a, _ in self._leaders)]


def _pin_points(S, vehicle_name: str, poses: dict) -> np.ndarray:
    """Hitch pins of a vehicle (from the front body's pose) in display units, shape (n, 2)."""
    v = next(x for x in S.sc.vehicles if x.name == vehicle_name)
    pts = [to_world(h.front_point, *poses[v.bodies[i].name]) for i, h in enumerate(v.hitches)]
    return S.d(np.reshape(pts, (-1, 2)))


def _frame_points(S, anim: SceneAnimation) -> np.ndarray:
    """Every outline corner (or CG) and pin of every frame, display units, shape (n, 2)."""
    pts = []
    for k in range(len(anim.times)):
        poses = anim.poses(anim.times[k])
        for name, (pos, heading) in poses.items():
            corners = S.body_of[name].outline()
            pts.append(S.d(pos if corners is None else to_world(corners, pos, heading)))
        for vn in anim.pins:
            pts.append(_pin_points(S, vn, poses))
    return np.vstack([np.reshape(p, (-1, 2)) for p in pts])


def _frame_boxes(S, anim: SceneAnimation) -> np.ndarray:
    """Box of every vehicle's outlines (or CGs) and pins at each frame, display units, shape (n, 4)."""
    out = np.empty((len(anim.times), 4))
    for k in range(len(anim.times)):
        poses = anim.poses(anim.times[k])
        pts = []
        for name, (pos, heading) in poses.items():
            corners = S.body_of[name].outline()
            pts.append(np.reshape(S.d(pos if corners is None else to_world(corners, pos, heading)), (-1, 2)))
        pts = np.vstack(pts)
        out[k] = (*pts.min(axis=0), *pts.max(axis=0))
    return out


def _contain(ax, pts: np.ndarray) -> bool:
    """Widen the axis limits (3 % margin) to contain ``pts`` and lay the scene figure out again
    at the new aspect; True if the limits changed."""
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    if lo[0] >= x0 and lo[1] >= y0 and hi[0] <= x1 and hi[1] <= y1:
        return False
    pad = 0.03 * max(x1 - x0, y1 - y0)
    ax.set_xlim(min(x0, lo[0] - pad), max(x1, hi[0] + pad))
    ax.set_ylim(min(y0, lo[1] - pad), max(y1, hi[1] + pad))
    _relayout(ax)
    return True


def _relayout(ax) -> None:
    """Lay the scene figure out again for the axes' current limits (their aspect), the legend
    where :func:`crashsim.plotting.plot_scene` put it."""
    leg = ax.get_legend()
    fig = ax.figure
    r = fig.canvas.get_renderer()
    # plot_scene put an outside legend under a wide scene, else at the right: keep its choice
    outside = leg is not None and not ax.get_window_extent(r).contains(*leg.get_window_extent(r).get_points()[1])
    below = outside and leg.get_window_extent(r).y1 <= ax.get_window_extent(r).y0 + 1.0
    layout_scene_figure(ax, leg if outside else None, below)


def _check_choice(value, allowed, field: str, what: str) -> str:
    if value not in allowed:
        raise ScenarioError(f"{what} {value!r} is unknown; allowed {', '.join(allowed)}", field=field)
    return value


def scene_animation(scene, *, dt: float = 0.05, system: str | None = None, t_end: float | None = None,
                    approach: bool = True, view: str = "follow", legend: str = "compact") -> SceneAnimation:
    """Build the figure of an animation, set to its first frame (nothing written).

    Parameters
    ----------
    scene : SceneResult
        From :func:`crashsim.reconstruct.run_scene`, with a run-out.
    dt : float
        Scene time between frames [s].
    system : {"SI", "US"}, optional
        Display units of the figure and the clock; default the scenario's.
    t_end : float, optional
        Last frame time [s]; default the end of the run-out (the latest vehicle's ``t_end``).
    approach : bool
        For a scene with approaches: start at the earliest start of braking (negative times,
        every dt up to the impact at 0) and show the approach drawn on the figure; vehicles
        without an approach move at constant velocity then. False: start at the impact.
    view : {"follow", "scene"}
        ``"follow"``: the limits of each frame frame the vehicles (every body's outline and pin)
        at its time, with a margin of 10 % of their box plus 3 m, at least 20 m wide, smoothed
        over :data:`CAMERA_WINDOW` s (:func:`camera_limits`); the figure's size and aspect are
        the scene view's. ``"scene"``: fixed limits holding every pose of every frame.
    legend : {"compact", "none"}
        The compact legend outside the view (under it for a wide scene, at its right for a tall
        one), or none.

    Returns
    -------
    SceneAnimation

    Raises
    ------
    ScenarioError
        If the scene has no run-out, or for a bad ``dt``, ``t_end``, ``system``, ``view`` or
        ``legend``.

    Notes
    -----
    Moving outlines use the colour family of each vehicle in the scene figure (its line colour,
    half transparent, as fill; the dark edge of the outline at rest) and lie above the outlines
    at impact and at rest, below the evidence and the arrows.
    """
    from matplotlib.colors import to_rgba

    _check_choice(view, VIEWS, "view", "view")
    _check_choice(legend, ANIMATION_LEGENDS, "legend", "legend")
    system = figure_system(scene, system)
    if not scene.runout:
        raise ScenarioError(f"scene {scene.scenario.title!r} has no run-out (impact only): nothing moves after "
                            "separation, so there is nothing to animate; add a [runout] section to the scenario",
                            field="runout")
    run_end = max(float(r.t_end) for r in scene.runout.values())
    if t_end is None:
        t_end = run_end
    elif not (isinstance(t_end, (int, float, np.floating)) and math.isfinite(t_end) and t_end > 0):
        raise ScenarioError(f"end of the animation {t_end!r} s is not a positive time; allowed t_end > 0 s "
                            f"(default: the end of the run-out, {run_end:.4g} s)", field="t_end")
    times = frame_times(float(t_end), dt)
    approaches = scene.scenario.approaches if approach else {}
    if approaches:
        t0 = max(a.time_to_impact for a in approaches.values())
        before = -frame_times(t0, dt)[::-1]  # -t0, ..., -2 dt, -dt, 0: multiples of dt back from the impact
        times = np.concatenate([before[:-1], times])
        if len(times) > MAX_FRAMES:
            raise ScenarioError(f"time between frames {dt:g} s gives {len(times)} frames from the start of braking "
                                f"({-t0:.4g} s) to {float(t_end):.4g} s; at most {MAX_FRAMES}", field="dt")

    ax = plot_scene(scene, times=(), system=system, approach=approach, legend=legend, inset=False)
    fig = ax.figure
    S = scene_drawing(ax)
    outlines, pins = {}, {}
    z = Z_REST + 0.5
    for vn, r in scene.runout.items():
        _, line, dark = S.colors(next(iter(r.bodies)))
        for name in r.bodies:
            body = S.body_of[name]
            if body.outline() is None:
                (outlines[name],) = ax.plot([], [], "o", ms=6, color=dark, zorder=z, gid=f"anim:cg:{name}")
            else:
                # stronger than the outlines at impact and at rest under it: half-transparent line colour
                outlines[name] = S.outline(body, (0.0, 0.0), 0.0, gid=f"anim:outline:{name}", fill=line, edge=dark,
                                           lw=2.0, zorder=z)
                outlines[name].set_alpha(None)
                outlines[name].set_facecolor(to_rgba(line, 0.45))
        v = next(x for x in scene.scenario.vehicles if x.name == vn)
        if v.hitches:
            (pins[vn],) = ax.plot([], [], "o", ls="none", ms=4.5, mfc="white", mec=dark, mew=1.0, zorder=z + 0.2,
                                  gid=f"anim:pins:{vn}")
    clock = ax.text(0.985, 0.975, "", transform=ax.transAxes, ha="right", va="top", fontsize=11, family="monospace",
                    zorder=Z_TEXT + 3, gid="anim:clock",
                    bbox=dict(boxstyle="round,pad=0.3", facecolor="white", edgecolor="0.5", lw=0.6, alpha=0.9))
    end_note = ""
    if times[-1] >= run_end:
        end_note = ", at rest" if scene.at_rest else ", run stopped"
    anim = SceneAnimation(scene, fig, ax, times, S, outlines, pins, clock, _decimals(dt), end_note)
    anim.before_impact = bool(approaches)
    if view == "scene":
        _contain(ax, _frame_points(S, anim))
    place_labels(ax, S.texts, [*S.fixed, clock], np.vstack(S.points))  # the scale may have changed; the clock
    timed = [(t, on) for t, on in S.appear if hasattr(t, "xyann")]
    for leader in (a for a in ax.texts if (a.get_gid() or "").startswith("leader:")):
        on = next((on for t, on in timed if np.allclose(t.xy, leader.xy)), None)
        if on is not None:
            anim._leaders.append((leader, on))
    if view == "follow":
        boxes = _frame_boxes(S, anim)
        pad = _CAMERA_PAD * S.k
        # the figure's aspect: the vehicles' usual shape, within 0.5 (wide) to 1.4 (tall)
        size = boxes[:, 2:] - boxes[:, :2]
        grow = 2.0 * (_CAMERA_MARGIN * size.max(axis=1) + pad)
        aspect = float(np.clip(np.median((size[:, 1] + grow) / (size[:, 0] + grow)), _ASPECTS[0], _ASPECTS[1]))
        first = camera_limits(times, boxes, aspect, pad=pad, min_width=_CAMERA_MIN_WIDTH * S.k)[0]
        ax.set_xlim(first[0], first[1])
        ax.set_ylim(first[2], first[3])
        _relayout(ax)
        fig.draw_without_rendering()
        box = ax.get_window_extent(fig.canvas.get_renderer())
        anim.view = "follow"
        anim.limits = camera_limits(times, boxes, box.height / box.width, pad=pad, min_width=_CAMERA_MIN_WIDTH * S.k)
        for t in ax.texts:  # a label whose anchor is in view but whose text reaches past it: cut at the axes
            t.set_clip_box(ax.bbox)
            t.set_clip_on(True)
    anim.frame(0)
    return anim


def animate_scene(scene, path, *, dt: float = 0.05, speed: float = 1.0, system: str | None = None, dpi: int = 100,
                  t_end: float | None = None, approach: bool = True, progress=None, view: str = "follow",
                  legend: str = "compact") -> Path:
    """Write an animation of a scene's run-out to scale: the scene diagram with the bodies moving.

    Parameters
    ----------
    scene : SceneResult
        From :func:`crashsim.reconstruct.run_scene`, with a run-out.
    path : str or Path
        Output file: ``.gif`` (matplotlib's PillowWriter) or ``.mp4`` (FFMpegWriter, only
        where ffmpeg is available; see :func:`animation_formats`). Parent directories are
        created.
    dt : float
        Scene time between frames [s]: frames at 0, dt, 2 dt, ... after separation and at the
        end of the run-out. At most :data:`MAX_FRAMES` frames.
    speed : float
        Playback speed: ``fps = speed / dt`` frames per second, so 1 is real time and 0.5
        slow motion. The last frame is held for about :data:`HOLD` s of playback.
    system : {"SI", "US"}, optional
        Display units of the figure and the clock; default the scenario's.
    dpi : int
        Resolution [dots per inch]; the figure is the scene figure's size (10 in wide).
    t_end : float, optional
        Last frame time [s]; default the end of the run-out (the latest vehicle's ``t_end``).
    approach : bool
        A scene with approaches starts at the earliest start of braking (see
        :func:`scene_animation`); False starts at the impact.
    progress : callable, optional
        ``progress(done, total)`` after each frame is rendered (the command line's progress
        bar); nothing is printed here.
    view : {"follow", "scene"}
        A camera framed on the vehicles at each frame, or the whole scene still (see
        :func:`scene_animation`).
    legend : {"compact", "none"}
        The compact legend outside the view, or none.

    Returns
    -------
    Path
        The file written.

    Raises
    ------
    ScenarioError
        For a format that cannot be written here (checked first, before any drawing), a scene
        without a run-out, or a bad ``dt``, ``speed``, ``dpi``, ``t_end``, ``system``, ``view``
        or ``legend``.

    Notes
    -----
    Each frame shows every body at ``BodyRunout.sol(t)``, ``t`` clamped to the end of its
    vehicle's run (a body at rest stays); before the impact, on the approach (see
    :meth:`SceneAnimation.poses`). GIF frame delays are whole milliseconds rounded to
    centiseconds by the format, and most viewers slow delays under 20 ms down, so keep
    ``speed / dt <= 50`` for a GIF (a warning on the "crashsim" logger says so otherwise).
    Identical consecutive GIF frames (the hold) are stored once with their delays summed.

    Tracks and CG paths grow with the clock, the outlines at rest (with their axles, pins and
    names) appear when their vehicle comes to rest; the delta-v and PDOF arrows, the contact point
    and each impact's number when their impact happens (none on a frame of the approach). A
    GIF of the scene view is rendered by drawing the fixed layer once and, per frame, only what
    changes over it (blitting); the follow view and an MP4 draw each frame whole.
    """
    p = check_animation_path(path)
    if not (isinstance(speed, (int, float, np.floating)) and math.isfinite(speed) and speed > 0):
        raise ScenarioError(f"playback speed {speed!r} is not a positive number; allowed speed > 0 "
                            "(1 = real time)", field="speed")
    if isinstance(dpi, bool) or not isinstance(dpi, (int, np.integer)) or not 10 <= dpi <= 1000:
        raise ScenarioError(f"resolution {dpi!r} dpi is outside the allowed range: an integer 10 to 1000",
                            field="dpi")
    from matplotlib import animation

    anim = scene_animation(scene, dt=dt, system=system, t_end=t_end, approach=approach, view=view, legend=legend)
    fps = float(speed) / float(dt)
    hold = max(math.ceil(HOLD * fps - 1e-9) - 1, 0)
    n = len(anim)
    try:
        p.parent.mkdir(parents=True, exist_ok=True)
        if p.suffix.lower() == ".gif":
            if 1000.0 / fps < _GIF_MIN_DELAY_MS:
                _log.warning("GIF at %.4g frames/s: delays under %d ms are played slower by most viewers; use a "
                             "larger dt or a smaller speed (speed / dt <= 50)", fps, _GIF_MIN_DELAY_MS)
            _write_gif(anim, p, fps, dpi, hold, progress)
        else:
            writer = animation.FFMpegWriter(fps=fps)
            with writer.saving(anim.fig, p, dpi=dpi):
                for k in range(n):
                    anim.frame(k)
                    writer.grab_frame()
                    if progress is not None:
                        progress(k + 1, n)
                for _ in range(hold):
                    writer.grab_frame()
    finally:
        import matplotlib.pyplot as plt

        plt.close(anim.fig)
    return p


def _write_gif(anim: SceneAnimation, path: Path, fps: float, dpi: int, hold: int, progress) -> None:
    """Render the frames by blitting (the fixed layer drawn once, the changing artists over it per
    frame) and write them as a GIF as matplotlib's PillowWriter does (one delay of 1000/fps ms
    each, looping; the last frame repeated ``hold`` times, merged by the encoder)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from PIL import Image

    fig, ax = anim.fig, anim.ax
    old_dpi, old_canvas, old_size = fig.dpi, fig.canvas, fig.get_size_inches().copy()
    canvas = FigureCanvasAgg(fig)
    fig.set_dpi(dpi)
    # whole pixels, rounded (as matplotlib's movie writers size their frames)
    fig.set_size_inches(round(old_size[0] * dpi) / dpi, round(old_size[1] * dpi) / dpi)
    changing = anim.changing if anim.limits is None else []  # the follow view: every frame drawn whole
    try:
        for a in changing:
            a.set_animated(True)
        canvas.draw()  # the fixed layer
        background = canvas.copy_from_bbox(fig.bbox)
        leg, legend_pixels = ax.get_legend(), None
        if anim.limits is not None and leg is not None:  # the follow view: the legend outside the view drawn once
            legend_pixels = canvas.copy_from_bbox(leg.get_window_extent(canvas.get_renderer()).padded(2.0))
            leg.set_visible(False)
        frames = []
        n = len(anim)
        for k in range(n):
            anim.frame(k)
            if anim.limits is not None:
                canvas.draw()
                if legend_pixels is not None:
                    canvas.restore_region(legend_pixels)
            else:
                canvas.restore_region(background)
                for a in sorted(changing, key=lambda a: a.get_zorder()):
                    if a.get_visible():
                        ax.draw_artist(a)
            rgba = np.asarray(canvas.buffer_rgba())
            frames.append(Image.fromarray(rgba[..., :3].copy()))
            if progress is not None:
                progress(k + 1, n)
        frames += [frames[-1]] * hold
        frames[0].save(path, save_all=True, append_images=frames[1:], duration=int(1000 / fps), loop=0)
    finally:
        if ax.get_legend() is not None:
            ax.get_legend().set_visible(True)
        for a in changing:
            a.set_animated(False)
        fig.set_dpi(old_dpi)
        fig.set_size_inches(old_size)
        fig.set_canvas(old_canvas)

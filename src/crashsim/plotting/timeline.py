"""The wheel time line: every wheel's state, its air-brake level, whether it slid, and the steering,
of every vehicle on one time axis from the start of its approach through the impact to rest.

The time axis has the first impact at 0, as the time-distance chart's.  For each wheel a row:

* a bar per stretch of its **set state** (rolling, braked with its fraction, locked, jammed), from
  the approach's wheel settings (its scheduled changes, the speed controller of a recorder's
  table) before the impact and from the run-out's after it (with ``through_impact``, the carried
  on time line);
* the **air-brake level** (0 to 1 of the row's height, a line) where the unit has air brakes;
* a black strip along the bottom where the simulation found the tyre **sliding** (a locked or
  jammed wheel, a braked wheel past its friction, ABS cycling is not sliding).

Below, the steer angle of each vehicle's steered wheels (the path driver's, the recorder's table's or
the file's), one line per vehicle.  It answers the question a report is asked about the braking
sequence: which wheel did what, when, and did the marks agree.
"""

from __future__ import annotations

import math
import textwrap
from dataclasses import replace

import numpy as np

from ..figure_options import NARROW_FIGURE, title_chars
from ..motion.brakes import ramp_level
from ..motion.recorded import wheel_setting_for

__all__ = ["STATE_COLORS", "wheel_rows", "plot_wheel_timeline"]

#: Bar colour of each set state.
STATE_COLORS = {"rolling": "#d9d9d9", "braked": "#6baed6", "locked": "#de2d26", "jammed": "#636363"}


def _stretches(times, values, t_end: float):
    """``[(t0, t1, value)]`` of a step function: each value held from its time to the next (the last to
    ``t_end``), empty stretches left out."""
    ends = list(times[1:]) + [t_end]
    return [(t0, t1, v) for t0, t1, v in zip(times, ends, values) if t1 > t0]


def _bars(stretches, shift: float) -> list:
    """``[(t0, t1, state, text)]``, times moved by ``-shift``: neighbouring stretches of one state merged
    into one bar (a speed controller changes the brake fraction at every update), a braked bar's text its
    fraction or the range of its fractions."""
    merged = []  # [t0, t1, state, lowest brake, highest brake]
    for t0, t1, w in stretches:
        b = w.brake if w.state == "braked" else None
        if merged and merged[-1][2] == w.state and math.isclose(merged[-1][1], t0 - shift):
            last = merged[-1]
            last[1] = t1 - shift
            if b is not None:
                last[3], last[4] = min(last[3], b), max(last[4], b)
        else:
            merged.append([t0 - shift, t1 - shift, w.state, b, b])
    bars = []
    for t0, t1, state, lo, hi in merged:
        if state != "braked":
            text = state
        elif round(lo * 100) == round(hi * 100):
            text = f"braked {lo:.0%}"
        else:
            text = f"braked {lo:.0%}-{hi:.0%}"
        bars.append((t0, t1, state, text))
    return bars


def _controller_friction(a, inp) -> np.ndarray:
    """The road friction at the first body's CG at each of the speed controller's updates (what it divided
    its demand by)."""
    first = next(iter(a.bodies))
    return np.array([float(inp.road.mu_at(np.asarray([a.pose(first, float(t))[0]]))[0])
                     for t in a.speed_control["t"]])


def _controlled(a, mus, times, sets, t_pre: float):
    """The approach's set states with the speed controller's decisions of a recorder's table applied,
    as the controller made them (:func:`crashsim.motion.recorded.wheel_setting_for`, with the friction
    ``mus`` at each update)."""
    ctl = a.speed_control
    t_ctl = ctl["t"] + t_pre  # from the start of the approach
    grid = sorted(set(times) | {float(t) for t in t_ctl if t < t_pre})
    out = []
    for t in grid:
        w = sets[int(np.searchsorted(times, t, side="right")) - 1]
        k = int(np.searchsorted(t_ctl, t + 1e-12, side="right")) - 1
        if w.state in ("rolling", "braked") and k >= 0:
            w = replace(w, **wheel_setting_for(float(ctl["demand"][k]), w.rolling_resistance or 0.0,
                                                float(mus[k]) * w.mu_factor))
        out.append(w)
    return grid, out


def _steps(t, values, t_end: float):
    """A step function's line ``(xs, ys)``: each value held from its time to the next (the last to ``t_end``)."""
    xs, ys = [], []
    for t0, t1, v in _stretches(list(t), list(values), t_end):
        xs += [t0, t1]
        ys += [v, v]
    return xs, ys


def wheel_rows(scene) -> list[dict]:
    """One row per wheel of every movable vehicle, front to rear: ``vehicle``, ``key``, ``label``,
    ``bars`` ([(t0, t1, state, text)] on the scene's time axis: 0 at the first impact), ``brake``
    ((t, level) of its air brakes or None), ``sliding`` ([(t0, t1)] found by the simulation) and
    ``steer`` ((t, angle [rad]) where the wheel is steered, else None)."""
    sc = scene.scenario
    rows = []
    for veh in sc.vehicles:
        if veh.is_barrier:
            continue
        a = (sc.approaches or {}).get(veh.name)
        inp = (sc.approach_inputs or {}).get(veh.name)
        run = (scene.runout or {}).get(veh.name)
        spec_runout = sc.runout.wheels.get(veh.name) if sc.runout is not None else None
        pre = inp.spec.wheels.resolve(veh) if (a is not None and inp is not None) else None
        post = spec_runout.resolve(veh) if (spec_runout is not None and run is not None) else None
        if pre is None and post is None:
            continue
        t_pre = a.time_to_impact if pre is not None else 0.0
        t_end = run.t_end if post is not None else 0.0
        steering = dict(a.steering.get("keys", ())) if (pre is not None and a.steering is not None) else {}
        mus = _controller_friction(a, inp) if (pre is not None and a.speed_control is not None) else None
        for i, spec in enumerate((pre or post).specs):
            bars, brake, steer = [], [], ([], [])
            if pre is not None:
                times = [t for t, _ in pre.phases]
                sets = [ws[i] for _, ws in pre.phases]
                if a.speed_control is not None:
                    times, sets = _controlled(a, mus, times, sets, t_pre)
                bars += _bars(_stretches(times, sets, t_pre), t_pre)
                if spec.key in steering:  # the driver's or the table's angle, held between its updates
                    st = a.steering
                    keep = st["t"] <= 0.0
                    xs, ys = _steps(st["t"][keep].tolist(), st[steering[spec.key]][keep].tolist(), 0.0)
                else:
                    xs, ys = _steps([t - t_pre for t in times], [w.steer for w in sets], 0.0)
                steer[0].extend(xs)
                steer[1].extend(ys)
                if pre.brakes is not None and spec.body in pre.brakes.units:
                    tt = np.linspace(0.0, t_pre, 200)
                    brake.append((tt - t_pre, ramp_level(tt, *pre.brakes.times(spec.body))))
            if post is not None:
                times = [t for t, _ in post.phases]
                sets = [ws[i] for _, ws in post.phases]
                bars += _bars(_stretches(times, sets, t_end), 0.0)
                xs, ys = _steps(times, [w.steer for w in sets], t_end)
                steer[0].extend(xs)
                steer[1].extend(ys)
                if post.brakes is not None and spec.body in post.brakes.units:
                    tt = np.linspace(0.0, t_end, 400)
                    brake.append((tt, ramp_level(tt, *post.brakes.times(spec.body))))
            sliding = []
            for track in ((a.tracks.get(spec.key) if pre is not None else None),
                          (run.wheels.get(spec.key) if post is not None else None)):
                for seg in (track.segments if track is not None else ()):
                    if seg.kind == "sliding":
                        sliding.append((float(seg.t[0]), float(seg.t[-1])))
            rows.append({"vehicle": veh.name, "key": spec.key, "label": spec.label, "bars": bars,
                         "brake": brake or None, "sliding": sliding,
                         "steer": (np.asarray(steer[0]), np.asarray(steer[1]))
                         if np.any(np.abs(steer[1]) > 1e-9) else None})
    return rows


def plot_wheel_timeline(scene, *, width: float = 10.5):
    """The wheel time line figure (module docstring) of a :class:`~crashsim.scene.run.SceneResult`,
    ``width`` inches wide (narrower than :data:`~crashsim.figure_options.NARROW_FIGURE`: the legends go
    under the panels).

    Returns
    -------
    matplotlib Figure
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    rows = wheel_rows(scene)
    steered = [r for r in rows if r["steer"] is not None]
    n = max(len(rows), 1)
    height = 1.2 + 0.24 * n + (1.8 if steered else 0.0)
    ratios = [0.24 * n] + ([1.8] if steered else [])
    narrow = width < NARROW_FIGURE
    height += 0.5 if narrow else 0.0
    fig, axes = plt.subplots(len(ratios), 1, figsize=(width, height), sharex=True, layout="constrained",
                             gridspec_kw={"height_ratios": ratios}, squeeze=False)
    ax = axes[0, 0]
    labels = []
    spans = [t for r in rows for b in r["bars"] for t in b[:2]]
    span = (max(spans) - min(spans)) if spans else 1.0
    for j, r in enumerate(rows):
        y = n - 1 - j
        for t0, t1, state, text in r["bars"]:
            ax.broken_barh([(t0, t1 - t0)], (y + 0.12, 0.76), facecolors=STATE_COLORS[state], edgecolor="white",
                           linewidth=0.5, gid=f"tl:state:{r['key']}:{state}")
            if state == "braked" and (t1 - t0) > 0.12 * span:  # the text fits in the bar
                ax.text(0.5 * (t0 + t1), y + 0.5, text, ha="center", va="center", fontsize=7, color="0.1",
                        clip_on=True)
        for t, lv in r["brake"] or ():
            ax.plot(t, y + 0.12 + 0.76 * lv, "-", color="#08306b", lw=1.0, gid=f"tl:brake:{r['key']}")
        for t0, t1 in r["sliding"]:
            ax.plot([t0, t1], [y + 0.16, y + 0.16], "-", color="black", lw=2.6, solid_capstyle="butt",
                    gid=f"tl:sliding:{r['key']}")
        labels.append(r["label"])
    later = [ev.t for ev in (scene.joint.impact_events() if scene.joint is not None else ())]
    for axx in axes[:, 0]:
        for t in later:
            axx.axvline(t, color="#b30000", lw=0.8, ls=(0, (4, 3)), gid="tl:later-impact")
    ax.set_yticks([n - 1 - j + 0.5 for j in range(len(rows))], labels, fontsize=7.5)
    ax.set_ylim(0, n)
    ax.axvline(0.0, color="#b30000", lw=0.9)
    ax.annotate("impact", (0.0, 1.0), xycoords=("data", "axes fraction"), xytext=(0, 2), textcoords="offset points",
                ha="center", va="bottom", color="#b30000", fontsize=7.5)
    ax.grid(True, axis="x", color="0.9", lw=0.6)
    handles = [Patch(facecolor=c, label=s) for s, c in STATE_COLORS.items()
               if any(b[2] == s for r in rows for b in r["bars"])]
    if any(r["brake"] is not None for r in rows):
        handles.append(Line2D([], [], color="#08306b", lw=1.0, label="air-brake level (0 to 1 of the row)"))
    if later:
        handles.append(Line2D([], [], color="#b30000", lw=0.8, ls=(0, (4, 3)), label="later impact"))
    if any(r["sliding"] for r in rows):
        handles.append(Line2D([], [], color="black", lw=2.6, label="sliding (computed)"))
    if not narrow:
        ax.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0,
                  frameon=False)
    title = f"Wheel states, brakes and steering: {scene.scenario.title}"
    ax.set_title("\n".join(textwrap.wrap(title, title_chars(width, 100), break_on_hyphens=False)), fontsize=10,
                 pad=14)
    bottom = ax
    if steered:
        ax2 = axes[1, 0]
        for r in steered:
            t, ang = r["steer"]
            ax2.plot(t, np.degrees(ang), "-", lw=1.2, label=r["label"], gid=f"tl:steer:{r['key']}")
        ax2.axvline(0.0, color="#b30000", lw=0.9)
        ax2.axhline(0.0, color="0.6", lw=0.6)
        ax2.set_ylabel("steer angle [deg]", fontsize=8)
        ax2.grid(True, color="0.9", lw=0.6)
        if not narrow:
            ax2.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, frameon=False)
        else:
            h2, _ = ax2.get_legend_handles_labels()
            handles += h2
        bottom = ax2
    bottom.set_xlabel("time from the first impact [s]")
    if narrow:
        fig.legend(handles=handles, fontsize=7, loc="outside lower center", ncols=3, frameon=False)
    return fig

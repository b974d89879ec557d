"""The time-distance and speed-time chart of every vehicle (:func:`plot_time_distance`), from the
start of its approach to rest, with the recorder's samples and the impacts.
"""

from __future__ import annotations

import numpy as np

from ..figure_options import NARROW_FIGURE, title_chars
from ..motion.result import path_length
from ..report import fmt
from ..units import Kind, to_unit
from .events import mark_impacts
from .labels import text_box
from .style import EVIDENCE_COLOR, FAMILIES, figure_system, halo, pyplot, wrap

__all__ = ["plot_time_distance"]


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
    plt = pyplot()
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
    colors = {v.name: FAMILIES[i % len(FAMILIES)][2] for i, v in enumerate(movable)}
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
        ax_v.errorbar(t, v, yerr=kv * x.tolerance, fmt="none", ecolor=EVIDENCE_COLOR, elinewidth=0.8, capsize=2.5,
                      alpha=0.6, zorder=6)
        for mask, marker, key in ((~low, "o", "recorded"), (low, "^", "lower")):
            if mask.any():
                ax_v.plot(t[mask], v[mask], marker, ls="none", ms=5.5, mfc="white", mec=EVIDENCE_COLOR, mew=1.4, zorder=7,
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
             (Line2D([], [], ls="none", marker="o", ms=5.5, mfc="white", mec=EVIDENCE_COLOR, mew=1.4),
              "recorded speed (bar: tolerance)", "recorded"),
             (Line2D([], [], ls="none", marker="^", ms=5.5, mfc="white", mec=EVIDENCE_COLOR, mew=1.4),
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
    # once the layout is final (crashsim.plotting.events)
    fig.draw_without_rendering()
    mark_impacts(ax_s, (ax_s, ax_v), impacts, halo=halo(2.0), text_box=text_box)
    ax_s.set_title(wrap(f"Time-distance: {sc.title}", title_chars(width, 100)), fontsize=10)
    return fig

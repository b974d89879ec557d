"""The roll panel of the run-out histories: each body's lateral acceleration against its rollover
threshold, and its load transfer ratio against the wheel lift at 1.

Drawn where the wheel-lift and rollover check ran (``[runout] rollover = true``, level
``load_transfer``: :mod:`crashsim.motion.rollover`), from the indicators it sampled (the values
its events are located on), so the panel and the report's verdict agree.
"""

from __future__ import annotations

import numpy as np

__all__ = ["has_roll_panel", "draw_roll_panel"]


def _histories(scene) -> dict:
    """``{vehicle: history}`` of the run-outs with sampled roll indicators."""
    out = {}
    for vn, r in (scene.runout or {}).items():
        roll = getattr(r, "rollover", None)
        if roll is not None and "history" in roll:
            out[vn] = roll
    return out


def has_roll_panel(scene) -> bool:
    """Whether the histories of ``scene`` get the roll panel (the rollover check ran)."""
    return bool(_histories(scene))


def draw_roll_panel(ax, scene, colors, styles=("-", "--", ":", "-.")):
    """Lateral acceleration |a_y| [g] of every body (solid, left axis) with its rollover threshold
    (a thin dashed line, gid ``"roll:threshold:<body>"``) and |LTR| (the unit load transfer ratio,
    dotted, right axis, gid ``"roll:ltr:<body>"``) with the wheel lift at 1; a cross where a body
    passes its threshold (event ``rollover_threshold``). ``colors`` maps each vehicle to a
    ``(first body, towed bodies)`` colour pair. Returns the right-hand axes.
    """
    twin = ax.twinx()
    peak_g, peak_ltr = 0.0, 0.0
    for vn, roll in _histories(scene).items():
        h = roll["history"]
        t = h["t"]
        first, towed = colors.get(vn, ("0.2", "0.4"))
        for j, (body, thr) in enumerate(roll["thresholds_g"].items()):
            if body not in h:
                continue
            c = first if j == 0 else towed
            ay = np.abs(h[body]["lateral_acceleration_g"])
            ltr = np.abs(h[body]["ltr"])
            ax.plot(t, ay, styles[j % len(styles)], color=c, lw=1.5, label=f"{body} ({vn}): |a_y|",
                    gid=f"roll:ay:{body}")
            ax.axhline(thr, color=c, lw=0.9, ls=(0, (6, 3)), gid=f"roll:threshold:{body}")
            ax.plot([], [], ls=(0, (6, 3)), color=c, lw=0.9, label=f"{body}: rollover threshold {thr:.3g} g")
            twin.plot(t, ltr, ":", color=c, lw=1.1, alpha=0.8, gid=f"roll:ltr:{body}")
            peak_g = max(peak_g, float(ay.max()) if ay.size else 0.0, thr)
            peak_ltr = max(peak_ltr, float(ltr.max()) if ltr.size else 0.0)
        for e in scene.runout[vn].events:
            if e.kind == "rollover_threshold":
                ax.plot(e.t, abs(e.data["lateral_acceleration_g"]), "X", color="#b30000", ms=7, zorder=5,
                        gid=f"roll:passed:{e.data['body']}")
                ax.plot([], [], "X", ls="none", color="#b30000", ms=7, label="threshold passed (report: event)")
    twin.axhline(1.0, color="0.35", lw=0.8, ls="-.", gid="roll:lift")
    ax.plot([], [], ":", color="0.3", lw=1.1, label="|LTR| (right axis)")
    ax.plot([], [], "-.", color="0.35", lw=0.8, label="|LTR| = 1: inner wheels lift")
    # headroom over the highest curve or threshold for the legend at the top
    ax.set_ylim(0.0, 1.5 * peak_g if peak_g > 0 else 1.0)
    twin.set_ylim(0.0, 1.5 * max(1.0, peak_ltr))
    ax.set_ylabel("lateral acceleration [g]")
    twin.set_ylabel("load transfer ratio |LTR|")
    handles, labels = ax.get_legend_handles_labels()
    seen = dict(zip(labels, handles))  # each label once
    ax.legend(list(seen.values()), list(seen), fontsize=7, loc="upper right", ncol=2)
    return twin

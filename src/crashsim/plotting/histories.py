"""The run-out time histories (:func:`plot_histories`): CG speed, yaw rate, articulation, and the
contact-force and roll panels where they apply (:func:`history_panels`).
"""

from __future__ import annotations

import numpy as np

from ..errors import ScenarioError
from ..figure_options import title_chars
from ..units import Kind, convert, format_value as fmt, to_unit
from .loads import draw_roll_panel, has_roll_panel
from .style import FAMILIES, figure_system, pyplot, wrap

__all__ = ["contact_force_line", "history_panels", "IMPACT_LABEL_GAP", "LIMIT_SHOWN_FROM", "plot_histories"]


def history_panels(scene) -> int:
    """Panels of :func:`plot_histories` for ``scene``: 3, one more when bodies stayed in sustained
    contact during the run-out (the contact-force panel), one more where the rollover check ran (the
    lateral-acceleration and load-transfer panel, :func:`crashsim.plotting.loads.draw_roll_panel`)."""
    joint = getattr(scene, "joint", None)
    contact = joint is not None and any(p.sustained for p in joint.pairs)
    return 3 + int(contact) + int(has_roll_panel(scene))


#: Impacts closer in time than this share of the histories' time axis get their labels on separate rows.
IMPACT_LABEL_GAP = 0.03

#: An articulation limit is drawn on the histories' articulation panel once a hitch's articulation
#: reaches this share of it (below, the legend names it without the lines).
LIMIT_SHOWN_FROM = 0.3


def contact_force_line(pair) -> tuple[np.ndarray, np.ndarray]:
    """(t [s], force [N]) of a pair's sustained-contact force as the histories draw it: the samples
    (``pair.t``, ``pair.force``) merged in time with the nodes the pair summary's peak was found on
    (every integrator step and its quarter points while in contact, ``pair.node_t``) and the
    refined peak itself, so that the line reaches ``pair.peak_force`` and shows a contact
    shorter than the sample step. At a time in both, the node comes last (a segment's end)."""
    t = [np.asarray(pair.t, dtype=float), np.asarray(pair.node_t, dtype=float)]
    f = [np.asarray(pair.force, dtype=float), np.asarray(pair.node_force, dtype=float)]
    if np.isfinite(pair.peak_time):
        t.append(np.array([pair.peak_time]))
        f.append(np.array([pair.peak_force]))
    t, f = np.concatenate(t), np.concatenate(f)
    order = np.argsort(t, kind="stable")
    return t[order], f[order]


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
    shows each pair's sustained-contact force on the samples and on the solution's own steps
    (:func:`contact_force_line`), its peak marked with the value the report gives
    (``PairSummary.peak_force`` at ``peak_time``).
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
        fig, axes = pyplot().subplots(n_panels, 1, figsize=(8.0, 2.85 * n_panels), sharex=True, layout="constrained")
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
    family = {v.name: FAMILIES[i % len(FAMILIES)] for i, v in enumerate(movable)}
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
        _, line, dark = family.get(vn, FAMILIES[-1])
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
            t, f = contact_force_line(p)
            (ln,) = ax_f.plot(t, kf * f, styles[k % len(styles)], lw=1.3, label=p.name.replace("|", " \N{EN DASH} "))
            if np.isfinite(p.peak_time):  # the report's peak, where the solution reached it
                ax_f.plot(p.peak_time, kf * p.peak_force, "v", color=ln.get_color(), ms=5,
                          gid=f"histories:peak:{p.name}",
                          label=f"peak {fmt(p.peak_force, 'force', system)} (the report's)")
        ax_f.set_ylabel(f"contact force [{funit}]")
        ax_f.margins(y=0.08)  # the peak's marker inside the panel, not cut at its top
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
    ax_v.set_title(wrap(f"{scene.scenario.title}: run-out after separation",
                         title_chars(float(ax_v.figure.get_size_inches()[0]), 90)), fontsize=10)
    return axes[0].figure if new else axes

"""Barrier sweeps: the paper's Figures 4 and 5 (energy loss and impulse ratio against barrier angle)."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .style import pyplot

__all__ = ["BarrierAxes", "plot_barrier_sweep", "plot_barrier_figures"]


def _new_axes(ax):
    if ax is not None:
        return ax
    _, ax = pyplot().subplots(figsize=(7.0, 5.6), layout="constrained")
    return ax


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
        _, axes = pyplot().subplots(1, 2, figsize=(14.0, 6.0), layout="constrained")
    for ax, sw in zip(axes, (loaded, empty)):
        plot_barrier_sweep(sw, ax, **kwargs)
    return axes[0].figure

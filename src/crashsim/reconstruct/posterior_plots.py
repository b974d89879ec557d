"""Figures of a posterior (:class:`~crashsim.reconstruct.posterior.PosteriorResult`): corner plot and trace plots.

matplotlib (and ``corner``) are imported on first use; every function draws on given axes or
a figure (``None``: a new one) and returns it; nothing calls ``plt.show()``. Values are shown in
the display units of ``system`` (default: the scenario's), converted by :mod:`crashsim.units`
(:func:`crashsim.reconstruct.mc_plots.display_values`: angles in deg, fractions in %).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..units import resolve_system
from .mc_plots import display_values, output_label

__all__ = ["plot_corner", "plot_traces", "save_posterior_figures"]


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _system(post, system):
    return resolve_system(system, post.units, field="system")


def _name(post, label: str) -> str:
    for u in post.unknowns:
        if u.path == label:
            return u.name
    return output_label(label)


def _columns(post, derived: bool):
    """(values (m, k) in display units, axis labels, kinds) of the kept samples: unknowns, then the
    derived quantities that vary."""
    cols, labels = [], []
    for j, u in enumerate(post.unknowns):
        kind = "plain" if u.kind == "dimensionless" else u.kind
        v, unit = (post.samples[:, j], "") if kind == "plain" else display_values(post.samples[:, j], u.kind, post._system)
        cols.append(v)
        labels.append(f"{u.name} [{unit}]" if unit else u.name)
    if derived:
        for k, key in enumerate(post.derived):
            if not (key.startswith("delta_v.") or key == "energy_loss.system"):
                continue  # the corner plot keeps delta-v and the system's energy loss (all are in the report)
            v = post.derived_samples[:, k]
            ok = np.isfinite(v)
            if not ok.all() or float(np.ptp(v)) <= 1e-9 * max(1.0, float(np.max(np.abs(v)))):
                continue
            d, unit = display_values(v, post.kind_of(key), post._system)
            cols.append(d)
            labels.append(f"{output_label(key)} [{unit}]")
    return np.column_stack(cols), labels


class _View:
    """The result with the display system attached (the helpers above read ``_system``)."""

    def __init__(self, post, system):
        self._post = post
        self._system = system

    def __getattr__(self, name):
        return getattr(self._post, name)


def plot_corner(post, *, derived: bool = True, system: str | None = None, fig=None):
    """Corner plot of the kept samples: 1-D histograms with the 2.5/50/97.5 percentiles dashed, and
    2-D densities with the 39 % and 86 % contours (1 and 2 sigma of a 2-D normal); the fit's best
    values (with ``start = "fit"``) marked in red.

    Parameters
    ----------
    post : PosteriorResult
    derived : bool
        Also the derived quantities that vary among delta-v of each body and the system's energy loss.
    system : {"SI", "US"}, optional
    fig : matplotlib Figure, optional

    Returns
    -------
    matplotlib Figure
    """
    import corner

    view = _View(post, _system(post, system))
    data, labels = _columns(view, derived)
    truths = None
    if post.fit is not None:
        truths = []
        for j, u in enumerate(post.unknowns):
            x = post.fit["x"][j]
            truths.append(x if u.kind == "dimensionless" else float(display_values(np.array([x]), u.kind, view._system)[0][0]))
        truths += [None] * (data.shape[1] - len(truths))
    fig = corner.corner(data, labels=labels, quantiles=(0.025, 0.5, 0.975), show_titles=True, title_fmt=".3g",
                        levels=(1 - np.exp(-0.5), 1 - np.exp(-2.0)), smooth=1.0, plot_datapoints=False,
                        fill_contours=False, color="#4C72B0", truths=truths, truth_color="#C44E52", fig=fig,
                        label_kwargs={"fontsize": 9}, title_kwargs={"fontsize": 8})
    sp = post.spec
    head = (f"Posterior ({sp.prior} prior): {post.samples.shape[0]} samples, {_chains(sp, post.steps)}, "
            f"burn-in {sp.burn_steps}, thin {sp.thin}; 2.5/50/97.5 % dashed")
    if post.fit is not None:
        head += "; red: the best fit"
    fig.suptitle(head, fontsize=10)
    return fig


def _chains(spec, steps: int) -> str:
    if spec.sampler == "imh":
        return f"one independence Metropolis-Hastings chain of {steps} steps"
    return f"{spec.walkers} walkers x {steps} steps"


def plot_traces(post, *, system: str | None = None, axes=None, max_walkers: int = 64):
    """Trace of every unknown (each walker a thin line) and of the log-posterior, with the burn-in shaded.

    Returns
    -------
    ndarray of matplotlib Axes
    """
    plt = _plt()
    sysname = _system(post, system)
    n = len(post.unknowns)
    if axes is None:
        fig, axes = plt.subplots(n + 1, 1, figsize=(8.0, 1.8 * (n + 1)), sharex=True, layout="constrained")
        fig.suptitle(f"Traces: {_chains(post.spec, post.steps)}, burn-in ({post.spec.burn_steps} steps) shaded; "
                     f"mean acceptance {np.mean(post.acceptance):.2f}", fontsize=10)
    axes = np.atleast_1d(axes)
    steps = np.arange(post.steps)
    w = min(post.spec.walkers, max_walkers)
    for j, u in enumerate(post.unknowns):
        ax = axes[j]
        if u.kind == "dimensionless":
            v, unit = post.chain[:, :w, j], ""
        else:
            v, unit = display_values(post.chain[:, :w, j], u.kind, sysname)
        ax.plot(steps, v, lw=0.4, alpha=0.5, color="#4C72B0")
        tau = post.tau[j]
        ax.set_ylabel(f"{u.name}\n[{unit}]" if unit else u.name, fontsize=8)
        if np.isfinite(tau):
            ax.text(0.99, 0.95, f"tau = {tau:.0f} steps", transform=ax.transAxes, ha="right", va="top", fontsize=8)
    ax = axes[n]
    lp = np.where(np.isfinite(post.log_prob[:, :w]), post.log_prob[:, :w], np.nan)
    ax.plot(steps, lp, lw=0.4, alpha=0.5, color="#55A868")
    ax.set_ylabel("log posterior", fontsize=8)
    ax.set_xlabel("step")
    for a in axes[:n + 1]:
        a.axvspan(0, post.spec.burn_steps, color="0.9", zorder=0)
    return axes


def save_posterior_figures(post, directory, *, system: str | None = None, dpi: int = 120) -> list[Path]:
    """Write ``posterior_corner.png`` and ``posterior_trace.png`` into ``directory``; return their paths."""
    plt = _plt()
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    out = []
    fig = plot_corner(post, system=system)
    path = directory / "posterior_corner.png"
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    out.append(path)
    axes = plot_traces(post, system=system)
    path = directory / "posterior_trace.png"
    axes[0].figure.savefig(path, dpi=min(dpi, 90))  # thousands of thin lines: a lower resolution keeps the file small
    plt.close(axes[0].figure)
    out.append(path)
    return out

"""Figures of a Monte Carlo result: histograms, rest-position clouds on the scene, tornado chart.

matplotlib is imported on first use (as in :mod:`crashsim.plotting`); every function draws on
given axes (``ax=None``/``axes=None``: a new figure) and returns them; nothing calls
``plt.show()``. Inputs are :class:`~crashsim.reconstruct.montecarlo.MCResult` objects (SI);
display units follow ``system`` (default: the scenario's).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_histograms", "plot_rest_clouds", "plot_tornado", "save_mc_figures", "default_histogram_keys"]


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _system(mc, system):
    if system is not None:
        return system
    if mc.nominal is not None:
        return mc.nominal.scenario.units
    return "SI"


def _display(values, kind: str, system: str):
    """Values and axis label unit in the display system (angles in deg, fractions in %)."""
    from ..units import to_unit

    v = np.asarray(values, dtype=float)
    if kind == "angle":
        return np.degrees(v), "deg"
    if kind == "dimensionless":
        return 100.0 * v, "%"
    if kind == "count":
        return v, "count"
    _, label = to_unit(1.0, kind, system)
    factor = to_unit(1.0, kind, system)[0]
    return v * factor, label


def _label(key: str) -> str:
    what, _, who = key.partition(".")
    names = {"delta_v": "delta-v", "speed": "impact speed", "speed_after": "speed after impact",
             "energy_loss": "energy loss", "rest_x": "rest x", "rest_y": "rest y", "rest_heading": "rest heading",
             "distance": "distance travelled", "delta_v_event": "delta-v, whole event",
             "impacts": "impacts after the first"}
    if what == "impacts":
        return names[what]
    return f"{names.get(what, what)}, {who}" if who else names.get(what, what)


def default_histogram_keys(mc) -> list[str]:
    """Delta-v of every moving body (first impact, and over the whole event where later impacts
    add to it), impact speeds of the vehicles, system energy loss, the number of later impacts;
    outputs that do not vary over the samples (a fixed speed, a car at rest) are left out."""
    keys = [k for k in mc.outputs if k.startswith("delta_v.")]
    keys += [k for k in mc.outputs if k.startswith("delta_v_event.")
             and not np.allclose(mc.outputs[k], mc.outputs.get("delta_v." + k.split(".", 1)[1], np.nan), equal_nan=False)]
    keys += [k for k in mc.outputs if k.startswith("speed.")]
    keys += [k for k in ("energy_loss.system", "impacts.later") if k in mc.outputs]

    def varies(k):
        v = np.asarray(mc.outputs[k], dtype=float)
        v = v[np.isfinite(v)]
        return v.size > 0 and float(np.ptp(v)) > 1e-12 * max(1.0, float(np.max(np.abs(v))))

    return [k for k in keys if varies(k)]


def plot_histograms(mc, keys=None, axes=None, *, system: str | None = None, bins: int = 40):
    """Histogram of each output, with its 5th, 50th and 95th percentiles marked.

    Parameters
    ----------
    mc : MCResult
    keys : sequence of str, optional
        Output keys (``"delta_v.car"``, ``"speed.A"``, ``"rest_x.trailer"``); default
        :func:`default_histogram_keys`.
    axes : sequence of matplotlib Axes, optional
        One per key; a new figure with a grid of panels if None.
    system : {"SI", "US"}, optional
    bins : int

    Returns
    -------
    ndarray of matplotlib Axes
    """
    plt = _plt()
    keys = list(keys) if keys is not None else default_histogram_keys(mc)
    sysname = _system(mc, system)
    if axes is None:
        ncol = min(3, len(keys))
        nrow = int(np.ceil(len(keys) / ncol))
        fig, axes = plt.subplots(nrow, ncol, figsize=(4.0 * ncol, 3.0 * nrow), layout="constrained", squeeze=False)
        for ax in axes.flat[len(keys):]:
            ax.set_visible(False)
        fig.suptitle(f"Monte Carlo: {mc.n_done - mc.n_failed} samples, seed {mc.seed}")
    flat = np.asarray(axes).ravel()
    for ax, key in zip(flat, keys):
        v = mc.outputs[key]
        v = v[np.isfinite(v)]
        d, unit = _display(v, mc.kind_of(key), sysname)
        ax.hist(d, bins=bins, color="#4C72B0", alpha=0.85)
        for q, ls in ((5, ":"), (50, "-"), (95, ":")):
            if d.size:
                ax.axvline(np.percentile(d, q), color="k", ls=ls, lw=1.0)
        ax.set_xlabel(f"{_label(key)} [{unit}]" if unit else _label(key))
        ax.set_ylabel("samples")
        if d.size:
            p5, p50, p95 = np.percentile(d, [5, 50, 95])
            ax.set_title(f"median {p50:.3g}, 90 % in [{p5:.3g}, {p95:.3g}]", fontsize=8)
    return np.asarray(axes)


def plot_rest_clouds(mc, scene=None, ax=None, *, system: str | None = None, max_points: int = 4000,
                     evidence: bool = True):
    """Rest positions of every sample, over the scene diagram of the median scene.

    Parameters
    ----------
    mc : MCResult
    scene : SceneResult, optional
        Scene drawn underneath (default ``mc.nominal``: every input at its median).
    ax : matplotlib Axes, optional
    system : {"SI", "US"}, optional
    max_points : int
        At most this many samples per body are drawn (evenly thinned).
    evidence : bool
        Draw the scene's evidence (measured rest positions, marks) with the diagram.

    Returns
    -------
    matplotlib Axes
    """
    plt = _plt()
    scene = scene if scene is not None else mc.nominal
    sysname = _system(mc, system)
    if scene is not None:
        from ..plotting import plot_scene

        ax = plot_scene(scene, ax=ax, times=(), evidence=evidence, arrows=False, system=sysname, legend=True)
    elif ax is None:
        _, ax = plt.subplots(figsize=(8, 6), layout="constrained")
        ax.set_aspect("equal")
    bodies = [k.split(".", 1)[1] for k in mc.outputs if k.startswith("rest_x.")]
    colors = plt.get_cmap("tab10")
    pts = []
    for j, b in enumerate(bodies):
        x, unit = _display(mc.outputs[f"rest_x.{b}"], "length", sysname)
        y, _ = _display(mc.outputs[f"rest_y.{b}"], "length", sysname)
        ok = np.isfinite(x) & np.isfinite(y)
        x, y = x[ok], y[ok]
        if x.size > max_points:
            sel = np.linspace(0, x.size - 1, max_points).astype(int)
            x, y = x[sel], y[sel]
        pts.append(np.column_stack([x, y]))
        ax.scatter(x, y, s=5, alpha=0.5, color=colors(j % 10), label=f"rest of {b} ({x.size} samples)",
                   zorder=6, linewidths=0)
    if pts:
        allp = np.vstack(pts)
        lo, hi = np.percentile(allp, 0.5, axis=0), np.percentile(allp, 99.5, axis=0)
        x0, x1 = ax.get_xlim()
        y0, y1 = ax.get_ylim()
        pad = 0.05 * max(hi - lo)
        ax.set_xlim(min(x0, lo[0] - pad), max(x1, hi[0] + pad))
        ax.set_ylim(min(y0, lo[1] - pad), max(y1, hi[1] + pad))
    ax.set_title(f"Rest positions of {mc.n_done - mc.n_failed} Monte Carlo samples over the median scene",
                 fontsize=9)
    handles, labels = ax.get_legend_handles_labels()
    ours = [(h, lab) for h, lab in zip(handles, labels) if lab.startswith("rest of") and "samples" in lab]
    if ours:
        leg = ax.get_legend()
        ax.legend([h for h, _ in ours], [lab for _, lab in ours], loc="lower right", fontsize=7, markerscale=4)
        if leg is not None:
            ax.add_artist(leg)
    return ax


def plot_tornado(mc, key: str | None = None, ax=None, *, system: str | None = None):
    """Tornado chart: the output (default the first contact body's delta-v) as each input goes from its
    5th to its 95th percentile with the others at their medians; Spearman rank correlation over
    the samples written beside each bar.

    Returns
    -------
    matplotlib Axes
    """
    plt = _plt()
    if not mc.tornado:
        raise ValueError("this Monte Carlo result has no tornado data (no swings were computed)")
    key = key if key is not None else next(iter(mc.tornado))
    rows = mc.tornado[key]
    sysname = _system(mc, system)
    kind = mc.kind_of(key)
    if ax is None:
        _, ax = plt.subplots(figsize=(7.5, 0.55 * len(rows) + 1.6), layout="constrained")
    base, unit = _display([rows[0]["base"]], kind, sysname)
    base = float(base[0])
    ys = np.arange(len(rows))[::-1]
    for y, r in zip(ys, rows):
        lo, hi = _display([r["low"], r["high"]], kind, sysname)[0]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            continue
        ax.barh(y, lo - base, left=base, color="#4C72B0", height=0.6)
        ax.barh(y, hi - base, left=base, color="#DD8452", height=0.6)
        rho = "" if r["spearman"] is None else f"  rho {r['spearman']:+.2f}"
        ax.text(max(lo, hi, base), y, f"  {abs(hi - lo):.3g} {unit}{rho}", va="center", fontsize=8)
    ax.axvline(base, color="k", lw=1)
    ax.set_yticks(ys, [r["input"] for r in rows])
    ax.set_xlabel(f"{_label(key)} [{unit}]")
    ax.set_title(f"What moves {_label(key)}: each input from its 5th (blue) to its 95th (orange) percentile",
                 fontsize=9)
    ax.margins(x=0.25)
    return ax


def save_mc_figures(mc, directory, *, prefix: str = "mc_", system: str | None = None, dpi: int = 150) -> list[Path]:
    """Write ``<prefix>histograms.png``, ``<prefix>rest_clouds.png`` and ``<prefix>tornado[_<body>].png``."""
    plt = _plt()
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    written = []
    axes = plot_histograms(mc, system=system)
    fig = np.asarray(axes).ravel()[0].figure
    path = directory / f"{prefix}histograms.png"
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
    written.append(path)
    ax = plot_rest_clouds(mc, system=system)
    path = directory / f"{prefix}rest_clouds.png"
    ax.figure.savefig(path, dpi=dpi)
    plt.close(ax.figure)
    written.append(path)
    for key in mc.tornado:
        ax = plot_tornado(mc, key, system=system)
        path = directory / f"{prefix}tornado_{key.split('.', 1)[1]}.png"
        ax.figure.savefig(path, dpi=dpi)
        plt.close(ax.figure)
        written.append(path)
    return written

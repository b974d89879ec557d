"""Figures of a Monte Carlo result: histograms, rest-position clouds on the scene, tornado chart.

matplotlib is imported on first use (as in :mod:`crashsim.plotting`); every function draws on
given axes (``ax=None``/``axes=None``: a new figure) and returns them; nothing calls
``plt.show()``. Inputs are :class:`~crashsim.reconstruct.montecarlo.MCResult` objects (SI);
display units follow ``system`` (default: the scenario's).

Headlines give the share of samples that meet *all* the evidence (``MCResult.evidence_headline``);
the verdict of the scene drawn under the rest clouds (every input at its median) is labelled as
that run's. With ``mc.accept`` (``crashsim mc --accept``) the samples that meet all the evidence
are drawn dark and the others pale, in the histograms and in the rest clouds.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ..plotting import layout_scene_figure, plot_scene, replace_scale_bar, scene_drawing
from ..plotting.layout import scene_legend
from ..units import resolve_system, to_unit

__all__ = ["plot_histograms", "plot_rest_clouds", "plot_tornado", "save_mc_figures", "default_histogram_keys"]


def _plt():
    import matplotlib.pyplot as plt

    return plt


def _system(mc, system):
    """SI or US (any case); default the scenario's units."""
    return resolve_system(system, mc.nominal.scenario.units if mc.nominal is not None else "SI", field="system")


def display_values(values, kind: str, system: str):
    """Values and axis label unit in the display system (angles in deg, fractions in %)."""
    v = np.asarray(values, dtype=float)
    if kind == "angle":
        return np.degrees(v), "deg"
    if kind == "dimensionless":
        return 100.0 * v, "%"
    if kind == "count":
        return v, "count"
    if kind == "ratio":
        return v, "ratio"
    _, label = to_unit(1.0, kind, system)
    factor = to_unit(1.0, kind, system)[0]
    return v * factor, label


#: Blue of the histograms; with acceptance, its pale (rejected) and dark (accepted) versions.
_BLUE, _PALE, _DARK = "#4C72B0", "#c6d3e8", "#1b2f5c"


def _shade(color, f: float):
    """``color`` mixed with black (f < 0, darker) or white (f > 0, paler) by |f|."""
    from matplotlib.colors import to_rgb

    c = np.asarray(to_rgb(color))
    return tuple(c * (1 + f) if f < 0 else c + (1 - c) * f)


def _summary(d: np.ndarray) -> str:
    p5, p50, p95 = np.percentile(d, [5, 50, 95])
    return f"median {p50:.3g}, 90 % in [{p5:.3g}, {p95:.3g}]"


def _headline(mc) -> str:
    """Figure headline: seed and the share of samples meeting all the evidence."""
    return f"Monte Carlo, seed {mc.seed}: {mc.evidence_headline()}"


def output_label(key: str) -> str:
    """Axis label of a Monte Carlo output key such as ``"delta_v.car"`` ('delta-v of car')."""
    what, _, who = key.partition(".")
    names = {"delta_v": "delta-v", "speed": "impact speed", "speed_after": "speed after impact",
             "energy_loss": "energy loss", "rest_x": "rest x", "rest_y": "rest y", "rest_heading": "rest heading",
             "distance": "distance travelled", "delta_v_event": "delta-v, whole event",
             "impacts": "impacts after the first", "speed_at_braking": "speed at the start of braking",
             "time_to_impact": "time from braking to impact", "braking_distance": "braking distance",
             "perception_distance": "distance from perception to impact", "mu": "impulse ratio mu",
             "mu_over_mu_max": "mu / mu_max"}
    if what == "impacts":
        return names[what]
    return f"{names.get(what, what)}, {who}" if who else names.get(what, what)


def default_histogram_keys(mc) -> list[str]:
    """Delta-v of every moving body (first impact, and over the whole event where later impacts
    add to it), impact speeds of the vehicles, the speed at the start of braking and the distance
    from perception of vehicles with an approach, system energy loss, the number of later impacts;
    outputs that do not vary over the samples (a fixed speed, a car at rest) are left out."""
    keys = [k for k in mc.outputs if k.startswith("delta_v.")]
    keys += [k for k in mc.outputs if k.startswith("delta_v_event.")
             and not np.allclose(mc.outputs[k], mc.outputs.get("delta_v." + k.split(".", 1)[1], np.nan), equal_nan=False)]
    keys += [k for k in mc.outputs if k.startswith("speed.")]
    keys += [k for k in mc.outputs if k.startswith(("speed_at_braking.", "perception_distance."))]
    keys += [k for k in ("energy_loss.system", "impacts.later") if k in mc.outputs]

    def varies(k):
        v = np.asarray(mc.outputs[k], dtype=float)
        v = v[np.isfinite(v)]
        return v.size > 0 and float(np.ptp(v)) > 1e-12 * max(1.0, float(np.max(np.abs(v))))

    return [k for k in keys if varies(k)]


def plot_histograms(mc, keys=None, axes=None, *, system: str | None = None, bins: int = 40):
    """Histogram of each output, with its 5th, 50th and 95th percentiles marked.

    The height of a bar is its share of *all* the samples (``mc.n_done``, a sample without a
    value for the output included), in %: the y-axis label says so and names the number. With
    ``mc.accept`` the samples that meet all the evidence are drawn dark over the pale histogram
    of all samples on the same bins and the same scale (59 accepted samples of 10 000 are bars of
    at most 0.59 %, never a 100 % bar), with their own percentiles (dashed).

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
        fig.suptitle(_headline(mc) + ("\nsamples meeting all the evidence dark, the others pale" if mc.accept else ""))
    flat = np.asarray(axes).ravel()
    meets = np.asarray(mc.meets_all, dtype=bool) if mc.accept and len(mc.meets_all) == mc.n_done else None
    n_all = mc.n_done
    for ax, key in zip(flat, keys):
        v = mc.values(key)  # an angle on its arc around the circular mean (as its percentiles)
        ok = np.isfinite(v)
        d, unit = display_values(v[ok], mc.kind_of(key), sysname)
        ax.set_xlabel(f"{output_label(key)} [{unit}]" if unit else output_label(key))
        # every bar is its share of all the samples (a sample without a value counts in the whole)
        ax.set_ylabel(f"share of all {n_all} samples [%]")
        if not d.size:
            continue
        share = np.full(d.size, 100.0 / max(n_all, d.size))
        novalue = "" if d.size == n_all else f"; {n_all - d.size} samples without a value"
        edges = np.histogram_bin_edges(d, bins=bins)
        if meets is None:
            ax.hist(d, bins=edges, weights=share, color=_BLUE, alpha=0.85)
            for q, ls in ((5, ":"), (50, "-"), (95, ":")):
                ax.axvline(np.percentile(d, q), color="k", ls=ls, lw=1.0)
            ax.set_title(_summary(d) + novalue, fontsize=8)
            continue
        inside = meets[ok]
        acc = d[inside]
        ax.hist(d, bins=edges, weights=share, color=_PALE, label=f"all ({d.size})")
        if acc.size:
            ax.hist(acc, bins=edges, weights=share[inside], color=_DARK, alpha=0.75,
                    label=f"meet all evidence ({acc.size}, {100.0 * acc.size / n_all:.3g} %)")
        for q, ls in ((5, ":"), (50, "-"), (95, ":")):
            ax.axvline(np.percentile(d, q), color="0.55", ls=ls, lw=1.0)
            if acc.size:
                ax.axvline(np.percentile(acc, q), color=_DARK, ls="--" if q == 50 else ":", lw=1.2)
        ax.set_title(f"all: {_summary(d)}{novalue}\naccepted: " + (_summary(acc) if acc.size else "none"), fontsize=7.5)
        ax.legend(fontsize=6.5, loc="best", framealpha=0.8)
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
        Draw the scene's evidence (measured rest positions, marks) with the diagram; its
        verdict there is the median scene's, and labelled so.

    The axes limits hold the scene and every sample's rest position with a margin (no sample
    is clipped). With ``mc.accept`` the samples that meet all the evidence are drawn dark
    (all of them, never thinned) and the others pale.

    Returns
    -------
    matplotlib Axes
    """
    plt = _plt()
    scene = scene if scene is not None else mc.nominal
    sysname = _system(mc, system)
    new = ax is None
    if scene is not None:
        ax = plot_scene(scene, ax=ax, times=(), evidence=evidence, arrows=False, system=sysname, legend=True)
    elif ax is None:
        _, ax = plt.subplots(figsize=(8, 6), layout="constrained")
        ax.set_aspect("equal")
    leg = ax.get_legend()
    verdict = leg.get_title().get_text() if leg is not None else ""
    if verdict.startswith("Evidence:"):  # plot_scene's verdict is the median scene's, not the samples'
        leg.get_title().set_text("Median scene (every input at its median): "
                                 + verdict.removeprefix("Evidence: ").replace("items", "evidence items"))
    bodies = [k.split(".", 1)[1] for k in mc.outputs if k.startswith("rest_x.")]
    colors = plt.get_cmap("tab10")
    meets = np.asarray(mc.meets_all, dtype=bool) if mc.accept and len(mc.meets_all) == mc.n_done else None
    pts = []
    for j, b in enumerate(bodies):
        x, unit = display_values(mc.outputs[f"rest_x.{b}"], "length", sysname)
        y, _ = display_values(mc.outputs[f"rest_y.{b}"], "length", sysname)
        ok = np.isfinite(x) & np.isfinite(y)
        acc = meets[ok] if meets is not None else np.zeros(int(ok.sum()), dtype=bool)
        x, y = x[ok], y[ok]
        pts.append(np.column_stack([x, y]))
        rx, ry = x[~acc], y[~acc]
        if rx.size > max_points:
            sel = np.linspace(0, rx.size - 1, max_points).astype(int)
            rx, ry = rx[sel], ry[sel]
        color = colors(j % 10)
        if meets is None:
            ax.scatter(rx, ry, s=5, alpha=0.5, color=color, label=f"rest of {b} ({rx.size} samples)",
                       zorder=6, linewidths=0)
            continue
        ax.scatter(rx, ry, s=5, alpha=0.6, color=_shade(color, 0.45), zorder=6, linewidths=0,
                   label=f"rest of {b}: {int((~acc).sum())} samples not meeting all evidence (pale)")
        ax.scatter(x[acc], y[acc], s=14, alpha=1.0, color=_shade(color, -0.35), zorder=7, linewidths=0.4,
                   edgecolors="white", label=f"rest of {b}: {int(acc.sum())} samples meeting all evidence (dark)")
    allp = np.vstack(pts) if pts else np.zeros((0, 2))
    if len(allp):  # every sample inside the limits, with a margin (the scene's extent is in them already)
        (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        pad = 0.03 * max(hi[0] - lo[0], hi[1] - lo[1], x1 - x0, y1 - y0)
        ax.set_xlim(min(x0, lo[0] - pad), max(x1, hi[0] + pad))
        ax.set_ylim(min(y0, lo[1] - pad), max(y1, hi[1] + pad))
    ax.set_title(f"Rest positions over the median scene. {_headline(mc)}", fontsize=9)
    if scene is not None:
        _lay_out_clouds(ax, [c for c in ax.collections if c.get_label().startswith("rest of")], new)
    elif pts:
        ax.legend(loc="best", fontsize=7)
    return ax


def _lay_out_clouds(ax, clouds, new: bool) -> None:
    """The scene figure laid out again for what :func:`plot_rest_clouds` added to it: the sample
    clouds as entries of the scene's legend (outside the axes, where they cover neither the
    scale bar nor the scene), the longer title and legend title, and the limits widened to the
    clouds; a new figure sized to hold them all (:func:`layout_scene_figure`)."""
    from matplotlib.lines import Line2D

    S = scene_drawing(ax)
    old = ax.get_legend()
    if S is None or old is None:
        return
    fig = ax.figure
    r = fig.canvas.get_renderer()
    below = old.get_window_extent(r).y1 <= ax.get_window_extent(r).y0  # plot_scene's legend: under or at the right
    title = old.get_title().get_text()
    old.remove()
    for c in clouds:  # a legend marker of the scatter's colour, opaque and of one size
        S.legend_entry(c.get_label(), Line2D([], [], ls="none", marker="o", markersize=5, markeredgewidth=0,
                                             markerfacecolor=c.get_facecolor()[0][:3]))
    leg = scene_legend(S, "outside", below)
    if title:
        leg.get_title().set_text(title)
        leg.set_alignment("left")  # the entries under the start of the (longer) title, not centred under it
    if new:
        layout_scene_figure(ax, leg, below, width=S.width)
    replace_scale_bar(ax)


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
    base, unit = display_values([rows[0]["base"]], kind, sysname)
    base = float(base[0])
    ys = np.arange(len(rows))[::-1]
    for y, r in zip(ys, rows):
        lo, hi = display_values([r["low"], r["high"]], kind, sysname)[0]
        if not (np.isfinite(lo) and np.isfinite(hi)):
            continue
        ax.barh(y, lo - base, left=base, color="#4C72B0", height=0.6)
        ax.barh(y, hi - base, left=base, color="#DD8452", height=0.6)
        rho = "" if r["spearman"] is None else f"  rho {r['spearman']:+.2f}"
        ax.text(max(lo, hi, base), y, f"  {abs(hi - lo):.3g} {unit}{rho}", va="center", fontsize=8)
    ax.axvline(base, color="k", lw=1)
    ax.set_yticks(ys, [r["input"] for r in rows])
    ax.set_xlabel(f"{output_label(key)} [{unit}]")
    ax.set_title(f"What moves {output_label(key)}: each input from its 5th (blue) to its 95th (orange) percentile",
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

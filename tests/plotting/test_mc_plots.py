"""Monte Carlo figures under Agg: headlines give the share meeting all the evidence, rest clouds are
never clipped, and with acceptance the accepted samples are drawn apart (dark) from the others (pale)."""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402

from crashsim.reconstruct.mc_plots import (display_values, output_label, plot_histograms, plot_rest_clouds,  # noqa: E402
                                           save_mc_figures)
from crashsim.reconstruct.montecarlo import monte_carlo  # noqa: E402
from crashsim.reconstruct.overrides import default_engine  # noqa: E402
from crashsim.schema import load_toml  # noqa: E402

FILE = Path(__file__).resolve().parents[2] / "scenarios" / "fit" / "intersection_fit.toml"
N = 10


@pytest.fixture(scope="module")
def mc():
    return monte_carlo(load_toml(FILE), n=N, engine=default_engine(), workers=1, progress=False, file=str(FILE))


@pytest.fixture(scope="module")
def mc_accept(mc):
    """The same samples with acceptance on and a known accepted set (samples 1, 4 and 7)."""
    meets = np.zeros(mc.n_done, dtype=bool)
    meets[[1, 4, 7]] = True
    return dataclasses.replace(mc, accept=True, meets_all=meets)


def _luminance(rgb) -> float:
    return float(np.dot(to_rgb(rgb), [0.2126, 0.7152, 0.0722]))


def test_headline_is_the_share_meeting_all_the_evidence(mc):
    k = mc.n_evidence
    assert k == 9
    expected = f"{100 * mc.n_accepted / N:.3g} % of {N} samples meet all {k} evidence items"
    assert mc.evidence_headline() == expected
    axes = plot_histograms(mc)
    assert expected in axes.ravel()[0].figure._suptitle.get_text()
    plt.close("all")
    ax = plot_rest_clouds(mc)
    assert expected in ax.get_title()
    assert "within tolerance" not in ax.get_title()
    # the scene underneath is the median run: its verdict says so
    titles = [a.get_title().get_text() for a in ax.get_children() if isinstance(a, matplotlib.legend.Legend)]
    assert any(t.startswith("Median scene (every input at its median): ") for t in titles), titles
    assert not any(t.startswith("Evidence:") for t in titles)
    plt.close("all")


def test_rest_clouds_are_never_clipped(mc):
    out = dict(mc.outputs)
    far = out["rest_x.tractor"].copy()
    far[3] += 60.0  # a sample far beyond the scene
    low = out["rest_y.car"].copy()
    low[5] -= 25.0
    out["rest_x.tractor"], out["rest_y.car"] = far, low
    ax = plot_rest_clouds(dataclasses.replace(mc, outputs=out))
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    for key in ("tractor", "trailer", "car"):
        x, y = out[f"rest_x.{key}"], out[f"rest_y.{key}"]
        assert np.all(x > x0) and np.all(x < x1) and np.all(y > y0) and np.all(y < y1), key
    # with a margin
    assert x1 - far.max() > 0.5 and low.min() - y0 > 0.5
    plt.close("all")


def test_accepted_samples_are_drawn_dark_the_others_pale(mc_accept):
    ax = plot_rest_clouds(mc_accept)
    clouds = [c for c in ax.collections if c.get_label().startswith("rest of")]
    acc = [c for c in clouds if "meeting all evidence (dark)" in c.get_label()]
    rej = [c for c in clouds if "not meeting all evidence (pale)" in c.get_label()]
    assert len(acc) == len(rej) == 3
    for a, r in zip(acc, rej):
        assert len(a.get_offsets()) == 3 and len(r.get_offsets()) == N - 3
        assert _luminance(a.get_facecolor()[0][:3]) < _luminance(r.get_facecolor()[0][:3]) - 0.2
    # the accepted tractor rests are the samples 1, 4 and 7
    tractor = next(c for c in acc if "tractor" in c.get_label())
    assert np.allclose(np.sort(tractor.get_offsets()[:, 0]), np.sort(mc_accept.outputs["rest_x.tractor"][[1, 4, 7]]))
    plt.close("all")

    axes = plot_histograms(mc_accept)
    for a in axes.ravel():
        if not a.get_visible():
            continue
        bars = a.containers
        assert len(bars) == 2  # all samples (pale), then the accepted ones (dark) on the same bins
        # both groups as their share of ALL the samples: the accepted bars are the accepted samples'
        # histogram in % of the N samples (3 of 10: at most 30 %), the pale ones sum to 100 %
        key = next(k for k in mc_accept.outputs if a.get_xlabel().startswith(output_label(k)))
        v = mc_accept.outputs[key]
        edges = [p.get_x() for p in bars[0]] + [bars[0][-1].get_x() + bars[0][-1].get_width()]
        shown = display_values(v, mc_accept.kind_of(key), "SI")[0]  # in the figure's units
        counts, _ = np.histogram(shown[[1, 4, 7]], bins=edges)
        assert np.allclose([p.get_height() for p in bars[1]], 100.0 * counts / N)
        assert sum(p.get_height() for p in bars[1]) == pytest.approx(100.0 * 3 / N)
        assert a.get_ylabel() == f"share of all {N} samples [%]"
        assert sum(p.get_height() for p in bars[0]) == pytest.approx(100.0)
        assert _luminance(bars[1][0].get_facecolor()[:3]) < _luminance(bars[0][0].get_facecolor()[:3]) - 0.3
        assert "accepted: median" in a.get_title()
    plt.close("all")


def test_no_accepted_sample_draws_and_says_so(mc, tmp_path):
    none = dataclasses.replace(mc, accept=True, meets_all=np.zeros(mc.n_done, dtype=bool))
    assert none.evidence_headline().startswith(f"0 % of {N} samples meet all")
    paths = save_mc_figures(none, tmp_path)
    assert all(p.stat().st_size > 10_000 for p in paths)
    axes = plot_histograms(none)
    assert "accepted: none" in axes.ravel()[0].get_title()
    assert "NO sample meets all the evidence" in none.report()
    plt.close("all")


def test_one_accepted_sample_is_one_sample_high_not_a_full_bar(mc):
    """One accepted sample of N is a bar of 100/N % of all samples (it was drawn as a 100 % bar)."""
    one = np.zeros(mc.n_done, dtype=bool)
    one[6] = True
    axes = plot_histograms(dataclasses.replace(mc, accept=True, meets_all=one), keys=["delta_v.car", "speed.A"])
    for a in axes.ravel():
        pale, dark = a.containers
        heights = np.array([p.get_height() for p in dark])
        assert heights.max() == pytest.approx(100.0 / N) and np.count_nonzero(heights) == 1
        assert sum(p.get_height() for p in pale) == pytest.approx(100.0)
        assert a.get_ylim()[1] < 100.0  # the axis is scaled to all samples' bars, not to a lone 100 % bar
        assert "all" in a.get_ylabel() and str(N) in a.get_ylabel()
    plt.close("all")


def test_histograms_without_acceptance_are_shares_of_all_samples(mc):
    """Without acceptance the bars are shares of all samples too; a sample without a value (NaN) still
    counts in the whole, so the bars then sum to less than 100 % and the title says how many lack one."""
    out = dict(mc.outputs)
    v = out["delta_v.car"].copy()
    v[[0, 2]] = np.nan
    out["delta_v.car"] = v
    axes = plot_histograms(dataclasses.replace(mc, outputs=out), keys=["delta_v.car", "speed.A"])
    gap, full = axes.ravel()
    assert sum(p.get_height() for p in gap.containers[0]) == pytest.approx(100.0 * (N - 2) / N)
    assert "2 samples without a value" in gap.get_title()
    assert sum(p.get_height() for p in full.containers[0]) == pytest.approx(100.0)
    assert full.get_ylabel() == gap.get_ylabel() == f"share of all {N} samples [%]"
    plt.close("all")


TALL = Path(__file__).resolve().parents[1] / "data" / "pinned_car_north.toml"


def _inside(inner, outer, slack: float = 1.0) -> bool:
    return (inner.x0 >= outer.x0 - slack and inner.x1 <= outer.x1 + slack and inner.y0 >= outer.y0 - slack
            and inner.y1 <= outer.y1 + slack)


def _clouds_figure_is_whole(ax):
    """The title and the one legend inside the figure, the legend outside the axes and holding the sample
    entries, and the scale bar covered by no legend."""
    fig = ax.figure
    fig.draw_without_rendering()
    r = fig.canvas.get_renderer()
    page = fig.bbox
    assert _inside(ax.title.get_window_extent(r), page), (ax.title.get_window_extent(r), page)
    legends = [a for a in ax.get_children() if isinstance(a, matplotlib.legend.Legend)]
    assert len(legends) == 1  # the sample clouds are entries of the scene's legend, not a second one over the scene
    leg = legends[0]
    texts = [t.get_text() for t in leg.get_texts()]
    assert any(t.startswith("rest of ") and "samples" in t for t in texts), texts
    lb = leg.get_window_extent(r)
    assert _inside(lb, page), (lb, page)
    assert not lb.overlaps(ax.get_window_extent(r))
    bar = next(a for a in ax.artists if a.get_gid() == "scalebar")
    assert not lb.overlaps(bar.get_window_extent(r))
    return texts


def test_rest_clouds_of_a_tall_scene_are_whole(tmp_path):
    """A tall scene (its legend at the right): the longer title and legend title of the Monte Carlo
    figure are not cut at the figure's edge, the samples' legend covers no scale bar, and the median
    road friction (0.723923...) is written to three digits."""
    mc = monte_carlo(load_toml(TALL), n=6, engine=default_engine(), workers=1, progress=False, file=str(TALL))
    ax = plot_rest_clouds(mc)
    texts = _clouds_figure_is_whole(ax)
    assert "road surface outside the zones: f = 0.724" in texts, texts
    plt.close("all")


def test_rest_clouds_of_a_wide_scene_are_whole(mc):
    _clouds_figure_is_whole(plot_rest_clouds(mc))
    plt.close("all")

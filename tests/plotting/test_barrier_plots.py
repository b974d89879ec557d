"""Smoke tests of the barrier-sweep figures (paper Figs. 4 and 5) under the Agg backend."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from crashsim.impact.sweeps import barrier_angle_sweep  # noqa: E402
from crashsim.plotting import BarrierAxes, plot_barrier_figures, plot_barrier_sweep  # noqa: E402


@pytest.fixture(scope="module")
def sweeps():
    return {t: barrier_angle_sweep(t, n=91) for t in ("loaded", "empty")}


def test_sweep_plot_new_figure(sweeps, tmp_path):
    axes = plot_barrier_sweep(sweeps["loaded"])
    assert isinstance(axes, BarrierAxes)
    ax, axm = axes
    assert ax.figure is axm.figure
    assert ax.get_title().startswith("Fig. 4") and "fully loaded trailer" in ax.get_title()
    assert "[deg]" in ax.get_xlabel()
    assert "[%]" in ax.get_ylabel()
    assert axm.get_ylabel()
    styles = {ln.get_linestyle() for ln in ax.get_lines() if len(ln.get_xdata())}
    assert {"-", "--"} <= styles  # solid while sticking, dashed while sliding
    assert len(axm.get_lines()) == 3  # |mu_max| and |mu| = f for two f
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("f = 0.2" in s for s in labels) and any("f = 0.6" in s for s in labels)
    assert any(g.get_visible() for g in ax.get_xgridlines())
    out = tmp_path / "fig4.png"
    ax.figure.savefig(out)
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000


def test_sweep_plot_on_given_axes_with_empty_title(sweeps):
    fig, ax = plt.subplots()
    axes = plot_barrier_sweep(sweeps["empty"], ax=ax)
    assert axes.energy is ax
    assert len(fig.axes) == 2
    assert ax.get_title().startswith("Fig. 5") and "empty trailer" in ax.get_title()
    # energy loss drawn in percent within the axis limits
    y = np.concatenate([ln.get_ydata() for ln in ax.get_lines() if len(ln.get_xdata())])
    y = y[np.isfinite(y)]
    assert 0.0 <= y.min() and y.max() <= 100.0 and y.max() > 99.0


def test_two_panel_figure_written(sweeps, tmp_path):
    fig = plot_barrier_figures(sweeps["loaded"], sweeps["empty"])
    assert len(fig.axes) == 4  # two panels, each with its twin mu axis
    out = tmp_path / "figure4_5.png"
    fig.savefig(out, dpi=60)
    assert out.exists() and out.stat().st_size > 10_000


def test_custom_title_and_contact_rule_shown():
    sw = barrier_angle_sweep("loaded", n=31, contact="corner")
    ax, _ = plot_barrier_sweep(sw, title="my title")
    assert ax.get_title() == "my title"
    assert "corner" in ax.get_legend().get_title().get_text()


def test_core_does_not_import_matplotlib():
    """crashsim.plotting is the only package that imports matplotlib, and only when used."""
    code = ("import sys, crashsim, crashsim.impact.sweeps, crashsim.plotting; "
            "print('matplotlib' in sys.modules)")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         env={**__import__("os").environ, "MPLBACKEND": "Agg"})
    assert res.stdout.strip() == "False"

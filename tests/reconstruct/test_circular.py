"""Angles are summarised on their arc around the circular mean, not as numbers in (-180, 180].

A rest heading whose samples run continuously from 191 to 231 deg (wrapped: -169 to -129 deg)
was reported as p5 -139.2 deg, p50 108.9 deg: percentiles of a cloud split in two by the wrap
(here, a cloud across +-180 deg: 160..200 deg).
"""

from __future__ import annotations

import json
import math

import matplotlib
import numpy as np
import pytest

from crashsim.geometry import circular_mean, circular_percentiles, unwrap_about_mean, wrap_angle
from crashsim.reconstruct.montecarlo import UncertaintySpec, load_results

matplotlib.use("Agg")

SPEC = {"samples": 41, "seed": 1, "inputs": [
    {"path": "runout.road_friction", "distribution": "uniform", "lower": "0.65", "upper": "0.85"}]}


def _deg(a):
    return np.degrees(a)


def test_cloud_from_191_to_231_deg():
    a = wrap_angle(np.radians(np.linspace(191.0, 231.0, 41)))
    assert a.min() < -2.9 and a.max() < -2.2  # wrapped: -169 to -129 deg
    p5, p50, p95 = _deg(circular_percentiles(a, [5, 50, 95]))
    assert p5 == pytest.approx(-167.0, abs=1e-9) and p50 == pytest.approx(-149.0, abs=1e-9)
    assert p95 == pytest.approx(-131.0, abs=1e-9)
    assert _deg(circular_mean(a)) == pytest.approx(-149.0, abs=1e-9)


def test_cloud_across_the_wrap_is_one_cloud():
    raw = np.radians(np.linspace(160.0, 200.0, 41))
    a = wrap_angle(raw)  # 160..180, then -180..-160
    p5, p50, p95 = _deg(circular_percentiles(a, [5, 50, 95]))
    assert p5 <= p50 <= p95
    assert abs(p50) == pytest.approx(180.0, abs=1e-9)
    assert p95 - p5 == pytest.approx(36.0, abs=1e-9)  # linear on the wrapped numbers: 356 deg wide
    u = unwrap_about_mean(a)
    assert np.ptp(u) == pytest.approx(math.radians(40.0), abs=1e-12)
    assert np.allclose(wrap_angle(u), a)  # the same directions


def test_a_cloud_away_from_the_wrap_keeps_its_linear_statistics():
    a = np.radians(np.linspace(10.0, 50.0, 41))
    assert np.allclose(circular_percentiles(a, [5, 50, 95]), np.percentile(a, [5, 50, 95]), atol=1e-12)


def _results_file(tmp_path, headings_deg):
    spec = UncertaintySpec.from_dict(SPEC)
    header = {"format": "crashsim-mc/1", "hash": "x", "seed": 1, "n": len(headings_deg), "engine": "compiled",
              "spec": spec.to_dict(), "paths": list(spec.paths)}
    lines = [json.dumps(header)]
    for i, h in enumerate(headings_deg):
        out = {"rest_heading.car": float(wrap_angle(math.radians(h))), "rest_x.car": 1.0 + i, "rest_y.car": 0.0,
               "delta_v.car": 5.0 + 0.01 * i}
        lines.append(json.dumps({"i": i, "x": [0.7], "out": out, "checks": {}}))
    path = tmp_path / "mc.jsonl"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_monte_carlo_percentiles_of_a_rest_heading(tmp_path):
    mc = load_results(_results_file(tmp_path, np.linspace(191.0, 231.0, 41)))
    p = {k: math.degrees(v) for k, v in mc.percentiles["rest_heading.car"].items() if k != "std"}
    assert p["p5"] == pytest.approx(-167.0, abs=1e-6) and p["p50"] == pytest.approx(-149.0, abs=1e-6)
    assert p["mean"] == pytest.approx(-149.0, abs=1e-6)
    assert math.degrees(mc.percentiles["rest_heading.car"]["std"]) < 12.0  # 40 deg wide, not 300
    assert mc.percentiles["delta_v.car"]["p50"] == pytest.approx(5.2)  # other outputs: linear
    report = mc.report("SI")
    assert "-149" in report and "108.9" not in report
    assert "rest headings: percentiles on the arc around their circular mean" in report


def test_monte_carlo_histogram_of_a_rest_heading_is_one_cloud(tmp_path):
    from crashsim.reconstruct.mc_plots import plot_histograms

    mc = load_results(_results_file(tmp_path, np.linspace(160.0, 200.0, 41)))
    (ax,) = plot_histograms(mc, keys=["rest_heading.car"]).ravel()
    lo, hi = ax.get_xlim()
    assert hi - lo < 60.0  # one cloud 40 deg wide, not two at -180 and +180 deg
    lines = sorted(ln.get_xdata()[0] for ln in ax.get_lines())
    assert lines[0] == pytest.approx(162.0, abs=1e-6) or lines[0] == pytest.approx(-198.0, abs=1e-6)
    assert lines[-1] - lines[0] == pytest.approx(36.0, abs=1e-6)

"""The fit and Monte Carlo chain gives the same numbers on its fast path as on the full one.

The fast path (:mod:`crashsim.reconstruct.patch` scenarios, the reused scene model of
:mod:`crashsim.scene.models`, the per-coordinate polyline distances of the evidence
checks) is compared with the full path (``crashsim.reconstruct.overrides.FAST = False``: every
scenario validated and built from the file dict, every scene model built again) on the shipped
fit scene: fit residuals and Monte Carlo sample records must agree exactly.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

import crashsim.reconstruct.overrides as overrides
from crashsim.evidence.checks import _nearest_on_polyline
from crashsim.reconstruct.fit import FitProblem, FitSpec
from crashsim.reconstruct.montecarlo import monte_carlo
from crashsim.schema import load_toml

from scenes import ENGINE

FILE = Path(__file__).resolve().parents[2] / "scenarios" / "fit" / "intersection_fit.toml"


@pytest.fixture()
def raw():
    return load_toml(FILE)


def _full_path(monkeypatch):
    monkeypatch.setattr(overrides, "FAST", False)


def test_fit_residuals_identical(raw, monkeypatch):
    """FitProblem.evaluate on both paths at the start, in both basins and near the bounds: the same
    weighted residuals (to 1e-12; they come out bit for bit) and the same scene numbers."""
    spec = FitSpec.from_dict(raw["fit"], raw, file=str(FILE))
    points = [np.array([0.5, 0.5, 0.5, 0.5]), np.array([0.44, 0.44, 0.125, 0.5]),
              np.array([0.44, 0.44, 0.375, 0.5]), np.array([0.02, 0.97, 0.01, 0.99])]
    fast = FitProblem(raw, spec, engine=ENGINE, file=str(FILE))
    got = [fast.evaluate(z) for z in points]
    assert fast.inputs.patched
    _full_path(monkeypatch)
    full = FitProblem(raw, spec, engine=ENGINE, file=str(FILE))
    assert not full.inputs.patched
    for z, (r_fast, scene_fast) in zip(points, got):
        r_full, scene_full = full.evaluate(z)
        np.testing.assert_allclose(r_fast, r_full, rtol=0, atol=1e-12)
        assert json.dumps(scene_fast.to_dict(), sort_keys=True) == json.dumps(scene_full.to_dict(), sort_keys=True)


def test_monte_carlo_records_identical(raw, monkeypatch, tmp_path):
    """The JSON-lines records of the same seed: identical line for line (inputs, outputs, checks)."""
    files = {}
    for name in ("fast", "full"):
        if name == "full":
            _full_path(monkeypatch)
        files[name] = tmp_path / f"{name}.jsonl"
        monte_carlo(raw, n=12, engine=ENGINE, workers=1, out_path=files[name], progress=False, file=str(FILE))
    fast_lines = files["fast"].read_text().splitlines()
    full_lines = files["full"].read_text().splitlines()
    assert len(fast_lines) == 13 and fast_lines == full_lines
    assert all("checks" in json.loads(line) for line in fast_lines[1:])


def _reference_nearest(points, polyline):
    """The (n, m, 2)-array form of the point-to-polyline distance the evidence checks used before
    (kept here as the reference the per-coordinate form must reproduce bit for bit)."""
    p = np.asarray(points, dtype=float)[:, None, :]
    line = np.asarray(polyline, dtype=float)
    a = line[:-1][None]
    ab = (line[1:] - line[:-1])[None]
    denom = np.sum(ab * ab, -1)
    t = np.clip(np.sum((p - a) * ab, -1) / np.where(denom > 0, denom, 1.0), 0.0, 1.0)
    d = p - (a + t[..., None] * ab)
    dist = np.hypot(d[..., 0], d[..., 1])
    j = np.argmin(dist, axis=1)
    rows = np.arange(p.shape[0])
    cross = ab[0, j, 0] * (p[:, 0, 1] - a[0, j, 1]) - ab[0, j, 1] * (p[:, 0, 0] - a[0, j, 0])
    return dist[rows, j], np.where(cross >= 0, 1.0, -1.0)


@pytest.mark.parametrize("seed", range(5))
@pytest.mark.parametrize("compiled", [False, True])
def test_polyline_distance_bit_for_bit(seed, compiled, monkeypatch):
    """Random tracks (with repeated vertices: zero-length segments) and points on, near and far off them:
    the array form and the compiled loop both give the reference's bits."""
    import crashsim.evidence.checks as evidence

    monkeypatch.setattr(evidence, "_COMPILED_FROM", 0 if compiled else 10**12)
    rng = np.random.default_rng(seed)
    line = np.cumsum(rng.normal(size=(rng.integers(2, 80), 2)), axis=0)
    line[len(line) // 2] = line[len(line) // 2 - 1]
    grid = rng.integers(-5, 5, size=(30, 2)).astype(float)  # integer tracks: many exact ties between segments
    pts = np.vstack([rng.normal(size=(150, 2)) * 6, line[::3], line[:-1] + 0.5 * np.diff(line, axis=0)])
    on_grid = rng.integers(-6, 6, size=(80, 2)) * 0.5
    for got, ref in zip(_nearest_on_polyline(on_grid, grid), _reference_nearest(on_grid, grid)):
        assert np.array_equal(got, ref)
    if compiled:
        from crashsim.evidence._polyline import nearest_on_polyline

        assert nearest_on_polyline(pts, line) is not None  # numba is there: the loop is what is tested
    d_new, s_new = _nearest_on_polyline(pts, line)
    d_ref, s_ref = _reference_nearest(pts, line)
    assert np.array_equal(d_new, d_ref) and np.array_equal(s_new, s_ref)


def test_lean_scene_gives_the_full_numbers(raw):
    """A lean run (``run_scene(..., lean=True)``, as fit, Monte Carlo and posterior samples run) gives the
    full run's sample record, evidence checks and fit residuals exactly, for the shipped fit scene's
    Monte Carlo samples (and the bodies' rest states and histories, the kept wheels' tracks)."""
    from crashsim.reconstruct.montecarlo import UncertaintySpec, _check_key, sample_inputs, scene_outputs
    from crashsim.reconstruct.overrides import ScenarioOverrides
    from crashsim.scene.run import run_scene

    spec = UncertaintySpec.from_dict(raw["uncertainty"], file=str(FILE))
    fspec = FitSpec.from_dict(raw["fit"], raw, file=str(FILE))
    ov = ScenarioOverrides(raw, spec.paths, engine=ENGINE, file=str(FILE))
    fit = FitProblem(raw, fspec, engine=ENGINE, file=str(FILE))
    for i in range(8):
        sc = ov.scenario(sample_inputs(spec, spec.seed, i))
        full, lean = run_scene(sc), run_scene(sc, lean=True)
        assert scene_outputs(lean) == scene_outputs(full)
        assert lean.warnings == full.warnings and lean.at_rest == full.at_rest
        checks = lambda s: [(_check_key(c), c.residual, c.passed, json.dumps(c.details, sort_keys=True))  # noqa: E731
                            for c in s.evidence.checks]
        assert checks(lean) == checks(full)
        assert np.array_equal(fit.evidence.weighted(lean), fit.evidence.weighted(full))
        assert lean.joint.pairs == () and len(lean.joint.impacts) == len(full.joint.impacts)
        for v, r in full.runout.items():
            lr = lean.runout[v]
            assert (lr.status, lr.message, lr.t_end, lr.energy_dissipated) == (r.status, r.message, r.t_end,
                                                                               r.energy_dissipated)
            assert [(e.t, e.kind) for e in lr.events] == [(e.t, e.kind) for e in r.events]
            for name, b in r.bodies.items():
                lb = lr.bodies[name]
                assert (lb.rest_position, lb.rest_heading, lb.time_to_rest, lb.distance) == \
                    (b.rest_position, b.rest_heading, b.time_to_rest, b.distance)
                assert np.array_equal(lb.history.x, b.history.x)
            assert set(lr.wheels) <= set(r.wheels)
            for key, tr in lr.wheels.items():
                assert np.array_equal(tr.points, r.wheels[key].points)
                assert tr.path_length == r.wheels[key].path_length
        assert any(lean.runout[v].wheels for v in lean.runout)  # the mark's wheels are kept
        assert sum(len(r.wheels) for r in lean.runout.values()) < sum(len(r.wheels) for r in full.runout.values())


def test_fit_evaluations_measure_the_marks_once(raw):
    """The fit's lean evaluations leave the tyre-mark checks out (its residuals measure each mark
    themselves) and keep every other check; their residuals are the full scene's, whose report still
    checks the marks."""
    fspec = FitSpec.from_dict(raw["fit"], raw, file=str(FILE))
    fit = FitProblem(raw, fspec, engine=ENGINE, file=str(FILE))
    for z in (np.full(len(fspec.unknowns), 0.5), np.array([0.3, 0.6, 0.4, 0.7])[: len(fspec.unknowns)]):
        x = fit.x_of(z)
        lean, full = fit.scene(x), fit.scene(x, lean=False)
        kinds = lambda s: [c.kind for c in s.evidence.checks]  # noqa: E731
        assert "mark" in kinds(full) and "mark" not in kinds(lean)
        assert kinds(lean) == [k for k in kinds(full) if k != "mark"]
        assert np.array_equal(fit.evidence.weighted(lean), fit.evidence.weighted(full))


def test_the_inverse_api_takes_a_scenario(raw, monkeypatch):
    """crashsim.fit / monte_carlo accept a Scenario (its file_data varied, not its file read again), also
    one built in memory with no file; the same numbers as from the file's path."""
    import crashsim
    import crashsim.scenario as sm
    from crashsim.inverse_schema import with_inverse_sections
    from crashsim.reconstruct.overrides import file_contents

    monkeypatch.setattr(sm, "SCHEMA", with_inverse_sections(sm.SCHEMA))
    sc = sm.scenario_from_dict(raw)  # no file behind it
    assert sc.path is None and sc.file_data is raw
    assert file_contents(sc) == (raw, None)
    import dataclasses

    assert file_contents(dataclasses.replace(sc, title="t")) == (raw, None)  # replace keeps the file's contents
    with pytest.raises(crashsim.errors.ScenarioError, match="cannot vary"):
        file_contents(dataclasses.replace(sc, file_data=None))  # made another way: no file contents to vary
    a = crashsim.monte_carlo(sc, samples=3, workers=1, engine=ENGINE)
    b = crashsim.monte_carlo(crashsim.load(FILE), samples=3, workers=1, engine=ENGINE)
    assert np.array_equal(a.inputs, b.inputs) and a.outputs.keys() == b.outputs.keys()
    for k in a.outputs:
        assert np.array_equal(a.outputs[k], b.outputs[k], equal_nan=True), k

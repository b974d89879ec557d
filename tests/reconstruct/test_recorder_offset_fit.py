"""A recorder's ``time_offset`` as a fit unknown: the residuals and the pre-crash window come from
each evaluation's own item, so the offset has a real sensitivity.

Synthetic record: the approach of car A (1 s reaction at constant speed, then locked braking)
sampled every 0.2 s and written with a clock that is ``TRUTH`` ahead of the impact's (a sample
at true time t is written at t - TRUTH). The fit of the offset alone, from a start 0.6 s away,
must give it back within its standard error; the posterior's residual function must put its
maximum there too. Before this was fixed the fit built its recorder residuals once from the
file's item: zero sensitivity, the start value returned as "not determined".
"""

from __future__ import annotations

import copy

import numpy as np
import pytest

from crashsim.reconstruct.fit import FitProblem, FitSpec, fit_scene
from crashsim.reconstruct.overrides import ScenarioOverrides
from crashsim.scene.run import run_scene

from scenes import ENGINE, car_car

PATH = "evidence.recorder[0].time_offset"
TRUTH = 0.45  # s
SIGMA = 0.3  # m/s


def _scene_with_record(truth: float = TRUTH) -> dict:
    data = car_car()
    a = data["vehicles"]["A"]
    del a["speed"]
    a["approach"] = {"speed": "17 m/s", "distance": "14 m", "reaction_time": "1 s", "tyres": {"state": "locked"}}
    scene = run_scene(ScenarioOverrides(data, [], engine=ENGINE).scenario(np.array([])))
    ap = scene.scenario.approaches["A"]
    t_true = np.arange(-2.6, -0.05, 0.2)
    v = ap.speed_at(t_true)
    data["evidence"] = {"recorder": [{
        "name": "A's EDR", "body": "carA", "tolerance": "0.5 m/s", "sigma": f"{SIGMA} m/s", "time_offset": "0 s",
        "samples": [{"time": f"{float(t - truth)!r} s", "speed": f"{float(s)!r} m/s"} for t, s in zip(t_true, v)]}]}
    return data


def _spec(initial: str = "-0.15 s") -> FitSpec:
    return FitSpec.from_dict({"unknowns": [{"path": PATH, "lower": "-1 s", "upper": "1.5 s", "initial": initial}],
                              "starts": 1})


def test_the_offset_moves_the_residuals_and_the_verdict():
    """The weighted residuals at two offsets differ, and the printed residuals agree with the verdict."""
    data = _scene_with_record()
    prob = FitProblem(data, _spec(), engine=ENGINE)
    r_start = prob.residual(prob.z_of([-0.15]))
    r_truth = prob.residual(prob.z_of([TRUTH]))
    assert np.max(np.abs(r_start - r_truth)) > 1.0  # more than one sigma: the offset is seen
    assert np.max(np.abs(r_truth)) < 0.05  # the truth fits its own record
    # residuals shown beside a verdict are the verdict's own
    for x in (-0.15, TRUTH):
        scene = prob.scene(prob.x_of(prob.z_of([x])), lean=False)
        raw, _ = prob.evidence.raw_residuals(scene)
        (check,) = [c for c in scene.evidence.checks if c.kind == "recorder"]
        assert check.passed == bool(np.all(np.abs(raw[0]) <= check.tolerance))
        assert np.allclose(raw[0], check.details["residuals"], rtol=0, atol=1e-12)


def test_fit_gives_the_offset_back_within_its_standard_error():
    data = _scene_with_record()
    res = fit_scene(data, _spec(), engine=ENGINE, workers=1)
    assert res.success, res.message
    se = res.stderr[0]
    assert np.isfinite(se) and 0 < se < 0.2
    assert abs(res.x[0] - TRUTH) < se
    assert not any("not determined" in w or "no evidence" in w for w in res.warnings), res.warnings
    assert res.scene.evidence.all_passed
    (item,) = [r for r in res.residuals if r.kind == "recorder"]
    assert item.passed and max(abs(v) for v in item.residual) <= item.tolerance


def test_samples_after_the_impact_leave_the_window_with_the_offset():
    """A sample the offset puts after the impact is not compared (residual 0, computed none); the
    one the file's offset keeps out comes in when the offset moves it before the impact."""
    data = _scene_with_record()
    smp = data["evidence"]["recorder"][0]["samples"]
    smp.append({"time": "0.3 s", "speed": "1 m/s"})  # after the impact at offset 0; at -0.45 s before it
    prob = FitProblem(data, _spec(), engine=ENGINE)
    s0 = prob.scene(prob.x_of(prob.z_of([0.0])), lean=False)
    (c0,) = [c for c in s0.evidence.checks if c.kind == "recorder"]
    assert c0.details["compared"][-1] is False and c0.details["residuals"][-1] == 0.0
    s1 = prob.scene(prob.x_of(prob.z_of([-0.45])), lean=False)
    (c1,) = [c for c in s1.evidence.checks if c.kind == "recorder"]
    assert c1.details["compared"][-1] is True and not c1.passed  # 1 m/s just before the impact: far off


def test_posterior_log_probability_peaks_at_the_true_offset():
    from crashsim.reconstruct.posterior import PosteriorProblem, build_priors

    data = _scene_with_record()
    data["fit"] = {"unknowns": [{"path": PATH, "lower": "-1 s", "upper": "1.5 s", "initial": "0 s"}]}
    fs = FitSpec.from_dict(data["fit"], data)
    prob = PosteriorProblem(copy.deepcopy(data), fs, build_priors(data, fs, "fit"), engine=ENGINE)
    grid = np.array([-0.3, 0.0, 0.25, TRUTH, 0.65, 0.9])
    lps = [prob.evaluate(prob.fit.z_of([x]))[0] for x in grid]
    assert all(np.isfinite(lps))
    assert int(np.argmax(lps)) == list(grid).index(TRUTH)
    assert lps[list(grid).index(TRUTH)] - min(lps) > 10.0  # not a flat likelihood
    assert prob.evaluate(prob.fit.z_of([TRUTH]))[0] == pytest.approx(max(lps))

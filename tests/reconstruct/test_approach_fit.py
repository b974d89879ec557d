"""The speed at the start of braking as a fit unknown: the impact speed follows from it.

Round trip: evidence made by the model itself at a true braking speed (the rest positions of
both cars, a pre-impact skid mark of car A and a recorder's pre-crash speeds) is fitted from a
start value 4 m/s away; the fit must find the truth inside its interval, and the evidence must
all pass at the best fit.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from crashsim.reconstruct.fit import FitSpec, fit_scene
from crashsim.reconstruct.overrides import ScenarioOverrides
from crashsim.scene.run import run_scene

from scenes import ENGINE, car_car, with_evidence

PATH = "vehicles.A.approach.speed"


def approach_scene() -> dict:
    data = car_car()
    a = data["vehicles"]["A"]
    del a["speed"]
    a["approach"] = {"speed": "17 m/s", "distance": "14 m", "reaction_time": "1 s", "tyres": {"state": "locked"}}
    return data


def _with_approach_evidence(data, truth):
    scene = run_scene(ScenarioOverrides(data, [PATH], engine=ENGINE).scenario(np.array([truth])))
    out = with_evidence(data, [PATH], np.array([truth]), heading=True, noise=False)
    a = scene.scenario.approaches["A"]
    tr = a.tracks["carA/1/right"]  # the rear right wheel's pre-impact skid, 2 m to 12 m along it
    pts = tr.points[(tr.t > -a.time_to_impact + 0.15) & (tr.t < -0.05)]
    out["evidence"]["marks"] = [{"name": "pre-impact skid A", "wheel": "carA/1/right", "phase": "approach",
                                 "points": [[f"{float(x)!r} m", f"{float(y)!r} m"] for x, y in pts[:: max(1, len(pts) // 6)]],
                                 "tolerance": "0.3 m", "sigma": "0.1 m"}]
    times = [-2.0, -1.5, -1.0, -0.5]
    v = a.speed_at(np.array(times))
    out["evidence"]["recorder"] = [{"name": "A's EDR", "body": "carA", "tolerance": "0.5 m/s", "sigma": "0.3 m/s",
                                    "samples": [{"time": f"{t} s", "speed": f"{float(s)!r} m/s", "brake": t > -1.0}
                                                for t, s in zip(times, v)]}]
    return out, scene


@pytest.mark.slow  # 4-10 s (tests/reconstruct --durations, 2-core machine)
def test_fit_recovers_the_speed_at_braking():
    truth = 16.0
    data, scene = _with_approach_evidence(approach_scene(), truth)
    spec = FitSpec.from_dict({"unknowns": [{"path": PATH, "lower": "15 m/s", "upper": "24 m/s",
                                            "initial": "20 m/s"}], "starts": 2})
    res = fit_scene(data, spec, engine=ENGINE, workers=1)
    assert res.success, res.message
    x = res.x[0]
    lo, hi = res.interval[0]
    assert lo <= truth <= hi
    assert x == pytest.approx(truth, abs=0.02)
    best = res.scene
    assert best.evidence.all_passed
    # the impact speed follows from the braking speed over 14 m of locked wheels
    a = best.scenario.approaches["A"]
    assert a.speed_at_impact == pytest.approx(math.sqrt(x**2 - 2 * 0.75 * 9.80665 * 14.0), rel=1e-5)
    kinds = {c.kind for c in best.evidence.checks}
    assert {"mark", "recorder", "rest"} <= kinds


def test_recorder_lower_bound_samples():
    """A braking sample that reads low passes (the recorder under-reads); one reading high fails."""
    data, scene = _with_approach_evidence(approach_scene(), 17.0)
    rec = data["evidence"]["recorder"][0]
    low = copy.deepcopy(data)
    low["evidence"]["recorder"][0]["samples"][-1]["speed"] = "5 m/s"   # brake on: a lower bound
    s_low = run_scene(ScenarioOverrides(low, [PATH], engine=ENGINE).scenario(np.array([17.0])))
    chk = next(c for c in s_low.evidence.checks if c.kind == "recorder")
    assert chk.passed and chk.details["residuals"][-1] == 0.0
    high = copy.deepcopy(data)
    high["evidence"]["recorder"][0]["samples"][-1]["speed"] = "25 m/s"
    s_high = run_scene(ScenarioOverrides(high, [PATH], engine=ENGINE).scenario(np.array([17.0])))
    chk = next(c for c in s_high.evidence.checks if c.kind == "recorder")
    assert not chk.passed and chk.residual < -5.0
    assert rec["samples"][0]["brake"] is False


def test_posterior_derived_quantities_of_an_approach():
    """With the speed at braking as the unknown, the impact speed it gives is a derived quantity
    of the posterior (and the unknown itself is not repeated among them)."""
    from crashsim.reconstruct.posterior import PosteriorProblem, build_priors

    data, _ = _with_approach_evidence(approach_scene(), 16.0)
    data["fit"] = {"unknowns": [{"path": PATH, "lower": "15 m/s", "upper": "24 m/s", "initial": "17 m/s"}]}
    fs = FitSpec.from_dict(data["fit"], data)
    prob = PosteriorProblem(data, fs, build_priors(data, fs, "fit"), engine=ENGINE)
    keys = prob.derived_keys(prob.fit.z_of([17.0]))
    assert "speed.A" in keys and "speed.B" in keys and "speed_at_braking.A" not in keys
    lp, blob, reason = prob.evaluate(prob.fit.z_of([17.0]))
    assert reason is None and np.isfinite(lp)
    vi = blob[keys.index("speed.A")]
    assert vi == pytest.approx(math.sqrt(17.0**2 - 2 * 0.75 * 9.80665 * 14.0), rel=1e-5)


def test_a_start_where_the_approach_cannot_reach_the_impact_is_named_so():
    """Below about 14.2 m/s car A stops before the 14 m of braking end: a start drawn there stays
    on the failure penalty; the fit says so instead of calling it another minimum."""
    data, _ = _with_approach_evidence(approach_scene(), 16.0)
    spec = FitSpec.from_dict({"unknowns": [{"path": PATH, "lower": "10 m/s", "upper": "24 m/s",
                                            "initial": "20 m/s"}], "starts": 4, "seed": 3})
    res = fit_scene(data, spec, engine=ENGINE, workers=1)
    assert res.x[0] == pytest.approx(16.0, abs=0.02)
    low = [s for s in res.starts if s.x0[0] < 14.0]
    assert low, "the seed should draw a start below the reachable speeds"
    assert any("began where the scene cannot be evaluated" in w for w in res.warnings)
    assert not any("other minima" in w and "e+" in w for w in res.warnings)

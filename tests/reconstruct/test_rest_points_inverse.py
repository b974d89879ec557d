"""Fit and Monte Carlo with rest evidence given by measured points of a body.

A copy of the shipped fit scene (scenarios/fit/intersection_fit.toml) whose car rest position
and heading are replaced by its four corners at that pose: the derived CG and heading equal the
file's, so every residual of the fit equals the original file's, and fit and Monte Carlo run
with it unchanged.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
import tomli_w

from crashsim.geometry import rotate
from crashsim.evidence.checks import named_body_points
from crashsim.reconstruct.fit import FitProblem, FitSpec, fit_scene
from crashsim.reconstruct.montecarlo import monte_carlo
from crashsim.scenario import load_scenario
from crashsim.schema import load_toml

from scenes import ENGINE

FILE = Path(__file__).resolve().parents[2] / "scenarios" / "fit" / "intersection_fit.toml"
CORNERS = ["front_left", "front_right", "rear_left", "rear_right"]


@pytest.fixture(scope="module")
def points_file(tmp_path_factory):
    raw = load_toml(FILE)
    sc = load_scenario(FILE)
    car = next(b for v in sc.vehicles for b in v.bodies if b.name == "car")
    item = raw["evidence"]["rest"][0]
    assert item["body"] == "car"
    pos = [float(v.split()[0]) for v in item["position"]]
    psi = math.radians(float(item["heading"].split()[0]))
    named = named_body_points(car)
    world = np.asarray(pos) + rotate(np.array([named[n] for n in CORNERS]), psi)
    new = {k: v for k, v in item.items() if k not in ("position", "heading")}
    new["points"] = [{"at": n, "position": [f"{float(x)!r} m", f"{float(y)!r} m"]}
                     for n, (x, y) in zip(CORNERS, world)]
    raw["evidence"]["rest"][0] = new
    path = tmp_path_factory.mktemp("points") / "intersection_points.toml"
    path.write_text(tomli_w.dumps(raw))
    return path


def test_points_file_gives_the_same_residuals_as_the_cg_file(points_file):
    raw_cg, raw_pts = load_toml(FILE), load_toml(points_file)
    spec = FitSpec.from_dict(raw_cg["fit"], raw_cg)
    p_cg = FitProblem(raw_cg, spec, engine=ENGINE)
    p_pts = FitProblem(raw_pts, FitSpec.from_dict(raw_pts["fit"], raw_pts), engine=ENGINE)
    assert [it.kind for it in p_pts.evidence.items] == [it.kind for it in p_cg.evidence.items]
    z = p_cg.z_of([13.41, 13.2, 0.05, 0.7])
    r_cg, _ = p_cg.evaluate(z)
    r_pts, scene = p_pts.evaluate(z)
    np.testing.assert_allclose(r_pts, r_cg, rtol=0, atol=1e-9)
    raw, det = p_pts.evidence.raw_residuals(scene)
    reg = det[1]["registration"]  # item 0 is the point of impact, 1 the car's rest
    assert reg["rms"] < 1e-9 and [p["at"] for p in reg["points"]] == CORNERS


def test_fit_and_monte_carlo_run_with_points(points_file, tmp_path):
    raw = load_toml(points_file)
    spec = {**raw["fit"], "starts": 1, "unknowns": raw["fit"]["unknowns"][:2]}  # the two speeds, one start
    res = fit_scene(raw, spec, engine=ENGINE, workers=1, file=str(points_file))
    assert res.success and np.all(np.isfinite(res.stderr))
    car = next(r for r in res.residuals if r.kind == "rest" and r.name == "rest of car")
    assert "registration" in car.details
    # the speeds come back near the scene's 30 mph (13.41 m/s)
    assert np.all(np.abs(res.x - 13.41) < 1.0)
    out = res.write_best(tmp_path / "best.toml")
    assert "points" in load_toml(out)["evidence"]["rest"][0]

    mc = monte_carlo(raw, n=4, engine=ENGINE, workers=1, progress=False, file=str(points_file), accept=True)
    assert mc.n_failed == 0 and "rest: rest of car" in mc.checks and "rest heading: rest of car (heading)" in mc.checks
    assert mc.meets_all.shape == (4,)

"""End to end through a scenario file: scenarios/fit/intersection_fit.toml.

The shipped intersection scene (the paper's Table 6 impact, 30 mph = 13.41 m/s each) with
sigmas on its evidence, a [fit] of both speeds, the restitution and the road friction, and an
[uncertainty] table. The fit must give intervals that cover the scene's own speeds.
"""

from __future__ import annotations

from pathlib import Path

import matplotlib
import numpy as np
import pytest

from crashsim.reconstruct.fit import FitSpec, fit_scene
from crashsim.reconstruct.montecarlo import monte_carlo
from crashsim.scenario import load_scenario
from crashsim.schema import load_toml

from scenes import ENGINE

FILE = Path(__file__).resolve().parents[2] / "scenarios" / "fit" / "intersection_fit.toml"


def test_file_validates_with_the_wired_schema():
    sc = load_scenario(FILE)
    assert sc.data["fit"]["unknowns"][0]["path"] == "vehicles.A.speed"
    assert sc.data["evidence"]["rest"][0]["sigma"] == pytest.approx(0.25)
    assert len(sc.data["uncertainty"]["inputs"]) == 5


def test_shipped_scene_speeds_come_back_from_its_evidence(caplog):
    raw = load_toml(FILE)
    spec = FitSpec.from_dict(raw["fit"], raw, file=str(FILE))
    res = fit_scene(raw, spec, engine=ENGINE, file=str(FILE))
    truth = {"vehicles.A.speed": 13.41, "vehicles.B.speed": 13.41, "impact.restitution": 0.05,
             "runout.road_friction": 0.7}
    for u, (lo, hi) in zip(res.unknowns, res.interval):
        assert lo <= truth[u.path] <= hi, (u.path, lo, hi)
    assert res.n_agree >= 2 and not any("rank" in w for w in res.warnings)
    assert res.chi2 < res.dof  # the hypothetical evidence was made to agree with the scene
    # speed and road friction trade off (v^2 / mu): every pair at |r| >= correlation_warning (0.99
    # by default, so 0.997 warns) is named, no other pair is
    assert spec.correlation_warning == 0.99
    n = len(res.unknowns)
    strong = {(res.unknowns[i].name, res.unknowns[j].name) for i in range(n) for j in range(i + 1, n)
              if abs(res.correlation[i, j]) >= 0.99}
    named = {(a.name, b.name) for a in res.unknowns for b in res.unknowns
             if any(w.startswith(f"{a.name} and {b.name} are correlated at ") for w in res.warnings)}
    assert strong and named == strong
    logged = [r.getMessage() for r in caplog.records if r.name == "crashsim" and "are correlated at" in r.getMessage()]
    assert len(logged) == len(strong)
    # the linearity check: along the ridge (the covariance's longest axis, probed first) toward low
    # speeds and low friction chi^2 rises several times what the linearised model gives (rest
    # distance ~ v^2 / mu is curved there); across the ridge the scene is linear over the intervals.
    # (The other way along the ridge, near the factor's edge, is not asserted either way.)
    probes = res.linearity
    assert len(probes) == 8 and probes[0].step["runout.road_friction"] < 0 and probes[0].ratio > 4
    assert all(p.linear for p in probes[2:]), [p.ratio for p in probes]
    assert any(w.startswith("the model is not linear over the intervals") for w in res.warnings)


def test_the_second_basin_is_a_worse_local_minimum():
    """The file's comment: above e ~ 0.07 the trailer no longer presses on the car after
    separation, and the best fit confined there is much worse than the truth's basin."""
    from crashsim.reconstruct.fit import FitProblem

    raw = load_toml(FILE)
    p = FitProblem(raw, FitSpec.from_dict(raw["fit"], raw, file=str(FILE)), engine=ENGINE, file=str(FILE))
    chi2 = {}
    for e in (0.05, 0.15):
        r, scene = p.evaluate(p.z_of(np.array([13.41, 13.41, e, 0.7])))
        chi2[e] = float(r @ r)
        kinds = [ev.kind for ev in scene.runout["B"].events]
        assert ("contact_pressed" in kinds) == (e == 0.05), (e, kinds)
    assert chi2[0.05] < 5.0 < 10.0 < chi2[0.15], chi2


@pytest.mark.slow  # 4-10 s (tests/reconstruct --durations, 2-core machine)
def test_shipped_scene_monte_carlo(tmp_path):
    matplotlib.use("Agg")
    from crashsim.reconstruct.mc_plots import save_mc_figures

    raw = load_toml(FILE)
    res = monte_carlo(raw, n=6, engine=ENGINE, workers=1, progress=False, out_path=tmp_path / "s.jsonl",
                      file=str(FILE))
    assert res.n_done == 6 and res.n_failed == 0
    assert np.all(np.isfinite(res.outputs["rest_x.trailer"]))
    paths = save_mc_figures(res, tmp_path)
    assert [p.name for p in paths] == ["mc_histograms.png", "mc_rest_clouds.png", "mc_tornado_trailer.png",
                                       "mc_tornado_car.png"]
    assert all(p.stat().st_size > 10_000 for p in paths)


@pytest.mark.slow  # a fit and about 15 000 scenes (two posteriors): minutes on a 2-core machine
def test_shipped_posterior_the_file_s_sampler_agrees_with_emcee():
    """The file's sampler (independence Metropolis-Hastings from the fit) and emcee's differential
    evolution (the sampler shipped before, 20 walkers around the best fit) sample the same posterior:
    each unknown's p2.5, p50, p97.5 and mean differ by less than four Monte Carlo standard errors of
    the difference (a percentile q: sqrt(q (1 - q) / ESS) / density, the density from the samples'
    spread between q -+ 5 %; the mean: sd / sqrt(ESS); each chain with its own ESS of that unknown).
    Shorter chains than the file's (a 300-sample target; 600 emcee steps): the tolerances follow."""
    import math
    from dataclasses import replace

    from crashsim.reconstruct.posterior import PosteriorSpec, run_posterior

    raw = load_toml(FILE)
    spec = PosteriorSpec.from_dict(raw["posterior"])
    assert spec.sampler == "imh"
    new = run_posterior(raw, replace(spec, ess=300), workers=2, progress=False, engine=ENGINE, file=str(FILE))
    old = run_posterior(raw, replace(spec, sampler="emcee", walkers=20, move="de", steps=600, burn=150, ess=None),
                        workers=2, progress=False, engine=ENGINE, file=str(FILE))
    assert new.ess.min() >= 300 and old.ess.min() > 200
    assert new.evaluations / new.ess.min() < old.evaluations / old.ess.min()

    def err(samples, q, ess):
        lo_q, hi_q = max(q - 5, 0.5), min(q + 5, 99.5)
        lo, hi = np.percentile(samples, [lo_q, hi_q])
        return math.sqrt(q / 100 * (1 - q / 100) / ess) / ((hi_q - lo_q) / 100 / (hi - lo))

    for i, u in enumerate(new.unknowns):
        a, b = new.samples[:, i], old.samples[:, i]
        for q in (2.5, 50.0, 97.5):
            d = new.percentiles[u.path][f"p{q:g}"] - old.percentiles[u.path][f"p{q:g}"]
            assert abs(d) < 4 * math.hypot(err(a, q, new.ess[i]), err(b, q, old.ess[i])), (u.path, q, d)
        d = new.percentiles[u.path]["mean"] - old.percentiles[u.path]["mean"]
        assert abs(d) < 4 * math.hypot(np.std(a) / math.sqrt(new.ess[i]), np.std(b) / math.sqrt(old.ess[i]))

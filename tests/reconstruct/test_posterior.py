"""Posterior by MCMC: a closed-form posterior, determinism, resume, Dask equals local, bad input, CLI.

The cheap scene of these tests: one mid-size car drives head-on into a rigid barrier (contact
on its centre line, no tangential impulse) and rebounds straight back with all wheels locked.
For a central impact with a fixed rigid body the separation speed is exactly ``e v``; the
rebound is a straight locked slide on road friction mu, so the car comes to rest

    d(v) = (e v)^2 / (2 mu g)

behind the impact point (closed form of a locked slide, ``notes``: d = v^2/(2 a), a = mu g; the
model's rest position differs from it by the v_stop/eps effects bounded in
``tests/analytic/test_straight_slide.py``, checked below to be negligible here). With the rest
position measured with a Gaussian error sigma (its y component is exactly 0 in the model and in
the measurement) and a flat prior on v in [lo, hi], the posterior density of v is

    p(v) ~ exp(-(d(v) - d_obs)^2 / (2 sigma^2))  on [lo, hi],

which the test integrates by quadrature.
"""

from __future__ import annotations

import copy
import json
import math

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.reconstruct.posterior import MIN_KEPT_STEPS, TAU_FACTOR, PosteriorSpec, _too_short, load_chain, run_posterior

from scenes import ENGINE

E, MU, D_OBS, SIGMA = 0.5, 0.7, 1.9, 0.2
LO, HI = 6.0, 10.5  # m/s; the upper bound cuts the posterior just above its mode (10.2 m/s)


def rebound(**posterior) -> dict:
    """The barrier-rebound scene with rest evidence, a [fit] of the car's speed and a [posterior] table."""
    return {
        "scenario": {"title": "car into a barrier, straight locked rebound"},
        "vehicles": {"car": {"position": ["0 m", "0 m"], "heading": "0 deg", "speed": "10 m/s",
                             "bodies": [{"name": "car", "preset": "car-midsize"}], "tyres": {"state": "locked"}}},
        "barrier": {"name": "wall"},
        "impact": {"body1": "car", "body2": "wall", "point": ["2.55 m", "0 m"], "point_frame": "car",
                   "normal": "180 deg", "tangent": "ccw", "restitution": E, "tangential": "no_slide"},
        "runout": {"road_friction": MU},
        "evidence": {"rest": [{"body": "car", "position": [f"{-D_OBS} m", "0 m"], "tolerance": "0.6 m",
                               "sigma": f"{SIGMA} m"}]},
        "fit": {"unknowns": [{"path": "vehicles.car.speed", "lower": f"{LO} m/s", "upper": f"{HI} m/s",
                              "initial": "9.5 m/s"}]},
        "posterior": {"walkers": 8, "steps": 60, "burn": 0, "seed": 3, **posterior},
    }


def _d(v):
    return (E * v) ** 2 / (2 * MU * G)


def test_the_model_is_the_closed_form_here():
    """Separation speed e v exactly, a straight slide, rest within 1e-3 sigma of d(v): the
    likelihood the sampler sees is the closed-form one to far below the Monte Carlo error."""
    from crashsim.reconstruct.overrides import ScenarioOverrides
    from crashsim.scene.run import run_scene

    ov = ScenarioOverrides(rebound(), ["vehicles.car.speed"], engine=ENGINE)
    for v in (LO, 9.0, HI):
        scene = run_scene(ov.scenario([v]))
        assert scene.impact.bodies["car"].velocity == pytest.approx([-E * v, 0.0], abs=1e-12)
        rest = scene.runout["car"].bodies["car"].rest_position
        assert abs(rest[1]) < 1e-9
        assert abs(-rest[0] - _d(v)) < 1e-3 * SIGMA


@pytest.mark.slow  # 4-10 s (tests/reconstruct --durations, 2-core machine)
def test_posterior_matches_the_closed_form():
    """Quantiles and mean of the chain against the quadrature of p(v); each tolerance is 4 Monte
    Carlo standard errors from the chain's effective sample size (quantile q: sqrt(q (1-q) / ESS)
    / p(v_q); mean: sd / sqrt(ESS)).

    The differential-evolution move: with one unknown it mixes about three times faster than the
    stretch move (autocorrelation times measured here ~6 and ~8-22 steps), so a chain of 50 tau
    costs a third; the likelihood and the prior under test are the same for every move."""
    res = run_posterior(rebound(walkers=8, steps=450, burn=100, seed=7, init_scale=0.1, move="de"), workers=2,
                        progress=False, engine=ENGINE)
    _check_against_the_quadrature(res)


@pytest.mark.slow  # a fit and about 1500 scenes
def test_the_independence_sampler_matches_the_closed_form():
    """The same closed form with sampler = "imh" (its proposal from the fit, refitted in the burn-in),
    stopped at a target effective sample size: one scene per step, and fewer than 4 per effective sample."""
    res = run_posterior(rebound(sampler="imh", steps=3000, burn=200, ess=400, check_every=100, seed=7), workers=2,
                        progress=False, engine=ENGINE)
    assert res.spec.sampler == "imh" and res.chain.shape[1] == 1
    assert res.evaluations == res.steps + 1  # the start (the best fit) and one scene per step
    assert res.steps < 3000 and res.ess[0] >= 400
    assert res.evaluations / res.ess[0] < 4
    _check_against_the_quadrature(res)


def _check_against_the_quadrature(res):
    assert res.success, res.warnings
    v = np.linspace(LO, HI, 40001)
    dens = np.exp(-(_d(v) - D_OBS) ** 2 / (2 * SIGMA**2))
    cdf = np.concatenate([[0.0], np.cumsum(0.5 * (dens[1:] + dens[:-1]) * np.diff(v))])
    norm = cdf[-1]
    cdf, pdf = cdf / norm, dens / norm
    mean = float(np.trapezoid(v * pdf, v))
    sd = math.sqrt(float(np.trapezoid((v - mean) ** 2 * pdf, v)))
    ess = float(res.ess[0])
    assert ess > 300  # a chain long enough for the tolerances below to be tight (4 MCSE of the median ~ 0.3 sd)
    samples = res.samples[:, 0]
    assert samples.min() >= LO and samples.max() <= HI
    for q in (0.025, 0.16, 0.5, 0.84, 0.975):
        exact = float(np.interp(q, cdf, v))
        mcse = math.sqrt(q * (1 - q) / ess) / float(np.interp(exact, v, pdf))
        got = res.percentiles["vehicles.car.speed"][f"p{100 * q:g}"]
        assert abs(got - exact) < 4 * mcse, (q, got, exact, mcse)
    assert abs(res.percentiles["vehicles.car.speed"]["mean"] - mean) < 4 * sd / math.sqrt(ess)
    assert res.percentiles["vehicles.car.speed"]["sd"] == pytest.approx(sd, rel=0.1)
    # the upper bound cuts the posterior just above its mode: the report says the prior limits it there
    assert any("from its upper bound: the bound (the prior)" in w for w in res.warnings)
    assert not any("from its lower bound" in w for w in res.warnings)
    # derived quantities ride along: delta-v of a central barrier impact is (1 + e) v
    k = res.derived.index("delta_v.car")
    assert np.allclose(res.derived_samples[:, k], (1 + E) * samples, rtol=1e-9)


def test_same_seed_same_chain():
    import crashsim

    a = run_posterior(rebound(), workers=1, progress=False, engine=ENGINE)
    b = crashsim.posterior(rebound(), workers=1, engine=ENGINE)  # the top-level API, as the CLI
    c = run_posterior(rebound(seed=4), workers=1, progress=False, engine=ENGINE)
    assert np.array_equal(a.chain, b.chain) and np.array_equal(a.log_prob, b.log_prob)
    assert np.array_equal(a.blobs, b.blobs, equal_nan=True)
    assert not np.array_equal(a.chain, c.chain)
    assert a.chain.shape == (60, 8, 1) and np.all(np.isfinite(a.log_prob))


def test_independence_sampler_same_seed_same_chain_in_any_pool():
    """sampler = "imh": the proposals and the acceptance tests draw from generators of the seed alone
    and each batch of scenes comes back in order, so one worker or two give the same chain."""
    data = rebound(sampler="imh", steps=120, burn=40, seed=5)
    a = run_posterior(data, workers=1, progress=False, engine=ENGINE)
    b = run_posterior(data, workers=2, progress=False, engine=ENGINE)
    c = run_posterior(rebound(sampler="imh", steps=120, burn=40, seed=6), workers=1, progress=False, engine=ENGINE)
    assert a.chain.shape == (120, 1, 1) and np.all(np.isfinite(a.log_prob))
    assert np.array_equal(a.chain, b.chain) and np.array_equal(a.log_prob, b.log_prob)
    assert np.array_equal(a.blobs, b.blobs, equal_nan=True)
    assert not np.array_equal(a.chain, c.chain)
    assert a.fit is not None  # the fit runs first: the proposal is built from it
    assert "independence Metropolis-Hastings" in a.report() and a.to_dict()["spec"]["sampler"] == "imh"


def test_a_sampler_not_known_and_a_chain_file_for_the_independence_sampler(tmp_path, capsys):
    with pytest.raises(ScenarioError) as e:
        PosteriorSpec.from_dict({"sampler": "hmc"}, file="scene.toml")
    assert e.value.field == "posterior.sampler" and "hmc" in str(e.value) and "imh" in str(e.value)
    with pytest.raises(ScenarioError) as e:
        run_posterior(rebound(sampler="imh"), workers=1, progress=False, chain_path=tmp_path / "c.npz", engine=ENGINE)
    assert e.value.field == "posterior.sampler" and "chain file" in str(e.value)
    PosteriorSpec(sampler="imh", walkers=1).check(4)  # one chain: the walkers' rule is emcee's


def test_resumed_chain_equals_an_uninterrupted_one(tmp_path):
    full = run_posterior(rebound(), workers=1, progress=False, engine=ENGINE)
    path = tmp_path / "chain.npz"

    def stop(done, total):
        if done == 23:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        run_posterior(rebound(checkpoint_every=10), workers=1, progress=stop, chain_path=path, engine=ENGINE)
    assert load_chain(path)["z"].shape[0] == 23  # written when stopped, not only every 10 steps
    resumed = run_posterior(rebound(), workers=2, progress=False, chain_path=path, engine=ENGINE)
    assert resumed.n_resumed == 23
    assert np.array_equal(resumed.chain, full.chain) and np.array_equal(resumed.log_prob, full.log_prob)
    assert np.array_equal(resumed.blobs, full.blobs, equal_nan=True)
    assert np.array_equal(resumed.accepted, full.accepted)
    assert resumed.percentiles == full.percentiles
    # more steps later continue the same chain
    more = run_posterior(rebound(), steps=70, workers=1, progress=False, chain_path=path, engine=ENGINE)
    assert more.n_resumed == 60 and np.array_equal(more.chain[:60], full.chain)
    # another seed is another chain: its file is refused
    with pytest.raises(ScenarioError, match="another scenario, prior, start or seed"):
        run_posterior(rebound(seed=9), workers=1, progress=False, chain_path=path, engine=ENGINE)


@pytest.mark.slow  # 4-10 s (tests/reconstruct --durations, 2-core machine)
def test_dask_cluster_equals_local():
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed")
    local = run_posterior(rebound(), workers=1, progress=False, engine=ENGINE)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cl:
        remote = run_posterior(rebound(), dask_address=cl.scheduler_address, progress=False, engine=ENGINE)
    assert remote.backend == "dask"
    assert np.array_equal(local.chain, remote.chain) and np.array_equal(local.log_prob, remote.log_prob)
    assert np.array_equal(local.blobs, remote.blobs, equal_nan=True)


def test_uncertainty_prior_is_the_distribution_truncated_to_the_bounds():
    """prior = "uncertainty": the [uncertainty] normal of the speed, cut at the [fit] bounds, adds
    -(v - mean)^2 / (2 sd^2) to the log-posterior (the likelihood is unchanged)."""
    from crashsim.reconstruct.fit import FitSpec
    from crashsim.reconstruct.posterior import PosteriorProblem, build_priors

    data = rebound()
    data["uncertainty"] = {"inputs": [{"path": "vehicles.car.speed", "distribution": "normal", "mean": "9 m/s",
                                       "sd": "0.5 m/s"}]}
    fs = FitSpec.from_dict(data["fit"], data)
    flat = PosteriorProblem(data, fs, build_priors(data, fs, "fit"), engine=ENGINE)
    norm = PosteriorProblem(data, fs, build_priors(data, fs, "uncertainty"), engine=ENGINE)
    for v in (7.0, 9.7):
        z = flat.fit.z_of([v])
        assert norm.log_prob(z)[0] - flat.log_prob(z)[0] == pytest.approx(-((v - 9.0) / 0.5) ** 2 / 2, rel=1e-12)
    assert norm.log_prior(flat.fit.z_of([HI + 0.1])) == -math.inf


def test_a_scene_that_cannot_be_evaluated_has_probability_zero_and_is_counted():
    """A run-out over its time limit: log-posterior -inf (never accepted), NaN derived values, and
    its reason, which the pools tally for the report."""
    from crashsim.reconstruct.fit import FitSpec
    from crashsim.reconstruct.parallel import Executor
    from crashsim.reconstruct.posterior import PosteriorProblem, _EmceePool, build_priors

    data = rebound()
    fs = FitSpec.from_dict(data["fit"], data)
    ok = PosteriorProblem(data, fs, build_priors(data, fs, "fit"), engine="scipy")
    keys = ok.derived_keys(ok.fit.z_of([9.0]))
    slow = PosteriorProblem(data, fs, build_priors(data, fs, "fit"), engine="scipy", sample_time_limit=1e-9,
                            derived=keys)
    lp, blob, reason = slow.evaluate(ok.fit.z_of([9.0]))
    assert lp == -math.inf and np.isnan(blob).all() and len(blob) == len(keys)
    assert reason == "run-out: wall_time_limit"
    pool = _EmceePool(Executor(None, {}, "serial", local=slow))
    assert [r[0] for r in pool.map(None, [ok.fit.z_of([8.0]), ok.fit.z_of([9.0])])] == [-math.inf, -math.inf]
    assert pool.failures == {"run-out: wall_time_limit": 2} and pool.evaluations == 2
    # outside the prior's support: -inf without running the scene, and not a failure
    assert ok.evaluate(np.array([1.2]))[0] == -math.inf and ok.evaluate(np.array([1.2]))[2] is None


# ---------------------------------------------------------------------------------------------
# Bad input: one line naming the file, the key and the value; the CLI exits 2
# ---------------------------------------------------------------------------------------------

def _cli(tmp_path, data, *args, capsys):
    import tomli_w

    from crashsim.cli import main

    f = tmp_path / "scene.toml"
    f.write_text(tomli_w.dumps(data))
    code = main(["posterior", str(f), "--quiet", "--workers", "1", *args])
    out = capsys.readouterr()
    return code, out, str(f)


def _error_line(err: str) -> str:
    """The one input-error line (a first run may also say on stderr that it compiles the kernels)."""
    lines = [ln for ln in err.splitlines() if ln.startswith("crashsim: input error:")]
    assert len(lines) == 1, err
    return lines[0]


def test_prior_excluding_the_initial_value(tmp_path, capsys):
    data = rebound(prior="uncertainty")
    data["uncertainty"] = {"inputs": [{"path": "vehicles.car.speed", "distribution": "uniform", "lower": "10 m/s",
                                       "upper": "10.4 m/s"}]}
    with pytest.raises(ScenarioError) as e:
        run_posterior(data, workers=1, progress=False, engine=ENGINE)
    assert e.value.field == "fit.unknowns[0].initial" and "excludes its initial value 9.5" in str(e.value)
    code, out, f = _cli(tmp_path, data, capsys=capsys)
    assert code == 2
    line = _error_line(out.err)
    assert f in line and "fit.unknowns[0].initial" in line and "9.5" in line


def test_a_chain_too_short_for_its_diagnostics(tmp_path, capsys):
    with pytest.raises(ScenarioError) as e:
        PosteriorSpec(steps=60, burn=20).check(1)
    assert e.value.field == "posterior.steps" and f"allowed steps >= {20 + MIN_KEPT_STEPS}" in str(e.value)
    code, out, f = _cli(tmp_path, rebound(), "--steps", "30", capsys=capsys)
    assert code == 2
    line = _error_line(out.err)
    assert f in line and "posterior.steps" in line and "steps = 30" in line
    assert f"at least {MIN_KEPT_STEPS} kept" in line
    with pytest.raises(ScenarioError, match="walkers = 1: .* >= 2"):
        PosteriorSpec(walkers=1).check(1)
    with pytest.raises(ScenarioError, match="posterior.burn: burn = 60 discards"):
        PosteriorSpec(steps=60, burn=60).check(1)


def test_a_sigma_of_zero(tmp_path, capsys):
    data = rebound()
    data["evidence"]["rest"][0]["sigma"] = "0 m"
    code, out, f = _cli(tmp_path, data, capsys=capsys)
    assert code == 2
    line = _error_line(out.err)
    assert f in line and "evidence.rest[0].sigma" in line and "0 m" in line


def test_cli_json_and_plots(tmp_path, capsys):
    code, out, _ = _cli(tmp_path, rebound(), "--json", "--plots", str(tmp_path / "figs"), "--units", "us",
                        capsys=capsys)
    assert code == 0
    d = json.loads(out.out)
    assert set(d) >= {"success", "message", "unknowns", "derived", "labels", "correlation", "diagnostics",
                      "evaluations", "failure_reasons", "warnings", "spec", "best"}
    u = d["unknowns"][0]
    assert u["path"] == "vehicles.car.speed" and set(u["percentiles"]) == {"p2.5", "p16", "p50", "p84", "p97.5",
                                                                           "mean", "sd"}
    assert set(d["diagnostics"]) >= {"acceptance_mean", "tau", "ess", "kept_steps", "chain_long_enough"}
    assert d["spec"]["steps"] == 60 and len(d["correlation"]) == len(d["labels"])
    for name in ("posterior_corner.png", "posterior_trace.png"):
        assert (tmp_path / "figs" / name).stat().st_size > 10_000
    code, out, _ = _cli(tmp_path, rebound(), "--units", "US", capsys=capsys)
    assert code == 0 and "mph" in out.out and "Diagnostics" in out.out and "autocorrelation time" in out.out


def test_the_shipped_fit_scene_has_a_valid_posterior_table():
    from pathlib import Path

    from crashsim.schema import load_toml

    raw = load_toml(Path(__file__).resolve().parents[2] / "scenarios" / "fit" / "intersection_fit.toml")
    spec = PosteriorSpec.from_dict(raw["posterior"])
    spec.check(len(raw["fit"]["unknowns"]))
    assert spec.start == "fit" and spec.prior == "fit" and spec.sampler == "imh"
    assert spec.ess == 1000 and spec.tolerance == "evidence" and spec.steps > spec.burn_steps


def test_logpdf_of_the_distributions():
    """InputDistribution.logpdf: a triangular density integrates to 1 and peaks at 2/(b-a); the
    normal's is its exponent; zero density (-inf) outside the support."""
    from crashsim.reconstruct.montecarlo import InputDistribution

    tri = InputDistribution("p", "p", "triangular", "dimensionless", lower=1.0, upper=4.0, mode=2.0)
    x = np.linspace(1.0, 4.0, 30001)
    p = np.exp([tri.logpdf(v) for v in x])
    assert float(np.trapezoid(p, x)) == pytest.approx(1.0, abs=1e-6)
    assert math.exp(tri.logpdf(2.0)) == pytest.approx(2 / 3)
    assert tri.logpdf(0.99) == -math.inf and tri.logpdf(4.01) == -math.inf
    nrm = InputDistribution("p", "p", "normal", "dimensionless", mean=1.0, sd=0.5, lower=0.0)
    assert nrm.logpdf(2.0) == pytest.approx(-2.0) and nrm.logpdf(-0.1) == -math.inf
    uni = copy.deepcopy(InputDistribution("p", "p", "uniform", "dimensionless", lower=0.0, upper=1.0))
    assert uni.logpdf(0.5) == 0.0 and uni.logpdf(1.5) == -math.inf


def test_settle_step_of_a_climbing_log_probability():
    from crashsim.reconstruct.posterior import settle_step

    rng = np.random.default_rng(1)
    steps, walkers = 200, 16
    climb = np.minimum(np.arange(steps), 50)[:, None] * 2.0 - 100.0  # climbs 100 over 50 steps, then flat
    lp = climb + rng.normal(0.0, 0.5, (steps, walkers))
    s = settle_step(lp, 2)
    assert 48 <= s <= 51
    assert settle_step(rng.normal(0.0, 0.5, (steps, walkers)), 2) == 0  # settled from the start


def test_a_burn_in_shorter_than_the_climb_warns(caplog):
    """Walkers started in a tight ball at 9.5 m/s climb to the posterior; with burn = 0 the
    summaries include the climb, and the result says from which step the chain has settled."""
    from crashsim.reconstruct.posterior import settle_step

    res = run_posterior(rebound(steps=60, burn=0, init_scale=0.001), workers=1, progress=False, engine=ENGINE)
    s = settle_step(res.log_prob, 1)
    assert s is not None and s > 0  # it does climb
    (w,) = [w for w in res.warnings if "log-probability settles only at step" in w]
    assert f"step {s} " in w and "after the burn-in of 0 steps" in w and f"posterior.burn >= {s}" in w
    assert any(r.name == "crashsim" and f"settles at step {s}" in r.getMessage() for r in caplog.records)
    later = run_posterior(rebound(steps=s + 60, burn=s, init_scale=0.001), workers=1, progress=False, engine=ENGINE)
    assert not [w for w in later.warnings if "settles only" in w]


@pytest.mark.slow  # 4-10 s (tests/reconstruct --durations, 2-core machine)
def test_a_target_effective_sample_size_stops_the_chain_where_it_is_met():
    """With ``ess`` the chain stops at the first check that meets it (every unknown >= ess
    effective samples, 50 tau kept, a burn-in of two tau); the chain up to there is the same as a
    chain of fixed length with the same seed (stopping does not change what was drawn)."""
    target = dict(walkers=8, steps=3000, seed=5, init_scale=0.1, move="de")

    def scene(**kw):
        data = rebound(**{**target, **kw})
        del data["posterior"]["burn"]  # the default: a quarter of the steps run
        return data

    res = run_posterior(scene(ess=400, check_every=50), workers=1, progress=False, engine=ENGINE)
    assert res.steps < 3000 and res.steps % 50 == 0
    assert np.all(res.ess >= 400) and res.success, res.warnings
    kept = res.samples.shape[0] // 8
    assert kept >= 50 * float(np.max(res.tau)) and res.spec.burn_steps == res.steps // 4
    assert f"met at step {res.steps}" in res.report()
    # the check one step earlier did not meet it: the stop is the first that does
    fixed = run_posterior(scene(steps=res.steps), workers=1, progress=False, engine=ENGINE)
    assert np.array_equal(fixed.chain, res.chain)
    from crashsim.reconstruct.posterior import _enough

    z = list((res.chain - LO) / (HI - LO))
    assert _enough(z, res.spec) and not _enough(z[:res.steps - 50], res.spec)


def test_samples_integrate_at_the_tolerance_their_evidence_needs():
    """The rule: rtol = 0.01 sigma / D (D the longest CG path), never tighter than the file's, at
    most 1e-4; atol scaled with it. Here sigma = 0.2 m and the rebound slides d ~ 1.9 m: the rule
    asks 1.06e-3, capped at 1e-4."""
    from crashsim.reconstruct.tolerance import LOOSEST_RTOL, evidence_tolerance

    res = run_posterior(rebound(), workers=1, progress=False, engine=ENGINE)
    tol = res.tolerance
    assert tol is not None and tol.file_rtol == 1e-8 and tol.rtol == LOOSEST_RTOL
    assert tol.atol == pytest.approx(tol.file_atol * LOOSEST_RTOL / 1e-8, rel=1e-12)
    assert "run-out tolerance of the samples: rtol 0.0001 (file 1e-08)" in res.report()
    assert res.to_dict()["tolerance"]["rtol"] == LOOSEST_RTOL
    # the sampled scenes run at it: the nominal scene's options
    assert res.nominal.scenario.runout.options.rtol == LOOSEST_RTOL
    # "file" keeps the file's tolerance
    assert run_posterior(rebound(tolerance="file"), workers=1, progress=False, engine=ENGINE).tolerance is None

    class Item:
        def __init__(self, kind, quantity, sigma):
            self.kind, self.quantity, self.sigma = kind, quantity, sigma

    scene = res.nominal
    path = max(b.distance for r in scene.runout.values() for b in r.bodies.values())
    # a tight sigma: the rule itself, between the file's rtol and the cap
    got = evidence_tolerance([Item("rest", "length", 0.002)], scene, 1e-8, 1e-10)
    assert got.rtol == pytest.approx(0.01 * 0.002 / path, rel=1e-12) and got.atol == pytest.approx(got.rtol / 100)
    # tighter than the file's: the file's stays
    assert evidence_tolerance([Item("rest", "length", 1e-9)], scene, 1e-8, 1e-10).rtol == 1e-8
    # evidence the run-out does not reach sets no bound; a looser file tolerance is kept
    assert not evidence_tolerance([Item("delta-v", "speed", 0.1)], scene, 1e-8, 1e-10).changed
    assert evidence_tolerance([Item("rest", "length", 1.0)], scene, 1e-3, 1e-5).rtol == 1e-3


def test_a_us_report_shows_its_lengths_in_ft_and_names_every_correlation_column():
    """A US report: the tolerance sentence's sigma and CG path in ft (it printed them in m), and every
    column of the correlation matrix named -- the derived quantities' columns, which have no row, in a
    line below it (they were numbers without a name)."""
    import re

    res = run_posterior(rebound(), workers=1, progress=False, engine=ENGINE)
    us, si = res.report("US"), res.report("SI")
    rule = next(line for line in us.splitlines() if line.startswith("run-out tolerance of the samples"))
    assert "0.656 ft" in rule and "longest CG path" in rule and not re.search(r"\d m\b", rule), rule
    assert "0.2 m" in next(line for line in si.splitlines() if line.startswith("run-out tolerance"))
    assert res.tolerance.rule == res.tolerance.text("SI")  # the JSON's sentence: SI
    lines = us.splitlines()
    i = lines.index("Posterior correlation (unknowns; derived quantities in the columns after them)")
    labels = res.labels
    assert len(labels) > len(res.unknowns)  # derived columns exist here
    legend = lines[i + 2 + len(res.unknowns)]
    for j, lab in enumerate(labels[len(res.unknowns):], start=len(res.unknowns) + 1):
        assert f"{j} {lab}" in legend, legend


def test_a_short_chain_s_advice_fits_its_sampler():
    """An ensemble's chain file continues a run; the independence sampler keeps none (one chain, run
    again): the warning of a chain shorter than TAU_FACTOR autocorrelation times says which."""
    ens = _too_short(1500, 38.0, 2399, "emcee")
    one = _too_short(15000, 1407.4, 75370, "imh")
    assert f"1500 kept steps per walker are {1500 / 38.0:.1f} autocorrelation times" in ens
    assert "run about 2399 steps (a chain file continues where it stopped)" in ens
    assert "15000 kept steps are 10.7" in one and "per walker" not in one and "continues" not in one
    assert "run about 75370 steps (posterior.steps or --steps; the independence sampler keeps no chain file" in one
    assert f"at least {TAU_FACTOR} are needed" in one and "run about" not in _too_short(10, math.inf, None, "imh")

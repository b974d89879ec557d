"""Monte Carlo: reproducibility by (seed, index), streaming and resume, Dask equals local."""

from __future__ import annotations

import json

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.reconstruct.montecarlo import UncertaintySpec, load_results, monte_carlo, sample_inputs

from scenes import ENGINE, car_car, with_evidence

SPEC = {"samples": 6, "seed": 42, "inputs": [
    {"path": "vehicles.A.speed", "distribution": "normal", "mean": "27 mph", "sd": "2 mph", "lower": "20 mph"},
    {"path": "vehicles.B.speed", "distribution": "triangular", "lower": "18 mph", "mode": "22 mph",
     "upper": "25 mph"},
    {"path": "runout.road_friction", "distribution": "uniform", "lower": "0.65", "upper": "0.85"},
]}


@pytest.fixture(scope="module")
def data():
    return with_evidence(car_car(), [], [], seed=1, delta_v=[("carB", "longitudinal")])


def _same(a, b):
    assert np.array_equal(a.indices, b.indices)
    assert np.array_equal(a.inputs, b.inputs)
    assert a.outputs.keys() == b.outputs.keys()
    for k in a.outputs:
        assert np.array_equal(a.outputs[k], b.outputs[k], equal_nan=True), k
    for k in a.checks:
        assert np.array_equal(a.checks[k][1], b.checks[k][1]), k
    assert a.percentiles == b.percentiles
    assert a.pass_share == b.pass_share


def test_inputs_depend_only_on_seed_and_index():
    spec = UncertaintySpec.from_dict(SPEC)
    x3 = sample_inputs(spec, 42, 3)
    assert np.array_equal(x3, sample_inputs(spec, 42, 3))
    assert not np.array_equal(x3, sample_inputs(spec, 43, 3))
    assert not np.array_equal(x3, sample_inputs(spec, 42, 4))
    big = np.array([sample_inputs(spec, 7, i) for i in range(4000)])
    assert np.all(big[:, 0] >= 20 * 0.44704)                     # truncated normal
    assert np.mean(big[:, 0]) == pytest.approx(27 * 0.44704, rel=0.01)
    assert big[:, 1].min() >= 18 * 0.44704 and big[:, 1].max() <= 25 * 0.44704
    assert np.mean(big[:, 2]) == pytest.approx(0.75, abs=0.005)


def test_reproducible_and_streamed(data, tmp_path):
    out = tmp_path / "mc.jsonl"
    a = monte_carlo(data, SPEC, workers=2, out_path=out, progress=False, engine=ENGINE)
    b = monte_carlo(data, SPEC, workers=1, progress=False, engine=ENGINE)
    _same(a, b)
    assert a.n_done == 6 and a.n_failed == 0
    lines = out.read_text().splitlines()
    assert json.loads(lines[0])["format"] == "crashsim-mc/1" and len(lines) == 7
    assert set(a.pass_share) >= {"rest: rest of carA", "delta-v: delta-v of carB (longitudinal)", "all evidence"}
    assert a.tornado and all(len(rows) == 3 for rows in a.tornado.values())
    # B's speed moves B's delta-v most; road friction does not move it at all (impact only)
    rows = a.tornado["delta_v.carB"]
    assert rows[0]["path"] == "vehicles.B.speed" and rows[-1]["swing"] == 0.0
    d = a.to_dict()
    assert d["n_done"] == 6 and "delta_v.carB" in d["percentiles"]
    assert "Share of samples" in a.report("US")
    c = load_results(out)
    assert np.array_equal(c.inputs, a.inputs) and c.percentiles == a.percentiles


def test_resume_after_interruption(data, tmp_path):
    full = monte_carlo(data, SPEC, workers=1, progress=False, engine=ENGINE)
    out = tmp_path / "mc.jsonl"

    def stop_after_two(done, total):
        if done >= 2:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        monte_carlo(data, SPEC, workers=1, out_path=out, progress=stop_after_two, engine=ENGINE)
    assert len(out.read_text().splitlines()) == 1 + 2
    with out.open("a") as fh:  # a torn last line, as a kill in the middle of a write leaves
        fh.write('{"i": 5, "x": [1.0')
    resumed = monte_carlo(data, SPEC, workers=2, out_path=out, progress=False, engine=ENGINE)
    assert resumed.n_resumed == 2
    _same(full, resumed)
    assert len(out.read_text().splitlines()) == 1 + 6
    # more samples later: the first six are read, not recomputed
    more = monte_carlo(data, SPEC, 8, workers=1, out_path=out, progress=False, engine=ENGINE)
    assert more.n_resumed == 6 and more.n_done == 8
    assert np.array_equal(more.inputs[:6], full.inputs)


def test_results_file_of_another_run_is_refused(data, tmp_path):
    out = tmp_path / "mc.jsonl"
    monte_carlo(data, SPEC, 1, workers=1, out_path=out, progress=False, engine=ENGINE)
    with pytest.raises(ScenarioError, match="another scenario or seed"):
        monte_carlo(data, SPEC, 2, seed=1, workers=1, out_path=out, progress=False, engine=ENGINE)


def test_spec_errors():
    bad = {"inputs": [{"path": "vehicles.A.speed", "distribution": "triangular", "lower": "1 m/s", "upper": "2 m/s"}]}
    with pytest.raises(ScenarioError) as e:
        UncertaintySpec.from_dict(bad)
    assert e.value.field == "uncertainty.inputs[0].mode"
    bad = {"inputs": [{"path": "vehicles.A.speed", "distribution": "uniform", "lower": "1 m/s", "upper": "2 m/s",
                       "sd": "1 m/s"}]}
    with pytest.raises(ScenarioError) as e:
        UncertaintySpec.from_dict(bad)
    assert e.value.field == "uncertainty.inputs[0].sd"
    bad = {"inputs": [{"path": "vehicles.A.speed", "distribution": "gauss", "mean": "1 m/s", "sd": "1 m/s"}]}
    with pytest.raises(ScenarioError, match="did you mean 'uniform'|allowed"):
        UncertaintySpec.from_dict(bad)


def test_a_distribution_beyond_the_allowed_range_is_refused_not_dropped(data):
    """A sample outside an input's allowed range would be invalid: such a distribution is refused
    at load (naming the bound and the range), never sampled and silently dropped."""
    spec = {"inputs": [{"path": "impact.restitution", "distribution": "uniform", "lower": "0.5", "upper": "1.5"}]}
    with pytest.raises(ScenarioError, match=r"uncertainty.inputs\[0\].upper: upper = '1.5' lies outside the allowed "
                                            r"range of impact.restitution, \[0, 1\]"):
        monte_carlo(data, spec, 6, seed=3, workers=1, progress=False, engine=ENGINE)
    wide = {"inputs": [{"path": "runout.road_friction", "distribution": "normal", "mean": "0.3", "sd": "0.35"}]}
    with pytest.raises(ScenarioError, match=r"puts 19.6 % of its samples outside the allowed range \(0, 2\]"):
        UncertaintySpec.from_dict(wide)


@pytest.mark.slow  # 4-10 s (tests/reconstruct --durations, 2-core machine)
def test_a_normal_distribution_with_a_small_tail_outside_is_truncated_and_said_so(data):
    """0.62 % of N(0.1, 0.04) lies below e = 0: truncated to [0, 1], the report says so, and
    every sample is valid (none fails)."""
    spec = {"inputs": [{"path": "impact.restitution", "distribution": "normal", "mean": "0.1", "sd": "0.04"}]}
    d = UncertaintySpec.from_dict(spec).inputs[0]
    assert (d.lower, d.upper) == (0.0, 1.0) and "truncated to the allowed range [0, 1] (0.62 %" in d.note
    xs = np.array([sample_inputs(UncertaintySpec.from_dict(spec), 5, i)[0] for i in range(3000)])
    assert xs.min() >= 0.0 and (xs < 0.005).any()
    res = monte_carlo(data, spec, 4, seed=3, workers=1, progress=False, engine=ENGINE)
    assert res.n_failed == 0 and "truncated to the allowed range" in res.report()


def test_failed_samples_are_recorded_with_their_reason(data):
    """An impulse ratio beyond mu_max is inadmissible: those samples fail with that reason, are
    kept out of the figures, and the report tallies them; the run goes on."""
    from crashsim import solve_impact
    from crashsim.scenario import scenario_from_dict

    ratio = dict(data, impact=dict(data["impact"], tangential="ratio", mu=-0.1))
    ratio["impact"].pop("friction")
    no_slide = dict(data, impact={k: v for k, v in data["impact"].items() if k != "friction"} | {"tangential": "no_slide"})
    mu_max = solve_impact(scenario_from_dict(no_slide).impact).mu_max
    spec = {"inputs": [{"path": "impact.mu", "distribution": "uniform", "lower": "-1.2", "upper": "0.0"}]}
    res = monte_carlo(ratio, spec, 8, seed=3, workers=1, progress=False, engine=ENGINE)
    bad = res.inputs[:, 0] < mu_max
    assert -1.2 < mu_max < 0 and bad.any() and (~bad).any()
    assert res.n_failed == int(bad.sum())
    assert res.failure_reasons == {"inadmissible impact: impulse ratio beyond mu_max (sliding reverses)": int(bad.sum())}
    assert all("exceeds mu_max" in m for _, m in res.errors)
    assert np.isnan(res.outputs["delta_v.carA"][bad]).all() and np.isfinite(res.outputs["delta_v.carA"][~bad]).all()
    text = res.report()
    assert f"{int(bad.sum()):6d}  inadmissible impact: impulse ratio beyond mu_max" in text
    assert res.to_dict()["failure_reasons"] == res.failure_reasons


def test_a_sample_over_its_time_limit_fails_with_that_reason_and_the_run_goes_on(data):
    res = monte_carlo(data, SPEC, 3, workers=1, progress=False, engine="scipy", sample_time_limit=1e-9)
    assert res.n_failed == 3 and res.failure_reasons == {"run-out: wall_time_limit": 3}
    assert all("max_wall_time = 1e-09 s of computing time used up" in m for _, m in res.errors)


def test_dask_cluster_equals_local(data):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed")
    local = monte_carlo(data, SPEC, 4, workers=1, progress=False, engine=ENGINE)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cl:
        remote = monte_carlo(data, SPEC, 4, dask_address=cl.scheduler_address, progress=False, engine=ENGINE,
                             chunk_size=1)
    assert remote.backend == "dask"
    _same(local, remote)


def test_whole_event_outputs_of_a_joint_run_out():
    """With later impacts, each body's delta-v over the whole event (the magnitude of the sum of
    its impacts' velocity changes) and the number of later impacts are outputs too; the waiting
    car of the third-vehicle scene, in no first impact, has only the whole-event one."""
    from pathlib import Path

    from crashsim.evidence.checks import body_impacts
    from crashsim.reconstruct.montecarlo import scene_outputs
    from crashsim.scene.run import run_scene
    from crashsim.scenario import load_scenario

    scene = run_scene(load_scenario(Path(__file__).resolve().parents[2] / "scenarios" / "scenes"
                                    / "third_vehicle_waiting_car.toml"))
    out = scene_outputs(scene)
    assert out["impacts.later"] == len(scene.joint.impacts) >= 3
    assert "delta_v.waiting" not in out
    own = body_impacts("waiting", scene.impact, scene.joint.impacts)
    assert out["delta_v_event.waiting"] == pytest.approx(float(np.hypot(*sum(d for d, _ in own))))
    assert out["delta_v_event.striker"] != pytest.approx(out["delta_v.striker"])  # the trailer's blow adds


def test_accept_keeps_the_samples_that_meet_all_the_evidence(data, tmp_path):
    """Rejection sampling: a sample is accepted when every evidence check passes; the accepted
    percentiles are those of the accepted samples; a resumed or re-read file knows the same."""
    out = tmp_path / "mc.jsonl"
    spec = dict(SPEC, samples=12)
    res = monte_carlo(data, spec, workers=1, out_path=out, progress=False, engine=ENGINE, accept=True)
    every = np.all(np.column_stack([ok for _, ok in res.checks.values()]), axis=1)
    assert res.n_evidence == 5 and np.array_equal(res.meets_all, every)
    assert 0 < res.n_accepted < res.n_done == 12  # this seed gives both
    assert res.accepted_share == pytest.approx(res.n_accepted / 12)
    assert res.pass_share["all evidence"] == pytest.approx(res.accepted_share)  # no failed sample here
    v = res.outputs["rest_x.carA"][every]
    assert res.accepted_percentiles["rest_x.carA"]["p50"] == pytest.approx(float(np.median(v)))
    assert res.accepted_percentiles["rest_x.carA"]["p95"] == pytest.approx(float(np.percentile(v, 95)))
    speed_b = res.inputs[every, 1]
    name_b = res.spec.inputs[1].name
    assert res.accepted_input_percentiles[name_b]["p5"] == pytest.approx(float(np.percentile(speed_b, 5)))
    d = res.to_dict()["accepted"]
    assert d["count"] == res.n_accepted and d["share"] == pytest.approx(res.accepted_share) and d["of"] == 12
    assert d["indices"] == [int(i) for i in np.nonzero(every)[0]]
    assert set(d["percentiles"]) == set(res.percentiles) and name_b in d["inputs"]
    text = res.report("US")
    headline = f"{100 * res.n_accepted / 12:.3g} % of 12 samples meet all 5 evidence items"
    assert f"Accepted samples (rejection sampling): {headline}" in text
    assert "accepted  " in text and "the inputs given the evidence" in text
    # read back from the results file, and resumed with more samples: the same verdicts
    back = load_results(out, accept=True)
    assert np.array_equal(back.meets_all, res.meets_all) and back.accepted_percentiles == res.accepted_percentiles
    more = monte_carlo(data, spec, 14, workers=1, out_path=out, progress=False, engine=ENGINE, accept=True)
    assert more.n_resumed == 12 and np.array_equal(more.meets_all[:12], res.meets_all)
    # without accept nothing changes but the summary: no "accepted" key, no section
    plain = monte_carlo(data, spec, workers=1, progress=False, engine=ENGINE)
    assert "accepted" not in plain.to_dict() and "rejection sampling" not in plain.report()
    assert np.array_equal(plain.meets_all, res.meets_all)


def test_accept_with_no_sample_meeting_the_evidence(data):
    tight = {**data, "evidence": {**data["evidence"],
                                  "rest": [dict(r, tolerance="1 mm") for r in data["evidence"]["rest"]]}}
    res = monte_carlo(tight, SPEC, 4, workers=1, progress=False, engine=ENGINE, accept=True)
    assert res.n_accepted == 0 and res.accepted_percentiles == {} and res.accepted_input_percentiles == {}
    assert res.to_dict()["accepted"]["count"] == 0 and res.to_dict()["accepted"]["percentiles"] == {}
    text = res.report()
    assert "0 % of 4 samples meet all 5 evidence items" in text and "NO sample meets all the evidence" in text


def test_cli_accept(data, tmp_path, capsys):
    import tomli_w

    from crashsim.cli import main

    f = tmp_path / "scene.toml"
    f.write_text(tomli_w.dumps({**data, "uncertainty": dict(SPEC, samples=4)}))
    assert main(["mc", str(f), "--accept", "--json", "--quiet", "--workers", "1"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert set(out["accepted"]) >= {"count", "share", "percentiles", "indices"}
    bare = {k: v for k, v in data.items() if k != "evidence"}
    f.write_text(tomli_w.dumps({**bare, "uncertainty": dict(SPEC, samples=4)}))
    assert main(["mc", str(f), "--accept", "--quiet"]) == 2
    assert "--accept" in capsys.readouterr().err


def test_samples_at_the_tolerance_of_their_evidence_checks(data):
    """[uncertainty] tolerance = "evidence": the samples integrate at the loosest rtol whose error
    bound stays at 1 % of the smallest tolerance of the run-out's evidence checks (at most 1e-4);
    their rest positions move by less than that share of the tolerance against the file's
    tolerance, and every verdict is the same."""
    from crashsim.reconstruct.tolerance import LOOSEST_RTOL

    a = monte_carlo(data, SPEC, workers=1, progress=False, engine=ENGINE)
    b = monte_carlo(data, dict(SPEC, tolerance="evidence"), workers=1, progress=False, engine=ENGINE)
    assert a.tolerance is None and b.tolerance is not None and b.tolerance.changed
    assert b.tolerance.file_rtol == a.nominal.scenario.runout.options.rtol
    assert a.nominal.scenario.runout.options.rtol < b.tolerance.rtol <= LOOSEST_RTOL
    assert b.nominal.scenario.runout.options.rtol == b.tolerance.rtol
    assert "run-out tolerance of the samples: rtol" in b.report() and b.to_dict()["tolerance"]["rtol"] == b.tolerance.rtol
    tol = min(r.tolerance for r in a.nominal.scenario.evidence.rest)
    assert np.array_equal(a.inputs, b.inputs)
    keys = [k for k in a.outputs if k.startswith("rest_x.") or k.startswith("rest_y.")]
    assert keys
    for k in keys:
        assert np.max(np.abs(a.outputs[k] - b.outputs[k])) < 0.01 * tol, k
    for k in a.checks:
        assert np.array_equal(a.checks[k][1], b.checks[k][1]), k


def test_tornado_of_a_scene_with_an_approach_starts_from_the_approach():
    """With an approach the impact speeds come from the approach: the one-at-a-time swings run it (they used the
    file's impact as written, with no speed for the approaching vehicle: 0 delta-v and 0 swings)."""
    from crashsim.reconstruct.montecarlo import _swings
    from crashsim.reconstruct.overrides import ScenarioOverrides
    from crashsim.scene.run import run_scene

    from test_approach_fit import approach_scene

    data = approach_scene()
    spec = UncertaintySpec.from_dict({"inputs": [
        {"path": "vehicles.A.approach.speed", "distribution": "normal", "mean": "17 m/s", "sd": "0.5 m/s"},
        {"path": "vehicles.A.approach.reaction_time", "distribution": "uniform", "lower": "0.8 s", "upper": "1.2 s"}]})
    swings, nominal = _swings(data, spec, ENGINE, None)
    median = run_scene(ScenarioOverrides(data, spec.paths, engine=ENGINE).scenario(
        np.array([d.median for d in spec.inputs])))
    for key, (base, lowhigh) in swings.items():
        body = key.split(".", 1)[1]
        assert base == pytest.approx(median.impact.bodies[body].delta_v_magnitude, rel=1e-12) and base > 1.0
        speed_low, speed_high = lowhigh[0]
        assert speed_high - speed_low > 0.1  # a faster approach hits harder
        assert lowhigh[1] == (base, base)  # the reaction time before braking does not change the impact speed

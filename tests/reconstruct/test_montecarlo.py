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


def test_failed_samples_are_recorded(data):
    spec = {"inputs": [{"path": "impact.restitution", "distribution": "uniform", "lower": "0.5", "upper": "1.5"}]}
    res = monte_carlo(data, spec, 6, seed=3, workers=1, progress=False, engine=ENGINE)
    bad = res.inputs[:, 0] > 1.0
    assert bad.any() and res.n_failed == int(bad.sum())
    assert all("restitution" in m for _, m in res.errors)
    assert np.isnan(res.outputs["delta_v.carA"][bad]).all()


def test_dask_cluster_equals_local(data):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed")
    local = monte_carlo(data, SPEC, 4, workers=1, progress=False, engine=ENGINE)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False, dashboard_address=None) as cl:
        remote = monte_carlo(data, SPEC, 4, dask_address=cl.scheduler_address, progress=False, engine=ENGINE,
                             chunk_size=1)
    assert remote.backend == "dask"
    _same(local, remote)

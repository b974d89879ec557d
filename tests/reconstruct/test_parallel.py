"""The one parallel-execution module (crashsim.reconstruct.parallel): the backend, the chunking and
the number of workers never change a number, and the seeds follow the documented rule."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from crashsim.reconstruct.fit import fit_scene
from crashsim.reconstruct.montecarlo import UncertaintySpec, sample_inputs
from crashsim.reconstruct.parallel import Executor, Progress, child_seed, choose_backend, chunk_size, chunks

from scenes import ENGINE, car_car, with_evidence


def _state(payload):
    return np.random.default_rng(child_seed(payload["seed"], 0)).normal(size=3)


def _work(state, item):
    return float(state @ np.array([item, item * item, 1.0]))


@pytest.mark.parametrize("backend, workers, size", [("serial", 1, 1), ("processes", 2, 1), ("processes", 2, 3),
                                                    ("processes", 3, 7)])
def test_every_backend_and_chunking_gives_the_same_results_in_order(backend, workers, size):
    payload = {"seed": 5}
    items = list(range(10))
    want = [_work(_state(payload), i) for i in items]
    with Executor(_state, payload, backend, workers) as ex:
        assert ex.map(_work, items, chunksize=size) == want
        assert list(ex.submit_each(_work, items[:4])) == want[:4]
        got = {}
        for part in ex.as_completed(_keyed, chunks(items, size)):  # any order: keyed by item
            got.update(part)
    assert got == dict(zip(items, want))


def _keyed(state, item):
    return item, _work(state, item)


def test_the_serial_backend_uses_the_state_given():
    calls = []

    def never(payload):  # the factory is not called when the state is given
        calls.append(payload)

    ex = Executor(never, {}, "serial", local=np.array([1.0, 0.0, 0.0]))
    assert ex.map(_work, [2, 3]) == [2.0, 3.0] and not calls


def test_backend_choice_and_chunks():
    assert choose_backend(1) == ("serial", 1)
    assert choose_backend(2, n_tasks=1) == ("serial", 2)
    assert choose_backend(2, n_tasks=5) == ("processes", 2)
    assert choose_backend(2, dask_address="tcp://nowhere:1") == ("dask", 0)
    assert chunk_size(1000, 2) == 64 and chunk_size(10, 2) == 2 and chunk_size(10, 2, 3) == 3
    assert chunks([1, 2, 3, 4, 5], 2) == [[1, 2], [3, 4], [5]]


def test_progress_reports_done_and_total():
    seen = []
    with Progress(lambda done, total: seen.append((done, total)), 5) as bar:
        bar.update(2, 2)
        bar.update(3, 5)
    assert seen == [(2, 5), (5, 5)]
    Progress(False, 5).update(1, 1)  # silent: nothing to call


def test_sample_seeds_follow_the_documented_rule():
    """Sample i's inputs come from default_rng(SeedSequence(seed, spawn_key=(i,))), the i-th child of
    SeedSequence(seed).spawn: the rule the Monte Carlo module states (and its files rely on)."""
    spec = UncertaintySpec.from_dict({"samples": 4, "seed": 9, "inputs": [
        {"path": "vehicles.A.speed", "distribution": "normal", "mean": "10 m/s", "sd": "1 m/s"},
        {"path": "runout.road_friction", "distribution": "uniform", "lower": "0.6", "upper": "0.8"}]}, file=None)
    children = np.random.SeedSequence(9).spawn(4)
    for i in range(4):
        assert child_seed(9, i).spawn_key == children[i].spawn_key == (i,)
        rng = np.random.default_rng(children[i])
        want = np.array([d.sample(rng) for d in spec.inputs])
        assert np.array_equal(sample_inputs(spec, 9, i), want)


def test_fit_on_two_processes_equals_the_fit_in_this_process():
    """The fit's screening and local starts through the executor: the same best point, chi^2 and
    standard errors, bit for bit, whether they run here or on two processes.  (Not the evaluation
    count: a worker keeps its scene evaluations cached from one start to the next, so how many are
    run depends on which worker takes which start; none changes a number.)"""
    paths = ["vehicles.A.speed", "vehicles.B.speed", "runout.road_friction"]
    data = with_evidence(car_car(), paths, [12.0, 10.0, 0.75], delta_v=[("carB", "longitudinal")], seed=11)
    unknown = lambda p, lo, hi, ini: {"path": p, "lower": lo, "upper": hi, "initial": ini}  # noqa: E731
    spec = {"starts": 3, "screen": 6, "seed": 1, "unknowns": [unknown(paths[0], "15 mph", "40 mph", "20 mph"),
            unknown(paths[1], "15 mph", "40 mph", "30 mph"), unknown(paths[2], "0.5", "0.95", "0.6")]}
    calls = []
    one = fit_scene(copy.deepcopy(data), spec, workers=1, engine=ENGINE, progress=lambda d, t: calls.append((d, t)))
    two = fit_scene(copy.deepcopy(data), spec, workers=2, engine=ENGINE)
    assert np.array_equal(one.x, two.x) and one.chi2 == two.chi2 and np.array_equal(one.stderr, two.stderr)
    assert calls == [(1, 3), (2, 3), (3, 3)]

"""A start that stops a few thousandths of chi^2 above the best is at the best minimum: no "other
minima" warning for it (a stranger's fit reported chi^2 7.371 as another minimum beside 7.363)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from crashsim.reconstruct import fit as fitmod


def _outcome(chi2: float, z: float) -> dict:
    return {"cost": chi2 / 2, "z": [z], "z0": [0.5], "evaluations": 10, "status": 1, "message": "ok"}


def _compare(chi2s, zs):
    problem = SimpleNamespace(span=np.ones(1), x_of=lambda z: np.asarray(z, dtype=float),
                              evidence=SimpleNamespace(size=6))
    outcomes = [_outcome(c, z) for c, z in zip(chi2s, zs)]
    warnings: list[str] = []
    starts, n_agree, n_same = fitmod._compare_starts(problem, outcomes, 0, np.array([zs[0]]), np.array([0.05]),
                                                     np.array([False]), warnings)
    return starts, n_agree, n_same, warnings


def test_a_start_a_hair_above_the_best_is_the_same_minimum():
    starts, n_agree, n_same, warnings = _compare([7.363, 7.371], [0.400, 0.401])
    assert n_same == 2 and n_agree == 2 and not any("other minima" in w for w in warnings)


def test_a_start_well_above_the_best_is_another_minimum():
    starts, n_agree, n_same, warnings = _compare([7.363, 9.5], [0.400, 0.9])
    assert n_same == 1 and any("1 of 2 starts ended in other minima (chi^2 9.5)" in w for w in warnings)


def test_percentiles_of_a_count_are_counts():
    """The Monte Carlo percentiles of the later impacts are a count some sample had (it printed 1.5)."""
    from crashsim.reconstruct import montecarlo

    v = np.array([0.0, 1.0, 1.0, 2.0, 2.0, 2.0, 3.0, 0.0, 1.0, 2.0])
    cols = {"impacts.later": v, "delta_v.car": v * 1.25}
    out = montecarlo._percentiles(cols, np.ones(v.size, bool), [5, 50, 95])
    assert all(out["impacts.later"][k] in set(v) for k in ("p5", "p50", "p95"))
    assert out["delta_v.car"]["p50"] == np.percentile(v * 1.25, 50)  # a continuous output as before

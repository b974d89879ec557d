"""The Metropolis-Hastings samplers of ``reconstruct/samplers.py`` on a closed-form posterior.

A linear-Gaussian model: measurements ``y = A x + e`` with ``e ~ N(0, sigma^2 I)`` and a flat
prior on the unit box, whose posterior (the box far wider than it, so the truncation is below
1e-30) is exactly normal with covariance ``S = sigma^2 (A^T A)^-1`` and mean ``S A^T y / sigma^2``.
The chains' mean and covariance must match within four Monte Carlo standard errors computed from
their effective sample sizes (emcee's integrated autocorrelation time, c = 5): for a mean
``sqrt(S_ii / ESS)``, for a covariance entry ``sqrt((S_ii S_jj + S_ij^2) / ESS)`` (the variance of a
product of two normal deviates). The independence sampler gets a proposal built like the fit's:
about the right place but off (a shifted mean, a wider and rotated covariance), and the
adaptive Metropolis sampler the same covariance as its first one.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from emcee.autocorr import integrated_time
from scipy import stats

from crashsim.reconstruct.samplers import (StudentT, adaptive_metropolis, box_covariance, chain_moments,
                                           independence_chain)

RNG = np.random.default_rng(12)
D = 3
A = RNG.normal(size=(8, D))
SIGMA = 0.004
X_TRUE = np.array([0.4, 0.55, 0.6])
Y = A @ X_TRUE + SIGMA * RNG.normal(size=8)
S = SIGMA**2 * np.linalg.inv(A.T @ A)
MU = S @ A.T @ Y / SIGMA**2


def log_post(z):
    z = np.asarray(z, float)
    if np.any(z < 0) or np.any(z > 1):
        return -math.inf
    r = (A @ z - Y) / SIGMA
    return -0.5 * float(r @ r)


def _evaluate(z):
    return log_post(z), np.array([float(np.sum(z))])


def _check_moments(chain):
    """Mean and covariance of ``chain`` (n, d) against MU and S within 4 Monte Carlo standard errors."""
    tau = integrated_time(chain[:, None, :], c=5, quiet=True)
    ess = chain.shape[0] / np.max(tau)
    assert ess > 1000  # tight enough: 4 MCSE of a mean are then < 0.13 sd
    mean = chain.mean(axis=0)
    cov = np.cov(chain, rowvar=False)
    sd = np.sqrt(np.diag(S))
    assert np.all(np.abs(mean - MU) < 4 * sd / math.sqrt(ess)), (mean - MU) / sd
    err = np.sqrt((np.outer(np.diag(S), np.diag(S)) + S**2) / ess)
    assert np.all(np.abs(cov - S) < 4 * err), (cov - S) / err
    return ess


def _proposal_like_a_fit():
    rot = np.linalg.qr(np.random.default_rng(3).normal(size=(D, D)))[0]
    wide = 1.5 * S + 0.5 * rot @ np.diag(np.diag(S)) @ rot.T
    return MU + 0.5 * np.sqrt(np.diag(S)), wide


def test_the_problem_is_posed_inside_the_box():
    assert np.all(MU - 10 * np.sqrt(np.diag(S)) > 0) and np.all(MU + 10 * np.sqrt(np.diag(S)) < 1)


def test_independence_sampler_matches_the_closed_form_posterior():
    """As run_posterior runs it: a burn-in proposing from the fit-like density, the proposal refitted
    to its chain, then a kept chain of that fixed proposal."""
    mean0, cov0 = _proposal_like_a_fit()
    evaluate = lambda ys: [_evaluate(y) for y in ys]  # noqa: E731
    rp, ra = np.random.default_rng(1), np.random.default_rng(2)
    burn = list(independence_chain(evaluate, StudentT.from_cov(mean0, cov0, scale=1.2), (mean0, *_evaluate(mean0)),
                                   500, rp, ra, batch=64))
    m, c = chain_moments(np.array([s[0] for s in burn]))
    steps = list(independence_chain(evaluate, StudentT.from_cov(m, c, scale=1.2), burn[-1][:3], 5000, rp, ra, batch=64))
    chain = np.array([s[0] for s in steps])
    assert all(s[2][0] == float(np.sum(s[0])) for s in steps[::97])  # the blobs follow the state
    ess = _check_moments(chain)
    # an independence sampler from a proposal refitted this way: fewer than 4 evaluations per effective sample
    assert chain.shape[0] / ess < 4
    acc = np.mean([s[3] for s in steps])
    assert 0.5 < acc < 1


def test_the_chain_does_not_depend_on_the_batch_size():
    mean0, cov0 = _proposal_like_a_fit()
    q = StudentT.from_cov(mean0, cov0)
    runs = [np.array([s[0] for s in independence_chain(lambda ys: [_evaluate(y) for y in ys], q,
                                                       (mean0, *_evaluate(mean0)), 300, np.random.default_rng(5),
                                                       np.random.default_rng(6), batch=b)]) for b in (1, 7, 300)]
    assert np.array_equal(runs[0], runs[1]) and np.array_equal(runs[0], runs[2])


def test_adaptive_metropolis_matches_the_closed_form_posterior():
    mean0, cov0 = _proposal_like_a_fit()
    steps = list(adaptive_metropolis(_evaluate, (mean0, *_evaluate(mean0)), cov0, 40000, np.random.default_rng(4)))
    chain = np.array([s[0] for s in steps])
    _check_moments(chain[4000:])


def test_student_t_density_and_box():
    q = StudentT.from_cov(np.array([0.5, 0.5]), np.diag([0.04, 0.01]), nu=5.0)
    # the density of a t with diagonal scale, up to its constant: (1 + m / nu)^(-(nu + d) / 2)
    x = np.array([0.7, 0.4])
    m = 0.2**2 / 0.04 + 0.1**2 / 0.01
    # to the 1e-12 relative jitter from_cov adds to the scale matrix
    assert q.log_density(x) - q.log_density(q.mean) == pytest.approx(-3.5 * math.log1p(m / 5), rel=1e-10)
    rng = np.random.default_rng(0)
    pts = np.array([q.draw_in_box(rng) for _ in range(2000)])
    assert pts.min() >= 0 and pts.max() <= 1
    # a narrow one, which the box cuts beyond 10 scales only (probability 8e-5): its marginal is the t's
    narrow = StudentT.from_cov(np.array([0.5, 0.5]), np.diag([0.05, 0.05]) ** 2, nu=5.0)
    u = (np.array([narrow.draw_in_box(rng) for _ in range(4000)])[:, 0] - 0.5) / 0.05
    share, exact = float(np.mean(np.abs(u) < 1)), float(stats.t.cdf(1, 5) - stats.t.cdf(-1, 5))
    assert abs(share - exact) < 4 * math.sqrt(exact * (1 - exact) / u.size)


def test_box_covariance_caps_wide_and_undetermined_unknowns():
    c = np.array([[0.25, 0.1, np.nan], [0.1, 4.0, np.nan], [np.nan, np.nan, np.nan]])
    b = box_covariance(c)
    assert np.all(np.isfinite(b)) and np.all(np.linalg.eigvalsh(b) > 0)
    assert b[0, 0] == pytest.approx(0.25) and b[1, 1] == pytest.approx(1.0) and b[2, 2] == pytest.approx(1.0)
    assert b[0, 1] / math.sqrt(b[0, 0] * b[1, 1]) == pytest.approx(0.1 / (0.5 * 2.0))  # the correlation kept
    assert b[0, 2] == 0 and b[1, 2] == 0
    assert chain_moments(np.zeros((50, 3))) is None

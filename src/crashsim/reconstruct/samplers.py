"""Metropolis-Hastings samplers that start from what the fit knows (pure numerics on the scaled unknowns).

The posterior's unknowns are sampled in the scaled coordinates ``z`` of the fit (each unknown's
``[fit]`` bounds mapped to [0, 1]); the prior's support is inside that box. Two samplers:

Independence Metropolis-Hastings (:func:`independence_chain`)
    Every proposal ``y`` is drawn from one fixed density ``q``, whatever the current state ``x``,
    and accepted with probability ``min(1, p(y) q(x) / (p(x) q(y)))`` (Tierney 1994, eq. 2.4;
    Robert and Casella, *Monte Carlo Statistical Methods*, 2nd ed., algorithm A.25). With ``q``
    close to the posterior nearly every proposal is accepted and successive samples are nearly
    independent. Here ``q`` is a multivariate Student-t (:class:`StudentT`) truncated to the box
    (drawn by rejection; its normalising constant cancels in the ratio): heavier tails than the
    posterior keep the weights ``p / q`` bounded, so the chain is uniformly ergodic. Because the
    proposals do not depend on the chain, a whole batch of them is drawn first and its scenes are
    evaluated in parallel; the accept/reject pass then runs in order. Proposals and the uniforms of
    the acceptance test come from two generators, so the chain does not depend on the batch size.

Adaptive random-walk Metropolis (:func:`adaptive_metropolis`)
    Haario, Saksman and Tamminen (2001), *An adaptive Metropolis algorithm*, Bernoulli 7(2),
    eq. (2.1)-(2.2): Gaussian steps of covariance ``s_d C_0`` for the first ``t0`` steps, then
    ``s_d (Cov(z_0..z_{t-1}) + eps I)`` with ``s_d = 2.38^2 / d`` (Gelman, Roberts and Gilks' scaling,
    applied to ``C_0`` too). One proposal after the other
    (each depends on the last state), so it runs serially; kept for the sampler comparison of
    ``benchmarks/posterior.py``.

A proposal outside the box has prior zero: it is rejected without evaluating its scene.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

__all__ = ["StudentT", "independence_chain", "adaptive_metropolis", "box_covariance", "chain_moments",
           "IMH_NU", "IMH_SCALE", "MAX_BOX_TRIES"]

#: Degrees of freedom of the Student-t proposal (heavier tails than a normal posterior).
IMH_NU = 5.0
#: The proposal's scale matrix is IMH_SCALE^2 times the posterior covariance it is built from.
IMH_SCALE = 1.2
#: Draws of the proposal allowed to find one point inside the box.
MAX_BOX_TRIES = 100_000


@dataclass(frozen=True)
class StudentT:
    """Multivariate Student-t density with ``nu`` degrees of freedom, location ``mean`` and scale
    matrix ``chol @ chol.T`` (``nu = inf``: the normal distribution).

    Parameters
    ----------
    mean : ndarray (d,)
    chol : ndarray (d, d)
        Lower Cholesky factor of the scale matrix.
    nu : float
    """

    mean: np.ndarray
    chol: np.ndarray
    nu: float = IMH_NU

    @classmethod
    def from_cov(cls, mean, cov, nu: float = IMH_NU, scale: float = 1.0) -> "StudentT":
        """The t with scale matrix ``scale^2 cov`` about ``mean``."""
        cov = np.asarray(cov, float)
        d = cov.shape[0]
        jitter = 1e-12 * max(float(np.max(np.diag(cov))), 1e-300)
        chol = np.linalg.cholesky(scale**2 * (0.5 * (cov + cov.T)) + jitter * np.eye(d))
        return cls(np.asarray(mean, float), chol, float(nu))

    @property
    def dim(self) -> int:
        return int(self.mean.size)

    def log_density(self, x) -> float:
        """Log density at ``x`` up to a constant (the same constant for every ``x``)."""
        u = np.linalg.solve(self.chol, np.asarray(x, float) - self.mean)
        m = float(u @ u)
        if math.isinf(self.nu):
            return -0.5 * m
        return -0.5 * (self.nu + self.dim) * math.log1p(m / self.nu)

    def draw(self, rng: np.random.Generator) -> np.ndarray:
        g = rng.standard_normal(self.dim)
        w = 1.0 if math.isinf(self.nu) else math.sqrt(self.nu / rng.chisquare(self.nu))
        return self.mean + self.chol @ g * w

    def draw_in_box(self, rng: np.random.Generator) -> np.ndarray:
        """One draw of the density truncated to the unit box (by rejection)."""
        for _ in range(MAX_BOX_TRIES):
            y = self.draw(rng)
            if np.all(y >= 0.0) and np.all(y <= 1.0):
                return y
        raise RuntimeError(f"the proposal put no draw inside the unknowns' bounds in {MAX_BOX_TRIES} tries "
                           f"(location {self.mean})")


def box_covariance(cov, fallback_sd: float = 1.0) -> np.ndarray:
    """A covariance on the unit box from the fit's (scaled unknowns): rows of undetermined unknowns
    (not finite) become independent with sd ``fallback_sd``, and every sd is capped at it (a linearised
    interval wider than the whole bound range says only that the bounds decide)."""
    c = np.array(cov, dtype=float)
    bad = ~np.isfinite(np.diag(c)) | ~(np.diag(c) > 0)
    c[~np.isfinite(c)] = 0.0
    c[bad, :] = 0.0
    c[:, bad] = 0.0
    c[bad, bad] = fallback_sd**2
    sd = np.sqrt(np.diag(c))
    corr = c / np.outer(sd, sd)
    sd = np.minimum(sd, fallback_sd)
    out = corr * np.outer(sd, sd)
    w, v = np.linalg.eigh(0.5 * (out + out.T))  # a linearisation may be singular to rounding: keep it positive
    w = np.maximum(w, 1e-10 * max(float(w.max()), 1e-300))
    return (v * w) @ v.T


def chain_moments(z: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """Mean and covariance of the states of a chain (shape (n, d)), or None when it visited fewer
    than d + 2 distinct states (too few to estimate a covariance)."""
    z = np.asarray(z, float)
    if len(np.unique(z, axis=0)) < z.shape[1] + 2:
        return None
    return z.mean(axis=0), np.atleast_2d(np.cov(z, rowvar=False))


def independence_chain(evaluate_batch: Callable[[list], Sequence[tuple]], proposal: StudentT, state: tuple,
                       n: int, rng_prop: np.random.Generator, rng_accept: np.random.Generator,
                       batch: int = 100):
    """``n`` steps of independence Metropolis-Hastings from ``state``.

    Parameters
    ----------
    evaluate_batch : callable
        ``evaluate_batch(points) -> [(log_prob, blob), ...]`` in the order given.
    proposal : StudentT
        The fixed proposal density (truncated to the unit box).
    state : tuple
        ``(z, log_prob, blob)`` of the current state.
    n, batch : int
        Steps, and proposals evaluated together.
    rng_prop, rng_accept : numpy Generator
        The proposals' and the acceptance tests' generators.

    Yields
    ------
    (z, log_prob, blob, accepted)
        After each step: the state and whether the step's proposal was accepted.
    """
    z, lp, blob = state
    lq = proposal.log_density(z)
    done = 0
    while done < n:
        k = min(batch, n - done)
        ys = [proposal.draw_in_box(rng_prop) for _ in range(k)]
        us = rng_accept.random(k)
        results = evaluate_batch(ys)
        for y, u, (lpy, bly) in zip(ys, us, results):
            accept = False
            if np.isfinite(lpy):
                lqy = proposal.log_density(y)
                log_alpha = (lpy - lp) + (lq - lqy) if np.isfinite(lp) else math.inf
                accept = bool(math.log(u) < log_alpha) if u > 0 else True
                if accept:
                    z, lp, blob, lq = np.asarray(y, float), float(lpy), bly, lqy
            yield z, lp, blob, accept
        done += k


def adaptive_metropolis(evaluate: Callable[[np.ndarray], tuple], state: tuple, cov0, n: int,
                        rng: np.random.Generator, t0: int | None = None, eps: float = 1e-10):
    """``n`` steps of Haario's adaptive Metropolis from ``state = (z, log_prob, blob)``.

    ``evaluate(z) -> (log_prob, blob)``; ``cov0`` the covariance of the first ``t0`` steps
    (default ``10 d``). Proposals outside the unit box are rejected without calling ``evaluate``.

    Yields ``(z, log_prob, blob, accepted, evaluated)`` after each step.
    """
    z, lp, blob = np.asarray(state[0], float), float(state[1]), state[2]
    d = z.size
    sd = 2.38**2 / d
    t0 = 10 * d if t0 is None else int(t0)
    mean = z.copy()
    m2 = np.zeros((d, d))  # running sum of outer products of deviations (Welford)
    chol = np.linalg.cholesky(sd * box_covariance(cov0))
    for t in range(n):
        if t >= t0:
            c = sd * (m2 / max(t - 1, 1) + eps * np.eye(d))
            chol = np.linalg.cholesky(0.5 * (c + c.T))
        y = z + chol @ rng.standard_normal(d)
        u = rng.random()
        evaluated = accept = False
        if np.all(y >= 0.0) and np.all(y <= 1.0):
            evaluated = True
            lpy, bly = evaluate(y)
            if np.isfinite(lpy) and (u <= 0 or math.log(u) < lpy - lp):
                z, lp, blob, accept = y, float(lpy), bly, True
        # running mean and covariance of the states z_0 .. z_t
        delta = z - mean
        mean = mean + delta / (t + 2)
        m2 = m2 + np.outer(delta, z - mean)
        yield z, lp, blob, accept, evaluated

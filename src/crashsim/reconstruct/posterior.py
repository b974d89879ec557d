"""The posterior of the unknowns given the evidence, sampled by MCMC (emcee's ensemble sampler, or
independence Metropolis-Hastings from the fit: ``[posterior] sampler``).

Where ``crashsim fit`` finds the best values and linearises around them, the posterior maps
how probable every combination of the unknowns is, given the evidence and what was known
before it:

    log p(x | evidence) = log prior(x) - chi^2(x) / 2 + const,
    chi^2(x) = sum_i (r_i(x) / sigma_i)^2,

with ``r_i / sigma_i`` exactly the weighted residuals of the fit
(:class:`~crashsim.reconstruct.fit.FitProblem`, :class:`~crashsim.reconstruct.fit.EvidenceModel`:
each evidence item with its sigma, a tyre mark weighing as one measurement): Gaussian,
independent measurement errors with standard deviations sigma.

Priors (``[posterior] prior``)
------------------------------
``"fit"``           uniform on each unknown's ``[fit]`` bounds.
``"uncertainty"``   the ``[uncertainty]`` distribution of the same path (uniform, triangular,
                    normal), truncated to the ``[fit]`` bounds; an unknown without one is
                    uniform on its bounds. Inputs of ``[uncertainty]`` that are not unknowns
                    keep the file's values (they are not marginalised).

The unknowns are independent a priori. A scene that cannot be evaluated (an inadmissible
impact, a run-out that did not reach rest, ...) has probability zero (log-probability -inf):
such proposals are rejected, counted by reason and reported.

Sampling
--------
``walkers`` walkers start in a normal ball around the ``[fit]`` initial values or the best fit
(``start``), ``init_scale`` times each bound range wide, redrawn until inside the prior's
support, and move by emcee's stretch move (or differential evolution). Derived quantities
(delta-v of every body of the first impact, speeds after it, its energy loss fractions) come
with every sample (emcee blobs).

With ``sampler = "imh"`` the fit runs first and one chain proposes from a Student-t built from its
best values and covariance, then from a mixture of that t and one refitted in the burn-in to the
importance-weighted moments of every scene it evaluated, fixed after the burn-in
(:mod:`crashsim.reconstruct.samplers`); each step is one scene, a batch of proposals runs in
parallel, and ``walkers``, ``move``, ``init_scale`` and chain files do not apply.

Determinism, parallelism and resume
-----------------------------------
The initial ball and the sampler's moves draw from generators seeded by ``seed`` only; the
log-probabilities are computed in the order emcee asks for them, whether in this process,
a process pool (``workers``) or a Dask cluster (``dask_address``): the same seed gives the
same chain everywhere. With ``chain_path`` the whole chain, its log-probabilities, blobs,
acceptance counts and the sampler's random state are written to a ``.npz`` file every
``checkpoint_every`` steps and when stopped; running again with the same file continues from
its last step, and the resumed chain equals an uninterrupted one exactly (a file of another
scenario, prior or seed is refused).

Diagnostics
-----------
Integrated autocorrelation time ``tau`` of every unknown (``emcee.autocorr.integrated_time``,
Sokal's window c = 5, over the kept steps), effective sample size ``walkers x kept / tau``,
mean acceptance fraction (flagged outside [0.15, 0.7]), a warning when the kept chain is
shorter than 50 tau (the estimates, tau itself included, are then unreliable), and an error
when fewer than :data:`MIN_KEPT_STEPS` steps are kept.
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import os
import threading
import time
import warnings
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable

import numpy as np

from ..errors import ScenarioError, failure_reason, in_file

__all__ = ["PosteriorSpec", "PosteriorProblem", "PosteriorResult", "run_posterior", "load_chain",
           "PERCENTILES", "MIN_KEPT_STEPS", "TAU_FACTOR", "settle_step", "SampleTolerance", "evidence_tolerance"]

_log = logging.getLogger("crashsim")

#: Percentiles reported for every unknown and derived quantity (the median, +-1 sigma and 95 % of a normal).
PERCENTILES = (2.5, 16.0, 50.0, 84.0, 97.5)
from ..inverse_schema import MIN_KEPT_STEPS, validate_posterior  # noqa: E402 - fewest steps kept after burn-in and thinning
from ..report import fmt, table
from ..scenario import Scenario
from ..units import resolve_system, system_label
from .fit import FitProblem, FitSpec, NotAtRest, fit_scene
from .montecarlo import DEFAULT_SAMPLE_TIME_LIMIT, MCResult, UncertaintySpec, scene_outputs
from .overrides import INVERSE_SECTIONS, default_engine, file_contents
from .parallel import Executor, Progress, child_seed, choose_backend
from .samplers import (IMH_DEFENSIVE, IMH_NU, IMH_SCALE, Mixture, StudentT, box_covariance, independence_chain,
                       refit_proposal)
from .tolerance import SampleTolerance, evidence_tolerance, with_tolerance
#: The kept chain should be this many autocorrelation times long (emcee's documentation: "you
#: should not trust an estimate of tau unless the chain is longer than about 50 tau").
TAU_FACTOR = 50
#: Mean acceptance fractions outside this range are flagged (about 0.2-0.5 is good for the stretch move).
ACCEPTANCE_RANGE = (0.15, 0.7)
#: A bound "limits" an unknown when more than EDGE_SHARE of its samples lie within EDGE of its
#: range from it (a posterior well inside its bounds has almost none there).
EDGE, EDGE_SHARE = 0.05, 0.01
#: Prefixes of :func:`~crashsim.reconstruct.montecarlo.scene_outputs` kept as derived quantities.
DERIVED_PREFIXES = ("speed", "speed_at_braking", "delta_v", "speed_after", "energy_loss", "rolled")
_FORMAT = "crashsim-posterior/1"


# ---------------------------------------------------------------------------------------------
# Specification
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PosteriorSpec:
    """A validated ``[posterior]`` table (see :data:`~crashsim.inverse_schema.POSTERIOR`)."""

    walkers: int = 32
    steps: int = 2000
    burn: int | None = None
    thin: int = 1
    seed: int = 0
    prior: str = "fit"
    start: str = "initial"
    init_scale: float = 0.01
    move: str = "stretch"
    checkpoint_every: int = 50
    ess: int | None = None
    check_every: int = 100
    tolerance: str = "evidence"
    sampler: str = "emcee"

    @property
    def burn_steps(self) -> int:
        """Steps discarded: ``burn``, or a quarter of the steps."""
        return self.steps // 4 if self.burn is None else int(self.burn)

    @classmethod
    def from_dict(cls, raw: dict | None, *, file: str | None = None) -> "PosteriorSpec":
        d = validate_posterior(raw or {}, file=file)
        return cls(**{k: d[k] for k in ("walkers", "steps", "burn", "thin", "seed", "prior", "start", "init_scale",
                                        "move", "checkpoint_every", "ess", "check_every", "tolerance",
                                        "sampler")})

    def to_dict(self) -> dict:
        return dict(self.__dict__, burn_steps=self.burn_steps)

    def check(self, n_unknowns: int, *, file: str | None = None) -> None:
        """Walkers, burn-in and thinning that leave the diagnostics something to work on."""
        if self.sampler == "emcee" and self.walkers < 2 * n_unknowns:
            raise ScenarioError(f"walkers = {self.walkers}: the ensemble sampler needs at least twice the number of "
                                f"unknowns ({n_unknowns}), i.e. >= {2 * n_unknowns}", field="posterior.walkers",
                                file=file)
        if self.burn is not None and self.burn_steps >= self.steps:
            raise ScenarioError(f"burn = {self.burn_steps} discards every one of the {self.steps} steps; allowed "
                                f"0 <= burn < steps", field="posterior.burn", file=file)
        kept = max(self.steps - self.burn_steps, 0) // self.thin
        if kept < MIN_KEPT_STEPS:
            need = self.burn_steps + MIN_KEPT_STEPS * self.thin
            if self.burn is None:  # the default burn-in grows with the steps: a quarter of them
                need = next(n for n in range(MIN_KEPT_STEPS * self.thin, 4 * MIN_KEPT_STEPS * self.thin + 4)
                            if (n - n // 4) // self.thin >= MIN_KEPT_STEPS)
            raise ScenarioError(f"steps = {self.steps} keeps {kept} steps per walker after burn = {self.burn_steps} "
                                f"and thin = {self.thin}: too few for any diagnostic (autocorrelation time, "
                                f"effective sample size); allowed steps >= {need} (at least {MIN_KEPT_STEPS} kept)",
                                field="posterior.steps", file=file)


# ---------------------------------------------------------------------------------------------
# The problem: log-prior + log-likelihood + derived quantities
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Prior:
    """Prior of one unknown: ``"uniform"`` on the [fit] bounds, or an [uncertainty] distribution
    (:class:`~crashsim.reconstruct.montecarlo.InputDistribution`) truncated to them."""

    path: str
    lower: float
    upper: float
    dist: Any = None  # InputDistribution or None (uniform on [lower, upper])

    def logpdf(self, x: float) -> float:
        if not self.lower <= x <= self.upper:
            return -math.inf
        return 0.0 if self.dist is None else self.dist.logpdf(x)

    def support(self) -> tuple[float, float]:
        if self.dist is None:
            return self.lower, self.upper
        lo, hi = self.dist.support()
        return max(lo, self.lower), min(hi, self.upper)

    def describe(self, kind: str, system: str) -> str:
        show = (lambda v: f"{v:.4g}") if kind == "dimensionless" else (lambda v: fmt(v, kind, system))  # noqa: E731
        bounds = f"[{show(self.lower)}, {show(self.upper)}]"
        d = self.dist
        if d is None:
            return f"uniform on the bounds {bounds}"
        return f"{d.parameters(show)} (uncertainty), within the bounds {bounds}"


def build_priors(data: dict, spec, prior: str, *, file: str | None = None) -> tuple[Prior, ...]:
    """The prior of each unknown of ``spec`` (a FitSpec) under ``prior`` = "fit" or "uncertainty"."""
    if prior == "fit":
        return tuple(Prior(u.path, u.lower, u.upper) for u in spec.unknowns)

    if "uncertainty" not in data:
        raise ScenarioError("prior = \"uncertainty\" takes the priors from the [uncertainty] table, but the scenario "
                            "has none; add it or use prior = \"fit\"", field="posterior.prior", file=file)
    unc = UncertaintySpec.from_dict(data["uncertainty"], file=file)
    by_path = {d.path: d for d in unc.inputs}
    out = []
    for u in spec.unknowns:
        d = by_path.get(u.path)
        if d is not None:
            lo, hi = d.support()
            if hi < u.lower or lo > u.upper:
                k = list(by_path).index(u.path)
                raise ScenarioError(f"the [uncertainty] distribution of {u.path} ({d.distribution}, support "
                                    f"[{lo:g}, {hi:g}] SI) lies outside its [fit] bounds [{u.lower:g}, {u.upper:g}] "
                                    "SI: the prior would be zero everywhere", field=f"uncertainty.inputs[{k}]",
                                    file=file)
        out.append(Prior(u.path, u.lower, u.upper, d))
    return tuple(out)


class PosteriorProblem:
    """Log-posterior of the scaled unknowns ``z`` (in [0, 1], as :class:`FitProblem`) and derived quantities.

    Parameters
    ----------
    data : dict
        The raw scenario (as from TOML).
    fit_spec : FitSpec
    priors : tuple of Prior
    derived : sequence of str, optional
        Keys of the derived quantities (:func:`~crashsim.reconstruct.montecarlo.scene_outputs`);
        default: those of the scene at the start values with a prefix in :data:`DERIVED_PREFIXES`.
    """

    def __init__(self, data: dict, fit_spec, priors, *, engine: str | None = None, file: str | None = None,
                 sample_time_limit: float | None = None, derived=None):
        self.fit = FitProblem(data, fit_spec, engine=engine, file=file, sample_time_limit=sample_time_limit)
        self.spec = fit_spec
        self.priors = tuple(priors)
        self.derived = None if derived is None else tuple(derived)

    def derived_keys(self, z0) -> tuple[str, ...]:
        if self.derived is None:
            _, scene = self.fit.evaluate(z0)
            if isinstance(scene, Exception):
                raise ScenarioError(f"the scene at the start values cannot be evaluated: {scene}",
                                    field="fit.unknowns", file=self.fit.file)
            # a speed that is an unknown itself is not repeated among the derived quantities
            own = {f"speed.{p.split('.')[1]}" for p in self.spec.paths if p.startswith("vehicles.") and
                   p.endswith(".speed") and p.count(".") == 2}
            own |= {f"speed_at_braking.{p.split('.')[1]}" for p in self.spec.paths if p.endswith(".approach.speed")}
            self.derived = tuple(k for k in scene_outputs(scene)
                                 if k.split(".", 1)[0] in DERIVED_PREFIXES and k not in own)
        return self.derived

    def log_prior(self, z) -> float:
        z = np.asarray(z, float)
        if np.any(z < 0.0) or np.any(z > 1.0):
            return -math.inf
        x = self.fit.x_of(z)
        return float(sum(p.logpdf(float(v)) for p, v in zip(self.priors, x)))

    def evaluate(self, z) -> tuple[float, np.ndarray, str | None]:
        """``(log posterior, derived values, failure reason or None)`` at ``z``."""
        nan = np.full(len(self.derived or ()), np.nan)
        lp = self.log_prior(z)
        if not np.isfinite(lp):
            return -math.inf, nan, None
        r, scene = self.fit.evaluate(np.asarray(z, float))
        if isinstance(scene, Exception):
            reason = f"run-out: {scene.status}" if isinstance(scene, NotAtRest) else failure_reason(scene)
            _log.debug("posterior: proposal rejected, its scene cannot be evaluated (%s): %s", reason, scene)
            return -math.inf, nan, reason
        out = scene_outputs(scene)
        blob = np.array([out.get(k, np.nan) for k in (self.derived or ())], dtype=float)
        return lp - 0.5 * float(r @ r), blob, None

    def log_prob(self, z) -> tuple[float, np.ndarray]:
        lp, blob, _ = self.evaluate(z)
        return lp, blob


# ---------------------------------------------------------------------------------------------
# The pool emcee calls (pool.map(fn, positions)): this problem's log-posterior evaluated through
# the one parallel-execution module (serial, processes or Dask), in the order given; failures tallied.
# ---------------------------------------------------------------------------------------------

def _evaluate(problem: "PosteriorProblem", z) -> tuple:
    return problem.evaluate(z)


class _EmceePool:
    def __init__(self, executor: Executor):
        self.executor = executor
        self.failures: dict[str, int] = {}
        self.evaluations = 0

    @property
    def workers(self) -> int:
        return self.executor.workers

    def map(self, fn, positions):
        positions = [np.asarray(z, float) for z in positions]
        size = max(1, math.ceil(len(positions) / self.executor.workers))  # one chunk per worker
        out = []
        for lp, blob, reason in self.executor.map(_evaluate, positions, chunksize=size):
            self.evaluations += 1
            if reason is not None:
                self.failures[reason] = self.failures.get(reason, 0) + 1
            out.append((lp, blob))
        return out

    def close(self) -> None:
        self.executor.close(cancel=True)


_LOCAL = threading.local()


def _problem_for(payload: dict) -> PosteriorProblem:
    cache = getattr(_LOCAL, "problems", None)
    if cache is None:
        cache = _LOCAL.problems = {}
    p = cache.get(payload["hash"])
    if p is None:
        p = cache[payload["hash"]] = PosteriorProblem(payload["data"], payload["fit_spec"], payload["priors"],
                                                      engine=payload["engine"], file=payload["file"],
                                                      sample_time_limit=payload["time_limit"],
                                                      derived=payload["derived"])
    return p


# ---------------------------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PosteriorResult:
    """Outcome of :func:`run_posterior` (SI; ``report`` for display units).

    Attributes
    ----------
    unknowns : tuple of Unknown
    priors : tuple of Prior
    derived : tuple of str
        Keys of the derived quantities (``"delta_v.car"``, ``"speed_after.car"``, ``"energy_loss.system"``).
    chain : ndarray (steps, walkers, n)
        Every step of every walker [SI], burn-in included.
    log_prob : ndarray (steps, walkers)
    blobs : ndarray (steps, walkers, n_derived)
        Derived quantities at every step [SI; energy loss as a fraction].
    samples, derived_samples : ndarray (m, n), (m, n_derived)
        The kept samples (after ``burn``, every ``thin``-th step, walkers flattened).
    percentiles : dict
        ``{name: {"p2.5", "p16", "p50", "p84", "p97.5", "mean", "sd"}}`` of unknowns (by path) and derived.
    correlation : ndarray
        Pearson correlation of the kept samples, unknowns then derived (``labels`` order).
    tau, ess : ndarray (n,)
        Integrated autocorrelation time [steps] and effective sample size of each unknown.
    acceptance : ndarray (walkers,)
        Acceptance fraction of each walker.
    failure_reasons : dict
        Proposals whose scene could not be evaluated (log-probability -inf), by reason.
    evaluations, elapsed : int, float
        Scene evaluations and wall-clock seconds of the whole chain: with a chain file, summed
        over every run that wrote it.
    fit : dict or None
        With ``start = "fit"``: the fit's best values and linearised intervals
        (``{"x", "interval", "confidence", "chi2"}``) for comparison.
    tolerance : SampleTolerance or None
        The run-out tolerance of the samples, when ``[posterior] tolerance = "evidence"`` chose it.
    warnings : tuple of str
    success : bool
        False when a diagnostic warns (chain too short, acceptance out of range).
    """

    unknowns: tuple
    priors: tuple
    derived: tuple
    spec: PosteriorSpec
    chain: np.ndarray
    log_prob: np.ndarray
    blobs: np.ndarray
    accepted: np.ndarray
    samples: np.ndarray
    derived_samples: np.ndarray
    percentiles: dict
    correlation: np.ndarray
    tau: np.ndarray
    ess: np.ndarray
    acceptance: np.ndarray
    evaluations: int
    failure_reasons: dict
    best: dict
    warnings: tuple
    success: bool
    message: str
    engine: str
    backend: str
    workers: int
    elapsed: float
    n_resumed: int
    chain_path: str | None
    start: np.ndarray
    fit: dict | None = None
    title: str = ""
    file: str | None = None
    units: str = "SI"
    nominal: Any = field(default=None, repr=False, compare=False)
    tolerance: SampleTolerance | None = None

    @property
    def labels(self) -> list[str]:
        """Unknowns (by path) then derived keys: the rows and columns of ``correlation``."""
        return [u.path for u in self.unknowns] + list(self.derived)

    @property
    def steps(self) -> int:
        return int(self.chain.shape[0])

    def kind_of(self, label: str) -> str:
        for u in self.unknowns:
            if u.path == label:
                return u.kind
        return MCResult.kind_of(label)

    def to_dict(self) -> dict:
        fin = lambda v: float(v) if v is not None and np.isfinite(v) else None  # noqa: E731
        return {
            "success": self.success, "message": self.message, "engine": self.engine, "backend": self.backend,
            "workers": self.workers, "elapsed": self.elapsed, "file": self.file, "spec": self.spec.to_dict(),
            "steps_done": self.steps, "n_resumed": self.n_resumed, "chain_path": self.chain_path,
            "unknowns": [{"path": u.path, "name": u.name, "kind": u.kind, "lower": u.lower, "upper": u.upper,
                          "start": float(self.start[i]), "prior": _prior_dict(self.priors[i]),
                          "tau": fin(self.tau[i]), "ess": fin(self.ess[i]),
                          "percentiles": {k: fin(v) for k, v in self.percentiles[u.path].items()}}
                         for i, u in enumerate(self.unknowns)],
            "derived": [{"key": k, "kind": self.kind_of(k),
                         "percentiles": {q: fin(v) for q, v in self.percentiles.get(k, {}).items()}}
                        for k in self.derived],
            "labels": self.labels,
            "correlation": [[fin(v) for v in row] for row in self.correlation],
            "diagnostics": {"acceptance_mean": fin(float(np.mean(self.acceptance))),
                            "acceptance_min": fin(float(np.min(self.acceptance))),
                            "acceptance_max": fin(float(np.max(self.acceptance))),
                            "tau": [fin(t) for t in self.tau], "ess": [fin(e) for e in self.ess],
                            "kept_steps": int(self.samples.shape[0] // max(1, self.spec.walkers)),
                            "samples": int(self.samples.shape[0]),
                            "chain_long_enough": bool(self._long_enough())},
            "evaluations": self.evaluations, "failure_reasons": dict(self.failure_reasons),
            "best": self.best, "fit": self.fit, "warnings": list(self.warnings),
            "tolerance": None if self.tolerance is None else self.tolerance.to_dict(),
        }

    def _long_enough(self) -> bool:
        kept = self.samples.shape[0] // max(1, self.spec.walkers)
        tmax = float(np.nanmax(self.tau)) if np.isfinite(self.tau).any() else math.inf
        return kept >= TAU_FACTOR * tmax

    def report(self, system: str | None = None) -> str:
        """Readable report: priors, percentiles of unknowns and derived quantities (beside the fit's
        linearised intervals when started from the fit), correlations, diagnostics, warnings."""
        system = resolve_system(system, self.units)

        def show(v, kind):
            if v is None or not np.isfinite(v):
                return "n/a"
            if kind == "dimensionless":
                return f"{v:.4g}"
            return fmt(v, kind, system)

        def show_d(v, kind):  # derived: energy loss as a percentage
            if kind == "dimensionless" and v is not None and np.isfinite(v):
                return f"{100 * v:.1f} %"
            return show(v, kind)

        sp = self.spec
        kept = self.samples.shape[0] // max(1, sp.walkers)
        lines = [f"crashsim posterior: {self.title}".rstrip()]
        if self.file:
            lines.append(f"file: {self.file}")
        resumed = f" ({self.n_resumed} resumed from {self.chain_path})" if self.n_resumed else ""
        lines.append(f"units: {system_label(system)}; run-out engine: {self.engine}; "
                     f"{self.backend}, {self.workers} worker(s); "
                     f"{self.evaluations} scene evaluations in {self.elapsed:.1f} s")
        if sp.sampler == "imh":
            lines.append(f"independence Metropolis-Hastings (Student-t proposals, nu = {IMH_NU:g}: "
                         f"{1 - IMH_DEFENSIVE:.0%} refitted in the burn-in, {IMH_DEFENSIVE:.0%} the fit's): one chain "
                         f"of {self.steps} steps, one scene each; burn-in {sp.burn_steps}, "
                         f"thin {sp.thin}: {self.samples.shape[0]} samples kept; seed {sp.seed}")
        else:
            lines.append(f"emcee {sp.move} move: {sp.walkers} walkers x {self.steps} steps{resumed}; burn-in "
                     f"{sp.burn_steps}, thin {sp.thin}: {self.samples.shape[0]} samples kept ({kept} per walker); "
                     f"seed {sp.seed}; start: {'best fit' if sp.start == 'fit' else '[fit] initial values'}")
        if sp.ess is not None:
            met = bool(np.all(np.isfinite(self.ess)) and np.all(self.ess >= sp.ess)) and self._long_enough()
            lines.append(f"target: {sp.ess} effective samples of every unknown, checked every {sp.check_every} steps: "
                         + (f"met at step {self.steps}" if met else f"not met in {self.steps} steps"))
        if self.tolerance is not None:
            lines.append(f"run-out tolerance of the samples: {self.tolerance.text(system)}")
        lines.append("")
        lines.append(f"Priors ({sp.prior}) and likelihood: -chi^2/2 of the evidence residuals over their sigmas")
        for u, p in zip(self.unknowns, self.priors):
            lines.append(f"  {u.name}: {p.describe(u.kind, system)}")
        lines.append("")
        heads = [f"p{q:g}" for q in PERCENTILES]
        lines.append("Unknowns: posterior percentiles (p2.5-p97.5: 95 % credible interval; p16-p84: 68 %)")
        rows = [["unknown"] + heads + ["mean", "sd"]]
        for u in self.unknowns:
            p = self.percentiles[u.path]
            rows.append([u.name] + [show(p[h], u.kind) for h in heads] + [show(p["mean"], u.kind),
                                                                          show(p["sd"], u.kind)])
        lines += table(rows, "l" + "r" * (len(heads) + 2))
        if self.fit is not None:
            pct = f"{100 * self.fit['confidence']:g} %"
            lines.append("")
            lines.append(f"Beside the fit (best values and linearised {pct} intervals; chi^2 = {self.fit['chi2']:.4g})")
            rows = [["unknown", "fit best", f"fit {pct} interval", "posterior median", "posterior 95 %"]]
            for i, u in enumerate(self.unknowns):
                lo, hi = self.fit["interval"][i]
                iv = (f"[{show(lo, u.kind)}, {show(hi, u.kind)}]" if lo is not None and hi is not None
                      else "not determined")
                p = self.percentiles[u.path]
                rows.append([u.name, show(self.fit["x"][i], u.kind), iv, show(p["p50"], u.kind),
                             f"[{show(p['p2.5'], u.kind)}, {show(p['p97.5'], u.kind)}]"])
            lines += table(rows, "lrrrr")
        if self.derived:
            lines.append("")
            lines.append("Derived quantities of the first impact (energy loss as a share of the kinetic energy)")
            rows = [["quantity"] + heads + ["mean", "sd"]]
            for k in self.derived:
                p = self.percentiles.get(k)
                if p is None:
                    continue
                kd = self.kind_of(k)
                rows.append([k] + [show_d(p[h], kd) for h in heads] + [show_d(p["mean"], kd),
                                                                       show(p["sd"], kd) if kd != "dimensionless"
                                                                       else f"{100 * p['sd']:.1f} %"])
            lines += table(rows, "l" + "r" * (len(heads) + 2))
            for k in self.derived:  # the wheel-lift and rollover check on: rolled.<vehicle> is 1 or 0 per sample
                if k.startswith("rolled.") and self.percentiles.get(k) is not None:
                    lines.append(f"  rollover (an outcome, not a failure): a unit of vehicle {k.split('.', 1)[1]} "
                                 f"rolls in {100 * self.percentiles[k]['mean']:.1f} % of the kept samples")
        n = len(self.unknowns)
        labels = self.labels
        lines.append("")
        lines.append("Posterior correlation (unknowns; derived quantities in the columns after them)")
        rows = [[""] + [str(j + 1) for j in range(len(labels))]]
        for i, lab in enumerate(labels):
            rows.append([f"{i + 1} {lab}"] + [f"{self.correlation[i, j]:.3f}" if np.isfinite(self.correlation[i, j])
                                              else "n/a" for j in range(len(labels))])
        lines += table(rows[:n + 1], "l" + "r" * len(labels))
        if len(labels) > n:  # the derived columns have no row: their numbers named here
            lines.append("  columns " + ", ".join(f"{j + 1} {labels[j]}" for j in range(n, len(labels))))
        lines.append("")
        lines.append("Diagnostics")
        acc = self.acceptance
        if sp.sampler == "imh":
            lines.append(f"  acceptance fraction: {np.mean(acc):.3f} (the proposal's overlap with the posterior; "
                         f"good: above {ACCEPTANCE_RANGE[0]:g})")
        else:
            lines.append(f"  acceptance fraction: mean {np.mean(acc):.3f} (walkers {np.min(acc):.3f} to "
                         f"{np.max(acc):.3f}; good: {ACCEPTANCE_RANGE[0]:g} to {ACCEPTANCE_RANGE[1]:g})")
        rows = [["unknown", "autocorrelation time", "effective samples", f"kept / tau (want >= {TAU_FACTOR})"]]
        for i, u in enumerate(self.unknowns):
            t = self.tau[i]
            rows.append([u.name, f"{t:.1f} steps" if np.isfinite(t) else "n/a",
                         f"{self.ess[i]:.0f}" if np.isfinite(self.ess[i]) else "n/a",
                         f"{kept / t:.1f}" if np.isfinite(t) and t > 0 else "n/a"])
        lines += table(rows, "lrrr")
        b = self.best
        if b:
            lines.append(f"  highest posterior sample: chi^2 = {b['chi2']:.4g}; "
                         + ", ".join(f"{u.name} {show(v, u.kind)}" for u, v in zip(self.unknowns, b["x"])))
        if self.failure_reasons:
            lines.append(f"  proposals whose scene could not be evaluated (rejected, probability zero): "
                         f"{sum(self.failure_reasons.values())}")
            for reason, count in sorted(self.failure_reasons.items(), key=lambda kv: -kv[1]):
                lines.append(f"    {count:6d}  {reason}")
        if self.warnings:
            lines.append("")
            lines.append("Warnings")
            lines += [f"  - {w}" for w in self.warnings]
        return "\n".join(lines)


def _prior_dict(p: Prior) -> dict:
    out = {"lower": p.lower, "upper": p.upper, "distribution": "uniform" if p.dist is None else p.dist.distribution}
    if p.dist is not None:
        out["from"] = "uncertainty"
        out.update({k: getattr(p.dist, k) for k in ("lower", "upper", "mode", "mean", "sd")
                    if getattr(p.dist, k) is not None and k not in ("lower", "upper")})
        out["support"] = list(p.support())
    else:
        out["from"] = "fit bounds"
    return out


# ---------------------------------------------------------------------------------------------
# Summaries
# ---------------------------------------------------------------------------------------------

def settle_step(log_prob: np.ndarray, n_unknowns: int) -> int | None:
    """The step from which the walkers' log-probability has settled, or None if it never does.

    ``log_prob``: shape (steps, walkers). The level is the median over the second half of the
    chain of the per-step median over the walkers; the chain has settled from the first step after
    which that median never falls more than sqrt(k/2) below the level (k unknowns: one standard
    deviation of the log-probability of a sample of a k-dimensional normal posterior, whose -2 log p
    is chi^2 with k degrees of freedom). None if its last step is still below that.
    """
    lp = np.asarray(log_prob, dtype=float)
    if lp.ndim != 2 or lp.shape[0] < 4:
        return None
    med = np.median(lp, axis=1)
    level = float(np.median(med[lp.shape[0] // 2:]))
    if not np.isfinite(level):
        return None
    below = np.nonzero(~(med >= level - math.sqrt(max(n_unknowns, 1) / 2)))[0]
    first = int(below[-1]) + 1 if below.size else 0
    return first if first < lp.shape[0] else None


def _percentiles(v: np.ndarray) -> dict:
    """Percentiles, mean and sd of one unknown or derived quantity over the kept samples.

    Linear statistics are right here, angles included: an unknown is sampled on its ``[fit]``
    bounds, an interval as written and never wrapped (a heading bounded by [170 deg, 200 deg] has
    samples from 170 to 200 deg), and no derived quantity is an angle. Wrapped angles (the rest
    headings of Monte Carlo samples) are summarised on their circular arc instead
    (:func:`crashsim.geometry.circular_percentiles`).
    """
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {}
    out = {f"p{q:g}": float(np.percentile(v, q)) for q in PERCENTILES}
    out["mean"] = float(np.mean(v))
    out["sd"] = float(np.std(v, ddof=1)) if v.size > 1 else 0.0
    return out


def _correlation(m: np.ndarray) -> np.ndarray:
    k = m.shape[1]
    out = np.full((k, k), np.nan)
    ok = np.all(np.isfinite(m), axis=1)
    mm = m[ok]
    if mm.shape[0] < 3:
        return out
    sd = np.std(mm, axis=0)
    live = sd > 1e-12 * np.maximum(1.0, np.abs(np.mean(mm, axis=0)))  # a constant (to rounding) has no correlation
    if live.any():
        c = np.corrcoef(mm[:, live], rowvar=False)
        out[np.ix_(live, live)] = np.atleast_2d(c)
    return out


def _too_short(kept_steps: int, tmax: float, need: int | None, sampler: str) -> str:
    """The warning of a chain shorter than TAU_FACTOR autocorrelation times ``tmax``, with the number
    of steps ``need`` to run (None: tau not finite) and how: an ensemble's chain file continues where
    it stopped; the independence sampler (one chain) keeps no chain file and starts again."""
    imh = sampler == "imh"
    how = ("posterior.steps or --steps; the independence sampler keeps no chain file, so the run starts again"
           if imh else "a chain file continues where it stopped")
    return (f"the chain is too short: {kept_steps} kept steps{'' if imh else ' per walker'} are "
            f"{kept_steps / tmax:.1f} autocorrelation times (largest tau {tmax:.1f} steps); at least {TAU_FACTOR} are "
            "needed to trust tau, and with it the effective sample sizes and the tails of the intervals"
            + ("" if need is None else f": run about {need} steps ({how})"))


def _diagnostics(chain_kept: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Integrated autocorrelation time of each unknown (emcee, quiet) and effective sample size."""
    from emcee.autocorr import integrated_time

    steps, walkers, n = chain_kept.shape
    emcee_log = logging.getLogger("emcee.autocorr")  # its "chain too short" warning: this module words its own
    was = emcee_log.disabled
    emcee_log.disabled = True
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            tau = np.asarray(integrated_time(chain_kept, c=5, tol=TAU_FACTOR, quiet=True), dtype=float)
    finally:
        emcee_log.disabled = was
    tau = np.where(np.isfinite(tau) & (tau > 0), np.maximum(tau, 1.0), np.nan)
    ess = steps * walkers / tau
    return tau, ess


# ---------------------------------------------------------------------------------------------
# Chain file
# ---------------------------------------------------------------------------------------------

def _run_hash(data: dict, fit_spec, spec: PosteriorSpec, priors, start: np.ndarray, engine: str) -> str:
    forward = {k: v for k, v in data.items() if k not in INVERSE_SECTIONS}
    key = {"data": forward, "unknowns": [u.__dict__ for u in fit_spec.unknowns],
           "priors": [_prior_dict(p) for p in priors], "walkers": spec.walkers, "seed": spec.seed,
           "move": spec.move, "init_scale": spec.init_scale, "start": [float(v).hex() for v in start],
           "engine": engine, "sigma_from_tolerance": fit_spec.sigma_from_tolerance, "tolerance": spec.tolerance,
           "mark_points": fit_spec.mark_points}
    return hashlib.sha256(json.dumps(key, sort_keys=True, default=str).encode()).hexdigest()[:16]


def _save(path: Path, run_hash: str, z, log_prob, blobs, accepted, rstate, failures, evaluations, derived,
          elapsed: float = 0.0) -> None:
    tmp = path.with_name(path.name + ".tmp")
    name, keys, pos, has_gauss, cached = rstate
    with open(tmp, "wb") as fh:
        np.savez(fh, format=np.array(_FORMAT), hash=np.array(run_hash), z=z, log_prob=log_prob, blobs=blobs,
                 accepted=accepted, rng_name=np.array(name), rng_keys=np.asarray(keys, dtype=np.uint32),
                 rng_pos=np.array(int(pos)), rng_has_gauss=np.array(int(has_gauss)),
                 rng_cached=np.array(float(cached)), failures=np.array(json.dumps(failures)),
                 evaluations=np.array(int(evaluations)), derived=np.array(json.dumps(list(derived))),
                 elapsed=np.array(float(elapsed)))
    os.replace(tmp, path)


def _load(path: Path, run_hash: str | None) -> dict | None:
    if not path.exists() or path.stat().st_size == 0:
        return None
    try:
        with np.load(path, allow_pickle=False) as f:
            d = {k: f[k] for k in f.files}
    except (OSError, ValueError) as exc:
        raise ScenarioError(f"{path} is not a crashsim posterior chain file ({exc})", field="chain") from None
    if str(d.get("format", "")) != _FORMAT:
        raise ScenarioError(f"{path} is not a crashsim posterior chain file", field="chain")
    if run_hash is not None and str(d["hash"]) != run_hash:
        raise ScenarioError(f"{path} holds a chain of another scenario, prior, start or seed (hash {d['hash']}, this run "
                            f"{run_hash}); delete it or choose another file", field="chain")
    d["rstate"] = (str(d["rng_name"]), d["rng_keys"], int(d["rng_pos"]), int(d["rng_has_gauss"]),
                   float(d["rng_cached"]))
    d["failures"] = json.loads(str(d["failures"]))
    d["derived"] = tuple(json.loads(str(d["derived"])))
    d["evaluations"] = int(d["evaluations"])
    d["elapsed"] = float(d["elapsed"]) if "elapsed" in d else 0.0
    return d


def load_chain(path: str | Path) -> dict:
    """The raw arrays of a chain file (``z``, ``log_prob``, ``blobs``, ``accepted``, ``rstate``, ...)."""
    d = _load(Path(path), None)
    if d is None:
        raise ScenarioError(f"{path} is empty or missing", field="chain")
    return d


# ---------------------------------------------------------------------------------------------
# run_posterior
# ---------------------------------------------------------------------------------------------

def _initial_ball(problem: PosteriorProblem, z0: np.ndarray, spec: PosteriorSpec) -> np.ndarray:
    """``walkers`` points ~ N(z0, init_scale^2) per coordinate, each redrawn until the prior is positive there."""
    rng = np.random.default_rng(child_seed(spec.seed, 1))
    out = np.empty((spec.walkers, z0.size))
    for k in range(spec.walkers):
        for _ in range(10_000):
            z = z0 + spec.init_scale * rng.standard_normal(z0.size)
            if np.isfinite(problem.log_prior(z)):
                break
        else:  # pragma: no cover - z0 itself is inside the support (checked before)
            z = z0.copy()
        out[k] = z
    return out


def _check_start(problem: PosteriorProblem, x0: np.ndarray, where: str, file: str | None) -> None:
    """The prior must be positive at the start values (else no walker can start there)."""
    for j, (u, p) in enumerate(zip(problem.spec.unknowns, problem.priors)):
        if not np.isfinite(p.logpdf(float(x0[j]))):
            lo, hi = p.support()
            key = f"fit.unknowns[{j}].initial" if where == "initial" else "posterior.start"
            what = "initial value" if where == "initial" else "best-fit value"
            raise ScenarioError(f"the prior of {u.path} ({'uncertainty ' + p.dist.distribution if p.dist else 'uniform'}"
                                f", support [{lo:g}, {hi:g}] SI) excludes its {what} {float(x0[j]):g} SI; allowed "
                                f"a start inside the support", field=key, file=file)


def _specs(scenario_data: dict, spec, steps, seed, start, chain_path, file: str | None):
    """The run's :class:`PosteriorSpec` (the file's, or ``spec``, with the overrides given) and the
    file's :class:`FitSpec`, checked together."""
    if "fit" not in scenario_data:
        raise ScenarioError("the posterior is over the unknowns of the [fit] table (with their bounds), but the "
                            "scenario has none", field="fit", file=file)
    if not isinstance(spec, PosteriorSpec):
        spec = PosteriorSpec.from_dict(spec if spec is not None else scenario_data.get("posterior"), file=file)
    over = {k: v for k, v in (("steps", steps), ("seed", seed), ("start", start)) if v is not None}
    spec = replace(spec, **over)  # --steps below the minimum: spec.check names the minimum for this burn-in
    if spec.sampler == "imh":
        if chain_path is not None:
            raise ScenarioError("a chain file (--chain) resumes the emcee sampler; sampler = \"imh\" runs its chain "
                                "in one go: drop the chain file or set sampler = \"emcee\"", field="posterior.sampler",
                                file=file)
        spec = replace(spec, start="fit")  # its proposal is built from the fit: it starts there
    with in_file(file):
        fit_spec = FitSpec.from_dict(scenario_data["fit"], scenario_data, file=file)
    spec.check(len(fit_spec.unknowns), file=file)
    return spec, fit_spec


def _at_sample_tolerance(problem: PosteriorProblem, spec, scenario_data: dict, z0, fit_spec, priors, engine: str,
                         file: str | None, limit: float):
    """The problem the samples run, the scenario it runs and its tolerance: at the evidence's tolerance
    (``spec.tolerance = "evidence"``, where it changes the file's and the run-out has no accuracy target),
    else the file's (tolerance None)."""
    raw_runout = scenario_data.get("runout")
    if spec.tolerance == "evidence" and isinstance(raw_runout, dict) and "accuracy" not in raw_runout:
        scene0 = problem.fit.evaluate(z0)[1]  # at the file's tolerance
        if not isinstance(scene0, Exception) and scene0.scenario.runout is not None:
            opts = scene0.scenario.runout.options
            tolerance = evidence_tolerance(problem.fit.evidence.items, scene0, opts.rtol, opts.atol)
            if tolerance.changed:
                sampled_data = with_tolerance(scenario_data, tolerance)
                return (PosteriorProblem(sampled_data, fit_spec, priors, engine=engine, file=file,
                                         sample_time_limit=limit), sampled_data, tolerance)
            return problem, scenario_data, tolerance
    return problem, scenario_data, None


def _resumed(saved: dict | None, steps: int):
    """The chain so far of a chain file (its first ``steps`` steps), or an empty one: ``(z, log_prob, blobs,
    accepted, failures, evaluations, steps resumed, elapsed)``."""
    if saved is None:
        return [], [], [], [], {}, 0, 0, 0.0
    z_all = [saved["z"][i] for i in range(saved["z"].shape[0])][:steps]
    lp_all = [saved["log_prob"][i] for i in range(len(z_all))]
    bl_all = [saved["blobs"][i] for i in range(len(z_all))]
    acc_all = [saved["accepted"][i] for i in range(len(z_all))]
    return z_all, lp_all, bl_all, acc_all, dict(saved["failures"]), saved["evaluations"], len(z_all), saved["elapsed"]


def _emcee_state(saved: dict | None, n_resumed: int, z_all: list, problem, z0, spec):
    """Where emcee's walkers go on from: the chain file's last step, nothing to run (the file holds more
    steps than asked for), or a ball around ``z0``: ``(state, accepted so far)``, state None for none."""
    import emcee

    if saved is not None and n_resumed > 0 and len(z_all) == saved["z"].shape[0]:
        last_blobs = saved["blobs"][-1]
        if last_blobs.ndim == 2 and last_blobs.shape[1] == 1:  # as emcee holds a single blob
            last_blobs = last_blobs[:, 0]
        state = emcee.State(saved["z"][-1], log_prob=saved["log_prob"][-1], blobs=last_blobs,
                            random_state=saved["rstate"])
        return state, saved["accepted"][-1].astype(float)
    if saved is not None and n_resumed > 0:  # fewer steps asked for than the file holds: nothing to run
        return None, None
    state = emcee.State(_initial_ball(problem, z0, spec),
                        random_state=np.random.RandomState(child_seed(spec.seed, 2).generate_state(4)).get_state())
    return state, np.zeros(spec.walkers)


def run_posterior(scenario_data: dict | Scenario, spec: PosteriorSpec | dict | None = None, *, steps: int | None = None,
                  seed: int | None = None, start: str | None = None, engine: str | None = None,
                  workers: int | None = None, dask_address: Any = None, chain_path: str | Path | None = None,
                  progress: bool | Callable[[int, int], None] = True, file: str | None = None,
                  sample_time_limit: float | None = None) -> PosteriorResult:
    """Sample the posterior of the ``[fit]`` unknowns given the evidence (emcee ensemble sampler).

    Parameters
    ----------
    scenario_data : dict or Scenario
        The raw scenario (as from TOML), or a Scenario loaded from one (its ``file_data``), with a
        ``[fit]`` table (the unknowns and bounds) and evidence sigmas; ``[uncertainty]`` too for ``prior = "uncertainty"``.
    spec : PosteriorSpec or dict, optional
        The sampler's settings; default the scenario's ``[posterior]`` table (or its defaults).
    steps, seed, start : optional
        Override ``spec.steps``, ``spec.seed``, ``spec.start``.
    engine : {"compiled", "scipy"}, optional
        Run-out engine; default the compiled one when this crashsim has it.
    workers : int, optional
        Local processes (default all cores; 1 runs in this process). Ignored with ``dask_address``.
    dask_address : str or distributed.Client, optional
        Run the evaluations on an existing Dask cluster.
    chain_path : str or Path, optional
        ``.npz`` chain file: written every ``checkpoint_every`` steps and when stopped; if it
        exists, the run continues from its last step (resume).
    progress : bool or callable
        True: a tqdm bar over the steps on stderr; a callable ``progress(done, total)`` after
        each step; False: silent.
    file : str, optional
        File name for messages.
    sample_time_limit : float, optional
        Wall-clock seconds allowed for one evaluation's run-out (default
        :data:`~crashsim.reconstruct.montecarlo.DEFAULT_SAMPLE_TIME_LIMIT`).

    Returns
    -------
    PosteriorResult

    Raises
    ------
    ScenarioError
        Invalid [posterior] or [fit] tables, a prior that excludes the start values, too few
        steps for the diagnostics, a chain file of another run.
    """
    import emcee

    scenario_data, file = file_contents(scenario_data, file)

    t0 = time.perf_counter()
    spec, fit_spec = _specs(scenario_data, spec, steps, seed, start, chain_path, file)
    engine = default_engine() if engine is None else engine
    limit = DEFAULT_SAMPLE_TIME_LIMIT if sample_time_limit is None else sample_time_limit
    if not (limit > 0):
        raise ScenarioError(f"the sample time limit must be > 0 s, got {limit!r}", field="sample_time_limit")
    priors = build_priors(scenario_data, fit_spec, spec.prior, file=file)
    problem = PosteriorProblem(scenario_data, fit_spec, priors, engine=engine, file=file, sample_time_limit=limit)
    problem.fit.check_bounds()
    x_init = np.array([u.initial for u in fit_spec.unknowns])
    fit_summary = None
    if spec.start == "initial":
        _check_start(problem, x_init, "initial", file)
    if spec.start == "fit":
        fr = fit_scene(scenario_data, fit_spec, engine=engine, workers=workers, file=file, sample_time_limit=limit)
        x0 = np.asarray(fr.x, float)
        fit_cov = np.asarray(fr.covariance, float)
        fit_summary = {"x": [float(v) for v in fr.x], "confidence": fr.confidence, "chi2": fr.chi2,
                       "interval": [[float(a) if np.isfinite(a) else None for a in row] for row in fr.interval],
                       "stderr": [float(s) if np.isfinite(s) else None for s in fr.stderr]}
        _check_start(problem, x0, "fit", file)
    else:
        x0 = x_init
    z0 = problem.fit.z_of(x0)
    problem, sampled_data, tolerance = _at_sample_tolerance(problem, spec, scenario_data, z0, fit_spec, priors,
                                                            engine, file, limit)
    derived = problem.derived_keys(z0)   # one scene here first: compiles the engine before any fork
    run_hash = _run_hash(scenario_data, fit_spec, spec, priors, x0, engine)
    ndim = len(fit_spec.unknowns)

    saved = None
    if chain_path is not None:
        chain_path = Path(chain_path)
        saved = _load(chain_path, run_hash)
    z_all, lp_all, bl_all, acc_all, failures, evaluations, n_resumed, elapsed0 = _resumed(saved, spec.steps)

    backend, nw = choose_backend(workers, dask_address)
    if spec.sampler == "imh":
        span = problem.fit.span
        return _run_imh(problem, spec, z0, fit_cov / np.outer(span, span), derived, run_hash, backend, nw, workers,
                        dask_address, progress, sampled_data, fit_spec, priors, engine, file, limit, x0, fit_summary,
                        tolerance, t0)
    payload = {"data": sampled_data, "fit_spec": fit_spec, "priors": priors, "engine": engine, "file": file,
               "time_limit": float(limit), "derived": derived, "hash": run_hash}
    todo = spec.steps - len(z_all)
    if spec.ess is not None and z_all and _enough(z_all, spec):
        todo = 0  # a resumed chain that meets its target already
    bar = Progress(progress, spec.steps, initial=len(z_all), desc="posterior (MCMC)", unit="step", show=todo > 0)
    pool = None
    rstate = None
    try:
        if todo > 0:
            pool = _EmceePool(Executor(_problem_for, payload, backend, nw, dask_address=dask_address, local=problem))
            nw = pool.workers if backend == "dask" else nw
            move = emcee.moves.StretchMove() if spec.move == "stretch" else emcee.moves.DEMove()
            sampler = emcee.EnsembleSampler(spec.walkers, ndim, problem.log_prob, pool=pool, moves=move)
            state, acc0 = _emcee_state(saved, n_resumed, z_all, problem, z0, spec)
            if state is not None:
                since = 0
                for st in sampler.sample(state, iterations=todo, store=True, skip_initial_state_check=True):
                    acc = acc0 + sampler.backend.accepted
                    blobs = np.array(st.blobs, dtype=float).reshape(spec.walkers, len(derived))  # a copy: emcee updates in place
                    z_all.append(np.array(st.coords))
                    lp_all.append(np.array(st.log_prob))
                    bl_all.append(blobs)
                    acc_all.append(acc.copy())
                    rstate = st.random_state
                    since += 1
                    if chain_path is not None and since >= spec.checkpoint_every:
                        _save(chain_path, run_hash, np.array(z_all), np.array(lp_all), np.array(bl_all),
                              np.array(acc_all), rstate, _merge(failures, pool.failures),
                              evaluations + pool.evaluations, derived, elapsed0 + time.perf_counter() - t0)
                        since = 0
                    bar.update(1, len(z_all))
                    if spec.ess is not None and len(z_all) % spec.check_every == 0 and _enough(z_all, spec):
                        break
    finally:
        if pool is not None:
            if chain_path is not None and rstate is not None:
                _save(chain_path, run_hash, np.array(z_all), np.array(lp_all), np.array(bl_all), np.array(acc_all),
                      rstate, _merge(failures, pool.failures), evaluations + pool.evaluations, derived,
                      elapsed0 + time.perf_counter() - t0)
            pool.close()
        bar.close()
    if pool is not None:
        failures = _merge(failures, pool.failures)
        evaluations += pool.evaluations
    nominal = None
    try:
        nominal = problem.fit.full_scene(z0)
    except Exception:  # pragma: no cover - evaluated above already
        nominal = None
    if spec.ess is not None and len(z_all) < spec.steps:
        spec = replace(spec, steps=len(z_all))  # stopped at its target: the burn-in is a quarter of what ran
    return _assemble(problem, spec, np.array(z_all), np.array(lp_all), np.array(bl_all), np.array(acc_all), derived,
                     x0, failures, evaluations, elapsed0 + time.perf_counter() - t0, engine, backend, nw, n_resumed,
                     None if chain_path is None else str(chain_path), fit_summary, file, nominal, tolerance)


#: The independence sampler's settle check (:func:`settle_step`) takes the median of blocks of this many steps.
IMH_SETTLE_BLOCK = 100
#: Rounds of the independence sampler's burn-in, each refitting the proposal to the weighted moments of the
#: evaluations of the rounds before.
IMH_ROUNDS = 2


def _run_imh(problem, spec, z0, cov_z, derived, run_hash, backend, nw, workers, dask_address, progress, sampled_data,
             fit_spec, priors, engine, file, limit, x0, fit_summary, tolerance, t0) -> PosteriorResult:
    """Independence Metropolis-Hastings (:func:`~crashsim.reconstruct.samplers.independence_chain`).

    The burn-in (``spec.burn_steps`` steps) runs in :data:`IMH_ROUNDS` rounds: the first proposes from
    the fit's Gaussian (best values and linearised covariance in the scaled unknowns, each sd capped at
    its bound range) as a Student-t with scale :data:`~crashsim.reconstruct.samplers.IMH_SCALE`; each
    round after it from :func:`~crashsim.reconstruct.samplers.refit_proposal`: that t for a share
    :data:`~crashsim.reconstruct.samplers.IMH_DEFENSIVE` of the draws, the rest a t about the
    importance-weighted mean and covariance of every proposal the rounds before evaluated. The proposal
    is then fixed for the kept chain (an adaptation that stops: the kept chain is a plain Metropolis-Hastings
    chain of that proposal). With ``ess`` the kept chain runs in blocks of ``check_every`` steps until
    the target is met.
    """
    burn = spec.burn_steps
    spec = replace(spec, walkers=1, burn=burn)
    payload = {"data": sampled_data, "fit_spec": fit_spec, "priors": priors, "engine": engine, "file": file,
               "time_limit": float(limit), "derived": derived, "hash": run_hash}
    rng_prop = np.random.default_rng(child_seed(spec.seed, 1))
    rng_acc = np.random.default_rng(child_seed(spec.seed, 2))
    rng_mass = np.random.default_rng(child_seed(spec.seed, 3))
    z_all, lp_all, bl_all, acc_all = [], [], [], []
    burn_points, burn_lp, burn_proposals, burn_counts = [], [], [], []  # every evaluation of the burn-in
    bar = Progress(progress, spec.steps, initial=0, desc="posterior (MCMC)", unit="step", show=True)
    pool = _EmceePool(Executor(_problem_for, payload, backend, nw, dask_address=dask_address, local=problem))
    nw = pool.workers if backend == "dask" else nw
    batch = max(10, min(spec.check_every, 50 * max(1, pool.workers)))
    fit_t = StudentT.from_cov(z0, box_covariance(cov_z), scale=IMH_SCALE)
    proposal = Mixture.of([fit_t], [1.0], rng_mass)
    accepted = 0
    try:
        lp0, blob0 = pool.map(None, [z0])[0]
        state = (np.asarray(z0, float), lp0, blob0)

        def evaluate(ys, keep):
            results = pool.map(None, ys)
            if keep:
                burn_points.extend(ys)
                burn_lp.extend(r[0] for r in results)
            return results

        def run(n, proposal, keep=False):
            nonlocal state, accepted
            for z, lp, blob, acc in independence_chain(lambda ys: evaluate(ys, keep), proposal, state, n, rng_prop,
                                                       rng_acc, batch):
                accepted += acc
                z_all.append(np.array(z, float)[None, :])
                lp_all.append(np.array([lp], float))
                bl_all.append(np.array(blob, float).reshape(1, len(derived)))
                acc_all.append(np.array([accepted], float))
                state = (z, lp, blob)
                bar.update(1, len(z_all))

        rounds = [burn // IMH_ROUNDS + (1 if k < burn % IMH_ROUNDS else 0) for k in range(IMH_ROUNDS)]
        for n in rounds:
            if n == 0:
                continue
            run(n, proposal, keep=True)
            burn_proposals.append(proposal)
            burn_counts.append(n)
            proposal = refit_proposal(fit_t, np.array(burn_points), np.array(burn_lp), burn_proposals, burn_counts,
                                      rng_mass)
        block = spec.check_every if spec.ess is not None else spec.steps - burn
        while len(z_all) < spec.steps:
            run(min(block, spec.steps - len(z_all)), proposal)
            if spec.ess is not None and _enough(z_all, spec):
                break
    finally:
        pool.close()
        bar.close()
    spec = replace(spec, steps=len(z_all))
    nominal = None
    try:
        nominal = problem.fit.full_scene(z0)
    except Exception:  # pragma: no cover - evaluated above already
        nominal = None
    return _assemble(problem, spec, np.array(z_all), np.array(lp_all), np.array(bl_all), np.array(acc_all), derived,
                     x0, dict(pool.failures), pool.evaluations, time.perf_counter() - t0, engine, backend, nw, 0, None,
                     fit_summary, file, nominal, tolerance)


def _enough(z_all: list, spec: PosteriorSpec) -> bool:
    """True when the chain so far meets ``spec.ess``: every unknown has at least that many
    effective samples, and the kept chain passes the length diagnostics (at least
    :data:`TAU_FACTOR` autocorrelation times kept, a burn-in of at least two)."""
    done = len(z_all)
    burn = replace(spec, steps=done).burn_steps
    kept = np.asarray(z_all[burn::spec.thin])
    if kept.shape[0] < MIN_KEPT_STEPS:
        return False
    tau, ess = _diagnostics(kept)
    if not np.all(np.isfinite(tau)):
        return False
    tmax = float(np.max(tau))
    return bool(np.all(ess >= spec.ess) and kept.shape[0] >= TAU_FACTOR * tmax and burn >= 2 * tmax)


def _merge(a: dict, b: dict) -> dict:
    out = dict(a)
    for k, v in b.items():
        out[k] = out.get(k, 0) + int(v)
    return out


def _assemble(problem, spec, z, lp, blobs, acc, derived, x0, failures, evaluations, elapsed, engine, backend, nw,
              n_resumed, chain_path, fit_summary, file, nominal, tolerance=None) -> PosteriorResult:
    fs = problem.spec
    lower = np.array([u.lower for u in fs.unknowns])
    span = np.array([u.upper - u.lower for u in fs.unknowns])
    chain = lower + z * span
    steps = chain.shape[0]
    burn = spec.burn_steps
    kept = chain[burn::spec.thin]
    kept_blobs = blobs[burn::spec.thin]
    samples = kept.reshape(-1, chain.shape[2])
    dsamples = kept_blobs.reshape(-1, len(derived))
    pct = {u.path: _percentiles(samples[:, j]) for j, u in enumerate(fs.unknowns)}
    for k, key in enumerate(derived):
        p = _percentiles(dsamples[:, k])
        if p:
            pct[key] = p
    corr = _correlation(np.column_stack([samples, dsamples]))
    tau, ess = _diagnostics(kept)
    acceptance = acc[-1] / steps
    warnings: list[str] = []
    kept_steps = kept.shape[0]
    tmax = float(np.nanmax(tau)) if np.isfinite(tau).any() else math.inf
    if not kept_steps >= TAU_FACTOR * tmax:
        need = math.ceil(TAU_FACTOR * tmax * spec.thin + burn) if np.isfinite(tmax) else None
        warnings.append(_too_short(kept_steps, tmax, need, spec.sampler))
    if np.isfinite(tmax) and burn < 2 * tmax:
        warnings.append(f"the burn-in ({burn} steps) is shorter than two autocorrelation times ({2 * tmax:.0f} steps): "
                        "the start may still show in the summaries")
    if spec.sampler == "imh":  # one chain: the per-step median of the walkers is that of blocks of consecutive steps
        b = IMH_SETTLE_BLOCK
        blocked = settle_step(lp[:lp.shape[0] // b * b].reshape(-1, b), len(fs.unknowns))
        settled = None if blocked is None else blocked * b
    else:
        settled = settle_step(lp, len(fs.unknowns))
    if settled is not None and burn < settled:
        _log.warning("posterior: the log-probability settles at step %d, after the burn-in of %d steps", settled, burn)
        warnings.append(f"the log-probability settles only at step {settled} (the walkers' median reaches its final "
                        f"level within sqrt(k/2) = {math.sqrt(len(fs.unknowns) / 2):.2g}), after the burn-in of {burn} "
                        f"steps: the summaries include samples still climbing from the start; set posterior.burn >= "
                        f"{settled} (and steps accordingly)")
    am = float(np.mean(acceptance))
    high = ACCEPTANCE_RANGE[1] if spec.sampler == "emcee" else 1.0  # an independence sampler near 1 is at its best
    if not ACCEPTANCE_RANGE[0] <= am <= high:
        warnings.append(f"mean acceptance fraction {am:.3f} is outside {ACCEPTANCE_RANGE[0]:g}-{ACCEPTANCE_RANGE[1]:g}: "
                        + (("the walkers hardly move (a narrow or curved posterior, or stuck walkers)"
                            if spec.sampler == "emcee" else "the proposal from the fit covers the posterior poorly "
                            "(a posterior far from its Gaussian: sampler = \"emcee\" explores it better)")
                           if am < 0.15
                           else "usual for the stretch move with one or two unknowns, or a posterior much wider than "
                                "the walkers' spread; harmless when the chain is long enough in autocorrelation times"))
    stuck = int(np.sum(acceptance == 0))
    if stuck:
        warnings.append(f"{stuck} walker(s) never moved: their samples are their start point")
    if failures:
        warnings.append(f"{sum(failures.values())} proposal(s) gave a scene that cannot be evaluated and were rejected "
                        "(probability zero); see the diagnostics")
    for j, u in enumerate(fs.unknowns):
        for name, near in (("lower", samples[:, j] <= u.lower + EDGE * u.span),
                           ("upper", samples[:, j] >= u.upper - EDGE * u.span)):
            share = float(np.mean(near))
            if share > EDGE_SHARE:
                warnings.append(f"{100 * share:.1f} % of the samples of {u.name} lie within {100 * EDGE:g} % of its "
                                f"[fit] range from its {name} bound: the bound (the prior), not the evidence, limits "
                                "it there")
    i_best = np.unravel_index(int(np.argmax(lp)), lp.shape)
    best = {"x": [float(v) for v in chain[i_best]], "log_prob": float(lp[i_best]),
            "chi2": float(-2 * (lp[i_best] - problem.log_prior(z[i_best])))}
    success = kept_steps >= TAU_FACTOR * tmax and am >= ACCEPTANCE_RANGE[0]
    message = "the chain passes its diagnostics" if success else "see the warnings: " + warnings[0]
    sc = nominal.scenario if nominal is not None and not isinstance(nominal, Exception) else None
    return PosteriorResult(
        unknowns=fs.unknowns, priors=problem.priors, derived=tuple(derived), spec=spec, chain=chain, log_prob=lp,
        blobs=blobs, accepted=acc, samples=samples, derived_samples=dsamples, percentiles=pct, correlation=corr,
        tau=tau, ess=ess, acceptance=acceptance, evaluations=int(evaluations), failure_reasons=dict(failures),
        best=best, warnings=tuple(warnings), success=bool(success), message=message, engine=engine, backend=backend,
        workers=int(nw), elapsed=float(elapsed), n_resumed=int(n_resumed), chain_path=chain_path, start=np.asarray(x0),
        fit=fit_summary, title=sc.title if sc is not None else "", file=file,
        units=sc.units if sc is not None else "SI", nominal=None if sc is None else nominal, tolerance=tolerance)

"""Monte Carlo propagation of input uncertainty through impact and run-out.

Every sample draws the uncertain inputs (uniform, triangular or normal, in the units of the
file), writes them into the scenario (:mod:`crashsim.reconstruct.overrides`, validated like
file values) and runs the whole scene to rest. The result is a table: delta-v, speeds,
energy loss and rest positions of every sample, and the verdict of every evidence item.

Rejection sampling
------------------
Every sample stores the verdict of every evidence item (its residual and whether it is within
its tolerance), so a result, also one read back or resumed from a results file, knows per
sample whether it meets *all* the evidence (:attr:`MCResult.meets_all`). With ``accept``
the result also summarises the accepted samples (those that meet all the evidence; a failed
sample meets none): their count and share, and the percentiles of the outputs and inputs over
them beside those over all samples. The accepted samples are draws of the inputs conditioned
on the evidence being met within its tolerances (rejection sampling with the tolerances as a
uniform likelihood); their number says how much the result rests on.

Reproducibility
---------------
Sample ``i`` draws its inputs from ``numpy.random.default_rng(SeedSequence(seed,
spawn_key=(i,)))`` (the i-th child of ``SeedSequence(seed).spawn``): its inputs depend only
on ``(seed, i)``, not on the number of samples, the order in which samples finish, the
number of workers or the machine. A local run, a resumed run and a Dask run with the same
seed give the same numbers.

Streaming and resume
--------------------
With ``out_path`` each sample is appended to a JSON-lines file as soon as it is done (first
line: a header naming the scenario and the seed by a hash). A run that is stopped keeps what
it wrote; running again with the same file computes only the samples not in it (a torn last
line is dropped). A file written for another scenario or seed is refused.

Parallelism
-----------
``workers`` processes (default all cores), or an existing Dask cluster (``dask_address``;
``dask.distributed``), with samples sent in chunks, through :mod:`crashsim.reconstruct.parallel`
(as the fit and the posterior).
"""

from __future__ import annotations

import hashlib
import json
import logging
import math
import threading
import time
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import CrashsimError, ScenarioError, failure_reason, in_file
from ..evidence.checks import body_impacts
from ..geometry import circular_mean, unwrap_about_mean
from ..impact import solve_impact
from ..inverse_schema import DISTRIBUTIONS, validate_uncertainty
from ..report import fmt
from ..scenario import Scenario
from ..scene.run import simulate_approaches
from ..schema import interval_text
from .overrides import INVERSE_SECTIONS, default_engine, file_contents, parse_value, resolve_path
from .parallel import Executor, Progress, child_seed, choose_backend, chunk_size as default_chunk_size, chunks
from .inputs import Scene, SceneInputs
from .tolerance import evidence_tolerance, tolerance_items, with_tolerance

__all__ = ["InputDistribution", "UncertaintySpec", "MCResult", "monte_carlo", "sample_inputs", "load_results",
           "DEFAULT_PERCENTILES", "DEFAULT_SAMPLE_TIME_LIMIT"]

_log = logging.getLogger("crashsim")

DEFAULT_PERCENTILES = (5.0, 25.0, 50.0, 75.0, 95.0)
#: Wall-clock seconds allowed for one sample's run-out by default (a compiled run-out takes
#: milliseconds, a SciPy one well under 10 s).
DEFAULT_SAMPLE_TIME_LIMIT = 30.0
_FORMAT = "crashsim-mc/1"


# ---------------------------------------------------------------------------------------------
# Specification
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class InputDistribution:
    """One uncertain input: a scenario path and its distribution (parameters in SI).

    ``uniform``: lower, upper. ``triangular``: lower, mode, upper. ``normal``: mean, sd,
    optionally truncated to [lower, upper] (by redrawing).
    """

    path: str
    name: str
    distribution: str
    kind: str
    lower: float | None = None
    upper: float | None = None
    mode: float | None = None
    mean: float | None = None
    sd: float | None = None
    note: str = ""  # how the distribution was fitted to the input's allowed range, for the report

    def sample(self, rng: np.random.Generator) -> float:
        if self.distribution == "uniform":
            return float(rng.uniform(self.lower, self.upper))
        if self.distribution == "triangular":
            if self.lower == self.upper:
                return float(self.lower)
            return float(rng.triangular(self.lower, self.mode, self.upper))
        lo = -math.inf if self.lower is None else self.lower
        hi = math.inf if self.upper is None else self.upper
        for _ in range(10_000):
            x = float(rng.normal(self.mean, self.sd))
            if lo <= x <= hi:
                return x
        raise ScenarioError(f"the truncation [{lo}, {hi}] of {self.path} keeps almost none of its normal "
                            "distribution", field=self.path)

    def ppf(self, q: float) -> float:
        """Quantile ``q`` in (0, 1) (for the one-at-a-time swings of the tornado chart)."""
        from scipy import stats

        if self.distribution == "uniform":
            return self.lower + q * (self.upper - self.lower)
        if self.distribution == "triangular":
            w = self.upper - self.lower
            if w == 0:
                return self.lower
            c = (self.mode - self.lower) / w
            return float(stats.triang.ppf(q, c, loc=self.lower, scale=w))
        lo = -np.inf if self.lower is None else (self.lower - self.mean) / self.sd
        hi = np.inf if self.upper is None else (self.upper - self.mean) / self.sd
        return float(stats.truncnorm.ppf(q, lo, hi, loc=self.mean, scale=self.sd))

    @property
    def median(self) -> float:
        return self.ppf(0.5)

    def logpdf(self, x: float) -> float:
        """Log density at ``x`` up to an additive constant (-inf outside the support), for
        :mod:`crashsim.reconstruct.posterior`'s priors. Triangular: exact; normal (truncated or
        not): ``-(x - mean)^2 / (2 sd^2)`` inside [lower, upper]; uniform: 0 inside."""
        lo = -math.inf if self.lower is None else self.lower
        hi = math.inf if self.upper is None else self.upper
        if not lo <= x <= hi:
            return -math.inf
        if self.distribution == "uniform":
            return 0.0
        if self.distribution == "triangular":
            if hi == lo:
                return 0.0
            c = self.mode
            p = 2 * (x - lo) / ((hi - lo) * (c - lo)) if x < c else (
                2 * (hi - x) / ((hi - lo) * (hi - c)) if x > c else 2 / (hi - lo))
            return math.log(p) if p > 0 else -math.inf
        return -0.5 * ((x - self.mean) / self.sd) ** 2

    def parameters(self, show) -> str:
        """The distribution in words with its parameters, each value written by ``show(value)``:
        ``"uniform [a, b]"``, ``"triangular [a, c, b]"``, ``"normal mean m, sd s"`` (and its truncation)."""
        if self.distribution == "uniform":
            return f"uniform [{show(self.lower)}, {show(self.upper)}]"
        if self.distribution == "triangular":
            return f"triangular [{show(self.lower)}, {show(self.mode)}, {show(self.upper)}]"
        par = f"normal mean {show(self.mean)}, sd {show(self.sd)}"
        if self.lower is not None or self.upper is not None:
            par += (f", truncated to [{show(self.lower) if self.lower is not None else '-inf'}, "
                    f"{show(self.upper) if self.upper is not None else 'inf'}]")
        return par

    def support(self) -> tuple[float, float]:
        """Where the density is positive (closed; infinite ends for an untruncated normal)."""
        lo = -math.inf if self.lower is None else self.lower
        hi = math.inf if self.upper is None else self.upper
        return lo, hi


@dataclass(frozen=True)
class UncertaintySpec:
    """A validated ``[uncertainty]`` table."""

    inputs: tuple[InputDistribution, ...]
    samples: int = 1000
    seed: int = 0
    tolerance: str = "file"

    @property
    def paths(self) -> tuple[str, ...]:
        return tuple(d.path for d in self.inputs)

    @classmethod
    def from_dict(cls, raw: dict, *, file: str | None = None) -> "UncertaintySpec":
        """Validate a raw [uncertainty] table (values with units) and convert it to SI."""
        d = validate_uncertainty(raw, file=file)
        out = []
        for i, e in enumerate(d["inputs"]):
            key = f"uncertainty.inputs[{i}]"
            t = resolve_path(e["path"], field=f"{key}.path")
            need, allowed = DISTRIBUTIONS[e["distribution"]]
            vals = {}
            for k in ("lower", "upper", "mode", "mean", "sd"):
                if e[k] is None:
                    if k in need:
                        raise ScenarioError(f"distribution {e['distribution']!r} needs {k} (and {', '.join(need)})",
                                            field=f"{key}.{k}", file=file)
                    continue
                if k not in need and k not in allowed:
                    raise ScenarioError(f"{k} does not belong to distribution {e['distribution']!r} (it takes "
                                        f"{', '.join(need + allowed)})", field=f"{key}.{k}", file=file)
                vals[k] = parse_value(e[k], t, field=f"{key}.{k}")
            lo, hi = vals.get("lower"), vals.get("upper")
            if lo is not None and hi is not None and not lo <= hi:
                raise ScenarioError(f"lower {e['lower']!r} is above upper {e['upper']!r}", field=f"{key}.upper",
                                    file=file)
            if "mode" in vals and not lo <= vals["mode"] <= hi:
                raise ScenarioError(f"mode {e['mode']!r} lies outside [{e['lower']}, {e['upper']}]",
                                    field=f"{key}.mode", file=file)
            if "sd" in vals and not vals["sd"] > 0:
                raise ScenarioError(f"sd {e['sd']!r} must be positive", field=f"{key}.sd", file=file)
            if e["distribution"] == "normal" and lo is not None and hi is not None and lo == hi:
                raise ScenarioError("a truncated normal needs lower < upper", field=f"{key}.upper", file=file)
            vals, note = _fit_to_range(e["distribution"], vals, t, key, e, file)
            out.append(InputDistribution(t.path, e["name"] or t.path, e["distribution"], t.kind, note=note, **vals))
        seen = set()
        for i, dist in enumerate(out):
            if dist.path in seen:
                raise ScenarioError(f"{dist.path!r} is given twice", field=f"uncertainty.inputs[{i}].path", file=file)
            seen.add(dist.path)
        return cls(tuple(out), samples=d["samples"], seed=d["seed"], tolerance=d["tolerance"])

    def to_dict(self) -> dict:
        return {"samples": self.samples, "seed": self.seed, "tolerance": self.tolerance,
                "inputs": [dict(d.__dict__) for d in self.inputs]}


#: Largest share of a normal distribution outside its input's allowed range that is cut off
#: (the distribution is then truncated to the range and the report says so); beyond it the
#: distribution does not describe the input and is refused.
MAX_TRUNCATED = 0.01


def _fit_to_range(distribution: str, vals: dict, target, key: str, raw: dict, file: str | None):
    """Keep a distribution inside the allowed range of its input (the schema's minimum/maximum).

    Uniform and triangular bounds must lie inside the range.  A normal distribution is
    truncated to the range when at most :data:`MAX_TRUNCATED` of it lies outside (the report
    notes it), and refused otherwise: never does a sample fall outside and get dropped.
    Returns ``(values, note)``.
    """
    from scipy import stats

    f = target.field
    lo_ok = -math.inf if f.minimum is None else float(f.minimum)
    hi_ok = math.inf if f.maximum is None else float(f.maximum)
    if lo_ok == -math.inf and hi_ok == math.inf:
        return vals, ""
    allowed = interval_text(f, next((raw[k] for k in ("mean", "lower", "upper", "mode") if isinstance(raw.get(k), str)),
                                    None))
    # an exclusive end is kept off by a relative 1e-9 (a value there would be refused)
    lo_in = lo_ok if not f.exclusive_minimum else lo_ok + 1e-9 * max(1.0, abs(lo_ok), abs(hi_ok) if hi_ok < math.inf else 1.0)
    hi_in = hi_ok if not f.exclusive_maximum else hi_ok - 1e-9 * max(1.0, abs(hi_ok))
    if distribution in ("uniform", "triangular"):
        for k in ("lower", "upper"):
            v = vals[k]
            if not lo_in <= v <= hi_in:
                raise ScenarioError(f"{k} = {raw[k]!r} lies outside the allowed range of {target.path}, {allowed}: "
                                    "every sample must be a valid input", field=f"{key}.{k}", file=file)
        return vals, ""
    mean, sd = vals["mean"], vals["sd"]
    lo_user = vals.get("lower", -math.inf)
    hi_user = vals.get("upper", math.inf)
    lo_eff, hi_eff = max(lo_user, lo_in), min(hi_user, hi_in)
    if not lo_eff < hi_eff:
        raise ScenarioError(f"the truncation [{raw.get('lower')}, {raw.get('upper')}] lies outside the allowed range "
                            f"of {target.path}, {allowed}", field=f"{key}.lower", file=file)
    # share of the (user-truncated) normal that falls outside the allowed range
    dist = stats.norm(mean, sd)
    kept_user = dist.cdf(hi_user) - dist.cdf(lo_user)
    cut = 1.0 - (dist.cdf(hi_eff) - dist.cdf(lo_eff)) / kept_user
    if cut <= 1e-12:
        return vals, ""
    if cut > MAX_TRUNCATED:
        raise ScenarioError(f"the normal distribution of {target.path} (mean {raw['mean']}, sd {raw['sd']}) puts "
                            f"{100 * cut:.3g} % of its samples outside the allowed range {allowed}; narrow it, or "
                            "truncate it yourself with lower and upper inside the range",
                            field=f"{key}.sd", file=file)
    out = dict(vals, lower=lo_eff, upper=hi_eff)
    return out, (f"truncated to the allowed range {allowed} ({100 * cut:.2g} % of the normal distribution lay "
                 "outside it)")


def sample_inputs(spec: UncertaintySpec, seed: int, i: int) -> np.ndarray:
    """The inputs of sample ``i`` (SI): a function of ``(seed, i)`` only."""
    rng = np.random.default_rng(child_seed(seed, i))
    return np.array([d.sample(rng) for d in spec.inputs])


# ---------------------------------------------------------------------------------------------
# One sample
# ---------------------------------------------------------------------------------------------

#: Unit kind of each output, by the prefix of its key ("delta_v.car").
OUTPUT_KINDS = {"delta_v": "speed", "speed": "speed", "speed_after": "speed", "energy_loss": "dimensionless",
                "rest_x": "length", "rest_y": "length", "rest_heading": "angle", "distance": "length",
                "delta_v_event": "speed", "impacts": "count", "speed_at_braking": "speed", "time_to_impact": "time",
                "braking_distance": "length", "perception_distance": "length", "mu": "ratio",
                "mu_over_mu_max": "dimensionless", "rolled": "dimensionless"}


def scene_outputs(scene) -> dict[str, float]:
    """Flat outputs of one scene (SI): delta-v, speeds before/after, energy loss, rest positions,
    the impulse ratio mu and mu / mu_max of the first impact, and for each vehicle with an approach
    its speed at the start of braking, the time and distance from it to the impact and the
    distance from perception;
    with a joint run-out also each body's delta-v over the whole event (``delta_v_event``: the
    magnitude of the sum over all its impacts, as a recorder accumulating the event sees it)
    and the number of impacts after the first (``impacts.later``); with the wheel-lift and rollover
    check on, ``rolled.<vehicle>``: 1 if a unit of the vehicle rolls, else 0 (an outcome, not a
    failed sample; its mean over the samples is the share that roll)."""
    imp = scene.impact
    out: dict[str, float] = {}
    sc = scene.scenario
    for veh in sc.vehicles:  # the first body's CG speed at impact (from the file, or from its approach)
        if not veh.is_barrier:
            out[f"speed.{veh.name}"] = float(np.hypot(*sc.states[veh.bodies[0].name].velocity))
    for vname, a in (getattr(sc, "approaches", None) or {}).items():
        out[f"speed_at_braking.{vname}"] = a.speed_at_braking
        out[f"time_to_impact.{vname}"] = a.time_to_impact
        out[f"braking_distance.{vname}"] = a.distance
        out[f"perception_distance.{vname}"] = a.distance + a.reaction_distance
    out["mu.impact"] = float(imp.mu)
    if imp.mu_fraction is not None:
        out["mu_over_mu_max.impact"] = float(imp.mu_fraction)
    for name, b in imp.bodies.items():
        if b.fixed:
            continue
        out[f"delta_v.{name}"] = b.delta_v_magnitude
        out[f"speed_after.{name}"] = float(np.hypot(*b.velocity))
    for k, v in imp.energy_loss.items():
        out[f"energy_loss.{k}"] = float(v)
    joint = getattr(scene, "joint", None)
    if joint is not None:
        out["impacts.later"] = float(len(joint.impact_events()))
        for r in scene.runout.values():
            for name in r.bodies:
                own = body_impacts(name, imp, joint.impacts)
                if own:
                    out[f"delta_v_event.{name}"] = float(np.hypot(*sum(d for d, _ in own)))
    for vname, roll in scene.rollover().items():  # the check on: 1 where a unit of the vehicle rolls
        out[f"rolled.{vname}"] = 1.0 if roll["rolled"] else 0.0
    for r in (scene.runout or {}).values():
        for name, b in r.bodies.items():
            out[f"rest_x.{name}"] = float(b.rest_position[0])
            out[f"rest_y.{name}"] = float(b.rest_position[1])
            out[f"rest_heading.{name}"] = float(b.rest_heading_wrapped)
            out[f"distance.{name}"] = float(b.distance)
    return out


def _check_key(c) -> str:
    return f"{c.kind}: {c.name}"


class _Runner:
    def __init__(self, data: dict, spec: UncertaintySpec, engine: str, file: str | None,
                 sample_time_limit: float | None = None):
        self.spec = spec
        self.inputs = Scene(data, engine=engine, file=file, max_wall_time=sample_time_limit).inputs(
            spec.paths, field="uncertainty.inputs", cache=1)

    def run(self, seed: int, i: int) -> dict:
        x = sample_inputs(self.spec, seed, i)
        row: dict[str, Any] = {"i": int(i), "x": [float(v) for v in x]}
        try:
            scene = self.inputs.run(x, lean=True)  # what the record reads, the same numbers
        except CrashsimError as exc:
            row["error"] = f"{type(exc).__name__}: {exc}"
            row["reason"] = failure_reason(exc)
            return row
        if not scene.at_rest:  # a run-out ended by a limit: its positions are not rest positions
            bad = [(v, r) for v, r in scene.runout.items() if not r.success]
            row["error"] = "run-out did not reach rest: " + "; ".join(f"{v}: {r.message}" for v, r in bad)
            row["reason"] = f"run-out: {bad[0][1].status}"
            return row
        row["out"] = scene_outputs(scene)
        if scene.evidence is not None:
            row["checks"] = {}
            for c in scene.evidence.checks:
                key, k = _check_key(c), 2
                while key in row["checks"]:  # two items of the same kind and name stay two
                    key, k = f"{_check_key(c)} ({k})", k + 1
                row["checks"][key] = [float(c.residual) if math.isfinite(c.residual) else None, bool(c.passed)]
        row["warnings"] = len(scene.warnings)
        row["rest"] = all(r.success for r in (scene.runout or {}).values())
        return row


_LOCAL = threading.local()


def _runner_for(payload: dict) -> _Runner:
    cache = getattr(_LOCAL, "runners", None)
    if cache is None:
        cache = _LOCAL.runners = {}
    key = (payload["hash"], payload["engine"], payload.get("time_limit"))
    r = cache.get(key)
    if r is None:
        r = cache[key] = _Runner(payload["data"], payload["spec"], payload["engine"], payload["file"],
                                             payload.get("time_limit"))
    return r


def _sampler_for(payload: dict) -> tuple:
    """A worker's state: the runner of ``payload`` (built once per thread) and the run's seed."""
    return _runner_for(payload), payload["seed"]


def _run_sample(state: tuple, i: int) -> dict:
    """Sample ``i`` (a task of :class:`~crashsim.reconstruct.parallel.Executor`)."""
    runner, seed = state
    return runner.run(seed, i)


# ---------------------------------------------------------------------------------------------
# Result
# ---------------------------------------------------------------------------------------------

@dataclass(frozen=True)
class MCResult:
    """Outcome of :func:`monte_carlo` (SI).

    Attributes
    ----------
    spec : UncertaintySpec
    seed : int
    n : int
        Samples asked for; ``indices`` those present (all of them unless interrupted).
    inputs : ndarray (n_done, k)
        Sampled inputs [SI], rows in index order.
    outputs : dict of ndarray (n_done,)
        By key (``"delta_v.car"``, ``"rest_x.trailer"``, ...); NaN for failed samples.
    checks : dict of (residuals, passed) arrays by evidence item (``"rest: rest of car"``).
    errors : list of (index, message)
    failure_reasons : dict
        Number of failed samples by reason (``"inadmissible impact: ..."``, ``"run-out: wall_time_limit"``, ...).
    percentiles : dict
        ``{key: {"p5": ..., ..., "mean": ..., "std": ...}}`` over successful samples.
    pass_share : dict
        Share of successful samples meeting each evidence tolerance, and ``"all evidence"``.
    tornado : dict
        By output key (delta-v of the bodies in contact): per input its Spearman rank
        correlation with the output over the samples and the one-at-a-time swing of the output
        (input at its 5th and 95th percentiles, others at their medians): ``low``, ``high``,
        ``base``.
    nominal : SceneResult or None
        The scene with every input at its median (for plots; not in ``to_dict``).
    meets_all : ndarray of bool (n_done,)
        Per sample (in ``indices`` order): it ran and every evidence item is within its
        tolerance. All False when the scenario has no evidence.
    accept : bool
        Whether the report and ``to_dict`` summarise the accepted samples (rejection sampling,
        ``crashsim mc --accept``) and the figures draw them apart.
    accepted_percentiles, input_percentiles, accepted_input_percentiles : dict
        As ``percentiles``, over the accepted samples; and of the inputs (by input name) over
        the successful and over the accepted samples.
    """

    spec: UncertaintySpec
    seed: int
    n: int
    indices: np.ndarray
    inputs: np.ndarray
    outputs: dict
    checks: dict
    errors: list
    percentiles: dict
    pass_share: dict
    tornado: dict
    n_resumed: int
    elapsed: float
    engine: str
    backend: str
    workers: int
    out_path: str | None
    nominal: Any = field(default=None, repr=False, compare=False)
    failure_reasons: dict = field(default_factory=dict)
    meets_all: np.ndarray = field(default_factory=lambda: np.zeros(0, dtype=bool), repr=False, compare=False)
    accept: bool = False
    accepted_percentiles: dict = field(default_factory=dict)
    input_percentiles: dict = field(default_factory=dict)
    accepted_input_percentiles: dict = field(default_factory=dict)
    tolerance: Any = None  # SampleTolerance when [uncertainty] tolerance = "evidence" chose it

    @property
    def n_done(self) -> int:
        return int(len(self.indices))

    @property
    def n_failed(self) -> int:
        return len(self.errors)

    @property
    def n_evidence(self) -> int:
        """Number of evidence checks of a sample (a rest item with a heading counts twice)."""
        return len(self.checks)

    @property
    def n_accepted(self) -> int:
        """Samples that meet all the evidence."""
        return int(np.count_nonzero(self.meets_all))

    @property
    def accepted_share(self) -> float:
        """Share of the samples run (failed ones included, as not meeting it) that meet all the evidence."""
        return self.n_accepted / self.n_done if self.n_done else float("nan")

    def evidence_headline(self) -> str:
        """One line: how many samples meet all the evidence (``"4.2 % of 3000 samples meet all 9 evidence
        items"``); failed samples count as not meeting it."""
        if not self.n_evidence:
            return f"{self.n_done} samples; no evidence items to meet"
        items = f"{self.n_evidence} evidence item{'s' if self.n_evidence != 1 else ''}"
        failed = f" ({self.n_failed} failed)" if self.n_failed else ""
        if self.n_evidence == 1:
            return f"{100 * self.accepted_share:.3g} % of {self.n_done} samples{failed} meet the {items}"
        return f"{100 * self.accepted_share:.3g} % of {self.n_done} samples{failed} meet all {items}"

    @property
    def rolled_share(self) -> dict:
        """By vehicle (the wheel-lift and rollover check on): the share of the successful samples in which
        a unit of it rolls; empty without the check."""
        failed = {i for i, _ in self.errors}
        good = np.array([int(i) not in failed for i in self.indices], dtype=bool)
        out = {}
        for key, v in self.outputs.items():
            if key.startswith("rolled.") and good.any():
                out[key.split(".", 1)[1]] = float(np.nanmean(np.asarray(v, dtype=float)[good]))
        return out

    def rollover_lines(self) -> list[str]:
        """The report's rollover lines (none without the check)."""
        share = self.rolled_share
        if not share:
            return []
        n_ok = self.n_done - self.n_failed
        return ["Rollover (an outcome of a sample, not a failure; wheel-lift and rollover check)"] + [
            f"  vehicle {v}: a unit rolls in {100 * f:.1f} % of the {n_ok} successful samples "
            f"({int(round(f * n_ok))} samples)" for v, f in share.items()]

    @staticmethod
    def kind_of(key: str) -> str:
        return OUTPUT_KINDS.get(key.split(".", 1)[0], "dimensionless")

    def values(self, key: str) -> np.ndarray:
        """The samples of an output (SI; NaN where a sample failed), an angle (a rest heading) on
        its arc around the circular mean (:func:`crashsim.geometry.unwrap_about_mean`), as its
        percentiles are taken: a cloud across +-180 deg is one cloud, not two."""
        v = np.asarray(self.outputs[key], dtype=float)
        return unwrap_about_mean(v) if self.kind_of(key) == "angle" else v

    def to_dict(self) -> dict:
        fin = lambda v: float(v) if v is not None and np.isfinite(v) else None  # noqa: E731
        return {
            "n": self.n, "n_done": self.n_done, "n_failed": self.n_failed, "n_resumed": self.n_resumed,
            "seed": self.seed, "engine": self.engine, "backend": self.backend, "workers": self.workers,
            "elapsed": self.elapsed, "out_path": self.out_path, "spec": self.spec.to_dict(),
            "tolerance": None if self.tolerance is None else self.tolerance.to_dict(),
            "percentiles": {k: {q: fin(v) for q, v in p.items()} for k, p in self.percentiles.items()},
            "pass_share": self.pass_share,
            "tornado": self.tornado,
            "errors": [{"i": int(i), "message": m} for i, m in self.errors[:50]],
            "failure_reasons": dict(self.failure_reasons),
            **({"rolled_share": self.rolled_share} if self.rolled_share else {}),
            **({"accepted": {
                "count": self.n_accepted, "share": fin(self.accepted_share), "of": self.n_done,
                "n_evidence": self.n_evidence, "indices": [int(i) for i in self.indices[self.meets_all]],
                "percentiles": {k: {q: fin(v) for q, v in p.items()} for k, p in self.accepted_percentiles.items()},
                "inputs": {k: {q: fin(v) for q, v in p.items()} for k, p in self.accepted_input_percentiles.items()},
                "inputs_all": {k: {q: fin(v) for q, v in p.items()} for k, p in self.input_percentiles.items()},
            }} if self.accept else {}),
        }

    def report(self, system: str = "SI") -> str:
        def show(v, kind):
            if v is None or not np.isfinite(v):
                return "n/a"
            if kind == "dimensionless":
                return f"{100 * v:.1f} %"
            if kind == "count":
                return f"{v:.3g}"
            if kind == "ratio":
                return f"{v:.4g}"
            return fmt(v, kind, system)

        title = self.nominal.scenario.title if self.nominal is not None else ""
        lines = [f"crashsim Monte Carlo: {title}".rstrip()]
        resumed = f", {self.n_resumed} resumed from the results file" if self.n_resumed else ""
        lines.append(f"{self.n_done} of {self.n} samples ({self.n_failed} failed{resumed}); seed {self.seed}; "
                     f"engine {self.engine}; "
                     + (f"{self.backend}, {self.workers} worker(s)" if self.backend != "serial" else "serial (this process)")
                     + f"; {self.elapsed:.1f} s")
        if self.tolerance is not None:
            lines.append(f"run-out tolerance of the samples: {self.tolerance.text(system)}")
        lines.append("")
        lines.append("Uncertain inputs")
        output_show = show

        def show(v, kind):  # noqa: F811 - inputs: plain numbers stay plain (restitution, friction)
            return f"{v:.4g}" if kind == "dimensionless" and v is not None else output_show(v, kind)

        for d in self.spec.inputs:
            par = d.parameters(lambda v, k=d.kind: show(v, k))
            lines.append(f"  {d.name:<34} {par}")
            if d.note:
                lines.append(f"  {'':<34} ({d.note})")
        show = output_show
        lines.append("")
        qs = [q for q in next(iter(self.percentiles.values()), {}) if q.startswith("p")]
        both = self.accept and bool(self.accepted_percentiles)
        lines.append("Outputs (percentiles over the successful samples" + (
            "; below each, over the accepted samples: those that meet all the evidence)" if both else ")"))
        lines.append(f"  {'output':<28}{'':<10}" if both else f"  {'output':<28}")
        lines[-1] += "".join(f"{q:>13}" for q in qs)
        for key, p in self.percentiles.items():
            kind = self.kind_of(key)
            row = "".join(f"{show(p[q], kind):>13}" for q in qs)
            lines.append(f"  {key:<28}" + (f"{'all':<10}" if both else "") + row)
            a = self.accepted_percentiles.get(key) if both else None
            if a is not None:
                lines.append(f"  {'':<28}{'accepted':<10}" + "".join(f"{show(a[q], kind):>13}" for q in qs))
        if any(self.kind_of(k) == "angle" for k in self.percentiles):
            lines.append("  (rest headings: percentiles on the arc around their circular mean, so a cloud across "
                         "+-180 deg is one cloud; a value may pass +-180 deg)")
        if self.pass_share:
            lines.append("")
            lines.append(f"Evidence over the samples: {self.evidence_headline()}")
            lines.append("Share of samples within each evidence tolerance (over the successful samples)")
            for k, s in self.pass_share.items():
                lines.append(f"  {100 * s:6.1f} %  {k}")
        if self.rolled_share:
            lines += [""] + self.rollover_lines()
        if self.accept:
            lines += [""] + self._accepted_lines(show, qs)
        if self.tornado:
            lines.append("")
            lines.append("What moves delta-v (one input from its 5th to its 95th percentile, the others at their "
                         "medians; Spearman rank correlation over the samples)")
            for key, rows in self.tornado.items():
                lines.append(f"  {key} (all inputs at their medians: {show(rows[0]['base'], self.kind_of(key))})")
                kind = self.kind_of(key)
                for r in rows:
                    rho = "n/a" if r["spearman"] is None else f"{r['spearman']:+.2f}"
                    lines.append(f"    {r['input']:<34} {show(r['low'], kind):>12} .. {show(r['high'], kind):<12} "
                                 f"swing {show(r['swing'], kind):>12}   rho {rho}")
        if self.errors:
            lines.append("")
            lines.append(f"Failed samples ({len(self.errors)}) by reason (they are left out of every figure above)")
            for reason, count in sorted(self.failure_reasons.items(), key=lambda kv: -kv[1]):
                lines.append(f"  {count:6d}  {reason}")
            lines.append(f"  first: sample {self.errors[0][0]}: {self.errors[0][1]}")
        return "\n".join(lines)


    def _accepted_lines(self, show, qs) -> list[str]:
        """The report's rejection-sampling section: the accepted count, and the inputs over all and accepted samples
        (the outputs of the accepted samples are in the outputs table)."""
        lines = [f"Accepted samples (rejection sampling): {self.evidence_headline()}"]
        if not self.n_evidence:
            lines.append("  the scenario has no evidence: there is nothing to accept the samples against")
            return lines
        if not self.n_accepted:
            lines.append("  NO sample meets all the evidence: there are no accepted percentiles. The evidence and the "
                         "[uncertainty] inputs disagree (widen the distributions, check the evidence), or more "
                         "samples are needed.")
            return lines
        few = " (few: their percentiles are rough)" if self.n_accepted < 30 else ""
        lines.append(f"  {self.n_accepted} accepted{few}. The inputs, over all successful samples and over the "
                     "accepted ones (the inputs given the evidence):")
        w = max([28] + [len(d.name) + 2 for d in self.spec.inputs])
        lines.append(f"  {'input':<{w}}{'':<10}" + "".join(f"{q:>13}" for q in qs))
        for d in self.spec.inputs:
            for tag, table in (("all", self.input_percentiles), ("accepted", self.accepted_input_percentiles)):
                p = table.get(d.name)
                if p is not None:
                    shown = [f"{p[q]:.4g}" if d.kind == "dimensionless" else show(p[q], d.kind) for q in qs]
                    lines.append(f"  {d.name if tag == 'all' else '':<{w}}{tag:<10}"
                                 + "".join(f"{v:>13}" for v in shown))
        return lines


# ---------------------------------------------------------------------------------------------
# Results file
# ---------------------------------------------------------------------------------------------

def _run_hash(data: dict, spec: UncertaintySpec) -> str:
    forward = {k: v for k, v in data.items() if k not in INVERSE_SECTIONS}
    key = {"data": forward, "inputs": spec.to_dict()["inputs"], "seed": spec.seed}
    if spec.tolerance != "file":  # files written before the setting existed keep their hash
        key["tolerance"] = spec.tolerance
    blob = json.dumps(key, sort_keys=True, default=str)
    return hashlib.sha256(blob.encode()).hexdigest()[:16]


def _read_rows(path: Path, run_hash: str | None) -> tuple[dict | None, dict[int, dict]]:
    """Header and rows of a results file; a torn last line is cut off the file."""
    if not path.exists() or path.stat().st_size == 0:
        return None, {}
    raw = path.read_bytes()
    if not raw.endswith(b"\n"):
        cut = raw.rfind(b"\n") + 1
        with path.open("r+b") as fh:
            fh.truncate(cut)
        raw = raw[:cut]
    lines = raw.decode("utf-8").splitlines()
    header = json.loads(lines[0]) if lines else None
    if header is None or header.get("format") != _FORMAT:
        raise ScenarioError(f"{path} is not a crashsim Monte Carlo results file", field="out_path")
    if run_hash is not None and header.get("hash") != run_hash:
        raise ScenarioError(f"{path} holds samples of another scenario or seed (hash {header.get('hash')}, this run "
                            f"{run_hash}); delete it or choose another file", field="out_path")
    rows = {}
    for line in lines[1:]:
        try:
            row = json.loads(line)
        except json.JSONDecodeError:
            continue
        rows[int(row["i"])] = row
    return header, rows


def load_results(path: str | Path, scenario_data: dict | None = None, spec: UncertaintySpec | dict | None = None,
                 *, percentiles: Sequence[float] = DEFAULT_PERCENTILES, accept: bool = False) -> MCResult:
    """An :class:`MCResult` from a results file alone (no evaluation; no tornado swings, no nominal scene).

    ``accept``: summarise the samples that meet all the evidence (see :func:`monte_carlo`).
    """
    header, rows = _read_rows(Path(path), None)
    if header is None:
        raise ScenarioError(f"{path} is empty", field="out_path")
    spec = UncertaintySpec.from_dict(spec) if isinstance(spec, dict) else spec
    if spec is None:
        spec = _spec_from_header(header)
    n = max([int(header.get("n", 0))] + [i + 1 for i in rows])
    return _assemble(spec, header["seed"], n, rows, len(rows), 0.0, header.get("engine", "?"), "file", 0, str(path),
                     percentiles, swings=None, nominal=None, accept=accept)


def _spec_from_header(header: dict) -> UncertaintySpec:
    ins = tuple(InputDistribution(**d) for d in header["spec"]["inputs"])
    return UncertaintySpec(ins, samples=header["spec"]["samples"], seed=header["spec"]["seed"])


# ---------------------------------------------------------------------------------------------
# Aggregation
# ---------------------------------------------------------------------------------------------

def _spearman(a: np.ndarray, b: np.ndarray) -> float | None:
    from scipy.stats import rankdata

    ok = np.isfinite(a) & np.isfinite(b)
    if ok.sum() < 3 or np.ptp(a[ok]) == 0 or np.ptp(b[ok]) == 0:
        return None

    ra, rb = rankdata(a[ok]), rankdata(b[ok])
    return float(np.corrcoef(ra, rb)[0, 1])


def _percentiles(columns: dict, mask: np.ndarray, percentiles: Sequence[float], angles: Sequence[str] = ()) -> dict:
    """``{key: {"p5": ..., "mean": ..., "std": ...}}`` of each column over the samples in ``mask`` (finite values).

    The columns named in ``angles`` are wrapped angles (rest headings, in (-pi, pi]): their
    statistics are those of the arc around their circular mean
    (:func:`crashsim.geometry.unwrap_about_mean`): the mean is the circular mean, the percentiles
    and the standard deviation those of the unwrapped values (a percentile may pass +-pi where the
    cloud crosses it, so that p5 <= p50 <= p95). A count's percentiles are those of its empirical
    distribution (``inverted_cdf``: a value some sample has), not interpolated between samples.
    """
    out = {}
    for key, v in columns.items():
        vv = v[mask & np.isfinite(v)]
        if vv.size == 0:
            continue
        if key in angles:
            vv = unwrap_about_mean(vv)
        # a count (the later impacts) has percentiles that are counts: a sample's own value
        method = "inverted_cdf" if OUTPUT_KINDS.get(key.split(".", 1)[0]) == "count" else "linear"
        p = {f"p{q:g}": float(np.percentile(vv, q, method=method)) for q in percentiles}
        p["mean"] = circular_mean(vv) if key in angles else float(np.mean(vv))
        p["std"] = float(np.std(vv, ddof=1)) if vv.size > 1 else 0.0
        out[key] = p
    return out


def _assemble(spec, seed, n, rows: dict, n_resumed, elapsed, engine, backend, workers, out_path, percentiles,
              swings, nominal, accept: bool = False, tolerance=None) -> MCResult:
    idx = np.array(sorted(i for i in rows if i < n), dtype=int)
    k = len(spec.inputs)
    X = np.array([rows[i]["x"] for i in idx], dtype=float).reshape(len(idx), k)
    keys: list[str] = []
    ckeys: list[str] = []
    for i in idx:
        for key in rows[i].get("out", {}):
            if key not in keys:
                keys.append(key)
        for key in rows[i].get("checks", {}):
            if key not in ckeys:
                ckeys.append(key)
    outputs = {key: np.array([rows[i].get("out", {}).get(key, np.nan) for i in idx], dtype=float) for key in keys}
    checks = {}
    for key in ckeys:
        res = np.array([(rows[i].get("checks", {}).get(key, [None, False])[0]) for i in idx], dtype=float)
        ok = np.array([bool(rows[i].get("checks", {}).get(key, [None, False])[1]) for i in idx])
        checks[key] = (res, ok)
    errors = [(int(i), rows[i]["error"]) for i in idx if rows[i].get("error")]
    reasons: dict[str, int] = {}
    for i in idx:
        if rows[i].get("error"):
            why = rows[i].get("reason") or rows[i]["error"].split(":", 1)[0]  # files written before reasons
            reasons[why] = reasons.get(why, 0) + 1
    good = np.array([not rows[i].get("error") for i in idx], dtype=bool)
    angles = [key for key in outputs if OUTPUT_KINDS.get(key.split(".", 1)[0]) == "angle"]  # wrapped: circular
    pct = _percentiles(outputs, good, percentiles, angles)
    meets = good.copy() if checks else np.zeros(len(idx), dtype=bool)
    for _, ok in checks.values():
        meets &= ok
    inputs = {d.name: X[:, j] for j, d in enumerate(spec.inputs)}
    share = {}
    if good.any():
        for key, (_, ok) in checks.items():
            share[key] = float(np.mean(ok[good]))
        if checks:
            share["all evidence"] = float(np.mean(np.all(np.column_stack([ok[good] for _, ok in checks.values()]),
                                                         axis=1)))
    tornado = {}
    if swings is not None:
        for key, (base, lowhigh) in swings.items():
            rows_t = []
            for j, d in enumerate(spec.inputs):
                lo, hi = lowhigh[j]
                rho = _spearman(X[good, j], outputs[key][good]) if key in outputs else None
                rows_t.append({"input": d.name, "path": d.path, "low": lo, "high": hi, "base": base,
                               "swing": float(abs(hi - lo)) if np.isfinite(hi - lo) else None, "spearman": rho})
            rows_t.sort(key=lambda r: -(r["swing"] or 0.0))
            tornado[key] = rows_t
    return MCResult(spec=spec, seed=int(seed), n=int(n), indices=idx, inputs=X, outputs=outputs, checks=checks,
                    errors=errors, percentiles=pct, pass_share=share, tornado=tornado, n_resumed=int(n_resumed),
                    elapsed=float(elapsed), engine=engine, backend=backend, workers=int(workers),
                    out_path=None if out_path is None else str(out_path), nominal=nominal, failure_reasons=reasons,
                    meets_all=meets, accept=bool(accept),
                    accepted_percentiles=_percentiles(outputs, meets, percentiles, angles),
                    input_percentiles=_percentiles(inputs, good, percentiles),
                    accepted_input_percentiles=_percentiles(inputs, meets, percentiles), tolerance=tolerance)


def _median_scene(inputs: SceneInputs, med: np.ndarray):
    """The scene with every input at its median, or None (logged) if it cannot be run."""
    try:
        return inputs.run(med)
    except CrashsimError as exc:
        _log.warning("the scene with every input at its median cannot be run: %s", exc)
        return None


def _swings(data, spec: UncertaintySpec, engine, file, q=(0.05, 0.95)) -> tuple[dict, Any]:
    """One-at-a-time swings of the contact bodies' delta-v (the impact only, after the vehicles' approaches where
    the scene has them: their speeds at the impact come from there) and the median scene."""
    ov = Scene(data, engine=engine, file=file).inputs(spec.paths, field="uncertainty.inputs", cache=1)
    med = np.array([d.median for d in spec.inputs])
    nominal = _median_scene(ov, med)
    try:
        base_imp = solve_impact(simulate_approaches(ov.scenario(med)).impact)
    except CrashsimError:
        return {}, nominal
    keys = [f"delta_v.{base_imp.body1}", f"delta_v.{base_imp.body2}"]
    keys = [k for k in keys if not base_imp.bodies[k.split(".", 1)[1]].fixed]

    def dv(x):
        try:
            imp = solve_impact(simulate_approaches(ov.scenario(x)).impact)
        except CrashsimError:
            return {k: float("nan") for k in keys}
        return {k: imp.bodies[k.split(".", 1)[1]].delta_v_magnitude for k in keys}

    base = dv(med)
    out = {k: (base[k], []) for k in keys}
    for j, d in enumerate(spec.inputs):
        vals = []
        for qq in q:
            x = med.copy()
            x[j] = d.ppf(qq)
            vals.append(dv(x))
        for k in keys:
            out[k][1].append((vals[0][k], vals[1][k]))
    return out, nominal


# ---------------------------------------------------------------------------------------------
# monte_carlo
# ---------------------------------------------------------------------------------------------

def monte_carlo(scenario_data: dict | Scenario, spec: UncertaintySpec | dict | None = None, n: int | None = None, *,
                seed: int | None = None, engine: str | None = None, workers: int | None = None,
                dask_address: Any = None, out_path: str | Path | None = None,
                progress: bool | Callable[[int, int], None] = True, chunk_size: int | None = None,
                percentiles: Sequence[float] = DEFAULT_PERCENTILES, file: str | None = None,
                sample_time_limit: float = DEFAULT_SAMPLE_TIME_LIMIT, accept: bool = False) -> MCResult:
    """Propagate the uncertain inputs through impact and run-out by Monte Carlo sampling.

    Parameters
    ----------
    scenario_data : dict or Scenario
        The raw scenario (as from TOML), or a Scenario loaded from one (its ``file_data``, not read
        again).
    spec : UncertaintySpec or dict, optional
        The uncertain inputs: an :class:`UncertaintySpec`, a raw [uncertainty] table, or None
        for the scenario's own ``[uncertainty]`` table.
    n : int, optional
        Number of samples (default ``spec.samples``); samples ``0 .. n-1`` are run.
    seed : int, optional
        Default ``spec.seed``. Sample i depends only on (seed, i).
    engine : {"compiled", "scipy"}, optional
        Run-out engine; default the compiled one when this crashsim has it.
    workers : int, optional
        Local processes (default all cores; 1 runs in this process). Ignored with ``dask_address``.
    dask_address : str or distributed.Client, optional
        Run on an existing Dask cluster (scheduler address such as ``"tcp://10.0.0.5:8786"``);
        its workers need crashsim installed.
    out_path : str or Path, optional
        JSON-lines results file, written as samples complete; if it exists, the samples in it
        are kept and only the others are run (resume).
    progress : bool or callable
        True: a tqdm progress bar on stderr; a callable ``progress(done, total)`` after each
        chunk; False: silent.
    chunk_size : int, optional
        Samples per task (default: about 4 tasks per worker, at most 64 samples).
    percentiles : sequence of float
        Percentiles reported for every output.
    sample_time_limit : float
        Wall-clock seconds allowed for the run-out of one sample (default
        :data:`DEFAULT_SAMPLE_TIME_LIMIT`); a sample that needs longer fails with the reason
        ``"run-out: wall_time_limit"`` and the run goes on.
    accept : bool
        Rejection sampling: summarise the samples that meet all the evidence (count, share,
        percentiles of outputs and inputs beside those of all samples) in the report and
        ``to_dict()["accepted"]``, and draw them apart in the figures. Nothing else changes:
        every sample is run and stored.

    Failed samples (an inadmissible impact, a run-out that did not reach rest, ...) are kept
    with their reason; ``MCResult.failure_reasons`` tallies them and the report lists them.

    Returns
    -------
    MCResult

    Raises
    ------
    ScenarioError
        Invalid [uncertainty] table or paths, or a results file of another run.
    """
    scenario_data, file = file_contents(scenario_data, file)
    t0 = time.perf_counter()
    if spec is None:
        if "uncertainty" not in scenario_data:
            raise ScenarioError("the scenario has no [uncertainty] table naming the uncertain inputs",
                                field="uncertainty", file=file)
        spec = scenario_data["uncertainty"]
    with in_file(file):
        spec = spec if isinstance(spec, UncertaintySpec) else UncertaintySpec.from_dict(spec, file=file)
    seed = spec.seed if seed is None else int(seed)
    if seed != spec.seed:
        spec = replace(spec, seed=seed)
    n = spec.samples if n is None else int(n)
    if n < 1:
        raise ScenarioError(f"the number of samples must be >= 1, got {n}", field="samples")
    engine = default_engine() if engine is None else engine
    # Fail early, in this process, on paths the scenario cannot hold or an invalid median scene.
    Scene(scenario_data, engine=engine, file=file).inputs(spec.paths, field="uncertainty.inputs")
    run_hash = _run_hash(scenario_data, spec)
    if not (sample_time_limit > 0):
        raise ScenarioError(f"the sample time limit must be > 0 s, got {sample_time_limit!r}", field="sample_time_limit")
    payload = {"data": scenario_data, "spec": spec, "engine": engine, "file": file, "seed": seed, "hash": run_hash,
               "time_limit": float(sample_time_limit)}

    rows: dict[int, dict] = {}
    fh = None
    if out_path is not None:
        out_path = Path(out_path)
        header, rows = _read_rows(out_path, run_hash)
        rows = {i: r for i, r in rows.items() if i < n}
        fh = out_path.open("a", encoding="utf-8")
        if header is None:
            header = {"format": _FORMAT, "hash": run_hash, "seed": seed, "n": n, "engine": engine,
                      "spec": spec.to_dict(), "paths": list(spec.paths)}
            fh.write(json.dumps(header) + "\n")
            fh.flush()
    n_resumed = len(rows)
    todo = [i for i in range(n) if i not in rows]
    # The median scene and the tornado swings, in this process and first: this also compiles the
    # run-out engine once here, before the worker processes are forked.
    swings, nominal = _swings(scenario_data, spec, engine, file)
    tolerance = None
    raw_runout = scenario_data.get("runout")
    if (spec.tolerance == "evidence" and isinstance(raw_runout, dict) and "accuracy" not in raw_runout
            and nominal is not None and not isinstance(nominal, Exception) and nominal.scenario.runout is not None):
        opts = nominal.scenario.runout.options
        tolerance = evidence_tolerance(tolerance_items(nominal.scenario.evidence), nominal, opts.rtol, opts.atol,
                                       what="tolerance")
        if tolerance.changed:  # the samples and the median scene at the evidence's tolerance (the swings: impact only)
            scenario_data = with_tolerance(scenario_data, tolerance)
            payload["data"] = scenario_data
            nominal = _median_scene(Scene(scenario_data, engine=engine, file=file).inputs(
                spec.paths, field="uncertainty.inputs", cache=1), np.array([d.median for d in spec.inputs]))

    backend, nw = choose_backend(workers, dask_address, len(todo))
    bar = Progress(progress, n, initial=n_resumed, desc="Monte Carlo", unit="sample")

    def take(new_rows: list[dict]) -> None:
        for row in new_rows:
            rows[row["i"]] = row
            if fh is not None:
                fh.write(json.dumps(row) + "\n")
        if fh is not None:
            fh.flush()
        bar.update(len(new_rows), len(rows))

    try:
        if todo:
            with Executor(_sampler_for, payload, backend, nw, dask_address=dask_address) as ex:
                nw = ex.workers
                size = (chunk_size or 1) if backend == "serial" else default_chunk_size(len(todo), nw, chunk_size)
                for new_rows in ex.as_completed(_run_sample, chunks(todo, size)):
                    take(new_rows)
    finally:
        if fh is not None:
            fh.close()
        bar.close()
    return _assemble(spec, seed, n, rows, n_resumed, time.perf_counter() - t0, engine, backend, nw,
                     out_path, percentiles, swings, nominal, accept=accept, tolerance=tolerance)

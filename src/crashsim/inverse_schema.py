"""File schema of the inverse side: ``[fit]``, ``[uncertainty]`` and the evidence ``sigma`` keys.

These are :class:`~crashsim.schema.Section` objects like the rest of the scenario schema, so
they are validated and documented by the same machinery. :func:`with_inverse_sections`
returns a scenario schema with them added (the ``[fit]`` and ``[uncertainty]`` tables at the
end, the ``sigma`` keys in the evidence items); ``crashsim.scenario`` uses it for
:data:`~crashsim.scenario.SCHEMA`.

Values of unknowns and distributions
------------------------------------
An unknown or an uncertain input names a scenario input by its path in the file
(``"vehicles.B.speed"``, ``"impact.point[0]"``, see :mod:`crashsim.reconstruct.overrides`).
Its bounds and parameters are written like the value at that path, with its unit, **as
strings**: ``lower = "20 mph"``, ``upper = "45 mph"``; plain numbers in quotes too:
``lower = "0.02"`` (or ``"2 %"``). The unit kind depends on the path, so it is checked when
the path is resolved, not by the schema's type check.

Example
-------
.. code-block:: toml

    [fit]
    starts = 4
    seed = 1

    [[fit.unknowns]]
    path = "vehicles.B.speed"
    lower = "20 mph"
    upper = "45 mph"
    initial = "30 mph"

    [uncertainty]
    samples = 2000
    seed = 7

    [[uncertainty.inputs]]
    path = "runout.road_friction"
    distribution = "uniform"
    lower = "0.6"
    upper = "0.8"

    [[evidence.rest]]
    body = "car"
    position = ["-6.7 m", "-0.6 m"]
    tolerance = "0.5 m"
    sigma = "0.2 m"           # standard uncertainty of each coordinate
"""

from __future__ import annotations

from dataclasses import replace

from .schema import ArrayOf, Field, Section, validate
from .units import Kind

__all__ = ["UNKNOWN", "FIT", "INPUT", "UNCERTAINTY", "POSTERIOR", "EVIDENCE_SIGMA_FIELDS", "DISTRIBUTIONS",
           "with_inverse_sections", "validate_fit", "validate_uncertainty", "validate_posterior"]

_VALUE = ('written like the value at path, with its unit, in quotes ("20 mph", "85 deg"; a plain '
          'number also in quotes: "0.05")')

UNKNOWN = Section("unknown", [
    Field("path", "str", example="vehicles.B.speed",
          description="Input to find, by its path in this file (key.key, key[i] for an array item or a vector "
                      "component): vehicles.<v>.speed, vehicles.<v>.heading, impact.point[0], impact.restitution, "
                      "impact.friction, impact.mu, impact.mu_fraction, impact.moment_restitution, runout.road_friction, "
                      "vehicles.<v>.tyres.brake, vehicles.<v>.bodies[i].mass, ..."),
    Field("name", "str", default="", description="Label for the report (default: the path)"),
    Field("lower", "str", example="20 mph", description=f"Lower bound, {_VALUE}"),
    Field("upper", "str", example="45 mph", description=f"Upper bound, {_VALUE}"),
    Field("initial", "str", required=False, example="30 mph",
          description=f"Start value of the first local fit (default: the file's value if within the bounds, "
                      f"else the middle of the bounds), {_VALUE}"),
], description="One unknown of the fit: an input of this file and its bounds")

#: Default ``[fit] correlation_warning``: |r| from which a pair of unknowns is reported as determined
#: only together (0.99: the shipped fit scene's speeds and friction are at 0.97-0.999).
CORRELATION_WARNING = 0.99

FIT = Section("fit", [
    Field("starts", "int", default=4, minimum=1, maximum=1000,
          description="Local least-squares fits: the first from the initial values, the others from points "
                      "spread over the bounds (scrambled Sobol sequence); the report says how many agree"),
    Field("screen", "int", default=0, minimum=0, maximum=100000,
          description="Global stage: evaluate this many points spread over the bounds first and start the "
                      "local fits (after the first) from the best of them (0: no screening)"),
    Field("seed", "int", default=0, minimum=0, description="Seed of the start points (reproducible fits)"),
    Field("method", choices=("trf", "dogbox"), default="trf",
          description="Bounded least-squares method of scipy.optimize.least_squares"),
    Field("max_evaluations", "int", default=200, minimum=5, maximum=100000,
          description="Largest number of scene evaluations of one local fit (Jacobians not counted)"),
    Field("diff_step", "float", default=1e-3, minimum=1e-8, maximum=0.1,
          description="Finite-difference step of the Jacobian, as a fraction of each unknown's bound range "
                      "(above the run-out solver's noise at its default rtol 1e-8)"),
    Field("confidence", "float", default=0.95, minimum=0.5, maximum=0.9999,
          description="Confidence level of the reported intervals"),
    Field("correlation_warning", "float", default=CORRELATION_WARNING, minimum=0.5, maximum=1.0,
          description="Warn when two unknowns are correlated at least this strongly (|r|): the evidence then fixes "
                      "only a combination of them (speed and road friction through v^2 / mu), and each one's "
                      "interval rests on the other's bounds"),
    Field("covariance", choices=("absolute", "scaled"), default="absolute",
          description="absolute: the evidence sigmas are the measurement uncertainties, covariance (J^T W J)^-1; "
                      "scaled: multiplied by chi^2/dof (sigmas known only up to a common factor; Student t)"),
    Field("sigma_from_tolerance", "float", required=False, minimum=0, exclusive_minimum=True, maximum=10,
          example="0.5",
          description="For evidence items without sigma: use this fraction of their tolerance as sigma "
                      "(0.5 reads a tolerance as a 2-sigma bound); without it every item needs a sigma"),
    Field("mark_points", "int", default=10, minimum=2, maximum=1000,
          description="Points along each tyre mark at which its distance to the computed track is a residual "
                      "(the mark weighs as one measurement with its sigma, whatever this number)"),
], subsections=[ArrayOf("unknowns", UNKNOWN, min_items=1, description="The unknowns, with bounds")],
   required=False, description="Least-squares fit of unknown inputs to the evidence (crashsim fit)")

#: Distribution names and the keys each one needs (and allows).
DISTRIBUTIONS = {
    "uniform": (("lower", "upper"), ()),
    "triangular": (("lower", "mode", "upper"), ()),
    "normal": (("mean", "sd"), ("lower", "upper")),
}

INPUT = Section("input", [
    Field("path", "str", example="vehicles.B.speed",
          description="Input of this file to vary, by its path (as fit.unknowns[].path)"),
    Field("name", "str", default="", description="Label for the report (default: the path)"),
    Field("distribution", choices=tuple(DISTRIBUTIONS), example="uniform",
          description="uniform (lower, upper); triangular (lower, mode, upper); normal (mean, sd; optional "
                      "lower/upper truncate it)"),
    Field("lower", "str", required=False, example="25 mph", description=f"Lower end, {_VALUE}"),
    Field("upper", "str", required=False, example="35 mph", description=f"Upper end, {_VALUE}"),
    Field("mode", "str", required=False, example="30 mph", description=f"Most likely value (triangular), {_VALUE}"),
    Field("mean", "str", required=False, example="30 mph", description=f"Mean (normal), {_VALUE}"),
    Field("sd", "str", required=False, example="2 mph", description=f"Standard deviation (normal), {_VALUE}"),
], description="One uncertain input and its distribution")

UNCERTAINTY = Section("uncertainty", [
    Field("samples", "int", default=1000, minimum=1, maximum=10_000_000,
          description="Number of Monte Carlo samples (crashsim mc --samples overrides it)"),
    Field("seed", "int", default=0, minimum=0,
          description="Seed: sample i depends only on (seed, i), so local, resumed and cluster runs agree"),
    Field("tolerance", choices=("file", "evidence"), default="file",
          description="Run-out tolerance of the samples: file (the [runout] rtol and atol as written) or evidence "
                      "(the loosest rtol whose integration error stays below 1 % of the smallest tolerance of the "
                      "run-out's evidence checks, never tighter than the file's, at most 1e-4)"),
], subsections=[ArrayOf("inputs", INPUT, min_items=1, description="The uncertain inputs")],
   required=False, description="Monte Carlo propagation of input uncertainty through impact and run-out (crashsim mc)")

#: Fewest steps per walker after the burn-in and thinning for which any diagnostic is computed.
MIN_KEPT_STEPS = 50
#: Fewest steps per walker with the default burn-in (a quarter of the steps) and no thinning.
MIN_STEPS_DEFAULT_BURN = next(n for n in range(MIN_KEPT_STEPS, 4 * MIN_KEPT_STEPS) if n - n // 4 >= MIN_KEPT_STEPS)

POSTERIOR = Section("posterior", [
    Field("sampler", choices=("emcee", "imh"), default="emcee",
          description="emcee: the ensemble sampler (walkers, move, chain files); imh: independence "
                      "Metropolis-Hastings with a Student-t proposal built from the fit's best values and "
                      "covariance, refitted during the burn-in to the importance-weighted moments of the scenes it evaluated "
                      "(one chain, each step one scene; "
                      "the fit is run first; steps and burn count scene evaluations; no chain file)"),
    Field("walkers", "int", default=32, minimum=2, maximum=100000,
          description="Walkers of the ensemble sampler (emcee); at least twice the number of [fit] unknowns"),
    Field("steps", "int", default=2000, minimum=MIN_KEPT_STEPS, maximum=10_000_000,
          description="Steps of every walker (crashsim posterior --steps overrides it); a chain that is stopped "
                      "and run again with more steps continues where it stopped. At least burn + "
                      f"{MIN_KEPT_STEPS} x thin ({MIN_STEPS_DEFAULT_BURN} with the default burn-in, "
                      f"{MIN_KEPT_STEPS} with burn = 0): fewer leave no diagnostic"),
    Field("burn", "int", required=False, minimum=0, example="500",
          description="Steps of every walker discarded at the start (burn-in) before the summaries "
                      "(default: a quarter of the steps)"),
    Field("thin", "int", default=1, minimum=1, maximum=100000,
          description="Keep every thin-th step after the burn-in for the summaries and plots"),
    Field("seed", "int", default=0, minimum=0,
          description="Seed of the initial walkers and of the sampler's moves: the same seed gives the same chain"),
    Field("prior", choices=("fit", "uncertainty"), default="fit",
          description="fit: uniform on each unknown's [fit] bounds; uncertainty: the [uncertainty] distribution "
                      "of the same path, truncated to the [fit] bounds (an unknown without one: uniform on its "
                      "bounds)"),
    Field("start", choices=("initial", "fit"), default="initial",
          description="Centre of the initial walkers: the [fit] initial values, or the best fit (crashsim fit "
                      "is run first; use it where the sum of squares has several basins)"),
    Field("init_scale", "float", default=0.01, minimum=0, exclusive_minimum=True, maximum=0.5,
          description="Spread of the initial walkers around the centre, as a fraction of each unknown's bound "
                      "range (standard deviation of a normal ball, redrawn inside the prior's support)"),
    Field("move", choices=("stretch", "de"), default="stretch",
          description="Proposal of emcee: stretch (Goodman-Weare affine-invariant stretch move, emcee's default) "
                      "or de (differential evolution)"),
    Field("ess", "int", required=False, minimum=1, maximum=10_000_000, example="1000",
          description="Target effective sample size of every unknown: the chain stops at the first check (every "
                      "check_every steps) where each unknown has at least this many effective samples and the kept "
                      "chain is 50 autocorrelation times long; steps is then the most it runs"),
    Field("check_every", "int", default=100, minimum=10, maximum=1_000_000,
          description="With ess: steps between two checks of the effective sample size"),
    Field("tolerance", choices=("evidence", "file"), default="evidence",
          description="Run-out tolerance of the samples: evidence (the loosest rtol whose integration error stays "
                      "below 1 % of the smallest sigma of the run-out's evidence, never tighter than the file's, "
                      "at most 1e-4) or file (the [runout] rtol and atol as written)"),
    Field("checkpoint_every", "int", default=50, minimum=1, maximum=1_000_000,
          description="With a chain file: write it every this many steps (and when stopped)"),
], required=False, description="Posterior of the [fit] unknowns given the evidence by MCMC (crashsim posterior)")

#: The ``sigma`` keys of the evidence items (standard measurement uncertainties, used by the fit).
EVIDENCE_SIGMA_FIELDS = {
    "rest": (
        Field("sigma", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="0.2 m",
              description="Standard uncertainty of each coordinate of the measured rest position (fit; with "
                          "points: of the CG derived from them)"),
        Field("heading_sigma", Kind.ANGLE, required=False, minimum=0, exclusive_minimum=True, example="2 deg",
              description="Standard uncertainty of the measured rest heading (fit; with points: of the heading "
                          "derived from them)"),
    ),
    "marks": (
        Field("sigma", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="0.15 m",
              description="Standard uncertainty of the mark's position across its length (fit)"),
    ),
    "impact_point": (
        Field("sigma", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="0.3 m",
              description="Standard uncertainty of each coordinate of the measured point of impact (fit)"),
    ),
    "delta_v": (
        Field("sigma", Kind.SPEED, required=False, minimum=0, exclusive_minimum=True, example="0.5 mph",
              description="Standard uncertainty of the recorded delta-v (fit)"),
    ),
    "recorder": (
        Field("sigma", Kind.SPEED, required=False, minimum=0, exclusive_minimum=True, example="0.6 mph",
              description="Standard uncertainty of each recorded speed sample (fit, posterior)"),
    ),
    "crush": (
        Field("sigma", Kind.ENERGY, required=False, minimum=0, exclusive_minimum=True, example="8 kJ",
              description="Standard uncertainty of this item's crush energy (fit; a group's sigma is the root sum "
                          "of squares of its items')"),
    ),
}


def _add_fields(section: Section, extra) -> Section:
    have = set(section.keys)
    new = [f for f in extra if f.name not in have]
    return replace(section, fields=tuple(section.fields) + tuple(new)) if new else section


def with_inverse_sections(schema: Section) -> Section:
    """``schema`` (the scenario schema) with [fit], [uncertainty], [posterior] and the evidence sigma keys.

    Idempotent: keys and sections already present are left as they are.
    """
    subs = []
    for s in schema.subsections:
        if s.name == "evidence" and isinstance(s, Section):
            ev_subs = []
            for e in s.subsections:
                extra = EVIDENCE_SIGMA_FIELDS.get(e.name, ())
                if isinstance(e, ArrayOf):
                    e = replace(e, entry=_add_fields(e.entry, extra))
                elif isinstance(e, Section):
                    e = _add_fields(e, extra)
                ev_subs.append(e)
            s = replace(s, subsections=tuple(ev_subs))
        subs.append(s)
    names = {s.name for s in subs}
    subs += [sec for sec in (FIT, UNCERTAINTY, POSTERIOR) if sec.name not in names]
    return replace(schema, subsections=tuple(subs))


def _validate_one(section: Section, raw, file: str | None) -> dict:
    root = Section("scenario file", subsections=[replace(section, required=True)], description="inverse sections")
    return validate({section.name: raw}, root, file=file)[section.name]


def validate_fit(raw: dict, *, file: str | None = None) -> dict:
    """Validate a raw ``[fit]`` table alone (keys reported as ``fit.unknowns[0].lower``)."""
    return _validate_one(FIT, raw, file)


def validate_uncertainty(raw: dict, *, file: str | None = None) -> dict:
    """Validate a raw ``[uncertainty]`` table alone."""
    return _validate_one(UNCERTAINTY, raw, file)


def validate_posterior(raw: dict, *, file: str | None = None) -> dict:
    """Validate a raw ``[posterior]`` table alone."""
    return _validate_one(POSTERIOR, raw, file)

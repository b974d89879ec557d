"""The posterior of the shipped fit scene beside the fit, and the samplers compared by scene evaluations
per effective sample.

    python benchmarks/posterior.py                  # the [posterior] table of the scene file
    python benchmarks/posterior.py --steps 400      # a shorter chain (the report warns if too short)

Scene: ``scenarios/fit/intersection_fit.toml`` (four unknowns: both impact speeds, the
restitution and the road friction; uniform priors on the [fit] bounds). Every sampler starts
from the best fit (the sum of squares has two basins, and a chain started from the [fit]
initial values would first have to find the truth's).

The samplers, in one run, each to its own stop, on the same scenes (the samples' tolerance of the file's
[posterior] rule):

1. the file's sampler (``sampler = "imh"``: independence Metropolis-Hastings, a mixture of Student-t
   proposals, one refitted in the burn-in, one the fit's; stopped at ``ess``), the run the report and
   figures show, and again at the seeds of ``OTHER_SEEDS`` (one seed's figure varies by 2x);
2. emcee's differential evolution, 20 walkers in a small ball around the best fit, stopped at
   ``ess`` (the settings shipped before: the old sampler, whose intervals the new one must match);
3. emcee with a mix of DEMove (0.8) and DESnookerMove (0.2), the walkers drawn from the fit's Gaussian
   (fixed length, in this process);
4. adaptive random-walk Metropolis (Haario et al. 2001) from the fit's covariance (fixed length, in this
   process).

The effective sample size (ESS) of each unknown is kept samples / tau, with tau emcee's integrated
autocorrelation time (Sokal's window c = 5) over the kept chain (all walkers of an ensemble); the
slowest unknown's counts. "Evaluations" are the scenes a sampler evaluated, burn-in included, the fit's
own excluded (every sampler starts from it); a proposal outside the bounds costs none.

Writes
    plots/posterior.md          settings, timing, the sampler comparison, the old and new intervals
                                side by side in Monte Carlo errors, the fit's linearised 95 % intervals
                                beside the posterior's, diagnostics, the tolerance check, the full report
    plots/posterior_corner.png  corner plot of the unknowns and derived quantities (US units)
    plots/posterior_trace.png   trace plots
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import sys
from pathlib import Path

import numpy as np
from _machine import cpu_name

ROOT = Path(__file__).resolve().parents[1]
FILE = ROOT / "scenarios" / "fit" / "intersection_fit.toml"
PLOTS = ROOT / "plots"
#: What each [posterior] prior setting means, for the report's sampler line.
#: Sizes of the two fixed-length comparison runs (emcee's DE + snooker mix; adaptive Metropolis) and of the old
#: sampler's most steps.
MIX_WALKERS, MIX_STEPS, MIX_BURN = 20, 300, 100
AM_STEPS, AM_BURN, AM_T0 = 4000, 800, 400
OLD_STEPS, OLD_BURN = 6000, 300
#: Further seeds of the file's sampler (its evaluations per effective sample vary from seed to seed).
OTHER_SEEDS = (2, 3, 4, 5)
PRIOR_WORDS = {"fit": "uniform on the [fit] bounds",
               "uncertainty": "the [uncertainty] distributions, cut to the [fit] bounds"}


def _machine() -> str:
    cpu = cpu_name()
    import emcee
    import numpy

    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    return (f"{os.cpu_count()} cores ({cpu}); Python {platform.python_version()}, numpy {numpy.__version__}, "
            f"emcee {emcee.__version__}; load average at start {load:.2f}")


def comparison_rows(post, system: str = "US") -> list[str]:
    """Markdown rows: each unknown's fit best value and linearised 95 % interval beside the posterior's."""
    from crashsim.report import fmt

    def show(v, kind):
        if v is None:
            return "n/a"
        return f"{v:.4g}" if kind == "dimensionless" else fmt(v, kind, system)

    rows = ["| unknown | fit: best | fit: linearised 95 % interval | posterior: median | posterior: 95 % credible "
            "interval | bounds |", "|---|---|---|---|---|---|"]
    for i, u in enumerate(post.unknowns):
        lo, hi = post.fit["interval"][i]
        p = post.percentiles[u.path]
        rows.append(f"| {u.name} | {show(post.fit['x'][i], u.kind)} | [{show(lo, u.kind)}, {show(hi, u.kind)}] | "
                    f"{show(p['p50'], u.kind)} | [{show(p['p2.5'], u.kind)}, {show(p['p97.5'], u.kind)}] | "
                    f"[{show(u.lower, u.kind)}, {show(u.upper, u.kind)}] |")
    return rows


class Counted:
    """The posterior's log-probability, counting the scenes evaluated (a point outside the prior costs none)."""

    def __init__(self, problem):
        self.problem, self.n = problem, 0

    def __call__(self, z) -> float:
        if not np.isfinite(self.problem.log_prior(z)):
            return -math.inf
        self.n += 1
        return float(self.problem.log_prob(z)[0])


def problem_of(raw, post, rel, workers):
    """The problem the file's run sampled (the same samples' tolerance), and the fit's best values and
    covariance in the scaled unknowns."""
    from crashsim.reconstruct.fit import FitSpec, fit_scene
    from crashsim.reconstruct.posterior import PosteriorProblem, build_priors
    from crashsim.reconstruct.tolerance import with_tolerance

    fit_spec = FitSpec.from_dict(raw["fit"], raw, file=rel)
    fr = fit_scene(raw, fit_spec, engine=post.engine, workers=workers, file=rel)
    data = with_tolerance(raw, post.tolerance) if post.tolerance is not None and post.tolerance.changed else raw
    problem = PosteriorProblem(data, fit_spec, build_priors(raw, fit_spec, post.spec.prior, file=rel),
                               engine=post.engine, file=rel, derived=post.derived)
    span = problem.fit.span
    return problem, problem.fit.z_of(fr.x), np.asarray(fr.covariance, float) / np.outer(span, span)


def ess_of(kept: np.ndarray) -> np.ndarray:
    """Effective samples of each unknown of a kept chain (steps, walkers, unknowns): samples / tau."""
    from emcee.autocorr import integrated_time

    tau = np.maximum(np.asarray(integrated_time(kept, c=5, tol=0, quiet=True), float), 1.0)
    return kept.shape[0] * kept.shape[1] / tau


def run_emcee_mix(problem, z0, cov, seed, walkers=MIX_WALKERS, steps=MIX_STEPS, burn=MIX_BURN):
    """emcee with DEMove (0.8) and DESnookerMove (0.2), the walkers drawn from the fit's Gaussian."""
    import time

    import emcee
    from crashsim.reconstruct.samplers import StudentT, box_covariance

    t = time.perf_counter()
    rng = np.random.default_rng(seed)
    gauss = StudentT.from_cov(z0, box_covariance(cov), nu=math.inf)
    p0 = np.array([gauss.draw_in_box(rng) for _ in range(walkers)])
    lp = Counted(problem)
    sampler = emcee.EnsembleSampler(walkers, z0.size, lp, moves=[(emcee.moves.DEMove(), 0.8),
                                                                   (emcee.moves.DESnookerMove(), 0.2)])
    sampler.run_mcmc(emcee.State(p0, random_state=np.random.RandomState(seed).get_state()), steps, progress=False)
    kept = sampler.get_chain()[burn:]
    return {"evaluations": lp.n, "ess": ess_of(kept), "acceptance": float(np.mean(sampler.acceptance_fraction)),
            "elapsed": time.perf_counter() - t, "samples": kept.reshape(-1, z0.size),
            "settings": f"{walkers} walkers x {steps} steps, burn-in {burn}, walkers drawn from the fit's Gaussian "
                        "(sd capped at each bound range); in this process"}


def run_am(problem, z0, cov, seed, steps=AM_STEPS, burn=AM_BURN, t0=AM_T0):
    """Haario's adaptive Metropolis from the fit's covariance."""
    import time

    from crashsim.reconstruct.samplers import adaptive_metropolis

    t = time.perf_counter()
    lp = Counted(problem)
    chain, acc = [], 0
    for z, _, _, a, _ in adaptive_metropolis(lambda z: (lp(z), None), (z0, lp(z0), None), cov, steps,
                                             np.random.default_rng(seed), t0=t0):
        chain.append(z)
        acc += a
    kept = np.array(chain[burn:])[:, None, :]
    return {"evaluations": lp.n, "ess": ess_of(kept), "acceptance": acc / steps, "elapsed": time.perf_counter() - t,
            "samples": kept[:, 0, :],
            "settings": f"one chain of {steps} steps, burn-in {burn}, the fit's covariance for the first {t0}; "
                        "in this process"}


def percentile_error(samples: np.ndarray, q: float, ess: float) -> float:
    """Monte Carlo standard error of the q-th percentile: sqrt(q (1 - q) / ESS) / density, the density
    from the samples' spread between the (q - 5)-th and (q + 5)-th percentiles."""
    lo_q, hi_q = max(q - 5, 0.5), min(q + 5, 99.5)
    lo, hi = np.percentile(samples, [lo_q, hi_q])
    dens = (hi_q - lo_q) / 100 / max(hi - lo, 1e-300)
    return math.sqrt((q / 100) * (1 - q / 100) / ess) / dens


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=None)
    ap.add_argument("--burn", type=int, default=None)
    ap.add_argument("--workers", type=int, default=None)
    args = ap.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    from dataclasses import replace

    from crashsim.reconstruct.posterior import PosteriorSpec, run_posterior
    from crashsim.reconstruct.posterior_plots import save_posterior_figures
    from crashsim.reconstruct.samplers import IMH_DEFENSIVE, IMH_NU, IMH_REFIT_SCALE, IMH_SCALE
    from crashsim.schema import load_toml

    raw = load_toml(FILE)
    rel = FILE.relative_to(ROOT).as_posix()
    spec = PosteriorSpec.from_dict(raw.get("posterior"), file=rel)
    if args.burn is not None:
        spec = replace(spec, burn=args.burn)
    machine = _machine()
    post = run_posterior(raw, spec, steps=args.steps, start="fit", workers=args.workers, progress=True, file=rel)
    save_posterior_figures(post, PLOTS, system="US")
    seeds = [(spec.seed, post)] + [(k, run_posterior(raw, replace(spec, seed=k), steps=args.steps, start="fit",
                                                     workers=args.workers, progress=True, file=rel))
                                   for k in OTHER_SEEDS]
    # 2. the old sampler: emcee's differential evolution as shipped before, 20 walkers around the best fit
    old_spec = replace(spec, sampler="emcee", walkers=20, move="de", init_scale=0.01, steps=OLD_STEPS, burn=OLD_BURN, ess=1000,
                       check_every=100)
    old = run_posterior(raw, old_spec, start="fit", workers=args.workers, progress=True, file=rel)
    # 3. and 4. in this process, on the same problem
    problem, z0, cov = problem_of(raw, post, rel, args.workers)
    mix = run_emcee_mix(problem, z0, cov, spec.seed)
    am = run_am(problem, z0, cov, spec.seed)
    # the samples at the file's tolerance: does the tolerance rule move the posterior?
    ref = run_posterior(raw, replace(post.spec, tolerance="file", steps=spec.steps, burn=spec.burn_steps), start="fit",
                        workers=args.workers, progress=True, file=rel)
    d = post.to_dict()["diagnostics"]
    sp = post.spec
    cmd = "python benchmarks/posterior.py" + (f" --steps {args.steps}" if args.steps else "") + (
        f" --burn {args.burn}" if args.burn is not None else "")
    names = [u.name for u in post.unknowns]
    md = ["# Posterior of the shipped fit scene, beside the fit", "",
          f"Regenerate: `{cmd}` (or `crashsim posterior {rel} --plots plots` for the file's sampler alone). "
          f"Scene: `{rel}`.", "",
          f"Machine: {machine}.", "",
          f"Sampler: independence Metropolis-Hastings (`sampler = \"{sp.sampler}\"`), Student-t proposals (nu = "
          f"{IMH_NU:g}): first the fit's (its best values, its covariance x {IMH_SCALE:g}^2), then in the burn-in's "
          f"second round and the kept chain a mixture, {1 - IMH_DEFENSIVE:.0%} of the draws from a t about the "
          f"importance-weighted moments of every scene the burn-in evaluated (covariance x {IMH_REFIT_SCALE:g}^2), "
          f"{IMH_DEFENSIVE:.0%} from the fit's; one chain of {post.steps} steps (one scene each), burn-in "
          f"{sp.burn_steps}, thin "
          f"{sp.thin}, seed {sp.seed}; prior: {sp.prior} ({PRIOR_WORDS[sp.prior]}). {post.evaluations} scene "
          f"evaluations ({post.engine} engine, {post.backend}, {post.workers} workers) in {post.elapsed:.1f} s, "
          "the fit included.", "",
          "## Samplers compared: scene evaluations per effective sample", "",
          "One run, the same scenes (the samples' tolerance of the file's rule), every sampler from the best fit. "
          "ESS: kept samples / tau, tau emcee's integrated autocorrelation time (Sokal's window c = 5) over the "
          "kept chain (all walkers of an ensemble), per unknown; the slowest unknown's counts. Evaluations: the "
          "scenes the sampler evaluated, burn-in included, the fit's own excluded (every sampler starts from it); "
          "a proposal outside the bounds costs none.", "",
          "| sampler | settings | scene evaluations | ESS per unknown (" + ", ".join(names) + ") | slowest ESS | "
          "evaluations per effective sample | acceptance | wall time |", "|---|---|---|---|---|---|---|---|"]
    rows = [("independence Metropolis-Hastings, Student-t mixture from the fit (the file's)",
             f"one chain of {post.steps} steps, burn-in {sp.burn_steps} in 2 rounds, target {sp.ess} effective "
             f"samples, checked every {sp.check_every} steps ({post.backend}, {post.workers} workers)", post.evaluations, post.ess,
             float(np.mean(post.acceptance)), post.elapsed),
            ("emcee DEMove around the best fit (shipped before)",
             f"{old.spec.walkers} walkers x {old.steps} steps, burn-in {old.spec.burn_steps}, target "
             f"{old_spec.ess} effective samples, checked every {old_spec.check_every} steps ({old.backend}, "
             f"{old.workers} workers)", old.evaluations, old.ess,
             float(np.mean(old.acceptance)), old.elapsed),
            ("emcee DEMove 0.8 + DESnookerMove 0.2", mix["settings"], mix["evaluations"], mix["ess"],
             mix["acceptance"], mix["elapsed"]),
            ("adaptive Metropolis (Haario), the fit's covariance", am["settings"], am["evaluations"], am["ess"],
             am["acceptance"], am["elapsed"])]
    per = {}
    for name, settings, n, ess, acc, el in rows:
        per[name] = n / float(np.min(ess))
        md.append(f"| {name} | {settings} | {n} | " + ", ".join(f"{e:.0f}" for e in ess) +
                  f" | {np.min(ess):.0f} | {per[name]:.2f} | {acc:.3f} | {el:.1f} s |")
    new_per, old_per = per[rows[0][0]], per[rows[1][0]]
    md += ["", f"The file's sampler needs {new_per:.2f} scene evaluations per effective sample of the slowest unknown, "
           f"the sampler shipped before {old_per:.2f}: {old_per / new_per:.1f}x fewer (wall times include the fit for "
           "the first two; the last two ran in this process, one scene after the other).", "",
           "## The file's sampler at other seeds", "",
           "The same settings, each seed its own chain to the same target (a chain stops at the first check that "
           "meets it, or at the file's most steps).", "",
           "| seed | scene evaluations | ESS per unknown | slowest ESS | evaluations per effective sample | acceptance |",
           "|---|---|---|---|---|---|"]
    per_seed = []
    for k, r in seeds:
        per_seed.append(r.evaluations / float(np.min(r.ess)))
        md.append(f"| {k} | {r.evaluations} | " + ", ".join(f"{e:.0f}" for e in r.ess) +
                  f" | {np.min(r.ess):.0f} | {per_seed[-1]:.2f} | {float(np.mean(r.acceptance)):.3f} |")
    md += ["", f"Over {len(seeds)} seeds: median {float(np.median(per_seed)):.2f} scene evaluations per effective "
           f"sample of the slowest unknown, mean {float(np.mean(per_seed)):.2f}, the worst {max(per_seed):.2f} "
           f"(goal <= 8: {'met' if float(np.median(per_seed)) <= 8 else 'missed'} by the median, "
           f"{'met' if max(per_seed) <= 8 else 'missed'} by the worst).", "",
           "## The new sampler's intervals against the old one's", "",
           "Each percentile's difference in units of its Monte Carlo error: sqrt(e_new^2 + e_old^2), e = sqrt(q (1 - q) "
           "/ ESS) / density for a percentile (the density from the samples' spread around it), sd / sqrt(ESS) for the "
           "mean, each sampler with its own ESS of that unknown.", "",
           "| unknown | quantity | independence MH | emcee DEMove (before) | difference / its Monte Carlo error |",
           "|---|---|---|---|---|"]
    diffs = []
    for i, u in enumerate(post.unknowns):
        a_s, b_s = post.samples[:, i], old.samples[:, i]
        for q in (2.5, 16.0, 50.0, 84.0, 97.5):
            a, b = post.percentiles[u.path][f"p{q:g}"], old.percentiles[u.path][f"p{q:g}"]
            err = math.hypot(percentile_error(a_s, q, post.ess[i]), percentile_error(b_s, q, old.ess[i]))
            diffs.append(abs(a - b) / err)
            md.append(f"| {u.name} | p{q:g} | {a:.5g} | {b:.5g} | {diffs[-1]:.2f} |")
        a, b = post.percentiles[u.path]["mean"], old.percentiles[u.path]["mean"]
        err = math.hypot(np.std(a_s) / math.sqrt(post.ess[i]), np.std(b_s) / math.sqrt(old.ess[i]))
        diffs.append(abs(a - b) / err)
        md.append(f"| {u.name} | mean | {a:.5g} | {b:.5g} | {diffs[-1]:.2f} |")
    over2 = sum(x > 2 for x in diffs)
    md += ["", f"Largest difference: {max(diffs):.2f} Monte Carlo errors; {over2} of {len(diffs)} beyond 2 (about "
           f"{0.0455 * len(diffs):.1f} expected by chance alone if both sample the same posterior).", "",
           "## Fit (linearised) and posterior, 95 %", ""]
    md += comparison_rows(post)
    md += ["", f"Fit: chi^2 = {post.fit['chi2']:.3g} at its best point; highest posterior sample: chi^2 = "
           f"{post.best['chi2']:.3g}.", "",
           "## Diagnostics", "",
           f"Acceptance fraction {d['acceptance_mean']:.3f}; kept {d['kept_steps']} steps ({d['samples']} samples).",
           "", "| unknown | autocorrelation time [steps] | effective samples | kept steps / tau |", "|---|---|---|---|"]
    for i, u in enumerate(post.unknowns):
        t = post.tau[i]
        md.append(f"| {u.name} | {t:.1f} | {post.ess[i]:.0f} | {d['kept_steps'] / t:.1f} |")
    md += ["", "## The samples' tolerance", "",
           f"The samples integrate at {post.tolerance.rule if post.tolerance else 'the file tolerance'}. "
           f"The same sampler settings (seed {sp.seed}) with every sample at the file's tolerance "
           f"(rtol {ref.nominal.scenario.runout.options.rtol:g}) took {ref.elapsed:.1f} s ({ref.evaluations} scene "
           f"evaluations, {ref.steps} steps; the fit included in the time). The two chains differ by their Monte Carlo "
           "error only if each percentile moves by less than about two standard errors of the difference (for a "
           "percentile q: sqrt(2 q (1 - q) / ESS) / density, the density from the samples' spread around it).", "",
           "| unknown | percentile | samples at the evidence's tolerance | at the file's tolerance | difference / "
           "its Monte Carlo error |", "|---|---|---|---|---|"]
    worst = 0.0
    for i, u in enumerate(post.unknowns):
        ess = min(post.ess[i], ref.ess[i])
        for q in (2.5, 50.0, 97.5):
            a, b = post.percentiles[u.path][f"p{q:g}"], ref.percentiles[u.path][f"p{q:g}"]
            err = math.sqrt(2) * percentile_error(post.samples[:, i], q, ess)
            worst = max(worst, abs(a - b) / err)
            md.append(f"| {u.name} | p{q:g} | {a:.5g} | {b:.5g} | {abs(a - b) / err:.2f} |")
    md += ["", f"Largest difference: {worst:.2f} Monte Carlo errors"
           + (" (within 2: the tolerance rule does not move the posterior beyond its Monte Carlo error)."
              if worst <= 2 else " (more than 2: look at the rule)."), ""]
    md += ["", "Figures: `plots/posterior_corner.png` (corner plot; red: the best fit), `plots/posterior_trace.png`.",
           "", "## Report", "", "```", post.report("US"), "```", ""]
    (PLOTS / "posterior.md").write_text("\n".join(md))
    sys.stdout.write("\n".join(md) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

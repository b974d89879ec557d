"""The posterior of the shipped fit scene beside the fit's linearised intervals.

    python benchmarks/posterior.py                  # the [posterior] table of the scene file
    python benchmarks/posterior.py --steps 400      # a shorter chain (the report warns if too short)

Scene: ``scenarios/fit/intersection_fit.toml`` (four unknowns: both impact speeds, the
restitution and the road friction; uniform priors on the [fit] bounds). The walkers start
around the best fit (``start = "fit"``: the sum of squares has two basins, and a chain started
from the [fit] initial values would first have to find the truth's).

Writes
    plots/posterior.md          settings, timing, the fit's linearised 95 % intervals beside the
                                posterior's 95 % credible intervals, diagnostics, the full report
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=None)
    ap.add_argument("--walkers", type=int, default=None)
    ap.add_argument("--burn", type=int, default=None)
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--chain", default=None, help="chain file (resume); default none")
    args = ap.parse_args(argv)

    import matplotlib

    matplotlib.use("Agg")
    from dataclasses import replace

    from crashsim.reconstruct.posterior import PosteriorSpec, run_posterior
    from crashsim.reconstruct.posterior_plots import save_posterior_figures
    from crashsim.schema import load_toml

    raw = load_toml(FILE)
    rel = FILE.relative_to(ROOT).as_posix()
    spec = PosteriorSpec.from_dict(raw.get("posterior"), file=rel)
    if args.walkers:
        spec = replace(spec, walkers=args.walkers)
    if args.burn is not None:
        spec = replace(spec, burn=args.burn)
    machine = _machine()
    post = run_posterior(raw, spec, steps=args.steps, start="fit", workers=args.workers, chain_path=args.chain,
                         progress=True, file=rel)
    save_posterior_figures(post, PLOTS, system="US")
    # The same chain settings with the samples at the file's tolerance: does the tolerance rule move the posterior?
    ref = run_posterior(raw, replace(post.spec, tolerance="file", ess=None), start="fit", workers=args.workers,
                        progress=True, file=rel)
    d = post.to_dict()["diagnostics"]
    sp = post.spec
    cmd = "python benchmarks/posterior.py" + (f" --steps {args.steps}" if args.steps else "") + (
        f" --walkers {args.walkers}" if args.walkers else "") + (
        f" --burn {args.burn}" if args.burn is not None else "")
    md = ["# Posterior of the shipped fit scene, beside the fit", "",
          f"Regenerate: `{cmd}` (or `crashsim posterior {rel} --from-fit --plots plots`). Scene: `{rel}`.", "",
          f"Machine: {machine}.", "",
          f"Sampler: emcee {sp.move} move, {sp.walkers} walkers x {post.steps} steps, burn-in {sp.burn_steps}, "
          f"thin {sp.thin}, seed {sp.seed}; prior: {sp.prior} ({PRIOR_WORDS[sp.prior]}); walkers started around "
          f"the best fit. {post.evaluations} scene evaluations ({post.engine} engine, {post.backend}, "
          f"{post.workers} workers) in {post.elapsed / 60:.1f} min, the fit included"
          + (f" (over the runs that wrote its chain file; {post.n_resumed} steps were resumed from it)."
             if post.n_resumed else "."), "",
          "## Fit (linearised) and posterior, 95 %", ""]
    md += comparison_rows(post)
    md += ["", f"Fit: chi^2 = {post.fit['chi2']:.3g} at its best point; highest posterior sample: chi^2 = "
           f"{post.best['chi2']:.3g}.", "",
           "## Diagnostics", "",
           f"Mean acceptance fraction {d['acceptance_mean']:.3f}; kept {d['kept_steps']} steps per walker "
           f"({d['samples']} samples).", "", "| unknown | autocorrelation time [steps] | effective samples | "
           "kept steps / tau |", "|---|---|---|---|"]
    for i, u in enumerate(post.unknowns):
        t = post.tau[i]
        md.append(f"| {u.name} | {t:.1f} | {post.ess[i]:.0f} | {d['kept_steps'] / t:.1f} |")
    md += ["", "## The samples' tolerance", "",
           f"The samples integrate at {post.tolerance.rule if post.tolerance else 'the file tolerance'}. "
           f"The same sampler settings ({ref.steps} steps, seed {sp.seed}) with every sample at the file's tolerance "
           f"(rtol {ref.nominal.scenario.runout.options.rtol:g}) took {ref.elapsed:.1f} s ({ref.evaluations} scene "
           f"evaluations, the fit included). The two chains differ by their Monte Carlo error only if each percentile "
           "moves by less than about two standard errors of the difference (for a percentile q: sqrt(2 q (1 - q) / "
           "ESS) / density, the density from the samples' spread around it).", "",
           "| unknown | percentile | samples at the evidence's tolerance | at the file's tolerance | difference / "
           "its Monte Carlo error |", "|---|---|---|---|---|"]
    worst = 0.0
    for i, u in enumerate(post.unknowns):
        ess = min(post.ess[i], ref.ess[i])
        for q in (2.5, 50.0, 97.5):
            a, b = post.percentiles[u.path][f"p{q:g}"], ref.percentiles[u.path][f"p{q:g}"]
            lo, hi = np.percentile(post.samples[:, i], [max(q - 5, 0.5), min(q + 5, 99.5)])
            dens = (min(q + 5, 99.5) - max(q - 5, 0.5)) / 100 / max(hi - lo, 1e-300)
            err = math.sqrt(2 * (q / 100) * (1 - q / 100) / ess) / dens
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

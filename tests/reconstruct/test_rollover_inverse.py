"""Rollover in the inverse tools: fit, Monte Carlo and the posterior count the samples in which a unit rolls
(an outcome, not a failure), and a rollover statement is an evidence item with a verdict.

The scene is the shipped barrier glance (a loaded tractor-van semitrailer at 15 deg) with the wheel-lift and
rollover check on; over 40-90 km/h some samples roll and some do not.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from crashsim.reconstruct import monte_carlo
from crashsim.reconstruct.fit import fit_scene
from crashsim.reconstruct.fit import FitSpec
from crashsim.reconstruct.posterior import PosteriorProblem, build_priors
from crashsim.scene.run import run_scene
from crashsim.scenario import load_scenario
from crashsim.schema import load_toml

SCENE = Path(__file__).resolve().parents[2] / "scenarios" / "scenes" / "barrier_glance_15deg.toml"
EVIDENCE = ('[[evidence.rollover]]\nunit = "trailer"\nrolled = true\nname = "trailer on its side"\n\n'
            '[[evidence.rollover]]\nunit = "tractor"\nrolled = false\n\n[evidence.impact_point]')
UNCERTAINTY = ('\n[uncertainty]\nsamples = 6\nseed = 3\n\n[[uncertainty.inputs]]\nname = "impact speed"\n'
               'path = "vehicles.truck.speed"\ndistribution = "uniform"\nlower = "40 km/h"\nupper = "90 km/h"\n')
FIT = ('\n[fit]\nstarts = 1\nsigma_from_tolerance = 0.5\nmax_evaluations = 6\n\n[[fit.unknowns]]\n'
       'path = "vehicles.truck.speed"\nlower = "60 km/h"\nupper = "90 km/h"\ninitial = "80 km/h"\n')


def _file(tmp_path, extra: str = "") -> Path:
    text = SCENE.read_text()
    out = text.replace("[runout]\nroad_friction = 0.8\n", '[runout]\nroad_friction = 0.8\nlevel = "load_transfer"\n'
                       'rollover = true\n', 1)
    out = out.replace("[evidence.impact_point]", EVIDENCE, 1)
    assert out.count("rollover") > 2
    f = tmp_path / "glance.toml"
    f.write_text(out + extra)
    return f


def test_a_rollover_statement_is_checked(tmp_path):
    scene = run_scene(load_scenario(_file(tmp_path)))
    roll = scene.rollover()["truck"]
    checks = {c.name: c for c in scene.evidence.checks if c.kind == "rollover"}
    trailer, tractor = checks["trailer on its side"], checks["tractor does not roll"]
    assert trailer.passed == ("trailer" in roll["rolled_bodies"])
    assert tractor.passed == ("tractor" not in roll["rolled_bodies"])
    assert trailer.details["computed"] == ("trailer" in roll["rolled_bodies"]) and trailer.details["stated"]
    assert "rollover" in scene.report()


def test_monte_carlo_counts_the_samples_that_roll(tmp_path):
    f = _file(tmp_path, UNCERTAINTY)
    res = monte_carlo(load_toml(f), workers=1, progress=False, engine="compiled", file=str(f))
    assert res.n_failed == 0 and res.n_done == 6
    rolled = res.outputs["rolled.truck"]
    assert set(np.unique(rolled)) <= {0.0, 1.0}
    share = res.rolled_share["truck"]
    assert share == pytest.approx(rolled.mean()) and 0.0 < share < 1.0  # the speeds cover both outcomes
    # a sample whose vehicle did not roll cannot meet "the trailer rolled"
    _, ok = res.checks["rollover: trailer on its side"]
    assert not np.any(ok[rolled == 0.0])
    assert f"a unit rolls in {100 * share:.1f} % of the 6 successful samples" in res.report()
    assert res.to_dict()["rolled_share"] == {"truck": share}


def test_fit_counts_the_evaluations_that_roll(tmp_path):
    f = _file(tmp_path, FIT)
    res = fit_scene(load_toml(f), workers=1, engine="compiled", file=str(f))
    assert res.rolled_evaluations is not None and 0 <= res.rolled_evaluations <= res.rolled_of
    assert res.rolled_of >= 2
    best = res.scene.rollover()["truck"]
    d = res.to_dict()
    assert d["rolled_evaluations"] == res.rolled_evaluations and d["rollover"]["truck"]["rolled"] == best["rolled"]
    text = res.report()
    assert f"a unit rolls in {res.rolled_evaluations} of the {res.rolled_of} scene evaluations" in text
    trailer = "trailer" in best["rolled_bodies"]
    assert f"{'PASS' if trailer else 'FAIL'}  evidence 'trailer on its side' (a verdict, not fitted)" in text


def test_the_posterior_carries_rolled_as_a_derived_quantity(tmp_path):
    f = _file(tmp_path, FIT)
    data = load_toml(f)
    spec = FitSpec.from_dict(data["fit"], data, file=str(f))
    problem = PosteriorProblem(data, spec, build_priors(data, spec, "fit", file=str(f)), engine="compiled", file=str(f))
    z0 = problem.fit.z_of([u.initial for u in spec.unknowns])
    keys = problem.derived_keys(z0)
    assert "rolled.truck" in keys
    _, blob, reason = problem.evaluate(z0)
    assert reason is None and blob[keys.index("rolled.truck")] in (0.0, 1.0)

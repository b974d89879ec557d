"""The PIM convention: the impulse ratio as a share of the critical one (tangential = "fraction").

mu = mu_fraction x mu_max of that very impact. Checked against the no-slide and "ratio" laws
solved independently, on the dense and the batched (compiled) solver paths, through the scenario
file (errors included), and as a fit unknown that follows each evaluation's mu_max.
"""

from __future__ import annotations

import copy
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import crashsim
from crashsim.errors import ScenarioError
from crashsim.impact import TangentialLaw, solve_impact
from crashsim.schema import load_toml

ROOT = Path(__file__).resolve().parents[2]
TABLE6 = ROOT / "scenarios" / "paper" / "table6.toml"


def _with_law(problem, law):
    return replace(problem, surface=replace(problem.surface, tangential=law))


@pytest.fixture(scope="module")
def problem():
    return crashsim.load(TABLE6).impact


def test_fraction_one_is_no_sliding_and_zero_is_frictionless(problem):
    ns = solve_impact(_with_law(problem, TangentialLaw("no_slide")))
    one = solve_impact(_with_law(problem, TangentialLaw("fraction", 1.0)))
    zero = solve_impact(_with_law(problem, TangentialLaw("fraction", 0.0)))
    assert one.mu == pytest.approx(ns.mu_max, rel=1e-12)
    assert abs(one.separation_tangential_velocity) < 1e-9 * abs(ns.closing_velocity)
    assert not one.sliding
    for name, b in ns.bodies.items():
        np.testing.assert_allclose(one.bodies[name].velocity, b.velocity, rtol=1e-10, atol=1e-12)
    assert zero.tangential_impulse == pytest.approx(0.0, abs=1e-9 * abs(zero.normal_impulse))
    assert zero.sliding


@pytest.mark.parametrize("fraction", [0.25, 0.85])
def test_fraction_equals_ratio_at_that_share_of_mu_max(problem, fraction):
    mu_max = solve_impact(_with_law(problem, TangentialLaw("no_slide"))).mu_max
    frac = solve_impact(_with_law(problem, TangentialLaw("fraction", fraction)))
    ratio = solve_impact(_with_law(problem, TangentialLaw("ratio", fraction * mu_max)))
    assert frac.mu_max == pytest.approx(mu_max, rel=1e-12)
    assert frac.mu == pytest.approx(fraction * mu_max, rel=1e-12)
    assert frac.mu_fraction == pytest.approx(fraction, rel=1e-12)
    assert frac.sliding  # less than the critical ratio: the surfaces still slide at separation
    assert frac.tangential_law == "fraction"
    for name, b in ratio.bodies.items():
        np.testing.assert_allclose(frac.bodies[name].velocity, b.velocity, rtol=1e-10, atol=1e-12)
    assert frac.to_dict()["mu_fraction"] == pytest.approx(fraction)


def test_batched_path_follows_each_items_mu_max(problem):
    """A batch of different geometries (the compiled batch solver): mu / mu_max is the
    fraction in every item while mu_max itself changes."""
    from crashsim.impact.core import solve_arrays
    from crashsim.impact.solve import compile_problem

    S, A = compile_problem(_with_law(problem, TangentialLaw("fraction", 0.6)))
    B = 300
    A = replace(A, **{f: np.repeat(getattr(A, f), B, axis=0) for f in A.__dataclass_fields__})
    A.normal_angle[:] = A.normal_angle[0] + np.linspace(-0.3, 0.3, B)
    out = solve_arrays(S, A)
    assert out["ok"].all()
    np.testing.assert_allclose(out["mu"] / out["mu_max"], 0.6, rtol=1e-9)
    assert np.ptp(out["mu_max"]) > 0.05
    dense = solve_arrays(S, A, method="dense")
    np.testing.assert_allclose(out["velocity"], dense["velocity"], rtol=1e-9, atol=1e-9)


def _data(**impact):
    data = load_toml(TABLE6)
    data = copy.deepcopy(data)
    data["impact"].update(impact)
    return data


def test_scenario_key_and_report():
    scene = crashsim.run(_data(tangential="fraction", mu_fraction=0.85))
    assert scene.impact.mu_fraction == pytest.approx(0.85, rel=1e-12)
    text = scene.report("US")
    assert "mu / mu_max = 85.0 %" in text and "law fraction" in text


@pytest.mark.parametrize("impact, key, words", [
    ({"tangential": "fraction", "mu_fraction": 1.5}, "impact.mu_fraction", "1.5"),
    ({"tangential": "fraction", "mu_fraction": -0.1}, "impact.mu_fraction", "-0.1"),
    ({"tangential": "fraction"}, "impact.mu_fraction", "needs mu_fraction"),
    ({"tangential": "no_slide", "mu_fraction": 0.8}, "impact.mu_fraction", "does not use it"),
])
def test_bad_fraction_names_key_value_and_range(impact, key, words):
    with pytest.raises(ScenarioError) as err:
        crashsim.run(_data(**impact))
    msg = str(err.value)
    assert key in msg and words in msg


def test_bad_fraction_exits_2_from_the_command_line(tmp_path, capsys):
    text = TABLE6.read_text().replace('tangential = "no_slide"', 'tangential = "fraction"\nmu_fraction = 2')
    path = tmp_path / "bad.toml"
    path.write_text(text)
    from crashsim.cli import main

    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err
    assert "impact.mu_fraction" in err and "2" in err and str(path) in err


def test_fraction_follows_mu_max_when_an_input_changes():
    """As in fit and Monte Carlo, another speed gives another mu_max: mu follows it."""
    a = crashsim.run(_data(tangential="fraction", mu_fraction=0.85))
    b = crashsim.run(_data(tangential="fraction", mu_fraction=0.85), vehicles__B__speed="45 mph")
    assert a.impact.mu_max != pytest.approx(b.impact.mu_max, rel=1e-3)
    for s in (a, b):
        assert s.impact.mu == pytest.approx(0.85 * s.impact.mu_max, rel=1e-12)


def test_fit_recovers_the_fraction_from_recorded_delta_v():
    """Round trip: delta-v components made by the model at mu = 0.6 mu_max are fitted with
    mu_fraction unknown from 0.95; the fit returns 0.6 (mu_max changes along the way)."""
    truth = crashsim.run(_data(tangential="fraction", mu_fraction=0.6))
    car = truth.impact.bodies["car"]
    h = car.heading
    dv = np.asarray(car.delta_v)
    comps = {"longitudinal": dv @ (np.cos(h), np.sin(h)), "lateral": dv @ (-np.sin(h), np.cos(h))}
    data = _data(tangential="fraction", mu_fraction=0.95)
    data["evidence"] = {"delta_v": [
        {"name": f"car {k}", "body": "car", "component": k, "value": f"{float(v)!r} m/s", "tolerance": "0.5 m/s",
         "sigma": "0.1 m/s", **({"lateral_positive": "left"} if k == "lateral" else {})}
        for k, v in comps.items()]}
    data["fit"] = {"starts": 1, "unknowns": [{"path": "impact.mu_fraction", "lower": "0", "upper": "1",
                                             "initial": "0.95"}]}
    fit = crashsim.fit(data, workers=1)
    best = fit.to_dict()["unknowns"][0]
    assert best["value"] == pytest.approx(0.6, abs=1e-4)

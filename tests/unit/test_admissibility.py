"""Inadmissible impacts are refused with the coefficient, its value and its admissible range;
inputs far outside anything on a road are refused at load; the contact point must lie on the
contacting bodies; every error names the file.

The impact of the T-bone reproducers (a 4800 lb SUV at 28 mph into the right side of a
3400 lb sedan at 35 mph) is rebuilt here from ``scenarios/``-style TOML text, so that the
tests need nothing outside the repository.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from crashsim import solve_impact
from crashsim.cli import main
from crashsim.errors import InadmissibleImpactError, ScenarioError
from crashsim.impact import ImpactBatch
from crashsim.impact.admissible import admissibility, impulse_work
from crashsim.scene.run import run_scene
from crashsim.scenario import load_scenario, scenario_from_dict

ROOT = Path(__file__).resolve().parents[2]

T_BONE = """
[scenario]
title = "T-bone"
units = "US"

[vehicles.V1]
position = ["0 ft", "0 ft"]
heading = "0 deg"
speed = "35 mph"
[[vehicles.V1.bodies]]
name = "sedan"
mass = "3400 lbf"
yaw_inertia = "1850 slug ft^2"
length = "15.9 ft"
width = "6.0 ft"
outline_center = ["0.4 ft", "0 ft"]

[vehicles.V2]
position = ["1.5 ft", "-11.2 ft"]
heading = "90 deg"
speed = "28 mph"
[[vehicles.V2.bodies]]
name = "suv"
mass = "4800 lbf"
yaw_inertia = "2900 slug ft^2"
length = "16.4 ft"
width = "6.4 ft"
outline_center = ["0.5 ft", "0 ft"]

[impact]
body1 = "sedan"
body2 = "suv"
point = ["1.5 ft", "-3.0 ft"]
normal = "90 deg"
tangent = "ccw"
restitution = 0.1
moment_restitution = -1
tangential = "no_slide"
"""


def t_bone(**impact) -> dict:
    data = tomllib.loads(T_BONE)
    data["impact"].update(impact)
    return data


def refusal(data) -> InadmissibleImpactError:
    with pytest.raises(InadmissibleImpactError) as info:
        run_scene(scenario_from_dict(data, file="t_bone.toml"))
    return info.value


MU_MAX = solve_impact(scenario_from_dict(t_bone()).impact).mu_max


def test_the_t_bone_geometry_has_the_reproducers_mu_max():
    assert MU_MAX == pytest.approx(0.4722, abs=5e-5)


def test_mu_beyond_mu_max_is_refused_with_the_range():
    err = refusal(t_bone(tangential="ratio", mu=0.9))
    assert str(err) == ('t_bone.toml: impact.mu = 0.9 exceeds mu_max = 0.4722 for this geometry: the sliding would '
                        'reverse; use 0 <= mu <= 0.4722 or tangential = "no_slide"')
    assert err.field == "impact.mu" and err.value == 0.9 and err.allowed == pytest.approx((0.0, MU_MAX), abs=1e-4)


def test_mu_against_the_sliding_is_refused():
    err = refusal(t_bone(tangential="ratio", mu=-0.9))
    assert "impact.mu = -0.9 has the opposite sign of mu_max = 0.4722" in str(err)
    assert err.reason == "impulse ratio drives the sliding"


def test_mu_at_the_limits_of_the_reported_range_is_admitted():
    for mu in (0.0, 0.5 * MU_MAX, 0.9999 * MU_MAX):
        r = run_scene(scenario_from_dict(t_bone(tangential="ratio", mu=mu))).impact
        assert r.energy_loss["system"] > 0 and r.normal_impulse > 0


def test_moment_restitution_that_creates_energy_names_e_prime_and_its_range():
    err = refusal(t_bone(restitution=1.0, moment_restitution=1.0))
    assert err.field == "impact.moment_restitution"
    assert "creates energy at the crush surface (2.06 % of the kinetic energy before the impact)" in str(err)
    lo, hi = err.allowed
    assert lo == 0.0 and 0.5 < hi < 1.0
    for ep, ok in ((hi * 0.999, True), (min(1.0, hi * 1.01), False)):
        data = t_bone(restitution=1.0, moment_restitution=ep)
        if ok:
            run_scene(scenario_from_dict(data))
        else:
            with pytest.raises(InadmissibleImpactError):
                run_scene(scenario_from_dict(data))


def test_restitution_that_creates_energy_with_no_slide_names_e_and_its_closed_form_limit():
    """A car's front-right corner (2, -0.8) m into a wall at 10 m/s with 1 m/s along it, no
    sliding at separation: the energy change is quadratic in e, dT(e) = dT(0) + e^2 (dT(1) -
    dT(0)), so the largest e without a gain is sqrt(-dT(0) / (dT(1) - dT(0))).  The refusal of
    e = 1 reports that limit (to the bisection's 1e-4), which is admissible, and 1 % more is not."""
    from crashsim import Body, BodyState, CrushSurface, ImpactProblem, TangentialLaw, Vehicle

    def problem(e):
        car = Vehicle("car", (Body("car", 1500.0, 2800.0),))
        wall = Vehicle("wall", (Body("wall", math.inf, math.inf),))
        states = {"car": BodyState((0.0, 0.0), 0.0, (10.0, 1.0), 0.0), "wall": BodyState((2.0, -0.8), 0.0, (0.0, 0.0))}
        return ImpactProblem((car, wall), states, "car", "wall",
                             CrushSurface((2.0, -0.8), math.pi, e, TangentialLaw("no_slide"), -1.0, -1))

    def d_ke(e):
        r = solve_impact(problem(e), check=False)
        return r.kinetic_energy["system"]["after"] - r.kinetic_energy["system"]["before"]

    e_max = math.sqrt(-d_ke(0.0) / (d_ke(1.0) - d_ke(0.0)))
    with pytest.raises(InadmissibleImpactError) as info:
        solve_impact(problem(1.0))
    err = info.value
    assert err.field == "impact.restitution" and err.allowed[0] == 0.0
    assert err.allowed[1] == pytest.approx(e_max, abs=2e-4)
    assert "admissible: 0 <= e <= " in str(err) and "no sliding at separation" in str(err)
    solve_impact(problem(0.999 * e_max))
    with pytest.raises(InadmissibleImpactError):
        solve_impact(problem(1.01 * e_max))


def test_check_off_returns_the_equations_answer_with_a_warning():
    sc = scenario_from_dict(t_bone(tangential="ratio", mu=0.9))
    r = solve_impact(sc.impact, check=False)
    assert r.mu == pytest.approx(0.9) and any("inadmissible impact" in w for w in r.warnings)


def test_work_of_the_impulses_adds_up_to_the_change_of_kinetic_energy():
    """KE+ - KE- = W_n + W_t + W_M + W_hitches + W_constraints + W_external, on the shipped
    scenes (hitches, constraints and external impulses among them)."""
    for path in sorted(ROOT.glob("scenarios/*/*.toml")):
        sc = load_scenario(path)
        r = solve_impact(sc.impact)
        dke = r.kinetic_energy["system"]["after"] - r.kinetic_energy["system"]["before"]
        total = sum(r.work.values())
        assert total == pytest.approx(dke, rel=1e-9, abs=1e-6 * r.kinetic_energy["system"]["before"]), path.name
        assert r.work["hitches"] == pytest.approx(0.0, abs=1e-7 * r.kinetic_energy["system"]["before"]), path.name
        assert r.energy_loss_crush >= 0 and r.energy_loss_normal >= 0, path.name
        d = r.to_dict()
        assert d["energy_loss_normal"] + d["energy_loss_tangential"] + d["energy_loss_moment"] == \
            pytest.approx(d["energy_loss_crush"])


def test_batch_flags_agree_with_the_single_solve():
    sc = scenario_from_dict(t_bone(tangential="ratio", mu=0.1))
    batch = ImpactBatch.from_problem(sc.impact, 5)
    batch.arrays.law_value[:] = [-0.5, 0.0, 0.3, 0.47, 0.6]
    out = batch.solve()
    ok, reason = admissibility(batch.structure, batch.arrays, out)
    assert ok.tolist() == [False, True, True, True, False]
    assert reason.tolist() == [3, 0, 0, 0, 2]
    work = impulse_work(batch.structure, batch.arrays, out)
    dke = out["ke_after"].sum(1) - out["ke_before"].sum(1)
    assert np.allclose(sum(work.values()), dke, rtol=1e-9, atol=1e-6)


# ----------------------------------------------------------------------------- inputs at load

def test_a_speed_far_beyond_any_road_vehicle_is_refused_in_the_users_unit():
    data = t_bone()
    data["vehicles"]["V1"]["speed"] = "1e6 mph"
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, file="fast.toml")
    assert str(info.value) == ('fast.toml: vehicles.V1.speed: "1e6 mph" is out of range; allowed [0, 335.5] mph '
                               '([0, 150] m/s)')


def test_a_contact_point_far_from_both_bodies_is_refused_naming_the_distances():
    data = t_bone(point=["1.5 ft", "-330 ft"])
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, file="far.toml")
    text = str(info.value)
    assert text.startswith("far.toml: impact.point: the contact point (1.5 ft, -330 ft) lies 327 ft outside the "
                           "outline of 'sedan' and 311.1 ft outside the outline of 'suv'")
    assert "impact.contact_tolerance = 1.64 ft" in text
    # the tolerance is the file's to change
    data["impact"]["contact_tolerance"] = "400 ft"
    scenario_from_dict(data)


def test_a_contact_point_inside_both_outlines_passes():
    sc = scenario_from_dict(t_bone())
    assert sc.impact.surface.point == pytest.approx((1.5 * 0.3048, -3.0 * 0.3048))


def test_not_approaching_names_the_file(tmp_path):
    data = t_bone(normal="-90 deg")
    with pytest.raises(ScenarioError) as info:
        run_scene(scenario_from_dict(data, file="apart.toml"))
    assert str(info.value).startswith("apart.toml: impact.normal: the contact points are not approaching")


def test_cli_refuses_an_inadmissible_impact_with_exit_2_and_one_line(tmp_path, capsys):
    text = T_BONE.replace('tangential = "no_slide"', 'tangential = "ratio"\nmu = 0.9')
    path = tmp_path / "mu.toml"
    path.write_text(text)
    assert main(["run", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"crashsim: input error: {path}: impact.mu = 0.9 exceeds mu_max")


def test_sign_of_e_prime_admissible_range_is_within_zero_one():
    err = refusal(t_bone(restitution=1.0, moment_restitution=1.0))
    assert 0.0 <= err.allowed[0] <= err.allowed[1] <= 1.0 and math.isfinite(err.value)


def test_a_mark_selector_that_matches_no_wheel_is_refused_at_load():
    data = tomllib.loads((ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml").read_text())
    data["evidence"]["marks"][0]["wheel"] = "trailer/rear/lft"
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(data, file="marks.toml")
    assert str(info.value) == ("marks.toml: evidence.marks[0].wheel: no axle 'rear' on body 'trailer'; allowed "
                               "['0', '1', 'axle 1', 'axle 2']")


def test_a_fit_path_naming_a_missing_vehicle_is_reported_as_such():
    from crashsim.reconstruct.fit import FitProblem, FitSpec

    data = tomllib.loads((ROOT / "scenarios" / "fit" / "intersection_fit.toml").read_text())
    data["fit"]["unknowns"][1]["path"] = "vehicles.V3.speed"
    spec = FitSpec.from_dict(data["fit"], data, file="fit.toml")
    with pytest.raises(ScenarioError) as info:
        FitProblem(data, spec, file="fit.toml")
    assert str(info.value) == ("fit.toml: fit.unknowns[1]: 'vehicles.V3.speed' names 'V3', but the scenario has no "
                               "entry 'V3' in [vehicles] Entries: 'A', 'B'")


def test_fit_bounds_outside_the_allowed_range_are_refused():
    from crashsim.reconstruct.fit import FitSpec

    data = tomllib.loads((ROOT / "scenarios" / "fit" / "intersection_fit.toml").read_text())
    data["fit"]["unknowns"][2]["upper"] = "1.4"  # impact.restitution
    with pytest.raises(ScenarioError, match=r"fit.toml: fit.unknowns\[2\].upper: upper = '1.4' lies outside the "
                                            r"allowed range of impact.restitution, \[0, 1\]"):
        FitSpec.from_dict(data["fit"], data, file="fit.toml")

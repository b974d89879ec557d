"""Crush energy against the impact model's energy loss: the work-energy split and closed forms.

Work-energy identity (Brach's formulation; Brach & Brach, SAE 2007-01-0737; docs/crush-energy.md):
the kinetic energy the pair loses at the crush surface is

    T_L = -1/2 [P_n (u_n- + u_n+) + P_t (u_t- + u_t+) + M (W- + W+)]

(u the relative velocity of the contact point, W the relative yaw rate), exact for rigid bodies, and the
hitch impulses of an articulated vehicle do no net work (the pin velocity is continuous). So with no
external impulses the normal, tangential and moment parts add up to the kinetic energy lost, to round-off.

Central collinear impact (docs/crush-energy.md, worked example 5): m1 = 1500 kg, m2 = 1200 kg, closing
speed 15 m/s: reduced mass 666.667 kg, energy absorbed at maximum compression 1/2 m v^2 = 75 000 J,
normal impulse (1 + e) m v, and T_L = (1 - e^2) 75 000 J (74 250 J for e = 0.1, with P_n = 11 000 N s).
"""

from __future__ import annotations

import copy
import math
import tomllib
from pathlib import Path

import pytest

from crashsim.impact import solve_impact
from crashsim.scene.run import run_scene
from crashsim.scenario import load_scenario, scenario_from_dict

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "tests" / "data" / "crush_head_on.toml"


def _head_on(**impact):
    d = tomllib.loads(SCENE.read_text())
    d["impact"].update(impact)
    return d


@pytest.mark.parametrize("e", [0.0, 0.1, 0.5])
def test_central_impact_loss_is_one_minus_e_squared_times_the_absorbed_energy(e):
    r = solve_impact(scenario_from_dict(_head_on(restitution=e)).impact)
    m = 1500.0 * 1200.0 / 2700.0
    absorbed = 0.5 * m * 15.0**2
    assert absorbed == pytest.approx(75_000.0)
    ke = r.kinetic_energy["system"]
    assert ke["before"] - ke["after"] == pytest.approx((1 - e * e) * 75_000.0, rel=1e-12)
    assert r.energy_loss_normal == pytest.approx((1 - e * e) * 75_000.0, rel=1e-12)
    assert abs(r.energy_loss_tangential) < 1e-9 and r.energy_loss_moment == 0.0
    assert r.normal_impulse == pytest.approx((1 + e) * m * 15.0, rel=1e-12)
    if e == 0.1:
        assert r.normal_impulse == pytest.approx(11_000.0, rel=1e-12)
        assert r.bodies["carA"].delta_v_magnitude == pytest.approx(7.3333333, abs=1e-6)
        assert r.bodies["carB"].delta_v_magnitude == pytest.approx(9.1666667, abs=1e-6)
        assert ke["before"] - ke["after"] == pytest.approx(74_250.0, rel=1e-12)


def _assert_split_adds_up(r, label):
    ke = r.kinetic_energy["system"]
    lost = ke["before"] - ke["after"]
    parts = r.energy_loss_normal + r.energy_loss_tangential + r.energy_loss_moment
    # external impulses (tyre friction during the impact) and velocity constraints do work of their own
    other = -r.work.get("external", 0.0) - r.work.get("constraints", 0.0)
    assert parts + other == pytest.approx(lost, rel=1e-10, abs=1e-9 * ke["before"]), label
    assert lost > 0.01 * ke["before"], label  # a real loss, not 0 = 0


@pytest.mark.parametrize("impact", [
    {},  # central
    {"point": ["2.3 m", "0.6 m"], "tangential": "friction", "friction": 0.3},  # eccentric, sliding
    {"point": ["2.3 m", "-0.5 m"], "normal": "165 deg", "moment_restitution": 0.2},  # oblique, moment impulse
    {"point": ["2.3 m", "0.4 m"], "normal": "200 deg", "tangential": "no_slide", "restitution": 0.3},
])
def test_work_split_adds_up_to_the_kinetic_energy_lost(impact):
    r = solve_impact(scenario_from_dict(_head_on(**impact)).impact)
    _assert_split_adds_up(r, impact)
    if impact.get("moment_restitution", -1) != -1:
        assert abs(r.energy_loss_moment) > 1e-6 * r.kinetic_energy["system"]["before"]  # the moment part is tested


@pytest.mark.parametrize("table", ["table5", "table6", "table7", "table8"])
def test_work_split_articulated_hitch_impulses_do_no_net_work(table):
    """The paper's tractor-semitrailer impacts: the split of the contact impulses (plus the work of the
    tyre-friction impulses of Table 7) equals the loss of the whole articulated system; the hitch
    impulses (non-zero) do no net work."""
    sc = load_scenario(ROOT / "scenarios" / "paper" / f"{table}.toml")
    r = solve_impact(sc.impact)
    assert any(abs(h.longitudinal) + abs(h.lateral) > 100.0 for h in r.hitches.values())
    assert abs(r.work["hitches"]) < 1e-9 * r.kinetic_energy["system"]["before"]
    _assert_split_adds_up(r, table)


def test_secondary_impacts_expose_the_split_in_results_and_json():
    """The run-out's impacts (here the trailer swinging into the pier) carry the same split, in the
    ImpactResult and in the scene's JSON, beside the kinetic energy lost."""
    scene = run_scene(load_scenario(ROOT / "scenarios" / "scenes" / "barrier_75deg.toml"))
    assert scene.joint.impacts
    for s in scene.joint.impacts:
        _assert_split_adds_up(s.result, s.t)
        assert s.result.energy_loss_crush == pytest.approx(s.energy_loss, rel=1e-9)
    impacts = scene.to_dict()["impacts"]
    assert len(impacts) == 1 + len(scene.joint.impacts)
    for i in impacts:
        split = i["energy_loss_normal"] + i["energy_loss_tangential"] + i["energy_loss_moment"]
        assert split == pytest.approx(i["energy_loss"], rel=1e-9)


def test_crush_check_compares_with_the_loss_at_the_crush_surface():
    """The test scene: car A's six-point profile (55 175 J, square-on so factor 1) plus car B's EES 6.5 m/s
    (25 350 J) against T_L = 74 250 J: residual 74 250 - 80 525 = -6 275 J, tolerance 10 + 5 kJ."""
    scene = run_scene(load_scenario(SCENE))
    (c,) = [c for c in scene.evidence.checks if c.kind == "crush energy"]
    assert c.details["bodies"]["carA"]["items"][0]["factor"] == pytest.approx(1.0, abs=1e-12)
    assert c.details["measured"] == pytest.approx(55_175.0 + 25_350.0, rel=1e-12)
    assert c.details["computed"] == pytest.approx(74_250.0, rel=1e-12)
    assert c.residual == pytest.approx(-6_275.0, rel=1e-9) and c.tolerance == pytest.approx(15_000.0)
    assert c.passed and c.details["complete"]
    d = copy.deepcopy(tomllib.loads(SCENE.read_text()))
    d["evidence"]["crush"][0]["tolerance"] = "1 kJ"
    assert not [c for c in run_scene(scenario_from_dict(d)).evidence.checks if c.kind == "crush energy"][0].passed


def test_oblique_force_gets_the_factor_and_normal_comparison_drops_it():
    """An oblique normal (20 deg) turns the PDOF of car A by 20 deg from its front: factor 1/cos^2(20 deg),
    used with compare = "total" (against T_n + T_t + T_M) and not with compare = "normal" (against T_n + T_M)."""
    d = _head_on(normal="200 deg", point=["2.3 m", "0 m"], tangential="ratio", mu=0.0)  # impulse along n
    del d["evidence"]["crush"][1]
    base = run_scene(scenario_from_dict(d))
    (c,) = base.evidence.checks
    item = c.details["bodies"]["carA"]["items"][0]
    pdof = base.impact.bodies["carA"].pdof
    assert abs(math.degrees(pdof)) == pytest.approx(20.0, abs=1e-9)
    assert item["factor"] == pytest.approx(1 / math.cos(math.radians(20.0)) ** 2, rel=1e-12)
    assert c.details["measured"] == pytest.approx(55_175.0 * item["factor"], rel=1e-12)
    assert c.details["computed"] == pytest.approx(base.impact.energy_loss_crush, rel=1e-12)
    assert not c.details["complete"] and c.details["missing"] == ["carB"]  # car B's crush left out: lower bound
    d["evidence"]["crush"][0]["compare"] = "normal"
    (c2,) = run_scene(scenario_from_dict(d)).evidence.checks
    assert c2.details["measured"] == pytest.approx(55_175.0, rel=1e-12)
    assert c2.details["computed"] == pytest.approx(base.impact.energy_loss_normal + base.impact.energy_loss_moment,
                                                   rel=1e-12)


def test_all_impacts_group_counts_the_run_out_impacts_of_the_body():
    """barrier_75deg: the tractor strikes the barrier, then the trailer swings into it (t = 0.47 s).
    A trailer item with impacts = "all" is compared with the trailer's own (secondary) impact; the
    barrier is rigid, so the comparison is complete. With impacts = "first" the trailer was not in
    contact, and the check fails with that reason."""
    d = tomllib.loads((ROOT / "scenarios" / "scenes" / "barrier_75deg.toml").read_text())
    item = {"body": "trailer", "face": "right", "ees": "20 km/h", "tolerance": "50 kJ", "impacts": "all"}
    d["evidence"] = {"crush": [dict(item), {"body": "tractor", "face": "front", "ees": "25 km/h",
                                            "tolerance": "50 kJ", "impacts": "first"}]}
    scene = run_scene(scenario_from_dict(d))
    later, first = [c for c in scene.evidence.checks if c.kind == "crush energy"]  # groups in order of appearance
    assert (later.details["impacts"], first.details["impacts"]) == ("all", "first")
    (s,) = [s for s in scene.joint.impacts if "trailer" in (s.body1, s.body2)]
    assert [x["time"] for x in later.details["impacts_counted"]] == [s.t]
    assert later.details["computed"] == pytest.approx(s.result.energy_loss_crush, rel=1e-12)
    assert later.details["complete"]
    assert later.details["measured"] == pytest.approx(0.5 * 20_000.0 * (20 / 3.6) ** 2, rel=1e-12)  # loaded trailer
    assert first.details["computed"] == pytest.approx(scene.impact.energy_loss_crush, rel=1e-12)
    assert [x["time"] for x in first.details["impacts_counted"]] == [0.0]
    d["evidence"]["crush"][0]["impacts"] = "first"
    d["evidence"]["crush"].pop(1)
    (c,) = run_scene(scenario_from_dict(d)).evidence.checks
    assert not c.passed and c.residual == float("inf") and "trailer not in contact" in c.details["reason"]


def test_factor_beyond_45_degrees_is_held_at_2_with_a_warning():
    """A crush force 60 deg off the face normal: CRASH3's factor applies up to 45 deg only, so it is held
    at 2 and the report says so; relative_tolerance scales with the corrected energy."""
    d = _head_on(normal="240 deg", tangential="ratio", mu=0.0)
    d["evidence"]["crush"] = [{"body": "carA", "face": "front", "A": "50000 N/m", "B": "600000 N/m^2",
                               "width": "1.5 m", "profile": ["0.3 m", "0.3 m"], "relative_tolerance": "25 %"}]
    scene = run_scene(scenario_from_dict(d))
    (c,) = scene.evidence.checks
    item = c.details["bodies"]["carA"]["items"][0]
    assert abs(item["alpha"]) == pytest.approx(math.radians(60.0), abs=1e-9)
    assert item["factor"] == 2.0 and item["factor_capped"]
    assert item["energy"] == pytest.approx(2 * 66_125.0, rel=1e-12)  # worked example 3, uniform 0.30 m
    assert c.tolerance == pytest.approx(0.25 * 2 * 66_125.0, rel=1e-12)
    text = scene.report()
    assert "2.0000 (capped)" in text and "beyond the 45 deg" in text

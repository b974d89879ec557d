"""Scenario input of the whole-scene run-out: [contacts], [[contacts.pairs]], [[obstacles]],
more than two vehicles, and the run-out bounds -- clear errors that name the field, the value
and what is allowed, and results that follow the inputs.

Base scene: ``scenarios/scenes/barrier_75deg.toml`` (the trailer swings into the pier 0.47 s
after the first impact: a secondary impact with the [contacts] defaults e = 0.2, f = 0.6).
"""

from __future__ import annotations

import json
import math
import tomllib
from pathlib import Path

import numpy as np
import pytest

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.scene.run import run_scene
from crashsim.scenario import scenario_from_dict

ROOT = Path(__file__).resolve().parents[2]
B75 = ROOT / "scenarios" / "scenes" / "barrier_75deg.toml"
THIRD = ROOT / "scenarios" / "scenes" / "third_vehicle_waiting_car.toml"


@pytest.fixture
def data():
    return tomllib.loads(B75.read_text())


def _error(d) -> str:
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d, file="case.toml")
    return str(info.value)


def _cli(tmp_path, text, capsys, *extra):
    f = tmp_path / "case.toml"
    f.write_text(text)
    code = main(["run", str(f), *extra])
    return code, capsys.readouterr()


# ---------------------------------------------------------------------------- bad input
def test_obstacle_needs_two_points(data):
    data["obstacles"] = [{"name": "post", "points": [["20 m", "5 m"]]}]
    msg = _error(data)
    assert "obstacles[0].points" in msg and "2" in msg


def test_closed_obstacle_must_not_cross_itself(data):
    bow_tie = [["20 m", "5 m"], ["24 m", "8 m"], ["24 m", "5 m"], ["20 m", "6 m"]]
    data["obstacles"] = [{"name": "pier", "points": bow_tie, "closed": True}]
    msg = _error(data)
    assert "obstacles[0].points" in msg and "crosses itself" in msg


def test_obstacle_name_must_be_unique(data):
    data["obstacles"] = [{"name": "trailer", "points": [["20 m", "5 m"], ["30 m", "5 m"]]}]
    msg = _error(data)
    assert "obstacles[0].name" in msg and "'trailer'" in msg and "unique" in msg


def test_obstacle_thickness_range(data):
    data["obstacles"] = [{"name": "rail", "points": [["20 m", "5 m"], ["30 m", "5 m"]], "thickness": "0 m"}]
    msg = _error(data)
    assert "obstacles[0].thickness" in msg and "0" in msg


def test_unknown_pair_name_suggests_the_nearest(data):
    data["contacts"] = {"pairs": [{"first": "trailr", "second": "barrier", "restitution": 0.1}]}
    msg = _error(data)
    assert "contacts.pairs[0].first" in msg and "'trailr'" in msg and "did you mean 'trailer'" in msg


def test_pair_within_one_vehicle_is_an_error(data):
    data["contacts"] = {"pairs": [{"first": "tractor", "second": "trailer", "friction": 0.3}]}
    msg = _error(data)
    assert "contacts.pairs[0].second" in msg and "same vehicle" in msg


@pytest.mark.parametrize("key, value, allowed", [("restitution", 1.5, "1"), ("friction", -0.1, "0"),
                                                 ("stiffness", 0.0, "0"), ("damping_ratio", 200.0, "100")])
def test_contact_coefficients_out_of_range(data, key, value, allowed):
    data["contacts"] = {key: value}
    msg = _error(data)
    assert f"contacts.{key}" in msg and str(value) in msg and allowed in msg


@pytest.mark.parametrize("where", ["scene", "pair"])
def test_a_stiffness_that_cannot_hold_the_heaviest_vehicle_is_refused(data, where):
    """The loaded tractor-semitrailer weighs (9500 + 20000) kg x g = 289.3 kN: held within
    0.1 m, the stiffness must be at least 2.893e6 N/m."""
    if where == "scene":
        data["contacts"] = {"stiffness": 1e5}
        key = "contacts.stiffness"
    else:
        data["contacts"] = {"pairs": [{"first": "trailer", "second": "barrier", "stiffness": 1e6}]}
        key = "contacts.pairs[0].stiffness"
    msg = _error(data)
    assert msg.startswith(f"case.toml: {key}: ") and "allowed >= 2.893e+06 N/m" in msg
    assert ("100000 N/m" if where == "scene" else "1e+06 N/m") in msg and "'truck'" in msg
    assert len(msg.splitlines()) == 1
    data["contacts"] = {"stiffness": 2.9e6}
    scenario_from_dict(data, file="case.toml")  # just enough


def test_bad_contact_input_exits_2_and_names_the_field(tmp_path, capsys):
    code, out = _cli(tmp_path, B75.read_text() + "\n[contacts]\nrestitution = 2.0\n", capsys)
    assert code == 2 and out.out == ""
    assert "case.toml" in out.err and "contacts.restitution" in out.err and "2.0" in out.err


# ---------------------------------------------------------------------------- inputs act
def test_contact_off_lets_the_trailer_pass_through_the_pier(data):
    data["contacts"] = {"enabled": False}
    scene = run_scene(scenario_from_dict(data))
    assert scene.joint.impacts == () or len(scene.joint.impacts) == 0
    assert all(p.contact_time == 0 for p in scene.joint.pairs)


def test_pair_override_sets_the_second_impact_coefficients(data):
    data["contacts"] = {"pairs": [{"first": "trailer", "second": "barrier", "restitution": 0.0, "friction": 0.1}]}
    scene = run_scene(scenario_from_dict(data))
    (second,) = scene.joint.impacts[:1]
    assert (second.body1, second.body2) == ("trailer", "barrier")
    assert second.restitution == 0.0 and second.friction == 0.1


def test_scene_wide_restitution_changes_the_rebound(data):
    """A stiffer bounce (e = 0.6) throws the trailer off the pier faster than e = 0.2."""
    speeds = {}
    for e in (0.2, 0.6):
        data["contacts"] = {"restitution": e}
        scene = run_scene(scenario_from_dict(data))
        imp = scene.joint.impacts[0]
        speeds[e] = float(np.dot(imp.delta_v["trailer"], imp.normal))
    assert speeds[0.6] > speeds[0.2] > 0


def test_an_obstacle_in_the_path_is_struck(data):
    """A pole 1 m wide where the tractor runs to rest (about (13.8, -1.1) m) is struck."""
    data["obstacles"] = [{"name": "pole", "closed": True,
                          "points": [["11.0 m", "-2.5 m"], ["12.0 m", "-2.5 m"], ["12.0 m", "-1.5 m"],
                                     ["11.0 m", "-1.5 m"]]}]
    scene = run_scene(scenario_from_dict(data))
    struck = [i for i in scene.joint.impacts if "pole" in (i.body1, i.body2)]
    touched = [p for p in scene.joint.pairs if "pole" in (p.body1, p.body2) and (p.impacts or p.contact_time > 0)]
    assert struck or touched
    assert scene.at_rest


def test_max_impacts_bounds_the_run_and_exits_3(tmp_path, capsys):
    text = B75.read_text().replace("[runout]\n", "[runout]\nmax_impacts = 0\n")
    code, out = _cli(tmp_path, text, capsys, "--json")
    assert code == 3
    res = json.loads(out.out)
    assert res["runout"]["status"] == "event_limit"
    assert "max_impacts = 0" in res["runout"]["message"]
    assert not any(b["at_rest"] for b in res["runout"]["bodies"].values())


# ---------------------------------------------------------------------------- more vehicles
def test_third_vehicle_waits_then_is_struck():
    """The waiting car is not in the impact: it keeps its state (at rest) until the spinning
    car reaches it; its delta-v over all its impacts is what its module records."""
    sc = scenario_from_dict(tomllib.loads(THIRD.read_text()))
    assert [v.name for v in sc.impact.vehicles] == ["towing", "striking"]
    scene = run_scene(sc)
    hits = [i for i in scene.joint.impacts if "waiting" in (i.body1, i.body2)]
    assert len(hits) >= 2
    assert min(i.t for i in hits) > 0.3
    first_move = min(i.t for i in hits)
    w = scene.runout_body("waiting").history
    before = w.t < first_move - 1e-9
    assert np.all(np.hypot(w.vx[before], w.vy[before]) == 0.0)
    # delta-v "all": the sum of the body's impacts (its world-frame vectors), here all later ones
    total = np.sum([i.delta_v["waiting"] for i in hits], axis=0)
    (check,) = [c for c in scene.evidence.checks if c.kind == "delta-v"]
    heading = sc.states["waiting"].heading
    lateral = -math.sin(heading) * total[0] + math.cos(heading) * total[1]
    assert check.details["computed"] == pytest.approx(lateral, rel=1e-9)
    assert check.details["impacts_counted"] == len(hits)


def test_json_of_a_joint_run_out(capsys):
    assert main(["run", str(THIRD), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [i["time"] for i in out["impacts"]] == sorted(i["time"] for i in out["impacts"])
    assert out["impacts"][0]["time"] == 0.0 and len(out["impacts"]) >= 4
    for i in out["impacts"][1:]:
        assert {"body1", "body2", "point", "normal", "closing_speed", "normal_impulse", "tangential_impulse",
                "energy_loss", "delta_v", "law", "restitution", "friction"} <= set(i)
    e = out["runout"]["energy_J"]
    assert {"before_impact", "first_impact", "later_impacts", "tyres", "stops", "contacts", "final",
            "closing_error"} == set(e)
    assert abs(e["closing_error"]) < 1e-5 * e["before_impact"]
    for b in out["runout"]["bodies"].values():
        assert np.asarray(b["outline"]).shape == (4, 2)
    assert {p["name"] for p in out["runout"]["pairs"]} >= {"car|waiting", "trailer|striker"}


# ---------------------------------------------------------------------------- penalty contact
@pytest.mark.parametrize("path", sorted((ROOT / "scenarios" / "scenes").glob("*.toml")), ids=lambda p: p.stem)
def test_penetration_stays_within_force_over_stiffness(path):
    """Sustained contact holds bodies within F / k of each other (plus 1 mm): the penalty
    spring is stiff enough for every shipped scene (k = 1e7 N/m per contact point)."""
    sc = scenario_from_dict(tomllib.loads(path.read_text()))
    scene = run_scene(sc)
    if scene.joint is None:
        pytest.skip("no joint run-out at this level")
    k = sc.runout.contact.stiffness
    for p in scene.joint.pairs:
        assert p.max_penetration <= p.peak_force / k + 1e-3, (p.name, p.max_penetration, p.peak_force)


# ---------------------------------------------------------------------------- later contact, both engines
SCENES = sorted((ROOT / "scenarios" / "scenes").glob("*.toml"))


def _engine_run(path, engine, **runout):
    d = tomllib.loads(path.read_text())
    d.setdefault("runout", {}).update(engine=engine, **runout)
    sc = scenario_from_dict(d)
    return sc, run_scene(sc)


@pytest.mark.parametrize("path", SCENES, ids=lambda p: p.stem)
def test_both_engines_see_the_same_later_impacts_and_close_the_ledger(path):
    """Every shipped scene: the same later impacts on both engines (pairs in order, times within
    1 ms); the ledger closes to 1e-6 of the kinetic energy with no negative line; no point in
    contact closes at the impulse threshold outside an impact (every re-strike is an impact)."""
    runs = {e: _engine_run(path, e) for e in ("scipy", "compiled")}
    seqs = []
    for engine, (sc, scene) in runs.items():
        if scene.joint is None:
            pytest.skip("no joint run-out at this level")
        e = scene.energy_ledger()
        for line in ("first_impact", "later_impacts", "tyres", "stops", "contacts", "final"):
            assert e[line] >= -1e-9 * e["before_impact"], (engine, line, e)
        assert abs(e["closing_error"]) <= 1e-6 * e["before_impact"], (engine, e)
        for p in scene.joint.pairs:
            thr = sc.runout.pair_contact.get((p.body1, p.body2), sc.runout.contact).velocity_threshold
            assert p.max_closing < thr * (1 + 1e-6) + 1e-9, (engine, p.name, p.max_closing)
        seqs.append([(i.body1, i.body2, i.t) for i in scene.joint.impacts])
    assert [s[:2] for s in seqs[0]] == [s[:2] for s in seqs[1]]
    assert all(abs(a[2] - b[2]) <= 1e-3 for a, b in zip(*seqs))


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_contact_summaries_do_not_depend_on_the_sample_grid(engine):
    """Peak force, deepest penetration, contact time and work of each pair come from the
    solution, not from the printed samples: 1, 10 and 50 ms give the same numbers (the run is
    the same run; the sample grid only sets how densely tracks are printed).  The contact time
    is the span of the pair's own contact events."""
    path = ROOT / "scenarios" / "scenes" / "barrier_75deg.toml"
    out = {}
    for dt in ("0.001 s", "0.01 s", "0.05 s"):
        _, scene = _engine_run(path, engine, sample_dt=dt)
        out[dt] = {p.name: p for p in scene.joint.pairs}
        events = [e for e in scene.joint.events if e.kind.startswith("contact")]
    for dt, pairs in out.items():
        p, q = pairs["trailer|barrier"], out["0.01 s"]["trailer|barrier"]
        assert p.peak_force == pytest.approx(q.peak_force, rel=1e-9) and p.peak_force > 1e5
        assert p.max_penetration == pytest.approx(q.max_penetration, rel=1e-9)
        assert p.contact_time == pytest.approx(q.contact_time, rel=1e-12)
        assert p.contact_work == pytest.approx(q.contact_work, rel=1e-9)
    # the span of the pair's contact events: from an impact, a touch or a press to its end (or the run's)
    span, since = 0.0, None
    for e in scene.joint.events:
        if e.data.get("pair") != "trailer|barrier":
            continue
        if e.kind in ("impact", "contact", "contact_pressed") and since is None:
            since = e.t
        elif e.kind == "contact_end" and since is not None:
            span, since = span + e.t - since, None
    if since is not None:
        span += scene.joint.t_end - since
    assert "contact_end" in [e.kind for e in events]
    assert out["0.05 s"]["trailer|barrier"].contact_time == pytest.approx(span, rel=1e-9)

"""The validation suite (``validation/``) in CI: every case run once, every quantity's status against its
case's record, the published table against today's run, the scenes against their data and the rules, the
bands against the published numbers they come from.

What fails here, and what to do:

* a quantity leaves its band (status ``MISS``), or a documented miss comes within it (``record stale``):
  the physics changed the suite's result. Find out why; if the change is right, update the case's
  ``record.toml`` and ``README.md`` and run ``python benchmarks/validation_suite.py``;
* the published table (``docs/validation/errors.md``, ``src/crashsim/data/validation_errors.json``) differs
  from today's run beyond the quantities' precision: run ``python benchmarks/validation_suite.py``;
* a RICSAC scene is not what its data and the rules give: ``python benchmarks/validation_suite.py --scenes``.

The whole suite costs a few seconds of CPU (``docs/validation/errors.md``, "Cost"): it is all fast tier.
"""

from __future__ import annotations

import json
import math
import re
import tomllib
from pathlib import Path

import pytest

from crashsim.cli import main
from crashsim.scenario import load_scenario
from crashsim.schema import load_toml
from crashsim.units import Kind, parse
from crashsim.validation import STATUS, load_suite, run_suite
from crashsim.validation import ricsac
from crashsim.validation.core import read_case

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "validation"
TABLE = ROOT / "src" / "crashsim" / "data" / "validation_errors.json"
DOCS = ROOT / "docs" / "validation" / "errors.md"

#: How far today's value may be from the published table's: below any printed digit of the table and
#: above the run-out's round-off between processors (rtol 1e-8; rest positions agree to 0.1 mm).
TOLERANCE = {"relative": 1e-4, "range": 1e-4, "criterion": 0.0, "limit": {"length": 1e-3, "angle": 1e-4},
             "difference": {"speed": 1e-4, "angle": 1e-4, "angular_velocity": 1e-4, "length": 1e-3,
                            "dimensionless": 1e-5}}


@pytest.fixture(scope="module")
def suite():
    return load_suite(SUITE)


@pytest.fixture(scope="module")
def results(suite):
    return {r.id: r for r in run_suite(suite)}


def test_the_suite_has_every_case_the_issue_asks_for(suite):
    assert {"ricsac-01", "ricsac-03", "ricsac-06", "ricsac-08", "ricsac-11", "mash-3-10", "tl5-tractor-van-glance",
            "fmvss121-stop", "j695-offtracking"} <= set(suite.cases)
    for cid, data in suite.cases.items():
        folder = data["folder"]
        assert (folder / "README.md").is_file(), cid
        assert data["case"]["class"] and data["case"]["title"]


@pytest.mark.parametrize("cid", sorted(load_suite(SUITE).cases))
def test_every_quantity_agrees_with_its_record(results, cid):
    r = results[cid]
    assert r.quantities, cid
    changed = [f"{q.name}: {q.status} (error {q.error:.4g}, band {q.band:.4g})" for q in r.quantities
               if q.status not in (STATUS[0], STATUS[1])]
    assert not changed, f"{cid}: the record (record.toml) no longer holds: {changed}"


def test_documented_misses_name_real_quantities_and_are_explained(results, suite):
    for cid, data in suite.cases.items():
        names = {q.name for q in results[cid].quantities}
        for quantity, why in data["record"].items():
            assert quantity in names, f"{cid}/record.toml names {quantity!r}, which the case does not compare"
            assert len(why) > 30, f"{cid}/record.toml: say why {quantity!r} misses"
        readme = (data["folder"] / "README.md").read_text()
        if data["record"]:
            assert "## Why the misses happen" in readme, f"{cid}/README.md must explain its misses"
        else:
            assert re.search(r"Misses: none|## Misses\s+None", readme), f"{cid}/README.md: say it has no misses"


def test_every_quantity_has_a_source_and_a_band_basis(results):
    for r in results.values():
        for q in r.quantities:
            assert q.source and q.basis.split(":")[0] in ("scatter", "anchors", "stated"), (r.id, q.name, q.basis)
            assert q.band >= 0 and math.isfinite(q.band), (r.id, q.name)


# ------------------------------------------------------------------ the published table is today's
def test_the_published_table_is_today_s_run(results):
    table = json.loads(TABLE.read_text())
    published = {(row["case"], row["name"]): row for row in table["quantities"]}
    today = {(r.id, q.name): q for r in results.values() for q in r.quantities}
    assert set(published) == set(today), "run python benchmarks/validation_suite.py"
    for key, q in today.items():
        row = published[key]
        tol = TOLERANCE[q.metric]
        tol = tol[q.kind] if isinstance(tol, dict) else tol
        assert row["status"] == q.status, (key, row["status"], q.status)
        assert abs(row["error"] - q.error) <= tol, (key, row["error"], q.error)
        assert abs(row["band"] - q.band) <= tol, (key, row["band"], q.band)
    md = DOCS.read_text()
    for (cid, name), q in today.items():
        row = re.search(rf"^\| {re.escape(name)} \|[^|]*\|[^|]*\|[^|]*\|[^|]*\| ({'|'.join(map(re.escape, STATUS))}) \|",
                        md.split(f"## {cid}:")[1]
                        .split("\n## ")[0], flags=re.M)
        assert row and row.group(1) == q.status, (cid, name)
    counts = re.search(r"\*\*(\d+) cases, (\d+) quantities: (\d+) within their band, (\d+) outside it", md)
    qs = list(today.values())
    assert counts and [int(x) for x in counts.groups()] == [len(results), len(qs), sum(q.within for q in qs),
                                                            sum(not q.within for q in qs)]


# ------------------------------------------------------------------ scenes: the data and the rules
def test_ricsac_scenes_are_what_their_data_and_the_rules_give(suite):
    for cid, data in suite.cases.items():
        if data["case"]["kind"] != "staged_collision":
            continue
        text = (data["folder"] / data["case"]["scene"]).read_text()
        assert text == ricsac.scene_text(ricsac.load_test(data), suite.rules), (
            f"{cid}/scene.toml differs from its data and the rules: python benchmarks/validation_suite.py --scenes")


def _scene(data):
    return load_toml((data["folder"] / data["case"]["scene"]).resolve())


def test_every_scene_follows_the_rules(suite):
    rules = suite.rules
    vv, vb, tyres = rules["vehicle_to_vehicle"], rules["vehicle_to_barrier"], rules["car_tyres"]
    seen = set()
    for cid, data in suite.cases.items():
        if "scene" not in data["case"]:
            continue
        s = _scene(data)
        imp = s["impact"]
        if "barrier" in s:
            assert (imp["restitution"], imp["tangential"], imp["friction"], imp["moment_restitution"]) == (
                vb["restitution"], vb["tangential"], vb["friction"], vb["moment_restitution"]), cid
            assert (s["contacts"]["restitution"], s["contacts"]["friction"]) == (
                vb["contact_restitution"], vb["contact_friction"]), cid
            seen.add("barrier")
        else:
            assert (imp["restitution"], imp["tangential"], imp["moment_restitution"]) == (
                vv["restitution"], vv["tangential"], vv["moment_restitution"]), cid
            seen.add("vehicle")
        for name, v in s["vehicles"].items():
            if all(b.get("preset") is None for b in v["bodies"]) and len(v["bodies"]) == 1:  # the cars
                t = v["tyres"]
                assert (t["state"], t["cornering_coefficient"], t["rolling_resistance"]) == (
                    tyres["state"], tyres["cornering_coefficient"], tyres["rolling_resistance"]), (cid, name)
                assert "wheels" not in v, (cid, name)  # no wheel set apart: none jammed, none steered
        if "runout" in s and data["case"]["kind"] == "staged_collision":
            assert s["runout"]["road_friction"] == data["test"]["surface_friction"], cid
            assert s["runout"]["engine"] == rules["runout"]["engine"], cid
        elif "runout" in s and data["case"]["kind"] == "barrier_test":
            assert s["runout"]["road_friction"] == rules["road"]["friction_unpublished"], cid
    assert seen == {"barrier", "vehicle"}


def test_the_glance_case_runs_the_shipped_scene_whose_coefficients_are_the_rules(suite):
    data = suite.cases["tl5-tractor-van-glance"]
    assert (data["folder"] / data["case"]["scene"]).resolve() == ROOT / "scenarios" / "scenes" / "barrier_glance_15deg.toml"


# ------------------------------------------------------------------ bands from the published numbers
def _si(values, kind):
    return [parse(v, kind, field="x") for v in values]


def test_ricsac_bands_are_the_published_scatter(suite):
    """Each pooled band recomputed here from the measured.toml strings, independently of the module."""
    raw = [tomllib.loads((d["folder"] / "measured.toml").read_text()) for d in suite.cases.values()
           if d["case"]["kind"] == "staged_collision"]
    dv = max((max(r) - min(r)) / 2 / (sum(r) / 3) for m in raw for k in (0, 1)
             for r in [[_si(m["measured"]["delta_v"][n], Kind.SPEED)[k] for n in
                        ("untransformed", "brach_smith_2002", "mchenry_1997")]])
    sep = max(abs(_si(m["measured"]["delta_v"][n], Kind.SPEED)[k] - _si(m["measured"]["delta_v"]["untransformed"],
                                                                         Kind.SPEED)[k])
              for m in raw for k in (0, 1) for n in ("brach_smith_2002", "mchenry_1997"))
    yaw = max(parse(m["anchors"]["fitted_separation_error"][i], Kind.ANGULAR_VELOCITY, field="x")
              for m in raw for i in (2, 5))
    tests = [ricsac.load_test(d) for d in suite.cases.values() if d["case"]["kind"] == "staged_collision"]
    bands = ricsac.pooled_bands(tests)
    assert bands["delta_v"][0] == pytest.approx(dv, rel=1e-12)
    assert bands["separation"][0] == pytest.approx(sep, rel=1e-12)
    assert bands["yaw_rate"][0] == pytest.approx(abs(yaw), rel=1e-12)
    assert 0.05 < dv < 0.15 and 0.5 < sep < 2.0  # the scale the README states ("about 10 %", "about 1.2 m/s")


def test_the_energy_reductions_agree_as_the_sources_file_says(suite):
    """Brach1987's energies (transcribed from a scan) against those of Vossou2018's velocities and Neades2011's
    masses: within 1.5 % initial and 2.3 % loss (validation/sources.toml)."""
    for d in suite.cases.values():
        if d["case"]["kind"] != "staged_collision":
            continue
        t = ricsac.load_test(d)
        e0, loss = ricsac.loss_from_velocities(t)
        assert e0 == pytest.approx(t["energy"][0], rel=0.015)
        assert loss == pytest.approx(t["energy"][1], rel=0.023)


def test_day2004_frame_meets_its_published_path_lengths(suite):
    """The recovered frame: the handedness the yaw rates give, and both path lengths within Day2004's intervals."""
    mirrored = {}
    for cid in ("ricsac-03", "ricsac-06"):
        d = suite.cases[cid]
        t = ricsac.load_test(d)
        sc = load_scenario(d["folder"] / d["case"]["scene"])
        f = ricsac.day_frame(t, [sc.states[v["name"]].position for v in t["vehicles"]])
        for (best, lo, hi), given in zip(f["lengths"], f["frame_lengths"]):
            assert lo <= given <= hi
        mirrored[cid] = f["mirror"]
    assert mirrored == {"ricsac-03": False, "ricsac-06": True}


# ------------------------------------------------------------------ the command
def test_validate_json_one_case(capsys):
    assert main(["validate", "--suite", str(SUITE), "ricsac-11", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [c["id"] for c in out["cases"]] == ["ricsac-11"]
    assert out["counts"]["MISS"] == 0 and len(out["cases"][0]["quantities"]) == 11


def test_validate_text_csv_and_plot(tmp_path, capsys):
    csv_path, plots = tmp_path / "e.csv", tmp_path / "figs"
    assert main(["validate", "--suite", str(SUITE), "ricsac-08", "fmvss121-stop", "--csv", str(csv_path), "--plots",
                 str(plots), "--units", "US"]) == 0
    out = capsys.readouterr().out
    assert "ricsac-08" in out and "mph" in out and "Errors per case class" in out
    rows = csv_path.read_text().splitlines()
    assert rows[0].startswith("case,class,quantity") and len(rows) == 1 + 11 + 2
    assert sorted(p.name for p in plots.iterdir()) == ["fmvss121-stop.png", "ricsac-08.png"]
    assert (plots / "ricsac-08.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


@pytest.mark.parametrize("args, field", [
    (["nosuch"], "CASE"),
    (["--suite", "SCENARIOS"], "--suite"),
    (["ricsac-11", "--csv", "FILE/x.csv"], "--csv"),
    (["ricsac-11", "--plots", "FILE"], "--plots"),
])
def test_validate_bad_input_is_one_line_and_exit_2(args, field, tmp_path, capsys):
    blocker = tmp_path / "a_file"
    blocker.write_text("")
    args = [a.replace("SCENARIOS", str(ROOT / "scenarios")).replace("FILE", str(blocker)) for a in args]
    if "--suite" not in args:
        args = ["--suite", str(SUITE)] + args
    assert main(["validate"] + args) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and field in err and "input error" in err


def test_a_case_folder_must_name_itself(tmp_path):
    folder = tmp_path / "ricsac-99"
    folder.mkdir()
    (folder / "measured.toml").write_text('[case]\nid = "ricsac-98"\nkind = "staged_collision"\ntitle = "t"\n'
                                          'class = "car-to-car"\n')
    with pytest.raises(Exception, match="differs from its folder"):
        read_case(folder)

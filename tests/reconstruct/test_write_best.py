"""crashsim fit --write-best: the best fit as a runnable scenario that reproduces the fit's residuals."""

from __future__ import annotations

import json

import numpy as np
import pytest
import tomli_w

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.reconstruct.fit import EvidenceModel, fit_scene
from crashsim.reconstruct.overrides import resolve_path, set_value
from crashsim.scene.run import run_scene, simulate_approaches
from crashsim.scenario import load_scenario
from crashsim.schema import load_toml
from crashsim.units import parse

from scenes import ENGINE, car_car, with_evidence

FIT = {"starts": 1, "seed": 1, "unknowns": [
    {"path": "vehicles.A.speed", "lower": "15 mph", "upper": "40 mph", "initial": "25 mph"},
    {"path": "vehicles.B.speed", "lower": "6 m/s", "upper": "16 m/s", "initial": "11 m/s"},
    {"path": "runout.road_friction", "lower": "0.5", "upper": "0.95", "initial": "0.7"},
]}


@pytest.fixture(scope="module")
def scene_file(tmp_path_factory):
    """The car-car scene with evidence from known inputs, speeds written in mph and m/s, and a [fit]."""
    data = with_evidence(car_car(), ["vehicles.A.speed", "vehicles.B.speed"], [12.0, 10.0], seed=11)
    data["vehicles"]["A"]["speed"] = "26 mph"
    data["fit"] = FIT
    path = tmp_path_factory.mktemp("wb") / "scene.toml"
    path.write_text(tomli_w.dumps(data))
    return path


@pytest.fixture(scope="module")
def fitted(scene_file):
    return fit_scene(load_toml(scene_file), None, engine=ENGINE, workers=1, file=str(scene_file))


def _residuals_of(path, spec):
    """Run a scenario file as `crashsim run` does; the fit's residual vectors (unweighted, SI) of its evidence."""
    scene = run_scene(load_scenario(path))
    model = EvidenceModel(scene.scenario, sigma_from_tolerance=spec.get("sigma_from_tolerance"))
    return model.raw_residuals(scene)[0], scene


def test_best_dict_writes_each_unknown_in_its_files_unit(fitted):
    d = fitted.best_scenario_dict()
    assert "fit" not in d
    a, b, mu = fitted.x
    assert d["vehicles"]["A"]["speed"].endswith(" mph")
    assert float(d["vehicles"]["A"]["speed"].split()[0]) * 0.44704 == pytest.approx(a, rel=1e-15)
    assert d["vehicles"]["B"]["speed"] == f"{float(b)!r} m/s"
    assert d["runout"]["road_friction"] == mu
    assert d["runout"].get("engine", "scipy") == ENGINE
    # the input is left as it was
    assert fitted.source_data["vehicles"]["A"]["speed"] == "26 mph" and "fit" in fitted.source_data


def test_written_file_reproduces_the_fit(fitted, scene_file, tmp_path):
    out = fitted.write_best(tmp_path / "best.toml")
    text = out.read_text()
    head = text.split("\n[", 1)[0]
    assert "crashsim fit --write-best" in head and str(scene_file) in head
    assert f"chi^2 = {fitted.chi2:.6g} for {fitted.dof} degrees of freedom" in head
    for u in fitted.unknowns:
        assert f"#   {u.path} = " in head
    assert "\n# [fit]\n" in text and "\n[fit]" not in text  # removed, kept as a comment
    raw = load_toml(out)
    assert "fit" not in raw
    got, scene = _residuals_of(out, FIT)
    want = [r.residual for r in fitted.residuals]
    assert len(got) == len(want) == 4
    for g, w in zip(got, want):
        np.testing.assert_allclose(g, w, rtol=1e-6, atol=1e-12)
    assert scene.evidence.all_passed


def test_cli_write_best_then_run(scene_file, tmp_path, capsys):
    out = tmp_path / "best_cli.toml"
    assert main(["fit", str(scene_file), "--json", "--workers", "1", "--write-best", str(out)]) == 0
    cap = capsys.readouterr()
    res = json.loads(cap.out)
    assert f"wrote the best-fit scenario to {out}" in cap.err
    assert main(["run", str(out), "--json"]) == 0
    run = json.loads(capsys.readouterr().out)
    checks = run["evidence"]["checks"]
    fit_res = res["residuals"]
    assert [c["name"] for c in checks] == [r["name"] for r in fit_res]
    for c, r in zip(checks, fit_res):
        v = np.asarray(r["residual"])
        expected = float(np.hypot(*v)) if v.size == 2 else float(v[0])  # a rest check is the CG distance
        assert c["residual"] == pytest.approx(expected, rel=1e-6, abs=1e-12), c["name"]


def test_the_input_file_is_never_overwritten(fitted, scene_file, capsys):
    before = scene_file.read_text()
    assert main(["fit", str(scene_file), "--write-best", str(scene_file.parent / "." / scene_file.name)]) == 2
    err = capsys.readouterr().err
    assert "--write-best" in err and "is the input file" in err
    with pytest.raises(ScenarioError, match="is the input file") as info:
        fitted.write_best(scene_file)
    assert info.value.field == "--write-best"
    assert scene_file.read_text() == before


def test_a_value_the_file_does_not_give_is_written_in_si():
    """A preset's value (not in the file) is written in SI, and then overrides the preset."""
    raw = car_car()
    t = resolve_path("vehicles.A.bodies[0].mass")
    out = set_value(raw, t, 1612.5, like=True)
    assert out["vehicles"]["A"]["bodies"][0]["mass"] == "1612.5 kg"
    assert "mass" not in raw["vehicles"]["A"]["bodies"][0]
    raw["vehicles"]["A"]["bodies"][0]["mass"] = "3300 lb"
    out = set_value(raw, t, 1612.5, like=True)
    written = out["vehicles"]["A"]["bodies"][0]["mass"]
    assert written.endswith(" lb") and parse(written, "mass", field="m") == pytest.approx(1612.5, rel=1e-15)


# --------------------------------------------------------------------------- the user's own file, edited in place
def test_best_fit_is_the_users_file_with_its_values_replaced(tmp_path):
    """Comments, order and layout kept; the survey a reference to its files (not the items it
    imports); an unknown of a survey-generated recorder item written at its [[survey.recorders]]
    entry; every path relative to the written file, which loads and runs from its own folder."""
    import shutil
    from pathlib import Path

    from crashsim.reconstruct.write_best import edit_best
    from crashsim.survey.mapping import load_scene_data

    root = Path(__file__).resolve().parents[2] / "scenarios" / "survey"
    case = tmp_path / "case"
    shutil.copytree(root / "files", case / "files")
    src = (root / "truck_brakes_survey.toml").read_text()
    anchor = 'initial = "0.75"\n'
    assert anchor in src
    src = src.replace(anchor, anchor + '\n# the recorder clock\n[[fit.unknowns]]\npath = "evidence.recorder[0].time_offset"\n'
                      'lower = "-1 s"\nupper = "1 s"\n', 1)
    scene = case / "scene.toml"
    scene.write_text(src)
    paths = ["evidence.recorder[0].time_offset", "vehicles.truck.approach.speed"]
    best = load_scene_data(scene)
    best = set_value(best, resolve_path(paths[0]), -0.3, like=True)
    best = set_value(best, resolve_path(paths[1]), 24.6, like=True)
    out = tmp_path / "handed_over" / "best.toml"
    out.parent.mkdir()
    text = edit_best(scene, out, best, paths, engine="compiled", header="# header\n", trailer="# trailer\n")
    out.write_text(text)
    written = load_toml(out)
    assert "fit" not in written and "imported" not in written["survey"]
    assert written["survey"]["recorders"][0]["time_offset"] == "-0.3 s"
    assert written["vehicles"]["truck"]["approach"]["speed"].endswith(" mph")
    assert written["survey"]["files"][0]["file"] == "../case/files/scene.dxf"
    assert written["survey"]["underlay"]["image"].startswith("../case/files/")
    # every line of the input but the changed ones, in order, comments included
    changed = ("time_offset", "speed = \"55 mph\"", "file = ", "image = ", "world_file = ", "engine = ")
    head, rest = src.split("\n[fit]\n", 1)
    tail = "[uncertainty]\n" + rest.split("\n[uncertainty]\n", 1)[1]  # the [fit] table goes
    kept = [ln for ln in (head + "\n" + tail).splitlines() if not any(c in ln for c in changed)]
    lines = text.splitlines()
    it = iter(lines)
    assert all(any(ln == w for w in it) for ln in kept), "a line of the input lost or moved"
    assert len(lines) < len(src.splitlines()) + 10  # no inlined survey (it was 2,137 lines)
    # it runs from its own folder, with the fitted values
    sc = simulate_approaches(load_scenario(out))
    (rec,) = sc.evidence.recorder
    assert rec.time_offset == pytest.approx(-0.3, abs=1e-12)
    assert sc.approaches["truck"].speed_at_braking == pytest.approx(24.6, rel=1e-12)

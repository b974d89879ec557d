"""The shipped survey scene runs from its survey, orthophoto and recorder files through every
command: run (its evidence within tolerance), plot (with the underlay), animate, fit, mc, export."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from crashsim.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENE = str(ROOT / "scenarios" / "survey" / "truck_brakes_survey.toml")
TYPED = str(ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml")


def test_run_matches_the_typed_scene(capsys):
    """The survey gives the typed scene's evidence: the rest positions, marks and point of impact
    check with the same residuals as the typed scene's to the report's 4 digits (the corners were
    written from the typed CGs and headings; the files hold them to 1e-4 ft)."""
    assert main(["run", SCENE, "--json", "--strict"]) == 0
    a = json.loads(capsys.readouterr().out)
    assert main(["run", TYPED, "--json"]) == 0
    b = json.loads(capsys.readouterr().out)
    ca = {(c["kind"], c["name"]): c for c in a["evidence"]["checks"]}
    cb = {(c["kind"], c["name"]): c for c in b["evidence"]["checks"]}
    pairs = [(("rest", "REST-TRACTOR A6"), ("rest", "rest of tractor")),
             (("rest", "CAR REST 106-109"), ("rest", "rest of car")),
             (("mark", "pre-impact skid, tractor/1/left"), ("mark", "pre-impact skid, tractor/1/left")),
             (("point of impact", "point of impact"), ("point of impact", "point of impact"))]
    for ka, kb in pairs:
        assert ca[ka]["residual"] == pytest.approx(cb[kb]["residual"], abs=1e-4), (ka, kb)
    assert a["runout"]["bodies"]["car"]["rest"] == b["runout"]["bodies"]["car"]["rest"]
    assert len(a["survey"]) > 20


@pytest.mark.slow
@pytest.mark.slow  # 5-21 s (tests/validation --durations, 2-core machine)
def test_plot_animate_fit_mc_export(tmp_path, capsys):
    assert main(["plot", SCENE, "-o", str(tmp_path / "s.png"), "--no-approach"]) == 0
    assert main(["animate", SCENE, "-o", str(tmp_path / "a.gif"), "--no-approach", "--dt", "0.5 s", "--dpi", "40"]) == 0
    assert main(["mc", SCENE, "--samples", "4", "--quiet", "--workers", "1", "--json",
                 "--plots", str(tmp_path / "mc")]) == 0
    capsys.readouterr()
    assert (tmp_path / "mc" / "mc_rest_clouds.png").is_file()
    assert main(["fit", SCENE, "--workers", "1", "--json"]) == 0
    fit = json.loads(capsys.readouterr().out)
    speed = next(u for u in fit["unknowns"] if u["path"] == "vehicles.truck.approach.speed")
    assert abs(speed["value"] - 55 * 0.44704) < 1.0 and fit["success"]  # the evidence was made at 55 mph
    assert main(["export", SCENE, "--dxf", str(tmp_path / "r.dxf"), "--geojson", str(tmp_path / "r.geojson")]) == 0
    for p in ("s.png", "a.gif", "r.dxf", "r.geojson"):
        assert (tmp_path / p).stat().st_size > 1000, p

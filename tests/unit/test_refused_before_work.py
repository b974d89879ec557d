"""Option values and output paths refused before any work (issue 31, item 5): one line, exit 2
(the refusals used to come after the scene was computed: 38-139 s).  No timing here: a test that
fails when the loading or the computing is called is what shows that nothing ran before the refusal.

In-process, the loading and computing are replaced by a function that fails the test; the paper
and scale check needs the scene loaded (the extent known before the run), not the run.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import crashsim.scene as scene
import crashsim.scenario as scenario
from crashsim import cli
from crashsim.cli import main

ROOT = Path(__file__).resolve().parents[2]
SCENE = str(ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml")


def _fail(*a, **k):
    raise AssertionError("work started before the options were checked")


@pytest.fixture
def no_work(monkeypatch):
    # where the command line takes them from when a command runs (it imports them inside the command)
    monkeypatch.setattr(cli, "_first_compile", _fail)
    monkeypatch.setattr(scenario, "load_scenario", _fail)
    monkeypatch.setattr(scene, "run_scene", _fail)


def _cases(tmp: Path) -> dict:
    return {
        "export-dxf-unwritable": (["export", SCENE, "--dxf", "/proc/x.dxf"], ["--dxf", "/proc"]),
        "export-dxf-missing-folder": (["export", SCENE, "--dxf", str(tmp / "no" / "x.dxf")], ["--dxf", "does not exist"]),
        "export-geojson-suffix": (["export", SCENE, "--geojson", str(tmp / "x.txt")], ["--geojson", "'.txt'"]),
        "export-times-parsecs": (["export", SCENE, "--dxf", str(tmp / "x.dxf"), "--times", "2 parsecs"],
                                 ["--times", "2 parsecs", "a length"]),
        "export-times-negative": (["export", SCENE, "--dxf", str(tmp / "x.dxf"), "--times", "-1 s"], ["--times", "> 0"]),
        "report-missing-folder": (["report", SCENE, "-o", str(tmp / "no" / "dir" / "r.html")], ["-o", "does not exist"]),
        "animate-speed-0": (["animate", SCENE, "-o", str(tmp / "a.gif"), "--speed", "0"], ["--speed", "> 0"]),
        "plot-interval-0": (["plot", SCENE, "-o", str(tmp / "p.png"), "--interval", "0 s"], ["--interval", "> 0"]),
        "plot-dpi-0": (["plot", SCENE, "-o", str(tmp / "p.png"), "--dpi", "0"], ["--dpi", ">= 1"]),
        "run-dt-negative": (["run", SCENE, "--csv", str(tmp / "c"), "--dt", "-0.1 s"], ["--dt", "> 0"]),
        "mc-samples-0": (["mc", SCENE, "--samples", "0"], ["--samples", ">= 1"]),
        "posterior-steps-0": (["posterior", SCENE, "--steps", "0"], ["--steps", ">= 1"]),
    }


@pytest.mark.parametrize("name", list(_cases(Path("/tmp"))))
def test_refused_before_loading(no_work, tmp_path, capsys, name):
    argv, words = _cases(tmp_path)[name]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    for w in words:
        assert w in err, (w, err)


def test_paper_and_scale_refused_before_the_run(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(scene, "run_scene", _fail)
    assert main(["plot", SCENE, "-o", str(tmp_path / "p.png"), "--paper", "A4", "--scale", "1:10"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--scale" in err and "1:10 is too large" in err, err
    assert not (tmp_path / "p.png").exists()


def test_an_approach_path_too_large_for_the_sheet_is_refused_before_the_run(monkeypatch, tmp_path, capsys):
    """The loader does not simulate, so the plot command runs the approaches before the sheet check
    (the scene run then uses them): at 1:225 on A4 the truck's braking approach leaves the sheet,
    though the vehicles at impact and the evidence alone would fit (checked here too)."""
    from crashsim.plotting import check_sheet
    from crashsim.scenario import load_scenario

    truck = str(ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml")
    check_sheet(load_scenario(truck), "A4", 225.0)  # without the approach's path: fits
    monkeypatch.setattr(scene, "run_scene", _fail)
    assert main(["plot", truck, "-o", str(tmp_path / "p.png"), "--paper", "A4", "--scale", "1:225"]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "--scale" in err and "1:225 is too large" in err, err
    assert not (tmp_path / "p.png").exists()


def test_the_sheet_check_is_a_lower_bound_of_the_figure():
    """What check_sheet passes the figure may still refuse, never the other way round: at the scale
    the figure needs, the pre-run check passes."""
    from crashsim.plotting import check_sheet
    from crashsim.scenario import load_scenario

    sc = load_scenario(SCENE)
    for n in (200.0, 500.0, 1000.0):
        check_sheet(sc, "A4", n)  # the intersection scene fits A4 from 1:200 on (its figure: tests/plotting)

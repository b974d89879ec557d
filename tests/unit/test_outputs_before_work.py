"""Every output path and worker count is checked before any work: one line on stderr, exit 2.

Each case runs the command with the loading, compiling and computing replaced by a function that
fails the test, so a check that came after any work would show here.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

import crashsim.cli as cli
import crashsim.scene as scene
import crashsim.scenario as scenario
from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.outputs import check_output_dir, check_output_file, check_workers

ROOT = Path(__file__).resolve().parents[2]
SCENE = str(ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml")
FIT = str(ROOT / "scenarios" / "fit" / "intersection_fit.toml")


@pytest.fixture
def no_work(monkeypatch):
    def refuse(*a, **k):
        raise AssertionError("work started before the outputs were checked")

    monkeypatch.setattr(cli, "_first_compile", refuse)
    monkeypatch.setattr(scenario, "load_scenario", refuse)
    monkeypatch.setattr(scene, "run_scene", refuse)


@pytest.fixture
def places(tmp_path):
    """A file, a path below that file (cannot exist), an existing folder."""
    f = tmp_path / "a_file.txt"
    f.write_text("keep me\n")
    d = tmp_path / "folder"
    d.mkdir()
    return {"file": f, "below_file": f / "sub" / "x.png", "dir": d, "missing": tmp_path / "no" / "such"}


def _refused(capsys, argv, *words):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1, err
    assert err.startswith("crashsim: input error: ")
    for w in words:
        assert w in err, (w, err)
    return err


def test_run_csv_onto_an_existing_file(no_work, places, capsys):
    _refused(capsys, ["run", SCENE, "--csv", str(places["file"])], "--csv", "is a file")
    assert places["file"].read_text() == "keep me\n"


def test_run_csv_below_a_file(no_work, places, capsys):
    _refused(capsys, ["run", SCENE, "--csv", str(places["below_file"])], "--csv", "is a file, not a folder")


@pytest.mark.parametrize("field", ["-o", "--histories", "--time-distance"])
def test_plot_outputs_unwritable(no_work, places, capsys, field):
    ok = str(places["dir"] / "scene.png")
    argv = ["plot", SCENE, "-o", ok]
    argv += [field, str(places["below_file"])] if field != "-o" else []
    if field == "-o":
        argv[3] = str(places["below_file"])
    _refused(capsys, argv, field, "not a folder")


def test_plot_output_with_a_format_matplotlib_cannot_write(no_work, places, capsys):
    _refused(capsys, ["plot", SCENE, "-o", str(places["dir"] / "scene.xyz")], "-o", "'.xyz'", ".png")


@pytest.mark.parametrize("option", ["-o", "--histories", "--time-distance", "--wheels"])
def test_plot_output_in_a_format_matplotlib_writes_but_the_figures_do_not(no_work, places, capsys, option):
    """.jpg: matplotlib can write it, the scene figures are not (png, svg, pdf); refused before the
    load, naming the option as written (it was refused after the run-out, as key 'path')."""
    argv = ["plot", SCENE, "-o", str(places["dir"] / "scene.png")]
    argv += [] if option == "-o" else [option, str(places["dir"] / "other.png")]
    argv[argv.index(option) + 1] = str(places["dir"] / "figure.jpg")
    _refused(capsys, argv, f"{option}: ", "'.jpg'", ".png, .svg, .pdf")


def test_plot_output_onto_a_folder(no_work, places, capsys):
    bad = places["dir"] / "x.png"
    bad.mkdir()
    _refused(capsys, ["plot", SCENE, "-o", str(bad)], "is a folder")


def test_animate_into_an_unwritable_place_fails_before_rendering(no_work, places, capsys):
    _refused(capsys, ["animate", SCENE, "-o", str(places["file"] / "scene.gif")], "-o", "not a folder")


def test_fit_write_best_into_a_missing_folder(no_work, places, capsys):
    _refused(capsys, ["fit", FIT, "--write-best", str(places["missing"] / "best.toml")], "--write-best",
             "does not exist")


def test_mc_out_onto_a_folder_and_plots_onto_a_file(no_work, places, capsys):
    _refused(capsys, ["mc", FIT, "--out", str(places["dir"])], "--out", "is a folder")
    _refused(capsys, ["mc", FIT, "--plots", str(places["file"])], "--plots", "is a file")


def test_posterior_chain_and_plots(no_work, places, capsys):
    _refused(capsys, ["posterior", FIT, "--chain", str(places["missing"] / "c.npz")], "--chain", "does not exist")
    _refused(capsys, ["posterior", FIT, "--plots", str(places["below_file"])], "--plots", "not a folder")


@pytest.mark.parametrize("command", ["fit", "mc", "posterior"])
@pytest.mark.parametrize("workers", ["0", "-1", "1.5", "many"])
def test_workers_must_be_at_least_one(no_work, capsys, command, workers):
    _refused(capsys, [command, FIT, "--workers", workers], "--workers", ">= 1", '"auto"')


def test_workers_auto_and_whole_numbers():
    assert check_workers("auto") is None and check_workers(None) is None and check_workers("AUTO") is None
    assert check_workers("3") == 3 and check_workers(2) == 2
    for bad in (0, -2, 1.5, "0", "x"):
        with pytest.raises(ScenarioError, match=">= 1"):
            check_workers(bad)


def test_library_refuses_zero_workers():
    import crashsim

    with pytest.raises(ScenarioError, match="workers"):
        crashsim.monte_carlo(FIT, samples=2, workers=0, progress=False)


@pytest.mark.skipif(os.name != "posix" or os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_folder(places, capsys):
    ro = places["dir"]
    ro.chmod(0o500)
    try:
        with pytest.raises(ScenarioError, match="cannot be written"):
            check_output_file(ro / "x.png", field="-o")
        with pytest.raises(ScenarioError, match="cannot be written"):
            check_output_dir(ro / "csv", field="--csv")
    finally:
        ro.chmod(0o700)


def test_writable_places_pass_and_leave_nothing_behind(places):
    existing = places["file"]
    before = (existing.read_text(), existing.stat().st_mtime_ns)
    assert check_output_file(existing, field="--out") == existing
    assert (existing.read_text(), existing.stat().st_mtime_ns) == before
    new = places["dir"] / "deeper" / "x.png"
    assert check_output_file(new, field="-o") == new
    assert not (places["dir"] / "deeper").exists() and list(places["dir"].iterdir()) == []
    assert check_output_dir(places["missing"], field="--csv") == places["missing"]
    assert not places["missing"].exists()
    with pytest.raises(ScenarioError, match="exists"):
        check_output_file(existing, field="--x", overwrite=False)

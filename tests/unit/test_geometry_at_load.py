"""Impossible geometry is refused at load: one line, exit 2, naming the key as written, the value
as written in the file, and the allowed range (issue 19's cases), while every shipped scene,
test scene and regression scene still loads."""

from __future__ import annotations

import glob
from pathlib import Path

import pytest

from crashsim.cli import main
from crashsim.errors import ScenarioError
from crashsim.scenario import DEFAULT_DRAWBAR, DEFAULT_OVERHANG, DEFAULT_OVERLAP, load_scenario

ROOT = Path(__file__).resolve().parents[2]
SIDE = ROOT / "scenarios" / "scenes" / "car_trailer_side_impact.toml"
INTERSECTION = ROOT / "scenarios" / "scenes" / "intersection_car_trailer_wheels.toml"


def _refused(tmp_path, capsys, text, *words):
    f = tmp_path / "scene.toml"
    f.write_text(text)
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err
    lines = [ln for ln in err.strip().splitlines() if not ln.startswith("crashsim: compil")]  # a first compile
    assert len(lines) == 1, err
    err = lines[0]
    assert err.startswith(f"crashsim: input error: {f}: ")
    for w in words:
        assert w in err, (w, err)
    assert "contact point" not in err  # not blamed on the impact's contact point
    return err


def test_ball_hitch_12_ft_behind_the_rear_bumper(tmp_path, capsys):
    # car-midsize: rear bumper 2.25 m behind the CG; 12 ft = 3.658 m further back
    text = SIDE.read_text().replace('rear_hitch = ["-2.55 m", "0 m"]', 'rear_hitch = ["-19.38 ft", "0 ft"]')
    _refused(tmp_path, capsys, text, "vehicles.towing.bodies[0].rear_hitch:", 'rear_hitch = ["-19.38 ft", "0 ft"]',
             "lies 12 ft outside", f"drawbar = {DEFAULT_DRAWBAR:g} m")  # in the unit written


def test_a_declared_drawbar_allows_a_long_one(tmp_path):
    text = SIDE.read_text().replace('rear_hitch = ["-2.55 m", "0 m"]', 'rear_hitch = ["-4.5 m", "0 m"]\ndrawbar = "2.5 m"')
    f = tmp_path / "long_drawbar.toml"
    f.write_text(text)
    load_scenario(f)


def test_trailer_axle_60_ft_behind_the_cg_of_a_24_ft_trailer(tmp_path, capsys):
    text = SIDE.read_text().replace('preset = "car-trailer"', 'preset = "car-trailer"\nlength = "24 ft"\n'
                                    'outline_center = ["0 ft", "0 ft"]\nfront_hitch = ["14 ft", "0 ft"]\n'
                                    'axles = [{ name = "axle", x = "-60 ft", track = "5.2 ft" }]')
    _refused(tmp_path, capsys, text, "vehicles.towing.bodies[1].axles[0].x:", 'x = "-60 ft"',
             "allowed [-18.56 ft, 18.56 ft] from the CG", "overhang = 2 m")


def test_12_ft_track_on_a_6_7_ft_wide_body(tmp_path, capsys):
    text = SIDE.read_text().replace('name = "striker"\npreset = "car-midsize"',
                                    'name = "striker"\npreset = "car-midsize"\nwidth = "6.7 ft"\n'
                                    'axles = [{ name = "front", x = "1.35 m", track = "12 ft" }, '
                                    '{ name = "rear", x = "-1.35 m", track = "1.55 m" }]')
    _refused(tmp_path, capsys, text, "vehicles.striking.bodies[0].axles[0].track:", 'track = "12 ft"',
             "wider than body 'striker' (width 6.7 ft)", "allowed a track <= 7.684 ft",
             "overhang = 0.15 m on each side")


def test_car_placed_on_top_of_the_trailer(tmp_path, capsys):
    # the car crosswise over the trailer, its contact point unchanged: 2.5 m deep along the normal
    text = INTERSECTION.read_text().replace('position = ["-9.6063 m", "-3.160 m"]', 'position = ["-9.6063 m", "0 m"]')
    _refused(tmp_path, capsys, text, "vehicles.B.position:", "'trailer' (vehicle 'A') and 'car' (vehicle 'B') overlap",
             "2.5 m deep along the impact normal", "impact.overlap_tolerance = 2 m")


def test_initial_articulation_beyond_its_limit(tmp_path, capsys):
    text = SIDE.read_text().replace('preset = "car-trailer"', 'preset = "car-trailer"\narticulation = "100 deg"')
    _refused(tmp_path, capsys, text, "vehicles.towing.bodies[1].articulation:", "articulation = 100 deg",
             "allowed [-90, 90] deg")


def test_overlap_tolerance_is_a_setting_of_the_file(tmp_path):
    text = INTERSECTION.read_text().replace('position = ["-9.6063 m", "-3.160 m"]', 'position = ["-9.6063 m", "0 m"]')
    text = text.replace("[impact]\n", '[impact]\noverlap_tolerance = "3 m"\n')
    f = tmp_path / "underride.toml"
    f.write_text(text)
    load_scenario(f)


def test_defaults_are_stated():
    assert DEFAULT_DRAWBAR == 1.5 and DEFAULT_OVERHANG == (2.0, 0.15) and DEFAULT_OVERLAP == 2.0


@pytest.mark.parametrize("path", sorted(glob.glob(str(ROOT / "scenarios" / "**" / "*.toml"), recursive=True)
                                        + glob.glob(str(ROOT / "tests" / "**" / "*.toml"), recursive=True)),
                         ids=lambda p: Path(p).name)
def test_every_shipped_and_test_scene_still_loads(path):
    load_scenario(path)

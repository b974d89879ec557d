"""[fit] and [uncertainty] are checked at load by every command (a path typo refused by `run`, not
only by `fit`), and a fit whose bounds exclude the file's own value says so."""

from __future__ import annotations

from pathlib import Path

import pytest

from crashsim.cli import main
from crashsim.reconstruct.fit import FitSpec
from crashsim.schema import load_toml

SCENE = Path(__file__).parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml"


@pytest.mark.parametrize("section, key", [("fit", "fit.unknowns[1].path"), ("uncertainty", "uncertainty.inputs[")])
@pytest.mark.parametrize("command", [["run"], ["plot", "-o", "{out}"]])
def test_a_path_typo_is_refused_by_a_command_that_does_not_use_the_section(tmp_path, capsys, section, key, command):
    text = SCENE.read_text(encoding="utf-8")
    start = text.index(f"[{section}]")
    assert 'path = "runout.road_friction"' in text[start:]
    f = tmp_path / "scene.toml"
    typo = text[start:].replace('path = "runout.road_friction"', 'path = "runout.road_fricton"', 1)
    f.write_text(text[:start] + typo, encoding="utf-8")
    out = tmp_path / "scene.png"
    code = main([command[0], str(f), *[c.format(out=out) for c in command[1:]]])
    err = capsys.readouterr().err
    assert code == 2
    assert "scene.toml" in err and key in err and "'runout.road_fricton'" in err
    assert "did you mean 'road_friction'" in err
    assert not out.exists()


def test_bounds_that_exclude_the_files_value_are_noted():
    data = load_toml(SCENE)
    assert data["runout"]["road_friction"] == 0.7
    (u,) = [u for u in data["fit"]["unknowns"] if u["path"] == "runout.road_friction"]
    assert not FitSpec.from_dict(data["fit"], data).notes  # 0.7 within [0.5, 0.9]
    u.update(lower="0.2", upper="0.4", initial="0.3")
    (note,) = FitSpec.from_dict(data["fit"], data).notes
    assert note.startswith("fit.unknowns[1]:") and "runout.road_friction = 0.7" in note and "[0.2, 0.4]" in note
    del u["initial"]  # the start is then the middle of the bounds, and the note the same
    spec = FitSpec.from_dict(data["fit"], data)
    assert spec.notes == (note,) and spec.unknowns[1].initial == pytest.approx(0.3)


def test_a_range_error_speaks_the_files_unit(tmp_path, capsys):
    """An [uncertainty] bound outside its input's range: the allowed range in SI and in the unit the
    file wrote the bound in (it gave kg alone to a file in lb)."""
    text = SCENE.read_text(encoding="utf-8")
    i = text.index("[[uncertainty.inputs]]")
    item = ('[[uncertainty.inputs]]\nname = "car mass"\npath = "vehicles.car.bodies[0].mass"\n'
            'distribution = "uniform"\nlower = "-100 lb"\nupper = "3500 lb"\n\n')
    f = tmp_path / "scene.toml"
    f.write_text(text[:i] + item + text[i:], encoding="utf-8")
    assert main(["run", str(f)]) == 2
    err = capsys.readouterr().err
    assert "uncertainty.inputs[0].lower" in err and "'-100 lb'" in err
    assert "(0, 250000] kg = (0, 551156] lb" in err

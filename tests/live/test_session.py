"""The live view's model: its inputs in the file's units, a recompute, an invalid change, the file saved."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import crashsim
from crashsim.errors import ScenarioError
from crashsim.live.session import LiveSession, canonical
from crashsim.live.view import result_payload
from crashsim.units import Kind


def test_inputs_are_the_files_own_values_in_its_units(scene_copy):
    s = LiveSession(scene_copy)
    c = s.controls
    assert c["vehicles.B.speed"].written == "13.41 m/s" and c["vehicles.B.speed"].unit == "m/s"
    assert c["vehicles.B.heading"].written == "90 deg"
    assert c["impact.restitution"].written == 0.05
    assert c["runout.road_friction"].written == 0.7
    assert c["impact.moment_restitution"].written == -1.0  # the schema's default: the file does not give it
    # a [fit] unknown's slider spans its [fit] bounds (15-45 mph)
    assert c["vehicles.A.speed"].lower == pytest.approx(15 * 0.44704) and c["vehicles.A.speed"].upper == pytest.approx(
        45 * 0.44704)


def test_a_value_in_another_unit_is_written_in_the_files_unit(scene_copy):
    s = LiveSession(scene_copy)
    text, si = s.read("vehicles.B.speed", "40 mph")
    assert text == "17.8816 m/s" and si == pytest.approx(17.8816)
    assert canonical(0.05, Kind.DIMENSIONLESS, "5 %") == "5 %"


def test_an_invalid_change_gives_the_files_error_and_keeps_the_last_result(scene_copy, tmp_path):
    s = LiveSession(scene_copy)
    good = s.apply({"vehicles.B.speed": "31 mph"})
    assert good["ok"]
    bad = s.apply({"impact.restitution": 1.5})
    assert not bad["ok"] and bad["values"]["impact.restitution"] == 0.05
    assert s.controls["vehicles.B.speed"].written == good["values"]["vehicles.B.speed"]
    assert s.payload["evidence"] == good["evidence"]  # the last good result is kept
    # the same line the command line prints for a file with that value
    f = tmp_path / "bad.toml"
    f.write_text(scene_copy.read_text().replace("restitution = 0.05", "restitution = 1.5"))
    err = subprocess.run([sys.executable, "-m", "crashsim", "run", str(f)], capture_output=True, text=True).stderr
    assert "impact.restitution" in bad["error"] and "allowed [0" in bad["error"]
    assert "impact.restitution" in err and "1.5" in err
    unit = s.apply({"vehicles.B.speed": "fast"})
    assert not unit["ok"] and 'write a speed such as "30 mph"' in unit["error"]


def test_a_change_changes_the_result(scene_copy):
    s = LiveSession(scene_copy)
    a = s.apply({})
    b = s.apply({"vehicles.B.speed": "40 mph"})
    car = lambda p: next(x for x in p["bodies"] if x["name"] == "car")  # noqa: E731
    assert car(a)["delta_v_si"] < car(b)["delta_v_si"]
    assert a["n_passed"] > b["n_passed"]
    assert a["poses"]["car"][-1] != b["poses"]["car"][-1]
    assert json.dumps(b)  # plain JSON


def test_saved_file_keeps_its_comments_and_runs_to_the_pages_numbers(scene_copy):
    before = scene_copy.read_text()
    s = LiveSession(scene_copy)
    page = s.apply({"vehicles.B.speed": "40 mph", "vehicles.B.position[0]": "-9.4 m", "impact.restitution": 0.1})
    s.save()
    after = scene_copy.read_text()
    comments = [ln for ln in before.splitlines() if ln.lstrip().startswith("#")]
    assert comments and all(ln in after.splitlines() for ln in comments)
    assert 'position = ["-9.4 m", "-3.160 m"]   # as scenarios/paper/table6.toml' in after
    assert 'speed = "17.8816 m/s"' in after and "restitution = 0.1" in after
    changed = [(a, b) for a, b in zip(before.splitlines(), after.splitlines()) if a != b]
    assert len(changed) == 3 and len(before.splitlines()) == len(after.splitlines())
    # crashsim run of the saved file (the file's own engine) prints the page's numbers
    again = result_payload(crashsim.run(scene_copy), s)
    assert [(c["residual"], c["passed"]) for c in again["evidence"]] == [(c["residual"], c["passed"])
                                                                         for c in page["evidence"]]
    assert [b["delta_v"] for b in again["bodies"]] == [b["delta_v"] for b in page["bodies"]]
    assert s.changed() == {}


def test_a_file_changed_on_disk_is_not_overwritten(scene_copy):
    s = LiveSession(scene_copy)
    s.apply({"vehicles.B.speed": "35 mph"})
    scene_copy.write_text(scene_copy.read_text() + "\n# edited elsewhere\n")
    with pytest.raises(ScenarioError, match="changed on disk"):
        s.save()
    assert scene_copy.read_text().endswith("# edited elsewhere\n")
    out = s.save("other.toml")
    assert out.endswith("other.toml") and 'speed = "15.6464 m/s"' in (scene_copy.parent / "other.toml").read_text()
    for name in ("../x.toml", "/tmp/x.toml", "x.txt", ".hidden.toml", "other.toml"):
        with pytest.raises(ScenarioError, match="save as"):
            s.save(name)
    s.reload()
    assert s.controls["vehicles.B.speed"].written == "13.41 m/s"


def test_the_band_draws_about_the_views_values(scene_copy):
    s = LiveSession(scene_copy)
    payload, rows = s.band_task(4)
    i = payload["paths"].index("vehicles.B.speed")
    s.apply({"vehicles.B.speed": "40 mph"})
    moved_payload, moved = s.band_task(4)
    shift = 17.8816 - 13.41
    k = moved_payload["paths"].index("vehicles.B.speed")
    assert [r[k] for r in moved] == pytest.approx([r[i] + shift for r in rows])
    assert "vehicles.A.position[0]" not in payload["paths"]  # the file's value: not written
    s.apply({"vehicles.A.position[0]": "0.5 m"})
    p2, moved = s.band_task(4)
    j = p2["paths"].index("vehicles.A.position[0]")  # not uncertain: the view's value in every sample
    assert {r[j] for r in moved} == {0.5}


def test_the_command_refuses_bad_input_before_serving(tmp_path, capsys):
    from crashsim.cli import main

    assert main(["live", str(tmp_path / "missing.toml"), "--no-browser"]) == 2
    assert "missing.toml" in capsys.readouterr().err
    for args, key in ((["--port", "70000"], "--port"), (["--band-samples", "-1"], "--band-samples"),
                      (["--workers", "0"], "--workers")):
        assert main(["live", str(tmp_path / "missing.toml"), "--no-browser", *args]) == 2
        assert key in capsys.readouterr().err
    bad = tmp_path / "bad.toml"
    bad.write_text((ROOT_SCENE := __import__("pathlib").Path(__file__).resolve().parents[2] / "scenarios" / "fit"
                    / "intersection_fit.toml").read_text().replace('speed = "13.41 m/s"', 'speed = "13.41 m"', 1))
    assert ROOT_SCENE.is_file()
    assert main(["live", str(bad), "--no-browser"]) == 2
    err = capsys.readouterr().err
    assert "bad.toml" in err and "vehicles.A.speed" in err and "13.41 m" in err


def test_a_notebook_shows_the_view_inline(scene_copy):
    from crashsim import open_live

    view = open_live(scene_copy, band_samples=0)
    try:
        html = view._repr_html_()
        assert "<iframe" in html and view.url in html and f"token={view.token}" in view.url
        assert view.url.startswith("http://127.0.0.1:")
    finally:
        view.stop()


def test_save_writes_only_what_changed_not_the_defaults_the_file_leaves_out(tmp_path):
    """A scene without moment_restitution (its default -1, no moment impulse): saving a changed
    restitution writes that one line, not the default the view's slider holds."""
    src = Path(__file__).parents[2] / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
    f = tmp_path / "scene.toml"
    before = src.read_text(encoding="utf-8")
    assert "moment_restitution" not in before
    f.write_text(before, encoding="utf-8")
    s = LiveSession(f)
    assert s.controls["impact.moment_restitution"].written == -1.0
    assert s.apply({"impact.restitution": 0.2})["ok"]
    assert s.changed() == {"impact.restitution": 0.2}
    s.save()
    after = f.read_text(encoding="utf-8")
    diff = [(a, b) for a, b in zip(before.splitlines(), after.splitlines()) if a != b]
    assert "moment_restitution" not in after and len(after.splitlines()) == len(before.splitlines())
    assert diff == [("restitution = 0.1", "restitution = 0.2")]

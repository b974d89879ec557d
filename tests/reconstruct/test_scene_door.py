"""The one door (crashsim.Scene, crashsim.reconstruct.inputs): a scene built once, its inputs varied by
name; the same result as the value written in the file, a record of the lean result, and the run-out's
scene model kept across the samples that share it."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

import crashsim
from crashsim.errors import ScenarioError
from crashsim.motion.result import jsonable
from crashsim.reconstruct.inputs import Scene
from crashsim.scene import models

from scenes import ENGINE

FILE = Path(__file__).resolve().parents[2] / "scenarios" / "fit" / "intersection_fit.toml"


def _json(result) -> str:
    return json.dumps(jsonable(result.to_dict()), sort_keys=True)


def test_a_value_by_name_is_the_value_written_in_the_file():
    sc = crashsim.load(FILE)
    scene = Scene(sc, engine=sc.runout.options.engine)  # the file's engine, as crashsim.run uses it
    inputs = scene.inputs(["vehicles.B.speed", "impact.restitution"])
    assert inputs.paths == ("vehicles.B.speed", "impact.restitution")
    got = inputs.run([12.0, 0.2])
    written = crashsim.run(FILE, vehicles__B__speed="12.0 m/s", impact__restitution=0.2)
    assert _json(got) == _json(written)
    assert _json(scene.run()) == _json(crashsim.run(FILE))  # no input varied: the file's scene


def test_a_record_reads_the_lean_result():
    inputs = Scene(crashsim.load(FILE), engine=ENGINE).inputs(["vehicles.A.speed"])
    seen = []

    def record(result):
        seen.append(result)
        return {name: tuple(b.rest_position) for r in result.runout.values() for name, b in r.bodies.items()}

    rest = inputs.run([13.0], record=record)
    full = inputs.run([13.0])
    assert rest == {name: tuple(b.rest_position) for r in full.runout.values() for name, b in r.bodies.items()}
    lean_tracks = sum(len(r.wheels) for r in seen[0].runout.values())
    assert lean_tracks < sum(len(r.wheels) for r in full.runout.values())  # the lean run keeps fewer tracks


def test_the_scene_model_is_built_once_for_the_samples_that_share_it(monkeypatch):
    built = []
    real = models.SceneModel

    def counting(*args, **kwargs):
        built.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(models, "SceneModel", counting)
    inputs = Scene(crashsim.load(FILE), engine=ENGINE).inputs(["vehicles.A.speed", "runout.road_friction"])
    for x in ([13.0, 0.7], [13.2, 0.7], [13.4, 0.65]):
        inputs.run(x, record=lambda r: None)
    assert inputs.patched and len(built) == 1  # speeds and the road friction share the first model
    other = Scene(crashsim.load(FILE), engine=ENGINE).inputs(["vehicles.A.speed"])
    other.run([13.0], record=lambda r: None)
    assert len(built) == 2  # another scene's inputs build their own


def test_a_path_the_file_cannot_hold_is_refused_naming_where_it_was_given():
    with pytest.raises(ScenarioError) as e:
        Scene(crashsim.load(FILE), engine=ENGINE).inputs(["vehicles.C.speed"], field="uncertainty.inputs")
    assert "uncertainty.inputs" in str(e.value) and "'C'" in str(e.value)

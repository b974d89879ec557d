"""The fast override path (:mod:`crashsim.reconstruct.patch`) gives the scenario of the full build.

Every supported path kind is compared with the full rebuild (``ScenarioOverrides(fast=False)``)
object by object, value for value (floats exactly), and by the scene it runs; unsupported paths
and invalid values fall back to the full build (same scenario, same error).
"""

from __future__ import annotations

import dataclasses
import json
import math
from pathlib import Path

import numpy as np
import pytest

from crashsim.errors import ScenarioError
from crashsim.reconstruct.overrides import ScenarioOverrides
from crashsim.reconstruct.patch import patch_kind
from crashsim.scene.run import run_scene, simulate_approaches
from crashsim.schema import load_toml

from scenes import ENGINE, car_car, car_trailer

ROOT = Path(__file__).resolve().parents[2]
SHIPPED = ROOT / "scenarios" / "fit" / "intersection_fit.toml"


def same(a, b, where="scenario") -> None:
    """Recursive equality: dataclasses field by field, arrays and floats exactly (NaN equal to NaN)."""
    if dataclasses.is_dataclass(a) and not isinstance(a, type):
        assert type(a) is type(b), where
        for f in dataclasses.fields(a):
            if f.name != "file_data":  # the full build's raw contents; a patched scenario has none
                same(getattr(a, f.name), getattr(b, f.name), f"{where}.{f.name}")
    elif isinstance(a, dict):
        assert isinstance(b, dict) and list(a) == list(b), where
        for k in a:
            same(a[k], b[k], f"{where}[{k!r}]")
    elif isinstance(a, (list, tuple)):
        assert type(a) is type(b) and len(a) == len(b), where
        for i, (x, y) in enumerate(zip(a, b)):
            same(x, y, f"{where}[{i}]")
    elif isinstance(a, np.ndarray):
        assert isinstance(b, np.ndarray) and a.shape == b.shape and a.dtype == b.dtype, where
        assert np.array_equal(a, b, equal_nan=a.dtype.kind == "f"), where
    elif isinstance(a, float) and math.isnan(a):
        assert isinstance(b, float) and math.isnan(b), where
    else:
        assert type(a) is type(b) and a == b, f"{where}: {a!r} != {b!r}"


def _pair(data, paths, file=None):
    fast = ScenarioOverrides(data, paths, engine=ENGINE, file=file, cache=1, max_wall_time=30.0)
    full = ScenarioOverrides(data, paths, engine=ENGINE, file=file, cache=1, max_wall_time=30.0, fast=False)
    return fast, full


SHIPPED_PATHS = ["vehicles.A.speed", "vehicles.B.speed", "impact.restitution", "runout.road_friction",
                 "impact.point[0]", "impact.point[1]", "impact.normal"]


@pytest.fixture(scope="module")
def shipped():
    import crashsim.scenario as sm
    from crashsim.inverse_schema import with_inverse_sections

    saved = sm.SCHEMA
    sm.SCHEMA = with_inverse_sections(saved)
    try:
        yield load_toml(SHIPPED)
    finally:
        sm.SCHEMA = saved


def test_every_kind_matches_the_full_build(shipped):
    """All supported kinds of the shipped fit scene at once, and each alone, at random values."""
    rng = np.random.default_rng(7)
    fast, full = _pair(shipped, SHIPPED_PATHS, file="intersection_fit.toml")
    base = np.array([13.41, 13.41, 0.05, 0.7, -2.517, -1.157, math.pi / 2])
    fast.scenario(base)  # the base of the fast path (built the full way)
    kinds = {patch_kind(t, fast._fast_base.data) for t in fast.targets}
    assert kinds == {"speed", "restitution", "road_friction", "point", "normal"}
    for k in range(6):
        x = base + rng.normal(0, 1, base.size) * np.array([1.5, 1.5, 0.03, 0.05, 0.1, 0.05, 0.02])
        a, b = fast.scenario(x), full.scenario(x)
        assert a.vehicles is fast._fast_base.vehicles  # patched, not rebuilt
        same(a, b)
    for j in range(len(base)):  # one path at a time (the others keep their base objects)
        x = base.copy()
        x[j] += 0.01
        same(fast.scenario(x), full.scenario(x))


def test_patched_scene_runs_identically(shipped):
    """The scene of a patched scenario: the same result dict as the full build's (every number, exactly)."""
    fast, full = _pair(shipped, SHIPPED_PATHS[:5])
    fast.scenario([13.41, 13.41, 0.05, 0.7, -2.517])
    x = [14.2, 12.9, 0.08, 0.74, -2.4]
    assert fast.scenario(x).vehicles is fast._fast_base.vehicles  # patched
    a, b = run_scene(fast.scenario(x)), run_scene(full.scenario(x))
    assert json.dumps(a.to_dict(), sort_keys=True) == json.dumps(b.to_dict(), sort_keys=True)


def test_tangential_law_value():
    """impact.friction (the scene's law is "friction") is patched; mu (another law's key) is not a fast kind."""
    data = car_car()
    fast, full = _pair(data, ["impact.friction", "vehicles.B.speed"])
    fast.scenario([0.5, 10.0])
    assert patch_kind(fast.targets[0], fast._fast_base.data) == "law"
    for x in ([0.3, 9.0], [0.62, 11.5]):
        a = fast.scenario(x)
        assert a.vehicles is fast._fast_base.vehicles  # patched, not rebuilt
        same(a, full.scenario(x))
    t_mu = ScenarioOverrides(car_car(), ["impact.mu"], fast=True).targets[0]
    assert patch_kind(t_mu, fast._fast_base.data) is None


def test_unsupported_path_falls_back():
    """A path the fast path does not handle (a body's mass, the heading) is built the full way."""
    data = car_trailer()
    paths = ["vehicles.towing.bodies[1].mass", "vehicles.striking.heading", "vehicles.striking.speed"]
    fast, full = _pair(data, paths)
    fast.scenario([700.0, math.pi / 2, 11.0])
    assert patch_kind(fast.targets[0], fast._fast_base.data) is None
    assert patch_kind(fast.targets[1], fast._fast_base.data) is None
    for x in ([650.0, 1.6, 10.5], [720.0, 1.55, 11.7]):
        a = fast.scenario(x)
        same(a, full.scenario(x))
        assert a.vehicles[0] is not fast._fast_base.vehicles[0]  # rebuilt, not patched


def test_invalid_values_give_the_full_build_error():
    """Out of range (a negative restitution) or inadmissible (a contact point off both outlines): the error
    of the full build."""
    data = car_trailer()
    paths = ["impact.restitution", "impact.point[1]"]
    fast, full = _pair(data, paths)
    fast.scenario([0.1, -0.9])
    for x in ([-0.2, -0.9], [0.1, -9.0], [float("nan"), -0.9]):
        with pytest.raises(ScenarioError) as e_fast:
            fast.scenario(x)
        with pytest.raises(ScenarioError) as e_full:
            full.scenario(x)
        assert str(e_fast.value) == str(e_full.value)


def test_unchanged_objects_keep_their_identity(shipped):
    """A speed or friction sample keeps the vehicles, wheels, contact and options objects (the run-out's
    compiled scene model is reused for them)."""
    fast, _ = _pair(shipped, ["vehicles.A.speed", "runout.road_friction"])
    base = fast.scenario([13.41, 0.7])
    sc = fast.scenario([12.0, 0.65])
    assert sc.vehicles is base.vehicles and sc.runout.wheels is base.runout.wheels
    assert sc.runout.options is base.runout.options and sc.runout.obstacles is base.runout.obstacles
    assert sc.runout.road.mu == 0.65 and base.runout.road.mu == 0.7


@pytest.mark.parametrize("name, paths", [
    # a [barrier] scene: speed and restitution are patched (the point of impact goes the full way, below)
    ("barrier_15deg.toml", ["vehicles.{v}.speed", "impact.restitution"]),
    # friction zones: the road friction is patched around the zones (the scene model keeps their arrays)
    ("verge_run_off.toml", ["runout.road_friction", "vehicles.{v}.speed"]),
    # a sloped road: the road friction is patched and the grade and cross-slope kept (they were lost)
    ("truck_downgrade_abs.toml", ["runout.road_friction", "vehicles.car.speed", "impact.restitution",
                                  "vehicles.truck.approach.speed"]),
])
def test_shipped_scenes_with_a_barrier_or_zones(name, paths):
    """The fast path on other shipped scenes: the same scenario and the same scene as the full build."""
    data = load_toml(ROOT / "scenarios" / "scenes" / name)
    vname = next(iter(data["vehicles"]))
    paths = [p.format(v=vname) for p in paths]
    fast, full = _pair(data, paths)
    x0 = np.array([fast.base_value(i) for i in range(len(paths))], dtype=float)
    fast.scenario(x0)
    assert None not in [patch_kind(t, fast._fast_base.data) for t in fast.targets]
    if fast._fast_base.data.get("barrier") is not None:  # the barrier's obstacle is built from the point
        from crashsim.reconstruct.overrides import resolve_path

        assert patch_kind(resolve_path("impact.point[0]"), fast._fast_base.data) is None
    for scale in (0.97, 1.04):
        x = x0 * scale
        a, b = fast.scenario(x), full.scenario(x)
        assert a.vehicles is fast._fast_base.vehicles  # patched
        same(a, b)
        ra, rb = run_scene(a), run_scene(b)
        assert json.dumps(ra.to_dict(), sort_keys=True) == json.dumps(rb.to_dict(), sort_keys=True)


def test_a_scene_with_an_approach():
    """The approach runs in the scene run: a sample's scenario carries the approach's inputs, and the speed at
    braking, the road friction (the approach runs on the run-out's road) and the impact's coefficients are
    patched into them (the approach ends at the impact positions, unchanged); the run simulates the approach.
    The same scenario and scene as the full build, and at the file's values the scene of the loaded file."""
    import crashsim

    path = ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml"
    data = load_toml(path)
    with_approach = [n for n, v in data["vehicles"].items() if "approach" in v]
    assert with_approach == ["truck"]
    paths = ["vehicles.truck.approach.speed", "runout.road_friction", "impact.restitution",
             "vehicles.truck.approach.reaction_time"]
    fast, full = _pair(data, paths)
    x0 = [fast.base_value(i) for i in range(len(paths))]
    base = fast.scenario(x0)
    assert base.approach_inputs and not base.approaches  # not simulated at load
    assert fast._variant is not None and fast._variant.patchable
    sc = crashsim.load(path)  # the loaded file, the run-out as fast's
    sc = dataclasses.replace(sc, path=None, runout=dataclasses.replace(sc.runout, options=base.runout.options))
    assert not sc.approaches and sc.approach_inputs == base.approach_inputs
    loaded = run_scene(sc)
    ran = run_scene(base)
    assert ran.scenario.approaches and ran.scenario.approaches_simulated
    assert json.dumps(ran.to_dict(), sort_keys=True) == json.dumps(loaded.to_dict(), sort_keys=True)
    # an approach simulated beforehand is the one the scene run uses (not run twice, the same scene)
    pre = simulate_approaches(sc)
    assert pre.approaches_simulated
    assert json.dumps(run_scene(pre).to_dict(), sort_keys=True) == json.dumps(loaded.to_dict(), sort_keys=True)
    for x in ([x0[0] * 1.03, x0[1], x0[2], x0[3]], [x0[0], 0.65, x0[2] + 0.02, x0[3] + 0.3],
              [x0[0] * 0.98, 0.72, x0[2], 0.0]):
        a, b = fast.scenario(x), full.scenario(x)
        assert a.vehicles is fast._fast_base.vehicles  # patched
        same(a, b)
        assert json.dumps(run_scene(a).to_dict(), sort_keys=True) == json.dumps(run_scene(b).to_dict(), sort_keys=True)
    from crashsim.reconstruct.overrides import resolve_path

    d = fast._fast_base.data
    # the file gives the speed at braking: the speed at impact follows from the approach (both given: an error)
    assert patch_kind(resolve_path("vehicles.truck.speed"), d) is None
    assert patch_kind(resolve_path("vehicles.truck.approach.speed"), d) == "approach_speed"
    assert patch_kind(resolve_path("runout.road_friction"), d) == "road_friction"
    assert patch_kind(resolve_path("vehicles.truck.approach.reaction_time"), d) == "approach_reaction_time"
    assert patch_kind(resolve_path("vehicles.truck.approach.distance"), d) is None


def test_an_approach_from_its_speed_at_impact():
    """A file that gives the speed at impact (the approach solves the speed at braking): that speed is patched
    into the approach's inputs and the placeholder states; the same scenario and scene as the full build."""
    data = load_toml(ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml")
    data["vehicles"]["truck"] = dict(data["vehicles"]["truck"], speed="40 mph")
    data["vehicles"]["truck"]["approach"] = {k: v for k, v in data["vehicles"]["truck"]["approach"].items()
                                             if k != "speed"}
    fast, full = _pair(data, ["vehicles.truck.speed"])
    x0 = fast.base_value(0)
    fast.scenario([x0])
    assert fast._variant is not None and fast._variant.kinds == ("approach_impact_speed",)
    for x in (x0 * 0.95, x0 * 1.05):
        a, b = fast.scenario([x]), full.scenario([x])
        assert a.vehicles is fast._fast_base.vehicles
        same(a, b)
        ra, rb = run_scene(a), run_scene(b)
        assert ra.scenario.approaches["truck"].speed_solved
        assert json.dumps(ra.to_dict(), sort_keys=True) == json.dumps(rb.to_dict(), sort_keys=True)


def replace_approaches(sc):
    """The scenario with its approaches as their result dicts (their dense solutions are functions)."""
    return dataclasses.replace(sc, approaches={k: a.to_dict() for k, a in sc.approaches.items()})


def test_scene_model_on_another_road_equals_a_new_model():
    """SceneModel.with_road (the kept model of crashsim.scene.models.ModelReuse on another road friction) holds
    the arrays of a model built from scratch on that road; another zone set is refused; a ModelReuse gives
    its model again only to a scene of the same model input objects."""
    from crashsim.motion.scene_model import SceneModel
    from crashsim.motion.road import Road
    from crashsim.scene import models

    data = load_toml(ROOT / "scenarios" / "scenes" / "verge_run_off.toml")
    sc = ScenarioOverrides(data, ["runout.road_friction"], engine=ENGINE).scenario([0.75])
    spec = sc.runout
    movable = [v for v in sc.vehicles if not v.is_barrier]
    kwargs = dict(contact=spec.contact, pair_contact=spec.pair_contact, obstacles=spec.obstacles)
    base = SceneModel(movable, spec.wheels, spec.road, spec.options, **kwargs)
    road = Road(0.55, spec.road.zones)
    moved, fresh = base.with_road(road), SceneModel(movable, spec.wheels, road, spec.options, **kwargs)
    assert moved.road is road and base.road is spec.road
    assert len(moved.M) == len(fresh.M)
    for a, b, c in zip(moved.M, fresh.M, base.M):
        assert a.dtype == b.dtype and np.array_equal(a, b)
    assert not all(np.array_equal(a, c) for a, c in zip(moved.M, base.M))  # the base model is unchanged
    with pytest.raises(ScenarioError):
        base.with_road(Road(0.55, ()))
    reuse = models.ModelReuse()
    m1 = models.scene_model(movable, spec, reuse)
    assert models.scene_model(movable, spec, reuse) is m1  # kept
    assert models.scene_model(movable, spec) is not m1  # without a ModelReuse: built for the run
    m2 = models.scene_model(movable, dataclasses.replace(spec, road=road), reuse)
    assert m2 is not m1 and m2.road is road and all(np.array_equal(a, b) for a, b in zip(m2.M, fresh.M))
    # other model inputs (equal values, other objects: a scenario built the full way) get a new model
    other = dataclasses.replace(spec, wheels=dataclasses.replace(spec.wheels) if dataclasses.is_dataclass(spec.wheels)
                                else dict(spec.wheels))
    m3 = models.scene_model(movable, other, reuse)
    assert m3 is not m1 and all(np.array_equal(a, b) for a, b in zip(m3.M, m1.M))


def _law(data, law, key, value):
    out = dict(data)
    out["impact"] = {k: v for k, v in data["impact"].items() if k not in ("mu", "mu_fraction", "friction")}
    out["impact"].update(tangential=law, **{key: value})
    return out


#: Every path kind the variant patches, on a scene that has it: (scene, path, values around the file's).
EVERY_PATH = [
    (car_car, "vehicles.A.speed", [9.0, 12.5]),
    (car_car, "vehicles.B.speed", [8.0, 11.0]),
    (car_trailer, "vehicles.striking.speed", [10.5, 12.0]),
    (car_trailer, "vehicles.towing.speed", [0.0, 3.0]),
    (car_car, "impact.restitution", [0.0, 0.35]),
    (car_trailer, "impact.restitution", [0.02, 1.0]),
    (car_car, "impact.friction", [0.0, 0.8]),
    (lambda: _law(car_car(), "ratio", "mu", -0.2), "impact.mu", [-0.05, -0.4]),
    (lambda: _law(car_car(), "fraction", "mu_fraction", 0.8), "impact.mu_fraction", [0.0, 1.0]),
    (car_car, "impact.normal", [1.5, 1.62]),
    (car_trailer, "impact.normal", [1.45, 1.7]),
    (car_car, "impact.point[0]", [-0.5, -0.3]),
    (car_car, "impact.point[1]", [-0.95, -0.85]),
    (car_trailer, "impact.point[0]", [-0.7, -0.2]),
    (car_trailer, "impact.point[1]", [-0.95, -0.8]),
    (car_car, "runout.road_friction", [0.4, 0.9]),
    (car_trailer, "runout.road_friction", [0.55, 1.1]),
]


@pytest.mark.parametrize("scene, path, values", EVERY_PATH, ids=[f"{s.__name__}:{p}" for s, p, _ in EVERY_PATH])
def test_every_path_through_the_variant(scene, path, values):
    """Each patchable path alone and beside a speed: the variant's scenario is the full build's, value for
    value, and its scene is the full build's, number for number."""
    from crashsim.reconstruct.variants import ScenarioVariant

    data = scene()
    speed = next(f"vehicles.{n}.speed" for n in data["vehicles"] if f"vehicles.{n}.speed" != path)
    for paths in ([path], [path, speed]):
        fast, full = _pair(data, paths)
        x0 = [fast.base_value(i) for i in range(len(paths))]
        fast.scenario(x0)
        variant = fast._variant
        assert isinstance(variant, ScenarioVariant) and variant.patchable, paths
        for v in values:
            x = [v, *x0[1:]]
            a, b = variant.scenario(x), full.scenario(x)
            assert a is not None and a.vehicles is fast._fast_base.vehicles
            same(a, b)
        a, b = variant.scenario([values[-1], *x0[1:]]), full.scenario([values[-1], *x0[1:]])
        assert json.dumps(run_scene(a).to_dict(), sort_keys=True) == json.dumps(run_scene(b).to_dict(), sort_keys=True)


@pytest.mark.parametrize("scene, path, bad", [
    (car_car, "impact.restitution", [1.01, -1e-9, math.inf]),
    (car_car, "vehicles.A.speed", [-1.0, math.nan]),
    (car_car, "runout.road_friction", [0.0, 2.5]),
    (car_car, "impact.friction", [-0.1]),
    (car_car, "impact.point[1]", [-4.0, 3.0]),
])
def test_the_variant_leaves_what_it_cannot_vouch_for_to_the_full_build(scene, path, bad):
    """Out of its field's range, not finite, or a contact point off the outlines: the variant gives None, and
    ScenarioOverrides raises the full build's error, text for text."""
    data = scene()
    fast, full = _pair(data, [path])
    fast.scenario([fast.base_value(0)])
    for x in bad:
        assert fast._variant.scenario([x]) is None
        with pytest.raises(ScenarioError) as e_fast:
            fast.scenario([x])
        with pytest.raises(ScenarioError) as e_full:
            full.scenario([x])
        assert str(e_fast.value) == str(e_full.value)


@pytest.mark.parametrize("path", ["vehicles.A.speed", "impact.restitution", "impact.point[0]", "impact.normal",
                                  "runout.road_friction", "impact.friction"])
def test_the_file_text_round_trip_is_the_identity(path):
    """The full build sees a sampled SI value as file text and back (``parse_value(format_value(x))``): for
    the SI units that is exactly x, so the variant, which uses x as given, builds the same floats."""
    from crashsim.reconstruct.overrides import format_value, parse_value, resolve_path

    t = resolve_path(path)
    rng = np.random.default_rng(3)
    xs = np.concatenate([rng.normal(size=2000) * 10.0 ** rng.integers(-9, 9, size=2000), rng.uniform(-8, 8, 2000),
                         [0.0, -0.0, 5e-324, 1.7976931348623157e308, 0.1, 1 / 3]])
    for x in xs.tolist():
        y = parse_value(format_value(x, t), t, field=path)
        assert y == x and math.copysign(1.0, y) == math.copysign(1.0, x), (path, x, y)

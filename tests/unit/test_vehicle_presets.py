"""The presets of the light vehicles, the rigid truck and what they tow (docs/vehicle-presets.md): each
loads, stands on its wheels (static axle and hitch loads positive, summing to the weight), has its
hitches where its source says, and runs out to rest in a short scene of its combination."""

from __future__ import annotations


import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

from crashsim.errors import ScenarioError
from crashsim.motion import static_loads
from crashsim.motion.rollover import default_rollover_threshold, static_stability_factor
from crashsim.scenario import preset_geometry, presets, scenario_from_dict
from crashsim.scene.run import run_scene
from crashsim.units import G0
from crashsim.vehicle_plan import plot_body_plan

NEW = ("suv-midsize", "pickup-fullsize", "van-fullsize", "rigid-truck", "full-trailer-24ft", "tanker-semitrailer",
       "travel-trailer", "caravan", "btrain-lead", "motorcycle")

#: Each new preset in the combination it is made for: (vehicle's presets front to rear, the new one's index).
COMBINATIONS = {
    "suv-midsize": (("suv-midsize",), 0),
    "pickup-fullsize": (("pickup-fullsize",), 0),
    "van-fullsize": (("van-fullsize",), 0),
    "rigid-truck": (("rigid-truck",), 0),
    "motorcycle": (("motorcycle",), 0),
    "travel-trailer": (("pickup-fullsize", "travel-trailer"), 1),
    "caravan": (("car-midsize", "caravan"), 1),
    "full-trailer-24ft": (("rigid-truck", "dolly-a", "full-trailer-24ft"), 2),
    "btrain-lead": (("tractor-3axle", "btrain-lead", "semitrailer-45ft"), 1),
    "tanker-semitrailer": (("tractor-3axle", "tanker-semitrailer"), 1),
}


def _front(name):
    g = preset_geometry(name)
    return g["outline_center"][0] + g["length"] / 2


def scene(chain, *, speed="15 m/s", striker="car-midsize", striker_speed="40 km/h", hitches=None):
    """The combination ``chain`` driving along x at ``speed``, struck square on its first body's right
    side, a quarter of its length ahead of its middle, by ``striker`` (tyres locked after the impact)."""
    g = preset_geometry(chain[0])
    x_hit = g["outline_center"][0] + g["length"] / 4
    bodies = [{"name": f"b{i}", "preset": p} for i, p in enumerate(chain)]
    if chain[0] == "car-midsize":  # the car preset has no tow ball: the car scenes' 0.3 m behind its bumper
        bodies[0]["rear_hitch"] = ["-2.55 m", "0 m"]
    return {"scenario": {"title": "preset combination"},
            "vehicles": {
                "A": {"position": ["0 m", "0 m"], "heading": "0 deg", "speed": speed, "bodies": bodies,
                      "tyres": {"state": "locked"}},
                "S": {"position": [f"{x_hit} m", f"{-g['width'] / 2 - _front(striker)} m"], "heading": "90 deg",
                      "speed": striker_speed, "bodies": [{"name": "striker", "preset": striker}],
                      "tyres": {"state": "locked"}}},
            "impact": {"body1": "b0", "body2": "striker", "point": [f"{x_hit} m", f"{-g['width'] / 2} m"],
                       "point_frame": "b0", "normal": "90 deg", "restitution": 0.1, "tangential": "friction",
                       "friction": 0.5},
            "runout": {"road_friction": 0.75}}


def test_every_preset_loads_with_a_source():
    library = presets()
    assert set(NEW) <= set(library)
    for name in library:
        g = preset_geometry(name)
        assert g["mass"] > 0 and g["yaw_inertia"] > 0 and g["axles"], name
        assert len(library[name]["source"]) > 40, name
    for name in NEW:  # every new set says which of its numbers are assumptions, and where it is documented
        assert "assumption" in library[name]["source"] and "docs/vehicle-presets.md" in library[name]["source"], name


@pytest.mark.parametrize("name", NEW)
def test_static_loads_are_positive_and_sum_to_the_weight(name):
    chain, k = COMBINATIONS[name]
    vehicle = scenario_from_dict(scene(chain)).vehicles[0]
    loads = static_loads(vehicle)
    masses = [b.mass for b in vehicle.bodies]
    assert loads.total == pytest.approx(sum(masses) * G0, rel=1e-12)
    for b in vehicle.bodies:
        assert np.all(loads.axle[b.name] > 0), (b.name, loads.axle[b.name])
    assert np.all(np.asarray(loads.hitch) > 0), loads.hitch
    # the preset's own share: its axles and the hitch it hangs on carry its weight (and what it carries behind)
    body = vehicle.bodies[k]
    behind = loads.hitch[k] if k < len(vehicle.hitches) else 0.0
    ahead = loads.hitch[k - 1] if k > 0 else 0.0
    assert loads.axle[body.name].sum() + ahead - behind == pytest.approx(body.mass * G0, rel=1e-12)


def _tongue_share(name):
    """Share of a single-unit trailer's weight on its coupling (moment balance about its axle group)."""
    g = preset_geometry(name)
    xa = sum(a["x"] for a in g["axles"]) / len(g["axles"])
    return -xa / (g["front_hitch"][0] - xa)


def test_bumper_pull_tongue_loads_are_the_stated_shares():
    assert _tongue_share("travel-trailer") == pytest.approx(0.120, abs=5e-4)  # source: 12.0 %, in 10-15 %
    assert 0.10 <= _tongue_share("travel-trailer") <= 0.15
    assert _tongue_share("caravan") == pytest.approx(0.069, abs=5e-4)  # source: 6.9 %, in 5-7 %
    assert 0.05 <= _tongue_share("caravan") <= 0.07
    caravan = preset_geometry("caravan")
    assert caravan["mass"] * _tongue_share("caravan") == pytest.approx(90, abs=1)  # the nose weight in kg


@pytest.mark.parametrize(("name", "behind_bumper"), [("suv-midsize", 0.30), ("pickup-fullsize", 0.25),
                                                     ("van-fullsize", 0.25), ("rigid-truck", 0.20)])
def test_tow_hitches_sit_behind_the_rear_bumper(name, behind_bumper):
    g = preset_geometry(name)
    rear = g["outline_center"][0] - g["length"] / 2
    assert rear - g["rear_hitch"][0] == pytest.approx(behind_bumper, abs=1e-9)
    assert g["rear_hitch"][1] == 0.0 and g["front_hitch"] is None


def test_light_vehicles_have_the_stated_front_axle_share_and_yaw_inertia():
    for name, front_share in (("suv-midsize", 0.55), ("pickup-fullsize", 0.57), ("van-fullsize", 0.55)):
        g = preset_geometry(name)
        a, b = g["axles"][0]["x"], -g["axles"][1]["x"]
        assert b / (a + b) == pytest.approx(front_share, abs=0.005), name
        assert g["yaw_inertia"] == pytest.approx(g["mass"] * a * b, abs=5), name  # m a b, to 10 kg m^2


def test_btrain_fifth_wheel_is_ahead_of_its_tandem_and_inside_the_deck():
    g = preset_geometry("btrain-lead")
    centre = sum(a["x"] for a in g["axles"]) / 2
    assert g["rear_hitch"][0] - centre == pytest.approx(0.30, abs=1e-9)
    assert g["front_hitch"][0] == pytest.approx(g["length"] / 2 - 0.914, abs=1e-9)
    assert g["outline_center"][0] - g["length"] / 2 < g["rear_hitch"][0]


def test_full_trailer_kingpin_rides_on_the_dolly():
    """Rigid truck -> dolly-a -> full trailer: the trailer's kingpin on the dolly's fifth wheel, the dolly's
    eye on the truck's pintle hook; the trailer's CG lies the two hitch offsets behind the dolly's."""
    sc = scenario_from_dict(scene(COMBINATIONS["full-trailer-24ft"][0]))
    truck, dolly, trailer = (sc.states[f"b{i}"] for i in range(3))
    assert dolly.position[0] == pytest.approx(-5.72 - 2.4, abs=1e-9)
    assert trailer.position[0] == pytest.approx(dolly.position[0] + 0.15 - 2.744, abs=1e-9)


def test_tanker_threshold_is_the_stated_one():
    sc = scenario_from_dict(scene(COMBINATIONS["tanker-semitrailer"][0]))
    tank = sc.vehicles[0].bodies[1]
    assert static_stability_factor(tank) == pytest.approx(0.451, abs=5e-4)
    assert default_rollover_threshold(tank) == pytest.approx(0.34, abs=5e-3)
    assert default_rollover_threshold(tank) < 0.40  # below the Canadian minimum for tank vehicles (the source)
    loaded = preset_geometry("semitrailer-loaded")
    assert tank.cg_height > loaded["cg_height"]


def test_motorcycle_is_a_narrow_track_and_a_zero_track_is_refused():
    g = preset_geometry("motorcycle")
    assert all(0 < a["track"] <= 0.10 for a in g["axles"]) and len(g["axles"]) == 2
    data = scene(("motorcycle",))
    data["vehicles"]["A"]["bodies"][0]["axles"] = [{"name": "front", "x": "0.77 m", "track": "0 m"},
                                                   {"name": "rear", "x": "-0.71 m", "track": "0.10 m"}]
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(data)
    assert "track" in str(err.value)


#: The combinations of the issue, each struck by a car (the motorcycle struck by one).
SCENES = {
    "suv+travel-trailer": ("suv-midsize", "travel-trailer"),
    "pickup+caravan": ("pickup-fullsize", "caravan"),
    "rigid-truck+dolly-a+full-trailer": ("rigid-truck", "dolly-a", "full-trailer-24ft"),
    "tractor+btrain-lead+semitrailer": ("tractor-3axle", "btrain-lead", "semitrailer-45ft"),
    "tractor+tanker": ("tractor-3axle", "tanker-semitrailer"),
    "motorcycle": ("motorcycle",),
}


@pytest.mark.parametrize("label", [pytest.param(k, marks=pytest.mark.slow) if k == "suv+travel-trailer" else k
                                   for k in SCENES])
def test_combination_runs_to_rest(label):
    chain = SCENES[label]
    speed = "10 m/s" if chain == ("motorcycle",) else "15 m/s"
    result = run_scene(scenario_from_dict(scene(chain, speed=speed))).to_dict()
    out = result["runout"]
    assert {v: r["status"] for v, r in out["vehicles"].items()} == {"A": "rest", "S": "rest"}
    assert set(out["bodies"]) == {*(f"b{i}" for i in range(len(chain))), "striker"}
    for name, b in out["bodies"].items():
        assert 0 < b["time_to_rest"] < 10, name
    e = out["energy_J"]
    assert abs(e["closing_error"]) <= 1e-6 * e["before_impact"], e
    # struck from its right, the combination's first body moves left (+y) of its path
    assert out["bodies"]["b0"]["rest"]["y"] > 0


@pytest.mark.parametrize("name", sorted(presets()))
def test_the_plan_of_every_preset_is_legible(name):
    """Every label inside the axes, and the tyres of one side of a short body apart (a motorcycle's)."""
    import matplotlib.pyplot as plt

    g = preset_geometry(name)
    ax = plot_body_plan(g)
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    for t in ax.texts:
        x, y = t.get_position()
        assert x0 < x < x1 and y0 < y < y1, (t.get_text(), (x, y), (x0, x1, y0, y1))
    width = next(t for t in ax.texts if t.get_text().startswith("width"))
    hitches = [g[k][0] for k in ("front_hitch", "rear_hitch") if g.get(k) is not None]
    assert all(width.get_position()[0] > x + 0.3 for x in hitches), name  # the label clear of a coupler's marker
    tyres = sorted((p for p in ax.patches if (p.get_gid() or "").startswith("tyre") and p.get_y() > 0),
                   key=lambda p: p.get_x())
    for rear, front in zip(tyres, tyres[1:]):
        assert rear.get_x() + rear.get_width() < front.get_x(), name
    for p in tyres:
        assert p.get_height() <= min(a["track"] for a in g["axles"]) + 1e-12
    plt.close(ax.figure)


def test_readme_and_docs_quote_the_presets():
    """The user guide's (docs/guide.md, the README's manual) and docs/vehicle-presets.md's numbers are the
    presets' (a changed preset fails here)."""
    from pathlib import Path

    root = Path(__file__).resolve().parents[2]
    readme = " ".join((root / "docs" / "guide.md").read_text(encoding="utf-8").split())
    tank = scenario_from_dict(scene(COMBINATIONS["tanker-semitrailer"][0])).vehicles[0].bodies[1]
    moto = preset_geometry("motorcycle")
    assert f"CG {tank.cg_height:.2f} m high, default rollover threshold {default_rollover_threshold(tank):.2f} g" in readme
    assert f"two wheels of {moto['axles'][0]['track']:.2f} m track" in readme
    for name in NEW:
        assert f"`{name}`" in readme, name
    rows = {line.split("|")[1].strip(" `"): line.split("|")[2:5]
            for line in (root / "docs" / "vehicle-presets.md").read_text(encoding="utf-8").splitlines()
            if line.startswith("| `")}
    assert set(rows) == set(NEW)
    for name, (mass, size, _axles) in rows.items():
        g = preset_geometry(name)
        assert float(mass.split()[0]) == g["mass"], name
        length, width = (float(v) for v in size.replace(" m", "").split(" x "))
        assert (length, width) == (pytest.approx(g["length"], abs=0.006), pytest.approx(g["width"], abs=0.006)), name

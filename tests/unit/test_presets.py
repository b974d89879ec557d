"""The vehicle library shows its geometry: ``crashsim presets`` lists it in the user's units, ``--plot``
draws a preset to scale, and the trailer presets in the usual lengths load in a scene."""

from __future__ import annotations

import math

import matplotlib
import pytest

matplotlib.use("Agg")

from crashsim.cli import main
from crashsim.scenario import preset_geometry, presets, scenario_from_dict
from crashsim.vehicle_plan import plot_body_plan

FT = 0.3048

#: Preset -> (length in ft, number of axles, rear overhang behind the last axle in ft): the published
#: sizes of docs/trailer-presets.md (23 CFR 658.13/658.15, AASHTO Green Book 2018 Table 2-4a).
TRAILERS = {"semitrailer-45ft": (45, 2, 4.5), "semitrailer-48ft": (48, 2, 4.5), "semitrailer-53ft": (53, 2, 4.5),
            "pup-28ft": (28, 1, 3.0)}


@pytest.mark.parametrize("name", sorted(TRAILERS))
def test_trailer_presets_have_the_published_sizes(name):
    g = preset_geometry(name)
    length_ft, n_axles, overhang_ft = TRAILERS[name]
    assert g["length"] == pytest.approx(length_ft * FT, abs=5e-4)
    assert g["width"] == pytest.approx(102 * 0.0254, abs=5e-4)
    assert len(g["axles"]) == n_axles
    rear = g["outline_center"][0] - g["length"] / 2
    assert min(a["x"] for a in g["axles"]) - rear == pytest.approx(overhang_ft * FT, abs=1e-3)  # two positions, each to the mm
    assert g["front_hitch"] is not None and g["rear_hitch"] is None
    # the yaw inertia of a uniform box, as the source says
    assert g["yaw_inertia"] == pytest.approx(g["mass"] * (g["length"] ** 2 + g["width"] ** 2) / 12, abs=50)  # rounded to 100 kg m^2
    assert "23 CFR 658" in presets()[name]["source"]


def test_the_48ft_kingpin_to_rear_axle_is_the_wb62s():
    g = preset_geometry("semitrailer-48ft")
    assert (g["front_hitch"][0] - min(a["x"] for a in g["axles"])) / FT == pytest.approx(40.5, abs=0.01)


def test_the_old_presets_keep_their_numbers():
    """The shipped scenes depend on them."""
    g = preset_geometry("semitrailer-loaded")
    assert (g["mass"], g["yaw_inertia"], g["length"], g["front_hitch"]) == (20000.0, 150000.0, 9.3, (3.991, 0.0))


def test_presets_list_geometry_in_us_units(capsys):
    assert main(["presets", "--units", "us"]) == 0
    out = capsys.readouterr().out
    block = out[out.index("semitrailer-53ft\n"):].split("\n    source")[0]
    assert "length 53 ft" in block and "width 8.5 ft," in block
    assert "axle 'axle 2': x -22 ft" in block and "track 6.07 ft, dual tyres" in block
    assert "front hitch (kingpin, drawbar eye): (23.5 ft, 0 ft)" in block
    assert "CG height 4.265 ft" in block and "articulation limit 90.0 deg" in block
    si = capsys.readouterr().out if main(["presets"]) == 0 else ""
    assert "length 16.15 m, width 2.591 m," in si


def test_plot_draws_the_preset_to_scale(tmp_path):
    g = preset_geometry("tractor-3axle")
    ax = plot_body_plan(g)
    outline = next(p for p in ax.patches if p.get_gid() == "outline")
    xy = outline.get_xy()
    assert xy[:, 0].max() - xy[:, 0].min() == pytest.approx(8.30)
    assert xy[:, 1].max() - xy[:, 1].min() == pytest.approx(2.50)
    tyres = [p for p in ax.patches if (p.get_gid() or "").startswith("tyre")]
    assert len(tyres) == 6
    hitch = next(line for line in ax.lines if line.get_gid() == "rear_hitch")
    assert tuple(hitch.get_xydata()[0]) == pytest.approx((-3.1, 0.0))
    lo, hi = ax.get_xlim()
    assert lo < -4.35 and hi > 3.75  # the whole outline in view
    out = tmp_path / "tractor.png"
    assert main(["presets", "--plot", "tractor-3axle", "-o", str(out)]) == 0
    assert out.stat().st_size > 10_000


def test_plot_needs_both_options_and_a_known_preset(tmp_path, capsys):
    assert main(["presets", "--plot", "tractor-3axle"]) == 2
    assert "-o FILE" in capsys.readouterr().err
    assert main(["presets", "--plot", "semitrailer-54ft", "-o", str(tmp_path / "x.png")]) == 2
    assert "did you mean 'semitrailer-53ft'" in capsys.readouterr().err


def test_a_53ft_trailer_loads_behind_the_tractor():
    data = {"scenario": {"title": "t"},
            "vehicles": {"A": {"position": ["0 m", "0 m"], "heading": "0 deg", "speed": "20 mph",
                               "bodies": [{"name": "tractor", "preset": "tractor-3axle"},
                                          {"name": "trailer", "preset": "semitrailer-53ft"}]}},
            "barrier": {"name": "wall"},
            "impact": {"body1": "tractor", "body2": "wall", "point": ["4.1 m", "0 m"], "normal": "180 deg",
                       "restitution": 0.1, "tangential": "no_slide"}}
    sc = scenario_from_dict(data)
    trailer = sc.states["trailer"]
    # kingpin on the fifth wheel: the trailer's CG 3.1 m + 7.163 m behind the tractor's
    assert trailer.position[0] == pytest.approx(-(3.1 + 7.163), abs=1e-9)
    assert math.isclose(sc.vehicles[0].bodies[1].length, 16.154)

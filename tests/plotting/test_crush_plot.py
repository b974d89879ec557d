"""The measured crush profile is drawn on the damaged face of the body at impact, to scale."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

matplotlib = pytest.importorskip("matplotlib")
matplotlib.use("Agg")

from crashsim.geometry import to_world  # noqa: E402
from crashsim.plotting import plot_scene  # noqa: E402
from crashsim.reconstruct import run_scene  # noqa: E402
from crashsim.evidence.crush import profile_outline  # noqa: E402
from crashsim.scenario import load_scenario, scenario_from_dict  # noqa: E402
from crashsim.schema import load_toml  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "tests" / "data" / "crush_head_on.toml"


def _patch(ax, gid):
    (p,) = [p for p in ax.patches if p.get_gid() == gid]
    return p.get_xy()


def test_front_profile_on_the_front_face_at_impact_to_scale():
    scene = run_scene(load_scenario(SCENE))
    ax = plot_scene(scene)
    xy = _patch(ax, "crush:carA:front")[:8]  # the polygon as drawn (matplotlib closes it: first point again)
    # car A: CG at the origin, heading 0, length 4.6 m: front face at x = 2.3 m; width 1.5 m centred
    assert np.allclose(xy[0], [2.3, 0.75]) and np.allclose(xy[1], [2.3, -0.75])
    # C6..C1 back from the right end to the left, each its depth behind the face
    assert np.allclose(2.3 - xy[2:, 0], [0.20, 0.30, 0.35, 0.30, 0.20, 0.10])
    assert np.allclose(xy[2:, 1], np.linspace(-0.75, 0.75, 6))
    assert not any(p.get_gid() == "crush:carB:front" for p in ax.patches)  # an EES item has no profile
    texts = [t.get_text() for leg in ax.figure.legends + ([ax.get_legend()] if ax.get_legend() else [])
             for t in leg.get_texts()]
    assert "measured crush (to scale)" in texts


@pytest.mark.parametrize("face, heading_deg, offset", [("left", 30.0, 0.4), ("rear", -120.0, -0.2),
                                                       ("right", 75.0, 0.0)])
def test_outline_follows_the_face_heading_and_offset(face, heading_deg, offset):
    sc = load_scenario(SCENE)
    body = next(b for v in sc.vehicles for b in v.bodies if b.name == "carA")
    it = dataclasses.replace(sc.evidence.crush[0], face=face, offset=offset, profile=(0.1, 0.3, 0.2, 0.0))
    poly = profile_outline(body, it)
    world = to_world(poly, (1.0, 2.0), math.radians(heading_deg))
    # the undeformed damage ends lie on the face, L apart, centred offset from the face centre
    assert np.hypot(*(world[0] - world[1])) == pytest.approx(1.5)
    centre = 0.5 * (poly[0] + poly[1])
    expect = {"left": (offset, 0.9), "right": (offset, -0.9), "rear": (-2.3, offset)}[face]
    assert np.allclose(centre, expect)
    # every crushed point lies its depth inside the face
    inward = -np.asarray(expect) / np.linalg.norm(expect) if face == "rear" else np.array([0.0, -np.sign(expect[1])])
    inward = np.array([1.0, 0.0]) if face == "rear" else inward
    face_pt = poly[0]
    depths = (poly[2:] - face_pt) @ inward
    assert np.allclose(sorted(depths), sorted([0.1, 0.3, 0.2, 0.0]))


def test_a_one_sided_crush_check_reads_as_a_bound():
    """A crush check with a body of the impact lacking a crush item is a lower bound (the report: "one-sided");
    the figure says so, with the bound it checks, not "PASS" beside a residual twice its tolerance."""
    data = load_toml(ROOT / "scenarios" / "scenes" / "truck_brakes_into_car.toml")
    data["evidence"]["crush"] = [c for c in data["evidence"]["crush"] if c["body"] == "car"]  # none for the tractor
    scene = run_scene(scenario_from_dict(data))
    (c,) = [c for c in scene.evidence.checks if c.kind == "crush energy"]
    assert c.passed and not c.details["complete"] and c.residual > 1.5 * c.tolerance  # passes as a bound only
    ax = plot_scene(scene, legend="outside")
    (text,) = [t.get_text() for t in ax.get_legend().get_texts() if t.get_text().startswith("crush energy")]
    head, bound, why = text.split("\n")
    assert head == "crush energy, first impact: PASS (one-sided bound)"
    assert "|model loss - crush|" not in text
    k = 1.0 / 1.3558179483314004  # J -> ft lbf
    loss, crush, tol = (float(s.replace(",", "")) for s in
                        bound.removeprefix("  model loss at least crush - tol.: ").removesuffix(" ft lbf")
                        .replace("\N{GREATER-THAN OR EQUAL TO}", "-").split(" - "))
    assert loss == pytest.approx(k * c.details["computed"], rel=5e-3)  # three significant digits
    assert crush == pytest.approx(k * c.details["measured"], rel=5e-3)
    assert tol == pytest.approx(k * c.tolerance, rel=5e-3)
    assert "tractor" in why and "lower bound" in why

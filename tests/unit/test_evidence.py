"""Evidence residuals and verdicts (reconstruct/evidence.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.evidence.checks import (Check, EvidenceReport, _densify, wheel_matches, distance_to_polyline)


def test_distance_to_polyline_known_values():
    line = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    pts = np.array([[5.0, 3.0], [-4.0, 3.0], [12.0, 5.0], [10.0, 11.0]])
    d = distance_to_polyline(pts, line)
    assert d == pytest.approx([3.0, 5.0, 2.0, 1.0], abs=1e-12)


def test_distance_to_single_point_polyline():
    assert distance_to_polyline([[3.0, 4.0]], [[0.0, 0.0]])[0] == pytest.approx(5.0)


def test_densify_keeps_ends_and_spacing():
    pts = _densify(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 0.35]]), 0.1)
    assert pts[0] == pytest.approx([0, 0]) and pts[-1] == pytest.approx([1.0, 0.35])
    steps = np.hypot(*np.diff(pts, axis=0).T)
    assert np.all(steps <= 0.1 + 1e-12)


class _Track:
    body, axle_index, axle_name, side = "trailer", 1, "axle 2", "right"


@pytest.mark.parametrize("sel,ok", [("*", True), (None, True), ("trailer", True), ("tractor", False),
                                     ("trailer/1", True), ("trailer/axle 2", True), ("trailer/0", False),
                                     ("trailer/1/right", True), ("trailer/1/left", False)])
def test_wheel_selector(sel, ok):
    assert wheel_matches(_Track(), sel) is ok


def test_report_counts_failures():
    rep = EvidenceReport((Check("rest", "a", 0.1, 0.5, True, "length"), Check("mark", "b", math.inf, 0.3, False, "length")))
    assert not rep.all_passed and rep.n_failed == 1
    d = rep.to_dict()
    assert d["n_checks"] == 2 and d["checks"][1]["passed"] is False


def test_bbox_bound_is_a_lower_bound():
    from crashsim.evidence.checks import _bbox_lower_bound

    rng = np.random.default_rng(3)
    for _ in range(50):
        line = rng.normal(size=(20, 2)) * 5
        pts = rng.normal(size=(15, 2)) * 8
        exact = float(np.max(distance_to_polyline(pts, line)))
        assert _bbox_lower_bound(pts, line.min(0), line.max(0)) <= exact + 1e-12


def test_tensile_normal_impulse_is_refused():
    """A sideswipe (0.5 m/s into a wall, 10 m/s along it, contact at the rear-left corner) with
    no sliding at separation needs a pulling normal impulse (found by the property tests): it is
    refused, naming the tangential law; with the check off the result warns; the front-corner
    case is compressive and passes."""
    from crashsim import Body, BodyState, CrushSurface, ImpactProblem, TangentialLaw, Vehicle, solve_impact
    from crashsim.errors import InadmissibleImpactError

    car = Vehicle("A", (Body("car", 1500.0, 2800.0),))
    wall = Vehicle("W", (Body("wall", math.inf, math.inf),))

    def solve(cx, check=True):
        st = {"car": BodyState((0.0, 0.0), 0.0, (10.0, 0.5)), "wall": BodyState((cx, 0.9), 0.0, (0.0, 0.0))}
        return solve_impact(ImpactProblem((car, wall), st, "car", "wall",
                                          CrushSurface((cx, 0.9), -math.pi / 2, 0.0, TangentialLaw("no_slide"), -1.0, 1)),
                            check=check)

    with pytest.raises(InadmissibleImpactError, match="tensile") as err:
        solve(-2.0)
    assert err.value.field == "impact.tangential" and err.value.reason == "tensile normal impulse"
    # the no-slide law is what pulls here (mu = 0 is compressive), so the message offers the laws that slide
    assert 'use tangential = "friction" or "ratio"' in str(err.value) and "even without" not in str(err.value)
    rear, front = solve(-2.0, check=False), solve(2.0)
    assert rear.normal_impulse < 0 and any("tensile" in w for w in rear.warnings)
    assert front.normal_impulse > 0 and not front.warnings
    assert rear.to_dict()["warnings"] == list(rear.warnings)


def test_signed_distance_sides():
    from crashsim.evidence.checks import signed_distance_to_polyline

    line = np.array([[0.0, 0.0], [10.0, 0.0]])
    d = signed_distance_to_polyline(np.array([[5.0, 2.0], [5.0, -3.0]]), line)
    assert d == pytest.approx([2.0, -3.0])

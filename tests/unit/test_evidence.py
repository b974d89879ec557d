"""Evidence residuals and verdicts (reconstruct/evidence.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.reconstruct.evidence import (Check, EvidenceReport, _densify, _wheel_matches, distance_to_polyline)


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
    assert _wheel_matches(_Track(), sel) is ok


def test_report_counts_failures():
    rep = EvidenceReport((Check("rest", "a", 0.1, 0.5, True, "length"), Check("mark", "b", math.inf, 0.3, False, "length")))
    assert not rep.all_passed and rep.n_failed == 1
    d = rep.to_dict()
    assert d["n_checks"] == 2 and d["checks"][1]["passed"] is False

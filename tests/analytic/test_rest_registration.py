"""Rest pose from measured points of a body: the planar rigid least-squares fit (Kabsch/Procrustes).

Closed forms checked here:

* exact data: the body's corners moved by a known rigid motion (CG ``c``, heading ``psi``)
  give back ``c`` and ``psi`` to rounding, with zero misfit;
* noisy data: the fit is the least-squares one. Its optimality conditions are known in
  closed form: the misfits sum to zero (translation) and their moment about the fitted
  centroid is zero (rotation), and a general-purpose minimiser of the same sum of squares
  finds the same pose.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import minimize

from crashsim.geometry import rotate
from crashsim.evidence.checks import named_body_points, register_points
from crashsim.vehicles import Axle, Body

BODY = Body("van", 2500.0, 4500.0, length=5.4, width=2.0, outline_center=(0.35, 0.05),
            axles=(Axle(1.6, 1.7), Axle(-1.9, 1.72, name="rear")))


@pytest.mark.parametrize("psi_deg", [0.0, 37.0, -125.0, 179.9, 90.0])
def test_exact_pose_from_the_four_corners(psi_deg):
    psi = math.radians(psi_deg)
    c = np.array([12.3, -4.7])
    named = named_body_points(BODY)
    names = ["front_left", "front_right", "rear_left", "rear_right"]
    body = np.array([named[n] for n in names])
    # corners in closed form: outline centre +- half length / half width
    cx, cy = BODY.outline_center
    assert np.allclose(body, [[cx + 2.7, cy + 1.0], [cx + 2.7, cy - 1.0], [cx - 2.7, cy + 1.0], [cx - 2.7, cy - 1.0]])
    measured = c + rotate(body, psi)
    r = register_points(body, measured, names)
    assert r.position == pytest.approx(tuple(c), abs=1e-12)
    assert math.remainder(r.heading - psi, 2 * math.pi) == pytest.approx(0.0, abs=1e-13)
    assert r.rms < 1e-12 and np.all(r.misfit < 1e-12)
    assert r.labels == tuple(names)


def test_two_tyre_contacts_fix_the_pose():
    """Two points are the minimum; tyre contacts sit at (axle x, +-track/2), by index or name."""
    named = named_body_points(BODY)
    assert named["axle1/left"] == (1.6, 0.85) and named["axle2/right"] == (-1.9, -0.86)
    assert named["rear/right"] == named["axle2/right"]
    psi, c = math.radians(-63.0), np.array([-3.0, 8.0])
    body = np.array([named["axle1/left"], named["rear/right"]])
    r = register_points(body, c + rotate(body, psi))
    assert r.position == pytest.approx(tuple(c), abs=1e-12)
    assert r.heading == pytest.approx(psi, abs=1e-13)


def test_with_noise_the_fit_is_the_least_squares_one():
    rng = np.random.default_rng(4)
    named = named_body_points(BODY)
    names = ["front_left", "front_right", "rear_left", "rear_right", "axle1/left", "rear/right"]
    body = np.array([named[n] for n in names])
    psi, c = math.radians(-25.0), np.array([-7.3, -0.7])
    measured = c + rotate(body, psi) + rng.normal(0.0, 0.05, body.shape)
    r = register_points(body, measured)

    def sse(p):
        return float(np.sum((measured - (p[:2] + rotate(body, p[2]))) ** 2))

    # optimality in closed form: misfit vectors sum to zero, and have no moment about the centroid
    fitted = np.asarray(r.position) + rotate(body, r.heading)
    e = measured - fitted
    assert np.allclose(e.sum(axis=0), 0.0, atol=1e-12)
    arm = fitted - fitted.mean(axis=0)
    assert abs(float(np.sum(arm[:, 0] * e[:, 1] - arm[:, 1] * e[:, 0]))) < 1e-12
    # the same minimum as a general-purpose minimiser from a start some way off
    best = minimize(sse, x0=[c[0] + 0.5, c[1] - 0.4, psi + 0.2], method="Nelder-Mead",
                    options={"xatol": 1e-10, "fatol": 1e-14, "maxiter": 20000})
    assert best.x[:2] == pytest.approx(r.position, abs=1e-7)
    assert best.x[2] == pytest.approx(r.heading, abs=1e-7)
    p = np.array([*r.position, r.heading])
    for k, h in ((0, 1e-3), (1, 1e-3), (2, 1e-4)):
        for sign in (1, -1):
            q = p.copy()
            q[k] += sign * h
            assert sse(q) > sse(p)
    assert r.rms == pytest.approx(math.sqrt(sse(p) / len(body)), rel=1e-12)
    assert np.allclose(r.misfit, np.hypot(*e.T))
    # the noise moves the pose a little, as it should
    assert 0 < np.hypot(*(np.asarray(r.position) - c)) < 0.1


def test_coincident_or_too_few_points_fix_no_heading():
    with pytest.raises(ValueError, match="at least two"):
        register_points([[0.0, 0.0]], [[1.0, 1.0]])
    with pytest.raises(ValueError, match="measured points coincide"):
        register_points([[1.0, 0.0], [-1.0, 0.0]], [[3.0, 3.0], [3.0, 3.0]])
    with pytest.raises(ValueError, match="body points coincide"):
        register_points([[1.0, 0.0], [1.0, 0.0]], [[3.0, 3.0], [5.0, 3.0]])

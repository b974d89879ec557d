"""Road grade and cross-slope: locked slides against the closed forms of a block on an incline.

On a grade theta (``tan theta`` = rise over run) a body sliding on locked wheels straight up
(+) or down (-) the fall line decelerates at ``a = g (f cos theta +- sin theta)``, so
``v^2 = 2 g d (f cos theta +- sin theta)`` (note on post-impact dynamics, sec. 5 item 1).  The
integrated engines are compared with the closed form of the *regularised* model (Coulomb
friction ``f N v / sqrt(v^2 + eps^2)`` stopped at ``v_stop``; the gravity part is not
regularised), integrated by quadrature, to ``GLOBAL * rtol``; and with the ideal closed form
within the low-speed bound ``v_stop^2 / (2 a)`` plus the regularisation's effect.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from runout_cases import GLOBAL, G, car, tractor_semitrailer
from scipy.integrate import quad

from crashsim.errors import ScenarioError
from crashsim.motion import FrictionZone, Road, RunoutOptions, simulate_runout
from crashsim.motion.levels import simulate_level
from crashsim.motion.road import slope_gravity
from crashsim.vehicles import BodyState, chain_states


def regularised_slope_slide(v0, v_end, eps, fg, gs):
    """Distance and time of a slide with ``a(v) = fg v / sqrt(v^2 + eps^2) + gs`` from v0 to v_end (quadrature)."""
    def a(v):
        return fg * v / math.hypot(v, eps) + gs
    d = quad(lambda v: v / a(v), v_end, v0, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    t = quad(lambda v: 1.0 / a(v), v_end, v0, epsabs=0.0, epsrel=1e-13, limit=200)[0]
    return d, t


def test_slope_gravity_is_the_incline_decomposition():
    theta = math.atan(0.12)
    ax, ay, n = slope_gravity(0.12, 0.0)
    assert ax == pytest.approx(-G * math.sin(theta), rel=1e-15) and ay == 0.0
    assert n == pytest.approx(math.cos(theta), rel=1e-15)
    ax, ay, n = slope_gravity(0.0, -0.08)
    assert ax == 0.0 and ay == pytest.approx(G * math.sin(math.atan(0.08)), rel=1e-15)
    # both: in-plane and normal parts make up g (the in-plane basis is orthonormal)
    ax, ay, n = slope_gravity(0.2, 0.1)
    assert math.hypot(ax, ay, G * n) == pytest.approx(G, rel=1e-14)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
@pytest.mark.parametrize("grade", [0.10, -0.10, 0.30, -0.25])
def test_locked_slide_on_a_grade(engine, grade):
    v0, mu = 20.0, 0.7
    opts = RunoutOptions(engine=engine, rtol=1e-9, atol=1e-11)
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None, Road(mu, grade=grade), opts)
    assert res.status == "rest" and res.success
    theta = math.atan(grade)
    fg, gs = mu * G * math.cos(theta), G * math.sin(theta)
    body = res.bodies["car"]
    d_reg, t_reg = regularised_slope_slide(v0, opts.v_stop, opts.eps, fg, gs)
    assert body.rest_position[0] == pytest.approx(d_reg, abs=GLOBAL * opts.rtol * d_reg)
    assert body.time_to_rest == pytest.approx(t_reg, abs=GLOBAL * opts.rtol * t_reg + 1e-9)
    assert abs(body.rest_position[1]) < 1e-9 and abs(body.rest_heading) < 1e-9
    # the ideal v^2 = 2 g d (f cos theta + sin theta), within the low-speed bound
    a = fg + gs
    d_ideal = v0 ** 2 / (2 * a)
    # (on a downgrade the regularised friction falls below gravity's pull under a creep speed
    # eps |sin| / sqrt(f^2 cos^2 - sin^2), far below v_stop: its effect is measured above v_stop)
    eps_effect = abs(d_reg - (v0 ** 2 - opts.v_stop ** 2) / (2 * a))
    bound = opts.v_stop ** 2 / (2 * a) + eps_effect + GLOBAL * opts.rtol * d_ideal
    assert abs(body.rest_position[0] - d_ideal) <= bound
    # the energy balance closes with the gravity's work m g sin(theta) d (negative uphill)
    assert res.gravity_work == pytest.approx(-1500.0 * gs * body.rest_position[0], rel=1e-12)
    assert abs(res.energy_residual) < GLOBAL * opts.rtol
    # the wheel loads follow the slope: sum N = m g cos theta
    loads = sum(track.load[0] for track in res.wheels.values())
    assert loads == pytest.approx(1500.0 * G * math.cos(theta), rel=1e-12)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_block_sliding_down_a_cross_slope(engine):
    """Heading along x, sliding sideways down the fall line (-y): pure translation, a = g (f cos phi - sin phi)."""
    v0, mu, cross = 8.0, 0.7, 0.08
    opts = RunoutOptions(engine=engine, rtol=1e-9, atol=1e-11)
    res = simulate_runout(car(), {"car": BodyState((0.0, 0.0), 0.0, (0.0, -v0))}, None,
                          Road(mu, cross_slope=cross), opts)
    assert res.status == "rest"
    phi = math.atan(cross)
    fg, gs = mu * G * math.cos(phi), -G * math.sin(phi)
    d_reg, _ = regularised_slope_slide(v0, opts.v_stop, opts.eps, fg, gs)
    body = res.bodies["car"]
    assert -body.rest_position[1] == pytest.approx(d_reg, abs=GLOBAL * opts.rtol * d_reg)
    # the static loads balance about the CG and the friction forces are proportional to them: no yaw
    assert abs(body.rest_position[0]) < 1e-9 and abs(body.rest_heading) < 1e-9


def test_energy_level_on_a_grade_is_exact():
    v0, mu, grade = 20.0, 0.7, -0.12
    res = simulate_level("energy", car(), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None,
                         Road(mu, grade=grade))
    theta = math.atan(grade)
    d = v0 ** 2 / (2 * G * (mu * math.cos(theta) + math.sin(theta)))
    assert res.bodies["car"].rest_position[0] == pytest.approx(d, rel=1e-12)
    assert abs(res.energy_residual) < 1e-12


def test_zone_slope_overrides_the_road_and_both_engines_agree():
    """A downgrade zone on a level road: the slide ends farther than on the level, the engines agree."""
    v0, mu = 25.0, 0.7
    zone = FrictionZone(((10.0, -20.0), (200.0, -20.0), (200.0, 20.0), (10.0, 20.0)), mu, "ramp", grade=-0.08)
    rest = {}
    for engine in ("scipy", "compiled"):
        opts = RunoutOptions(engine=engine, rtol=1e-9, atol=1e-11)
        res = simulate_runout(tractor_semitrailer(), _straight(tractor_semitrailer(), v0), None,
                              Road(mu, (zone,)), opts)
        assert res.status == "rest"
        rest[engine] = np.array([b.rest_position for b in res.bodies.values()])
        # the gravity's work summed on the samples across the zone edge: the balance closes to the sampling
        assert abs(res.energy_residual) < 2e-3
    level = simulate_runout(tractor_semitrailer(), _straight(tractor_semitrailer(), v0), None, Road(mu),
                            RunoutOptions(rtol=1e-9, atol=1e-11))
    level_rest = np.array([b.rest_position for b in level.bodies.values()])
    assert np.all(rest["scipy"][:, 0] > level_rest[:, 0] + 1.0)
    assert np.max(np.abs(rest["scipy"] - rest["compiled"])) < 1e-5


def _straight(vehicle, v0):
    return chain_states(vehicle, (0.0, 0.0), 0.0, (v0, 0.0))


@pytest.mark.parametrize("kwargs", [dict(grade=0.31), dict(cross_slope=-0.5)])
def test_slope_beyond_30_percent_is_refused(kwargs):
    with pytest.raises(ScenarioError, match="30 %"):
        Road(0.7, **kwargs)


@pytest.mark.parametrize("engine", ["scipy", "compiled"])
def test_load_transfer_on_a_grade_follows_the_tyre_forces_only(engine):
    """Locked slide up a 10 % grade with load transfer: the axle loads shift by m f g cos(theta) h / L.

    Gravity acts at the CG, so only the tyre forces' share of the acceleration moves load (the
    deceleration g (f cos + sin) less gravity's g sin): the front axle carries
    ``m g cos(theta) b / L + m f g cos(theta) h / L``; the slide's length is that of the static loads.
    """
    v0, mu, grade, h = 20.0, 0.7, 0.10, 0.55
    opts = RunoutOptions(engine=engine, rtol=1e-9, atol=1e-11, load_transfer=True)
    res = simulate_runout(car(cg_height=h), {"car": BodyState((0.0, 0.0), 0.0, (v0, 0.0))}, None,
                          Road(mu, grade=grade), opts)
    cos = math.cos(math.atan(grade))
    front = res.wheels["car/0/left"].load + res.wheels["car/0/right"].load  # axle 0: the front (1.1 m ahead)
    mid = len(front) // 2
    expected = 1500.0 * G * cos * 1.5 / 2.6 + 1500.0 * mu * G * cos * h / 2.6
    assert front[mid] == pytest.approx(expected, rel=1e-6)
    fg, gs = mu * G * cos, G * math.sin(math.atan(grade))
    d_reg, _ = regularised_slope_slide(v0, opts.v_stop, opts.eps, fg, gs)
    assert res.bodies["car"].rest_position[0] == pytest.approx(d_reg, abs=GLOBAL * opts.rtol * d_reg)

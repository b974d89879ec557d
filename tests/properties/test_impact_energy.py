"""Properties: kinetic energy in Brach's model -- what is guaranteed and what is not.

Notation: u and U are the relative velocities at the contact (normal n, tangential t, and the
relative yaw rate for the moment law) before and after; K is the inverse of the effective
contact mobility of the two articulated vehicles (hitch pins eliminated: they do no work, their
pins move alike before and after). With no constraints and no external impulses the energy
change is exactly

    dT = 1/2 (U^T K U - u^T K u)                                            (*)

Guaranteed (and tested here on random articulated scenes, e' = -1 or 0):

1. frictionless (mu = 0), e' = -1: dT(e) = (1 - e^2) dT(0) <= 0; e = 1 conserves energy.
2. no sliding at separation: U = (-e u_n, 0[, 0]), so dT(e) = dT(0) + e^2 (dT(1) - dT(0)) with
   dT(0) = -1/2 u^T K u <= 0 (a perfectly plastic impact never gains energy).
3. e = 0 and an impulse ratio between 0 and mu_max (the ratio law, or the friction law, whose
   mu is mu_max or f sign(mu_max) with f < |mu_max|), provided P_n is compressive (and above
   rounding level) both at mu = 0 and at mu_max: dT <= 0. (P_n(mu) = -u_n / b(mu) with b linear
   in mu, so U_t(mu) is monotone between its values at 0 and mu_max and, by (*) with U_n = 0,
   dT(mu) <= dT(0) <= 0.)

NOT guaranteed -- physics of the model, demonstrated by the deterministic tests at the end:

a. no sliding with e > 0: by 2., dT > 0 when e^2 > -dT(0) / (dT(1) - dT(0)); a car corner
   striking a wall with e = 1 gains 4.5 %.
b. the no-slide solution can be tensile (P_n < 0) although the contact points approach (a
   sideswipe). Then P_n(mu) has a pole between 0 and mu_max and ratios in between create
   energy: mu_max is no bound there.  No compressive impulse can stop the sliding, so the
   contact slides throughout, and the friction law takes Coulomb's mu = -f sign(u_t) against
   the initial slip (which dissipates; the ratio law refuses ratios that drive the slip).
c. e' > 0: Eq. 6 ties M to the *final* relative yaw rate with Ibar = I1 I2 / (I1 + I2) of the
   isolated bodies, although M also feels the lever arms of P. For two equal bodies with
   radius of gyration k struck at a lever arm d, frictionless and plastic, the normal impulse
   is P_n = -u_n / ((2/m)(1 - e' d^2/k^2)): singular at e' = k^2/d^2, tensile beyond, and the
   energy grows without bound near it (e' = 1 more than doubles it in the example).

Tolerance: these compare separate solves (different e), so they carry the forward error of
the solve, ~cond eps relative to the energies involved; ``_tol`` allows 1e3 cond eps + 1e-12.
"""

from __future__ import annotations

import math

import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from crashsim.impact.core import MU_MAX_LIMIT

from impact_scenes import EPS, SETTINGS, lever_length, scenes, system_energy_change, with_law

from crashsim.errors import InadmissibleImpactError
from crashsim import (Body, BodyState, CrushSurface, IllConditionedError, ImpactProblem, TangentialLaw, Vehicle,
                      solve_impact as _solve_impact)


def solve_impact(problem):
    """The impact equations' answer with the admissibility check off: these properties hold for
    every input the equations accept (tests/unit/test_admissibility.py covers the refusals)."""
    return _solve_impact(problem, check=False)


def _tol(*results):
    cond = max(max(r.condition_number, 1.0) for r in results)
    scale = max(r.kinetic_energy["system"]["before"] + r.kinetic_energy["system"]["after"] for r in results)
    return (1e-12 + 1e3 * cond * EPS) * scale


plain_scenes = scenes(constraints=False, external=False, moment=False, solve=False)


@SETTINGS
@given(plain_scenes)
def test_frictionless_energy_loss_is_one_minus_e_squared(scene):
    """1.: dT(e) = (1 - e^2) dT(0) <= 0, and e = 1 conserves energy, for any articulated pair."""
    p = with_law(scene.problem, TangentialLaw("ratio", 0.0), moment_restitution=-1.0)
    e = p.surface.restitution
    r_e, r_0, r_1 = (solve_impact(with_law(p, restitution=x)) for x in (e, 0.0, 1.0))
    tol = _tol(r_e, r_0, r_1)
    dT0 = system_energy_change(r_0)
    assert dT0 <= tol
    assert abs(system_energy_change(r_1)) <= tol
    assert abs(system_energy_change(r_e) - (1 - e * e) * dT0) <= tol


@SETTINGS
@given(plain_scenes, st.sampled_from([-1.0, 0.0]))
def test_no_slide_energy_change_is_quadratic_in_e(scene, ep):
    """2.: dT(e) = dT(0) + e^2 (dT(1) - dT(0)), dT(0) <= 0 and dT(1) >= dT(0)."""
    p = with_law(scene.problem, TangentialLaw("no_slide"), moment_restitution=ep)
    e = p.surface.restitution
    try:
        r_e, r_0, r_1 = (solve_impact(with_law(p, restitution=x)) for x in (e, 0.0, 1.0))
    except IllConditionedError:
        assume(False)  # e.g. e' = 0 locks a rotation that a barrier contact already fixes
    tol = _tol(r_e, r_0, r_1)
    d0, d1, de = (system_energy_change(r) for r in (r_0, r_1, r_e))
    assert d0 <= tol
    assert d1 >= d0 - tol
    assert abs(de - (d0 + e * e * (d1 - d0))) <= tol


@SETTINGS
@given(plain_scenes, st.sampled_from([-1.0, 0.0]), st.sampled_from(["ratio", "friction"]),
       st.floats(0.0, 1.0), st.floats(0.0, 1.5))
def test_plastic_impact_within_mu_max_never_gains_energy(scene, ep, kind, frac, f):
    """3.: e = 0, mu between 0 and mu_max (same sign), compressive P_n at both ends: dT <= 0."""
    p = with_law(scene.problem, restitution=0.0, moment_restitution=ep)
    try:
        r_ns = solve_impact(with_law(p, TangentialLaw("no_slide")))
        r_0 = solve_impact(with_law(p, TangentialLaw("ratio", 0.0)))
    except IllConditionedError:
        assume(False)
    # compressive at both ends (see b. in the module docstring), and not at rounding level: with
    # e' = 0 the moment impulse alone may stop a spinning body, leaving P_n ~ 1e-14 N s and a
    # meaningless mu = P_t / P_n
    scale = max(abs(r.normal_impulse) + abs(r.tangential_impulse) + abs(r.moment_impulse) / lever_length(p)
                for r in (r_ns, r_0))
    assume(r_ns.normal_impulse > 1e-6 * scale and r_0.normal_impulse > 1e-6 * scale)
    # beyond MU_MAX_LIMIT the friction law gives up on mu_max and opposes the initial slip
    assume(abs(r_ns.mu_max) <= MU_MAX_LIMIT)
    law = TangentialLaw("ratio", frac * r_ns.mu_max) if kind == "ratio" else TangentialLaw("friction", f)
    r = solve_impact(with_law(p, law))
    # mu between 0 and mu_max, up to the rounding of mu = P_t / P_n: impulses carry ~cond eps of
    # the impulse scale, so mu carries that divided by P_n
    mu_tol = 1e3 * EPS * max(r.condition_number, r_ns.condition_number) * scale * (1 + abs(r_ns.mu_max)) / min(
        r_ns.normal_impulse, r_0.normal_impulse)
    assert abs(r.mu) <= abs(r_ns.mu_max) + mu_tol
    assert r.mu * r_ns.mu_max >= -mu_tol * abs(r_ns.mu_max)
    assert system_energy_change(r) <= _tol(r, r_ns, r_0)


# ----------------------------------------------------------------- what the model does not promise

def _car_at_wall(velocity, corner, law, e, ep=-1.0):
    """A 1500 kg car (yaw inertia 2800 kg m^2) at the origin, heading +x, striking a wall whose
    face is the line x = corner[0]; the wall's normal (into the car) is -x, t = +y."""
    car = Vehicle("car", (Body("car", 1500.0, 2800.0),))
    wall = Vehicle("wall", (Body("wall", math.inf, math.inf),))
    states = {"car": BodyState((0.0, 0.0), 0.0, velocity, 0.0), "wall": BodyState(corner, 0.0, (0.0, 0.0), 0.0)}
    return ImpactProblem((car, wall), states, "car", "wall", CrushSurface(corner, math.pi, e, law, ep, -1))


def test_a_no_slide_with_restitution_can_gain_energy():
    """a.: front-right corner (2, -0.8) m into a wall at 10 m/s with 1 m/s along it, e = 1,
    no sliding at separation: 75750 J -> 79150 J. The gain is exactly e^2 (dT(1) - dT(0)) on
    top of the plastic loss, per 2."""
    dT = {e: system_energy_change(solve_impact(_car_at_wall((10.0, 1.0), (2.0, -0.8), TangentialLaw("no_slide"), e)))
          for e in (0.0, 0.5, 1.0)}
    assert dT[1.0] == pytest.approx(3399.6, abs=0.1)  # +4.5 % of 75750 J
    assert dT[0.0] < 0 < dT[1.0]
    assert dT[0.5] == pytest.approx(dT[0.0] + 0.25 * (dT[1.0] - dT[0.0]), rel=1e-12)


def test_b_tensile_no_slide_solution_slides_throughout_against_the_slip():
    """b.: a sideswipe -- 1 m/s into the wall, 10 m/s along it, trailing corner (2, -0.8) m --
    e = 0. The no-slide solution pulls (P_n < 0), and ratios between 0 and its mu_max pass a
    pole of P_n: mu_max is no bound.  The friction law slides throughout with Coulomb's
    mu = -f sign(u_t) (f = 0.6): closed form P_n = -u_n / (W_nn + mu W_nt), P_t = mu P_n, with
    the corner's mobilities W_nn = 1/m + (r x n)^2 / I and W_nt = (r x n)(r x t) / I; the
    normal velocity ends at 0 (e = 0), the slip keeps its sign, and energy is dissipated."""
    ns = solve_impact(_car_at_wall((1.0, 10.0), (2.0, -0.8), TangentialLaw("no_slide"), 0.0))
    assert ns.closing_velocity < 0 and ns.normal_impulse < 0
    assert ns.mu_max == pytest.approx(2.316, abs=1e-3) and ns.slides_throughout
    pn = [solve_impact(_car_at_wall((1.0, 10.0), (2.0, -0.8), TangentialLaw("ratio", x * ns.mu_max), 0.0)
                       ).normal_impulse for x in (0.5, 0.75)]
    assert pn[0] > 0 > pn[1]  # the pole of P_n(mu) between 0 and mu_max
    f, m, inertia = 0.6, 1500.0, 2800.0
    r = solve_impact(_car_at_wall((1.0, 10.0), (2.0, -0.8), TangentialLaw("friction", f), 0.0))
    u_n, u_t = -1.0, 10.0  # n = -x, t = +y at the corner r = (2, -0.8)
    rxn, rxt = 2.0 * 0.0 - (-0.8) * (-1.0), 2.0 * 1.0 - (-0.8) * 0.0
    w_nn, w_nt = 1 / m + rxn**2 / inertia, rxn * rxt / inertia
    mu = -f * math.copysign(1.0, u_t)
    assert r.sliding and r.slides_throughout and r.mu == pytest.approx(mu, rel=1e-12)
    assert r.normal_impulse == pytest.approx(-u_n / (w_nn + mu * w_nt), rel=1e-12)
    assert r.tangential_impulse == pytest.approx(mu * r.normal_impulse, rel=1e-12)
    assert r.separation_normal_velocity == pytest.approx(0.0, abs=1e-12)
    assert r.separation_tangential_velocity > 0  # the slip is slowed, not reversed
    assert system_energy_change(r) < 0
    # the ratio law: against the slip is admissible, with the slip is refused
    ok = _solve_impact(_car_at_wall((1.0, 10.0), (2.0, -0.8), TangentialLaw("ratio", -0.4), 0.0))
    assert ok.normal_impulse > 0 and system_energy_change(ok) < 0
    with pytest.raises(InadmissibleImpactError, match="drives the sliding"):
        _solve_impact(_car_at_wall((1.0, 10.0), (2.0, -0.8), TangentialLaw("ratio", 0.4), 0.0))


def _equal_bodies(ep, k=1.0, d=2.0, m=1000.0):
    """Two equal bodies (mass m, radius of gyration k), CGs at height d above the contact point,
    closing at 10 m/s along the normal x, no yaw: frictionless, plastic (e = 0)."""
    a = Vehicle("A", (Body("a", m, m * k * k),))
    b = Vehicle("B", (Body("b", m, m * k * k),))
    states = {"a": BodyState((0.5, d), 0.0, (-5.0, 0.0), 0.0), "b": BodyState((-0.5, d), 0.0, (5.0, 0.0), 0.0)}
    return ImpactProblem((a, b), states, "a", "b", CrushSurface((0.0, 0.0), 0.0, 0.0, TangentialLaw("ratio", 0.0), ep))


@pytest.mark.parametrize("ep", [0.0, 0.1, 0.2, 0.24, 0.3, 0.5, 1.0])
def test_c_moment_restitution_closed_form(ep):
    """c.: P_n = -u_n / ((2/m)(1 - e' d^2/k^2)) with u_n = -10 m/s, m = 1000 kg, k = 1 m, d = 2 m."""
    r = solve_impact(_equal_bodies(ep))
    expected = 10.0 / ((2 / 1000.0) * (1 - ep * 4.0))
    assert r.normal_impulse == pytest.approx(expected, rel=1e-12 * max(r.condition_number, 1.0) * 100)
    if ep >= 0.2:
        # from e' ~ 0.2 on, this frictionless plastic impact creates energy
        assert system_energy_change(r) > 0
    else:
        assert system_energy_change(r) < 0


def test_c_moment_restitution_singular_at_k2_over_d2():
    """c.: at e' = k^2 / d^2 = 0.25 the restitution and moment equations are dependent."""
    with pytest.raises(IllConditionedError) as info:
        solve_impact(_equal_bodies(0.25))
    assert "restitution (Eq. 5)" in str(info.value) and "moment restitution (Eq. 6)" in str(info.value)
    assert info.value.condition_number > 1e12
    r = solve_impact(_equal_bodies(1.0))
    ke = r.kinetic_energy["system"]
    assert ke["after"] > 2 * ke["before"]  # 25000 J -> 55556 J

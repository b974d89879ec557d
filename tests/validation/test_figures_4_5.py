"""Validation: the paper's statements about its Figures 4 and 5 (rigid-barrier impacts).

Source: "Impact of Articulated Vehicles",
section RIGID BARRIER COLLISIONS, Table 2 and the text on Figures 4 and 5; the omitted
dimensions and the contact points from docs/paper-geometry.md. The figures
themselves are lost, so only what the text states is checked; the contact point the paper
used moved with the barrier angle, and each test says which contact it uses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim import ImpactBatch, solve_impact
from crashsim.impact.sweeps import (CONTACT_15, TABLE2, barrier_angle_sweep, barrier_problem, contact_points,
                                    crossings, parameter_sweep, sliding_onset)

DEG = math.pi / 180.0
E = 0.05  # Table 2: coefficient of restitution


def _sweep(truck, contact="fixed", lo=0.0, hi=90.0, step=0.05, friction=(0.2, 0.6)):
    angles = np.arange(lo, hi + step / 2, step) * DEG
    return barrier_angle_sweep(truck, angles, friction=friction, contact=contact)


@pytest.fixture(scope="module")
def fixed():
    """Full 0-90 deg sweeps, contact at the Table 3 point (3.924, 0.240) m, 0.05 deg step."""
    return {t: _sweep(t, "fixed") for t in ("loaded", "empty")}


@pytest.mark.parametrize("truck", ["loaded", "empty"])
def test_f02_sliding_throughout_from_about_14_deg(truck, fixed):
    """"for f = 0.2 the vehicle will continue sliding along the barrier surface throughout the
    collision for barrier angles of about 14 degrees or greater" (text on Figs. 4, 5).

    Contact: the Table 3 point (docs/paper-geometry.md: "mu_max reaches 0.2 at G of about 14 deg
    with the G = 15 contact point"). Tolerance [13.5, 14.5] deg: "about 14" read off a figure
    is a whole degree, i.e. anything that rounds to 14. The onset is the last angle where
    |mu_max| = 0.2 (|mu_max| is small but non-zero near 0 deg); the 0.05 deg grid with linear
    interpolation locates it to better than 0.001 deg.
    """
    sw = fixed[truck]
    g = sw["angle"] / DEG
    onset = sliding_onset(g, sw["mu_max"][0], 0.2)
    assert 13.5 <= onset <= 14.5, onset
    # and the sliding flag of the f = 0.2 solutions switches there, never to switch back
    k = list(sw["friction"]).index(0.2)
    slides = sw["sliding"][k] & sw["approaching"][k]
    assert not slides[g < onset].any()
    assert slides[(g > onset) & sw["approaching"][k]].all()


@pytest.mark.parametrize("truck, expected", [("loaded", 1.12), ("empty", 1.06)])
def test_mu_max_at_60_deg_with_corner_contact(truck, expected):
    """"For a barrier angle of 60 degrees, a friction coefficient of 1.2 is needed to stop the
    initial sliding" (text on Figs. 4, 5).

    docs/paper-geometry.md: this holds only with the front-corner contact (3.884, 1.205) m,
    |mu_max| = 1.12 loaded and 1.06 empty; checked to those printed 2 decimals. With the Table 3
    point the model needs about 1.57, evidence that the paper's contact moved with the angle.
    """
    corner = barrier_angle_sweep(truck, np.array([60.0 * DEG]), friction=(0.6,), contact="corner")
    assert round(abs(float(corner["mu_max"][0, 0])), 2) == expected
    assert corner["sliding"][0, 0]  # f = 0.6 < 1.12: slides all through the impact
    at_15 = barrier_angle_sweep(truck, np.array([60.0 * DEG]), friction=(0.6,), contact="fixed")
    assert abs(float(at_15["mu_max"][0, 0])) > 1.5


@pytest.mark.parametrize("truck", ["loaded", "empty"])
@pytest.mark.parametrize("contact", ["fixed", "corner", "interpolate"])
def test_f06_sticks_at_30_and_slides_at_60_deg(truck, contact):
    """"if f = 0.6 and the barrier angle is 30 degrees, sliding will cease prior to separation.
    For a barrier angle of 60 degrees ... for f = 0.6, the vehicle will slide over the barrier
    all through the impact" (text on Figs. 4, 5). Holds for every contact rule.
    """
    sw = barrier_angle_sweep(truck, np.array([30.0, 60.0]) * DEG, friction=(0.6,), contact=contact)
    assert sw["sliding"][0].tolist() == [False, True]
    mu_max = np.abs(sw["mu_max"][0])
    assert mu_max[0] <= 0.6 < mu_max[1]


@pytest.mark.parametrize("truck", ["loaded", "empty"])
def test_energy_loss_near_100_percent_head_on(truck, fixed):
    """"The corresponding energy loss curves start at near 100% (for e = 0.05) and
    Gamma = 0 degrees" (text on Figs. 4, 5).

    Expectation. At G = 0 the contact point moves along the normal and, sticking, ends with
    normal velocity -e times its initial value and no tangential velocity; the kinetic energy
    change is then P_n v (1 - e) / 2 (work of the crush impulse at the mean contact velocity;
    the hitch impulses do no work), so the loss fraction is exactly (1 - e) P_n / (M v).
    With a contact on the centre line the whole truck stops rigidly (P_n = (1 + e) M v) and the
    loss is 1 - e^2 = 99.75 %; the Table 3 point, 0.24 m off the centre line, lets the tractor
    keep a little rotational energy: strictly less, but still above 99 %.
    """
    sw = fixed[truck]
    t = TABLE2[truck]
    m, v = t.tractor_mass + t.trailer_mass, t.speed
    for k in range(len(sw["friction"])):
        assert not sw["sliding"][k, 0]
        el0 = float(sw["energy_loss"][k, 0])
        assert 0.99 < el0 < 1 - E**2
        assert el0 == pytest.approx((1 - E) * float(sw["normal_impulse"][k, 0]) / (m * v), rel=1e-12)
    centred = barrier_angle_sweep(truck, np.array([0.0]), friction=(0.2, 0.6), contact=(3.924, 0.0))
    np.testing.assert_allclose(centred["energy_loss"][:, 0], 1 - E**2, rtol=1e-12)
    np.testing.assert_allclose(centred["normal_impulse"][:, 0], (1 + E) * m * v, rtol=1e-12)


@pytest.mark.parametrize("truck", ["loaded", "empty"])
@pytest.mark.parametrize("f", [0.2, 0.6])
def test_energy_loss_drops_once_sliding(truck, f, fixed):
    """"... and drop rapidly once mu = f is less than mu_max" (text on Figs. 4, 5).

    Contact: the Table 3 point. Found: the drop does not start at the very onset of sliding;
    the loss first rises by < 0.1 point over < 0.5 deg, peaking where the tractor's final yaw
    rate changes sign (the "cutoff" between counter-clockwise and glancing-off rebound the
    section asks about), then falls strictly monotonically to 0 at 90 deg. "Rapidly": by more
    than 5 points in the first 5 deg of sliding (computed 7.9 to 13.0), while over the whole
    sticking range (>= 13.7 deg) it varies by < 0.2 point.
    """
    sw = fixed[truck]
    k = list(sw["friction"]).index(f)
    g = sw["angle"] / DEG
    ok = sw["approaching"][k]
    el = 100 * sw["energy_loss"][k]
    onset = sliding_onset(g, sw["mu_max"][k], f)
    stick = g < onset
    assert np.ptp(el[stick]) < 0.2
    ip = int(np.argmax(np.where(ok, el, -np.inf)))
    assert onset <= g[ip] < onset + 0.5
    assert el[ip] - np.interp(onset, g, el) < 0.1
    yaw_change = crossings(g, sw["tractor_yaw_rate"][k])
    assert abs(yaw_change[-1] - g[ip]) < 0.1
    after = el[ip:][ok[ip:]]
    assert np.all(np.diff(after) < 0)
    assert np.interp(onset, g, el) - np.interp(onset + 5.0, g, el) > 5.0
    assert el[ok][-1] < 0.5


def test_loaded_and_empty_do_not_differ_greatly(fixed):
    """"These results do not differ greatly from Figure 4 to Figure 5" (text on Figs. 4, 5),
    said of the sliding cut-offs (mu_max) just before.

    Quantified with the Table 3 contact: sliding-onset angles within 0.5 deg of each other for
    f = 0.2 and 0.6 (computed: 0.34 and 0.36 deg); |mu_max| within 0.03 absolute over 0-60 deg
    and within 5 % relative from 10 to 60 deg (computed 0.022, 4.3 %); energy loss within 0.05
    point wherever both stick. Not asserted "not greatly": the energy loss on the sliding branch,
    which differs by up to ~15 points (empty loses more, as Table 4's 4.4 % vs 7.2 %).
    """
    L, Em = fixed["loaded"], fixed["empty"]
    g = L["angle"] / DEG
    for f in (0.2, 0.6):
        assert abs(sliding_onset(g, L["mu_max"][0], f) - sliding_onset(g, Em["mu_max"][0], f)) < 0.5
    a, b = np.abs(L["mu_max"][0]), np.abs(Em["mu_max"][0])
    sel = g <= 60.0
    assert np.max(np.abs(a - b)[sel]) < 0.03
    sel = (g >= 10.0) & (g <= 60.0)
    assert np.max(np.abs(a - b)[sel] / a[sel]) < 0.05
    both = ~L["sliding"] & ~Em["sliding"] & L["approaching"]
    assert np.max(100 * np.abs(L["energy_loss"] - Em["energy_loss"])[both]) < 0.05
    slide = L["sliding"] & Em["sliding"] & L["approaching"]
    assert np.max((Em["energy_loss"] - L["energy_loss"])[slide]) > 0.05  # documented difference


@pytest.mark.parametrize("truck, angle, contact, loss, mu, yaw", [
    ("loaded", 15, "fixed", 99.4, -90270 / 403164, 0.18),   # Table 3-a
    ("empty", 15, "fixed", 99.4, -46202 / 212215, 0.16),    # Table 3-b
    ("loaded", 75, "corner", 4.4, -0.6, -0.64),             # Table 4-a
    ("empty", 75, "corner", 7.2, -0.6, -0.71),              # Table 4-b
])
def test_sweep_points_reproduce_tables_3_and_4(truck, angle, contact, loss, mu, yaw):
    """Tables 3 and 4 (f = 0.6): the sweep machinery (frame, contact rule, friction rule) gives
    the printed kinetic-energy loss (1 decimal), impulse ratio (3 decimals of the printed
    impulses' ratio) and tractor yaw rate (2 decimals), and agrees with a single
    ``solve_impact`` of the same problem to 1e-12.
    """
    sw = barrier_angle_sweep(truck, np.array([angle * DEG]), friction=(0.6,), contact=contact)
    assert round(100 * float(sw["energy_loss"][0, 0]), 1) == loss
    assert float(sw["mu"][0, 0]) == pytest.approx(mu, abs=6e-4)
    assert round(float(sw["tractor_yaw_rate"][0, 0]), 2) == yaw
    r = solve_impact(barrier_problem(truck, angle * DEG, tuple(contact_points([angle * DEG], contact)[0])))
    assert r.energy_loss["system"] == pytest.approx(float(sw["energy_loss"][0, 0]), rel=1e-12)
    assert r.mu_max == pytest.approx(float(sw["mu_max"][0, 0]), rel=1e-12)


def test_friction_rule_and_no_impact_at_90_deg(fixed):
    """Eq. 8 as the figures use it: mu = mu_max where |mu_max| <= f, else |mu| = f with the sign
    of mu_max (the "solid horizontal curve"); at G = 90 deg there is no impact (closing velocity
    0), flagged ``approaching = False`` with mu, mu_max NaN and no energy lost.
    """
    sw = fixed["loaded"]
    ok = sw["approaching"]
    for k, f in enumerate(sw["friction"]):
        mm, mu, sl = sw["mu_max"][k], sw["mu"][k], sw["sliding"][k]
        np.testing.assert_array_equal(sl[ok[k]], (np.abs(mm) > f)[ok[k]])
        np.testing.assert_allclose(mu[sl & ok[k]], f * np.sign(mm[sl & ok[k]]), rtol=1e-12)
        np.testing.assert_allclose(mu[~sl & ok[k]], mm[~sl & ok[k]], rtol=1e-12)
    assert not ok[:, -1].any() and ok[:, :-1].all()
    assert np.isnan(sw["mu_max"][:, -1]).all()
    assert np.abs(sw["energy_loss"][:, -1]).max() < 1e-12


def test_parameter_sweep_matches_individual_solves():
    """The general sweep (any ImpactArrays field) equals one batch-of-one solve per value."""
    prob = barrier_problem("loaded", 15 * DEG, CONTACT_15)
    values = np.linspace(0.0, 1.0, 5)
    sw = parameter_sweep(prob, "restitution", values, friction=(0.2, 0.6))
    assert sw["energy_loss.system"].shape == (2, 5)
    for i, f in enumerate((0.2, 0.6)):
        for j, e in enumerate(values):
            b = ImpactBatch.from_problem(barrier_problem("loaded", 15 * DEG, CONTACT_15, friction=f, restitution=e))
            out = b.solve()
            assert sw["energy_loss.system"][i, j] == pytest.approx(out["energy_loss.system"][0], rel=1e-12)
            assert sw["mu"][i, j] == pytest.approx(out["mu"][0], rel=1e-12)

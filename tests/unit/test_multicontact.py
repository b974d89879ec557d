"""The simultaneous impact of several contact points (crashsim.impact.multicontact).

* Lemke's method against every active set of small random problems (the unique solution of a
  positive definite LCP), and complementarity on positive semidefinite ones;
* one contact point is Brach's impact with the friction law and no moment impulse
  (:func:`crashsim.impact.solve_impact`), for single bodies and articulated vehicles, sticking
  and sliding;
* Newton's cradle of three equal boxes in closed form: plastic, all at v/3; elastic, the
  simultaneous law's (-v/3, 2v/3, 2v/3);
* no solution gains kinetic energy (hypothesis), and a closed stop only pushes.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from crashsim.impact import CrushSurface, ImpactProblem, TangentialLaw, solve_impact
from crashsim.impact.multicontact import constrained_inverse, lemke, solve_contacts
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states


def _brute_lcp(M, q):
    """The solution of a P-matrix LCP by trying every active set."""
    n = len(q)
    for active in itertools.product([False, True], repeat=n):
        idx = np.flatnonzero(active)
        z = np.zeros(n)
        if idx.size:
            z[idx] = np.linalg.solve(M[np.ix_(idx, idx)], -q[idx])
        w = M @ z + q
        if np.all(z >= -1e-12) and np.all(w >= -1e-12):
            return z
    raise AssertionError("no solution")


@pytest.mark.parametrize("seed", range(20))
def test_lemke_matches_enumeration_on_positive_definite_problems(seed):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 7))
    B = rng.normal(size=(n, n))
    M = B @ B.T + 0.1 * np.eye(n)
    q = rng.normal(size=n)
    z = lemke(M, q)
    assert z is not None
    assert z == pytest.approx(_brute_lcp(M, q), abs=1e-9)


@pytest.mark.parametrize("seed", range(10))
def test_lemke_complementarity_on_semidefinite_problems(seed):
    rng = np.random.default_rng(100 + seed)
    n = int(rng.integers(2, 9))
    B = rng.normal(size=(n, n - 1))  # rank n - 1: degenerate, as duplicated contact points are
    M = B @ B.T
    q = M @ rng.normal(size=n) + rng.uniform(0.0, 1.0, size=n)  # feasible
    z = lemke(M, q)
    assert z is not None
    w = M @ z + q
    assert np.all(z >= -1e-9) and np.all(w >= -1e-9)
    assert abs(float(z @ w)) < 1e-9


def _jacobians(bodies, states, hitches, point, normal):
    """minv, G, Jn, Jt of bodies (name -> Body) in z order, for one contact between bodies[0] and
    bodies[1] (``None`` for a fixed obstacle) at ``point`` with ``normal`` from the second into the first."""
    names = [n for n in bodies if n is not None]
    nb = len(names)
    minv = np.concatenate([[1 / bodies[n].mass for n in names]] * 2 + [[1 / bodies[n].yaw_inertia for n in names]])
    G = []
    for front, rear, h in hitches:
        i, j = names.index(front), names.index(rear)
        for axis in range(2):
            row = np.zeros(3 * nb)
            for k, name, pt, sign in ((i, front, h.front_point, 1.0), (j, rear, h.rear_point, -1.0)):
                psi = states[name].heading
                rx = math.cos(psi) * pt[0] - math.sin(psi) * pt[1]
                ry = math.sin(psi) * pt[0] + math.cos(psi) * pt[1]
                row[axis * nb + k] = sign
                row[2 * nb + k] = sign * (-ry if axis == 0 else rx)
            G.append(row)
    nx, ny = normal
    Jn, Jt = np.zeros(3 * nb), np.zeros(3 * nb)
    for name, sign in zip(list(bodies)[:2], (1.0, -1.0)):
        if name is None:
            continue
        k = names.index(name)
        rx, ry = point[0] - states[name].position[0], point[1] - states[name].position[1]
        Jn[[k, nb + k, 2 * nb + k]] = sign * np.array([nx, ny, rx * ny - ry * nx])
        Jt[[k, nb + k, 2 * nb + k]] = sign * np.array([-ny, nx, rx * nx + ry * ny])
    u = np.concatenate([[states[n].velocity[0] for n in names], [states[n].velocity[1] for n in names],
                        [states[n].yaw_rate for n in names]])
    return names, minv, np.array(G).reshape(-1, 3 * nb), Jn[None], Jt[None], u


def _car(name, mass=1500.0, inertia=2500.0):
    return Vehicle(name, (Body(name, mass, inertia, 4.5, 1.8, axles=(Axle(1.2, 1.5), Axle(-1.4, 1.5))),))


def _tractor_semi(name):
    tractor = Body(f"{name}_t", 8000.0, 30000.0, 6.0, 2.5, axles=(Axle(2.0, 2.0), Axle(-2.0, 1.8)))
    semi = Body(f"{name}_s", 12000.0, 150000.0, 12.0, 2.5, axles=(Axle(-4.0, 1.8),))
    return Vehicle(name, (tractor, semi), (Hitch((-1.5, 0.0), (5.0, 0.0)),))


CASES = [  # (e, f, normal angle [deg], car speed [m/s], truck articulation [deg], car heading offset)
    (0.2, 0.6, 90.0, 12.0, 0.0, 0.3),     # sticking: |mu_max| <= f
    (0.0, 0.1, 80.0, 15.0, 10.0, 0.0),    # sliding: |mu| = f
    (0.5, 0.3, 100.0, 9.0, -20.0, -0.4),
    (0.1, 1.0, 60.0, 20.0, 5.0, 0.8),
    (0.3, 0.05, 120.0, 11.0, 30.0, 0.2),
]


@pytest.mark.parametrize("e, f, angle, speed, art, offset", CASES)
def test_one_point_is_brachs_impact_with_the_friction_law(e, f, angle, speed, art, offset):
    """A car strikes the side of a tractor-semitrailer: solve_contacts with one point gives the
    velocities of solve_impact (friction law, no moment impulse) to round-off."""
    truck = _tractor_semi("truck")
    car = _car("car")
    states = chain_states(truck, (0.0, 0.0), 0.0, (8.0, 0.0), yaw_rates=[0.1, -0.05], articulation=[math.radians(art)])
    n_ang = math.radians(angle)
    point = (1.0, -1.25)
    car_pos = (point[0] - 2.25 * math.cos(n_ang + math.pi + offset), point[1] - 2.25 * math.sin(n_ang + math.pi + offset))
    states["car"] = BodyState(car_pos, n_ang + math.pi + offset, (speed * math.cos(n_ang), speed * math.sin(n_ang)), 0.2)
    # body1 = car (the normal from the truck into the car), body2 = the tractor
    surface = CrushSurface(point, n_ang + math.pi, e, TangentialLaw("friction", f), -1.0, 1)
    ref = solve_impact(ImpactProblem((car, truck), states, "car", "truck_t", surface))
    bodies = {"car": car.bodies[0], "truck_t": truck.bodies[0], "truck_s": truck.bodies[1]}
    nrm = (math.cos(n_ang + math.pi), math.sin(n_ang + math.pi))
    names, minv, G, Jn, Jt, u = _jacobians(bodies, states, [("truck_t", "truck_s", truck.hitches[0])], point, nrm)
    sol = solve_contacts(minv, G, Jn, Jt, np.zeros((0, minv.size)), u, [e], [f])
    assert sol.law == "friction"
    nb = len(names)
    for k, name in enumerate(names):
        b = ref.bodies[name]
        assert sol.velocity[[k, nb + k]] == pytest.approx(b.velocity, abs=1e-9 * (1 + speed))
        assert sol.velocity[2 * nb + k] == pytest.approx(b.yaw_rate, abs=1e-9 * (1 + speed))
    assert sol.normal[0] == pytest.approx(ref.normal_impulse, rel=1e-9)
    assert sol.tangential[0] == pytest.approx(ref.tangential_impulse, rel=1e-9, abs=1e-9 * ref.normal_impulse)
    assert sol.energy_loss == pytest.approx(ref.kinetic_energy["system"]["before"] - ref.kinetic_energy["system"]["after"],
                                            rel=1e-9)


def _cradle(e):
    """Three equal boxes in a row along x (unit mass), the first at v = 1 into the second, the second
    touching the third: two frictionless contact points, normals along -x (from the box behind into
    the one in front... as the first body of each point is the front box)."""
    nb = 3
    minv = np.array([1.0] * 3 + [1.0] * 3 + [1.0] * 3)
    Jn = np.zeros((2, 3 * nb))
    # point 1: body1 = box 2, body2 = box 1, normal from box 1 into box 2 = +x
    Jn[0, 1], Jn[0, 0] = 1.0, -1.0
    Jn[1, 2], Jn[1, 1] = 1.0, -1.0
    Jt = np.zeros((2, 3 * nb))
    Jt[0, 4], Jt[0, 3] = 1.0, -1.0
    Jt[1, 5], Jt[1, 4] = 1.0, -1.0
    u = np.zeros(3 * nb)
    u[0] = 1.0
    return solve_contacts(minv, np.zeros((0, 3 * nb)), Jn, Jt, np.zeros((0, 3 * nb)), u, [e, e], [0.0, 0.0])


def test_newtons_cradle_plastic_moves_all_three_at_a_third():
    sol = _cradle(0.0)
    assert sol.velocity[:3] == pytest.approx([1 / 3, 1 / 3, 1 / 3], abs=1e-12)
    assert sol.energy_loss == pytest.approx(0.5 - 0.5 * 3 / 9, abs=1e-12)


def test_newtons_cradle_elastic_is_the_simultaneous_law():
    """e = 1 at both points at once: (-1/3, 2/3, 2/3), energy kept (steel balls instead pass the pulse on
    one contact after the other, 0, 0, 1: the simultaneous law is not that, and says so in its docs)."""
    sol = _cradle(1.0)
    assert sol.velocity[:3] == pytest.approx([-1 / 3, 2 / 3, 2 / 3], abs=1e-12)
    assert sol.energy_loss == pytest.approx(0.0, abs=1e-12)
    assert sol.velocity[:3].sum() == pytest.approx(1.0, abs=1e-12)


def test_newtons_cradle_struck_point_first():
    """With strike thresholds the struck point is solved first and the one it drives in next, each by its
    own e: at e = 1 the pulse passes on, (0, 0, v), energy kept; at e = 0 the last, simultaneous step
    leaves all three at v/3; a plastic contact behind an elastic one, e = (0, 1): the first two move on at
    v/2, the second passes its v/2 on to the third and stops, the first catches it up plastically: (v/4, v/4,
    v/2)."""
    for e, expect in (([1.0, 1.0], [0.0, 0.0, 1.0]), ([0.0, 0.0], [1 / 3, 1 / 3, 1 / 3]), ([0.0, 1.0], [0.25, 0.25, 0.5])):
        nb = 3
        minv = np.ones(3 * nb)
        Jn = np.zeros((2, 3 * nb))
        Jn[0, 1], Jn[0, 0] = 1.0, -1.0
        Jn[1, 2], Jn[1, 1] = 1.0, -1.0
        u = np.zeros(3 * nb)
        u[0] = 1.0
        sol = solve_contacts(minv, np.zeros((0, 3 * nb)), Jn, np.zeros((2, 3 * nb)), np.zeros((0, 3 * nb)), u, e,
                             [0.0, 0.0], strike=[0.01, 0.01])
        assert sol.velocity[:3] == pytest.approx(expect, abs=1e-9), e
        assert sol.energy_after <= sol.energy_before + 1e-12
        assert float(np.sum(sol.work)) == pytest.approx(sol.energy_loss, abs=1e-12)


def test_closed_stop_only_pushes():
    """A stop row resists being driven further past the stop, and takes nothing when the impact turns
    the bodies away from it."""
    minv = np.array([1.0, 1.0, 1.0, 1.0, 1.0, 1.0])  # two bodies, z order
    Js = np.zeros((1, 6))
    Js[0, 4], Js[0, 5] = -1.0, 1.0  # w_front - w_rear may not grow (an upper stop)
    for push, expect in ((+1.0, True), (-1.0, False)):
        Jn = np.zeros((1, 6))
        Jn[0, 0], Jn[0, 4] = 1.0, push  # a point on the front body whose impulse also turns it
        u = np.zeros(6)
        u[0] = -2.0
        sol = solve_contacts(minv, np.zeros((0, 6)), Jn, np.zeros((1, 6)), Js, u, [0.0], [0.0])
        assert (sol.stop[0] > 1e-9) == expect
        assert float((Js @ sol.velocity)[0]) >= -1e-12


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 10_000), n_points=st.integers(1, 6), e=st.floats(0.0, 1.0), f=st.floats(0.0, 1.5))
@example(seed=203, n_points=6, e=0.0, f=0.0)  # frictionless: Lemke's method ended on a ray; now non-negative least squares
@example(seed=6378, n_points=6, e=0.0, f=0.0)  # six points jammed on two bodies: impulses of 3e7 N s
def test_no_simultaneous_impact_gains_energy(seed, n_points, e, f):
    """Random bodies and points (all approaching or touching): kinetic energy after <= before, every
    normal impulse >= 0, |lambda_t| <= f lambda_n, and every point that takes an impulse leaves at e
    times its approach speed (the accepted law's e)."""
    rng = np.random.default_rng(seed)
    nb = int(rng.integers(2, 5))
    minv = np.concatenate([1 / rng.uniform(500, 20000, nb)] * 2 + [1 / rng.uniform(500, 2e5, nb)])
    Jn = np.zeros((n_points, 3 * nb))
    Jt = np.zeros((n_points, 3 * nb))
    for r in range(n_points):
        a, b = rng.choice(nb, 2, replace=False)
        ang = rng.uniform(0, 2 * np.pi)
        nx, ny = math.cos(ang), math.sin(ang)
        for k, sign in ((a, 1.0), (b, -1.0)):
            rx, ry = rng.uniform(-5, 5, 2)
            Jn[r, [k, nb + k, 2 * nb + k]] = sign * np.array([nx, ny, rx * ny - ry * nx])
            Jt[r, [k, nb + k, 2 * nb + k]] = sign * np.array([-ny, nx, rx * nx + ry * ny])
    u = rng.normal(scale=5.0, size=3 * nb)
    sol = solve_contacts(minv, np.zeros((0, 3 * nb)), Jn, Jt, np.zeros((0, 3 * nb)), u, [e] * n_points, [f] * n_points)
    assert sol.energy_after <= sol.energy_before * (1 + 1e-12) + 1e-9
    assert np.all(sol.normal >= -1e-9)
    ff = 0.0 if sol.law == "frictionless" else f
    assert np.all(np.abs(sol.tangential) <= ff * sol.normal + 1e-6 * (1 + sol.normal))
    ee = e if sol.law == "friction" else 0.0
    un0, un1 = Jn @ u, Jn @ sol.velocity
    target = ee * np.maximum(-un0, 0.0)
    scale = 1e-6 * (1 + np.max(np.abs(u)))
    assert np.all(un1 >= target - scale)
    hit = sol.normal > 1e-6 * (1 + sol.normal.max())
    assert un1[hit] == pytest.approx(target[hit], abs=scale)


def test_constrained_inverse_holds_the_pins():
    """An impulse through P keeps the pin rows at zero velocity change."""
    rng = np.random.default_rng(3)
    minv = 1 / rng.uniform(1000, 5000, 6)
    G = rng.normal(size=(2, 6))
    P, project = constrained_inverse(minv, G)
    assert G @ P @ rng.normal(size=6) == pytest.approx(np.zeros(2), abs=1e-12)
    assert G @ project(rng.normal(size=6)) == pytest.approx(np.zeros(2), abs=1e-12)

"""Closed forms of the self-steering (castor) wheel and the yaw-locked C-dolly (docs/heavy-vehicles.md).

* A body on free castors (limit 90 deg) carries only rolling resistance along each wheel: pushed in
  any direction, sideways too, it rolls straight to rest after ``d = v^2 / (2 f_r g)`` without turning.
* A castor wheel with the limit 0 is a fixed straight wheel, to the last bit.
* Beyond its limit a castor wheel is a fixed wheel steered by the limit.
* A C-dolly (a hitch locked in yaw) makes the lead trailer and the dolly one rigid body: at any
  consistent state their accelerations are those of the welded pair under the same external forces
  (parallel-axis inertia), and with load-independent tyre forces the run-out equals that of the
  merged rigid body, on both engines.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from crashsim.geometry import perp, rotate
from crashsim.motion import Road, RunoutOptions, WheelSetting, WheelSettings, make_hitch_consistent, simulate_runout
from crashsim.motion.hitches import RunoutModel
from crashsim.motion.loads import STANDARD_GRAVITY
from crashsim.motion.simulate import zone_membership
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle, chain_states

ENGINES = ("scipy", "compiled")
TYRE = dict(cornering_coefficient=6.0, rolling_resistance=0.01)


def _cart():
    """A symmetric 4-wheel body (equal static loads), CG at the centre."""
    return Vehicle("cart", (Body("cart", 3000.0, 4000.0, length=4.0, width=2.0,
                                 axles=(Axle(1.2, 1.8, name="front"), Axle(-1.2, 1.8, name="rear"))),))


@pytest.mark.parametrize("engine", ENGINES)
@pytest.mark.parametrize("direction_deg", [0.0, 90.0, 135.0])
def test_free_castors_roll_straight_to_rest_at_rolling_resistance(engine, direction_deg):
    """d = v^2 / (2 f_r g) in any direction of travel, no yaw (every wheel lies along the velocity)."""
    veh = _cart()
    v0, fr = 4.0, TYRE["rolling_resistance"]
    course = math.radians(direction_deg)
    init = {"cart": BodyState((0.0, 0.0), 0.0, (v0 * math.cos(course), v0 * math.sin(course)), 0.0)}
    wheels = WheelSettings(default=WheelSetting("rolling", self_steer_limit=math.pi / 2, **TYRE))
    opts = RunoutOptions(engine=engine, rtol=1e-9, atol=1e-11)
    res = simulate_runout(veh, init, wheels, Road(0.8), opts)
    assert res.status == "rest"
    b = res.bodies["cart"]
    a = fr * STANDARD_GRAVITY
    d = math.hypot(*b.rest_position)
    # the rest threshold leaves at most v_stop^2 / (2 a) untravelled; the regularisation eps adds O(eps^2 / a)
    assert d == pytest.approx(v0**2 / (2 * a), abs=opts.v_stop**2 / (2 * a) + 2e-3)
    assert abs(math.remainder(math.atan2(b.rest_position[1], b.rest_position[0]) - course, 2 * math.pi)) < 1e-6
    assert abs(b.rest_heading) < 1e-9


@pytest.mark.parametrize("engine", ENGINES)
def test_fixed_wheels_stop_a_sideways_slide_far_sooner(engine):
    """The same sideways push on fixed wheels: the tyres' lateral force stops it within v^2 / (2 mu g) + a little."""
    veh = _cart()
    init = {"cart": BodyState((0.0, 0.0), 0.0, (0.0, 4.0), 0.0)}
    res = simulate_runout(veh, init, WheelSettings(default=WheelSetting("rolling", **TYRE)), Road(0.8),
                          RunoutOptions(engine=engine))
    assert math.hypot(*res.bodies["cart"].rest_position) < 1.1 * 4.0**2 / (2 * 0.8 * STANDARD_GRAVITY)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_castor_locked_at_zero_is_a_fixed_wheel_to_the_bit(engine):
    veh = _cart()
    init = {"cart": BodyState((0.0, 0.0), 0.3, (9.0, 2.0), 0.8)}
    base = dict(brake=0.3, **TYRE)
    fixed = WheelSettings(default=WheelSetting("braked", **base))
    locked = WheelSettings(default=WheelSetting("braked", self_steer_limit=0.0, **base))
    a = simulate_runout(veh, init, fixed, Road(0.7), RunoutOptions(engine=engine))
    b = simulate_runout(veh, init, locked, Road(0.7), RunoutOptions(engine=engine))
    assert a.bodies["cart"].rest_position == b.bodies["cart"].rest_position
    assert a.bodies["cart"].rest_heading == b.bodies["cart"].rest_heading
    assert a.t_end == b.t_end


def test_beyond_its_limit_a_castor_is_a_wheel_steered_by_the_limit():
    """Right-hand side: a castor at its stop gives the forces of a fixed wheel steered by the limit;
    within its limit it gives no lateral force (the slip angle is zero)."""
    veh = _cart()
    lim = math.radians(20.0)
    model_c = RunoutModel(veh, WheelSettings(default=WheelSetting("rolling", self_steer_limit=lim, **TYRE)).resolve(veh),
                          Road(0.8), RunoutOptions())
    model_f = RunoutModel(veh, WheelSettings(default=WheelSetting("rolling", steer=lim, **TYRE)).resolve(veh),
                          Road(0.8), RunoutOptions())
    # pure translation at 60 deg from the body axis: every castor needs 60 deg, so sits at +20 deg
    y = model_c.layout.pack({"cart": BodyState((0.0, 0.0), 0.0, (5 * math.cos(1.047), 5 * math.sin(1.047)), 0.0)})
    seg_c = model_c.segment(0.0, zone_membership(model_c, y))
    seg_f = model_f.segment(0.0, zone_membership(model_f, y))
    ev_c, ev_f = model_c.evaluate(y[:, None], seg_c), model_f.evaluate(y[:, None], seg_f)
    assert np.allclose(ev_c.y_dot, ev_f.y_dot, rtol=1e-13, atol=1e-12)
    # at 10 deg, within the limit: the forces are rolling resistance along the velocity only
    y = model_c.layout.pack({"cart": BodyState((0.0, 0.0), 0.0, (5 * math.cos(0.1745), 5 * math.sin(0.1745)), 0.0)})
    ev = model_c.evaluate(y[:, None], seg_c)
    f = ev.body_force[:, 0]
    load = ev.load[:, 0].sum()
    eps = RunoutOptions().eps  # the regularised rolling resistance, f_r N u / sqrt(u^2 + eps^2), at u = 5 m/s
    assert math.hypot(f[0], f[1]) == pytest.approx(TYRE["rolling_resistance"] * load * 5 / math.hypot(5, eps), rel=1e-9)
    assert math.atan2(f[1], f[0]) == pytest.approx(0.1745 - math.pi, abs=1e-9)
    assert abs(f[2]) < 1e-6 * load


# ------------------------------------------------------------------------------------- C-dolly
def _doubles(c_dolly: bool):
    """Truck, lead trailer, dolly (A or C), as a chain of pins."""
    truck = Body("truck", 9000.0, 30000.0, length=7.0, axles=(Axle(2.2, 2.05, name="steer"), Axle(-2.4, 1.85, True, "drive")))
    lead = Body("lead", 8000.0, 60000.0, length=8.0, axles=(Axle(-2.5, 1.85, True, "axle"),))
    dolly = Body("dolly", 1500.0, 1200.0, length=3.0, axles=(Axle(0.1, 1.85, True, "axle"),))
    return Vehicle("D", (truck, lead, dolly),
                   (Hitch((-3.2, 0.0), (3.5, 0.0)), Hitch((-4.2, 0.0), (2.3, 0.0), None if c_dolly else 1.5, yaw_locked=c_dolly)))


def _merged():
    """The lead trailer and the C-dolly welded into one rigid body (parallel axes)."""
    veh = _doubles(True)
    truck, lead, dolly = veh.bodies
    m1, m2 = lead.mass, dolly.mass
    d2 = np.array(veh.hitches[1].front_point) - np.array(veh.hitches[1].rear_point)  # dolly CG in lead axes
    cg = m2 * d2 / (m1 + m2)
    inertia = lead.yaw_inertia + dolly.yaw_inertia + m1 * cg @ cg + m2 * (d2 - cg) @ (d2 - cg)
    axles = tuple(Axle(a.x - cg[0], a.track, a.dual, "lead " + a.name) for a in lead.axles) + tuple(
        Axle(a.x + d2[0] - cg[0], a.track, a.dual, "dolly " + a.name) for a in dolly.axles)
    body = Body("merged", m1 + m2, inertia, axles=axles)
    front = tuple(np.array(veh.hitches[0].rear_point) - cg)
    return Vehicle("M", (truck, body), (Hitch(veh.hitches[0].front_point, front),)), cg


def test_a_c_dolly_and_its_trailer_accelerate_as_one_rigid_body():
    """At a consistent state, the chain's accelerations of the lead trailer and the C-dolly equal those
    of the welded pair under the same external forces (its tyres, and the pin force from the truck)."""
    veh = _doubles(True)
    wheels = WheelSettings(default=WheelSetting("braked", brake=0.3, **TYRE),
                           wheels={"truck/0": WheelSetting("rolling", steer=0.1, **TYRE),
                                   "dolly": WheelSetting("rolling", **TYRE), "lead": WheelSetting("locked")})
    model = RunoutModel(veh, wheels.resolve(veh), Road(0.7), RunoutOptions())
    L = model.layout
    states = chain_states(veh, (1.0, -2.0), 0.4, (14.0, 2.0), yaw_rates=[0.3, -0.25, -0.25], articulation=[0.35, 0.0])
    y = L.pack(states)
    ev = model.evaluate(y[:, None], model.segment(0.0, zone_membership(model, y)))
    nb = L.n_bodies
    acc = ev.y_dot[3 * nb: 6 * nb, 0]
    f = ev.body_force[:, 0]
    lam0 = ev.lam[0, 0:2]  # pin force of hitch 0 on the truck; the lead trailer receives -lam0
    m = np.array([b.mass for b in veh.bodies])
    inertia = np.array([b.yaw_inertia for b in veh.bodies])
    r = np.array([states[b.name].position for b in veh.bodies])
    w = states["lead"].yaw_rate
    pin = r[1] + rotate(veh.hitches[0].rear_point, states["lead"].heading)
    mt = m[1] + m[2]
    R = (m[1] * r[1] + m[2] * r[2]) / mt
    force = np.array([f[1] + f[2] - lam0[0], f[nb + 1] + f[nb + 2] - lam0[1]])
    cross = lambda a, b: a[0] * b[1] - a[1] * b[0]  # noqa: E731
    moment = (f[2 * nb + 1] + f[2 * nb + 2] + cross(r[1] - R, (f[1], f[nb + 1])) + cross(r[2] - R, (f[2], f[nb + 2]))
              + cross(pin - R, -lam0))
    I_tot = inertia[1] + inertia[2] + m[1] * (r[1] - R) @ (r[1] - R) + m[2] * (r[2] - R) @ (r[2] - R)
    alpha = moment / I_tot
    for i in (1, 2):
        rho = r[i] - R
        expect = force / mt + alpha * perp(rho) - w * w * rho
        assert acc[i] == pytest.approx(expect[0], rel=1e-9, abs=1e-9)
        assert acc[nb + i] == pytest.approx(expect[1], rel=1e-9, abs=1e-9)
        assert acc[2 * nb + i] == pytest.approx(alpha, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("engine", ENGINES)
def test_a_c_dolly_runs_out_as_the_merged_rigid_body(engine):
    """Load-independent tyres (linear lateral curve, fixed cornering stiffness per tyre, no rolling
    resistance, no saturation): the chain with the yaw-locked dolly and the two-body vehicle with the
    lead trailer and dolly merged follow the same path over 3 s, to the solver's tolerance."""
    chain = _doubles(True)
    merged, cg = _merged()
    tyre = dict(cornering_stiffness=30000.0, rolling_resistance=0.0)
    wheels = WheelSettings(default=WheelSetting("rolling", **tyre), wheels={"truck/0": WheelSetting("rolling", steer=0.03, **tyre)})
    states = make_hitch_consistent(chain, chain_states(chain, (0.0, 0.0), 0.0, (15.0, 0.2), yaw_rates=[0.05, 0.02, 0.02],
                                                       articulation=[0.04, 0.0]))
    lead = states["lead"]
    R = np.array(lead.position) + rotate(cg, lead.heading)
    vR = np.array(lead.velocity) + lead.yaw_rate * perp(rotate(cg, lead.heading))
    m_states = {"truck": states["truck"], "merged": BodyState(tuple(R), lead.heading, tuple(vR), lead.yaw_rate)}
    opts = RunoutOptions(engine=engine, rtol=1e-10, atol=1e-12, t_max=3.0, lateral_model="linear")
    a = simulate_runout(chain, states, wheels, Road(1.0), opts)
    b = simulate_runout(merged, make_hitch_consistent(merged, m_states), wheels, Road(1.0), opts)
    assert a.status == b.status == "time_limit"
    ha, hb = a.bodies["lead"], b.bodies["merged"]
    assert ha.rest_heading == pytest.approx(hb.rest_heading, abs=1e-7)
    lead_from_merged = np.array(hb.rest_position) - rotate(cg, hb.rest_heading)
    assert np.allclose(ha.rest_position, lead_from_merged, atol=1e-5)
    assert np.allclose(a.bodies["truck"].rest_position, b.bodies["truck"].rest_position, atol=1e-5)
    assert a.bodies["dolly"].rest_heading == pytest.approx(ha.rest_heading, abs=1e-8)
    # and an A-dolly in its place does not follow that path (the lock matters here)
    c = simulate_runout(_doubles(False), states, wheels, Road(1.0), opts)
    assert abs(c.bodies["dolly"].rest_heading - c.bodies["lead"].rest_heading) > 1e-3


# ------------------------------------------------------------------------------------ the impact
def _with_second(vehicle: Vehicle, at: tuple) -> Vehicle:
    """``vehicle`` with a second trailer on the rear hitch ``at`` of its last body."""
    second = Body("second", 9000.0, 55000.0, length=8.5, axles=(Axle(-3.0, 1.85, True, "axle"),))
    return Vehicle(vehicle.name, vehicle.bodies + (second,), vehicle.hitches + (Hitch(at, (3.6, 0.0)),))


@pytest.mark.parametrize("struck", ["second", "dolly", "lead"])
@pytest.mark.parametrize("dense", [False, True])
def test_a_c_dolly_takes_the_impact_as_the_merged_rigid_body(struck, dense):
    """The impulse solver with a yaw-locked hitch (one more unknown: its moment impulse) gives the
    lead trailer and the dolly the rigid motion of the merged body, and every other number (crush
    and hitch impulses, the other bodies' velocities) equals that of the merged vehicle; on the
    compiled single solve and on the dense NumPy path."""
    from crashsim.impact import CrushSurface, ImpactBatch, ImpactProblem, TangentialLaw, solve_impact

    chain = _with_second(_doubles(True), (0.15, 0.0))
    merged, cg = _merged()
    d2 = np.array(chain.hitches[1].front_point) - np.array(chain.hitches[1].rear_point)
    merged = _with_second(merged, tuple(d2 + np.array((0.15, 0.0)) - cg))
    states = chain_states(chain, (0.0, 0.0), 0.2, (12.0, 1.0), yaw_rates=[0.1, -0.05, -0.05, 0.2],
                          articulation=[0.15, 0.0, -0.2])
    lead = states["lead"]
    R = np.array(lead.position) + rotate(cg, lead.heading)
    vR = np.array(lead.velocity) + lead.yaw_rate * perp(rotate(cg, lead.heading))
    m_states = {"truck": states["truck"], "second": states["second"],
                "merged": BodyState(tuple(R), lead.heading, tuple(vR), lead.yaw_rate)}
    car = Vehicle("C", (Body("car", 1500.0, 2800.0),))
    target = states[struck]
    side = rotate((0.0, 1.2), target.heading)
    point = tuple(np.array(target.position) + side)
    normal = math.atan2(side[1], side[0])
    car_state = BodyState(tuple(np.array(point) + 2.4 * np.array(side) / 1.2), normal + math.pi,
                          tuple(-12.0 * np.array(side) / 1.2), 0.0)
    surface = CrushSurface(point, normal, 0.2, TangentialLaw("friction", 0.4), -1.0, 1)  # from the struck body into the car
    body2 = {"second": "second", "dolly": "merged", "lead": "merged"}[struck]
    pa = ImpactProblem((car, chain), {**states, "car": car_state}, "car", struck, surface)
    pb = ImpactProblem((car, merged), {**m_states, "car": car_state}, "car", body2, surface)
    if dense:
        ba, bb = ImpactBatch.from_problem(pa), ImpactBatch.from_problem(pb)
        oa, ob = ba.solve(condition=True), bb.solve(condition=True)
        vel = lambda o, b, n: (o["velocity"][0, b.body_index(n)], o["yaw_rate"][0, b.body_index(n)])  # noqa: E731
        pn_a, pn_b = oa["normal_impulse"][0], ob["normal_impulse"][0]
        get_a = lambda n: vel(oa, ba, n)  # noqa: E731
        get_b = lambda n: vel(ob, bb, n)  # noqa: E731
    else:
        ra, rb = solve_impact(pa), solve_impact(pb)
        pn_a, pn_b = ra.normal_impulse, rb.normal_impulse
        get_a = lambda n: (ra.bodies[n].velocity, ra.bodies[n].yaw_rate)  # noqa: E731
        get_b = lambda n: (rb.bodies[n].velocity, rb.bodies[n].yaw_rate)  # noqa: E731
    assert pn_a == pytest.approx(pn_b, rel=1e-9) and abs(pn_a) > 100.0
    for n in ("car", "truck", "second"):
        (va, wa), (vb, wb) = get_a(n), get_b(n)
        assert np.allclose(va, vb, rtol=1e-9, atol=1e-9) and wa == pytest.approx(wb, rel=1e-9, abs=1e-12)
    if not dense and struck != "dolly":  # the lock's moment closes the dolly's angular momentum balance (no crush on it)
        dolly = chain.body("dolly")
        hd = states["dolly"].heading
        lock = ra.hitches["lead-dolly"].lock_moment
        r1, r2 = ra.hitches["lead-dolly"].impulse, ra.hitches["dolly-second"].impulse
        b1, a2 = rotate(chain.hitches[1].rear_point, hd), rotate(chain.hitches[2].front_point, hd)
        change = dolly.yaw_inertia * (ra.bodies["dolly"].yaw_rate - states["dolly"].yaw_rate)
        cross = lambda a, b: a[0] * b[1] - a[1] * b[0]  # noqa: E731
        assert change == pytest.approx(-lock + cross(b1, -r1) + cross(a2, r2), rel=1e-9, abs=1e-6)
        assert abs(lock) > 1.0 and ra.hitches["truck-lead"].lock_moment is None
    vm, wm = get_b("merged")
    heading = states["lead"].heading
    for n, offset in (("lead", -cg), ("dolly", d2 - cg)):
        v, w = get_a(n)
        assert w == pytest.approx(wm, rel=1e-9, abs=1e-12)
        assert np.allclose(v, np.asarray(vm) + wm * perp(rotate(offset, heading)), rtol=1e-9, atol=1e-9)

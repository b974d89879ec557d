"""Every input error of the impact dataclasses is a ScenarioError that names the field and the value.

Each case builds one bad input and checks: the exception type (ScenarioError, also a
ValueError), its ``field`` attribute, and that the message contains the field and the
offending value (and, where there is one, the allowed range).
"""

from __future__ import annotations

import math

import pytest

from crashsim import (Axle, Body, BodyState, CrushSurface, ExternalImpulse, Hitch, ImpactBatch, ImpactProblem,
                      ScenarioError, TangentialLaw, Vehicle, VelocityConstraint, chain_states, solve_impact,
                      tyre_friction_impulse)

NAN, INF = math.nan, math.inf


def semi(name="A"):
    return Vehicle(name, (Body(f"{name}_tractor", 9500.0, 21000.0), Body(f"{name}_trailer", 20000.0, 150000.0)),
                   (Hitch((-3.1, 0.0), (3.991, 0.0)),))


def auto(name="B"):
    return Vehicle(name, (Body(f"{name}_car", 1500.0, 2800.0),))


def wall(name="wall"):
    return Vehicle(name, (Body(name, INF, INF),))


def scene(**kw):
    """Paper Fig. 6 (car B into A's trailer) with any ImpactProblem argument replaced."""
    A, B = semi(), auto()
    st = chain_states(A, (0.0, 0.0), 0.0, (13.41, 0.0))
    pt = (st["A_trailer"].position[0] - 2.517, -1.157)
    st.update(chain_states(B, (pt[0], pt[1] - 2.003), math.pi / 2, (0.0, 13.41)))
    args = dict(vehicles=(A, B), states=st, body1="A_trailer", body2="B_car",
                surface=CrushSurface(pt, math.pi / 2, 0.05, TangentialLaw("no_slide"), -1.0, -1))
    args.update(kw)
    return ImpactProblem(**args)


def states_with(name, **changes):
    st = dict(scene().states)
    s = st[name]
    st[name] = BodyState(changes.get("position", s.position), changes.get("heading", s.heading),
                         changes.get("velocity", s.velocity), changes.get("yaw_rate", s.yaw_rate))
    return st


def check(make, field, *fragments):
    with pytest.raises(ScenarioError) as info:
        make()
    err = info.value
    assert isinstance(err, ValueError)
    assert err.field == field
    msg = str(err)
    assert msg.startswith(f"{field}: "), msg
    for frag in fragments:
        assert frag in msg, (frag, msg)
    return err


# ------------------------------------------------------------------------------- crush surface

@pytest.mark.parametrize("e", [-0.1, 1.5, NAN, INF])
def test_restitution_out_of_range(e):
    check(lambda: CrushSurface((0, 0), 0.0, e), "impact.restitution", repr(e), "allowed [0, 1]")


@pytest.mark.parametrize("ep", [-0.5, -1.0000001, 1.5, -2.0, NAN])
def test_moment_restitution_not_minus_one_nor_in_unit_interval(ep):
    check(lambda: CrushSurface((0, 0), 0.0, 0.5, TangentialLaw(), ep), "impact.moment_restitution", repr(ep),
          "allowed -1 (no moment) or [0, 1]")


@pytest.mark.parametrize("ep", [-1.0, 0.0, 0.5, 1.0, -0.0])
def test_moment_restitution_accepted_values(ep):
    assert CrushSurface((0, 0), 0.0, 0.5, TangentialLaw(), ep).moment_restitution == ep


@pytest.mark.parametrize("sign", [0, 2, -2])
def test_tangent_sign(sign):
    check(lambda: CrushSurface((0, 0), 0.0, 0.5, TangentialLaw(), -1.0, sign), "impact.tangent", repr(sign),
          "+1 or -1")


@pytest.mark.parametrize("point", [(0.0, NAN), (1.0, 2.0, 3.0), (INF, 0.0)])
def test_contact_point(point):
    check(lambda: CrushSurface(point, 0.0, 0.5), "impact.point", repr(point))


@pytest.mark.parametrize("angle", [NAN, INF])
def test_normal_angle(angle):
    check(lambda: CrushSurface((0, 0), angle, 0.5), "impact.normal", repr(angle))


# ------------------------------------------------------------------------------- tangential law

@pytest.mark.parametrize("f", [-0.1, -1e-300])
def test_negative_friction(f):
    check(lambda: TangentialLaw("friction", f), "impact.friction", repr(f), ">= 0")


def test_unknown_tangential_law():
    check(lambda: TangentialLaw("coulomb", 0.3), "impact.tangential", "'coulomb'", "'ratio'", "'no_slide'",
          "'friction'")


@pytest.mark.parametrize("kind", ["ratio", "friction"])
@pytest.mark.parametrize("value", [NAN, INF, -INF])
def test_non_finite_law_value(kind, value):
    check(lambda: TangentialLaw(kind, value), f"impact.{kind}", repr(value))


def test_negative_ratio_is_allowed():
    assert TangentialLaw("ratio", -0.4).value == -0.4  # mu takes the sign of the tangent


# ------------------------------------------------------------------------------- bodies, vehicles, states

@pytest.mark.parametrize("attr, value", [("mass", -1.0), ("mass", 0.0), ("mass", NAN),
                                         ("yaw_inertia", -5.0), ("yaw_inertia", NAN)])
def test_body_mass_and_inertia(attr, value):
    kw = {"mass": 1500.0, "yaw_inertia": 2800.0, attr: value}
    check(lambda: Body("car", **kw), f"car.{attr}", repr(value), "(0, inf]")


@pytest.mark.parametrize("mass, inertia", [(INF, 2800.0), (1500.0, INF)])
def test_barrier_needs_both_infinite(mass, inertia):
    check(lambda: Body("x", mass, inertia), "x.mass", f"mass={float(mass)}", f"yaw_inertia={float(inertia)}")


@pytest.mark.parametrize("attr", ["length", "width", "cg_height"])
def test_body_dimensions(attr):
    check(lambda: Body("car", 1500.0, 2800.0, **{attr: -4.5}), f"car.{attr}", "-4.5")


def test_body_name():
    check(lambda: Body("", 1500.0, 2800.0), "name", "''")


def test_outline_center():
    check(lambda: Body("car", 1500.0, 2800.0, outline_center=(0.0, NAN)), "car.outline_center", "nan")


def test_axle():
    check(lambda: Axle(NAN, 1.8, name="steer"), "axle 'steer'.x", "nan")
    check(lambda: Axle(1.2, -1.8, name="steer"), "axle 'steer'.track", "-1.8")


@pytest.mark.parametrize("which", ["front_point", "rear_point"])
def test_hitch_points(which):
    kw = {"front_point": (-3.1, 0.0), "rear_point": (3.991, 0.0), which: (NAN, 0.0)}
    check(lambda: Hitch(**kw), f"hitch.{which}", "nan")


@pytest.mark.parametrize("limit", [0.0, -1.0, 4.0, NAN])
def test_hitch_articulation_limit(limit):
    check(lambda: Hitch((-3.1, 0.0), (3.991, 0.0), limit), "hitch.articulation_limit", repr(limit), "(0, pi]")


def test_vehicle_without_bodies():
    check(lambda: Vehicle("V", ()), "V.bodies", "at least one body")


def test_vehicle_hitch_count():
    check(lambda: Vehicle("V", (Body("a", 1.0, 1.0), Body("b", 1.0, 1.0))), "V.hitches", "2 bodies need 1", "got 0")


def test_vehicle_duplicate_body_names():
    check(lambda: Vehicle("V", (Body("a", 1.0, 1.0), Body("a", 1.0, 1.0)), (Hitch((-1, 0), (1, 0)),)),
          "V.bodies", "['a', 'a']")


def test_articulated_barrier():
    check(lambda: Vehicle("V", (Body("a", INF, INF), Body("b", 1.0, 1.0)), (Hitch((-1, 0), (1, 0)),)),
          "V.bodies", "barrier", "one body")


def test_vehicle_body_lookup():
    check(lambda: semi().body("A_dolly"), "A", "'A_dolly'", "A_tractor", "A_trailer")


@pytest.mark.parametrize("attr", ["heading", "yaw_rate"])
def test_body_state_angles(attr):
    kw = {"position": (0, 0), "heading": 0.0, "velocity": (0, 0), "yaw_rate": 0.0, attr: NAN}
    check(lambda: BodyState(**kw), attr, "nan")


@pytest.mark.parametrize("attr", ["position", "velocity"])
def test_body_state_vectors(attr):
    kw = {"position": (0, 0), "heading": 0.0, "velocity": (0, 0), attr: (1.0, INF)}
    check(lambda: BodyState(**kw), attr, "inf")


def test_chain_states_counts():
    check(lambda: chain_states(semi(), (0, 0), 0.0, (1, 0), yaw_rates=[0.0]), "A.yaw_rates", "needs 2", "got 1")
    check(lambda: chain_states(semi(), (0, 0), 0.0, (1, 0), articulation=[0.0, 0.1]), "A.articulation", "needs 1",
          "got 2")


# ------------------------------------------------------------------------------- constraints, external impulses

def test_constraint_fields():
    check(lambda: VelocityConstraint("A_tractor", (0.0, NAN), 0.0, name="lat"), "constraint 'lat'.point", "nan")
    check(lambda: VelocityConstraint("A_tractor", (0.0, 0.0), INF, name="lat"), "constraint 'lat'.direction", "inf")
    check(lambda: VelocityConstraint("A_tractor", (0.0, 0.0), 0.0, NAN, name="lat"), "constraint 'lat'.value", "nan")


def test_external_impulse_fields():
    check(lambda: ExternalImpulse("A_trailer", (0.0, INF), (0.0, -3260.0), "tyres"), "external 'tyres'.point", "inf")
    check(lambda: ExternalImpulse("A_trailer", (0.0, 0.0), (NAN, -3260.0), "tyres"), "external 'tyres'.impulse",
          "nan")


@pytest.mark.parametrize("arg", ["friction", "load", "duration"])
def test_tyre_friction_impulse(arg):
    kw = {"friction": 0.6, "load": 36222.0, "duration": 0.15, arg: -1.0}
    check(lambda: tyre_friction_impulse(direction=0.0, **kw), f"tyre_friction.{arg}", "-1.0", ">= 0")


# ------------------------------------------------------------------------------- the problem

@pytest.mark.parametrize("which", ["body1", "body2"])
def test_unknown_contact_body(which):
    check(lambda: scene(**{which: "A_dolly"}), f"impact.{which}", "'A_dolly'", "A_tractor", "B_car")


def test_contact_bodies_in_the_same_vehicle():
    check(lambda: scene(body1="A_tractor", body2="A_trailer"), "impact.body2", "'A_tractor'", "'A_trailer'",
          "same vehicle 'A'")


def test_contact_body_with_itself():
    check(lambda: scene(body1="B_car", body2="B_car"), "impact.body2", "'B_car'", "same vehicle 'B'")


def test_both_barriers():
    st = {"w1": BodyState((0, 0), 0.0, (0, 0)), "w2": BodyState((1, 0), 0.0, (0, 0))}
    check(lambda: ImpactProblem((wall("w1"), wall("w2")), st, "w1", "w2", CrushSurface((0, 0), 0.0, 0.5)),
          "vehicles", "both vehicles are barriers", "infinite mass")


def test_number_of_vehicles():
    p = scene()
    check(lambda: scene(vehicles=p.vehicles[:1]), "vehicles", "exactly 2", "got 1")


def test_body_names_unique_across_the_scene():
    check(lambda: scene(vehicles=(semi("A"), Vehicle("B", (Body("A_tractor", 1500.0, 2800.0),)))), "vehicles",
          "'A_tractor', 'A_trailer', 'A_tractor'")


def test_vehicle_names_unique():
    check(lambda: scene(vehicles=(semi("A"), Vehicle("A", (Body("B_car", 1500.0, 2800.0),)))), "vehicles",
          "['A', 'A']")


def test_missing_state():
    st = dict(scene().states)
    del st["A_trailer"]
    check(lambda: scene(states=st), "states.A_trailer", "'A_trailer'")


def test_state_for_unknown_body():
    st = dict(scene().states)
    st["A_dolly"] = st["A_trailer"]
    check(lambda: scene(states=st), "states.A_dolly", "'A_dolly'", "A_tractor")


def test_constraint_on_unknown_body():
    c = VelocityConstraint("A_dolly", (0.0, 0.0), 0.0, name="lat")
    check(lambda: scene(constraints=(c,)), "constraint 'lat'.body", "'A_dolly'", "B_car")


def test_constraint_on_a_barrier():
    A = auto("A")
    st = {"A_car": BodyState((0, 0), 0.0, (10.0, 0.0)), "wall": BodyState((2, 0), 0.0, (0, 0))}
    c = VelocityConstraint("wall", (2.0, 0.0), 0.0, name="hold")
    check(lambda: ImpactProblem((A, wall()), st, "A_car", "wall", CrushSurface((2, 0), math.pi, 0.5), (c,)),
          "constraint 'hold'.body", "'wall'", "barrier")


def test_external_impulse_on_unknown_body():
    x = ExternalImpulse("A_dolly", (0.0, 0.0), (0.0, -3260.0), "tyres")
    check(lambda: scene(external=(x,)), "external 'tyres'.body", "'A_dolly'", "A_trailer")


def test_pins_not_coinciding():
    s = scene().states["A_trailer"]
    st = states_with("A_trailer", position=(s.position[0] - 0.5, s.position[1]))
    check(lambda: scene(states=st), "states.A_trailer.position", "'A_tractor'", "'A_trailer'", "0.5 m apart",
          "allowed <= 0.001 m")


def test_pin_velocities_unequal_before_impact():
    s = scene().states["A_trailer"]
    st = states_with("A_trailer", velocity=(s.velocity[0], s.velocity[1] + 0.25))
    check(lambda: scene(states=st), "states.A_trailer.velocity", "'A_tractor'", "'A_trailer'", "differ by 0.25 m/s",
          "allowed <= 0.001 m/s")


def test_pin_velocities_unequal_through_yaw_rate():
    st = states_with("A_trailer", yaw_rate=0.1)  # kingpin 3.991 m ahead: 0.3991 m/s lateral mismatch
    check(lambda: scene(states=st), "states.A_trailer.velocity", "differ by 0.3991 m/s")


@pytest.mark.parametrize("flip", [math.pi, -math.pi / 2])
def test_contact_not_approaching(flip):
    """The relative contact velocity is (13.41, -13.41) m/s: the normal reversed (-y) or turned to
    +x sees the points separating at +13.41 m/s."""
    from dataclasses import replace
    p = scene()
    bad = replace(p, surface=replace(p.surface, normal_angle=p.surface.normal_angle + flip))
    check(lambda: solve_impact(bad), "impact.normal", "not approaching", "+13.41 m/s", "(must be < 0)",
          "from 'B_car' into 'A_trailer'")


def test_contact_at_rest_is_not_approaching():
    from dataclasses import replace
    A, B = auto("A"), auto("B")
    st = {"A_car": BodyState((0, 0), 0.0, (0, 0)), "B_car": BodyState((4, 0), math.pi, (0, 0))}
    p = ImpactProblem((A, B), st, "A_car", "B_car", CrushSurface((2, 0), math.pi, 0.5))
    check(lambda: solve_impact(p), "impact.normal", "+0 m/s")
    # a yaw rate alone can close the contact: then it is an impact
    st["A_car"] = BodyState((0, 0), 0.0, (0, 0), -1.0)  # point (2, 0) moves along -y
    ok = replace(p, states=st, surface=replace(p.surface, normal_angle=math.pi / 2))
    assert solve_impact(ok).closing_velocity == pytest.approx(-2.0)


def test_batch_size():
    p = scene()
    for n in (0, -3, 2.5):
        check(lambda: ImpactBatch.from_problem(p, n), "n", repr(n), ">= 1")
    check(lambda: ImpactBatch.from_problem(p, 2).body_index("A_dolly"), "body", "'A_dolly'", "B_car")


def test_duplicate_constraint_names():
    """Results are keyed by name: two constraints called 'lat' would lose one impulse."""
    c = (VelocityConstraint("A_tractor", (0.0, 0.0), math.pi / 2, 0.0, "lat"),
         VelocityConstraint("A_tractor", (1.0, 0.0), math.pi / 2, 0.0, "lat"))
    check(lambda: scene(constraints=c), "impact.constraints", "['lat']", "unique")


def test_duplicate_external_impulse_names():
    x = (ExternalImpulse("A_trailer", (0.0, 0.0), (0.0, -1000.0), "tyre"),
         ExternalImpulse("A_tractor", (0.0, 0.0), (0.0, -2000.0), "tyre"))
    check(lambda: scene(external=x), "impact.external_impulses", "['tyre']", "unique")


def test_unnamed_constraints_are_not_duplicates():
    c = (VelocityConstraint("A_tractor", (0.0, 0.0), math.pi / 2), VelocityConstraint("A_tractor", (1.0, 0.0), math.pi / 2))
    assert len(scene(constraints=c).constraints) == 2

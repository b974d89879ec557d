"""Static wheel loads from moment balance (note sec. 2.6): totals and the closed-form formulas."""

from __future__ import annotations

import pytest
from runout_cases import G, car, tractor_semitrailer

from crashsim.errors import ScenarioError
from crashsim.motion import static_loads
from crashsim.vehicles import Axle, Body, Hitch, Vehicle


def test_car_two_axles():
    veh = car()
    loads = static_loads(veh)
    w = veh.mass * G
    a, b = 1.1, 1.5
    assert loads.axle["car"] == pytest.approx([w * b / (a + b), w * a / (a + b)], rel=1e-12)
    assert loads.total == pytest.approx(w, rel=1e-12)
    assert loads.wheel == pytest.approx([w * b / (a + b) / 2] * 2 + [w * a / (a + b) / 2] * 2, rel=1e-12)


def test_tractor_semitrailer_kingpin_formula():
    veh = tractor_semitrailer()
    tractor, trailer = veh.bodies
    loads = static_loads(veh)
    w1, w2 = tractor.mass * G, trailer.mass * G
    x_k = veh.hitches[0].rear_point[0]
    x_t = sum(a.x for a in trailer.axles) / 3
    n_kp = w2 * (0 - x_t) / (x_k - x_t)
    assert loads.hitch[0] == pytest.approx(n_kp, rel=1e-12)
    assert loads.axle["trailer"] == pytest.approx([(w2 - n_kp) / 3] * 3, rel=1e-12)
    x_f, x_r, x_5 = tractor.axles[0].x, (tractor.axles[1].x + tractor.axles[2].x) / 2, veh.hitches[0].front_point[0]
    n_f = (w1 * (0 - x_r) + n_kp * (x_5 - x_r)) / (x_f - x_r)
    assert loads.axle["tractor"] == pytest.approx([n_f, (w1 + n_kp - n_f) / 2, (w1 + n_kp - n_f) / 2], rel=1e-12)
    assert loads.total == pytest.approx(w1 + w2, rel=1e-12)
    assert loads.groups["tractor"] == ((0,), (1, 2))


def test_paper_trailer_axle_load():
    """The Table 6 empty trailer (6000 kg, CG 3.991 m behind the pin) with its axle group 2.494 m behind
    the CG carries 36 222 N of its 58 860 N weight on its wheels (the paper's figures, with g = 9.81),
    the share the benchmark's axle layout was chosen to reproduce."""
    trailer = Body("trailer", 6000.0, 48000.0, axles=(Axle(-1.844, 1.85, True), Axle(-3.144, 1.85, True)))
    tractor = Body("tractor", 9500.0, 21000.0, axles=(Axle(1.6, 2.05), Axle(-2.75, 1.85, True), Axle(-4.05, 1.85, True)))
    veh = Vehicle("A", (tractor, trailer), (Hitch((-3.1, 0.0), (3.991, 0.0)),))
    loads = static_loads(veh)
    assert loads.axle["trailer"].sum() / (6000.0 * G) == pytest.approx(36222.0 / (6000.0 * 9.81), rel=1e-4)


def test_doubles_chain_passes_loads_down():
    """Tractor + semitrailer + converter dolly + second semitrailer: every hitch load follows from the body
    behind it, and the total equals the weight."""
    tractor = Body("tractor", 8000.0, 30000.0, axles=(Axle(1.5, 2.0), Axle(-2.0, 1.8, True)))
    trailer1 = Body("trailer1", 12000.0, 100000.0, axles=(Axle(-3.5, 1.8, True),))
    dolly = Body("dolly", 1200.0, 800.0, axles=(Axle(0.0, 1.8, True),))
    trailer2 = Body("trailer2", 12000.0, 100000.0, axles=(Axle(-3.5, 1.8, True),))
    veh = Vehicle(
        "doubles",
        (tractor, trailer1, dolly, trailer2),
        (Hitch((-1.8, 0.0), (4.0, 0.0)), Hitch((-5.0, 0.0), (2.5, 0.0)), Hitch((0.1, 0.0), (4.0, 0.0))),
    )
    loads = static_loads(veh)
    w = [b.mass * G for b in veh.bodies]
    assert loads.total == pytest.approx(sum(w), rel=1e-12)
    # rear trailer on the dolly's fifth wheel
    p3 = w[3] * 3.5 / (4.0 + 3.5)
    assert loads.hitch[2] == pytest.approx(p3, rel=1e-12)
    # dolly: drawbar-eye load from its moment balance about its axle at x = 0
    p2 = (w[2] * 0.0 + p3 * 0.1) / 2.5
    assert loads.hitch[1] == pytest.approx(p2, rel=1e-12)
    assert loads.axle["dolly"][0] == pytest.approx(w[2] + p3 - p2, rel=1e-12)
    # first trailer carries the drawbar-eye load at x = -5
    p1 = (w[1] * 3.5 + p2 * (-5.0 + 3.5)) / (4.0 + 3.5)
    assert loads.hitch[0] == pytest.approx(p1, rel=1e-12)


@pytest.mark.parametrize(
    "bodies, hitches, field",
    [
        ((Body("c", 1000.0, 1000.0, axles=(Axle(0.5, 1.5),)),), (), "c.axles"),
        ((Body("c", 1000.0, 1000.0, axles=(Axle(1.0, 1.5), Axle(0.0, 1.5), Axle(-1.0, 1.5))),), (), "c.axles"),
        (
            (Body("t", 1000.0, 1000.0, axles=(Axle(1.0, 1.5), Axle(-1.0, 1.5))), Body("s", 1000.0, 1000.0)),
            (Hitch((-1.0, 0.0), (3.0, 0.0)),),
            "s.axles",
        ),
        (
            (Body("t", 1000.0, 1000.0, axles=(Axle(1.0, 1.5), Axle(-1.0, 1.5))), Body("s", 1000.0, 1000.0, axles=(Axle(3.0, 1.5),))),
            (Hitch((-1.0, 0.0), (3.0, 0.0)),),
            "hitches[0].rear_point",
        ),
        ((Body("c", 1000.0, 1000.0, axles=(Axle(2.0, 1.5), Axle(1.0, 1.5))),), (), "c.axles[0].x"),
    ],
    ids=["one-axle-car", "equal-gaps", "towed-without-axles", "hitch-on-axle", "cg-outside-wheelbase"],
)
def test_indeterminate_or_impossible_layouts_raise(bodies, hitches, field):
    with pytest.raises(ScenarioError) as err:
        static_loads(Vehicle("v", bodies, hitches))
    assert field in str(err.value)

"""Vehicles and closed forms shared by the run-out tests (analytic and cross-check tiers).

The vehicles are invented but plausible; no expected result depends on their numbers except
through the closed forms below.
"""

from __future__ import annotations

import math

from crashsim.motion.loads import STANDARD_GRAVITY as G
from crashsim.vehicles import Axle, Body, Hitch, Vehicle

__all__ = [
    "G",
    "GLOBAL",
    "CAR_TYRE",
    "TRUCK_TYRE",
    "symmetric_car",
    "car",
    "tractor_semitrailer",
    "regularised_slide",
    "regularised_work",
]

#: Allowance for the global error of an adaptive solver relative to ``rtol * scale``.  These
#: run-outs are dissipative (errors are damped, not amplified), so the global error stays
#: within tens of local tolerances; measured ratios are below 5 for the straight slides.
GLOBAL = 50

#: Car tyre data: 15 %/deg of load (8.6 /rad), rolling resistance 0.012 (note sec. 2.5).
CAR_TYRE = dict(cornering_coefficient=8.6, rolling_resistance=0.012)
#: Truck tyre data: 0.105 /deg of load (6.0 /rad), rolling resistance 0.007 (note sec. 2.5).
TRUCK_TYRE = dict(cornering_coefficient=6.0, rolling_resistance=0.007)


def symmetric_car(name: str = "car") -> Vehicle:
    """Car with its CG midway between the axles: four equal loads, all at the same distance from the CG."""
    return Vehicle(
        name,
        (Body(name, 1500.0, 2500.0, length=4.5, axles=(Axle(1.3, 1.5, name="front"), Axle(-1.3, 1.5, name="rear"))),),
    )


def car(name: str = "car", cg_height: float | None = None) -> Vehicle:
    """Car with the CG 1.1 m behind the front axle and 1.5 m ahead of the rear axle."""
    return Vehicle(
        name,
        (
            Body(
                name,
                1500.0,
                2800.0,
                length=4.6,
                axles=(Axle(1.1, 1.5, name="front"), Axle(-1.5, 1.5, name="rear")),
                cg_height=cg_height,
            ),
        ),
    )


def tractor_semitrailer(articulation_limit: float | None = None) -> Vehicle:
    """Three-axle tractor (8 t) and loaded tri-axle semitrailer (25 t), the note's sec. 1.5 masses."""
    tractor = Body(
        "tractor",
        8000.0,
        32000.0,
        length=6.0,
        axles=(Axle(1.9, 2.05, name="steer"), Axle(-1.6, 1.85, True, "drive 1"), Axle(-2.9, 1.85, True, "drive 2")),
    )
    trailer = Body(
        "trailer",
        25000.0,
        330000.0,
        length=13.6,
        axles=(Axle(-3.0, 1.85, True, "t1"), Axle(-4.3, 1.85, True, "t2"), Axle(-5.6, 1.85, True, "t3")),
    )
    return Vehicle("ts", (tractor, trailer), (Hitch((-2.0, 0.0), (6.0, 0.0), articulation_limit=articulation_limit),))


def regularised_slide(v0: float, v_end: float, eps: float, decel: float) -> tuple[float, float]:
    """Distance and time of a straight slide with ``a(v) = decel * v / sqrt(v^2 + eps^2)`` from v0 to v_end.

    Closed form of the regularised Coulomb law used by the tyre model:
    ``x = [F(v0) - F(v_end)] / decel`` with ``F(v) = (v sqrt(v^2+eps^2) + eps^2 asinh(v/eps)) / 2``, and
    ``t = [T(v0) - T(v_end)] / decel`` with ``T(v) = sqrt(v^2+eps^2) - eps asinh(eps/v)``.
    """

    def F(v):
        return 0.5 * (v * math.hypot(v, eps) + eps * eps * math.asinh(v / eps))

    def T(v):
        return math.hypot(v, eps) - eps * math.asinh(eps / v)

    return (F(v0) - F(v_end)) / decel, (T(v0) - T(v_end)) / decel


def regularised_work(v0: float, v_end: float, eps: float) -> float:
    """``integral_{v_end}^{v0} sqrt(v^2 + eps^2) dv`` [m^2/s^2]: friction work per unit mass and unit mu g."""
    return regularised_slide(v0, v_end, eps, 1.0)[0]


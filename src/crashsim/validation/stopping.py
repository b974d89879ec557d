"""FMVSS 121 road test: a loaded truck tractor's stopping distance from 60 mph (and from 20 mph).

49 CFR 571.121, S5.3.1.1 and Table II as amended in 2009 (74 FR 37122): a loaded truck tractor stops
from 60 mph within 250 ft; the 2011 reconsideration (76 FR 44829) keeps 32 ft from 20 mph. The set-up
is the standard's procedure, with what it leaves open stated (``docs/heavy-vehicles.md``, "Validation:
the FMVSS 121 stop"; ``validation/fmvss121-stop/README.md``):

* a typical three-axle (6x4) truck tractor at its GVWR of 52,000 lb (steer axle 12,000 lb, drive
  tandem 40,000 lb, their usual ratings), loaded through its fifth wheel by an *unbraked* flatbed
  control semitrailer whose single axle carries 4,500 lb;
* a straight stop with a full brake application at time 0 (the distance is measured from the first
  movement of the control), the tractor's ABS active;
* a level, dry test surface of peak friction 0.9; an ABS wheel uses it at the efficiency ``eta``;
* typical brakes: the tractor's default air timing (S5.3.3: 60 psi within 0.45 s), capacities of 60 kN
  (steer) and 100 kN (each drive axle) at full application, ABS efficiency 0.85; truck tyres
  (6 /rad, rolling resistance 0.007).

The standard's limit is the band (one-sided): the stop passes at or below it. What it does not show:
that any particular tractor complies, nor that the ABS model's efficiency is right (the margin scales
with it).
"""

from __future__ import annotations

import time
from pathlib import Path

from ..motion import Road, RunoutOptions, simulate_runout
from ..motion.brakes import AirBrakes, BrakeUnit
from ..motion.wheels import WheelSetting, WheelSettings
from ..units import Kind
from ..vehicles import Axle, Body, Hitch, Vehicle, chain_states
from .core import CaseResult, Quantity, quantity

__all__ = ["LB", "fmvss_tractor_with_control_trailer", "stopping_distance", "run_case"]

LB = 0.45359237  # kg per lb (mass)
IN = 0.0254


def fmvss_tractor_with_control_trailer() -> Vehicle:
    """The tractor at GVWR on an unbraked single-axle control semitrailer (module docstring)."""
    w_tractor_axles = 52000.0 * LB  # steer + drive, kingpin load included [kg]
    w_trailer_axle = 4500.0 * LB
    m2 = 2 * w_trailer_axle  # CG midway between kingpin and axle: half on each
    m1 = w_tractor_axles - w_trailer_axle
    wheelbase = 5.5  # steer axle to the drive tandem's centre [m]
    x_r = -12000.0 * LB / m1 * wheelbase  # the tractor's own weight puts 12,000 lb on the steer axle
    x_f = x_r + wheelbase
    tractor = Body("tractor", m1, 60000.0, length=7.0, width=2.5, outline_center=(x_f - 4.6 + 3.5, 0.0),
                   axles=(Axle(x_f, 2.05, name="steer"), Axle(x_r + 0.65, 1.85, True, "drive 1"),
                          Axle(x_r - 0.65, 1.85, True, "drive 2")), cg_height=1.1)
    half = 0.5 * 258.0 * IN  # S6.1.10.3: the axle 258 in behind the kingpin, the CG midway [m]
    trailer = Body("control", m2, 80000.0, length=8.5, width=2.5, axles=(Axle(-half, 1.85, True, "axle"),),
                   cg_height=1.2)
    return Vehicle("truck", (tractor, trailer), (Hitch((x_r, 0.0), (half, 0.0)),))


def stopping_distance(speed: float, engine: str = "compiled", friction: float = 0.9):
    """Stopping distance [m] of the tractor's CG from ``speed`` [m/s], and the run-out (module docstring)."""
    veh = fmvss_tractor_with_control_trailer()
    brakes = AirBrakes({"tractor": BrakeUnit((60e3, 100e3, 100e3), "tractor", abs=True)}, apply=0.0,
                       abs_efficiency=0.85)
    tyre = WheelSetting("rolling", cornering_coefficient=6.0, rolling_resistance=0.007)
    init = chain_states(veh, (0.0, 0.0), 0.0, (speed, 0.0))
    res = simulate_runout(veh, init, WheelSettings(default=tyre, brakes=brakes), Road(friction),
                          RunoutOptions(engine=engine))
    return res.bodies["tractor"].rest_position[0], res


def run_case(data: dict, rules: dict, suite_folder: Path) -> CaseResult:
    """Each stop of ``measured.toml``'s ``[[stop]]`` tables against its limit."""
    t0 = time.process_time()
    f = data["folder"] / "measured.toml"
    q = []
    figure = {"stops": []}
    for i, s in enumerate(data["stop"]):
        v0 = quantity(s["speed"], Kind.SPEED, f"stop[{i}].speed", f)
        limit = quantity(s["limit"], Kind.LENGTH, f"stop[{i}].limit", f)
        d, res = stopping_distance(v0, rules["runout"]["engine"], float(data["test"]["surface_friction"]))
        q.append(Quantity(data["case"]["id"], f"stopping distance from {s['speed']}", "stopping distance", "length",
                          limit, d, "limit", d - limit, 0.0, "stated: the standard's limit (one-sided)", s["source"],
                          {}, "US", "status: at rest" if res.status == "rest" else f"status: {res.status}"))
        h = res.bodies["tractor"].history
        figure["stops"].append({"label": s["speed"], "t": h.t, "x": h.x, "limit": limit})
    return CaseResult(data["case"]["id"], data["case"]["title"], data["case"]["kind"], data["case"]["class"],
                      data["case"].get("configuration", ""), tuple(x.with_record(data["record"]) for x in q),
                      (), figure, time.process_time() - t0, data["record"])

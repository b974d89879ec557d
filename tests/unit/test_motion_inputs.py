"""Unit tests of the run-out inputs: wheel settings and selectors, roads and zones, options, state layout."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from crashsim.errors import ScenarioError
from crashsim.motion import (
    FrictionZone,
    Road,
    RunoutOptions,
    ScheduledChange,
    StateLayout,
    WheelSetting,
    WheelSettings,
)
from crashsim.motion.road import points_in_polygon, signed_distance
from crashsim.vehicles import Axle, Body, BodyState, Hitch, Vehicle

TYRE = dict(cornering_coefficient=8.6, rolling_resistance=0.012)


def _truck():
    tractor = Body("tractor", 8000.0, 30000.0, axles=(Axle(1.9, 2.0, name="steer"), Axle(-1.6, 1.8, True, "drive")))
    trailer = Body("trailer", 20000.0, 200000.0, axles=(Axle(-3.0, 1.8, True), Axle(-4.3, 1.8, True)))
    return Vehicle("ts", (tractor, trailer), (Hitch((-1.5, 0.0), (5.0, 0.0)),))


# ---------------------------------------------------------------- wheel settings
def test_selectors_from_general_to_specific():
    ws = WheelSettings(
        default=WheelSetting("rolling", **TYRE),
        wheels={
            "trailer": WheelSetting("locked"),
            "tractor/drive": WheelSetting("braked", brake=0.5, **TYRE),
            "trailer/1/right": WheelSetting("jammed", mu_factor=0.6),
        },
    )
    settings_ = dict(zip([s.key for s in ws.resolve(_truck()).specs], ws.resolve(_truck()).at(0.0)))
    assert settings_["tractor/0/left"].state == "rolling"
    assert settings_["tractor/1/right"].state == "braked"
    assert settings_["trailer/0/left"].state == "locked"
    assert settings_["trailer/1/right"].state == "jammed" and settings_["trailer/1/right"].mu_factor == 0.6
    assert settings_["trailer/1/left"].state == "locked"


def test_schedule_changes_apply_from_their_time_on():
    ws = WheelSettings(
        default=WheelSetting("braked", brake=0.7, **TYRE),
        schedule=[ScheduledChange(0.5, "tractor", {"state": "rolling"}), ScheduledChange(1.2, "*", {"state": "locked"})],
    )
    r = ws.resolve(_truck())
    assert r.change_times == (0.5, 1.2)
    assert r.at(0.49)[0].state == "braked" and r.at(0.5)[0].state == "rolling" and r.at(0.5)[0].brake == 0.0
    assert r.at(0.5)[-1].state == "braked"
    assert all(s.state == "locked" for s in r.at(5.0))


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: WheelSetting("skidding"), "state: must be one of"),
        (lambda: WheelSetting("braked", brake=1.5), "brake: brake fraction must lie in"),
        (lambda: WheelSetting("rolling", brake=0.3), "brake: a brake fraction"),
        (lambda: WheelSetting("rolling", steer=2.0), "steer: must lie in"),
        (lambda: WheelSetting("rolling", cornering_stiffness=-1.0), "cornering_stiffness: must be a positive"),
        (lambda: WheelSetting("rolling", cornering_stiffness=1e4, cornering_coefficient=8.0), "not both"),
        (lambda: WheelSetting("rolling", rolling_resistance=0.9), "rolling_resistance: must lie in"),
        (lambda: WheelSetting("jammed", mu_factor=0.0), "mu_factor: must lie in"),
        (lambda: ScheduledChange(-1.0, "*", {"state": "locked"}), "schedule.time"),
        (lambda: ScheduledChange(1.0, "*", {"sate": "locked"}), "best matches are \\['state'"),
    ],
)
def test_invalid_wheel_settings_name_field_and_range(make, match):
    with pytest.raises(ScenarioError, match=match):
        make()


@pytest.mark.parametrize(
    "ws, match",
    [
        (WheelSettings(wheels={"tractor": WheelSetting("locked")}), "has no setting"),
        (WheelSettings(default=WheelSetting("locked"), wheels={"tractr": WheelSetting("locked")}), "best matches are \\['tractor'"),
        (WheelSettings(default=WheelSetting("locked"), wheels={"tractor/5": WheelSetting("locked")}), "no axle '5'"),
        (WheelSettings(default=WheelSetting("locked"), wheels={"tractor/0/up": WheelSetting("locked")}), "side must be"),
        (WheelSettings(default=WheelSetting("rolling")), "needs cornering_stiffness"),
        (WheelSettings(default=WheelSetting("rolling", cornering_coefficient=8.0)), "needs rolling_resistance"),
        (
            WheelSettings(
                default=WheelSetting("locked"),
                wheels={"tractor/0": WheelSetting("locked"), "tractor/steer": WheelSetting("jammed")},
            ),
            "both set wheel",
        ),
        (
            WheelSettings(default=WheelSetting("locked"), schedule=[ScheduledChange(1.0, "trailer", {"state": "rolling"})]),
            "t >= 1.0 s",
        ),
    ],
)
def test_resolution_errors(ws, match):
    with pytest.raises(ScenarioError, match=match):
        ws.resolve(_truck())


# ---------------------------------------------------------------- road and zones
L_SHAPE = ((0.0, 0.0), (4.0, 0.0), (4.0, 1.0), (1.0, 1.0), (1.0, 4.0), (0.0, 4.0))


def test_point_in_non_convex_polygon():
    pts = np.array([[0.5, 0.5], [3.0, 0.5], [0.5, 3.0], [3.0, 3.0], [-1.0, 0.5], [2.0, 2.0]])
    assert points_in_polygon(pts, L_SHAPE).tolist() == [True, True, True, False, False, False]
    # orientation does not matter
    assert points_in_polygon(pts, L_SHAPE[::-1]).tolist() == [True, True, True, False, False, False]


def test_signed_distance_is_continuous_and_zero_on_edges():
    assert signed_distance([[0.5, 0.5], [3.0, 3.0], [1.0, 2.0]], L_SHAPE) == pytest.approx([0.5, -2.0, 0.0])
    # along a line crossing the concave corner: |d(p) - d(q)| <= |p - q| (1-Lipschitz, no jumps)
    s = np.linspace(-1, 5, 60001)
    pts = np.stack([s, 0.6 * s + 0.3], 1)
    d = signed_distance(pts, L_SHAPE)
    assert np.max(np.abs(np.diff(d))) <= np.max(np.hypot(*np.diff(pts, axis=0).T)) * (1 + 1e-9)
    assert np.any(d > 0) and np.any(d < 0)


@settings(max_examples=200, deadline=None)
@given(st.floats(-2, 6), st.floats(-2, 6))
def test_signed_distance_sign_matches_inside_test(x, y):
    d = float(signed_distance([[x, y]], L_SHAPE)[0])
    if abs(d) > 1e-9:
        assert (d > 0) == bool(points_in_polygon([[x, y]], L_SHAPE)[0])


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: Road(0.0), "road.mu: friction coefficient must lie in"),
        (lambda: Road(2.5), "road.mu"),
        (lambda: FrictionZone(((0, 0), (1, 0)), 0.5), "polygon must be"),
        (lambda: FrictionZone(((0, 0), (1, 0), (2, 0)), 0.5), "zero area"),
        (lambda: FrictionZone(((0, 0), (4, 4), (4, 0), (0, 3)), 0.5, "bow"), "zone 'bow'.polygon: polygon edges 0 and 2 cross"),
        (lambda: FrictionZone(((0, 0), (1, 0), (1, 1)), -0.1), "mu"),
    ],
)
def test_invalid_roads(make, match):
    with pytest.raises(ScenarioError, match=match):
        make()


def test_later_zones_take_precedence():
    road = Road(0.8, (FrictionZone(((0, 0), (10, 0), (10, 10), (0, 10)), 0.5), FrictionZone(((5, 5), (6, 5), (6, 6)), 0.2)))
    assert road.mu_at([[1, 1], [5.9, 5.2], [20, 20]]).tolist() == [0.5, 0.2, 0.8]


# ---------------------------------------------------------------- options and layout
@pytest.mark.parametrize(
    "kwargs, match",
    [
        (dict(method="Euler"), "options.method"),
        (dict(rtol=0.0), "options.rtol"),
        (dict(eps=-1.0), "options.eps"),
        (dict(v_stop=1e-5), "options.v_stop: must be >= eps/10"),
        (dict(t_max=float("nan")), "options.t_max"),
        (dict(lateral_model="pacejka"), "options.lateral_model"),
    ],
)
def test_invalid_options(kwargs, match):
    with pytest.raises(ScenarioError, match=match):
        RunoutOptions(**kwargs)


def test_layout_round_trip_and_named_slices():
    layout = StateLayout(("a", "b"), accel_filter=True)
    states = {"a": BodyState((1, 2), 0.3, (4, 5), 0.6), "b": BodyState((7, 8), 0.9, (10, 11), 1.2)}
    y = layout.pack(states)
    assert y.size == layout.size == 16
    assert y[layout.x].tolist() == [1, 7] and y[layout.w].tolist() == [0.6, 1.2]
    assert y[layout.index("vy", "b")] == 11
    assert layout.unpack(y) == states
    assert layout.body_columns(y, "b").tolist() == [7, 8, 0.9, 10, 11, 1.2]
    with pytest.raises(ScenarioError, match="no initial state for body 'b'"):
        layout.pack({"a": states["a"]})

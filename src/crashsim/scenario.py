"""Scenario files: one TOML file per scene, strictly validated, units written with each value.

The schema below is the single definition of the file format: :func:`load_scenario`
validates against it and ``crashsim schema`` prints it (:func:`schema_document`). Values
are converted to SI once, here; everything downstream is SI.

Frames: the world frame of the scene (X, Y, angles counter-clockwise from +X). A point or
direction may instead be given in a body's axes (origin at its CG, x forward, y left) by
naming the body in the matching ``*_frame`` / ``frame`` key.
"""

from __future__ import annotations

import copy
import dataclasses
import difflib
import math
import re
import tomllib
from dataclasses import dataclass, field, replace as _replace
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

from .errors import ScenarioError, with_file
from .evidence.checks import (CORNERS, DeltaVEvidence, Evidence, ImpactPointEvidence, MarkEvidence, RolloverEvidence,
                              RecorderEvidence, RestEvidence, named_body_points, register_points)
from .geometry import rotate
from .impact import (CrushSurface, ExternalImpulse, ImpactProblem, TangentialLaw, VelocityConstraint,
                     tyre_friction_impulse)
from .motion import (LATERAL_MODELS, METHODS, WHEEL_STATES, ContactModel, FrictionZone, Obstacle, Road, RunoutOptions,
                     ScheduledChange, WheelSetting, WheelSettings)
from .motion.brakes import MAX_BRAKE_TIME, MAX_CAPACITY, UNIT_TYPES, AirBrakes, BrakeUnit, unit_type_default
from .motion.contact import CONTACT_KEYS, WEIGHT_DEPTH
from .motion.road import MAX_SLOPE
from .motion.levels import LEVELS
from .motion.wheels import select_wheels, enumerate_wheels
from .schema import (ArrayOf, Field, ScenarioValidationError, Section, Table, document, load_toml, validate,
                     validate_collect)
from .survey.schema import MAP_LINE_STYLES, SURVEY
from .units import SPEED_UNITS, DisplaySystem, Kind, format_value, parse, toml_repr
from .vehicles import MAX_ROLLOVER_THRESHOLD, Axle, Body, BodyState, Hitch, Vehicle, chain_states

__all__ = ["SCHEMA", "MAP_LINE_STYLES", "MapLine", "Scenario", "RunoutSpec", "load_scenario", "presets", "preset_geometry",
           "scenario_from_dict", "schema_document"]

# ----------------------------------------------------------------------------------------
# The schema (validates and documents)

# Plausibility bounds (SI): far outside anything on a road, so a typing slip ("1e6 mph") is an
# error at load instead of a run-out that never ends.  The fastest production cars reach about
# 135 m/s; heavy-haulage combinations about 200 t; a 20 m trailer of 40 t has a yaw inertia of
# about 1.5e6 kg m^2.
MAX_SPEED = 150.0           # m/s (335.5 mph)
MAX_YAW_RATE = 15.0         # rad/s (860 deg/s)
MAX_MASS = 250_000.0        # kg
MAX_YAW_INERTIA = 5.0e7     # kg m^2
MAX_LENGTH = 40.0           # m (body length, axle offset)
MAX_WIDTH = 6.0             # m
MAX_TRACK = 4.0             # m
MAX_CONTACT_HEIGHT = 5.0    # m (above the tallest road vehicles: 4.0 m in the EU, 13 ft 6 in in most US states)

AXLE = Section("axle", [
    Field("name", "str", default="", description="Label (\"steer\", \"drive 1\"); selects wheels as <body>/<name>"),
    Field("x", Kind.LENGTH, minimum=-MAX_LENGTH, maximum=MAX_LENGTH, example="-3.2 m",
          description="Axle position from the body CG, forward positive"),
    Field("track", Kind.LENGTH, minimum=0, maximum=MAX_TRACK, exclusive_minimum=True, example="2.05 m",
          description="Distance between the left and right tyre contact centres"),
    Field("dual", "bool", default=False, description="Dual tyres on each side (one contact per side, summed)"),
], description="One axle (each axle of a tandem group separately), for the run-out")

#: Default of a body's ``drawbar`` [m]: how far its hitch points may lie outside its outline.
#: Measured: 1.10 m for the tongue of a random trailer in a regression scene, 0.8 m for the
#: car-trailer preset's coupling, 0.3 m for tow balls of the shipped scenes.
DEFAULT_DRAWBAR = 1.5
#: Default of a body's ``overhang`` [m]: how far its tyre contacts may lie beyond the outline's ends
#: and beyond its sides. Lengthwise 2 m: a tractor of a reproducer scene (random, kept verbatim)
#: has its rear drive axle 1.45 m behind its outline, and it must still load; sideways 0.15 m (half
#: a tyre's width: the track is measured between tyre centres).
DEFAULT_OVERHANG = (2.0, 0.15)
#: Default of ``impact.overlap_tolerance`` [m]: how deep two vehicles' outlines may overlap at the
#: impact: the impact's bodies along its normal (their crush), other pairs by the distance to clear
#: each other. The shipped scenes overlap by up to 0.64 m, the reproducer scenes' impact pairs by up
#: to 1.11 m; a regression scene (random, kept verbatim, it must still load) has a tractor 1.90 m
#: into a trailer that is not in the impact. A car put crosswise on a trailer: 2.5 m.
DEFAULT_OVERLAP = 2.0

BODY = Section("body", [
    Field("preset", "str", required=False, example="tractor-3axle",
          description="Name of a parameter set of crashsim's vehicle library (crashsim presets); keys given here override it"),
    Field("name", "str", description="Body name, unique in the scene (results are keyed by it)",
          example='tractor'),
    Field("mass", Kind.MASS, minimum=0, maximum=MAX_MASS, exclusive_minimum=True, example="9500 kg",
          description="Mass (a weight such as \"20945 lbf\" is accepted and divided by g0)"),
    Field("yaw_inertia", Kind.YAW_INERTIA, minimum=0, maximum=MAX_YAW_INERTIA, exclusive_minimum=True,
          example="21000 kg m^2",
          description="Yaw moment of inertia about the CG"),
    Field("yaw_rate", Kind.ANGULAR_VELOCITY, minimum=-MAX_YAW_RATE, maximum=MAX_YAW_RATE, default="0 rad/s",
          description="Yaw rate just before the impact (counter-clockwise positive)"),
    Field("length", Kind.LENGTH, required=False, minimum=0, maximum=MAX_LENGTH, exclusive_minimum=True,
          example="6.0 m",
          description="Overall length of the outline (plots)"),
    Field("width", Kind.LENGTH, required=False, minimum=0, maximum=MAX_WIDTH, exclusive_minimum=True,
          example="2.5 m",
          description="Overall width of the outline (plots)"),
    Field("outline_center", Kind.LENGTH, n=2, default=["0 m", "0 m"],
          description="Centre of the outline rectangle in body axes"),
    Field("rear_hitch", Kind.LENGTH, n=2, required=False, example='["-3.1 m", "0 m"]',
          description="Pin towing the next body (fifth wheel, ball), in this body's axes; "
                      "required on every body but the last"),
    Field("front_hitch", Kind.LENGTH, n=2, required=False, example='["3.991 m", "0 m"]',
          description="Pin by which this body is towed (kingpin, drawbar eye), in this body's axes; "
                      "required on every body but the first"),
    Field("articulation", Kind.ANGLE, default="0 deg",
          description="Articulation at the front hitch: heading of the towing body minus this body's"),
    Field("articulation_limit", Kind.ANGLE, required=False, minimum=0, maximum=math.pi,
          exclusive_minimum=True, example="80 deg",
          description="Largest articulation before the bodies meet (jack-knife stop)"),
    Field("cg_height", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="1.1 m",
          description="CG height above ground (only for the run-out's load transfer)"),
    Field("contact_height", Kind.LENGTH, required=False, minimum=0, maximum=MAX_CONTACT_HEIGHT,
          exclusive_minimum=True, example="0.5 m",
          description="Height above ground at which contact forces (other vehicles, obstacles) act on this body, "
                      "only for the run-out's load transfer: below the CG a side push rolls the body toward it; "
                      "default: the CG height (a push there moves no load)"),
    Field("yaw_locked", "bool", default=False,
          description="The front hitch is locked in yaw at zero articulation: a C-dolly (two drawbars) on the trailer "
                      "ahead, which must itself be towed (bodies[2] or later); free in pitch. Its articulation is 0, "
                      "its yaw rate that of the body ahead, and an articulation_limit (e.g. from a preset) is not used"),
    Field("roll_coupled", "bool", default=False,
          description="The hitch towing this body carries roll moment (a fifth wheel, stiff in roll): with load "
                      "transfer its roll moment is shared with the towing body in proportion to the hitch's static "
                      "load; false (default): free in roll, as a ball or a drawbar eye"),
    Field("rollover_threshold", "float", required=False, minimum=0, exclusive_minimum=True,
          maximum=MAX_ROLLOVER_THRESHOLD, example="0.35",
          description="Lateral acceleration in g at which this body rolls (static rollover threshold, e.g. a "
                      "tilt-table value); turns the wheel-lift and rollover check on (level load_transfer); "
                      "default 0.75 t / (2 h) from the mean track t and cg_height h"),
    Field("drawbar", Kind.LENGTH, minimum=0, maximum=MAX_LENGTH, default=f"{DEFAULT_DRAWBAR:g} m",
          description="How far this body's hitch points (rear_hitch, front_hitch) may lie outside its outline: a "
                      "drawbar, an A-frame tongue, a ball mount (checked at load; the default covers car-trailer "
                      "tongues and ball mounts)"),
    Field("overhang", Kind.LENGTH, n=2, minimum=0, maximum=MAX_LENGTH,
          default=[f"{DEFAULT_OVERHANG[0]:g} m", f"{DEFAULT_OVERHANG[1]:g} m"],
          description="How far the tyre contacts may lie outside the outline: beyond its front or rear end, and "
                      "beyond its sides (checked at load: axle x within the length, track within the width)"),
], subsections=[ArrayOf("axles", AXLE, required=False, description="Axles, front to rear (needed for a run-out)")],
   description="One rigid body of the vehicle, front to rear")

def _wheel_fields(override: bool) -> list[Field]:
    opt = {"required": False}
    # the tyres section states every wheel's state: a rolling or braked wheel needs its tyre data there (an
    # override inherits the state and the data, checked when the settings are resolved)
    moving = {} if override else {"required_if": ("state", ("rolling", "braked"))}
    return [
        Field("state", choices=WHEEL_STATES, **({"required": False} if override else {}), example="locked",
              description="rolling (free), braked (brake fraction), locked (slides), jammed (damaged, slides)"),
        Field("brake", "float", minimum=0, maximum=1, **opt, example="0.5",
              description="Brake fraction of mu N, for state = \"braked\""),
        Field("steer", Kind.ANGLE, **opt, example="5 deg", description="Fixed steer angle, counter-clockwise positive"),
        Field("cornering_coefficient", "float", minimum=0, exclusive_minimum=True, **opt, example="8.6",
              **moving, **({} if override else {"unless": ("cornering_stiffness",)}),
              description="Cornering stiffness per unit load [1/rad] (8.6/rad = 15 %/deg, car tyres)"),
        Field("cornering_stiffness", Kind.CORNERING_STIFFNESS, minimum=0, exclusive_minimum=True, **opt,
              example="40000 N/rad",
              description="Cornering stiffness per tyre, a force per angle of slip (\"155 lbf/deg\"; a bare force "
                          "such as \"40000 N\" is read per radian)"),
        Field("rolling_resistance", "float", minimum=0, maximum=0.5, **opt, example="0.012", **moving,
              description="Rolling-resistance coefficient f_r (rolling and braked wheels)"),
        Field("mu_factor", "float", minimum=0, maximum=2, exclusive_minimum=True, **opt, example="0.5",
              description="Multiplier on the road friction at this wheel (e.g. a flat tyre)"),
        Field("self_steer_limit", Kind.ANGLE, minimum=0, maximum=math.pi / 2, **opt, example="20 deg",
              description="Self-steering (castor) wheel: it follows its path with no lateral force while the "
                          "steer angle that needs stays within +-this limit, and acts as a fixed wheel at the "
                          "limit beyond it; \"0 deg\" locks it straight (as for reversing); steer is then not used"),
    ]


TYRES = Section("tyres", _wheel_fields(False), required=False,
                description="Wheel state and tyre data of every wheel of the vehicle (run-out)")
WHEEL = Section("wheel", [Field("select", "str", example="trailer/0/right",
                                description="Which wheels: \"*\", a body, <body>/<axle>, <body>/<axle>/<left|right>")]
                + _wheel_fields(True), description="Override of the tyres section for some wheels")
WHEEL_CHANGE = Section("wheel_change", [
    Field("at", Kind.TIME, minimum=0, exclusive_minimum=True, example="0.8 s", description="Time after separation"),
    Field("select", "str", example="tractor", description="Which wheels (as in wheels[].select)"),
] + _wheel_fields(True), description="A change of wheel settings from a given time on (brakes released, ...)")

APPROACH_WHEEL_CHANGE = Section("wheel_change", [
    Field("at", Kind.TIME, minimum=0, exclusive_minimum=True, example="0.3 s",
          description="Time after the start of braking (brake lag, trailer brakes applying later)"),
    Field("select", "str", example="trailer", description="Which wheels (as in wheels[].select)"),
] + _wheel_fields(True), description="A change of the approach's wheel settings from a given time on")

BRAKE_UNIT = Section("unit", [
    Field("body", "str", example="tractor", description="The braked body (a body without an entry has no air brakes)"),
    Field("type", choices=UNIT_TYPES, required=False, example="last_trailer",
          description="Unit type whose default timing applies (default: the first body a tractor, the last a "
                      "last_trailer, a body named like a dolly a dolly, others a towing_trailer)"),
    Field("capacity", Kind.FORCE, counts=tuple(range(1, 13)), minimum=0, maximum=MAX_CAPACITY,
          example='["45 kN", "90 kN", "90 kN"]',
          description="Brake capacity of each axle, front to rear (one value: every axle): the brake force at the road "
                      "its brakes develop at full application, both sides together"),
    Field("delay", Kind.TIME, required=False, minimum=0, maximum=MAX_BRAKE_TIME, example="0.225 s",
          description="From the first movement of the brake control until the unit's brake force starts to build "
                      "(default by unit type, from FMVSS 121's application timing: docs/heavy-vehicles.md)"),
    Field("rise", Kind.TIME, required=False, minimum=0, maximum=MAX_BRAKE_TIME, example="0.375 s",
          description="Time the brake force takes to build linearly to its full value (default by unit type)"),
    Field("release_delay", Kind.TIME, required=False, minimum=0, maximum=MAX_BRAKE_TIME, example="0.275 s",
          description="From the release of the control until the brake force starts to fall (default by unit type)"),
    Field("fall", Kind.TIME, required=False, minimum=0, maximum=MAX_BRAKE_TIME, example="0.29 s",
          description="Time the brake force takes to fall linearly to zero (default by unit type)"),
    Field("out_of_adjustment", "float", minimum=0, maximum=1, default=0.0, example="0.2",
          description="Fraction of the unit's brake capacity lost to brakes out of adjustment"),
], description="The air brakes of one body (unit)")


def _brakes_section(when: str) -> Section:
    return Section("brakes", [
        Field("apply", Kind.TIME, minimum=-60, maximum=60, default="0 s", example="0.5 s",
              description=f"First movement of the brake control, {when}"),
        Field("release", Kind.TIME, required=False, minimum=-60, maximum=600, example="3 s",
              description=f"Release of the brake control, {when} (absent: held)"),
        Field("tractor_abs", "bool", default=False, description="ABS on the first body's wheels"),
        Field("trailer_abs", "bool", default=False, description="ABS on the wheels of every other body"),
        Field("abs_efficiency", "float", required=False, minimum=0, maximum=1, exclusive_minimum=True,
              exclusive_maximum=True, example="0.85",
              description="ABS modulation efficiency: the longitudinal force of a wheel under ABS as a fraction of "
                          "the sliding force's (required with ABS; docs/heavy-vehicles.md)"),
    ], subsections=[ArrayOf("units", BRAKE_UNIT, min_items=1, description="The braked bodies")], required=False,
        description="Air brakes: each unit's brake force builds after a delay along a ramp (and releases the same "
                    "way), limited by the tyre (the wheel locks) or, with ABS, held below it")


#: Largest approach (distance from the start of braking to the impact [m], time [s]).
MAX_APPROACH_DISTANCE = 2000.0
MAX_APPROACH_TIME = 120.0

APPROACH_PATH = Section("path", [
    Field("points", Kind.LENGTH, n=2, points=True, min_points=2, required=False,
          example='[["-80 m", "0 m"], ["-20 m", "0 m"], ["0 m", "5 m"]]',
          description="The path as a polyline in the direction of travel, world frame (or give line)"),
    Field("line", "str", required=False, example="eastbound lane centre",
          description="The name of a [[map.lines]] line (typed, or imported from a survey layer) to follow instead of "
                      "points"),
    Field("reverse", "bool", default=False, description="With line: its points run against the direction of travel"),
    Field("preview_time", Kind.TIME, minimum=0.3, maximum=5.0, default="1.0 s", example="1.0 s",
          description="The driver's preview: the goal point lies this time ahead at the current speed (pure pursuit)"),
    Field("min_preview", Kind.LENGTH, minimum=0.5, maximum=200, default="4 m", example="4 m",
          description="Shortest preview distance (at low speed)"),
    Field("max_steer", Kind.ANGLE, minimum=0.0175, maximum=1.05, default="40 deg", example="40 deg",
          description="Largest steer angle of the first axle's centre"),
    Field("max_steer_rate", Kind.ANGULAR_VELOCITY, minimum=0.0175, maximum=12.6, default="30 deg/s",
          example="30 deg/s", description="Largest rate of that steer angle"),
    Field("update", Kind.TIME, minimum=0.01, maximum=1.0, default="0.1 s", example="0.1 s",
          description="The driver's update interval (the steer angle is held between updates)"),
], required=False, description="A path the driver follows (docs/approach.md): the first unit's first axle is steered "
                               "so that the centre of its rear axles follows it; needs distance (the start lies that "
                               "far before the impact position along the path)")

MAX_STEERING_WHEEL_ANGLE = 6 * math.pi  # three turns either way [rad]

APPROACH_RECORDED_SAMPLE = Section("sample", [
    Field("time", Kind.TIME, minimum=-MAX_APPROACH_TIME, maximum=0, example="-2.5 s",
          description="Time of the sample relative to the impact (the recorder's trigger), negative before it"),
    Field("speed", Kind.SPEED, required=False, minimum=0, maximum=MAX_SPEED, example="52 mph",
          description="Recorded speed (give it in every sample or in none)"),
    Field("steering", Kind.ANGLE, required=False, minimum=-MAX_STEERING_WHEEL_ANGLE, maximum=MAX_STEERING_WHEEL_ANGLE,
          example="-15 deg", description="Recorded steering-wheel angle (give it in every sample or in none)"),
], description="One sample of the recorder's pre-crash table")
APPROACH_RECORDED = Section("recorded", [
    Field("steering_ratio", "float", required=False, minimum=5, maximum=40, example="16",
          description="Overall steering ratio: steering-wheel angle over the steer angle of the first axle's centre "
                      "(with steering samples)"),
    Field("steering_positive", choices=("left", "right"), default="left", example="left",
          description="Which turn a positive recorded steering angle is: left (counter-clockwise, most recorders) "
                      "or right; check the recorder's documentation"),
    Field("update", Kind.TIME, minimum=0.01, maximum=0.5, default="0.05 s", example="0.05 s",
          description="Interval of the speed controller's decisions and of the steering's steps"),
    Field("speed_time", Kind.TIME, minimum=0.05, maximum=5, default="0.3 s", example="0.3 s",
          description="Time constant of the speed controller (how fast a speed error is taken out)"),
], subsections=[ArrayOf("samples", APPROACH_RECORDED_SAMPLE, min_items=2,
                        description="The samples, e.g. [{time = \"-5 s\", speed = \"55 mph\", steering = \"0 deg\"}, "
                                    "...]")],
    required=False, description="A recorder's pre-crash table that drives the approach from its first sample to the "
                                "impact (docs/approach.md): its steering steers the first axle, its speeds set the "
                                "brakes; give neither distance, time, start_position nor a path")

APPROACH = Section("approach", [
    Field("speed", Kind.SPEED, required=False, minimum=0, exclusive_minimum=True, maximum=MAX_SPEED, example="55 mph",
          description="CG speed of the first body at the start of braking; absent: solved from the speed at impact "
                      "(vehicles.<name>.speed). Give one of the two"),
    Field("distance", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, maximum=MAX_APPROACH_DISTANCE,
          example="38 m", description="Path length of the first body's CG from the start of braking to the impact "
                                      "(give one of distance, time, start_position)"),
    Field("time", Kind.TIME, required=False, minimum=0, exclusive_minimum=True, maximum=MAX_APPROACH_TIME,
          example="2.1 s", description="Time from the start of braking to the impact"),
    Field("start_position", Kind.LENGTH, n=2, required=False, example='["-60 m", "0 m"]',
          description="First body's CG at the start of braking, world frame (the approach then ends where the CG "
                      "passes closest to its position at impact)"),
    Field("start_heading", Kind.ANGLE, required=False, example="0 deg",
          description="First body's heading at the start of braking (with start_position)"),
    Field("tolerance", Kind.LENGTH, minimum=0, exclusive_minimum=True, default="0.5 m", example="0.5 m",
          description="With start_position: largest distance by which the approach may miss the impact position"),
    Field("reaction_time", Kind.TIME, minimum=0, maximum=10, default="0 s", example="1.5 s",
          description="Perception-reaction time before the start of braking, at constant speed (reported with its "
                      "distance; no standard value exists: state the expectancy assumed)"),
    Field("road_friction", "float", required=False, minimum=0, maximum=2, exclusive_minimum=True, example="0.7",
          description="Road friction coefficient of the approach (default: runout.road_friction, with its zones)"),
    Field("articulation", Kind.ANGLE, counts=(1, 2, 3, 4), required=False, minimum=-math.pi, maximum=math.pi,
          example='["6 deg"]', description="Articulation angle at each hitch at the start (front minus rear heading, "
                                           "front to rear; default straight): a caravan already swaying"),
    Field("yaw_rates", Kind.ANGULAR_VELOCITY, counts=(1, 2, 3, 4, 5), required=False, minimum=-MAX_YAW_RATE,
          maximum=MAX_YAW_RATE, example='["0 deg/s", "-12 deg/s"]',
          description="Yaw rate of each body at the start, front to rear (default none)"),
    Field("through_impact", "bool", default=False,
          description="One time line: the approach's wheel states, scheduled changes, air brakes and last steer angles "
                      "carry on through the impact into the run-out (the vehicle's own tyres section then gives no base; "
                      "its wheel_changes, at times after the impact, apply on top; give brakes once, here)"),
    Field("solve_articulation", "bool", default=False,
          description="Solve the articulation at the start (articulation: the first guess) so that the approach ends "
                      "at the impact configuration's articulation"),
], subsections=[
    APPROACH_PATH,
    APPROACH_RECORDED,
    Section("tyres", _wheel_fields(False), description="Wheel state and tyre data of every wheel from the start of "
                                                       "braking (e.g. state = \"locked\")"),
    ArrayOf("wheels", WHEEL, required=False, description="Per-wheel overrides of the approach's tyres section"),
    ArrayOf("wheel_changes", APPROACH_WHEEL_CHANGE, required=False,
            description="Scheduled changes of the approach's wheel settings (times after the start of braking)"),
    _brakes_section("after the start of braking"),
], required=False, description="The motion before the impact, from the start of braking, simulated with the run-out's "
                               "tyre model and engine; it gives the vehicle's velocity and yaw rates at impact")

VEHICLE = Section("vehicle", [
    Field("description", "str", default="", description="Free text for the report"),
    Field("position", Kind.LENGTH, n=2, example='["0 m", "0 m"]',
          description="CG of the first (front) body at impact, world frame"),
    Field("heading", Kind.ANGLE, example="90 deg", description="Heading of the first body at impact"),
    Field("speed", Kind.SPEED, required=False, minimum=0, maximum=MAX_SPEED, example="30 mph",
          description="CG speed of the first body at impact (required unless approach.speed gives the speed at the "
                      "start of braking)"),
    Field("course", Kind.ANGLE, required=False, example="95 deg",
          description="Direction of the first body's CG velocity (default: its heading, no side slip; with an "
                      "approach it follows from the approach)"),
], subsections=[
    ArrayOf("bodies", BODY, min_items=1, description="The bodies, front to rear, joined by hitches"),
    TYRES,
    ArrayOf("wheels", WHEEL, required=False, description="Per-wheel overrides of the tyres section"),
    ArrayOf("wheel_changes", WHEEL_CHANGE, required=False, description="Scheduled changes of wheel settings"),
    _brakes_section("after separation (negative: before the impact)"),
    APPROACH,
], description="A vehicle: a chain of bodies (car; car + trailer; tractor + semitrailer; doubles)")

BARRIER = Section("barrier", [
    Field("name", "str", example='barrier', description="Name of the barrier body (use it as impact.body2)"),
    Field("description", "str", default="", description="Free text for the report"),
    Field("extent", Kind.LENGTH, n=2, required=False, example='["-3 m", "20 m"]',
          description="Where the barrier face lies along the crush-surface tangent, from the contact point "
                      "(default: an endless line); used to draw it and to warn of contact after separation"),
], required=False, description="A rigid barrier: a body of infinite mass at rest (exact, not a large number)")

CONSTRAINT = Section("constraint", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", description="Body whose velocity is constrained", example='tractor'),
    Field("point", Kind.LENGTH, n=2, example='["2 m", "0 m"]', description="Point of the body held"),
    Field("frame", "str", default="world", description="Frame of point and direction: \"world\" or a body name"),
    Field("direction", Kind.ANGLE, example="90 deg", description="Direction along which the velocity is held"),
    Field("value", Kind.SPEED, default="0 m/s", description="Velocity held along the direction after impact"),
], description="A velocity constraint with its own unknown external impulse (paper Eq. 7)")

EXTERNAL = Section("external_impulse", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", description="Body the impulse acts on", example='trailer'),
    Field("point", Kind.LENGTH, n=2, example='["-2.477 m", "0 m"]', description="Point of application"),
    Field("frame", "str", default="world",
          description="Frame of point, impulse and direction: \"world\" or a body name"),
    Field("impulse", Kind.IMPULSE, n=2, required=False, example='["0 N s", "-3260 N s"]',
          description="The impulse vector; or give friction, load, duration and direction instead"),
    Field("friction", "float", required=False, minimum=0, example="0.6",
          description="Tyre-road friction f for the helper impulse f x load x duration"),
    Field("load", Kind.FORCE, required=False, minimum=0, example="36222 N",
          description="Normal load on the sliding tyres (helper)"),
    Field("duration", Kind.TIME, required=False, minimum=0, example="0.15 s",
          description="Impact duration (helper)"),
    Field("direction", Kind.ANGLE, required=False, example="-90 deg",
          description="Direction of the helper impulse (opposite the tyres' sliding)"),
], description="A known external impulse, e.g. tyre friction over the impact")

IMPACT = Section("impact", [
    Field("body1", "str", example='trailer', description="Body of one vehicle in contact; the impulse P acts on it"),
    Field("body2", "str", example='car', description="Body of the other vehicle (or the barrier) in contact"),
    Field("point", Kind.LENGTH, n=2, example='["-2.517 m", "-1.157 m"]',
          description="Contact point: where the resultant crush impulse acts"),
    Field("point_frame", "str", default="world", description="Frame of point: \"world\" or a body name"),
    Field("contact_tolerance", Kind.LENGTH, minimum=0, default="0.5 m",
          description="How far the contact point may lie outside either contacting body's outline (a check "
                      "of the geometry: the point must be in or near the crush zone of both bodies)"),
    Field("overlap_tolerance", Kind.LENGTH, minimum=0, default=f"{DEFAULT_OVERLAP:g} m",
          description="How deep the outlines of bodies of two vehicles may overlap at the impact: the impact's "
                      "two bodies along its normal (their crush), any other pair by the distance one must move to "
                      "clear the other; deeper is an error at load (a vehicle placed on top of another)"),
    Field("normal", Kind.ANGLE, example="90 deg",
          description="Direction of the crush-surface normal n, pointing from body2 into body1"),
    Field("normal_frame", "str", default="world", description="Frame of normal: \"world\" or a body name"),
    Field("tangent", choices=("ccw", "cw"), default="ccw",
          description="Tangent t = n turned 90 deg counter-clockwise (ccw) or clockwise (cw); "
                      "mu and the tangential impulse are signed along t"),
    Field("restitution", "float", minimum=0, maximum=1, example="0.05",
          description="Coefficient of restitution e (Eq. 5)"),
    Field("moment_restitution", "float", default=-1.0, minimum=-1, maximum=1,
          description="Moment coefficient e' (Eq. 6): -1 for no moment impulse, else 0 <= e' <= 1"),
    Field("tangential", choices=("no_slide", "ratio", "fraction", "friction"), example='friction',
          description="Tangential law: no sliding at separation (mu = mu_max); a given impulse ratio mu; "
                      "a share of this impact's critical ratio (mu = mu_fraction x mu_max, PIM's \"85 % of mu_0\"); "
                      "or friction f (stick if |mu_max| <= f, else slide with |mu| = f)"),
    Field("mu", "float", required=False, example="0.3", description="Impulse ratio P_t/P_n, for tangential = \"ratio\""),
    Field("mu_fraction", "float", required=False, minimum=0, maximum=1, example="0.85",
          description="mu as a share of mu_max of this very impact, for tangential = \"fraction\" (1: no sliding at "
                      "separation; as a fit unknown or uncertain input mu follows each sample's mu_max)"),
    Field("friction", "float", required=False, minimum=0, example="0.6",
          description="Crush-surface friction f, for tangential = \"friction\""),
], subsections=[
    ArrayOf("constraints", CONSTRAINT, required=False, description="Velocity constraints"),
    ArrayOf("external_impulses", EXTERNAL, required=False, description="Known external impulses"),
], description="The impact: crush surface, coefficients, constraints, external impulses")

_OPT = RunoutOptions()
ZONE = Section("zone", [
    Field("name", "str", default="", description="Label (\"grass verge\")"),
    Field("friction", "float", minimum=0, maximum=2, exclusive_minimum=True, example="0.35",
          description="Tyre-road friction coefficient inside the zone"),
    Field("polygon", Kind.LENGTH, n=2, points=True, min_points=3, example='[["0 m", "-4 m"], ["60 m", "-4 m"], ["60 m", "-12 m"]]',
          description="Vertices of the zone, world frame"),
    Field("grade", Kind.SLOPE, required=False, minimum=-MAX_SLOPE, maximum=MAX_SLOPE, example="-6 %",
          description="Grade inside the zone, rise over run along world +x (default: runout.grade)"),
    Field("cross_slope", Kind.SLOPE, required=False, minimum=-MAX_SLOPE, maximum=MAX_SLOPE, example="2 %",
          description="Cross-slope inside the zone, rise over run along world +y (default: runout.cross_slope)"),
], description="A friction zone (polygon with its own coefficient); later zones win where zones overlap")

RUNOUT = Section("runout", [
    Field("level", choices=LEVELS, default="articulated",
          description="Model fidelity: impact (no run-out), energy (hand-calculation work model), rigid (bodies "
                      "run out alone, hitch ignored), articulated (full, default), load_transfer (plus load transfer)"),
    Field("accuracy", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, example="1 cm",
          description="Rest-position accuracy wanted: the solver picks the cheapest setting that meets it and "
                      "reports its error estimate (then rtol, atol, eps and v_stop are its to choose)"),
    Field("accuracy_heading", Kind.ANGLE, required=False, minimum=0, exclusive_minimum=True, example="0.5 deg",
          description="Rest-heading accuracy wanted (with accuracy)"),
    Field("engine", choices=("scipy", "compiled"), default="scipy",
          description="Run-out integrator: scipy's solve_ivp (default) or crashsim's compiled engine (fast, "
                      "same model; used by fit and mc)"),
    Field("road_friction", "float", minimum=0, maximum=2, exclusive_minimum=True, example="0.7",
          description="Tyre-road friction coefficient outside the zones"),
    Field("grade", Kind.SLOPE, default=0.0, minimum=-MAX_SLOPE, maximum=MAX_SLOPE, example="-6 %",
          description="Road grade, rise over run along world +x (\"-6 %\": downhill toward +x); in-plane gravity "
                      "on every body, normal loads scaled (run-out, approach, energy level); or the surface's angle "
                      "(\"-3.43 deg\" is about -6 %)"),
    Field("cross_slope", Kind.SLOPE, default=0.0, minimum=-MAX_SLOPE, maximum=MAX_SLOPE, example="2 %",
          description="Road cross-slope, rise over run along world +y (a percentage, a number, or the surface's angle: "
                      "\"2 %\", \"0.02\" and \"1.15 deg\" are about the same)"),
    Field("method", choices=METHODS, default=_OPT.method, description="solve_ivp method (LSODA: cheap also when stiff)"),
    Field("rtol", "float", minimum=1e-14, maximum=0.1, default=_OPT.rtol, description="Relative tolerance of the solver"),
    Field("atol", "float", minimum=0, maximum=1, exclusive_minimum=True, default=_OPT.atol,
          description="Absolute tolerance (state in m, rad, m/s, rad/s)"),
    Field("eps", Kind.SPEED, minimum=0, exclusive_minimum=True, default=f"{_OPT.eps} m/s",
          description="Low-speed regularisation speed of the friction laws"),
    Field("v_stop", Kind.SPEED, minimum=0, exclusive_minimum=True, default=f"{_OPT.v_stop} m/s",
          description="Rest threshold (residual travel <= v_stop^2 / (2 a_min))"),
    Field("max_step", Kind.TIME, minimum=0, exclusive_minimum=True, default=f"{_OPT.max_step} s",
          description="Largest solver step (lower it for thin friction zones)"),
    Field("t_max", Kind.TIME, minimum=0, exclusive_minimum=True, default=f"{_OPT.t_max} s",
          description="Time limit of the run-out"),
    Field("sample_dt", Kind.TIME, minimum=0, exclusive_minimum=True, default=f"{_OPT.sample_dt} s",
          description="Spacing of the sampled histories and tracks"),
    Field("lateral_model", choices=LATERAL_MODELS, default=_OPT.lateral_model, description="Lateral tyre curve"),
    Field("max_impacts", "int", minimum=0, maximum=100_000, default=_OPT.max_impacts,
          description="Secondary impacts allowed in the run-out; more end it with status event_limit (exit 3)"),
    Field("max_wall_time", Kind.TIME, minimum=0, exclusive_minimum=True, maximum=1e6,
          default=f"{_OPT.max_wall_time} s",
          description="Computing time allowed for the run-out; more ends it with status wall_time_limit (exit 3)"),
    Field("load_transfer", "bool", default=_OPT.load_transfer,
          description="Quasi-static load transfer (needs every body's cg_height)"),
    Field("rollover", "bool", default=False,
          description="Record when a body's inner wheels lift and when it passes its rollover threshold "
                      "(needs level load_transfer; each body's rollover_threshold, default 0.75 t / (2 h)); the "
                      "result says from when the planar run-out is outside its validity"),
], subsections=[ArrayOf("zones", ZONE, required=False, description="Friction zones")],
   required=False, description="Run-out of every vehicle from separation to rest (omit for an impact-only study)")

EV_REST_POINT = Section("point", [
    Field("at", "str", required=False, example="front_left",
          description="Which point of the body: an outline corner front_left, front_right, rear_left, rear_right "
                      "(from the body's length, width and outline_center), or a tyre contact <axle>/left or "
                      "<axle>/right (axle x, +-track/2), where <axle> is the axle's name or axle1, axle2, ... "
                      "counted front to rear (for unnamed axles too); or give body_point instead"),
    Field("body_point", Kind.LENGTH, n=2, required=False, example='["2.1 m", "0.9 m"]',
          description="The point in body axes (origin at the CG, x forward, y left), instead of at"),
    Field("position", Kind.LENGTH, n=2, example='["12.1 m", "3.4 m"]', description="Where it was measured, world"),
], description="One measured point of the body at rest")
EV_REST = Section("rest", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", example="trailer", description="Body whose rest position was measured"),
    Field("position", Kind.LENGTH, n=2, required=False, example='["12.3 m", "2.6 m"]',
          description="Measured CG rest position, world (or give points instead)"),
    Field("tolerance", Kind.LENGTH, minimum=0, example="0.5 m", description="Largest acceptable distance of the CG"),
    Field("heading", Kind.ANGLE, required=False, example="-25 deg",
          description="Measured rest heading (not with points: they give it)"),
    Field("heading_tolerance", Kind.ANGLE, required=False, minimum=0, example="5 deg",
          description="Largest acceptable heading error (required with heading; with points, the heading derived "
                      "from them is checked if this is given)"),
], subsections=[
    ArrayOf("points", EV_REST_POINT, required=False,
            description="Instead of position: two or more measured points of the body (corners, tyre contacts); "
                        "the CG and heading follow by a least-squares rigid fit of the body's points to them, "
                        "e.g. points = [{at = \"front_left\", position = [\"12.1 m\", \"3.4 m\"]}, "
                        "{at = \"rear_left\", position = [\"4.0 m\", \"1.9 m\"]}]"),
], description="A measured rest position (and heading) of a body: its CG, or measured points of it")
EV_MARK = Section("mark", [
    Field("name", "str", default="", description="Label for the report"),
    Field("wheel", "str", default="*", description="Wheel(s) that may have left it: \"*\", a body, "
                                                     "<body>/<axle>, <body>/<axle>/<left|right>"),
    Field("points", Kind.LENGTH, n=2, points=True, min_points=2, example='[["-9 m", "-1 m"], ["-4 m", "0.5 m"]]',
          description="The mark as a polyline, world"),
    Field("tolerance", Kind.LENGTH, minimum=0, example="0.3 m",
          description="Largest acceptable distance of any point of the mark from the computed track"),
    Field("sliding_only", "bool", default=True, description="Compare with the sliding parts of tracks only"),
    Field("phase", choices=("runout", "approach"), default="runout",
          description="runout: left after the impact; approach: before it (a pre-impact skid or yaw mark, compared "
                      "with the tracks of the vehicles' approaches)"),
], description="A tyre mark measured at the scene")
EV_POI = Section("impact_point", [
    Field("position", Kind.LENGTH, n=2, example='["-9.6 m", "-1.2 m"]', description="Measured point of impact, world"),
    Field("tolerance", Kind.LENGTH, minimum=0, example="0.5 m", description="Largest acceptable distance"),
], required=False, description="The point of impact found at the scene (gouges, debris)")
EV_DV = Section("delta_v", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", example="tractor", description="Body carrying the recorder"),
    Field("value", Kind.SPEED, example="2.5 mph", description="Recorded delta-v"),
    Field("component", choices=("magnitude", "longitudinal", "lateral"), default="magnitude",
          description="What was recorded: the magnitude, or the component along the body's x or y axis"),
    Field("tolerance", Kind.SPEED, minimum=0, example="1 mph", description="Largest acceptable difference"),
    Field("impacts", choices=("first", "all"), default="first",
          description="Which impacts the recorder saw: the first (default: a recorder records one event, normally the "
                      "first impact) or all of the body's impacts summed (a later secondary impact in the same event)"),
], description="A delta-v recorded by an event data recorder")
EV_CRUSH = Section("crush", [
    Field("name", "str", default="", description="Label for the report"),
    Field("body", "str", example="car", description="Body whose crush was measured"),
    Field("face", choices=("front", "rear", "left", "right"), example="front",
          description="Damaged face of the body; the angle of the computed crush force (PDOF) to this face's "
                      "normal sets the force-direction factor"),
    Field("A", Kind.FORCE_PER_LENGTH, required=False, minimum=0, maximum=1e8, example="50000 N/m",
          description="CRASH3 stiffness coefficient A: force per unit damage width at zero residual crush "
                      "(lb/in is read as lbf/in: in CRASH3 practice lb is pound-force); with B, width and "
                      "profile; omit A and B to use the body preset's stiffness of this face (crashsim presets)"),
    Field("B", Kind.FORCE_PER_AREA, required=False, minimum=0, exclusive_minimum=True, maximum=1e10,
          example="600000 N/m^2",
          description="CRASH3 stiffness coefficient B: force per unit width per unit crush (lb/in^2 is read as "
                      "lbf/in^2)"),
    Field("width", Kind.LENGTH, required=False, minimum=0, exclusive_minimum=True, maximum=MAX_LENGTH,
          example="1.5 m", description="Damage width L over which the profile was measured"),
    Field("profile", Kind.LENGTH, counts=(2, 4, 6), required=False, minimum=0, maximum=5.0,
          example='["0.10 m", "0.20 m", "0.30 m", "0.35 m", "0.30 m", "0.20 m"]',
          description="Residual crush depths C1..Cn, equally spaced over the width (2, 4 or 6 of them; "
                      "from the body's left to its right on the front and rear faces, "
                      "front to rear on the sides)"),
    Field("offset", Kind.LENGTH, default="0 m", minimum=-MAX_LENGTH, maximum=MAX_LENGTH,
          description="Centre of the damage from the centre of the face, along the face (front/rear: to the "
                      "body's left; left/right: forward); for the figure"),
    Field("ees", Kind.SPEED, required=False, minimum=0, maximum=MAX_SPEED, example="30 km/h",
          description="Energy equivalent speed, instead of A, B, width and profile: crush energy 1/2 m EES^2 "
                      "(m the body's mass), taken as it is (no force-direction factor)"),
    Field("correction", choices=("pdof", "none"), default="pdof",
          description="Force-direction factor 1 + tan^2(alpha), alpha the angle of the computed PDOF to the face "
                      "normal, applied up to 45 deg (factor 2; beyond: held at 2, with a warning): pdof, or none"),
    Field("impacts", choices=("first", "all"), default="first",
          description="Which impacts made this damage: the first, or all the body's impacts (the first and the "
                      "run-out's); items with the same setting are summed and compared as one group"),
    Field("compare", choices=("total", "normal"), default="total",
          description="total: the group's crush energies (with the factor) against the whole loss at the crush "
                      "surface T_n + T_t + T_M; normal: the energies without the factor against the normal and "
                      "moment parts T_n + T_M (Brach & Brach's partition); the same in every item of a group"),
    Field("tolerance", Kind.ENERGY, required=False, minimum=0, example="10 kJ",
          description="This item's share of the group's tolerance (the group's is the sum of its items'); "
                      "or give relative_tolerance"),
    Field("relative_tolerance", Kind.DIMENSIONLESS, required=False, minimum=0, exclusive_minimum=True, maximum=10,
          example="25 %", description="Tolerance as a fraction of this item's crush energy, instead of tolerance"),
], description="The measured crush of one face of one body (CRASH3): its energy is compared with the impact "
               "model's energy loss")
EV_RECORDER_SAMPLE = Section("sample", [
    Field("time", Kind.TIME, maximum=5, example="-2.5 s",
          description="Time of the sample relative to the impact (negative: before it). Pre-crash data end at the "
                      "impact: a sample is compared only where time + time_offset <= 0, decided with the offset of "
                      "each evaluation (a fitted time_offset moves the window)"),
    Field("speed", Kind.SPEED, minimum=0, maximum=MAX_SPEED, example="52 mph", description="Recorded speed"),
    Field("brake", "bool", default=False,
          description="Service brake on at this sample: wheel-speed recorders under-read while braking (locked or "
                      "ABS-cycling wheels), so the sample counts as a lower bound of the speed"),
], description="One pre-crash sample")
EV_RECORDER = Section("recorder", [
    Field("name", "str", default="", description="Label for the report (\"tractor ECM hard-brake record\")"),
    Field("body", "str", example="tractor", description="Body carrying the recorder (its vehicle needs an approach)"),
    Field("tolerance", Kind.SPEED, minimum=0, exclusive_minimum=True, example="1 mph",
          description="Largest acceptable difference of every sample (49 CFR 563 asks +-1 km/h of the speed the "
                      "vehicle reports)"),
    Field("time_offset", Kind.TIME, default="0 s", minimum=-5, maximum=5, example="-0.2 s",
          description="Added to every sample time: the recorder's time zero is not the first contact (latency)"),
], subsections=[ArrayOf("samples", EV_RECORDER_SAMPLE, min_items=1,
                        description="The samples, e.g. [{time = \"-2 s\", speed = \"55 mph\"}, ...]")],
    description="Pre-crash speeds of an event data recorder")

EV_ROLLOVER = Section("rollover", [
    Field("unit", "str", example="trailer",
          description="A vehicle (any of its units) or one body (unit) the statement is about"),
    Field("rolled", "bool", example="true",
          description="true: it rolled (found on its side or roof, or witnessed tipping); false: it stayed upright"),
    Field("name", "str", default="", description="Label for the report (\"trailer found on its side\")"),
], description="Whether a vehicle or one of its units rolled, against the wheel-lift and rollover check (needs "
               "runout.rollover or a rollover_threshold, level load_transfer)")

EVIDENCE = Section("evidence", [], subsections=[
    ArrayOf("rest", EV_REST, required=False, description="Rest positions"),
    ArrayOf("marks", EV_MARK, required=False, description="Tyre marks"),
    EV_POI,
    ArrayOf("delta_v", EV_DV, required=False, description="Recorded delta-v"),
    ArrayOf("recorder", EV_RECORDER, required=False, description="Recorded pre-crash speeds (needs an approach)"),
    ArrayOf("crush", EV_CRUSH, required=False, description="Crush profiles (CRASH3) or EES of damaged faces"),
    ArrayOf("rollover", EV_ROLLOVER, required=False,
            description="Statements that a vehicle or unit did or did not roll (a verdict; not fitted)"),
], required=False, description="What was found at the scene; each item is checked against its tolerance")

_CM = ContactModel()


def _contact_fields(defaults: bool) -> list[Field]:
    """The contact-model keys: with the scene's defaults, or all optional (a pair's overrides)."""
    d = (lambda v: {"default": v}) if defaults else (lambda v: {"required": False})  # noqa: E731
    return [
        Field("restitution", "float", minimum=0, maximum=1, **d(_CM.restitution), example="0.2",
              description="Coefficient of restitution e of a secondary impact (low-speed impacts: about 0.1-0.3)"),
        Field("friction", "float", minimum=0, maximum=5, **d(_CM.friction), example="0.6",
              description="Crush-surface friction f of a secondary impact (friction law), and the friction of "
                          "sustained contact"),
        Field("velocity_threshold", Kind.SPEED, minimum=0, exclusive_minimum=True, maximum=50,
              **d(f"{_CM.velocity_threshold} m/s"), example="0.5 m/s",
              description="Approach speed from which a touch is an impact (impulse); slower: sustained contact"),
        Field("stiffness", "float", minimum=0, exclusive_minimum=True, maximum=1e12, **d(_CM.stiffness),
              example="1e7", description="Penalty stiffness of sustained contact per contact point [N/m]: bodies "
                                         "stay within force / stiffness of each other"),
        Field("damping_ratio", "float", minimum=0, maximum=100, **d(_CM.damping_ratio), example="1.0",
              description="Damping of sustained contact relative to critical (1: no bounce)"),
        Field("arm_distance", Kind.LENGTH, minimum=0, exclusive_minimum=True, maximum=10,
              **d(f"{_CM.arm_distance} m"), example="0.05 m",
              description="Gap at which a pair leaves sustained contact, or is armed after the crush of the impact"),
        Field("enabled", "bool", **d(True), example="true",
              description="false: the bodies pass through each other (no contact modelled)"),
    ]


CONTACT_PAIR = Section("pair", [
    Field("first", "str", example="trailer", description="A body, a vehicle or an obstacle"),
    Field("second", "str", example="car",
          description="Another body, vehicle or obstacle (of another vehicle); the most specific override wins: "
                      "body-body over body-vehicle over vehicle-vehicle"),
] + _contact_fields(False), description="Contact coefficients for one pair (overrides the scene's)")

CONTACTS = Section("contacts", _contact_fields(True), subsections=[
    ArrayOf("pairs", CONTACT_PAIR, required=False, description="Overrides for some pairs"),
], required=False, description="How vehicles meet again after the first impact, and meet obstacles (run-out)")

OBSTACLE = Section("obstacle", [
    Field("name", "str", example="guardrail", description="Name of the obstacle, unique in the scene"),
    Field("points", Kind.LENGTH, n=2, points=True, min_points=2, example='[["0 m", "-5 m"], ["80 m", "-5 m"]]',
          description="Centre line of the obstacle (a polyline), or with closed = true its outline, world frame"),
    Field("thickness", Kind.LENGTH, minimum=0, exclusive_minimum=True, maximum=50, default="0.3 m",
          description="Width of a polyline obstacle (its faces lie half of it either side of the line)"),
    Field("closed", "bool", default=False, description="The points outline a solid obstacle (a pier, a pole)"),
    Field("description", "str", default="", description="Free text for the report"),
], description="A fixed obstacle: guardrail, wall, pole, pier")

MAP_LINE = Section("line", [
    Field("name", "str", default="", description="Label drawn on the scene figure (\"north kerb\"); empty: none"),
    Field("style", choices=MAP_LINE_STYLES, example="edge",
          description="How it is drawn: edge (solid road edge), lane (dashed lane line), centre (double centre "
                      "line), kerb (thick kerb or verge edge), stop (thick stop bar), other (thin grey line)"),
    Field("points", Kind.LENGTH, n=2, points=True, min_points=2, example='[["-40 m", "3.5 m"], ["60 m", "3.5 m"]]',
          description="The line as a polyline, world frame"),
    Field("color", "str", required=False, example="#7f7f7f",
          description="Colour instead of the style's own: a matplotlib colour name or hex code"),
], description="A line of the road layout (edge, lane line, kerb, ...), drawn under the vehicles; no physics")

MAP = Section("map", [
    Field("north", Kind.ANGLE, required=False, minimum=-2.0 * math.pi, maximum=2.0 * math.pi, example="30 deg",
          description="Bearing of the scene's +Y axis: the compass direction it points in, clockwise from north "
                      "(0 deg: +Y points north, 90 deg: +Y points east); drawn as a north arrow on the scene figures "
                      "and animations. A scene placed on a survey takes grid north from [survey] instead"),
], subsections=[
    ArrayOf("lines", MAP_LINE, required=False,
            description="Lines of the road layout (road edges, lane and centre lines, kerbs, stop bars), drawn "
                        "under the vehicles on the scene figure; they do not change the physics"),
], required=False, description="Road layout drawn on the scene figure (does not change the physics)")

META = Section("scenario", [
    Field("title", "str", example='Car into trailer wheels', description="Title of the scene"),
    Field("source", "str", default="", description="Where the inputs come from (report, paper, measurement)"),
    Field("notes", "str", default="", description="Free text"),
    Field("units", choices=("SI", "US"), default="SI",
          description="Units of every output (any case): the reports of run, fit and mc, the CSV files, the figures "
                      "and animations (US: ft, mph, lb, lbf, lbf s, ft lbf, deg); --units overrides it"),
    Field("speed_unit", choices=SPEED_UNITS, required=False, example="km/h",
          description="Unit of the speeds in SI outputs (reports, tables, figures, animations, the case report): "
                      "m/s, km/h or mph; absent: m/s. US outputs show mph; with --units SI it still applies"),
], description="What the scene is")

SCHEMA = Section("scenario file", subsections=[
    META,
    Table("vehicles", VEHICLE, min_entries=1, placeholder="<vehicle>", description="The vehicles, by name"),
    BARRIER,
    IMPACT,
    RUNOUT,
    CONTACTS,
    ArrayOf("obstacles", OBSTACLE, required=False, description="Fixed obstacles of the scene (run-out)"),
    MAP,
    EVIDENCE,
    SURVEY,
], description="A crashsim scenario file (TOML)")

# [fit], [uncertainty] and the evidence sigmas (crashsim fit / crashsim mc)
from .inverse_schema import with_inverse_sections  # noqa: E402
from .evidence.crush import CrushEvidence, crush_groups
from .motion.approach import ApproachSpec, check_path, path_start, simulate_approach
from .motion.driver import DriverSpec, Path as DrivePath, steer_geometry
from .motion.recorded import RecordedDrive, rising_speed
from .motion.loads import STANDARD_GRAVITY
from .motion.road import signed_distance
from .plotting import is_color
from .scene.run import simulate_approaches
from .survey.frame import SceneFrame
from .survey.mapping import as_written, expand_survey, is_placed, survey_frame

SCHEMA = with_inverse_sections(SCHEMA)


def schema_document(fmt: str = "text") -> str:
    """The scenario-file reference, generated from the validating schema."""
    return document(SCHEMA, fmt)


# ----------------------------------------------------------------------------------------
# From validated data to typed SI objects


@dataclass(frozen=True, eq=False)
class MapLine:
    """A line of the road layout (``[[map.lines]]``): drawn on the scene figure, no physics.

    Attributes
    ----------
    name : str
        Label ("" for none).
    style : str
        One of :data:`MAP_LINE_STYLES`.
    points : ndarray, shape (n, 2)
        The polyline in the world frame [m], n >= 2 (read-only).
    color : str or None
        A matplotlib colour replacing the style's own; None for the style's.
    layer : str
        The survey file's layer or point code the line was imported from (``survey.imported``);
        "" for a line written in the scenario file. The figure's legend names it.
    imported_as : str
        What the survey mapping made of that layer: ``"line"``, ``"gouge"`` or ``"debris"``
        (``survey.files.map.kind``); "" for a line written in the scenario file.
    """

    name: str
    style: str
    points: np.ndarray
    color: str | None = None
    layer: str = ""
    imported_as: str = ""

    def __post_init__(self) -> None:
        pts = np.array(self.points, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < 2:
            raise ScenarioError(f"a map line needs at least 2 points (x, y), got shape {pts.shape}", field="points")
        if self.style not in MAP_LINE_STYLES:
            raise ScenarioError(f"unknown style {self.style!r}; allowed {', '.join(MAP_LINE_STYLES)}", field="style")
        pts.flags.writeable = False
        object.__setattr__(self, "points", pts)

    def _key(self) -> tuple:
        return (self.name, self.style, self.color, self.layer, self.imported_as, self.points.shape,
                self.points.tobytes())

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, MapLine):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())


def _build_map_lines(m: dict, file: str | None, survey: dict | None = None) -> tuple[MapLine, ...]:
    """The ``[[map.lines]]`` of a validated file (points already in m); colours checked here. A line
    imported from a survey file carries the layer or code it came from (its ``survey.imported``
    record, whose target is ``map.lines[i]``)."""
    source = {}
    for rec in ((survey or {}).get("imported") or ()):
        target = rec.get("target") or ""
        if target.startswith("map.lines[") and rec.get("layer") is not None:
            source.setdefault(target, (rec["layer"], rec.get("kind") or ""))
    lines = []
    for i, ln in enumerate(m["lines"]):
        color = ln["color"]
        if color is not None:
            if not is_color(color):
                raise _err(f"{color!r} is not a colour; use a matplotlib colour name (\"white\", \"tab:orange\") "
                           "or a hex code (\"#7f7f7f\")", f"map.lines[{i}].color", file)
        layer, kind = source.get(f"map.lines[{i}]", ("", ""))
        lines.append(MapLine(ln["name"], ln["style"], np.asarray(ln["points"], dtype=float), color, layer, kind))
    return tuple(lines)


def _check_north(d: dict, file: str | None) -> None:
    """``[map] north`` is for scenes not placed on a survey (a placed scene's grid north is the survey's +y)."""
    north = (d.get("map") or {}).get("north")
    if north is not None and is_placed(d.get("survey")):
        raise _err(f"{math.degrees(north):g} deg is given for a scene placed on a survey, whose north arrow is the "
                   "survey's grid north (its +y, turned by survey.rotation); allowed only without a placed [survey]: "
                   "remove map.north", "map.north", file)


@dataclass(frozen=True)
class Scenario:
    """A loaded scenario: typed SI inputs, ready to run.

    Attributes
    ----------
    path : str or None
    title, source, units : str
        ``units`` is "SI" or "US"; with ``[scenario] speed_unit`` a :class:`crashsim.units.DisplaySystem`
        (equal to that string) carrying it, which every output of the scene reads.
    vehicles : tuple of Vehicle
        Including a barrier vehicle if the file has ``[barrier]``.
    states : dict of BodyState
        Every body's state at impact.
    impact : ImpactProblem
    runout : RunoutSpec or None
        Road, solver options and wheel settings; None for an impact-only scenario.
    evidence : Evidence
        What was measured at the scene (possibly empty).
    data : dict
        The validated file contents (SI floats), for traceability.
    map_lines : tuple of MapLine
        The road layout of ``[[map.lines]]`` (drawing only; empty without a ``[map]``).
    approaches : dict of ApproachResult
        By vehicle name: the simulated approach of each vehicle with ``[vehicles.<name>.approach]``
        (its velocity and yaw rates at impact are in ``states``); empty until the approaches are
        simulated (:func:`crashsim.scene.run.simulate_approaches`: by :func:`scenario_from_dict` unless asked not to,
        else by the scene run).
    approach_inputs : dict of ApproachInput
        By vehicle name: what each vehicle's approach needs (its spec, road and options, the
        speed at impact if the file gives it), built and checked at load.
    descriptions : dict of str
        By vehicle name: the file's ``description`` of each vehicle ("" if none), for figures and reports.
    survey_frame : SceneFrame or None
        Where the scene lies on its survey (``[survey]`` with files, an underlay or a CRS); None
        for a scene not placed on a survey.
    north : float or None
        ``[map] north``: the bearing of the scene's +Y axis, clockwise from north [rad]; None if the
        file does not give it.
    barrier_extent : (float, float) or None
        (from, to) along the crush tangent [m] of the ``[barrier]`` face, from the contact point;
        (-inf, inf) for an endless one; None without a barrier.
    """

    path: str | None
    title: str
    source: str
    units: str
    vehicles: tuple[Vehicle, ...]
    states: dict
    impact: ImpactProblem
    runout: "RunoutSpec | None"
    evidence: Evidence
    data: dict = field(repr=False)
    map_lines: tuple[MapLine, ...] = ()
    approaches: dict = field(default_factory=dict)
    approach_inputs: dict = field(default_factory=dict)
    descriptions: dict = field(default_factory=dict)
    survey_frame: SceneFrame | None = None
    north: float | None = None
    barrier_extent: tuple[float, float] | None = None
    #: Doubtful values the loader accepted (an angle of more than a turn: "192 rad" meant as
    #: degrees?); the run's warnings carry them
    load_warnings: tuple[str, ...] = ()

    @property
    def approaches_simulated(self) -> bool:
        """True when every vehicle's approach has been simulated (its states at impact are final)."""
        return len(self.approaches) == len(self.approach_inputs)

    @property
    def file_data(self) -> dict | None:
        """The file contents (raw, as from TOML) this scenario was built from by
        :func:`scenario_from_dict`, or None (a scenario made another way, e.g. by
        :func:`dataclasses.replace`): what fit, Monte Carlo and posterior samples vary."""
        return self.__dict__.get("_file_data")


@dataclass(frozen=True)
class RunoutSpec:
    """What the run-out needs besides the separation states (all SI)."""

    road: Road
    options: RunoutOptions
    wheels: dict  # vehicle name -> WheelSettings
    level: str = "articulated"
    accuracy: float | None = None
    accuracy_heading: float | None = None
    contact: ContactModel = field(default_factory=ContactModel)
    pair_contact: dict = field(default_factory=dict)  # (name, name) -> ContactModel
    obstacles: tuple = ()  # Obstacle, the barrier of the impact first


_WHEEL_KEYS = ("state", "brake", "steer", "cornering_coefficient", "cornering_stiffness", "rolling_resistance",
               "mu_factor", "self_steer_limit")


def _given(d: dict) -> dict:
    return {k: d[k] for k in _WHEEL_KEYS if d.get(k) is not None}


def _rewrap(exc: ScenarioError, prefix: str, file: str | None) -> ScenarioError:
    msg = str(exc)
    if exc.field and msg.startswith(f"{exc.field}: "):
        msg = msg[len(exc.field) + 2:]
    key = f"{prefix}.{exc.field}" if exc.field else prefix
    return ScenarioError(msg, field=key, file=file)


def _build_wheels(vehicle: Vehicle, v: dict, file: str | None, prefix: str | None = None) -> WheelSettings:
    """The wheel settings of ``v`` (a vehicle's, or its approach's: ``prefix`` names where they are)."""
    name = vehicle.name
    prefix = prefix or f"vehicles.{name}"
    tyres = v["tyres"]
    if tyres is None:
        raise _err("the run-out needs the wheel state and tyre data of every wheel: add a ["
                   f"{prefix}.tyres] section with at least state = \"locked\" (or rolling/braked with "
                   "cornering_coefficient and rolling_resistance)", f"{prefix}.tyres", file)
    for i, b in enumerate(v["bodies"]):
        if not b["axles"]:
            raise _err(f"body {b['name']!r} has no axles; the run-out needs them ([[vehicles.{name}.bodies.axles]] "
                       "with x and track)", f"vehicles.{name}.bodies[{i}].axles", file)
    try:
        default = WheelSetting(**_given(tyres))
    except ScenarioError as exc:
        raise _rewrap(exc, f"{prefix}.tyres", file) from None
    if not default.is_sliding:
        if default.cornering_stiffness is None and default.cornering_coefficient is None:
            raise _err(f'state = "{default.state}" needs cornering_coefficient (cornering stiffness per unit load, '
                       "1/rad: about 8.6 for car tyres, 6 for truck tyres) or cornering_stiffness (N/rad per tyre)",
                       f"{prefix}.tyres.cornering_coefficient", file)
        if default.rolling_resistance is None:
            raise _err(f'state = "{default.state}" needs rolling_resistance (in [0, 0.5]: about 0.012 for car tyres, '
                       "0.008 for truck tyres)", f"{prefix}.tyres.rolling_resistance", file)
    overrides = {}
    for i, w in enumerate(v["wheels"]):
        merged = {**_given(tyres), **_given(w)}
        if "state" in _given(w) and w["state"] != "braked" and w.get("brake") is None:
            merged.pop("brake", None)
        for pair in (("cornering_coefficient", "cornering_stiffness"), ("cornering_stiffness", "cornering_coefficient")):
            if w.get(pair[0]) is not None:
                merged.pop(pair[1], None)
        try:
            overrides[w["select"]] = WheelSetting(**merged)
        except ScenarioError as exc:
            raise _rewrap(exc, f"{prefix}.wheels[{i}]", file) from None
    schedule = []
    for k, c in enumerate(v["wheel_changes"]):  # each change alone first: an error names its key as written
        key = f"{prefix}.wheel_changes[{k}]"
        try:
            change = ScheduledChange(c["at"], c["select"], _given(c))
            WheelSettings(default, overrides, [change]).resolve(vehicle)
        except ScenarioError as exc:
            msg = str(exc)
            if exc.field and msg.startswith(f"{exc.field}: "):
                msg = msg[len(exc.field) + 2:]
            word, _, rest = msg.partition(": ")
            if rest and word in c:  # "steer: must lie in ...": that key of the change
                raise _err(rest, f"{key}.{word}", file) from None
            raise _err(f"select = {c['select']!r} at {c['at']:g} s: {msg}", f"{key}.select", file) from None
        schedule.append(change)
    brakes = _build_brakes(vehicle, v.get("brakes"), file, f"{prefix}.brakes")
    try:
        ws = WheelSettings(default, overrides, schedule)
        ws.resolve(vehicle)
    except ScenarioError as exc:
        raise _rewrap(exc, prefix, file) from None
    if brakes is not None:
        try:
            ws = WheelSettings(default, overrides, schedule, brakes)
            ws.resolve(vehicle)
        except ScenarioError as exc:
            if (exc.field or "").startswith("units[") and "is 'braked'" in str(exc) and \
                    (v.get("tyres") or {}).get("state") == "braked":  # the key to change: the tyres' state
                msg = str(exc).removeprefix(f"{exc.field}: ")
                raise _err(f'state = "braked" on a body with air brakes: {msg}', f"{prefix}.tyres.state",
                           file) from None
            raise _rewrap(exc, f"{prefix}.brakes", file) from None
    return ws


def _build_brakes(vehicle: Vehicle, b: dict | None, file: str | None, key: str) -> AirBrakes | None:
    """The air brakes of ``vehicle`` from its (validated) brakes table, or None."""
    if b is None:
        return None
    names = [body.name for body in vehicle.bodies]
    if b["release"] is not None and b["release"] < b["apply"]:
        raise _err(f"release = {b['release']:g} s is before apply = {b['apply']:g} s; allowed: release >= apply",
                   f"{key}.release", file)
    if (b["tractor_abs"] or b["trailer_abs"]) and b["abs_efficiency"] is None:
        raise _err("ABS is on (tractor_abs or trailer_abs) but abs_efficiency is missing; give it in (0, 1), e.g. "
                   "0.85 (docs/heavy-vehicles.md)", f"{key}.abs_efficiency", file)
    units = {}
    for i, u in enumerate(b["units"]):
        where = f"{key}.units[{i}]"
        if u["body"] not in names:
            near = difflib.get_close_matches(u["body"], names, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise _err(f"body = {u['body']!r} is not a body of vehicle {vehicle.name!r}{hint} Allowed: {names}",
                       f"{where}.body", file)
        if u["body"] in units:
            raise _err(f"body = {u['body']!r} has two entries; give one per body", f"{where}.body", file)
        index = names.index(u["body"])
        n_axles = len(vehicle.bodies[index].axles)
        if len(u["capacity"]) not in (1, n_axles):
            raise _err(f"gives {len(u['capacity'])} values for body {u['body']!r} with {n_axles} axles; allowed: one "
                       "per axle, or one for every axle", f"{where}.capacity", file)
        try:
            units[u["body"]] = BrakeUnit(
                tuple(u["capacity"]), u["type"] or unit_type_default(len(names), index, u["body"]),
                u["delay"], u["rise"], u["release_delay"], u["fall"], u["out_of_adjustment"],
                bool(b["tractor_abs"] if index == 0 else b["trailer_abs"]))
        except ScenarioError as exc:
            raise _rewrap(exc, where, file) from None
    try:
        return AirBrakes(units, b["apply"], b["release"], b["abs_efficiency"] or 0.0)
    except ScenarioError as exc:
        raise _rewrap(exc, key, file) from None


def _rollover_check(r: dict, level: str, vehicles, file: str | None) -> bool:
    """Whether the wheel-lift and rollover check is asked for (runout.rollover, or a body's
    rollover_threshold), and that it can be done: level load_transfer, and the CG height of every
    body whose threshold is the default."""
    asked = [("runout.rollover", "rollover = true")] if r["rollover"] else []
    for veh in vehicles:
        for i, b in enumerate(veh.bodies):
            if b.rollover_threshold is not None:
                asked.append((f"vehicles.{veh.name}.bodies[{i}].rollover_threshold",
                              f"rollover_threshold = {b.rollover_threshold:g}"))
    if not asked:
        return False
    if level != "load_transfer":
        key, text = asked[0]
        raise _err(f"{text} asks for the wheel-lift and rollover check, which reads the load transfer: it needs "
                   f"level \"load_transfer\", but level = {level!r}", key, file)
    for veh in vehicles:
        for i, b in enumerate(veh.bodies):
            if not b.is_fixed and b.rollover_threshold is None and b.cg_height is None:
                raise _err(f"the default rollover threshold 0.75 t / (2 h) of body {b.name!r} needs its CG height h; "
                           "give cg_height (m, > 0), or rollover_threshold in g, allowed (0, "
                           f"{MAX_ROLLOVER_THRESHOLD:g}]", f"vehicles.{veh.name}.bodies[{i}].cg_height", file)
    return True


def _build_runout(r: dict, vehicles, raw_vehicles: dict, file: str | None, raw: dict | None = None) -> RunoutSpec:
    raw = raw or {}
    level = r["level"]
    if r["load_transfer"] and (level not in ("articulated", "load_transfer") or
                               (level == "articulated" and "level" in raw)):  # a level written is never overruled
        raise _err(f"load_transfer = true asks for level \"load_transfer\", but level = {level!r}; give one of them",
                   "runout.load_transfer", file)
    if r["load_transfer"]:
        level = "load_transfer"
    if r["accuracy"] is None and r["accuracy_heading"] is not None:
        raise _err("accuracy_heading needs accuracy (the rest-position target) too", "runout.accuracy_heading", file)
    if r["accuracy"] is not None:
        if level in ("impact", "energy"):
            raise _err(f"accuracy = {r['accuracy']} m needs an integrated run-out; level {level!r} has no solver "
                       "settings to choose", "runout.accuracy", file)
        fixed = [k for k in ("rtol", "atol", "eps", "v_stop") if k in raw]
        if fixed:
            raise _err(f"accuracy chooses {', '.join(fixed)} itself; remove them or remove accuracy",
                       f"runout.{fixed[0]}", file)
    for i, z in enumerate(r["zones"]):
        why = outline_problem(z["polygon"])
        if why:
            raw_zones = raw.get("zones") if isinstance(raw.get("zones"), list) else []
            shown = raw_zones[i].get("polygon") if i < len(raw_zones) and isinstance(raw_zones[i], dict) else None
            value = f"polygon = {_written(shown)} " if shown is not None and len(shown) <= 8 else ""
            name = f"zone {z['name']!r}" if z["name"] else f"zone {i + 1}"
            raise _err(f"{value}is not the outline of {name}: {why}", f"runout.zones[{i}].polygon", file)
    try:
        zones = tuple(FrictionZone(tuple(z["polygon"]), z["friction"], z["name"] or f"zone {i + 1}",
                                   z["grade"], z["cross_slope"])
                      for i, z in enumerate(r["zones"]))
        road = Road(r["road_friction"], zones, r["grade"], r["cross_slope"])
    except ScenarioError as exc:
        raise _rewrap(exc, "runout.zones", file) from None
    rollover = _rollover_check(r, level, vehicles, file)
    try:
        extra = {"engine": r["engine"]} if "engine" in RunoutOptions.__dataclass_fields__ else {}
        if r["engine"] != "scipy" and not extra:
            raise ScenarioError("the compiled engine is not available in this installation", field="engine")
        options = RunoutOptions(method=r["method"], rtol=r["rtol"], atol=r["atol"], eps=r["eps"], v_stop=r["v_stop"],
                                max_step=r["max_step"], t_max=r["t_max"], sample_dt=r["sample_dt"],
                                lateral_model=r["lateral_model"], load_transfer=level == "load_transfer",
                                rollover=rollover, max_impacts=r["max_impacts"], max_wall_time=r["max_wall_time"],
                                **extra)
    except ScenarioError as exc:
        raise _rewrap(exc, "runout", file) from None
    if options.load_transfer:
        for veh in vehicles:
            for i, b in enumerate(veh.bodies):
                if b.cg_height is None and not b.is_fixed:
                    raise _err(f"level \"load_transfer\" needs the CG height of body {b.name!r}",
                               f"vehicles.{veh.name}.bodies[{i}].cg_height", file)
    if level == "impact":
        return RunoutSpec(road, options, {}, level)
    wheels, problems = {}, _Problems(file)
    for veh in vehicles:  # every vehicle's wheel errors at once
        if not veh.is_barrier:
            with problems.each():
                wheels[veh.name] = _build_wheels(veh, raw_vehicles[veh.name], file)
    problems.raise_any()
    return RunoutSpec(road, options, wheels, level, r["accuracy"], r["accuracy_heading"])


def _contact_model(base: ContactModel, entry: dict, key: str, file: str | None) -> ContactModel:
    changes = {k: entry[k] for k in CONTACT_KEYS if entry.get(k) is not None}
    try:
        return base.updated(**changes)
    except ScenarioError as exc:
        raise _rewrap(exc, key, file) from None


def _with_contact(spec: "RunoutSpec", d: dict, vehicles, problem: ImpactProblem, file: str | None) -> "RunoutSpec":
    """The run-out's contact model, pair overrides and obstacles (the barrier of the impact first)."""
    c = d["contacts"] or {}
    contact = _contact_model(ContactModel(), c, "contacts", file)
    bodies = {b.name for v in vehicles for b in v.bodies if not b.is_fixed}
    vnames = {v.name for v in vehicles if not v.is_barrier}
    obstacles = []
    barrier = d["barrier"]
    if barrier is not None:
        surf = problem.surface
        into_vehicle = surf.normal if problem.body2 == barrier["name"] else -surf.normal
        tangent = surf.tangent
        extent = None if barrier["extent"] is None else tuple(barrier["extent"])
        if extent is not None and problem.body2 != barrier["name"]:
            extent = (-extent[1], -extent[0]) if surf.tangent_sign < 0 else extent
        obstacles.append(Obstacle.barrier(barrier["name"], surf.point, into_vehicle, tangent, extent))
    taken = bodies | vnames | {o.name for o in obstacles}
    for i, o in enumerate(d["obstacles"]):
        key = f"obstacles[{i}]"
        if o["name"] in taken:
            raise _err(f"name {o['name']!r} is already a body, vehicle or obstacle name; names must be unique",
                       f"{key}.name", file)
        taken.add(o["name"])
        try:
            obstacles.append(Obstacle(o["name"], tuple(o["points"]), o["thickness"], o["closed"]))
        except ScenarioError as exc:
            msg = str(exc)
            if exc.field and msg.startswith(f"{exc.field}: "):
                msg = msg[len(exc.field) + 2:]
            raise _err(msg, f"{key}.points", file) from None
    names = bodies | vnames | {o.name for o in obstacles}
    owner = {b.name: v.name for v in vehicles for b in v.bodies}
    pairs = {}
    for i, p in enumerate(c.get("pairs", []) or []):
        key = f"contacts.pairs[{i}]"
        for which in ("first", "second"):
            if p[which] not in names:
                near = difflib.get_close_matches(p[which], sorted(names), n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise _err(f"{p[which]!r} names no body, vehicle or obstacle of the scene{hint} Names: "
                           f"{', '.join(map(repr, sorted(names)))}", f"{key}.{which}", file)
        a, b = p["first"], p["second"]
        va, vb = owner.get(a, a if a in vnames else None), owner.get(b, b if b in vnames else None)
        if a == b or (va is not None and va == vb):
            raise _err(f"{a!r} and {b!r} are not a pair that can meet: they are the same vehicle or body "
                       "(contact is between bodies of different vehicles, or a body and an obstacle)",
                       f"{key}.second", file)
        if va is None and vb is None:
            raise _err(f"{a!r} and {b!r} are both obstacles: obstacles do not meet each other", f"{key}.second", file)
        pairs[(a, b)] = _contact_model(contact, p, key, file)
    _check_stiffness(contact, pairs, c, vehicles, file)
    return _replace(spec, contact=contact, pair_contact=pairs, obstacles=tuple(obstacles))


def _check_stiffness(contact: ContactModel, pairs: dict, raw: dict, vehicles, file: str | None) -> None:
    """A contact stiffness must hold the heaviest vehicle's weight within WEIGHT_DEPTH."""
    movable = [v for v in vehicles if not v.is_barrier]
    if not movable:
        return
    heavy = max(movable, key=lambda v: sum(b.mass for b in v.bodies))
    weight = sum(b.mass for b in heavy.bodies) * STANDARD_GRAVITY
    least = weight / WEIGHT_DEPTH
    entries = [("contacts.stiffness", contact, raw.get("stiffness") is not None)]
    entries += [(f"contacts.pairs[{i}].stiffness", model, p.get("stiffness") is not None)
                for i, (p, model) in enumerate(zip(raw.get("pairs", []) or [], pairs.values()))]
    for key, model, given in entries:
        if given and model.enabled and model.stiffness < least:
            raise _err(f"{model.stiffness:g} N/m lets the weight of vehicle {heavy.name!r} ({weight:.4g} N) press "
                       f"{weight / model.stiffness:.3g} m deep; allowed >= {least:.4g} N/m (that weight held within "
                       f"{WEIGHT_DEPTH:g} m)", key, file)


def _err(msg: str, key: str, file: str | None) -> ScenarioError:
    return ScenarioError(msg, field=key, file=file)


def _build_vehicle(name: str, v: dict, file: str | None) -> tuple[Vehicle, dict[str, BodyState]]:
    bodies, hitches = [], []
    raw = v["bodies"]
    for i, b in enumerate(raw):
        key = f"vehicles.{name}.bodies[{i}]"
        if i < len(raw) - 1 and b["rear_hitch"] is None:
            raise _err(f"body {b['name']!r} tows {raw[i + 1]['name']!r} but has no rear_hitch; "
                       "give the pin position in its axes, e.g. [\"-3.1 m\", \"0 m\"]", f"{key}.rear_hitch", file)
        if i > 0 and b["front_hitch"] is None:
            raise _err(f"body {b['name']!r} is towed by {raw[i - 1]['name']!r} but has no front_hitch; "
                       "give the pin position in its axes, e.g. [\"3.991 m\", \"0 m\"]", f"{key}.front_hitch", file)
        if i == len(raw) - 1 and b["rear_hitch"] is not None:
            raise _err(f"body {b['name']!r} is the last body but has a rear_hitch {b['rear_hitch']}; "
                       "add the towed body after it or remove the key", f"{key}.rear_hitch", file)
        if i == 0 and b["front_hitch"] is not None:
            raise _err(f"body {b['name']!r} is the first body but has a front_hitch {b['front_hitch']}",
                       f"{key}.front_hitch", file)
        if i == 0 and b["roll_coupled"]:
            raise _err(f"body {b['name']!r} is the first body: it has no front hitch to carry roll moment (roll_coupled "
                       "belongs on the towed body, e.g. the semitrailer)", f"{key}.roll_coupled", file)
        if i == 0 and b["articulation"] != 0.0:
            raise _err("the first body has no front hitch to articulate about", f"{key}.articulation", file)
        if b["yaw_locked"] and i < 2:
            where = ("the first body has no front hitch" if i == 0 else
                     f"the body ahead, {raw[0]['name']!r}, is the first body (a tractor or truck), not a trailer")
            raise _err(f"yaw_locked = true: a C-dolly is yaw-locked to the trailer ahead, but {where}; allowed on "
                       f"bodies[2] or later (a body towed by a towed body)", f"{key}.yaw_locked", file)
        if b["yaw_locked"] and b["articulation"] != 0.0:
            raise _err(f"articulation = {math.degrees(b['articulation']):.6g} deg on a yaw-locked body (C-dolly, "
                       "yaw_locked = true): it cannot articulate; allowed 0 deg", f"{key}.articulation", file)
        if b["yaw_locked"] and b["yaw_rate"] != raw[i - 1]["yaw_rate"]:
            raise _err(f"yaw_rate = {b['yaw_rate']:.6g} rad/s on a yaw-locked body (C-dolly, yaw_locked = true) differs "
                       f"from that of {raw[i - 1]['name']!r} ({raw[i - 1]['yaw_rate']:.6g} rad/s); allowed: the same",
                       f"{key}.yaw_rate", file)
        lim = None if b["yaw_locked"] else b["articulation_limit"]
        if i > 0 and lim is not None and abs(b["articulation"]) > lim:
            raise _err(f"articulation = {math.degrees(b['articulation']):.6g} deg exceeds the jack-knife stop of body "
                       f"{b['name']!r}; allowed [-{math.degrees(lim):.6g}, {math.degrees(lim):.6g}] deg "
                       "(articulation_limit)", f"{key}.articulation", file)
        try:
            axles = tuple(Axle(a["x"], a["track"], a["dual"], a["name"]) for a in b["axles"])
            bodies.append(Body(b["name"], b["mass"], b["yaw_inertia"], b["length"], b["width"],
                               tuple(b["outline_center"]), axles, b["cg_height"], b["rollover_threshold"],
                               bool(b["roll_coupled"]), b["contact_height"]))
        except ScenarioError as exc:
            raise _err(str(exc), key, file) from None
        if i > 0:
            hitches.append(Hitch(tuple(raw[i - 1]["rear_hitch"]), tuple(b["front_hitch"]), lim, b["yaw_locked"]))
    try:
        veh = Vehicle(name, tuple(bodies), tuple(hitches))
    except ScenarioError as exc:
        raise _err(str(exc), f"vehicles.{name}", file) from None
    return veh, vehicle_states(veh, v)


def vehicle_states(veh: Vehicle, v: dict) -> dict[str, BodyState]:
    """The states at impact of a vehicle's bodies from its validated table ``v`` (position, heading,
    course, speed, the bodies' yaw rates and articulations)."""
    raw = v["bodies"]
    course = v["heading"] if v["course"] is None else v["course"]
    speed = 0.0 if v["speed"] is None else v["speed"]  # None: set by the approach (scenario_from_dict)
    vel = speed * np.array([math.cos(course), math.sin(course)])
    return chain_states(veh, v["position"], v["heading"], vel,
                        [b["yaw_rate"] for b in raw], [b["articulation"] for b in raw[1:]])


@dataclass(frozen=True)
class ApproachInput:
    """What a vehicle's approach needs, built and checked at load (SI).

    Attributes
    ----------
    spec : ApproachSpec
    road : Road
        The approach's road (the run-out's unless ``approach.road_friction`` is given).
    options : RunoutOptions
    speed_at_impact : float or None
        The file's speed at impact (``vehicles.<name>.speed``); None when the approach gives
        the speed at the start of braking.
    through_impact : bool
        The approach's wheel settings carry on into the run-out on one time line
        (:func:`crashsim.motion.approach.continued_wheels`).
    runout_wheels : WheelSettings or None
        The file's own run-out wheel settings of the vehicle (with ``through_impact`` their
        scheduled changes apply on top of the continued ones).
    """

    spec: Any
    road: Road
    options: RunoutOptions
    speed_at_impact: float | None
    through_impact: bool = False
    runout_wheels: Any = None


def _approach_input(veh: Vehicle, v: dict, runout: "RunoutSpec | None", file: str | None,
                    lines=(), path_given: bool = False, raw_recorded: dict | None = None) -> ApproachInput:
    """What the approach of ``veh`` (``v["approach"]``) needs, checked (its simulation comes later)."""
    a = v["approach"]
    key = f"vehicles.{veh.name}.approach"
    if a["speed"] is not None and v["speed"] is not None:
        raise _err(f"both the speed at impact (vehicles.{veh.name}.speed) and the speed at the start of braking "
                   f"({key}.speed) are given: give one, the approach gives the other", f"{key}.speed", file)
    if v["course"] is not None:
        raise _err("with an approach the direction of the velocity at impact follows from the approach; remove "
                   "course", f"vehicles.{veh.name}.course", file)
    wheels = _build_wheels(veh, {"tyres": a["tyres"], "wheels": a["wheels"], "wheel_changes": a["wheel_changes"],
                                 "bodies": v["bodies"], "brakes": a["brakes"]}, file, prefix=key)
    if a["road_friction"] is not None:
        road = (Road(a["road_friction"], runout.road.zones, runout.road.grade, runout.road.cross_slope)
                if runout is not None else Road(a["road_friction"]))
    elif runout is not None:
        road = runout.road
    else:
        raise _err("the approach needs the road friction: give road_friction here or a [runout] section",
                   f"{key}.road_friction", file)
    options = runout.options if runout is not None else RunoutOptions()
    n = len(veh.bodies)
    for name, want in (("articulation", n - 1), ("yaw_rates", n)):
        if a[name] is not None and len(a[name]) != want:
            raise _err(f"vehicle {veh.name!r} has {n} bodies: give {want} value(s), one per "
                       f"{'hitch' if name == 'articulation' else 'body'}, front to rear; got {len(a[name])}",
                       f"{key}.{name}", file)
    if a["articulation"] is not None:
        for i, (hitch, ang) in enumerate(zip(veh.hitches, a["articulation"])):
            if hitch.articulation_limit is not None and abs(ang) > hitch.articulation_limit:
                raise _err(f"{math.degrees(ang):.2f} deg at hitch {i + 1} lies beyond its articulation stop of "
                           f"{math.degrees(hitch.articulation_limit):.2f} deg", f"{key}.articulation", file)
    if a["solve_articulation"] and n < 2:
        raise _err(f"vehicle {veh.name!r} has no hitch: there is no articulation to solve", f"{key}.solve_articulation",
                   file)
    if a["through_impact"] and v.get("brakes") is not None:
        raise _err("with through_impact the approach's air brakes carry on into the run-out: give the brakes once, in "
                   f"{key}.brakes, and remove vehicles.{veh.name}.brakes", f"vehicles.{veh.name}.brakes", file)
    # the schema fills in the section's defaults when it is absent: a path is given by its table in the file
    given = a["path"] is not None and (path_given or a["path"]["points"] is not None or a["path"]["line"] is not None)
    driver = _approach_driver(veh, v, a, key, lines, file) if given else None
    recorded = None
    speed = a["speed"]
    if raw_recorded is not None:
        recorded = _approach_recorded(veh, v, a, key, raw_recorded, file)
        if recorded.speed is not None:
            speed = recorded.speed[0]
    try:
        spec = ApproachSpec(wheels, speed, a["distance"], a["time"],
                            None if a["start_position"] is None else tuple(a["start_position"]), a["start_heading"],
                            a["reaction_time"], a["tolerance"], key,
                            None if a["articulation"] is None else tuple(a["articulation"]),
                            None if a["yaw_rates"] is None else tuple(a["yaw_rates"]), a["solve_articulation"], driver,
                            recorded)
    except ScenarioError as exc:
        raise with_file(exc, file) from None
    return ApproachInput(spec, road, options, v["speed"], a["through_impact"],
                         runout.wheels.get(veh.name) if runout is not None else None)


def _approach_driver(veh: Vehicle, v: dict, a: dict, key: str, lines, file: str | None) -> DriverSpec:
    """The driver of ``[vehicles.<name>.approach.path]``, its path checked against the vehicle and the
    impact position (a path the vehicle cannot follow, or that does not reach the impact, is refused)."""
    p = a["path"]
    pkey = f"{key}.path"
    if (p["points"] is None) == (p["line"] is None):
        raise _err("give the path's points or the name of a [[map.lines]] line (one of the two)", f"{pkey}.points", file)
    if p["line"] is not None:
        names = [ln["name"] for ln in lines]
        if p["line"] not in names:
            near = difflib.get_close_matches(p["line"], names, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise _err(f"no [[map.lines]] line is named {p['line']!r}{hint} Named lines: "
                       f"{', '.join(repr(x) for x in names if x) or 'none'}", f"{pkey}.line", file)
        pts = np.asarray(lines[names.index(p["line"])]["points"], dtype=float)
        pts = pts[::-1] if p["reverse"] else pts
    else:
        pts = np.asarray(p["points"], dtype=float)
    try:
        driver = DriverSpec(DrivePath(pts, key=pkey), p["preview_time"], p["min_preview"], p["max_steer"],
                            p["max_steer_rate"], p["update"], pkey)
        check_path(veh, driver)
        if a["distance"] is not None:
            path_start(veh, driver, np.asarray(v["position"], dtype=float), a["distance"], a["tolerance"])
    except ScenarioError as exc:
        raise with_file(exc, file) from None
    return driver


def _recorded_speeds(a: dict) -> bool:
    """The approach's recorded table (if any) gives speeds: the speed at its start."""
    r = a.get("recorded")
    return bool(r and r.get("samples") and all(x.get("speed") is not None for x in r["samples"]))


def _approach_recorded(veh: Vehicle, v: dict, a: dict, key: str, raw: dict, file: str | None) -> RecordedDrive:
    """The recorder's table of ``[vehicles.<name>.approach.recorded]``: each column in every sample or in
    none, steering with its ratio, no speed rise the model has no engine for, and no other way of placing
    the approach's start given beside it."""
    r = a["recorded"]
    rkey = f"{key}.recorded"
    samples = r["samples"]
    raw_samples = raw.get("samples") if isinstance(raw.get("samples"), list) else []
    for other in ("distance", "time", "start_position"):
        if a[other] is not None:
            raise _err(f"the recorded table places the approach's start at its first sample ({samples[0]['time']:g} s "
                       f"before the impact): remove {other}", f"{key}.{other}", file)
    if a["path"] is not None and (a["path"]["points"] is not None or a["path"]["line"] is not None):
        raise _err("give a path or a recorded table to drive the approach, not both", f"{key}.path", file)
    if a["reaction_time"]:
        raise _err("the recorded table starts the simulated approach at its first sample; a reaction time before it "
                   "has no place: remove reaction_time", f"{key}.reaction_time", file)
    columns = {}
    for col in ("speed", "steering"):
        have = [x[col] is not None for x in samples]
        if any(have) and not all(have):
            j = have.index(False)
            raise _err(f"sample {j} has no {col}, others do: give {col} in every sample or in none",
                       f"{rkey}.samples[{j}].{col}", file)
        columns[col] = [x[col] for x in samples] if all(have) else None
    times = [x["time"] for x in samples]
    for j in range(1, len(times)):
        if times[j] <= times[j - 1]:
            raise _err(f"{_written(raw_samples[j].get('time')) if j < len(raw_samples) else times[j]} follows "
                       f"{_written(raw_samples[j - 1].get('time')) if j < len(raw_samples) else times[j - 1]}: sample "
                       "times must increase", f"{rkey}.samples[{j}].time", file)
    if times[0] >= 0.0:
        raise _err("the first sample must lie before the impact (a negative time)", f"{rkey}.samples[0].time", file)
    speed = columns["speed"]
    if speed is not None:
        if v["speed"] is not None:
            raise _err("the recorded speeds give the speed at the start; the speed at impact follows from the approach: "
                       f"remove vehicles.{veh.name}.speed", f"vehicles.{veh.name}.speed", file)
        if a["speed"] is not None:
            raise _err("the recorded speeds give the speed at the start: remove approach.speed", f"{key}.speed", file)
        rise = rising_speed(times, speed)
        if rise is not None:
            i, j = rise
            written = [_written(raw_samples[k].get("speed")) if k < len(raw_samples) else f"{speed[k]:g} m/s"
                       for k in (i, j)]
            raise _err(f"the recorded speed rises from {written[0]} (sample {i}) to {written[1]}: the approach has no "
                       "drive force (an engine), it can hold a speed but not gain one; start the table where the rise "
                       "ends, or give no speeds (the steering alone then drives, the speed given as for any approach); "
                       "a rise of up to 1 km/h, the recording's resolution, is accepted",
                       f"{rkey}.samples[{j}].speed", file)
    steer = None
    if columns["steering"] is not None:
        if r["steering_ratio"] is None:
            raise _err("the steering samples need the overall steering ratio (steering-wheel angle over the road wheels' "
                       "steer angle, e.g. 16)", f"{rkey}.steering_ratio", file)
        sign = 1.0 if r["steering_positive"] == "left" else -1.0
        steer = tuple(sign * x / r["steering_ratio"] for x in columns["steering"])
    elif r["steering_ratio"] is not None:
        raise _err("no sample has steering: remove steering_ratio, or give steering in every sample",
                   f"{rkey}.steering_ratio", file)
    try:
        drive = RecordedDrive(tuple(times), None if speed is None else tuple(speed), steer, r["update"],
                              r["speed_time"], rkey)
        if steer is not None:
            steer_geometry(veh, rkey)
    except ScenarioError as exc:
        raise with_file(exc, file) from None
    return drive


def frame_xform(frame: str, states: dict, key: str, file: str | None):
    """(origin, angle) of a frame named in the file."""
    if frame == "world":
        return np.zeros(2), 0.0
    if frame not in states:
        names = ["world", *states]
        near = difflib.get_close_matches(frame, names, n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise _err(f"unknown frame {frame!r}{hint} Allowed: {', '.join(repr(n) for n in names)}", key, file)
    s = states[frame]
    return np.asarray(s.position), s.heading


def frame_point(p, frame, states, key, file):
    """The point ``p`` [m] given in ``frame`` (``"world"`` or a body's name, see :func:`frame_xform`) in world
    coordinates; the scenario loader and :mod:`crashsim.reconstruct.patch` build impact points with it."""
    origin, ang = frame_xform(frame, states, key, file)
    return tuple(origin + rotate(np.asarray(p), ang))


def presets() -> dict[str, dict]:
    """crashsim's library of body parameter sets (raw file values, each with its ``source``)."""
    return tomllib.loads(files("crashsim").joinpath("data/vehicles.toml").read_text(encoding="utf-8"))


def preset_geometry(name: str) -> dict:
    """One preset validated as a body of a scenario file: SI values with defaults filled (mass, yaw_inertia,
    length, width, outline_center, axles with x, track, dual, name, front_hitch, rear_hitch, cg_height,
    articulation_limit, ...), and its ``source``. An unknown name is a :class:`ScenarioError` naming the
    presets."""
    library = presets()
    if name not in library:
        near = difflib.get_close_matches(str(name), list(library), n=2)
        hint = f"; did you mean {', '.join(map(repr, near))}?" if near else ""
        raise ScenarioError(f"unknown preset {name!r}{hint} Presets: {', '.join(library)}", field="preset")
    raw = {k: v for k, v in library[name].items() if k not in ("source", "crush")}
    out = validate({"name": name, **raw}, BODY)
    out["source"] = library[name]["source"]
    return out


def apply_presets(data: dict, file: str | None) -> dict:
    """Merge each body's preset under its own keys (before validation, so units are checked alike)."""
    vehicles = data.get("vehicles")
    if not isinstance(vehicles, dict):
        return data
    library = None
    data = copy.deepcopy(data)
    for vname, v in data["vehicles"].items():
        bodies = v.get("bodies") if isinstance(v, dict) else None
        if not isinstance(bodies, list):
            continue
        for i, b in enumerate(bodies):
            if not isinstance(b, dict) or "preset" not in b:
                continue
            library = library if library is not None else presets()
            name = b["preset"]
            if name not in library:
                near = difflib.get_close_matches(str(name), list(library), n=2)
                hint = f"; did you mean {', '.join(map(repr, near))}?" if near else ""
                raise _err(f"unknown preset {name!r}{hint} Presets: {', '.join(library)}",
                           f"vehicles.{vname}.bodies[{i}].preset", file)
            base = {k: copy.deepcopy(val) for k, val in library[name].items() if k not in ("source", "crush")}
            # a coupling the preset has but the body's place in the chain does not use (a tractor preset run
            # bobtail, as the last body: its fifth wheel tows nothing); one the file gives is checked as given
            if i == len(bodies) - 1 and "rear_hitch" not in b:
                base.pop("rear_hitch", None)
            if i == 0 and "front_hitch" not in b:
                base.pop("front_hitch", None)
            base.update({k: val for k, val in b.items()})
            bodies[i] = base
    return data


def _units_any_case(data: dict) -> dict:
    """``scenario.units`` written in any case ("us", "Si") read as "US"/"SI"."""
    meta = data.get("scenario") if isinstance(data, dict) else None
    if isinstance(meta, dict) and isinstance(meta.get("units"), str) and meta["units"].strip().upper() in ("SI", "US"):
        data = {**data, "scenario": {**meta, "units": meta["units"].strip().upper()}}
    return data


class _Problems:
    """The input errors of independent parts of a file, collected so that one run reports them all.

    ``with problems.each(): ...`` keeps a :class:`ScenarioError` raised inside and goes on;
    :meth:`raise_any` then raises them together: the error itself if it is the only one (its type
    kept: fit and Monte Carlo tell an unreachable or inadmissible impact from a bad file), else one
    :class:`~crashsim.schema.ScenarioValidationError` listing every one on its own line."""

    def __init__(self, file: str | None, lenient: bool = False):
        self.file = file
        self.lenient = lenient  # after schema errors: a part that fails on a bad value is skipped
        self.errors: list[ScenarioError] = []

    def each(self):
        return _Keep(self)

    def raise_any(self) -> None:
        if not self.errors:
            return
        if len(self.errors) == 1:
            raise self.errors[0]
        problems = []
        for exc in self.errors:
            if isinstance(exc, ScenarioValidationError):
                problems += exc.problems
                continue
            text = str(exc)
            if exc.file and text.startswith(f"{exc.file}: "):
                text = text[len(exc.file) + 2:]
            if exc.field and text.startswith(f"{exc.field}: "):
                text = text[len(exc.field) + 2:]
            for j, extra in enumerate(text.split("\n")):  # a multi-problem error: one line each
                if j == 0:
                    problems.append((exc.field or "", extra))
                elif extra.strip() and not extra.rstrip().endswith("more problems:") and not extra.rstrip().endswith(
                        "more problem:"):
                    path, _, rest = extra.strip().partition(": ")
                    problems.append((path, rest) if rest else (exc.field or "", extra.strip()))
        raise ScenarioValidationError(problems, file=self.file)


class _Skip(Exception):
    """A part left for the next run (lenient: what it needs could not be built)."""


class _Keep:
    def __init__(self, owner: _Problems):
        self.owner = owner

    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if exc is not None and isinstance(exc, ScenarioError):
            self.owner.errors.append(exc)
            return True
        if exc is not None and self.owner.lenient and isinstance(exc, Exception):
            return True  # a part built on a value the schema refused: its own checks cannot run
        return False


def scenario_from_dict(data: dict[str, Any], *, file: str | None = None, approaches: bool = True) -> Scenario:
    """Validate a parsed scenario (as from TOML) and build the typed SI objects.

    A ``[survey]`` section not yet read is read here (:func:`crashsim.survey.expand_survey`): its
    items join the file's own tables before validation.

    ``approaches``: simulate the vehicles' approaches (:func:`crashsim.scene.run.simulate_approaches`,
    the default);
    False leaves them to the scene run (:func:`crashsim.reconstruct.run_scene` simulates them
    before the impact): the scenario then carries their inputs (``approach_inputs``), and the
    states at impact of a vehicle with an approach are those of its file speed (0 if none) until
    then.  Fit, Monte Carlo and posterior samples build their scenarios so, and a sample that
    changes an approach re-runs only that approach."""
    source = data
    if isinstance(data, dict) and "survey" in data:
        data = expand_survey(data, file)
    data = _units_any_case(data)
    try:
        merged = apply_presets(data, file)
        d, schema_problems = validate_collect(merged, SCHEMA)
        if schema_problems:  # the checks after the schema too, on the parts it found valid: every error in one run
            raise ScenarioValidationError(schema_problems + _later_problems(d, data, merged, source, file,
                                                                            schema_problems), file=file)
        return _from_validated(d, data, merged, source, file, approaches)
    except ScenarioError as exc:  # an item the survey made: named by the key the user wrote
        raise as_written(exc, data) from None


def _related(a: str, b: str) -> bool:
    """Whether key paths ``a`` and ``b`` are the same key or one lies inside the other."""
    if a == b:
        return True
    short, long = sorted((a, b), key=len)
    return not short or (long.startswith(short) and long[len(short)] in ".[")


def _later_problems(d, data, merged, source, file, schema_problems) -> list[tuple[str, str]]:
    """The errors the checks after the schema find in a file that has schema errors: every part
    is built and checked where it can be (a part that fails on a value the schema refused is
    skipped), and an error at or inside a key the schema refused is left out (it repeats it)."""
    found: list[tuple[str, str]] = []
    try:
        _from_validated(d, data, merged, source, file, False, lenient=True)
    except ScenarioValidationError as exc:
        found = list(exc.problems)
    except ScenarioError as exc:
        text = str(exc).removeprefix(f"{exc.file}: " if exc.file else "")
        found = [(exc.field or "", text.removeprefix(f"{exc.field}: " if exc.field else ""))]
    except Exception:  # noqa: BLE001 - a part built on a refused value: nothing more to report
        found = []
    bad = [p for p, _ in schema_problems]
    return [(p, m) for p, m in found if not any(_related(p, b) or _about_sibling(p, m, b) for b in bad)]


def _about_sibling(path: str, message: str, refused: str) -> bool:
    """Whether a later error at ``path`` is about a key of the same table that the schema refused
    (``evidence.crush[0].A``: "... or ees; given: none" when ``evidence.crush[0].ees`` was refused):
    it names that key, whose value it cannot see."""
    parent, _, key = refused.rpartition(".")
    if not parent or path.rpartition(".")[0] != parent:
        return False
    return re.search(rf"(?<![\w.]){re.escape(key)}(?!\w)", message) is not None


def _from_validated(d: dict, data: dict, merged: dict, source, file: str | None, approaches: bool,
                    lenient: bool = False) -> Scenario:
    """The typed scenario of a validated document ``d`` (see :func:`scenario_from_dict`); ``lenient``:
    ``d`` has values the schema refused (None), and a part that fails on one is skipped."""
    vehicles, states = [], {}
    problems = _Problems(file, lenient)  # the independent parts of the file first: every error of them at once
    for name, v in d["vehicles"].items():
        with problems.each():
            if v["speed"] is None and v["approach"] is None:
                raise _err("the speed at impact is missing: give speed (CG speed of the first body at impact), or "
                           "an [vehicles.<name>.approach] with the speed at the start of braking",
                           f"vehicles.{name}.speed", file)
        with problems.each():
            if (v["approach"] is not None and v["approach"]["speed"] is None and v["speed"] is None
                    and not _recorded_speeds(v["approach"])):
                raise _err("the approach needs the speed at the start of braking (approach.speed) or the speed at "
                           "impact (speed)", f"vehicles.{name}.approach.speed", file)
        with problems.each():
            veh, st = _build_vehicle(name, v, file)
            _check_vehicle_geometry(veh, v, merged["vehicles"][name], d["scenario"]["units"], file)
            for bn in st:
                if bn in states:
                    raise _err(f"body name {bn!r} is used twice; body names must be unique in the scene",
                               f"vehicles.{name}.bodies", file)
            vehicles.append(veh)
            states.update(st)
    _check_impact_law(d["impact"], problems, file)
    runout = None
    if d["runout"] is not None:
        raw_runout = data.get("runout") if isinstance(data.get("runout"), dict) else {}
        with problems.each():
            runout = _build_runout(d["runout"], vehicles, d["vehicles"], file, raw_runout)
    problems.raise_any()
    # lenient: a [runout] refused by the schema is no run-out; what needs it (the approaches) is not checked
    runout_lost = lenient and d["runout"] is not None and runout is None
    approach_inputs = {}
    for veh in vehicles:
        v = d["vehicles"][veh.name]
        if v["approach"] is not None and not runout_lost:
            raw = ((merged.get("vehicles") or {}).get(veh.name) or {}).get("approach") or {}
            approach_inputs[veh.name] = _approach_input(veh, v, runout, file,
                                                        (d.get("map") or {}).get("lines") or (),
                                                        path_given="path" in raw,
                                                        raw_recorded=raw.get("recorded") if isinstance(
                                                            raw.get("recorded"), dict) else None)
    later = _Problems(file, lenient)
    imp = d["impact"]
    problem = None
    # lenient: a vehicle that could not be built (a value of it refused) leaves the checks that need it
    # (the impact, the evidence) for the next run, and a [runout] not built says nothing of its options
    vehicle_lost = lenient and len(vehicles) < len(d["vehicles"])
    runout_failed = d["runout"] is not None and runout is None
    if vehicle_lost:
        pass
    elif lenient:  # a file with schema errors: the evidence and the map are checked even if the impact fails
        with later.each():
            problem = _impact_problem(d, vehicles, states, file)
    else:
        problem = _impact_problem(d, vehicles, states, file)
    # the geometry at impact, the contact model, the evidence and the map: independent, every error at once
    if problem is not None:
        with later.each():
            _check_overlap(problem, vehicles, states, imp["overlap_tolerance"], d["scenario"]["units"], file)  # cause
            check_contact_point(problem, imp["contact_tolerance"], d["scenario"]["units"], file)  # first
    if runout is not None and problem is not None:
        with later.each():
            runout = _with_contact(runout, d, vehicles, problem, file)
    evidence = map_lines = crush = None
    with later.each():
        if vehicle_lost:
            raise _Skip
        evidence = _build_evidence(d["evidence"], states, file, vehicles,
                                   {n: v["approach"] for n, v in d["vehicles"].items()})
        if evidence.rollover and not runout_failed and (runout is None or not runout.options.rollover):
            raise _err("a rollover statement is checked against the wheel-lift and rollover check, which is off: add "
                       "runout.rollover = true (level \"load_transfer\")", "evidence.rollover[0].unit", file)
    with later.each():
        if d["evidence"] is not None and d["evidence"]["crush"] and not vehicle_lost:
            crush = _build_crush(d["evidence"]["crush"], d, vehicles, file)
    if evidence is not None and crush is not None:
        evidence = dataclasses.replace(evidence, crush=crush)
    with later.each():
        map_lines = _build_map_lines(d["map"], file, d.get("survey"))
    with later.each():
        _check_north(d, file)
    later.raise_any()
    meta = d["scenario"]
    survey = d.get("survey")
    placed = is_placed(survey)
    units = DisplaySystem(meta["units"], meta["speed_unit"]) if meta.get("speed_unit") else meta["units"]
    out = Scenario(file, meta["title"], meta["source"], units, tuple(vehicles), states, problem, runout,
                   evidence, d, map_lines, {}, approach_inputs,
                   descriptions={n: v.get("description") or "" for n, v in d["vehicles"].items()},
                   survey_frame=survey_frame(survey) if placed else None,
                   north=(d.get("map") or {}).get("north"), barrier_extent=_barrier_extent(d.get("barrier")),
                   load_warnings=tuple(_angle_warnings(data)))
    object.__setattr__(out, "_file_data", source)  # the file contents it was built from (Scenario.file_data)
    if not approaches:
        return out
    return simulate_approaches(out)


_ANGLE = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(rad|radians?|deg|degrees?)\s*$",
                    re.IGNORECASE)


def _angle_warnings(data, path: str = "") -> list[str]:
    """A warning for every angle of the file beyond one turn: in rad most likely degrees meant
    ("192 rad" is 30.6 turns), in deg a doubtful value (a rotation of 1e9 deg)."""
    out: list[str] = []
    if isinstance(data, dict):
        for k, v in data.items():
            if k != "imported":
                out += _angle_warnings(v, f"{path}.{k}" if path else str(k))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            out += _angle_warnings(v, f"{path}[{i}]")
    elif isinstance(data, str):
        m = _ANGLE.match(data)
        if m:
            x, unit = float(m[1]), m[2].lower()
            turns = abs(x) / (2 * math.pi) if unit.startswith("rad") else abs(x) / 360.0
            if turns > 1.0:
                hint = f"; did you mean \"{m[1]} deg\"?" if unit.startswith("rad") else ""
                out.append(f"{path} = {data!r} is {turns:.4g} turns (more than 2 pi rad){hint}")
    return out


def _barrier_extent(barrier: dict | None) -> tuple[float, float] | None:
    """:attr:`Scenario.barrier_extent` of a validated ``[barrier]`` table."""
    if barrier is None:
        return None
    return tuple(barrier["extent"]) if barrier["extent"] is not None else (-math.inf, math.inf)


def _impact_problem(d: dict, vehicles: list, states: dict, file: str | None) -> ImpactProblem:
    """The [impact] (and [barrier]) of a validated file as an ImpactProblem; a barrier joins
    ``vehicles`` and ``states``."""
    imp = d["impact"]
    if d["barrier"] is not None:
        bname = d["barrier"]["name"]
        if bname in states:
            raise _err(f"barrier name {bname!r} is also a body name", "barrier.name", file)
    elif len(vehicles) < 2:
        raise _err(f"an impact needs two vehicles, or one and a [barrier]; got {len(vehicles)}: "
                   f"{[v.name for v in vehicles]}", "vehicles", file)
    for k in ("body1", "body2"):
        allowed = list(states) + ([d["barrier"]["name"]] if d["barrier"] is not None else [])
        if imp[k] not in allowed:
            near = difflib.get_close_matches(imp[k], allowed, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise _err(f"unknown body {imp[k]!r}{hint} Bodies: {', '.join(map(repr, allowed))}", f"impact.{k}", file)
    same = [v for v in vehicles if {imp["body1"], imp["body2"]} <= {b.name for b in v.bodies}]
    if same:
        raise _err(f"impact.body1 = {imp['body1']!r} and impact.body2 = {imp['body2']!r} are both bodies of vehicle "
                   f"{same[0].name!r}; the impact is between two vehicles (or one and the [barrier]): give a body of "
                   "another vehicle as impact.body2 (a vehicle's own bodies meet at their articulation stop, set by "
                   "articulation_limit)", "impact.body2", file)
    if d["barrier"] is not None and d["barrier"]["name"] not in (imp["body1"], imp["body2"]):
        raise _err(f"the barrier {d['barrier']['name']!r} is neither impact.body1 ({imp['body1']!r}) nor impact.body2 "
                   f"({imp['body2']!r}); [barrier] is the rigid body of the impact (fixed obstacles met in the "
                   "run-out go in [[obstacles]])", "barrier.name", file)
    point = frame_point(imp["point"], imp["point_frame"], states, "impact.point_frame", file)
    _, nang = frame_xform(imp["normal_frame"], states, "impact.normal_frame", file)
    if d["barrier"] is not None:
        bname = d["barrier"]["name"]
        vehicles.append(Vehicle(bname, (Body(bname, math.inf, math.inf),)))
        states[bname] = BodyState(point, 0.0, (0.0, 0.0), 0.0)
    law = imp["tangential"]
    ep = imp["moment_restitution"]
    value = {"ratio": imp["mu"], "fraction": imp["mu_fraction"], "friction": imp["friction"]}.get(law, 0.0)
    surface = CrushSurface(point, imp["normal"] + nang, imp["restitution"], TangentialLaw(law, value), ep,
                           1 if imp["tangent"] == "ccw" else -1)
    constraints = []
    for i, c in enumerate(imp["constraints"]):
        key = f"impact.constraints[{i}]"
        origin, ang = frame_xform(c["frame"], states, f"{key}.frame", file)
        constraints.append(VelocityConstraint(c["body"], tuple(origin + rotate(np.asarray(c["point"]), ang)),
                                              c["direction"] + ang, c["value"], c["name"] or f"constraint {i + 1}"))
    external = []
    for i, x in enumerate(imp["external_impulses"]):
        key = f"impact.external_impulses[{i}]"
        origin, ang = frame_xform(x["frame"], states, f"{key}.frame", file)
        helper = [x[k] is not None for k in ("friction", "load", "duration", "direction")]
        if x["impulse"] is not None:
            if any(helper):
                raise _err("give either impulse, or friction + load + duration + direction, not both", key, file)
            vec = rotate(np.asarray(x["impulse"]), ang)
        elif all(helper):
            vec = tyre_friction_impulse(x["friction"], x["load"], x["duration"], x["direction"] + ang)
        else:
            missing = [k for k, h in zip(("friction", "load", "duration", "direction"), helper) if not h]
            raise _err(f"needs impulse, or all of friction, load, duration, direction (missing: {', '.join(missing)})",
                       key, file)
        external.append(ExternalImpulse(x["body"], tuple(origin + rotate(np.asarray(x["point"]), ang)), tuple(vec),
                                        x["name"] or f"impulse {i + 1}"))
    # the impact involves the two vehicles of body1 and body2; any others wait for the run-out
    owner = {b.name: v for v in vehicles for b in v.bodies}
    involved = []
    for k in ("body1", "body2"):
        v = owner[imp[k]]
        if v not in involved:
            involved.append(v)
    for i, c in enumerate(imp["constraints"]):
        if c["body"] in owner and owner[c["body"]] not in involved:
            raise _err(f"body {c['body']!r} is not in the impact (vehicles {[v.name for v in involved]})",
                       f"impact.constraints[{i}].body", file)
    for i, x in enumerate(imp["external_impulses"]):
        if x["body"] in owner and owner[x["body"]] not in involved:
            raise _err(f"body {x['body']!r} is not in the impact (vehicles {[v.name for v in involved]})",
                       f"impact.external_impulses[{i}].body", file)
    try:
        problem = ImpactProblem(tuple(involved), {b.name: states[b.name] for v in involved for b in v.bodies},
                                imp["body1"], imp["body2"], surface, tuple(constraints), tuple(external))
    except ScenarioError as exc:
        raise ScenarioError(str(exc), field=exc.field, file=file) from None
    return problem


def _check_impact_law(imp: dict, problems: _Problems, file: str | None) -> None:
    """The [impact] table's tangential law and its coefficient, and the moment restitution: each error kept."""
    law = imp["tangential"]
    with problems.each():
        if law == "ratio" and imp["mu"] is None:
            raise _err('tangential = "ratio" needs mu (the impulse ratio P_t/P_n), e.g. mu = 0.3', "impact.mu", file)
        if law == "fraction" and imp["mu_fraction"] is None:
            raise _err('tangential = "fraction" needs mu_fraction (mu as a share of mu_max, 0 to 1), e.g. '
                       'mu_fraction = 0.85', "impact.mu_fraction", file)
        if law == "friction" and imp["friction"] is None:
            raise _err('tangential = "friction" needs friction (f >= 0), e.g. friction = 0.6', "impact.friction",
                       file)
    for k, needed in (("mu", "ratio"), ("mu_fraction", "fraction"), ("friction", "friction")):
        with problems.each():
            if imp[k] is not None and law != needed:
                raise _err(f"{k} = {imp[k]} is given but tangential = {law!r} does not use it "
                           f'(it belongs to tangential = "{needed}")', f"impact.{k}", file)
    ep = imp["moment_restitution"]
    with problems.each():
        if not (ep == -1.0 or 0.0 <= ep <= 1.0):
            raise _err(f"{ep} is out of range; allowed -1 (no moment impulse) or [0, 1]", "impact.moment_restitution",
                       file)


def outline_problem(points) -> str | None:
    """Why ``points`` (a closed outline, in order) is not a simple polygon, or None: fewer than 3
    points, all on one line (no area), or edges crossing (a bow-tie: points not in order around it)."""
    p = np.asarray(points, dtype=float)
    n = len(p)
    if n < 3:
        return f"{n} point(s); an outline needs at least 3"

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    scale = max(float(np.ptp(p[:, 0])), float(np.ptp(p[:, 1])), 1e-300)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue  # adjacent through the closing edge
            a, b, c, d = p[i], p[(i + 1) % n], p[j], p[(j + 1) % n]
            d1, d2, d3, d4 = cross(c, d, a), cross(c, d, b), cross(a, b, c), cross(a, b, d)
            if d1 * d2 < 0 and d3 * d4 < 0:
                return (f"its edges cross (points {i + 1}-{i + 2} and points {j + 1}-{(j + 1) % n + 1}): the outline "
                        "intersects itself; list the points in order around the zone")
    x, y = p[:, 0], p[:, 1]
    area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if area <= 1e-12 * scale * scale:
        return "its points lie on one line: it has no area"
    return None


def _written(raw) -> str:
    """A value as written in the file (``["-6.2 m", "0 m"]``)."""
    return toml_repr(raw)


def _check_vehicle_geometry(veh: Vehicle, v: dict, raw: dict, system: str, file: str | None) -> None:
    """Hitch points within (or within ``drawbar`` of) both bodies they join; tyre contacts within
    (or within ``overhang`` of) their body's outline. One error, naming the key as written, the
    value as written in the file, how far it is off and the allowed range."""
    def L(x, like=None):
        """A length in the unit of ``like`` (a value as written in the file), else the file's system's."""
        like = like[0] if isinstance(like, (list, tuple)) and like else like
        if isinstance(like, str) and len(like.split(maxsplit=1)) == 2:
            unit = like.split(maxsplit=1)[1]
            try:
                return f"{x / parse(f'1 {unit}', Kind.LENGTH, field='unit'):.4g} {unit}"
            except ScenarioError:
                pass
        return format_value(x, Kind.LENGTH, system)

    bodies = v["bodies"]
    for i, body in enumerate(veh.bodies):
        corners = body.outline()
        if corners is None:
            continue
        b, rb = bodies[i], raw["bodies"][i]
        key = f"vehicles.{veh.name}.bodies[{i}]"
        size = f"outline {L(body.length, rb.get('length'))} x {L(body.width, rb.get('width'))}"
        for which in ("rear_hitch", "front_hitch"):
            if b[which] is None:
                continue
            out = max(0.0, -float(signed_distance(np.asarray(b[which], dtype=float)[None], corners)[0]))
            if out > b["drawbar"] + 1e-9:
                raise _err(f"{which} = {_written(rb[which])} lies {L(out, rb[which])} outside the {size} of body "
                           f"{body.name!r}; allowed: within the outline or at most drawbar = "
                           f"{L(b['drawbar'], rb.get('drawbar'))} outside "
                           f"it (a longer drawbar or tongue: set {key}.drawbar)", f"{key}.{which}", file)
        cx, cy = body.outline_center
        ahead, side = b["overhang"]
        for k, ax in enumerate(body.axles):
            front, rear = cx + body.length / 2 + ahead, cx - body.length / 2 - ahead
            rax = rb["axles"][k] if isinstance(rb.get("axles"), list) and k < len(rb["axles"]) else {}
            akey = f"{key}.axles[{k}]"
            if not rear - 1e-9 <= ax.x <= front + 1e-9:
                lx = rax.get("x")
                raise _err(f"x = {_written(rax.get('x', ax.x))} puts the axle outside the body: allowed "
                           f"[{L(rear, lx)}, {L(front, lx)}] from the CG ({size} centred at {L(cx, lx)}, plus overhang "
                           f"= {L(ahead, rb.get('overhang'))} beyond its ends; set {key}.overhang for more)", f"{akey}.x", file)
            half = body.width / 2 + side - abs(cy)  # tyre contacts at +-track/2 from the CG line
            if ax.track / 2 > half + 1e-9:
                lt = rax.get("track")
                raise _err(f"track = {_written(rax.get('track', ax.track))} is wider than body {body.name!r} "
                           f"(width {L(body.width, lt)}); allowed a track <= {L(2 * half, lt)} (the width plus overhang "
                           f"= {L(side, (rb.get('overhang') or [None, None])[1:])} on each side; set {key}.overhang for more)",
                           f"{akey}.track", file)


def _sat_depth(a: np.ndarray, b: np.ndarray) -> float:
    """How far one convex polygon must move to clear the other (separating axes) [m]; 0 if apart."""
    depth = math.inf
    for poly in (a, b):
        for i in range(len(poly)):
            e = poly[(i + 1) % len(poly)] - poly[i]
            n = np.array([-e[1], e[0]]) / math.hypot(e[0], e[1])
            pa, pb = a @ n, b @ n
            ov = min(pa.max(), pb.max()) - max(pa.min(), pb.min())
            if ov <= 0:
                return 0.0
            depth = min(depth, ov)
    return float(depth)


def _check_overlap(problem: ImpactProblem, vehicles, states: dict, tolerance: float, system: str,
                   file: str | None) -> None:
    """Bodies of different vehicles may overlap at the impact by at most ``tolerance``: the impact's
    two bodies measured along the impact normal (their crush), any other pair by the distance one
    must move to clear the other (they are not in the impact: any overlap is a misplaced vehicle)."""
    normal = np.asarray(problem.surface.normal, dtype=float)
    pair = {problem.body1, problem.body2}
    placed = []
    for v in vehicles:
        for b in v.bodies:
            corners = b.outline()
            if corners is None or b.is_fixed or b.name not in states:
                continue
            st = states[b.name]
            placed.append((v.name, b.name, np.asarray(st.position) + rotate(corners, st.heading)))
    for i, (va, ba, pa) in enumerate(placed):
        for vb, bb, pb in placed[i + 1:]:
            if va == vb or _sat_depth(pa, pb) == 0.0:
                continue
            crush = {ba, bb} == pair
            if crush:
                qa, qb = pa @ normal, pb @ normal
                depth, how = min(qa.max(), qb.max()) - max(qa.min(), qb.min()), "along the impact normal"
            else:
                depth, how = _sat_depth(pa, pb), "(the distance one must move to clear the other)"
            if depth > tolerance:
                L = lambda x: format_value(x, Kind.LENGTH, system)  # noqa: E731
                raise _err(f"at the impact the outlines of {ba!r} (vehicle {va!r}) and {bb!r} (vehicle {vb!r}) overlap "
                           f"{L(depth)} deep {how}: one vehicle is placed on top of the other; allowed at most "
                           f"impact.overlap_tolerance = {L(tolerance)} (the crush of the first impact); check the "
                           f"positions and headings of vehicles.{va} and vehicles.{vb}", f"vehicles.{vb}.position",
                           file)


def contact_outlines(problem: ImpactProblem, states: dict) -> list[tuple[str, np.ndarray]]:
    """``(name, corners in world coordinates)`` of the impact's two contacting bodies at ``states``
    (a fixed body, or one without an outline, left out)."""
    out = []
    for name in (problem.body1, problem.body2):
        body = next(b for v in problem.vehicles for b in v.bodies if b.name == name)
        corners = body.outline()
        if body.is_fixed or corners is None:
            continue
        st = states[name]
        out.append((name, np.asarray(st.position) + rotate(corners, st.heading)))
    return out


def check_contact_point(problem: ImpactProblem, tolerance: float, system: str, file: str | None) -> None:
    """The contact point must lie in or near (``tolerance``) the outline of both contacting bodies."""
    point = np.asarray(problem.surface.point)
    far = []
    for name, world in contact_outlines(problem, problem.states):
        gap = max(0.0, -float(signed_distance(point[None], world)[0]))
        if gap > tolerance:
            far.append(f"{format_value(gap, Kind.LENGTH, system)} outside the outline of {name!r}")
    if far:
        shown = ", ".join(format_value(float(c), Kind.LENGTH, system) for c in point)
        raise _err(f"the contact point ({shown}) lies " + " and ".join(far)
                   + f" at impact (allowed: within impact.contact_tolerance = {format_value(tolerance, Kind.LENGTH, system)} "
                   "of both outlines); check impact.point and its point_frame, and the vehicles' positions and headings",
                   "impact.point", file)


def _rest_registration(r: dict, body: Body, key: str, file: str | None):
    """The CG and heading of a rest item given by measured points of ``body`` (a rigid least-squares fit)."""
    if r["position"] is not None:
        raise _err("give either position (the measured CG) or points (measured points of the body), not both",
                   f"{key}.points", file)
    if r["heading"] is not None:
        raise _err(f"heading = {math.degrees(r['heading']):.6g} deg is given with points: the points give the heading; "
                   "remove heading (heading_tolerance then applies to the derived heading)", f"{key}.heading", file)
    pts = r["points"]
    if len(pts) < 2:
        raise _err(f"{len(pts)} measured point: at least two are needed to fix the CG and the heading",
                   f"{key}.points", file)
    named = named_body_points(body)
    labels, body_pts, measured = [], [], []
    for j, p in enumerate(pts):
        pkey = f"{key}.points[{j}]"
        if (p["at"] is None) == (p["body_point"] is None):
            raise _err("give at (a named point of the body, e.g. \"front_left\") or body_point (in body axes), "
                       f"{'not both' if p['at'] is not None else 'one of them'}", pkey, file)
        if p["at"] is not None:
            at = p["at"]
            if at not in named:
                if at in CORNERS:
                    raise _err(f"at = {at!r} is a corner of the outline, but body {body.name!r} has no length and "
                               "width; give them in its [[vehicles.<v>.bodies]] entry, or give body_point",
                               f"{pkey}.at", file)
                near = difflib.get_close_matches(at, list(named), n=2)
                hint = f"; did you mean {' or '.join(map(repr, near))}?" if near else ""
                raise _err(f"at = {at!r} is not a named point of body {body.name!r}{hint} Named points: "
                           f"{', '.join(named) or 'none (no length, width or axles)'}", f"{pkey}.at", file)
            labels.append(at)
            body_pts.append(named[at])
        else:
            bp = tuple(p["body_point"])
            labels.append("(" + ", ".join(format_value(v, Kind.LENGTH) for v in bp) + ")")
            body_pts.append(bp)
        measured.append(tuple(p["position"]))
    try:
        return register_points(body_pts, measured, labels)
    except ValueError as exc:
        shown = "; ".join(f"{lab} at (" + ", ".join(format_value(v, Kind.LENGTH) for v in m) + ")"
                          for lab, m in zip(labels, measured))
        raise _err(f"{exc}: {shown}", f"{key}.points", file) from None


def _build_evidence(e: dict | None, states: dict, file: str | None, vehicles=(), d_approach: dict | None = None
                    ) -> Evidence:
    """The evidence items; ``d_approach``: the validated approach section of each vehicle (or None).
    Every item is checked: the errors of all of them come together."""
    if e is None:
        return Evidence()
    problems = _Problems(file)

    def body(name, key):
        if name not in states:
            near = difflib.get_close_matches(name, list(states), n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise _err(f"unknown body {name!r}{hint} Bodies: {', '.join(map(repr, states))}", key, file)
        return name

    rest = []
    by_name = {b.name: b for v in vehicles for b in v.bodies}
    for i, r in enumerate(e["rest"]):
        with problems.each():
            rest.append(_rest_item(r, i, body, by_name, file))
    marks = []
    for i, m in enumerate(e["marks"]):
        with problems.each():
            marks.append(_mark_item(m, i, body, vehicles, d_approach, file))
    poi = None
    if e["impact_point"] is not None:
        poi = ImpactPointEvidence(tuple(e["impact_point"]["position"]), e["impact_point"]["tolerance"],
                                  sigma=e["impact_point"].get("sigma"))
    dv = []
    for i, x in enumerate(e["delta_v"]):
        with problems.each():
            dv.append(DeltaVEvidence(body(x["body"], f"evidence.delta_v[{i}].body"), x["value"], x["tolerance"],
                                     x["component"], x["name"], x["impacts"], sigma=x.get("sigma")))
    recorder = []
    for i, x in enumerate(e["recorder"]):
        with problems.each():
            recorder.append(_recorder_item(x, i, body, vehicles, d_approach, file))
    rollover = []
    units = {v.name for v in vehicles if not v.is_barrier} | {b.name for v in vehicles if not v.is_barrier
                                                               for b in v.bodies}
    for i, x in enumerate(e.get("rollover") or []):
        with problems.each():
            if x["unit"] not in units:
                near = difflib.get_close_matches(x["unit"], sorted(units), n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise _err(f"unknown vehicle or body {x['unit']!r}{hint} Vehicles and bodies: "
                           f"{', '.join(map(repr, sorted(units)))}", f"evidence.rollover[{i}].unit", file)
            rollover.append(RolloverEvidence(x["unit"], bool(x["rolled"]), x["name"]))
    problems.raise_any()
    return Evidence(tuple(rest), tuple(marks), poi, tuple(dv), tuple(recorder), rollover=tuple(rollover))


def _rest_item(r: dict, i: int, body, by_name: dict, file: str | None) -> RestEvidence:
    """One ``[[evidence.rest]]`` item."""
    key = f"evidence.rest[{i}]"
    name = body(r["body"], f"{key}.body")
    if r["points"]:
        reg = _rest_registration(r, by_name[name], key, file)
        heading = reg.heading if r["heading_tolerance"] is not None else None
        return RestEvidence(name, reg.position, r["tolerance"], heading, r["heading_tolerance"], r["name"], reg,
                            sigma=r.get("sigma"), heading_sigma=r.get("heading_sigma"))
    if r["position"] is None:
        raise _err(f"rest evidence of {name!r} needs position (the measured CG) or points (two or more measured "
                   "points of the body, e.g. its corners)", f"{key}.position", file)
    if (r["heading"] is None) != (r["heading_tolerance"] is None):
        raise _err("heading and heading_tolerance go together", f"{key}.heading_tolerance", file)
    return RestEvidence(name, tuple(r["position"]), r["tolerance"], r["heading"], r["heading_tolerance"], r["name"],
                        sigma=r.get("sigma"), heading_sigma=r.get("heading_sigma"))


def _mark_item(m: dict, i: int, body, vehicles, d_approach, file: str | None) -> MarkEvidence:
    """One ``[[evidence.marks]]`` item."""
    sel = m["wheel"]
    if sel != "*":
        key = f"evidence.marks[{i}].wheel"
        vehicle = next(v for v in vehicles if body(sel.split("/")[0], key) in {b.name for b in v.bodies})
        try:  # the wheels the selector names must exist (as for wheel settings)
            select_wheels(vehicle, enumerate_wheels(vehicle), sel, key)
        except ScenarioError as exc:
            raise _err(str(exc).removeprefix(f"{key}: "), key, file) from None
    if m["phase"] == "approach":
        owner = (sel.split("/")[0] if sel != "*" else None)
        with_approach = [v for v in vehicles if (d_approach or {}).get(v.name)]
        if not with_approach or (owner is not None and not any(owner in {b.name for b in v.bodies}
                                                               for v in with_approach)):
            raise _err("a pre-impact mark (phase = \"approach\") needs an approach of the vehicle that left it "
                       f"({owner or 'any vehicle'}): add [vehicles.<name>.approach]",
                       f"evidence.marks[{i}].phase", file)
    return MarkEvidence(np.asarray(m["points"], dtype=float), m["tolerance"], sel, m["sliding_only"], m["name"],
                        m["phase"], sigma=m.get("sigma"))


def _recorder_item(x: dict, i: int, body, vehicles, d_approach, file: str | None) -> RecorderEvidence:
    """One ``[[evidence.recorder]]`` item."""
    key = f"evidence.recorder[{i}]"
    name = body(x["body"], f"{key}.body")
    veh = next(v for v in vehicles if name in {b.name for b in v.bodies})
    if not (d_approach or {}).get(veh.name):
        raise _err(f"recorder samples are compared with the approach of vehicle {veh.name!r}, which has none: add "
                   f"[vehicles.{veh.name}.approach]", f"{key}.body", file)
    smp = x["samples"]
    first: dict = {}
    for j, p in enumerate(smp):
        if p["time"] in first:
            raise _err(f"samples[{first[p['time']]}] and samples[{j}] have the same time ({p['time']:g} s); a "
                       "recorder takes one sample at a time", f"{key}.samples[{j}].time", file)
        first[p["time"]] = j
    if len(smp) == 1 and smp[0]["time"] + x["time_offset"] > 0:
        raise _err(f"time = {smp[0]['time']:g} s is after the impact (time + time_offset = "
                   f"{smp[0]['time'] + x['time_offset']:g} s); allowed <= {-x['time_offset']:g} s: pre-crash data "
                   "end at the impact", f"{key}.samples[0].time", file)
    if not any(p["time"] + x["time_offset"] <= 0 for p in smp):
        raise _err(f"no sample is before the impact: every time + time_offset ({x['time_offset']:g} s) is > 0; "
                   "allowed at least one sample at or before it", f"{key}.samples", file)
    return RecorderEvidence(name, tuple(p["time"] for p in smp), tuple(p["speed"] for p in smp),
                            tuple(bool(p["brake"]) for p in smp), x["tolerance"], x["time_offset"], x["name"],
                            sigma=x.get("sigma"))


def _build_crush(items: list, d: dict, vehicles, file: str | None) -> tuple:
    """The ``[[evidence.crush]]`` items as CrushEvidence (A and B from the body's preset where omitted); the
    errors of every item together."""
    by_name = {b.name: b for v in vehicles for b in v.bodies}
    preset_of = {b["name"]: b.get("preset") for v in d["vehicles"].values() for b in v["bodies"]}
    out = []
    problems = _Problems(file)  # every item checked: their errors come together
    for i, c in enumerate(items):
        with problems.each():
            key = f"evidence.crush[{i}]"
            name = c["body"]
            if name not in by_name or by_name[name].is_fixed:
                near = difflib.get_close_matches(name, [n for n, b in by_name.items() if not b.is_fixed], n=1)
                hint = f"; did you mean {near[0]!r}?" if near else ""
                raise _err(f"unknown body {name!r}{hint} (a movable body of a vehicle)", f"{key}.body", file)
            profile_keys = ("A", "B", "width", "profile")
            given = [k for k in profile_keys if c[k] is not None]
            A, B, source = c["A"], c["B"], "given in the scenario"
            if c["ees"] is not None:
                if given:
                    raise _err(f"give either ees or a crush profile (A, B, width, profile), not both (ees with "
                               f"{', '.join(given)})", f"{key}.ees", file)
            else:
                if A is None and B is None and c["profile"] is not None:
                    preset = preset_of.get(name)
                    stiff = (presets().get(preset, {}).get("crush", {}).get(c["face"]) if preset else None)
                    if stiff is None:
                        raise _err(f"needs A and B (CRASH3 stiffness of the {c['face']} face of {name!r}, e.g. "
                                   "A = \"50000 N/m\", B = \"600000 N/m^2\"); "
                                   + (f"preset {preset!r} has no crush stiffness for this face" if preset
                                      else "the body has no preset with crush stiffness"), f"{key}.A", file)
                    where = f"vehicles library preset {preset!r} crush.{c['face']}"
                    A = parse(stiff["A"], Kind.FORCE_PER_LENGTH, field=f"{where}.A")
                    B = parse(stiff["B"], Kind.FORCE_PER_AREA, field=f"{where}.B")
                    source = f"preset {preset!r}: {stiff['source']}"
                for k, v in (("A", A), ("B", B), ("width", c["width"]), ("profile", c["profile"])):
                    if v is None:
                        raise _err(f"missing {k}: a crush item needs A, B, width and profile (CRASH3), or ees; "
                                   f"given: {', '.join(given) or 'none of them'}", f"{key}.{k}", file)
            if (c["tolerance"] is None) == (c["relative_tolerance"] is None):
                raise _err("give tolerance (an energy, e.g. \"10 kJ\") or relative_tolerance (e.g. \"25 %\"), "
                           f"{'not both' if c['tolerance'] is not None else 'one of them'}", f"{key}.tolerance", file)
            out.append(CrushEvidence(name, c["face"], by_name[name].mass, A, B, c["width"],
                                     None if c["profile"] is None else tuple(c["profile"]), c["offset"], c["ees"],
                                     c["tolerance"], c["relative_tolerance"], c["impacts"], c["compare"],
                                     c["correction"] == "pdof", source, c["name"], sigma=c.get("sigma")))
    problems.raise_any()
    for which, idx in crush_groups(out):
        modes = {out[i].compare for i in idx}
        if len(modes) > 1:
            j = next(i for i in idx if out[i].compare != out[idx[0]].compare)
            raise _err(f"compare = {out[j].compare!r}, but evidence.crush[{idx[0]}] (same impacts = {which!r}) has "
                       f"{out[idx[0]].compare!r}: the items of a group are compared together",
                       f"evidence.crush[{j}].compare", file)
    bodies_seen: dict[str, str] = {}
    for i, it in enumerate(out):
        if bodies_seen.setdefault(it.body, it.impacts) != it.impacts:
            raise _err(f"impacts = {it.impacts!r}, but another crush item of {it.body!r} has "
                       f"{bodies_seen[it.body]!r}: a body's damage belongs to one group", f"evidence.crush[{i}].impacts",
                       file)
    return tuple(out)


def load_scenario(path: str | Path) -> Scenario:
    """Load and validate a scenario file (TOML); all values converted to SI.

    Raises
    ------
    ScenarioError
        Naming the file, the key, the value and what is allowed.
    """
    path = str(path)
    return scenario_from_dict(load_toml(path), file=path)

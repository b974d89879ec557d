"""The scenario file format: its plausibility bounds and defaults, the :class:`~crashsim.schema.Section` of every table
(vehicles, approach, impact, run-out, contacts, map, evidence), the root :data:`SCHEMA` (with the inverse sections of
:mod:`crashsim.inverse_schema`) and :func:`schema_document`, the reference ``crashsim schema`` prints.
"""

from __future__ import annotations

import math

from ..inverse_schema import with_inverse_sections
from ..motion import ContactModel, LATERAL_MODELS, METHODS, RunoutOptions, WHEEL_STATES
from ..motion.brakes import MAX_BRAKE_TIME, MAX_CAPACITY, UNIT_TYPES
from ..motion.runners import LEVELS
from ..motion.road import MAX_SLOPE
from ..schema import ArrayOf, Field, Section, Table, document
from ..survey.schema import MAP_LINE_STYLES, SURVEY
from ..units import Kind, SPEED_UNITS
from ..vehicles import MAX_ROLLOVER_THRESHOLD


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
          description="What was recorded: the magnitude, or the component along the body's x axis (longitudinal, "
                      "positive forward) or across it (lateral: its sign convention is lateral_positive)"),
    Field("lateral_positive", choices=("left", "right"), required=False, example="right",
          description="For component = \"lateral\" (required there, refused elsewhere): the side toward which the "
                      "recorded lateral delta-v is positive. \"left\": crashsim's body y axis (x forward, y left, "
                      "z up: ISO 8855); \"right\": SAE J670 vehicle axes (x forward, y right, z down), the axes of "
                      "many recorder reports (check the report's own sign statement). The check compares, and "
                      "reports, the computed component in the convention given"),
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
SCHEMA = with_inverse_sections(SCHEMA)


def schema_document(fmt: str = "text") -> str:
    """The scenario-file reference, generated from the validating schema."""
    return document(SCHEMA, fmt)

"""Scenario files: one TOML file per scene, strictly validated, units written with each value.

The schema (:mod:`crashsim.scenario.schema`) is the single definition of the file format: :func:`load_scenario`
validates against it and ``crashsim schema`` prints it (:func:`schema_document`). Values
are converted to SI once, here; everything downstream is SI.

Frames: the world frame of the scene (X, Y, angles counter-clockwise from +X). A point or
direction may instead be given in a body's axes (origin at its CG, x forward, y left) by
naming the body in the matching ``*_frame`` / ``frame`` key.

The package, by subject, from the bottom up (a module imports only from those before it; pyproject's
import-linter contract "The scenario package imports one way"): :mod:`~crashsim.scenario.schema` (the file
format: its sections, :data:`SCHEMA`, :func:`schema_document`); :mod:`~crashsim.scenario.types`
(:class:`Scenario`, :class:`RunoutSpec`, :class:`ApproachInput`, :class:`MapLine`) and
:mod:`~crashsim.scenario.problems` (an input error at a key; every error of a file at once);
:mod:`~crashsim.scenario.presets` (the vehicle library), :mod:`~crashsim.scenario.vehicles` (bodies, wheels,
brakes), :mod:`~crashsim.scenario.impact` (the impact problem, frames) and :mod:`~crashsim.scenario.checks`
(geometry, overlap, contact point, impact law); :mod:`~crashsim.scenario.runout`,
:mod:`~crashsim.scenario.approach`, :mod:`~crashsim.scenario.evidence` (with crush) and
:mod:`~crashsim.scenario.layout` (map lines, north); :mod:`~crashsim.scenario.load`
(:func:`scenario_from_dict`, :func:`load_scenario`).
"""

from ..survey.schema import MAP_LINE_STYLES
from .schema import (APPROACH, APPROACH_PATH, APPROACH_RECORDED, APPROACH_RECORDED_SAMPLE, APPROACH_WHEEL_CHANGE, AXLE,
                     BARRIER, BODY, BRAKE_UNIT, CONSTRAINT, CONTACTS, CONTACT_PAIR, DEFAULT_DRAWBAR, DEFAULT_OVERHANG,
                     DEFAULT_OVERLAP, EVIDENCE, EV_CRUSH, EV_DV, EV_MARK, EV_POI, EV_RECORDER, EV_RECORDER_SAMPLE,
                     EV_REST, EV_REST_POINT, EV_ROLLOVER, EXTERNAL, IMPACT, MAP, MAP_LINE, MAX_APPROACH_DISTANCE,
                     MAX_APPROACH_TIME, MAX_CONTACT_HEIGHT, MAX_LENGTH, MAX_MASS, MAX_SPEED, MAX_STEERING_WHEEL_ANGLE,
                     MAX_TRACK, MAX_WIDTH, MAX_YAW_INERTIA, MAX_YAW_RATE, META, OBSTACLE, RUNOUT, SCHEMA, TYRES,
                     VEHICLE, WHEEL, WHEEL_CHANGE, ZONE, schema_document)
from .types import ApproachInput, MapLine, RunoutSpec, Scenario
from .checks import check_contact_point, contact_outlines, outline_problem
from .presets import apply_presets, preset_geometry, presets
from .vehicles import vehicle_states
from .impact import frame_point, frame_xform
from .load import load_scenario, scenario_from_dict

__all__ = [
    "APPROACH", "APPROACH_PATH", "APPROACH_RECORDED", "APPROACH_RECORDED_SAMPLE", "APPROACH_WHEEL_CHANGE", "AXLE",
    "BARRIER", "BODY", "BRAKE_UNIT", "CONSTRAINT", "CONTACTS", "CONTACT_PAIR", "DEFAULT_DRAWBAR", "DEFAULT_OVERHANG",
    "DEFAULT_OVERLAP", "EVIDENCE", "EV_CRUSH", "EV_DV", "EV_MARK", "EV_POI", "EV_RECORDER", "EV_RECORDER_SAMPLE",
    "EV_REST", "EV_REST_POINT", "EV_ROLLOVER", "EXTERNAL", "IMPACT", "MAP", "MAP_LINE", "MAX_APPROACH_DISTANCE",
    "MAX_APPROACH_TIME", "MAX_CONTACT_HEIGHT", "MAX_LENGTH", "MAX_MASS", "MAX_SPEED", "MAX_STEERING_WHEEL_ANGLE",
    "MAX_TRACK", "MAX_WIDTH", "MAX_YAW_INERTIA", "MAX_YAW_RATE", "META", "OBSTACLE", "RUNOUT", "SCHEMA", "TYRES",
    "VEHICLE", "WHEEL", "WHEEL_CHANGE", "ZONE", "schema_document", "ApproachInput", "MapLine", "RunoutSpec",
    "Scenario", "check_contact_point", "contact_outlines", "outline_problem", "apply_presets", "preset_geometry",
    "presets", "vehicle_states", "frame_point", "frame_xform", "load_scenario", "scenario_from_dict",
    "MAP_LINE_STYLES",
]

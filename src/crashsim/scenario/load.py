"""The loader: :func:`scenario_from_dict` (presets, survey, validation, then every builder, each error of the file
at once) and :func:`load_scenario`.
"""

from __future__ import annotations

import dataclasses
import math
import re
from pathlib import Path
from typing import Any

from ..errors import ScenarioError
from ..schema import ScenarioValidationError, load_toml, validate_collect
from ..survey.mapping import as_written, expand_survey, is_placed, survey_frame
from ..units import DisplaySystem
from .approach import approach_input, recorded_speeds
from .checks import check_contact_point, check_impact_law, check_overlap, check_vehicle_geometry, inertia_warnings
from .evidence import build_crush, build_evidence
from .impact import barrier_extent, impact_problem
from .layout import build_map_lines, check_north
from .presets import apply_presets
from .problems import Problems, Skip, error_at
from .runout import build_runout, with_contact
from .schema import SCHEMA
from .types import Scenario
from .vehicles import build_vehicle


def _units_any_case(data: dict) -> dict:
    """``scenario.units`` written in any case ("us", "Si") read as "US"/"SI"."""
    meta = data.get("scenario") if isinstance(data, dict) else None
    if isinstance(meta, dict) and isinstance(meta.get("units"), str) and meta["units"].strip().upper() in ("SI", "US"):
        data = {**data, "scenario": {**meta, "units": meta["units"].strip().upper()}}
    return data


def scenario_from_dict(data: dict[str, Any], *, file: str | None = None) -> Scenario:
    """Validate a parsed scenario (as from TOML) and build the typed SI objects.

    A ``[survey]`` section not yet read is read here (:func:`crashsim.survey.expand_survey`): its
    items join the file's own tables before validation.

    The loader simulates nothing: a vehicle's approach (``[vehicles.<name>.approach]``) is built and
    checked here (``approach_inputs``), and run by the scene run (:func:`crashsim.scene.run_scene`,
    before the impact; :func:`crashsim.scene.simulate_approaches` for the scenario alone). Until
    then the states at impact of a vehicle with an approach are those of its file speed (0 if none)
    and ``approaches`` is empty. So reading a file costs no run-out (a refused file is refused
    before anything is computed), and a fit, Monte Carlo or posterior sample that changes an
    approach re-runs only that approach."""
    if isinstance(data, dict) and "survey" in data:
        data = expand_survey(data, file)
    source = data  # the file's contents with its survey read: Scenario.file_data, what samples vary
    data = _units_any_case(data)
    try:
        merged = apply_presets(data, file)
        d, schema_problems = validate_collect(merged, SCHEMA)
        if schema_problems:  # the checks after the schema too, on the parts it found valid: every error in one run
            raise ScenarioValidationError(schema_problems + _later_problems(d, data, merged, source, file,
                                                                            schema_problems), file=file)
        return _from_validated(d, data, merged, source, file)
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
        _from_validated(d, data, merged, source, file, lenient=True)
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


def _from_validated(d: dict, data: dict, merged: dict, source, file: str | None,
                    lenient: bool = False) -> Scenario:
    """The typed scenario of a validated document ``d`` (see :func:`scenario_from_dict`); ``lenient``:
    ``d`` has values the schema refused (None), and a part that fails on one is skipped."""
    vehicles, states, notes = [], {}, []
    problems = Problems(file, lenient)  # the independent parts of the file first: every error of them at once
    for name, v in d["vehicles"].items():
        with problems.each():
            if v["speed"] is None and v["approach"] is None:
                raise error_at("the speed at impact is missing: give speed (CG speed of the first body at impact), or "
                               "an [vehicles.<name>.approach] with the speed at the start of braking",
                               f"vehicles.{name}.speed", file)
        with problems.each():
            if (v["approach"] is not None and v["approach"]["speed"] is None and v["speed"] is None
                    and not recorded_speeds(v["approach"])):
                raise error_at("the approach needs the speed at the start of braking (approach.speed) or the speed at "
                               "impact (speed)", f"vehicles.{name}.approach.speed", file)
        with problems.each():
            veh, st = build_vehicle(name, v, file)
            check_vehicle_geometry(veh, v, merged["vehicles"][name], d["scenario"]["units"], file)
            notes += inertia_warnings(veh, (data.get("vehicles") or {}).get(name) or {})
            for bn in st:
                if bn in states:
                    raise error_at(f"body name {bn!r} is used twice; body names must be unique in the scene",
                                   f"vehicles.{name}.bodies", file)
            vehicles.append(veh)
            states.update(st)
    check_impact_law(d["impact"], problems, file)
    runout = None
    if d["runout"] is not None:
        raw_runout = data.get("runout") if isinstance(data.get("runout"), dict) else {}
        with problems.each():
            runout = build_runout(d["runout"], vehicles, d["vehicles"], file, raw_runout)
    problems.raise_any()
    # lenient: a [runout] refused by the schema is no run-out; what needs it (the approaches) is not checked
    runout_lost = lenient and d["runout"] is not None and runout is None
    approach_inputs = {}
    for veh in vehicles:
        v = d["vehicles"][veh.name]
        if v["approach"] is not None and not runout_lost:
            raw = ((merged.get("vehicles") or {}).get(veh.name) or {}).get("approach") or {}
            approach_inputs[veh.name] = approach_input(veh, v, runout, file,
                                                       (d.get("map") or {}).get("lines") or (),
                                                       path_given="path" in raw,
                                                       raw_recorded=raw.get("recorded") if isinstance(
                                                            raw.get("recorded"), dict) else None)
    later = Problems(file, lenient)
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
            problem = impact_problem(d, vehicles, states, file)
    else:
        problem = impact_problem(d, vehicles, states, file)
    # the geometry at impact, the contact model, the evidence and the map: independent, every error at once
    if problem is not None:
        with later.each():
            check_overlap(problem, vehicles, states, imp["overlap_tolerance"], d["scenario"]["units"], file)  # cause
            check_contact_point(problem, imp["contact_tolerance"], d["scenario"]["units"], file)  # first
    if runout is not None and problem is not None:
        with later.each():
            runout = with_contact(runout, d, vehicles, problem, file)
    evidence = map_lines = crush = None
    with later.each():
        if vehicle_lost:
            raise Skip
        evidence = build_evidence(d["evidence"], states, file, vehicles,
                                  {n: v["approach"] for n, v in d["vehicles"].items()})
        if evidence.rollover and not runout_failed and (runout is None or not runout.options.rollover):
            raise error_at("a rollover statement is checked against the wheel-lift and rollover check, which is off: add "
                           "runout.rollover = true (level \"load_transfer\")", "evidence.rollover[0].unit", file)
    with later.each():
        if d["evidence"] is not None and d["evidence"]["crush"] and not vehicle_lost:
            crush = build_crush(d["evidence"]["crush"], d, vehicles, file)
    if evidence is not None and crush is not None:
        evidence = dataclasses.replace(evidence, crush=crush)
    with later.each():
        map_lines = build_map_lines(d["map"], file, d.get("survey"))
    with later.each():
        check_north(d, file)
    later.raise_any()
    meta = d["scenario"]
    survey = d.get("survey")
    placed = is_placed(survey)
    units = DisplaySystem(meta["units"], meta["speed_unit"]) if meta.get("speed_unit") else meta["units"]
    out = Scenario(file, meta["title"], meta["source"], units, tuple(vehicles), states, problem, runout,
                   evidence, d, map_lines, {}, approach_inputs,
                   descriptions={n: v.get("description") or "" for n, v in d["vehicles"].items()},
                   survey_frame=survey_frame(survey) if placed else None,
                   north=(d.get("map") or {}).get("north"), barrier_extent=barrier_extent(d.get("barrier")),
                   load_warnings=tuple(_angle_warnings(data) + notes), file_data=source)
    return out


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


def load_scenario(path: str | Path) -> Scenario:
    """Load and validate a scenario file (TOML); all values converted to SI.

    Raises
    ------
    ScenarioError
        Naming the file, the key, the value and what is allowed.
    """
    path = str(path)
    return scenario_from_dict(load_toml(path), file=path)

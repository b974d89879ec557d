"""The vehicle library (``data/vehicles.toml``): :func:`presets`, :func:`preset_geometry`, and :func:`apply_presets`,
which merges each body's preset under its own keys before validation.
"""

from __future__ import annotations

import copy
import difflib
import tomllib
from importlib.resources import files

from ..errors import ScenarioError
from ..schema import validate
from .problems import error_at
from .schema import BODY


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
                raise error_at(f"unknown preset {name!r}{hint} Presets: {', '.join(library)}",
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

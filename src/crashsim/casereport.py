"""One self-contained HTML case report of a scene: inputs, impacts, run-out, evidence, fit / Monte Carlo /
posterior results, assumptions, and what it takes to re-run it (program version, date, SHA-256 of every
input file) -- ``crashsim report FILE -o case.html``.

The page is rendered from the Jinja2 template ``templates/case_report.html.j2``; figures are embedded as
SVG data URIs (no file beside it, no request to anything outside the page); a print stylesheet lays it
out for A4 and US letter (the content width fits the narrower of the two).
"""

from __future__ import annotations

import base64
import datetime as _dt
import hashlib
import io
import json
import math
import re
import tomllib
from importlib.resources import files
from pathlib import Path

import jinja2
import markupsafe

from ._version import __version__
from .errors import ScenarioError
from .plotting import figure_system, history_panels, plot_histories, plot_scene, plot_time_distance
from .plotting.timeline import plot_wheel_timeline
from .motion.wheels import wheel_labels
from .report import closing_error_text, describe_event, format_approach, rollover_cells, validity_text
from .survey.report import survey_records
from .units import DISPLAY_UNITS, format_value, system_label, to_unit, toml_repr

__all__ = ["toml_comments", "input_rows", "sha256_file", "survey_files", "load_json", "inputs_sha256", "made_from",
           "check_result_json", "MADE_FROM", "render_case_report", "write_case_report",
           "VALIDITY_NOTES", "FILE_COMMENT", "breakable_key", "percent", "report_figures", "figure_scale",
           "survey_provenance", "FIGURE_DISPLAY_MM", "FIGURE_WIDTH_IN", "MIN_TEXT_PT"]

#: Width at which the report shows every figure [mm] (its CSS width): within the content width of
#: A4 and US letter (182 mm between the print margins) and of the screen layout (180 mm).
FIGURE_DISPLAY_MM = 170.0
#: Width of the report's figures [in]: shown at FIGURE_DISPLAY_MM they are enlarged by 1.08, so that
#: the smallest type of the figures (6.5 pt labels of the scene diagram) reads at 7 pt or more.
FIGURE_WIDTH_IN = 6.2
#: Smallest type of a figure as the report shows it [pt] (tests/report/test_case_report.py measures it).
MIN_TEXT_PT = 7.0

#: The model's assumptions and limits that every case report carries: the short form of the user guide's
#: "Limits you should know" (docs/guide.md).
VALIDITY_NOTES = (
    "Every impact, first or later, is instantaneous and planar (impulse-momentum, Brach's assumptions); "
    "external impulses during the first impact are inputs.",
    "The coefficients of the impact (restitution e, moment restitution e', the impulse ratio mu or friction f) "
    "are inputs, to be estimated or bracketed for the case (fit, Monte Carlo and posterior take them as "
    "unknowns or uncertain inputs).",
    "Outlines are rectangles; a body's crush does not change its outline. Sustained contact is a penalty "
    "force whose stiffness is numerical, not a crush stiffness.",
    "Bodies touching at one instant are one impact event: every touching point solved together (Newton's "
    "restitution, Coulomb friction, the hitches), in at most 8 rounds; where points jam, the velocities after "
    "it are unique but the impulses reported are one solution of several.",
    "The reaction time before the approach is at constant speed along a straight line. Steering in the approach "
    "is a fixed angle per wheel changed at scheduled times, a pure-pursuit driver along a path, or a recorder's "
    "steering table; there is no drive force, so a recorded speed can be held but not gained.",
    "Crush energy is CRASH3's absorbed energy, compared with the energy the impulse model dissipates.",
    "The run-out is planar: roll and pitch are not modelled. At the load_transfer level the wheel-lift and "
    "rollover check (runout.rollover) records when a body's inner wheels lift or it passes its rollover "
    "threshold; from then on its planar result is outside its validity.",
    "Values of the vehicle library marked \"assumption\" in their source are typical engineering values, not "
    "measurements of the case vehicle.",
)

_KEY = re.compile(r'^\s*("[^"]*"|[A-Za-z0-9_\-]+(?:\s*\.\s*(?:"[^"]*"|[A-Za-z0-9_\-]+))*)\s*=')
_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(?:#(.*))?$")


def _parts(dotted: str) -> list[str]:
    return [p.strip().strip('"') for p in re.findall(r'"[^"]*"|[^.]+', dotted)]


def _unquoted(text: str):
    """``(index, character)`` of the characters of a TOML line outside its strings (quotes left out)."""
    quote = None
    for i, ch in enumerate(text):
        if quote:
            if ch == quote:
                quote = None
        elif ch in "\"'":
            quote = ch
        else:
            yield i, ch


def _comment_of(line: str) -> str | None:
    """The comment at the end of a TOML line (a ``#`` outside any string), or None."""
    for i, ch in _unquoted(line):
        if ch == "#":
            return line[i + 1:].strip() or None
    return None


def toml_comments(text: str) -> dict[str, str]:
    """The comments of a TOML file by dotted key path (``vehicles.A.bodies[0].mass``): a comment at the
    end of a key's line, or the comment lines right above the key or table header; a table's own
    comments under its path. Arrays of tables are indexed as they come (``[[impact.constraints]]``
    -> ``impact.constraints[0]``, ``[1]``, ...)."""
    out: dict[str, str] = {}
    table: list[str] = []
    counts: dict[str, int] = {}
    above: list[str] = []
    depth = 0  # open brackets of a multi-line value: its lines are not keys
    opening: list[str] = []  # the comment lines before the first table or key: the file's own
    started = False
    for line in text.splitlines():
        stripped = line.strip()
        if not started and stripped.startswith("#"):
            opening.append(stripped[1:].strip())
            continue  # the file's own comment, not the first table's
        elif stripped:
            started = True
        if depth > 0:
            depth += line.count("[") - line.count("]")
            continue
        if not stripped:
            above = []
            continue
        if stripped.startswith("#"):
            above.append(stripped[1:].strip())
            continue
        head = _HEADER.match(line) if stripped.startswith("[") else None
        if head:
            name = ".".join(_parts(head[2]))
            if head[1] == "[[":
                i = counts.get(name, 0)
                counts[name] = i + 1
                # nested arrays: the index belongs to the deepest array of tables named so far
                path = f"{_indexed(name, counts)}[{i}]"
            else:
                path = _indexed(name, counts)
            table = [path]
            note = " ".join(above + ([head[3].strip()] if head[3] and head[3].strip() else []))
            if note:
                out[path] = note
            above = []
            continue
        key = _KEY.match(line)
        if key:
            path = ".".join(table + _parts(key[1].replace(" ", "")))
            comment = _comment_of(line[key.end():])
            note = " ".join(above + ([comment] if comment else []))
            if note:
                out[path] = note
            rest = line[key.end():]
            depth = _open_brackets(rest)
        above = []
    if any(opening):
        out[FILE_COMMENT] = " ".join(line for line in opening if line)
    return out


#: Key of :func:`toml_comments` for the comment lines that open the file (before any table or key).
FILE_COMMENT = "(file)"


def _indexed(name: str, counts: dict[str, int]) -> str:
    """``a.b.c`` with the current index of every array of tables among its prefixes (``a.b[1].c``)."""
    parts = name.split(".")
    out = []
    for k in range(1, len(parts) + 1):
        prefix = ".".join(parts[:k])
        out.append(parts[k - 1] + (f"[{counts[prefix] - 1}]" if prefix in counts and k < len(parts) else ""))
    return ".".join(out)


def _open_brackets(text: str) -> int:
    """Brackets a value leaves open at the end of its first line (outside strings and comments)."""
    depth = 0
    for _, ch in _unquoted(text):
        if ch == "#":
            break
        if ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
    return max(depth, 0)


def _flatten(value, path: str):
    """(dotted path, leaf value) of a TOML document; lists of tables indexed, lists of values kept whole."""
    if isinstance(value, dict):
        for k, v in value.items():
            yield from _flatten(v, f"{path}.{k}" if path else str(k))
    elif isinstance(value, list) and value and all(isinstance(v, dict) for v in value):
        for i, v in enumerate(value):
            yield from _flatten(v, f"{path}[{i}]")
    else:
        yield path, value


def _lookup(data, path: str):
    """The value at a dotted, indexed path of nested dicts and lists (None where there is none)."""
    node = data
    for part in path.split("."):
        m = re.fullmatch(r"(.+?)((?:\[\d+\])*)", part)
        name, idx = m[1], [int(i) for i in re.findall(r"\[(\d+)\]", m[2])]
        if not isinstance(node, dict) or name not in node:
            return None
        node = node[name]
        for i in idx:
            if not isinstance(node, (list, tuple)) or i >= len(node):
                return None
            node = node[i]
    return node


def _unit_of(written) -> str:
    """The unit of a value as written in the file (``"30 mph"`` -> ``mph``; a plain number: ``-``)."""
    if isinstance(written, str):
        m = re.fullmatch(r"\s*[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?\s*(.+?)\s*", written)
        return m[1] if m else ""
    if isinstance(written, list) and written and all(isinstance(w, str) for w in written):
        units = {_unit_of(w) for w in written}
        return units.pop() if len(units) == 1 else ", ".join(sorted(units))
    if isinstance(written, bool):
        return ""
    return "-" if isinstance(written, (int, float)) or (isinstance(written, list) and written) else ""


def _si_text(value) -> str:
    if isinstance(value, bool) or value is None or isinstance(value, str):
        return ""
    if isinstance(value, (int, float)):
        return format(float(value), ".6g")
    if isinstance(value, (list, tuple)) and value and all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                         for v in value):
        return "(" + ", ".join(format(float(v), ".6g") for v in value) + ")"
    return ""


def _kind_of_unit(unit: str):
    """The kind whose display unit (SI or US, :data:`~crashsim.units.DISPLAY_UNITS`) is ``unit``, or None."""
    return next((k for k, labels in DISPLAY_UNITS.items() if unit and unit in labels.values()), None)


def _in_system(leaf, si, system) -> tuple[str, str] | None:
    """A preset's value (``leaf`` as the library writes it, ``si`` validated) as ``(value, unit)`` in the
    report's ``system`` where its unit differs from the library's (``"8.30 m"`` in a US report:
    ``("27.23 ft", "ft")``); None to keep it as written."""
    written = _unit_of(leaf)
    kind = _kind_of_unit(written)
    if system is None or kind is None or si is None:
        return None
    values = si if isinstance(si, (list, tuple)) else [si]
    if not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in values):
        return None
    # 4 significant digits, more for a number of 5 or more digits (20944 lb, not 2.094e+04 lb)
    texts = [format_value(float(v), kind, system, max(4, len(f"{abs(to_unit(float(v), kind, system)[0]):.0f}")))
             for v in values]
    unit = texts[0].split(" ", 1)[1] if " " in texts[0] else ""
    if unit == written:
        return None
    value = texts[0] if not isinstance(si, (list, tuple)) else "[" + ", ".join(texts) + "]"
    return value, unit


def input_rows(raw: dict, comments: dict[str, str], validated: dict | None = None,
               presets: dict | None = None, system: str | None = None) -> list[dict]:
    """Every value of a scenario file as a row: ``key`` (dotted path), ``value`` as written, ``unit`` as
    written (``-`` for a plain number), ``si`` (the validated value in SI, where it is a number),
    ``comment`` (from the file) and ``origin`` (``file``, or ``preset NAME`` for a value a body takes from
    the vehicle library, whose source is then its comment). Given a ``system`` ("SI", "US"), a preset's
    value and unit are in its units (the library writes SI; the file's own values stay as written)."""
    rows = []
    if comments.get(FILE_COMMENT):
        rows.append({"key": "(the file)", "value": "", "unit": "", "si": "", "comment": comments[FILE_COMMENT],
                     "origin": "table"})
    shown: set[str] = set()
    for path, value in _flatten(raw, ""):
        for cut in [m.start() for m in re.finditer(r"[.\[]", path)]:  # the comments of the tables above the key
            table = path[:cut]
            if table in comments and table not in shown:
                shown.add(table)
                rows.append({"key": f"[{table}]", "value": "", "unit": "", "si": "", "comment": comments[table],
                             "origin": "table"})
        comment = comments.get(path, "")
        is_preset = bool(presets) and path.endswith(".preset") and isinstance(value, str) and value in presets
        if is_preset:
            comment = "; ".join(c for c in (comment, f"source of the preset: {presets[value]['source']}") if c)
        si = _si_text(_lookup(validated, path)) if validated is not None else ""
        rows.append({"key": path, "value": toml_repr(value), "unit": _unit_of(value) if si or validated is None else "",
                     "si": si, "comment": comment, "origin": "file"})
        if is_preset:
            body = path[: -len(".preset")]
            given = _lookup(raw, body) or {}
            for k, v in presets[value].items():
                if k in ("source", "crush") or k in given:
                    continue
                for sub, leaf in _flatten(v, f"{body}.{k}"):
                    si = _si_text(_lookup(validated, sub)) if validated is not None else ""
                    conv = _in_system(leaf, _lookup(validated, sub), system) if si else None
                    rows.append({"key": sub, "value": conv[0] if conv else toml_repr(leaf),
                                 "unit": conv[1] if conv else _unit_of(leaf) if si or validated is None else "",
                                 "si": si, "comment": f"from preset {value}", "origin": f"preset {value}"})
    return rows


def survey_files(scenario_path) -> list[str]:
    """The files a scenario's ``[survey]`` section reads (survey drawing, points, breaklines, recorder tables,
    orthophotos and their world files), as paths relative to the working folder, those that exist."""
    path = Path(scenario_path)
    try:
        raw = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return []
    out: list[str] = []

    def walk(node):
        if isinstance(node, dict):
            for k, v in node.items():
                if isinstance(v, str) and k in ("file", "breaklines", "image", "world_file", "world"):
                    p = path.parent / v
                    if p.is_file() and str(p) not in out:
                        out.append(str(p))
                else:
                    walk(v)
        elif isinstance(node, list):
            for v in node:
                walk(v)

    walk(raw.get("survey"))
    return out


#: The JSON key under which ``crashsim fit/mc/posterior --json`` name what a result was made from.
MADE_FROM = "made_from"


def inputs_sha256(scenario_path) -> str:
    """SHA-256 of a scene's inputs: the scenario file and every file its ``[survey]`` reads, in
    order (each file's own SHA-256, hexadecimal, one a line): the same wherever the files lie."""
    h = hashlib.sha256()
    for p in [str(scenario_path)] + survey_files(scenario_path):
        h.update((sha256_file(p) + "\n").encode())
    return h.hexdigest()


def made_from(command: str, scenario_path) -> dict:
    """What a ``--json`` result of ``command`` (fit, mc, posterior) carries to say which inputs made it."""
    return {"command": command, "scenario": Path(scenario_path).name, "inputs_sha256": inputs_sha256(scenario_path),
            "crashsim": __version__}


def check_result_json(path, command: str, scenario_path, *, field: str) -> dict:
    """The ``--json`` result of ``crashsim <command>`` in ``path``, if it was made from the inputs of
    ``scenario_path`` (:func:`inputs_sha256`); else a ScenarioError naming what it is."""
    try:
        obj = load_json(path)
    except (OSError, ValueError) as exc:
        raise ScenarioError(f"{str(path)!r} is not readable JSON of crashsim {command} --json: {exc}",
                            field=field) from None
    if not isinstance(obj, dict):
        raise ScenarioError(f"{str(path)!r} is not a JSON object (crashsim {command} --json writes one)", field=field)
    stamp = obj.get(MADE_FROM)
    if not isinstance(stamp, dict) or "inputs_sha256" not in stamp:
        raise ScenarioError(f"{str(path)!r} is not the JSON that crashsim {command} FILE --json writes (it has no "
                            f"{MADE_FROM!r} naming its inputs); run crashsim {command} {Path(scenario_path).name} "
                            "--json again", field=field)
    if stamp.get("command") != command:
        raise ScenarioError(f"{str(path)!r} is the result of crashsim {stamp.get('command')}, not of crashsim "
                            f"{command}", field=field)
    want = inputs_sha256(scenario_path)
    if stamp["inputs_sha256"] != want:
        raise ScenarioError(f"{str(path)!r} was made from other inputs ({stamp.get('scenario')!r}, SHA-256 "
                            f"{str(stamp['inputs_sha256'])[:12]}...) than {Path(scenario_path).name!r} and its "
                            f"survey files now ({want[:12]}...); run crashsim {command} again on this file",
                            field=field)
    return obj


def sha256_file(path) -> str:
    """SHA-256 of a file's bytes, hexadecimal."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def _svg(fig) -> str:
    """A matplotlib figure as an SVG data URI (the figure is closed)."""
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="svg", metadata={"Date": None})
    plt.close(fig)
    return "data:image/svg+xml;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def report_figures(scene, system: str | None = None) -> list[dict]:
    """The figures of the case report of ``scene``: ``id``, ``title`` and ``figure`` (an open matplotlib
    figure, :data:`FIGURE_WIDTH_IN` wide: shown :data:`FIGURE_DISPLAY_MM` wide, :func:`figure_scale`);
    the caller closes them."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    system = figure_system(scene, system)
    w = FIGURE_WIDTH_IN
    figs = []
    ax = plot_scene(scene, system=system, approach=False, width=w)
    figs.append({"id": "scene", "title": "Scene diagram: positions at impact, run-out to rest, evidence",
                 "figure": ax.figure})
    if scene.scenario.approaches:
        # no inset of the impact: the figure before is the close view of it
        ax = plot_scene(scene, system=system, width=w, inset=False)
        figs.append({"id": "scene-approach", "title": "Scene diagram with the approaches from the start of braking",
                     "figure": ax.figure})
    if scene.runout is not None:
        n = history_panels(scene)
        fig, axes = plt.subplots(n, 1, figsize=(w, 2.3 * n), sharex=True, layout="constrained")
        plot_histories(scene, axes, system=system)
        figs.append({"id": "histories", "title": "Run-out histories: CG speed, yaw rate, articulation",
                     "figure": fig})
    if scene.runout is not None or scene.scenario.approaches:
        fig, axes = plt.subplots(2, 1, figsize=(w, 4.8), sharex=True, layout="constrained")
        plot_time_distance(scene, axes, system=system)
        figs.append({"id": "time-distance", "title": "Time-distance and speed-time, from the approach to rest",
                     "figure": fig})
        figs.append({"id": "wheels", "title": "Wheel states, air brakes, sliding and steering on one time line",
                     "figure": plot_wheel_timeline(scene, width=w)})
    return figs


def figure_scale(fig) -> float:
    """How much the report enlarges ``fig`` (a figure of :func:`report_figures`): its display width
    (:data:`FIGURE_DISPLAY_MM`) over its own; a text of ``s`` pt in it reads at ``s * figure_scale(fig)`` pt."""
    return FIGURE_DISPLAY_MM / (float(fig.get_size_inches()[0]) * 25.4)


def _figures(scene, system: str) -> list[dict]:
    return [{"id": f["id"], "title": f["title"], "uri": _svg(f["figure"])} for f in report_figures(scene, system)]


def _impacts(scene, system: str) -> list[dict]:
    s = system
    out = []
    for imp in scene.impacts:
        dv = imp.get("delta_v") or {}
        out.append({
            "n": imp["event"], "time": format_value(imp["time"], "time", s), "bodies": f"{imp['body1']} / {imp['body2']}",
            "closing_speed": format_value(imp.get("closing_speed"), "speed", s) if imp.get("closing_speed") is not None
            else "",
            "normal_impulse": format_value(imp["normal_impulse"], "impulse", s),
            "tangential_impulse": format_value(imp["tangential_impulse"], "impulse", s),
            "energy_loss": format_value(imp["energy_loss"], "energy", s),
            "delta_v": ", ".join(f"{n} {format_value(v['magnitude'], 'speed', s)}" for n, v in dv.items()),
        })
    return out


def _first_impact_bodies(scene, system: str) -> list[dict]:
    s = system
    rows = []
    for name, b in scene.impact.bodies.items():
        if b.fixed:
            continue
        rows.append({"body": name, "vehicle": b.vehicle,
                     "speed_before": format_value(math.hypot(*b.velocity_before), "speed", s),
                     "speed_after": format_value(math.hypot(*b.velocity), "speed", s),
                     "yaw_before": format_value(b.yaw_rate_before, "angular_velocity", s),
                     "yaw_after": format_value(b.yaw_rate, "angular_velocity", s),
                     "delta_v": format_value(b.delta_v_magnitude, "speed", s),
                     "pdof": "" if b.pdof is None else format_value(b.pdof, "angle", s)})
    return rows


def _runout(scene, system: str) -> dict | None:
    if scene.runout is None:
        return None
    s = system
    bodies = []
    for vname, r in scene.runout.items():
        for name, b in r.bodies.items():
            bodies.append({"body": name, "vehicle": vname,
                           "rest": f"({format_value(b.rest_position[0], 'length', s)}, "
                                   f"{format_value(b.rest_position[1], 'length', s)})",
                           "heading": format_value(b.rest_heading_wrapped, "angle", s),
                           "time": "not at rest: " + r.status if b.time_to_rest is None
                           else format_value(b.time_to_rest, "time", s),
                           "distance": format_value(b.distance, "length", s)})
    events = []
    source = scene.joint.events if scene.joint is not None else [e for r in scene.runout.values() for e in r.events]
    for e in source:
        place = "" if e.place is None else (f"({format_value(e.place[0], 'length', s)}, "
                                            f"{format_value(e.place[1], 'length', s)})")
        events.append({"time": format_value(e.t, "time", s), "kind": e.kind, "place": place,
                       "what": describe_event(e, s)})
    ledger = scene.energy_ledger()
    rows = []
    if ledger is not None:
        labels = [("before_impact", "kinetic energy before the impact"), ("first_impact", "lost in the first impact"),
                  ("later_impacts", "lost in later impacts"), ("tyres", "work of the tyres"),
                  ("stops", "articulation-stop impacts"), ("contacts", "sustained contact"),
                  ("final", "kinetic energy left")]
        rows = [{"item": label, "value": format_value(ledger[k], "energy", s)} for k, label in labels]
        opts = scene.scenario.runout.options
        rows.append({"item": "closing error", "value": closing_error_text(ledger, opts.rtol)})
    validity = [f"vehicle {vname}: {validity_text(r, s)}" for vname, r in scene.runout.items()
                if r.rollover is not None]
    return {"bodies": bodies, "events": events, "ledger": rows, "level": scene.scenario.runout.level,
            "validity": validity}


def _evidence(scene, system: str) -> dict | None:
    ev = scene.evidence
    if ev is None:
        return None
    labels = wheel_labels(scene.scenario.vehicles)
    s = system
    rows = []
    for c in ev.checks:
        if c.kind == "rollover":
            res, tol = rollover_cells(c)
        elif math.isinf(c.residual):
            res, tol = "none computed", format_value(c.tolerance, c.quantity, s)
        else:
            res, tol = format_value(c.residual, c.quantity, s), format_value(c.tolerance, c.quantity, s)
        wheel = c.details.get("matched_wheel")
        note = labels.get(wheel, wheel) if wheel else (c.details.get("reason") or "")
        rows.append({"verdict": "PASS" if c.passed else "FAIL", "kind": c.kind, "name": c.name, "residual": res,
                     "tolerance": tol, "note": f"closest track: {note}"
                     if "matched_wheel" in c.details else note})
    return {"rows": rows, "n": len(ev.checks), "passed": len(ev.checks) - ev.n_failed}


#: What each kind of ``survey.imported`` record says, in the report's provenance table.
_SURVEY_KINDS = {"label": "label (a text naming the item nearest it)", "ignore": "ignored (map kind = \"ignore\")",
                 "note": "note of the import", "warning": "warning", "underlay": "orthophoto under the figures",
                 "recorder": "recorder table"}


def survey_provenance(scenario) -> dict | None:
    """The survey provenance of a scenario (its ``survey.imported`` records, :func:`crashsim.survey.report.survey_records`),
    None without a survey: ``rows``, one per record in the order of the import -- ``file``, ``layer``,
    ``entity`` (type and handle, point numbers or feature index), ``kind``, ``target`` (the scene item it
    became, ``evidence.marks[0]``; "" for a record that made none), ``name`` (that item's name), ``note``,
    ``key`` (the map entry or recorder table that made it) -- and counts: ``n_items`` (scene items made),
    ``entities`` (survey entities and points that made them), ``left_out`` (records that made no item)."""
    records = survey_records(scenario)
    if not records:
        return None
    rows = []
    for r in records:
        target = r.get("target") or ""
        name = _lookup(scenario.data, f"{target}.name") if target else None
        rows.append({"file": r.get("file") or "", "layer": r.get("layer") or "",
                     "entity": f"{r.get('type') or ''} {r.get('ref') or ''}".strip(),
                     "kind": _SURVEY_KINDS.get(r.get("kind"), r.get("kind") or ""), "target": target,
                     "name": name if isinstance(name, str) else "", "note": r.get("note") or "", "key": r.get("key") or ""})
    made = [r for r in records if r.get("target") and r.get("kind") != "warning"]
    return {"rows": rows, "n_items": len({r["target"] for r in made}), "entities": len(made),
            "left_out": sum(1 for r in records if not r.get("target"))}


def _num(v, kind: str | None, system: str) -> str:
    if v is None:
        return "n/a"
    if kind:
        try:
            return format_value(float(v), kind, system)
        except (ValueError, KeyError, TypeError):
            pass
    return format(float(v), ".4g") if isinstance(v, (int, float)) else str(v)


def _fit(d: dict, system: str) -> dict:
    rows = [{"name": u.get("name") or u["path"], "path": u["path"], "value": _num(u["value"], u.get("kind"), system),
             "stderr": _num(u.get("stderr"), u.get("kind"), system),
             "interval": f"{_num(u['interval'][0], u.get('kind'), system)} to {_num(u['interval'][1], u.get('kind'), system)}"}
            for u in d.get("unknowns", [])]
    summary = [("success", d.get("success")), ("message", d.get("message")), ("chi^2", d.get("chi2")),
               ("degrees of freedom", d.get("dof")), ("p-value", d.get("p_value")),
               ("confidence", d.get("confidence")), ("starts agreeing", f"{d.get('n_agree')} of {d.get('n_starts')}")]
    probes = d.get("linearity") or []
    if probes:  # the fit's check of its linearised intervals (fit.LinearityProbe; the factor comes with them)
        skipped = d.get("linearity_skipped", 0)
        summary.append(("linearity of the intervals",
                        f"{sum(bool(p['linear']) for p in probes)} of {len(probes)} points one standard error from the "
                        f"best pass (chi^2 within {d['linearity_factor']:g}x of the linearised rise)"
                        + (f"; {skipped} direction{'s' if skipped != 1 else ''} at a bound not probed" if skipped else "")))
    return {"unknowns": rows, "summary": [(k, _num(v, None, system) if isinstance(v, float) else v)
                                          for k, v in summary], "warnings": d.get("warnings", [])}


def percent(v, decimals: int = 1) -> str:
    """A fraction as the text reports print it: ``0.083 -> "8.3 %"``; None or NaN: "n/a"."""
    if v is None or not isinstance(v, (int, float)) or not math.isfinite(v):
        return "n/a"
    return f"{100.0 * float(v):.{decimals}f} %"


def _headline_share(v) -> str:
    """A share as ``MCResult.evidence_headline`` prints it (3 significant digits: "0.59 %")."""
    return "n/a" if v is None or not math.isfinite(float(v)) else f"{100.0 * float(v):.3g} %"


def _mc_value(v, kind: str | None, system: str) -> str:
    """A Monte Carlo output value as ``MCResult.report`` prints it: a fraction (dimensionless) in %, a
    count to 3 digits, a ratio to 4, a physical quantity in the report's units; a kind not known: plain."""
    if kind == "dimensionless":
        return percent(v)
    if kind == "count":
        return "n/a" if v is None else f"{float(v):.3g}"
    if kind == "ratio":
        return "n/a" if v is None else f"{float(v):.4g}"
    return _num(v, kind, system)


def _mc(d: dict, system: str, kinds: dict | None) -> dict:
    pct = d.get("percentiles", {})
    qs = list(dict.fromkeys(q for p in pct.values() for q in p))  # the JSON's order: p5 ... p95, mean, std
    kinds = kinds or {}
    acc = d.get("accepted") if isinstance(d.get("accepted"), dict) else None
    acc_pct = (acc or {}).get("percentiles") or {}

    def kind(key):
        return kinds.get(key.split(".", 1)[0])

    rows = []
    for k, p in pct.items():
        rows.append({"key": k, "group": "all" if acc_pct else "",
                     "values": [_mc_value(p.get(q), kind(k), system) for q in qs]})
        if k in acc_pct:
            rows.append({"key": "", "group": "accepted",
                         "values": [_mc_value(acc_pct[k].get(q), kind(k), system) for q in qs]})
    summary = [("samples", d.get("n")), ("done", d.get("n_done")), ("failed", d.get("n_failed")), ("seed", d.get("seed"))]
    if acc is not None:
        summary.append(("samples meeting all the evidence (accepted)",
                        f"{acc.get('count')} of {acc.get('of')} ({_headline_share(acc.get('share'))})"))
    share = d.get("pass_share")
    evidence = []
    if isinstance(share, dict):  # share of the samples within each evidence item's tolerance
        evidence = [{"key": k, "share": percent(v)} for k, v in share.items()]
    elif isinstance(share, (int, float)):
        summary.append(("share meeting every evidence item", percent(share)))
    return {"quantiles": qs, "rows": rows, "summary": summary, "evidence": evidence, "accepted": bool(acc_pct)}


#: Where a key (``vehicles.car.bodies[0].mass``, ``delta_v.car``) may wrap: after each of its separators.
_KEY_BREAKS = re.compile(r"(?<=[._/-])|(?=\[)")


def breakable_key(key) -> markupsafe.Markup:
    """A key as HTML that wraps only at a separator (after ``.``, ``_``, ``/``, ``-``, before ``[``): the key
    escaped, a ``<wbr>`` at each (the table's CSS keeps the words between them whole)."""
    return markupsafe.Markup("<wbr>").join(markupsafe.escape(part) for part in _KEY_BREAKS.split(str(key)))


def _posterior(d: dict, system: str) -> dict:
    rows = []
    for u in d.get("unknowns", []) + [{"name": x["key"], "path": x["key"], "derived": True, **x}
                                      for x in d.get("derived", [])]:
        p = u.get("percentiles", {})
        # a derived fraction (an energy loss) in percent, as the posterior's text report and the Monte Carlo's
        show = percent if u.get("derived") and u.get("kind") == "dimensionless" else (
            lambda v, kind=u.get("kind"): _num(v, kind, system))
        rows.append({"name": u.get("name") or u["path"], "values": {q: show(v) for q, v in p.items()},
                     "ess": _num(u.get("ess"), None, system) if u.get("ess") is not None else ""})
    qs = list(dict.fromkeys(q for r in rows for q in r["values"]))  # the JSON's order
    diag = d.get("diagnostics", {})
    summary = [("success", d.get("success")), ("message", d.get("message")),
               ("kept samples", diag.get("samples")), ("mean acceptance", _num(diag.get("acceptance_mean"), None, "SI")),
               ("chain long enough", diag.get("chain_long_enough"))]
    return {"quantiles": qs, "rows": [{**r, "values": [r["values"].get(q, "") for q in qs]} for r in rows],
            "summary": summary, "warnings": d.get("warnings", [])}


def render_case_report(scene, *, input_files, system: str | None = None, fit: dict | None = None,
                       mc: dict | None = None, posterior: dict | None = None, presets: dict | None = None,
                       command: str | None = None, now: _dt.datetime | None = None, figures: bool = True,
                       output_kinds: dict | None = None, validation: dict | None = None) -> str:
    """The case report of ``scene`` as one HTML document (text).

    Parameters
    ----------
    scene : SceneResult
        The run of the scenario file (the first of ``input_files``).
    input_files : sequence of path
        Every input file: the scenario first, then any other (survey files, fit / Monte Carlo /
        posterior JSON); each is listed with its SHA-256.
    system : {"SI", "US"}, optional
        Units of the report (default: the scenario's).
    fit, mc, posterior : dict, optional
        The JSON output (``crashsim fit/mc/posterior --json``) of those commands, loaded.
    presets : dict, optional
        The vehicle library (:func:`crashsim.scenario.presets`): values a body takes from a preset are
        listed with the preset's source.
    command : str, optional
        The command that re-runs the scene, shown in the reproduction section.
    now : datetime, optional
        The report's date (default: now, UTC).
    figures : bool
        Embed the figures (SVG).
    output_kinds : dict, optional
        Quantity kind of each Monte Carlo output by its first word (``{"speed": "speed", ...}``,
        :data:`crashsim.reconstruct.montecarlo.OUTPUT_KINDS`): its percentiles then in ``system`` units.
    validation : dict, optional
        The validation suite's errors for the scene's case class (:func:`crashsim.validation.class_errors`),
        quoted in the "Known error of the method" section.
    """
    system = figure_system(scene, system)
    files_ = [Path(p) for p in input_files]
    text = files_[0].read_text(encoding="utf-8")
    raw = tomllib.loads(text)
    sc = scene.scenario
    now = now or _dt.datetime.now(_dt.timezone.utc)
    notes = list(VALIDITY_NOTES)
    approach = format_approach(sc.approaches, system) if sc.approaches else ""
    context = {
        "title": sc.title, "source": sc.source, "file": files_[0].name, "system": system_label(system),
        "version": __version__,
        "date": now.strftime("%Y-%m-%d %H:%M UTC"),
        "files": [{"name": str(p), "sha256": sha256_file(p), "bytes": p.stat().st_size} for p in files_],
        "inputs": input_rows(raw, toml_comments(text), sc.data, presets, system),
        "approach": approach, "impacts": _impacts(scene, system), "first_bodies": _first_impact_bodies(scene, system),
        "law": scene.impact.tangential_law, "runout": _runout(scene, system), "evidence": _evidence(scene, system),
        "fit": _fit(fit, system) if fit else None, "mc": _mc(mc, system, output_kinds) if mc else None,
        "posterior": _posterior(posterior, system) if posterior else None,
        "warnings": list(scene.warnings), "notes": notes, "figures": _figures(scene, system) if figures else [],
        "figure_mm": format(FIGURE_DISPLAY_MM, "g"), "survey": survey_provenance(sc),
        "command": command or f"crashsim report {files_[0].name} -o case.html",
        "validation": validation,
    }
    env = jinja2.Environment(loader=jinja2.FileSystemLoader(str(files("crashsim").joinpath("templates"))),
                             autoescape=jinja2.select_autoescape(["html", "j2"]), undefined=jinja2.StrictUndefined,
                             trim_blocks=True, lstrip_blocks=True)
    env.filters["key"] = breakable_key
    return env.get_template("case_report.html.j2").render(**context)


def write_case_report(scene, path, **kwargs) -> Path:
    """Write :func:`render_case_report` to ``path`` (UTF-8); returns the path."""
    path = Path(path)
    path.write_text(render_case_report(scene, **kwargs), encoding="utf-8")
    return path


def load_json(path) -> dict:
    """A JSON output file of crashsim fit / mc / posterior (``--json``), as a dict."""
    with open(path, encoding="utf-8") as fh:
        return json.load(fh)

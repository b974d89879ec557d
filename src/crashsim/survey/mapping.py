"""From survey files to scene items: the ``[survey]`` section expanded into the file's own tables.

:func:`expand_survey` reads each survey file once, maps its layers or codes to scene items and
appends them to the raw scenario dict as a user would type them (``[[map.lines]]``,
``[[obstacles]]``, ``[[runout.zones]]``, ``[[evidence.marks]]``, ``[[evidence.rest]]``,
``[evidence.impact_point]``, ``[[evidence.recorder]]``), coordinates written in metres of the
scene frame to full precision. The scenario is then validated and built by the one path of
:func:`crashsim.scenario.scenario_from_dict`, so an imported item is the same typed object as
a typed one and every check applies. ``survey.imported`` records the source of each item
(file, layer or code, handle or point numbers, type) and marks the dict as expanded: fit,
Monte Carlo and posterior samples rebuild from the expanded dict and never read the files again.
"""

from __future__ import annotations

import copy
import difflib
import fnmatch
import logging
import math
import os
from pathlib import Path

import numpy as np

from ..errors import ScenarioError
from ..schema import ScenarioValidationError, Section, load_toml, validate
from ..units import Kind, parse
from .dxf import read_dxf
from .frame import SceneFrame, unit_scale
from .geojson import read_geojson
from .points import read_points
from .recorder import read_recorder
from .schema import MAP_LINE_STYLES, SURVEY
from .underlay import georef_from_section

__all__ = ["expand_survey", "load_scene_data", "read_survey_file", "survey_frame", "survey_section",
           "is_expanded", "is_placed", "as_written"]

_log = logging.getLogger("crashsim")
_ROOT = Section("root", subsections=[SURVEY], description="survey only")
SURVEY_FORMATS = {".dxf": "dxf", ".csv": "points", ".txt": "points", ".asc": "points", ".pnezd": "points", ".xyz": "points",
        ".geojson": "geojson", ".json": "geojson"}
_CACHE: dict = {}
_COLORS = {"gouge": "#8c564b", "debris": "#7f7f7f"}


def survey_section(raw: dict, file: str | None) -> dict:
    """The validated ``[survey]`` section (SI values) of a raw scenario dict."""
    return validate({"survey": raw.get("survey")}, _ROOT, file=file)["survey"]


def survey_frame(s: dict) -> SceneFrame:
    """The scene frame of a validated ``[survey]`` section."""
    return SceneFrame(tuple(s["origin"]), s["rotation"])


def is_expanded(raw: dict) -> bool:
    """Whether the survey of a raw scenario dict has been read (``survey.imported`` present)."""
    s = raw.get("survey")
    return not isinstance(s, dict) or "imported" in s


def _resolve(name: str, file: str | None) -> str:
    p = Path(name).expanduser()
    if not p.is_absolute() and file is not None:
        p = Path(file).resolve().parent / p
    return str(p)


def _format(entry: dict, path: str, key: str, file: str | None) -> str:
    if entry["format"] is not None:
        return entry["format"]
    ext = Path(path).suffix.lower()
    if ext not in SURVEY_FORMATS:
        raise ScenarioError(f"{entry['file']!r}: cannot tell the format from the extension {ext!r}; give format = "
                            "\"dxf\", \"points\" or \"geojson\"", field=f"{key}.format", file=file)
    return SURVEY_FORMATS[ext]


def read_survey_file(entry: dict, crs: str | None, *, key: str = "survey.files[0]", file: str | None = None):
    """The :class:`~crashsim.survey.entities.SurveyData` of a validated ``[[survey.files]]`` entry
    (memoised by path, modification time, size and reading options: read once per process)."""
    path = _resolve(entry["file"], file)
    if not os.path.isfile(path):
        raise ScenarioError(f"survey file {entry['file']!r} not found (looked for {os.path.relpath(path)})",
                            field=f"{key}.file", file=file)
    fmt = _format(entry, path, key, file)
    st = os.stat(path)
    brk = _resolve(entry["breaklines"], file) if entry.get("breaklines") else None
    opts = (fmt, entry.get("units"), entry.get("columns"), entry.get("join"), brk, entry.get("crs"),
            entry.get("layer_property"), entry.get("chord_tolerance"), crs)
    ck = (path, st.st_mtime_ns, st.st_size, opts)
    if ck in _CACHE:
        return _CACHE[ck]
    try:
        if fmt == "dxf":
            data = read_dxf(path, entry["units"], chord_tolerance=entry["chord_tolerance"], file=file)
        elif fmt == "points":
            if entry["units"] is None:
                raise ScenarioError(f"{entry['file']!r}: a point file does not state its units; give units = \"m\" "
                                    "(or \"ft\", \"us_ft\", ...)", field=f"{key}.units", file=file)
            data = read_points(path, entry["units"], entry["columns"], join=entry["join"], breaklines=brk, file=file)
        else:
            data = read_geojson(path, crs, crs=entry["crs"], layer_property=entry["layer_property"], file=file)
    except ScenarioError as exc:
        if exc.field is None:  # the reader's own error: the file named as the scene file writes it
            text = str(exc).removeprefix(f"{file}: ") if file else str(exc)
            raise ScenarioError(text.replace(path, entry["file"]), field=f"{key}.file", file=file) from None
        if exc.field.startswith("survey.files."):  # a reader's key: this entry's, with its index
            text = str(exc).removeprefix(f"{file}: " if file else "").removeprefix(f"{exc.field}: ")
            raise ScenarioError(text.replace(path, entry["file"]),
                                field=f"{key}.{exc.field.removeprefix('survey.files.')}", file=file) from None
        raise
    if len(_CACHE) > 32:
        _CACHE.clear()
    _CACHE[ck] = data
    return data


def _m(x: float) -> str:
    return f"{float(x)!r} m"


def _pts(a) -> list:
    return [[f"{x!r} m", f"{y!r} m"] for x, y in np.asarray(a, dtype=float).tolist()]


def _polygon(center, diameter: float, n: int) -> np.ndarray:
    ang = (np.arange(n) + 0.5) * 2 * np.pi / n
    r = diameter / 2 / (math.cos(math.pi / n) if n == 8 else math.sqrt(2))
    return np.asarray(center, dtype=float) + r * np.column_stack([np.cos(ang), np.sin(ang)])


def _label(m: dict, e) -> str:
    return m["name"] or f"{e.layer} {e.ref}".strip()


def _match(pattern: str, layer: str) -> bool:
    return fnmatch.fnmatchcase(layer.upper(), pattern.upper())


class _Out:
    """The raw dict being extended, and the provenance records."""

    def __init__(self, data: dict):
        self.data = data
        self.records: list[dict] = []
        self.faces_taken: set = set()  # (id of the SurveyData, face index) of the TIN faces a surface took

    def append(self, where: tuple, item: dict) -> str:
        node = self.data
        for k in where[:-1]:
            node = node.setdefault(k, {})
        lst = node.setdefault(where[-1], [])
        lst.append(item)
        return f"{'.'.join(where)}[{len(lst) - 1}]"

    def record(self, path: str, e, kind: str, target: str, note: str = "", key: str = "") -> None:
        self.records.append({"file": path, "layer": "" if e is None else e.layer, "ref": "" if e is None else e.ref,
                             "type": "" if e is None else e.dxftype, "kind": kind, "target": target, "note": note,
                             "key": key})


def _need(m: dict, raw: dict, keys, mkey: str, file: str | None) -> None:
    for k in keys:
        if m.get(k) is None:
            raise ScenarioError(f"kind = {m['kind']!r} needs {k}", field=f"{mkey}.{k}", file=file)
    for k in raw:
        if k not in _ALLOWED[m["kind"]]:
            raise ScenarioError(f"{k} does not apply to kind = {m['kind']!r} (keys of this kind: "
                                f"{', '.join(sorted(_ALLOWED[m['kind']]))})", field=f"{mkey}.{k}", file=file)


_COMMON = {"match", "kind", "name"}
_ALLOWED = {
    "line": _COMMON | {"style", "color"},
    "obstacle": _COMMON | {"thickness", "size"},
    "zone": _COMMON | {"friction"},
    "mark": _COMMON | {"wheel", "phase", "sliding_only", "tolerance", "sigma"},
    "rest": _COMMON | {"body", "at", "tolerance", "heading_tolerance", "sigma", "heading_sigma"},
    "impact_point": _COMMON | {"tolerance", "sigma"},
    "gouge": _COMMON | {"color", "size"},
    "debris": _COMMON | {"color", "size"},
    "surface": _COMMON,
    "ignore": _COMMON,
}


def _map_file(out: _Out, sd, entry: dict, raw_entry: dict, frame: SceneFrame, key: str, file: str | None,
              have_runout: bool) -> None:
    taken = _map_entries(out, sd, entry, raw_entry, frame, key, file, have_runout)
    left = {}
    for e, t in zip(sd.entities, taken):
        if not t:
            left[e.layer] = left.get(e.layer, 0) + 1
    faces_taken = out.faces_taken
    for j, (layer, _, _) in enumerate(sd.faces):
        if (id(sd), j) not in faces_taken:
            left[layer] = left.get(layer, 0) + 1
    if left:
        shown = ", ".join(f"{lay or '(empty)'} ({n})" for lay, n in sorted(left.items()))
        out.record(entry["file"], None, "note", "", f"{sum(left.values())} entities on layers or codes no map entry "
                                                    f"matches were not imported: {shown}")


def _refuse_unmatched(m: dict, sd, layers: list, src: str, mkey: str, file: str | None):
    """A map entry that matches no entity left: say why (faces only, taken by an earlier entry, or no such
    layer, with the nearest and the file's layers) as a ScenarioError naming ``mkey``."""
    matched = [lay for lay in layers if _match(m["match"], lay)]
    if matched and not any(e.layer in matched for e in sd.entities):
        raise ScenarioError(f"{src}: {', '.join(map(repr, matched))} holds TIN faces (3DFACE) only: map it "
                            "as kind = \"surface\" (the road's grade and cross-slope)",
                            field=f"{mkey}.kind", file=file)
    if matched:  # its layers were taken by an earlier entry
        raise ScenarioError(f"{src}: match = {m['match']!r}: every entity of {', '.join(map(repr, matched))} "
                            "is taken by an earlier map entry", field=f"{mkey}.match", file=file)
    near = difflib.get_close_matches(m["match"], layers, n=1, cutoff=0.3)
    hint = f"; nearest: {near[0]!r}" if near else ""
    shown = ", ".join(map(repr, layers[:40])) + (f" and {len(layers) - 40} more" if len(layers) > 40 else "")
    if sd.empty_layers and layers == [""]:
        raise ScenarioError(f"{src} has no layer or code matching {m['match']!r}: {sd.empty_layers}",
                            field=f"{mkey}.match", file=file)
    raise ScenarioError(f"{src} has no layer or code matching {m['match']!r}{hint}. It has: "
                        f"{shown or 'none'}", field=f"{mkey}.match", file=file)


def _map_entries(out: _Out, sd, entry: dict, raw_entry: dict, frame: SceneFrame, key: str, file: str | None,
                 have_runout: bool) -> np.ndarray:
    """Apply the file's map entries; returns which entities were taken."""
    src = entry["file"]
    layers = sorted({e.layer for e in sd.entities} | {f[0] for f in sd.faces})
    taken = np.zeros(len(sd.entities), dtype=bool)
    for i, (m, rm) in enumerate(zip(entry["map"], raw_entry["map"])):
        mkey = f"{key}.map[{i}]"
        if m["kind"] == "surface":
            _need(m, rm, (), mkey, file)
            _surface(out, sd, m, frame, mkey, src, file, have_runout)
            continue
        _need(m, rm, {"line": ("style",), "zone": ("friction",), "mark": ("tolerance",),
                      "rest": ("body", "tolerance"), "impact_point": ("tolerance",)}.get(m["kind"], ()), mkey, file)
        if m["kind"] == "line" and m["style"] not in MAP_LINE_STYLES:
            near = difflib.get_close_matches(m["style"], MAP_LINE_STYLES, n=1)
            hint = f"; did you mean {near[0]!r}?" if near else ""
            raise ScenarioError(f"style = {m['style']!r} is not a map line style{hint} Allowed: "
                                f"{', '.join(MAP_LINE_STYLES)}", field=f"{mkey}.style", file=file)
        idx = [j for j, e in enumerate(sd.entities) if not taken[j] and _match(m["match"], e.layer)]
        if not idx:
            _refuse_unmatched(m, sd, layers, src, mkey, file)
        taken[idx] = True
        ents = [sd.entities[j] for j in idx]
        texts = [e for e in ents if e.geometry == "text"]
        shapes = [e for e in ents if e.geometry != "text"]
        kind = m["kind"]
        if kind == "ignore":
            for e in ents:
                out.record(src, e, "ignore", "")
            continue
        made: list = []  # (entity, dict item, where)
        # the scene-frame points of every entity of this entry, transformed at once
        if ents:
            sizes = np.cumsum([len(e.points) for e in ents])[:-1]
            moved = dict(zip(map(id, ents), np.split(frame.to_scene(np.vstack([e.points for e in ents])), sizes)))
        else:
            moved = {}

        def scene(e):
            got = moved.get(id(e))
            return got if got is not None else frame.to_scene(e.points)

        for e in (shapes if kind not in ("rest", "impact_point") else []):
            p = scene(e)
            if kind == "line":
                if e.geometry != "line":
                    out.record(src, e, kind, "", "a point cannot be a map line: left out")
                    continue
                item = {"name": m["name"], "style": m["style"], "points": _pts(np.vstack([p, p[:1]]) if e.closed
                                                                              else p)}
                if rm.get("color") is not None:
                    item["color"] = rm["color"]
                made.append((e, item, ("map", "lines")))
            elif kind == "obstacle":
                if e.geometry == "point":
                    item = {"name": _label(m, e), "points": _pts(_polygon(p[0], m["size"], 8)), "closed": True,
                            "description": f"post of diameter {m['size']:g} m at a surveyed point"}
                else:
                    item = {"name": _label(m, e), "points": _pts(p), "closed": bool(e.closed and len(p) >= 3)}
                    if rm.get("thickness") is not None:
                        item["thickness"] = rm["thickness"]
                made.append((e, item, ("obstacles",)))
            elif kind == "zone":
                closed = e.closed or (len(p) > 3 and np.allclose(p[0], p[-1], rtol=0, atol=1e-9))
                if e.geometry != "line" or not closed:
                    raise ScenarioError(f"{src}: {e.dxftype} {e.ref} on {e.layer!r} is not a closed outline; a friction "
                                        "zone needs one (close the polyline)", field=f"{mkey}.match", file=file)
                if not e.closed:
                    p = p[:-1]
                made.append((e, {"name": _label(m, e), "friction": rm["friction"], "polygon": _pts(p)},
                             ("runout", "zones")))
            elif kind == "mark":
                if e.geometry != "line":
                    raise ScenarioError(f"{src}: {e.dxftype} {e.ref} on {e.layer!r} is a point; a tyre mark is a "
                                        "polyline", field=f"{mkey}.match", file=file)
                item = {"name": _label(m, e), "points": _pts(np.vstack([p, p[:1]]) if e.closed else p)}
                for k in ("wheel", "phase", "sliding_only", "tolerance", "sigma"):
                    if rm.get(k) is not None:
                        item[k] = rm[k]
                made.append((e, item, ("evidence", "marks")))
            else:  # gouge, debris: drawn only
                drawn = (np.vstack([p, p[:1]]) if e.closed else p) if e.geometry == "line" else \
                    _polygon(p[0], m["size"] * math.sqrt(2), 4)
                if e.geometry == "point":
                    drawn = np.vstack([drawn, drawn[:1]])
                made.append((e, {"name": m["name"], "style": "other", "color": rm.get("color") or _COLORS[kind],
                                 "points": _pts(drawn)}, ("map", "lines")))
        if kind == "zone" and not have_runout:
            raise ScenarioError("friction zones need a [runout] section (road_friction outside them)",
                                field=f"{mkey}.kind", file=file)
        if kind == "rest":
            at = [a.strip() for a in (m["at"] or "").split(",") if a.strip()]
            groups = [[e] for e in shapes if e.geometry == "line"]
            pts_only = [e for e in shapes if e.geometry == "point"]
            if pts_only:
                groups.append(pts_only)
            for g in groups:
                p = np.vstack([scene(e) for e in g])
                ref = ", ".join(e.ref for e in g)
                item = {"name": m["name"] or f"{g[0].layer} {ref}", "body": m["body"], "tolerance": rm["tolerance"]}
                if not at:
                    if len(p) != 1:
                        raise ScenarioError(f"{src}: {len(p)} points of {m['body']!r} on {g[0].layer!r} ({ref}); "
                                            "give at = the named point each one is (e.g. \"front_left, "
                                            "rear_left\"), or survey one point, the CG", field=f"{mkey}.at", file=file)
                    item["position"] = _pts(p)[0]
                else:
                    if len(p) != len(at):
                        raise ScenarioError(f"{src}: {len(p)} points on {g[0].layer!r} ({ref}) but at names "
                                            f"{len(at)}: {', '.join(at)}", field=f"{mkey}.at", file=file)
                    item["points"] = [{"at": a, "position": q} for a, q in zip(at, _pts(p))]
                for k in ("heading_tolerance", "sigma", "heading_sigma"):
                    if rm.get(k) is not None:
                        item[k] = rm[k]
                made.append((g[0] if len(g) == 1 else _Group(g), item, ("evidence", "rest")))
        if kind == "impact_point":
            if len(shapes) != 1:
                raise ScenarioError(f"{src}: {len(shapes)} entities match {m['match']!r}; the point of impact is one "
                                    "point (or one circle, whose centre is taken)", field=f"{mkey}.match", file=file)
            e = shapes[0]
            c = scene(e).mean(axis=0) if e.geometry == "line" else scene(e)[0]
            if "impact_point" in out.data.get("evidence", {}):
                raise ScenarioError("the scenario has an [evidence.impact_point] already", field=f"{mkey}.kind",
                                    file=file)
            item = {"position": [_m(c[0]), _m(c[1])], "tolerance": rm["tolerance"]}
            if rm.get("sigma") is not None:
                item["sigma"] = rm["sigma"]
            out.data.setdefault("evidence", {})["impact_point"] = item
            out.record(src, e, kind, "evidence.impact_point", key=mkey)
        # labels: a text names the nearest item it made on its layer (nearest vertex, a k-d tree per layer)
        if texts:
            _name_by_labels(out, src, texts, made, scene)
        for e, item, where in made:
            target = out.append(where, item)
            if isinstance(e, _Group):
                for x in e.members:
                    out.record(src, x, kind, target, key=mkey)
            else:
                out.record(src, e, kind, target, key=mkey)
    return taken


def _surface(out: "_Out", sd, m: dict, frame: SceneFrame, mkey: str, src: str, file: str | None,
             have_runout: bool) -> None:
    """A TIN's faces (kind = "surface") as the road's plane: runout.grade and runout.cross_slope, rise over
    run along the scene's +x and +y, from the least-squares plane through every vertex."""
    idx = [j for j, (layer, _, _) in enumerate(sd.faces) if (id(sd), j) not in out.faces_taken and
           _match(m["match"], layer)]
    if not idx:
        have = sorted({f[0] for f in sd.faces})
        raise ScenarioError(f"{src} has no TIN faces (3DFACE) on a layer matching {m['match']!r}; layers with "
                            f"faces: {', '.join(map(repr, have)) or 'none'}", field=f"{mkey}.match", file=file)
    if not have_runout:
        raise ScenarioError("a road surface (its grade and cross-slope) needs a [runout] section",
                            field=f"{mkey}.kind", file=file)
    given = [k for k in ("grade", "cross_slope") if k in (out.data.get("runout") or {})]
    if given:
        raise ScenarioError(f"kind = 'surface' gives runout.grade and runout.cross_slope from the TIN, but the file "
                            f"gives runout.{given[0]} too; give one of them", field=f"{mkey}.kind", file=file)
    v = np.vstack([sd.faces[j][2] for j in idx])
    xy = frame.to_scene(v[:, :2])
    a = np.column_stack([np.ones(len(xy)), xy - xy.mean(axis=0)])
    if len(v) < 3 or np.linalg.matrix_rank(a[:, 1:]) < 2:
        raise ScenarioError(f"{src}: the faces on {m['match']!r} do not span a plane (their vertices lie on a line)",
                            field=f"{mkey}.match", file=file)
    coef, *_ = np.linalg.lstsq(a, v[:, 2], rcond=None)
    rms = float(np.sqrt(np.mean((a @ coef - v[:, 2]) ** 2)))
    grade, cross = float(coef[1]), float(coef[2])
    out.data["runout"]["grade"] = grade
    out.data["runout"]["cross_slope"] = cross
    out.faces_taken.update((id(sd), j) for j in idx)
    note = (f"road plane of {len(idx)} faces ({len(v)} vertices): grade {100 * grade:.3g} %, cross-slope "
            f"{100 * cross:.3g} %, RMS of the vertices about it {rms:.3g} m (one plane for the scene: no vertical "
            "curve or changing banking)")
    for target in ("runout.grade", "runout.cross_slope"):
        out.records.append({"file": src, "layer": sd.faces[idx[0]][0], "ref": f"{len(idx)} faces", "type": "3DFACE",
                            "kind": "surface", "target": target, "note": note if target == "runout.grade" else "",
                            "key": mkey})


def _name_by_labels(out: "_Out", src: str, texts, made: list, scene) -> None:
    """Each TEXT/MTEXT names the item made from its layer whose nearest vertex is closest to it."""
    from scipy.spatial import cKDTree

    by_layer: dict = {}
    for k, (e, item, _) in enumerate(made):
        if "name" in item:
            pts = np.vstack([scene(x) for x in e.members]) if isinstance(e, _Group) else scene(e)
            by_layer.setdefault(e.layer, []).append((k, pts))
    trees = {}
    for layer, lst in by_layer.items():
        idx = np.concatenate([np.full(len(p), k) for k, p in lst])
        trees[layer] = (cKDTree(np.vstack([p for _, p in lst])), idx)
    for t in texts:
        tree = trees.get(t.layer)
        if tree is not None:
            _, j = tree[0].query(scene(t)[0])
            made[int(tree[1][j])][1]["name"] = t.text
        out.record(src, t, "label", "", f"text {t.text!r}" + ("" if tree else ": no item of its layer to name"))


class _Group:
    def __init__(self, members):
        self.members = members
        self.layer = members[0].layer


def is_placed(survey) -> bool:
    """Whether a ``[survey]`` table places the scene on a survey (files, an underlay, a CRS or
    imported items): its +y is then grid north, drawn as the scene figure's north arrow."""
    return isinstance(survey, dict) and any(survey.get(k) for k in ("files", "underlay", "crs", "imported"))


def expand_survey(data: dict, file: str | None = None) -> dict:
    """The raw scenario dict with its survey read and mapped (a new dict; ``data`` is not changed).

    Without a ``[survey]`` section, or with one already expanded (``survey.imported`` present),
    ``data`` is returned as it is.

    Raises
    ------
    ScenarioError
        One line naming the file, the item and the value: a mapped layer or code the file lacks
        (with the ones it has and the nearest), units that contradict the drawing's header, a
        CSV without a mapped column, an unknown CRS, an unreadable file.
    """
    if not isinstance(data, dict) or not isinstance(data.get("survey"), dict) or is_expanded(data):
        return data
    s = survey_section(data, file)
    if s["units"] is not None:
        unit_scale(s["units"], field="survey.units", file=file)
    frame = survey_frame(s)
    out = _Out(copy.deepcopy(data))
    raw_files = data["survey"].get("files", [])
    have_runout = isinstance(data.get("runout"), dict)
    for i, entry in enumerate(s["files"]):
        key = f"survey.files[{i}]"
        sd = read_survey_file(entry, s["crs"], key=key, file=file)
        _map_file(out, sd, entry, raw_files[i], frame, key, file, have_runout)
        msgs = ([sd.skipped_warning()] if sd.skipped else []) + list(sd.notes)
        for msg in msgs:
            if msg:  # the file as the scene file writes it, not the analyst's absolute path
                out.record(entry["file"], None, "note", "", msg.replace(sd.path, entry["file"]))
        if sd.skipped:
            _log.warning("%s", sd.skipped_warning())
    raw_rec = data["survey"].get("recorders", [])
    for i, r in enumerate(s["recorders"]):
        key = f"survey.recorders[{i}]"

        path = _resolve(r["file"], file)
        try:
            samples, notes = read_recorder(path, r, key=key, file=file)
        except ScenarioError as exc:  # the table named as the scene file writes it
            text = str(exc).removeprefix(f"{file}: " if file else "").removeprefix(f"{exc.field}: " if exc.field else "")
            raise ScenarioError(text.replace(path, r["file"]), field=exc.field, file=file) from None
        item = {"name": r["name"] or f"recorder {Path(r['file']).name}", "body": r["body"],
                "tolerance": raw_rec[i]["tolerance"], "time_offset": raw_rec[i].get("time_offset", "0 s"),
                "samples": [{"time": f"{t!r} s", "speed": f"{v!r} m/s", "brake": low} for t, v, low in samples]}
        if raw_rec[i].get("sigma") is not None:
            item["sigma"] = raw_rec[i]["sigma"]
        target = out.append(("evidence", "recorder"), item)
        out.records.append({"file": r["file"], "layer": "", "ref": f"{len(samples)} samples", "type": "CSV",
                            "kind": "recorder", "target": target, "note": "; ".join(notes), "key": key})
    if s["underlay"]:  # placed now, so that a world file or control points that do not fit fail at load

        g = georef_from_section(s["underlay"], frame, file, file)
        # the image and world file by absolute path in the expanded file: a best-fit file written
        # elsewhere (fit --write-best) still finds them
        u = out.data["survey"]["underlay"]
        for k in ("image", "world_file"):
            if u.get(k):
                u[k] = _resolve(u[k], file)
        note = f"{g.how}; {g.pixel_size:.4g} m per pixel"
        if len(g.residuals):
            note += "; control point residuals " + ", ".join(f"{r:.3g} m" for r in g.residuals)
        out.records.append({"file": s["underlay"]["image"], "layer": "", "ref": "", "type": "image",
                            "kind": "underlay", "target": "", "note": note})
    _far_items(out, data, file)
    out.data["survey"]["imported"] = out.records
    return out.data


#: An imported item farther than this from every vehicle at the impact is warned of [m]: a scene is
#: tens to hundreds of metres across, a wrong origin or swapped columns put the survey kilometres off.
FAR = 1000.0


def _metres(node, out: list) -> None:
    """The scene points [m] written in an item (pairs of "x m" strings), collected into ``out``."""
    if isinstance(node, dict):
        for v in node.values():
            _metres(v, out)
    elif isinstance(node, list):
        if len(node) == 2 and all(isinstance(v, str) and v.endswith(" m") for v in node):
            try:
                out.append((float(node[0][:-2]), float(node[1][:-2])))
            except ValueError:
                pass
        else:
            for v in node:
                _metres(v, out)


def _far_items(out: _Out, data: dict, file: str | None) -> None:
    """A warning record (in the report's warnings) for each imported item farther than :data:`FAR` from
    every vehicle's position at the impact, naming it and its source."""
    cars = []
    for name, v in (data.get("vehicles") or {}).items():
        try:
            cars.append([parse(x, Kind.LENGTH, field=f"vehicles.{name}.position", file=file) for x in v["position"]])
        except (ScenarioError, KeyError, TypeError, ValueError):
            continue
    if not cars:
        return
    cars = np.asarray(cars, dtype=float)
    seen = set()
    dists = []
    for r in list(out.records):
        t = r.get("target") or ""
        if not t or t in seen or r["kind"] in ("note", "label", "ignore", "underlay", "warning", "recorder"):
            continue
        seen.add(t)
        node = out.data
        try:
            for part in t.split("."):
                name, _, idx = part.partition("[")
                node = node[name] if not idx else node[name][int(idx.rstrip("]"))]
        except (KeyError, IndexError, ValueError, TypeError):
            continue
        pts: list = []
        _metres(node, pts)
        if not pts:
            continue
        d = float(np.min(np.hypot(*(np.asarray(pts)[:, None, :] - cars[None, :, :]).transpose(2, 0, 1))))
        dists.append(d)
        if d > FAR:
            out.records.append({"file": r["file"], "layer": r["layer"], "ref": r["ref"], "type": r["type"],
                                "kind": "warning", "target": t,
                                "note": f"survey item {t} ({r['kind']} from {r['file']}, {r['layer'] or '(no layer)'} "
                                        f"{r['ref']}) lies {d / 1000:.4g} km from every vehicle at the impact: check "
                                        "survey.origin, survey.rotation and the file's columns and units"})
    if len(dists) >= 2 and min(dists) > FAR:  # the whole survey is off: its placement, not an item
        o = (data.get("survey") or {}).get("origin")
        raise ScenarioError(f"every item imported from the survey ({len(dists)}) lies at least {min(dists) / 1000:.4g} "
                            f"km from every vehicle at the impact: survey.origin = {o!r} (easting or x first, then "
                            "northing or y, in the survey's coordinates) or survey.rotation does not place the survey "
                            "on the scene", field="survey.origin", file=file)


def _written(field: str, targets: dict) -> str | None:
    """The key the user wrote for ``field`` of an item the survey generated (``evidence.rest[1].points[3].at``
    -> ``survey.files[1].map[0].at (imported as evidence.rest[1].points[3].at)``), or None."""
    for target, key in targets.items():
        if field == target or field.startswith((target + ".", target + "[")):
            rest = field[len(target):].lstrip(".")
            last = rest.rsplit(".", 1)[-1].split("[", 1)[0] if rest else ""
            return f"{key}.{last}" if last else key
    return None


def as_written(exc: ScenarioError, data: dict) -> ScenarioError:
    """``exc`` with the keys of survey-generated items named as the user wrote them (the map entry or
    recorder table that made the item, the generated key in brackets); ``exc`` itself if none."""
    s = data.get("survey") if isinstance(data, dict) else None
    records = (s or {}).get("imported") if isinstance(s, dict) else None
    if not records or type(exc) not in (ScenarioError, ScenarioValidationError):
        return exc
    targets = {r["target"]: r["key"] for r in records if r.get("target") and r.get("key")}
    if not targets:
        return exc
    if isinstance(exc, ScenarioValidationError):
        problems, changed = [], False
        for path, text in exc.problems:
            w = _written(path, targets)
            changed |= w is not None
            problems.append((w, f"{text} (imported as {path})") if w else (path, text))
        return ScenarioValidationError(problems, file=exc.file) if changed else exc
    w = _written(exc.field or "", targets)
    if w is None:
        return exc
    text = str(exc).removeprefix(f"{exc.file}: " if exc.file else "").removeprefix(f"{exc.field}: ")
    return ScenarioError(f"{text} (imported as {exc.field})", field=w, file=exc.file)


def load_scene_data(path: str | os.PathLike) -> dict:
    """The raw scenario dict of a file (:func:`crashsim.schema.load_toml`) with its survey read
    (:func:`expand_survey`): what fit, Monte Carlo and posterior take."""
    return expand_survey(load_toml(path), str(path))

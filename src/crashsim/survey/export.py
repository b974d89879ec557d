"""The reconstruction out to CAD: DXF and GeoJSON in the survey's own frame and units.

Layers (one per thing, so a user can switch them in the drawing the survey came from):

=============================  ==================================================================
``CRASHSIM-IMPACT-<body>``     the body's outline at impact (closed polyline)
``CRASHSIM-T<t>-<body>``       its outline at a chosen time ``t`` after separation [s]
``CRASHSIM-REST-<body>``       its outline at rest (or where the run stopped)
``CRASHSIM-CG-<body>``         its CG path from separation to rest
``CRASHSIM-TRACK-SLIDING``     computed tyre tracks, sliding stretches (tyre marks expected)
``CRASHSIM-TRACK-ROLLING``     computed tyre tracks, rolling stretches
``CRASHSIM-IMPACTS``           the contact point of every impact (POINT and a TEXT "1", "2", ...)
``CRASHSIM-EVIDENCE-PASS``     evidence within tolerance: marks, measured rest points and CGs, the
                               point of impact, with a TEXT naming the item and its residual
``CRASHSIM-EVIDENCE-FAIL``     the same, out of tolerance
=============================  ==================================================================

Coordinates: scene metres taken back through the scene frame (``survey.origin``,
``survey.rotation``) and divided by the survey unit (``survey.units``, default the first survey
file's, else metres); the DXF header's ``$INSUNITS`` names that unit. GeoJSON with a
``survey.crs`` is RFC 7946 (WGS 84 longitude/latitude, no ``crs`` member); without one, the
survey's own axes in its unit.
"""

from __future__ import annotations

import json
from dataclasses import dataclass

import numpy as np

from ..errors import ScenarioError
from ..geometry import rotate
from ..units import Kind, format_value
from .frame import INSUNITS, SceneFrame, unit_scale
from .geojson import projected_crs
from .mapping import read_survey_file

__all__ = ["ExportItem", "export_items", "export_frame", "write_dxf", "write_geojson"]


@dataclass(frozen=True)
class ExportItem:
    """One thing to write: layer, ``"line"``/``"point"``/``"text"``, scene points [m], closed, text."""

    layer: str
    geometry: str
    points: np.ndarray
    closed: bool = False
    text: str = ""


def export_frame(scenario) -> tuple[SceneFrame, str]:
    """(scene frame, survey unit) of a scenario: its [survey] section's; without survey files or
    ``survey.units``, the length unit of its reports (``scenario.units``: ft for "US", else m)."""
    own = "ft" if scenario.units == "US" else "m"
    s = scenario.data.get("survey") if isinstance(scenario.data, dict) else None
    if not isinstance(s, dict):
        return SceneFrame(), own
    unit = s.get("units")
    if unit is None:
        files = s.get("files") or []
        unit = next((f["units"] for f in files if f.get("units")), None)
        if unit is None:
            unit = "m" if files else own
            for f in files:
                if str(f.get("file", "")).lower().endswith(".dxf"):
                    unit = read_survey_file(f, s.get("crs"), file=scenario.path).unit
                    break
    unit_scale(unit, field="survey.units", file=scenario.path)
    return SceneFrame(tuple(s["origin"]), s["rotation"]), unit


def _pose_outline(body, pos, heading) -> np.ndarray | None:
    corners = body.outline()
    if corners is None:
        return None
    return np.asarray(pos, dtype=float) + rotate(corners, heading)


def _layer_name(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def export_items(scene, times=()) -> list[ExportItem]:
    """What :func:`write_dxf` and :func:`write_geojson` write, in scene metres."""
    sc = scene.scenario
    out: list[ExportItem] = []
    bodies = {b.name: b for v in sc.vehicles for b in v.bodies if not b.is_fixed}
    for name, b in bodies.items():
        st = sc.states[name]
        o = _pose_outline(b, st.position, st.heading)
        if o is not None:
            out.append(ExportItem(f"CRASHSIM-IMPACT-{_layer_name(name)}", "line", o, True))
    for r in (scene.runout or {}).values():
        for name, br in r.bodies.items():
            b = bodies[name]
            for t in times:
                if 0 < t < r.t_end:
                    s = np.asarray(br.sol(float(t)), dtype=float)
                    o = _pose_outline(b, s[:2], s[2])
                    if o is not None:
                        out.append(ExportItem(f"CRASHSIM-T{t:g}-{_layer_name(name)}", "line", o, True))
            o = _pose_outline(b, br.rest_position, br.rest_heading)
            if o is not None:
                out.append(ExportItem(f"CRASHSIM-REST-{_layer_name(name)}", "line", o, True))
            h = br.history
            out.append(ExportItem(f"CRASHSIM-CG-{_layer_name(name)}", "line", np.column_stack([h.x, h.y])))
        for tr in r.wheels.values():
            for seg in tr.segments:
                if len(seg.points) >= 2:
                    out.append(ExportItem("CRASHSIM-TRACK-" + ("SLIDING" if seg.kind == "sliding" else "ROLLING"),
                                          "line", np.asarray(seg.points, dtype=float)))
    for imp in scene.impacts:  # numbered by event, as the figures and the report number them
        p = np.asarray(imp["point"], dtype=float)[None]
        out.append(ExportItem("CRASHSIM-IMPACTS", "point", p))
        out.append(ExportItem("CRASHSIM-IMPACTS", "text", p, text=f"{imp['event']}"))
    rep = scene.evidence
    if rep is not None:
        checks = {(c.kind, c.name): c for c in rep.checks}
        ev = sc.evidence

        def verdict(kind, name):
            c = checks.get((kind, name))
            if c is None:
                return "CRASHSIM-EVIDENCE-PASS", name
            res = format_value(abs(c.residual), Kind.LENGTH, sc.units) if c.quantity == "length" else f"{c.residual:.4g}"
            return ("CRASHSIM-EVIDENCE-" + ("PASS" if c.passed else "FAIL"),
                    f"{name}: {'PASS' if c.passed else 'FAIL'} {res}")

        if ev.impact_point is not None:
            layer, text = verdict("point of impact", ev.impact_point.name)
            p = np.asarray(ev.impact_point.position, dtype=float)[None]
            out += [ExportItem(layer, "point", p), ExportItem(layer, "text", p, text=text)]
        for i, r in enumerate(ev.rest):
            name = r.name or f"rest of {r.body}"
            layer, text = verdict("rest", name)
            p = np.asarray(r.position, dtype=float)[None]
            out += [ExportItem(layer, "point", p), ExportItem(layer, "text", p, text=text)]
            reg = getattr(r, "registration", None)
            if reg is not None:
                for q in np.asarray(reg.measured, dtype=float):
                    out.append(ExportItem(layer, "point", q[None]))
        for i, m in enumerate(ev.marks):
            name = m.name or f"mark {i + 1}"
            layer, text = verdict("mark", name)
            pts = np.asarray(m.points, dtype=float)
            out += [ExportItem(layer, "line", pts), ExportItem(layer, "text", pts[:1], text=text)]
    return out


def write_dxf(items, path, frame: SceneFrame, unit: str) -> str:
    """Write ``items`` to a DXF (R2010) in the survey's axes and ``unit``; returns the path."""
    import ezdxf

    scale = unit_scale(unit, field="survey.units")
    doc = ezdxf.new("R2010", setup=True)
    code = next((k for k, v in INSUNITS.items() if v == unit), 0)
    doc.header["$INSUNITS"] = 21 if unit == "survey_foot" else code
    msp = doc.modelspace()
    colors = {"PASS": 3, "FAIL": 1, "SLIDING": 250, "ROLLING": 8, "IMPACTS": 6}
    for it in items:
        if it.layer not in doc.layers:
            doc.layers.add(it.layer, color=next((c for k, c in colors.items() if it.layer.endswith(k)), 7))
        p = frame.to_survey(it.points) / scale
        att = {"layer": it.layer}
        if it.geometry == "line":
            msp.add_lwpolyline(p.tolist(), close=it.closed, dxfattribs=att)
        elif it.geometry == "point":
            msp.add_point(p[0].tolist(), dxfattribs=att)
        else:
            msp.add_text(it.text, height=0.3 / scale, dxfattribs={**att, "insert": p[0].tolist()})
    try:
        doc.saveas(path)
    except OSError as exc:
        raise ScenarioError(f"cannot write {path}: {exc}", field="--dxf") from None
    return str(path)


def write_geojson(items, path, frame: SceneFrame, unit: str, crs: str | None = None) -> str:
    """Write ``items`` to a GeoJSON FeatureCollection; returns the path.

    With the survey's projected ``crs`` (``survey.crs``) the file is RFC 7946: WGS 84 longitude and
    latitude (degrees, in that order), no ``crs`` member, so that any GIS puts it on the map; the
    survey's coordinates are taken from metres to the CRS's own axis unit and transformed with
    pyproj. Without a CRS there is no map to put it on: the coordinates are the survey's own axes
    in ``unit`` (a local frame), named by the ``crashsim_units`` member. A text becomes a Point
    with a ``text`` property.
    """
    scale = unit_scale(unit, field="survey.units")
    transform = None
    if crs:
        from pyproj import Transformer

        src, factor = projected_crs(crs)
        to_lonlat = Transformer.from_crs(src, "EPSG:4326", always_xy=True)

        def transform(p):  # survey metres -> the CRS's unit -> lon, lat
            lon, lat = to_lonlat.transform(p[:, 0] / factor, p[:, 1] / factor)
            return np.column_stack([lon, lat])

    feats = []
    for it in items:
        p = frame.to_survey(it.points)
        p = transform(p) if transform is not None else p / scale
        if it.geometry == "line":
            coords = p.tolist() + ([p[0].tolist()] if it.closed else [])
            geom = {"type": "Polygon", "coordinates": [coords]} if it.closed else \
                {"type": "LineString", "coordinates": coords}
        else:
            geom = {"type": "Point", "coordinates": p[0].tolist()}
        props = {"layer": it.layer}
        if it.text:
            props["text"] = it.text
        feats.append({"type": "Feature", "properties": props, "geometry": geom})
    doc = {"type": "FeatureCollection", "features": feats}
    if crs:
        doc["crashsim_source_crs"] = crs  # a foreign member (RFC 7946, 6.1): where the coordinates came from
    else:
        doc["crashsim_units"] = unit
    try:
        with open(path, "w", encoding="utf-8") as fh:
            json.dump(doc, fh)
    except OSError as exc:
        raise ScenarioError(f"cannot write {path}: {exc}", field="--geojson") from None
    return str(path)

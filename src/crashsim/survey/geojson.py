"""GeoJSON (RFC 7946) features: Point, LineString, Polygon and their Multi- forms, projected with pyproj.

A file without a ``crs`` member is longitude/latitude on WGS 84 (RFC 7946); a legacy ``crs``
member (``"urn:ogc:def:crs:EPSG::32633"``) or the scene file's ``crs`` names another. The
coordinates are projected into the survey's projected CRS (``survey.crs``) and converted from
its axis unit to metres, so a lon/lat file and its projected twin land on the same points.
A feature's layer is the value of one of its properties (``layer_property``, default
``"layer"``); a polygon's holes are dropped with a note (an outline is what a scene needs).
"""

from __future__ import annotations

import json

import numpy as np

from ..errors import ScenarioError
from .entities import Entity, SurveyData

__all__ = ["read_geojson", "projected_crs"]


def _crs(text: str, what: str, file: str | None):
    try:
        from pyproj import CRS
        from pyproj.exceptions import CRSError
    except ImportError:  # pragma: no cover - a dependency of crashsim
        raise ScenarioError("GeoJSON needs the pyproj package (pip install pyproj)", file=file) from None
    try:
        return CRS.from_user_input(text)
    except CRSError:
        raise ScenarioError(f"{what} = {text!r} is not a coordinate reference system pyproj knows (write e.g. "
                            "\"EPSG:32633\")", field=what, file=file) from None


def projected_crs(text: str, *, field: str = "survey.crs", file: str | None = None):
    """(pyproj CRS, metres per axis unit) of a projected CRS; an error for an unknown or geographic one."""
    crs = _crs(text, field, file)
    if not crs.is_projected:
        raise ScenarioError(f"{field} = {text!r} is not a projected CRS (its axes are {crs.axis_info[0].unit_name}); "
                            "the scene needs plane coordinates, e.g. the UTM zone \"EPSG:32633\"", field=field,
                            file=file)
    return crs, float(crs.axis_info[0].unit_conversion_factor)


def _rings(geom: dict, ref: str, notes: list):
    t = geom.get("type")
    c = geom.get("coordinates")
    if t == "Point":
        yield "point", [c], False, t
    elif t == "MultiPoint":
        for p in c:
            yield "point", [p], False, t
    elif t == "LineString":
        yield "line", c, False, t
    elif t == "MultiLineString":
        for ln in c:
            yield "line", ln, False, t
    elif t in ("Polygon", "MultiPolygon"):
        polys = [c] if t == "Polygon" else c
        for poly in polys:
            if len(poly) > 1:
                notes.append(f"feature {ref}: {len(poly) - 1} holes of a {t} dropped (the outline is kept)")
            ring = poly[0]
            if len(ring) > 1 and ring[0] == ring[-1]:
                ring = ring[:-1]
            yield "line", ring, True, t
    elif t == "GeometryCollection":
        for g in geom.get("geometries", []):
            yield from _rings(g, ref, notes)
    else:
        yield None, None, None, str(t)


def read_geojson(path: str, target_crs: str | None, *, crs: str | None = None, layer_property: str = "layer",
                 file: str | None = None) -> SurveyData:
    """The features of a GeoJSON file in metres of ``target_crs``.

    Parameters
    ----------
    path : str
    target_crs : str or None
        The survey's projected CRS (``survey.crs``). None only for a file already in a
        projected CRS, whose coordinates are then taken in its own axis unit.
    crs : str, optional
        The CRS of the file's coordinates; default its legacy ``crs`` member, else WGS 84 lon/lat.
    layer_property : str
        The property whose value is the feature's layer.
    """
    try:
        with open(path, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError) as exc:
        raise ScenarioError(f"cannot read the GeoJSON file {path}: {exc}", file=file) from None
    feats = doc.get("features") if doc.get("type") == "FeatureCollection" else [doc] if doc.get("type") == "Feature" \
        else None
    if feats is None:
        raise ScenarioError(f"{path}: not a GeoJSON FeatureCollection or Feature (type = {doc.get('type')!r})",
                            file=file)
    src_text = crs
    if src_text is None:
        member = doc.get("crs")
        if isinstance(member, dict):
            src_text = (member.get("properties") or {}).get("name")
    src_text = src_text or "EPSG:4326"
    src = _crs(src_text, "survey.files.crs", file)
    if target_crs is None:
        if not src.is_projected:
            raise ScenarioError(f"{path} is in longitude/latitude ({src_text}): give survey.crs, the projected CRS "
                                "of the scene frame (e.g. the UTM zone, \"EPSG:32633\")", field="survey.crs",
                                file=file)
        dst, factor, transformer = src, float(src.axis_info[0].unit_conversion_factor), None
    else:
        from pyproj import Transformer

        dst, factor = projected_crs(target_crs, file=file)
        transformer = None if src == dst else Transformer.from_crs(src, dst, always_xy=True)
    data = SurveyData(path, "geojson", f"{dst.axis_info[0].unit_name} ({dst.to_string()})")
    data.notes.append(f"coordinates in {src_text}, projected to {dst.to_string()}" if transformer else
                      f"coordinates in {src_text}")
    names: set = set()
    with_layer = 0
    for k, f in enumerate(feats):
        ref = f"#{k}" if f.get("id") is None else f"#{k} (id {f['id']})"
        props = f.get("properties") or {}
        names.update(props)
        with_layer += layer_property in props
        layer = props.get(layer_property)
        layer = "" if layer is None else str(layer)
        geom = f.get("geometry")
        if not geom:
            data.skipped["Feature without geometry"] += 1
            continue
        parts = list(_rings(geom, ref, data.notes))
        for j, (g, coords, closed, t) in enumerate(parts):
            if g is None:
                data.skipped[t] += 1
                continue
            a = np.asarray([(p[0], p[1]) for p in coords], dtype=float).reshape(-1, 2)
            if transformer is not None:
                x, y = transformer.transform(a[:, 0], a[:, 1])
                a = np.column_stack([x, y])
            if not np.all(np.isfinite(a)):
                raise ScenarioError(f"{path}: feature {ref} does not project to {dst.to_string()} (coordinates "
                                    f"{coords[0]!r} ...)", field="survey.crs", file=file)
            data.entities.append(Entity(layer, ref if len(parts) == 1 else f"{ref}/{j + 1}", g, a * factor, closed,
                                        "", t))
    if feats and not with_layer:
        shown = ", ".join(sorted(map(str, names))[:20]) or "none"
        data.empty_layers = f"no feature has a property {layer_property!r} (layer_property); the properties: {shown}"
        data.notes.append(data.empty_layers)
    return data

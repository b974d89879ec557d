"""DXF drawings (R12 to current, ASCII or binary) read with ezdxf.

Taken: LINE, LWPOLYLINE, POLYLINE (2-D and 3-D; polyface and mesh are not), ARC, CIRCLE,
ELLIPSE and SPLINE (as polylines whose chords lie within ``chord_tolerance`` of the curve),
POINT, TEXT and MTEXT (labels), and INSERT (the block's entities placed, scaled and turned by
ezdxf's virtual entities, on the INSERT's layer where they lie on layer 0). Z is dropped (the
scene is planar). Any other type is counted and named in one warning, never dropped silently.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np

from ..errors import ScenarioError
from .entities import Entity, SurveyData
from .frame import INSUNITS, UNIT_METRES, unit_scale

__all__ = ["read_dxf", "header_unit"]

_CURVES = ("ARC", "CIRCLE", "ELLIPSE", "SPLINE")


def _open(path: str):
    try:
        import ezdxf
        from ezdxf import recover
    except ImportError:  # pragma: no cover - a dependency of crashsim
        raise ScenarioError("reading DXF needs the ezdxf package (pip install ezdxf)", file=path) from None
    try:
        return ezdxf.readfile(path)
    except IOError as exc:
        raise ScenarioError(f"cannot read the DXF file: {exc}", file=path) from None
    except ezdxf.DXFStructureError:
        pass
    try:
        doc, auditor = recover.readfile(path)
    except Exception as exc:
        raise ScenarioError(f"not a readable DXF file ({type(exc).__name__}: {exc})", file=path) from None
    if auditor.has_errors:
        raise ScenarioError(f"the DXF file is damaged: {len(auditor.errors)} errors, the first: "
                            f"{auditor.errors[0].message}", file=path)
    return doc


def header_unit(doc) -> str | None:
    """The drawing unit named by ``$INSUNITS`` (None where it is 0, unitless, or absent)."""
    code = int(doc.header.get("$INSUNITS", 0) or 0)
    return INSUNITS.get(code)


def _xy(pts) -> np.ndarray:
    a = np.asarray([(p[0], p[1]) for p in pts], dtype=float)
    return a.reshape(-1, 2)


def _flatten(e, sagitta: float) -> np.ndarray:
    return _xy(e.flattening(sagitta))


def _bulge_points(vertices, closed: bool, sagitta: float) -> np.ndarray:
    """Vertices (x, y, bulge) of a polyline with its bulged segments as exact arcs: chord points on
    the circle, chords within ``sagitta`` of it (bulge = tan(included angle / 4), DXF reference)."""
    v = [(float(x), float(y), float(b or 0.0)) for x, y, b in vertices]
    out = []
    n = len(v)
    for i in range(n if closed else n - 1):
        x0, y0, b = v[i]
        x1, y1, _ = v[(i + 1) % n]
        out.append((x0, y0))
        if b == 0.0:
            continue
        theta = 4.0 * math.atan(b)                  # included angle, signed (ccw positive)
        chord = math.hypot(x1 - x0, y1 - y0)
        if chord == 0.0:
            continue
        r = chord / (2.0 * math.sin(abs(theta) / 2.0))
        # centre: from the chord midpoint along its left normal (ccw arc) by r cos(theta/2)
        mx, my = (x0 + x1) / 2, (y0 + y1) / 2
        nx, ny = -(y1 - y0) / chord, (x1 - x0) / chord
        d = r * math.cos(abs(theta) / 2.0) * (1 if b > 0 else -1)  # < 0 past a half circle: centre beyond
        cx, cy = mx + nx * d, my + ny * d
        a0 = math.atan2(y0 - cy, x0 - cx)
        step = 2.0 * math.acos(max(-1.0, 1.0 - sagitta / r)) if sagitta < r else math.pi / 2
        k = max(2, int(math.ceil(abs(theta) / max(step, 1e-9))))
        for j in range(1, k):
            a = a0 + theta * j / k
            out.append((cx + r * math.cos(a), cy + r * math.sin(a)))
    if not closed:
        out.append(v[-1][:2])
    return np.asarray(out, dtype=float).reshape(-1, 2)


def _entity_points(e, kind: str, sagitta: float):
    """(geometry, points (n, 2) in drawing units, closed, text) of a taken entity; None to skip."""
    if kind == "LINE":
        return "line", _xy([e.dxf.start, e.dxf.end]), False, ""
    if kind == "POINT":
        return "point", _xy([e.dxf.location]), False, ""
    if kind == "LWPOLYLINE":
        closed = bool(e.closed)
        simple = tuple(e.dxf.extrusion) == (0.0, 0.0, 1.0) and e.dxf.elevation == 0
        # the vertex array's values: x, y, start width, end width, bulge per vertex
        v = np.asarray(e.lwpoints.values, dtype=float).reshape(-1, 5)
        if simple and not v[:, 4].any():
            return "line", v[:, :2].copy(), closed, ""
        if simple:
            return "line", _bulge_points(v[:, [0, 1, 4]], closed, sagitta), closed, ""
        from ezdxf import path as ezpath

        pts = _xy(ezpath.make_path(e).flattening(sagitta))
        if closed and len(pts) > 1 and np.allclose(pts[0], pts[-1]):
            pts = pts[:-1]
        return "line", pts, closed, ""
    if kind == "POLYLINE":
        if e.is_polygon_mesh or e.is_poly_face_mesh:
            return None
        closed = bool(e.is_closed)
        if e.is_2d_polyline and any(v.dxf.bulge for v in e.vertices) and \
                tuple(e.dxf.extrusion) == (0.0, 0.0, 1.0):
            vs = [(v.dxf.location[0], v.dxf.location[1], v.dxf.bulge) for v in e.vertices]
            return "line", _bulge_points(vs, closed, sagitta), closed, ""
        if e.is_2d_polyline and any(v.dxf.bulge for v in e.vertices):
            from ezdxf import path as ezpath

            pts = _xy(ezpath.make_path(e).flattening(sagitta))
            if closed and len(pts) > 1 and np.allclose(pts[0], pts[-1]):
                pts = pts[:-1]
        else:
            pts = _xy(e.points_in_wcs() if e.is_2d_polyline else e.points())
        return "line", pts, closed, ""
    if kind in _CURVES:
        pts = _flatten(e, sagitta)
        closed = kind == "CIRCLE" or (kind == "ELLIPSE" and e.dxf.start_param == 0 and
                                      abs(e.dxf.end_param - 2 * np.pi) < 1e-12) or (kind == "SPLINE" and e.closed)
        if closed and len(pts) > 1 and np.allclose(pts[0], pts[-1]):
            pts = pts[:-1]
        return "line", pts, closed, ""
    if kind == "TEXT":
        return "text", _xy([e.dxf.insert]), False, e.dxf.text
    if kind == "MTEXT":
        return "text", _xy([e.dxf.insert]), False, e.plain_text().strip()
    return None


def read_dxf(path: str, units: str | None = None, *, chord_tolerance: float = 0.01,
             file: str | None = None) -> SurveyData:
    """The entities of a DXF file, in metres.

    Parameters
    ----------
    path : str
    units : str, optional
        The drawing unit (a key of :data:`~crashsim.survey.frame.UNIT_METRES`) from the scene
        file. Where the header's ``$INSUNITS`` names a unit too, the two must agree; where neither
        names one, the file cannot be placed and this is an error.
    chord_tolerance : float
        Largest distance [m] of a chord from the arc, circle, ellipse or spline it replaces.
    file : str, optional
        The scene file, for error messages.

    Raises
    ------
    ScenarioError
        An unreadable file, or drawing units missing or contradicting the header.
    """
    doc = _open(path)
    head = header_unit(doc)
    if units is not None:
        scale = unit_scale(units, field="survey.files.units", file=file)
        if head is not None and not np.isclose(UNIT_METRES[head], scale, rtol=1e-12):
            raise ScenarioError(f"{path}: units = {units!r}, but the drawing's header says $INSUNITS = "
                                f"{doc.header.get('$INSUNITS')} ({head}); remove units or correct it",
                                field="survey.files.units", file=file)
        unit = units
    elif head is not None:
        unit, scale = head, UNIT_METRES[head]
    else:
        raise ScenarioError(f"{path}: the drawing does not state its units ($INSUNITS = "
                            f"{doc.header.get('$INSUNITS', 'absent')}); give units = \"m\" (or \"ft\", \"us_ft\", "
                            "\"mm\", ...) in its [[survey.files]] entry", field="survey.files.units", file=file)
    sagitta = chord_tolerance / scale
    data = SurveyData(path, "dxf", unit)
    data.notes.append(f"$ACADVER {doc.dxfversion}, $INSUNITS {doc.header.get('$INSUNITS', 'absent')}"
                      f" ({head or 'unitless'}), read as {unit}")
    skipped: Counter = Counter()
    out = data.entities

    def take(e, layer: str, ref: str) -> None:
        kind = e.dxftype()
        if kind == "INSERT":
            try:
                children = list(e.virtual_entities())
            except Exception as exc:  # a block ezdxf cannot place (non-uniform scaling of text, ...)
                skipped[f"INSERT ({type(exc).__name__})"] += 1
                return
            for j, child in enumerate(children):
                clayer = child.dxf.layer if child.dxf.layer not in ("0", "") else layer
                take(child, clayer, f"{ref}/{j + 1}")
            return
        got = _entity_points(e, kind, sagitta)
        if got is None:
            skipped[kind if kind != "POLYLINE" else "POLYLINE (mesh)"] += 1
            return
        geom, pts, closed, text = got
        if len(pts) == 0 or not math.isfinite(float(pts.sum())):
            skipped[f"{kind} (no finite coordinates)"] += 1
            return
        out.append(Entity(layer, ref, geom, pts * scale, closed, text, kind))

    for e in doc.modelspace():
        take(e, e.dxf.layer, e.dxf.handle or "?")
    data.skipped = skipped
    return data

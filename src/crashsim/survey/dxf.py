"""DXF drawings (R12 to current, ASCII or binary) read with ezdxf.

Taken: LINE, LWPOLYLINE, POLYLINE (2-D and 3-D; polyface and mesh are not), 3DFACE (the faces of a
TIN, with their elevations: the road's grade and cross-slope, kind = "surface"), ARC, CIRCLE,
ELLIPSE and SPLINE (as polylines whose chords lie within ``chord_tolerance`` of the curve),
POINT, TEXT and MTEXT (labels), and INSERT (the block's entities placed, scaled and turned by
ezdxf's virtual entities, on the INSERT's layer where they lie on layer 0). Z is dropped (the
scene is planar). Any other type is counted and named in one warning, never dropped silently.
"""

from __future__ import annotations

import math
import re
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
    except ezdxf.DXFStructureError as exc:
        first = exc
    try:  # ezdxf's recover module reads what it can of a damaged file, and says where it is damaged
        doc, auditor = recover.readfile(path)
    except Exception as exc:
        raise ScenarioError(f"the DXF file is damaged{_at_line(exc)} ({type(exc).__name__}: {exc})",
                            file=path) from None
    if auditor.has_errors:
        raise ScenarioError(f"the DXF file is damaged{_at_line(first)}: {len(auditor.errors)} errors, the first: "
                            f"{auditor.errors[0].message} (ezdxf: {first})", file=path)
    if not len(doc.modelspace()):
        raise ScenarioError(f"the DXF file is damaged{_at_line(first)}: {first} (recovered with no entities)",
                            file=path)
    return doc


def _at_line(exc) -> str:
    m = re.search(r"line (\d+)", str(exc))
    return f" at line {m[1]}" if m else ""


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


#: The unit of a drawing that states none, read for a listing only (``crashsim survey``).
UNITLESS = "unitless"


def _drawing_unit(path: str, insunits, units: str | None, file: str | None,
                  need_units: bool = True) -> tuple[str, float]:
    """(unit, metres per unit) of a drawing from its $INSUNITS and the scene file's units
    (``need_units`` False: a drawing without any is read as written, :data:`UNITLESS`)."""
    head = INSUNITS.get(int(insunits or 0))
    if units is not None:
        scale = unit_scale(units, field="survey.files.units", file=file)
        if head == "ft" and units.strip() in ("us_ft", "survey_foot"):
            return units, scale  # $INSUNITS has no code for the US survey foot before R2018: feet it says
        if head is not None and not np.isclose(UNIT_METRES[head], scale, rtol=1e-12):
            raise ScenarioError(f"{path}: units = {units!r}, but the drawing's header says $INSUNITS = "
                                f"{insunits} ({head}): one of them is wrong (they place the scene differently); "
                                f"give the unit its coordinates are in (the header's: units = \"{head}\")",
                                field="survey.files.units", file=file)
        return units, scale
    if head is not None:
        return head, UNIT_METRES[head]
    if not need_units:
        return UNITLESS, 1.0
    raise ScenarioError(f"{path}: the drawing does not state its units ($INSUNITS = "
                        f"{'absent' if insunits is None else insunits}); give units = \"m\" (or \"ft\", \"us_ft\", "
                        "\"mm\", ...) in its [[survey.files]] entry", field="survey.files.units", file=file)


def _header_note(version, insunits, unit: str) -> str:
    head = INSUNITS.get(int(insunits or 0))
    note = (f"$ACADVER {version}, $INSUNITS {'absent' if insunits is None else insunits} ({head or 'unitless'}), "
            f"read as {unit}")
    if head == "ft" and unit in ("us_ft", "survey_foot"):
        note += (" as units says (a DXF before R2018 has no $INSUNITS code for the US survey foot; the two feet "
                 "differ by 2 ppm, 0.6 m at 1,000,000 ft)")
    return note


def _read_dxf_fast(path: str, units: str | None, chord_tolerance: float, file: str | None,
                   need_units: bool = True) -> SurveyData:
    def scale_of(header):
        return _drawing_unit(path, header.get("$INSUNITS"), units, file, need_units)

    header, unit, ents = _read_fast(path, chord_tolerance, scale_of)
    data = SurveyData(path, "dxf", unit, ents)
    data.notes.append(_header_note(header.get("$ACADVER", "?"), header.get("$INSUNITS"), unit))
    return data


def read_dxf(path: str, units: str | None = None, *, chord_tolerance: float = 0.01,
             file: str | None = None, fast: bool = True, need_units: bool = True) -> SurveyData:
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
    need_units : bool
        False (a listing): a drawing that states no units is read as written, unit ``"unitless"``.
    fast : bool
        Read an ASCII drawing of only LINE, LWPOLYLINE (without bulges), POINT, TEXT, ARC and
        CIRCLE in world coordinates without building an ezdxf document (the same entities,
        several times faster); anything else, and ``fast=False``, goes through ezdxf.

    Raises
    ------
    ScenarioError
        An unreadable file, or drawing units missing or contradicting the header.
    """
    if fast:
        try:
            return _read_dxf_fast(path, units, chord_tolerance, file, need_units)
        except ScenarioError:
            raise
        except (_NotFast, ValueError, IndexError, KeyError):  # a type or quirk the fast path leaves to ezdxf
            pass
    doc = _open(path)
    unit, scale = _drawing_unit(path, doc.header.get("$INSUNITS"), units, file, need_units)
    sagitta = chord_tolerance / scale
    data = SurveyData(path, "dxf", unit)
    data.notes.append(_header_note(doc.dxfversion, doc.header.get("$INSUNITS"), unit))
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
        if kind == "3DFACE":  # a TIN face: its vertices with their elevation (kind = "surface")
            v = np.asarray([(p[0], p[1], p[2]) for p in (e.dxf.vtx0, e.dxf.vtx1, e.dxf.vtx2, e.dxf.vtx3)], dtype=float)
            if np.allclose(v[3], v[2], rtol=0, atol=0):
                v = v[:3]  # a triangle (its fourth vertex repeats the third)
            if np.all(np.isfinite(v)):
                data.faces.append((layer, ref, v * scale))
                return
        got = _entity_points(e, kind, sagitta)
        if got is None:
            skipped[kind if kind != "POLYLINE" else "POLYLINE (mesh)"] += 1
            data.skipped_layers[(layer, kind if kind != "POLYLINE" else "POLYLINE (mesh)")] += 1
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


# ------------------------------------------------------------------------------------------
# Fast path: ASCII drawings whose model space holds only the simplest entities

#: Entity types the fast path reads itself; a drawing with any other type in its ENTITIES
#: section (INSERT, POLYLINE, MTEXT, SPLINE, ...) is read by ezdxf in full instead.
_FAST_TYPES = frozenset({"LINE", "LWPOLYLINE", "POINT", "TEXT", "ARC", "CIRCLE"})


class _NotFast(Exception):
    """The drawing needs ezdxf (a type or a feature the fast path does not read)."""


def _fast_tags(path: str):
    """(header dict, list of entities as (type, [(code, value), ...])) of an ASCII DXF, or
    raise _NotFast."""
    with open(path, "rb") as fh:
        head = fh.read(22)
        if head.startswith(b"AutoCAD Binary DXF"):
            raise _NotFast("binary")
        raw = head + fh.read()
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        text = raw.decode("cp1252", errors="replace")
    lines = text.splitlines()
    n = len(lines)
    i = 0
    while i < n and lines[i].strip() == "999":  # comments before the first SECTION
        i += 2
    header: dict = {}
    ents: list = []
    section = None
    cur = None
    seen = False
    while i + 1 < n:
        code = lines[i].strip()
        value = lines[i + 1]
        i += 2
        if code == "0":
            value = value.strip()
            if cur is not None:
                ents.append(cur)
                cur = None
            if value == "SECTION":
                seen = True
                name = lines[i + 1].strip() if i + 1 < n else ""
                section = name
                i += 2
                continue
            if value in ("ENDSEC", "EOF"):
                section = None
                continue
            if section == "ENTITIES":
                if value not in _FAST_TYPES:
                    raise _NotFast(value)
                cur = (value, [])
            continue
        if section == "HEADER":
            if code == "9":
                var = value.strip()
                if var in ("$INSUNITS", "$ACADVER"):
                    header[var] = lines[i + 1].strip() if i + 1 < n else ""
        elif cur is not None:
            cur[1].append((int(code), value))
    if cur is not None:
        ents.append(cur)
    if not seen:
        raise _NotFast("no sections")
    if section is not None or not any(ln.strip() == "EOF" for ln in lines[-4:]):
        where = f"inside the {section} section (no ENDSEC, no EOF)" if section else "without EOF"
        raise ScenarioError(f"the DXF file is damaged at line {n}: it ends there {where}; a truncated copy? "
                            "(crashsim survey FILE lists what it holds)", file=path)
    return header, ents


def _fast_entity(kind: str, tags: list, sagitta: float):
    """(layer, handle, geometry, points, closed, text) of one fast-path entity; None for a
    paper-space one."""
    layer, handle, text = "0", "?", ""
    xs, ys = [], []
    vals: dict = {}
    closed = False
    for code, v in tags:
        if code == 8:
            layer = v.strip()
        elif code == 5:
            handle = v.strip()
        elif code == 67 and v.strip() == "1":
            return None
        elif code == 10:
            xs.append(float(v))
        elif code == 20:
            ys.append(float(v))
        elif code == 1 and kind == "TEXT":
            text = v
        elif code in (210, 220, 230):
            vals[code] = float(v)
        elif code == 42 and float(v) != 0.0:
            raise _NotFast("bulge")
        elif code == 70 and kind == "LWPOLYLINE":
            closed = bool(int(v) & 1)
        elif code == 38 and float(v) != 0.0:
            raise _NotFast("elevation")
        elif code in (11, 21, 40, 50, 51, 72, 73):
            vals[code] = float(v) if code not in (72, 73) else int(v)
    if vals.get(210, 0.0) != 0.0 or vals.get(220, 0.0) != 0.0 or vals.get(230, 1.0) != 1.0:
        raise _NotFast("extrusion")
    if kind == "TEXT" and (vals.get(72, 0) or vals.get(73, 0)):
        raise _NotFast("aligned text")  # its place is the alignment point: ezdxf knows the rules
    if kind == "LWPOLYLINE":
        return layer, handle, "line", np.column_stack([xs, ys]), closed, ""
    if kind == "LINE":
        return layer, handle, "line", np.array([[xs[0], ys[0]], [vals[11], vals[21]]]), False, ""
    if kind == "POINT":
        return layer, handle, "point", np.array([[xs[0], ys[0]]]), False, ""
    if kind == "TEXT":
        return layer, handle, "text", np.array([[xs[0], ys[0]]]), False, text
    # ARC and CIRCLE with ezdxf's own construction (the vertices its entities' flattening gives)
    from ezdxf.math import ConstructionArc, Vec3, arc_segment_count

    center, radius = (xs[0], ys[0]), abs(vals[40])
    if kind == "CIRCLE":
        if radius == 0.0:
            raise _NotFast("zero radius")
        count = arc_segment_count(radius, math.tau, sagitta)
        c = Vec3(center)
        pts = _xy([c + Vec3.from_deg_angle(a, radius) for a in np.linspace(0.0, 360.0, count + 1)])
        return layer, handle, "line", pts[:-1] if np.allclose(pts[0], pts[-1]) else pts, True, ""
    if math.isclose(vals.get(50, 0.0) % 360.0, vals.get(51, 360.0) % 360.0) or radius == 0.0:
        raise _NotFast("degenerate arc")  # ezdxf's reading decides what it is
    arc = ConstructionArc(center, radius, vals.get(50, 0.0), vals.get(51, 360.0))
    return layer, handle, "line", _xy(arc.flattening(sagitta)), False, ""


def _read_fast(path: str, sagitta_m: float, scale_of):
    """The entities of an ASCII DXF of only LINE, LWPOLYLINE, POINT, TEXT, ARC and CIRCLE
    (straight, flat, in world coordinates), read without building an ezdxf document: the
    same entities :func:`read_dxf` gives through ezdxf (tests compare them). ``scale_of(header)``
    returns (unit, metres per unit). Raises _NotFast for anything else."""
    header, ents = _fast_tags(path)
    unit, scale = scale_of(header)
    sagitta = sagitta_m / scale
    out = []
    for kind, tags in ents:
        got = _fast_entity(kind, tags, sagitta)
        if got is None:
            continue
        layer, handle, geom, pts, closed, text = got
        if len(pts) == 0 or not math.isfinite(float(pts.sum())):
            raise _NotFast("non-finite")
        out.append(Entity(layer, handle, geom, pts * scale, closed, text, kind))
    return header, unit, out

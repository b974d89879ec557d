"""A first look at a survey file: layers or codes with entity counts and extents, and a preview."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..errors import ScenarioError
from .dxf import UNITLESS, read_dxf
from .frame import UNIT_METRES
from .geojson import read_geojson
from .mapping import SURVEY_FORMATS
from .points import read_points

__all__ = ["read_any", "summary", "preview"]


def read_any(path: str, *, units: str | None = None, columns: str = "PNEZD", crs: str | None = None,
             layer_property: str = "layer"):
    """Read a survey file by its extension (.dxf; .csv/.txt/.asc/.pnezd points; .geojson/.json)."""
    fmt = SURVEY_FORMATS.get(Path(path).suffix.lower())
    if not Path(path).is_file():
        raise ScenarioError(f"{path}: no such file", field="file")
    if fmt == "dxf":
        data = read_dxf(path, units, need_units=False)  # a listing needs no units
        if data.unit == UNITLESS:
            data.notes.append("the drawing does not state its units ($INSUNITS): coordinates as written; a scene "
                              "that maps it needs units = \"m\" (or \"ft\", \"us_ft\", ...) in its [[survey.files]] "
                              "entry")
        return data
    if fmt == "points":
        return read_points(path, units or "m", columns)
    if fmt == "geojson":
        note = None
        if crs is None:
            crs, note = _utm_for(path)
        data = read_geojson(path, crs, layer_property=layer_property)
        if note:
            data.notes.insert(0, note)
        return data
    raise ScenarioError(f"{path}: cannot tell the format from the extension {Path(path).suffix!r}; allowed .dxf, "
                        ".csv, .txt, .asc, .pnezd, .geojson, .json", field="file")


def _utm_for(path: str):
    """(UTM zone CRS, note) for a lon/lat GeoJSON shown without --crs; (None, None) otherwise."""
    try:
        doc = json.loads(Path(path).read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None, None
    if doc.get("crs"):
        return None, None

    def first(c):
        while isinstance(c, list) and c and isinstance(c[0], list):
            c = c[0]
        return c

    for f in doc.get("features") or []:
        c = first((f.get("geometry") or {}).get("coordinates"))
        if isinstance(c, list) and len(c) >= 2 and abs(c[0]) <= 180 and abs(c[1]) <= 90:
            zone = int((c[0] + 180) // 6) % 60 + 1
            epsg = (32600 if c[1] >= 0 else 32700) + zone
            return f"EPSG:{epsg}", (f"longitude/latitude shown in UTM zone {zone}{'N' if c[1] >= 0 else 'S'} "
                                    f"(EPSG:{epsg}); give --crs for another")
    return None, None


def summary(data) -> str:
    """The layers or codes of a survey file with entity counts by type and extents (in its unit)."""
    k = UNIT_METRES.get(data.unit, 1.0)
    unit = data.unit if data.unit in UNIT_METRES or data.unit == UNITLESS else "m"
    what = {"dxf": "layer", "points": "code", "geojson": "layer"}[data.format]
    lines = [f"{data.path}: {data.format}, {len(data.entities)} entities, coordinates in {data.unit}"]
    lines += [f"  note: {n}" for n in data.notes]
    rows = []
    taken = data.layers()
    left: dict = {}
    for (layer, kind), n in getattr(data, "skipped_layers", {}).items():
        left.setdefault(layer, []).append(f"{n} {kind} (not imported)")
    for layer in sorted(set(taken) | set(left)):
        counts = taken.get(layer)
        parts = [f"{n} {t}" for t, n in counts.most_common()] if counts else []
        parts += sorted(left.get(layer, []))
        if counts:
            lo, hi = data.extents(layer)
            ext = f"x {lo[0] / k:.3f} .. {hi[0] / k:.3f}, y {lo[1] / k:.3f} .. {hi[1] / k:.3f} {unit}"
        else:
            ext = "-"
        rows.append((layer or "(empty)", ", ".join(parts), ext))
    if rows:
        w0 = max(len(what), *(len(r[0]) for r in rows))
        w1 = max(len("entities"), *(len(r[1]) for r in rows))
        lines.append(f"  {what.ljust(w0)}  {'entities'.ljust(w1)}  extent")
        lines += [f"  {r[0].ljust(w0)}  {r[1].ljust(w1)}  {r[2]}" for r in rows]
    warn = data.skipped_warning()
    if warn:
        lines.append(f"  warning: {warn}")
    return "\n".join(lines)


def preview(data, path: str, dpi: int = 120) -> str:
    """Draw every entity, coloured by layer or code, in the file's unit; returns the path."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    k = UNIT_METRES.get(data.unit, 1.0)
    layers = sorted(data.layers())
    cmap = plt.get_cmap("tab20")
    fig, ax = plt.subplots(figsize=(9, 7))
    try:
        ext = data.extents()
        origin = np.zeros(2) if ext is None else np.floor(ext[0] / k / 100.0) * 100.0
        for i, layer in enumerate(layers):
            color = cmap(i % 20)
            first = True
            for e in (e for e in data.entities if e.layer == layer):
                p = e.points / k - origin
                if e.geometry == "line":
                    q = np.vstack([p, p[:1]]) if e.closed else p
                    ax.plot(q[:, 0], q[:, 1], "-", color=color, lw=0.8, label=layer if first else None)
                elif e.geometry == "point":
                    ax.plot(p[:, 0], p[:, 1], ".", color=color, ms=3, label=layer if first else None)
                else:
                    ax.text(p[0, 0], p[0, 1], e.text, fontsize=6, color=color)
                first = False
        ax.set_aspect("equal", adjustable="datalim")
        unit = data.unit if data.unit in UNIT_METRES else "m"
        ax.set_xlabel(f"x - {origin[0]:.0f} [{unit}]")
        ax.set_ylabel(f"y - {origin[1]:.0f} [{unit}]")
        ax.set_title(f"{Path(data.path).name}: {len(data.entities)} entities, {len(layers)} layers or codes",
                     fontsize=10)
        if 0 < len(layers) <= 30:
            ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.01, 0.5))
        ax.grid(True, color="0.9", lw=0.5)
        fig.tight_layout()
        fig.savefig(path, dpi=dpi)
    finally:
        plt.close(fig)
    return str(path)

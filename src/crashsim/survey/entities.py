"""What every survey reader returns: entities in metres of the survey's axes, each with its source."""

from __future__ import annotations

from collections import Counter
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Entity", "SurveyData"]


@dataclass(frozen=True, eq=False)
class Entity:
    """One drawn or measured thing of a survey file.

    Attributes
    ----------
    layer : str
        The DXF layer, the point code of a total-station string, or the GeoJSON property value
        that the scene file's mapping matches.
    ref : str
        Where it is in the file: a DXF entity handle (``"1A3"``; ``"1A3/2"`` for the second entity
        of the block an INSERT places), point numbers (``"101-107"``) or a feature index (``"#4"``).
    geometry : str
        ``"point"``, ``"line"`` or ``"text"``.
    points : ndarray, shape (n, 2)
        Survey coordinates [m] (units converted, scene frame not yet applied).
    closed : bool
        A closed outline (the last point joins the first; not repeated in ``points``).
    text : str
        The label of a TEXT/MTEXT entity ("" otherwise).
    dxftype : str
        The entity type it came from (``"LWPOLYLINE"``, ``"POINT"``, ``"Polygon"``, ``"PNEZD"``).
    """

    layer: str
    ref: str
    geometry: str
    points: np.ndarray
    closed: bool = False
    text: str = ""
    dxftype: str = ""


@dataclass
class SurveyData:
    """The entities of one survey file, and what was not taken.

    Attributes
    ----------
    path : str
    format : str
        ``"dxf"``, ``"points"`` or ``"geojson"``.
    unit : str
        The survey unit the coordinates were read in (converted to m in ``entities``).
    entities : list of Entity
    skipped : Counter
        Entity types the reader does not take, by type (reported in one warning).
    notes : list of str
        What the reader noticed (header units, strings closed, rows skipped).
    """

    path: str
    format: str
    unit: str
    entities: list = field(default_factory=list)
    skipped: Counter = field(default_factory=Counter)
    #: The entities not taken, by (layer, type): what ``crashsim survey`` lists beside the others
    skipped_layers: Counter = field(default_factory=Counter)
    #: Why every entity's layer or code is empty, where the reader can tell (no D column, no feature
    #: with the layer property): said where a map entry matches nothing
    empty_layers: str = ""
    notes: list = field(default_factory=list)
    #: The faces of a TIN (DXF 3DFACE): (layer, handle, vertices (n, 3) [m] in the survey's axes, z up);
    #: a map entry of kind "surface" makes them the road's grade and cross-slope
    faces: list = field(default_factory=list)

    def layers(self) -> dict[str, Counter]:
        """Entity counts by geometry (and type) for each layer or code (TIN faces as 3DFACE)."""
        out: dict[str, Counter] = {}
        for e in self.entities:
            out.setdefault(e.layer, Counter())[e.dxftype or e.geometry] += 1
        for layer, _, _ in self.faces:
            out.setdefault(layer, Counter())["3DFACE"] += 1
        return out

    def extents(self, layer: str | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """(min, max) of the coordinates [m] of a layer's entities (all with None); None if empty."""
        pts = [e.points for e in self.entities if layer is None or e.layer == layer]
        pts += [v[:, :2] for lay, _, v in self.faces if layer is None or lay == layer]
        if not pts:
            return None
        a = np.vstack(pts)
        return a.min(axis=0), a.max(axis=0)

    def skipped_warning(self) -> str | None:
        """One line naming every entity type not taken, with its count; None if none."""
        if not self.skipped:
            return None
        parts = ", ".join(f"{n} {t}" for t, n in sorted(self.skipped.items(), key=lambda kv: (-kv[1], kv[0])))
        return (f"{self.path}: {sum(self.skipped.values())} entities of types the importer does not take were left "
                f"out: {parts}")

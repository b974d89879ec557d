"""Survey units and the scene frame: large survey coordinates to the scene's local metres, and back.

Units are converted once, here, at the edge: a reader returns coordinates in metres of the
survey's own axes; :class:`SceneFrame` moves them to the scene frame (origin subtracted, then
turned by ``-rotation``), and :meth:`SceneFrame.to_survey` takes scene points back to the
survey's axes and units (CAD export).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass

import numpy as np

from ..errors import ScenarioError

__all__ = ["UNIT_METRES", "INSUNITS", "unit_scale", "SceneFrame"]

#: Metres per survey unit. ``us_ft`` is the US survey foot (1200/3937 m), the unit of most US
#: State Plane coordinates in feet; it differs from the international foot (0.3048 m) by 2 ppm,
#: which is 0.6 m at 1,000,000 ft.
UNIT_METRES = {
    "m": 1.0, "mm": 1e-3, "cm": 1e-2, "dm": 0.1, "km": 1e3,
    "in": 0.0254, "ft": 0.3048, "us_ft": 1200.0 / 3937.0, "survey_foot": 1200.0 / 3937.0, "yd": 0.9144, "mi": 1609.344,
}
#: DXF header ``$INSUNITS`` codes (DXF reference, HEADER section) and the unit each names.
INSUNITS = {1: "in", 2: "ft", 3: "mi", 4: "mm", 5: "cm", 6: "m", 7: "km", 10: "yd", 14: "dm", 21: "us_ft"}


def unit_scale(unit: str, *, field: str = "units", file: str | None = None) -> float:
    """Metres per ``unit`` (one of :data:`UNIT_METRES`)."""
    key = str(unit).strip()
    if key not in UNIT_METRES:
        near = difflib.get_close_matches(key, list(UNIT_METRES), n=1)
        hint = f"; did you mean {near[0]!r}?" if near else ""
        raise ScenarioError(f"unknown survey unit {unit!r}{hint} Allowed: {', '.join(UNIT_METRES)}", field=field,
                            file=file)
    return UNIT_METRES[key]


@dataclass(frozen=True)
class SceneFrame:
    """Where the scene frame lies in the survey's axes.

    Attributes
    ----------
    origin : (float, float)
        Survey coordinates [m] (easting/x, northing/y) of the scene origin.
    rotation : float
        Direction of the scene's +X axis in the survey's axes [rad], counter-clockwise from the
        survey's +x (east). ``scene = R(-rotation) (p - origin)``.
    """

    origin: tuple[float, float] = (0.0, 0.0)
    rotation: float = 0.0

    def to_scene(self, pts) -> np.ndarray:
        """Survey points [m], shape (n, 2), in the scene frame [m]."""
        p = np.asarray(pts, dtype=float).reshape(-1, 2) - np.asarray(self.origin, dtype=float)
        if self.rotation == 0.0:
            return p
        c, s = math.cos(self.rotation), math.sin(self.rotation)
        return np.column_stack([c * p[:, 0] + s * p[:, 1], -s * p[:, 0] + c * p[:, 1]])

    def to_survey(self, pts) -> np.ndarray:
        """Scene points [m], shape (n, 2), in the survey's axes [m] (the inverse of :meth:`to_scene`)."""
        p = np.asarray(pts, dtype=float).reshape(-1, 2)
        if self.rotation != 0.0:
            c, s = math.cos(self.rotation), math.sin(self.rotation)
            p = np.column_stack([c * p[:, 0] - s * p[:, 1], s * p[:, 0] + c * p[:, 1]])
        return p + np.asarray(self.origin, dtype=float)

"""The validation suite's records: a compared quantity, a case's result, the metrics and their bands.

Every comparison is one :class:`Quantity`: a measured value (as published, in SI), the value crashsim
computes for it, the error by the quantity's metric and the acceptance band with its basis. The
metrics follow the roadside-safety verification and validation procedures (NCHRP Web-Only Document
179, 2011, and its RSVVP program) for scalar results: the relative error of a peak or final value
(a speed, a delta-v, a stopping distance), the difference of an angle (an angle's relative error has
no meaning), the distance between computed and measured positions relative to the path length
(Day2004's range error, the anchors' metric). None of the suite's sources publish time histories in
text, so no time-history metric (RSVVP's Sprague-Geers or ANOVA) is computed: ``validation/README.md``.

SI inside; ``display`` names the unit system of the published source (values are shown in it unless
asked otherwise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from pathlib import Path

from ..errors import ScenarioError
from ..schema import load_toml
from ..units import Kind, parse, parse_vector

__all__ = ["METRICS", "Quantity", "CaseResult", "read_case", "quantity", "vector", "angle_difference", "STATUS"]

#: How a quantity's error is measured; the band is on the same measure.
METRICS = {
    "relative": "(computed - measured) / |measured|",
    "difference": "computed - measured",
    "range": "distance between the computed and the measured position / measured path length (Day2004)",
    "limit": "computed - limit (at most 0 passes)",
    "criterion": "1 if the published criterion holds, else 0 (passes at 1)",
}

#: A quantity's status against its band and the case's record of documented misses.
STATUS = ("within", "miss (documented)", "MISS", "within (documented miss: record stale)")


@dataclass(frozen=True)
class Quantity:
    """One compared quantity of a case (SI values).

    Attributes
    ----------
    case, name : str
        The case id and the quantity's name within it ("delta-v, pinto").
    group : str
        What kind of result it is ("delta-v", "separation velocity", "rest position", ...): errors are
        summarised per group and case class.
    kind : str
        Physical kind of ``measured`` and ``computed`` (a :class:`crashsim.units.Kind` value).
    measured, computed : float
        The published value (for several published reductions: their mean) and crashsim's value.
    metric : str
        A key of :data:`METRICS`.
    error : float
        The error by the metric: a fraction for ``relative`` and ``range``, SI for ``difference``.
    band : float
        Half-width of the acceptance band on ``error`` (same measure).
    basis : str
        Where the band comes from ("scatter: ...", "anchors: ...", "stated: ...").
    source : str
        Where the measured value is published (report, table, page).
    anchors : dict
        The errors of published methods on the same quantity (same measure as ``error``), by name.
    display : str
        "SI" or "US": the unit system of the source.
    note : str
        What was assumed for this quantity, if anything particular.
    """

    case: str
    name: str
    group: str
    kind: str
    measured: float
    computed: float
    metric: str
    error: float
    band: float
    basis: str
    source: str
    anchors: dict = field(default_factory=dict)
    display: str = "SI"
    note: str = ""
    status: str = ""

    @property
    def within(self) -> bool:
        """The error lies inside its band (one-sided for a limit; a NaN error never does)."""
        if not math.isfinite(self.error):
            return False
        return bool(self.error <= self.band) if self.metric == "limit" else bool(abs(self.error) <= self.band)

    def with_record(self, documented_misses) -> "Quantity":
        """This quantity with its status against the case's documented misses."""
        documented = self.name in documented_misses
        if self.within:
            status = STATUS[3] if documented else STATUS[0]
        else:
            status = STATUS[1] if documented else STATUS[2]
        return replace(self, status=status)

    def to_dict(self) -> dict:
        return {"case": self.case, "name": self.name, "group": self.group, "kind": self.kind,
                "measured": self.measured, "computed": self.computed, "metric": self.metric, "error": self.error,
                "band": self.band, "within": self.within, "status": self.status, "basis": self.basis,
                "source": self.source, "anchors": dict(self.anchors), "display": self.display, "note": self.note}


@dataclass(frozen=True)
class CaseResult:
    """A case's quantities, what it assumed, and what its figure needs (SI)."""

    id: str
    title: str
    kind: str
    case_class: str
    configuration: str
    quantities: tuple[Quantity, ...]
    assumptions: tuple[str, ...] = ()
    figure: dict = field(default_factory=dict)
    cpu_seconds: float = 0.0
    record: dict = field(default_factory=dict)

    @property
    def new_misses(self) -> list[Quantity]:
        return [q for q in self.quantities if q.status in (STATUS[2], STATUS[3])]

    def to_dict(self) -> dict:
        return {"id": self.id, "title": self.title, "kind": self.kind, "class": self.case_class,
                "configuration": self.configuration, "cpu_seconds": self.cpu_seconds,
                "assumptions": list(self.assumptions), "quantities": [q.to_dict() for q in self.quantities]}


def read_case(folder: Path) -> dict:
    """A case folder's ``measured.toml`` (its ``[case]`` table checked), and its ``record.toml`` of
    documented misses under ``"record"`` (empty if there is none)."""
    path = folder / "measured.toml"
    data = load_toml(path)
    case = data.get("case")
    if not isinstance(case, dict):
        raise ScenarioError("no [case] table (id, kind, title, class)", field="case", file=str(path))
    for key in ("id", "kind", "title", "class"):
        if not isinstance(case.get(key), str) or not case[key]:
            raise ScenarioError(f"case.{key} is missing; allowed a non-empty string", field=f"case.{key}",
                                file=str(path))
    if case["id"] != folder.name:
        raise ScenarioError(f"case.id = {case['id']!r} differs from its folder's name {folder.name!r}; allowed "
                            f"{folder.name!r}", field="case.id", file=str(path))
    record_path = folder / "record.toml"
    record = load_toml(record_path) if record_path.is_file() else {}
    misses = record.get("misses", [])
    if not isinstance(misses, list) or not all(isinstance(m, dict) and isinstance(m.get("quantity"), str)
                                               and isinstance(m.get("why"), str) for m in misses):
        raise ScenarioError("misses must be a list of {quantity = \"...\", why = \"...\"}", field="misses",
                            file=str(record_path))
    data["record"] = {m["quantity"]: m["why"] for m in misses}
    data["folder"] = folder
    return data


def quantity(value, kind: Kind, where: str, file: Path | None = None) -> float:
    """A published value with its unit (``"251 cm"``, ``"64877 ft-lb"``) in SI."""
    return parse(value, kind, field=where, file=str(file) if file else None)


def vector(value, kind: Kind, where: str, file: Path | None = None, n: int | None = 2):
    """A list of published values with their units, in SI."""
    return parse_vector(value, kind, n, field=where, file=str(file) if file else None)


def angle_difference(a: float, b: float) -> float:
    """a - b wrapped to [-pi, pi) [rad]."""
    return (a - b + math.pi) % (2 * math.pi) - math.pi

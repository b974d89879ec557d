"""The outcome of one evidence item: :class:`Check` (residual, tolerance, verdict).

Shared by the evidence checks (:mod:`crashsim.evidence.checks`) and the crush-energy checks
(:mod:`crashsim.evidence.crush`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["Check"]


@dataclass(frozen=True)
class Check:
    """Outcome of one evidence item.

    Attributes
    ----------
    kind : {"rest", "rest heading", "mark", "point of impact", "delta-v", "crush energy"}
    name : str
    residual : float
        Computed minus measured (or a distance) in SI: m, rad or m/s (``quantity`` says which);
        ``inf`` if the computation has nothing to compare (no run-out, no track).
    tolerance : float
        The user's tolerance for this item, same unit.
    passed : bool
        ``abs(residual) <= tolerance``.
    quantity : str
        Unit kind of residual and tolerance ("length", "angle", "speed", "energy").
    details : dict
        Computed and measured values and any extra figure (mean distance, matched wheel).
    """

    kind: str
    name: str
    residual: float
    tolerance: float
    passed: bool
    quantity: str
    details: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        return {"kind": self.kind, "name": self.name, "residual": self.residual, "tolerance": self.tolerance,
                "passed": self.passed, "quantity": self.quantity, "details": self.details}

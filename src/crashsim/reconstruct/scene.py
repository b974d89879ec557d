"""A whole scene: impact, then (when the scenario asks for it) run-out and evidence checks."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..impact import ImpactResult, solve_impact

__all__ = ["SceneResult", "run_scene"]


@dataclass(frozen=True)
class SceneResult:
    """Everything computed for one scenario (SI, world frame of the scene).

    Attributes
    ----------
    scenario : Scenario
        The loaded scenario (inputs, converted to SI).
    impact : ImpactResult
    """

    scenario: Any
    impact: ImpactResult
    extras: dict = field(default_factory=dict)

    def to_dict(self) -> dict:
        sc = self.scenario
        return {
            "scenario": {"title": sc.title, "source": sc.source, "file": sc.path},
            "units": "SI",
            "impact": self.impact.to_dict(),
        }

    def report(self, system: str = "SI") -> str:
        from ..report import format_impact

        sc = self.scenario
        head = [f"crashsim: {sc.title}"]
        if sc.source:
            head.append(f"source: {sc.source}")
        if sc.path:
            head.append(f"file: {sc.path}")
        head.append(f"units: {system}")
        return "\n".join(head) + "\n\n" + format_impact(self.impact, system)

    def write_csv(self, directory: Path) -> list[Path]:
        """Write time histories (none for an impact-only scene); returns the files written."""
        directory.mkdir(parents=True, exist_ok=True)
        return []


def run_scene(scenario) -> SceneResult:
    """Solve a loaded scenario: the impact (and, later, run-out and evidence)."""
    impact = solve_impact(scenario.impact)
    return SceneResult(scenario=scenario, impact=impact)

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
    runout: dict | None = None  # vehicle name -> RunoutResult
    evidence: Any = None  # EvidenceReport or None

    def runout_body(self, name: str):
        """The BodyRunout of a body (KeyError if the scene has no run-out or no such body)."""
        if self.runout is None:
            raise KeyError("this scene has no run-out")
        for r in self.runout.values():
            if name in r.bodies:
                return r.bodies[name]
        raise KeyError(name)

    def to_dict(self, *, history: bool = False) -> dict:
        """JSON-ready result (SI units, world frame). ``history`` adds sampled time histories."""
        sc = self.scenario
        out = {
            "scenario": {"title": sc.title, "source": sc.source, "file": sc.path},
            "units": "SI",
            "impact": self.impact.to_dict(),
        }
        if self.runout is not None:
            bodies = {}
            for r in self.runout.values():
                for name, b in r.bodies.items():
                    bodies[name] = {
                        "vehicle": r.vehicle,
                        "rest": {"x": float(b.rest_position[0]), "y": float(b.rest_position[1]),
                                 "heading": float(b.rest_heading_wrapped)},
                        "time_to_rest": b.time_to_rest,
                        "distance": float(b.distance),
                    }
            out["runout"] = {
                "bodies": bodies,
                "vehicles": {name: r.to_dict(history=history) for name, r in self.runout.items()},
            }
        if self.evidence is not None:
            out["evidence"] = self.evidence.to_dict()
        return out

    def report(self, system: str = "SI") -> str:
        from ..report import format_impact

        sc = self.scenario
        head = [f"crashsim: {sc.title}"]
        if sc.source:
            head.append(f"source: {sc.source}")
        if sc.path:
            head.append(f"file: {sc.path}")
        head.append(f"units: {system}")
        text = "\n".join(head) + "\n\n" + format_impact(self.impact, system)
        if self.runout is not None:
            from ..report import format_runout

            text += "\n\n" + format_runout(self.runout, system)
        if self.evidence is not None:
            from ..report import format_evidence

            text += "\n\n" + format_evidence(self.evidence, system)
        return text

    def write_csv(self, directory: Path) -> list[Path]:
        """Write time histories (none for an impact-only scene); returns the files written."""
        directory.mkdir(parents=True, exist_ok=True)
        return []


def separation_states(scenario, impact: ImpactResult) -> dict:
    """Body states at separation: impact positions and headings, post-impact velocities."""
    from ..vehicles import BodyState

    out = {}
    for name, b in impact.bodies.items():
        if b.fixed:
            continue
        s0 = scenario.states[name]
        out[name] = BodyState(s0.position, s0.heading, tuple(b.velocity), b.yaw_rate)
    return out


def run_scene(scenario) -> SceneResult:
    """Solve a loaded scenario: the impact, then the run-out of every vehicle if asked for."""
    impact = solve_impact(scenario.impact)
    runout = None
    if scenario.runout is not None:
        from ..motion import make_hitch_consistent, simulate_runout

        states = separation_states(scenario, impact)
        spec = scenario.runout
        runout = {}
        for veh in scenario.vehicles:
            if veh.is_barrier:
                continue
            initial = make_hitch_consistent(veh, {b.name: states[b.name] for b in veh.bodies})
            runout[veh.name] = simulate_runout(veh, initial, spec.wheels[veh.name], spec.road, spec.options)
    evidence = None
    if not scenario.evidence.empty:
        from .evidence import evaluate_evidence

        evidence = evaluate_evidence(scenario.evidence, impact, runout, scenario.impact.surface.point)
    return SceneResult(scenario=scenario, impact=impact, runout=runout, evidence=evidence)

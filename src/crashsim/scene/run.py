"""A whole scene: impact, then (when the scenario asks for it) run-out and evidence checks."""

from __future__ import annotations

import csv
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from ..animation import animate_scene
from ..errors import ScenarioError, with_file
from ..evidence.checks import REST_MISFIT_SHARE, evaluate_evidence, wheel_matches
from ..impact import ImpactResult, solve_impact
from ..impact.problem import ImpactProblem
from ..motion import make_hitch_consistent
from ..motion.approach import continued_wheels, simulate_approach
from ..motion.result import time_grid
from ..motion.runout import CONTACT_LEVELS, run_runout
from ..motion.wheels import enumerate_wheels, wheel_labels
from ..plotting import plot_scene
from ..report import (format_approach, format_crush, format_events, format_evidence, format_impact,
                      format_joint, format_runout, message_in)
from ..survey.report import format_survey, survey_records
from ..units import Kind, format_value, resolve_system, speed_unit_of, system_label, to_unit
from ..vehicles import BodyState, chain_states
from .models import ModelReuse, scene_model

__all__ = ["SceneResult", "run_scene", "rest_misfit_warnings", "simulate_approaches"]


def rest_misfit_warnings(evidence) -> list[str]:
    """A warning for each rest item whose measured points fit the body with an RMS misfit above
    :data:`~crashsim.evidence.checks.REST_MISFIT_SHARE` of its tolerance (SI text)."""
    out = []
    for r in getattr(evidence, "rest", ()):
        reg = r.registration
        if reg is not None and reg.rms > REST_MISFIT_SHARE * r.tolerance:
            worst = reg.labels[int(reg.misfit.argmax())]
            out.append(f"{r.name or 'rest of ' + r.body}: the measured points fit the body with an RMS misfit of "
                       f"{reg.rms:.4g} m, more than {REST_MISFIT_SHARE:g} x its tolerance {r.tolerance:.4g} m (largest "
                       f"{float(max(reg.misfit)):.4g} m at {worst}): a point may be mislabelled or mismeasured, and "
                       "the CG and heading derived from them are doubtful")
    return out


def _format_registrations(evidence, system: str) -> str:
    """Lines for the rest items derived from measured points: the derived CG and heading, the fit's misfit."""
    lines = []
    for r in evidence.rest:
        reg = r.registration
        if reg is None:
            continue
        L = lambda v: format_value(v, Kind.LENGTH, system)  # noqa: E731
        lines.append(f"  {r.name or 'rest of ' + r.body}: CG ({L(reg.position[0])}, {L(reg.position[1])}), heading "
                     f"{format_value(reg.heading, Kind.ANGLE, system)} from {len(reg.labels)} measured points "
                     f"(rigid least-squares fit; RMS misfit {L(reg.rms)}, largest {L(float(max(reg.misfit)))} at "
                     f"{reg.labels[int(reg.misfit.argmax())]})")
    if not lines:
        return ""
    return "\n\nRest positions from measured points of the body\n" + "\n".join(lines)


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
    warnings: tuple[str, ...] = ()
    accuracy: dict | None = None  # vehicle name -> AccuracyReport, when the scenario asks for an accuracy
    joint: Any = None  # SceneRunout: the run-out of the whole scene (impacts, pairs, events, energy ledger)

    @property
    def at_rest(self) -> bool:
        """True if there is no run-out or every run-out ended at rest."""
        return self.runout is None or all(r.success for r in self.runout.values())

    def rollover(self) -> dict:
        """By vehicle, its wheel-lift and rollover summary (:attr:`RunoutResult.rollover`); empty when the
        check is off."""
        return {v: {k: x for k, x in r.rollover.items() if k != "history"}  # the sampled indicators: figures only
                for v, r in (self.runout or {}).items() if getattr(r, "rollover", None) is not None}

    def energy_ledger(self) -> dict | None:
        """The scene's energy ledger from the approach to rest [J] (None without a joint run-out).

        ``before_impact`` = ``first_impact`` (loss in the first impact) + ``later_impacts`` +
        ``tyres`` + ``stops`` + ``contacts`` + ``final`` + ``closing_error`` (+ ``potential``, the
        potential energy gained, on a sloped road).
        """
        if self.joint is None:
            return None
        e = self.joint.energy
        ke = self.impact.kinetic_energy["system"]
        first = ke["before"] - ke["after"]
        ledger = {"before_impact": ke["before"], "first_impact": first, "later_impacts": e["impacts"],
                  "tyres": e["tyres"], "stops": e["stops"], "contacts": e["contacts"], "final": e["final"]}
        if "potential" in e:  # a sloped road: the potential energy gained
            ledger["potential"] = e["potential"]
        # kinetic energy of bystanders (not in the first impact) is in the run-out's initial energy
        bystanders = e["initial"] - ke["after"]
        ledger["before_impact"] += bystanders
        ledger["closing_error"] = ledger["before_impact"] - sum(v for k, v in ledger.items() if k != "before_impact")
        return ledger

    def runout_body(self, name: str):
        """The BodyRunout of a body (KeyError if the scene has no run-out or no such body)."""
        if self.runout is None:
            raise KeyError("this scene has no run-out")
        for r in self.runout.values():
            if name in r.bodies:
                return r.bodies[name]
        raise KeyError(name)

    @property
    def impacts(self) -> list[dict]:
        """Every impact in time order, the first (t = 0) and those of the run-out (SI, world frame).

        Each: ``time`` [s] after the first separation, ``event`` (the number reports and figures give it: 1
        for the first; the pairs of one instant, and its bounces, share one), ``body1``, ``body2``, ``point`` [m],
        ``normal``, ``normal_impulse`` and ``tangential_impulse`` [N s], ``energy_loss`` [J] (kinetic)
        and its parts by the work of the impulses ``energy_loss_normal``, ``energy_loss_tangential``,
        ``energy_loss_moment`` [J], ``delta_v`` (per body of the two vehicles: ``vector`` [m/s] and ``magnitude``).
        """
        imp = self.impact
        ke = imp.kinetic_energy["system"]
        first = {"time": 0.0, "event": 1, "body1": imp.body1, "body2": imp.body2, "point": [float(v) for v in imp.point],
                 "normal": [float(v) for v in imp.normal], "normal_impulse": imp.normal_impulse,
                 "tangential_impulse": imp.tangential_impulse, "energy_loss": ke["before"] - ke["after"],
                 "closing_speed": -imp.closing_velocity, "law": imp.tangential_law,
                 "energy_loss_normal": imp.energy_loss_normal, "energy_loss_tangential": imp.energy_loss_tangential,
                 "energy_loss_moment": imp.energy_loss_moment,
                 "delta_v": {n: {"vector": [float(v) for v in b.delta_v], "magnitude": b.delta_v_magnitude}
                             for n, b in imp.bodies.items() if not b.fixed}}
        later = [i.to_dict() for i in self.joint.impacts] if self.joint is not None else []
        return [first] + later

    def to_dict(self, *, history: bool = False) -> dict:
        """JSON-ready result (SI units, world frame). ``history`` adds sampled time histories."""
        sc = self.scenario
        out = {
            "scenario": {"title": sc.title, "source": sc.source, "file": sc.path},
            "units": "SI",
            "impact": self.impact.to_dict(),
            "impacts": self.impacts,
        }
        if self.runout is not None:
            bodies = {}
            for r in self.runout.values():
                for name, b in r.bodies.items():
                    at_rest = b.time_to_rest is not None
                    body = next(bb for v in sc.vehicles for bb in v.bodies if bb.name == name)
                    outline = body.outline()
                    bodies[name] = {
                        "vehicle": r.vehicle,
                        "at_rest": at_rest,
                        "rest": {"x": float(b.rest_position[0]), "y": float(b.rest_position[1]),
                                 "heading": float(b.rest_heading_wrapped)},
                        "time_to_rest": b.time_to_rest,
                        "distance": float(b.distance),
                        "outline": None if outline is None else outline.tolist(),
                    }
                    if not at_rest:
                        bodies[name]["reason"] = f"{r.status}: {r.message}"
            out["runout"] = {
                "bodies": bodies,
                "vehicles": {name: r.to_dict(history=history) for name, r in self.runout.items()},
            }
            if self.joint is not None:
                j = self.joint
                out["runout"].update(
                    status=j.status, message=j.message, t_end_s=j.t_end, method=j.method,
                    pairs=[p.to_dict() for p in j.pairs],
                    energy_J=self.energy_ledger(),
                    events=[{"t_s": e.t, "kind": e.kind, "detail": e.detail, "energy_J": e.energy,
                             "vehicles": list(e.vehicles), **e.data} for e in j.events],
                    obstacles=[{"name": o.name, "points": [list(p) for p in o.points], "thickness": o.thickness,
                                "closed": o.closed} for o in sc.runout.obstacles])
        if sc.approaches:
            out["approach"] = {name: a.to_dict() for name, a in sc.approaches.items()}
        if self.evidence is not None:
            out["evidence"] = self.evidence.to_dict()
            crush = crush_by_body(self.evidence)
            if crush:
                out["crush"] = crush
        if self.accuracy is not None:
            out["accuracy"] = {name: rep.to_dict() for name, rep in self.accuracy.items()}
        if self.scenario.runout is not None:
            out["runout_level"] = self.scenario.runout.level
        out["warnings"] = list(self.warnings)

        if survey_records(sc):
            out["survey"] = survey_records(sc)
        return out

    def report(self, units: str | None = None, *, system: str | None = None) -> str:
        """The readable report: impact, run-out, later impacts, events, evidence, warnings.

        ``units`` (or ``system``): ``"SI"`` or ``"US"`` (any case); default the scenario's ``units``.
        """
        system = _system(self, units if units is not None else system)
        sc = self.scenario
        head = [f"crashsim: {sc.title}"]
        if sc.source:
            head.append(f"source: {sc.source}")
        if sc.path:
            head.append(f"file: {sc.path}")
        head.append(f"units: {system_label(system)}")
        text = "\n".join(head) + "\n\n"
        if sc.approaches:
            text += format_approach(sc.approaches, system) + "\n\n"
        text += format_impact(self.impact, system)
        if self.runout is not None:
            text += "\n\n" + format_runout(self.runout, system, joint=self.joint is not None)
            text += f"\n  model level: {self.scenario.runout.level}"
            if self.joint is not None:
                joint = format_joint(self, system)
                if joint:
                    text += "\n\n" + joint
                text += "\n\n" + format_events(self.joint.events, system)
            else:
                for vname, r in self.runout.items():
                    text += "\n\n" + format_events(r.events, system, title=f"Run-out events, vehicle {vname}")
            for name, rep in (self.accuracy or {}).items():
                text += f"\n  accuracy, vehicle {name}: {rep.message}"
        if self.evidence is not None:
            text += "\n\n" + format_evidence(self.evidence, system, wheel_labels(sc.vehicles))
            text += _format_registrations(self.scenario.evidence, system)
            if any(c.kind == "crush energy" for c in self.evidence.checks):
                text += "\n\n" + format_crush(self.evidence, system)

        if survey_records(sc):
            text += "\n\n" + format_survey(survey_records(sc))
        if self.warnings:
            text += "\n\nWarnings\n" + "\n".join(f"  - {message_in(w, system)}" for w in self.warnings)
        return text

    # ------------------------------------------------------------------ histories
    @property
    def t_end(self) -> float:
        """End of the run-out [s] (the latest vehicle's rest); 0 without a run-out."""
        return max((r.t_end for r in (self.runout or {}).values()), default=0.0)

    def times(self, dt: float | None = None):
        """Times from the first separation to :attr:`t_end` every ``dt`` [s] (default: the
        run-out's ``sample_dt``), the end included."""
        if self.runout is None:
            raise ScenarioError("this scene has no run-out (runout.level = \"impact\" or no [runout])", field="runout")
        dt = self.scenario.runout.options.sample_dt if dt is None else float(dt)
        if not (dt > 0 and np.isfinite(dt)):
            raise ScenarioError(f"dt = {dt!r} s; allowed a time step > 0", field="dt")
        n = int(np.floor(self.t_end / dt + 1e-9))
        if n > 1_000_000:
            raise ScenarioError(f"dt = {dt:g} s gives {n} steps over {self.t_end:.4g} s; allowed at most "
                                f"1,000,000 (dt >= {self.t_end / 1e6:.3g} s)", field="dt")
        return time_grid(self.t_end, dt)

    def history(self, dt: float | None = None) -> dict:
        """Every body's state at common times, as arrays (SI): the positions at any time step.

        Parameters
        ----------
        dt : float, optional
            Time step [s] (default: the run-out's ``sample_dt``).  States come from the
            run-out's dense solution, exact to its tolerance; a vehicle at rest stays at rest.

        Returns
        -------
        dict of str to ndarray
            ``"t"`` [s] and per body ``"<body>.x"``, ``".y"`` [m], ``".heading"`` [rad],
            ``".vx"``, ``".vy"``, ``".speed"`` [m/s], ``".yaw_rate"`` [rad/s].
        """
        t = self.times(dt)
        out = {"t": t}
        for r in self.runout.values():
            for name, b in r.bodies.items():
                x, y, h, vx, vy, w = np.asarray(b.sol(np.clip(t, 0.0, r.t_end)))
                out.update({f"{name}.x": x, f"{name}.y": y, f"{name}.heading": h, f"{name}.vx": vx,
                            f"{name}.vy": vy, f"{name}.speed": np.hypot(vx, vy), f"{name}.yaw_rate": w})
        return out

    def history_frame(self, dt: float | None = None):
        """:meth:`history` as a pandas DataFrame indexed by time (needs pandas installed)."""
        try:
            import pandas as pd
        except ImportError:  # pragma: no cover - depends on the environment
            raise ImportError("history_frame needs pandas (pip install pandas); history() gives the same "
                              "columns as numpy arrays") from None
        h = self.history(dt)
        return pd.DataFrame({k: v for k, v in h.items() if k != "t"}, index=pd.Index(h["t"], name="t [s]"))

    # ------------------------------------------------------------------ figures
    def plot(self, ax=None, **kwargs):
        """The scene diagram on ``ax`` (a new figure if None); see :func:`crashsim.plotting.plot_scene`.
        Returns the axes."""
        return plot_scene(self, ax, **kwargs)

    def animate(self, path, **kwargs):
        """Write an animation (``.gif``; ``.mp4`` where ffmpeg is present); see
        :func:`crashsim.animation.animate_scene`.  Returns the path written."""
        return animate_scene(self, path, **kwargs)

    def _track_at(self, r, key: str, tr, dt: float | None):
        """A wheel's track (t, points, sliding) at its stored samples, or every ``dt`` [s] from the body's
        dense solution (the contact point of the rigid body; the sliding flag of the latest sample)."""
        if dt is None:
            return tr.t, tr.points, tr.sliding
        t = self.times(dt)
        t = t[t <= r.t_end + 1e-12]
        spec = next(w for v in self.scenario.vehicles for w in enumerate_wheels(v) if w.key == key)
        x, y, h = np.asarray(r.bodies[tr.body].sol(np.clip(t, 0.0, r.t_end)))[:3]
        px, py = spec.position
        points = np.column_stack([x + np.cos(h) * px - np.sin(h) * py, y + np.sin(h) * px + np.cos(h) * py])
        k = np.clip(np.searchsorted(tr.t, t, side="right") - 1, 0, len(tr.t) - 1)
        return t, points, np.asarray(tr.sliding)[k]

    def write_csv(self, directory: Path, *, system: str | None = None, dt: float | None = None) -> list[Path]:
        """Write CSV files (column headers carry the unit); returns the paths written.

        ``impact.csv``: one row per body (velocities before/after, delta-v, yaw rates);
        ``<vehicle>_history.csv``: the run-out history of every body and hitch, at the stored
        samples or every ``dt`` [s] (:meth:`crashsim.motion.RunoutResult.table`);
        ``<vehicle>_tracks.csv``: every wheel's track (time, x, y, sliding flag), the wheel named by its
        axle's name from the file (``trailer/axle 2/right``; the index where the axle has no name);
        ``<vehicle>_approach.csv``: a vehicle's approach as a time-distance-speed table (time and
        distance from the impact, the first body's CG; perception, then the braking phase).
        With ``dt`` every one of them is given every ``dt`` (the approach back from the impact).
        Numbers carry :data:`CSV_DECIMALS` decimals.
        ``system``: ``"SI"`` (angles in rad) or ``"US"`` (ft, mph, lbf, deg); default the
        scenario's ``units``.
        """
        system = _system(self, system)
        directory = Path(directory)
        labels = wheel_labels(self.scenario.vehicles)
        if dt is not None:
            self.times(dt)  # checked before anything is written
        directory.mkdir(parents=True, exist_ok=True)
        written = []
        path = directory / "impact.csv"
        cols = [("vx_before", "speed"), ("vy_before", "speed"), ("yaw_rate_before", "angular_velocity"),
                ("vx_after", "speed"), ("vy_after", "speed"), ("yaw_rate_after", "angular_velocity"),
                ("delta_vx", "speed"), ("delta_vy", "speed"), ("delta_v", "speed"), ("pdof", "angle")]
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["body", "vehicle"] + [f"{n} [{_unit(k, system)}]" for n, k in cols])
            for name, b in self.impact.bodies.items():
                if b.fixed:
                    continue
                values = [*b.velocity_before, b.yaw_rate_before, *b.velocity, b.yaw_rate, *b.delta_v,
                          b.delta_v_magnitude, b.pdof]
                w.writerow([name, b.vehicle] + [csv_number(v, k, system) for v, (_, k) in zip(values, cols)])
        written.append(path)
        for vname, r in (self.runout or {}).items():
            table = r.table(None if dt is None else self.times(dt))
            path = directory / f"{vname}_history.csv"
            heads, columns = [], []
            for head, values in table.items():
                name, si = head[:-1].split(" [")
                kind = _SI_KIND[si]
                heads.append(f"{name} [{_unit(kind, system)}]")
                columns.append([csv_number(v, kind, system) for v in values.tolist()])
            with path.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(heads)
                w.writerows(zip(*columns))
            written.append(path)
            path = directory / f"{vname}_tracks.csv"
            lu = _unit("length", system)
            with path.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(["wheel", "t [s]", f"x [{lu}]", f"y [{lu}]", "sliding"])
                for key, tr in r.wheels.items():
                    t, points, sliding = self._track_at(r, key, tr, dt)
                    for ti, (x, y), sl in zip(t.tolist(), points.tolist(), sliding.tolist()):
                        w.writerow([labels.get(key, key), csv_number(ti, "time", system),
                                    csv_number(x, "length", system), csv_number(y, "length", system), int(sl)])
            written.append(path)
        for vname, a in self.scenario.approaches.items():
            path = directory / f"{vname}_approach.csv"
            tab = a.table(dt=dt)
            lu, vu = _unit("length", system), _unit("speed", system)
            with path.open("w", newline="") as fh:
                w = csv.writer(fh)
                w.writerow(["t from impact [s]", f"distance from impact [{lu}]", f"speed [{vu}]"])
                for t, d, v in zip(tab["t"].tolist(), tab["s"].tolist(), tab["v"].tolist()):
                    w.writerow([csv_number(t, "time", system), csv_number(d, "length", system),
                                csv_number(v, "speed", system)])
            written.append(path)
        return written


def crush_by_body(evidence) -> dict:
    """Per crushed body, from the crush-energy checks: ``energy`` [J] (CRASH3, with the force-direction
    factor), ``energy_uncorrected`` [J], ``ees`` [m/s] and the ``impacts`` group ("first" or "all")."""
    out = {}
    for c in evidence.checks:
        if c.kind != "crush energy":
            continue
        for name, b in c.details["bodies"].items():
            out[name] = {"energy": b["energy"], "energy_uncorrected": b["energy_uncorrected"], "ees": b["ees"],
                         "impacts": c.details["impacts"]}
    return out


#: The kind of a CSV column from its SI unit label.
_SI_KIND = {"s": "time", "m": "length", "rad": "angle", "m/s": "speed", "rad/s": "angular_velocity", "N": "force"}

#: Decimals of the CSV numbers, by quantity and unit system: a precision that carries meaning (README, CSV
#: paragraph). Below the run-out's own accuracy (lengths to 0.1 mm, speeds to 0.1 mm/s, times to 0.1 ms,
#: headings to 1e-6 rad = 0.06 mdeg, forces to 0.1 N), above the round-off that differs between processors.
CSV_DECIMALS = {"SI": {"time": 4, "length": 4, "speed": 4, "angle": 6, "angular_velocity": 5, "force": 1},
                "US": {"time": 4, "length": 4, "speed": 4, "angle": 4, "angular_velocity": 3, "force": 1}}


def csv_number(value, kind: str, system: str) -> str:
    """An SI value as a CSV field in ``system`` units at :data:`CSV_DECIMALS` (empty for None or NaN)."""
    if value is None or not np.isfinite(value):
        return ""
    text = f"{_convert(value, kind, system):.{CSV_DECIMALS[system][kind]}f}"
    return "0" if float(text) == 0 else text.rstrip("0").rstrip(".")


def _unit(kind: str, system: str) -> str:
    return to_unit(0.0, kind, system)[1]


def _convert(value: float, kind: str, system: str) -> float:
    if system == "SI" and (kind != "speed" or speed_unit_of(system) == "m/s"):
        return float(value)  # SI as computed (a speed in km/h or mph with [scenario] speed_unit)
    return to_unit(value, kind, system)[0]


def _system(scene, system: str | None) -> str:
    """``system`` (any case) or the scenario's units; a ScenarioError names anything else."""
    return resolve_system(system, scene.scenario.units)


def separation_states(scenario, impact: ImpactResult) -> dict:
    """Body states at separation: impact positions and headings, post-impact velocities.

    A vehicle that is not in the impact keeps its state from the file (it may be at rest, or
    moving towards the scene: the run-out finds out whether it is struck).
    """
    out = {}
    for v in scenario.vehicles:
        for b in v.bodies:
            if b.is_fixed:
                continue
            s0 = scenario.states[b.name]
            if b.name in impact.bodies:
                bi = impact.bodies[b.name]
                out[b.name] = BodyState(s0.position, s0.heading, tuple(bi.velocity), bi.yaw_rate)
            else:
                out[b.name] = s0
    return out


def simulate_approaches(scenario):
    """The scenario with its vehicles' approaches simulated (itself if there are none, or they are).

    Each approach runs from the start of braking to the vehicle's impact configuration
    (:func:`crashsim.motion.approach.simulate_approach`); its velocity and yaw rates at the end
    become the vehicle's states at impact (hitch-consistent, the file's articulations), in
    ``states`` and in the impact problem.

    Raises
    ------
    ScenarioError
        (naming the file) An approach that does not reach the impact, or a speed that cannot be solved.
    """
    if scenario.approaches_simulated:
        return scenario
    states = dict(scenario.states)
    approaches = {}
    d = scenario.data
    for veh in scenario.vehicles:
        a = scenario.approach_inputs.get(veh.name)
        if a is None:
            continue
        try:
            res = simulate_approach(veh, a.spec, {b.name: states[b.name] for b in veh.bodies}, a.road, a.options,
                                    speed_at_impact=a.speed_at_impact)
        except ScenarioError as exc:
            raise with_file(exc, scenario.path) from None
        approaches[veh.name] = res
        v = d["vehicles"][veh.name]
        end = res.impact_states
        states.update(chain_states(veh, v["position"], v["heading"], end[veh.bodies[0].name].velocity,
                                   [end[b.name].yaw_rate for b in veh.bodies],
                                   [b["articulation"] for b in v["bodies"][1:]]))
    runout = scenario.runout
    continued = {name: continued_wheels(veh, scenario.approach_inputs[name].spec.wheels, res.time_to_impact,
                                        res.steer_at_impact(), scenario.approach_inputs[name].runout_wheels)
                 for veh in scenario.vehicles for name, res in approaches.items()
                 if veh.name == name and scenario.approach_inputs[name].through_impact}
    if continued and runout is not None:
        runout = replace(runout, wheels={**runout.wheels, **continued})
    p = scenario.impact
    try:
        problem = ImpactProblem(p.vehicles, {b.name: states[b.name] for v in p.vehicles for b in v.bodies}, p.body1,
                                p.body2, p.surface, p.constraints, p.external)
    except ScenarioError as exc:
        raise ScenarioError(str(exc), field=exc.field, file=scenario.path) from None
    return replace(scenario, states=states, impact=problem, approaches=approaches, runout=runout)


def run_scene(scenario, *, lean: bool = False, separation: dict | None = None,
              models: ModelReuse | None = None, mark_checks: bool = True) -> SceneResult:
    """Solve a loaded scenario: the impact, then the run-out of the whole scene if asked for.

    At the ``articulated`` and ``load_transfer`` levels every vehicle runs out together, with
    contact between them and with the scene's obstacles (the barrier of the impact among
    them): later impacts are solved by the impulse solver (:func:`crashsim.motion.run_runout`, the one
    run-out entry).
    The ``energy`` and ``rigid`` levels run each vehicle alone, without contact.

    ``lean``: the result a fit, Monte Carlo or posterior sample reads (its records, residuals
    and evidence checks), with the same numbers: the joint run-out keeps only the tracks of
    the wheels a run-out tyre mark of the evidence can match, no hitch histories, no pair
    summaries, no event places (:func:`crashsim.motion.postprocess.assemble_scene`).  Reports,
    figures and ``to_dict`` need the full result (the default).

    ``separation``: ``{body: (velocity (2,) [m/s], yaw rate [rad/s])}`` to start the run-out of those
    bodies from instead of the impact's separation velocities (at the impact's positions): a run-out
    from measured separation velocities, as the validation suite runs it. The impact is solved and
    reported as usual; an articulated vehicle's bodies are made hitch-consistent as always.

    ``models``: the run-out scene model kept across the samples of one scene
    (:class:`~crashsim.scene.models.ModelReuse`, owned by a
    :class:`~crashsim.reconstruct.inputs.SceneInputs`); None builds it for this run.

    ``mark_checks``: False leaves the tyre-mark checks out of the evidence report (a fit's lean
    evaluations, which measure their own distances along each mark: ``evaluate_evidence(marks=)``).

    Raises
    ------
    ScenarioError
        (naming the scenario file) The impact cannot be solved as given: the bodies are not
        approaching, or the coefficients are inadmissible for this geometry.
    """
    scenario = simulate_approaches(scenario)  # a vehicle's approach before the impact (unless already run)
    try:
        impact = solve_impact(scenario.impact)
    except ScenarioError as exc:
        raise with_file(exc, scenario.path) from None
    runout = None
    accuracy = None
    joint = None
    spec = scenario.runout
    if spec is not None and spec.level != "impact":
        states = separation_states(scenario, impact)
        for name, (velocity, yaw_rate) in (separation or {}).items():
            if name not in states:
                raise ScenarioError(f"separation state for {name!r}, which is not a movable body of the scene; "
                                    f"allowed {', '.join(states)}", field="separation", file=scenario.path)
            s0 = states[name]
            states[name] = BodyState(s0.position, s0.heading, tuple(velocity), float(yaw_rate))
        movable = [v for v in scenario.vehicles if not v.is_barrier]
        initial = {}
        for veh in movable:
            initial.update(make_hitch_consistent(veh, {b.name: states[b.name] for b in veh.bodies}))
        contact = spec.level in CONTACT_LEVELS
        run = run_runout(movable, initial, spec.wheels, spec.road, spec.options, level=spec.level,
                         contact=spec.contact, pair_contact=spec.pair_contact, obstacles=spec.obstacles,
                         accuracy=spec.accuracy, accuracy_heading=spec.accuracy_heading,
                         # the scene model, reused across the samples of one scene
                         model=scene_model(movable, spec, models) if contact and spec.accuracy is None else None,
                         lean=_track_filter(scenario) if lean and contact else None)
        runout, joint, accuracy = run
    evidence = None
    if not scenario.evidence.empty:
        evidence = evaluate_evidence(scenario.evidence, impact, runout, scenario.impact.surface.point,
                                     secondary=joint.impacts if joint is not None else (),
                                     approaches=scenario.approaches, marks=mark_checks)
    warnings = [f"approach of {name}: {w}" for name, a in scenario.approaches.items() for w in a.warnings]
    warnings += [f"impact: {w}" for w in impact.warnings]
    warnings += rest_misfit_warnings(scenario.evidence)
    warnings += [r["note"] for r in survey_records(scenario) if r.get("kind") == "warning"]
    warnings += list(getattr(scenario, "load_warnings", ()))
    if runout is not None:
        if joint is None:
            warnings += barrier_crossings(scenario, runout)
        else:
            warnings += [f"secondary impact at t = {i.t:.3f} s ({i.body1}/{i.body2}): {i.warning}"
                         for i in joint.impacts if i.warning]
        for vname, r in runout.items():
            if not r.success:
                warnings.append(f"the run-out of vehicle {vname!r} did not reach rest: {r.status} ({r.message})"
                                + rolling_downhill(spec.road, r))
    return SceneResult(scenario=scenario, impact=impact, runout=runout, evidence=evidence, warnings=tuple(warnings),
                       accuracy=accuracy, joint=joint)


def rolling_downhill(road, r) -> str:
    """A hint for a run-out that hit its time limit on a slope: free-rolling wheels on a slope steeper
    than their rolling resistance never stop (a reading of the input, not a fault of the solver)."""
    if r.status != "time_limit" or road is None or not road.sloped:
        return ""
    ends = np.array([b.final.position for b in r.bodies.values()], dtype=float)
    slopes = road.slope_from_membership(road.membership(ends))
    steepest = float(np.max(np.hypot(slopes[:, 0], slopes[:, 1])))
    if steepest == 0.0:
        return ""
    return (f"; it stopped on a slope of {100 * steepest:.3g} %: a vehicle whose wheels roll freely keeps rolling "
            f"where the slope is steeper than their rolling resistance; if it came to rest, give it braked or "
            f"locked wheels (tyres, wheels[] or wheel_changes[]) or air brakes")


@dataclass(frozen=True)
class _TrackFilter:
    """The wheels whose tracks a lean run keeps: those a run-out tyre mark's ``wheel`` selector can
    match. A predicate on wheel specs; two filters of the same selectors are equal, so that the
    wheels it keeps are found once per run-out model, not once per sample."""

    selectors: tuple

    def __call__(self, spec) -> bool:
        return any(wheel_matches(spec, s) for s in self.selectors)


def _track_filter(scenario) -> _TrackFilter:
    """The :class:`_TrackFilter` of a scenario's run-out tyre marks."""
    return _TrackFilter(tuple(m.wheel for m in scenario.evidence.marks if m.phase == "runout"))


#: Growth of a body's overlap with the barrier after separation [m] that is reported: the
#: run-out does not model a second contact with the barrier.
BARRIER_OVERLAP_WARNING = 0.25


def barrier_crossings(scenario, runout: dict) -> list[str]:
    """Warnings for bodies whose outline moves into the barrier after separation (the ``energy``
    and ``rigid`` levels, which model no contact)."""
    extent = scenario.barrier_extent
    if extent is None:
        return []
    surf = scenario.impact.surface
    n, t, p0 = surf.normal, surf.tangent, np.asarray(surf.point)
    out = []
    for r in runout.values():
        for name, b in r.bodies.items():
            body = next(bb for v in scenario.vehicles for bb in v.bodies if bb.name == name)
            corners = body.outline()
            if corners is None:
                continue
            h = b.history
            c, s_ = np.cos(h.heading)[:, None], np.sin(h.heading)[:, None]
            wx = h.x[:, None] + c * corners[:, 0] - s_ * corners[:, 1]
            wy = h.y[:, None] + s_ * corners[:, 0] + c * corners[:, 1]
            dn = (wx - p0[0]) * n[0] + (wy - p0[1]) * n[1]  # > 0 on the vehicle's side
            dt = (wx - p0[0]) * t[0] + (wy - p0[1]) * t[1]
            inside = (dt >= extent[0]) & (dt <= extent[1])
            depth = np.max(np.where(inside, -dn, -np.inf), axis=1)
            growth = depth - max(depth[0], 0.0)
            k = np.nonzero(growth > BARRIER_OVERLAP_WARNING)[0]
            if len(k):
                out.append(f"body {name!r} moves {np.max(growth):.2f} m into the barrier after separation "
                           f"(from t = {h.t[k[0]]:.2f} s): the {scenario.runout.level!r} level models no contact, "
                           "so its run-out past that time is not physical (the articulated levels do)")
    return out

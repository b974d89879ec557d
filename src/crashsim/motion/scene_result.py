"""Result objects of a whole scene's run-out: its later impacts, its pairs in contact, and the scene.

:class:`SceneRunout` holds every vehicle's :class:`~crashsim.motion.result.RunoutResult`, the
later impacts (:class:`SecondaryImpact`, each pair's share a :class:`PairImpulse`; numbered
events :class:`ImpactEvent`), the pair summaries (:class:`PairSummary`) and the energy ledger.
All numbers are SI in the world frame, as in :mod:`crashsim.motion.result`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable

import numpy as np

from .result import jsonable

#: A sustained-contact force below this [N] is no force (round-off at a contact that carries nothing).
FORCE_FLOOR = 1.0

__all__ = ["SecondaryImpact", "PairImpulse", "ImpactEvent", "impact_events", "PairSummary", "SceneRunout"]


@dataclass(frozen=True, eq=False)
class PairImpulse:
    """One pair's share of a simultaneous impact, as the evidence checks read an impact (SI, world frame).

    Attributes
    ----------
    body1, body2 : str
        The pair (``body2`` may be a fixed obstacle); impulses act on body1, minus them on body2.
    normal_impulse, tangential_impulse : float
        Sums over the pair's contact points [N s].
    bodies : dict of str to BodyImpact
        Every body of the pair's vehicles: velocities before and after the instant, and the velocity
        change this pair's impulses alone caused (``delta_v``; the shares of all pairs and closed stops
        of the instant sum to its whole change); the PDOF of the pair's impulse on body1 and body2.
    energy_loss_normal, energy_loss_tangential : float
        The work the pair's normal and friction impulses took [J] (:class:`crashsim.impact.multicontact.ContactSolution`).
    kinetic_energy : dict
        ``{"system": {"before": ..., "after": ...}}`` [J]: the kinetic energy before the instant and
        that less this pair's share of the loss.
    sliding : bool
        A point of the pair still slides along the other body after the impact (its friction at f).
    closing_velocity, separation_normal_velocity, separation_tangential_velocity : float
        The normal relative velocity of the pair's points before the impact (< 0: approaching) and their
        normal and tangential relative velocities after it [m/s], means weighted by the points' normal
        impulses (as :class:`crashsim.impact.ImpactResult` gives them for its one point).
    """

    body1: str
    body2: str
    normal_impulse: float
    tangential_impulse: float
    bodies: dict
    energy_loss_normal: float
    energy_loss_tangential: float
    kinetic_energy: dict
    sliding: bool = False
    closing_velocity: float = 0.0
    separation_normal_velocity: float = 0.0
    separation_tangential_velocity: float = 0.0
    energy_loss_moment: float = 0.0
    #: Work of impulses other than the contacts' [J] (none here: :attr:`crashsim.impact.ImpactResult.work`'s keys)
    work: dict = field(default_factory=dict)

    @property
    def energy_loss_crush(self) -> float:
        """Work of the pair's impulses [J] (normal, tangential and moment parts)."""
        return self.energy_loss_normal + self.energy_loss_tangential + self.energy_loss_moment


def _delta_v_json(delta_v: dict) -> dict:
    """``{body: (dvx, dvy)}`` as the JSON gives a delta-v: ``{body: {"vector": [dvx, dvy], "magnitude": |dv|}}``."""
    return {k: {"vector": list(v), "magnitude": float(np.hypot(*v))} for k, v in delta_v.items()}


@dataclass(frozen=True, eq=False)
class SecondaryImpact:
    """One pair's part of an impact during the run-out (SI, world frame).

    Every impact of the run-out is simultaneous: all the points of any bodies touching at its
    instant are solved together (:func:`crashsim.impact.multicontact.solve_contacts`); a record is
    one pair's share of it, and the records of one instant share their ``event`` number.

    Attributes
    ----------
    t : float
        Time after the first separation [s].
    body1, body2 : str
        The bodies in contact (``body2`` may be a fixed obstacle); the normal points from body2
        into body1 and the impulse acts on body1.
    point, normal : ndarray (2,)
        Contact point [m] (the mean of the pair's points, weighted by their normal impulses) and
        the mean normal.
    closing_speed : float
        Approach speed of the pair's fastest point along its normal before the impact [m/s].
    normal_impulse, tangential_impulse : float
        [N s].
    energy_loss : float
        Kinetic energy this pair's impulses took [J] (the records of an instant sum to its loss).
    delta_v : dict
        Velocity change of every body of the two vehicles that this pair's impulses caused [m/s],
        world frame, ``{body: (dvx, dvy)}``.
    law : str
        ``"friction"`` with the pair's coefficients; ``"plastic"`` (e = 0) or ``"frictionless"``
        where Newton's law would have made energy for the geometry (``warning`` says so).
    restitution, friction : float
        The coefficients used.
    result : PairImpulse
        What the evidence checks read of it.
    warning : str
    event : int
        The impact event the record belongs to: 2 for the first instant after the first impact,
        then 3, ... (the figures and reports number events).
    points : int
        Contact points of the pair in the solve.
    """

    t: float
    body1: str
    body2: str
    point: np.ndarray
    normal: np.ndarray
    closing_speed: float
    normal_impulse: float
    tangential_impulse: float
    energy_loss: float
    delta_v: dict
    law: str
    restitution: float
    friction: float
    result: Any = None
    warning: str = ""
    event: int = 2
    points: int = 1

    def to_dict(self) -> dict:
        return jsonable({
            "time": self.t, "event": self.event, "points": self.points,
            "body1": self.body1, "body2": self.body2, "point": self.point, "normal": self.normal,
            "closing_speed": self.closing_speed, "normal_impulse": self.normal_impulse,
            "tangential_impulse": self.tangential_impulse, "energy_loss": self.energy_loss,
            "delta_v": _delta_v_json(self.delta_v),
            "law": self.law, "restitution": self.restitution, "friction": self.friction, "warning": self.warning,
            **_work_split(self.result),
        })


def _work_split(result) -> dict:
    """The energy loss at the crush surface by the work of the impulses [J] (normal, tangential and moment
    parts: :attr:`crashsim.impact.ImpactResult.energy_loss_normal` and friends); empty without a result."""
    if result is None:
        return {}
    return {"energy_loss_normal": result.energy_loss_normal, "energy_loss_tangential": result.energy_loss_tangential,
            "energy_loss_moment": result.energy_loss_moment}


@dataclass(frozen=True, eq=False)
class ImpactEvent:
    """The impacts reports and figures number as one: every pair of one instant, and the instants that
    follow within :data:`crashsim.motion.impacts.IMPACT_EVENT_WINDOW` between the same bodies (the
    bounces of one collision).

    Attributes
    ----------
    number : int
        2 for the first event after the first impact, then 3, ...
    t : float
        Its first instant [s].
    records : tuple of SecondaryImpact
        The pairs' shares, in time order.
    """

    number: int
    t: float
    records: tuple

    @property
    def energy_loss(self) -> float:
        """Kinetic energy the event took [J]."""
        return float(sum(r.energy_loss for r in self.records))

    @property
    def instants(self) -> int:
        return len({r.t for r in self.records})

    @property
    def pairs(self) -> tuple:
        return tuple(dict.fromkeys(f"{r.body1}|{r.body2}" for r in self.records))

    def delta_v(self) -> dict:
        """Velocity change of every body the event moved [m/s] (world frame, the sum of its records)."""
        out: dict = {}
        for r in self.records:
            for b, d in r.delta_v.items():
                a = out.get(b, (0.0, 0.0))
                out[b] = (a[0] + d[0], a[1] + d[1])
        return out

    def to_dict(self) -> dict:
        return jsonable({"event": self.number, "time": self.t, "instants": self.instants, "pairs": list(self.pairs),
                         "energy_loss": self.energy_loss,
                         "normal_impulse": float(sum(r.normal_impulse for r in self.records)),
                         "delta_v": _delta_v_json(self.delta_v())})


def impact_events(impacts) -> list[ImpactEvent]:
    """``impacts`` (SecondaryImpact records with their ``event`` numbers) grouped as ImpactEvent objects."""
    groups: dict = {}
    for r in impacts:
        groups.setdefault(r.event, []).append(r)
    return [ImpactEvent(n, float(rs[0].t), tuple(rs)) for n, rs in sorted(groups.items())]


@dataclass(frozen=True, eq=False)
class PairSummary:
    """What happened between two bodies (or a body and an obstacle) during the run-out.

    Attributes
    ----------
    name, body1, body2 : str
    impacts : int
        Impact instants in which the pair took an impulse.
    contact_time : float
        Time spent in sustained contact [s]: the span of the pair's contact events (from a
        touch, a press or an impact to the contact's end, or to the end of the run).
    peak_force : float
        Largest sustained-contact force [N], from the solution (every integrator step, the
        largest refined; not the sample grid: ``sample_dt`` does not change it).
    max_penetration : float
        Largest depth of one body in the other beyond the allowance [m], from the solution and
        the samples:
        ``F / k`` while in sustained contact, round-off while apart; the crush of the first
        impact is the allowance of a pair that started overlapped.
    contact_work : float
        Work of the pair's contact forces on the bodies [J] (<= 0: dissipated, less the
        energy still stored in the penalty spring).
    t, force : ndarray
        The sampled sustained-contact force on body1 [N] against time [s].
    max_closing : float
        Largest strike measure [m/s] of a point pressed beyond the allowance while the pair was
        in contact or disarmed, outside its impacts (from the solution): its closing speed less
        the speed its depth ``e`` holds, ``omega e`` (``omega = sqrt(k / m_eff)``; the closing
        speed itself for a point at the surface). Below the pair's impulse threshold, since a
        larger one is an impact (the re-strike rule).
    peak_time : float
        When the force reached ``peak_force`` [s] (NaN without a force).
    node_t, node_force : ndarray
        The sustained-contact force on body1 [N] at the nodes ``peak_force`` was found on (every
        integrator step and its quarter points in the segments with the pair in contact or
        disarmed; zero out of contact) against time [s]: what a figure draws beside ``t, force``
        so that it shows the peak and a contact shorter than the sample step.
    """

    name: str
    body1: str
    body2: str
    impacts: int
    contact_time: float
    peak_force: float
    max_penetration: float
    contact_work: float
    t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    force: np.ndarray = field(default_factory=lambda: np.zeros(0))
    max_closing: float = 0.0
    peak_time: float = float("nan")
    node_t: np.ndarray = field(default_factory=lambda: np.zeros(0))
    node_force: np.ndarray = field(default_factory=lambda: np.zeros(0))

    @property
    def sustained(self) -> bool:
        """The pair pressed on each other with a force (a peak above :data:`FORCE_FLOOR`: less is round-off
        of the integration at a contact that carries nothing)."""
        return self.peak_force > FORCE_FLOOR

    def to_dict(self, history: bool = False) -> dict:
        d = {k: v for k, v in self.__dict__.items() if k not in ("t", "force", "peak_time", "node_t", "node_force")}
        if history:
            d.update(t=self.t, force=self.force)
        return jsonable(d)


@dataclass(frozen=True, eq=False)
class SceneRunout:
    """The run-out of a whole scene: every vehicle integrated together from the first separation.

    Attributes
    ----------
    vehicles : dict of str to RunoutResult
        Per vehicle, as :func:`~crashsim.motion.simulate_runout` returns it (its own status:
        ``"rest"`` if it came to rest, else the run's status).
    impacts : tuple of SecondaryImpact
        The impacts during the run-out, in time order.
    pairs : tuple of PairSummary
    events : tuple of RunoutEvent
        Every event of the scene in time order.
    energy : dict
        The energy ledger [J]: ``initial`` kinetic energy = ``impacts`` (losses) + ``tyres``
        (tyre work) + ``stops`` (articulation-stop impacts) + ``contacts`` (sustained-contact
        work) + ``final`` kinetic energy + ``closing_error``.
    status, message, t_end, nfev, n_segments, method
        Of the whole run.
    sol : callable
        ``sol(t)`` -> the scene's state vector(s).
    layout : StateLayout
    """

    vehicles: dict
    impacts: tuple
    pairs: tuple
    events: tuple
    energy: dict
    status: str
    message: str
    t_end: float
    nfev: int
    n_segments: int
    method: str
    sol: Callable[[Any], np.ndarray]
    layout: Any

    @property
    def success(self) -> bool:
        return self.status == "rest"

    def impact_events(self) -> list["ImpactEvent"]:
        """The impacts grouped into the events reports and figures number (:class:`ImpactEvent`)."""
        return impact_events(self.impacts)

    def to_dict(self, *, history: bool = True) -> dict:
        return jsonable({
            "status": self.status, "message": self.message, "t_end_s": self.t_end, "method": self.method,
            "nfev": self.nfev, "n_segments": self.n_segments,
            "impacts": [i.to_dict() for i in self.impacts],
            "impact_events": [e.to_dict() for e in self.impact_events()],
            "pairs": [p.to_dict() for p in self.pairs],
            "energy_J": self.energy,
            "events": [{"t_s": e.t, "kind": e.kind, "detail": e.detail, "energy_J": e.energy,
                        "vehicles": list(e.vehicles), **e.data} for e in self.events],
            "vehicles": {name: r.to_dict(history=history) for name, r in self.vehicles.items()},
        })

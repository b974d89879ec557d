"""ImpactResult: everything one impact solve produces, traceable to the equations."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..geometry import rotate, wrap_angle
from .core import energy_loss_fraction

__all__ = ["ImpactResult", "BodyImpact", "HitchImpulse", "ConstraintImpulse", "clock_direction", "pdof_from_force"]


def _row(A, i: int):
    """Batch item ``i`` of ImpactArrays as a batch of one."""
    from dataclasses import fields, replace

    return replace(A, **{f.name: getattr(A, f.name)[i : i + 1] for f in fields(A)})


def clock_direction(pdof: float) -> int:
    """Clock direction of a principal direction of force [rad] (0 -> 12 o'clock, +90 deg -> 3)."""
    h = int(round(math.degrees(pdof) / 30.0)) % 12
    return 12 if h == 0 else h


def pdof_from_force(force, heading: float) -> float:
    """Principal direction of force (SAE J224 convention) of a force vector on a body [rad].

    The direction the force comes *from*, measured clockwise from the body's heading:
    0 = frontal (the force pushes rearward), +pi/2 = from the right, -pi/2 = from the left.
    """
    angle_body = math.atan2(force[1], force[0]) - heading
    return float(wrap_angle(-(angle_body + math.pi)))


@dataclass(frozen=True)
class BodyImpact:
    """Result for one body (world frame, SI).

    ``delta_v`` is the CG velocity change [m/s]; ``pdof`` is the principal direction of the
    crush force on this body [rad], SAE J224 style: where the force comes from, clockwise from
    the heading (0 = frontal, +pi/2 = from the right); only for the two bodies in contact.
    """

    name: str
    vehicle: str
    heading: float
    velocity_before: np.ndarray
    velocity: np.ndarray
    yaw_rate_before: float
    yaw_rate: float
    delta_v: np.ndarray
    crush_impulse: np.ndarray | None
    pdof: float | None
    ke_before: float
    ke_after: float
    mass: float
    fixed: bool = False

    @property
    def delta_v_magnitude(self) -> float:
        return float(np.hypot(*self.delta_v))

    @property
    def delta_v_direction(self) -> float:
        """Direction of delta-v in the body's axes [rad] (0 = forward)."""
        return float(wrap_angle(math.atan2(self.delta_v[1], self.delta_v[0]) - self.heading))

    @property
    def clock(self) -> int | None:
        """PDOF as a clock direction (12 = frontal), or None if not in contact."""
        return None if self.pdof is None else clock_direction(self.pdof)

    @property
    def delta_yaw_rate(self) -> float:
        return self.yaw_rate - self.yaw_rate_before

    def to_dict(self) -> dict:
        d = {
            "vehicle": self.vehicle,
            "velocity": [float(v) for v in self.velocity],
            "yaw_rate": float(self.yaw_rate),
            "delta_v": [float(v) for v in self.delta_v],
            "delta_v_magnitude": self.delta_v_magnitude,
            "delta_v_direction": self.delta_v_direction,
            "delta_yaw_rate": float(self.delta_yaw_rate),
            "speed": float(np.hypot(*self.velocity)),
            "velocity_before": [float(v) for v in self.velocity_before],
            "yaw_rate_before": float(self.yaw_rate_before),
            "kinetic_energy_before": float(self.ke_before),
            "kinetic_energy_after": float(self.ke_after),
        }
        if self.crush_impulse is not None:
            d["crush_impulse"] = [float(v) for v in self.crush_impulse]
            d["pdof"] = float(self.pdof)
            d["pdof_clock"] = clock_direction(self.pdof)
        return d


@dataclass(frozen=True)
class HitchImpulse:
    """Impulse of one hitch on its front body (the rear body receives the opposite) [N s]."""

    name: str
    impulse: np.ndarray
    front_heading: float

    @property
    def longitudinal(self) -> float:
        """Component along the front body's x axis (positive pulls it forward)."""
        return float(rotate(self.impulse, -self.front_heading)[0])

    @property
    def lateral(self) -> float:
        return float(rotate(self.impulse, -self.front_heading)[1])

    def to_dict(self) -> dict:
        return {"impulse": [float(v) for v in self.impulse], "magnitude": float(np.hypot(*self.impulse)),
                "longitudinal": self.longitudinal, "lateral": self.lateral}


@dataclass(frozen=True)
class ConstraintImpulse:
    """Unknown external impulse that enforces one velocity constraint [N s]."""

    name: str
    body: str
    impulse: float
    vector: np.ndarray

    def to_dict(self) -> dict:
        return {"body": self.body, "impulse": float(self.impulse), "vector": [float(v) for v in self.vector]}


@dataclass(frozen=True)
class ImpactResult:
    """Outcome of one impact solve (SI units, world frame of the scene).

    Attributes
    ----------
    bodies : dict of BodyImpact
    normal_impulse, tangential_impulse : float
        Crush impulse on body 1 along n and t [N s].
    moment_impulse : float
        Moment impulse on body 1 [N m s].
    mu, mu_max : float
        Impulse ratio used and the no-sliding-at-separation ratio (:attr:`mu_fraction` is
        their ratio).
    sliding : bool
        True if the surfaces still slide at separation.
    energy_loss : dict
        Fraction of kinetic energy lost, per vehicle and ``"system"`` (negative = gain).
    condition_number : float
        Of the equilibrated impulse system (large = ill-conditioned).
    """

    body1: str
    body2: str
    normal: np.ndarray
    tangent: np.ndarray
    point: np.ndarray
    bodies: dict
    normal_impulse: float
    tangential_impulse: float
    moment_impulse: float
    mu: float
    mu_max: float
    sliding: bool
    tangential_law: str
    hitches: dict
    constraints: dict
    external: dict
    closing_velocity: float
    separation_normal_velocity: float
    separation_tangential_velocity: float
    kinetic_energy: dict
    energy_loss: dict
    condition_number: float
    success: bool = True
    message: str = "solved"
    warnings: tuple[str, ...] = ()
    work: dict = field(default_factory=dict)

    @classmethod
    def from_arrays(cls, problem, S, A, out, i: int, work: dict | None = None) -> "ImpactResult":
        P = out["normal_impulse"][i] * out["normal"][i] + out["tangential_impulse"][i] * out["tangent"][i]
        bodies = {}
        vnames = S.vehicle_names
        for k, name in enumerate(S.body_names):
            crush = None
            pdof = None
            if k == S.body1:
                crush = P.copy()
            elif k == S.body2:
                crush = -P
            if crush is not None:
                pdof = pdof_from_force(crush, float(A.heading[i, k]))
            bodies[name] = BodyImpact(
                name=name, vehicle=vnames[S.vehicle_index[k]], heading=float(A.heading[i, k]),
                velocity_before=A.velocity[i, k].copy(), velocity=out["velocity"][i, k].copy(),
                yaw_rate_before=float(A.yaw_rate[i, k]), yaw_rate=float(out["yaw_rate"][i, k]),
                delta_v=out["velocity"][i, k] - A.velocity[i, k], crush_impulse=crush, pdof=pdof,
                ke_before=float(out["ke_before"][i, k]), ke_after=float(out["ke_after"][i, k]),
                mass=float(A.mass[i, k]), fixed=bool(S.fixed[k]),
            )
        hitches = {
            nm: HitchImpulse(nm, out["hitch_impulse"][i, j].copy(), float(A.heading[i, S.hitches[j][0]]))
            for j, nm in enumerate(S.hitch_names)
        }
        cons = {}
        for c, nm in enumerate(S.constraint_names):
            d = A.constraint_direction[i, c]
            lam = float(out["constraint_impulse"][i, c])
            cons[nm] = ConstraintImpulse(nm, S.body_names[S.constraint_bodies[c]], lam,
                                         lam * np.array([math.cos(d), math.sin(d)]))
        ext = {nm: {"body": S.body_names[S.external_bodies[x]], "impulse": A.external_impulse[i, x].copy(),
                    "point": A.external_point[i, x].copy()} for x, nm in enumerate(S.external_names)}
        ke = {}
        loss = {}
        vidx = np.asarray(S.vehicle_index)
        for v, vn in enumerate(vnames):
            sel = vidx == v
            e0 = float(out["ke_before"][i, sel].sum())
            e1 = float(out["ke_after"][i, sel].sum())
            ke[vn] = {"before": e0, "after": e1}
            if not S.fixed[np.nonzero(sel)[0][0]]:
                loss[vn] = float(energy_loss_fraction(e0, e1))
        e0 = float(out["ke_before"][i].sum())
        e1 = float(out["ke_after"][i].sum())
        ke["system"] = {"before": e0, "after": e1}
        loss["system"] = float(energy_loss_fraction(e0, e1))
        from .admissible import REASONS, admissibility, impulse_work

        if work is None:
            work = impulse_work(S, A, out)
        sl = slice(i, i + 1)
        one = {k: v[sl] for k, v in out.items() if isinstance(v, np.ndarray) and v.ndim and v.shape[0] == out["ok"].shape[0]}
        ok, reason = admissibility(S, _row(A, i), one, {k: v[sl] for k, v in work.items()})
        warn = []
        if not ok[0] and reason[0] != 5:
            warn.append(f"inadmissible impact ({REASONS[int(reason[0])]}): solved with the admissibility check "
                        "switched off; no collision produces these coefficients for this geometry")
        work_i = {k: float(v[i]) for k, v in work.items()}
        return cls(
            body1=S.body_names[S.body1], body2=S.body_names[S.body2],
            normal=out["normal"][i].copy(), tangent=out["tangent"][i].copy(), point=A.point[i].copy(),
            bodies=bodies,
            normal_impulse=float(out["normal_impulse"][i]),
            tangential_impulse=float(out["tangential_impulse"][i]),
            moment_impulse=float(out["moment_impulse"][i]),
            mu=float(out["mu"][i]), mu_max=float(out["mu_max"][i]), sliding=bool(out["sliding"][i]),
            tangential_law=S.tangential,
            hitches=hitches, constraints=cons, external=ext,
            closing_velocity=float(out["closing_velocity"][i]),
            separation_normal_velocity=float(out["separation_normal"][i]),
            separation_tangential_velocity=float(out["separation_tangential"][i]),
            kinetic_energy=ke, energy_loss=loss,
            condition_number=float(out["condition"][i]) if "condition" in out else float("nan"),
            warnings=tuple(warn),
            work=work_i,
        )

    @property
    def energy_loss_normal(self) -> float:
        """Energy lost at the crush surface by the normal impulse, ``-P_n (u_n^- + u_n^+)/2`` [J]."""
        return -self.work.get("normal", math.nan)

    @property
    def energy_loss_tangential(self) -> float:
        """Energy lost at the crush surface by the tangential impulse, ``-P_t (u_t^- + u_t^+)/2`` [J]."""
        return -self.work.get("tangential", math.nan)

    @property
    def energy_loss_moment(self) -> float:
        """Energy lost by the moment impulse, ``-M (Omega^- + Omega^+)/2`` [J] (0 when e' = -1)."""
        return -self.work.get("moment", math.nan)

    @property
    def energy_loss_crush(self) -> float:
        """Energy lost at the crush surface [J]: normal + tangential + moment parts."""
        return self.energy_loss_normal + self.energy_loss_tangential + self.energy_loss_moment

    @property
    def crush_impulse(self) -> np.ndarray:
        """Crush impulse on body 1, world frame [N s]."""
        return self.normal_impulse * self.normal + self.tangential_impulse * self.tangent

    def vehicle_delta_v(self, vehicle: str) -> np.ndarray:
        """Delta-v of a vehicle's mass centre (mass-weighted over its bodies) [m/s]."""
        members = [b for b in self.bodies.values() if b.vehicle == vehicle and not b.fixed]
        if not members:
            raise KeyError(f"no movable vehicle {vehicle!r}")
        total = sum(b.mass for b in members)
        return sum(b.mass * b.delta_v for b in members) / total

    @property
    def mu_fraction(self) -> float | None:
        """The impulse ratio as a share of the critical one, mu / mu_max (PIM's "85 % of mu_0");
        None where mu_max is zero or unknown."""
        if not (math.isfinite(self.mu) and math.isfinite(self.mu_max)) or self.mu_max == 0.0:
            return None
        return self.mu / self.mu_max

    def to_dict(self) -> dict:
        """JSON-ready dictionary, SI units, world frame."""
        return {
            "body1": self.body1,
            "body2": self.body2,
            "bodies": {n: b.to_dict() for n, b in self.bodies.items() if not b.fixed},
            "normal": [float(v) for v in self.normal],
            "tangent": [float(v) for v in self.tangent],
            "point": [float(v) for v in self.point],
            "normal_impulse": self.normal_impulse,
            "tangential_impulse": self.tangential_impulse,
            "crush_impulse": [float(v) for v in self.crush_impulse],
            "moment_impulse": self.moment_impulse,
            "mu": self.mu,
            "mu_max": self.mu_max,
            "mu_fraction": self.mu_fraction,
            "sliding": self.sliding,
            "tangential_law": self.tangential_law,
            "closing_velocity": self.closing_velocity,
            "separation_velocity": {"normal": self.separation_normal_velocity,
                                    "tangential": self.separation_tangential_velocity},
            "hitches": {n: h.to_dict() for n, h in self.hitches.items()},
            "constraints": {n: c.to_dict() for n, c in self.constraints.items()},
            "external_impulses": {n: {"body": x["body"], "impulse": [float(v) for v in x["impulse"]],
                                      "point": [float(v) for v in x["point"]]} for n, x in self.external.items()},
            "kinetic_energy": self.kinetic_energy,
            "energy_loss": self.energy_loss,
            "energy_loss_normal": self.energy_loss_normal,
            "energy_loss_tangential": self.energy_loss_tangential,
            "energy_loss_moment": self.energy_loss_moment,
            "energy_loss_crush": self.energy_loss_crush,
            "work_external": self.work.get("external", 0.0),
            "work_constraints": self.work.get("constraints", 0.0),
            "condition_number": self.condition_number,
            "warnings": list(self.warnings),
        }

"""ImpactResult: everything one impact solve produces, traceable to the equations."""

from __future__ import annotations

import functools
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields, replace

import numpy as np

from ..geometry import rotate, wrap_angle
from .admissible import REASONS, admissibility, impulse_work
from .core import MU_MAX_LIMIT, energy_loss_fraction

__all__ = ["ImpactResult", "BodyImpact", "HitchImpulse", "ConstraintImpulse", "clock_direction", "pdof_from_force"]


def _row(A, i: int):
    """Batch item ``i`` of ImpactArrays as a batch of one."""
    return replace(A, **{f.name: getattr(A, f.name)[i : i + 1] for f in fields(A)})


class LazyDict(Mapping):
    """A read-only mapping built on first use by ``build()`` (the per-body results of a single
    solve: most callers of :func:`crashsim.impact.solve_impact` never read them all). It
    pickles, compares and prints as the dict it stands for."""

    __slots__ = ("_build", "_dict")

    def __init__(self, build):
        self._build = build
        self._dict = None

    def _get(self) -> dict:
        if self._dict is None:
            self._dict = self._build()
            self._build = None
        return self._dict

    def __getitem__(self, key):
        return self._get()[key]

    def __iter__(self):
        return iter(self._get())

    def __len__(self) -> int:
        return len(self._get())

    def __eq__(self, other):
        return self._get() == (other._get() if isinstance(other, LazyDict) else other)

    __hash__ = None

    def __repr__(self) -> str:
        return repr(self._get())

    def __reduce__(self):
        return (dict, (self._get(),))


def _body_impacts(S, inp: dict, out: dict, px: float, py: float) -> dict:
    """{body name: BodyImpact} of one solved impact (``ImpactResult.from_item``'s inputs; (px, py)
    the crush impulse on body 1)."""
    heading = inp["heading"]
    v0 = inp["velocity"]
    v1 = out["velocity"]
    w0 = inp["yaw_rate"]
    w1 = out["yaw_rate"]
    ke0 = out["ke_before"]
    ke1 = out["ke_after"]
    mass = inp["mass"]
    bodies = {}
    vnames = S.vehicle_names
    for k, name in enumerate(S.body_names):
        crush = None
        pdof = None
        if k == S.body1:
            crush = np.array([px, py])
        elif k == S.body2:
            crush = -np.array([px, py])
        if crush is not None:
            pdof = pdof_from_force(crush, heading[k])
        a, b = v0[2 * k:2 * k + 2], v1[2 * k:2 * k + 2]
        bodies[name] = BodyImpact(
            name=name, vehicle=vnames[S.vehicle_index[k]], heading=heading[k],
            velocity_before=np.array(a), velocity=np.array(b),
            yaw_rate_before=w0[k], yaw_rate=w1[k],
            delta_v=np.array([b[0] - a[0], b[1] - a[1]]), crush_impulse=crush, pdof=pdof,
            ke_before=ke0[k], ke_after=ke1[k], mass=mass[k], fixed=bool(S.fixed[k]),
        )
    return bodies


def _sum(xs: list) -> float:
    """numpy's sum of a few floats, in its order (sequential below 8 terms), without the array."""
    if len(xs) >= 8:
        return float(np.sum(xs))
    acc = 0.0
    for x in xs:
        acc += x
    return acc


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
    """Impulse of one hitch on its front body (the rear body receives the opposite) [N s].

    ``lock_moment``: for a yaw-locked hitch (C-dolly), the moment impulse of the lock on the front
    body [N m s] (the rear body receives the opposite); None for a pin free in yaw.
    """

    name: str
    impulse: np.ndarray
    front_heading: float
    lock_moment: float | None = None

    @property
    def longitudinal(self) -> float:
        """Component along the front body's x axis (positive pulls it forward)."""
        return float(rotate(self.impulse, -self.front_heading)[0])

    @property
    def lateral(self) -> float:
        return float(rotate(self.impulse, -self.front_heading)[1])

    def to_dict(self) -> dict:
        out = {"impulse": [float(v) for v in self.impulse], "magnitude": float(np.hypot(*self.impulse)),
               "longitudinal": self.longitudinal, "lateral": self.lateral}
        if self.lock_moment is not None:
            out["lock_moment_impulse"] = float(self.lock_moment)
        return out


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
    success: bool = True
    message: str = "solved"
    warnings: tuple[str, ...] = ()
    work: dict = field(default_factory=dict)
    #: True where no compressive impulse can stop the sliding (the no-slide solution needs a
    #: tensile normal impulse, or none exists): mu_max is then no bound, the contact slides
    #: throughout and friction opposes the initial slip (:mod:`crashsim.impact.admissible`)
    slides_throughout: bool = False
    #: the 2-norm condition number, or a function computing it (:attr:`condition_number`)
    _condition: object = field(default=math.nan, repr=False, compare=False)

    @classmethod
    def from_arrays(cls, problem, S, A, out, i: int, work: dict | None = None, reason: int | None = None,
                    condition=None) -> "ImpactResult":
        """The result of batch item ``i`` of a solve (``out`` of ``core.solve_arrays``).

        ``work``: the work of each group of impulses (``admissible.impulse_work``; computed if
        None). ``reason``: the item's admissibility code (``admissible.REASONS``; computed if
        None). ``condition``: the 2-norm condition number, or a function computing it on first
        access of :attr:`condition_number` (default: ``out["condition"]``, NaN if absent).
        """
        if work is None:
            work = impulse_work(S, A, out)
        if reason is None:
            sl = slice(i, i + 1)
            one = {k: v[sl] for k, v in out.items()
                   if isinstance(v, np.ndarray) and v.ndim and v.shape[0] == out["ok"].shape[0]}
            reason = int(admissibility(S, _row(A, i), one, {k: v[sl] for k, v in work.items()})[1][0])
        if condition is None:
            condition = float(out["condition"][i]) if "condition" in out else float("nan")

        def item(a):
            return a[i].ravel().tolist() if a.ndim > 1 else a[i].item()

        inp = {f.name: item(getattr(A, f.name)) for f in fields(A)}
        res = {k: item(v) for k, v in out.items() if k not in ("condition", "matrix")}
        return cls.from_item(problem, S, inp, res, {k: float(v[i]) for k, v in work.items()}, reason, condition)

    @classmethod
    def from_item(cls, problem, S, inp: dict, out: dict, work: dict, reason: int, condition) -> "ImpactResult":
        """The result of one solved impact from its numbers as python floats and flat lists:
        ``inp`` the fields of ``core.ImpactArrays`` and ``out`` the outputs of the solve (of
        one batch item, flattened), ``work`` {group: work [J]}, ``reason`` the admissibility
        code, ``condition`` the 2-norm condition number or a function computing it."""
        nrm = out["normal"]
        tng = out["tangent"]
        lam = out["impulses"]
        pn, pt = lam[0], lam[1]
        px, py = pn * nrm[0] + pt * tng[0], pn * nrm[1] + pt * tng[1]
        heading = inp["heading"]
        ke0 = out["ke_before"]
        ke1 = out["ke_after"]
        bodies = LazyDict(functools.partial(_body_impacts, S, inp, out, px, py))
        vnames = S.vehicle_names
        locks = {pair: 3 + 2 * len(S.hitches) + l for l, pair in enumerate(S.locks)}
        hitches = {nm: HitchImpulse(nm, np.array(lam[3 + 2 * j:5 + 2 * j]), heading[S.hitches[j][0]],
                                    float(lam[locks[S.hitches[j]]]) if S.hitches[j] in locks else None)
                   for j, nm in enumerate(S.hitch_names)}
        k0 = 3 + 2 * len(S.hitches) + len(S.locks)
        cons = {}
        for c, nm in enumerate(S.constraint_names):
            d = inp["constraint_direction"][c]
            lc = lam[k0 + c]
            cons[nm] = ConstraintImpulse(nm, S.body_names[S.constraint_bodies[c]], lc,
                                         lc * np.array([math.cos(d), math.sin(d)]))
        ext = {nm: {"body": S.body_names[S.external_bodies[x]],
                    "impulse": np.array(inp["external_impulse"][2 * x:2 * x + 2]),
                    "point": np.array(inp["external_point"][2 * x:2 * x + 2])} for x, nm in enumerate(S.external_names)}
        ke = {}
        loss = {}
        vidx = S.vehicle_index
        for v, vn in enumerate(vnames):
            sel = [k for k in range(len(vidx)) if vidx[k] == v]
            e0 = _sum([ke0[k] for k in sel])
            e1 = _sum([ke1[k] for k in sel])
            ke[vn] = {"before": e0, "after": e1}
            if not S.fixed[sel[0]]:
                loss[vn] = float(energy_loss_fraction(e0, e1))
        e0 = _sum(ke0)
        e1 = _sum(ke1)
        ke["system"] = {"before": e0, "after": e1}
        loss["system"] = float(energy_loss_fraction(e0, e1))
        warn = ()
        if reason not in (0, 5):
            warn = (f"inadmissible impact ({REASONS[int(reason)]}): solved with the admissibility check "
                    "switched off; no collision produces these coefficients for this geometry",)
        return cls(
            body1=S.body_names[S.body1], body2=S.body_names[S.body2],
            normal=np.array(nrm), tangent=np.array(tng), point=np.array(inp["point"]),
            bodies=bodies,
            normal_impulse=pn,
            tangential_impulse=pt,
            moment_impulse=lam[2],
            mu=out["mu"], mu_max=out["mu_max"], sliding=bool(out["sliding"]),
            tangential_law=S.tangential,
            hitches=hitches, constraints=cons, external=ext,
            closing_velocity=out["closing_velocity"],
            separation_normal_velocity=out["separation_normal"],
            separation_tangential_velocity=out["separation_tangential"],
            kinetic_energy=ke, energy_loss=loss,
            warnings=warn,
            work=work,
            slides_throughout=not (out["no_slide_normal"] > 0.0 and abs(out["mu_max"]) <= MU_MAX_LIMIT),
            _condition=condition,
        )

    @property
    def condition_number(self) -> float:
        """2-norm condition number of the equilibrated impulse system (an SVD; the single solve
        computes it on first access)."""
        c = self._condition
        if callable(c):
            c = float(c())
            object.__setattr__(self, "_condition", c)
        return c

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
            "slides_throughout": self.slides_throughout,
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

"""Public impact API: one impact -> ImpactResult; many -> ImpactBatch."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import IllConditionedError, ScenarioError
from .admissible import check_admissible, impulse_work
from .core import COND_LIMIT, ImpactArrays, ImpactStructure, energy_loss_fraction, solve_arrays
from .model import ImpactProblem
from .result import ImpactResult

__all__ = ["compile_problem", "solve_impact", "ImpactBatch", "CONDITION_LIMIT"]

#: Condition number of the equilibrated impulse system above which a single solve is refused
#: (the 2-norm value from an SVD; the batch path flags items by the exact 1-norm value against
#: the same limit, core.COND_LIMIT): past it, double precision leaves fewer than ~4 significant
#: digits in the impulses.
CONDITION_LIMIT = COND_LIMIT


def compile_problem(problem: ImpactProblem) -> tuple[ImpactStructure, ImpactArrays]:
    """Split an ImpactProblem into its fixed structure and a batch of one of numbers."""
    bodies = problem.bodies
    names = tuple(b.name for b in bodies)
    index = {nm: i for i, nm in enumerate(names)}
    vidx = tuple(k for k, v in enumerate(problem.vehicles) for _ in v.bodies)
    hitches, hnames, hf, hr = [], [], [], []
    for v in problem.vehicles:
        for a, b, h in zip(v.bodies[:-1], v.bodies[1:], v.hitches):
            hitches.append((index[a.name], index[b.name]))
            hnames.append(f"{a.name}-{b.name}")
            hf.append(h.front_point)
            hr.append(h.rear_point)
    cons = problem.constraints
    ext = problem.external
    surf = problem.surface
    S = ImpactStructure(
        body_names=names,
        vehicle_index=vidx,
        vehicle_names=tuple(v.name for v in problem.vehicles),
        fixed=tuple(b.is_fixed for b in bodies),
        body1=index[problem.body1],
        body2=index[problem.body2],
        hitches=tuple(hitches),
        hitch_names=tuple(hnames),
        constraint_bodies=tuple(index[c.body] for c in cons),
        constraint_names=tuple(c.name or f"constraint {i + 1}" for i, c in enumerate(cons)),
        external_bodies=tuple(index[x.body] for x in ext),
        external_names=tuple(x.name or f"impulse {i + 1}" for i, x in enumerate(ext)),
        tangential=surf.tangential.kind,
    )
    st = [problem.states[nm] for nm in names]

    def arr(values, shape):
        return np.asarray(values, dtype=float).reshape((1,) + shape)

    n, h, c, x = len(names), len(hitches), len(cons), len(ext)
    A = ImpactArrays(
        mass=arr([b.mass for b in bodies], (n,)),
        yaw_inertia=arr([b.yaw_inertia for b in bodies], (n,)),
        position=arr([s.position for s in st], (n, 2)),
        heading=arr([s.heading for s in st], (n,)),
        velocity=arr([s.velocity for s in st], (n, 2)),
        yaw_rate=arr([s.yaw_rate for s in st], (n,)),
        hitch_front_point=arr(hf, (h, 2)),
        hitch_rear_point=arr(hr, (h, 2)),
        point=arr(surf.point, (2,)),
        normal_angle=arr([surf.normal_angle], ()),
        tangent_sign=arr([surf.tangent_sign], ()),
        restitution=arr([surf.restitution], ()),
        law_value=arr([surf.tangential.value], ()),
        moment_restitution=arr([surf.moment_restitution], ()),
        constraint_point=arr([cc.point for cc in cons], (c, 2)),
        constraint_direction=arr([cc.direction for cc in cons], (c,)),
        constraint_value=arr([cc.value for cc in cons], (c,)),
        external_point=arr([xx.point for xx in ext], (x, 2)),
        external_impulse=arr([xx.impulse for xx in ext], (x, 2)),
    )
    return S, A


def _dependent_rows(Ms: np.ndarray, labels: tuple[str, ...]) -> tuple[str, ...]:
    """Equations taking part in the (near) linear dependence of an equilibrated matrix."""
    u, s, vt = np.linalg.svd(Ms)
    left = np.abs(u[:, -1])
    return tuple(lbl for lbl, w in zip(labels, left) if w > 1e-3)


def solve_impact(problem: ImpactProblem, *, check: bool = True) -> ImpactResult:
    """Solve one impact of articulated vehicles (paper Eqs. 1-8).

    Parameters
    ----------
    problem : ImpactProblem
    check : bool
        Refuse an inadmissible impact (default): a tensile normal impulse, an impulse ratio
        beyond mu_max or against the sliding, or energy created at the crush surface
        (:mod:`crashsim.impact.admissible`).  ``check=False`` returns the equations' answer
        anyway (for studies of the model itself), with a warning in ``result.warnings``.

    Returns
    -------
    ImpactResult

    Raises
    ------
    ScenarioError
        The bodies are not approaching at the contact point.
    InadmissibleImpactError
        (a ScenarioError) The coefficients cannot happen for this geometry; the message names
        the coefficient, its value and its admissible range here.
    IllConditionedError
        The equations are singular (conflicting or redundant constraints) or their
        condition number exceeds ``CONDITION_LIMIT``; the message names the equations involved.
    """
    S, A = compile_problem(problem)
    out = solve_arrays(S, A, condition=True)
    closing = float(out["closing_velocity"][0])
    if not closing < 0:
        raise ScenarioError(
            f"the contact points are not approaching: relative normal velocity {closing:+.4g} m/s along the "
            f"normal (must be < 0). Check that the normal points from {problem.body2!r} into {problem.body1!r}",
            field="impact.normal",
        )
    cond = float(out["condition"][0])
    if not out["ok"][0] or not cond < CONDITION_LIMIT:
        dep = _dependent_rows(out["matrix"][0], S.equation_labels())
        raise IllConditionedError(
            "the impact equations are singular or ill-conditioned (condition number "
            f"{cond:.3g}, limit {CONDITION_LIMIT:.0e}); linearly dependent: " + "; ".join(dep)
            + ". Remove a redundant or conflicting constraint.",
            condition_number=cond,
            dependent=dep,
        )
    work = impulse_work(S, A, out)
    if check:
        check_admissible(S, A, out, work=work)
    return ImpactResult.from_arrays(problem, S, A, out, 0, work=work)


@dataclass
class ImpactBatch:
    """Many impacts of one structure, solved at once (sweeps, fits, Monte Carlo).

    Build it from a problem, change any numbers in ``arrays`` (leading axis = sample), and
    call :meth:`solve`. The result is a dict of arrays (see :func:`crashsim.impact.core.solve_arrays`)
    plus ``energy_loss`` per vehicle and for the system, and ``delta_v``.

    Examples
    --------
    >>> batch = ImpactBatch.from_problem(problem, 1000)            # doctest: +SKIP
    >>> batch.arrays.restitution[:] = np.linspace(0, 1, 1000)      # doctest: +SKIP
    >>> out = batch.solve()                                         # doctest: +SKIP
    """

    structure: ImpactStructure
    arrays: ImpactArrays
    problem: ImpactProblem | None = field(default=None, repr=False)

    @classmethod
    def from_problem(cls, problem: ImpactProblem, n: int = 1) -> "ImpactBatch":
        if not (isinstance(n, int) and n >= 1):
            raise ScenarioError(f"batch size must be an integer >= 1, got {n!r}", field="n")
        S, A = compile_problem(problem)
        return cls(S, A.repeat(n) if n > 1 else A, problem)

    def body_index(self, name: str) -> int:
        try:
            return self.structure.body_names.index(name)
        except ValueError:
            raise ScenarioError(f"no body {name!r}; bodies are {list(self.structure.body_names)}", field="body") from None

    def solve(self, *, condition: bool = False) -> dict[str, np.ndarray]:
        S, A = self.structure, self.arrays
        out = solve_arrays(S, A, condition=condition)
        out["delta_v"] = out["velocity"] - A.velocity
        out["delta_yaw_rate"] = out["yaw_rate"] - A.yaw_rate
        vidx = np.asarray(S.vehicle_index)
        ke0, ke1 = out["ke_before"], out["ke_after"]
        for k, vn in enumerate(S.vehicle_names):
            sel = vidx == k
            out[f"energy_loss.{vn}"] = energy_loss_fraction(ke0[:, sel].sum(1), ke1[:, sel].sum(1))
        out["energy_loss.system"] = energy_loss_fraction(ke0.sum(1), ke1.sum(1))
        return out

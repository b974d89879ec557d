"""Public impact API: one impact -> ImpactResult; many -> ImpactBatch."""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field

import numpy as np

from ..errors import IllConditionedError, ScenarioError
from .admissible import check_admissible, impulse_work
from .core import (COND_LIMIT, WORK_KEYS, ImpactArrays, ImpactStructure, energy_loss_fraction, input_shapes,
                   inputs, solve_arrays, solve_packed)
from .problem import ImpactProblem
from .result import ImpactResult

__all__ = ["compile_problem", "solve_impact", "ImpactBatch", "CONDITION_LIMIT"]

#: Condition number of the equilibrated impulse system above which a single solve is refused
#: (the 2-norm value from an SVD; the batch path flags items by the exact 1-norm value against
#: the same limit, core.COND_LIMIT): past it, double precision leaves fewer than ~4 significant
#: digits in the impulses.
CONDITION_LIMIT = COND_LIMIT


#: Structures of the problems solved so far, by shape (:func:`_structure_key`): a problem that
#: differs only in its numbers reuses its structure (and the kernel's view of it).
_STRUCTURES: dict = {}
_STRUCTURES_MAX = 256


def _structure_key(problem: ImpactProblem) -> tuple:
    """Everything :class:`ImpactStructure` is made of: names, barriers, contact bodies, the
    constraints' and known impulses' bodies and names, the tangential law."""
    return (tuple((v.name, tuple((b.name, b.is_fixed) for b in v.bodies)) for v in problem.vehicles),
            problem.body1, problem.body2, tuple((c.body, c.name) for c in problem.constraints),
            tuple((x.body, x.name) for x in problem.external), problem.surface.tangential.kind)


def _structure(problem: ImpactProblem) -> ImpactStructure:
    key = _structure_key(problem)
    S = _STRUCTURES.get(key)
    if S is None:
        S = _build_structure(problem)
        if len(_STRUCTURES) >= _STRUCTURES_MAX:
            _STRUCTURES.clear()
        _STRUCTURES[key] = S
    return S


def _build_structure(problem: ImpactProblem) -> ImpactStructure:
    bodies = problem.bodies
    names = tuple(b.name for b in bodies)
    index = {nm: i for i, nm in enumerate(names)}
    hitches, hnames = [], []
    for v in problem.vehicles:
        for a, b in zip(v.bodies[:-1], v.bodies[1:]):
            hitches.append((index[a.name], index[b.name]))
            hnames.append(f"{a.name}-{b.name}")
    cons = problem.constraints
    ext = problem.external
    return ImpactStructure(
        body_names=names,
        vehicle_index=tuple(k for k, v in enumerate(problem.vehicles) for _ in v.bodies),
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
        tangential=problem.surface.tangential.kind,
    )


def _values(problem: ImpactProblem, S: ImpactStructure) -> list:
    """The numbers of a problem, packed field by field as ``core.input_shapes`` lays them out
    (a batch of one: the fields of ImpactArrays, flattened and concatenated)."""
    bodies = [b for v in problem.vehicles for b in v.bodies]
    st = [problem.states[nm] for nm in S.body_names]
    hitches = [h for v in problem.vehicles for h in v.hitches]
    surf = problem.surface
    vals = [b.mass for b in bodies]
    vals += [b.yaw_inertia for b in bodies]
    for s in st:
        vals += s.position
    vals += [s.heading for s in st]
    for s in st:
        vals += s.velocity
    vals += [s.yaw_rate for s in st]
    for h in hitches:
        vals += h.front_point
    for h in hitches:
        vals += h.rear_point
    vals += surf.point
    vals += (surf.normal_angle, surf.tangent_sign, surf.restitution, surf.tangential.value, surf.moment_restitution)
    cons = problem.constraints
    for c in cons:
        vals += c.point
    vals += [c.direction for c in cons]
    vals += [c.value for c in cons]
    for x in problem.external:
        vals += x.point
    for x in problem.external:
        vals += x.impulse
    return vals


def _arrays(S: ImpactStructure, X: np.ndarray) -> ImpactArrays:
    """ImpactArrays of a batch of one as views of the packed vector X (:func:`_values`)."""
    fields_, o = {}, 0
    for name, shape in _input_shapes(S):
        size = math.prod(shape)
        fields_[name] = X[o:o + size].reshape((1,) + shape)
        o += size
    return ImpactArrays(**fields_)


def compile_problem(problem: ImpactProblem) -> tuple[ImpactStructure, ImpactArrays]:
    """Split an ImpactProblem into its fixed structure and a batch of one of numbers.

    The structure is built once per shape of problem (bodies, hitches, constraints, known
    impulses, tangential law) and reused for problems that differ only in their numbers.
    """
    S = _structure(problem)
    return S, _arrays(S, np.array(_values(problem, S), dtype=float))


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
        Its per-body objects (``bodies``) and the SVD condition number (``condition_number``)
        are computed on first access.

    Notes
    -----
    The equations are solved by the compiled kernel (:mod:`crashsim.impact.kernel`; the
    cost of a call is measured in ``plots/impact_speed.md``). An impact that is not clearly
    approaching, solvable, well inside the condition limit and admissible is solved again by
    the dense numpy path with the SVD condition number (:func:`_solve_impact_full`), which
    words the refusal or the warning as before.

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
    S = _structure(problem)
    vals = _values(problem, S)
    X = np.array(vals, dtype=float)
    y = solve_packed(S, X)
    # The compiled solve decides alone where its answer is clear: approaching, solvable, far
    # below the condition limit (the SVD 2-norm condition number is at most K times the 1-norm
    # one) and admissible. Anything else takes the full path, whose errors and warnings it keeps.
    if (y["closing_velocity"] < -_CLOSING_CLEAR and y["ok"] == 1.0 and y["reason"] == 0.0
            and y["condition_1norm"] < CONDITION_LIMIT / (2 * S.n_unknowns)):
        inp = inputs(S, X.tolist())
        return ImpactResult.from_item(problem, S, inp, y, dict(zip(WORK_KEYS, y["work"])), 0,
                                      functools.partial(_condition_number, S, X))
    return _solve_impact_full(problem, S, _arrays(S, X), check)


def _input_shapes(S: ImpactStructure) -> tuple:
    return input_shapes(S.n_bodies, len(S.hitches), len(S.constraint_bodies), len(S.external_bodies))


#: Closing speed [m/s] below which the single solve leaves the decision "approaching or not"
#: to the full path (the two paths compute it with different roundings).
_CLOSING_CLEAR = 1e-9


def _condition_number(S: ImpactStructure, X: np.ndarray) -> float:
    """The 2-norm condition number of a single solve's equilibrated system (the full path's SVD)."""
    return float(solve_arrays(S, _arrays(S, X), condition=True, method="dense")["condition"][0])


def _solve_impact_full(problem: ImpactProblem, S: ImpactStructure, A: ImpactArrays, check: bool) -> ImpactResult:
    """:func:`solve_impact` by the dense numpy path with the SVD condition number: the
    reference path, and the one that words every refusal."""
    out = solve_arrays(S, A, condition=True, method="dense")
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


def _row_sum(a: np.ndarray, cols: list) -> np.ndarray:
    """a[:, cols].sum(axis=1) by adding whole columns (numpy's order below 8 terms; a reduction
    over a short last axis is several times slower on large batches)."""
    if len(cols) >= 8:
        return a[:, cols].sum(axis=1)
    acc = a[:, cols[0]].copy()
    for c in cols[1:]:
        acc += a[:, c]
    return acc


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
        ke0, ke1 = out["ke_before"], out["ke_after"]
        for k, vn in enumerate(S.vehicle_names):
            sel = [b for b, v in enumerate(S.vehicle_index) if v == k]
            out[f"energy_loss.{vn}"] = energy_loss_fraction(_row_sum(ke0, sel), _row_sum(ke1, sel))
        every = list(range(S.n_bodies))
        out["energy_loss.system"] = energy_loss_fraction(_row_sum(ke0, every), _row_sum(ke1, every))
        return out

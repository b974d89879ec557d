"""Work of every impulse of an impact, and which impacts are physically admissible.

Work of an impulse
------------------
An impulse ``lambda_k`` acting through row ``J_k`` of the Jacobian (see
:mod:`crashsim.impact.core`) does the work ``lambda_k (u_k^- + u_k^+) / 2`` on the system, where
``u_k = J_k q`` is the velocity it acts on (a relative velocity of the contact points, a pin
velocity mismatch, a constrained velocity) before (``-``) and after (``+``) the impact: for an
impulse the force integral times the mean velocity of its point of application (exact, because
the velocities change linearly with the impulse during the impact).  A known external impulse
``p`` at a point does ``p . (v^- + v^+) / 2``.  The change of the kinetic energy is the sum of
all of them::

    KE^+ - KE^- = W_n + W_t + W_M + W_hitches + W_constraints + W_external

with ``W_n = P_n (u_n^- + u_n^+)/2``, ``W_t = P_t (u_t^- + u_t^+)/2`` (the crush surface's
normal and tangential impulse on the relative contact-point velocity) and ``W_M = M
(Omega^- + Omega^+)/2`` (the moment impulse on the relative yaw rate).  The hitch impulses do no
work (the pin velocities are equal before the impact and are made equal by it).  The energy
lost at the crush surface is ``-(W_n + W_t + W_M)``, split into its normal, tangential and
moment parts (Brach's work-energy partition of the crush energy).

Admissibility
-------------
Brach's equations accept coefficients that no collision can produce.  An impact is
*admissible* when

1. the normal impulse is compressive, ``P_n >= 0`` (surfaces push, they do not pull);
2. with a given impulse ratio mu (``tangential = "ratio"``): ``0 <= mu / mu_max <= 1``: the
   tangential impulse opposes the sliding and does not reverse it (mu_max is the ratio that
   just stops the sliding at separation; paper, Eq. 8 and the text around it).  Where the
   no-sliding solution needs a tensile normal impulse, no compressive impact can stop the
   sliding and mu_max is no bound: the contact slides throughout, and mu must oppose the
   initial tangential slip u_t (``mu u_t <= 0``, Coulomb) without reversing it (the
   tangential separation velocity keeps the sign of u_t).  The friction law takes
   ``mu = -f sign(u_t)`` there; a body glancing off a wall at a shallow angle is the
   closed-form case (``P_t = -f P_n sign(u_t)``, tests/analytic/test_contact.py);
3. the crush surface does not create energy: ``W_n + W_t + W_M <= 0``.  Without external or
   constraint impulses this is "no kinetic-energy gain"; with them, "no gain beyond the work
   those impulses do" (which is computed and reported).

(The restitution coefficients' ranges, ``0 <= e <= 1`` and ``e' = -1`` or ``0 <= e' <= 1``
(paper, after Eq. 6), are checked where the inputs are built.)  Rule 3 bounds e and e' for a
given geometry: with no sliding at separation, a large e can gain energy (the tangential
impulse that stops the sliding then does positive work), and so can an e' above
``k^2/d^2``-like limits of the configuration.  :func:`check_admissible` names the coefficient,
its value and the admissible range for this geometry, found by solving the same impact over
that coefficient's range.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ..errors import InadmissibleImpactError
from . import kernel
from .kernel import REL_ENERGY, REL_IMPULSE, REL_RATIO
from .core import MU_MAX_LIMIT, WORK_KEYS, ImpactArrays, ImpactStructure, contiguous, kernel_structure, solve_arrays

__all__ = ["impulse_work", "admissibility", "check_admissible", "REASONS"]

#: Why an impact is inadmissible (codes returned by :func:`admissibility`).
REASONS = {
    0: "admissible",
    1: "tensile normal impulse",
    2: "impulse ratio beyond mu_max (sliding reverses)",
    3: "impulse ratio drives the sliding",
    4: "energy created at the crush surface",
    5: "not solvable",
}

#: Largest |mu| searched for the admissible range of a sliding-throughout impact (the friction
#: coefficients of crashsim's inputs lie in [0, 5]).
_MU_SEARCH = 5.0


def impulse_work(S: ImpactStructure, A: ImpactArrays, out: dict) -> dict[str, np.ndarray]:
    """Work [J] done on the system by each group of impulses of a solved batch (module docstring).

    Returns
    -------
    dict of ndarray, shape (B,)
        ``normal``, ``tangential``, ``moment`` (crush surface), ``hitches``, ``constraints``,
        ``external``; their sum equals ``KE_after - KE_before`` of the batch item.

    The formula is coded once, in :func:`crashsim.impact.kernel.impulse_work_item` (compiled;
    the single solve calls it inside its kernel).
    """
    W = kernel.work_batch(kernel_structure(S), kernel.pack_items(A), contiguous(out["velocity"]), contiguous(out["yaw_rate"]),
                          contiguous(out["impulses"]))
    return {key: W[:, j] for j, key in enumerate(WORK_KEYS)}


def admissibility(S: ImpactStructure, A: ImpactArrays, out: dict, work: dict | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Which items of a solved batch are admissible (rules 1-3 of the module docstring).

    Returns
    -------
    (ok, reason) : ndarray of bool, ndarray of int, shape (B,)
        ``reason`` indexes :data:`REASONS` (0 where admissible; the first rule broken otherwise).
    The rules are coded once, in :func:`crashsim.impact.kernel.reason_item` (compiled; the
    single solve calls it inside its kernel), with the allowances of this module.
    """
    work = impulse_work(S, A, out) if work is None else work
    W = np.ascontiguousarray(np.stack([np.broadcast_to(work[key], (A.size,)) for key in WORK_KEYS], axis=1),
                             dtype=float)
    reason = kernel.reason_batch(np.ascontiguousarray(out["ok"], dtype=bool), contiguous(out["impulses"]),
                                  kernel.LAW_CODES[S.tangential], contiguous(A.law_value), contiguous(out["mu_max"]),
                                  contiguous(out["no_slide_normal"]), contiguous(out["approach_tangential"]),
                                  contiguous(out["separation_tangential"]), contiguous(out["ke_before"].sum(axis=1)), W,
                                  kernel.limits())
    return reason == 0, reason


def _fmt(x: float) -> str:
    return f"{x:.4g}"


def _sweep(S: ImpactStructure, A: ImpactArrays, field: str, values: np.ndarray) -> np.ndarray:
    """Admissible flags of the impact with ``field`` set to each of ``values``."""
    B = len(values)
    batch = replace(A, **{f: np.repeat(getattr(A, f), B, axis=0) for f in A.__dataclass_fields__})
    getattr(batch, field)[:] = values
    out = solve_arrays(S, batch, method="dense")
    return admissibility(S, batch, out)[0]


def _interval(S, A, field, lo, hi, anchor) -> tuple[float, float] | None:
    """The admissible interval of ``field`` within [lo, hi] that contains ``anchor`` (None if ``anchor`` is not admissible).

    A grid of 201 values, then bisection of each end to ~1e-4 of the range.
    """
    grid = np.linspace(lo, hi, 201)
    grid = np.unique(np.concatenate([grid, [anchor]]))
    ok = _sweep(S, A, field, grid)
    i = int(np.searchsorted(grid, anchor))
    if not ok[i]:
        return None
    a = i
    while a > 0 and ok[a - 1]:
        a -= 1
    b = i
    while b < len(grid) - 1 and ok[b + 1]:
        b += 1
    ends = []
    for inside, outside in ((grid[a], grid[a - 1] if a > 0 else None), (grid[b], grid[b + 1] if b < len(grid) - 1 else None)):
        if outside is None:
            ends.append(inside)
            continue
        good, bad = inside, outside
        for _ in range(12):
            mids = np.linspace(good, bad, 9)[1:-1]
            flags = _sweep(S, A, field, mids)
            k = int(np.argmin(flags)) if not flags.all() else len(mids)
            good = mids[k - 1] if k > 0 else good
            bad = mids[k] if k < len(mids) else bad
            if abs(bad - good) <= 1e-4 * (hi - lo):
                break
        ends.append(good)
    return min(ends), max(ends)


def _tensile_cause(S: ImpactStructure, A: ImpactArrays) -> str:
    """The end of the tensile-impulse message: the tangential law to change, or, where the normal
    impulse is tensile without any tangential impulse too (mu = 0), the inputs that pull the
    surfaces apart instead (velocity constraints, external impulses or the states)."""
    frictionless = solve_arrays(replace(S, tangential="ratio"), replace(A, law_value=np.zeros(1)), method="dense")
    if not frictionless["normal_impulse"][0] > 0.0:
        given = [what for what, there in (("velocity constraints", S.constraint_bodies),
                                          ("external impulses", S.external_bodies)) if there]
        by = " and ".join(given) if given else "states (the surfaces are not closing at the contact point)"
        return (f" even without a tangential impulse (mu = 0 gives P_n = {_fmt(float(frictionless['normal_impulse'][0]))}"
                f" N s): the impact's {by} drive them apart: check those before the tangential law")
    return {"no_slide": " to stop the sliding (a sideswipe); use tangential = \"friction\" or \"ratio\"",
            "friction": " (a sideswipe); use a smaller friction f or tangential = \"ratio\" with a smaller |mu|",
            "ratio": " (a sideswipe); use a smaller |mu| or tangential = \"friction\"",
            "fraction": " (a sideswipe); use a smaller fraction of mu_max or tangential = \"friction\""}[S.tangential]


def check_admissible(S: ImpactStructure, A: ImpactArrays, out: dict, *, work: dict | None = None) -> None:
    """Raise :class:`~crashsim.errors.InadmissibleImpactError` if the (single) impact is inadmissible.

    The message names the coefficient to change, its value and its admissible range for this
    geometry (found by re-solving the impact over that coefficient's range), in the file's
    keys (``impact.mu``, ``impact.restitution``, ``impact.moment_restitution``,
    ``impact.tangential``).
    """
    ok, reason = admissibility(S, A, out, work)
    if ok[0] or reason[0] == 5:
        return
    code = int(reason[0])
    law = S.tangential
    e = float(A.restitution[0])
    ep = float(A.moment_restitution[0])
    mu_max = float(out["mu_max"][0])
    pn = float(out["normal_impulse"][0])
    work = impulse_work(S, A, out) if work is None else work
    ke0 = float(out["ke_before"][0].sum())
    created = float(work["normal"][0] + work["tangential"][0] + work["moment"][0])
    share = f"{100 * created / ke0:.3g} % of the kinetic energy before the impact" if ke0 > 0 else f"{created:.4g} J"

    if law == "ratio" and code in (2, 3):
        mu = float(A.law_value[0])
        slip = float(out["approach_tangential"][0])
        stoppable = float(out["no_slide_normal"][0]) > 0.0 and abs(mu_max) <= MU_MAX_LIMIT
        if stoppable:
            lo, hi = sorted((0.0, mu_max))
        else:  # sliding throughout: any ratio against the slip, up to where it would reverse it
            lo, hi = sorted((0.0, -math.copysign(_MU_SEARCH, slip)))
        rng = _interval(S, A, "law_value", lo, hi, 0.0)
        allowed = f"{_fmt(rng[0])} <= mu <= {_fmt(rng[1])}" if rng else "no impulse ratio"
        if not stoppable:
            why = ("drives the sliding (the no-slide solution would need a tensile normal impulse here, so the "
                   f"contact slides throughout and mu must oppose the initial tangential slip {_fmt(slip)} m/s)"
                   if code == 3 else "would reverse the sliding")
        elif code == 2:
            why = f"exceeds mu_max = {_fmt(mu_max)} for this geometry: the sliding would reverse"
        else:
            why = (f"has the opposite sign of mu_max = {_fmt(mu_max)} for this geometry: the tangential impulse "
                   "would drive the sliding instead of resisting it")
        raise InadmissibleImpactError(f"impact.mu = {_fmt(mu)} {why}; use {allowed} or tangential = \"no_slide\"",
                                      field="impact.mu", reason=REASONS[code], value=mu, allowed=rng)
    if code == 1:
        raise InadmissibleImpactError(
            f"impact.tangential = \"{law}\" needs a tensile normal impulse here (P_n = {_fmt(pn)} N s < 0): the "
            f"surfaces would have to pull on each other{_tensile_cause(S, A)}",
            field="impact.tangential", reason=REASONS[code], value=pn, allowed=None)
    # energy created at the crush surface: blame e' if the moment impulse does it, else e
    if ep >= 0.0:
        base = replace(A, moment_restitution=np.array([-1.0]))
        no_moment = solve_arrays(S, base, method="dense")
        if admissibility(S, base, no_moment)[0][0]:
            rng = _interval(S, A, "moment_restitution", 0.0, 1.0, 0.0)
            allowed = f"-1 or {_fmt(rng[0])} <= e' <= {_fmt(rng[1])}" if rng else "-1 (no moment impulse)"
            raise InadmissibleImpactError(
                f"impact.moment_restitution = {_fmt(ep)} creates energy at the crush surface ({share}); "
                f"admissible for this geometry: {allowed}",
                field="impact.moment_restitution", reason=REASONS[code], value=ep, allowed=rng)
    rng = _interval(S, A, "restitution", 0.0, max(e, 1e-12), 0.0) if e > 0 else None
    allowed = f"0 <= e <= {_fmt(rng[1])}" if rng else "no restitution coefficient"
    law_hint = {"no_slide": " with no sliding at separation (or use tangential = \"friction\")",
                "ratio": f" with mu = {_fmt(float(A.law_value[0]))}",
                "fraction": f" with mu = {_fmt(float(A.law_value[0]))} x mu_max",
                "friction": f" with friction f = {_fmt(float(A.law_value[0]))}"}[law]
    raise InadmissibleImpactError(
        f"impact.restitution = {_fmt(e)} creates energy at the crush surface ({share}) for this geometry"
        f"{law_hint}; admissible: {allowed}",
        field="impact.restitution", reason=REASONS[code], value=e, allowed=rng)

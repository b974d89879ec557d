"""The run-out tolerance that samples need: integration error negligible beside their evidence.

A fit, Monte Carlo or posterior sample needs the run-out only as accurately as its evidence is
measured or checked. :func:`evidence_tolerance` gives the loosest ``rtol`` whose bound on the
integration error stays at :data:`EVIDENCE_SHARE` of the smallest sigma (posterior) or tolerance
(Monte Carlo) of the evidence the run-out feeds (``docs/posterior.md``, "The samples' integration
tolerance").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from ..units import format_value

__all__ = ["EVIDENCE_SHARE", "LOOSEST_RTOL", "SampleTolerance", "evidence_tolerance", "tolerance_items",
           "with_tolerance"]

#: Tolerance rule of the samples (``[posterior] tolerance = "evidence"``): the integration error of
#: the run-out is bounded by EVIDENCE_SHARE of the smallest sigma of the evidence it feeds.
EVIDENCE_SHARE = 0.01
#: The loosest relative tolerance the rule gives (a run-out must still resolve its events).
LOOSEST_RTOL = 1e-4


@dataclass(frozen=True)
class SampleTolerance:
    """The run-out tolerance of the posterior's samples and how it was chosen (:func:`evidence_tolerance`).

    ``rtol``, ``atol``: what the samples integrate at; ``file_rtol``, ``file_atol``: the scenario's;
    ``rule``: the sentence of the report that says why (SI); ``bound``: the evidence bound that chose
    ``rtol`` -- ``(quantity, sigma, scale, what)``, SI -- from which :meth:`text` writes the sentence in
    a report's units (empty: no bound, ``rule`` as it is).
    """

    rtol: float
    atol: float
    file_rtol: float
    file_atol: float
    rule: str
    bound: tuple = ()

    def text(self, system: str = "SI") -> str:
        """``rule`` with its sigma and scale in the units of ``system`` ("SI", "US")."""
        return _rule_text(self.rtol, self.file_rtol, self.bound, system) if self.bound else self.rule

    @property
    def changed(self) -> bool:
        return self.rtol != self.file_rtol or self.atol != self.file_atol

    def to_dict(self) -> dict:
        return dict(self.__dict__)


def evidence_tolerance(items, scene, rtol: float, atol: float, what: str = "sigma") -> SampleTolerance:
    """The loosest run-out tolerance whose integration error stays negligible beside the evidence.

    The integration error of a rest position is at most about ``rtol * D`` (``D`` the longest
    CG path of a body; the floor of :mod:`crashsim.motion.accuracy`, which overestimates the
    measured error of the shipped fit scene about tenfold), of a heading ``rtol * max(|change|,
    1 rad)``, of a speed ``rtol * v`` (``v`` the largest body speed at separation). The rule keeps
    each bound at :data:`EVIDENCE_SHARE` (1 %) of the smallest sigma of the evidence of its kind
    (rest positions and tyre marks; rest headings; recorder speeds), so that the likelihood moves by
    at most about ``(0.01)^2`` per item::

        rtol_s = min(0.01 sigma_len / D,  0.01 sigma_ang / max(dpsi, 1),  0.01 sigma_v / v)

    and the samples integrate at ``min(max(rtol, rtol_s), LOOSEST_RTOL)`` (never tighter than the
    file's ``rtol``), with ``atol`` scaled by the same factor (the file's ratio kept). Evidence that
    the run-out does not reach (point of impact, delta-v, crush) sets no bound. ``D``, ``dpsi`` and
    ``v`` are read off ``scene`` (the scene at the start values, integrated at the file's
    tolerance).

    Parameters
    ----------
    items : sequence
        Evidence items with ``kind``, ``quantity`` and ``sigma`` [SI]: those of
        :class:`~crashsim.reconstruct.fit.EvidenceModel` (the posterior: measurement sigmas), or
        :func:`tolerance_items` (Monte Carlo: the checks' tolerances).
    scene : SceneResult
    rtol, atol : float
        The scenario's run-out tolerances.
    what : str
        What the items' ``sigma`` is, for the rule's sentence (``"sigma"``, ``"tolerance"``).
    """
    path = turn = speed = 0.0
    for r in scene.runout.values():
        for b in r.bodies.values():
            path = max(path, float(b.distance))
            turn = max(turn, abs(float(b.final.heading) - float(b.initial.heading)))
            speed = max(speed, math.hypot(*b.initial.velocity))
    bounds = []
    runout_kinds = {"rest", "rest heading", "mark", "recorder"}
    for quantity, scale in (("length", max(path, 1.0)), ("angle", max(turn, 1.0)), ("speed", max(speed, 1.0))):
        sig = [it.sigma for it in items if it.kind in runout_kinds and it.quantity == quantity]
        if sig:
            bounds.append((EVIDENCE_SHARE * min(sig) / scale, (quantity, min(sig), scale, what)))
    if not bounds:
        return SampleTolerance(rtol, atol, rtol, atol, "the file's tolerance (no evidence of the run-out sets a bound)")
    bound, why = min(bounds)
    new = min(max(rtol, bound), LOOSEST_RTOL) if rtol < LOOSEST_RTOL else rtol
    return SampleTolerance(new, atol * new / rtol, rtol, atol, _rule_text(new, rtol, why, "SI"), why)


#: What bounds the integration error of each kind of evidence, in the rule's sentence.
_SCALES = {"length": "the longest CG path", "angle": "the largest heading change", "speed": "the largest speed"}


def _rule_text(new: float, rtol: float, bound: tuple, system: str) -> str:
    """The sentence of :attr:`SampleTolerance.rule` for ``bound`` (quantity, sigma, scale, what), in ``system``."""
    quantity, sigma, scale, what = bound
    capped = EVIDENCE_SHARE * sigma / scale > LOOSEST_RTOL and new == LOOSEST_RTOL
    shown = (lambda v: format(v, ".3g") + " rad") if quantity == "angle" else (  # noqa: E731
        lambda v: format_value(v, quantity, system, 3))
    return (f"rtol {new:.3g} (file {rtol:.3g}): the integration error bound rtol x scale is at most "
            f"{EVIDENCE_SHARE:g} x the smallest {quantity} {what} {shown(sigma)} over {_SCALES[quantity]} "
            f"{shown(scale)}" + (f", capped at {LOOSEST_RTOL:g}" if capped else ""))


@dataclass(frozen=True)
class _Item:
    kind: str
    quantity: str
    sigma: float


def tolerance_items(evidence) -> list:
    """The run-out evidence of a scenario as items for :func:`evidence_tolerance`, each with its
    check's tolerance as the scale (rest positions and headings, tyre marks, recorder speeds; the
    approach integrates at the run-out's tolerance, so its marks and recorder count too)."""
    out = []
    for r in evidence.rest:
        out.append(_Item("rest", "length", float(r.tolerance)))
        if r.heading is not None and r.heading_tolerance is not None:
            out.append(_Item("rest heading", "angle", float(r.heading_tolerance)))
    for m in evidence.marks:  # run-out and approach marks: the approach integrates at the run-out's tolerance
        out.append(_Item("mark", "length", float(m.tolerance)))
    for x in evidence.recorder:
        out.append(_Item("recorder", "speed", float(x.tolerance)))
    return out


def with_tolerance(data: dict, tol: SampleTolerance) -> dict:
    """The file contents ``data`` with the ``[runout]`` rtol and atol of ``tol`` (the rest shared)."""
    return dict(data, runout=dict(data["runout"], rtol=tol.rtol, atol=tol.atol))

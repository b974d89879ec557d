"""Crush energy (CRASH3) as evidence: the bodies' crush energies against the impacts' energy loss.

Each ``[[evidence.crush]]`` item is the measured damage of one face of one body: the CRASH3
stiffness coefficients A and B with the damage width and crush profile, or an energy equivalent
speed (EES) directly.  Items are compared per *group*: all items with the same ``impacts``
setting ("first": the damage is from the first impact; "all": from all the impacts of the body).
A group's check compares the sum of its crush energies with the energy the impact model loses at
the crush surface in the impacts counted (the first impact, or every impact of the group's
bodies), by the work of the impulses (:attr:`crashsim.impact.ImpactResult.energy_loss_normal`
and friends):

``compare = "total"`` (default)
    sum of the CRASH3 energies *with* the force-direction factor  vs  T_n + T_t + T_M;
``compare = "normal"``
    sum of the CRASH3 energies *without* the factor  vs  T_n + T_M (Brach & Brach's partition:
    the normal work is the crush, the tangential work is sliding and snagging along the contact).

The residual is computed minus measured: the model's loss minus the crush energy [J].  If a
movable body of a counted impact has no crush item, the sum is a lower bound of the energy
absorbed and the check is one-sided (it fails only if the crush energy exceeds the model's loss by
more than the tolerance).  All SI.  The numeric core is :mod:`crashsim.impact.crush`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..impact.crush import (energy_equivalent_speed, face_angle, force_direction_factor, profile_energy)
from .outcome import Check

__all__ = ["CrushEvidence", "crush_groups", "crush_checks", "group_impacts", "profile_outline", "GROUP_TITLES"]

#: Label of each ``impacts`` setting in check names.
GROUP_TITLES = {"first": "first impact", "all": "all impacts"}


@dataclass(frozen=True)
class CrushEvidence:
    """The measured crush of one face of one body (SI).

    Either ``A`` [N/m], ``B`` [N/m^2], ``width`` [m] and ``profile`` (2, 4 or 6 crush depths [m]),
    or ``ees`` [m/s].  ``offset`` [m] places the centre of the damage along the face from the
    face's centre (front/rear: along the body's y, to the left; left/right: along x, forward);
    it is drawn, not used in the energy.  ``mass`` [kg] is the body's (for the EES).
    ``tolerance`` [J] or ``relative_tolerance`` (of this item's crush energy) is the item's share of
    the group's tolerance.  ``source`` says where A and B come from.
    """

    body: str
    face: str
    mass: float
    A: float | None = None
    B: float | None = None
    width: float | None = None
    profile: tuple[float, ...] | None = None
    offset: float = 0.0
    ees: float | None = None
    tolerance: float | None = None
    relative_tolerance: float | None = None
    impacts: str = "first"
    compare: str = "total"
    correction: bool = True
    source: str = "given"
    name: str = ""
    sigma: float | None = None  # measurement uncertainty of its energy [J] (fit, posterior)

    @property
    def energy_uncorrected(self) -> float:
        """CRASH3 energy of the profile without the force-direction factor, or 1/2 m EES^2 [J]."""
        if self.ees is not None:
            return 0.5 * self.mass * self.ees ** 2
        return profile_energy(self.A, self.B, self.width, self.profile)


def crush_groups(items) -> list[tuple[str, list[int]]]:
    """The groups of crush items by their ``impacts`` setting, in order of first appearance:
    ``[(impacts, [item indices])]``.  One check each."""
    groups: dict[str, list[int]] = {}
    for i, it in enumerate(items):
        groups.setdefault(it.impacts, []).append(i)
    return list(groups.items())


def _contact_impacts(body: str, impact, secondary, which: str) -> list[tuple[float, object]]:
    """``[(time, ImpactResult)]`` of the impacts in which ``body`` was one of the two bodies in contact."""
    out = []
    if body in (impact.body1, impact.body2):
        out.append((0.0, impact))
    if which == "all":
        out += [(float(s.t), s.result) for s in secondary if body in (s.body1, s.body2) and s.result is not None]
    return out


def group_impacts(bodies, impact, secondary, which: str) -> list[tuple[float, object]]:
    """The impacts a group of crushed bodies is compared with, in time order: the first impact
    (``which = "first"``), or every impact in which one of ``bodies`` was in contact (``"all"``)."""
    if which == "first":
        return [(0.0, impact)]
    seen, out = set(), []
    for b in bodies:
        for t, r in _contact_impacts(b, impact, secondary, "all"):
            if id(r) not in seen:
                seen.add(id(r))
                out.append((t, r))
    return sorted(out, key=lambda x: x[0])


def _item_result(it: CrushEvidence, own) -> dict:
    """Energy, angle and factor of one item; ``own`` its body's counted impacts."""
    d = {"face": it.face, "source": it.source, "offset": it.offset, "name": it.name}
    if it.ees is not None:
        d.update(ees_given=it.ees)
    else:
        d.update(A=it.A, B=it.B, width=it.width, profile=list(it.profile))
    raw = it.energy_uncorrected
    alpha = pdof = None
    factor, capped = 1.0, False
    warn = []
    if own:
        # the PDOF of the body's largest crush impulse among the counted impacts
        t, main = max(own, key=lambda x: float(abs(x[1].normal_impulse) + abs(x[1].tangential_impulse)))
        pdof = main.bodies[it.body].pdof
        alpha = face_angle(pdof, it.face)
        if abs(alpha) > math.pi / 2:
            warn.append(f"the computed force on {it.body} (PDOF {math.degrees(pdof):.1f} deg) does not push into "
                        f"its {it.face} face (angle to the face normal {math.degrees(alpha):.1f} deg): check the face")
        if it.ees is None and it.correction:
            factor, capped = force_direction_factor(alpha)
            if capped:
                warn.append(f"{it.body} {it.face}: the force is {abs(math.degrees(alpha)):.1f} deg from the face "
                            "normal, beyond the 45 deg to which CRASH3's factor 1 + tan^2(alpha) applies; "
                            "the factor is held at 2")
    d.update(pdof=pdof, alpha=alpha, factor=factor, factor_capped=capped, energy_uncorrected=raw,
             energy=factor * raw, warnings=warn)
    d["tolerance"] = it.tolerance if it.tolerance is not None else (
        it.relative_tolerance * d["energy"] if it.relative_tolerance is not None else 0.0)
    return d


def crush_checks(items, impact, secondary=()) -> list:
    """One :class:`~crashsim.evidence.checks.Check` (kind ``"crush energy"``, quantity
    ``"energy"``) per group of crush items (:func:`crush_groups`), in group order.

    ``details`` holds ``bodies`` (per body: ``energy`` and ``energy_uncorrected`` [J], ``ees``
    [m/s], ``mass`` and ``items`` with each item's A, B, width, profile, PDOF, angle to the face
    normal ``alpha`` [rad], ``factor`` and energy), ``impacts_counted`` (per impact: time, bodies,
    ``energy_loss`` (kinetic) and the work parts ``normal``, ``tangential``, ``moment`` [J]),
    ``computed`` (the model's loss compared) and ``measured`` (the crush energy compared),
    ``complete`` and ``missing`` (movable bodies in contact without a crush item), ``warnings``.
    """
    checks = []
    for which, idx in crush_groups(items):
        group = [items[i] for i in idx]
        compare = group[0].compare
        names = list(dict.fromkeys(it.body for it in group))
        title = f"crush energy, {GROUP_TITLES[which]}"
        bodies: dict[str, dict] = {}
        warnings: list[str] = []
        for it in group:
            own = _contact_impacts(it.body, impact, secondary, which)
            r = _item_result(it, own)
            b = bodies.setdefault(it.body, {"mass": it.mass, "energy": 0.0, "energy_uncorrected": 0.0, "items": [],
                                            "in_contact": bool(own)})
            b["energy"] += r["energy"]
            b["energy_uncorrected"] += r["energy_uncorrected"]
            b["items"].append(r)
            warnings += r["warnings"]
        for b in bodies.values():
            b["ees"] = energy_equivalent_speed(b["energy"], b["mass"])
            b["ees_uncorrected"] = energy_equivalent_speed(b["energy_uncorrected"], b["mass"])
        tolerance = sum(r["tolerance"] for b in bodies.values() for r in b["items"])
        absent = [n for n, b in bodies.items() if not b["in_contact"]]
        if absent:
            where = "the first impact" if which == "first" else "any impact"
            checks.append(Check("crush energy", title, math.inf, tolerance, False, "energy",
                                {"impacts": which, "compare": compare, "bodies": bodies, "warnings": warnings,
                                 "reason": f"{', '.join(absent)} not in contact in {where}"}))
            continue
        counted = group_impacts(names, impact, secondary, which)
        rows, missing = [], []
        for t, r in counted:
            ke = r.kinetic_energy["system"]
            rows.append({"time": t, "body1": r.body1, "body2": r.body2, "energy_loss": ke["before"] - ke["after"],
                         "normal": r.energy_loss_normal, "tangential": r.energy_loss_tangential,
                         "moment": r.energy_loss_moment, "crush_surface": r.energy_loss_crush})
            for n in (r.body1, r.body2):
                if not r.bodies[n].fixed and n not in bodies and n not in missing:
                    missing.append(n)
        if compare == "normal":
            computed = sum(x["normal"] + x["moment"] for x in rows)
            measured = sum(b["energy_uncorrected"] for b in bodies.values())
        else:
            computed = sum(x["crush_surface"] for x in rows)
            measured = sum(b["energy"] for b in bodies.values())
        res = computed - measured
        complete = not missing
        passed = abs(res) <= tolerance if complete else res >= -tolerance
        checks.append(Check("crush energy", title, res, tolerance, passed, "energy",
                            {"impacts": which, "compare": compare, "computed": computed, "measured": measured,
                             "ratio": measured / computed if computed > 0 else None, "complete": complete,
                             "missing": missing, "bodies": bodies, "impacts_counted": rows, "warnings": warnings}))
        if missing:
            checks[-1].details["reason"] = (f"lower bound: no crush item for {', '.join(missing)}, so the crush energy "
                                            "is checked only not to exceed the loss")
    return checks


def profile_outline(body, item: CrushEvidence):
    """The crushed region of a crush item in the body's axes [m], shape (N + 2, 2), or None.

    The undeformed face between the damage ends, then the crushed points C_N..C_1 (each moved
    into the body along the face's inward normal by its crush depth): a closed polygon, to scale.
    Stations run from the body's left to its right on the front and rear faces and from front to
    rear on the sides; ``offset`` moves the centre of the damage along the face.  None for an
    EES item or a body without an outline (length and width).
    """
    if item.profile is None or body.length is None or body.width is None:
        return None
    cx, cy = body.outline_center
    hl, hw = body.length / 2, body.width / 2
    n = len(item.profile)
    s = item.width / 2 - np.arange(n) * item.width / (n - 1)  # +L/2 .. -L/2 along the face's axis
    c = np.asarray(item.profile, dtype=float)
    if item.face in ("front", "rear"):
        x0, inward = (cx + hl, -1.0) if item.face == "front" else (cx - hl, 1.0)
        y = cy + item.offset + s
        face = np.column_stack([np.full(n, x0), y])
        crushed = np.column_stack([x0 + inward * c, y])
    else:
        y0, inward = (cy + hw, -1.0) if item.face == "left" else (cy - hw, 1.0)
        x = cx + item.offset + s
        face = np.column_stack([x, np.full(n, y0)])
        crushed = np.column_stack([x, y0 + inward * c])
    return np.vstack([face[[0, -1]], crushed[::-1]])

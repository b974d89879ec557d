"""CRASH3 crush energy: the numeric core (SI floats, no units, no I/O).

The crush model of CRASH3 (Campbell 1974; NHTSA CRASH3 manual, DOT HS 805 732, 1981) takes
the force per unit width of damage as linear in the residual crush depth C,

    F/w = A + B C                                   [N/m],  A [N/m], B [N/m^2]

so the energy per unit width absorbed up to a residual crush C, including the energy G = A^2/(2B)
absorbed without permanent crush, is

    e(C) = A C + B C^2/2 + G = (A + B C)^2 / (2B)   [J/m].

The damage is measured as N = 2, 4 or 6 equally spaced crush depths C_1..C_N over the damage
width L; the crush is taken as linear between stations (segment width L/(N-1)).  Integrating
e(C) exactly over each linear segment gives

    E = (L/(N-1)) sum_i [ A (C_i + C_i+1)/2 + B (C_i^2 + C_i C_i+1 + C_i+1^2)/6 + G ]

which for N = 6 is the CRASH3/NASS six-point formula.  An oblique crush force is accounted for by
the force-direction factor 1 + tan^2(alpha) = 1/cos^2(alpha), alpha the angle of the force to the
normal of the damaged face, applied only up to |alpha| = 45 deg (factor 2), as CRASH practice does.
See ``docs/crush-energy.md`` for the sources and conventions.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["PROFILE_COUNTS", "FACES", "MAX_FACTOR_ANGLE", "crush_energy", "profile_energy", "uniform_energy",
           "force_direction_factor", "face_angle", "energy_equivalent_speed", "campbell_coefficients",
           "campbell_slope"]

#: Allowed numbers of crush measurements over the damage width.
PROFILE_COUNTS = (2, 4, 6)

#: Direction each damaged face is struck from, as a PDOF (SAE J224: where the force comes from,
#: clockwise from the heading) [rad]: a force square onto the face.
FACES = {"front": 0.0, "right": math.pi / 2, "rear": math.pi, "left": -math.pi / 2}

#: Largest angle of the force to the face normal for which the factor 1 + tan^2(alpha) is applied
#: [rad]; beyond it the factor is held at its value there, 2.
MAX_FACTOR_ANGLE = math.pi / 4


def _check(A: float, B: float, width: float, profile: Sequence[float]) -> list[float]:
    c = [float(x) for x in profile]
    if len(c) not in PROFILE_COUNTS:
        raise ValueError(f"{len(c)} crush depths; allowed 2, 4 or 6 (equally spaced over the damage width)")
    if any(not math.isfinite(x) or x < 0 for x in c):
        raise ValueError(f"crush depths {c} m; allowed finite values >= 0")
    if not (B > 0 and math.isfinite(B)):
        raise ValueError(f"B = {B!r} N/m^2; allowed a finite stiffness > 0")
    if not (A >= 0 and math.isfinite(A)):
        raise ValueError(f"A = {A!r} N/m; allowed a finite value >= 0")
    if not (width > 0 and math.isfinite(width)):
        raise ValueError(f"width = {width!r} m; allowed a finite length > 0")
    return c


def profile_energy(A: float, B: float, width: float, profile: Sequence[float]) -> float:
    """CRASH3 crush energy of a measured profile, without the force-direction factor [J].

    Parameters
    ----------
    A : float
        Force per unit width at zero residual crush [N/m].
    B : float
        Crush stiffness per unit width [N/m^2], > 0.
    width : float
        Damage width L [m].
    profile : sequence of float
        2, 4 or 6 residual crush depths [m], equally spaced over the width, each >= 0.

    Returns
    -------
    float
        ``(L/(N-1)) sum_i [A (C_i + C_i+1)/2 + B (C_i^2 + C_i C_i+1 + C_i+1^2)/6 + A^2/(2B)]``: the
        exact integral of ``(A + B C)^2/(2B)`` over the piecewise-linear profile [J].

    Examples
    --------
    >>> round(profile_energy(50e3, 600e3, 1.5, [0.10, 0.20, 0.30, 0.35, 0.30, 0.20]), 6)
    55175.0
    """
    c = _check(A, B, width, profile)
    G = A * A / (2.0 * B)
    seg = width / (len(c) - 1)
    return seg * sum(A * (a + b) / 2.0 + B * (a * a + a * b + b * b) / 6.0 + G for a, b in zip(c[:-1], c[1:]))


def uniform_energy(A: float, B: float, width: float, crush: float) -> float:
    """Crush energy of a uniform crush C over the width L: ``L (A + B C)^2 / (2B)`` [J] (closed form,
    a check of :func:`profile_energy`)."""
    return width * (A + B * crush) ** 2 / (2.0 * B)


def force_direction_factor(alpha: float) -> tuple[float, bool]:
    """CRASH3 force-direction factor ``1 + tan^2(alpha)`` and whether it was capped.

    ``alpha`` [rad] is the angle of the crush force to the normal of the damaged face.  The factor
    is applied for ``|alpha| <= 45 deg`` (at most 2); beyond, it is held at 2 and ``capped`` is True.
    """
    a = abs(float(alpha))
    if a > MAX_FACTOR_ANGLE:
        return 2.0, True
    return 1.0 + math.tan(a) ** 2, False


def crush_energy(A: float, B: float, width: float, profile: Sequence[float], alpha: float = 0.0) -> float:
    """CRASH3 crush energy with the force-direction factor [J]: ``factor(alpha) * profile_energy``."""
    return force_direction_factor(alpha)[0] * profile_energy(A, B, width, profile)


def face_angle(pdof: float, face: str) -> float:
    """Angle of a crush force to the normal of a damaged face [rad], wrapped to (-pi, pi].

    ``pdof`` is the principal direction of force (SAE J224: where the force comes from, clockwise
    from the heading; :func:`crashsim.impact.result.pdof_from_force`); ``face`` one of
    :data:`FACES`.  0 is a force square onto the face; beyond +-90 deg the force does not push
    into that face at all.
    """
    d = float(pdof) - FACES[face]
    return math.atan2(math.sin(d), math.cos(d))


def energy_equivalent_speed(energy: float, mass: float) -> float:
    """EES [m/s]: the speed whose kinetic energy equals the crush energy, ``sqrt(2 E / m)``."""
    if energy < 0:
        raise ValueError(f"energy = {energy!r} J; allowed >= 0")
    return math.sqrt(2.0 * energy / mass)


def campbell_slope(speed: float, crush: float, b0: float) -> float:
    """Slope b1 [1/s] of Campbell's line V = b0 + b1 C through one barrier test (speed V [m/s],
    uniform residual crush C [m]) and the no-damage speed b0 [m/s]."""
    if not (crush > 0 and speed > b0 >= 0):
        raise ValueError(f"need crush > 0 and speed > b0 >= 0 (crush {crush!r} m, speed {speed!r} m/s, b0 {b0!r} m/s)")
    return (speed - b0) / crush


def campbell_coefficients(mass: float, width: float, b0: float, b1: float) -> tuple[float, float, float]:
    """A [N/m], B [N/m^2] and G [J/m] from Campbell's barrier-speed line V = b0 + b1 C.

    Equating the test's kinetic energy m V^2 / 2 with the crush energy L e(C) of a uniform crush
    over the tested width L, for every C on the line, gives ``A = m b0 b1 / L``,
    ``B = m b1^2 / L`` and ``G = m b0^2 / (2 L)`` (Campbell, SAE 740565, 1974).
    """
    return mass * b0 * b1 / width, mass * b1 * b1 / width, mass * b0 * b0 / (2.0 * width)

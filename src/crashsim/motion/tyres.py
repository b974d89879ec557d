"""Tyre force laws for the post-impact run-out: pure functions of NumPy arrays.

The SciPy engine (:mod:`crashsim.motion.simulate`), the pymunk cross-check
(:mod:`crashsim.crosscheck.pymunk_runout`) and the compiled engine
(:mod:`crashsim.motion.compiled_solution`) all evaluate the same source, :func:`tyre_kernel` (with
:func:`fiala_curve` / :func:`linear_curve`): the SciPy engine and the cross-check on NumPy
arrays, the compiled engine per contact after numba compiles that very function for scalars.
A difference between the integrations is therefore an integration difference, never a model
difference.

Model (after SMAC / EDSMAC / PC-Crash, research note ``post-impact-dynamics.md`` sec. 2)
-----------------------------------------------------------------------------------------
Each contact (one per side of an axle; dual tyres are one contact with the summed load and
cornering stiffness) has the velocity ``(u, w)`` of its contact point in wheel axes
(u along the wheel heading, w to the left of it), a normal load ``N`` and a friction
coefficient ``mu`` (road or zone value times the wheel's ``mu_factor``).  No wheel-spin
degree of freedom is integrated; the user sets the wheel state.

* **Sliding** (state ``"locked"`` or ``"jammed"``): Coulomb friction opposite the
  contact-point velocity, regularised at low speed (note sec. 3.2)::

      F = -mu N v / sqrt(|v|^2 + eps^2)

* **Rolling / braked** (state ``"rolling"``, or ``"braked"`` with brake fraction b):

  - longitudinal demand ``Fx = -min(b mu + f_r, mu) N u / sqrt(u^2 + eps^2)``
    (brake force b mu N plus rolling resistance f_r N, never more than mu N);
  - slip angle ``tan(alpha) = w / sqrt(u^2 + eps^2)`` (smooth minimum-denominator
    regularisation, note sec. 3.2, PhysX ``minLatSlipDenominator`` [25]);
  - pure-slip lateral force ``Fy0(alpha)`` from the **Fiala** brush model (default) or the
    PC-Crash-style **linear-saturated** curve (``lateral="linear"``), see
    :func:`lateral_force`;
  - **friction circle with braking priority** (note sec. 2.3 (i)): ``|Fy| <= sqrt(R^2 - Fx^2)``
    with the circle radius ``R = mu N |v| / sqrt(|v|^2 + eps^2)``, the magnitude of the
    regularised sliding force (``R = mu N`` to within 0.5 (eps/|v|)^2);
  - **lock-up**: when the lateral demand reaches the circle ("saturated": the contact
    slides sideways) *and* the longitudinal demand is at least what a locked wheel
    transmits along its heading (``|Fx| >= mu N |u| / sqrt(|v|^2 + eps^2)``), the brake
    torque wins and the wheel slides like a locked wheel (force opposite the contact
    velocity).  At the switch both forces have the same longitudinal component and lie on
    the same circle, so they coincide: the force law is **continuous everywhere**, for any
    tyre with ``|Fy0(alpha)| >= mu N sin(alpha)`` (true for Fiala when C_alpha >= 3 mu N and
    for the linear curve when C_alpha >= mu N -- every real tyre).  A free rolling wheel
    (b = 0) locks only where it has no longitudinal velocity, where both laws agree; a
    saturated free-rolling wheel slides sideways while it keeps rolling.

Why Fiala is the default: it needs the same two parameters as the linear-saturated curve
(mu, C_alpha), it is the model EDSMAC uses [3], and it is C1-smooth (the linear curve has
a kink at alpha_max), which keeps the adaptive integrators' step control and event location
clean.

"Sliding" (used to split tyre marks into sliding and rolling segments) means: the wheel is
locked or jammed, or its lateral demand is saturated (on the friction circle).  Such a
contact leaves a skid or yaw mark; below saturation the tyre is in partial (adhesion)
slip and leaves no mark.

Parameters and typical values (note sec. 2.5, sources numbered as in the note)
-----------------------------------------------------------------------------
=============================  ==========================================  ======================
quantity                       typical value                               source
=============================  ==========================================  ======================
mu, dry asphalt, car, locked   0.7 - 0.8 (case-specific skid tests better)  Brach & Brach [13]
mu, heavy truck, locked        lower than for cars; use [13], UMTRI [15]    [13, 15]
C_alpha car tyre               ~15 %/deg of load (11-19 %), 8.6 /rad x N    Gillespie via [5, 6]
                               e.g. N = 4 kN -> 35-39 kN/rad
C_alpha truck tyre             ~13 %/deg at 6.7 kN/tyre (degressive);      McHenry [6b], [15]
                               0.09-0.12 /deg at rated load (verify)
rolling resistance f_r         car 0.010-0.015, truck 0.005-0.010           engineering values
eps (regularisation)           0.01 m/s (error O(eps^2/(mu g)))            note sec. 3.2, 3.4
=============================  ==========================================  ======================

Conversion: C_alpha [N/rad] = c [1/deg] x N [N] x 57.3.

All inputs are SI: velocities [m/s], loads and forces [N], stiffness [N/rad], angles [rad].
Every function broadcasts over arrays of any common shape.
"""

from __future__ import annotations

import numpy as np

from ..errors import ScenarioError

__all__ = [
    "LATERAL_MODELS",
    "lateral_force",
    "tyre_forces",
    "tyre_forces_core",
    "tyre_kernel",
    "tyre_parts",
    "sliding_force",
    "fiala_curve",
    "linear_curve",
    "castor_angle",
]

#: Names of the pure-slip lateral force curves.
LATERAL_MODELS = ("fiala", "linear")

# Smallest friction capacity mu*N [N] used as a divisor; a contact with zero load (lift-off)
# then produces exactly zero force instead of a division by zero.
_TINY_FORCE = 1e-12


def _select(cond, if_true, if_false):
    """Elementwise choice, ``np.where`` (the compiled engine registers a scalar overload)."""
    return np.where(cond, if_true, if_false)


def fiala_curve(tan_alpha, mu_load, cornering_stiffness):
    """Fiala pure-slip lateral force [N] (see :func:`lateral_force`); arrays or scalars, no checks.

    Written with NumPy ufuncs only, so the same source runs on arrays (SciPy engine) and,
    compiled by numba, on scalars (:mod:`crashsim.motion.compiled_solution`).
    """
    # signed normalised slip z = C tan(a) / (3 mu N), clipped to [-1, 1];
    # sgn(z) [1 - (1 - |z|)^3] = z (3 - 3 |z| + z^2)
    z = tan_alpha * (cornering_stiffness / (3.0 * np.maximum(mu_load, _TINY_FORCE)))
    z = np.minimum(np.maximum(z, -1.0), 1.0)
    return (-mu_load) * z * (3.0 - 3.0 * np.abs(z) + z * z)


def linear_curve(tan_alpha, mu_load, cornering_stiffness):
    """Linear-saturated (PC-Crash style) pure-slip lateral force [N] (see :func:`lateral_force`)."""
    alpha = np.arctan(tan_alpha)
    return -np.sign(alpha) * np.minimum(cornering_stiffness * np.abs(alpha), mu_load)


def lateral_force(tan_alpha, mu_load, cornering_stiffness, model: str = "fiala"):
    """Pure-slip lateral tyre force.

    Parameters
    ----------
    tan_alpha : array_like
        Tangent of the slip angle, ``w / |u|`` (regularised by the caller) [-].
    mu_load : array_like
        Friction capacity ``mu N`` [N], >= 0.
    cornering_stiffness : array_like
        Cornering stiffness ``C_alpha`` [N/rad], >= 0 (initial slope of the curve).
    model : {"fiala", "linear"}
        ``"fiala"`` (default): brush model with parabolic pressure and mu_slide = mu_peak,
        for ``|tan a| < tan a_sl = 3 mu N / C_alpha``::

            Fy = -C tan a + C^2/(3 mu N) |tan a| tan a - C^3/(27 mu^2 N^2) tan^3 a
               = -mu N sgn(a) [1 - (1 - C |tan a| / (3 mu N))^3]

        and ``-mu N sgn(a)`` beyond (Fiala 1954, note sec. 2.2 [9]).
        ``"linear"``: PC-Crash style, ``Fy = -sgn(a) min(C |a|, mu N)`` with ``a = atan(tan a)``
        (saturation at ``a_max = mu N / C``, note sec. 2.2 [8]).

    Returns
    -------
    ndarray
        Lateral force [N], opposing the lateral slip, ``|Fy| <= mu N``.
    """
    tan_alpha = np.asarray(tan_alpha, dtype=float)
    mu_load = np.asarray(mu_load, dtype=float)
    if model == "fiala":
        return fiala_curve(tan_alpha, mu_load, cornering_stiffness)
    if model == "linear":
        return linear_curve(tan_alpha, mu_load, cornering_stiffness)
    raise ScenarioError(f"must be one of {LATERAL_MODELS}, got {model!r}", field="lateral_model")


def tyre_forces(u, w, load, mu, locked, brake, cornering_stiffness, rolling_resistance, eps, lateral="fiala"):
    """Force of every tyre contact, in wheel axes (see the module docstring for the model).

    Parameters
    ----------
    u, w : array_like
        Contact-point velocity along and across the wheel heading [m/s].
    load : array_like
        Normal load ``N`` [N], >= 0.
    mu : array_like
        Friction coefficient at the contact (road or zone mu times the wheel's mu factor) [-].
    locked : array_like of bool
        True for a locked or jammed wheel (pure sliding).
    brake : array_like
        Brake fraction ``b`` in [0, 1] of ``mu N`` (0 for a free-rolling wheel).
    cornering_stiffness : array_like
        ``C_alpha`` of the contact [N/rad] (ignored for locked wheels).
    rolling_resistance : array_like
        Rolling-resistance coefficient ``f_r`` [-] (ignored for locked wheels).
    eps : float
        Low-speed regularisation speed [m/s], > 0.
    lateral : {"fiala", "linear"}
        Pure-slip lateral curve, see :func:`lateral_force`.

    Returns
    -------
    fx, fy : ndarray
        Longitudinal and lateral force [N] in wheel axes; ``hypot(fx, fy) <= mu N`` always
        (precisely ``<= mu N |v| / sqrt(|v|^2 + eps^2)``).
    sliding : ndarray of bool
        True where the contact slides (locked/jammed, or lateral demand saturated).
    """
    mu = np.asarray(mu, dtype=float)
    load = np.asarray(load, dtype=float)
    demand = np.minimum(np.asarray(brake) * mu + rolling_resistance, mu) * load
    return tyre_forces_core(u, w, mu * load, demand, cornering_stiffness, locked, eps, lateral)


def tyre_forces_core(u, w, mu_load, demand, cornering_stiffness, locked, eps, lateral="fiala"):
    """:func:`tyre_forces` with the friction capacity and longitudinal demand precomputed.

    Parameters
    ----------
    u, w : ndarray
        Contact-point velocity along and across the wheel heading [m/s].
    mu_load : ndarray
        Friction capacity ``mu N`` [N].
    demand : ndarray
        Longitudinal force demand of a rolling/braked wheel ``min(b mu + f_r, mu) N`` [N].
    cornering_stiffness : ndarray
        [N/rad].
    locked : ndarray of bool, or True
        Locked/jammed contacts; the scalar ``True`` (every contact slides) skips the
        rolling-tyre branch.
    eps : float
        [m/s].
    lateral : {"fiala", "linear"}

    Returns
    -------
    fx, fy, sliding : ndarray
        As :func:`tyre_forces`.
    """
    u = np.asarray(u, dtype=float)
    w = np.asarray(w, dtype=float)
    if locked is True:
        # every contact slides: the sliding branch of tyre_kernel alone
        fx_lock, fy_lock = sliding_force(u, w, mu_load, eps)
        return fx_lock, fy_lock, np.ones(np.broadcast(fx_lock, fy_lock).shape, dtype=bool)
    if lateral not in LATERAL_MODELS:
        raise ScenarioError(f"must be one of {LATERAL_MODELS}, got {lateral!r}", field="lateral_model")
    return tyre_kernel(u, w, mu_load, demand, cornering_stiffness, locked, eps, lateral == "fiala")


def sliding_force(u, w, mu_load, eps):
    """Force of a sliding (locked or jammed) contact, ``-mu N v / sqrt(|v|^2 + eps^2)`` [N], wheel axes.

    The sliding branch of :func:`tyre_kernel`, with the same arithmetic (so the same bits);
    arrays or scalars.

    Returns
    -------
    fx, fy : float or ndarray
    """
    neg_scale = -mu_load / np.sqrt(u * u + w * w + eps * eps)
    return neg_scale * u, neg_scale * w


def tyre_kernel(u, w, mu_load, demand, cornering_stiffness, locked, eps, fiala):
    """The tyre force law itself: one source for both engines.

    Written with NumPy ufuncs and :func:`_select` only, so it broadcasts over arrays (the
    SciPy engine, through :func:`tyre_forces_core`) and, compiled by numba with a scalar
    ``_select``, runs per contact in the compiled engine (:mod:`crashsim.motion.compiled_solution`).
    Arguments as :func:`tyre_forces_core`, except ``locked`` (bool or bool array, never the
    shortcut ``True`` object) and ``fiala`` (bool: Fiala curve, else the linear one).

    Returns
    -------
    fx, fy : float or ndarray
        Force in wheel axes [N].
    sliding : bool or ndarray of bool
    """
    fx, fy, sliding, _, _ = tyre_parts(u, w, mu_load, demand, cornering_stiffness, locked, eps, fiala)
    return fx, fy, sliding


def tyre_parts(u, w, mu_load, demand, cornering_stiffness, locked, eps, fiala):
    """:func:`tyre_kernel` with the margins of the law's two switches: ``(fx, fy, sliding, m_sat, m_lock)``.

    ``m_sat = |Fy0| - sqrt(R^2 - Fx^2)`` [N], >= 0 where the lateral demand is saturated (on the
    friction circle); ``m_lock = |Fx_roll| - |Fx_lock|`` [N], >= 0 where a braked wheel would
    transmit along its heading at least what a locked wheel does (it locks where both are >= 0).
    The force is continuous across both switches, its slope is not: the compiled integrator
    aims a step at the switch where a rejected step crossed one
    (:func:`crashsim.motion.kernels.integrator.kink_fraction`).
    """
    u2 = u * u
    v2 = u2 + w * w
    eps2 = eps * eps
    u_reg = np.sqrt(u2 + eps2)
    neg_scale = -mu_load / np.sqrt(v2 + eps2)  # -mu N / sqrt(|v|^2 + eps^2)

    # sliding (locked) contact: opposite the contact velocity
    fx_lock = neg_scale * u
    fy_lock = neg_scale * w

    # rolling / braked contact: braking priority inside the (regularised) friction circle
    fx_roll = u * (-demand / u_reg)
    if fiala:
        fy_demand = fiala_curve(w / u_reg, mu_load, cornering_stiffness)
    else:
        fy_demand = linear_curve(w / u_reg, mu_load, cornering_stiffness)
    available = np.sqrt(np.maximum(neg_scale * neg_scale * v2 - fx_roll * fx_roll, 0.0))
    saturated = np.abs(fy_demand) >= available
    fy_roll = np.minimum(np.maximum(fy_demand, -available), available)
    lock_up = saturated & (np.abs(fx_roll) >= np.abs(fx_lock))

    slide = locked | lock_up
    fx = _select(slide, fx_lock, fx_roll)
    fy = _select(slide, fy_lock, fy_roll)
    return fx, fy, locked | saturated, np.abs(fy_demand) - available, np.abs(fx_roll) - np.abs(fx_lock)


def castor_angle(vx, vy, limit):
    """Steer angle of a self-steering (castor) wheel [rad], relative to its body's x axis.

    A self-steering axle's wheels pivot behind a king pin (castor trail), so the ground turns
    them to roll along the path of their contact point: the slip angle, and with it the tyre's
    lateral force, is zero.  The wheel therefore lies along the line of the contact-point
    velocity ``(vx, vy)`` (body axes), ``delta = atan(vy / vx)`` folded into [-pi/2, pi/2]
    (moving backwards it lies along the same line), while that angle is within ``+-limit``; beyond it the
    wheel rests against its stop, ``delta = +-limit``, and is a fixed wheel steered by the limit
    (the ordinary tyre law then gives its slip angle and lateral force).  ``limit = 0`` is the
    axle locked straight.  The castor's self-centring moment and the pivot's friction are
    neglected (an idealisation: the free wheel carries no lateral force at all); the force law
    stays continuous where the wheel meets its stop.  Arrays or scalars (one source for both
    engines, as :func:`tyre_kernel`).
    """
    d = np.arctan2(vy, vx)
    half = 0.5 * np.pi
    d = _select(d > half, d - np.pi, _select(d < -half, d + np.pi, d))
    return np.minimum(np.maximum(d, -limit), limit)

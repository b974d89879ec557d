"""Static wheel loads of a chain of bodies, and the quasi-static load-transfer matrix.

Static loads (note sec. 2.6)
----------------------------
Loads follow from vertical-force and pitch-moment balance of each body, solved from the
rear body of the chain to the front, so that the vertical load a rear body puts on its hitch
(kingpin load, drawbar-eye load) is passed on to the body in front.  x is measured forward
from each body's CG.  The equalising assumptions that make every case determinate:

* **Axle groups share equally.**  All axles of a group carry the same load (tandem and
  tri-axle groups with load-equalising suspension).  Each axle's load is split equally
  between its left and right contact (the CG lies on the centre line).
* **A towed body** (any body behind the first) is supported by its front hitch and by *all*
  its axles as one group at the mean axle position ``x_t``:
  ``N_hitch = [W (0 - x_t) + P_rear (x_h - x_t) + M] / (x_k - x_t)``, group load
  ``W + P_rear - N_hitch``.  For a semitrailer this is the note's kingpin formula
  ``N_kp = W2 (0 - x_t)/(x_k - x_t)``.  It needs at least one axle and ``x_k != x_t``.
* **The first body** (car, tractor, rigid truck) has no hitch in front.  Its axles, sorted by
  x, are split into a front and a rear group at the **largest gap** between consecutive
  axles (a car: front | rear; a tractor: steer | drive tandem; an 8x4 rigid truck: twin
  steer | tandem).  Then
  ``N_f = [W (0 - x_r) + P_rear (x_5 - x_r) + M] / (x_f - x_r)``, ``N_r = W + P_rear - N_f``.
  It needs at least two axles, and a unique largest gap (two equal largest gaps leave the
  split, and so the loads, undetermined: ScenarioError).

Here ``W = m g`` is the body weight, ``P_rear`` the vertical load the body behind puts on
this body's rear hitch at ``x_h`` (``x_5`` for a fifth wheel), and ``M`` a nose-down pitch
moment (zero for static loads).  A negative axle load (CG outside the wheelbase) is a
ScenarioError; a negative hitch load (a tail-heavy trailer lifting its drawbar) is allowed
and logged.

Quasi-static load transfer (optional, note sec. 2.6)
----------------------------------------------------
Loads are linear in the body accelerations, ``N = max(N_static + A @ [a_x; a_y], 0)``, with
the body-axes CG accelerations ``a_x`` (forward), ``a_y`` (left) of every body:

* longitudinal: the inertial force ``-m a_x`` at CG height ``h`` gives the nose-down pitch
  moment ``M = -m a_x h`` in the chain balance above (braking loads the front axles and,
  through the kingpin, the tractor).  Hitch forces are taken to act at ground level (hitch
  heights are not part of the vehicle description);
* lateral: the roll moment ``m a_y h`` of each body is carried by that body's own axles in
  proportion to their static loads, ``dN_right = -dN_left = share * m a_y h / track``.  A towed
  body with ``roll_coupled`` (its fifth wheel stiff in roll) passes the fraction
  ``s = N_hitch / (N_hitch + its axle loads)`` of its roll moment (the share of its weight the
  hitch carries, static) to the towing body's axles, by their static-load shares, and keeps
  ``1 - s`` on its own: under one lateral acceleration its own axles then transfer
  ``2 h a_y / (g t)`` of their load, the rigid body's ratio.

Clamping at zero (wheel lift-off) is done by the caller.  The accelerations come from a
first-order lag state (time constant tau, suspension pitch/roll response; note option 2),
see :mod:`crashsim.motion.simulate`.  They are the specific forces that transfer load: the
acceleration less the in-plane gravity (at the CG) and less the share of contact forces that acts
at the CG's height (a contact force at ``h_c`` counts with ``1 - h_c / h`` of it;
:func:`crashsim.motion.kernels.equations.specific_force`), so that ``m a h`` is the moment about the
ground of the forces acting above it.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass

import numpy as np
from ..errors import ScenarioError
from ..units import G0 as STANDARD_GRAVITY
from ..vehicles import Vehicle
from .wheels import SIDES, enumerate_wheels

__all__ = ["STANDARD_GRAVITY", "StaticLoads", "static_loads", "load_transfer_matrix"]

_log = logging.getLogger("crashsim")

# Two largest axle gaps closer than this [m] count as equal (split undetermined).
_GAP_TIE = 1e-6


@dataclass(frozen=True)
class StaticLoads:
    """Static vertical loads of a vehicle [N].

    Attributes
    ----------
    axle : dict of str to ndarray
        Body name -> load of each axle (both sides together), in ``Body.axles`` order.
    hitch : ndarray
        Vertical load carried by each hitch [N] (positive: the rear body presses down on
        the front body), in ``Vehicle.hitches`` order.
    wheel : ndarray
        Load of every contact, in :func:`~crashsim.motion.wheels.enumerate_wheels` order.
    groups : dict of str to tuple of tuple of int
        Body name -> axle index groups used for the equalising assumption.
    """

    axle: dict[str, np.ndarray]
    hitch: np.ndarray
    wheel: np.ndarray
    groups: dict[str, tuple[tuple[int, ...], ...]]

    @property
    def total(self) -> float:
        """Sum of all wheel loads [N] (equals the vehicle weight)."""
        return float(self.wheel.sum())


def _groups(vehicle: Vehicle) -> dict[str, tuple[tuple[int, ...], ...]]:
    out = {}
    for i, body in enumerate(vehicle.bodies):
        n = len(body.axles)
        if i > 0:
            if n == 0:
                raise ScenarioError(
                    "a towed body needs at least one axle to be supported (it has none)",
                    field=f"{vehicle.name}.{body.name}.axles",
                )
            out[body.name] = (tuple(range(n)),)
            continue
        if n < 2:
            raise ScenarioError(
                f"the first body of a vehicle needs at least 2 axles for determinate loads, got {n}",
                field=f"{vehicle.name}.{body.name}.axles",
            )
        order = sorted(range(n), key=lambda k: -body.axles[k].x)
        xs = np.array([body.axles[k].x for k in order])
        gaps = xs[:-1] - xs[1:]
        split = int(np.argmax(gaps))
        if gaps[split] <= 0:
            raise ScenarioError(
                "all axles at the same x: front/rear load split undetermined", field=f"{vehicle.name}.{body.name}.axles"
            )
        if np.sum(gaps >= gaps[split] - _GAP_TIE) > 1:
            raise ScenarioError(
                f"two equal largest gaps between axles (x = {xs.tolist()} m): the split into a front and a rear "
                "axle group, and so the static loads, is undetermined",
                field=f"{vehicle.name}.{body.name}.axles",
            )
        out[body.name] = (tuple(order[: split + 1]), tuple(order[split + 1 :]))
    return out


def _chain(vehicle: Vehicle, groups, weights, moments) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Axle and hitch loads for given body weights [N] and nose-down pitch moments [N m]."""
    nb = len(vehicle.bodies)
    axle_loads: dict[str, np.ndarray] = {}
    hitch_loads = np.zeros(nb - 1)
    p_rear = 0.0
    for i in range(nb - 1, -1, -1):
        body = vehicle.bodies[i]
        xs = np.array([a.x for a in body.axles], dtype=float)
        x_h = vehicle.hitches[i].front_point[0] if i < nb - 1 else 0.0
        w, m = weights[i], moments[i]
        loads = np.zeros(len(xs))
        if i > 0:
            (grp,) = groups[body.name]
            x_t = float(np.mean(xs[list(grp)]))
            x_k = vehicle.hitches[i - 1].rear_point[0]
            if abs(x_k - x_t) < 1e-9:
                raise ScenarioError(
                    f"hitch x = {x_k} m lies on the axle-group centre x = {x_t} m: the hitch load is undetermined",
                    field=f"{vehicle.name}.hitches[{i - 1}].rear_point",
                )
            p_front = (w * (0.0 - x_t) + p_rear * (x_h - x_t) + m) / (x_k - x_t)
            loads[list(grp)] = (w + p_rear - p_front) / len(grp)
            hitch_loads[i - 1] = p_front
            p_rear = p_front
        else:
            front, rear = groups[body.name]
            x_f = float(np.mean(xs[list(front)]))
            x_r = float(np.mean(xs[list(rear)]))
            n_f = (w * (0.0 - x_r) + p_rear * (x_h - x_r) + m) / (x_f - x_r)
            loads[list(front)] = n_f / len(front)
            loads[list(rear)] = (w + p_rear - n_f) / len(rear)
        axle_loads[body.name] = loads
    return axle_loads, hitch_loads


def _wheel_vector(vehicle: Vehicle, axle_loads: dict[str, np.ndarray]) -> np.ndarray:
    """Half of each axle's load on each of its contacts, in :func:`~crashsim.motion.wheels.enumerate_wheels`
    order (body by body, axle by axle, left then right)."""
    out = []
    for body in vehicle.bodies:
        loads = axle_loads[body.name]
        for ai in range(len(body.axles)):
            out += [loads[ai] / 2] * len(SIDES)
    return np.array(out)


def static_loads(vehicle: Vehicle, gravity: float = STANDARD_GRAVITY) -> StaticLoads:
    """Static axle, hitch and wheel loads of a vehicle (see the module docstring).

    Parameters
    ----------
    vehicle : Vehicle
        A movable vehicle (finite masses).
    gravity : float
        Gravitational acceleration [m/s^2] (standard gravity by default).

    Returns
    -------
    StaticLoads

    Raises
    ------
    ScenarioError
        If the loads are undetermined (see the module docstring) or an axle load is negative.
    """
    if vehicle.is_barrier:
        raise ScenarioError("a barrier (infinite mass) has no wheel loads", field=f"{vehicle.name}.bodies")
    groups = _groups(vehicle)
    weights = [b.mass * gravity for b in vehicle.bodies]
    axle, hitch = _chain(vehicle, groups, weights, [0.0] * len(weights))
    for body in vehicle.bodies:
        loads = axle[body.name]
        if np.any(loads < 0):
            k = int(np.argmin(loads))
            raise ScenarioError(
                f"static load of axle {k} is {loads[k]:.1f} N < 0: the CG (or hitch load) lies outside the "
                "supporting axles; check the axle positions",
                field=f"{vehicle.name}.{body.name}.axles[{k}].x",
            )
    for j, p in enumerate(hitch):
        if p < 0:
            _log.warning("hitch %d of %s carries a negative (lifting) vertical load of %.1f N", j, vehicle.name, p)
    return StaticLoads(axle=axle, hitch=hitch, wheel=_wheel_vector(vehicle, axle), groups=groups)


def _couple_roll(a: np.ndarray, vehicle: Vehicle, loads: StaticLoads, specs, i: int, height: float) -> None:
    """Move the hitch's share of body ``i``'s roll moment (column ``nb + i`` of ``a``) to the body towing it."""
    nb = len(vehicle.bodies)
    body, front = vehicle.bodies[i], vehicle.bodies[i - 1]
    own = float(loads.axle[body.name].sum())
    hitch = float(loads.hitch[i - 1])
    s = min(max(hitch / (hitch + own), 0.0), 1.0) if hitch + own > 0 else 0.0
    front_axles = loads.axle[front.name]
    total = float(front_axles.sum())
    for k, spec in enumerate(specs):
        if spec.body_index == i:
            a[k, nb + i] *= 1.0 - s
        elif spec.body_index == i - 1 and total > 0:
            sign = 1.0 if spec.side == "right" else -1.0
            share = front_axles[spec.axle_index] / total
            a[k, nb + i] += sign * s * share * body.mass * height / front.axles[spec.axle_index].track


def load_transfer_matrix(vehicle: Vehicle, loads: StaticLoads) -> np.ndarray:
    """Sensitivity of the contact loads to the body accelerations.

    Parameters
    ----------
    vehicle : Vehicle
        Every body needs ``cg_height``.
    loads : StaticLoads
        Static loads of ``vehicle`` (for the lateral shares).

    Returns
    -------
    ndarray, shape (n_wheels, 2 * n_bodies)
        ``A`` with ``dN = A @ concatenate([a_x, a_y])`` [N], ``a_x``, ``a_y`` the body-axes CG
        accelerations [m/s^2] of every body.
    """
    specs = enumerate_wheels(vehicle)
    nb = len(vehicle.bodies)
    groups = _groups(vehicle)
    heights = []
    for body in vehicle.bodies:
        if body.cg_height is None:
            raise ScenarioError(
                "load transfer needs the CG height [m, > 0] of every body", field=f"{vehicle.name}.{body.name}.cg_height"
            )
        heights.append(body.cg_height)
    a = np.zeros((len(specs), 2 * nb))
    for i, body in enumerate(vehicle.bodies):
        # longitudinal: unit nose-down moment on body i, scaled by dM/da_x = -m h
        moments = np.zeros(nb)
        moments[i] = 1.0
        axle, _ = _chain(vehicle, groups, np.zeros(nb), moments)
        a[:, i] = _wheel_vector(vehicle, axle) * (-body.mass * heights[i])
        # lateral: roll moment m h a_y on body i's own axles, by static-load share
        body_axles = loads.axle[body.name]
        total = float(body_axles.sum())
        for k, s in enumerate(specs):
            if s.body_index != i or total <= 0:
                continue
            track = body.axles[s.axle_index].track
            share = body_axles[s.axle_index] / total
            sign = 1.0 if s.side == "right" else -1.0
            a[k, nb + i] = sign * share * body.mass * heights[i] / track
        if i > 0 and body.roll_coupled:  # a fifth wheel stiff in roll: the hitch's share to the towing body
            _couple_roll(a, vehicle, loads, specs, i, heights[i])
    if not np.all(np.isfinite(a)):
        raise ScenarioError("load-transfer matrix is not finite", field=f"{vehicle.name}.bodies")
    return a


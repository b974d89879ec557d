"""Hitch constraint rows of a chain of bodies on tyres (maximal coordinates + hitch multipliers), and
:class:`RunoutModel`, one vehicle's equations for NumPy callers (the equations themselves are
:mod:`crashsim.motion.kernels.equations`).

Formulation (note sec. 1.4)
---------------------------
Generalised coordinates ``z = (X_0.., Y_0.., psi_0..)`` (world frame, field-major as in
:class:`~crashsim.motion.layout.StateLayout`) with ``M = diag(m.., m.., I..)``.  Hitch ``j``
joins body ``j`` (front) and ``j+1`` (rear)::

    g_j(z) = r_j + a_j - r_{j+1} - b_j = 0,   a_j = R(psi_j) rho_front,  b_j = R(psi_{j+1}) rho_rear
    G_j    = [ I2 | a_j^perp | -I2 | -b_j^perp ]     (columns of body j and j+1)
    gamma_j = -w_j^2 a_j + w_{j+1}^2 b_j              (g'' = G z'' + gamma)

An articulation stop that has closed (see :mod:`crashsim.motion.simulate`) adds the row
``psi_j - psi_{j+1} - theta_lock = 0``.  The multipliers follow from the Baumgarte-stabilised
acceleration constraint ``g'' + 2 zeta omega0 g' + omega0^2 g = 0``::

    (G M^-1 G^T) lambda = -(G M^-1 f + gamma + 2 zeta omega0 G z' + omega0^2 g)
    z'' = M^-1 (f + G^T lambda)

``lambda_j`` (rows 2j, 2j+1) is the world-frame hitch force **on the front body** [N]; the
rear body receives ``-lambda_j``.  A stop row's multiplier is the stop moment on the front
body [N m].

The engines evaluate these equations in the compiled kernels (:mod:`crashsim.motion.kernels`,
the one source of the run-out physics).  This module keeps the hitch geometry in NumPy for
preparing inputs (:func:`make_hitch_consistent`, the consistency checks) and offers
:class:`RunoutModel`, one vehicle's equations for NumPy callers, evaluated by the kernels.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..errors import ScenarioError, SolverError
from ..vehicles import BodyState, Vehicle
from .contact import ContactModel
from .layout import SV_HEADING, SV_VX, SV_VY, SV_X, SV_Y, SV_YAW_RATE, StateLayout
from .loads import StaticLoads
from .scene_model import SceneModel, kernels, reference_lengths
from .options import RunoutOptions
from .road import Road

__all__ = [
    "RunoutModel",
    "SegmentParams",
    "Evaluation",
    "make_hitch_consistent",
    "hitch_rows",
    "hitch_state",
    "yaw_locks",
    "check_pin_gaps",
    "project_velocities",
    "reference_lengths",
]


@functools.lru_cache(maxsize=64)
def _hitch_pattern(nb: int, nh: int, lock_hitches: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Constant entries of the constraint Jacobian (flattened) and flat indices of the pin-offset entries.

    The variable entries are ordered ``-a_y, b_y, a_x, -b_x`` (each over all hitches), matching
    :func:`hitch_rows`.
    """
    m = 2 * nh + len(lock_hitches)
    G = np.zeros((m, 3 * nb))
    j = np.arange(nh)
    G[2 * j, SV_X * nb + j] = 1.0
    G[2 * j, SV_X * nb + j + 1] = -1.0
    G[2 * j + 1, SV_Y * nb + j] = 1.0
    G[2 * j + 1, SV_Y * nb + j + 1] = -1.0
    for n, jl in enumerate(lock_hitches):
        G[2 * nh + n, SV_HEADING * nb + jl] = 1.0
        G[2 * nh + n, SV_HEADING * nb + jl + 1] = -1.0
    flat = lambda rows, cols: rows * 3 * nb + cols  # noqa: E731
    variable = np.concatenate(
        [flat(2 * j, SV_HEADING * nb + j), flat(2 * j, SV_HEADING * nb + j + 1), flat(2 * j + 1, SV_HEADING * nb + j),
         flat(2 * j + 1, SV_HEADING * nb + j + 1)]
    )
    G.setflags(write=False)
    return G.ravel(), variable


def hitch_rows(front_points, rear_points, cos_psi, sin_psi, x, y, vx, vy, w, locks=()):
    """Constraint Jacobian, residual, residual rate and curvature term of a chain of hitches.

    Rows ``2j, 2j+1`` are the x and y components of hitch ``j`` (joining bodies ``j`` and
    ``j+1``); one row per closed articulation stop follows.

    Parameters
    ----------
    front_points, rear_points : ndarray, shape (n_hitches, 2)
        Pin in the front body's and in the rear body's axes [m].
    cos_psi, sin_psi, x, y, vx, vy, w : ndarray, shape (n_bodies, K)
        Body heading cosine/sine, CG position [m], CG velocity [m/s], yaw rate [rad/s].
    locks : sequence of (int, float)
        Closed articulation stops: (hitch index, locked articulation angle [rad]).  The
        residual is ``psi_j - psi_{j+1} - angle`` wrapped to (-pi, pi].

    Returns
    -------
    G : ndarray, shape (K, m, 3 n_bodies)
    g, g_dot, gamma : ndarray, shape (m, K)
    """
    nb, k = cos_psi.shape
    nh = len(front_points)
    m = 2 * nh + len(locks)
    hfx, hfy = front_points[:, 0:1], front_points[:, 1:2]
    hrx, hry = rear_points[:, 0:1], rear_points[:, 1:2]
    cf, sf, cr, sr = cos_psi[:-1], sin_psi[:-1], cos_psi[1:], sin_psi[1:]
    ax = cf * hfx - sf * hfy
    ay = sf * hfx + cf * hfy
    bx = cr * hrx - sr * hry
    by = sr * hrx + cr * hry
    wf, wr = w[:-1], w[1:]
    wf2, wr2 = wf * wf, wr * wr
    g = np.empty((m, k))
    g_dot = np.empty((m, k))
    gamma = np.zeros((m, k))
    g[0 : 2 * nh : 2] = x[:-1] + ax - x[1:] - bx
    g[1 : 2 * nh : 2] = y[:-1] + ay - y[1:] - by
    g_dot[0 : 2 * nh : 2] = vx[:-1] - wf * ay - vx[1:] + wr * by
    g_dot[1 : 2 * nh : 2] = vy[:-1] + wf * ax - vy[1:] - wr * bx
    gamma[0 : 2 * nh : 2] = wr2 * bx - wf2 * ax
    gamma[1 : 2 * nh : 2] = wr2 * by - wf2 * ay
    template, variable = _hitch_pattern(nb, nh, tuple(j for j, _ in locks))
    G = np.empty((k, template.size))
    G[:] = template
    G[:, variable] = np.concatenate([-ay, by, ax, -bx]).T
    G = G.reshape(k, m, 3 * nb)
    for n, (jl, theta_lock) in enumerate(locks):
        row = 2 * nh + n
        r = jl + 1
        theta = np.arctan2(
            sin_psi[jl] * cos_psi[r] - cos_psi[jl] * sin_psi[r], cos_psi[jl] * cos_psi[r] + sin_psi[jl] * sin_psi[r]
        )
        g[row] = np.remainder(theta - theta_lock + math.pi, 2 * math.pi) - math.pi
        g_dot[row] = w[jl] - w[r]
    return G, g, g_dot, gamma


def project_velocities(minv: np.ndarray, G: np.ndarray, z_dot: np.ndarray) -> np.ndarray:
    """Velocities satisfying ``G z' = 0`` closest to ``z_dot`` in the kinetic-energy metric.

    ``z'+ = z' - M^-1 G^T (G M^-1 G^T)^-1 G z'`` (note sec. 1.4): the effect of the hitch
    impulse, which conserves the linear and angular momentum of the bodies it joins.

    Parameters
    ----------
    minv : ndarray, shape (3 n_bodies,)
        Inverse masses and inertias in z order.
    G : ndarray, shape (m, 3 n_bodies)
    z_dot : ndarray, shape (3 n_bodies,)

    Returns
    -------
    ndarray, shape (3 n_bodies,)
    """
    gm = G * minv
    impulse = np.linalg.solve(gm @ G.T, G @ z_dot)
    return z_dot - minv * (G.T @ impulse)


def yaw_locks(vehicle: Vehicle) -> tuple[tuple[int, float], ...]:
    """The yaw-locked hitches of ``vehicle`` (C-dollies) as locks for :func:`hitch_rows`: (hitch index, 0 rad)."""
    return tuple((j, 0.0) for j, h in enumerate(vehicle.hitches) if h.yaw_locked)


def hitch_state(vehicle: Vehicle, layout: StateLayout, y: np.ndarray, locks=()):
    """:func:`hitch_rows` for one state vector ``y`` of ``vehicle`` (not a hot path).

    The rows of the yaw-locked hitches (C-dollies) follow those of ``locks``.

    Returns
    -------
    G : ndarray, shape (m, 3 n_bodies)
    gaps, pin_speeds : ndarray, shape (n_hitches,)
        Distance between paired pins [m] and magnitude of their relative velocity [m/s].
    """
    front = np.array([h.front_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
    rear = np.array([h.rear_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
    locks = tuple(locks) + yaw_locks(vehicle)
    col = np.asarray(y, dtype=float)[:, None]
    psi = col[layout.psi]
    G, g, g_dot, _ = hitch_rows(
        front, rear, np.cos(psi), np.sin(psi), col[layout.x], col[layout.y], col[layout.vx], col[layout.vy], col[layout.w], locks
    )
    nh = len(vehicle.hitches)
    gaps = np.hypot(g[0 : 2 * nh : 2, 0], g[1 : 2 * nh : 2, 0])
    pin_speeds = np.hypot(g_dot[0 : 2 * nh : 2, 0], g_dot[1 : 2 * nh : 2, 0])
    return G[0], gaps, pin_speeds


def check_pin_gaps(vehicle: Vehicle, gaps: np.ndarray, tol: float) -> None:
    """Raise ScenarioError naming the first hitch whose pins are more than ``tol`` [m] apart."""
    for j, gap in enumerate(gaps):
        if gap > tol:
            raise ScenarioError(
                f"pin points of {vehicle.bodies[j].name!r} and {vehicle.bodies[j + 1].name!r} are {gap:.4g} m apart "
                f"(allowed <= {tol} m): positions are not hitch-consistent",
                field=f"initial[{vehicle.bodies[j + 1].name!r}].position",
            )


@functools.lru_cache(maxsize=64)
def _chain_layout(names: tuple) -> StateLayout:
    """The state layout of a chain of bodies (immutable: one per chain, not one per call)."""
    return StateLayout(names)


def make_hitch_consistent(
    vehicle: Vehicle, states: Mapping[str, BodyState], *, position_tol: float = 1e-3
) -> dict[str, BodyState]:
    """Project body velocities onto the hitch constraints (equal pin velocities).

    The impact solver may leave the bodies of an articulated vehicle with velocities whose
    pin points move apart (or a yaw-locked C-dolly turning against the trailer it is locked to:
    its moment impulse is part of the projection).  The projection ``z'+ = z' - M^-1 G^T (G M^-1 G^T)^-1 G z'``
    applies the hitch impulse that makes them equal: it conserves the vehicle's linear and
    angular momentum and is the smallest velocity change in the kinetic-energy metric
    (note sec. 1.4).  Positions and headings are not changed.

    Parameters
    ----------
    vehicle : Vehicle
    states : mapping of str to BodyState
        State of every body of the vehicle (others are ignored and returned unchanged).
    position_tol : float
        Largest accepted pin gap [m] between the bodies' pin points.

    Returns
    -------
    dict of str to BodyState
        ``states`` with the vehicle's bodies' velocities replaced.

    Raises
    ------
    ScenarioError
        If a pin gap exceeds ``position_tol`` (positions are inconsistent, not only velocities).
    """
    out = dict(states)
    if len(vehicle.bodies) < 2:
        return out
    layout = _chain_layout(tuple(b.name for b in vehicle.bodies))
    y = layout.pack(states)
    nb = layout.n_bodies
    G, gaps, _ = hitch_state(vehicle, layout, y)
    check_pin_gaps(vehicle, gaps, position_tol)
    minv = np.concatenate([[1 / b.mass for b in vehicle.bodies]] * 2 + [[1 / b.yaw_inertia for b in vehicle.bodies]])
    z_dot = project_velocities(minv, G, y[layout.velocity])
    for i, name in enumerate(layout.bodies):
        s = states[name]
        out[name] = BodyState(s.position, s.heading, (z_dot[i], z_dot[nb + i]), z_dot[2 * nb + i])
    return out


@dataclass(frozen=True, eq=False)
class SegmentParams:
    """Inputs held constant over one integration segment of a :class:`RunoutModel`.

    Attributes
    ----------
    phase : int
        Wheel-setting phase (index into ``model.wheels.phases``).
    settings : tuple of WheelSetting
        The wheel settings of that phase.
    membership : ndarray of bool, shape (n_wheels, n_zones)
        Which zone each wheel is in.
    locks : tuple of (int, float)
        Closed articulation stops: (hitch index, locked angle [rad]).
    road_mu : ndarray or None
        Per-wheel road friction replacing the membership's (the pymunk cross-check blends mu
        over a step that crosses a zone edge), or None.
    """

    phase: int
    settings: tuple
    membership: np.ndarray
    locks: tuple
    road_mu: np.ndarray | None = None


@dataclass(eq=False, slots=True)
class Evaluation:
    """Everything the model computes for a batch of K states (world frame, SI).

    Attributes
    ----------
    y_dot : ndarray, shape (n_state, K)
    body_force : ndarray, shape (3 n_bodies, K)
        Sum of tyre forces and moments per body, z order (F_X..., F_Y..., M_z...) [N, N m].
    wheel_x, wheel_y : ndarray, shape (n_wheels, K)
        Contact positions [m].
    wheel_speed : ndarray, shape (n_wheels, K)
        Contact-point speed [m/s].
    tyre_power : ndarray, shape (n_wheels, K)
        Power of the tyre force ``F . v`` [W] (<= 0: friction dissipates).
    sliding : ndarray of bool, shape (n_wheels, K)
    load : ndarray, shape (n_wheels, K)
        Normal loads [N].
    lam : ndarray, shape (K, m)
        Constraint multipliers (hitch forces on the front body [N], stop moments [N m]).
    accel_body : ndarray, shape (2 n_bodies, K)
        Body-axes CG accelerations (a_x..., a_y...) [m/s^2].
    """

    y_dot: np.ndarray
    body_force: np.ndarray
    wheel_x: np.ndarray
    wheel_y: np.ndarray
    wheel_speed: np.ndarray
    tyre_power: np.ndarray
    sliding: np.ndarray
    load: np.ndarray
    lam: np.ndarray
    accel_body: np.ndarray


class RunoutModel:
    """One vehicle's run-out equations, evaluated by the compiled kernels, for NumPy callers.

    The pymunk cross-check, the rigid and energy levels and the tests use it; the engines
    integrate the same kernels directly (:mod:`crashsim.motion.engine`).  There is no second
    copy of the equations here: :meth:`evaluate` calls
    :func:`crashsim.motion.kernels.samples.evaluate_columns`.

    Parameters
    ----------
    vehicle : Vehicle
        A movable vehicle.
    wheels : ResolvedWheels or WheelSettings
        Its wheel settings over time.
    road : Road
    options : RunoutOptions
    hitches : bool
        False: the hitches are removed (each body runs out alone, static loads those of the
        coupled vehicle; the ``rigid`` level).
    """

    def __init__(self, vehicle: Vehicle, wheels, road: Road, options: RunoutOptions, *, hitches: bool = True):
        if vehicle.is_barrier:
            raise ScenarioError("a barrier (infinite mass) has no run-out", field=f"{vehicle.name}.bodies")
        self.scene = SceneModel([vehicle], {vehicle.name: wheels}, road, options, contact=ContactModel(enabled=False),
                                hitches=hitches)
        self.vehicle = vehicle
        self.wheels = self.scene.resolved[vehicle.name]
        self.road = road
        self.options = options
        self.layout = self.scene.layout
        self.specs = self.scene.specs
        self.mass = self.scene.mass
        self.inertia = self.scene.inertia
        self.minv = self.scene.minv
        self.loads: StaticLoads = self.scene.loads[vehicle.name]
        self.static_load = self.scene.static_load.copy()
        self.n_hitches = self.scene.n_hitches
        self.wheel_body = np.array([s.body_index for s in self.specs], dtype=int)
        self.front_points = np.array([h.front_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
        self.rear_points = np.array([h.rear_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
        self.l_ref = self.scene.M.body[:, 2].copy()
        rho = np.array([s.position for s in self.specs], dtype=float).reshape(-1, 2)
        self._rx, self._ry = rho[:, 0:1], rho[:, 1:2]

    # ------------------------------------------------------------------ segment inputs
    def segment(self, t: float, membership: np.ndarray, locks: Sequence[tuple[int, float]] = (),
                road_mu: np.ndarray | None = None) -> SegmentParams:
        """Inputs in force from time ``t`` [s] for given zone membership and closed stops."""
        phase = int(np.searchsorted(self.scene.phase_times, t, side="right") - 1)
        settings = self.wheels.at(t)
        mu = None if road_mu is None else np.asarray(road_mu, dtype=float).reshape(-1)
        return SegmentParams(phase, settings, np.asarray(membership, dtype=bool).copy(), tuple(locks), mu)

    def _mode(self, seg: SegmentParams):
        D = self.scene.fresh_mode()
        if seg.membership.size:
            D.memb[:] = seg.membership
        for n, (j, theta) in enumerate(seg.locks):
            D.lk_j[n] = j
            D.lk_th[n] = theta
        D.lk_n[0] = len(seg.locks)
        return D

    # ------------------------------------------------------------------ kinematics
    def wheel_positions(self, y: np.ndarray) -> np.ndarray:
        """Contact positions for one state, shape (n_wheels, 2) [m]."""
        L = self.layout
        bi = self.wheel_body
        psi = y[L.psi][bi]
        c, s = np.cos(psi), np.sin(psi)
        rx, ry = self._rx[:, 0], self._ry[:, 0]
        return np.stack([y[L.x][bi] + c * rx - s * ry, y[L.y][bi] + s * rx + c * ry], 1)

    def wheel_velocities(self, y: np.ndarray) -> np.ndarray:
        """Contact-point velocities for one state, shape (n_wheels, 2) [m/s]."""
        L = self.layout
        bi = self.wheel_body
        psi = y[L.psi][bi]
        c, s = np.cos(psi), np.sin(psi)
        rx, ry = self._rx[:, 0], self._ry[:, 0]
        dx, dy = c * rx - s * ry, s * rx + c * ry
        w = y[L.w][bi]
        return np.stack([y[L.vx][bi] - w * dy, y[L.vy][bi] + w * dx], 1)

    def membership(self, y: np.ndarray) -> np.ndarray:
        """Zone membership of every wheel (the kernels' rule: a wheel on an edge goes where it heads)."""
        out = np.zeros((len(self.specs), len(self.road.zones)), dtype=bool)
        kernels().membership(np.ascontiguousarray(y, dtype=float), self.scene.M, out,
                             np.zeros((2, self.layout.n_bodies)))
        return out

    def rest_measure(self, y: np.ndarray) -> float:
        """``max over bodies of max(|v_cg|, |yaw rate| L_ref)`` [m/s] for one state."""
        L = self.layout
        speed = np.hypot(y[L.vx], y[L.vy])
        return float(np.max(np.maximum(speed, np.abs(y[L.w]) * self.l_ref)))

    def kinetic_energy(self, y: np.ndarray) -> np.ndarray:
        """Kinetic energy of the vehicle [J] (any trailing shape)."""
        L = self.layout
        y = np.asarray(y)
        return 0.5 * (
            np.tensordot(self.mass, y[L.vx] ** 2 + y[L.vy] ** 2, axes=(0, 0))
            + np.tensordot(self.inertia, y[L.w] ** 2, axes=(0, 0))
        )

    # ------------------------------------------------------------------ forces and accelerations
    def evaluate(self, y: np.ndarray, seg: SegmentParams, full: bool = True) -> Evaluation:
        """Evaluate the model (the compiled kernels) for K states ``y`` of shape (n_state, K)."""
        k = kernels()
        Y = np.ascontiguousarray(np.asarray(y, dtype=float).reshape(self.layout.size, -1))
        mu = np.full(len(self.specs), np.nan) if seg.road_mu is None else seg.road_mu
        ydot, wk, lam, f = k.evaluate_columns(Y, self.scene.M, seg.phase, self._mode(seg), mu)
        L = self.layout
        nb = L.n_bodies
        psi = Y[L.psi]
        c, s = np.cos(psi), np.sin(psi)
        acc_x, acc_y = ydot[SV_VX * nb: SV_VY * nb], ydot[SV_VY * nb: SV_YAW_RATE * nb]
        pos = np.stack([self.wheel_positions(Y[:, j]) for j in range(Y.shape[1])], axis=-1)  # (nw, 2, K)
        u, v = wk[:, :, k.W_U].T, wk[:, :, k.W_V].T
        fx, fy = wk[:, :, k.W_FX].T, wk[:, :, k.W_FY].T
        return Evaluation(
            y_dot=ydot, body_force=f.T.copy(), wheel_x=pos[:, 0], wheel_y=pos[:, 1], wheel_speed=np.hypot(u, v),
            tyre_power=fx * u + fy * v, sliding=wk[:, :, k.W_SLIDE].T != 0.0, load=wk[:, :, k.W_LOAD].T.copy(),
            lam=lam, accel_body=np.concatenate([c * acc_x + s * acc_y, c * acc_y - s * acc_x]))

    def tyre_body_forces(self, y: np.ndarray, seg: SegmentParams) -> np.ndarray:
        """Sum of tyre forces and moments per body for K states, z order, shape (3 n_bodies, K) [N, N m]."""
        return self.evaluate(y, seg).body_force

    def rhs(self, t: float, y: np.ndarray, seg: SegmentParams) -> np.ndarray:
        """Right-hand side ``y' = f(t, y)`` for one state (n_state,) or a batch (n_state, K)."""
        y_dot = self.evaluate(y[:, None] if y.ndim == 1 else y, seg, full=False).y_dot
        if not np.isfinite(y_dot).all():
            raise SolverError(f"non-finite state derivative at t = {t:.6g} s (state {np.asarray(y).ravel().tolist()})")
        return y_dot[:, 0] if y.ndim == 1 else y_dot

    def consistent_accelerations(self, y: np.ndarray, seg: SegmentParams, iterations: int = 50) -> np.ndarray:
        """State with the filtered accelerations set to their quasi-static fixed point (load transfer)."""
        L = self.layout
        if L.accel is None:
            return y
        y = y.copy()
        for _ in range(iterations):
            new = self.evaluate(y[:, None], seg, full=False).accel_body[:, 0]
            done = np.max(np.abs(new - y[L.accel])) < 1e-10
            y[L.accel] = new
            if done:
                break
        return y

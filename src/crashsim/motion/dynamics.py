"""Planar equations of motion of a chain of bodies on tyres: maximal coordinates + hitch multipliers.

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

Everything is vectorised over a trailing axis of states, so the same code is the
right-hand side (one column) and the post-processor (many columns).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

import numpy as np

from ..errors import ScenarioError, SolverError
from ..vehicles import BodyState, Vehicle
from .layout import StateLayout
from .loads import StaticLoads, load_transfer_matrix, static_loads
from .options import RunoutOptions
from .road import Road
from .tyres import tyre_forces_core
from .wheels import ResolvedWheels, WheelSetting

__all__ = [
    "RunoutModel",
    "SegmentParams",
    "Evaluation",
    "make_hitch_consistent",
    "hitch_rows",
    "hitch_state",
    "check_pin_gaps",
    "project_velocities",
    "reference_lengths",
]

# Minimum rest reference length [m] (|yaw rate| * L_ref is compared with v_stop).
_MIN_L_REF = 0.5


@functools.lru_cache(maxsize=64)
def _hitch_pattern(nb: int, nh: int, lock_hitches: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
    """Constant entries of the constraint Jacobian (flattened) and flat indices of the pin-offset entries.

    The variable entries are ordered ``-a_y, b_y, a_x, -b_x`` (each over all hitches), matching
    :func:`hitch_rows`.
    """
    m = 2 * nh + len(lock_hitches)
    G = np.zeros((m, 3 * nb))
    j = np.arange(nh)
    G[2 * j, j] = 1.0
    G[2 * j, j + 1] = -1.0
    G[2 * j + 1, nb + j] = 1.0
    G[2 * j + 1, nb + j + 1] = -1.0
    for n, jl in enumerate(lock_hitches):
        G[2 * nh + n, 2 * nb + jl] = 1.0
        G[2 * nh + n, 2 * nb + jl + 1] = -1.0
    flat = lambda rows, cols: rows * 3 * nb + cols  # noqa: E731
    variable = np.concatenate(
        [flat(2 * j, 2 * nb + j), flat(2 * j, 2 * nb + j + 1), flat(2 * j + 1, 2 * nb + j), flat(2 * j + 1, 2 * nb + j + 1)]
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


def _solve_small(A: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve the batch of symmetric systems ``A[k] x[k] = b[k]``; closed form for 2x2 (one hitch)."""
    if A.shape[1] == 2:
        a00, a01, a11 = A[:, 0, 0], A[:, 0, 1], A[:, 1, 1]
        b0, b1 = b[:, 0], b[:, 1]
        x = np.empty_like(b)
        x[:, 0] = a11 * b0 - a01 * b1
        x[:, 1] = a00 * b1 - a01 * b0
        return x / (a00 * a11 - a01 * a01)[:, None]
    return np.linalg.solve(A, b[..., None])[..., 0]


def hitch_state(vehicle: Vehicle, layout: StateLayout, y: np.ndarray, locks=()):
    """:func:`hitch_rows` for one state vector ``y`` of ``vehicle`` (not a hot path).

    Returns
    -------
    G : ndarray, shape (m, 3 n_bodies)
    gaps, pin_speeds : ndarray, shape (n_hitches,)
        Distance between paired pins [m] and magnitude of their relative velocity [m/s].
    """
    front = np.array([h.front_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
    rear = np.array([h.rear_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
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


def make_hitch_consistent(
    vehicle: Vehicle, states: Mapping[str, BodyState], *, position_tol: float = 1e-3
) -> dict[str, BodyState]:
    """Project body velocities onto the hitch constraints (equal pin velocities).

    The impact solver may leave the bodies of an articulated vehicle with velocities whose
    pin points move apart.  The projection ``z'+ = z' - M^-1 G^T (G M^-1 G^T)^-1 G z'``
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
    layout = StateLayout(tuple(b.name for b in vehicle.bodies))
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


def reference_lengths(vehicle: Vehicle, specs) -> np.ndarray:
    """Rest reference length L_ref of every body [m]: half its length, else its farthest contact (>= 0.5 m).

    Parameters
    ----------
    vehicle : Vehicle
    specs : sequence of WheelSpec
        The vehicle's contacts (:func:`~crashsim.motion.wheels.enumerate_wheels`).

    Returns
    -------
    ndarray, shape (n_bodies,)
    """
    out = []
    for i, body in enumerate(vehicle.bodies):
        if body.length is not None:
            out.append(max(body.length / 2, _MIN_L_REF))
        else:
            reach = [math.hypot(*s.position) for s in specs if s.body_index == i]
            out.append(max(max(reach, default=0.0), _MIN_L_REF))
    return np.array(out, dtype=float)


@dataclass(frozen=True, eq=False)
class SegmentParams:
    """Inputs held constant over one integration segment (arrays per wheel, shape (n_wheels, 1)).

    Attributes
    ----------
    settings : tuple of WheelSetting
    membership : ndarray of bool, shape (n_wheels, n_zones)
        Which zone each wheel is in (fixed within a segment; flipped at crossing events).
    locks : tuple of (int, float)
        Closed articulation stops: (hitch index, locked angle [rad]).
    mu, locked, c_fixed, c_coeff : ndarray
        Friction coefficient, sliding flag, cornering stiffness [N/rad] (fixed part and
        per-load part [1/rad]).
    demand_coef : ndarray
        ``min(b mu + f_r, mu)``: longitudinal demand per unit load of a rolling/braked wheel.
    kin : ndarray, shape (2 n_wheels, 3 n_bodies)
        Linear map from the body-axes CG velocities ``(v_x..., v_y..., w...)`` to the
        contact-point velocities in wheel axes ``(u..., w_lat...)``.  By the principle of
        virtual power its transpose maps the wheel-axes tyre forces ``(F_x..., F_y...)`` to
        the body-axes forces and yaw moments of the bodies.
    kin_t : ndarray
        ``kin.T`` (C-contiguous).
    locked_arg : ndarray of bool or True
        ``locked``, or True when every wheel slides (fast path of the tyre function).
    mu_load, demand, c_alpha : ndarray or None
        With static loads: ``mu N`` [N], ``demand_coef N`` [N] and the cornering stiffness
        [N/rad], precomputed for the segment.
    """

    settings: tuple[WheelSetting, ...]
    membership: np.ndarray
    locks: tuple[tuple[int, float], ...]
    mu: np.ndarray
    locked: np.ndarray
    c_fixed: np.ndarray
    c_coeff: np.ndarray
    demand_coef: np.ndarray
    kin: np.ndarray
    kin_t: np.ndarray
    locked_arg: np.ndarray | bool
    mu_load: np.ndarray | None
    demand: np.ndarray | None
    c_alpha: np.ndarray | None


@dataclass(eq=False, slots=True)
class Evaluation:
    """Everything the model computes for a batch of K states (world frame, SI).

    Attributes
    ----------
    y_dot : ndarray, shape (n_state, K)
    body_force : ndarray, shape (3 n_bodies, K)
        Sum of tyre forces and moments per body, z order (F_X..., F_Y..., M_z...) [N, N m].
    wheel_x, wheel_y : ndarray, shape (n_wheels, K) or None
        Contact positions [m] (only with ``full=True``).
    wheel_speed : ndarray, shape (n_wheels, K)
        Contact-point speed [m/s].
    tyre_power : ndarray, shape (n_wheels, K)
        Power of the tyre force ``F . v`` [W] (<= 0: friction dissipates).
    sliding : ndarray of bool, shape (n_wheels, K)
    load : ndarray, shape (n_wheels, K)
        Normal loads [N].
    lam : ndarray, shape (K, m)
        Constraint multipliers (hitch forces on the front body [N], stop moments [N m]).
    accel_body : ndarray, shape (2 n_bodies, K) or None
        Body-axes CG accelerations (a_x..., a_y...) [m/s^2] (with ``full=True`` or load transfer).
    """

    y_dot: np.ndarray
    body_force: np.ndarray
    wheel_x: np.ndarray | None
    wheel_y: np.ndarray | None
    wheel_speed: np.ndarray | None
    tyre_power: np.ndarray | None
    sliding: np.ndarray
    load: np.ndarray
    lam: np.ndarray
    accel_body: np.ndarray | None


class RunoutModel:
    """A vehicle compiled into arrays for fast evaluation of the run-out equations.

    Parameters
    ----------
    vehicle : Vehicle
        A movable vehicle.
    wheels : ResolvedWheels
        Its wheel settings over time.
    road : Road
    options : RunoutOptions
    """

    def __init__(self, vehicle: Vehicle, wheels: ResolvedWheels, road: Road, options: RunoutOptions):
        if vehicle.is_barrier:
            raise ScenarioError("a barrier (infinite mass) has no run-out", field=f"{vehicle.name}.bodies")
        self.vehicle = vehicle
        self.wheels = wheels
        self.road = road
        self.options = options
        bodies = vehicle.bodies
        nb = len(bodies)
        self.layout = StateLayout(tuple(b.name for b in bodies), accel_filter=options.load_transfer)
        self.mass = np.array([b.mass for b in bodies])
        self.inertia = np.array([b.yaw_inertia for b in bodies])
        self.minv = np.concatenate([1 / self.mass, 1 / self.mass, 1 / self.inertia])
        self._minv_col = self.minv[:, None]
        self._minv_list = self.minv.tolist()
        specs = wheels.specs
        self.specs = specs
        nw = len(specs)
        if nw == 0:
            raise ScenarioError("a run-out needs at least one axle", field=f"{vehicle.name}.bodies")
        self.wheel_body = np.array([s.body_index for s in specs], dtype=int)
        rho = np.array([s.position for s in specs], dtype=float)
        self._rx = rho[:, 0:1]
        self._ry = rho[:, 1:2]
        self.tyres = np.array([s.tyres for s in specs], dtype=float)
        self.loads: StaticLoads = static_loads(vehicle)
        self.static_load = self.loads.wheel.copy()
        self._n_static = self.static_load[:, None]
        self.transfer = load_transfer_matrix(vehicle, self.loads) if options.load_transfer else None
        self.front_points = np.array([h.front_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
        self.rear_points = np.array([h.rear_point for h in vehicle.hitches], dtype=float).reshape(-1, 2)
        self.n_hitches = len(vehicle.hitches)
        self._hitch_points = (*self.front_points[0], *self.rear_points[0]) if self.n_hitches == 1 else None
        # contact positions: x_k = X_i + cos(psi_i) rho_x - sin(psi_i) rho_y, y_k = Y_i + sin(psi_i) rho_x + cos(psi_i) rho_y
        pmap = np.zeros((2 * nw, 4 * nb))
        k, bi = np.arange(nw), self.wheel_body
        pmap[k, bi] = 1.0
        pmap[k, 2 * nb + bi] = rho[:, 0]
        pmap[k, 3 * nb + bi] = -rho[:, 1]
        pmap[nw + k, nb + bi] = 1.0
        pmap[nw + k, 2 * nb + bi] = rho[:, 1]
        pmap[nw + k, 3 * nb + bi] = rho[:, 0]
        self._position_map = pmap
        self._alpha2 = 2.0 * options.baumgarte_zeta * options.baumgarte_omega
        self._beta2 = options.baumgarte_omega**2
        self.l_ref = reference_lengths(vehicle, specs)
        self.eps = options.eps
        self.lateral = options.lateral_model

    # ------------------------------------------------------------------ segment inputs
    def segment(
        self,
        t: float,
        membership: np.ndarray,
        locks: Sequence[tuple[int, float]] = (),
        road_mu: np.ndarray | None = None,
    ) -> SegmentParams:
        """Inputs in force from time ``t`` [s] for given zone membership and closed stops.

        ``road_mu`` (per wheel), if given, replaces the road friction coefficient derived from
        ``membership`` (the pymunk cross-check blends mu over a step that crosses a zone edge).
        """
        settings = self.wheels.at(t)
        col = lambda values: np.asarray(values, dtype=float)[:, None]  # noqa: E731
        if road_mu is None:
            road_mu = self.road.mu_from_membership(membership)
        mu = col(np.asarray(road_mu, dtype=float) * np.array([s.mu_factor for s in settings]))
        brake = col([s.brake for s in settings])
        f_roll = col([s.rolling_resistance or 0.0 for s in settings])
        c_fixed = col([(s.cornering_stiffness or 0.0) * n for s, n in zip(settings, self.tyres)])
        c_coeff = col([s.cornering_coefficient or 0.0 for s in settings])
        demand_coef = np.minimum(brake * mu + f_roll, mu)
        static = self.transfer is None
        # contact velocity in wheel axes: u = cos(d) cvx + sin(d) cvy, w = -sin(d) cvx + cos(d) cvy,
        # with cvx = v_x - rho_y w and cvy = v_y + rho_x w (body axes)
        nb, nw = self.layout.n_bodies, len(self.specs)
        cd = np.array([math.cos(s.steer) for s in settings])
        sd = np.array([math.sin(s.steer) for s in settings])
        rx, ry = self._rx[:, 0], self._ry[:, 0]
        k, bi = np.arange(nw), self.wheel_body
        kin = np.zeros((2 * nw, 3 * nb))
        kin[k, bi] = cd
        kin[k, nb + bi] = sd
        kin[k, 2 * nb + bi] = sd * rx - cd * ry
        kin[nw + k, bi] = -sd
        kin[nw + k, nb + bi] = cd
        kin[nw + k, 2 * nb + bi] = cd * rx + sd * ry
        locked = np.array([s.is_sliding for s in settings], dtype=bool)[:, None]
        return SegmentParams(
            settings=settings,
            membership=membership.copy(),
            locks=tuple(locks),
            mu=mu,
            locked=locked,
            c_fixed=c_fixed,
            c_coeff=c_coeff,
            demand_coef=demand_coef,
            kin=kin,
            kin_t=np.ascontiguousarray(kin.T),
            locked_arg=True if locked.all() else locked,
            mu_load=mu * self._n_static if static else None,
            demand=demand_coef * self._n_static if static else None,
            c_alpha=c_fixed + c_coeff * self._n_static if static else None,
        )

    # ------------------------------------------------------------------ kinematics
    def wheel_positions(self, y: np.ndarray) -> np.ndarray:
        """Contact positions for one state, shape (n_wheels, 2) [m].

        One product with the constant map from ``(X, Y, cos psi, sin psi)`` of the bodies to
        ``(x..., y...)`` of the contacts (events call this at every solver step).
        """
        L = self.layout
        psi = y[L.psi]
        xy = self._position_map @ np.concatenate([y[L.x], y[L.y], np.cos(psi), np.sin(psi)])
        return xy.reshape(2, -1).T

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
    def _tyres(self, y: np.ndarray, seg: SegmentParams):
        """Tyre forces of K states: world-frame body forces ``f`` (3 n_bodies, K) and wheel-axes quantities.

        Contact velocities come from one matrix product with the segment's map ``kin`` and
        the body forces from one product with its transpose (fewest NumPy calls); the body
        sums are rotated to the world frame.
        """
        L = self.layout
        nb, nw = L.n_bodies, len(self.specs)
        psi, vx, vy, w = y[L.psi], y[L.vx], y[L.vy], y[L.w]
        c, s = np.cos(psi), np.sin(psi)
        uv = seg.kin @ np.concatenate([c * vx + s * vy, c * vy - s * vx, w])
        u, v_lat = uv[:nw], uv[nw:]
        if self.transfer is None:
            load = self._n_static
            mu_load, demand, c_alpha = seg.mu_load, seg.demand, seg.c_alpha
        else:
            load = np.maximum(self._n_static + self.transfer @ y[L.accel], 0.0)
            mu_load = seg.mu * load
            demand = seg.demand_coef * load
            c_alpha = seg.c_fixed + seg.c_coeff * load
        fx, fy, sliding = tyre_forces_core(u, v_lat, mu_load, demand, c_alpha, seg.locked_arg, self.eps, self.lateral)
        gen = seg.kin_t @ np.concatenate([fx, fy])
        sum_x, sum_y = gen[:nb], gen[nb : 2 * nb]
        f = np.concatenate([c * sum_x - s * sum_y, s * sum_x + c * sum_y, gen[2 * nb :]])
        return f, c, s, u, v_lat, fx, fy, sliding, load

    def _single_hitch(self, y: np.ndarray, c: np.ndarray, s: np.ndarray, f: np.ndarray):
        """Constraint solve of one state of a two-body vehicle in scalar arithmetic.

        The same equations as :func:`hitch_rows` plus the Schur-complement solve, written out
        for the right-hand side's most common case (one hitch, no closed stop, one state),
        where NumPy's per-call overhead on 2x6 arrays would dominate.  Tested against the
        general path.
        """
        L = self.layout
        X0, X1 = y[L.x].tolist()
        Y0, Y1 = y[L.y].tolist()
        U0, U1 = y[L.vx].tolist()
        V0, V1 = y[L.vy].tolist()
        W0, W1 = y[L.w].tolist()
        c0, c1 = c.tolist()
        s0, s1 = s.tolist()
        FX0, FX1, FY0, FY1, M0, M1 = f.tolist()
        m0, m1, _, _, i0, i1 = self._minv_list
        hfx, hfy, hrx, hry = self._hitch_points
        ax, ay = c0 * hfx - s0 * hfy, s0 * hfx + c0 * hfy
        bx, by = c1 * hrx - s1 * hry, s1 * hrx + c1 * hry
        al, be = self._alpha2, self._beta2
        # G rows (z order X0 X1 Y0 Y1 psi0 psi1): x = [1, -1, 0, 0, -ay, by]; y = [0, 0, 1, -1, ax, -bx]
        rx = -(
            FX0 * m0 - FX1 * m1 - ay * M0 * i0 + by * M1 * i1
            + (W1 * W1 * bx - W0 * W0 * ax)
            + al * (U0 - W0 * ay - U1 + W1 * by)
            + be * (X0 + ax - X1 - bx)
        )
        ry = -(
            FY0 * m0 - FY1 * m1 + ax * M0 * i0 - bx * M1 * i1
            + (W1 * W1 * by - W0 * W0 * ay)
            + al * (V0 + W0 * ax - V1 - W1 * bx)
            + be * (Y0 + ay - Y1 - by)
        )
        a00 = m0 + m1 + ay * ay * i0 + by * by * i1
        a11 = m0 + m1 + ax * ax * i0 + bx * bx * i1
        a01 = -ax * ay * i0 - bx * by * i1
        det = a00 * a11 - a01 * a01
        lx = (a11 * rx - a01 * ry) / det
        ly = (a00 * ry - a01 * rx) / det
        acc = np.array(
            [
                [(FX0 + lx) * m0],
                [(FX1 - lx) * m1],
                [(FY0 + ly) * m0],
                [(FY1 - ly) * m1],
                [(M0 - ay * lx + ax * ly) * i0],
                [(M1 + by * lx - bx * ly) * i1],
            ]
        )
        return acc, np.array([[lx, ly]])

    def tyre_body_forces(self, y: np.ndarray, seg: SegmentParams) -> np.ndarray:
        """Sum of tyre forces and moments per body for K states, z order, shape (3 n_bodies, K) [N, N m]."""
        return self._tyres(y, seg)[0]

    def evaluate(self, y: np.ndarray, seg: SegmentParams, full: bool = True) -> Evaluation:
        """Evaluate the model for K states ``y`` of shape (n_state, K).

        ``full=False`` (the right-hand side) skips the contact positions, speeds and powers.
        """
        L = self.layout
        f, c, s, u, v_lat, fx, fy, sliding, load = self._tyres(y, seg)
        vx, vy, w = y[L.vx], y[L.vy], y[L.w]
        if self.n_hitches == 1 and y.shape[1] == 1 and not seg.locks:
            acc, lam = self._single_hitch(y[:, 0], c[:, 0], s[:, 0], f[:, 0])
        elif self.n_hitches:
            G, g, g_dot, gamma = hitch_rows(self.front_points, self.rear_points, c, s, y[L.x], y[L.y], vx, vy, w, seg.locks)
            gm = G * self.minv
            rhs = -((gm @ f.T[:, :, None])[..., 0] + (gamma + self._alpha2 * g_dot + self._beta2 * g).T)
            lam = _solve_small(gm @ G.transpose(0, 2, 1), rhs)
            acc = self._minv_col * (f + (G.transpose(0, 2, 1) @ lam[:, :, None])[..., 0].T)
        else:
            lam = np.zeros((y.shape[1], 0))
            acc = self._minv_col * f
        accel_body = None
        if full or L.accel is not None:
            nb = L.n_bodies
            acc_x, acc_y = acc[:nb], acc[nb : 2 * nb]
            accel_body = np.concatenate([c * acc_x + s * acc_y, c * acc_y - s * acc_x])
        if L.accel is None:
            y_dot = np.concatenate([y[L.velocity], acc])
        else:
            y_dot = np.concatenate([y[L.velocity], acc, (accel_body - y[L.accel]) / self.options.load_transfer_tau])
        wheel_x = wheel_y = speed = power = None
        if full:
            bi = self.wheel_body
            cb, sb = c[bi], s[bi]
            wheel_x = y[L.x][bi] + cb * self._rx - sb * self._ry
            wheel_y = y[L.y][bi] + sb * self._rx + cb * self._ry
            speed = np.hypot(u, v_lat)
            power = fx * u + fy * v_lat
            load = np.broadcast_to(load, u.shape)
        return Evaluation(
            y_dot=y_dot,
            body_force=f,
            wheel_x=wheel_x,
            wheel_y=wheel_y,
            wheel_speed=speed,
            tyre_power=power,
            sliding=sliding,
            load=load,
            lam=lam,
            accel_body=accel_body,
        )

    def rhs(self, t: float, y: np.ndarray, seg: SegmentParams) -> np.ndarray:
        """Right-hand side ``y' = f(t, y)`` for one state (n_state,) or a batch (n_state, K).

        Raises
        ------
        SolverError
            If the derivative is not finite (never for valid inputs).
        """
        y_dot = self.evaluate(y[:, None] if y.ndim == 1 else y, seg, full=False).y_dot
        if not np.isfinite(y_dot).all():
            # solve_ivp can loop forever on NaN; stop with a clear message instead
            raise SolverError(f"non-finite state derivative at t = {t:.6g} s (state {np.asarray(y).ravel().tolist()})")
        return y_dot[:, 0] if y.ndim == 1 else y_dot

    def consistent_accelerations(self, y: np.ndarray, seg: SegmentParams, iterations: int = 50) -> np.ndarray:
        """State with the filtered accelerations set to their quasi-static fixed point.

        Used at the start of a run with load transfer, so the loads start consistent with
        the initial accelerations instead of lagging in from the static loads.  The
        iteration ``a_f <- a(a_f)`` contracts (mu h / L < 1, note sec. 2.6).
        """
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

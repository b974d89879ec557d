"""Reduced-coordinate formulation of a two-body combination: an independent test oracle.

Generalised coordinates ``q = (X1, Y1, psi1, psi2)``; the rear body's CG is eliminated
through the hitch, ``r2 = r1 + a - b`` (note sec. 1.3)::

    M(q) q'' = Q - m2 J^T c

    M = [[(m1+m2) I2,   m2 a^perp,        -m2 b^perp       ],
         [m2 a^perp^T,  I1 + m2 |a|^2,    -m2 a^perp.b^perp],
         [-m2 b^perp^T, -m2 a^perp.b^perp, I2 + m2 |b|^2   ]]
    Q = (F1 + F2,  M1 + a x F2,  M2 - b x F2),   c = -w1^2 a + w2^2 b

The constraint holds exactly by construction, so comparing this with the maximal-coordinate
engine (:mod:`crashsim.motion.hitches`, Lagrange multipliers + Baumgarte) checks the
multiplier and stabilisation code.  The tyre forces come from the same
:class:`~crashsim.motion.hitches.RunoutModel` (same wheels, loads and tyre law).  Only
what the oracle tests need is supported: one hitch, no friction zones, no schedule, no
articulation limit, no load transfer.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping

import numpy as np
from scipy.integrate import solve_ivp

from crashsim.errors import ScenarioError
from crashsim.vehicles import BodyState, Vehicle
from crashsim.motion.hitches import RunoutModel
from crashsim.motion.options import RunoutOptions
from crashsim.motion.road import Road
from crashsim.motion.wheels import WheelSettings

__all__ = ["ReducedResult", "simulate_reduced"]


@dataclass(frozen=True)
class ReducedResult:
    """Outcome of :func:`simulate_reduced`.

    Attributes
    ----------
    status : {"rest", "time_limit", "solver_failure"}
    t_end : float
        [s]
    final : dict of str to BodyState
    nfev : int
    """

    status: str
    t_end: float
    final: dict[str, BodyState]
    nfev: int


class _Reduced:
    def __init__(self, model: RunoutModel):
        self.model = model
        self.m1, self.m2 = model.mass
        self.i1, self.i2 = model.inertia
        self.rho_f = model.front_points[0]
        self.rho_r = model.rear_points[0]
        self.seg = model.segment(0.0, np.zeros((len(model.specs), 0), dtype=bool))

    def offsets(self, psi1, psi2):
        c1, s1, c2, s2 = np.cos(psi1), np.sin(psi1), np.cos(psi2), np.sin(psi2)
        a = np.array([c1 * self.rho_f[0] - s1 * self.rho_f[1], s1 * self.rho_f[0] + c1 * self.rho_f[1]])
        b = np.array([c2 * self.rho_r[0] - s2 * self.rho_r[1], s2 * self.rho_r[0] + c2 * self.rho_r[1]])
        return a, b

    def full_state(self, q, qd) -> np.ndarray:
        """Maximal-coordinate state vector of the model's layout from (q, q')."""
        L = self.model.layout
        a, b = self.offsets(q[2], q[3])
        a_perp, b_perp = np.array([-a[1], a[0]]), np.array([-b[1], b[0]])
        r2 = q[:2] + a - b
        v2 = qd[:2] + qd[2] * a_perp - qd[3] * b_perp
        y = np.zeros(L.size)
        y[L.x] = q[0], r2[0]
        y[L.y] = q[1], r2[1]
        y[L.psi] = q[2], q[3]
        y[L.vx] = qd[0], v2[0]
        y[L.vy] = qd[1], v2[1]
        y[L.w] = qd[2], qd[3]
        return y

    def rhs(self, t, state):
        q, qd = state[:4], state[4:]
        y = self.full_state(q, qd)
        f = self.model.evaluate(y[:, None], self.seg, full=False).body_force[:, 0]
        F1, F2 = np.array([f[0], f[2]]), np.array([f[1], f[3]])
        M1, M2 = f[4], f[5]
        a, b = self.offsets(q[2], q[3])
        a_perp, b_perp = np.array([-a[1], a[0]]), np.array([-b[1], b[0]])
        m1, m2 = self.m1, self.m2
        w1, w2 = qd[2], qd[3]
        M = np.zeros((4, 4))
        M[:2, :2] = (m1 + m2) * np.eye(2)
        M[:2, 2] = M[2, :2] = m2 * a_perp
        M[:2, 3] = M[3, :2] = -m2 * b_perp
        M[2, 2] = self.i1 + m2 * a @ a
        M[3, 3] = self.i2 + m2 * b @ b
        M[2, 3] = M[3, 2] = -m2 * a_perp @ b_perp
        cross = lambda u, v: u[0] * v[1] - u[1] * v[0]  # noqa: E731
        Q = np.array([*(F1 + F2), M1 + cross(a, F2), M2 - cross(b, F2)])
        axb = cross(a, b)
        JTc = m2 * np.array([*(-(w1**2) * a + w2**2 * b), w2**2 * axb, -(w1**2) * axb])
        qdd = np.linalg.solve(M, Q - JTc)
        return np.concatenate([qd, qdd])


def simulate_reduced(
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    options: RunoutOptions = RunoutOptions(),
) -> ReducedResult:
    """Run-out of a two-body vehicle in reduced coordinates (test oracle; see the module docstring).

    Parameters and rest criterion as :func:`~crashsim.motion.simulate_runout`; the initial
    state of the rear body is taken from the front body's state, the headings and the rear
    yaw rate (the hitch holds exactly).
    """
    if len(vehicle.bodies) != 2:
        raise ScenarioError(f"the reduced oracle needs exactly 2 bodies, got {len(vehicle.bodies)}", field="vehicle")
    if road.zones or options.load_transfer or vehicle.hitches[0].articulation_limit is not None:
        raise ScenarioError("the reduced oracle supports no zones, load transfer or articulation limit", field="options")
    settings = WheelSettings.all_locked() if wheels is None else wheels
    resolved = settings.resolve(vehicle)
    if resolved.change_times:
        raise ScenarioError("the reduced oracle supports no scheduled wheel changes", field="wheels.schedule")
    model = RunoutModel(vehicle, resolved, road, options)
    red = _Reduced(model)
    s1, s2 = initial[vehicle.bodies[0].name], initial[vehicle.bodies[1].name]
    state0 = np.array([*s1.position, s1.heading, s2.heading, *s1.velocity, s1.yaw_rate, s2.yaw_rate])

    def rest(t, state):
        return model.rest_measure(red.full_state(state[:4], state[4:])) - options.v_stop

    rest.terminal, rest.direction = True, -1
    sol = solve_ivp(
        red.rhs,
        (0.0, options.t_max),
        state0,
        method=options.method,
        rtol=options.rtol,
        atol=options.atol,
        max_step=options.max_step,
        events=[rest],
    )
    status = {1: "rest", 0: "time_limit"}.get(sol.status, "solver_failure")
    y_end = red.full_state(sol.y[:4, -1], sol.y[4:, -1])
    return ReducedResult(status=status, t_end=float(sol.t[-1]), final=model.layout.unpack(y_end), nfev=int(sol.nfev))

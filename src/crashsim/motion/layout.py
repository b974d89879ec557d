"""The run-out state vector, declared once.

The state is stored field-major: all bodies' X, then all Y, then all headings, then the
three velocity fields, then (with load transfer) the filtered body-axes accelerations::

    y = [x_0..x_{n-1}, y_0.., psi_0.., vx_0.., vy_0.., w_0.., (ax_f_0.., ay_f_0..)]

so that ``y[layout.x]`` is the vector of every body's X [m], ``y[layout.position]`` the
generalised coordinates z = (X..., Y..., psi...) and ``y[layout.velocity]`` their rates.
Units: m, rad, m/s, rad/s (world frame), m/s^2 (body axes).  The same slices work on a
2-D array of states, one column per time.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Mapping

import numpy as np

from ..errors import ScenarioError
from ..vehicles import BodyState

__all__ = ["StateLayout", "SV_X", "SV_Y", "SV_HEADING", "SV_VX", "SV_VY", "SV_YAW_RATE", "SV_AX_F", "SV_AY_F"]

#: Field offsets of the state vector, in units of the number of bodies ``nb``: field ``F`` of body
#: ``i`` is ``y[F * nb + i]`` (the order of :attr:`StateLayout.FIELDS`, then the filtered
#: accelerations).  The kernels compile them in as constants (:func:`crashsim._jit.kernel_sources`
#: lists this module).  The first three also address the generalised coordinates
#: z = (X..., Y..., psi...) (the columns of a hitch Jacobian).
SV_X, SV_Y, SV_HEADING, SV_VX, SV_VY, SV_YAW_RATE, SV_AX_F, SV_AY_F = range(8)


@dataclass(frozen=True)
class StateLayout:
    """Named slices into the run-out state vector.

    Parameters
    ----------
    bodies : tuple of str
        Body names, front to rear.
    accel_filter : bool
        Whether the state carries the filtered accelerations used for load transfer.
    clock : bool
        Whether the state ends with the clock (time [s], derivative 1): the air brakes' force
        is a function of time, and every kernel that evaluates a state reads it there.

    Attributes
    ----------
    x, y, psi, vx, vy, w : slice
        Each field for all bodies (length ``n_bodies``).
    position, velocity : slice
        ``(x, y, psi)`` and ``(vx, vy, w)`` blocks (length ``3 n_bodies``).
    ax_f, ay_f : slice or None
        Filtered body-axes accelerations [m/s^2] (None without load transfer).
    clock_index : int or None
        Index of the clock (with ``clock``).
    size : int
        Length of the state vector.
    """

    bodies: tuple[str, ...]
    accel_filter: bool = False
    clock: bool = False

    FIELDS = ("x", "y", "psi", "vx", "vy", "w")

    def __post_init__(self):
        object.__setattr__(self, "bodies", tuple(self.bodies))
        n = len(self.bodies)
        for k, name in enumerate(self.FIELDS):
            object.__setattr__(self, name, slice(k * n, (k + 1) * n))
        object.__setattr__(self, "position", slice(0, 3 * n))
        object.__setattr__(self, "velocity", slice(3 * n, 6 * n))
        if self.accel_filter:
            object.__setattr__(self, "ax_f", slice(6 * n, 7 * n))
            object.__setattr__(self, "ay_f", slice(7 * n, 8 * n))
            object.__setattr__(self, "accel", slice(6 * n, 8 * n))
        else:
            object.__setattr__(self, "ax_f", None)
            object.__setattr__(self, "ay_f", None)
            object.__setattr__(self, "accel", None)
        size = (8 if self.accel_filter else 6) * n
        object.__setattr__(self, "clock", bool(self.clock))
        object.__setattr__(self, "clock_index", size if self.clock else None)
        object.__setattr__(self, "size", size + (1 if self.clock else 0))

    @property
    def n_bodies(self) -> int:
        return len(self.bodies)

    def index(self, field: str, body: str) -> int:
        """Index of one field of one body in the state vector."""
        sl = getattr(self, field)
        return sl.start + self.bodies.index(body)

    def pack(self, states: Mapping[str, BodyState]) -> np.ndarray:
        """State vector from body states (filtered accelerations zero)."""
        y = np.zeros(self.size)
        for i, name in enumerate(self.bodies):
            if name not in states:
                raise ScenarioError(f"no initial state for body {name!r}; got {sorted(states)}", field="initial")
            s = states[name]
            if not isinstance(s, BodyState):
                raise ScenarioError(f"must be a BodyState, got {type(s).__name__}", field=f"initial[{name!r}]")
            y[self.x][i], y[self.y][i] = s.position
            y[self.psi][i] = s.heading
            y[self.vx][i], y[self.vy][i] = s.velocity
            y[self.w][i] = s.yaw_rate
        return y

    def unpack(self, y) -> dict[str, BodyState]:
        """Body states from a state vector.

        Finite values (every solver state) skip BodyState's input validation, which would only
        convert the same floats again (a few microseconds per body, noticeable in run-outs of
        a millisecond); anything else goes through the validating constructor (and its error).
        """
        values = np.asarray(y, dtype=float)[: 6 * len(self.bodies)].tolist()
        n = len(self.bodies)
        out = {}
        for i, name in enumerate(self.bodies):
            x, yy, psi, vx, vy, w = (values[k * n + i] for k in range(6))
            if math.isfinite(x + yy + psi + vx + vy + w):
                state = object.__new__(BodyState)
                object.__setattr__(state, "position", (x, yy))
                object.__setattr__(state, "heading", psi)
                object.__setattr__(state, "velocity", (vx, vy))
                object.__setattr__(state, "yaw_rate", w)
            else:
                state = BodyState((x, yy), psi, (vx, vy), w)
            out[name] = state
        return out

    def body_columns(self, y, body: str) -> np.ndarray:
        """The six fields of one body, shape ``(6,) + y.shape[1:]`` in :attr:`FIELDS` order."""
        i = self.bodies.index(body)
        return np.stack([np.asarray(y)[getattr(self, f)][i] for f in self.FIELDS])

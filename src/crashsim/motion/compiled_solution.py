"""The compiled engine's dense output (:class:`CompiledSolution`), and the notes on that engine: the SciPy
engine's model, events and results, integrated in numba (the loop is :mod:`crashsim.motion.kernels.integrator`).

Use it through the common entry points with ``RunoutOptions(engine="compiled")``
(:func:`~crashsim.motion.simulate_runout`, :func:`~crashsim.motion.simulate_scene`), which
return the same results as the SciPy engine.  Fits and Monte Carlo runs that repeat a
run-out thousands of times are what it is for.

Why numba (and not diffrax, numbalsoda, SUNDIALS)
-------------------------------------------------
The cost of a SciPy run-out is interpreter overhead per step and per event.  numba compiles
the whole loop -- right-hand side, integrator, event location, restarts -- into one call with
no Python in between, on NumPy arrays, with an on-disk cache (``cache=True``) and no new heavy
dependency.  Wrappers of compiled ODE libraries (numbalsoda's LSODA, SUNDIALS through
scikits.odes) still call back into Python for events or offer none; JAX/diffrax compiles per
array shape, has no event restarts with state jumps, and would add JAX.

Design
------
* **One source of the physics.**  The right-hand side, the event functions and what happens
  at an event are the kernels of :mod:`crashsim.motion.kernels`, which the SciPy engine calls
  too; the tyre law is :func:`crashsim.motion.tyres.tyre_kernel`, compiled for scalars.
* **Integrator.**  An explicit embedded Runge-Kutta pair with solve_ivp's own step-size
  controller, initial-step selection and tableaux: ``scheme="dopri5"`` (Dormand-Prince 5(4),
  RK45's tableau and 4th-order dense output, the default) or ``"bs3"`` (Bogacki-Shampine
  3(2), RK23's).  ``rtol``, ``atol``, ``max_step`` and ``first_step`` mean what they mean for
  solve_ivp.  One addition: a rejected step across a switch of a wheel's force law (lateral
  saturation, a braked wheel's lock-up, the ABS limit, a wheel lifting: the force keeps its
  value there, not its slope) is retried up to the switch instead of being shrunk by the error
  control's factor again and again (:func:`crashsim.motion.kernels.integrator.kink_fraction`);
  a run that crosses no switch in a rejected step takes solve_ivp's steps.
* **Stiffness.**  Free-rolling tyres make the equations stiff at low speed (eigenvalue
  ``~ -sum C_alpha / (m |u|)``); the slip denominator ``sqrt(u^2 + eps^2)`` caps it at
  ``sum C_alpha / (m eps)`` and the rest event ends a vehicle's run at ``v_stop``, so the
  explicit steps shrink to the stability limit only late in a long roll-out.
* **Events and impacts** exactly as the SciPy engine (:mod:`crashsim.motion.engine`): the same
  event functions located by Brent's method on the dense output with solve_ivp's tolerances,
  the same handling; the loop returns to Python only when a touch needs an impulse.

Compile time
------------
The first call in a fresh environment compiles the kernels (a minute or two on a 2-CPU
machine); later processes load them from numba's on-disk cache in about a second.
:func:`crashsim.warmup.compile_runout` triggers this explicitly and reports the time.
"""

from __future__ import annotations

import numpy as np

__all__ = ["CompiledSolution"]


# ----------------------------------------------------------------------------- dense output
class CompiledSolution:
    """Dense output of a compiled run: ``sol(t)`` -> state(s), like the SciPy engine's ``sol``.

    Evaluates the scheme's continuous extension of the solver step containing ``t``
    (``y_old + h Q [x, x^2, ...]``, ``x = (t - t_old)/h``).  Times are clipped to the run,
    ``[0, t_end]``: before separation the initial state, at and after the end the final state.
    At a segment boundary the later segment is used (the state after a stop or an impact).

    Parameters
    ----------
    t_old, h : ndarray, shape (n_steps,)
        Step start times and sizes [s], in time order over all segments.
    y_old : ndarray, shape (n_steps, n_state)
    q : ndarray, shape (n_steps, n_state, degree)
    y_end : ndarray, shape (n_state,)
    t_end : float
    """

    def __init__(self, t_old, h, y_old, q, y_end, t_end):
        self._t = t_old
        self._h = h
        self._y = y_old
        self._q = q
        self._y_end = y_end
        self._t_end = float(t_end)

    def __call__(self, t):
        t_arr = np.asarray(t, dtype=float)
        flat = np.clip(np.atleast_1d(t_arr).ravel(), 0.0, self._t_end)
        n = self._y_end.size
        out = np.empty((n, flat.size))
        if self._t.size == 0:
            out[:] = self._y_end[:, None]
        else:
            idx = np.clip(np.searchsorted(self._t, flat, side="right") - 1, 0, self._t.size - 1)
            h = self._h[idx]
            x = (flat - self._t[idx]) / h
            powers = np.cumprod(np.repeat(x[:, None], self._q.shape[2], axis=1), axis=1)  # (K, degree)
            out[:] = (self._y[idx] + h[:, None] * np.einsum("kid,kd->ki", self._q[idx], powers)).T
            out[:, flat >= self._t_end] = self._y_end[:, None]
        return out[:, 0] if t_arr.ndim == 0 else out.reshape((n,) + t_arr.shape)

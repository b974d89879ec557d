"""The nearest point of a polyline to each of many points, compiled (numba), for the evidence checks.

The same arithmetic, operation for operation, as the array form in
:func:`crashsim.evidence.checks._nearest_on_polyline` (no fused multiply-adds, no
reordering: numba's default, not ``fastmath``), so both give the same bits
(``tests/reconstruct/test_lean_chain.py``); a loop over the segments of each point instead of
(n, m) temporary arrays, and the exact (slow) ``hypot`` only for the segments whose squared
distance is within rounding of the least, several times faster for a measured mark against a
computed track.
Compiled on first use and cached on disk (:mod:`crashsim._jit`); without numba the
array form is used.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import configure

__all__ = ["nearest_on_polyline"]

_KERNEL = None


def _kernel():
    global _KERNEL
    if _KERNEL is None:
        configure()
        from numba import njit

        @njit(cache=True)
        def nearest(p, line):  # pragma: no cover - compiled
            n, m = p.shape[0], line.shape[0] - 1
            dist = np.empty(n)
            side = np.empty(n)
            ax = line[:-1, 0].copy()
            ay = line[:-1, 1].copy()
            abx = line[1:, 0] - ax
            aby = line[1:, 1] - ay
            denom = abx * abx + aby * aby
            dx = np.empty(m)
            dy = np.empty(m)
            d2 = np.empty(m)
            for i in range(n):
                px, py = p[i, 0], p[i, 1]
                low, finite = np.inf, True
                for j in range(m):
                    t = (px - ax[j]) * abx[j]
                    t += (py - ay[j]) * aby[j]
                    t /= denom[j] if denom[j] > 0 else 1.0
                    t = min(max(t, 0.0), 1.0)
                    dx[j] = px - (ax[j] + t * abx[j])
                    dy[j] = py - (ay[j] + t * aby[j])
                    d2[j] = dx[j] * dx[j] + dy[j] * dy[j]
                    if d2[j] < low:
                        low = d2[j]
                    elif not d2[j] < np.inf:
                        finite = False
                # numpy's argmin of hypot(dx, dy): the first index of the least distance.  Any index
                # whose distance ties the least has its square within a few ulp of the least square,
                # so only those within a relative 1e-9 need the (slow, exact) hypot.
                bound = low * (1.0 + 1e-9) if finite else np.inf
                best, jb = np.inf, -1
                for j in range(m):
                    if d2[j] <= bound or not finite:
                        d = math.hypot(dx[j], dy[j])
                        if jb < 0 or d < best or (d != d and best == best):  # the first minimum, or the first NaN
                            best, jb = d, j
                dist[i] = best
                side[i] = 1.0 if abx[jb] * (py - ay[jb]) - aby[jb] * (px - ax[jb]) >= 0 else -1.0
            return dist, side

        _KERNEL = nearest
    return _KERNEL


def nearest_on_polyline(points: np.ndarray, polyline: np.ndarray):
    """(distance, side) of each point (n, 2) to a polyline (m >= 2, 2), or None without numba."""
    try:
        k = _kernel()
    except ImportError:  # pragma: no cover - numba is a dependency of the compiled engine
        return None
    return k(np.ascontiguousarray(points, dtype=float), np.ascontiguousarray(polyline, dtype=float))

"""Compiled entry points the SciPy engine calls from its Python loop.

The right-hand side, event values and the event handler of the kernels behind small
allocating wrappers (:mod:`crashsim.motion.engine`, ``_ScipyIntegrator``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from .jit import JIT
from .arrays import LOG_SCHEDULE, N_S, Events, make_work
from .equations import evaluate, segment_params
from .events import build_events, event_rate, event_resolution, event_value, handle_event, log_record, settle

@njit(**JIT)
def rhs(y, M, phase, D):
    """Right-hand side of one state in wheel phase ``phase`` and mode ``D`` (the SciPy engine's ``fun``)."""
    W = make_work(M)
    sw = np.zeros((M.wheel.shape[0], N_S))
    segment_params(phase, D.memb, M, sw)
    dydt = np.zeros(y.shape[0])
    evaluate(y, M, sw, D, dydt, W)
    return dydt


@njit(**JIT)
def rhs_work(y, M, phase, D, n):
    """:func:`rhs` of the state ``y[:n]`` followed by the contact powers of every pair [W]: the
    SciPy engine integrates the contact work with the state while pairs are in contact, so the
    work it books is that of the forces its own steps felt (the compiled engine sums the same
    powers with the Runge-Kutta weights of its stages)."""
    W = make_work(M)
    sw = np.zeros((M.wheel.shape[0], N_S))
    segment_params(phase, D.memb, M, sw)
    out = np.zeros(y.shape[0])
    evaluate(y[:n], M, sw, D, out[:n], W)
    for p in range(y.shape[0] - n):
        out[n + p] = W.pair_power[p]
    return out


@njit(**JIT)
def rhs_many(Y, M, phase, D):
    """:func:`rhs` of the columns of ``Y`` (n, K) (SciPy's implicit methods estimate Jacobians with it)."""
    W = make_work(M)
    sw = np.zeros((M.wheel.shape[0], N_S))
    segment_params(phase, D.memb, M, sw)
    out = np.zeros(Y.shape)
    dydt = np.zeros(Y.shape[0])
    col = np.zeros(Y.shape[0])
    for k in range(Y.shape[1]):
        for i in range(Y.shape[0]):
            col[i] = Y[i, k]
        evaluate(col, M, sw, D, dydt, W)
        for i in range(Y.shape[0]):
            out[i, k] = dydt[i]
    return out


@njit(**JIT)
def segment_events(M, D, offsets):
    """The events of a segment in mode ``D``: ``(ev_kind, ev_idx, ev_val, ev_dir)`` (:func:`build_events`)."""
    n_max = D.parked.shape[0] + M.zone_mu.shape[0] + 3 * M.hitch.shape[0] + 3 * M.pair_body.shape[0] + 1
    ev_kind = np.zeros(n_max, np.int64)
    ev_idx = np.zeros(n_max, np.int64)
    ev_val = np.zeros(n_max)
    ev_dir = np.zeros(n_max)
    n_ev = build_events(M, D, offsets, Events(ev_kind, ev_idx, ev_val, ev_dir))
    return ev_kind[:n_ev], ev_idx[:n_ev], ev_val[:n_ev], ev_dir[:n_ev]


@njit(**JIT)
def event_values(y, M, phase, D, ev_kind, ev_idx, ev_val):
    """Values and rate bounds of the segment's events at ``y`` (:func:`event_value`, :func:`event_rate`)."""
    W = make_work(M)
    sw = np.zeros((M.wheel.shape[0], N_S))
    segment_params(phase, D.memb, M, sw)
    dydt = np.zeros(y.shape[0])
    n_ev = ev_kind.shape[0]
    ev = Events(ev_kind, ev_idx, ev_val, ev_val)  # directions are not read
    g = np.zeros(n_ev)
    r = np.zeros(n_ev)
    for e in range(n_ev):
        g[e] = event_value(e, y, M, ev, D, sw, dydt, W)
        r[e] = event_rate(e, y, M, ev, W)
    return g, r


@njit(**JIT)
def event_resolutions(M, ev_kind, ev_idx):
    out = np.zeros(ev_kind.shape[0])
    ev = Events(ev_kind, ev_idx, out, out)  # kinds and indices only are read
    for e in range(ev_kind.shape[0]):
        out[e] = event_resolution(e, M, ev)
    return out


@njit(**JIT)
def event_value_at(e, y, M, phase, D, ev_kind, ev_idx, ev_val):
    """One event value (the SciPy engine's root finder calls it on its dense output)."""
    W = make_work(M)
    sw = np.zeros((M.wheel.shape[0], N_S))
    segment_params(phase, D.memb, M, sw)
    ev = Events(ev_kind, ev_idx, ev_val, ev_val)  # directions are not read
    return event_value(e, y, M, ev, D, sw, np.zeros(y.shape[0]), W)


@njit(**JIT)
def apply_event(e, t, y, M, phase, D, offsets, ev_kind, ev_idx, ev_val, ev_dir):
    """:func:`handle_event` then (unless an impulse is needed) :func:`settle`: ``(impact, records, geo)``."""
    W = make_work(M)
    sw = np.zeros((M.wheel.shape[0], N_S))
    segment_params(phase, D.memb, M, sw)
    rec = np.zeros((M.wheel.shape[0] * max(M.zone_mu.shape[0], 1) + D.parked.shape[0] + 8, 5))
    geo = np.zeros(6)
    impact, n = handle_event(e, t, y, M, D, offsets, Events(ev_kind, ev_idx, ev_val, ev_dir), sw, np.zeros(y.shape[0]), W,
                             rec, geo)
    if not impact:
        n = settle(y, M, D, np.zeros((M.wheel.shape[0], M.zone_mu.shape[0]), np.bool_), W, rec, n)
    return impact, rec[:n], geo


@njit(**JIT)
def schedule_change(y, M, D):
    """A scheduled wheel change: the log record, then :func:`settle`."""
    W = make_work(M)
    rec = np.zeros((M.wheel.shape[0] * max(M.zone_mu.shape[0], 1) + D.parked.shape[0] + 8, 5))
    n = log_record(rec, 0, LOG_SCHEDULE, 0, 0, 0.0, 0.0)
    n = settle(y, M, D, np.zeros((M.wheel.shape[0], M.zone_mu.shape[0]), np.bool_), W, rec, n)
    return rec[:n]

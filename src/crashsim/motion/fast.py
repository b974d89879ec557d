"""The compiled run-out engine: the SciPy engine's model, events and results, integrated in numba.

Use it through the common entry point,
``simulate_runout(..., options=RunoutOptions(engine="compiled"))``, which returns the same
:class:`~crashsim.motion.result.RunoutResult` as the SciPy engine.  Fits and Monte Carlo runs
that repeat a run-out thousands of times are what it is for.

Why numba (and not diffrax, numbalsoda, SUNDIALS)
-------------------------------------------------
The cost of a SciPy run-out is interpreter overhead: about 100 us per right-hand side (RHS)
evaluation, of which the arithmetic is well under 1 us.  The run-out is also event-heavy
(rest, per-zone crossings, articulation stops that close and open with an impulsive
projection, scheduled wheel changes) and needs dense output for tracks.  numba compiles the
whole loop -- RHS, integrator, event location, restarts and the post-processing -- into one
call with no Python in between, on NumPy arrays, with an on-disk cache (``cache=True``) and
no new heavy dependency.  Wrappers of compiled ODE libraries (numbalsoda's LSODA, SUNDIALS
through scikits.odes) still call back into Python for events or offer none; JAX/diffrax
compiles per array shape, has no event restarts with state jumps, and would add JAX.

Design
------
* **Model.**  The same equations as :class:`~crashsim.motion.dynamics.RunoutModel`: maximal
  coordinates with the Baumgarte-stabilised hitch multipliers (any chain of bodies; closed
  articulation stops as extra constraint rows), per-wheel tyre forces, static loads or
  quasi-static load transfer with its first-order lag states.  The tyre law is not
  re-implemented: numba compiles :func:`crashsim.motion.tyres.tyre_kernel`, the function the
  SciPy engine evaluates on arrays (:mod:`crashsim.motion._fast_kernels` registers scalar
  overloads for its helpers).  Loads, reference lengths and wheel phases come from the same
  Python functions as for the SciPy engine.
* **Integrator.**  An explicit embedded Runge-Kutta pair with solve_ivp's own step-size
  controller, initial-step selection and tableaux: ``scheme="dopri5"`` (Dormand-Prince 5(4),
  RK45's tableau and 4th-order dense output, the default) or ``"bs3"`` (Bogacki-Shampine
  3(2), RK23's).  ``rtol``, ``atol``, ``max_step`` and ``first_step`` mean what they mean for
  solve_ivp.
* **Stiffness.**  Free-rolling tyres make the equations stiff at low speed (eigenvalue
  ``~ -sum C_alpha / (m |u|)``).  The minimum slip denominator ``sqrt(u^2 + eps^2)`` of the
  shared tyre law caps it at ``sum C_alpha / (m eps)`` and the rest event ends the run at
  ``v_stop``, so the explicit steps shrink to the stability limit only late in a long
  roll-out and never collapse.  Measured (``plots/fast_path.md``) on a 59 s free-rolling car:
  dopri5 needs 9.5x LSODA's right-hand-side evaluations, yet at well under a microsecond per
  evaluation the run-out takes ~4 ms against ~68 ms (17x; bs3, with the larger stability
  region per evaluation, 20x).  No implicit scheme is included: a Rosenbrock step would need
  a Jacobian (n extra evaluations) and an LU solve per step, and a third of that run-out's
  time is the post-processing of its 5900 samples anyway.
* **Events** exactly as :mod:`crashsim.motion.simulate`: the same event functions (rest
  measure with the same ``v_stop`` and ``L_ref``; per zone the minimum over wheels of the
  side-signed distance to the polygon plus the 0.1 nm overshoot; articulation angle against
  its limits; the closed stop's multiplier), checked at every step end, located on the dense
  output by Brent's method with solve_ivp's tolerances (4 machine epsilons), the earliest
  root ending the segment.  Restarts recompute zone membership with the same
  direction-of-motion rule, apply the plastic stop impact (projection in the kinetic-energy
  metric, then close the stop unless its moment would pull) and start the next wheel phase
  at the scheduled time.  So zone crossings and stops are located to ~1e-15 s, not to a step.
* **Results.**  Samples on the same time grid as the SciPy engine (segment starts, the
  ``sample_dt`` grid, the end), the same path integrals (5-point Gauss-Legendre on each
  solver step), the same zone-missed check; the objects are built by
  :func:`crashsim.motion.postprocess.build_result`, shared with the SciPy engine.  ``sol`` is
  the solver's dense output (exact to the scheme's interpolant, as SciPy's).  ``nfev``
  counts RHS evaluations of the integrator (event location and post-processing excluded,
  as for solve_ivp).

Compile time
------------
The first call in a fresh environment compiles the kernels (55-65 s on the 2-CPU benchmark
machine); later processes load them from numba's on-disk cache (``__pycache__`` next to the
module) in about a second.  :func:`compile_kernels` triggers this explicitly and reports the
time.  The cache is keyed on the sources of the kernels *and* of :mod:`crashsim.motion.tyres`.

Performance notes
-----------------
Per right-hand side the articulated truck of the Table 6 scene (10 contacts, one hitch)
costs ~0.3 us, a car ~0.15 us; a whole run-out to rest including the result objects about
1 ms (truck) and 0.3-0.6 ms (car).  What made the difference: no NRT reference counting in
the hot functions (``_nrt=False``), small helpers and the right-hand side inlined into the
RK step (numba passes tuples of arrays as hundreds of scalar arguments), path integrals
accumulated from the RK stages instead of a quadrature pass, and cached set-up of the
vehicle, road and options (keyed by object identity).

Differences from the SciPy engine
---------------------------------
Nothing of the model is left out: every option of :class:`RunoutOptions` except ``method``
(the solve_ivp method) acts identically; ``scheme`` selects the compiled scheme instead.
``njev`` and ``nlu`` are always 0 (no Jacobians).  Path integrals on steps where no contact
switches between rolling and sliding come from the RK stages (5th order, like the step);
sliding lengths carry, in both engines, an error of about speed x step per switch (neither
locates the switch).  When an event's sign change at a step end is not reproduced by the
dense output (round-off at a root on the step start), the event is placed at the step end
instead of failing as solve_ivp's brentq would.  Warnings logged while preparing a vehicle
(negative hitch loads) appear once per cached vehicle, not on every call.
"""

from __future__ import annotations

import logging
import math
import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Mapping

import numpy as np
from scipy.integrate import RK23, RK45

from ..errors import ScenarioError
from ..vehicles import BodyState, Vehicle
from .dynamics import RunoutModel, reference_lengths
from .layout import StateLayout
from .loads import StaticLoads, load_transfer_matrix, static_loads
from .options import RunoutOptions
from .postprocess import _GL_NODES, _GL_WEIGHTS, build_result
from .result import RunoutEvent, RunoutResult, limit_message
from .road import Road
from .wheels import ResolvedWheels, WheelSettings

__all__ = ["simulate_runout_compiled", "compile_kernels", "compile_report", "CompiledSolution", "model_bundle"]

_log = logging.getLogger("crashsim")

# Same thresholds as crashsim.motion.simulate.check_hitch_consistency.
_PIN_VELOCITY_TOL = 1e-6
_PIN_GAP_TOL = 1e-3

#: Explicit RK schemes: solve_ivp's tableaux (A, B, C, E, P) and error-estimator order.
_SCHEMES = {"dopri5": RK45, "bs3": RK23}


def _kernels():
    """The kernel module (imported on first use: importing it registers the numba overloads)."""
    from . import _fast_kernels

    return _fast_kernels


# ----------------------------------------------------------------------------- prepared inputs
@dataclass(eq=False)
class _VehiclePack:
    """Everything about a vehicle and its wheel settings the kernels need (independent of road and options)."""

    vehicle: Vehicle
    resolved: ResolvedWheels
    layout: StateLayout
    layout_lt: StateLayout
    specs: tuple
    loads: StaticLoads
    static_load: np.ndarray
    mass: np.ndarray
    inertia: np.ndarray
    body: np.ndarray
    wheel: np.ndarray
    wbody: np.ndarray
    hitch: np.ndarray
    minv: np.ndarray
    phase_t: np.ndarray
    phase_w: np.ndarray
    change_times: tuple
    no_transfer: np.ndarray
    transfer: np.ndarray | None = None
    stops: dict = field(default_factory=dict)


def _vehicle_pack(vehicle: Vehicle, wheels: WheelSettings) -> _VehiclePack:
    k = _kernels()
    resolved = wheels.resolve(vehicle)
    specs = resolved.specs
    if not specs:
        raise ScenarioError("a run-out needs at least one axle", field=f"{vehicle.name}.bodies")
    loads = static_loads(vehicle)
    bodies = vehicle.bodies
    names = tuple(b.name for b in bodies)
    mass = np.array([b.mass for b in bodies], dtype=float)
    inertia = np.array([b.yaw_inertia for b in bodies], dtype=float)
    l_ref = reference_lengths(vehicle, specs)
    body = np.ascontiguousarray(np.stack([mass, inertia, l_ref], 1))
    wheel = np.array([[s.position[0], s.position[1], n] for s, n in zip(specs, loads.wheel)], dtype=float)
    wbody = np.array([s.body_index for s in specs], dtype=np.int64)
    hitch = np.array(
        [
            [*h.front_point, *h.rear_point, math.nan if h.articulation_limit is None else h.articulation_limit]
            for h in vehicle.hitches
        ],
        dtype=float,
    ).reshape(-1, 5)
    minv = np.concatenate([1 / mass, 1 / mass, 1 / inertia])
    phase_t = np.array([t for t, _ in resolved.phases], dtype=float)
    phase_w = np.zeros((len(resolved.phases), len(specs), k.N_P))
    for p, (_, settings) in enumerate(resolved.phases):
        for i, (s, spec) in enumerate(zip(settings, specs)):
            phase_w[p, i, k.P_MUF] = s.mu_factor
            phase_w[p, i, k.P_BRAKE] = s.brake
            phase_w[p, i, k.P_FROLL] = s.rolling_resistance or 0.0
            phase_w[p, i, k.P_CFIX] = (s.cornering_stiffness or 0.0) * spec.tyres
            phase_w[p, i, k.P_CCOEF] = s.cornering_coefficient or 0.0
            phase_w[p, i, k.P_CD] = math.cos(s.steer)
            phase_w[p, i, k.P_SD] = math.sin(s.steer)
            phase_w[p, i, k.P_LOCKED] = 1.0 if s.is_sliding else 0.0
    return _VehiclePack(
        vehicle=vehicle,
        resolved=resolved,
        layout=StateLayout(names),
        layout_lt=StateLayout(names, accel_filter=True),
        specs=specs,
        loads=loads,
        static_load=loads.wheel.copy(),
        mass=mass,
        inertia=inertia,
        body=body,
        wheel=wheel,
        wbody=wbody,
        hitch=np.ascontiguousarray(hitch),
        minv=minv,
        phase_t=phase_t,
        phase_w=phase_w,
        change_times=resolved.change_times,
        no_transfer=np.zeros((len(specs), 2 * len(bodies))),
    )


def _road_arrays(road: Road):
    zone_mu = np.array([z.mu for z in road.zones], dtype=float)
    ptr = np.zeros(len(road.zones) + 1, dtype=np.int64)
    edges = []
    for i, z in enumerate(road.zones):
        x0, y0, ex, ey, inv = z._edge_arrays
        edges.append(np.stack([x0, y0, ex, ey, inv], 1))
        ptr[i + 1] = ptr[i] + len(x0)
    edge_arr = np.ascontiguousarray(np.concatenate(edges, 0)) if edges else np.zeros((0, 5))
    box = np.array([[*np.min(z.vertices, 0), *np.max(z.vertices, 0)] for z in road.zones], dtype=float).reshape(-1, 4)
    return zone_mu, ptr, edge_arr, box


def _option_arrays(options: RunoutOptions, road: Road):
    k = _kernels()
    cfg = np.zeros(k.N_CFG)
    cfg[k.C_EPS] = options.eps
    cfg[k.C_ALPHA2] = 2.0 * options.baumgarte_zeta * options.baumgarte_omega
    cfg[k.C_BETA2] = options.baumgarte_omega**2
    cfg[k.C_TAU] = options.load_transfer_tau
    cfg[k.C_VSTOP] = options.v_stop
    cfg[k.C_RTOL] = options.rtol
    cfg[k.C_ATOL] = options.atol
    cfg[k.C_MAXSTEP] = options.max_step
    cfg[k.C_FIRST] = 0.0 if options.first_step is None else options.first_step
    cfg[k.C_TMAX] = options.t_max
    cfg[k.C_SDT] = options.sample_dt
    cfg[k.C_ROADMU] = road.mu
    scheme = _SCHEMES[options.scheme]
    icfg = np.zeros(k.N_ICFG, dtype=np.int64)
    icfg[k.I_FIALA] = 1 if options.lateral_model == "fiala" else 0
    icfg[k.I_LT] = 1 if options.load_transfer else 0
    icfg[k.I_MAXSEG] = int(options.max_segments)
    icfg[k.I_MAXEVAL] = int(options.max_evaluations)
    icfg[k.I_ORDER] = scheme.error_estimator_order
    icfg[k.I_NSTAGES] = scheme.n_stages
    tab = (
        np.ascontiguousarray(scheme.A, dtype=float),
        np.ascontiguousarray(scheme.B, dtype=float),
        np.ascontiguousarray(scheme.C, dtype=float),
        np.ascontiguousarray(scheme.E, dtype=float),
        np.ascontiguousarray(scheme.P, dtype=float),
    )
    return cfg, icfg, tab


class _Cache:
    """Small LRU caches of prepared inputs, so repeated run-outs (fits, Monte Carlo) skip the set-up.

    Keyed by the identity of the (frozen) input objects; each entry keeps its objects alive, so
    an identity cannot be reused while cached.  New but equal objects just build a new entry.
    """

    def __init__(self, size: int = 64):
        self.size = size
        self.lock = threading.Lock()
        self.table: OrderedDict = OrderedDict()

    def get(self, key, refs, make):
        with self.lock:
            hit = self.table.get(key)
            if hit is not None:
                self.table.move_to_end(key)
                return hit[1]
        value = make()
        with self.lock:
            self.table[key] = (refs, value)
            while len(self.table) > self.size:
                self.table.popitem(last=False)
        return value

    def vehicle(self, vehicle, wheels):
        return self.get(("vehicle", id(vehicle), id(wheels)), (vehicle, wheels), lambda: _vehicle_pack(vehicle, wheels))

    def road(self, road):
        return self.get(("road", id(road)), road, lambda: _road_arrays(road))

    def option_arrays(self, options, road):
        return self.get(("options", id(options), road.mu), options, lambda: _option_arrays(options, road))


_CACHE = _Cache()


# ----------------------------------------------------------------------------- dense output
class CompiledSolution:
    """Dense output of a compiled run: ``sol(t)`` -> state(s), like the SciPy engine's ``sol``.

    Evaluates the scheme's continuous extension of the solver step containing ``t``
    (``y_old + h Q [x, x^2, ...]``, ``x = (t - t_old)/h``).  Times are clipped to the run,
    ``[0, t_end]``: before separation the initial state, at and after the end the final state.
    At a segment boundary the later segment is used (the state after a stop impact).

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


# ----------------------------------------------------------------------------- compile / warm-up
_COMPILE = {"seconds": None, "from_cache": None}
_COMPILE_LOCK = threading.Lock()


def compile_kernels() -> float:
    """Compile (or load from numba's on-disk cache) the kernels by running a tiny run-out.

    Returns
    -------
    float
        Wall time [s] of the first call in this process (0.0 if already done).  The first call
        in a fresh environment compiles (tens of seconds); later processes load the cache.
    """
    with _COMPILE_LOCK:
        if _COMPILE["seconds"] is not None:
            return 0.0
        from ..vehicles import Axle, Body, Hitch

        t0 = time.perf_counter()
        k = _kernels()
        tractor = Body("a", 1000.0, 1000.0, axles=(Axle(1.0, 1.5), Axle(-1.0, 1.5)))
        trailer = Body("b", 500.0, 500.0, axles=(Axle(-1.0, 1.5),))
        vehicle = Vehicle("warm-up", (tractor, trailer), (Hitch((-2.0, 0.0), (1.5, 0.0), articulation_limit=1.0),))
        states = {
            "a": BodyState((0.0, 0.0), 0.0, (0.5, 0.0), 0.0),
            "b": BodyState((-3.5, 0.0), 0.0, (0.5, 0.0), 0.0),
        }
        simulate_runout_compiled(vehicle, states, None, Road(0.7), RunoutOptions(engine="compiled", t_max=0.5))
        _COMPILE["seconds"] = time.perf_counter() - t0
        _COMPILE["from_cache"] = bool(k.run.stats.cache_hits) and not k.run.stats.cache_misses
        return _COMPILE["seconds"]


def compile_report() -> dict:
    """``{"seconds": first-call time [s] or None, "from_cache": bool or None}`` of this process."""
    return dict(_COMPILE)


# ----------------------------------------------------------------------------- the engine
_STATUS = {0: "rest", 1: "time_limit", 2: "event_limit", 3: "solver_failure", 4: "solver_failure",
           5: "evaluation_limit", 6: "wall_time_limit", 7: "event_limit"}


@dataclass(eq=False)
class _ModelView:
    """What :func:`~crashsim.motion.postprocess.build_result` needs of a model."""

    vehicle: Vehicle
    layout: StateLayout
    specs: tuple
    static_load: np.ndarray
    loads: StaticLoads
    mass: np.ndarray
    inertia: np.ndarray
    options_dict: dict


_OPTIONS_DICT: dict = {}


def _options_dict(options: RunoutOptions) -> dict:
    d = _OPTIONS_DICT.get(options)
    if d is None:
        d = options.to_dict()
        if len(_OPTIONS_DICT) > 256:
            _OPTIONS_DICT.clear()
        _OPTIONS_DICT[options] = d
    return d


def model_bundle(vehicle: Vehicle, wheels: WheelSettings, road: Road, options: RunoutOptions):
    """The kernels' model bundle ``M`` (see :mod:`crashsim.motion._fast_kernels`), cached.

    Returns
    -------
    (pack, layout, M)
        Prepared vehicle data, the state layout and the tuple of arrays the kernels take.
    """
    pack = _CACHE.vehicle(vehicle, wheels)
    lt = bool(options.load_transfer)
    if lt and pack.transfer is None:
        pack.transfer = np.ascontiguousarray(load_transfer_matrix(vehicle, pack.loads))
    layout = pack.layout_lt if lt else pack.layout
    transfer = pack.transfer if lt else pack.no_transfer
    zone_mu, zone_ptr, edges, zone_box = _CACHE.road(road)
    cfg, icfg, tab = _CACHE.option_arrays(options, road)
    M = (pack.body, pack.wheel, pack.wbody, pack.hitch, transfer, pack.minv, pack.phase_t, pack.phase_w,
         zone_mu, zone_ptr, edges, cfg, icfg, *tab, zone_box)
    return pack, layout, M


def simulate_runout_compiled(
    vehicle: Vehicle,
    initial: Mapping[str, BodyState],
    wheels: WheelSettings | None,
    road: Road,
    options: RunoutOptions,
) -> RunoutResult:
    """Run-out of one vehicle with the compiled engine (use ``simulate_runout(..., RunoutOptions(engine="compiled"))``).

    Parameters, returns and errors as :func:`~crashsim.motion.simulate_runout`; the result's
    ``method`` is ``"compiled/<scheme>"``.
    """
    k = _kernels()
    settings = WheelSettings.all_locked() if wheels is None else wheels
    if not isinstance(settings, WheelSettings):
        raise ScenarioError(f"must be WheelSettings or None, got {type(wheels).__name__}", field=f"wheels[{vehicle.name!r}]")
    pack, layout, M = model_bundle(vehicle, settings, road, options)
    y0 = layout.pack(initial)
    _check_hitches(vehicle, initial, road, options, pack, y0)
    stops = pack.stops.get(options.t_max)
    if stops is None:
        stops = np.array(sorted({tc for tc in pack.change_times if tc < options.t_max} | {options.t_max}), dtype=float)
        pack.stops[options.t_max] = stops

    (status_code, t_end, y_end, y_initial, nfev, n_steps, n_seg, quad, ke0, ke1, st_t, st_h, st_y, st_q,
     sg_t, sg_s, sg_phase, sg_memb, sg_nlk, sg_lkj, sg_lkth,
     lg_n, lg_t, lg_kind, lg_i, lg_j, lg_x, lg_e) = k.run(y0, M, stops, _GL_NODES, _GL_WEIGHTS,
                                                          time.perf_counter() + options.max_wall_time)
    (T, Y, P, SL, LD, LAMH, STOPM, max_gap, miss_t, miss_k) = k.postprocess(
        M, t_end, y_end, st_t, st_h, st_y, st_q, sg_t, sg_s, sg_phase, sg_memb, sg_nlk, sg_lkj, sg_lkth,
        options.sample_dt, True,
    )
    nb, nw = len(vehicle.bodies), len(pack.specs)
    status = _STATUS[int(status_code)]
    events = _events(pack, road, lg_t, lg_kind, lg_i, lg_j, lg_x, lg_e, k)
    message = _message(int(status_code), options, t_end, y_end, k, M, events)
    events.append(RunoutEvent(float(t_end), status, message))
    if status != "rest":
        _log.warning("run-out of %s did not reach rest (%s): %s", vehicle.name, status, message)
    _log.debug("run-out of %s: %s after %d segments, nfev=%d (compiled)", vehicle.name, status, n_seg, nfev)
    view = _ModelView(vehicle, layout, pack.specs, pack.static_load, pack.loads, pack.mass, pack.inertia,
                      _options_dict(options))
    sol = CompiledSolution(st_t, st_h, st_y, st_q, y_end, t_end)
    return build_result(
        view,
        t=T,
        Y=Y,
        points=P,
        sliding=SL,
        load=LD,
        hitch_force=LAMH,
        stop_moment=STOPM,
        distance=quad[:nb],
        path_length=quad[nb : nb + nw],
        sliding_length=quad[nb + nw : nb + 2 * nw],
        energy=quad[nb + 2 * nw :],
        max_gap=max_gap,
        missed=(float(miss_t), pack.specs[int(miss_k)].key) if miss_k >= 0 else None,
        status=status,
        message=message,
        t_end=t_end,
        y_initial=y_initial,
        y_final=y_end,
        sol=sol,
        events=events,
        nfev=nfev,
        njev=0,
        nlu=0,
        n_segments=n_seg,
        method=f"compiled/{options.scheme}",
        kinetic_energies=(ke0, ke1),
    )


def _check_hitches(vehicle, initial, road, options, pack, y0):
    """The checks of :func:`crashsim.motion.simulate.check_hitch_consistency`, raising its errors.

    Pin gaps, pin relative speeds and articulation limits in scalar arithmetic (a few
    microseconds); on a violation the SciPy engine's check is run to raise its exact error.
    """
    if not vehicle.hitches:
        return
    nb = len(vehicle.bodies)
    y = y0.tolist()
    x, yy, psi, vx, vy, w = (y[i * nb : (i + 1) * nb] for i in range(6))
    allowed = _PIN_VELOCITY_TOL * (1.0 + max(math.hypot(a, b) for a, b in zip(vx, vy)))
    bad = False
    for j, h in enumerate(vehicle.hitches):
        c0, s0, c1, s1 = math.cos(psi[j]), math.sin(psi[j]), math.cos(psi[j + 1]), math.sin(psi[j + 1])
        (fx, fy), (rx, ry) = h.front_point, h.rear_point
        ax, ay = c0 * fx - s0 * fy, s0 * fx + c0 * fy
        bx, by = c1 * rx - s1 * ry, s1 * rx + c1 * ry
        gap = math.hypot(x[j] + ax - x[j + 1] - bx, yy[j] + ay - yy[j + 1] - by)
        speed = math.hypot(vx[j] - w[j] * ay - vx[j + 1] + w[j + 1] * by, vy[j] + w[j] * ax - vy[j + 1] - w[j + 1] * bx)
        bad = bad or gap > _PIN_GAP_TOL or speed > allowed
        if h.articulation_limit is not None:
            theta = math.remainder(psi[j] - psi[j + 1], 2 * math.pi)
            bad = bad or abs(theta) > h.articulation_limit + 1e-9
    if bad:
        from .simulate import check_hitch_consistency

        model = RunoutModel(vehicle, pack.resolved, road, options)
        check_hitch_consistency(model, model.layout.pack(initial))
        raise ScenarioError(  # pragma: no cover - the SciPy check raises first
            "initial states are not hitch-consistent", field=f"initial[{vehicle.bodies[0].name!r}]"
        )


def _message(code, options, t_end, y_end, k, M, events) -> str:
    if code == k.ST_REST:
        return f"all bodies below v_stop = {options.v_stop} m/s at t = {t_end:.4f} s"
    if code == k.ST_TIME_LIMIT:
        return limit_message("time_limit", options, t_end, k.rest_measure(y_end, M))
    if code == k.ST_MAX_SEGMENTS:
        return limit_message("event_limit", options, t_end, last_event=events[-1].detail if events else None)
    if code == k.ST_NO_PROGRESS:
        return limit_message("no_progress", options, t_end, last_event=events[-1].detail if events else None)
    if code == k.ST_MAX_EVAL:
        return limit_message("evaluation_limit", options, t_end)
    if code == k.ST_WALL_TIME:
        return limit_message("wall_time_limit", options, t_end)
    if code == k.ST_STEP_TOO_SMALL:
        return f"compiled/{options.scheme} failed at t = {t_end:.6g} s: required step size is less than spacing between numbers"
    return f"compiled/{options.scheme} failed at t = {t_end:.6g} s: non-finite state derivative"


def _events(pack, road, lg_t, lg_kind, lg_i, lg_j, lg_x, lg_e, k) -> list[RunoutEvent]:
    out = []
    for t, kind, i, j, x, e in zip(lg_t.tolist(), lg_kind.tolist(), lg_i.tolist(), lg_j.tolist(), lg_x.tolist(),
                                   lg_e.tolist()):
        if kind == k.LOG_ZONE_ENTER or kind == k.LOG_ZONE_EXIT:
            name = "zone_enter" if kind == k.LOG_ZONE_ENTER else "zone_exit"
            zone = road.zones[j]
            out.append(RunoutEvent(t, name, f"wheel {pack.specs[i].key} {name[5:]}s zone {j} {zone.name!r}"))
        elif kind == k.LOG_SCHEDULE:
            out.append(RunoutEvent(t, "schedule", "wheel settings change"))
        elif kind == k.LOG_STOP_CLOSED:
            detail = f"articulation stop of hitch {i} closes at {x:+.4f} rad (impact dissipates {e:.1f} J)"
            out.append(RunoutEvent(t, "stop_closed", detail, energy=e))
        elif kind == k.LOG_STOP_IMPACT:
            detail = f"articulation stop of hitch {i} struck at {x:+.4f} rad and left (impact dissipates {e:.1f} J)"
            out.append(RunoutEvent(t, "stop_impact", detail, energy=e))
        elif kind == k.LOG_STOP_OPEN:
            out.append(RunoutEvent(t, "stop_open", f"articulation stop of hitch {i} opens"))
    return out

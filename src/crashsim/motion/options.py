"""Numerical options of the run-out simulation, with their defaults and what they cost."""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..errors import ScenarioError
from .tyres import LATERAL_MODELS

__all__ = ["RunoutOptions", "METHODS", "ENGINES", "SCHEMES", "STOP_HYSTERESIS", "MAX_STILL_SEGMENTS"]

#: An articulation stop that is left (struck and left, or released) engages again only past its
#: limit plus a threshold raised this much [rad] above where it was left: an articulation that
#: rests on the limit when the stop opens cannot fire the stop event again at the same instant
#: (the cause of an endless loop of stop impacts, fixed in both engines).  1e-7 rad is 0.5 um
#: at a 5 m lever.
STOP_HYSTERESIS = 1e-7
#: Consecutive integration segments that end where they start before a run stops with status
#: ``"event_limit"`` (event chattering), in both engines.
MAX_STILL_SEGMENTS = 50

#: solve_ivp methods accepted by :class:`RunoutOptions` (``engine="scipy"``).
METHODS = ("RK45", "DOP853", "LSODA", "Radau", "BDF")
#: Run-out engines: SciPy's solve_ivp, or the numba-compiled integrator of :mod:`crashsim.motion.compiled_solution`.
ENGINES = ("scipy", "compiled")
#: Integration schemes of the compiled engine (``engine="compiled"``).
SCHEMES = ("dopri5", "bs3")


def _in_range(name, value, lo, hi, *, lo_open=True):
    """``value`` as float if it lies in (lo, hi] (or [lo, hi]); NaN never does."""
    v = float(value)
    if not ((v > lo if lo_open else v >= lo) and v <= hi):
        raise ScenarioError(f"must lie in {'(' if lo_open else '['}{lo}, {hi}], got {value!r}", field=f"options.{name}")
    return v


@dataclass(frozen=True)
class RunoutOptions:
    """Solver and model options of :func:`~crashsim.motion.simulate_runout`.

    The defaults follow the research note (sec. 3.5, 6).  What they cost and give, measured
    on the paper's Table 6 scene (``benchmarks/runout_solvers.py``,
    ``plots/runout_benchmark.md``): about 80 ms CPU for the articulated truck's 4.9 s
    run-out (787 right-hand-side evaluations) and 53 ms for the spinning car's 1.5 s
    run-out; rest positions within 0.05 mm (truck) and 1.8 mm (car) of a converged
    reference (rtol 1e-10, eps = v_stop = 1e-3), of which only 0.0004 / 0.012 mm is
    integration error -- the rest is the effect of ``eps`` and ``v_stop``.

    Parameters
    ----------
    method : {"LSODA", "RK45", "DOP853", "Radau", "BDF"}
        solve_ivp method of the SciPy engine (not used by ``engine="compiled"``, which
        integrates with ``scheme``).  LSODA (default) switches between Adams and BDF and stays cheap
        when free-rolling tyres make the equations stiff at low speed (stiffness
        ~ sum C_alpha/(m |u|)); RK45/DOP853 are fine for locked or braked run-outs (on the
        benchmark RK45 cost about the same as LSODA, DOP853 1.0-1.3x) but need ~10x more
        right-hand-side evaluations for long free-rolling run-outs (note sec. 3.5); Radau/BDF
        are robust but cost 1.5-2x at rtol 1e-6 in pure Python.
    rtol, atol : float
        Relative and absolute local error tolerances (atol in the state's SI units: m, rad,
        m/s, rad/s), the same for both engines.  Default 1e-8 / 1e-10.  Measured on 190
        random valid inputs against a converged reference (``benchmarks/engine_fuzz.py``,
        ``plots/engine_fuzz.md``): at 1e-8 the largest rest-position error was 1.3 mm
        (compiled) / 0.2 mm (SciPy) for single vehicles, 0.4 / 0.2 mm for scenes of 2-3
        vehicles with secondary impacts and 7 / 0.0 mm for doubles on dollies.  At the former
        default 1e-6 the compiled engine's errors reached 3.6 cm; 1e-8 costs 1.2-1.3x the CPU
        time of 1e-6 (compiled) and 1.4-1.5x (SciPy).  SciPy's own default rtol 1e-3 gave
        1-2 cm errors on the simplest run-outs.
    eps : float
        Low-speed regularisation speed [m/s] of the friction laws, default 0.01.  Error in
        stopping distance O(eps^2/(mu g)) (~0.1 mm at 20 m/s); larger eps biases results,
        smaller eps adds stiffness mu g/eps only in the last moments.
    v_stop : float
        Rest threshold [m/s], default 0.03.  The run stops when, for every body,
        ``max(|v_cg|, |yaw rate| * L_ref) <= v_stop``.  Residual travel after the stop is at
        most ``v_stop^2/(2 a_min)``: 0.06 mm with locked wheels (a = mu g), ~5 mm for a
        free-rolling vehicle (a = f_r g ~ 0.1 m/s^2).  Must exceed ``eps`` / 10.
    max_step : float
        Largest solver step [s], default 0.1.  A zone crossing is found only if a step ends
        inside the zone, so a zone narrower than ``speed * max_step`` (1.5 m at 15 m/s with
        the default) can be stepped over; the result then carries a ``"zone_missed"`` event
        (samples are checked against the zones) and a warning is logged.  Lower it for thin
        zones (a 0.3 m painted line at 15 m/s needs 0.02 s).  Costs little: a 5 s run-out
        needs >= 50 steps anyway.
    first_step : float or None
        Initial step [s]; None lets the solver choose.
    t_max : float
        Time limit [s], default 120 (a free-rolling truck at 13 m/s needs ~2 min).  Reaching
        it ends the run with status ``"time_limit"``, never ``"rest"``.
    sample_dt : float
        Spacing [s] of the sampled history and wheel tracks in the result, default 0.01
        (post-processing only; the dense solution ``sol`` is exact to the solver).
    lateral_model : {"fiala", "linear"}
        Pure-slip lateral tyre curve, see :func:`~crashsim.motion.tyres.lateral_force`.
    load_transfer : bool
        Quasi-static longitudinal and lateral load transfer (default off; needs every body's
        ``cg_height``), see :mod:`crashsim.motion.loads`.
    rollover : bool
        Record wheel lift and rollover events (default off; with ``load_transfer`` only, off
        without it, so the lower levels of a scene run without the check; a scenario file asking
        for it at another level is rejected at load): each
        body's load transfer ratio and lateral acceleration against its rollover threshold, see
        :mod:`crashsim.motion.rollover`.
    load_transfer_tau : float
        Time constant [s] of the first-order lag on the accelerations used for load transfer
        (suspension pitch/roll response, 0.1-0.3 s), default 0.2.
    baumgarte_omega, baumgarte_zeta : float
        Hitch-constraint stabilisation ``g'' + 2 zeta omega g' + omega^2 g = 0``; default
        10 /s and 1 (critical damping), note sec. 1.4.
    max_segments : int
        Safety limit on restarts of the integration (events and scheduled changes; a restart
        that ends where it started counts too).  Reaching it ends the run with status
        ``"event_limit"``, as do 50 consecutive restarts without progress in time.
    max_evaluations : int
        Right-hand-side evaluations allowed per run-out, default 1 000 000 (a 120 s
        free-rolling run-out needs well under 100 000).  Bounds the work and, in the compiled
        engine, the memory of the stored steps.  Reaching it ends the run with status
        ``"evaluation_limit"``.
    max_wall_time : float
        Wall-clock seconds allowed per run-out, default 120 (a run-out takes milliseconds
        compiled, well under 10 s with SciPy).  Reaching it ends the run with status
        ``"wall_time_limit"``; fits and Monte Carlo set it per sample.
    max_impacts : int
        Secondary impacts allowed in one run-out, default 100 (real scenes have a handful;
        sustained contact is a force, not a chain of impacts).  Exceeding it ends the run with
        status ``"event_limit"``.
    engine : {"scipy", "compiled"}
        ``"scipy"`` (default): ``scipy.integrate.solve_ivp`` with ``method``
        (:mod:`crashsim.motion.simulate`).  ``"compiled"``: the same model, events and
        result integrated by numba-compiled code (:mod:`crashsim.motion.compiled_solution`), about two
        orders of magnitude faster per run-out (``plots/fast_path.md``), for fits and Monte
        Carlo; the first call in a fresh environment compiles it (tens of seconds, then
        cached on disk).  Every other option means the same for both engines.
    scheme : {"dopri5", "bs3"}
        Integration scheme of the compiled engine (ignored by the SciPy engine):
        ``"dopri5"`` (default), Dormand-Prince 5(4) with 4th-order dense output (the
        tableau of solve_ivp's RK45); ``"bs3"``, Bogacki-Shampine 3(2) (RK23's tableau),
        cheaper at loose tolerances.  Both control the local error with ``rtol``/``atol``.
    """

    method: str = "LSODA"
    rtol: float = 1e-8
    atol: float = 1e-10
    eps: float = 0.01
    v_stop: float = 0.03
    max_step: float = 0.1
    first_step: float | None = None
    t_max: float = 120.0
    sample_dt: float = 0.01
    lateral_model: str = "fiala"
    load_transfer: bool = False
    rollover: bool = False
    load_transfer_tau: float = 0.2
    baumgarte_omega: float = 10.0
    baumgarte_zeta: float = 1.0
    max_segments: int = 10_000
    max_evaluations: int = 1_000_000
    max_wall_time: float = 120.0
    max_impacts: int = 100
    engine: str = "scipy"
    scheme: str = "dopri5"

    def __post_init__(self):
        if self.engine not in ENGINES:
            raise ScenarioError(f"must be one of {ENGINES}, got {self.engine!r}", field="options.engine")
        if self.scheme not in SCHEMES:
            raise ScenarioError(f"must be one of {SCHEMES}, got {self.scheme!r}", field="options.scheme")
        if self.method not in METHODS:
            raise ScenarioError(f"must be one of {METHODS}, got {self.method!r}", field="options.method")
        if self.lateral_model not in LATERAL_MODELS:
            raise ScenarioError(
                f"must be one of {LATERAL_MODELS}, got {self.lateral_model!r}", field="options.lateral_model"
            )
        _in_range("rtol", self.rtol, 1e-14, 0.1)
        _in_range("atol", self.atol, 0.0, 1.0)
        _in_range("eps", self.eps, 0.0, 1.0)
        _in_range("v_stop", self.v_stop, 0.0, 5.0)
        if self.v_stop < self.eps / 10:
            raise ScenarioError(
                f"must be >= eps/10 = {self.eps / 10} m/s (below, the regularised friction cannot bring the "
                f"vehicle to v_stop in reasonable time), got {self.v_stop!r}",
                field="options.v_stop",
            )
        _in_range("max_step", self.max_step, 0.0, math.inf)
        if self.first_step is not None:
            _in_range("first_step", self.first_step, 0.0, 1.0)
        _in_range("t_max", self.t_max, 0.0, 1e5)
        _in_range("sample_dt", self.sample_dt, 0.0, 10.0)
        _in_range("load_transfer_tau", self.load_transfer_tau, 0.0, 10.0)
        _in_range("baumgarte_omega", self.baumgarte_omega, 0.0, 1e4, lo_open=False)
        _in_range("baumgarte_zeta", self.baumgarte_zeta, 0.0, 100.0, lo_open=False)
        if int(self.max_segments) < 1:
            raise ScenarioError(f"must be >= 1, got {self.max_segments!r}", field="options.max_segments")
        if int(self.max_evaluations) < 100:
            raise ScenarioError(f"must be >= 100, got {self.max_evaluations!r}", field="options.max_evaluations")
        _in_range("max_wall_time", self.max_wall_time, 0.0, 1e6)
        if int(self.max_impacts) < 0:
            raise ScenarioError(f"must be >= 0, got {self.max_impacts!r}", field="options.max_impacts")
        object.__setattr__(self, "load_transfer", bool(self.load_transfer))
        # the check reads the load transfer: without it (the lower levels) it is off
        object.__setattr__(self, "rollover", bool(self.rollover) and self.load_transfer)

    def to_dict(self) -> dict:
        """Options as a JSON-ready dict (SI units); ``rollover`` only when on (results without the
        check are the same as before it existed)."""
        d = asdict(self)
        if not d["rollover"]:
            del d["rollover"]
        return d

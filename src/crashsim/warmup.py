"""Warm-up: compile (or load from numba's disk cache) every kernel before a user's first run.

The warm-up runs the whole pipeline on a tiny scene (scenario -> scene -> impact -> run-out on
both engines), so it sits at the top layer beside the command line; the cache directory and its
"ready" marker are the numba set-up of :mod:`crashsim._jit` at the bottom.

compile_kernels(progress)
    Every kernel through the scenario loader and :func:`crashsim.scene.run_scene`, then mark
    the cache ready (what ``crashsim`` does once, with a progress line, before a first run).
compile_runout(), compile_report()
    The run-out kernels alone through :func:`crashsim.motion.run_runout`, timed (the
    compile-time benchmark).

``python -m crashsim.warmup`` is the detached compile of a first run
(:func:`crashsim.first_run.background_main`; its output goes to ``compile.log``).
"""

from __future__ import annotations

import threading
import time
from dataclasses import replace
from pathlib import Path
from typing import Callable

from ._jit import marker
from .first_run import background_main
from .motion import RunoutOptions, Road, run_runout
from .motion.scene_model import kernels
from .scenario import scenario_from_dict
from .scene import run_scene
from .vehicles import Axle, Body, BodyState, Hitch, Vehicle

__all__ = ["compile_kernels", "COMPILE_STEPS", "compile_runout", "compile_report"]

#: What :func:`compile_kernels` compiles, in order (labels for a progress display).
COMPILE_STEPS = ("kernel module", "scene model", "SciPy engine (right-hand side, events, results)",
                 "compiled engine (integrator)")


def _tiny_scene():
    """Two small vehicles that meet again (contact, stops, zones): every kernel is used."""
    axles = [{"x": "1.2 m", "track": "1.5 m"}, {"x": "-1.2 m", "track": "1.5 m"}]
    body = {"mass": "1200 kg", "yaw_inertia": "1800 kg m^2", "length": "4 m", "width": "1.8 m", "axles": axles}
    data = {
        "scenario": {"title": "compile"},
        "vehicles": {
            "A": {"speed": "10 m/s", "heading": "0 deg", "position": ["0 m", "0 m"],
                  "bodies": [{**body, "name": "a", "rear_hitch": ["-2.2 m", "0 m"]},
                             {**body, "name": "a2", "front_hitch": ["2.2 m", "0 m"], "articulation_limit": "60 deg"}],
                  "tyres": {"state": "braked", "brake": 0.3, "cornering_coefficient": 8.6, "rolling_resistance": 0.012}},
            "B": {"speed": "0 m/s", "heading": "90 deg", "position": ["2.9 m", "0 m"], "bodies": [{**body, "name": "b"}],
                  "tyres": {"state": "locked"}},
        },
        "impact": {"body1": "a", "body2": "b", "point": ["2 m", "0 m"], "normal": "180 deg",
                   "restitution": 0.1, "tangential": "no_slide"},
        "runout": {"road_friction": 0.7, "t_max": "5 s",
                   "zones": [{"friction": 0.4, "polygon": [["5 m", "-5 m"], ["9 m", "-5 m"], ["9 m", "5 m"]]}]},
    }
    return scenario_from_dict(data)


def compile_kernels(progress: Callable[[int, str], None] | None = None) -> Path:
    """Compile (or load from the cache) every kernel, then mark the cache ready.

    ``progress(i, label)`` is called before each of :data:`COMPILE_STEPS`. Returns the
    cache directory.
    """

    def step(i):
        if progress is not None:
            progress(i, COMPILE_STEPS[i])

    # the marker names the sources compiled now, read before the compile: a reinstall under a long
    # compile removes or replaces them, and this compile is then of the old ones
    done = marker()
    step(0)
    kernels()  # defining the kernels

    step(1)
    scenario = _tiny_scene()

    step(2)
    spec = scenario.runout
    run_scene(replace(scenario, runout=replace(spec, options=replace(spec.options, engine="scipy"))))
    step(3)
    run_scene(replace(scenario, runout=replace(spec, options=replace(spec.options, engine="compiled"))))
    try:
        done.parent.mkdir(parents=True, exist_ok=True)
        done.touch()  # others stay: installations elsewhere may share this cache (each its own marker)
    except OSError:  # pragma: no cover - read-only cache
        pass
    return done.parent


# ----------------------------------------------------------------------------- run-out kernels alone, timed
_COMPILE = {"seconds": None, "from_cache": None}
_COMPILE_LOCK = threading.Lock()


def compile_runout() -> float:
    """Compile (or load from numba's on-disk cache) the run-out kernels by running a tiny scene on both engines.

    Returns
    -------
    float
        Wall time [s] of the first call in this process (0.0 if already done).  The first call
        in a fresh environment compiles (a minute or two); later processes load the cache.
    """
    with _COMPILE_LOCK:
        if _COMPILE["seconds"] is not None:
            return 0.0
        t0 = time.perf_counter()
        k = kernels()
        tractor = Body("a", 1000.0, 1000.0, 3.0, 1.8, axles=(Axle(1.0, 1.5), Axle(-1.0, 1.5)))
        trailer = Body("b", 500.0, 500.0, 2.0, 1.6, axles=(Axle(-1.0, 1.5),))
        other = Body("c", 800.0, 900.0, 3.0, 1.6, axles=(Axle(1.0, 1.4), Axle(-1.0, 1.4)))
        states = {
            "a": BodyState((0.0, 0.0), 0.0, (2.0, 0.0), 0.0),
            "b": BodyState((-3.5, 0.0), 0.0, (2.0, 0.0), 0.0),
            "c": BodyState((3.5, 0.0), 0.0, (0.0, 0.0), 0.0),
        }
        scene = [Vehicle("warm-up", (tractor, trailer), (Hitch((-2.0, 0.0), (1.5, 0.0), articulation_limit=1.0),)),
                 Vehicle("struck", (other,))]
        for engine in ("compiled", "scipy"):
            run_runout(scene, states, None, Road(0.7), RunoutOptions(t_max=2.0), engine=engine)
        _COMPILE["seconds"] = time.perf_counter() - t0
        _COMPILE["from_cache"] = bool(k.run.stats.cache_hits) and not k.run.stats.cache_misses
        return _COMPILE["seconds"]


def compile_report() -> dict:
    """``{"seconds": first-call time [s] or None, "from_cache": bool or None}`` of :func:`compile_runout` in this process."""
    return dict(_COMPILE)


if __name__ == "__main__":  # pragma: no cover - the detached process of a first run (tests/unit/test_first_run.py)
    raise SystemExit(background_main(compile_kernels))

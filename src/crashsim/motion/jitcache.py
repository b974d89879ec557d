"""Where the compiled kernels are cached, and their one-time compile.

The kernels of :mod:`crashsim.motion.kernels` (the run-out) and :mod:`crashsim.impact.kernel`
(the impact solver) are compiled by numba on first use (about a minute or two on one core) and
cached on disk. The cache lives in a user-writable directory,
so an installation into a read-only or non-editable location keeps it too:

1. ``$CRASHSIM_CACHE_DIR`` if set;
2. else ``$NUMBA_CACHE_DIR`` if set (numba's own setting, honoured as is);
3. else the user cache directory: ``$XDG_CACHE_HOME/crashsim`` or ``~/.cache/crashsim``
   (``~/Library/Caches/crashsim`` on macOS, ``%LOCALAPPDATA%\\crashsim`` on Windows).

Below it the numba version and the source path keep installations apart. :func:`ready`
tells whether the kernels of these sources have been compiled here (a marker written by
:func:`compile_kernels`), so an application can say "compiling once" before it happens.
"""

from __future__ import annotations

import hashlib
import os
import sys
from pathlib import Path
from typing import Callable

__all__ = ["cache_dir", "configure", "ready", "compile_kernels", "kernel_sources", "COMPILE_STEPS"]


def cache_dir() -> Path:
    """The directory of crashsim's compiled-kernel cache (see the module notes)."""
    if os.environ.get("CRASHSIM_CACHE_DIR"):
        return Path(os.environ["CRASHSIM_CACHE_DIR"]).expanduser()
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]).expanduser()
    if sys.platform == "win32":  # pragma: no cover - platform
        base = Path(os.environ.get("LOCALAPPDATA", Path.home() / "AppData" / "Local"))
    elif sys.platform == "darwin":  # pragma: no cover - platform
        base = Path.home() / "Library" / "Caches"
    else:
        base = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return base / "crashsim"


def _numba_dir() -> Path:
    import numba

    return cache_dir() / f"numba-{numba.__version__}"


def configure() -> Path:
    """Point numba's cache at :func:`cache_dir` (before the kernels are defined); returns it.

    numba's own ``NUMBA_CACHE_DIR`` wins if set. If the directory cannot be created, numba's
    default (next to the sources, else its user-wide directory) stays in force.
    """
    from numba.core import config

    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(config.CACHE_DIR)
    path = _numba_dir()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:  # pragma: no cover - read-only home
        return path
    config.CACHE_DIR = str(path)
    return path


def kernel_sources(impact: bool = True) -> list[Path]:
    """The source files the compiled kernels compile in, in a fixed order: every module of the
    run-out kernel package (``motion/kernels/*.py``), the tyre law and the options they
    compile in, and (``impact``) the impact solver's kernel."""
    here = Path(__file__).parent
    paths = sorted((here / "kernels").glob("*.py")) + [here / "tyres.py", here / "options.py"]
    if impact:
        paths.append(here.parent / "impact" / "kernel.py")
    return paths


def _digest() -> str:
    """Hash of the kernel sources and the numba version (the cache's validity)."""
    import numba

    h = hashlib.sha256(numba.__version__.encode())
    for path in kernel_sources():
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _marker() -> Path:
    return _numba_dir() / f"ready-{_digest()}"


def ready() -> bool:
    """True if the kernels of these sources were compiled and cached here already."""
    try:
        return _marker().exists()
    except OSError:  # pragma: no cover
        return False


#: What :func:`compile_kernels` compiles, in order (labels for a progress display).
COMPILE_STEPS = ("kernel module", "scene model", "SciPy engine (right-hand side, events, results)",
                 "compiled engine (integrator)")


def _tiny_scene():
    """Two small vehicles that meet again (contact, stops, zones): every kernel is used."""
    from ..scenario import scenario_from_dict

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
    from dataclasses import replace

    def step(i):
        if progress is not None:
            progress(i, COMPILE_STEPS[i])

    step(0)
    from . import kernels  # noqa: F401  (defining the kernels)

    step(1)
    scenario = _tiny_scene()
    from ..reconstruct import run_scene

    step(2)
    spec = scenario.runout
    run_scene(replace(scenario, runout=replace(spec, options=replace(spec.options, engine="scipy"))))
    step(3)
    run_scene(replace(scenario, runout=replace(spec, options=replace(spec.options, engine="compiled"))))
    marker = _marker()
    try:
        marker.parent.mkdir(parents=True, exist_ok=True)
        for old in marker.parent.glob("ready-*"):
            old.unlink()
        marker.touch()
    except OSError:  # pragma: no cover - read-only cache
        pass
    return marker.parent

"""Where the compiled kernels are cached (the numba set-up; no pipeline here).

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
:func:`crashsim.warmup.compile_kernels`), so an application can say "compiling once" before it
happens. The warm-up itself runs the whole pipeline and so lives at the top, in :mod:`crashsim.warmup`.
"""

from __future__ import annotations

import hashlib
import importlib.metadata
import os
import sys
from pathlib import Path

__all__ = ["cache_dir", "numba_version", "numba_dir", "configure", "kernel_sources", "digest", "marker", "ready"]


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


def numba_version() -> str:
    """The installed numba's version, read from its package metadata: whether the kernels are compiled
    (:func:`ready`) is answered without importing numba (about 0.7 s of CPU), so a command that
    refuses its input, or finds the kernels ready, does not pay for it."""
    return importlib.metadata.version("numba")


def numba_dir() -> Path:
    """The numba cache below :func:`cache_dir`, one per numba version."""
    return cache_dir() / f"numba-{numba_version()}"


def configure() -> Path:
    """Point numba's cache at :func:`cache_dir` (before the kernels are defined); returns it.

    numba's own ``NUMBA_CACHE_DIR`` wins if set. If the directory cannot be created, numba's
    default (next to the sources, else its user-wide directory) stays in force.
    """
    from numba.core import config

    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(config.CACHE_DIR)
    path = numba_dir()
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:  # pragma: no cover - read-only home
        return path
    config.CACHE_DIR = str(path)
    return path


def kernel_sources(impact: bool = True) -> list[Path]:
    """The source files the compiled kernels are built from, in a fixed order: every module of the
    run-out kernel package (``motion/kernels/*.py``), the tyre law, the options and the state layout
    they compile in (``motion/tyres.py``, ``motion/options.py``, ``motion/layout.py``), and
    (``impact``) the impact solver's kernel (``impact/kernel.py``)."""
    here = Path(__file__).parent
    motion = here / "motion"
    paths = sorted((motion / "kernels").glob("*.py")) + [motion / "tyres.py", motion / "options.py",
                                                         motion / "layout.py"]
    if impact:
        paths.append(here / "impact" / "kernel.py")
    return paths


def digest() -> str:
    """Hash of the kernel sources and the numba version (the cache's validity): their contents, and
    where they are and when they were written, as numba's own cache index stamps a kernel by its
    file (a reinstall, editable or not, puts new files there: their kernels compile anew, and the
    marker says so instead of a ready cache that every process would silently recompile)."""
    h = hashlib.sha256(numba_version().encode())
    for path in kernel_sources():
        st = path.stat()
        h.update(f"{path.resolve()}\0{st.st_mtime_ns}\0{st.st_size}\0".encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def marker() -> Path:
    """The file whose presence says the kernels of these sources were compiled here (:func:`ready`)."""
    return numba_dir() / f"ready-{digest()}"


def ready() -> bool:
    """True if the kernels of these sources were compiled and cached here already."""
    try:
        return marker().exists()
    except OSError:  # pragma: no cover
        return False

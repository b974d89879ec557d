"""What machine a benchmark ran on: shared by the scripts of this folder (their reports name it)."""

from __future__ import annotations

import platform
import resource
import subprocess
from pathlib import Path


def cpu_name(default: str = "?") -> str:
    """The processor's model name (``/proc/cpuinfo`` where there is one, else ``platform.processor()``)."""
    cpu = platform.processor() or default
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return cpu


def run_cpu(cmd: list[str], **kwargs) -> tuple[float, subprocess.CompletedProcess]:
    """Run ``cmd`` (``subprocess.run`` keyword arguments) and return the CPU seconds (user + system) of
    it and of everything it started (``RUSAGE_CHILDREN`` around it), and its result."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(cmd, **kwargs)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), out

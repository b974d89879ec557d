"""What machine a benchmark ran on: shared by the scripts of this folder (their reports name it)."""

from __future__ import annotations

import platform
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

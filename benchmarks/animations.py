"""Regenerate the committed animation example (plots/animation_trailer_swings_into_car.gif)
with the project's own command, ``crashsim animate``.

Run from the repository root: ``python benchmarks/animations.py``. Real time (20 frames/s at
dt = 0.05 s), 100 dpi: about 2 MB.
"""

from __future__ import annotations

import sys
from pathlib import Path

from crashsim.cli import main as crashsim

ROOT = Path(__file__).resolve().parents[1]

#: Scene files (stems in scenarios/scenes/) animated, with the command's options.
ANIMATIONS = {"trailer_swings_into_car": ["--dt", "0.05 s", "--speed", "1", "--dpi", "100"]}


def main() -> int:
    for stem, options in ANIMATIONS.items():
        scene = ROOT / "scenarios" / "scenes" / f"{stem}.toml"
        out = ROOT / "plots" / f"animation_{stem}.gif"
        code = crashsim(["animate", str(scene), "-o", str(out), *options])
        if code:
            return code
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Regenerate the committed animation examples (plots/animation_<scene>.gif) with the project's
own command, ``crashsim animate``: the trailer that swings into the car (real time, 20 frames/s
at dt = 0.05 s, 100 dpi: about 2 MB) and the truck that brakes into a car (from the start of
braking, 10 frames/s at dt = 0.1 s).

Run from the repository root: ``python benchmarks/animations.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from crashsim.cli import main as crashsim

ROOT = Path(__file__).resolve().parents[1]

#: Scene files (stems in scenarios/scenes/) animated, with the command's options.
ANIMATIONS = {"trailer_swings_into_car": ["--dt", "0.05 s", "--speed", "1", "--dpi", "100"],
              "truck_brakes_into_car": ["--dt", "0.1 s", "--speed", "1", "--dpi", "80"]}


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

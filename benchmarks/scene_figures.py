"""Regenerate the committed figures of every shipped scene (plots/scene_<name>.png and
plots/scene_<name>_histories.png) with the project's own command, ``crashsim plot``.

Run from the repository root: ``python benchmarks/scene_figures.py``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from crashsim.cli import main as crashsim

ROOT = Path(__file__).resolve().parents[1]


def main() -> int:
    for scene in sorted((ROOT / "scenarios" / "scenes").glob("*.toml")):
        out = ROOT / "plots" / f"scene_{scene.stem}.png"
        hist = ROOT / "plots" / f"scene_{scene.stem}_histories.png"
        code = crashsim(["plot", str(scene), "-o", str(out), "--histories", str(hist)])
        if code:
            return code
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Regenerate the committed figures of every shipped scene (plots/scene_<name>.png and
plots/scene_<name>_histories.png; for a scene with an approach also its time-distance chart
plots/scene_<name>_time_distance.png and a close view without the approach,
plots/scene_<name>_impact.png) with the project's own command, ``crashsim plot``.

Run from the repository root: ``python benchmarks/scene_figures.py`` (every scene of
scenarios/scenes/, among them verge_run_off: friction zone and road layout, and of
scenarios/survey/, drawn over its orthophoto), or name some
scenes: ``python benchmarks/scene_figures.py verge_run_off``.
"""

from __future__ import annotations

import sys
from pathlib import Path

from crashsim.cli import main as crashsim

ROOT = Path(__file__).resolve().parents[1]


def main(names: list[str] | None = None) -> int:
    """Draw the scenes named (file stems in scenarios/scenes/; all of them if none); 0 on success,
    2 for an unknown name, else the first failing ``crashsim plot`` exit code."""
    scenes = sorted((ROOT / "scenarios" / "scenes").glob("*.toml")) + sorted((ROOT / "scenarios" / "survey").glob("*.toml"))
    if names:
        unknown = sorted(set(names) - {s.stem for s in scenes})
        if unknown:
            print(f"unknown scene(s) {', '.join(unknown)}; shipped: {', '.join(s.stem for s in scenes)}",
                  file=sys.stderr)
            return 2
        scenes = [s for s in scenes if s.stem in names]
    for scene in scenes:
        out = ROOT / "plots" / f"scene_{scene.stem}.png"
        hist = ROOT / "plots" / f"scene_{scene.stem}_histories.png"
        args = ["plot", str(scene), "-o", str(out), "--histories", str(hist)]
        if "approach]" in scene.read_text():
            args += ["--time-distance", str(ROOT / "plots" / f"scene_{scene.stem}_time_distance.png")]
            code = crashsim(["plot", str(scene), "-o", str(ROOT / "plots" / f"scene_{scene.stem}_impact.png"),
                             "--no-approach"])
            if code:
                return code
        code = crashsim(args)
        if code:
            return code
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

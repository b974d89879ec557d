"""Regenerate the committed animation examples (plots/animation_<scene>.gif) with the project's
own command, ``crashsim animate``, and measure how long each takes: the trailer that swings into
the car (real time, 20 frames/s at dt = 0.05 s, 100 dpi), the truck that brakes into a car (from
the start of braking, 10 frames/s at dt = 0.1 s) and the three-vehicle intersection (half speed:
its 5.6 s run-out plays in about 11 s, 20 frames/s, 100 dpi).

Run from the repository root: ``python benchmarks/animations.py`` (writes plots/animations.md
with the wall-clock time of each command: loading, the run, rendering and writing the GIF), or
``python benchmarks/animations.py --quick`` for the three-vehicle scene alone, written to a
temporary folder (nothing in plots/ changes). Kernels are compiled first (not timed).
"""

from __future__ import annotations

import os
import sys
import tempfile
import time
from pathlib import Path

from _machine import cpu_name

from crashsim.cli import main as crashsim
from crashsim.warmup import compile_kernels

ROOT = Path(__file__).resolve().parents[1]

#: Scene files (stems in scenarios/scenes/) animated, with the command's options.
ANIMATIONS = {"trailer_swings_into_car": ["--dt", "0.05 s", "--speed", "1", "--dpi", "100"],
              "truck_brakes_into_car": ["--dt", "0.1 s", "--speed", "1", "--dpi", "80"],
              "third_vehicle_waiting_car": ["--dt", "0.05 s", "--speed", "0.5", "--dpi", "100"]}

#: The scene of the quick run: three vehicles, an animation of about 10 s.
QUICK = "third_vehicle_waiting_car"


def _gif_seconds(path: Path) -> tuple[int, float]:
    """(frames, playback seconds) of a GIF."""
    from PIL import Image

    with Image.open(path) as im:
        total = 0
        for k in range(im.n_frames):
            im.seek(k)
            total += im.info.get("duration", 0)
        return im.n_frames, total / 1000.0


def main(argv: list[str]) -> int:
    quick = "--quick" in argv
    compile_kernels()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp) if quick else ROOT / "plots"
        for stem, options in ANIMATIONS.items():
            if quick and stem != QUICK:
                continue
            scene = ROOT / "scenarios" / "scenes" / f"{stem}.toml"
            out = folder / f"animation_{stem}.gif"
            load = os.getloadavg()[0]
            t0, c0 = time.perf_counter(), time.process_time()
            code = crashsim(["animate", str(scene), "-o", str(out), "--quiet", *options])
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            if code:
                return code
            frames, seconds = _gif_seconds(out)
            rows.append((stem, " ".join(options), frames, seconds, wall, cpu, load))
            print(f"{stem}: {frames} frames, {seconds:.1f} s of playback, {wall:.1f} s to make ({cpu:.1f} s CPU, "
                  f"load average {load:.1f})", flush=True)
    if not quick:
        lines = ["# Animation rendering time (`python benchmarks/animations.py`)", "",
                 "Wall-clock and CPU time of `crashsim animate` (load, run, render, write; default view: follow), "
                 f"kernels compiled beforehand; the load average (1 min) at the start of each, on {os.cpu_count()} "
                 f"cores ({cpu_name()}).", "",
                 "| scene | options | frames | playback [s] | time to make [s] | CPU [s] | load average |",
                 "|---|---|---|---|---|---|---|"]
        lines += [f"| {s} | `{o}` | {f} | {p:.1f} | {w:.1f} | {c:.1f} | {a:.1f} |" for s, o, f, p, w, c, a in rows]
        (ROOT / "plots" / "animations.md").write_text("\n".join(lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

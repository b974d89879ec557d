"""The shipped double on a C-dolly against the same combination on an A-dolly.

Runs ``scenarios/scenes/doubles_c_dolly.toml`` as written (C-dolly: yaw-locked to the lead trailer,
self-steering axle) and with the dolly replaced by the ``dolly-a`` preset (one drawbar, free in
yaw, its axle not steering), and writes

* ``plots/dollies_compare.png``: both scenes to scale (paths, tyre tracks, rest outlines) and the
  articulation angles at the three joints over time;
* ``plots/dollies.md``: rest positions and headings of every body, the largest articulations,
  time to rest, and the command that regenerated it.

Usage: ``python benchmarks/dollies.py`` (a few seconds once the kernels are compiled).
"""

from __future__ import annotations

import copy
import math
import sys
import time
from pathlib import Path

import numpy as np

import crashsim
from crashsim.schema import load_toml

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenarios" / "scenes" / "doubles_c_dolly.toml"
OUT = ROOT / "plots"


def a_dolly(data: dict) -> dict:
    """The same file with an A-dolly: preset dolly-a, not yaw-locked, its wheels not self-steering (and
    without the evidence, which was made up for the C-dolly scene)."""
    out = copy.deepcopy(data)
    truck = out["vehicles"]["truck"]
    for b in truck["bodies"]:
        if b["name"] == "dolly":
            b["preset"] = "dolly-a"
    truck["wheels"] = [w for w in truck.get("wheels", []) if w.get("select") != "dolly"]
    out.pop("evidence", None)  # the hypothetical evidence was made up for the C-dolly scene
    return out


def articulation(h: dict, front: str, rear: str) -> np.ndarray:
    return np.degrees(np.remainder(h[f"{front}.heading"] - h[f"{rear}.heading"] + math.pi, 2 * math.pi) - math.pi)


def main() -> int:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    data = load_toml(str(SCENE))
    runs, times = {}, {}
    for label, d in (("C-dolly", data), ("A-dolly", a_dolly(data))):
        crashsim.run(d)  # the kernels loaded, the structures cached: the time below is a run's own
        t0 = time.perf_counter()
        runs[label] = crashsim.run(d)
        times[label] = time.perf_counter() - t0
    joints = (("tractor", "lead"), ("lead", "dolly"), ("dolly", "second"))
    fig = plt.figure(figsize=(12, 9.5))
    grid = fig.add_gridspec(3, 2, height_ratios=[1.0, 1.0, 0.9])
    lines = ["# A double on a C-dolly and on an A-dolly", "",
             f"`python benchmarks/dollies.py`: `{SCENE.relative_to(ROOT)}` as written (C-dolly, yaw-locked, axle "
             "self-steering within 20 deg) and with the dolly replaced by the `dolly-a` preset (free in yaw, axle "
             "not steering); everything else the same. SI units.", "",
             "| dolly | body | rest x [m] | rest y [m] | rest heading [deg] | time to rest [s] |",
             "|---|---|---|---|---|---|"]
    for row, (label, scene) in enumerate(runs.items()):
        ax = fig.add_subplot(grid[row, :])
        scene.plot(ax=ax, legend="none")
        ax.set_title(f"{label}: {scene.scenario.title}" if row == 0 else f"{label}: the same scene", fontsize=10)
        for name, b in scene.runout["truck"].bodies.items():
            lines.append(f"| {label} | {name} | {b.rest_position[0]:.2f} | {b.rest_position[1]:.2f} | "
                         f"{math.degrees(b.rest_heading_wrapped):.2f} | {b.time_to_rest:.3f} |")
    ax = fig.add_subplot(grid[2, 0])
    ax2 = fig.add_subplot(grid[2, 1])
    lines += ["", "| dolly | joint | largest articulation [deg] |", "|---|---|---|"]
    for label, scene in runs.items():
        h = scene.history(dt=0.01)
        style = "-" if label == "C-dolly" else "--"
        for (front, rear), a, color in zip(joints, (ax, ax, ax2), ("C0", "C3", "C2")):
            art = articulation(h, front, rear)
            a.plot(h["t"], art, style, color=color, label=f"{front}-{rear} ({label})")
            lines.append(f"| {label} | {front}-{rear} | {art[np.argmax(np.abs(art))]:.3f} |")
    for a, title in ((ax, "articulation at the fifth wheel and the drawbar"), (ax2, "articulation at the dolly's fifth wheel")):
        a.set_xlabel("time after the impact [s]")
        a.set_ylabel("articulation [deg]")
        a.set_title(title, fontsize=10)
        a.grid(alpha=0.3)
        a.legend(fontsize=8)
    fig.tight_layout()
    OUT.mkdir(exist_ok=True)
    fig.savefig(OUT / "dollies_compare.png", dpi=110)
    lines += ["", "Run time of each scene (impact and run-out, compiled kernels): "
              + ", ".join(f"{k} {v:.2f} s" for k, v in times.items()) + " (shared machine).", ""]
    (OUT / "dollies.md").write_text("\n".join(lines))
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())

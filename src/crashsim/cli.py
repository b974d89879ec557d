"""Command line: load -> call the public API -> write -> exit code.

Exit codes: 0 success, 1 a run finished but some evidence verdict failed (``run --strict``),
2 bad input (scenario or arguments), 3 a computation failed (singular equations, solver).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from .errors import CrashsimError, ScenarioError, SolverError

__all__ = ["main"]


def _clean(obj):
    """JSON-safe copy: numpy scalars/arrays to Python, NaN/inf to None."""
    import numpy as np

    if isinstance(obj, dict):
        return {str(k): _clean(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_clean(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return _clean(obj.tolist())
    if isinstance(obj, (np.floating, float)):
        v = float(obj)
        return v if math.isfinite(v) else None
    if isinstance(obj, (np.integer,)):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def _cmd_run(args) -> int:
    from .scenario import load_scenario
    from .reconstruct import run_scene

    scenario = load_scenario(args.file)
    result = run_scene(scenario)
    if args.csv:
        result.write_csv(Path(args.csv))
    if args.json:
        json.dump(_clean(result.to_dict()), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(result.report(args.units) + "\n")
    if args.strict and result.evidence is not None and not result.evidence.all_passed:
        return 1
    return 0


def _cmd_plot(args) -> int:
    from .plotting import save_scene_figures
    from .reconstruct import run_scene
    from .scenario import load_scenario
    from .units import Kind, parse

    interval = None if args.interval is None else parse(args.interval, Kind.TIME, field="--interval")
    scene = run_scene(load_scenario(args.file))
    written = save_scene_figures(scene, Path(args.output), histories_path=args.histories and Path(args.histories),
                                 dpi=args.dpi, interval=interval, system=args.units)
    for path in written:
        sys.stdout.write(f"wrote {path}\n")
    return 0


def _cmd_schema(args) -> int:
    from .scenario import schema_document

    sys.stdout.write(schema_document(args.format) + "\n")
    return 0


def _cmd_presets(args) -> int:
    from .scenario import presets

    for name, p in presets().items():
        sys.stdout.write(f"{name}\n    mass {p['mass']}, yaw inertia {p['yaw_inertia']}, "
                         f"{len(p.get('axles', []))} axles\n    source: {p['source']}\n")
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="crashsim", description="Reconstruct collisions of articulated vehicles.")
    from . import __version__

    p.add_argument("--version", action="version", version=f"crashsim {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="solve a scenario file and report")
    r.add_argument("file", help="scenario file (TOML)")
    r.add_argument("--json", action="store_true", help="print the full result as one JSON object (SI units)")
    r.add_argument("--units", choices=("SI", "US"), default="SI", help="units of the readable report")
    r.add_argument("--csv", metavar="DIR", help="write time histories as CSV files into DIR")
    r.add_argument("--strict", action="store_true", help="exit with code 1 if an evidence item is out of tolerance")
    r.set_defaults(func=_cmd_run)

    pl = sub.add_parser("plot", help="draw the scene diagram (and the run-out histories)")
    pl.add_argument("file", help="scenario file (TOML)")
    pl.add_argument("-o", "--output", required=True, help="scene diagram: .png, .svg or .pdf")
    pl.add_argument("--histories", metavar="FILE", help="also draw speed, yaw rate and articulation histories")
    pl.add_argument("--interval", metavar="TIME", help='time between ghost outlines, e.g. "0.5 s"')
    pl.add_argument("--units", choices=("SI", "US"), default=None, help="units of the figure (default: the scenario's)")
    pl.add_argument("--dpi", type=int, default=150)
    pl.set_defaults(func=_cmd_plot)

    s = sub.add_parser("schema", help="print the documented scenario-file schema")
    s.add_argument("--format", choices=("text", "markdown"), default="text")
    s.set_defaults(func=_cmd_schema)

    pr = sub.add_parser("presets", help="list the vehicle library's body parameter sets and their sources")
    pr.set_defaults(func=_cmd_presets)
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return int(args.func(args))
    except ScenarioError as exc:
        sys.stderr.write(f"crashsim: input error: {exc}\n")
        return 2
    except SolverError as exc:
        sys.stderr.write(f"crashsim: solver error: {exc}\n")
        return 3
    except CrashsimError as exc:  # pragma: no cover - every raised error is one of the above
        sys.stderr.write(f"crashsim: error: {exc}\n")
        return 3

"""Command line: load -> call the public API -> write -> exit code.

Exit codes: 0 success, 1 a run finished but some evidence verdict failed (``run --strict``),
2 bad input (scenario or arguments), 3 a computation failed (singular equations, solver) or a
run-out did not reach rest (a limit ended it; the results are still printed or written).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import webbrowser
from pathlib import Path

from ._jit import cache_dir, ready
from ._version import __version__
from .errors import CrashsimError, ScenarioError, SolverError
from .figure_options import (ANIMATION_LEGENDS, LABEL_KINDS, LEGEND_MODES, PAPER_SIZES, VIEWS, ZOOMS, check_hide,
                             check_view, parse_scale)
from .outputs import check_output_dir, check_output_file, check_workers
from .units import Kind, format_value, parse, resolve_system, to_unit

# The light face: the parser, --help, --version and the checks of options and output paths need
# none of the physics, so a command imports what it runs (the scenario loader, the kernels, SciPy,
# matplotlib) inside the function that runs it: ``crashsim --version`` starts in tenths of a second
# (benchmarks/startup.py, tests/unit/test_light_import.py).

__all__ = ["main"]


def _units(text: str) -> str:
    """argparse type of ``--units``: SI or US in any case."""
    try:
        return resolve_system(text)
    except ScenarioError:
        raise argparse.ArgumentTypeError(f"{text!r}: allowed SI or US (any case)") from None


def _hide(text: str) -> frozenset:
    """argparse type of ``--hide``: label kinds, comma-separated."""
    try:
        return check_hide(text)
    except ScenarioError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None


class _ViewAction(argparse.Action):
    """``--view X0 Y0 X1 Y1``: four numbers with X1 > X0 and Y1 > Y0, checked as the line is parsed
    (before the file is read or anything compiled or run); stored as written, converted once the
    file's length unit is known."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            check_view(values, field="--view", unit="")
        except ScenarioError as exc:
            parser.error(f"argument --view: {str(exc).split(': ', 1)[-1]}")
        setattr(namespace, self.dest, list(values))


def _scale(text: str) -> float:
    """argparse type of ``--scale``: 1:N, or an engineer's scale 1" = F'."""
    try:
        return parse_scale(text, field="--scale")
    except ScenarioError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None


def _dt(text: str | None) -> float | None:
    if text is None:
        return None
    dt = parse(text, Kind.TIME, field="--dt")
    if not dt > 0:
        raise ScenarioError(f"--dt = {text!r}; allowed a time step > 0 (e.g. \"0.1 s\")", field="--dt")
    return dt


def _load(path: str):
    """The scenario of ``path``; in an interpreted first run without the run-out's wall-time limit
    (a budget for compiled kernels: a result must not depend on whether they were compiled yet), said
    on stderr."""
    from . import first_run
    from .scenario import load_scenario

    scenario = load_scenario(path)
    ro = scenario.runout
    if first_run.interpreted() and ro is not None and ro.options.max_wall_time < first_run.INTERPRETED_WALL_TIME:
        sys.stderr.write(f"crashsim: interpreted run: the run-out's wall-time limit (runout.max_wall_time = "
                         f"{ro.options.max_wall_time:g} s) is lifted, so that it ends as the compiled run would\n")
        opts = dataclasses.replace(ro.options, max_wall_time=first_run.INTERPRETED_WALL_TIME)
        scenario = dataclasses.replace(scenario, runout=dataclasses.replace(ro, options=opts))
    return scenario


def _figure_inputs(scenario) -> None:
    """What a figure reads besides the scene, read before the run: the underlay image (a damaged one is
    refused now, not after the run-out)."""
    from .survey.underlay import scene_underlay

    scene_underlay(scenario)


def _cmd_run(args) -> int:
    scenario = _load(args.file)  # a refused file before the engines are imported
    dt = _dt(args.dt)  # checked before any work (_check_options)
    from .motion.result import jsonable
    from .scene import run_scene

    result = run_scene(scenario)
    if args.csv:
        result.write_csv(Path(args.csv), system=args.units, dt=dt)
    if args.json:
        json.dump(jsonable(result.to_dict()), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(result.report(args.units) + "\n")
    if not result.at_rest:
        stopped = [f"{v} ({r.status})" for v, r in result.runout.items() if not r.success]
        sys.stderr.write(f"crashsim: the run-out did not reach rest: {', '.join(stopped)}; the positions reported "
                         "are where it stopped\n")
        return 3
    if args.strict and result.evidence is not None and not result.evidence.all_passed:
        return 1
    return 0


def _cmd_fit(args) -> int:
    from .outputs import same_file
    from .scenario import load_scenario

    if args.write_best is not None and same_file(Path(args.write_best), Path(args.file)):  # before the fit
        raise ScenarioError(f"{args.write_best!r} is the input file; write the best fit to another file",
                            field="--write-best", file=args.file)
    scenario = load_scenario(args.file)  # the whole file validated first ([fit] and evidence sigmas included)
    from .reconstruct.fit import fit_scene

    system = resolve_system(args.units, scenario.units)  # the file's speed_unit kept
    result = fit_scene(scenario, None, engine=args.engine, workers=args.workers,
                       progress=args.progress, file=args.file, sample_time_limit=args.sample_time_limit)
    if args.json:
        _dump_result(result, "fit", args.file)
    else:
        sys.stdout.write(result.report(system) + "\n")
    if args.write_best is not None:
        path = result.write_best(args.write_best)
        sys.stderr.write(f"crashsim: wrote the best-fit scenario to {path} (crashsim run {path})\n")
    return 0


def _dump_result(result, command: str, file: str) -> None:
    """The result as one JSON object (SI), with what it was made from (:func:`made_from`: the SHA-256
    of the scene's inputs), so that a case report embeds it only beside the scene it belongs to."""
    from .casereport import made_from
    from .motion.result import jsonable

    d = jsonable(result.to_dict())
    d["made_from"] = made_from(command, file)
    json.dump(d, sys.stdout, indent=2)
    sys.stdout.write("\n")


def _cmd_mc(args) -> int:
    from .scenario import load_scenario

    scenario = load_scenario(args.file)  # a refused file before the engines are imported
    from .reconstruct.mc_plots import save_mc_figures
    from .reconstruct.montecarlo import monte_carlo

    system = resolve_system(args.units, scenario.units)  # the file's speed_unit kept
    if args.accept and scenario.evidence.empty:
        raise ScenarioError("--accept keeps the samples that meet all the evidence, but the scenario has no "
                            "[evidence] items", field="--accept", file=args.file)
    try:
        result = monte_carlo(scenario, None, args.samples, seed=args.seed, engine=args.engine,
                             workers=args.workers, dask_address=args.dask, out_path=args.out,
                             progress=not args.quiet, file=args.file, sample_time_limit=args.sample_time_limit,
                             accept=args.accept)
    except KeyboardInterrupt:
        return _stopped("samples", args.out)
    if args.plots:
        import matplotlib

        matplotlib.use("Agg")

        save_mc_figures(result, Path(args.plots), system=system)
    if args.json:
        _dump_result(result, "mc", args.file)
    else:
        sys.stdout.write(result.report(system) + "\n")
    return 0


def _sampling_options(parser, engines, figures: str) -> None:
    """The options mc and posterior share: where they run, what they write, in which units."""
    parser.add_argument("--workers", default=None, help="local processes, >= 1 or auto (default: all cores)")
    parser.add_argument("--dask", metavar="ADDRESS", help="run on an existing Dask cluster (scheduler address)")
    parser.add_argument("--plots", metavar="DIR", help=f"write {figures} into DIR")
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object (SI units)")
    parser.add_argument("--units", type=_units, default=None,
                        help="SI or US (any case): units of the report and plots (default: the scenario's units)")
    parser.add_argument("--engine", choices=engines, default=None,
                        help="run-out engine (default: compiled if available)")


def _stopped(what: str, kept_in) -> int:
    """Ctrl-C in a long run: say where the work done is kept (resumable), exit code 130."""
    kept = f"; the {what} done are kept in {kept_in}: run the same command again to resume" if kept_in else ""
    sys.stderr.write(f"crashsim: stopped{kept}\n")
    return 130


def _cmd_posterior(args) -> int:
    from .scenario import load_scenario

    scenario = load_scenario(args.file)  # the whole file validated first ([fit], [posterior], evidence sigmas)
    from .reconstruct.posterior import run_posterior
    from .reconstruct.posterior_plots import save_posterior_figures

    system = resolve_system(args.units, scenario.units)  # the file's speed_unit kept
    try:
        result = run_posterior(scenario, None, steps=args.steps, seed=args.seed,
                               start="fit" if args.from_fit else None, engine=args.engine, workers=args.workers,
                               dask_address=args.dask, chain_path=args.chain, progress=not args.quiet,
                               file=args.file, sample_time_limit=args.sample_time_limit)
    except KeyboardInterrupt:
        return _stopped("steps", args.chain)
    if args.plots:
        import matplotlib

        matplotlib.use("Agg")

        for path in save_posterior_figures(result, Path(args.plots), system=system):
            sys.stderr.write(f"crashsim: wrote {path}\n")
    if args.json:
        _dump_result(result, "posterior", args.file)
    else:
        sys.stdout.write(result.report(system) + "\n")
    return 0


def _add_inverse_commands(sub):
    engines = ("compiled", "scipy")
    f = sub.add_parser("fit", help="find the [fit] unknowns from the evidence (weighted least squares, intervals)")
    f.add_argument("file", help="scenario file (TOML) with a [fit] table and evidence sigmas")
    f.add_argument("--json", action="store_true", help="print the full result as one JSON object (SI units)")
    f.add_argument("--units", type=_units, default=None,
                   help="SI or US (any case): units of the report (default: the scenario's units)")
    f.add_argument("--engine", choices=engines, default=None, help="run-out engine (default: compiled if available)")
    f.add_argument("--workers", default=None, help="processes for the starts, >= 1 or auto (default: all cores)")
    f.add_argument("--progress", action="store_true", help="progress bar over the starts on stderr")
    f.add_argument("--sample-time-limit", type=float, default=30.0, metavar="SECONDS",
                   help="wall-clock limit of one scene evaluation's run-out (default 30 s); a slower one is penalised")
    f.add_argument("--write-best", metavar="OUT.toml",
                   help="write a runnable scenario: the input file with the unknowns at their best values, "
                        "[fit] removed (not the input file itself)")
    f.set_defaults(func=_cmd_fit)

    m = sub.add_parser("mc", help="Monte Carlo of the [uncertainty] inputs through impact and run-out")
    m.add_argument("file", help="scenario file (TOML) with an [uncertainty] table")
    m.add_argument("--samples", type=int, default=None, help="number of samples (default: uncertainty.samples)")
    m.add_argument("--seed", type=int, default=None, help="seed (default: uncertainty.seed)")
    m.add_argument("--out", metavar="FILE", help="stream samples to this JSON-lines file; resume if it exists")
    _sampling_options(m, engines, "histograms, rest clouds and tornado charts")
    m.add_argument("--accept", action="store_true",
                   help="rejection sampling: also report the samples that meet ALL the evidence (count, share, "
                        "their percentiles beside all samples'), and draw them apart in the --plots figures")
    m.add_argument("--quiet", action="store_true", help="no progress bar")
    m.add_argument("--sample-time-limit", type=float, default=30.0, metavar="SECONDS",
                   help="wall-clock limit of one sample's run-out (default 30 s); a slower sample fails with that "
                        "reason and the run goes on")
    m.set_defaults(func=_cmd_mc)

    p = sub.add_parser("posterior", help="MCMC posterior of the [fit] unknowns given the evidence (emcee)")
    p.add_argument("file", help="scenario file (TOML) with a [fit] table, evidence sigmas and optionally [posterior]")
    p.add_argument("--steps", type=int, default=None, help="steps per walker (default: posterior.steps)")
    p.add_argument("--seed", type=int, default=None, help="seed (default: posterior.seed)")
    p.add_argument("--from-fit", action="store_true",
                   help="start the walkers around the best fit (runs crashsim fit first; posterior.start = \"fit\")")
    p.add_argument("--chain", metavar="FILE.npz",
                   help="keep the chain in this file (written as it runs); resume from it if it exists")
    _sampling_options(p, engines, "the corner plot and the trace plots")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("--sample-time-limit", type=float, default=30.0, metavar="SECONDS",
                   help="wall-clock limit of one evaluation's run-out (default 30 s); a slower one is rejected")
    p.set_defaults(func=_cmd_posterior)


def _cmd_plot(args) -> int:
    interval = None if args.interval is None else parse(args.interval, Kind.TIME, field="--interval")
    scenario = _load(args.file)  # a refused file before the engines are imported
    from .plotting import check_sheet
    from .scene import run_scene, simulate_approaches

    args.view_si = None
    if args.view is not None:  # the file's length unit -> m
        per_m, unit = to_unit(1.0, Kind.LENGTH, resolve_system(None, scenario.units))
        args.view_si = tuple(v / per_m for v in check_view(args.view, field="--view", unit=unit))
    if args.paper is not None or args.scale is not None:  # the sheet against what is known before the run-out
        if not args.no_approach:  # the approaches' paths first (the scene run then uses them, not run twice)
            scenario = simulate_approaches(scenario)
        check_sheet(scenario, args.paper or "A4", args.scale, approach=not args.no_approach, field="--scale")
    _figure_inputs(scenario)
    scene = run_scene(scenario)
    try:
        written = _save_figures(args, scene, interval)
    except ScenarioError as exc:  # a scale too large for the page: name the option as written
        if exc.field != "scale":
            raise
        raise ScenarioError(str(exc).removeprefix("scale: "), field="--scale") from None
    for path in written:
        sys.stdout.write(f"wrote {path}\n")
    return 0


def _save_figures(args, scene, interval) -> list:
    from .plotting import save_scene_figures

    return save_scene_figures(scene, Path(args.output), histories_path=args.histories and Path(args.histories),
                              dpi=args.dpi, interval=interval, system=args.units,
                              time_distance_path=args.time_distance and Path(args.time_distance),
                              approach=not args.no_approach, legend=args.legend, hide=args.hide or (),
                              paper=args.paper, scale=args.scale, view=getattr(args, "view_si", None),
                              zoom=args.zoom, wheels_path=args.wheels and Path(args.wheels))


def _cmd_animate(args) -> int:
    from tqdm import tqdm

    scenario = _load(args.file)  # a refused file before the engines are imported
    from .animation import animate_scene, check_animation_path, frame_times
    from .scene import run_scene

    out = check_animation_path(args.output, field="-o")  # before anything long
    dt = parse(args.dt, Kind.TIME, field="--dt")
    frame_times(0.0, dt, field="--dt")  # dt > 0; the frame count is checked once the run-out's end is known
    _figure_inputs(scenario)
    scene = run_scene(scenario)
    if scene.runout:
        frame_times(max(r.t_end for r in scene.runout.values()), dt, field="--dt")
    with tqdm(total=None, file=sys.stderr, unit="frame", desc="rendering", disable=args.quiet) as bar:
        def progress(done, total):
            bar.total = total
            bar.update(done - bar.n)

        written = animate_scene(scene, out, dt=dt, speed=args.speed, system=args.units, dpi=args.dpi,
                                approach=not args.no_approach, progress=progress, view=args.view,
                                legend=args.legend)
    sys.stdout.write(f"wrote {written}\n")
    return 0


def _cmd_survey(args) -> int:
    from .survey.inspect import preview, read_any, summary

    data = read_any(args.file, units=args.units, columns=args.columns, crs=args.crs,
                    layer_property=args.layer_property)
    sys.stdout.write(summary(data) + "\n")
    if args.output:
        sys.stdout.write(f"wrote {preview(data, args.output)}\n")
    return 0


def _cmd_export(args) -> int:
    times = args.times_s  # checked before any work (_check_options), as the output paths
    scenario = _load(args.file)  # a refused file before the engines are imported
    from .scene import run_scene
    from .survey.export import export_frame, export_items, write_dxf, write_geojson

    frame, unit = export_frame(scenario)
    items = export_items(run_scene(scenario), times)
    if args.dxf:
        sys.stdout.write(f"wrote {write_dxf(items, args.dxf, frame, unit)} ({len(items)} entities, {unit})\n")
    if args.geojson:
        crs = (scenario.data.get("survey") or {}).get("crs")
        sys.stdout.write(f"wrote {write_geojson(items, args.geojson, frame, unit, crs)} ({len(items)} features, "
                         + (f"WGS 84 longitude/latitude from {crs})\n" if crs else f"{unit})\n"))
    return 0


def _cmd_report(args) -> int:
    extra = args.results  # read and checked before any work (_check_outputs)
    scenario = _load(args.file)  # a refused file before the engines are imported
    from .casereport import survey_files, write_case_report
    from .reconstruct.montecarlo import OUTPUT_KINDS
    from .scenario import presets
    from .scene import run_scene
    from .validation import class_errors

    _figure_inputs(scenario)
    scene = run_scene(scenario)
    inputs = [args.file] + survey_files(args.file) + [getattr(args, k) for k in ("fit", "mc", "posterior")
                                                      if getattr(args, k)]
    command = " ".join(["crashsim", "report", args.file, "-o", Path(args.output).name]
                       + [f"--{k} {getattr(args, k)}" for k in ("fit", "mc", "posterior") if getattr(args, k)]
                       + ([f"--units {args.units}"] if args.units else []))
    written = write_case_report(scene, args.output, input_files=inputs, system=args.units, presets=presets(),
                                command=command, output_kinds=OUTPUT_KINDS,
                                validation=class_errors(scene, system=args.units), **extra)
    sys.stdout.write(f"wrote {written}\n")
    return 0


def _cmd_schema(args) -> int:
    from .scenario import schema_document

    sys.stdout.write(schema_document(args.format) + "\n")
    return 0


def _cmd_presets(args) -> int:
    from .scenario import preset_geometry, presets
    from .vehicle_plan import geometry_lines, plot_body_plan

    system = args.units or "SI"
    if args.plot:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        g = preset_geometry(args.plot)
        ax = plot_body_plan(g, title=f"preset {args.plot} (to scale)", system=system)
        ax.figure.savefig(args.output, dpi=150)
        plt.close(ax.figure)
        sys.stdout.write(f"wrote {args.output}\n")
        return 0
    for name, p in presets().items():
        g = preset_geometry(name)
        sys.stdout.write(f"{name}\n    mass {format_value(g['mass'], Kind.MASS, system, 6)}, yaw inertia "
                         f"{format_value(g['yaw_inertia'], Kind.YAW_INERTIA, system, 6)}, "
                         f"{len(g['axles'])} axles\n")
        for line in geometry_lines(g, system):
            sys.stdout.write(f"    {line}\n")
        sys.stdout.write(f"    source: {p['source']}\n")
        for face, c in p.get("crush", {}).items():
            sys.stdout.write(f"    crush stiffness, {face}: A {c['A']}, B {c['B']}\n      source: {c['source']}\n")
    return 0


def _cmd_validate(args) -> int:
    from .motion.result import jsonable
    from .validation import load_suite, plot_case, results_dict, run_suite, table_text, write_csv

    suite = load_suite(args.suite)
    chosen = suite.select(args.cases, "fast" if args.quick else None)  # unknown names: exit 2 before any work
    if not chosen:
        raise ScenarioError("no case to run (--quick keeps the fast tier only)", field="CASE")
    results = run_suite(suite, chosen, progress=None if args.json else
                        (lambda cid: sys.stderr.write(f"crashsim: validating {cid}\n")))
    if args.csv:
        write_csv(results, Path(args.csv), args.units)
    if args.plots:
        import matplotlib

        matplotlib.use("Agg")
        Path(args.plots).mkdir(parents=True, exist_ok=True)
        for r in results:
            plot_case(r, Path(args.plots) / f"{r.id}.png", args.units)
    if args.json:
        json.dump(jsonable(results_dict(results)), sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        sys.stdout.write(table_text(results, args.units))
    changed = [f"{q.case}: {q.name} ({q.status})" for r in results for q in r.new_misses]
    if changed:
        sys.stderr.write(f"crashsim: {len(changed)} quantit{'y differs' if len(changed) == 1 else 'ies differ'} from the "
                         f"suite's record of documented misses: {'; '.join(changed)}\n")
        return 1
    return 0


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="crashsim", description="Reconstruct collisions of articulated vehicles.")

    p.add_argument("--version", action="version", version=f"crashsim {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="solve a scenario file and report")
    r.add_argument("file", help="scenario file (TOML)")
    r.add_argument("--json", action="store_true", help="print the full result as one JSON object (SI units)")
    r.add_argument("--units", type=_units, default=None,
                   help="SI or US (any case): units of the report and the CSV files (default: the scenario's units)")
    r.add_argument("--csv", metavar="DIR", help="write time histories as CSV files into DIR (headers carry the unit)")
    r.add_argument("--dt", metavar="TIME", help='time step of every CSV history (bodies, wheel tracks, approaches), e.g. "0.1 s" '
                        '(default: runout.sample_dt; the approach: 201 points)')
    r.add_argument("--strict", action="store_true", help="exit with code 1 if an evidence item is out of tolerance")
    r.set_defaults(func=_cmd_run)

    _add_inverse_commands(sub)

    pl = sub.add_parser("plot", help="draw the scene diagram (and the run-out histories)")
    pl.add_argument("file", help="scenario file (TOML)")
    pl.add_argument("-o", "--output", required=True, help="scene diagram: .png, .svg or .pdf")
    pl.add_argument("--histories", metavar="FILE", help="also draw speed, yaw rate and articulation histories")
    pl.add_argument("--time-distance", metavar="FILE",
                    help="also draw the time-distance and speed-time chart (approach, impacts, run-out to rest)")
    pl.add_argument("--wheels", metavar="FILE",
                    help="also draw the wheel time line: every wheel's state, air-brake level, sliding and the "
                         "steering, from the approach through the impact to rest, on one time axis")
    pl.add_argument("--no-approach", action="store_true",
                    help="leave the approaches out of the scene diagram (a close view of impact and run-out)")
    pl.add_argument("--interval", metavar="TIME", help='time between ghost outlines, e.g. "0.5 s"')
    detail = pl.add_mutually_exclusive_group()
    detail.add_argument("--view", nargs=4, metavar=("X0", "Y0", "X1", "Y1"), action=_ViewAction,
                        help="a detail view: the window from (X0, Y0) to (X1, Y1) in the file's length unit "
                             "(m, or ft with units = \"US\"), X1 > X0 and Y1 > Y0")
    detail.add_argument("--zoom", choices=ZOOMS, default=None,
                        help="impact: a window around the outlines at impact of the bodies in the first impact, "
                             "with a margin (without it, an overview whose impact is small gets an inset of it)")
    pl.add_argument("--units", type=_units, default=None, help="SI or US: units of the figure (default: the scenario's)")
    pl.add_argument("--dpi", type=int, default=150)
    pl.add_argument("--legend", choices=LEGEND_MODES, default="compact",
                    help="compact legend under or beside the diagram, one line per entry (default); the full one "
                         "there, each evidence item with its residual (outside); small inside it; or none")
    pl.add_argument("--hide", type=_hide, default=None, metavar="KINDS",
                    help=f"label kinds to leave out, comma-separated: labels (all), {', '.join(LABEL_KINDS)}")
    pl.add_argument("--paper", choices=tuple(PAPER_SIZES), default=None,
                    help="print sheet: the figure is the page, the drawing to scale (PDF/SVG print at 100 %%)")
    pl.add_argument("--scale", type=_scale, default=None, metavar="1:N",
                    help='drawing scale on the sheet, e.g. "1:200" or an engineer\'s scale "1\" = 40\'" (default: '
                         'the largest standard scale that fits, in US units an engineer\'s scale; A4 without '
                         '--paper)')
    pl.set_defaults(func=_cmd_plot)

    an = sub.add_parser("animate", help="animate the run-out over the scene diagram (.gif, or .mp4 with ffmpeg)")
    an.add_argument("file", help="scenario file (TOML) with a [runout] section")
    an.add_argument("-o", "--output", required=True, help="animation: .gif, or .mp4 where ffmpeg is installed")
    an.add_argument("--dt", metavar="TIME", default="0.05 s", help='scene time between frames (default "0.05 s")')
    an.add_argument("--speed", type=float, default=1.0,
                    help="playback speed, 1 = real time (frames per second = speed / dt)")
    an.add_argument("--units", type=_units, default=None, help="SI or US: units of the figure (default: the scenario's)")
    an.add_argument("--dpi", type=int, default=100)
    an.add_argument("--no-approach", action="store_true",
                    help="start at the impact (a scene with approaches starts at the earliest start of braking)")
    an.add_argument("--view", choices=VIEWS, default="follow",
                    help="follow: a camera framed on the vehicles at each frame, smoothed (default); "
                         "scene: the whole scene still")
    an.add_argument("--legend", choices=ANIMATION_LEGENDS, default="compact",
                    help="a compact legend outside the view (default), or none")
    an.add_argument("--quiet", action="store_true", help="no progress bar")
    an.set_defaults(func=_cmd_animate)

    sv = sub.add_parser("survey", help="list a survey file's layers or codes with entity counts and extents")
    sv.add_argument("file", help="survey file: .dxf, point file (.csv, .txt, .asc, .pnezd) or .geojson")
    sv.add_argument("-o", "--output", metavar="PREVIEW.png", help="also draw every entity, coloured by layer or code")
    sv.add_argument("--units", default=None, help="unit of the coordinates (DXF: default $INSUNITS; points: m)")
    sv.add_argument("--columns", default="PNEZD", help="point files: column letters (default PNEZD)")
    sv.add_argument("--crs", default=None, help="GeoJSON: projected CRS to show it in (e.g. EPSG:32633)")
    sv.add_argument("--layer-property", default="layer", help="GeoJSON: the property that names a feature's layer")
    sv.set_defaults(func=_cmd_survey)

    ex = sub.add_parser("export", help="write the reconstruction as CAD (DXF) or GeoJSON in the survey's frame")
    ex.add_argument("file", help="scenario file (TOML)")
    ex.add_argument("--dxf", metavar="OUT.dxf", help="DXF drawing, one layer per outline, path, track and evidence")
    ex.add_argument("--geojson", metavar="OUT.geojson", help="the same as GeoJSON features with a layer property")
    ex.add_argument("--times", metavar="TIMES", help='outlines also at these times after separation, e.g. "0.5 s, 1 s"')
    ex.set_defaults(func=_cmd_export)

    rp = sub.add_parser("report", help="write one self-contained HTML case report (inputs, impacts, run-out, "
                                       "evidence, figures, SHA-256 of every input file)")
    rp.add_argument("file", help="scenario file (TOML)")
    rp.add_argument("-o", "--output", required=True, help="the report: .html")
    rp.add_argument("--fit", metavar="FIT.json", help="include a fit's result (crashsim fit FILE --json > FIT.json)")
    rp.add_argument("--mc", metavar="MC.json", help="include a Monte Carlo result (crashsim mc FILE --json)")
    rp.add_argument("--posterior", metavar="POST.json", help="include a posterior (crashsim posterior FILE --json)")
    rp.add_argument("--units", type=_units, default=None, help="SI or US: units of the report (default: the scenario's)")
    rp.set_defaults(func=_cmd_report)

    va = sub.add_parser("validate", help="run the validation suite (staged collisions, full-scale tests): every "
                                         "quantity's error against its band")
    va.add_argument("cases", nargs="*", metavar="CASE", help="case ids (folders of the suite; default: all)")
    va.add_argument("--suite", metavar="DIR", help="the suite's folder (default: ./validation, else the source "
                                                   "checkout's validation/)")
    va.add_argument("--quick", action="store_true", help="only the fast tier's cases")
    va.add_argument("--json", action="store_true", help="print every case and quantity as one JSON object (SI)")
    va.add_argument("--csv", metavar="FILE", help="write one row per quantity to FILE")
    va.add_argument("--plots", metavar="DIR", help="write one figure per case into DIR (measured against computed, "
                                                   "error and its band)")
    va.add_argument("--units", type=_units, default=None,
                    help="SI or US (any case) for every value (default: each source's own units)")
    va.set_defaults(func=_cmd_validate)

    s = sub.add_parser("schema", help="print the documented scenario-file schema")
    s.add_argument("--format", choices=("text", "markdown"), default="text")
    s.set_defaults(func=_cmd_schema)

    pr = sub.add_parser("presets", help="list the vehicle library's body parameter sets, their geometry and sources")
    pr.add_argument("--units", type=_units, default=None, help="SI or US (any case): units of the list (default SI)")
    pr.add_argument("--plot", metavar="NAME", help="draw preset NAME to scale in plan view (with -o FILE)")
    pr.add_argument("-o", "--output", metavar="FILE", help="figure of --plot: .png, .svg or .pdf")
    pr.set_defaults(func=_cmd_presets)

    lv = sub.add_parser("live", help="open the scene in a live view in the browser: drag vehicles, set speeds and "
                                     "frictions, see the scene, its evidence and its uncertainty recomputed at once")
    lv.add_argument("file", help="scenario file (TOML)")
    lv.add_argument("--port", type=int, default=0, help="port on 127.0.0.1 (default: a free one)")
    lv.add_argument("--no-browser", action="store_true", help="print the address only, do not open a browser")
    lv.add_argument("--band-samples", type=int, default=32,
                    help="samples of the Monte Carlo band (with [uncertainty]; 0: none; default 32)")
    lv.add_argument("--workers", type=int, default=2, help="worker processes of the band (default 2)")
    lv.set_defaults(func=_cmd_live)
    return p


def _cmd_live(args) -> int:
    try:
        from .live.server import LiveServer
    except ImportError as exc:  # aiohttp or tomlkit missing: the optional extra
        raise ScenarioError(f"the live view needs the 'live' extra ({exc.name} is not installed): "
                            "pip install \"crashsim[live]\"", field="live") from None
    server = LiveServer(args.file, port=args.port, band_samples=args.band_samples, workers=args.workers)

    def ready(url):
        sys.stderr.write(f"crashsim live: {args.file} at\n  {url}\n(Ctrl+C stops it; the address carries the "
                         "token the server asks of every request)\n")
        if not args.no_browser:
            webbrowser.open(url)

    server.run(on_ready=ready)
    return 0


#: Commands that run the run-out kernels (and so may compile them on a first run).
_COMPUTING = ("run", "fit", "mc", "posterior", "plot", "animate", "export", "report", "validate", "live")


def _first_compile(bar: bool = True) -> None:
    """Compile the run-out kernels once, saying so on stderr with a progress bar (a line per step
    without ``bar``); the first run after installing or upgrading, later runs load them from the cache."""
    from tqdm import tqdm

    from .warmup import COMPILE_STEPS, compile_kernels

    if ready():
        return
    sys.stderr.write("crashsim: compiling the run-out kernels (once after installing or upgrading; about 1-2 "
                     f"minutes; cached in {cache_dir()})\n")
    if not bar:
        n = len(COMPILE_STEPS)
        compile_kernels(lambda i, label: sys.stderr.write(f"crashsim: compiling {i + 1}/{n}: {label}\n"))
        sys.stderr.write("crashsim: compiled\n")
        return

    with tqdm(total=len(COMPILE_STEPS), file=sys.stderr, unit="step",
              bar_format="{l_bar}{bar}| {n_fmt}/{total_fmt} [{elapsed}]") as bar:
        def progress(i, label):
            bar.n = i
            bar.set_description_str(f"compiling: {label}")
            bar.refresh()

        compile_kernels(progress)
        bar.n = len(COMPILE_STEPS)
        bar.set_description_str("compiled")
        bar.refresh()


def _figure_suffixes() -> tuple[str, ...]:
    from matplotlib.backend_bases import FigureCanvasBase

    return tuple(sorted("." + k for k in FigureCanvasBase.get_supported_filetypes()))


def _check_outputs(args) -> None:
    """Every output path and worker count of the command, before any work (loading, compiling,
    computing): a path that cannot be written is an input error (exit 2) now, not a traceback later."""
    c = args.command
    if hasattr(args, "workers"):
        args.workers = check_workers(args.workers, field="--workers")
    if c == "run" and args.csv:
        check_output_dir(args.csv, field="--csv", what="the CSV files")
    if c == "fit" and args.write_best is not None:
        check_output_file(args.write_best, field="--write-best", make_parents=False, what="the best-fit scenario")
    if c == "mc" and args.out:
        check_output_file(args.out, field="--out", make_parents=False, what="the samples")
    if c == "posterior" and args.chain:
        check_output_file(args.chain, field="--chain", make_parents=False, what="the chain")
    if c in ("mc", "posterior") and args.plots:
        check_output_dir(args.plots, field="--plots", what="the figures")
    if c == "plot":
        figs = _figure_suffixes()
        for field, path in (("-o", args.output), ("--histories", args.histories),
                            ("--time-distance", args.time_distance), ("--wheels", args.wheels)):
            if path:
                check_output_file(path, field=field, suffixes=figs, what="a figure")
    if c == "report":
        from .casereport import check_result_json

        check_output_file(args.output, field="-o", suffixes=(".html", ".htm"), make_parents=False,
                          what="the case report")
        args.results = {}
        for key in ("fit", "mc", "posterior"):
            path = getattr(args, key)
            if path and not Path(path).is_file():
                raise ScenarioError(f"{path!r} is not a file; give the JSON that crashsim {key} FILE --json wrote",
                                    field=f"--{key}")
            if path:  # of that command, made from this scene's inputs (their SHA-256)
                args.results[key] = check_result_json(path, key, args.file, field=f"--{key}")
    if c == "presets" and (args.plot or args.output):
        if not (args.plot and args.output):
            raise ScenarioError("--plot NAME and -o FILE go together: the preset to draw and the figure to write",
                                field="--plot" if args.output else "-o")
        check_output_file(args.output, field="-o", suffixes=_figure_suffixes(), what="a figure")
    if c == "validate":
        if args.csv:
            check_output_file(args.csv, field="--csv", suffixes=(".csv",), what="the table")
        if args.plots:
            check_output_dir(args.plots, field="--plots", what="the figures")
    if c == "animate":
        from .animation import check_animation_path

        check_output_file(check_animation_path(args.output, field="-o"), field="-o", what="the animation")
        if not parse(args.dt, Kind.TIME, field="--dt") > 0:
            raise ScenarioError(f"{args.dt!r} is not a positive time; allowed a time between frames > 0 s, "
                                "e.g. \"0.05 s\"", field="--dt")
        if not (math.isfinite(args.speed) and args.speed > 0):
            raise ScenarioError(f"--speed = {args.speed:g}: allowed a playback speed > 0 (1 = real time, 0.5 = "
                                "slow motion)", field="--speed")
    _check_options(args)


def _check_options(args) -> None:
    """The option values of the command that need no scene, before any work (exit 2, one line)."""
    c = args.command
    if c == "run":
        args.dt_s = _dt(args.dt)
        if args.dt_s is not None and not args.csv:
            raise ScenarioError("--dt sets the time step of the --csv histories; give --csv DIR too", field="--dt")
    if c in ("plot", "animate") and args.dpi < 1:
        raise ScenarioError(f"--dpi = {args.dpi}; allowed a resolution >= 1 dot per inch (e.g. 150)", field="--dpi")
    if c == "plot" and args.interval is not None:
        args.interval_s = parse(args.interval, Kind.TIME, field="--interval")
        if not args.interval_s > 0:
            raise ScenarioError(f"--interval = {args.interval!r}; allowed a time > 0 between ghost outlines, e.g. "
                                "\"0.5 s\"", field="--interval")
    if c == "export":
        if not (args.dxf or args.geojson):
            raise ScenarioError("give --dxf OUT.dxf and/or --geojson OUT.geojson", field="export")
        if args.dxf:
            check_output_file(args.dxf, field="--dxf", make_parents=False, suffixes=(".dxf",), what="the drawing")
        if args.geojson:
            check_output_file(args.geojson, field="--geojson", make_parents=False, suffixes=(".geojson", ".json"),
                              what="the GeoJSON file")
        args.times_s = []
        for t in (args.times or "").split(","):
            if t.strip():
                v = parse(t.strip(), Kind.TIME, field="--times")
                if not v > 0:
                    raise ScenarioError(f"--times: {t.strip()!r}; allowed times > 0 after separation, e.g. "
                                        "\"0.5 s, 1 s\"", field="--times")
                args.times_s.append(v)
    if c == "live":
        if not 0 <= args.port <= 65535:
            raise ScenarioError(f"--port = {args.port}; allowed 0 (a free port) to 65535", field="--port")
        if args.band_samples < 0:
            raise ScenarioError(f"--band-samples = {args.band_samples}; allowed 0 (no band) or more", field="--band-samples")
        if args.workers < 1:
            raise ScenarioError(f"--workers = {args.workers}; allowed 1 or more", field="--workers")
    if c == "mc" and args.samples is not None and args.samples < 1:
        raise ScenarioError(f"--samples = {args.samples}; allowed a number of samples >= 1", field="--samples")
    if c == "posterior" and args.steps is not None and args.steps < 1:
        raise ScenarioError(f"--steps = {args.steps}; allowed a number of steps >= 1", field="--steps")
    if c in ("fit", "mc", "posterior") and not (math.isfinite(args.sample_time_limit) and args.sample_time_limit > 0):
        raise ScenarioError(f"--sample-time-limit = {args.sample_time_limit:g}; allowed seconds > 0",
                            field="--sample-time-limit")


def _check_scene_file(path: str) -> None:
    """Read and validate the scenario file ``path`` without simulating its approaches (they run the
    kernels): a :class:`ScenarioError` for a file that cannot be read or has an error."""
    from .scenario import scenario_from_dict
    from .schema import load_toml

    scenario_from_dict(load_toml(path), file=path)


def _first_run(args, argv: list[str]) -> int | None:
    """On a machine whose kernels are not compiled: run a single-scene command interpreted while they
    compile in the background, or compile first (:mod:`crashsim.first_run`). An exit code if the command
    ran in a child process, else None (run it here). The scenario file is read and validated first, so
    that a file refused is refused at once, before any compile or child process starts."""
    if args.command not in _COMPUTING or ready():
        return None
    from . import first_run

    if first_run.interpreted():
        return None
    how = first_run.policy()
    if getattr(args, "file", None) is not None:
        _check_scene_file(args.file)
    dead = first_run.dead_compile()
    if dead is not None:  # say so once, and compile again (below: in the background or here)
        sys.stderr.write(f"crashsim: {dead}; compiling again\n")
    if how != "wait" and args.command in first_run.SINGLE_SCENE:
        log = first_run.start_background_compile() if how == "background" else None
        sys.stderr.write("crashsim: first run on this machine: this scene runs interpreted (seconds) "
                         + (f"while the kernels compile in the background for the next commands (log: {log})\n"
                            if log is not None else
                            "while the kernels compile in the background\n" if how == "background" else "\n"))
        code = first_run.run_interpreted(argv, race=log is not None or first_run.compile_in_progress())
        if code is not None:
            return code
        sys.stderr.write("crashsim: the kernels compiled first: the scene runs compiled\n")
        return None
    if first_run.compile_in_progress():
        sys.stderr.write("crashsim: waiting for the kernels that compile in the background (started by an earlier "
                         "command)\n")
        first_run.wait_for_background_compile()
    _first_compile(bar=sys.stderr.isatty())
    return None


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    try:
        _check_outputs(args)
        code = _first_run(args, argv)
        if code is not None:
            return code
        return int(args.func(args))
    except ScenarioError as exc:
        sys.stderr.write(f"crashsim: input error: {exc}\n")
        return 2
    except SolverError as exc:
        sys.stderr.write(f"crashsim: solver error: {exc}\n")
        return 3
    except OSError as exc:  # an output that became unwritable during the work (disk full, removed folder)
        where = f" {exc.filename!r}" if exc.filename else ""
        sys.stderr.write(f"crashsim: file error{where}: {exc.strerror or exc}\n")
        return 2
    except CrashsimError as exc:  # pragma: no cover - every raised error is one of the above
        sys.stderr.write(f"crashsim: error: {exc}\n")
        return 3

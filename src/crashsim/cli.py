"""Command line: load -> call the public API -> write -> exit code.

Exit codes: 0 success, 1 a run finished but some evidence verdict failed (``run --strict``),
2 bad input (scenario or arguments), 3 a computation failed (singular equations, solver) or a
run-out did not reach rest (a limit ended it; the results are still printed or written).
"""

from __future__ import annotations

import dataclasses
import json
import math
import sys
import webbrowser
from pathlib import Path

from ._jit import cache_dir, ready
from .errors import CrashsimError, ScenarioError, SolverError
from .cli_parser import build_parser
from .figure_options import SCENE_FIGURE_SUFFIXES, check_view
from .outputs import check_output_dir, check_output_file, check_workers
from .units import Kind, format_value, parse, resolve_system, to_unit

# The light face: the parser, --help, --version and the checks of options and output paths need
# none of the physics, so a command imports what it runs (the scenario loader, the kernels, SciPy,
# matplotlib) inside the function that runs it: ``crashsim --version`` starts in tenths of a second
# (benchmarks/startup.py, tests/unit/test_light_import.py).

__all__ = ["main"]


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
    _check_sections(scenario)
    ro = scenario.runout
    if first_run.interpreted() and ro is not None and ro.options.max_wall_time < first_run.INTERPRETED_WALL_TIME:
        sys.stderr.write(f"crashsim: interpreted run: the run-out's wall-time limit (runout.max_wall_time = "
                         f"{ro.options.max_wall_time:g} s) is lifted, so that it ends as the compiled run would\n")
        opts = dataclasses.replace(ro.options, max_wall_time=first_run.INTERPRETED_WALL_TIME)
        scenario = dataclasses.replace(scenario, runout=dataclasses.replace(ro, options=opts))
    return scenario


def _check_sections(scenario) -> None:
    """The file's [fit] and [uncertainty] checked at load, whatever the command (their paths, bounds)."""
    from .reconstruct.sections import check_sections

    check_sections(scenario.file_data, scenario.path)


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
    _check_sections(scenario)
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
    _check_sections(scenario)
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


def _stopped(what: str, kept_in) -> int:
    """Ctrl-C in a long run: say where the work done is kept (resumable), exit code 130."""
    kept = f"; the {what} done are kept in {kept_in}: run the same command again to resume" if kept_in else ""
    sys.stderr.write(f"crashsim: stopped{kept}\n")
    return 130


def _cmd_posterior(args) -> int:
    from .scenario import load_scenario

    scenario = load_scenario(args.file)  # the whole file validated first ([fit], [posterior], evidence sigmas)
    _check_sections(scenario)
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
                         + (f"WGS 84 longitude/latitude from {crs})\n" if crs else
                            f"{unit} in the scene's own axes: not on a map, a GIS reads them as degrees near 0 N 0 E; "
                            "give survey.crs for WGS 84)\n"))
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
    system = resolve_system(args.units, scenario.units)  # the report's units, its validation table's too
    written = write_case_report(scene, args.output, input_files=inputs, system=system, presets=presets(),
                                command=command, output_kinds=OUTPUT_KINDS,
                                validation=class_errors(scene, system=system), **extra)
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
        figs = SCENE_FIGURE_SUFFIXES  # what save_scene_figures writes (matplotlib would write more)
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


#: The function that runs each command of the parser (:func:`crashsim.cli_parser.build_parser`).
COMMANDS = {
    "animate": _cmd_animate,
    "export": _cmd_export,
    "fit": _cmd_fit,
    "live": _cmd_live,
    "mc": _cmd_mc,
    "plot": _cmd_plot,
    "posterior": _cmd_posterior,
    "presets": _cmd_presets,
    "report": _cmd_report,
    "run": _cmd_run,
    "schema": _cmd_schema,
    "survey": _cmd_survey,
    "validate": _cmd_validate,
}


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    args = parser.parse_args(argv)
    try:
        _check_outputs(args)
        code = _first_run(args, argv)
        if code is not None:
            return code
        return int(COMMANDS[args.command](args))
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

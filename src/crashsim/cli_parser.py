"""The command line's parser: every command, its arguments and their argparse types.

It needs none of the physics (``crashsim --help`` and ``--version`` start in tenths of a second);
:mod:`crashsim.cli` runs the command the parser names (``args.command``).
"""

from __future__ import annotations

import argparse

from ._version import __version__
from .errors import ScenarioError
from .figure_options import (ANIMATION_LEGENDS, LABEL_KINDS, LEGEND_MODES, PAPER_SIZES, VIEWS, ZOOMS, check_hide,
                             check_view, parse_scale)
from .units import resolve_system

__all__ = ["build_parser", "units_type", "hide_type", "scale_type", "ViewAction"]


def units_type(text: str) -> str:
    """argparse type of ``--units``: SI or US in any case."""
    try:
        return resolve_system(text)
    except ScenarioError:
        raise argparse.ArgumentTypeError(f"{text!r}: allowed SI or US (any case)") from None


def hide_type(text: str) -> frozenset:
    """argparse type of ``--hide``: label kinds, comma-separated."""
    try:
        return check_hide(text)
    except ScenarioError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None


class ViewAction(argparse.Action):
    """``--view X0 Y0 X1 Y1``: four numbers with X1 > X0 and Y1 > Y0, checked as the line is parsed
    (before the file is read or anything compiled or run); stored as written, converted once the
    file's length unit is known."""

    def __call__(self, parser, namespace, values, option_string=None):
        try:
            check_view(values, field="--view", unit="")
        except ScenarioError as exc:
            parser.error(f"argument --view: {str(exc).split(': ', 1)[-1]}")
        setattr(namespace, self.dest, list(values))


def scale_type(text: str) -> float:
    """argparse type of ``--scale``: 1:N, or an engineer's scale 1" = F'."""
    try:
        return parse_scale(text, field="--scale")
    except ScenarioError as exc:
        raise argparse.ArgumentTypeError(str(exc).split(": ", 1)[-1]) from None


def _sampling_options(parser, engines, figures: str) -> None:
    """The options mc and posterior share: where they run, what they write, in which units."""
    parser.add_argument("--workers", default=None, help="local processes, >= 1 or auto (default: all cores)")
    parser.add_argument("--dask", metavar="ADDRESS", help="run on an existing Dask cluster (scheduler address)")
    parser.add_argument("--plots", metavar="DIR", help=f"write {figures} into DIR")
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object (SI units)")
    parser.add_argument("--units", type=units_type, default=None,
                        help="SI or US (any case): units of the report and plots (default: the scenario's units)")
    parser.add_argument("--engine", choices=engines, default=None,
                        help="run-out engine (default: compiled if available)")


def _add_inverse_commands(sub):
    engines = ("compiled", "scipy")
    f = sub.add_parser("fit", help="find the [fit] unknowns from the evidence (weighted least squares, intervals)")
    f.add_argument("file", help="scenario file (TOML) with a [fit] table and evidence sigmas")
    f.add_argument("--json", action="store_true", help="print the full result as one JSON object (SI units)")
    f.add_argument("--units", type=units_type, default=None,
                   help="SI or US (any case): units of the report (default: the scenario's units)")
    f.add_argument("--engine", choices=engines, default=None, help="run-out engine (default: compiled if available)")
    f.add_argument("--workers", default=None, help="processes for the starts, >= 1 or auto (default: all cores)")
    f.add_argument("--progress", action="store_true", help="progress bar over the starts on stderr")
    f.add_argument("--sample-time-limit", type=float, default=30.0, metavar="SECONDS",
                   help="wall-clock limit of one scene evaluation's run-out (default 30 s); a slower one is penalised")
    f.add_argument("--write-best", metavar="OUT.toml",
                   help="write a runnable scenario: the input file with the unknowns at their best values, "
                        "[fit] removed (not the input file itself)")

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


def build_parser() -> argparse.ArgumentParser:
    """The ``crashsim`` parser: ``--version`` and one subcommand per command (``args.command`` names it;
    :data:`crashsim.cli.COMMANDS` holds the function that runs each)."""
    p = argparse.ArgumentParser(prog="crashsim", description="Reconstruct collisions of articulated vehicles.")

    p.add_argument("--version", action="version", version=f"crashsim {__version__}")
    sub = p.add_subparsers(dest="command", required=True)

    r = sub.add_parser("run", help="solve a scenario file and report")
    r.add_argument("file", help="scenario file (TOML)")
    r.add_argument("--json", action="store_true", help="print the full result as one JSON object (SI units)")
    r.add_argument("--units", type=units_type, default=None,
                   help="SI or US (any case): units of the report and the CSV files (default: the scenario's units)")
    r.add_argument("--csv", metavar="DIR", help="write time histories as CSV files into DIR (headers carry the unit)")
    r.add_argument("--dt", metavar="TIME", help='time step of every CSV history (bodies, wheel tracks, approaches), e.g. "0.1 s" '
                        '(default: runout.sample_dt; the approach: 201 points)')
    r.add_argument("--strict", action="store_true", help="exit with code 1 if an evidence item is out of tolerance")

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
    detail.add_argument("--view", nargs=4, metavar=("X0", "Y0", "X1", "Y1"), action=ViewAction,
                        help="a detail view: the window from (X0, Y0) to (X1, Y1) in the file's length unit "
                             "(m, or ft with units = \"US\"), X1 > X0 and Y1 > Y0")
    detail.add_argument("--zoom", choices=ZOOMS, default=None,
                        help="impact: a window around the outlines at impact of the bodies in the first impact, "
                             "with a margin (without it, an overview whose impact is small gets an inset of it)")
    pl.add_argument("--units", type=units_type, default=None, help="SI or US: units of the figure (default: the scenario's)")
    pl.add_argument("--dpi", type=int, default=150)
    pl.add_argument("--legend", choices=LEGEND_MODES, default="compact",
                    help="compact legend under or beside the diagram, one line per entry (default); the full one "
                         "there, each evidence item with its residual (outside); small inside it; or none")
    pl.add_argument("--hide", type=hide_type, default=None, metavar="KINDS",
                    help=f"label kinds to leave out, comma-separated: labels (all), {', '.join(LABEL_KINDS)}")
    pl.add_argument("--paper", choices=tuple(PAPER_SIZES), default=None,
                    help="print sheet: the figure is the page, the drawing to scale (PDF/SVG print at 100 %%)")
    pl.add_argument("--scale", type=scale_type, default=None, metavar="1:N",
                    help='drawing scale on the sheet, e.g. "1:200" or an engineer\'s scale "1\" = 40\'" (default: '
                         'the largest standard scale that fits, in US units an engineer\'s scale; A4 without '
                         '--paper)')

    an = sub.add_parser("animate", help="animate the run-out over the scene diagram (.gif, or .mp4 with ffmpeg)")
    an.add_argument("file", help="scenario file (TOML) with a [runout] section")
    an.add_argument("-o", "--output", required=True, help="animation: .gif, or .mp4 where ffmpeg is installed")
    an.add_argument("--dt", metavar="TIME", default="0.05 s", help='scene time between frames (default "0.05 s")')
    an.add_argument("--speed", type=float, default=1.0,
                    help="playback speed, 1 = real time (frames per second = speed / dt)")
    an.add_argument("--units", type=units_type, default=None, help="SI or US: units of the figure (default: the scenario's)")
    an.add_argument("--dpi", type=int, default=100)
    an.add_argument("--no-approach", action="store_true",
                    help="start at the impact (a scene with approaches starts at the earliest start of braking)")
    an.add_argument("--view", choices=VIEWS, default="follow",
                    help="follow: a camera framed on the vehicles at each frame, smoothed (default); "
                         "scene: the whole scene still")
    an.add_argument("--legend", choices=ANIMATION_LEGENDS, default="compact",
                    help="a compact legend outside the view (default), or none")
    an.add_argument("--quiet", action="store_true", help="no progress bar")

    sv = sub.add_parser("survey", help="list a survey file's layers or codes with entity counts and extents")
    sv.add_argument("file", help="survey file: .dxf, point file (.csv, .txt, .asc, .pnezd) or .geojson")
    sv.add_argument("-o", "--output", metavar="PREVIEW.png", help="also draw every entity, coloured by layer or code")
    sv.add_argument("--units", default=None, help="unit of the coordinates (DXF: default $INSUNITS; points: m)")
    sv.add_argument("--columns", default="PNEZD", help="point files: column letters (default PNEZD)")
    sv.add_argument("--crs", default=None, help="GeoJSON: projected CRS to show it in (e.g. EPSG:32633)")
    sv.add_argument("--layer-property", default="layer", help="GeoJSON: the property that names a feature's layer")

    ex = sub.add_parser("export", help="write the reconstruction as CAD (DXF) or GeoJSON in the survey's frame")
    ex.add_argument("file", help="scenario file (TOML)")
    ex.add_argument("--dxf", metavar="OUT.dxf", help="DXF drawing, one layer per outline, path, track and evidence")
    ex.add_argument("--geojson", metavar="OUT.geojson", help="the same as GeoJSON features with a layer property")
    ex.add_argument("--times", metavar="TIMES", help='outlines also at these times after separation, e.g. "0.5 s, 1 s"')

    rp = sub.add_parser("report", help="write one self-contained HTML case report (inputs, impacts, run-out, "
                                       "evidence, figures, SHA-256 of every input file)")
    rp.add_argument("file", help="scenario file (TOML)")
    rp.add_argument("-o", "--output", required=True, help="the report: .html")
    rp.add_argument("--fit", metavar="FIT.json", help="include a fit's result (crashsim fit FILE --json > FIT.json)")
    rp.add_argument("--mc", metavar="MC.json", help="include a Monte Carlo result (crashsim mc FILE --json)")
    rp.add_argument("--posterior", metavar="POST.json", help="include a posterior (crashsim posterior FILE --json)")
    rp.add_argument("--units", type=units_type, default=None, help="SI or US: units of the report (default: the scenario's)")

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
    va.add_argument("--units", type=units_type, default=None,
                    help="SI or US (any case) for every value (default: each source's own units)")

    s = sub.add_parser("schema", help="print the documented scenario-file schema")
    s.add_argument("--format", choices=("text", "markdown"), default="text")

    pr = sub.add_parser("presets", help="list the vehicle library's body parameter sets, their geometry and sources")
    pr.add_argument("--units", type=units_type, default=None, help="SI or US (any case): units of the list (default SI)")
    pr.add_argument("--plot", metavar="NAME", help="draw preset NAME to scale in plan view (with -o FILE)")
    pr.add_argument("-o", "--output", metavar="FILE", help="figure of --plot: .png, .svg or .pdf")

    lv = sub.add_parser("live", help="open the scene in a live view in the browser: drag vehicles, set speeds and "
                                     "frictions, see the scene, its evidence and its uncertainty recomputed at once")
    lv.add_argument("file", help="scenario file (TOML)")
    lv.add_argument("--port", type=int, default=0, help="port on 127.0.0.1 (default: a free one)")
    lv.add_argument("--no-browser", action="store_true", help="print the address only, do not open a browser")
    lv.add_argument("--band-samples", type=int, default=32,
                    help="samples of the Monte Carlo band (with [uncertainty]; 0: none; default 32)")
    lv.add_argument("--workers", type=int, default=2, help="worker processes of the band (default 2)")
    return p

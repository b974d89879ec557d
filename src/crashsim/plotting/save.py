"""The scene's figures written to files (:func:`save_scene_figures`): the diagram, and optionally the
histories, the time-distance chart and the wheel time line.
"""

from __future__ import annotations

from pathlib import Path

from ..errors import ScenarioError
from ..figure_options import SCENE_FIGURE_SUFFIXES, check_hide, check_view
from .histories import plot_histories
from .scene import plot_scene
from .sheet import print_sheet
from .style import pyplot
from .time_distance import plot_time_distance
from .timeline import plot_wheel_timeline

__all__ = ["SCENE_FIGURE_SUFFIXES", "save_scene_figures"]


def save_scene_figures(scene, path, *, histories_path=None, dpi: int = 150, interval: float | None = None,
                       system: str | None = None, time_distance_path=None, approach: bool = True, legend="compact",
                       hide=(), paper: str | None = None, scale: float | None = None, view=None,
                       zoom: str | None = None, wheels_path=None) -> list:
    """Write the scene diagram (and optionally the histories) to files; closes its figures.

    Parameters
    ----------
    scene : SceneResult
    path : str or Path
        Scene diagram; the format follows the suffix: ``.png``, ``.svg`` or ``.pdf``.
    histories_path : str or Path, optional
        Run-out histories (:func:`plot_histories`), same suffixes; needs a run-out.
    time_distance_path : str or Path, optional
        Time-distance and speed-time chart (:func:`plot_time_distance`), same suffixes.
    wheels_path : str or Path, optional
        The wheel time line (:func:`crashsim.plotting.timeline.plot_wheel_timeline`): every wheel's state,
        air-brake level, sliding and steering from the approach to rest, same suffixes.
    approach : bool
        Draw the approaches on the scene diagram (see :func:`plot_scene`).
    legend, hide, paper, scale, view, zoom
        Legend, hidden label kinds, print sheet and detail view of the scene diagram (see
        :func:`plot_scene`).
    dpi : int
        Resolution of raster output [dots per inch].
    interval : float, optional
        Ghost-outline interval [s] (see :func:`plot_scene`).
    system : {"SI", "US"}, optional
        Display units; default the scenario's.

    Returns
    -------
    list of Path
        The files written, scene diagram first. Parent directories are created.

    Raises
    ------
    ScenarioError
        For a suffix other than .png/.svg/.pdf (before anything is drawn or written), or
        histories asked of a scene without a run-out.
    """
    named = [(Path(path), "path")] + ([(Path(histories_path), "histories_path")] if histories_path is not None else [])
    named += [(Path(time_distance_path), "time_distance_path")] if time_distance_path is not None else []
    named += [(Path(wheels_path), "wheels_path")] if wheels_path is not None else []
    targets = [p for p, _ in named]
    for p, key in named:
        if p.suffix.lower() not in SCENE_FIGURE_SUFFIXES:
            raise ScenarioError(f"cannot write a figure to {str(p)!r}: unsupported suffix {p.suffix!r}; allowed "
                                f"{', '.join(SCENE_FIGURE_SUFFIXES)}", field=key)
    if histories_path is not None and not scene.runout:
        raise ScenarioError(f"cannot write histories to {str(histories_path)!r}: scene "
                            f"{scene.scenario.title!r} has no run-out (impact only)", field="histories_path")
    check_hide(hide)
    if paper is not None:
        print_sheet(paper, (0.0, 0.0), (1.0, 1.0), 1.0)  # a known paper, before anything is drawn
    plt = pyplot()
    written = []
    if view is not None:
        check_view(view, field="view")  # before anything is drawn
    ax = plot_scene(scene, interval=interval, system=system, approach=approach, legend=legend, hide=hide, paper=paper,
                    scale=scale, view=view, zoom=zoom)
    try:
        targets[0].parent.mkdir(parents=True, exist_ok=True)
        ax.figure.savefig(targets[0], dpi=dpi)
        written.append(targets[0])
    finally:
        plt.close(ax.figure)
    for p, key in named[1:]:
        if key == "wheels_path":
            fig = plot_wheel_timeline(scene)
        else:
            fig = (plot_histories if key == "histories_path" else plot_time_distance)(scene, system=system)
        try:
            p.parent.mkdir(parents=True, exist_ok=True)
            fig.savefig(p, dpi=dpi)
            written.append(p)
        finally:
            plt.close(fig)
    return written

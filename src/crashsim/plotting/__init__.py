"""Figures. The only package of crashsim that imports matplotlib (lazily, on first use).

Every function draws on a given Axes (``ax=None``: a new figure) and returns what it drew
on; nothing here calls ``plt.show()``, so the package works under any backend, including
Agg on a machine without a screen. Inputs are the SI dicts and arrays of the numeric core;
degrees and percent appear only on the axes.

Modules by subject, each importing only from those above it in this list (no circle):

* :mod:`~crashsim.plotting.style`: colours, families, z-orders, halos, title wrapping;
* :mod:`~crashsim.plotting.labels`: text boxes, the ink of drawn lines, :func:`place_labels`;
* :mod:`~crashsim.plotting.events`, :mod:`~crashsim.plotting.loads`, :mod:`~crashsim.plotting.detail`:
  impact lines of the time charts, the roll panel, the impact inset;
* :mod:`~crashsim.plotting.drawing`: the drawing state of a scene figure (:class:`SceneDrawing`);
* :mod:`~crashsim.plotting.sheet`: print sheets, engineer's scales, scale bar, north arrow;
* :mod:`~crashsim.plotting.road`, :mod:`~crashsim.plotting.layers`: the layers of the scene
  diagram (zones and map lines; tracks, approaches, evidence, arrows, obstacles, impacts, barrier);
* :mod:`~crashsim.plotting.layout`: legend and figure size;
* :mod:`~crashsim.plotting.scene`: :func:`plot_scene`;
* :mod:`~crashsim.plotting.time_distance`, :mod:`~crashsim.plotting.histories`,
  :mod:`~crashsim.plotting.timeline`, :mod:`~crashsim.plotting.barrier`: the other figures;
* :mod:`~crashsim.plotting.save`: :func:`save_scene_figures`.

The names below are importable from :mod:`crashsim.plotting` itself.
"""

from __future__ import annotations

from ..figure_options import LABEL_KINDS, LEGEND_MODES, PAPER_SIZES, check_hide, is_color, parse_scale
from .barrier import BarrierAxes, plot_barrier_figures, plot_barrier_sweep
from .drawing import SceneDrawing, scene_drawing
from .histories import IMPACT_LABEL_GAP, LIMIT_SHOWN_FROM, history_panels, plot_histories
from .labels import LINE_SHY, line_ink, place_labels, text_box
from .layout import layout_scene_figure, legend_mode
from .road import map_line_legend_texts, zone_colors
from .save import SCENE_FIGURE_SUFFIXES, save_scene_figures
from .scene import plot_scene
from .sheet import (ENGINEER_SCALES_FT, PrintSheet, check_sheet, engineer_scale_text, layout_print, north_direction,
                    print_sheet, replace_scale_bar)
from .style import MAX_WIDTH, MIN_WIDTH, Z_REST, Z_TEXT, figure_system
from .time_distance import plot_time_distance
from .timeline import plot_wheel_timeline

__all__ = ["is_color", "LABEL_KINDS", "LINE_SHY", "line_ink", "LEGEND_MODES", "PAPER_SIZES", "PrintSheet", "place_labels", "check_hide",
           "legend_mode", "parse_scale", "replace_scale_bar", "north_direction", "print_sheet", "scene_drawing", "text_box", "BarrierAxes",
           "plot_barrier_sweep", "plot_barrier_figures", "plot_scene", "plot_histories",
           "history_panels", "save_scene_figures", "SCENE_FIGURE_SUFFIXES", "check_sheet", "zone_colors",
           "map_line_legend_texts", "engineer_scale_text", "ENGINEER_SCALES_FT",
           # public before the split too, outside its __all__
           "SceneDrawing", "Z_REST", "Z_TEXT", "figure_system", "layout_print", "layout_scene_figure", "MIN_WIDTH",
           "MAX_WIDTH", "IMPACT_LABEL_GAP", "LIMIT_SHOWN_FROM", "plot_time_distance", "plot_wheel_timeline"]

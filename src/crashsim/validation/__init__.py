"""The validation suite: staged collisions and full-scale tests against crashsim, their errors and bands.

``validation/`` at the repository's root holds one folder per case (its scene, the published
measurements with their sources, what was assumed, the record of documented misses) and the suite's
rules; this package finds and runs it (``crashsim validate``), measures every quantity's error with
its metric against its band (:mod:`.core`), writes the table, JSON, CSV and figures (:mod:`.output`),
and says which case class a scene belongs to and what the suite's errors for that class are
(:mod:`.classify`), which the case report quotes. ``validation/README.md`` is the suite's account of
its rules, metrics and bands.
"""

from .classify import class_errors, scene_class
from .core import METRICS, STATUS, CaseResult, Quantity
from .output import plot_case, results_dict, summaries, table_text, write_csv
from .suite import KINDS, Suite, find_suite, load_suite, run_suite

__all__ = ["find_suite", "load_suite", "run_suite", "Suite", "KINDS", "Quantity", "CaseResult", "METRICS", "STATUS",
           "table_text", "results_dict", "write_csv", "plot_case", "summaries", "scene_class", "class_errors"]

"""Scene evidence: the measured items (rest positions, tyre marks, point of impact, delta-v,
recorder tables, crush) and their checks against a computed scene.

:mod:`crashsim.evidence.checks` holds the items and :func:`evaluate_evidence`;
:mod:`crashsim.evidence.crush` the crush-energy (CRASH3) items and their checks. The layer
depends on geometry and the impact's crush formulas only, so the scenario loader and the
plots read it without the run-out.
"""

from .checks import *  # noqa: F401,F403
from .checks import __all__ as _checks_all
from .crush import CrushEvidence, crush_checks, crush_groups

__all__ = [*_checks_all, "CrushEvidence", "crush_checks", "crush_groups"]

"""The reconstruction sections of a scenario file checked at load, whatever the command.

A ``[fit]`` or ``[uncertainty]`` table that names an input the file does not have (a typo in a
``path``), or bounds outside the input's allowed range, is an error of the file: every command
that reads the file refuses it, not only the command that would use the table (``crashsim run``
of a file whose ``[fit]`` says ``runout.road_fricton`` ran without a word).
"""

from __future__ import annotations

from ..errors import in_file
from .fit import FitSpec
from .montecarlo import UncertaintySpec

__all__ = ["check_sections"]


def check_sections(data: dict | None, file: str | None = None) -> None:
    """Raise the :class:`~crashsim.errors.ScenarioError` of the first bad ``[fit]`` or
    ``[uncertainty]`` item of the raw file contents ``data`` (nothing for a file without them)."""
    if not isinstance(data, dict):
        return
    with in_file(file):
        if isinstance(data.get("fit"), dict):
            FitSpec.from_dict(data["fit"], data, file=file)
        if isinstance(data.get("uncertainty"), dict):
            UncertaintySpec.from_dict(data["uncertainty"], file=file)

"""Exception types of crashsim.

Every error raised for bad input names the field, the value and what is allowed.
"""

from __future__ import annotations

__all__ = ["CrashsimError", "ScenarioError", "SolverError", "IllConditionedError"]


class CrashsimError(Exception):
    """Base class of every error crashsim raises on purpose."""


class ScenarioError(CrashsimError, ValueError):
    """Invalid input: a scenario file, a parameter or an argument.

    Parameters
    ----------
    message
        What is wrong, naming the field, the value and the allowed range.
    field
        Dotted path of the offending field (``"vehicles.A.bodies.tractor.mass"``), if known.
    file
        The scenario file the field came from, if any.
    """

    def __init__(self, message: str, *, field: str | None = None, file: str | None = None):
        self.field = field
        self.file = file
        prefix = ""
        if file:
            prefix += f"{file}: "
        if field:
            prefix += f"{field}: "
        super().__init__(prefix + message)


class SolverError(CrashsimError, RuntimeError):
    """A computation could not produce a trustworthy answer."""


class IllConditionedError(SolverError):
    """The impact equations are singular or too ill-conditioned to solve.

    Attributes
    ----------
    condition_number
        Condition number of the (equilibrated) impulse system, ``inf`` if singular.
    dependent
        Labels of the equations found linearly dependent (may be empty).
    """

    def __init__(self, message: str, *, condition_number: float, dependent: tuple[str, ...] = ()):
        self.condition_number = condition_number
        self.dependent = dependent
        super().__init__(message)

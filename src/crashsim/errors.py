"""Exception types of crashsim.

Every error raised for bad input names the field, the value and what is allowed.
"""

from __future__ import annotations

from contextlib import contextmanager

__all__ = ["CrashsimError", "ScenarioError", "InadmissibleImpactError", "SolverError", "IllConditionedError",
           "with_file", "in_file", "failure_reason"]


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
        if field and not message.startswith((f"{field} = ", f"{field}: ")):  # "key = value ..." names it once
            prefix += f"{field}: "
        super().__init__(prefix + message)


class InadmissibleImpactError(ScenarioError):
    """Coefficients that no collision can produce for this geometry (see :mod:`crashsim.impact.admissible`).

    Attributes
    ----------
    reason : str
        Which rule is broken ("tensile normal impulse", "energy created at the crush surface", ...).
    value : float
        The offending value (of the coefficient the message names).
    allowed : (float, float) or None
        The admissible range of that coefficient for this geometry, if there is one.
    """

    def __init__(self, message: str, *, field: str | None = None, file: str | None = None, reason: str = "",
                 value: float = float("nan"), allowed=None):
        self.reason = reason
        self.value = value
        self.allowed = allowed
        super().__init__(message, field=field, file=file)


class UnreachableImpactError(ScenarioError):
    """Valid inputs whose motion cannot reach the impact: an approach that stops before it, or
    passes the impact position too far away.  A fit or Monte Carlo sample in such a region fails
    (like an inadmissible impact); a bound of a fit unknown may lie in one."""


def with_file(exc: ScenarioError, file: str | None) -> ScenarioError:
    """``exc`` with the scenario file named (a copy of the same type), unless it names one already."""
    if file is None or exc.file is not None:
        return exc
    text = str(exc)
    if exc.field and text.startswith(f"{exc.field}: "):
        text = text[len(exc.field) + 2:]
    new = exc.__class__.__new__(exc.__class__)
    new.__dict__.update(exc.__dict__)
    ScenarioError.__init__(new, text, field=exc.field, file=file)
    return new


@contextmanager
def in_file(file: str | None):
    """A :class:`ScenarioError` raised in the block names ``file`` (see :func:`with_file`)."""
    try:
        yield
    except ScenarioError as exc:
        raise with_file(exc, file) from None


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


def failure_reason(exc: BaseException) -> str:
    """A short category of why a scene evaluation failed, for the tallies of fits and Monte Carlo.

    ``"inadmissible impact: <rule>"``, ``"ill-conditioned impact"``, ``"approach does not reach the
    impact"``, ``"invalid input"``,
    ``"solver error"``, or the exception's type name.
    """
    if isinstance(exc, InadmissibleImpactError):
        return f"inadmissible impact: {exc.reason}"
    if isinstance(exc, IllConditionedError):
        return "ill-conditioned impact"
    if isinstance(exc, UnreachableImpactError):
        return "approach does not reach the impact"
    if isinstance(exc, ScenarioError):
        text = str(exc)
        if "not approaching" in text:
            return "contact points not approaching"
        return "invalid input"
    if isinstance(exc, SolverError):
        return "solver error"
    return type(exc).__name__

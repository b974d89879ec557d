"""Input errors at a key of the file: :func:`error_at`, :func:`rewrap`, :func:`written` (a value as written), and
:class:`Problems`, which collects the errors of independent parts of a file so that one run reports them all.
"""

from __future__ import annotations

from ..errors import ScenarioError
from ..schema import ScenarioValidationError
from ..units import toml_repr


def rewrap(exc: ScenarioError, prefix: str, file: str | None) -> ScenarioError:
    msg = str(exc)
    if exc.field and msg.startswith(f"{exc.field}: "):
        msg = msg[len(exc.field) + 2:]
    key = f"{prefix}.{exc.field}" if exc.field else prefix
    return ScenarioError(msg, field=key, file=file)


def error_at(msg: str, key: str, file: str | None) -> ScenarioError:
    return ScenarioError(msg, field=key, file=file)


class Problems:
    """The input errors of independent parts of a file, collected so that one run reports them all.

    ``with problems.each(): ...`` keeps a :class:`ScenarioError` raised inside and goes on;
    :meth:`raise_any` then raises them together: the error itself if it is the only one (its type
    kept: fit and Monte Carlo tell an unreachable or inadmissible impact from a bad file), else one
    :class:`~crashsim.schema.ScenarioValidationError` listing every one on its own line."""

    def __init__(self, file: str | None, lenient: bool = False):
        self.file = file
        self.lenient = lenient  # after schema errors: a part that fails on a bad value is skipped
        self.errors: list[ScenarioError] = []

    def each(self):
        return _Keep(self)

    def raise_any(self) -> None:
        if not self.errors:
            return
        if len(self.errors) == 1:
            raise self.errors[0]
        problems = []
        for exc in self.errors:
            if isinstance(exc, ScenarioValidationError):
                problems += exc.problems
                continue
            text = str(exc)
            if exc.file and text.startswith(f"{exc.file}: "):
                text = text[len(exc.file) + 2:]
            if exc.field and text.startswith(f"{exc.field}: "):
                text = text[len(exc.field) + 2:]
            for j, extra in enumerate(text.split("\n")):  # a multi-problem error: one line each
                if j == 0:
                    problems.append((exc.field or "", extra))
                elif extra.strip() and not extra.rstrip().endswith("more problems:") and not extra.rstrip().endswith(
                        "more problem:"):
                    path, _, rest = extra.strip().partition(": ")
                    problems.append((path, rest) if rest else (exc.field or "", extra.strip()))
        raise ScenarioValidationError(problems, file=self.file)


class Skip(Exception):
    """A part left for the next run (lenient: what it needs could not be built)."""


class _Keep:
    def __init__(self, owner: Problems):
        self.owner = owner

    def __enter__(self):
        return self

    def __exit__(self, kind, exc, tb):
        if exc is not None and isinstance(exc, ScenarioError):
            self.owner.errors.append(exc)
            return True
        if exc is not None and self.owner.lenient and isinstance(exc, Exception):
            return True  # a part built on a value the schema refused: its own checks cannot run
        return False


def as_in_file(raw) -> str:
    """A value as written in the file (``["-6.2 m", "0 m"]``)."""
    return toml_repr(raw)

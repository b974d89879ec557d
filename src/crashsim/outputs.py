"""Output paths checked before any work: a file or folder that cannot be written is an input error
found in a millisecond, not a traceback after minutes of computation.

The check creates nothing that stays: an existing file is opened for appending (its contents and
time stamp unchanged), a folder is probed with a temporary file that is removed at once, and a
folder that does not exist yet is judged by the nearest folder above it that does (the writers
create the missing ones).
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

from .errors import ScenarioError

__all__ = ["check_output_file", "check_output_dir", "check_workers", "same_file"]


def _cause(exc: OSError) -> str:
    return exc.strerror or type(exc).__name__


def _existing_ancestor(p: Path) -> Path:
    q = p.absolute()
    while not q.exists() and q != q.parent:
        q = q.parent
    return q


def _probe_dir(d: Path, *, field: str, target: Path, what: str) -> None:
    """``d`` (an existing path) must be a folder in which a file can be created."""
    if not d.is_dir():
        raise ScenarioError(f"{str(target)!r}: cannot write {what} there: {str(d)!r} is a file, not a folder",
                            field=field)
    try:
        with tempfile.TemporaryFile(dir=d):
            pass
    except OSError as exc:
        raise ScenarioError(f"{str(target)!r}: cannot write {what} there: the folder {str(d)!r} cannot be "
                            f"written ({_cause(exc)})", field=field) from None


def check_output_file(path, *, field: str, make_parents: bool = True, overwrite: bool = True,
                      suffixes: tuple[str, ...] | None = None, what: str = "a file") -> Path:
    """The output file ``path`` as a Path, if it can be written; else a :class:`ScenarioError`.

    Parameters
    ----------
    path : str or Path
        The file to be written.
    field : str
        The argument as the user wrote it (``"-o"``, ``"--write-best"``), named in the message.
    make_parents : bool
        The writer creates missing folders; else the folder must exist.
    overwrite : bool
        An existing file may be replaced (or appended to); else it is an error.
    suffixes : tuple of str, optional
        Allowed suffixes (lower case, with the dot).
    what : str
        What is written, for the message ("the scene figure").
    """
    p = Path(path)
    if suffixes is not None and p.suffix.lower() not in suffixes:
        raise ScenarioError(f"{str(p)!r}: cannot write {what} with the suffix {p.suffix or '(none)'!r}; allowed: "
                            f"{', '.join(suffixes)}", field=field)
    if p.is_dir():
        raise ScenarioError(f"{str(p)!r} is a folder; give the name of {what}", field=field)
    if p.exists():
        if not overwrite:
            raise ScenarioError(f"{str(p)!r} exists; give a new file name (it is not overwritten)", field=field)
        try:
            with open(p, "ab"):
                pass
        except OSError as exc:
            raise ScenarioError(f"{str(p)!r}: the file cannot be written ({_cause(exc)})", field=field) from None
        return p
    parent = p.absolute().parent
    if not parent.exists() and not make_parents:
        raise ScenarioError(f"{str(p)!r}: cannot write {what} there: the folder {str(p.parent)!r} does not exist",
                            field=field)
    _probe_dir(_existing_ancestor(parent), field=field, target=p, what=what)
    return p


def check_output_dir(path, *, field: str, what: str = "files") -> Path:
    """The output folder ``path`` as a Path, if files can be written into it (created if missing);
    else a :class:`ScenarioError` (a file of that name, a folder that cannot be written)."""
    p = Path(path)
    if p.exists() and not p.is_dir():
        raise ScenarioError(f"{str(p)!r} is a file; give a folder to write {what} into", field=field)
    _probe_dir(_existing_ancestor(p), field=field, target=p, what=what)
    return p


def check_workers(workers, *, field: str = "workers") -> int | None:
    """A worker count: ``None`` or ``"auto"`` (all cores) as None, else an integer >= 1."""
    if workers is None or (isinstance(workers, str) and workers.strip().lower() == "auto"):
        return None
    try:
        n = int(workers)
        ok = n == float(workers) if not isinstance(workers, str) else str(n) == workers.strip()
    except (TypeError, ValueError):
        ok = False
    if not ok or n < 1:
        raise ScenarioError(f"{field} = {workers!r}; allowed a whole number >= 1, or \"auto\" (all "
                            f"{os.cpu_count() or 1} cores)", field=field)
    return n


def same_file(a, b) -> bool:
    """Whether two paths name the same file (existing or not)."""
    try:
        if a.exists() and b.exists():
            return a.samefile(b)
    except OSError:  # pragma: no cover - unreadable paths
        pass
    return a.resolve() == b.resolve()
